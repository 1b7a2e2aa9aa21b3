//! Flatland (2-D) scenes: segments with per-segment reflectance and emission, and their JSON format.

use crate::scene::check_material;
use crate::{Result, SceneError, Spectrum};
use glam::DVec2;

/// One segment of a Flatland scene.
///
/// The front side is to the LEFT of `a → b`: `normal = (b − a) rotated by +90°, normalized` (FORMATS.md).
/// Only the front reflects and emits; both sides block light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// Unit normal of the front side.
    pub normal: DVec2,
    /// Length (> 0).
    pub length: f64,
    /// Reflectance ρ per band, in `[0, 1)`.
    pub rho: Spectrum,
    /// Emitted radiosity (exitance) per band. Flatland files give it directly (no π factor).
    pub emission: Spectrum,
    /// Object index (into [`FlatlandScene::objects`]).
    pub object: u32,
    /// Surface index (segments of one straight input edge share it; in JSON every segment is its own surface).
    pub surface: u32,
}

impl Segment {
    /// Builds a segment; normal and length are computed.
    pub fn new(
        a: DVec2,
        b: DVec2,
        rho: Spectrum,
        emission: Spectrum,
        object: u32,
        surface: u32,
    ) -> Self {
        let d = b - a;
        let length = d.length();
        let normal = if length > 0.0 {
            DVec2::new(-d.y, d.x) / length
        } else {
            DVec2::ZERO
        };
        Segment {
            a,
            b,
            normal,
            length,
            rho,
            emission,
            object,
            surface,
        }
    }
    /// The point at fraction `t ∈ [0,1]` from `a` to `b`.
    pub fn point(&self, t: f64) -> DVec2 {
        self.a + t * (self.b - self.a)
    }
    /// Fraction along the segment of the closest point to `p`, clamped to `[0,1]`.
    pub fn closest_t(&self, p: DVec2) -> f64 {
        let d = self.b - self.a;
        ((p - self.a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
    }
}

/// The rectangle a Flatland figure shows: the "camera" of a 2-D scene.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FlatView {
    /// Lower-left corner.
    pub min: DVec2,
    /// Upper-right corner.
    pub max: DVec2,
}

/// A validated Flatland scene.
#[derive(Clone, Debug)]
pub struct FlatlandScene {
    /// Name (file stem or built-in name).
    pub name: String,
    /// Source used in messages.
    pub source: String,
    /// 1 for grey, 3 for RGB.
    pub bands: usize,
    /// The segments, in file order (degenerate ones dropped). This order defines the arc-length
    /// parameterization `s ∈ [0,1]` of [`crate::FlatSampler`] (fig. B.2).
    pub segments: Vec<Segment>,
    /// Object names.
    pub objects: Vec<String>,
    /// Default view rectangle for figures.
    pub view: FlatView,
    /// Non-fatal problems found on load.
    pub warnings: Vec<String>,
}

impl FlatlandScene {
    /// Validates and builds a Flatland scene (same rules as [`crate::Scene::new`]: finite coordinates, ρ ∈ [0,1),
    /// E ≥ 0, degenerate segments dropped with a warning, at least one emitter). `bands` is 3 if any segment
    /// has a non-grey value, or if `force_rgb`.
    pub fn new(
        name: &str,
        source: &str,
        segments: Vec<Segment>,
        objects: Vec<String>,
        view: Option<FlatView>,
        force_rgb: bool,
    ) -> Result<FlatlandScene> {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for (i, s) in segments.iter().enumerate() {
            if !(s.a.is_finite() && s.b.is_finite()) {
                return Err(SceneError::NonFinite {
                    source_name: source.into(),
                    face: i,
                    what: "vertex coordinate".into(),
                });
            }
            check_material(source, i, s.rho, s.emission)?;
            lo = lo.min(s.a).min(s.b);
            hi = hi.max(s.a).max(s.b);
        }
        let diag = if segments.is_empty() {
            0.0
        } else {
            (hi - lo).length()
        };
        let mut kept = Vec::new();
        let mut dropped = Vec::new();
        for (i, s) in segments.into_iter().enumerate() {
            let s = Segment::new(s.a, s.b, s.rho, s.emission, s.object, s.surface);
            if s.length <= 1e-12 * diag || s.length == 0.0 {
                dropped.push(i.to_string());
            } else {
                kept.push(s);
            }
        }
        let mut warnings = Vec::new();
        if !dropped.is_empty() {
            warnings.push(format!(
                "{source}: dropped {} degenerate segment(s) (zero length): {}",
                dropped.len(),
                dropped.join(", ")
            ));
        }
        if kept.is_empty() {
            return Err(SceneError::NoFaces {
                source_name: source.into(),
                dropped: dropped.len(),
            });
        }
        if !kept.iter().any(|s| s.emission.max() > 0.0) {
            return Err(SceneError::NoEmitter {
                source_name: source.into(),
            });
        }
        let grey = !force_rgb && kept.iter().all(|s| s.rho.is_grey() && s.emission.is_grey());
        let mut objects = objects;
        let max_obj = kept
            .iter()
            .map(|s| s.object as usize + 1)
            .max()
            .unwrap_or(0);
        while objects.len() < max_obj {
            objects.push(format!("object{}", objects.len()));
        }
        let view = view.unwrap_or_else(|| {
            let m = 0.05 * diag;
            FlatView {
                min: lo - DVec2::splat(m),
                max: hi + DVec2::splat(m),
            }
        });
        Ok(FlatlandScene {
            name: name.into(),
            source: source.into(),
            bands: if grey { 1 } else { 3 },
            segments: kept,
            objects,
            view,
            warnings,
        })
    }

