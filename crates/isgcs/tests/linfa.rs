//! The linfa integration (feature `linfa`): accuracy against the native API, target shapes,
//! and every bad input as an error.

use isgcs::linfa::{IsgcsRegressor, IsgcsRegressorError, IsgcsRegressorParams};
use isgcs::test_functions::franke;
use isgcs::{Isgcs, Params, Stopped};
use linfa::prelude::*;
use ndarray::{Array1, Array2, Axis, Ix1, Ix2, Slice};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `rows` uniform points of the unit square.
fn points(rows: usize, rng: &mut ChaCha8Rng) -> Array2<f64> {
    Array2::from_shape_fn((rows, 2), |_| rng.random())
}

fn franke_of(x: &Array2<f64>) -> Array1<f64> {
    x.rows().into_iter().map(|r| franke(r[0], r[1])).collect()
}

/// RMS error of `predicted` against `truth`, relative to the standard deviation of `truth`.
fn relative_rms(predicted: &Array1<f64>, truth: &Array1<f64>) -> f64 {
    let mse = (predicted - truth).mapv(|d| d * d).mean().unwrap();
    mse.sqrt() / truth.std(0.0)
}

/// The native API as the `franke` example uses it: the example's initial triangle, training on
/// random rows of the same samples for cells · λ · 4/3 steps (insertion off at the budget),
/// then the least-squares polish.
fn native(x: &Array2<f64>, y: &Array1<f64>, cells: usize, seed: u64) -> Isgcs {
    let params = Params::accurate();
    let init = vec![vec![0.3, 0.3], vec![0.7, 0.3], vec![0.5, 0.7]];
    let mut net = Isgcs::new(params, 2, 1, 2, init).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for _ in 0..cells * params.lambda * 4 / 3 {
        if net.len() >= cells {
            net.set_growing(false);
        }
        let i = rng.random_range(0..x.nrows());
        net.train(x.row(i).as_slice().unwrap(), &[y[i]], None);
    }
    let flat: Vec<f64> = x.iter().copied().collect();
    net.fit_outputs(&flat, y.as_slice().unwrap(), 1e-9).unwrap();
    net
}

#[test]
fn franke_through_linfa_is_as_accurate_as_the_native_api() {
    let (cells, seed) = (200, 1);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let x = points(20 * cells, &mut rng);
    let y = franke_of(&x);
    let data = Dataset::new(x.clone(), y.clone());
    let start = std::time::Instant::now();
    let model = IsgcsRegressor::params()
        .max_cells(cells)
        .seed(seed)
        .fit(&data)
        .unwrap();
    let linfa_seconds = start.elapsed().as_secs_f64();
    assert_eq!(model.network().len(), cells);
    assert_eq!(model.report().stopped, Stopped::CellBudget);
    assert!(model.report().ridge.is_some());

    let test = points(10_000, &mut ChaCha8Rng::seed_from_u64(1000));
    let truth = franke_of(&test);
    let via_linfa = relative_rms(&model.predict(&test), &truth);

    let start = std::time::Instant::now();
    let net = native(&x, &y, cells, seed);
    let native_seconds = start.elapsed().as_secs_f64();
    let mut out = vec![0.0; test.nrows()];
    net.predict_batch(test.as_slice().unwrap(), &mut out)
        .unwrap();
    let via_native = relative_rms(&Array1::from(out), &truth);
    eprintln!(
        "franke, {cells} cells, accurate preset: rms/sd linfa {via_linfa:.4} \
         ({linfa_seconds:.2} s), native {via_native:.4} ({native_seconds:.2} s)"
    );
    assert!(via_linfa <= 0.02, "linfa rms/sd {via_linfa}");
    assert!(via_native <= 0.02, "native rms/sd {via_native}");
    assert!(
        (via_linfa - via_native).abs() <= 0.01,
        "linfa {via_linfa} vs native {via_native}"
    );

    // The same seed gives the same model; the dataset overload of predict agrees.
    let again = IsgcsRegressor::params()
        .max_cells(cells)
        .seed(seed)
        .fit(&data)
        .unwrap();
    let a: Array1<f64> = again.predict(&test);
    assert_eq!(a, model.predict(&test));
    let on_dataset: Array1<f64> = model.predict(&data);
    assert_eq!(on_dataset, model.predict(data.records()));
}

