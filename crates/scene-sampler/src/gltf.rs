//! The glTF 2.0 loader (`.gltf` with its buffers, or `.glb`): the node tree walked with its
//! transforms, triangle primitives with their materials, base-colour textures, cut-outs
//! ([`crate::gltf_cutouts`]), emissive textures ([`crate::gltf_emission`]), the camera and the
//! lights ([`crate::gltf_lights`]); files read through [`crate::gltf_resources`].
//!
//! Units (FORMATS.md): glTF `emissiveFactor × emissive_strength` is emitted **radiance** L_e, as a
//! path tracer reads it; the scene stores emitted radiosity (exitance) `E = π·L_e`.

use crate::confine::Folder;
use crate::provenance::{GltfSource, Part};
use crate::read::{average_albedo, stem};
use crate::scene::check_file_material;
use crate::texture::TextureBudget;
use crate::{
    Camera, Face, FaceTexture, LoadOptions, Result, Scene, SceneError, Spectrum, Texture, Wrap,
};
use glam::{DMat4, DVec3};
use std::f64::consts::PI;
use std::path::Path;

/// The glTF document of `path`, its buffers and its folder: the file and every buffer it names
/// read through the folder's confined reader (`gltf::import` would read any path it names).
fn gltf_document(
    path: &Path,
    source: &str,
    options: &LoadOptions,
) -> Result<(gltf::Document, Vec<Vec<u8>>, Folder)> {
    let bytes = crate::confine::read_regular_file(path, options.max_file_bytes)?;
    let folder = Folder::of(path, options)?;
    let parse = |message: String| SceneError::Parse {
        source_name: source.into(),
        message,
    };
    // gltf is third-party parsing of user input: a panic inside it becomes a parse error, never an abort.
    let gltf::Gltf { document, blob } = std::panic::catch_unwind(|| gltf::Gltf::from_slice(&bytes))
        .map_err(|_| parse("the glTF parser failed on this file".into()))?
        .map_err(|e| parse(e.to_string()))?;
    let buffers = crate::gltf_resources::read_buffers(&document, blob, source, &folder)?;
    Ok((document, buffers, folder))
}

/// Loads a glTF 2.0 file (`.gltf` with its buffers, or `.glb`).
///
/// Every triangle primitive of every mesh instance in the default scene (or the first) is loaded with its
/// node's world transform applied (windings flipped under mirroring transforms). `baseColorFactor.rgb` → ρ,
/// `emissiveFactor × KHR_materials_emissive_strength` → emitted radiance, E = π·that (ρ ≥ 1, such as the
/// default material's white, is clamped to [`RHO_MAX`] with a warning naming the material);
/// `baseColorTexture` (on its TEXCOORD set, with its sampler's wrap modes; sRGB) multiplies it per point
/// ([`Scene::rho_at`]). Triangle strips and fans are loaded as triangles; points and lines are skipped with a warning
/// naming their mesh, and a file with nothing else is an error saying so. The first node with a
/// perspective camera (in traversal order) becomes [`Scene::camera`] (with
/// [`Scene::camera_given`]); without one the image output places its automatic camera.
///
/// Provenance ([`crate::provenance`]): each node with a mesh is an object, each of its triangle
/// primitives a [`Part`] (node, mesh, primitive) that its faces name in [`Face::part`]; the
/// document's node tree, meshes and materials are kept in [`Scene::gltf`], with the world
/// transform applied to each node of the loaded scene.
///
/// Buffers and images are read from the file's folder only, and only the images a material's
/// baseColorTexture uses are decoded, within the default [`LoadOptions`]
/// ([`load_with`](crate::load_with) takes others).
pub fn load_gltf(path: impl AsRef<Path>) -> Result<Scene> {
    gltf_with(path.as_ref(), &LoadOptions::default())
}

