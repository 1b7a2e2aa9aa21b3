//! Approximates Franke's 2-D test function from scattered samples and reports the error on
//! 10 000 fresh points, relative to the function's standard deviation.
//!
//! `cargo run --release -p isgcs --example franke -- --cells 500 --seed 1`

use isgcs::{Isgcs, Params};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn franke(x: f64, y: f64) -> f64 {
    0.75 * (-((9.0 * x - 2.0).powi(2) + (9.0 * y - 2.0).powi(2)) / 4.0).exp()
        + 0.75 * (-(9.0 * x + 1.0).powi(2) / 49.0 - (9.0 * y + 1.0) / 10.0).exp()
        + 0.5 * (-((9.0 * x - 7.0).powi(2) + (9.0 * y - 3.0).powi(2)) / 4.0).exp()
        - 0.2 * (-(9.0 * x - 4.0).powi(2) - (9.0 * y - 7.0).powi(2)).exp()
}

fn arg(args: &[String], name: &str, default: u64) -> Result<u64, String> {
    match args.iter().position(|a| a == name) {
        None => Ok(default),
        Some(i) => args
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| format!("{name} needs a non-negative integer")),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (cells, seed) = match (arg(&args, "--cells", 500), arg(&args, "--seed", 1)) {
        (Ok(c), Ok(s)) if (3..=100_000).contains(&c) => (c as usize, s),
        (Ok(c), Ok(_)) => {
            eprintln!("error: --cells {c} out of range (3 to 100000)");
            std::process::exit(2);
        }
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let samples: Vec<[f64; 2]> = (0..20 * cells)
        .map(|_| [rng.random(), rng.random()])
        .collect();
    let init = vec![vec![0.3, 0.3], vec![0.7, 0.3], vec![0.5, 0.7]];
    let params = Params {
        lambda: 300,
        ..Params::default()
    };
    let mut net = Isgcs::new(params, 2, 1, 2, init).expect("valid parameters");
    let start = std::time::Instant::now();
    let mut steps = 0usize;
    // Grow to the budget, then keep training the output layer for a third as long again.
    let total = cells * params.lambda * 4 / 3;
    while steps < total {
        if net.len() >= cells {
            net.set_growing(false);
        }
        let s = samples[rng.random_range(0..samples.len())];
        net.train(&s, &[franke(s[0], s[1])], None);
        steps += 1;
    }
    let seconds = start.elapsed().as_secs_f64();
    let test: Vec<[f64; 2]> = (0..10_000).map(|_| [rng.random(), rng.random()]).collect();
    let values: Vec<f64> = test.iter().map(|p| franke(p[0], p[1])).collect();
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64).sqrt();
    let mut out = [0.0];
    let mse = test
        .iter()
        .zip(&values)
        .map(|(p, v)| {
            net.predict(p, &mut out);
            (out[0] - v).powi(2)
        })
        .sum::<f64>()
        / test.len() as f64;
    println!(
        "cells={} rms={:.4} seconds={:.2}",
        net.len(),
        mse.sqrt() / sd,
        seconds
    );
}
