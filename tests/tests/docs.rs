//! The docs' links hold: every relative link and image in the workspace's markdown (README.md,
//! docs/, the crates' READMEs) names a file or folder that exists, so that a newcomer following
//! the guide never lands on a moved page.

use std::path::{Path, PathBuf};

fn markdown_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            if !name.starts_with('.') && name != "target" && name != "node_modules" {
                markdown_files(&path, out);
            }
        } else if name.ends_with(".md") {
            out.push(path);
        }
    }
}

/// The targets of `[text](target)` and `![alt](target)` links outside code blocks and spans.
fn link_targets(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // drop inline code spans
        let line: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
        let mut rest = line.as_str();
        while let Some(i) = rest.find("](") {
            let tail = &rest[i + 2..];
            let end = tail.find(')').unwrap_or(tail.len());
            let target = tail[..end].split_whitespace().next().unwrap_or("");
            out.push(target.to_string());
            rest = &tail[end..];
        }
    }
    out
}

fn is_relative(target: &str) -> bool {
    !(target.is_empty()
        || target.starts_with('#')
        || target.contains("://")
        || target.starts_with("mailto:"))
}

#[test]
fn every_relative_markdown_link_names_an_existing_file() {
    let root = gcr_tests::workspace_path("");
    let mut files = Vec::new();
    markdown_files(&root, &mut files);
    assert!(files.len() > 10, "found {} markdown files", files.len());
    let mut broken = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for target in link_targets(&text) {
            if !is_relative(&target) {
                continue;
            }
            let path = target.split('#').next().unwrap_or("");
            if !f.parent().unwrap().join(path).exists() {
                let rel = f.strip_prefix(&root).unwrap_or(f);
                broken.push(format!("{}: {target}", rel.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links: {broken:#?}");
}

/// The reader finds links and skips code (so that the test above can fail).
#[test]
fn the_link_reader_sees_links_and_skips_code() {
    let md = "see [a](x.md#s) and ![p](f/p.png)\n`[no](code.md)`\n```\n[no](fenced.md)\n```\n";
    assert_eq!(link_targets(md), vec!["x.md#s", "f/p.png"]);
}
