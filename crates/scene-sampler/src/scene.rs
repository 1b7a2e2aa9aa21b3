//! The 3-D scene model: triangles with per-face reflectance and emission, validated on construction.

use crate::provenance::{GltfSource, Part};
use crate::{
    AlphaMask, EmitterTable, FaceCutout, FaceTexture, Light, LightSet, Result, SceneError,
    Spectrum, Texture,
};
use glam::DVec3;
use rayon::prelude::*;
use std::sync::Arc;

/// A pinhole camera for images of a scene (right-handed, `up` roughly perpendicular to the view direction).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Up direction.
    pub up: DVec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
}

impl Camera {
    /// A camera that frames an axis-aligned box `[lo, hi]` from the `-z` side, looking toward `+z`.
    pub fn framing(lo: DVec3, hi: DVec3) -> Self {
        let c = 0.5 * (lo + hi);
        let r = 0.5 * (hi - lo).length();
        let fov: f64 = 40.0;
        let dist = r / (0.5 * fov.to_radians()).tan() * 1.1;
        Camera {
            eye: c - DVec3::Z * dist,
            target: c,
            up: DVec3::Y,
            fov_y_deg: fov,
        }
    }
}

/// One triangle of a scene with its (constant) material.
///
/// Winding defines the front side: `normal = normalize((v1 - v0) × (v2 - v0))` (FORMATS.md). Only the front
/// side reflects and emits; the back is black and, for visibility, still opaque.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Face {
    /// Vertices, counter-clockwise seen from the front.
    pub v: [DVec3; 3],
    /// Unit geometric normal (front side).
    pub normal: DVec3,
    /// Area (> 0).
    pub area: f64,
    /// Diffuse reflectance ρ per band, each in `[0, 1)`.
    pub rho: Spectrum,
    /// Emitted radiosity (exitance) E per band, `E = π·Ke` for a file's emitted radiance Ke.
    pub emission: Spectrum,
    /// Object index (into [`Scene::objects`]): OBJ object/group, glTF mesh instance, or built-in part.
    pub object: u32,
    /// Surface index: faces that form one flat polygon of the input (a triangulated quad shares one id).
    pub surface: u32,
    /// The albedo texture mapping of a textured face ([`Scene::rho_at`]); [`Face::rho`] is then the
    /// face's mean reflectance.
    pub texture: Option<FaceTexture>,
    /// Part index (into [`Scene::parts`]): the input primitive of the node instance the face came
    /// from (glTF), or its object ([`Face::new`] sets `part = object`).
    pub part: u32,
    /// The alpha mask that cuts holes in the face ([`crate::cutout`]), if any.
    pub cutout: Option<FaceCutout>,
    /// The input's lightmap coordinates of the corners `v[0..3]` (glTF `TEXCOORD_1`), which a
    /// lightmap bake reuses instead of unwrapping the scene; `None` when the input has none.
    pub lightmap_uv: Option<[glam::DVec2; 3]>,
}

impl Face {
    /// Builds a face from its vertices and material; normal and area are computed (area may be 0: see
    /// [`Scene::new`] for how degenerate faces are handled).
    pub fn new(
        v: [DVec3; 3],
        rho: Spectrum,
        emission: Spectrum,
        object: u32,
        surface: u32,
    ) -> Self {
        let c = (v[1] - v[0]).cross(v[2] - v[0]);
        let len = c.length();
        let normal = if len > 0.0 { c / len } else { DVec3::ZERO };
        Face {
            v,
            normal,
            area: 0.5 * len,
            rho,
            emission,
            object,
            surface,
            texture: None,
            part: object,
            cutout: None,
            lightmap_uv: None,
        }
    }

