//! What an image output takes in memory, estimated before the solve, against what the machine
//! has: a `--resolution 16384x16384` image used to abort on a 24 GiB allocation after the whole
//! solve; now it is refused before, with the largest resolution of its aspect that fits.
//!
//! The estimate is per pixel and per view (views are rendered one after the other):
//!
//! - **mesh images** (`output/raster.rs`): `ss² = 4` sub-samples of B (3 × f64), depth (f64) and
//!   what was seen (1 byte): 132 bytes; their reduction to pixels (B, depth: 32 bytes); the
//!   8-bit pixels and depth kept for overlays (11 bytes), or the f32 radiance of an EXR (12):
//!   176 bytes; [`MESH_BYTES_PER_PIXEL`] = 192 leaves room for the allocator. Measured: 171–173
//!   bytes a pixel (peak RSS, Cornell box, 1024² − 512² and 640² − 256², PNG and EXR).
//! - **pixel images** of the default paths gather (`output/pixel.rs`): the footprint gather keeps
//!   per pixel its centre's hit, the running sums of its rounds and its sample points:
//!   [`PIXEL_BYTES_PER_PIXEL`] = 800, over the 736 bytes a pixel measured the same way (Cornell
//!   box, `--quality draft`, 1024² − 512²). With a gather that reads the networks, every
//!   sub-sample (`--pixel-samples`) is a point of its own: that times the sub-samples.
//!
//! - **probes** (and any points the paths gather runs to a target): per point its placement, its
//!   group, its seeds, its estimates and the rounds' state: [`PROBE_BYTES`] = 1 152, over the
//!   861–994 bytes a probe measured (Cornell box, 5 000 → 25 000 and 20 000 → 100 000 probes,
//!   radiosity and irradiance, peak RSS from the metrics); about 1 040 for 50 000 lone probes
//!   (`--share-paths 1`) on the door gap, unguided or `--guiding auto` left unguided (61 MB at
//!   the peak less a 2 000-probe run's 9 MB; 2 800 before a group's guide took memory only
//!   once guided). With `--guiding on`, the guides
//!   of as many groups as probes, a round's records and the spatial guides on top
//!   (`estimator::guide::guiding_bytes`; `auto` guides only where they fit, in the rounds).
//!
//! The machine's memory is Linux's `MemAvailable`, lowered to a cgroup v2 limit when one is set
//! (containers, CI runners); elsewhere nothing is checked.

use super::camera::{ImageMode, ImageSettings};
pub use crate::metrics::available_memory;
use crate::metrics::gib;

/// An image that would take more memory than is available.
#[derive(Debug, thiserror::Error)]
#[error(
    "image {width}x{height}: about {} at its peak, more than the {} available: choose a \
     smaller --resolution ({}x{} fits)",
    gib(*needed),
    gib(*available),
    fits.0,
    fits.1
)]
pub struct ImageTooLarge {
    /// The image's width.
    pub width: u32,
    /// The image's height.
    pub height: u32,
    /// Bytes it would take ([`image_bytes`]).
    pub needed: u64,
    /// Bytes available ([`available_memory`]).
    pub available: u64,
    /// The largest resolution of its aspect that takes at most 80 % of `available`.
    pub fits: (u32, u32),
}

/// Bytes a pixel of a mesh image takes at its peak (module docs).
pub const MESH_BYTES_PER_PIXEL: u64 = 192;

/// Bytes a pixel of a per-pixel image takes at its peak with the default paths gather (module
/// docs).
pub const PIXEL_BYTES_PER_PIXEL: u64 = 800;

/// Bytes a probe takes at the gather's peak (module docs).
pub const PROBE_BYTES: u64 = 1152;

