//! The glTF 2.0 loader (`.gltf` with its buffers, or `.glb`): the node tree walked with its
//! transforms, triangle primitives with their materials, base-colour textures, cut-outs
//! ([`crate::gltf_cutouts`]), emissive textures ([`crate::gltf_emission`]), the camera and the
//! lights ([`crate::gltf_lights`]); files read through [`crate::gltf_resources`].
//!
//! Units (FORMATS.md): glTF `emissiveFactor × emissive_strength` is emitted **radiance** L_e, as a
//! path tracer reads it; the scene stores emitted radiosity (exitance) `E = π·L_e`.

use crate::confine::Folder;
use crate::gltf_cutouts::{Alpha, Cutouts};
use crate::gltf_emission::EmissiveTextures;
use crate::gltf_resources::Images;
use crate::provenance::{GltfSource, Part};
use crate::read::{average_albedo, stem};
use crate::scene::check_file_material;
use crate::texture::TextureBudget;
use crate::{
    Camera, Face, FaceTexture, Light, LoadOptions, Result, Scene, SceneError, Spectrum, Texture,
    Wrap,
};
use glam::{DMat4, DVec2, DVec3};
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// The glTF document of `path`, its buffers and its folder: the file and every buffer it names
/// read through the folder's confined reader (`gltf::import` would read any path it names).
fn gltf_document(
    path: &Path,
    source: &str,
    options: &LoadOptions,
) -> Result<(gltf::Document, Vec<Vec<u8>>, Folder)> {
    let bytes = crate::confine::read_regular_file(path, options.max_file_bytes)?;
    let folder = Folder::of(path, options)?;
    // gltf is third-party parsing of user input: a panic inside it becomes a parse error, never an
    // abort. What it reads without a check is checked first.
    let gltf::Gltf { document, blob } =
        guarded(source, || gltf::Gltf::from_slice_without_validation(&bytes))?;
    crate::gltf_accessors::parser_prechecks(document.as_json(), source)?;
    let json = document.into_json();
    let document = guarded(source, || gltf::Document::from_json(json))?;
    let buffers = crate::gltf_resources::read_buffers(&document, blob, source, &folder)?;
    Ok((document, buffers, folder))
}

/// `parse()`, the gltf crate parsing user input, with its errors and panics as parse errors of
/// the file `source`.
fn guarded<T>(source: &str, parse: impl FnOnce() -> gltf::Result<T>) -> Result<T> {
    let error = |message: String| SceneError::Parse {
        source_name: source.into(),
        message,
    };
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(parse))
        .map_err(|_| error("the glTF parser failed on this file".into()))?
        .map_err(|e| error(e.to_string()))
}

/// Loads a glTF 2.0 file (`.gltf` with its buffers, or `.glb`).
///
/// Every triangle primitive of every mesh instance in the default scene (or the first) is loaded with its
/// node's world transform applied (windings flipped under mirroring transforms). `baseColorFactor.rgb` → ρ,
/// `emissiveFactor × KHR_materials_emissive_strength` → emitted radiance, E = π·that (ρ ≥ 1, such as the
/// default material's white, is clamped to [`RHO_MAX`](crate::RHO_MAX) with a warning naming the material);
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

/// [`load_gltf`] within `options` ([`crate::load_with`]).
pub(crate) fn gltf_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let source = path.display().to_string();
    let (doc, buffers, folder) = gltf_document(path, &source, options)?;
    let mut budget = TextureBudget::new(options.max_texture_bytes);
    let mut images = Images {
        source: &source,
        folder: &folder,
        buffers: &buffers,
        budget: &mut budget,
    };
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::Parse {
            source_name: source.clone(),
            message: "no scene in file".into(),
        })?;
    // ⟨The node tree, depth first: each node's world transform, then what it carries⟩
    let mut found = GltfFaces::new(GltfSource::of_document(&doc, &scene));
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
        let local = node_matrix(&node, &source, &mut found.warnings)?;
        let world = parent * local;
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
        found.add_node(&node, world, &mut images)?;
    }
    // ⟨The scene⟩
    found.into_scene(path, &source, options)
}

