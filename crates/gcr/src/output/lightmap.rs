//! The lightmap step of the output stage ([`write_lightmap`]) and its files: the pages as linear
//! OpenEXR, and a binary glTF of the scene with the lightmap on a second UV set, as web viewers
//! and engines read it.
//!
//! * **`<name>-lightmap-<k>.exr`** beside the .glb: page k, RGB f32, the linear values (irradiance
//!   E or radiosity B, [`LightmapQuantity`]), row 0 at v = 0 (the image's top row).
//! * **The .glb**: one node per scene object (world coordinates, identity transform), one
//!   primitive per (part, page, material) with `POSITION`, `NORMAL` (the face's), `TEXCOORD_1` (the
//!   lightmap coordinates; glTF's v = 0 is the image's top row, as the atlas has it; the same
//!   accessor serves as `TEXCOORD_0`, which glTF requires before a `TEXCOORD_1`); materials
//!   carry the faces' albedo (a textured part's mean) as `baseColorFactor` (Lambertian: `KHR_materials_specular`
//!   with `specularFactor` 0), its emitted radiance as `emissiveFactor`
//!   × `KHR_materials_emissive_strength` (in the lightmap's linear units), and the page as an
//!   8-bit PNG through the
//!   **`MOZ_lightmap`** extension (Mozilla Hubs' convention: `{"index": texture, "texCoord": 1,
//!   "intensity": s}`), sRGB-encoded like glTF's colour textures, scaled so that the brightest
//!   texel's largest channel is 1 ([`png_scale`]: nothing clips; `intensity` = 1 / that scale
//!   restores the linear value; `asset.extras` records it too). A viewer that knows the extension sets `material.lightMap` with
//!   `lightMapIntensity = intensity` on `uv1` (three.js); one that does not shows the plain
//!   material. Each face is written as its own three corners (a triangle soup: the lightmap's
//!   seams need split vertices anyway); back faces of two-sided materials are their own faces.