/// Probes that would take more memory than is available.
#[derive(Debug, thiserror::Error)]
#[error(
    "{probes} probes: about {} at the gather's peak, more than the {} available: split them \
     over machines (--block-points and --shard, docs/guide/probes.md) or give fewer{}",
    gib(*needed),
    gib(*available),
    if *guided { ", or leave guiding to --guiding auto (it guides only where the guides fit)" } else { "" }
)]
pub struct TooManyProbes {
    /// The probes.
    pub probes: usize,
    /// Whether their guides (`--guiding on`) are counted.
    pub guided: bool,
    /// Bytes they would take.
    pub needed: u64,
    /// Bytes available.
    pub available: u64,
}

/// Refuses `probes` probes that would take more than `available` bytes (none: no check).
pub(crate) fn check_probe_memory(
    probes: usize,
    guided: bool,
    available: Option<u64>,
) -> Result<(), TooManyProbes> {
    let mut needed = (probes as u64).saturating_mul(PROBE_BYTES);
    if guided && probes > 0 {
        needed = needed.saturating_add(crate::estimator::guide::guiding_bytes(probes));
    }
    match available {
        Some(available) if needed > available => Err(TooManyProbes {
            probes,
            guided,
            needed,
            available,
        }),
        _ => Ok(()),
    }
}

/// The output mesh's vertices that one gather may take in `available` bytes (none: no limit):
/// each is a point of the paths gather, as a probe ([`PROBE_BYTES`]). Measured on the temple
/// compound (`--mesh`, RSS sampled every second): its gather of 340 671 starting vertices peaked
/// at 419 MB over the 119 MB its scene and BVH hold, about 880 bytes a vertex; the refinement
/// levels of 57 034 … 201 900 new vertices at 360 … 606 MB, the mesh beside them growing to
/// its final 829 904 vertices (`--image --mesh`: 632 MB).
pub(crate) fn mesh_points_that_fit(available: Option<u64>) -> usize {
    available.map_or(usize::MAX, |a| (a / PROBE_BYTES) as usize)
}

/// Refuses an output mesh of `points` vertices to gather that would take more than `available`
/// bytes (none: no check), before they are gathered; else the vertices one gather may take
/// ([`mesh_points_that_fit`]).
pub(crate) fn check_mesh_memory(
    points: usize,
    available: Option<u64>,
) -> Result<usize, crate::estimator::GatherError> {
    let fits = mesh_points_that_fit(available);
    if points > fits {
        return Err(crate::estimator::GatherError::MeshMemory {
            points,
            needed: (points as u64).saturating_mul(PROBE_BYTES),
            available: available.unwrap_or(u64::MAX),
        });
    }
    Ok(fits)
}

/// The peak bytes one image of `settings` takes (`footprints`: a pixel image is gathered over
/// pixel footprints by the paths gather, not point by point per sub-sample).
pub fn image_bytes(settings: &ImageSettings, footprints: bool) -> u64 {
    let pixels = u64::from(settings.width) * u64::from(settings.height);
    let per_pixel = match settings.mode {
        ImageMode::Mesh => MESH_BYTES_PER_PIXEL,
        ImageMode::Pixel if footprints => PIXEL_BYTES_PER_PIXEL,
        ImageMode::Pixel => PIXEL_BYTES_PER_PIXEL * u64::from(settings.pixel_samples.max(1)),
    };
    pixels.saturating_mul(per_pixel)
}