    /// The face seen from its back: the same triangle wound the other way (its normal reversed,
    /// `v[1]` and `v[2]` swapped with their texture coordinates), the same material, on surface
    /// `surface` — the back of a two-sided face (glTF `doubleSided`), which keeps its own radiosity.
    pub fn flipped(&self, surface: u32) -> Face {
        let swap = |uv: [glam::DVec2; 3]| [uv[0], uv[2], uv[1]];
        Face {
            v: [self.v[0], self.v[2], self.v[1]],
            normal: -self.normal,
            surface,
            texture: self.texture.map(|t| FaceTexture {
                uv: swap(t.uv),
                ..t
            }),
            cutout: self.cutout.map(|c| FaceCutout {
                uv: swap(c.uv),
                ..c
            }),
            lightmap_uv: self.lightmap_uv.map(swap),
            ..*self
        }
    }

    /// The barycentric weights `(b1, b2)` of `p` projected onto the face's plane
    /// ([`Face::point`] inverts it for points on the face).
    pub fn barycentric(&self, p: DVec3) -> (f64, f64) {
        let (e1, e2, d) = (self.v[1] - self.v[0], self.v[2] - self.v[0], p - self.v[0]);
        let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (p1, p2) = (d.dot(e1), d.dot(e2));
        let det = a * c - b * b;
        if det <= 0.0 {
            return (0.0, 0.0);
        }
        ((c * p1 - b * p2) / det, (a * p2 - b * p1) / det)
    }
    /// The point with barycentric weights `(1 - b1 - b2, b1, b2)`.
    pub fn point(&self, b1: f64, b2: f64) -> DVec3 {
        self.v[0] + b1 * (self.v[1] - self.v[0]) + b2 * (self.v[2] - self.v[0])
    }
    /// Centroid.
    pub fn centroid(&self) -> DVec3 {
        (self.v[0] + self.v[1] + self.v[2]) / 3.0
    }
    /// Closest point of the triangle to `p` (Ericson, *Real-Time Collision Detection*, 5.1.5).
    pub fn closest_point(&self, p: DVec3) -> DVec3 {
        let [a, b, c] = self.v;
        let ab = b - a;
        let ac = c - a;
        let ap = p - a;
        let d1 = ab.dot(ap);
        let d2 = ac.dot(ap);
        if d1 <= 0.0 && d2 <= 0.0 {
            return a;
        }
        let bp = p - b;
        let d3 = ab.dot(bp);
        let d4 = ac.dot(bp);
        if d3 >= 0.0 && d4 <= d3 {
            return b;
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return a + ab * (d1 / (d1 - d3));
        }
        let cp = p - c;
        let d5 = ab.dot(cp);
        let d6 = ac.dot(cp);
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return a + ac * (d2 / (d2 - d6));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
        }
        let denom = 1.0 / (va + vb + vc);
        a + ab * (vb * denom) + ac * (vc * denom)
    }
}

/// A validated 3-D radiosity scene.
///
/// Construct it with [`Scene::new`] (which validates), a loader ([`crate::load`](fn@crate::load)) or a built-in
/// ([`crate::builtin`](fn@crate::builtin)). The face list is immutable afterwards so that samplers and BVHs built from it stay valid.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name (file stem or built-in name).
    pub name: String,
    /// Source used in messages (path or `builtin:<name>`).
    pub source: String,
    /// 1 for grey scenes (every ρ and E grey), 3 for RGB.
    pub bands: usize,
    /// The triangles (degenerate input faces already dropped).
    pub faces: Vec<Face>,
    /// Object names; `Face::object` indexes this.
    pub objects: Vec<String>,
    /// Default camera for images.
    pub camera: Camera,
    /// Whether [`Scene::camera`] came with the scene (a built-in's published camera, a glTF camera
    /// node); `false` when it is the bounding-box fallback of [`Camera::framing`], which image
    /// outputs replace by an automatic camera that sees closed scenes from inside.
    pub camera_given: bool,
    /// Non-fatal problems found on load (dropped degenerate faces, inconsistent windings), one message each.
    pub warnings: Vec<String>,
    /// Axis-aligned bounds `(lo, hi)` of all vertices.
    pub bounds: (DVec3, DVec3),
    /// Albedo textures, indexed by [`FaceTexture::texture`] (empty for untextured scenes).
    pub textures: Vec<Texture>,
    /// The input parts ([`Face::part`] indexes this): one per object unless a loader knows more
    /// (glTF: one per primitive of each node instance).
    pub parts: Vec<Part>,
    /// The glTF document the scene came from (node tree, mesh and material names), for writers
    /// that give an output the input's structure; `None` for OBJ, built-ins and [`Scene::new`].
    pub gltf: Option<Box<GltfSource>>,
    /// Lights other than the emitting faces (sun, sky, point and spot lights: [`crate::lights`]),
    /// from the input (glTF `KHR_lights_punctual`) or given by the caller before solving.
    pub lights: Vec<Arc<dyn Light>>,
    /// Alpha masks, indexed by [`FaceCutout::mask`] (empty without cut-outs).
    pub masks: Vec<AlphaMask>,
}

