//! What the program's integration tests share: running `gcr` from the workspace root, a fresh
//! directory per test, a directory's entries, probes on the Cornell box.

#![allow(dead_code)] // each test file uses its own part

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The workspace root: the program runs from here, so `scenes/…` paths resolve.
pub const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// Runs `gcr ARGS…` from the workspace root and waits for it.
pub fn gcr(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gcr"))
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("gcr runs")
}

/// A fresh, empty directory `gcr-cli-<group>-<pid>-<name>` under the temp directory.
pub fn dir(group: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gcr-cli-{group}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The names in directory `d`, sorted.
pub fn entries(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Writes `n` probes on the Cornell box's floor (facing up) and back wall (facing the room),
/// spread by a fixed low-discrepancy walk, to `path`.
pub fn cornell_probes(path: &Path, n: usize) {
    let mut text = String::new();
    for i in 0..n {
        let (u, v) = (
            (i as f64 * 0.618_034).fract(),
            (i as f64 * 0.754_878).fract(),
        );
        let (x, z) = (0.02 + 0.5 * u, 0.02 + 0.5 * v);
        text += &match i % 2 {
            0 => format!("{x} 0 {z} 0 1 0\n"),
            _ => format!("{x} {z} 0.5592 0 0 -1\n"),
        };
    }
    std::fs::write(path, text).unwrap();
}
