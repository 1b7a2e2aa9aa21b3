//! The lightmap denoiser (`--lightmap-denoise`) against a converged bake of the same texels: a
//! denoised bake run to a target error meets it, with fewer rays than the raw bake to the same
//! target, and its estimated error — the blur included — is what the reference measures.

use gcr::{
    Domain, GatherMode, Lightmap, LightmapQuantity, LightmapSettings, PathSettings, SolveConfig,
    Trained, bake_lightmap,
};
use scene_sampler::{AnyScene, KernelSampler, SceneBvh, builtin};

/// The Cornell box's irradiance lightmap on a 256-texel page, to `target`.
fn bake(target: f64, seed: u64, denoise: bool) -> Lightmap {
    let AnyScene::ThreeD(scene) = builtin("cornell-box").unwrap() else {
        panic!("the Cornell box is 3-D")
    };
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        gather: GatherMode::Paths,
        seed,
        paths: PathSettings {
            target_error: Some(target),
            ..PathSettings::default()
        },
        ..SolveConfig::default()
    };
    let trained = Trained::without_networks(&domain, &config);
    let settings = LightmapSettings {
        page_size: 256,
        quantity: LightmapQuantity::Irradiance,
        denoise,
        ..LightmapSettings::default()
    };
    bake_lightmap(&domain, &trained, &config, &settings).unwrap()
}

/// The relative L2 difference of `lm`'s texels from `reference`'s (the same layout), the
/// reference's own estimated error taken out.
fn measured(lm: &Lightmap, reference: &Lightmap) -> f64 {
    let w = reference.atlas.width as usize;
    let (mut d, mut r) = (0.0, 0.0);
    for t in &reference.texels {
        let i = t.y as usize * w + t.x as usize;
        let (a, b) = (
            lm.pages[t.page as usize][i],
            reference.pages[t.page as usize][i],
        );
        for k in 0..3 {
            d += f64::from(a[k] - b[k]).powi(2);
            r += f64::from(b[k]).powi(2);
        }
    }
    let own = reference.stats.relative_std_error.unwrap();
    (d / r - own * own).max(0.0).sqrt()
}

#[test]
fn a_denoised_bake_meets_its_target_with_fewer_rays_and_an_honest_estimate() {
    let target = 0.04;
    let reference = bake(0.01, 2, false);
    let raw = bake(target, 1, false);
    let denoised = bake(target, 1, true);
    let (raw_error, error) = (measured(&raw, &reference), measured(&denoised, &reference));
    let estimate = denoised.stats.relative_std_error.unwrap();
    let report = denoised.denoised.unwrap();
    eprintln!(
        "raw: {} rays, {raw_error:.4} measured; denoised: {} rays, {error:.4} measured, \
         {estimate:.4} estimated (raw {:.4}), mean σ {:.1} texels",
        raw.stats.rays,
        denoised.stats.rays,
        report.raw_error.unwrap(),
        report.mean_sigma
    );
    assert!(
        error <= 1.2 * target,
        "measured {error} for a target of {target}"
    );
    assert!(
        (0.75..1.33).contains(&(estimate / error)),
        "estimated {estimate}, measured {error}"
    );
    assert!(
        denoised.stats.rays < raw.stats.rays,
        "denoised {} rays, raw {}",
        denoised.stats.rays,
        raw.stats.rays
    );
}