pub(crate) fn gltf_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let source = path.display().to_string();
    let (doc, buffers, folder) = gltf_document(path, &source, options)?;
    let mut budget = TextureBudget::new(options.max_texture_bytes);
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::Parse {
            source_name: source.clone(),
            message: "no scene in file".into(),
        })?;
    let mut faces = Vec::new();
    let mut objects = Vec::new();
    let mut warnings = Vec::new();
    let mut skipped: Vec<String> = Vec::new();
    let mut checked: Vec<(Option<usize>, Spectrum)> = Vec::new();
    let mut textures: Vec<Texture> = Vec::new();
    // (image, wrap modes) → index into `textures`
    let mut texture_of: Vec<((usize, [Wrap; 2]), u32)> = Vec::new();
    let mut cutouts = crate::gltf_cutouts::Cutouts::default();
    let mut emissive = crate::gltf_emission::EmissiveTextures::default();
    // per part: whether its material is doubleSided
    let mut two_sided: Vec<bool> = Vec::new();
    let mut surface = 0u32;
    let mut camera: Option<Camera> = None;
    let mut lights = Vec::new();
    let mut provenance = GltfSource::of_document(&doc, &scene);
    let mut parts: Vec<Part> = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4, usize)> =
        scene.nodes().map(|n| (n, DMat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        // a node graph with a cycle (invalid glTF, but parseable) would never end
        if depth > 256 {
            return Err(SceneError::Parse {
                source_name: source.clone(),
                message: format!(
                    "node {} is nested more than 256 deep (a cycle?)",
                    node.index()
                ),
            });
        }
        // node transforms are composed in f64: only the mesh-local positions are f32 (glTF spec)
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(n) = provenance.nodes.get_mut(node.index()) {
            n.world = Some(world);
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
        if camera.is_none() {
            camera = gltf_camera(&node, world, &source, &mut warnings);
        }
        lights.extend(crate::gltf_lights::node_light(&node, world, &source)?);
        let Some(mesh) = node.mesh() else { continue };
        let obj = objects.len() as u32;
        let obj_name = node
            .name()
            .or(mesh.name())
            .map_or_else(|| format!("node{}", node.index()), String::from);
        objects.push(obj_name.clone());
        let flip = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                skipped.push(format!("`{obj_name}` ({mode:?})"));
                continue;
            }
            let part = parts.len() as u32;
            two_sided.push(prim.material().double_sided());
            parts.push(Part {
                object: obj,
                node: Some(node.index() as u32),
                mesh: Some(mesh.index() as u32),
                primitive: prim.index() as u32,
            });
            let mat = prim.material();
            let pbr = mat.pbr_metallic_roughness();
            let bc = pbr.base_color_factor();
            let strength = f64::from(mat.emissive_strength().unwrap_or(1.0));
            let ef = mat.emissive_factor();
            let e = Spectrum(ef.map(|v| f64::from(v) * strength * PI));
            let rho = match checked.iter().find(|(i, _)| *i == mat.index()) {
                Some(&(_, rho)) => rho,
                None => {
                    let name = match (mat.name(), mat.index()) {
                        (Some(n), _) => n.to_string(),
                        (None, Some(i)) => format!("material {i}"),
                        (None, None) => "the default material".to_string(),
                    };
                    let rho = Spectrum([bc[0], bc[1], bc[2]].map(f64::from));
                    let rho = check_file_material(&source, &name, rho, e, &mut warnings)?;
                    checked.push((mat.index(), rho));
                    rho
                }
            };
            let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let read_uv = |k: u32| {
                (reader.read_tex_coords(k)).map(|c| {
                    (c.into_f32())
                        .map(|[u, v]| glam::DVec2::new(f64::from(u), f64::from(v)))
                        .collect::<Vec<_>>()
                })
            };
            let mut images = crate::gltf_resources::Images {
                source: &source,
                folder: &folder,
                buffers: &buffers,
                budget: &mut budget,
            };
            // ⟨baseColorTexture × baseColorFactor, on its TEXCOORD set⟩
            let texture = match pbr.base_color_texture() {
                Some(info) => {
                    let tex = info.texture();
                    let wrap = crate::gltf_resources::wrap_of(&tex);
                    let image = tex.source().index();
                    let index = match texture_of.iter().find(|(k, _)| *k == (image, wrap)) {
                        Some(&(_, i)) => i,
                        None => {
                            let name = tex.source().name().map_or_else(
                                || format!("{source}: image {image}"),
                                |n| format!("{source}: image `{n}`"),
                            );
                            textures.push(crate::gltf_resources::decode_image(
                                &tex.source(),
                                &name,
                                wrap,
                                &mut images,
                            )?);
                            texture_of.push(((image, wrap), textures.len() as u32 - 1));
                            textures.len() as u32 - 1
                        }
                    };
                    let uv = crate::gltf_resources::info_uv(&info, read_uv);
                    match uv {
                        Some(uv) => Some((index, uv)),
                        None => {
                            warnings.push(format!(
                                "{source}: mesh `{obj_name}`: a baseColorTexture but no TEXCOORD_{}: \
                                 its baseColorFactor is used",
                                info.tex_coord()
                            ));
                            None
                        }
                    }
                }
                None => None,
            };
            // ⟨alphaMode: cut-outs; emissiveTexture⟩
            let alpha =
                cutouts.of_primitive(&mat, e.max() > 0.0, read_uv, &mut images, &mut warnings)?;
            let emissive_map = match e.max() > 0.0 {
                true => emissive.of_primitive(&mat, read_uv, &mut images)?,
                false => None,
            };
            let Some(pos) = reader.read_positions() else {
                return Err(SceneError::Parse {
                    source_name: source.clone(),
                    message: format!("mesh `{obj_name}`: primitive without POSITION"),
                });
            };
            let pos: Vec<DVec3> = pos
                .map(|p| world.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
                .collect();
            let idx: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..pos.len() as u32).collect(),
            };
            // strips and fans as triangle lists (glTF 2.0 §3.7.2.1: strip triangle i is (i, i+1, i+2) for even
            // i and (i+1, i, i+2) for odd i, so that every triangle winds like the first; fan i is (i+1, i+2, 0))
            let tris: Vec<[u32; 3]> = match mode {
                Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
                    .map(|i| {
                        if i % 2 == 0 {
                            [idx[i], idx[i + 1], idx[i + 2]]
                        } else {
                            [idx[i + 1], idx[i], idx[i + 2]]
                        }
                    })
                    .collect(),
                Mode::TriangleFan => (1..idx.len().saturating_sub(1))
                    .map(|i| [idx[i], idx[i + 1], idx[0]])
                    .collect(),
                _ => idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            };
            for t in tris {
                let get = |i: u32| {
                    pos.get(i as usize)
                        .copied()
                        .ok_or_else(|| SceneError::Parse {
                            source_name: source.clone(),
                            message: format!(
                                "mesh `{obj_name}`: index {i} out of range ({} vertices)",
                                pos.len()
                            ),
                        })
                };
                let (a, b, c) = (get(t[0])?, get(t[1])?, get(t[2])?);
                let (v, corners) = if flip {
                    ([a, c, b], [t[0], t[2], t[1]])
                } else {
                    ([a, b, c], t)
                };
                let mut face = Face {
                    part,
                    ..Face::new(v, rho, e, obj, surface)
                };
                if let Some((tex, uv)) = &emissive_map {
                    let at = |i: u32| uv.get(i as usize).copied();
                    if let [Some(a), Some(b), Some(c)] = corners.map(at) {
                        emissive.add(faces.len(), *tex, [a, b, c], e);
                    }
                }
                match &alpha {
                    crate::gltf_cutouts::Alpha::Opaque => {}
                    crate::gltf_cutouts::Alpha::Hidden => {
                        cutouts.hidden += 1;
                        continue;
                    }
                    crate::gltf_cutouts::Alpha::Cut {
                        mask,
                        uv,
                        threshold,
                    } => {
                        let at = |i: u32| uv.get(i as usize).copied();
                        if let [Some(a), Some(b), Some(c)] = corners.map(at) {
                            face.cutout = Some(crate::FaceCutout {
                                mask: *mask,
                                uv: [a, b, c],
                                threshold: *threshold,
                            });
                        }
                    }
                }
                if let Some((index, uv)) = &texture {
                    let at = |i: u32| uv.get(i as usize).copied();
                    if let [Some(a), Some(b), Some(c)] = corners.map(at) {
                        let ft = FaceTexture {
                            texture: *index,
                            uv: [a, b, c],
                            factor: rho,
                        };
                        face.texture = Some(ft);
                    }
                }
                faces.push(face);
                surface += 1;
            }
        }
    }
    if faces.is_empty() && !skipped.is_empty() {
        return Err(SceneError::Parse {
            source_name: source,
            message: format!(
                "no triangles: every primitive is points or lines ({}), which have no area to light",
                skipped.join(", ")
            ),
        });
    }
    average_albedo(&mut faces, &textures);
    let emitting = emissive.apply(&mut faces);
    if emitting > 0 {
        warnings.push(format!(
            "{source}: {emitting} face(s) with an emissiveTexture emit its mean over each face \
             (constant per face: a pattern finer than the faces is averaged)"
        ));
    }
    if cutouts.hidden > 0 {
        warnings.push(format!(
            "{source}: dropped {} face(s) whose material's alpha is below its alphaCutoff              everywhere (fully cut out)",
            cutouts.hidden
        ));
    }
    let mut scene = Scene::new(&stem(path), &source, faces, objects, camera)?
        .with_textures(textures)?
        .with_masks(cutouts.masks)?;
    scene.parts = parts;
    scene.gltf = Some(Box::new(provenance));
    if !options.single_sided {
        let backs = scene.add_back_faces(|f| two_sided.get(f.part as usize) == Some(&true));
        if backs > 0 {
            warnings.push(format!(
                "{source}: {backs} face(s) of doubleSided materials got a back face (both sides \
                 reflect and are solved); for closed solids --single-sided halves the work"
            ));
        }
    }
    scene.add_lights(lights);
    if !skipped.is_empty() {
        warnings.push(format!(
            "{source}: skipped {} point/line primitive(s): {}",
            skipped.len(),
            skipped.join(", ")
        ));
    }
    scene.warnings.extend(warnings);
    Ok(scene)
}

