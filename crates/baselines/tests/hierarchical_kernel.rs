//! HR's piecewise-constant kernel (fig. 4.2b) and the kernel error measure.

use baselines::hierarchical::strings::{Piece, form_factor};
use baselines::hierarchical::*;
use scene_sampler::{FlatKernelSampler, FlatSampler, builtin};

fn corner() -> scene_sampler::FlatlandScene {
    builtin("flatland-corner").unwrap().into_flatland().unwrap()
}

fn at_budget(scene: &scene_sampler::FlatlandScene, target: usize) -> FlatHr {
    let base = FlatHrConfig {
        min_length: budget::min_length_for(scene, target),
        ..FlatHrConfig::default()
    };
    solve_for_links(scene, target, base, 0.05).unwrap().hr
}

#[test]
fn every_link_owns_the_centre_of_its_block() {
    for name in ["flatland-corner", "flatland-blocker"] {
        let scene = builtin(name).unwrap().into_flatland().unwrap();
        let hr = at_budget(&scene, 100);
        let hk = HrKernel::new(&hr);
        let smp = FlatSampler::new(&scene);
        let centre = |p: &Patch| {
            let (a, b) = smp.segment_range(p.segment);
            a + 0.5 * (p.t0 + p.t1) * (b - a)
        };
        for (k, l) in hr.links().iter().enumerate() {
            let (r, s) = (
                &hr.patches()[l.receiver as usize],
                &hr.patches()[l.sender as usize],
            );
            let (sc, tc) = (centre(s), centre(r));
            assert_eq!(hk.link_at(sc, tc).unwrap(), Some(k), "{name}: link {k}");
            let v = hk.hr_kernel_at(sc, tc).unwrap().0[0];
            let want = scene.segments[r.segment as usize].rho.0[0] * l.form_factor() / s.length;
            assert!((v - want).abs() <= 1e-15 * want.max(1.0));
        }
    }
}

#[test]
fn both_kernels_integrate_to_the_transfer() {
    // flatland-corner has no occluder: ∫∫ K ds dt · T² = Σ_{r≠s} ρ_r L_r F_rs over the two segments, and HR's
    // blocks carry exactly the same total
    let scene = corner();
    let total = scene.total_length();
    let segs = &scene.segments;
    let mut want = 0.0;
    for r in 0..segs.len() {
        for s in 0..segs.len() {
            if r != s {
                let pr = Piece::new(segs[r].a, segs[r].b, r as u32);
                let ps = Piece::new(segs[s].a, segs[s].b, s as u32);
                want += segs[r].rho.0[0] * segs[r].length * form_factor(&pr, &ps);
            }
        }
    }
    let hr = at_budget(&scene, 100);
    let hk = HrKernel::new(&hr);
    let mut ks = FlatKernelSampler::new(&scene);
    ks.r_min = 0.0;
    let n = 1000;
    let (mut exact, mut approx) = (0.0, 0.0);
    for j in 0..n {
        for i in 0..n {
            let (s, t) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            exact += exact_kernel_at(&ks, s, t).unwrap().0[0];
            approx += hk.hr_kernel_at(s, t).unwrap().0[0];
        }
    }
    let scale = total * total / (n * n) as f64;
    let (exact, approx) = (exact * scale, approx * scale);
    assert!((approx - want).abs() < 1e-3 * want, "HR {approx} vs {want}");
    // the corner singularity (G ~ 1/r) makes the midpoint rule converge slowly
    assert!(
        (exact - want).abs() < 1e-2 * want,
        "exact {exact} vs {want}"
    );
}

#[test]
fn kernel_error_falls_with_the_link_budget_on_the_corner() {
    let scene = corner();
    let errs: Vec<KernelError> = [16, 100, 500]
        .iter()
        .map(|&n| kernel_error(&at_budget(&scene, n), 512, Weight::Emission).unwrap())
        .collect();
    for w in errs.windows(2) {
        assert!(w[1].relative_rms < w[0].relative_rms, "{errs:?}");
        assert!(w[1].rms < w[0].rms);
    }
    for e in &errs {
        assert!(e.relative_rms > 0.0 && e.relative_rms < 1.0);
        // the normalizations agree with their definitions
        assert!((e.rms_over_max - e.rms / e.max_exact).abs() < 1e-15);
        assert!((e.relative_rms - e.rms / e.rms_exact).abs() < 1e-12);
    }
}

#[test]
fn bad_parameters_are_errors() {
    let scene = corner();
    let hr = FlatHr::solve(&scene, FlatHrConfig::default()).unwrap();
    let hk = HrKernel::new(&hr);
    assert!(hk.hr_kernel_at(1.5, 0.2).is_err());
    assert!(hk.hr_kernel_at(0.2, f64::NAN).is_err());
    let ks = FlatKernelSampler::new(&scene);
    assert!(exact_kernel_at(&ks, -0.1, 0.2).is_err());
    assert!(kernel_error(&hr, 0, Weight::None).is_err());
    assert!(kernel_error_clamped(&hr, 8, Weight::None, -1.0).is_err());
    assert!(kernel_error_clamped(&hr, 8, Weight::None, f64::INFINITY).is_err());
}

#[test]
fn the_distance_clamp_only_lowers_the_exact_kernel() {
    let scene = corner();
    let hr = at_budget(&scene, 100);
    let n = 256;
    let raw = kernel_error(&hr, n, Weight::Emission).unwrap();
    assert_eq!(
        kernel_error_clamped(&hr, n, Weight::Emission, 0.0).unwrap(),
        raw
    );
    let r_min = 0.05 * scene.diagonal();
    let c = kernel_error_clamped(&hr, n, Weight::Emission, r_min).unwrap();
    assert!(c.max_exact < raw.max_exact && c.rms_exact < raw.rms_exact);
    // off the corner the two kernels agree: K·E is bounded by (1/2)·max E/r_min with ρ ≤ 1, cos ≤ 1
    let e_max = scene
        .segments
        .iter()
        .map(|s| s.emission.0[0])
        .fold(0.0, f64::max);
    assert!(c.max_exact <= 0.5 * e_max / r_min * (1.0 + 1e-12));
    assert!(c.mean_exact < raw.mean_exact && c.mean_exact > 0.9 * raw.mean_exact);
}
