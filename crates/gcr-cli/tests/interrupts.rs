//! Issue 35 item 11: an interrupted run leaves no file behind. The probes are staged to a
//! temporary file before the image's gather starts; SIGINT or SIGTERM during that gather used to
//! leave it (`.p.txt.gcr-PID-N.tmp`). Now they are removed and the exit code is 130; after a
//! SIGKILL, which nothing can catch, the next run writing the same target removes them.

#![cfg(unix)]

mod common;

use common::*;

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// `gcr solve cornell-box` writing probes to `d/p.txt`, and (`image`) a per-pixel image whose
/// gather runs long after the probes are staged.
fn solve(d: &Path, image: bool) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_gcr"));
    let probes = format!("{ROOT}/scenes/cornell-box.probes.txt");
    let out = d.join("p.txt");
    c.args(["solve", "cornell-box", "--probes", &probes, "--probe-out"])
        .arg(&out)
        .current_dir(ROOT)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    if image {
        c.arg("--image").arg(d.join("i.png"));
        c.args(["--image-mode", "pixel", "--target-error", "0.002"]);
    }
    c
}

/// Waits until a temporary file appears in `d` (the probes are staged); panics after 60 s.
fn wait_for_temp(d: &Path, child: &mut Child) {
    let start = Instant::now();
    while !entries(d).iter().any(|e| e.ends_with(".tmp")) {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("gcr ended ({status}) before staging anything");
        }
        assert!(start.elapsed() < Duration::from_secs(60), "nothing staged");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn signal(child: &Child, name: &str) {
    let ok = Command::new("sh")
        .args(["-c", &format!("kill -{name} {}", child.id())])
        .status()
        .unwrap();
    assert!(ok.success());
}

#[test]
fn sigint_and_sigterm_remove_the_staged_files() {
    for name in ["INT", "TERM"] {
        let d = dir("int", name);
        let mut child = solve(&d, true).spawn().unwrap();
        wait_for_temp(&d, &mut child);
        signal(&child, name);
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "SIG{name}: {err}");
        assert!(err.contains("interrupted"), "SIG{name}: {err}");
        assert!(entries(&d).is_empty(), "SIG{name} left {:?}", entries(&d));
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn the_next_run_removes_what_a_killed_run_left() {
    let d = dir("int", "kill");
    let mut child = solve(&d, true).spawn().unwrap();
    wait_for_temp(&d, &mut child);
    child.kill().unwrap();
    child.wait().unwrap();
    let left = entries(&d);
    assert!(
        left.iter().any(|e| e.starts_with(".p.txt.gcr-")),
        "{left:?}"
    );
    // another process's live temporary file, and another target's, are not touched
    let live = format!(".p.txt.gcr-{}-0.tmp", std::process::id());
    std::fs::write(d.join(&live), "").unwrap();
    std::fs::write(d.join(".q.txt.gcr-1-0.tmp"), "").unwrap();
    let out = solve(&d, false).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let want = [live.as_str(), ".q.txt.gcr-1-0.tmp", "p.txt"];
    assert_eq!(entries(&d), want);
    let _ = std::fs::remove_dir_all(d);
}
