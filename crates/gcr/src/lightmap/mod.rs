//! Lightmaps: the scene's light baked into textures on a second UV set, as game engines and web
//! viewers display it (Unity's and Godot's lightmappers, Bevy's `Lightmap`, three.js' `lightMap`).
//!
//! [`bake_lightmap`] in four steps (a sharded bake runs them apart: `output/shards.rs`):
//!
//! 1. **The atlas** (`atlas.rs`): every face a place on a page, at a texel density;
//! 2. **the texels' points** (`texels.rs`): a point on the surface per covered texel (chart rims
//!    included), texels under geometry left out so that no light or darkness leaks;
//! 3. **the estimate** at every texel point by the default estimator
//!    ([`crate::irradiance_at_points`] or [`crate::radiosity_at_points`]), run to the solve's
//!    target error, neighbouring texels sharing paths as any neighbouring output points do;
//! 4. **dilation** (`dilate.rs`): the left-out texels and the padding around every chart take the
//!    mean of their filled neighbours, so that bilinear filtering and mipmaps at a chart's edge
//!    read the chart's own values (no seams of black).
//!
//! The writers (OpenEXR pages, 8-bit PNG pages with their scale, the glTF with `TEXCOORD_1` and
//! the lightmap referenced) are in `output/lightmap.rs`.

mod atlas;
mod denoise;
mod dilate;
mod settings;
mod texels;

pub use atlas::{Atlas, FaceUv};
pub use denoise::DenoiseReport;
pub use settings::{LightmapError, LightmapQuantity, LightmapSettings};
pub use texels::Texel;

use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::estimator::{GatherStats, irradiance_at_shard, radiosity_at_shard};
use crate::gather::Gathered;
use crate::solve::Trained;

/// A baked lightmap: the atlas and its pages of linear values.
#[derive(Clone, Debug)]
pub struct Lightmap {
    /// The atlas the pages follow.
    pub atlas: Atlas,
    /// Per page, `width × height` RGB values, row-major, row 0 at v = 0.
    pub pages: Vec<Vec<[f32; 3]>>,
    /// What they hold.
    pub quantity: LightmapQuantity,
    /// The texels estimated, with their surface points (in the order of the gather).
    pub texels: Vec<Texel>,
    /// Texels left out because their point lay under geometry (filled by dilation).
    pub left_out: usize,
    /// What the gather at the texels measured (its estimated relative error among them; with
    /// [`LightmapSettings::denoise`], the denoised values').
    pub stats: GatherStats,
    /// What the denoiser did, when it ran.
    pub denoised: Option<DenoiseReport>,
}