#[test]
fn single_and_multi_output_targets_agree() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let x = points(1500, &mut rng);
    let y = franke_of(&x);
    let params = IsgcsRegressor::params().max_cells(60).seed(2);
    let one: IsgcsRegressor<Ix1> = params.fit(&Dataset::new(x.clone(), y.clone())).unwrap();
    let column = y.clone().insert_axis(Axis(1));
    let two: IsgcsRegressor<Ix2> = params.fit(&Dataset::new(x.clone(), column)).unwrap();
    let test = points(500, &mut rng);
    let p1: Array1<f64> = one.predict(&test);
    let p2: Array2<f64> = two.predict(&test);
    assert_eq!(p2.dim(), (500, 1));
    // One output column trains exactly like single-output targets.
    assert_eq!(p1, p2.column(0));
    assert_eq!(one.predict_outputs(&test).unwrap(), p2);

    // Two outputs: Franke and a plane, one column each.
    let plane = |x: &Array2<f64>| x.column(0).mapv(|a| 0.5 * a) - x.column(1).mapv(|b| 0.25 * b);
    let mut targets = Array2::zeros((x.nrows(), 2));
    targets.column_mut(0).assign(&y);
    targets.column_mut(1).assign(&plane(&x));
    let both = params.fit(&Dataset::new(x, targets)).unwrap();
    let p: Array2<f64> = both.predict(&test);
    assert_eq!(p.dim(), (500, 2));
    let franke_rms = relative_rms(&p.column(0).to_owned(), &franke_of(&test));
    let plane_rms = relative_rms(&p.column(1).to_owned(), &plane(&test));
    assert!(franke_rms < 0.1, "franke column rms/sd {franke_rms}");
    assert!(plane_rms < 0.01, "plane column rms/sd {plane_rms}");

    // Inputs in any memory layout predict the same.
    let transposed = test.t().to_owned();
    assert_eq!(one.predict(&transposed.t()), p1);
    // A column-major target array (not a row-major slice) is filled the same.
    let mut fortran = Array2::zeros((2, 500)).reversed_axes();
    both.predict_inplace(&test, &mut fortran);
    assert_eq!(fortran, p);
}

#[test]
fn thesis_preset_without_least_squares_and_early_stops() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let x = points(600, &mut rng);
    let data = Dataset::new(x.clone(), franke_of(&x));
    let model = IsgcsRegressor::params()
        .network_params(Params::thesis())
        .least_squares(None)
        .max_cells(40)
        .max_steps(Some(1000))
        .fit(&data)
        .unwrap();
    assert_eq!(model.report().stopped, Stopped::StepBudget);
    assert_eq!(model.report().growth_steps, 1000);
    assert_eq!(model.report().settle_steps, 333);
    assert_eq!(model.report().ridge, None);
    assert_eq!(model.network().len(), 3 + 1000 / 300);
    let model = IsgcsRegressor::params()
        .max_cells(1000)
        .target_error(Some(1.0))
        .settle(0.0)
        .fit(&data)
        .unwrap();
    assert_eq!(model.report().stopped, Stopped::TargetError);
    assert_eq!(model.report().settle_steps, 0);
    // A non-finite input row predicts NaN; the others are unaffected.
    let mut q = x.slice_axis(Axis(0), Slice::from(..3)).to_owned();
    q[[1, 0]] = f64::NAN;
    let p: Array1<f64> = model.predict(&q);
    assert!(p[0].is_finite() && p[1].is_nan() && p[2].is_finite());
}

fn fit_err(params: IsgcsRegressorParams, x: Array2<f64>, y: Array1<f64>) -> IsgcsRegressorError {
    params.fit(&Dataset::new(x, y)).unwrap_err()
}

