//! The lightmap's UV atlas: every face of the scene gets a place on an atlas page, charts of
//! connected, consistently wound faces cut where the surface bends, packed with padding at a
//! texel density (texels per scene unit), by `uvunwrap` (pure Rust, after xatlas).
//!
//! One unwrap input per scene part (a glTF primitive instance, an OBJ object), so a chart never
//! spans two parts; faces of different surfaces' materials stay in one chart when they connect.
//! The back faces of two-sided materials (`Scene::add_back_faces`) are wound the other way, so
//! they get their own charts: each side of a thin wall has its own light.
//!
//! **The input's own layout** ([`Atlas::of_input`]): a glTF whose every face has `TEXCOORD_1` (a
//! lightmap set an artist or an engine made) keeps it: the page is that layout at the page size
//! (or at the size that gives the density asked for), nothing is unwrapped, and the written .glb
//! carries the same coordinates. It is used only when it can hold the bake: every coordinate in
//! [0, 1] and no two faces on the same place (the two sides of a two-sided material share their
//! coordinates); otherwise the scene is unwrapped with a warning that says why.

use super::settings::{LightmapError, LightmapSettings};
use glam::DVec3;
use scene_sampler::Scene;

/// Below this share of its pages covered, an atlas of several pages at the automatic density is
/// mostly padding, and says so ([`Atlas::note`]): the public temple compound's 26 790 charts
/// covered 1.6 % of 4 pages of 512² at 0.61 texels per metre.
const PADDED_UTILIZATION: f64 = 0.1;

/// A face's corners on the atlas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceUv {
    /// Texture coordinates of the corners `v[0..3]`, in `[0, 1]` page coordinates (row 0 of the
    /// image at v = 0).
    pub uv: [[f32; 2]; 3],
    /// The atlas page.
    pub page: u32,
}

/// The atlas of a scene.
#[derive(Clone, Debug)]
pub struct Atlas {
    /// Page width in texels.
    pub width: u32,
    /// Page height in texels.
    pub height: u32,
    /// Number of pages.
    pub pages: u32,
    /// Texels per scene unit.
    pub texels_per_unit: f64,
    /// Charts over all parts.
    pub charts: u32,
    /// Share of the pages' texels covered by charts.
    pub utilization: f64,
    /// Per scene face, its place (`None`: a degenerate face with no chart).
    pub faces: Vec<Option<FaceUv>>,
    /// Whether the places are the input's own `TEXCOORD_1` ([`Atlas::of_input`]) rather than
    /// unwrapped.
    pub from_input: bool,
    /// Why the input's `TEXCOORD_1` was not used, when it has one but cannot hold the bake; and
    /// when the automatic density spread the charts over several pages that are mostly padding.
    pub note: Option<String>,
}

impl Atlas {
    /// The input's own lightmap coordinates when they can hold the bake ([`Atlas::of_input`]),
    /// else `scene` unwrapped at the settings' density (or the highest that fits one page).
    pub fn of_scene(scene: &Scene, settings: &LightmapSettings) -> Result<Self, LightmapError> {
        let note = match Self::of_input(scene, settings) {
            Ok(Some(atlas)) => return Ok(atlas),
            Ok(None) => None,
            Err(why) => Some(format!(
                "the scene's TEXCOORD_1 was not used for the lightmap ({why}): unwrapped instead"
            )),
        };
        let unwrapped = Self::unwrapped(scene, settings)?;
        let note = match (note, unwrapped.note.clone()) {
            (Some(a), Some(b)) => Some(format!("{a}; {b}")),
            (a, b) => a.or(b),
        };
        Ok(Self { note, ..unwrapped })
    }