impl Scene {
    /// Validates `faces` and builds the scene.
    ///
    /// * Non-finite vertex coordinates, ρ or E: error naming the face.
    /// * ρ outside `[0, 1)` in any band: error (energy would not be conserved). Negative E: error.
    /// * Degenerate faces (area ≤ 1e-14 · diagonal², or zero normal): dropped, with a count in `warnings`;
    ///   error if nothing remains.
    /// * A bounding-box diagonal outside `[1e-9, 1e12]` (the f32 BVH's range): error.
    /// * No face with positive emission: allowed (lights may be added to [`Scene::lights`]); the
    ///   solvers refuse a scene that nothing lights ([`Scene::check_lit`]).
    /// * Coincident duplicate faces (same vertices and winding): merged with a warning naming them, or an
    ///   error if their materials differ (see `merge_duplicates`).
    /// * Inconsistent windings (two faces of one object sharing an edge traversed in the same direction):
    ///   reported in `warnings` per object, never "fixed" (FORMATS.md: report, don't guess).
    ///
    /// `camera = None` picks a camera framing the scene bounds. Each face keeps its
    /// [`Face::part`]; [`Scene::parts`] gets one [`Part::of_object`] per part index (the object
    /// of that index: with [`Face::new`]'s `part = object` one part per object), and
    /// [`Scene::gltf`] is `None`: a loader that knows more sets both afterwards.
    pub fn new(
        name: &str,
        source: &str,
        faces: Vec<Face>,
        objects: Vec<String>,
        camera: Option<Camera>,
    ) -> Result<Scene> {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for (i, f) in faces.iter().enumerate() {
            if !f.v.iter().all(|v| v.is_finite()) {
                return Err(SceneError::NonFinite {
                    source_name: source.into(),
                    face: i,
                    what: "vertex coordinate".into(),
                });
            }
            check_material(source, i, f.rho, f.emission)?;
            for v in f.v {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        let diag2 = if faces.is_empty() {
            0.0
        } else {
            (hi - lo).length_squared()
        };
        let mut warnings = Vec::new();
        let n_in = faces.len();
        // (in place: a face is 384 bytes, and a second vector of a million of them was most of
        // a large model's peak memory at load)
        let mut kept = faces;
        kept.par_iter_mut().for_each(|f| {
            *f = Face {
                texture: f.texture.take(),
                part: f.part,
                cutout: f.cutout.take(),
                lightmap_uv: f.lightmap_uv,
                ..Face::new(f.v, f.rho, f.emission, f.object, f.surface)
            }
        });
        let degenerate =
            |f: &Face| f.area <= 1e-14 * diag2 || f.normal == DVec3::ZERO || !f.normal.is_finite();
        let (mut dropped_ids, mut i) = (Vec::new(), 0);
        kept.retain(|f| {
            let keep = !degenerate(f);
            if !keep {
                dropped_ids.push(i);
            }
            i += 1;
            keep
        });
        if !dropped_ids.is_empty() {
            let shown: Vec<String> = dropped_ids.iter().take(10).map(|i| i.to_string()).collect();
            warnings.push(format!(
                "{source}: dropped {} degenerate face(s) (zero area): {}{}",
                dropped_ids.len(),
                shown.join(", "),
                if dropped_ids.len() > 10 { ", ..." } else { "" }
            ));
        }
        if kept.is_empty() {
            return Err(SceneError::NoFaces {
                source_name: source.into(),
                dropped: dropped_ids.len(),
            });
        }
        // The BVH is f32 relative to the scene's centre: its boxes' surface areas (∝ size²) must stay well
        // inside f32's range (3·10³⁸, down to 10⁻³⁸); obvhs panics on a build when they overflow (found by
        // the fuzz test: two triangles 10³¹ across).
        let diagonal = diag2.sqrt();
        if !(1e-9..=1e12).contains(&diagonal) {
            return Err(SceneError::ExtentOutOfRange {
                source_name: source.into(),
                diagonal,
            });
        }
        let mut objects = objects;
        let max_obj = kept
            .iter()
            .map(|f| f.object as usize + 1)
            .max()
            .unwrap_or(0);
        while objects.len() < max_obj {
            objects.push(format!("object{}", objects.len()));
        }
        let kept = merge_duplicates(
            source,
            kept,
            &kept_ids(n_in, &dropped_ids),
            &objects,
            &mut warnings,
        )?;
        for (object, edges) in inconsistent_windings(&kept) {
            warnings.push(format!(
                "{source}: object `{}`: {edges} edge(s) shared by two of its faces with the same direction: \
                 inconsistent windings (normals) — front sides may be wrong",
                objects[object as usize]
            ));
        }
        let n_parts = kept
            .iter()
            .map(|f| f.part as usize + 1)
            .max()
            .unwrap_or(0)
            .max(objects.len());
        let parts = (0..n_parts as u32).map(Part::of_object).collect();
        let grey = kept.iter().all(|f| f.rho.is_grey() && f.emission.is_grey());
        let camera_given = camera.is_some();
        let camera = camera.unwrap_or_else(|| Camera::framing(lo, hi));
        Ok(Scene {
            name: name.into(),
            source: source.into(),
            bands: if grey { 1 } else { 3 },
            faces: kept,
            objects,
            camera,
            camera_given,
            warnings,
            bounds: (lo, hi),
            textures: Vec::new(),
            parts,
            gltf: None,
            lights: Vec::new(),
            masks: Vec::new(),
        })
    }

    /// Adds `lights` to [`Scene::lights`]; a light whose colour is not grey makes the scene RGB
    /// ([`Scene::bands`] 3).
    pub fn add_lights(&mut self, lights: impl IntoIterator<Item = Arc<dyn Light>>) {
        for light in lights {
            if !light.is_grey() {
                self.bands = 3;
            }
            self.lights.push(light);
        }
    }

    /// Errs ([`SceneError::NoEmitter`], with how to light the scene) when nothing gives light: no
    /// face emits and no light of positive power is in [`Scene::lights`].
    pub fn check_lit(&self) -> Result<()> {
        if LightSet::of_scene(self).is_empty() {
            return Err(SceneError::NoEmitter {
                source_name: self.source.clone(),
            });
        }
        Ok(())
    }

    /// Attaches the textures the faces' [`Face::texture`] mappings index (a loader's last step):
    /// a scene with a textured face reports all three bands.
    ///
    /// # Errors
    /// A face that names a texture that is not in `textures`.
    pub fn with_textures(mut self, textures: Vec<Texture>) -> Result<Self> {
        if let Some(i) = self.faces.iter().position(|f| {
            f.texture
                .is_some_and(|t| t.texture as usize >= textures.len())
        }) {
            return Err(SceneError::Parse {
                source_name: self.source.clone(),
                message: format!("face {i} names a texture that was not loaded"),
            });
        }
        if self.faces.iter().any(|f| f.texture.is_some()) {
            self.bands = 3;
        }
        self.textures = textures;
        Ok(self)
    }

    /// Gives every face for which `two_sided` holds a back face ([`Face::flipped`], appended after
    /// the faces, each on a surface of its own): both sides then reflect, emit and keep their own
    /// radiosity (glTF `doubleSided`). A face whose back the input already has is skipped. Returns
    /// how many were added.
    pub fn add_back_faces(&mut self, two_sided: impl Fn(&Face) -> bool) -> usize {
        // a back the input already models (the same triangle wound the other way) is not added
        let (lo, grid) = (self.bounds.0, 1e-9 * self.diagonal());
        let have: std::collections::HashSet<[[i64; 3]; 3]> = self
            .faces
            .iter()
            .map(|f| winding_key(f, lo, grid))
            .collect();
        let mut surface = self.faces.iter().map(|f| f.surface + 1).max().unwrap_or(0);
        let backs: Vec<Face> = (self.faces.iter())
            .filter(|f| two_sided(f))
            .map(|f| f.flipped(0))
            .filter(|b| !have.contains(&winding_key(b, lo, grid)))
            .map(|b| {
                surface += 1;
                Face {
                    surface: surface - 1,
                    ..b
                }
            })
            .collect();
        let n = backs.len();
        self.faces.extend(backs);
        n
    }

    /// Attaches the alpha masks the faces' [`Face::cutout`]s index (a loader's last step).
    ///
    /// # Errors
    /// A face that names a mask that is not in `masks`.
    pub fn with_masks(mut self, masks: Vec<AlphaMask>) -> Result<Self> {
        if let Some(i) = (self.faces.iter())
            .position(|f| f.cutout.is_some_and(|c| c.mask as usize >= masks.len()))
        {
            return Err(SceneError::Parse {
                source_name: self.source.clone(),
                message: format!("face {i} names an alpha mask that was not loaded"),
            });
        }
        self.masks = masks;
        Ok(self)
    }

    /// Whether `point` on face `face` lies in one of its cut-out holes ([`crate::cutout`]).
    pub fn is_hole(&self, face: u32, point: DVec3) -> bool {
        let f = &self.faces[face as usize];
        f.cutout.is_some_and(|c| {
            let (b1, b2) = f.barycentric(point);
            c.is_hole(&self.masks, b1, b2)
        })
    }

    /// ρ at `point` on face `face`: the face's constant ρ, or for a textured face its texture
    /// there ([`FaceTexture::rho`], the point projected onto the face's plane). This is the
    /// reflectance every pointwise estimator uses: the kernel, the gathers and the path tracers.
    pub fn rho_at(&self, face: u32, point: DVec3) -> Spectrum {
        let f = &self.faces[face as usize];
        match &f.texture {
            None => f.rho,
            Some(t) => {
                let (b1, b2) = f.barycentric(point);
                t.rho(&self.textures, b1, b2)
            }
        }
    }

    /// Total surface area.
    pub fn total_area(&self) -> f64 {
        self.faces.iter().map(|f| f.area).sum()
    }
    /// Length of the bounding-box diagonal (the scene's length scale).
    pub fn diagonal(&self) -> f64 {
        (self.bounds.1 - self.bounds.0).length()
    }
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.faces.len()
    }
    /// True if the scene has no faces (never true for a validated scene).
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }
    /// Indices of the faces that emit (some band > 0).
    pub fn emitters(&self) -> Vec<usize> {
        (0..self.faces.len())
            .filter(|&i| self.faces[i].emission.max() > 0.0)
            .collect()
    }
}

