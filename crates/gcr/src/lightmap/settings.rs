//! What a lightmap holds and how it is laid out, and why a bake can fail.

use crate::estimator::GatherError;
use thiserror::Error;

/// What a lightmap's texels hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightmapQuantity {
    /// Irradiance E at the surface (W/m², or lux with photometric lights): what engines multiply
    /// by the material's albedo (three.js: `lightMap` × diffuse colour / π gives the radiance).
    /// Smooth where the albedo is textured, so a coarse map holds it.
    #[default]
    Irradiance,
    /// Radiosity B = E + ρ·E_irr (exitance, emission included): the surface's own brightness.
    Radiosity,
}

impl std::str::FromStr for LightmapQuantity {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "irradiance" => Ok(Self::Irradiance),
            "radiosity" => Ok(Self::Radiosity),
            other => Err(format!(
                "unknown lightmap quantity `{other}` (expected irradiance or radiosity)"
            )),
        }
    }
}

/// How a lightmap is laid out and what it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightmapSettings {
    /// Texels per scene unit (`None`: the highest density at which the atlas fits one page).
    pub texels_per_unit: Option<f64>,
    /// Page width and height in texels (several pages when the atlas does not fit one).
    pub page_size: u32,
    /// Empty texels around each chart (filled by dilation).
    pub padding: u32,
    /// What the texels hold.
    pub quantity: LightmapQuantity,
    /// Denoise the texels (`lightmap/denoise.rs`: each texel averaged over the neighbourhood its
    /// SURE says is best, the error estimate with the blur in it).
    pub denoise: bool,
}

impl Default for LightmapSettings {
    fn default() -> Self {
        Self {
            texels_per_unit: None,
            page_size: 512,
            padding: 2,
            quantity: LightmapQuantity::Irradiance,
            denoise: false,
        }
    }
}

/// The largest page side, in texels (16 384² RGB f32 texels are 3 GiB).
pub const MAX_PAGE_SIZE: u32 = 16_384;

/// The most texels a bake may hold over all its pages (2²⁸: 16 pages of 4096², about 13 GiB
/// with the bake's per-texel state); more is refused before anything is estimated.
pub const MAX_TEXELS: u64 = 1 << 28;

/// The memory a bake of `pages` pages of `width × height` texels takes at most, in bytes: per
/// page texel the value (12), the filled flag (1) and the rasterizer's candidate (32), and per
/// covered texel its point (64) and its estimate (160); `denoise`d, per texel also the
/// denoiser's state (`lightmap/denoise.rs`: two samples of 144, the guide's estimate and the
/// denoised copy of 112 each, the chosen value and blend 96, the page's index 4).
pub fn bake_bytes(pages: u32, width: u32, height: u32, denoise: bool) -> u64 {
    let texels = u64::from(pages) * u64::from(width) * u64::from(height);
    let denoiser = if denoise {
        2 * 144 + 2 * 112 + 96 + 4
    } else {
        0
    };
    texels * (12 + 1 + 32 + 64 + 160 + denoiser)
}

impl LightmapSettings {
    /// Checks the settings: a density finite and positive, a page of 16 to `MAX_PAGE_SIZE`
    /// texels, padding below a quarter of the page.
    pub fn validate(&self) -> Result<(), LightmapError> {
        let bad = |m: String| Err(LightmapError::Settings(m));
        if let Some(t) = self.texels_per_unit {
            if !(t.is_finite() && t > 0.0) {
                return bad(format!("the texel density must be positive (got {t})"));
            }
        }
        if !(16..=MAX_PAGE_SIZE).contains(&self.page_size) {
            return bad(format!(
                "the page size must be 16 to {MAX_PAGE_SIZE} texels (got {})",
                self.page_size
            ));
        }
        if self.padding >= self.page_size / 4 {
            return bad(format!(
                "the padding ({}) must be below a quarter of the page ({})",
                self.padding, self.page_size
            ));
        }
        Ok(())
    }
}

/// Why a lightmap could not be baked.
#[derive(Debug, Error)]
pub enum LightmapError {
    /// A setting is out of range.
    #[error("lightmap: {0}")]
    Settings(String),
    /// The unwrapper failed (e.g. a chart larger than a page at the density asked for).
    #[error(
        "lightmap atlas: {message} (lower the texel density or raise the page size, now {page_size})"
    )]
    Unwrap {
        /// The unwrapper's message.
        message: String,
        /// The page size asked for.
        page_size: u32,
    },
    /// Lightmaps need a 3-D scene.
    #[error("lightmaps need a 3-D scene")]
    NotThreeD,
    /// The atlas needs more texels than a bake may hold (`MAX_TEXELS`).
    #[error(
        "lightmap atlas: {pages} page(s) of {width} × {height} texels are {texels} texels, more \
         than {max} (about {gib:.1} GiB to bake): lower the texel density"
    )]
    TooLarge {
        /// Pages.
        pages: u32,
        /// Page width.
        width: u32,
        /// Page height.
        height: u32,
        /// Their texels.
        texels: u64,
        /// The limit.
        max: u64,
        /// The memory they would take.
        gib: f64,
    },
    /// The gather at the texels failed.
    #[error(transparent)]
    Gather(#[from] GatherError),
}