/// The camera of a glTF node, if it has a perspective one (glTF 2.0 §3.10: the lens looks along the
/// node's local −Z, local +Y is up, `yfov` is the vertical field of view in radians); the node's
/// world transform places it. An orthographic camera, or one whose transform collapses its axes,
/// is skipped with a warning (the image then uses the automatic camera).
fn gltf_camera(
    node: &gltf::Node,
    world: DMat4,
    source: &str,
    warnings: &mut Vec<String>,
) -> Option<Camera> {
    let cam = node.camera()?;
    let name = cam
        .name()
        .map_or_else(|| format!("camera {}", cam.index()), |n| format!("`{n}`"));
    let gltf::camera::Projection::Perspective(p) = cam.projection() else {
        warnings.push(format!(
            "{source}: {name} is orthographic: not supported, the image uses the automatic camera"
        ));
        return None;
    };
    let eye = world.transform_point3(DVec3::ZERO);
    let forward = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
    let fov_y_deg = f64::from(p.yfov()).to_degrees();
    let usable = eye.is_finite()
        && forward != DVec3::ZERO
        && forward.cross(up).length() > 1e-6
        && fov_y_deg > 0.0
        && fov_y_deg < 180.0;
    if !usable {
        warnings.push(format!(
            "{source}: {name}: degenerate transform or field of view ({fov_y_deg}°): ignored, the \
             image uses the automatic camera"
        ));
        return None;
    }
    Some(Camera {
        eye,
        target: eye + forward,
        up,
        fov_y_deg,
    })
}