/// The local transform of `node`, its matrix or its translation, rotation and scale composed
/// (glTF 2.0 §3.5.3). The rotation must be a unit quaternion: one within 10⁻⁵ of unit length is
/// used as it is, a longer or shorter one normalised with a warning naming the node (unnormalised,
/// it would scale and shear the mesh), and a zero one is an error.
fn node_matrix(node: &gltf::Node, source: &str, warnings: &mut Vec<String>) -> Result<DMat4> {
    let mut transform = node.transform();
    if let gltf::scene::Transform::Decomposed { rotation, .. } = &mut transform {
        let length = rotation
            .iter()
            .map(|q| f64::from(*q).powi(2))
            .sum::<f64>()
            .sqrt();
        if !(length > 0.0 && length.is_finite()) {
            return Err(SceneError::Parse {
                source_name: source.into(),
                message: format!(
                    "node {}: rotation {rotation:?} is not a rotation (a unit quaternion)",
                    node.index()
                ),
            });
        }
        if (length - 1.0).abs() > 1e-5 {
            warnings.push(format!(
                "{source}: node {}: rotation {rotation:?} has length {length:.6}, not 1: \
                 normalised",
                node.index()
            ));
            *rotation = rotation.map(|q| (f64::from(q) / length) as f32);
        }
    }
    Ok(DMat4::from_cols_array_2d(
        &transform.matrix().map(|c| c.map(f64::from)),
    ))
}

/// A mesh instance of the node walk: the node and its mesh, the object it makes, and its world
/// transform.
struct Instance {
    /// The node's index.
    node: u32,
    /// The mesh's index.
    mesh: u32,
    /// The object's index.
    object: u32,
    /// The object's name: the node's, else the mesh's, else `node<index>`.
    name: String,
    world: DMat4,
    /// Whether `world` mirrors (the windings are then flipped).
    flip: bool,
}

/// How a primitive's faces look: their part, ρ and E, and the base colour texture, cut-out and
/// emissive texture with their per-vertex texture coordinates.
struct PrimitiveLook {
    part: u32,
    rho: Spectrum,
    e: Spectrum,
    /// The base colour texture (index) and its coordinates.
    texture: Option<(u32, Vec<DVec2>)>,
    alpha: Alpha,
    /// The emissive texture (index) and its coordinates.
    emissive_map: Option<(u32, Vec<DVec2>)>,
    /// The lightmap coordinates (`TEXCOORD_1`), if any ([`Face::lightmap_uv`]).
    lightmap_uv: Option<Vec<DVec2>>,
}

/// The base colour textures of a glTF document, decoded once per (image, wrap modes).
#[derive(Default)]
struct BaseColours {
    textures: Vec<Texture>,
    /// (image, wrap modes) → index into `textures`
    texture_of: Vec<((usize, [Wrap; 2]), u32)>,
}

impl BaseColours {
    /// A primitive's base colour texture (index) and its per-vertex texture coordinates, from
    /// the texture reference `info` (`read_uv(k)`: the primitive's `TEXCOORD_k`); the image
    /// decoded once. Without the coordinates `None`, with a warning naming the mesh `mesh`.
    fn of_primitive(
        &mut self,
        info: Option<gltf::texture::Info>,
        mesh: &str,
        read_uv: impl Fn(u32) -> Option<Vec<DVec2>>,
        images: &mut Images,
        warnings: &mut Vec<String>,
    ) -> Result<Option<(u32, Vec<DVec2>)>> {
        let Some(info) = info else {
            return Ok(None);
        };
        let source = images.source;
        let tex = info.texture();
        let wrap = crate::gltf_resources::wrap_of(&tex);
        let image = tex.source().index();
        let index = match self.texture_of.iter().find(|(k, _)| *k == (image, wrap)) {
            Some(&(_, i)) => i,
            None => {
                let name = tex.source().name().map_or_else(
                    || format!("{source}: image {image}"),
                    |n| format!("{source}: image `{n}`"),
                );
                (self.textures).push(crate::gltf_resources::decode_image(
                    &tex.source(),
                    &name,
                    wrap,
                    images,
                )?);
                (self.texture_of).push(((image, wrap), self.textures.len() as u32 - 1));
                self.textures.len() as u32 - 1
            }
        };
        let uv = crate::gltf_resources::info_uv(&info, read_uv);
        Ok(match uv {
            Some(uv) => Some((index, uv)),
            None => {
                warnings.push(format!(
                    "{source}: mesh `{mesh}`: a baseColorTexture but no TEXCOORD_{}: \
                     its baseColorFactor is used",
                    info.tex_coord()
                ));
                None
            }
        })
    }
}

