//! The chosen-from-data regressor (issue 19): accuracy against the k-means RBF reference,
//! no silent overfitting on noise, invariance to input units, determinism, save/load, and
//! every misuse an error.

use isgcs::rbf::KMeansRbf;
use isgcs::regressor::{Regressor, RegressorError, RegressorParams};
use isgcs::test_functions::suite;

fn rms_over_sd(pred: &[f64], truth: &[f64]) -> f64 {
    let n = truth.len() as f64;
    let mean = truth.iter().sum::<f64>() / n;
    let sd = (truth.iter().map(|t| (t - mean) * (t - mean)).sum::<f64>() / n).sqrt();
    let mse = pred
        .iter()
        .zip(truth)
        .map(|(p, t)| (p - t) * (p - t))
        .sum::<f64>()
        / n;
    mse.sqrt() / sd
}

fn params(cells: usize, seed: u64) -> RegressorParams {
    RegressorParams {
        max_cells: cells,
        seed,
        ..RegressorParams::default()
    }
}

fn predict(model: &Regressor, x: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; x.len() / model.input_dim() * model.output_dim()];
    model.predict(x, &mut out).unwrap();
    out
}

#[test]
fn franke_is_accurate_and_not_worse_than_the_kmeans_rbf() {
    let p = suite().into_iter().find(|p| p.name == "franke").unwrap();
    let (x, y) = p.sample(2000, false, 1);
    let (tx, ty) = p.sample(5000, false, 2);
    let model = Regressor::fit(&params(150, 1), &x, &y, 2, 1).unwrap();
    assert_eq!(model.len(), 150);
    let e = rms_over_sd(&predict(&model, &tx), &ty);
    let rbf = KMeansRbf::fit(&x, &y, 2, 1, 150, 1).unwrap();
    let mut out = vec![0.0; ty.len()];
    rbf.predict(&tx, &mut out).unwrap();
    let er = rms_over_sd(&out, &ty);
    eprintln!("franke 150 cells: isgcs {e:.5}, k-means rbf {er:.5}");
    assert!(e < 0.01, "rms/sd {e}");
    assert!(e < 1.5 * er, "isgcs {e} vs rbf {er}");
}

#[test]
fn pure_noise_predicts_about_the_mean() {
    // Targets: 3 + N(0, 1)-like noise without any signal. Predicting the mean has error ~0 on
    // the noise-free truth (the constant 3); a model that interpolates the noise has ~1.
    let rows = 1500;
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let x: Vec<f64> = (0..rows * 2).map(|_| next()).collect();
    let y: Vec<f64> = (0..rows)
        .map(|_| 3.0 + (next() + next() + next() - 1.5) * 2.0)
        .collect();
    let noise_sd = (y.iter().map(|v| (v - 3.0) * (v - 3.0)).sum::<f64>() / rows as f64).sqrt();
    let model = Regressor::fit(&params(200, 3), &x, &y, 2, 1).unwrap();
    let tx: Vec<f64> = (0..4000).map(|_| next()).collect();
    let pred = predict(&model, &tx);
    let rms = (pred.iter().map(|p| (p - 3.0) * (p - 3.0)).sum::<f64>() / pred.len() as f64).sqrt();
    eprintln!(
        "pure noise: rms {rms:.4} of noise sd {noise_sd:.4}, ridge {:.1e}, dof {:.1}",
        model.report().ridge,
        model.report().dof
    );
    assert!(rms < 0.35 * noise_sd, "rms {rms} vs noise sd {noise_sd}");
    // Just outside the data the prediction stays near the data's values.
    let outside = predict(&model, &[1.1, 1.1, -0.1, 0.5]);
    assert!(outside.iter().all(|v| (v - 3.0).abs() < 1.5), "{outside:?}");
}

