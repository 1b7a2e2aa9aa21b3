//! The workspace's shape as tests (issues 15, 30): no module of any crate imports, directly or
//! through others, a module that imports it back — neither the top-level modules nor the files
//! (`solve/run.rs` may not use `solve/mod.rs` when that uses it); no function longer than 100 lines
//! in `gcr`, `gcr-cli`, `scene-sampler`'s loaders or `isgcs`. Read from the sources as text:
//! `crate::`, `super::`, `self::` and child-module paths resolved through `pub use` re-exports to
//! the file that defines the item; comments, strings and unit tests skipped.

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

/// The files held to 100 lines a function: the `gcr` library, the program, `isgcs` and
/// `scene-sampler`'s loaders (data tables aside: none is a function).
fn short_function_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in ["crates/gcr/src", "crates/gcr-cli/src", "crates/isgcs/src"] {
        rust_files(&gcr_tests::workspace_path(dir), &mut files);
    }
    let mut sampler = Vec::new();
    rust_files(
        &gcr_tests::workspace_path("crates/scene-sampler/src"),
        &mut sampler,
    );
    files.extend(sampler.into_iter().filter(|f| {
        let name = f.file_name().unwrap().to_string_lossy();
        name == "load.rs" || name.starts_with("gltf") || name.starts_with("obj")
    }));
    files
}