/// What the node walk of [`gltf_with`] finds: the faces with their objects and parts, the
/// materials checked, the textures, cut-outs and emissive textures, the camera, the lights,
/// the provenance, and the warnings.
struct GltfFaces {
    faces: Vec<Face>,
    objects: Vec<String>,
    warnings: Vec<String>,
    /// Point and line primitives skipped, for the warning.
    skipped: Vec<String>,
    /// Per material (index; `None`: the default material) checked: its ρ.
    checked: Vec<(Option<usize>, Spectrum)>,
    base_colours: BaseColours,
    cutouts: Cutouts,
    emissive: EmissiveTextures,
    /// Per part: whether its material is doubleSided.
    two_sided: Vec<bool>,
    /// The next face's surface (one per triangle).
    surface: u32,
    camera: Option<Camera>,
    lights: Vec<Arc<dyn Light>>,
    provenance: GltfSource,
    parts: Vec<Part>,
}

impl GltfFaces {
    /// Nothing found yet, in the document described by `provenance`.
    fn new(provenance: GltfSource) -> Self {
        Self {
            faces: Vec::new(),
            objects: Vec::new(),
            warnings: Vec::new(),
            skipped: Vec::new(),
            checked: Vec::new(),
            base_colours: BaseColours::default(),
            cutouts: Cutouts::default(),
            emissive: EmissiveTextures::default(),
            two_sided: Vec::new(),
            surface: 0,
            camera: None,
            lights: Vec::new(),
            provenance,
            parts: Vec::new(),
        }
    }

    /// Adds what `node` (world transform `world`) carries: its world transform to the
    /// provenance, its camera unless one was found ([`gltf_camera`]), its light, and its
    /// mesh's primitives ([`Self::add_primitive`]) as one object.
    fn add_node(&mut self, node: &gltf::Node, world: DMat4, images: &mut Images) -> Result<()> {
        let source = images.source;
        if let Some(n) = self.provenance.nodes.get_mut(node.index()) {
            n.world = Some(world);
        }
        if self.camera.is_none() {
            self.camera = gltf_camera(node, world, source, &mut self.warnings);
        }
        (self.lights).extend(crate::gltf_lights::node_light(node, world, source)?);
        let Some(mesh) = node.mesh() else {
            return Ok(());
        };
        let obj_name = node
            .name()
            .or(mesh.name())
            .map_or_else(|| format!("node{}", node.index()), String::from);
        let at = Instance {
            node: node.index() as u32,
            mesh: mesh.index() as u32,
            object: self.objects.len() as u32,
            name: obj_name.clone(),
            world,
            flip: world.determinant() < 0.0,
        };
        self.objects.push(obj_name);
        for prim in mesh.primitives() {
            self.add_primitive(&prim, &at, images)?;
        }
        Ok(())
    }