#[test]
fn input_units_do_not_matter_and_fits_are_deterministic() {
    let p = suite().into_iter().find(|p| p.name == "ishigami").unwrap();
    let (x, y) = p.sample(1500, false, 4);
    let (tx, _) = p.sample(500, false, 5);
    let a = Regressor::fit(&params(80, 2), &x, &y, 3, 1).unwrap();
    let b = Regressor::fit(&params(80, 2), &x, &y, 3, 1).unwrap();
    let (pa, pb) = (predict(&a, &tx), predict(&b, &tx));
    assert!(pa.iter().zip(&pb).all(|(u, v)| u.to_bits() == v.to_bits()));
    // Input 1 in units 10× smaller (values 10× larger): standardization removes the factor.
    let scale = |v: &[f64]| -> Vec<f64> {
        v.chunks(3)
            .flat_map(|r| [r[0], 10.0 * r[1], r[2]])
            .collect()
    };
    // Nearly exactly (to 1e-4) without the learned metric: the standardized inputs differ in
    // their last bits, and the holdout selection may take ridges down to machine epsilon,
    // where that rounding moves the weights (1.8e-5 here; the leave-one-out selection used
    // on these 1500 rows before the holdout took over gave 1e-6); with it (the default) the discrete
    // choices of the metric search (pilot k-means, leave-one-out comparisons) can flip on
    // rounding-level differences, so there the two fits must only be about equally accurate.
    let fixed = RegressorParams {
        metric: false,
        ..params(80, 2)
    };
    let a0 = Regressor::fit(&fixed, &x, &y, 3, 1).unwrap();
    let c0 = Regressor::fit(&fixed, &scale(&x), &y, 3, 1).unwrap();
    let diff = rms_over_sd(&predict(&c0, &scale(&tx)), &predict(&a0, &tx));
    assert!(diff < 1e-4, "relative rms difference {diff}");
    let (_, ty) = p.sample(500, false, 5);
    let c = Regressor::fit(&params(80, 2), &scale(&x), &y, 3, 1).unwrap();
    let (ea, ec) = (
        rms_over_sd(&pa, &ty),
        rms_over_sd(&predict(&c, &scale(&tx)), &ty),
    );
    assert!(
        ec < 1.3 * ea && ea < 1.3 * ec,
        "rms/σ {ea} vs {ec} in other units"
    );
}

#[test]
fn save_and_load_give_the_same_predictions() {
    let p = suite().into_iter().find(|p| p.name == "jump2").unwrap();
    let (x, y) = p.sample(800, false, 6);
    let model = Regressor::fit(&params(60, 1), &x, &y, 2, 1).unwrap();
    let json = serde_json::to_string(&model).unwrap();
    let back: Regressor = serde_json::from_str(&json).unwrap();
    let (tx, _) = p.sample(300, false, 7);
    let (a, b) = (predict(&model, &tx), predict(&back, &tx));
    // serde_json's float parsing may be off by an ulp (without its `float_roundtrip` feature).
    assert!(
        a.iter()
            .zip(&b)
            .all(|(u, v)| (u - v).abs() <= 1e-9 * u.abs().max(1.0))
    );
    assert_eq!(model.input_dim(), back.input_dim());
    assert_eq!(model.len(), back.len());
}

#[test]
fn a_blended_fit_saves_and_loads_and_is_about_as_accurate_as_its_first_layer() {
    // Enough rows for the holdout selection (1500 fitted, 900 scored): the two walked output
    // layers are blended. Save/load keeps the blend (without it the predictions differ), and
    // on fresh points the blend is within the holdout's sampling error (α is fitted on 900
    // rows) of the share α = 0, the first layer alone (here 0.224 against 0.220 rms/σ).
    let p = suite().into_iter().find(|p| p.name == "ishigami").unwrap();
    let (x, y) = p.sample(2400, false, 8);
    let model = Regressor::fit(&params(80, 1), &x, &y, 3, 1).unwrap();
    let share = model.report().blend_share;
    assert!(share > 0.0 && share <= 1.0, "not blended: {share}");
    let json = serde_json::to_string(&model).unwrap();
    let back: Regressor = serde_json::from_str(&json).unwrap();
    let (tx, ty) = p.sample(3000, false, 9);
    let (a, b) = (predict(&model, &tx), predict(&back, &tx));
    // serde_json's float parsing may be off by an ulp; at this fit's relative ridge (~10⁻¹⁵)
    // the weights amplify that to ~10⁻⁹ of the outputs' spread, far below the blend's effect.
    let spread = ty.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(
        a.iter()
            .zip(&b)
            .all(|(u, v)| (u - v).abs() <= 1e-7 * spread)
    );
    assert_eq!(back.report().blend_share, share);
    // A model saved before blends existed (no `blend` entry) loads as the first layer alone.
    let mut old: serde_json::Value = serde_json::from_str(&json).unwrap();
    old.as_object_mut().unwrap().remove("blend");
    let first: Regressor = serde_json::from_value(old).unwrap();
    let (eb, e1) = (
        rms_over_sd(&a, &ty),
        rms_over_sd(&predict(&first, &tx), &ty),
    );
    eprintln!("blend {share:.3}: rms/σ {eb:.2e}, first layer alone {e1:.2e}");
    assert!(eb != e1, "the blend changed nothing");
    assert!(eb < 1.05 * e1, "blend {eb} vs first layer {e1}");
}

