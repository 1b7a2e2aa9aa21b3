//! Progressive refinement radiosity (Cohen, Chen, Wallace and Greenberg 1988; the "shooting" form of
//! eq. 1.17): on the mesh and with the form factors of [`crate::classical`], the element with the most
//! unshot power `ΔB_j·A_j` shoots it to every element `i`,
//!
//! ```text
//! Δ = ρ_i F_ij ΔB_j,    B_i += Δ,    ΔB_i += Δ,    ΔB_j = 0,
//! ```
//!
//! with `F_ij` the form factor from `i` to `j` (reciprocity `A_i F_ij = A_j F_ji` turns Cohen's
//! `ρ_i ΔB_j F_ji A_j/A_i` into this). Only the shooter's column of form factors is ever computed, so a
//! useful picture comes after a few shots instead of after the whole `n²` matrix; each shot costs one
//! column. Since `B` grows monotonically from `E`, every intermediate `B` is below the converged one, and
//! the unshot power bounds what is still missing. Converged, it solves the same system as
//! [`crate::classical::solve`] (tested).

use crate::classical::{self, ClassicalOptions, Element, Mesh, form_factor};
use crate::error::{BaselineError, check_range};
use rayon::prelude::*;
use scene_sampler::{Scene, SceneBvh, SurfacePoint};

/// Options of progressive refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressiveOptions {
    /// Mesh and form factors (the classical solver's `tolerance` and `max_iterations` are unused).
    pub classical: ClassicalOptions,
    /// Stop when the unshot power is below `tolerance ·` the emitted power (summed over bands).
    pub tolerance: f64,
    /// Shot cap (each shot computes one column of form factors).
    pub max_shots: usize,
}

impl Default for ProgressiveOptions {
    /// The classical defaults for the mesh, tolerance 10⁻³, at most 100 000 shots.
    fn default() -> Self {
        ProgressiveOptions {
            classical: ClassicalOptions::default(),
            tolerance: 1e-3,
            max_shots: 100_000,
        }
    }
}

/// The state after progressive refinement.
#[derive(Clone, Debug)]
pub struct ProgressiveRadiosity {
    /// The mesh.
    pub mesh: Mesh,
    /// Radiosity per element, per band.
    pub b: Vec<[f64; 3]>,
    /// Unshot radiosity per element, per band.
    pub unshot: Vec<[f64; 3]>,
    /// Shots made (form factor columns computed).
    pub shots: usize,
    /// Unshot power over emitted power at the end.
    pub unshot_fraction: f64,
}

fn power(e: &Element, b: &[f64; 3]) -> f64 {
    e.area * (b[0] + b[1] + b[2])
}

/// Meshes the scene and shoots until the unshot power falls below `tolerance` of the emitted power or
/// `max_shots` is reached (not an error: the state is a valid, lower estimate; see
/// [`ProgressiveRadiosity::unshot_fraction`]).
///
/// # Errors
/// Bad options (non-positive element size or tolerance, zero rays or shots), too many elements, or a
/// scene that emits nothing.
pub fn solve(
    scene: &Scene,
    bvh: &SceneBvh,
    opts: &ProgressiveOptions,
) -> Result<ProgressiveRadiosity, BaselineError> {
    check_range("tolerance", opts.tolerance, 0.0, 1.0, "0 < tolerance < 1")?;
    if opts.max_shots == 0 || opts.classical.form_factors.visibility_rays == 0 {
        return Err(BaselineError::InvalidParameter {
            name: if opts.max_shots == 0 {
                "max_shots"
            } else {
                "visibility_rays"
            },
            value: 0.0,
            expected: "at least 1",
        });
    }
    let mesh = Mesh::new(scene, opts.classical.element_size)?;
    let els = &mesh.elements;
    let mut b: Vec<[f64; 3]> = els.iter().map(|e| e.emission).collect();
    let mut unshot = b.clone();
    let emitted: f64 = els.iter().map(|e| power(e, &e.emission)).sum();
    if emitted <= 0.0 {
        return Err(BaselineError::InvalidParameter {
            name: "emission",
            value: emitted,
            expected: "a scene with at least one emitting face",
        });
    }
    let mut shots = 0;
    let mut left = 1.0;
    while shots < opts.max_shots {
        let (j, pj) = els
            .iter()
            .zip(&unshot)
            .map(|(e, u)| power(e, u))
            .enumerate()
            .fold(
                (0, 0.0),
                |best, (i, p)| if p > best.1 { (i, p) } else { best },
            );
        left = unshot
            .iter()
            .zip(els)
            .map(|(u, e)| power(e, u))
            .sum::<f64>()
            / emitted;
        if left < opts.tolerance || pj <= 0.0 {
            break;
        }
        let column: Vec<f64> = (0..els.len())
            .into_par_iter()
            .map(|i| form_factor(bvh, els, i, j, &opts.classical.form_factors))
            .collect();
        let shoot = unshot[j];
        unshot[j] = [0.0; 3];
        for (i, f) in column.into_iter().enumerate() {
            if f <= 0.0 {
                continue;
            }
            for k in 0..3 {
                let d = els[i].rho[k] * f * shoot[k];
                b[i][k] += d;
                unshot[i][k] += d;
            }
        }
        shots += 1;
    }
    Ok(ProgressiveRadiosity {
        mesh,
        b,
        unshot,
        shots,
        unshot_fraction: left,
    })
}