#[test]
fn no_function_in_the_checked_crates_is_over_100_lines() {
    let files = short_function_files();
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

// ---- File-level imports ------------------------------------------------------------------------

/// A file's module path in its crate: `solve/training.rs` → `solve::training`; `mod.rs`,
/// `lib.rs` and `main.rs` are their folder's module (the crate root is the empty path).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The source as code only: comments, string and char literals blanked, the `#[cfg(test)]` tail
/// (unit tests) dropped.
fn code_only(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => text,
    };
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match (b[i], b.get(i + 1).copied()) {
            ('/', Some('/')) => {
                while i < b.len() && b[i] != '\n' {
                    i += 1;
                }
            }
            ('/', Some('*')) => {
                i += 2;
                while i + 1 < b.len() && !(b[i] == '*' && b[i + 1] == '/') {
                    i += 1;
                }
                i += 2;
            }
            ('"', _) => {
                i += 1;
                while i < b.len() && b[i] != '"' {
                    i += if b[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
            }
            // a char literal ('x', '\n'), not a lifetime ('a)
            ('\'', Some(c)) if c == '\\' || b.get(i + 2) == Some(&'\'') => {
                i += 1;
                while i < b.len() && b[i] != '\'' {
                    i += if b[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("' '");
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    out
}

/// A `use` tree flattened into paths: `a::{b, c::{d, e as f}}` → `a::b`, `a::c::d`, `a::c::e`.
fn flatten_use(tree: &str) -> Vec<String> {
    // drop `as NAME` renames, then all whitespace
    let mut tokens = Vec::new();
    let mut words = tree.split_whitespace();
    while let Some(w) = words.next() {
        if w == "as" {
            let renamed = words.next().unwrap_or("");
            tokens.push(renamed.trim_start_matches(|c: char| c.is_alphanumeric() || c == '_'));
        } else {
            tokens.push(w);
        }
    }
    let tree = tokens.concat();
    let Some(open) = tree.find('{') else {
        return if tree.is_empty() { vec![] } else { vec![tree] };
    };
    let prefix = &tree[..open];
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let (mut parts, mut depth, mut cur) = (Vec::new(), 0, String::new());
    for ch in inner.chars() {
        match ch {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(std::mem::take(&mut cur));
                continue;
            }
            _ => {}
        }
        cur.push(ch);
    }
    parts.push(cur);
    parts
        .iter()
        .filter(|p| !p.is_empty())
        .flat_map(|p| flatten_use(&format!("{prefix}{p}")))
        .collect()
}

/// The `use` statements of `code` as (is a re-export, flattened paths), and the code without them.
fn use_statements(code: &str) -> (Vec<(bool, Vec<String>)>, String) {
    let mut uses = Vec::new();
    let mut rest = String::with_capacity(code.len());
    let mut from = 0;
    let is_ident = |c: char| c.is_alphanumeric() || c == '_';
    for (i, _) in code.match_indices("use ") {
        if i < from || code[..i].chars().next_back().is_some_and(is_ident) {
            continue;
        }
        let Some(end) = code[i..].find(';').map(|e| i + e) else {
            break;
        };
        let before = code[..i].trim_end();
        let public = before.ends_with("pub") || before.ends_with(')') && before.contains("pub(");
        uses.push((public, flatten_use(&code[i + 4..end])));
        rest.push_str(&code[from..i]);
        from = end + 1;
    }
    rest.push_str(&code[from..]);
    (uses, rest)
}

/// Every path `a::b::c` in `code` (identifiers joined by `::`, up to a `{`, `*` or `<`).
fn inline_paths(code: &str) -> Vec<String> {
    let c: Vec<char> = code.chars().collect();
    let is_ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let starts = is_ident(c[i]) && (i == 0 || !(is_ident(c[i - 1]) || c[i - 1] == ':'));
        if !starts {
            i += 1;
            continue;
        }
        let mut parts = Vec::new();
        loop {
            let s = i;
            while i < c.len() && is_ident(c[i]) {
                i += 1;
            }
            parts.push(c[s..i].iter().collect::<String>());
            let more = i + 2 < c.len() && c[i] == ':' && c[i + 1] == ':' && is_ident(c[i + 2]);
            if !more {
                break;
            }
            i += 2;
        }
        if parts.len() > 1 {
            out.push(parts.join("::"));
        }
    }
    out
}

/// The file-level import graph of one crate: module path → the module files it uses. A path is
/// resolved to the deepest file-module it names, through `pub use` re-exports to the item's own
/// file; re-exports themselves are not edges (a facade is not a dependency), `mod x;` neither.
struct FileGraph {
    edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
}

impl FileGraph {
    fn of_crate(src: &Path) -> Self {
        let mut files = Vec::new();
        rust_files(src, &mut files);
        let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_path(src, f)).collect();
        // (module, name) → the path it re-exports; module → (paths it uses, its child modules)
        let mut alias: BTreeMap<(Vec<String>, String), String> = BTreeMap::new();
        let mut uses: BTreeMap<Vec<String>, (Vec<String>, BTreeSet<String>)> = BTreeMap::new();
        for f in &files {
            let me = module_path(src, f);
            let text = code_only(&std::fs::read_to_string(f).unwrap());
            let (statements, rest) = use_statements(&text);
            let children: BTreeSet<String> = rest
                .match_indices("mod ")
                .filter_map(|(i, _)| {
                    let tail = &rest[i + 4..];
                    let name: String = tail
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    tail[name.len()..]
                        .trim_start()
                        .starts_with(';')
                        .then_some(name)
                })
                .collect();
            let mut paths = inline_paths(&rest);
            for (public, list) in statements {
                for p in list {
                    if public {
                        let name = p.rsplit("::").next().unwrap_or("").to_string();
                        alias.insert((me.clone(), name), p);
                    } else {
                        paths.push(p);
                    }
                }
            }
            uses.insert(me, (paths, children));
        }
        let graph = Self {
            edges: BTreeMap::new(),
        };
        let mut edges = BTreeMap::new();
        for (me, (paths, _)) in &uses {
            let deps: &mut BTreeSet<Vec<String>> = edges.entry(me.clone()).or_default();
            for p in paths {
                if let Some(to) = graph.resolve(me, p, &uses, &modules, &alias, 0) {
                    if &to != me {
                        deps.insert(to);
                    }
                }
            }
        }
        Self { edges }
    }

    /// The module file `path`, written in module `me`, names (`None`: another crate's).
    fn resolve(
        &self,
        me: &[String],
        path: &str,
        uses: &BTreeMap<Vec<String>, (Vec<String>, BTreeSet<String>)>,
        modules: &BTreeSet<Vec<String>>,
        alias: &BTreeMap<(Vec<String>, String), String>,
        depth: usize,
    ) -> Option<Vec<String>> {
        let mut parts: Vec<&str> = path.split("::").collect();
        let mut cur: Vec<String> = match parts[0] {
            "crate" => {
                parts.remove(0);
                Vec::new()
            }
            "super" | "self" => {
                let mut cur = me.to_vec();
                while let Some(&p @ ("super" | "self")) = parts.first() {
                    if p == "super" {
                        cur.pop();
                    }
                    parts.remove(0);
                }
                cur
            }
            first if uses.get(me).is_some_and(|u| u.1.contains(first)) => me.to_vec(),
            _ => return None,
        };
        let mut taken = 0;
        for p in &parts {
            let mut next = cur.clone();
            next.push(p.to_string());
            if !modules.contains(&next) {
                break;
            }
            cur = next;
            taken += 1;
        }
        if let Some(name) = parts.get(taken) {
            if let Some(target) = alias.get(&(cur.clone(), name.to_string())) {
                if depth < 8 {
                    if let Some(r) = self.resolve(&cur, target, uses, modules, alias, depth + 1) {
                        return Some(r);
                    }
                }
            }
        }
        modules.contains(&cur).then_some(cur)
    }
}

/// The workspace's crates with a `src` folder (the library crates, the program, xtask).
fn crate_sources() -> Vec<PathBuf> {
    let mut out = vec![gcr_tests::workspace_path("xtask/src")];
    for entry in std::fs::read_dir(gcr_tests::workspace_path("crates")).unwrap() {
        let src = entry.unwrap().path().join("src");
        if src.is_dir() {
            out.push(src);
        }
    }
    out.sort();
    out
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let mut found = Vec::new();
    for src in crate_sources() {
        let g = FileGraph::of_crate(&src);
        let named: BTreeMap<String, BTreeSet<String>> = g
            .edges
            .iter()
            .map(|(m, d)| (name(m), d.iter().map(|x| name(x)).collect()))
            .collect();
        if let Some(c) = cycle(&named) {
            found.push(format!("{}: {}", src.display(), c.join(" → ")));
        }
    }
    assert!(found.is_empty(), "file-level import cycles: {found:#?}");
}

fn name(m: &[String]) -> String {
    if m.is_empty() {
        "(root)".into()
    } else {
        m.join("/")
    }
}

/// The file-level reader sees what it must: a child using its parent's item through `super::`,
/// a parent using the child by its module name, a name re-exported from a sibling resolved to it.
#[test]
fn the_file_graph_reads_uses_and_re_exports() {
    let dir = std::env::temp_dir().join(format!("gcr-arch-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a")).unwrap();
    let write = |p: &str, t: &str| std::fs::write(src.join(p), t).unwrap();
    write("lib.rs", "mod a;\nmod b;\npub use b::Thing;\n");
    write(
        "a/mod.rs",
        "mod c;\npub(crate) struct Run;\nfn f() { c::go(); }\n",
    );
    write(
        "a/c.rs",
        "use super::Run; // comment crate::b\nuse crate::{Thing as T};\n",
    );
    write(
        "b.rs",
        "pub struct Thing; fn g() { let s = \"crate::a\"; }\n",
    );
    let g = FileGraph::of_crate(&src);
    let dep = |m: &[&str]| -> BTreeSet<String> {
        let key: Vec<String> = m.iter().map(|s| s.to_string()).collect();
        g.edges[&key].iter().map(|x| name(x)).collect()
    };
    assert_eq!(dep(&["a"]), BTreeSet::from(["a/c".to_string()]));
    assert_eq!(
        dep(&["a", "c"]),
        BTreeSet::from(["a".to_string(), "b".to_string()])
    );
    assert!(dep(&["b"]).is_empty(), "strings are not paths");
    assert!(dep(&[]).is_empty(), "re-exports are not edges");
    std::fs::remove_dir_all(&dir).ok();
}
