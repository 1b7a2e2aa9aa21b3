//! The workspace's shape as tests (issue 15): no module of any crate imports, directly or through
//! others, a module that imports it back; no function in the `gcr` library is longer than 100
//! lines. Read from the sources as text: `crate::m` paths and `crate::{…}` names resolved through
//! the crate root's `pub use m::…` re-exports; comment lines skipped.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The source without comment lines.
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    (text.lines())
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Identifiers after `from` up to the matching `}`.
fn words(s: &str) -> Vec<String> {
    s.split(|c: char| !(c.is_alphanumeric() || c == '_'))
        .filter(|w| !w.is_empty())
        .map(String::from)
        .collect()
}

/// Module → the crate's modules it uses (top level modules of `src`).
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let lib = code(&src.join("lib.rs"));
    // re-exported name → its module
    let mut owner: BTreeMap<String, String> = BTreeMap::new();
    for stmt in lib.split(';') {
        let stmt = stmt.trim();
        if let Some(rest) = stmt.strip_prefix("pub use ") {
            let rest = rest.trim_start_matches("crate::");
            let mut parts = rest.splitn(2, "::");
            if let (Some(module), Some(items)) = (parts.next(), parts.next()) {
                for w in words(items) {
                    owner.insert(w, module.trim().to_string());
                }
            }
        }
    }
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let module_of = |p: &Path| -> Option<String> {
        let rel = p.strip_prefix(src).unwrap();
        let first = rel
            .components()
            .next()?
            .as_os_str()
            .to_string_lossy()
            .into_owned();
        let name = first.trim_end_matches(".rs").to_string();
        (name != "lib" && name != "main").then_some(name)
    };
    let modules: BTreeSet<String> = files.iter().filter_map(|p| module_of(p)).collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in &files {
        let Some(m) = module_of(f) else { continue };
        let text = code(f);
        let deps = graph.entry(m.clone()).or_default();
        // a module by its name, else the module that owns a re-exported name
        let resolve = |w: &str| -> Option<String> {
            if modules.contains(w) {
                Some(w.to_string())
            } else {
                owner.get(w).filter(|o| modules.contains(*o)).cloned()
            }
        };
        for (i, _) in text.match_indices("crate::") {
            let rest = &text[i + 7..];
            if let Some(group) = rest.strip_prefix('{') {
                let end = group.find('}').unwrap_or(group.len());
                deps.extend(words(&group[..end]).iter().filter_map(|w| resolve(w)));
            } else if let Some(w) = words(rest).first() {
                deps.extend(resolve(w));
            }
        }
        deps.remove(&m);
    }
    graph
}

/// A cycle of the graph, if it has one (depth-first search).
fn cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        g: &BTreeMap<String, BTreeSet<String>>,
        m: &str,
        stack: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(k) = stack.iter().position(|s| s == m) {
            return Some(stack[k..].to_vec());
        }
        if done.contains(m) {
            return None;
        }
        stack.push(m.to_string());
        for d in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(g, d, stack, done) {
                return Some(c);
            }
        }
        stack.pop();
        done.insert(m.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph
        .keys()
        .find_map(|m| visit(graph, m, &mut Vec::new(), &mut done))
}

#[test]
fn no_crate_has_a_module_cycle() {
    let crates = gcr_tests::workspace_path("crates");
    for entry in std::fs::read_dir(&crates).unwrap() {
        let src = entry.unwrap().path().join("src");
        if !src.join("lib.rs").exists() {
            continue;
        }
        let graph = module_graph(&src);
        assert!(
            graph.len() > 1 || src.ends_with("gcr-cli/src"),
            "{}",
            src.display()
        );
        if let Some(c) = cycle(&graph) {
            panic!("{}: module cycle {}", src.display(), c.join(" → "));
        }
    }
}

/// The detector finds a cycle when there is one (so that the test above can fail).
#[test]
fn the_cycle_detector_sees_a_cycle() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("c".into());
    g.entry("c".into()).or_default().insert("a".into());
    assert_eq!(cycle(&g).map(|c| c.len()), Some(3));
    g.get_mut("c").unwrap().clear();
    assert_eq!(cycle(&g), None);
}

#[test]
fn no_function_in_the_gcr_library_is_over_100_lines() {
    let mut files = Vec::new();
    rust_files(&gcr_tests::workspace_path("crates/gcr/src"), &mut files);
    let mut long = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            let t = l.trim_start();
            let is_fn = ["fn ", "pub fn ", "pub(crate) fn ", "pub(super) fn "]
                .iter()
                .any(|p| t.starts_with(p));
            if !is_fn || t.ends_with(';') {
                continue;
            }
            // the body ends at the first line back at the signature's indentation that closes it
            let indent = l.len() - t.len();
            let end = (i + 1..lines.len()).find(|&j| {
                let u = lines[j];
                u.len() - u.trim_start().len() == indent && u.trim_start().starts_with('}')
            });
            if let Some(end) = end {
                if end - i + 1 > 100 {
                    long.push(format!("{}:{} ({} lines)", f.display(), i + 1, end - i + 1));
                }
            }
        }
    }
    assert!(long.is_empty(), "functions over 100 lines: {long:?}");
}
