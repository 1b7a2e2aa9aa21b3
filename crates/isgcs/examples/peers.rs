//! The default regressor against the k-means RBF reference at equal centres on the benchmark
//! suite (`isgcs::test_functions::suite`): rms/σ on 20 000 noise-free test points and fit time.
//!
//! `cargo run --release -p isgcs --example peers -- [--cells 300] [--rows 3000] [--seed 1]
//! [--only NAME] [--affine 0|1] [--normalized 0|1] [--lambda L] [--repeat R]`
//!
//! With `--repeat R` every fit runs R times and the shortest wall time is printed (the fits
//! are deterministic; the minimum is the least disturbed by other load on the machine).

mod common;

use common::{Run, arg, regressor_params};
use isgcs::rbf::KMeansRbf;
use isgcs::regressor::Regressor;
use isgcs::test_functions::suite;
use std::time::Instant;

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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let Run {
        cells,
        rows,
        seed,
        only,
    } = Run::from_args(&args);
    let repeat: usize = arg(&args, "--repeat", 1usize).max(1);
    let params = regressor_params(&args, cells, seed);
    println!(
        "function          isgcs    t(s)   rbf     t(s)   ratio  k lam  mult   ridge    dof  t-ratio"
    );
    for p in suite() {
        if !only.is_empty() && !p.name.contains(&only) {
            continue;
        }
        let n = p.dim();
        let (x, y) = p.sample(rows, true, seed);
        let (tx, ty) = p.sample(20_000, false, seed + 1000);
        let mut ts = f64::INFINITY;
        let mut fitted = None;
        for _ in 0..repeat {
            let t = Instant::now();
            fitted = Some(Regressor::fit(&params, &x, &y, n, 1)?);
            ts = ts.min(t.elapsed().as_secs_f64());
        }
        let model = fitted.expect("repeat >= 1");
        let mut out = vec![0.0; ty.len()];
        model.predict(&tx, &mut out)?;
        let e = rms_over_sd(&out, &ty);
        let mut tr_out = vec![0.0; y.len()];
        model.predict(&x, &mut tr_out)?;
        if std::env::var("DUMP").is_ok() {
            let net = model.network();
            for i in 0..net.len() {
                eprintln!("c {:?} hits {}", net.centre(i), net.hits(i));
            }
        }
        let w = model.widths();
        let (lo, hi) = w
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        eprintln!(
            "train rms/sd {:.4} widths {lo:.4}..{hi:.4}",
            rms_over_sd(&tr_out, &y)
        );
        let mut tr = f64::INFINITY;
        let mut fitted = None;
        for _ in 0..repeat {
            let t = Instant::now();
            fitted = Some(KMeansRbf::fit(&x, &y, n, 1, cells, seed)?);
            tr = tr.min(t.elapsed().as_secs_f64());
        }
        let rbf = fitted.expect("repeat >= 1");
        rbf.predict(&tx, &mut out)?;
        let er = rms_over_sd(&out, &ty);
        let r = model.report();
        println!(
            "{:16} {e:7.4} {ts:6.2} {er:7.4} {tr:6.2} {:6.3} {} {:3} {:5.2} {:8.1e} {:6.1} {:5.2}  rbf μ,ρ {:?} [{e:.2e} {er:.2e}]",
            p.name,
            e / er,
            r.topology_dim,
            r.lambda,
            r.width_multiplier,
            r.ridge,
            r.dof,
            ts / tr,
            rbf.chosen()
        );
    }
    Ok(())
}