    /// The input's `TEXCOORD_1` as the atlas (module docs): one page of the settings' page size,
    /// or of the size that gives their density (at most the page size). `Ok(None)` when no face
    /// has them; `Err(why)` when they cannot hold the bake.
    pub fn of_input(scene: &Scene, settings: &LightmapSettings) -> Result<Option<Self>, String> {
        let given = scene
            .faces
            .iter()
            .filter(|f| f.lightmap_uv.is_some())
            .count();
        if given == 0 {
            return Ok(None);
        }
        if given < scene.faces.len() {
            return Err(format!(
                "{} of {} faces have none",
                scene.faces.len() - given,
                scene.faces.len()
            ));
        }
        let uvs: Vec<[glam::DVec2; 3]> = scene.faces.iter().flat_map(|f| f.lightmap_uv).collect();
        if let Some(i) = uvs.iter().position(|t| {
            t.iter()
                .any(|p| !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y))
        }) {
            return Err(format!(
                "face {i} has coordinates outside [0, 1]: {:?}",
                uvs[i].map(|p| [p.x, p.y])
            ));
        }
        // the same triangle of coordinates twice (corners in any order): two faces on one place
        let mut seen = std::collections::HashMap::new();
        for (i, t) in uvs.iter().enumerate() {
            let mut key = t.map(|p| (p.x.to_bits(), p.y.to_bits()));
            key.sort_unstable();
            if let Some(j) = seen.insert(key, i) {
                return Err(format!(
                    "faces {j} and {i} have the same coordinates (the two sides of a two-sided \
                     material?)"
                ));
            }
        }
        let uv_area: f64 = (uvs.iter())
            .map(|t| 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs())
            .sum();
        let area: f64 = scene.faces.iter().map(|f| f.area).sum();
        if uv_area <= 0.0 || area <= 0.0 {
            return Err("the coordinates cover no area".into());
        }
        let size = match settings.texels_per_unit {
            Some(t) => ((t * (area / uv_area).sqrt()).ceil() as u32).clamp(1, settings.page_size),
            None => settings.page_size,
        };
        let faces = (uvs.iter())
            .map(|t| {
                Some(FaceUv {
                    uv: t.map(|p| [p.x as f32, p.y as f32]),
                    page: 0,
                })
            })
            .collect();
        Ok(Some(Self {
            width: size,
            height: size,
            pages: 1,
            texels_per_unit: f64::from(size) * (uv_area / area).sqrt(),
            charts: 0,
            utilization: uv_area,
            faces,
            from_input: true,
            note: None,
        }))
    }

    /// Unwraps `scene` at the settings' density (or the highest that fits one page).
    fn unwrapped(scene: &Scene, settings: &LightmapSettings) -> Result<Self, LightmapError> {
        // ⟨One unwrap input per part: its faces as a triangle soup, relative to the scene's corner
        // (f32 positions keep their precision; identical positions are welded by the unwrapper)⟩
        let origin = scene.bounds.0;
        let parts = scene.parts.len().max(1);
        let mut faces_of: Vec<Vec<usize>> = vec![Vec::new(); parts];
        for (i, f) in scene.faces.iter().enumerate() {
            faces_of[(f.part as usize).min(parts - 1)].push(i);
        }
        faces_of.retain(|f| !f.is_empty());
        let soup: Vec<Vec<[f32; 3]>> = (faces_of.iter())
            .map(|fs| {
                (fs.iter())
                    .flat_map(|&i| scene.faces[i].v)
                    .map(|p: DVec3| (p - origin).as_vec3().to_array())
                    .collect()
            })
            .collect();
        let indices: Vec<Vec<u32>> = (soup.iter())
            .map(|p| (0..p.len() as u32).collect())
            .collect();
        let inputs: Vec<uvunwrap::MeshInput> = (soup.iter().zip(&indices))
            .map(|(p, i)| uvunwrap::MeshInput::new(p, i))
            .collect();
        // ⟨Unwrap and pack⟩
        let options = uvunwrap::Options {
            density: match settings.texels_per_unit {
                Some(t) => uvunwrap::Density::Fixed {
                    texels_per_unit: t as f32,
                    page_size: Some(settings.page_size),
                },
                None => uvunwrap::Density::Auto {
                    page_size: settings.page_size,
                },
            },
            padding: settings.padding,
            ..uvunwrap::Options::default()
        };
        let atlas = uvunwrap::generate(&inputs, &options).map_err(|e| LightmapError::Unwrap {
            message: e.to_string(),
            page_size: settings.page_size,
        })?;
        // ⟨Each face's corners: output triangle k of a part is its k-th face⟩
        let mut faces = vec![None; scene.faces.len()];
        for (fs, mesh) in faces_of.iter().zip(&atlas.meshes) {
            for (k, &face) in fs.iter().enumerate() {
                let corner = |c: usize| mesh.vertices[mesh.indices[3 * k + c] as usize];
                let (a, b, c) = (corner(0), corner(1), corner(2));
                if let (Some(page), Some(_), Some(_)) = (a.page, b.page, c.page) {
                    faces[face] = Some(FaceUv {
                        uv: [a.uv, b.uv, c.uv],
                        page,
                    });
                }
            }
        }
        let utilization = f64::from(atlas.utilization);
        let padded = settings.texels_per_unit.is_none()
            && atlas.page_count > 1
            && utilization < PADDED_UTILIZATION;
        Ok(Self {
            width: atlas.width,
            height: atlas.height,
            pages: atlas.page_count,
            texels_per_unit: f64::from(atlas.texels_per_unit),
            charts: atlas.chart_count,
            utilization,
            faces,
            from_input: false,
            note: padded.then(|| {
                format!(
                    "the lightmap's {} charts did not fit one page at any density: {} pages of \
                     {}×{} at {:.2} texels per unit, {:.1} % of them covered and the rest padding \
                     (a model of many small parts); a texel density (--lightmap-density) sets the \
                     texels and the pages follow (docs/guide/lightmaps.md)",
                    atlas.chart_count,
                    atlas.page_count,
                    atlas.width,
                    atlas.height,
                    atlas.texels_per_unit,
                    100.0 * utilization
                )
            }),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
    use scene_sampler::{Face, Spectrum};

    /// A unit square of two faces with lightmap coordinates `uv` (per face, per corner).
    fn square(uv: [Option<[DVec2; 3]>; 2]) -> Scene {
        let p = |x: f64, z: f64| DVec3::new(x, 0.0, z);
        let grey = Spectrum([0.5; 3]);
        let faces = [
            [p(0.0, 0.0), p(0.0, 1.0), p(1.0, 1.0)],
            [p(0.0, 0.0), p(1.0, 1.0), p(1.0, 0.0)],
        ]
        .into_iter()
        .zip(uv)
        .map(|(v, uv)| Face {
            lightmap_uv: uv,
            ..Face::new(v, grey, Spectrum([0.0; 3]), 0, 0)
        })
        .collect();
        Scene::new("square", "test", faces, vec!["square".into()], None).unwrap()
    }

    fn uv(c: [[f64; 2]; 3]) -> Option<[DVec2; 3]> {
        Some(c.map(DVec2::from))
    }

    /// Many small separate parts (400 tiny triangles far apart) do not fit one page of 32² at any
    /// density: the pages are mostly padding, and the atlas says so; with a density given, or
    /// one part, it says nothing.
    #[test]
    fn an_atlas_of_mostly_padding_says_so() {
        let grey = Spectrum([0.5; 3]);
        let tiny = |k: usize| {
            let o = DVec3::new((k % 20) as f64 * 10.0, 0.0, (k / 20) as f64 * 10.0);
            let v = [
                o,
                o + DVec3::new(0.0, 0.0, 0.1),
                o + DVec3::new(0.1, 0.0, 0.0),
            ];
            Face::new(v, grey, Spectrum([0.0; 3]), 0, 0)
        };
        let scene = Scene::new(
            "bits",
            "test",
            (0..400).map(tiny).collect(),
            vec!["bits".into()],
            None,
        )
        .unwrap();
        let settings = LightmapSettings {
            page_size: 32,
            ..LightmapSettings::default()
        };
        let atlas = Atlas::of_scene(&scene, &settings).unwrap();
        assert!(atlas.pages > 1 && atlas.utilization < PADDED_UTILIZATION);
        let note = atlas.note.expect("a note");
        assert!(
            note.contains("400 charts") && note.contains("--lightmap-density"),
            "{note}"
        );
        let dense = LightmapSettings {
            texels_per_unit: Some(20.0),
            ..settings
        };
        assert!(Atlas::of_scene(&scene, &dense).unwrap().note.is_none());
        assert!(
            Atlas::of_scene(&square([None, None]), &settings)
                .unwrap()
                .note
                .is_none()
        );
    }

    #[test]
    fn the_inputs_coordinates_are_the_atlas_when_they_can_hold_the_bake() {
        let settings = LightmapSettings {
            page_size: 64,
            ..LightmapSettings::default()
        };
        let left = uv([[0.0, 0.0], [0.0, 0.5], [0.5, 0.5]]);
        let right = uv([[0.5, 0.5], [1.0, 1.0], [1.0, 0.5]]);
        let atlas = Atlas::of_scene(&square([left, right]), &settings).unwrap();
        assert!(atlas.from_input && atlas.note.is_none());
        assert_eq!((atlas.width, atlas.height, atlas.pages), (64, 64, 1));
        assert_eq!(
            atlas.faces[1].unwrap().uv,
            [[0.5, 0.5], [1.0, 1.0], [1.0, 0.5]]
        );
        // a quarter of the page over 1 m²: 32 texels per metre; a density sets the size
        assert!((atlas.texels_per_unit - 32.0).abs() < 1e-9);
        let dense = LightmapSettings {
            texels_per_unit: Some(10.0),
            ..settings
        };
        assert_eq!(
            Atlas::of_scene(&square([left, right]), &dense)
                .unwrap()
                .width,
            20
        );
        // refused, unwrapped instead, with the reason
        let why = |uv: [Option<[DVec2; 3]>; 2]| {
            let atlas = Atlas::of_scene(&square(uv), &settings).unwrap();
            assert!(!atlas.from_input);
            atlas.note.unwrap()
        };
        assert!(why([left, None]).contains("1 of 2 faces have none"));
        let outside = uv([[0.5, 0.5], [1.0, 1.5], [1.0, 0.5]]);
        assert!(why([left, outside]).contains("face 1 has coordinates outside [0, 1]"));
        let same = uv([[0.0, 0.5], [0.5, 0.5], [0.0, 0.0]]);
        assert!(why([left, same]).contains("faces 0 and 1 have the same coordinates"));
        // no coordinates at all: unwrapped without a word
        let atlas = Atlas::of_scene(&square([None, None]), &settings).unwrap();
        assert!(!atlas.from_input && atlas.note.is_none());
    }
}