use super::OutputError;
use super::gltf_bin::Bin;
use super::plan::OutputPlan;
use super::stage::Stage;
use super::staged::check_target;
use super::tonemap::srgb_encode;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::estimator::GatherStats;
use crate::gather::Gathered;
use crate::lightmap::{Lightmap, LightmapQuantity};
use crate::solve::Trained;
use scene_sampler::Scene;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The lightmap step of the output stage: lays out the texels, gathers them (all, or a shard's;
/// or merges the shards' partial outputs) and stages the .glb and its EXR pages — or, for a
/// shard, its partial output alone.
pub(super) fn write_lightmap(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    plan: &OutputPlan,
    path: &Path,
    stage: &mut Stage,
) -> Result<(), OutputError> {
    let Some(scene) = domain.scene_3d() else {
        return Err(OutputError::MeshNeeds3d);
    };
    let tg = Instant::now();
    let settings = &plan.lightmap;
    let texels = crate::lightmap::lay_out_texels(domain, settings)?;
    let points = texels.points();
    let print = || super::shards::fingerprint(domain, &points, config, &format!("{settings:?}"));
    // ⟨The denoiser's guide first: the rounds stop on the denoised error (every run that
    // denoises, a shard's and the merge's too, gathers the same guide)⟩
    let tguide = Instant::now();
    let guide = if settings.denoise {
        Some(crate::lightmap::gather_guide(
            domain, trained, config, settings, &texels,
        )?)
    } else {
        None
    };
    let guide_seconds = tguide.elapsed().as_secs_f64();
    // ⟨The texels' values: gathered (all of them, or a shard's), or the shards' merged⟩
    let (gathered, mine) = if !plan.merges(super::shards::Kind::Lightmap) {
        let _phase = crate::progress::phase("lightmap");
        let at = (&texels, guide.as_ref());
        crate::lightmap::gather_texels(domain, trained, config, settings, at)?
    } else {
        let merged = plan.merged_shards(super::shards::Kind::Lightmap, print())?;
        let every = (0..merged.len()).collect();
        (merged, every)
    };
    if let Some(shard) = config.paths.shard {
        // ⟨A shard writes its texels' estimates with their indices, nothing else⟩
        let theirs: Vec<Gathered> = mine.iter().map(|&i| gathered[i]).collect();
        stage.push_gather(GatherStats::of(&theirs));
        stage.metrics.seconds.gather += tg.elapsed().as_secs_f64();
        let lines: Vec<String> = gathered.iter().map(super::shards::gathered_line).collect();
        let kind = super::shards::Kind::Lightmap;
        let text = super::shards::partial_text(kind, shard, print(), &lines, &mine);
        let part = super::shards::part_path(path, shard);
        check_target(&part, "lightmap shard", None)?;
        stage.files.write_bytes(&part, text.as_bytes())?;
        return Ok(());
    }
    stage.metrics.warnings.extend(texels.atlas.note.clone());
    let lightmap =
        crate::lightmap::assemble_lightmap(domain, texels, &gathered, guide.as_ref(), settings);
    stage.push_gather(lightmap.stats);
    let (metrics, staged) = (&mut stage.metrics, &mut stage.files);
    metrics.seconds.gather += tg.elapsed().as_secs_f64();
    let to = Instant::now();
    let scale = png_scale(&lightmap);
    let io = |source| OutputError::Write {
        path: path.to_path_buf(),
        source,
    };
    let glb = to_lightmap_glb(&lightmap, scene, scale).map_err(io)?;
    staged.write_bytes(path, &glb)?;
    let pages = page_paths(path, lightmap.atlas.pages);
    for (k, page) in pages.iter().enumerate() {
        check_target(page, "lightmap page", Some("exr"))?;
        let exr = encode_page_exr(&lightmap, k).map_err(io)?;
        staged.write_bytes(page, &exr)?;
    }
    metrics.lightmap = Some(crate::metrics::LightmapRecord {
        path: path.display().to_string(),
        pages: lightmap.atlas.pages,
        width: lightmap.atlas.width,
        height: lightmap.atlas.height,
        texels_per_unit: lightmap.atlas.texels_per_unit,
        charts: lightmap.atlas.charts,
        uv_source: if lightmap.atlas.from_input {
            "input"
        } else {
            "unwrapped"
        },
        utilization: lightmap.atlas.utilization,
        texels: lightmap.texels.len(),
        left_out: lightmap.left_out,
        png_scale: scale,
        denoised: lightmap.denoised.map(|d| crate::metrics::DenoiseRecord {
            raw_error: d.raw_error,
            unfiltered: d.unfiltered,
            mean_sigma: d.mean_sigma,
            guide_seconds,
            filter_seconds: d.seconds,
        }),
    });
    metrics.seconds.output += to.elapsed().as_secs_f64();
    Ok(())
}

/// The EXR page files of a lightmap written to `glb`: `<stem>-lightmap-<k>.exr` beside it.
pub fn page_paths(glb: &Path, pages: u32) -> Vec<PathBuf> {
    let stem = glb
        .file_stem()
        .map_or("lightmap".into(), |s| s.to_string_lossy());
    (0..pages)
        .map(|k| glb.with_file_name(format!("{stem}-lightmap-{k}.exr")))
        .collect()
}

/// Encodes page `k` of `lightmap` as OpenEXR (RGB f32, lossless), in memory.
pub fn encode_page_exr(lightmap: &Lightmap, k: usize) -> std::io::Result<Vec<u8>> {
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let (w, h) = (
        lightmap.atlas.width as usize,
        lightmap.atlas.height as usize,
    );
    let page = &lightmap.pages[k];
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = page[y * w + x];
        (p[0], p[1], p[2])
    });
    let mut buf = std::io::Cursor::new(Vec::new());
    Image::from_channels((w, h), channels)
        .write()
        .to_buffered(&mut buf)
        .map_err(std::io::Error::other)?;
    Ok(buf.into_inner())
}

