//! All-or-nothing output files: each output is written to a temporary file beside its target
//! (flushed and synced), and only when every output succeeded are they all renamed onto their
//! targets. On any error, or when [`StagedFiles`] is dropped uncommitted, the temporary files are
//! removed and no target is touched.
//!
//! Targets that exist and are not regular files (`/dev/stdout`, a FIFO) cannot be replaced by a
//! rename; they are written directly at commit time, before the renames.
//!
//! Interrupted runs leave nothing behind: every temporary file of the process is registered
//! until it is renamed or removed, and [`remove_temporary_files`] (the `gcr` program calls it on
//! SIGINT, SIGTERM and SIGHUP) removes them all; a commit in progress finishes first, so targets
//! are never half replaced. A run killed outright (SIGKILL, a power cut) cannot clean up: the
//! next run that writes the same target removes the temporary files of processes that no longer
//! exist ([`check_target`]).

use super::OutputError;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes temporary files of one process (with the process id in the name).
static NEXT_TEMP: AtomicU64 = AtomicU64::new(0);

/// The temporary files of this process not yet renamed onto their targets or removed.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The registry of live temporary files (a panic while holding it cannot leave it inconsistent:
/// it is only pushed to and removed from).
fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    LIVE.lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Removes `temp` and forgets it.
fn remove_temp(temp: &Path) {
    let mut live = live();
    let _ = std::fs::remove_file(temp);
    live.retain(|p| p != temp);
}

/// Removes every temporary file of this process, waiting for a commit in progress to finish:
/// for an interrupted run (module docs). Outputs staged afterwards are not affected.
pub fn remove_temporary_files() {
    for temp in live().drain(..) {
        let _ = std::fs::remove_file(temp);
    }
}

/// The temporary files beside `target` left by processes that no longer exist (killed outright):
/// `.NAME.gcr-PID-N.tmp` for the target's NAME. Empty where processes cannot be listed (outside
/// Linux's `/proc`).
fn orphans(target: &Path) -> Vec<PathBuf> {
    let (Some(name), true) = (target.file_name(), Path::new("/proc/self").exists()) else {
        return Vec::new();
    };
    let prefix = format!(".{}.gcr-", name.to_string_lossy());
    let Ok(entries) = std::fs::read_dir(parent_dir(target)) else {
        return Vec::new();
    };
    entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let file = p.file_name().map(|f| f.to_string_lossy().into_owned());
            let pid = file.as_deref().and_then(|f| {
                let rest = f.strip_prefix(&prefix)?.strip_suffix(".tmp")?;
                let (pid, n) = rest.split_once('-')?;
                n.parse::<u64>().ok()?;
                pid.parse::<u32>().ok()
            });
            pid.is_some_and(|pid| !Path::new(&format!("/proc/{pid}")).exists())
        })
        .collect()
}