/// The largest reflectance a scene file may give: a file's ρ ≥ 1 in some band (which would create energy) is
/// clamped to this, with one warning naming the material. Not refused: white (1, 1, 1) is the common
/// default of modelling tools, e.g. glTF's `baseColorFactor`.
pub const RHO_MAX: f64 = 0.98;

/// Checks a file's material, clamping ρ ≥ 1 to [`RHO_MAX`] (one warning in `warnings`). Negative or
/// non-finite ρ or emission is an error naming the material. `e` is the emitted radiosity (already ×π).
pub(crate) fn check_file_material(
    source: &str,
    material: &str,
    rho: Spectrum,
    e: Spectrum,
    warnings: &mut Vec<String>,
) -> Result<Spectrum> {
    let bad = |message: String| SceneError::BadMaterial {
        source_name: source.into(),
        material: material.into(),
        message,
    };
    for (what, v) in [("reflectance", rho), ("emission", e)] {
        if let Some(x) = v.0.iter().find(|x| !x.is_finite()) {
            return Err(bad(format!("non-finite {what} {x}")));
        }
        if let Some(x) = v.0.iter().find(|&&x| x < 0.0) {
            return Err(bad(format!("negative {what} {x}")));
        }
    }
    if rho.0.iter().any(|&x| x >= 1.0) {
        warnings.push(format!(
            "{source}: material `{material}`: reflectance {} {} {} is not below 1 (it would create energy); \
             clamped to {RHO_MAX}",
            rho.0[0], rho.0[1], rho.0[2]
        ));
        return Ok(Spectrum(rho.0.map(|x| if x >= 1.0 { RHO_MAX } else { x })));
    }
    Ok(rho)
}

