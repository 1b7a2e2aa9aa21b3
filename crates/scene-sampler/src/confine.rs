//! What loading a scene may read (issue 35): the scene file, and the files it names inside its own
//! folder, regular files only, each within a size bound.
//!
//! A scene file comes from anywhere (a download, a bug report), and the files it names — glTF
//! buffers and images, an OBJ's material libraries and textures — are paths it chooses. Every such
//! path is resolved against the scene file's folder and refused when it leads outside that folder
//! (`../`, an absolute path, a `file://` URI, a symbolic link out), unless
//! [`LoadOptions::allow_outside`]. The refusal is one message whether or not the file exists, so
//! that a scene cannot probe the file system. Every file read — the scene file itself too — must be
//! a regular file (not `/dev/zero`, a FIFO or a directory: checked before opening) of at most
//! [`LoadOptions::max_file_bytes`] (checked from its size, and again while reading).
//!
//! Resolution follows symbolic links one component at a time (`Folder::locate`), so a path whose
//! last components do not exist is still placed inside or outside the folder by the components that
//! do. What is not covered: a folder changed by someone else while it is being read (a file swapped
//! for a link between the check and the read).

use crate::{Result, SceneError};
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// The default of [`LoadOptions::max_file_bytes`]: 2 GiB.
pub const DEFAULT_MAX_FILE_BYTES: u64 = 2 << 30;
/// The default of [`LoadOptions::max_texture_bytes`]: 1 GiB.
pub const DEFAULT_MAX_TEXTURE_BYTES: u64 = 1 << 30;
/// Symbolic links followed while resolving one path before it counts as outside (a loop).
const MAX_LINKS: usize = 40;

/// What loading a scene may read and decode ([`crate::load_with`]). The [`Default`] is for untrusted
/// files: nothing outside the scene's folder, 2 GiB per file, 1 GiB of decoded texture memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadOptions {
    /// Read files the scene names outside its own folder (`../`, absolute paths, `file://` URIs,
    /// symbolic links leading out). Default `false` (the `gcr` option `--allow-outside-files`).
    pub allow_outside: bool,
    /// The largest file read, in bytes: the scene file, each external glTF buffer and image, each
    /// material library and texture. Default [`DEFAULT_MAX_FILE_BYTES`].
    pub max_file_bytes: u64,
    /// The largest decoded size of all the scene's textures together, in bytes, at 12 bytes per
    /// texel (linear RGB in f32, as [`crate::Texture`] keeps them); an image's size is read from its
    /// header and checked before it is decoded. Default [`DEFAULT_MAX_TEXTURE_BYTES`].
    pub max_texture_bytes: u64,
    /// Read glTF `doubleSided` materials as one-sided (their faces get no back face: half the
    /// faces, for models whose surfaces are closed solids). Default `false`.
    pub single_sided: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            allow_outside: false,
            max_file_bytes: DEFAULT_MAX_FILE_BYTES,
            max_texture_bytes: DEFAULT_MAX_TEXTURE_BYTES,
            single_sided: false,
        }
    }
}

/// Why a file a scene names was not read.
#[derive(Debug)]
pub(crate) enum Refusal {
    /// It lies outside the scene's folder: the caller says what named it.
    Outside,
    /// Not a regular file, or too large: the error names the file.
    Refused(SceneError),
    /// The file system's error (inside the folder: a missing file is reported as missing).
    Io(std::io::Error),
}

/// Reads `path` if it is a regular file of at most `limit` bytes; `shown` names it in errors.
///
/// The type is checked before opening (opening a FIFO blocks until someone writes to it) and again
/// on the opened file; the size from the metadata, and while reading (files such as those of
/// `/proc` report a size of 0).
pub(crate) fn read_bounded(
    path: &Path,
    shown: &Path,
    limit: u64,
) -> std::result::Result<Vec<u8>, Refusal> {
    let refuse_type = || Refusal::Refused(SceneError::NotRegularFile { path: shown.into() });
    let too_large = || {
        Refusal::Refused(SceneError::FileTooLarge {
            path: shown.into(),
            limit,
        })
    };
    let meta = std::fs::metadata(path).map_err(Refusal::Io)?;
    if !meta.is_file() {
        return Err(refuse_type());
    }
    if meta.len() > limit {
        return Err(too_large());
    }
    let file = std::fs::File::open(path).map_err(Refusal::Io)?;
    let meta = file.metadata().map_err(Refusal::Io)?;
    if !meta.is_file() {
        return Err(refuse_type());
    }
    let mut bytes = Vec::with_capacity(meta.len().min(limit) as usize);
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(Refusal::Io)?;
    if bytes.len() as u64 > limit {
        return Err(too_large());
    }
    Ok(bytes)
}