    /// Total length of all segments.
    pub fn total_length(&self) -> f64 {
        self.segments.iter().map(|s| s.length).sum()
    }
    /// Length of the bounding-box diagonal.
    pub fn diagonal(&self) -> f64 {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for s in &self.segments {
            lo = lo.min(s.a).min(s.b);
            hi = hi.max(s.a).max(s.b);
        }
        (hi - lo).length()
    }

    /// Parses the Flatland JSON format of FORMATS.md:
    /// `{"segments": [{"a": [x,y], "b": [x,y], "rho": v | [r,g,b], "emission": v | [r,g,b]}, ...]}`
    /// with optional `"name"` per segment (object name) and optional top-level `"view": {"min": [..], "max": [..]}`.
    pub fn from_json(name: &str, source: &str, text: &str) -> Result<FlatlandScene> {
        let file: JsonFile = serde_json::from_str(text).map_err(|e| SceneError::Parse {
            source_name: source.into(),
            message: e.to_string(),
        })?;
        let mut rgb = false;
        let mut warnings = Vec::new();
        let mut objects: Vec<String> = Vec::new();
        let mut segs = Vec::with_capacity(file.segments.len());
        for (i, s) in file.segments.iter().enumerate() {
            rgb |= matches!(s.rho, JsonValue::Rgb(_)) || matches!(s.emission, JsonValue::Rgb(_));
            let obj = match &s.name {
                Some(n) => match objects.iter().position(|o| o == n) {
                    Some(k) => k,
                    None => {
                        objects.push(n.clone());
                        objects.len() - 1
                    }
                },
                None => {
                    objects.push(format!("segment{i}"));
                    objects.len() - 1
                }
            };
            // ρ ≥ 1 clamped to RHO_MAX, negative or non-finite refused, naming the segment (Flatland has no
            // materials: a segment's name, or its index, stands for one)
            let label = match &s.name {
                Some(n) => format!("segment {i} ({n})"),
                None => format!("segment {i}"),
            };
            let rho = crate::scene::check_file_material(
                source,
                &label,
                s.rho.spectrum(),
                s.emission.spectrum(),
                &mut warnings,
            )?;
            segs.push(Segment::new(
                DVec2::from(s.a),
                DVec2::from(s.b),
                rho,
                s.emission.spectrum(),
                obj as u32,
                i as u32,
            ));
        }
        let view = file.view.map(|v| FlatView {
            min: DVec2::from(v.min),
            max: DVec2::from(v.max),
        });
        let mut scene = FlatlandScene::new(name, source, segs, objects, view, rgb)?;
        scene.warnings.extend(warnings);
        Ok(scene)
    }

    /// Writes the scene in the Flatland JSON format, one segment per line (round-trips through
    /// [`FlatlandScene::from_json`]).
    pub fn to_json(&self) -> String {
        let val = |s: Spectrum| -> String {
            if self.bands == 1 {
                format!("{:?}", s.0[0])
            } else {
                format!("[{:?}, {:?}, {:?}]", s.0[0], s.0[1], s.0[2])
            }
        };
        let segs: Vec<String> = self
            .segments
            .iter()
            .map(|s| {
                format!(
                    "  {{\"name\": {}, \"a\": [{:?}, {:?}], \"b\": [{:?}, {:?}], \"rho\": {}, \"emission\": {}}}",
                    serde_json::Value::from(self.objects[s.object as usize].as_str()),
                    s.a.x, s.a.y, s.b.x, s.b.y, val(s.rho), val(s.emission)
                )
            })
            .collect();
        format!(
            "{{\"segments\": [\n{}\n],\n\"view\": {{\"min\": [{:?}, {:?}], \"max\": [{:?}, {:?}]}}}}\n",
            segs.join(",\n"),
            self.view.min.x,
            self.view.min.y,
            self.view.max.x,
            self.view.max.y
        )
    }
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonFile {
    segments: Vec<JsonSegment>,
    #[serde(default)]
    view: Option<JsonView>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonView {
    min: [f64; 2],
    max: [f64; 2],
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonSegment {
    #[serde(default)]
    name: Option<String>,
    a: [f64; 2],
    b: [f64; 2],
    rho: JsonValue,
    emission: JsonValue,
}

#[derive(serde::Deserialize)]
#[serde(untagged)]
enum JsonValue {
    Grey(f64),
    Rgb([f64; 3]),
}

impl JsonValue {
    fn spectrum(&self) -> Spectrum {
        match *self {
            JsonValue::Grey(v) => Spectrum::grey(v),
            JsonValue::Rgb(c) => Spectrum(c),
        }
    }
}

/// The scene's lights, written beside the scene (the lights module knows no scene).
impl crate::EmitterTable {
    /// The emitting segments of a Flatland scene.
    pub fn of_flatland(scene: &FlatlandScene) -> Self {
        Self::new(
            (scene.segments.iter().enumerate())
                .map(|(i, s)| (i as u32, s.length, s.emission.mean())),
        )
    }
}

impl crate::LightSet {
    /// The emitting segments of a Flatland scene (its only lights).
    pub fn of_flatland(scene: &FlatlandScene) -> Self {
        Self::new(crate::EmitterTable::of_flatland(scene), Vec::new(), 0.0)
    }
}