/// The scale of the 8-bit pages: 1 at the brightest texel's largest channel, so that no texel
/// clips (1 when every texel is dark). An 8-bit page is a display format: clipping at a lower
/// percentile flattened the hot spots near a light (the Cornell box's walls beside the light
/// read up to 25 % dark in three.js at the 95th percentile → 0.8 scale this replaced); the EXR
/// pages keep the full range.
pub fn png_scale(lightmap: &Lightmap) -> f64 {
    let peak = (lightmap.pages.iter().flatten())
        .flat_map(|p| p.iter().map(|&c| f64::from(c)))
        .filter(|c| c.is_finite())
        .fold(0.0, f64::max);
    if peak > 0.0 { 1.0 / peak } else { 1.0 }
}

/// Page `k` as an 8-bit sRGB PNG of `value × scale`.
fn encode_page_png(lightmap: &Lightmap, k: usize, scale: f64) -> std::io::Result<Vec<u8>> {
    let (w, h) = (lightmap.atlas.width, lightmap.atlas.height);
    let bytes: Vec<u8> = (lightmap.pages[k].iter())
        .flat_map(|p| {
            p.map(|c| (srgb_encode((f64::from(c) * scale).clamp(0.0, 1.0)) * 255.0).round() as u8)
        })
        .collect();
    let img = image::RgbImage::from_raw(w, h, bytes)
        .ok_or_else(|| std::io::Error::other("lightmap page size"))?;
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(std::io::Error::other)?;
    Ok(out.into_inner())
}

/// A part's material: its mean albedo, its emitted radiance L = E/π (as `emissiveFactor` × the
/// `KHR_materials_emissive_strength`, in the scene's units like the lightmap's linear values), and
/// the lightmap page. `KHR_materials_specular` with `specularFactor` 0 says the surface is the
/// Lambertian one that was solved: glTF's default dielectric keeps a 4 % Fresnel layer whose
/// energy three.js takes from the diffuse (the view read 1.3–3.6 % darker than gcr's pixels).
fn material(rho: [f64; 3], emission: [f64; 3], page: u32, scale: f64) -> Value {
    let mut m = json!({
        "pbrMetallicRoughness": {"baseColorFactor": [rho[0], rho[1], rho[2], 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 1.0},
        "extensions": {"MOZ_lightmap": {"index": page, "texCoord": 1, "intensity": 1.0 / scale},
            "KHR_materials_specular": {"specularFactor": 0.0}},
    });
    let radiance = emission.map(|e| e / std::f64::consts::PI);
    let peak = radiance.iter().copied().fold(0.0, f64::max);
    if peak > 0.0 {
        m["emissiveFactor"] = json!(radiance.map(|l| l / peak));
        m["extensions"]["KHR_materials_emissive_strength"] = json!({"emissiveStrength": peak});
    }
    m
}

/// The extensions the file uses: `MOZ_lightmap`, `KHR_materials_specular` (no specular layer),
/// and the emissive strength when a face emits.
fn extensions_used(scene: &Scene) -> Vec<&'static str> {
    let mut used = vec!["MOZ_lightmap", "KHR_materials_specular"];
    if scene.faces.iter().any(|f| !f.emission.is_zero()) {
        used.push("KHR_materials_emissive_strength");
    }
    used
}

/// A primitive's faces: (part, page, the exact albedo and emission bits of untextured faces).
type GroupKey = (u32, u32, Option<([u64; 3], [u64; 3])>);