impl ProgressiveRadiosity {
    /// B at surface points: the value of the containing element (piecewise constant).
    ///
    /// # Errors
    /// A point whose face is not in the scene.
    pub fn at_points(&self, points: &[SurfacePoint]) -> Result<Vec<[f64; 3]>, BaselineError> {
        classical::element_values(&self.mesh, &self.b, points)
    }

    /// B at surface points by a final gather over all elements (as
    /// [`classical::ClassicalRadiosity::gather`]).
    ///
    /// # Errors
    /// A point whose face is not in the scene.
    pub fn gather(
        &self,
        scene: &Scene,
        bvh: &SceneBvh,
        points: &[SurfacePoint],
        rays: usize,
        seed: u64,
    ) -> Result<Vec<[f64; 3]>, BaselineError> {
        classical::gather(scene, bvh, &self.mesh, &self.b, points, rays, seed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::{AnyScene, builtin};

    fn cornell() -> Scene {
        let AnyScene::ThreeD(scene) = builtin("cornell-box").unwrap() else {
            panic!()
        };
        scene
    }

    /// Converged shooting solves the same system as Gauss–Seidel on the same mesh and form factors,
    /// and every intermediate state lies below it (B grows monotonically from E).
    #[test]
    fn converged_shooting_equals_gauss_seidel_and_approaches_from_below() {
        let scene = cornell();
        let bvh = SceneBvh::new(&scene);
        let classical = ClassicalOptions {
            element_size: 0.2,
            ..ClassicalOptions::default()
        };
        let gs = classical::solve(&scene, &bvh, &classical).unwrap();
        let early = solve(
            &scene,
            &bvh,
            &ProgressiveOptions {
                classical,
                tolerance: 0.3,
                ..ProgressiveOptions::default()
            },
        )
        .unwrap();
        let done = solve(
            &scene,
            &bvh,
            &ProgressiveOptions {
                classical,
                tolerance: 1e-7,
                ..ProgressiveOptions::default()
            },
        )
        .unwrap();
        assert!(early.shots < done.shots && early.unshot_fraction < 0.3);
        assert!(done.unshot_fraction < 1e-7, "{}", done.unshot_fraction);
        let largest = gs.b.iter().flatten().fold(0.0f64, |m, v| m.max(*v));
        let mut worst: f64 = 0.0;
        for i in 0..gs.b.len() {
            for k in 0..3 {
                worst = worst.max((done.b[i][k] - gs.b[i][k]).abs());
                assert!(early.b[i][k] <= gs.b[i][k] * (1.0 + 1e-9) + 1e-12);
            }
        }
        assert!(
            worst < 1e-5 * largest,
            "max difference {worst} of {largest}"
        );
    }

    #[test]
    fn bad_options_and_dark_scenes_are_errors() {
        let scene = cornell();
        let bvh = SceneBvh::new(&scene);
        let d = ProgressiveOptions::default();
        for o in [
            ProgressiveOptions {
                tolerance: 0.0,
                ..d
            },
            ProgressiveOptions { max_shots: 0, ..d },
            ProgressiveOptions {
                tolerance: f64::NAN,
                ..d
            },
        ] {
            assert!(solve(&scene, &bvh, &o).is_err(), "{o:?}");
        }
        let dark = Scene::new(
            "dark",
            "test",
            scene
                .faces
                .iter()
                .map(|f| {
                    scene_sampler::Face::new(
                        f.v,
                        f.rho,
                        scene_sampler::Spectrum([0.0; 3]),
                        f.object,
                        f.surface,
                    )
                })
                .collect(),
            scene.objects.clone(),
            None,
        );
        // The loader may refuse a scene without an emitter itself; if it builds one, the solver must.
        if let Ok(dark) = dark {
            let bvh = SceneBvh::new(&dark);
            assert!(solve(&dark, &bvh, &d).is_err());
        }
    }
}