/// Checks ρ ∈ [0,1) and E ≥ 0, both finite, for face `i`.
pub(crate) fn check_material(source: &str, i: usize, rho: Spectrum, e: Spectrum) -> Result<()> {
    if !rho.is_finite() {
        return Err(SceneError::NonFinite {
            source_name: source.into(),
            face: i,
            what: "reflectance".into(),
        });
    }
    if !e.is_finite() {
        return Err(SceneError::NonFinite {
            source_name: source.into(),
            face: i,
            what: "emission".into(),
        });
    }
    for (band, &value) in rho.0.iter().enumerate() {
        if !(0.0..1.0).contains(&value) {
            return Err(SceneError::ReflectanceOutOfRange {
                source_name: source.into(),
                face: i,
                band,
                value,
            });
        }
    }
    for (band, &value) in e.0.iter().enumerate() {
        if value < 0.0 {
            return Err(SceneError::NegativeEmission {
                source_name: source.into(),
                face: i,
                band,
                value,
            });
        }
    }
    Ok(())
}

/// The load-order indices of the faces kept after dropping `dropped` (sorted) from `0..n`.
fn kept_ids(n: usize, dropped: &[usize]) -> Vec<usize> {
    let mut d = dropped.iter().peekable();
    (0..n)
        .filter(|i| {
            if d.peek() == Some(&i) {
                d.next();
                false
            } else {
                true
            }
        })
        .collect()
}