/// The lightmapped scene as a .glb (module docs); `scale` is the PNG pages' ([`png_scale`]).
pub fn to_lightmap_glb(lightmap: &Lightmap, scene: &Scene, scale: f64) -> std::io::Result<Vec<u8>> {
    let mut bin = Bin::default();
    // ⟨The pages as PNG images and textures⟩
    let mut images = Vec::new();
    for k in 0..lightmap.pages.len() {
        let png = encode_page_png(lightmap, k, scale)?;
        let view = bin.view(&png, None);
        images.push(
            json!({"bufferView": view, "mimeType": "image/png", "name": format!("lightmap-{k}")}),
        );
    }
    let textures: Vec<Value> = (0..images.len())
        .map(|k| json!({"source": k, "sampler": 0}))
        .collect();
    // ⟨Faces by object, then (part, page, material): faces of one albedo and emission share a
    // primitive (an OBJ object with several `usemtl` is several); textured faces, whose ρ is their
    // own texture's mean, share one per part and page with the mean⟩
    let mut groups: BTreeMap<u32, BTreeMap<GroupKey, Vec<usize>>> = BTreeMap::new();
    for (f, uv) in lightmap.atlas.faces.iter().enumerate() {
        if let Some(uv) = uv {
            let face = &scene.faces[f];
            let material = (face.texture.is_none()).then(|| {
                (
                    face.rho.0.map(f64::to_bits),
                    face.emission.0.map(f64::to_bits),
                )
            });
            groups
                .entry(face.object)
                .or_default()
                .entry((face.part, uv.page, material))
                .or_default()
                .push(f);
        }
    }
    let (mut nodes, mut meshes, mut materials) = (Vec::new(), Vec::new(), Vec::new());
    for (object, parts) in &groups {
        let mut primitives = Vec::new();
        for (&(_, page, _), faces) in parts {
            let (mut pos, mut nrm, mut uv1) = (Vec::new(), Vec::new(), Vec::new());
            let (mut rho, mut emission) = ([0.0f64; 3], [0.0f64; 3]);
            for &f in faces {
                let face = &scene.faces[f];
                let uv = lightmap.atlas.faces[f].expect("grouped faces have a place");
                for c in 0..3 {
                    pos.push(face.v[c].as_vec3().to_array());
                    nrm.push(face.normal.as_vec3().to_array());
                    uv1.push(uv.uv[c]);
                }
                for k in 0..3 {
                    let band = k.min(face.rho.0.len() - 1);
                    rho[k] += face.rho.0[band] / faces.len() as f64;
                    emission[k] += face.emission.0[band] / faces.len() as f64;
                }
            }
            let uv = bin.floats(&uv1, "VEC2", false);
            // (glTF wants TEXCOORD_0 before TEXCOORD_1; the materials have no other texture,
            // so the lightmap's coordinates serve as both)
            let attributes = json!({
                "POSITION": bin.floats(&pos, "VEC3", true),
                "NORMAL": bin.floats(&nrm, "VEC3", false),
                "TEXCOORD_0": uv,
                "TEXCOORD_1": uv,
            });
            materials.push(material(rho, emission, page, scale));
            primitives.push(
                json!({"attributes": attributes, "material": materials.len() - 1, "mode": 4}),
            );
        }
        meshes.push(json!({"primitives": primitives}));
        let mut node = json!({"mesh": meshes.len() - 1});
        if let Some(name) = scene.objects.get(*object as usize) {
            node["name"] = json!(name);
        }
        nodes.push(node);
    }
    let quantity = match lightmap.quantity {
        LightmapQuantity::Irradiance => "irradiance E",
        LightmapQuantity::Radiosity => "radiosity B",
    };
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "gcr (Growing Cells Radiosity)",
            "extras": {"lightmap_quantity": quantity, "lightmap_png_scale": scale,
                "lightmap": "MOZ_lightmap pages: sRGB PNG of value * lightmap_png_scale; intensity = 1 / scale; linear pages in the -lightmap-<k>.exr files"}},
        "extensionsUsed": extensions_used(scene),
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "materials": materials,
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}],
        "images": images,
        "textures": textures,
    });
    if !meshes.is_empty() {
        doc["meshes"] = json!(meshes);
    }
    Ok(bin.into_glb(doc))
}
