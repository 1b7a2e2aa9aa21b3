//! Approximates Franke's 2-D test function (or a smooth 6-D function) from scattered samples
//! with an ISGCS network, and in the same run with a least-squares Gaussian-RBF fit on as many
//! k-means centres; reports both errors on 10 000 fresh points, relative to the function's
//! standard deviation.
//!
//! `cargo run --release -p isgcs --example franke -- --cells 500 --seed 1 [--preset thesis|accurate]
//! [--function franke|smooth6] [--lambda L] [--width W] [--rbf-width W] [--ridge R] [--normalized 0|1]
//! [--polish 0|1] [--rbf 0|1] [--extended 0|1] [--gamma 0|1]`
//!
//! `--preset accurate` (the default) is `Params::accurate()` followed by the least-squares polish
//! `Isgcs::fit_outputs`; `--preset thesis` is `Params::thesis()` with the delta rule only. The other
//! options override single knobs of the preset (`--polish 0|1` the least-squares polish,
//! `--rbf 0` skips the reference fit, `--extended 1` the extended resource τ^x of eq. 2.19,
//! `--gamma 1` the Γ-redistribution at insertion, eq. 2.11–2.14).
//!
//! The last line is `cells=<z> rms=<rms / sd> seconds=<training time>` for the network.

use isgcs::rbf::GaussianRbf;
use isgcs::test_functions::{franke, smooth6};
use isgcs::{Isgcs, Params};
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

struct Options {
    cells: usize,
    seed: u64,
    accurate: bool,
    six: bool,
    lambda: Option<usize>,
    width: Option<f64>,
    rbf_width: f64,
    ridge: f64,
    normalized: Option<bool>,
    polish: Option<bool>,
    rbf: bool,
    extended: bool,
    gamma: bool,
}

fn options() -> Result<Options, String> {
    let args: Vec<String> = std::env::args().collect();
    let cells: usize = arg(&args, "--cells", 500)?;
    if !(3..=100_000).contains(&cells) {
        return Err(format!("--cells {cells} out of range (3 to 100000)"));
    }
    let accurate = match arg(&args, "--preset", "accurate".to_string())?.as_str() {
        "accurate" => true,
        "thesis" => false,
        p => return Err(format!("--preset {p}: expected thesis or accurate")),
    };
    let six = match arg(&args, "--function", "franke".to_string())?.as_str() {
        "franke" => false,
        "smooth6" => true,
        f => return Err(format!("--function {f}: expected franke or smooth6")),
    };
    let lambda: Option<usize> = match arg(&args, "--lambda", 0usize)? {
        0 => None,
        l => Some(l),
    };
    let width: f64 = arg(&args, "--width", 0.0)?;
    let rbf_width: f64 = arg(&args, "--rbf-width", 3.0)?;
    if !(rbf_width > 0.0 && width >= 0.0) {
        return Err("--width and --rbf-width must be positive".into());
    }
    Ok(Options {
        cells,
        seed: arg(&args, "--seed", 1)?,
        accurate,
        six,
        lambda,
        width: (width > 0.0).then_some(width),
        rbf_width,
        ridge: arg(&args, "--ridge", 1e-9)?,
        normalized: match arg(&args, "--normalized", 2u8)? {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        },
        polish: match arg(&args, "--polish", 2u8)? {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        },
        rbf: arg(&args, "--rbf", 1u8)? != 0,
        extended: arg(&args, "--extended", 0u8)? != 0,
        gamma: arg(&args, "--gamma", 0u8)? != 0,
    })
}

fn main() {
    let o = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let (n, k) = if o.six { (6, 4) } else { (2, 2) };
    let f = |p: &[f64]| {
        if o.six {
            smooth6(p)
        } else {
            franke(p[0], p[1])
        }
    };
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let samples: Vec<Vec<f64>> = (0..20 * o.cells)
        .map(|_| (0..n).map(|_| rng.random()).collect())
        .collect();
    let init: Vec<Vec<f64>> = if o.six {
        (0..=k)
            .map(|i| (0..n).map(|a| if a + 1 == i { 0.6 } else { 0.4 }).collect())
            .collect()
    } else {
        vec![vec![0.3, 0.3], vec![0.7, 0.3], vec![0.5, 0.7]]
    };
    let mut params = if o.accurate {
        Params::accurate()
    } else {
        Params::thesis()
    };
    if let Some(l) = o.lambda {
        params.lambda = l;
    }
    params.gamma_redistribution = o.gamma;
    if o.extended {
        params.extended_resource = true;
    }
    if let Some(v) = o.normalized {
        params.normalized = v;
    }
    if let Some(w) = o.width {
        params.width_multiplier = w;
    }
    let mut net = match Isgcs::new(params, n, 1, k, init) {
        Ok(net) => net,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let targets: Vec<f64> = samples.iter().map(|s| f(s)).collect();
    let start = std::time::Instant::now();
    let mut steps = 0usize;
    // Grow to the budget, then keep training the output layer for a third as long again.
    let total = o.cells * params.lambda * 4 / 3;
    while steps < total {
        if net.len() >= o.cells {
            net.set_growing(false);
        }
        let i = rng.random_range(0..samples.len());
        net.train(&samples[i], &[targets[i]], None);
        steps += 1;
    }
    let mut ridge = None;
    if o.polish.unwrap_or(o.accurate) {
        // The accurate preset ends with the least-squares polish of the output layer.
        match net.fit_outputs(&samples.concat(), &targets, o.ridge) {
            Ok(r) => ridge = Some(r),
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let test: Vec<Vec<f64>> = (0..10_000)
        .map(|_| (0..n).map(|_| rng.random()).collect())
        .collect();
    let values: Vec<f64> = test.iter().map(|p| f(p)).collect();
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64).sqrt();
    let rms = |predict: &dyn Fn(&[f64], &mut [f64])| {
        let mut out = [0.0];
        let mse = test
            .iter()
            .zip(&values)
            .map(|(p, v)| {
                predict(p, &mut out);
                (out[0] - v).powi(2)
            })
            .sum::<f64>()
            / test.len() as f64;
        mse.sqrt() / sd
    };
    let net_rms = rms(&|p, out| net.predict(p, out));
    // The reference in the same run: Gaussian RBF, k-means centres, least squares.
    let start = std::time::Instant::now();
    match (!o.rbf).then_some(()).map_or_else(
        || {
            GaussianRbf::fit(
                &samples.concat(),
                &targets,
                n,
                1,
                net.len(),
                o.rbf_width,
                30,
                o.ridge,
                o.seed,
            )
            .map(Some)
        },
        |_| Ok(None),
    ) {
        Ok(None) => {}
        Ok(Some(rbf)) => {
            let rbf_seconds = start.elapsed().as_secs_f64();
            println!(
                "rbf: centres={} rms={:.4} seconds={:.2}",
                rbf.len(),
                rms(&|p, out| rbf.predict(p, out)),
                rbf_seconds
            );
        }
        Err(e) => println!("rbf: {e}"),
    }
    println!(
        "isgcs: preset={} function={} lambda={} width_multiplier={} steps={} ridge={}",
        if o.accurate { "accurate" } else { "thesis" },
        if o.six { "smooth6" } else { "franke" },
        params.lambda,
        params.width_multiplier,
        steps,
        ridge.map_or("none".to_string(), |r| format!("{r:.0e}")),
    );
    println!(
        "cells={} rms={:.4} seconds={:.2}",
        net.len(),
        net_rms,
        seconds
    );
}