    /// Adds primitive `prim` of the mesh instance `at` as a part: its triangles (strips and
    /// fans too) as faces with its material's ρ and E, base colour texture, cut-out and
    /// emissive texture; a point or line primitive is skipped (and named for the warning).
    fn add_primitive(
        &mut self,
        prim: &gltf::Primitive,
        at: &Instance,
        images: &mut Images,
    ) -> Result<()> {
        use gltf::mesh::Mode;
        let (source, buffers) = (images.source, images.buffers);
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            self.skipped.push(format!("`{}` ({mode:?})", at.name));
            return Ok(());
        }
        crate::gltf_accessors::check_primitive(prim, &at.name, buffers, source)?;
        let part = self.parts.len() as u32;
        self.two_sided.push(prim.material().double_sided());
        self.parts.push(Part {
            object: at.object,
            node: Some(at.node),
            mesh: Some(at.mesh),
            primitive: prim.index() as u32,
        });
        let mat = prim.material();
        let strength = f64::from(mat.emissive_strength().unwrap_or(1.0));
        let ef = mat.emissive_factor();
        let e = Spectrum(ef.map(|v| f64::from(v) * strength * PI));
        let rho = self.rho_of(&mat, e, source)?;
        let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let read_uv = |k: u32| {
            (reader.read_tex_coords(k)).map(|c| {
                (c.into_f32())
                    .map(|[u, v]| DVec2::new(f64::from(u), f64::from(v)))
                    .collect::<Vec<_>>()
            })
        };
        // ⟨baseColorTexture × baseColorFactor, on its TEXCOORD set⟩
        let info = mat.pbr_metallic_roughness().base_color_texture();
        let texture = (self.base_colours).of_primitive(
            info,
            &at.name,
            read_uv,
            images,
            &mut self.warnings,
        )?;
        // ⟨alphaMode: cut-outs; emissiveTexture⟩
        let alpha = (self.cutouts).of_primitive(
            &mat,
            e.max() > 0.0,
            read_uv,
            images,
            &mut self.warnings,
        )?;
        let emissive_map = match e.max() > 0.0 {
            true => self.emissive.of_primitive(&mat, read_uv, images)?,
            false => None,
        };
        // ⟨The triangles, in world coordinates⟩
        let pos = world_positions(reader.read_positions(), at, source)?;
        let tris = triangles(reader.read_indices(), pos.len(), mode);
        let look = PrimitiveLook {
            part,
            rho,
            e,
            texture,
            alpha,
            emissive_map,
            lightmap_uv: read_uv(1),
        };
        self.add_faces(&pos, tris, at, &look, source)
    }

    /// ρ of material `mat` (emitting `e`): its `baseColorFactor.rgb`, checked once per material
    /// ([`check_file_material`]: ρ ≥ 1 clamped with a warning naming it).
    fn rho_of(&mut self, mat: &gltf::Material, e: Spectrum, source: &str) -> Result<Spectrum> {
        if let Some(&(_, rho)) = self.checked.iter().find(|(i, _)| *i == mat.index()) {
            return Ok(rho);
        }
        let name = match (mat.name(), mat.index()) {
            (Some(n), _) => n.to_string(),
            (None, Some(i)) => format!("material {i}"),
            (None, None) => "the default material".to_string(),
        };
        let bc = mat.pbr_metallic_roughness().base_color_factor();
        let rho = Spectrum([bc[0], bc[1], bc[2]].map(f64::from));
        let rho = check_file_material(source, &name, rho, e, &mut self.warnings)?;
        self.checked.push((mat.index(), rho));
        Ok(rho)
    }

    /// Adds the triangles `tris` (indices into the world positions `pos`) of a primitive of the
    /// mesh instance `at` as faces that look as `look` says, wound the other way when `at`
    /// mirrors; a face cut out everywhere is only counted. An index out of range is an error
    /// naming the mesh.
    fn add_faces(
        &mut self,
        pos: &[DVec3],
        tris: Vec<[u32; 3]>,
        at: &Instance,
        look: &PrimitiveLook,
        source: &str,
    ) -> Result<()> {
        for t in tris {
            let get = |i: u32| {
                pos.get(i as usize)
                    .copied()
                    .ok_or_else(|| SceneError::Parse {
                        source_name: source.into(),
                        message: format!(
                            "mesh `{}`: index {i} out of range ({} vertices)",
                            at.name,
                            pos.len()
                        ),
                    })
            };
            let (a, b, c) = (get(t[0])?, get(t[1])?, get(t[2])?);
            let (v, corners) = if at.flip {
                ([a, c, b], [t[0], t[2], t[1]])
            } else {
                ([a, b, c], t)
            };
            let mut face = Face {
                part: look.part,
                lightmap_uv: (look.lightmap_uv.as_ref()).and_then(|uv| corner_uvs(uv, corners)),
                ..Face::new(v, look.rho, look.e, at.object, self.surface)
            };
            if let Some((tex, uv)) = &look.emissive_map {
                if let Some(uv) = corner_uvs(uv, corners) {
                    self.emissive.add(self.faces.len(), *tex, uv, look.e);
                }
            }
            match &look.alpha {
                Alpha::Opaque => {}
                Alpha::Hidden => {
                    self.cutouts.hidden += 1;
                    continue;
                }
                Alpha::Cut {
                    mask,
                    uv,
                    threshold,
                } => {
                    if let Some(uv) = corner_uvs(uv, corners) {
                        face.cutout = Some(crate::FaceCutout {
                            mask: *mask,
                            uv,
                            threshold: *threshold,
                        });
                    }
                }
            }
            if let Some((index, uv)) = &look.texture {
                if let Some(uv) = corner_uvs(uv, corners) {
                    let ft = FaceTexture {
                        texture: *index,
                        uv,
                        factor: look.rho,
                    };
                    face.texture = Some(ft);
                }
            }
            self.faces.push(face);
            self.surface += 1;
        }
        Ok(())
    }

    /// The scene of the faces found (named after `path`), with the camera, textures, cut-out
    /// masks, parts, provenance and lights; textured faces' ρ and emissive-textured faces' E
    /// their texture's mean; back faces for doubleSided materials unless `options` say
    /// single-sided; the warnings after the scene's own. A file whose primitives are all
    /// points or lines is an error saying so.
    fn into_scene(self, path: &Path, source: &str, options: &LoadOptions) -> Result<Scene> {
        let skipped = self.skipped;
        if self.faces.is_empty() && !skipped.is_empty() {
            return Err(SceneError::Parse {
                source_name: source.into(),
                message: format!(
                    "no triangles: every primitive is points or lines ({}), which have no area to light",
                    skipped.join(", ")
                ),
            });
        }
        let (mut faces, mut warnings, textures) =
            (self.faces, self.warnings, self.base_colours.textures);
        average_albedo(&mut faces, &textures);
        let emitting = self.emissive.apply(&mut faces);
        if emitting > 0 {
            warnings.push(format!(
                "{source}: {emitting} face(s) with an emissiveTexture emit its mean over each face \
                 (constant per face: a pattern finer than the faces is averaged)"
            ));
        }
        if self.cutouts.hidden > 0 {
            warnings.push(format!(
                "{source}: dropped {} face(s) whose material's alpha is below its alphaCutoff              everywhere (fully cut out)",
                self.cutouts.hidden
            ));
        }
        let mut scene = Scene::new(&stem(path), source, faces, self.objects, self.camera)?
            .with_textures(textures)?
            .with_masks(self.cutouts.masks)?;
        scene.parts = self.parts;
        scene.gltf = Some(Box::new(self.provenance));
        if !options.single_sided {
            let two_sided = self.two_sided;
            let backs = scene.add_back_faces(|f| two_sided.get(f.part as usize) == Some(&true));
            if backs > 0 {
                warnings.push(format!(
                    "{source}: {backs} face(s) of doubleSided materials got a back face (both sides \
                     reflect and are solved); for closed solids --single-sided halves the work"
                ));
            }
        }
        scene.add_lights(self.lights);
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
}