/// Removes coincident duplicate faces: the same three vertices (within `1e-9 · diagonal`, each coordinate
/// rounded to that grid) in the same cyclic order, i.e. the same triangle with the same front side. A light
/// quad written twice would otherwise emit twice: B doubles in the solvers that integrate over faces, and
/// not in a path tracer (which sees only the face a ray hits first). Duplicates with the same material
/// ([`same_material`]: for textured faces the same texture and factor, whatever their texture
/// coordinates) are merged (the first kept) with a warning naming them; with different materials the
/// scene is refused ([`SceneError::ConflictingDuplicate`]), since which one a ray sees would be decided
/// by rounding. Coincident faces with *opposite* windings are two-sided thin geometry and are kept.
fn merge_duplicates(
    source: &str,
    mut faces: Vec<Face>,
    ids: &[usize],
    objects: &[String],
    warnings: &mut Vec<String>,
) -> Result<Vec<Face>> {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for f in &faces {
        for v in f.v {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let grid = 1e-9 * (hi - lo).length();
    let name = |o: u32| objects.get(o as usize).cloned().unwrap_or_default();
    // ⟨Each face's first coincident face (itself if none comes before it): the faces sorted by
    // key, then by index (sorting, not hashing: 0.2 s instead of 1 s for a million faces)⟩
    let mut keyed: Vec<([[i64; 3]; 3], usize)> = (faces.par_iter().enumerate())
        .map(|(k, f)| (winding_key(f, lo, grid), k))
        .collect();
    keyed.par_sort_unstable();
    let mut first: Vec<usize> = (0..faces.len()).collect();
    for run in keyed.chunk_by(|a, b| a.0 == b.0) {
        run[1..].iter().for_each(|&(_, k)| first[k] = run[0].1);
    }
    drop(keyed);
    // ⟨In the faces' order: a later face of another material refuses the scene, else it merges⟩
    let mut merged: Vec<String> = Vec::new();
    for (k, &j) in first.iter().enumerate().filter(|(k, j)| k != *j) {
        let (f, g) = (&faces[k], &faces[j]);
        if !same_material(g, f) {
            return Err(SceneError::ConflictingDuplicate {
                source_name: source.into(),
                face: ids[k],
                object: name(f.object),
                other: ids[j],
                other_object: name(g.object),
            });
        }
        let uv = if g.texture == f.texture {
            ""
        } else {
            " (other texture coordinates)"
        };
        merged.push(format!(
            "face {} (object `{}`) = face {} (object `{}`){uv}",
            ids[k],
            name(f.object),
            ids[j],
            name(g.object)
        ));
    }
    if !merged.is_empty() {
        let mut k = 0;
        faces.retain(|_| {
            k += 1;
            first[k - 1] == k - 1
        });
    }
    if !merged.is_empty() {
        warnings.push(format!(
            "{source}: merged {} coincident duplicate face(s) (same vertices, winding and material, the \
             first one's texture coordinates kept; each would have counted twice): {}{}",
            merged.len(),
            merged[..merged.len().min(10)].join(", "),
            if merged.len() > 10 { ", ..." } else { "" }
        ));
    }
    Ok(faces)
}

/// A key equal for the same triangle with the same winding, whatever vertex it was written from:
/// its vertices snapped to a grid of spacing `grid` from `lo`, the cycle rotated to start at the
/// smallest.
fn winding_key(f: &Face, lo: DVec3, grid: f64) -> [[i64; 3]; 3] {
    let q = |p: DVec3| {
        let c = (p - lo) / grid;
        [c.x.round() as i64, c.y.round() as i64, c.z.round() as i64]
    };
    let k = f.v.map(q);
    let s = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
    [k[s], k[(s + 1) % 3], k[(s + 2) % 3]]
}

/// Whether two coincident faces are of one material: the same emission and albedo, textured faces by
/// the same texture times the same factor (their texture coordinates, and so their mean ρ, may differ:
/// a model's UV seam written twice).
fn same_material(a: &Face, b: &Face) -> bool {
    a.emission == b.emission
        && match (&a.texture, &b.texture) {
            (Some(x), Some(y)) => x.texture == y.texture && x.factor == y.factor,
            (None, None) => a.rho == b.rho,
            _ => false,
        }
}

/// Counts, per object, directed edges that appear twice within it (the two faces sharing them wind the same
/// way, so one of them has its normal flipped relative to the other). Vertices are matched exactly. Returns
/// `(object, edges)` for the objects with at least one, in object order.
///
/// By sorting, not hashing (a million faces: 0.3 s and 110 MB instead of 1.5 s and some 300 MB):
/// each distinct vertex a number (its place among the sorted distinct positions), then the
/// directed edges (object, from, to) sorted, a run of two or more being an edge two of the
/// object's faces wind alike.
fn inconsistent_windings(faces: &[Face]) -> Vec<(u32, usize)> {
    let key = |p: DVec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let mut points: Vec<[u64; 3]> = (faces.par_iter()).flat_map_iter(|f| f.v.map(key)).collect();
    points.par_sort_unstable();
    points.dedup();
    // (every vertex is among the points: the search always finds it)
    let id = |p: DVec3| points.binary_search(&key(p)).unwrap_or_else(|i| i) as u32;
    let mut edges: Vec<(u32, u32, u32)> = (faces.par_iter())
        .flat_map_iter(|f| {
            let v = f.v.map(id);
            (0..3).map(move |k| (f.object, v[k], v[(k + 1) % 3]))
        })
        .collect();
    drop(points);
    edges.par_sort_unstable();
    let mut bad: std::collections::BTreeMap<u32, usize> = Default::default();
    for run in edges.chunk_by(|a, b| a == b).filter(|run| run.len() >= 2) {
        *bad.entry(run[0].0).or_insert(0) += 1;
    }
    bad.into_iter().collect()
}

/// The scene's lights, written beside the scene (the lights module knows no scene).
impl EmitterTable {
    /// The emitting triangles of a 3-D scene.
    pub fn of_scene(scene: &Scene) -> Self {
        Self::new(
            (scene.faces.iter().enumerate()).map(|(i, f)| (i as u32, f.area, f.emission.mean())),
        )
    }
}

impl LightSet {
    /// The lights of a 3-D scene: its emitting faces and [`Scene::lights`], with a light tree
    /// over the faces and the lights that have a position.
    pub fn of_scene(scene: &Scene) -> Self {
        let (lo, hi) = scene.bounds;
        let faces = EmitterTable::of_scene(scene);
        let bounds = (0..faces.len())
            .map(|i| {
                let f = &scene.faces[faces.get(i).0 as usize];
                crate::LightBounds::face(f.v, f.normal, f.area * f.emission.mean())
            })
            .collect();
        Self::with_tree(
            faces,
            bounds,
            scene.lights.clone(),
            0.5 * (hi - lo).length(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face(v: [DVec3; 3], object: u32) -> Face {
        Face::new(v, Spectrum::grey(0.5), Spectrum::ZERO, object, 0)
    }

    /// An edge that two or more faces of one object traverse the same way counts once for the
    /// object; the same edge in another object, or traversed the other way, does not.
    #[test]
    fn windings_count_each_edge_two_faces_wind_alike_once_per_object() {
        let p = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::new(0.5, -1.0, 0.0),
            DVec3::new(0.5, 0.0, 1.0),
        ];
        let faces = vec![
            // object 0: p0 → p1 in three faces (one edge), p1 → p0 in none
            face([p[0], p[1], p[2]], 0),
            face([p[0], p[1], p[3]], 0),
            face([p[4], p[0], p[1]], 0),
            // object 1: consistent (p0 → p1 once, p1 → p0 once)
            face([p[0], p[1], p[2]], 1),
            face([p[1], p[0], p[3]], 1),
            // object 2: two edges wound alike
            face([p[0], p[1], p[2]], 2),
            face([p[1], p[2], p[3]], 2),
            face([p[0], p[1], p[4]], 2),
        ];
        assert_eq!(inconsistent_windings(&faces), vec![(0, 1), (2, 2)]);
    }

    /// Coincident faces (same vertices and winding, whatever vertex they start from) keep the
    /// first in the faces' order, the others merged with a warning naming each; the faces keep
    /// their order; another material refuses the scene, naming the later face.
    #[test]
    fn coincident_faces_keep_the_first_in_order() {
        let (a, b, c, d) = (DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z);
        let faces = vec![
            face([a, b, c], 0),
            face([a, b, d], 0),
            face([b, c, a], 1),
            face([c, b, a], 0),
            face([a, b, d], 0),
        ];
        let ids = [0, 1, 2, 3, 4];
        let objects = ["one".to_string(), "two".to_string()];
        let mut warnings = Vec::new();
        let kept = merge_duplicates("s", faces.clone(), &ids, &objects, &mut warnings).unwrap();
        assert_eq!(kept.len(), 3);
        assert_eq!(kept[0].v, faces[0].v);
        assert_eq!(kept[1].v, faces[1].v);
        assert_eq!(kept[2].v, faces[3].v);
        assert_eq!(warnings.len(), 1);
        assert!(
            warnings[0].contains("merged 2 coincident")
                && warnings[0].contains("face 2 (object `two`) = face 0 (object `one`), face 4"),
            "{}",
            warnings[0]
        );
        let mut other = faces;
        other[4].rho = Spectrum::grey(0.9);
        match merge_duplicates("s", other, &ids, &objects, &mut Vec::new()) {
            Err(SceneError::ConflictingDuplicate { face, other, .. }) => {
                assert_eq!((face, other), (4, 1));
            }
            r => panic!("{:?}", r.map(|f| f.len())),
        }
    }
}
