//! The lightmap's UV atlas: every face of the scene gets a place on an atlas page, charts of
//! connected, consistently wound faces cut where the surface bends, packed with padding at a
//! texel density (texels per scene unit), by `uvunwrap` (pure Rust, after xatlas).
//!
//! One unwrap input per scene part (a glTF primitive instance, an OBJ object), so a chart never
//! spans two parts; faces of different surfaces' materials stay in one chart when they connect.
//! The back faces of two-sided materials (`Scene::add_back_faces`) are wound the other way, so
//! they get their own charts: each side of a thin wall has its own light.

use super::settings::{LightmapError, LightmapSettings};
use glam::DVec3;
use scene_sampler::Scene;

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
}

impl Atlas {
    /// Unwraps `scene` at the settings' density (or the highest that fits one page).
    pub fn of_scene(scene: &Scene, settings: &LightmapSettings) -> Result<Self, LightmapError> {
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
        Ok(Self {
            width: atlas.width,
            height: atlas.height,
            pages: atlas.page_count,
            texels_per_unit: f64::from(atlas.texels_per_unit),
            charts: atlas.chart_count,
            utilization: f64::from(atlas.utilization),
            faces,
        })
    }
}
