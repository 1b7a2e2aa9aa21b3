//! Helpers shared by the workspace's cross-crate tests (`tests/tests/*.rs`).

use std::path::PathBuf;

/// A path inside the workspace (e.g. `scenes/cornell-box.probes.txt`), whatever the current
/// directory.
pub fn workspace_path(relative: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(relative)
}

/// A fresh, empty directory for one test's files (removed first if a previous run left it).
pub fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gcr-tests-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("the temporary directory is writable");
    dir
}

/// The default gather of `gcr solve` (paths, every ray corrected) run to `target` relative
/// standard error.
pub fn paths_to(target: f64) -> gcr::SolveConfig {
    gcr::SolveConfig {
        gather: gcr::GatherMode::Paths,
        paths: gcr::PathSettings {
            target_error: Some(target),
            ..gcr::PathSettings::default()
        },
        ..gcr::SolveConfig::default()
    }
}