/// Refuses an image of `settings` that would take more than `available` bytes (none: no check),
/// naming the memory it needs and the largest resolution of its aspect that takes at most 80 %
/// of what is available (the rest is room for the solve).
pub(crate) fn check_image_memory(
    settings: &ImageSettings,
    footprints: bool,
    available: Option<u64>,
) -> Result<(), ImageTooLarge> {
    let (Some(available), needed) = (available, image_bytes(settings, footprints)) else {
        return Ok(());
    };
    if needed <= available {
        return Ok(());
    }
    // the same aspect, scaled to take at most 80 % (room for the solve), rounded down to whole
    // multiples of 16 pixels
    let scale = (0.8 * available as f64 / needed as f64).sqrt();
    let fit = |side: u32| ((f64::from(side) * scale) as u32 / 16 * 16).max(1);
    Err(ImageTooLarge {
        width: settings.width,
        height: settings.height,
        needed,
        available,
        fits: (fit(settings.width), fit(settings.height)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(width: u32, height: u32, mode: ImageMode) -> ImageSettings {
        ImageSettings {
            width,
            height,
            mode,
            ..ImageSettings::default()
        }
    }

    #[test]
    fn the_largest_resolution_is_refused_with_one_that_fits() {
        let big = settings(16384, 16384, ImageMode::Mesh);
        assert_eq!(image_bytes(&big, true), 16384 * 16384 * 192);
        let fits = check_image_memory(&big, true, Some(8 << 30))
            .unwrap_err()
            .fits;
        let fitted = settings(fits.0, fits.1, ImageMode::Mesh);
        assert!(image_bytes(&fitted, true) as f64 <= 0.8 * (8u64 << 30) as f64);
        assert!(fits.0 > 5500, "{fits:?}: not the largest that fits");
        let message = check_image_memory(&big, true, Some(8 << 30))
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("16384x16384")
                && message.contains("48.0 GiB")
                && message.contains("8.0 GiB available")
                && message.contains(&format!("{}x{}", fits.0, fits.1)),
            "{message}"
        );
        assert!(check_image_memory(&fitted, true, Some(8 << 30)).is_ok());
        assert!(check_image_memory(&big, true, None).is_ok());
    }

    #[test]
    fn pixel_images_count_their_sub_samples_unless_gathered_over_footprints() {
        let mut s = settings(100, 50, ImageMode::Pixel);
        s.pixel_samples = 4;
        assert_eq!(image_bytes(&s, true), 5000 * PIXEL_BYTES_PER_PIXEL);
        assert_eq!(image_bytes(&s, false), 4 * 5000 * PIXEL_BYTES_PER_PIXEL);
    }

    #[test]
    fn probes_beyond_memory_are_refused() {
        assert!(check_probe_memory(1_000_000, false, Some(2 << 30)).is_ok());
        let err = check_probe_memory(10_000_000, false, Some(2 << 30)).unwrap_err();
        assert_eq!(err.needed, 11_520_000_000);
        let message = err.to_string();
        assert!(
            message.contains("10000000 probes: about 10.7 GiB") && message.contains("--shard"),
            "{message}"
        );
        assert!(!message.contains("--guiding"), "{message}");
        assert!(check_probe_memory(10_000_000, false, None).is_ok());
        // guided: their guides count too
        assert!(check_probe_memory(500_000, false, Some(1 << 30)).is_ok());
        let err = check_probe_memory(500_000, true, Some(1 << 30)).unwrap_err();
        assert!(err.needed > 1 << 30, "{}", err.needed);
        assert!(err.to_string().contains("--guiding auto"), "{err}");
    }

    #[test]
    fn mesh_points_fit_as_probes_do() {
        assert_eq!(mesh_points_that_fit(None), usize::MAX);
        assert_eq!(mesh_points_that_fit(Some(1152 * 1000 + 5)), 1000);
        let fits = mesh_points_that_fit(Some(2 << 30));
        assert!(check_probe_memory(fits, false, Some(2 << 30)).is_ok());
        assert!(check_probe_memory(fits + 1, false, Some(2 << 30)).is_err());
        assert_eq!(check_mesh_memory(fits, Some(2 << 30)).unwrap(), fits);
        let message = check_mesh_memory(3_000_000, Some(2 << 30))
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("3000000 vertices")
                && message.contains("3.2 GiB")
                && message.contains("2.0 GiB available")
                && message.contains("leave out --mesh"),
            "{message}"
        );
    }

    #[test]
    fn available_memory_is_read_on_linux() {
        if cfg!(target_os = "linux") {
            let m = available_memory().unwrap();
            assert!(m > 1 << 20, "{m}");
        }
    }
}