/// Reads a file the user named (a scene file, a probe file): a regular file of at most `limit`
/// bytes, else an error naming it.
///
/// # Errors
/// [`SceneError::NotRegularFile`], [`SceneError::FileTooLarge`], or [`SceneError::Io`].
pub fn read_regular_file(path: &Path, limit: u64) -> Result<Vec<u8>> {
    read_bounded(path, path, limit).map_err(|r| match r {
        Refusal::Refused(e) => e,
        Refusal::Io(source) => SceneError::Io {
            path: path.into(),
            source,
        },
        // not produced by `read_bounded`
        Refusal::Outside => SceneError::NotRegularFile { path: path.into() },
    })
}

/// [`read_regular_file`] as UTF-8 text (an error like `std::fs::read_to_string`'s if it is not).
pub(crate) fn read_regular_text(path: &Path, limit: u64) -> Result<String> {
    let bytes = read_regular_file(path, limit)?;
    String::from_utf8(bytes).map_err(|_| SceneError::Io {
        path: path.into(),
        source: std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        ),
    })
}

/// A scene file's folder: the files the scene names are resolved against it, and must stay in it
/// unless allowed.
#[derive(Debug)]
pub(crate) struct Folder {
    /// The folder as the scene's path gives it (empty for a file name alone): names in messages
    /// and of textures join it, as before confinement.
    base: PathBuf,
    /// The folder's canonical path: every file read must be in it or below.
    root: PathBuf,
    /// The bounds.
    pub options: LoadOptions,
}

impl Folder {
    /// The folder of the scene file `scene` (which has been read, so the folder exists).
    pub(crate) fn of(scene: &Path, options: &LoadOptions) -> Result<Self> {
        let base = scene.parent().unwrap_or(Path::new("")).to_path_buf();
        let dir = if base.as_os_str().is_empty() {
            Path::new(".")
        } else {
            &base
        };
        let root = dir.canonicalize().map_err(|source| SceneError::Io {
            path: dir.into(),
            source,
        })?;
        Ok(Self {
            base,
            root,
            options: *options,
        })
    }

    /// `name` (relative to the folder, or absolute) as messages show it: joined to the folder as the
    /// scene's path gives it.
    pub(crate) fn shown(&self, name: &Path) -> PathBuf {
        self.base.join(name)
    }

    /// The path to open for `name`, or `None` if it leads outside the folder and that is not allowed.
    pub(crate) fn locate(&self, name: &Path) -> Option<PathBuf> {
        let joined = self.root.join(name);
        if self.options.allow_outside {
            return Some(joined);
        }
        settle(&joined, 0).filter(|p| p.starts_with(&self.root))
    }

    /// Reads the file `name` within the folder and the size bound.
    pub(crate) fn read(&self, name: &Path) -> std::result::Result<Vec<u8>, Refusal> {
        let path = self.locate(name).ok_or(Refusal::Outside)?;
        read_bounded(&path, &self.shown(name), self.options.max_file_bytes)
    }
}

/// Where the absolute path `path` leads: its symbolic links followed component by component (as
/// the operating system does), `.` dropped and `..` taken back a component of what is resolved so
/// far; components that do not exist are kept as written. `None` after [`MAX_LINKS`] links (a loop).
fn settle(path: &Path, links: usize) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    let mut links = links;
    for c in path.components() {
        match c {
            Component::Prefix(_) | Component::RootDir => out.push(c),
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            Component::Normal(n) => {
                out.push(n);
                let is_link = std::fs::symlink_metadata(&out).is_ok_and(|m| m.is_symlink());
                if is_link {
                    links += 1;
                    if links > MAX_LINKS {
                        return None;
                    }
                    let target = std::fs::read_link(&out).ok()?;
                    out.pop();
                    // a relative target is relative to the link's folder; an absolute one replaces it
                    out = settle(&out.join(target), links)?;
                }
            }
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settle_takes_dot_dot_back_and_keeps_missing_components() {
        let p = settle(Path::new("/a/b/../c/./d"), 0).unwrap();
        assert_eq!(p, Path::new("/a/c/d"));
        assert_eq!(settle(Path::new("/../x"), 0).unwrap(), Path::new("/x"));
    }

    #[test]
    fn defaults_confine_and_bound() {
        let o = LoadOptions::default();
        assert!(!o.allow_outside);
        assert_eq!(o.max_file_bytes, 2_147_483_648);
        assert_eq!(o.max_texture_bytes, 1_073_741_824);
    }
}