#[test]
fn bad_inputs_are_errors() {
    use IsgcsRegressorError as E;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let x = points(50, &mut rng);
    let y = franke_of(&x);
    let p = || IsgcsRegressor::params().max_cells(10);
    let e = fit_err(p(), Array2::zeros((0, 2)), Array1::zeros(0));
    assert!(matches!(e, E::EmptyDataset), "{e}");
    let e = fit_err(p(), Array2::zeros((50, 0)), y.clone());
    assert!(matches!(e, E::NoFeatures), "{e}");
    let e = p()
        .fit(&Dataset::new(x.clone(), Array2::<f64>::zeros((50, 0))))
        .unwrap_err();
    assert!(matches!(e, E::NoOutputs), "{e}");
    let e = fit_err(
        p(),
        x.clone(),
        y.slice_axis(Axis(0), Slice::from(..49)).to_owned(),
    );
    assert!(matches!(e, E::ShapeMismatch(_)), "{e}");

    let mut bad = x.clone();
    bad[[7, 1]] = f64::NAN;
    let e = fit_err(p(), bad, y.clone());
    assert!(
        matches!(e, E::NonFinite { what: "records", row: 7, column: 1, value } if value.is_nan()),
        "{e}"
    );
    let mut bad = x.clone();
    bad[[2, 0]] = f64::INFINITY;
    let e = fit_err(p(), bad, y.clone());
    assert!(
        matches!(
            e,
            E::NonFinite {
                what: "records",
                row: 2,
                column: 0,
                ..
            }
        ),
        "{e}"
    );
    let mut bad = y.clone();
    bad[11] = f64::NAN;
    let e = fit_err(p(), x.clone(), bad);
    assert!(
        matches!(
            e,
            E::NonFinite {
                what: "targets",
                row: 11,
                column: 0,
                ..
            }
        ),
        "{e}"
    );

    let e = fit_err(p().topology_dim(3), x.clone(), y.clone());
    assert!(matches!(e, E::TopologyDim { k: 3, n: 2 }), "{e}");
    let e = fit_err(p().topology_dim(0), x.clone(), y.clone());
    assert!(matches!(e, E::InvalidParams(_)), "{e}");
    let e = fit_err(p().max_cells(0), x.clone(), y.clone());
    assert!(matches!(e, E::CellBudget { cells: 0, min: 2 }), "{e}");
    let e = fit_err(p().topology_dim(2).max_cells(2), x.clone(), y.clone());
    assert!(matches!(e, E::CellBudget { cells: 2, min: 3 }), "{e}");
    // The default k = min(n, 2) is only known with the data.
    let e = fit_err(p().max_cells(2), x.clone(), y.clone());
    assert!(matches!(e, E::CellBudget { cells: 2, min: 3 }), "{e}");

    for params in [
        p().max_steps(Some(0)),
        p().target_error(Some(f64::NAN)),
        p().target_error(Some(-1.0)),
        p().settle(-0.5),
        p().settle(f64::INFINITY),
        p().least_squares(Some(f64::NAN)),
        p().network_params(Params {
            kappa: 400,
            ..Params::accurate()
        }),
    ] {
        assert!(matches!(params.check_ref(), Err(E::InvalidParams(_))));
        let e = fit_err(params, x.clone(), y.clone());
        assert!(matches!(e, E::InvalidParams(_)), "{e}");
    }
    let params = p().network_params(Params {
        eps_bmu: -1.0,
        ..Params::accurate()
    });
    let e = fit_err(params.clone(), x.clone(), y.clone());
    assert!(matches!(e, E::Network(_)), "{e}");
    assert!(params.check().is_err());
    // Deletion is fine with a step budget.
    let ok = p()
        .network_params(Params {
            kappa: 400,
            ..Params::accurate()
        })
        .max_steps(Some(2000));
    assert!(ok.fit(&Dataset::new(x.clone(), y.clone())).is_ok());

    // Prediction inputs with the wrong number of features.
    let model = p().fit(&Dataset::new(x, y)).unwrap();
    let e = model.predict_outputs(&Array2::zeros((4, 3))).unwrap_err();
    assert!(matches!(e, E::ShapeMismatch(_)), "{e}");
}

/// `predict` cannot return an error: like linfa's own models it panics on inputs with the wrong
/// number of features (`predict_outputs` is the fallible form, tested above).
#[test]
#[should_panic(expected = "fitted on 2 features, the input has 3")]
fn predict_panics_on_the_wrong_number_of_features() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let x = points(50, &mut rng);
    let y = franke_of(&x);
    let model = IsgcsRegressor::params()
        .max_cells(5)
        .fit(&Dataset::new(x, y))
        .unwrap();
    let _: Array1<f64> = model.predict(&Array2::zeros((4, 3)));
}