/// The positions of a primitive's vertices (`positions`, its POSITION attribute) in world
/// coordinates (the mesh instance `at`'s transform); an error naming the mesh without them.
fn world_positions(
    positions: Option<gltf::mesh::util::ReadPositions>,
    at: &Instance,
    source: &str,
) -> Result<Vec<DVec3>> {
    let Some(pos) = positions else {
        return Err(SceneError::Parse {
            source_name: source.into(),
            message: format!("mesh `{}`: primitive without POSITION", at.name),
        });
    };
    Ok(pos
        .map(|p| (at.world).transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
        .collect())
}

/// The triangles (vertex indices) of a primitive of `mode` with `indices` (without them: its
/// `vertices` vertices in order). Strips and fans as triangle lists (glTF 2.0 §3.7.2.1: strip
/// triangle i is (i, i+1, i+2) for even i and (i+1, i, i+2) for odd i, so that every triangle
/// winds like the first; fan i is (i+1, i+2, 0)).
fn triangles(
    indices: Option<gltf::mesh::util::ReadIndices>,
    vertices: usize,
    mode: gltf::mesh::Mode,
) -> Vec<[u32; 3]> {
    use gltf::mesh::Mode;
    let idx: Vec<u32> = match indices {
        Some(i) => i.into_u32().collect(),
        None => (0..vertices as u32).collect(),
    };
    match mode {
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
    }
}

/// The per-vertex texture coordinates `uv` at a triangle's `corners`, if all three exist.
fn corner_uvs(uv: &[DVec2], corners: [u32; 3]) -> Option<[DVec2; 3]> {
    match corners.map(|i| uv.get(i as usize).copied()) {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        _ => None,
    }
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