impl Lightmap {
    /// The lightmap's value at `point` of face `face` as a viewer reads it: the point's
    /// coordinates on the atlas (from its barycentrics in the face) filtered bilinearly, texel
    /// centres at half-integers, clamped at the page's edges. `None` for a face with no place.
    pub fn sample(
        &self,
        scene: &scene_sampler::Scene,
        face: u32,
        point: glam::DVec3,
    ) -> Option<[f32; 3]> {
        let uv = self.atlas.faces.get(face as usize).copied().flatten()?;
        let f = &scene.faces[face as usize];
        let (e1, e2, d) = (f.v[1] - f.v[0], f.v[2] - f.v[0], point - f.v[0]);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = d11 * d22 - d12 * d12;
        if det <= 0.0 {
            return None;
        }
        let (p1, p2) = (d.dot(e1), d.dot(e2));
        let b1 = (d22 * p1 - d12 * p2) / det;
        let b2 = (d11 * p2 - d12 * p1) / det;
        let at = |k: usize| {
            f64::from(uv.uv[0][k]) * (1.0 - b1 - b2)
                + f64::from(uv.uv[1][k]) * b1
                + f64::from(uv.uv[2][k]) * b2
        };
        let (w, h) = (self.atlas.width as usize, self.atlas.height as usize);
        let x = (at(0) * w as f64 - 0.5).clamp(0.0, (w - 1) as f64);
        let y = (at(1) * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
        let page = &self.pages[uv.page as usize];
        let texel = |x: usize, y: usize| page[y * w + x];
        let mut out = [0.0f32; 3];
        for (k, o) in out.iter_mut().enumerate() {
            let top = texel(x0, y0)[k] * (1.0 - fx) + texel(x1, y0)[k] * fx;
            let bottom = texel(x0, y1)[k] * (1.0 - fx) + texel(x1, y1)[k] * fx;
            *o = top * (1.0 - fy) + bottom * fy;
        }
        Some(out)
    }
}

/// The texels a lightmap estimates: the atlas and a surface point per covered texel (steps 1
/// and 2 of the module docs). A function of the scene and the settings alone, so that the
/// shards of a bake and the run that merges them lay out the same texels.
#[derive(Clone, Debug)]
pub struct LightmapTexels {
    /// The atlas.
    pub atlas: Atlas,
    /// The texels to estimate, in the order of the gather.
    pub texels: Vec<Texel>,
    /// Texels left out because their point lay under geometry (filled by dilation).
    pub left_out: usize,
}

impl LightmapTexels {
    /// The points the gather estimates, as [`crate::radiosity_at_points`] takes them (point,
    /// normal, face; the irradiance gather ignores the face).
    pub fn points(&self) -> Vec<(glam::DVec3, glam::DVec3, u32)> {
        (self.texels.iter())
            .map(|t| (t.point, t.normal, t.face))
            .collect()
    }
}

/// Bakes the lightmap of a solved 3-D scene (module docs): [`lay_out_texels`], [`gather_texels`],
/// [`assemble_lightmap`].
pub fn bake_lightmap(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    settings: &LightmapSettings,
) -> Result<Lightmap, LightmapError> {
    let texels = lay_out_texels(domain, settings)?;
    let guide = if settings.denoise {
        Some(gather_guide(domain, trained, config, settings, &texels)?)
    } else {
        None
    };
    let (gathered, _) =
        gather_texels(domain, trained, config, settings, (&texels, guide.as_ref()))?;
    Ok(assemble_lightmap(
        domain,
        texels,
        &gathered,
        guide.as_ref(),
        settings,
    ))
}

/// Steps 1 and 2: the atlas and the texels' points ([`LightmapTexels`]).
pub fn lay_out_texels(
    domain: &Domain,
    settings: &LightmapSettings,
) -> Result<LightmapTexels, LightmapError> {
    settings.validate()?;
    let Domain::ThreeD(kernel) = domain else {
        return Err(LightmapError::NotThreeD);
    };
    // ⟨The atlas and the texels' points⟩
    // (the surface alone, at the density asked for, must fit the bound before anything is
    // unwrapped: the unwrapper's packing allocates its pages)
    if let Some(t) = settings.texels_per_unit {
        let area: f64 = kernel.scene.faces.iter().map(|f| f.area).sum();
        let texels = area * t * t;
        if texels > settings::MAX_TEXELS as f64 {
            let side = (texels.sqrt().ceil() as u64).min(u64::from(u32::MAX)) as u32;
            return Err(LightmapError::TooLarge {
                pages: 1,
                width: side,
                height: side,
                texels: texels as u64,
                max: settings::MAX_TEXELS,
                gib: settings::bake_bytes(1, side, side, settings.denoise) as f64
                    / (1u64 << 30) as f64,
            });
        }
    }
    let atlas = Atlas::of_scene(kernel.scene, settings)?;
    let texels = u64::from(atlas.pages) * u64::from(atlas.width) * u64::from(atlas.height);
    if texels > settings::MAX_TEXELS {
        return Err(LightmapError::TooLarge {
            pages: atlas.pages,
            width: atlas.width,
            height: atlas.height,
            texels,
            max: settings::MAX_TEXELS,
            gib: settings::bake_bytes(atlas.pages, atlas.width, atlas.height, settings.denoise)
                as f64
                / (1u64 << 30) as f64,
        });
    }
    let (texels, left_out) = texels::texels(kernel.scene, kernel.bvh, &atlas);
    Ok(LightmapTexels {
        atlas,
        texels,
        left_out,
    })
}

/// Step 3: the estimate at every texel, and the indices (ascending) of the texels estimated:
/// with a shard in `config`, the shard's texels only, the others left at `Gathered::default()`
/// ([`crate::shard_points`]); else every one. With a denoiser's `guide` ([`gather_guide`]) and a
/// target error, the rounds stop when the denoised texels meet the target
/// (`lightmap/denoise.rs`, block by block).
pub fn gather_texels(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    settings: &LightmapSettings,
    (texels, guide): (&LightmapTexels, Option<&LightmapGuide>),
) -> Result<(Vec<Gathered>, Vec<usize>), LightmapError> {
    let emitters = Emitters::new(domain);
    let at = texels.points();
    let material = texel_materials(domain, &texels.texels, settings.quantity);
    let stop = |members: &[usize], values: &[Gathered]| -> Option<f64> {
        let guide = guide?;
        let pick = |i: &usize| texels.texels[*i];
        let block: Vec<Texel> = members.iter().map(pick).collect();
        let block_guide: Vec<Gathered> = members.iter().map(|&i| guide.values[i]).collect();
        let block_material: Option<Vec<_>> =
            (material.as_ref()).map(|m| members.iter().map(|&i| m[i]).collect());
        let values = (values, &block_guide[..]);
        let (bound, chosen) =
            denoise::denoised_error(&texels.atlas, &block, values, block_material.as_deref());
        // (the last test's samples and choice are the final pass's, if it saw the same values)
        *guide.last.lock().unwrap_or_else(|e| e.into_inner()) = chosen;
        bound
    };
    let stop = guide.map(|_| &stop as &crate::estimator::StopOn);
    Ok(match settings.quantity {
        LightmapQuantity::Irradiance => {
            let at: Vec<_> = at.iter().map(|&(p, n, _)| (p, n)).collect();
            irradiance_at_shard(domain, trained, &emitters, config, (&at, stop))?
        }
        LightmapQuantity::Radiosity => {
            radiosity_at_shard(domain, trained, &emitters, config, (&at, stop))?
        }
    })
}

/// Each texel's (ρ, E) for a radiosity lightmap (what the denoiser demodulates by); None for
/// irradiance.
fn texel_materials(
    domain: &Domain,
    texels: &[Texel],
    quantity: LightmapQuantity,
) -> Option<Vec<(crate::element::Bands, crate::element::Bands)>> {
    (quantity == LightmapQuantity::Radiosity).then(|| {
        (texels.iter())
            .map(|t| {
                (
                    domain.reflectance_at(t.face, t.point),
                    domain.emission(t.face),
                )
            })
            .collect()
    })
}

/// The denoiser's guide ([`gather_guide`]): its values, and the samples that the rounds' last
/// stopping test prepared and the candidates it chose (`lightmap/denoise.rs`), so that the final
/// pass does not prepare and choose again when it denoises the values that test saw (some 0.5 s
/// of a 230 000-texel bake).
pub struct LightmapGuide {
    values: Vec<Gathered>,
    last: std::sync::Mutex<Option<denoise::Chosen>>,
}

impl LightmapGuide {
    /// The guide's estimates, one per texel (every second texel of every second row; the others
    /// `Gathered::default()`).
    pub fn values(&self) -> &[Gathered] {
        &self.values
    }
}

/// Rays per texel of the denoiser's guide ([`gather_guide`]).
pub const GUIDE_RAYS: usize = 8;

/// Rays per texel of the guide's second look where its first [`GUIDE_RAYS`] found no light.
pub const GUIDE_DARK_RAYS: usize = 64;

/// The denoiser's guide (`lightmap/denoise.rs`): an estimate with [`GUIDE_RAYS`] rays of its own
/// (the solve's seed salted), independent of [`gather_texels`]' values, at every second texel of
/// every second row (the others left at `Gathered::default()`); of the whole lightmap, also in a
/// shard's run, so that every run that denoises has the same guide.
///
/// Where those rays found no light, the texel is estimated again with [`GUIDE_DARK_RAYS`] rays of
/// yet another seed, and that estimate stands (it is independent of the first, so choosing
/// where by the first biases nothing). The denoiser mixes texels the guide finds dark only with
/// each other (a closed room's texels, which must not take light from the lit room across a
/// wall), so a lit texel called dark by chance is left with a few, mostly unlit neighbours: on
/// the sun patch room's 2 % page, where a texel by a wall finds light in one ray of ten, 8 rays
/// alone left 349 texels below 0.3× the reference; the second look, 27 (a raw bake: 42), for
/// 0.3 s more.
pub fn gather_guide(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    settings: &LightmapSettings,
    texels: &LightmapTexels,
) -> Result<LightmapGuide, LightmapError> {
    let _phase = crate::progress::phase("denoiser's guide");
    let mut which: Vec<usize> = (0..texels.texels.len())
        .filter(|&i| denoise::guides(&texels.texels[i]))
        .collect();
    let mut out = vec![Gathered::default(); texels.texels.len()];
    for (pass, rays) in [(0, GUIDE_RAYS), (1, GUIDE_DARK_RAYS)] {
        let values = guide_pass(
            domain,
            trained,
            (config, rays, pass),
            settings,
            texels,
            &which,
        )?;
        for (&i, v) in which.iter().zip(values) {
            out[i] = v;
        }
        // ⟨The next look: where this one found no light⟩
        which.retain(|&i| out[i].radiosity == domain.emission(texels.texels[i].face));
    }
    Ok(LightmapGuide {
        values: out,
        last: std::sync::Mutex::new(None),
    })
}

/// One pass of [`gather_guide`] at `texels`' texels `which`, with `rays` rays each, one round,
/// the seed salted by `pass`.
fn guide_pass(
    domain: &Domain,
    trained: &Trained,
    (config, rays, pass): (&SolveConfig, usize, u64),
    settings: &LightmapSettings,
    texels: &LightmapTexels,
    which: &[usize],
) -> Result<Vec<Gathered>, LightmapError> {
    if which.is_empty() {
        return Ok(Vec::new());
    }
    let guide = SolveConfig {
        seed: config.seed ^ GUIDE_SALT ^ pass.wrapping_mul(0x9e37_79b9_7f4a_7c15),
        gather_samples: crate::config::GatherSamples {
            direct: rays,
            indirect: rays,
        },
        paths: crate::config::PathSettings {
            // one round of the guide's rays (the target cannot stop it earlier)
            target_error: Some(f64::MIN_POSITIVE),
            max_rays: rays,
            block_points: usize::MAX,
            shard: None,
            ..config.paths
        },
        ..config.clone()
    };
    let sparse = LightmapTexels {
        atlas: texels.atlas.clone(),
        texels: which.iter().map(|&i| texels.texels[i]).collect(),
        left_out: texels.left_out,
    };
    Ok(gather_texels(domain, trained, &guide, settings, (&sparse, None))?.0)
}

/// Salts the seed of [`gather_guide`].
const GUIDE_SALT: u64 = 0x6775_6964_6520_6c6d;

/// Step 4: the estimates (one per texel, in order), denoised with `guide` ([`gather_guide`]) if
/// given, into the pages, dilated over the padding and the left-out texels.
pub fn assemble_lightmap(
    domain: &Domain,
    texels: LightmapTexels,
    gathered: &[Gathered],
    guide: Option<&LightmapGuide>,
    settings: &LightmapSettings,
) -> Lightmap {
    let LightmapTexels {
        atlas,
        texels,
        left_out,
    } = texels;
    // ⟨Denoised: radiosity demodulated by each texel's (ρ, E)⟩
    let mut denoised = None;
    let denoised_values;
    let gathered = if let Some(guide) = guide {
        let material = texel_materials(domain, &texels, settings.quantity);
        let last = guide.last.lock().unwrap_or_else(|e| e.into_inner()).take();
        let (values, report) = denoise::denoise(
            &atlas,
            &texels,
            (gathered, &guide.values),
            material.as_deref(),
            last,
        );
        denoised = Some(report);
        denoised_values = values;
        &denoised_values[..]
    } else {
        gathered
    };
    // ⟨Into the pages, then dilated over the padding and the left-out texels⟩
    let (w, h) = (atlas.width as usize, atlas.height as usize);
    let mut pages = vec![vec![[0.0f32; 3]; w * h]; atlas.pages as usize];
    let mut filled = vec![vec![false; w * h]; atlas.pages as usize];
    for (t, g) in texels.iter().zip(gathered) {
        let i = t.y as usize * w + t.x as usize;
        pages[t.page as usize][i] = g.radiosity.map(|v| v as f32);
        filled[t.page as usize][i] = true;
    }
    for (page, filled) in pages.iter_mut().zip(&mut filled) {
        dilate::dilate(page, filled, w, h, 2 * settings.padding as usize + 2);
    }
    let mut stats = GatherStats::of(gathered);
    if let Some(report) = denoised {
        stats.relative_std_error = report.error;
    }
    Lightmap {
        stats,
        denoised,
        atlas,
        pages,
        quantity: settings.quantity,
        texels,
        left_out,
    }
}
