//! Public models for the benches (issue 36, "real models as benchmarks"), fetched from a package
//! registry into a cache outside the repository (`$CARGO_TARGET_DIR/public-models/`), never
//! committed.
//!
//! * **Temple compound** (`samurai_monastry.obj`, 124 990 triangles of which 124 580 are kept
//!   after the loader drops degenerate and duplicate faces; 82 materials, all grey ρ = 0.64,
//!   untextured): a walled courtyard with halls, gates and five pagodas, about 125 × 120 m. It
//!   ships in `pybullet_data` inside the `pybullet` 3.2.7 wheel on PyPI, whose licence is zlib
//!   (the model carries no licence of its own). Fetched with `python3 -m pip download
//!   pybullet==3.2.7 --no-deps` (about 100 MB) and unpacked with Python's `zipfile`.

use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The wheel that carries the temple compound.
const PYBULLET: &str = "pybullet==3.2.7";

/// The temple compound's OBJ (with its MTL beside it), fetched into the cache the first time.
/// Errs with what failed (no network to PyPI, no `python3` or `pip`): the caller skips the case
/// with that note.
pub fn temple_compound() -> Result<PathBuf> {
    let target = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".into());
    let dir = Path::new(&target)
        .join("public-models")
        .join("pybullet-3.2.7");
    let obj = dir.join("samurai_monastry.obj");
    if obj.is_file() && dir.join("samurai_monastry.mtl").is_file() {
        return Ok(obj);
    }
    std::fs::create_dir_all(&dir)?;
    let status = Command::new("python3")
        .args(["-m", "pip", "download", PYBULLET, "--no-deps", "-q", "-d"])
        .arg(&dir)
        .status()
        .context("python3 -m pip not runnable")?;
    if !status.success() {
        bail!("`python3 -m pip download {PYBULLET} --no-deps` failed ({status})");
    }
    let unpack = "import sys, zipfile, glob, os\n\
        d = sys.argv[1]\n\
        w = glob.glob(os.path.join(d, 'pybullet-*.whl'))[0]\n\
        with zipfile.ZipFile(w) as z:\n\
        \x20   for name in ('samurai_monastry.obj', 'samurai_monastry.mtl'):\n\
        \x20       open(os.path.join(d, name), 'wb').write(z.read('pybullet_data/' + name))\n\
        os.remove(w)\n";
    let status = Command::new("python3")
        .args(["-c", unpack])
        .arg(&dir)
        .status()
        .context("python3 not runnable")?;
    if !status.success() || !obj.is_file() {
        bail!("unpacking the pybullet wheel in {} failed", dir.display());
    }
    Ok(obj)
}