#[test]
fn misuse_is_an_error() {
    let x = vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.5, 0.5];
    let y = vec![0.0, 1.0, 1.0, 2.0, 1.0];
    let ok = params(4, 0);
    let shape = |r: Result<Regressor, RegressorError>| matches!(r, Err(RegressorError::Shape(_)));
    assert!(shape(Regressor::fit(&ok, &x[..9], &y, 2, 1)));
    assert!(shape(Regressor::fit(&ok, &x, &y[..4], 2, 1)));
    assert!(shape(Regressor::fit(&ok, &[], &[], 2, 1)));
    assert!(shape(Regressor::fit(&ok, &x, &y, 0, 1)));
    let mut nan = x.clone();
    nan[3] = f64::NAN;
    assert!(matches!(
        Regressor::fit(&ok, &nan, &y, 2, 1),
        Err(RegressorError::NonFinite {
            what: "inputs",
            row: 1,
            column: 1,
            ..
        })
    ));
    let invalid = |p: RegressorParams| {
        matches!(
            Regressor::fit(&p, &x, &y, 2, 1),
            Err(RegressorError::InvalidParams(_))
        )
    };
    let budget = |c: usize| {
        matches!(
            Regressor::fit(&params(c, 0), &x, &y, 2, 1),
            Err(RegressorError::CellBudget { .. })
        )
    };
    assert!(budget(6)); // more cells than rows
    assert!(budget(1)); // fewer than k + 1
    assert!(invalid(RegressorParams {
        topology_dim: Some(3),
        ..ok.clone()
    }));
    assert!(invalid(RegressorParams {
        ridge: Some(-1.0),
        ..ok.clone()
    }));
    assert!(invalid(RegressorParams {
        width_multiplier: Some(0.0),
        ..ok.clone()
    }));
    let model = Regressor::fit(&ok, &x, &y, 2, 1).unwrap();
    let mut out = [0.0; 2];
    assert!(model.predict(&[0.5, 0.5, 0.1], &mut out).is_err());
    assert!(model.predict(&[0.5, 0.5], &mut out).is_err());
    assert!(model.predict(&[0.5, 0.5, 0.1, 0.1], &mut out).is_ok());
    // A non-finite input row predicts NaN instead of a number.
    model.predict(&[f64::NAN, 0.5, 0.1, 0.1], &mut out).unwrap();
    assert!(out[0].is_nan() && out[1].is_finite());
}

#[test]
fn a_fixed_ridge_below_rounding_is_an_error_that_names_the_ridge() {
    // Wide Gaussians without a ridge: AᵀA is singular to rounding. A fixed ridge is used as
    // given, so the fit either factorises (finite predictions) or says which ridge failed.
    let p = suite().into_iter().find(|p| p.name == "franke").unwrap();
    let (x, y) = p.sample(600, false, 1);
    let mut failed = 0;
    for ridge in [0.0, 1e-16] {
        let fixed = RegressorParams {
            ridge: Some(ridge),
            width_multiplier: Some(8.0),
            ..params(60, 1)
        };
        match Regressor::fit(&fixed, &x, &y, 2, 1) {
            Ok(model) => assert!(predict(&model, &x).iter().all(|v| v.is_finite())),
            Err(RegressorError::Solve(msg)) => {
                failed += 1;
                assert!(msg.contains("fixed relative ridge"), "{msg}");
            }
            Err(e) => panic!("unexpected error {e}"),
        }
    }
    eprintln!("{failed} of 2 fixed ridges failed to factorise");
}

#[test]
fn repeated_rows_do_not_leak_into_the_holdout() {
    // Every noisy row three times: the selection must not score the interpolation of a row's
    // noise on its own copies (the holdout keeps repeated inputs on one side).
    let p = suite()
        .into_iter()
        .find(|p| p.name == "franke-noisy")
        .unwrap();
    let (x, y) = p.sample(1000, true, 1);
    let (tx, ty) = p.sample(5000, false, 2);
    let (x3, y3) = (x.repeat(3), y.repeat(3));
    let once = Regressor::fit(&params(300, 1), &x, &y, 2, 1).unwrap();
    let thrice = Regressor::fit(&params(300, 1), &x3, &y3, 2, 1).unwrap();
    let (e1, e3) = (
        rms_over_sd(&predict(&once, &tx), &ty),
        rms_over_sd(&predict(&thrice, &tx), &ty),
    );
    eprintln!(
        "franke-noisy 300 cells: rows once {e1:.4} (dof {:.0}), three times {e3:.4} (dof {:.0})",
        once.report().dof,
        thrice.report().dof
    );
    assert!(e3 < 1.25 * e1, "{e3} vs {e1}");
}
