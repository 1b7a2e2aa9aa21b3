//! Fits Franke's function through linfa's `Fit` / `Predict` traits (feature `linfa`) and reports
//! the error on 10 000 fresh points relative to the function's standard deviation.
//!
//! `cargo run --release -p isgcs --features linfa --example linfa_franke -- --cells 500 --seed 1
//! [--preset accurate|thesis]`
//!
//! The data are 20 · cells uniform random points of the unit square (as in the `franke`
//! example); the last line is `cells=<z> rms=<rms / sd> seconds=<fit time> predict_seconds=<..>`.

use isgcs::Params;
use isgcs::linfa::IsgcsRegressor;
use isgcs::test_functions::franke;
use linfa::prelude::*;
use ndarray::{Array1, Array2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> Result<T, String> {
    match args.iter().position(|a| a == name) {
        None => Ok(default),
        Some(i) => args
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| format!("{name} needs a valid value")),
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let cells: usize = arg(&args, "--cells", 500)?;
    let seed: u64 = arg(&args, "--seed", 1)?;
    let accurate = match arg(&args, "--preset", "accurate".to_string())?.as_str() {
        "accurate" => true,
        "thesis" => false,
        p => return Err(format!("--preset {p}: expected thesis or accurate").into()),
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut points = |rows: usize| Array2::from_shape_fn((rows, 2), |_| rng.random::<f64>());
    let franke_of = |x: &Array2<f64>| -> Array1<f64> {
        x.rows().into_iter().map(|r| franke(r[0], r[1])).collect()
    };
    let x = points(20 * cells);
    let data = Dataset::new(x.clone(), franke_of(&x));

    let params = IsgcsRegressor::params().max_cells(cells).seed(seed);
    let params = if accurate {
        params
    } else {
        params.network_params(Params::thesis()).least_squares(None)
    };
    let start = std::time::Instant::now();
    let model = params.fit(&data)?;
    let seconds = start.elapsed().as_secs_f64();

    let test = points(10_000);
    let truth = franke_of(&test);
    let start = std::time::Instant::now();
    let predicted = model.predict(&test);
    let predict_seconds = start.elapsed().as_secs_f64();
    let rms = predicted.mean_squared_error(&truth)?.sqrt() / truth.std(0.0);
    let r = model.report();
    println!(
        "isgcs via linfa: preset={} growth_steps={} settle_steps={} ridge={}",
        if accurate { "accurate" } else { "thesis" },
        r.growth_steps,
        r.settle_steps,
        r.ridge.map_or("none".to_string(), |v| format!("{v:.0e}")),
    );
    println!(
        "cells={} rms={rms:.4} seconds={seconds:.2} predict_seconds={predict_seconds:.3}",
        model.network().len()
    );
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