/// Whether `path` exists and is something other than a regular file or a directory (a device,
/// a FIFO, a socket): written directly, never renamed onto.
pub fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// The directory a target lives in (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Creates a new, empty temporary file beside `target` (same directory, so a rename is atomic).
fn create_temp(target: &Path) -> std::io::Result<(PathBuf, File)> {
    let name = target
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    loop {
        let n = NEXT_TEMP.fetch_add(1, Ordering::Relaxed);
        let temp = parent_dir(target).join(format!(".{name}.gcr-{}-{n}.tmp", std::process::id()));
        let mut live = live();
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(f) => {
                live.push(temp.clone());
                return Ok((temp, f));
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Checks that `target` can be written as an output named `what` (for messages): a missing or
/// regular file with the `extension` (case-insensitive, when given; `png|exr` accepts either) in
/// an existing, writable
/// directory, or an existing special file (then the extension is not checked). Writability is
/// tested by creating and removing a temporary file beside the target; temporary files of the
/// same target left by processes that no longer exist are removed.
pub fn check_target(
    target: &Path,
    what: &'static str,
    extension: Option<&'static str>,
) -> Result<(), OutputError> {
    let path = target.to_path_buf();
    if target.file_name().is_none() {
        return Err(OutputError::NotAFile { what, path });
    }
    match std::fs::metadata(target) {
        Ok(m) if m.is_dir() => return Err(OutputError::NotAFile { what, path }),
        Ok(m) if !m.is_file() => return Ok(()),
        _ => {}
    }
    if let Some(ext) = extension {
        let found = target
            .extension()
            .map(|e| e.to_string_lossy().to_lowercase());
        if !found
            .as_deref()
            .is_some_and(|f| ext.split('|').any(|e| e == f))
        {
            return Err(OutputError::Extension {
                what,
                path,
                expected: ext,
            });
        }
    }
    let dir = parent_dir(target);
    if !dir.is_dir() {
        return Err(OutputError::MissingDirectory {
            what,
            path,
            dir: dir.to_path_buf(),
        });
    }
    let (temp, file) = create_temp(target).map_err(|source| OutputError::NotWritable {
        what,
        path: path.clone(),
        source,
    })?;
    drop(file);
    remove_temp(&temp);
    for orphan in orphans(target) {
        let _ = std::fs::remove_file(orphan);
    }
    Ok(())
}

/// One staged output.
enum Staged {
    /// Written to `temp`, to be renamed onto `target`.
    Temp { temp: PathBuf, target: PathBuf },
    /// A special file: the bytes, written to `target` at commit.
    Direct { bytes: Vec<u8>, target: PathBuf },
}

/// Outputs written to temporary files, renamed onto their targets together by
/// [`StagedFiles::commit`]. Dropping it uncommitted removes the temporary files.
#[derive(Default)]
pub struct StagedFiles {
    files: Vec<Staged>,
}

impl StagedFiles {
    /// No outputs staged yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Stages `target`: runs `write` on a buffered temporary file beside it, flushes and syncs
    /// it. Every I/O error, the final flush's included, is returned naming `target`.
    pub fn write(
        &mut self,
        target: &Path,
        write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), OutputError> {
        let error = |source| OutputError::Write {
            path: target.to_path_buf(),
            source,
        };
        if is_special(target) {
            let mut bytes = Vec::new();
            write(&mut bytes).map_err(error)?;
            self.files.push(Staged::Direct {
                bytes,
                target: target.to_path_buf(),
            });
            return Ok(());
        }
        let (temp, file) = create_temp(target).map_err(error)?;
        // Registered first, so that the temporary file is removed whatever fails below.
        self.files.push(Staged::Temp {
            temp,
            target: target.to_path_buf(),
        });
        let mut w = BufWriter::new(file);
        write(&mut w).map_err(error)?;
        let file = w.into_inner().map_err(|e| error(e.into_error()))?;
        file.sync_all().map_err(error)
    }

    /// Stages `target` with `bytes` as its content.
    pub fn write_bytes(&mut self, target: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        self.write(target, |w| w.write_all(bytes))
    }

    /// Writes the special files, then renames every temporary file onto its target. On an error
    /// the temporary files not yet renamed are removed.
    pub fn commit(mut self) -> Result<(), OutputError> {
        for f in &self.files {
            if let Staged::Direct { bytes, target } = f {
                let error = |source| OutputError::Write {
                    path: target.clone(),
                    source,
                };
                let mut out = OpenOptions::new().write(true).open(target).map_err(error)?;
                out.write_all(bytes).map_err(error)?;
                out.flush().map_err(error)?;
            }
        }
        let files = std::mem::take(&mut self.files);
        let mut rest = files.into_iter();
        // the registry held through the renames: an interrupt waits for them (module docs)
        let mut live = live();
        while let Some(f) = rest.next() {
            if let Staged::Temp { temp, target } = f {
                live.retain(|p| *p != temp);
                if let Err(source) = std::fs::rename(&temp, &target) {
                    let _ = std::fs::remove_file(&temp);
                    drop(live);
                    self.files = rest.collect();
                    return Err(OutputError::Write {
                        path: target,
                        source,
                    });
                }
            }
        }
        Ok(())
    }
}

impl Drop for StagedFiles {
    fn drop(&mut self) {
        for f in &self.files {
            if let Staged::Temp { temp, .. } = f {
                remove_temp(temp);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("gcr-staged-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn nothing_reaches_a_target_before_commit_and_a_failure_leaves_no_file() {
        let d = dir("fail");
        let mut s = StagedFiles::new();
        s.write_bytes(&d.join("a.txt"), b"a").unwrap();
        assert!(!d.join("a.txt").exists());
        let err = s
            .write(&d.join("b.txt"), |w| {
                w.write_all(b"partial")?;
                Err(std::io::Error::other("disk on fire"))
            })
            .unwrap_err();
        assert!(err.to_string().contains("b.txt"), "{err}");
        drop(s);
        assert!(entries(&d).is_empty(), "{:?}", entries(&d));
    }

    #[test]
    fn commit_renames_every_output_and_leaves_no_temporary_file() {
        let d = dir("ok");
        std::fs::write(d.join("a.txt"), "old").unwrap();
        let mut s = StagedFiles::new();
        s.write_bytes(&d.join("a.txt"), b"new").unwrap();
        s.write(&d.join("b.txt"), |w| write!(w, "{}", 42)).unwrap();
        s.commit().unwrap();
        assert_eq!(entries(&d), ["a.txt", "b.txt"]);
        assert_eq!(std::fs::read_to_string(d.join("a.txt")).unwrap(), "new");
        assert_eq!(std::fs::read_to_string(d.join("b.txt")).unwrap(), "42");
    }

    /// A special file is written at commit, and its write error is reported there, naming it.
    #[test]
    fn a_special_targets_write_error_is_reported_at_commit() {
        let d = dir("flush");
        let mut s = StagedFiles::new();
        let r = s.write(Path::new("/dev/full"), |w| w.write_all(b"short"));
        // Special file: buffered in memory, written at commit, where the error must surface.
        r.unwrap();
        let err = s.commit().unwrap_err();
        assert!(err.to_string().contains("/dev/full"), "{err}");
        assert!(entries(&d).is_empty());
    }

    #[test]
    fn targets_are_checked_for_extension_directory_and_kind() {
        let d = dir("check");
        let ok = check_target(&d.join("i.PNG"), "image", Some("png"));
        assert!(ok.is_ok(), "{ok:?}");
        let e = check_target(&d.join("i.bmp"), "image", Some("png")).unwrap_err();
        assert!(e.to_string().contains(".png"), "{e}");
        let e = check_target(&d.join("i.bmp"), "image", Some("png|exr")).unwrap_err();
        assert!(e.to_string().contains("a .png or .exr file"), "{e}");
        assert!(check_target(&d.join("i.exr"), "image", Some("png|exr")).is_ok());
        let e = check_target(&d.join("nodir/m.glb"), "mesh", Some("glb")).unwrap_err();
        assert!(
            matches!(&e, OutputError::MissingDirectory { dir, .. } if dir.ends_with("nodir")),
            "{e}"
        );
        let e = check_target(&d, "metrics", None).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        assert!(check_target(Path::new("/dev/null"), "mesh", Some("glb")).is_ok());
        assert!(entries(&d).is_empty());
    }
}
