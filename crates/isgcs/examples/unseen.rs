//! The default regressor against the k-means RBF on functions and data *not* in
//! `isgcs::test_functions::suite`, the suite the defaults were tuned on (issue 19, round
//! eleven): 1-D functions, kinks and ridges, published engineering functions (borehole, OTL
//! circuit, piston), Genz's product peak, a sharp peak, a high-frequency sine, a ball
//! indicator, Gaussian, clustered and manifold inputs, two outputs, a constant input column,
//! repeated rows, an input offset, Gaussian and Student-t noise; `--edge 1` runs the misuse
//! and tiny-data cases instead. Results and the changes they led to: `docs/design/isgcs.md`.
//!
//! `cargo run --release -p isgcs --example unseen -- [--cells 300] [--rows 10*cells] [--seed 1]
//! [--only NAME] [--exact NAME] [--mult μ] [--ridge ρ] [--norbf 1] [--dump DIR] [--edge 1]`
//!
//! rms/σ: RMS error on 20 000 noise-free test points drawn from the *same input distribution*
//! as the training rows, over the test targets' std (per output column; for m = 2 the mean of
//! the two is the headline and both are printed). `--dump DIR` writes DIR/NAME.{train,test}.csv
//! (inputs then targets; test targets noise-free) for the Python smoothers.

mod common;

use common::{Run, arg, regressor_params};
use isgcs::rbf::KMeansRbf;
use isgcs::regressor::{Regressor, RegressorParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;
use std::io::Write;
use std::time::Instant;

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
    (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
}

#[derive(Clone, Copy)]
enum Noise {
    None,
    /// Gaussian, std = frac × σ(f).
    Gauss(f64),
    /// Student t with 3 dof, scaled to std = frac × σ(f).
    T3(f64),
}

#[derive(Clone)]
enum Input {
    /// Uniform on the box.
    Box(Vec<f64>, Vec<f64>),
    /// Standard normal in every coordinate.
    Gauss,
    /// Six tight Gaussian clusters (sd 0.04) at fixed random centres in [0, 1]^n.
    Clusters,
    /// A 2-D manifold (u, v) ∈ [0, 1]² embedded in 5-D.
    Manifold,
}

type F = fn(&[f64], &mut [f64]);

#[derive(Clone)]
struct Case {
    name: &'static str,
    n: usize,
    m: usize,
    input: Input,
    f: F,
    noise: Noise,
    /// Each row (inputs and noisy target) repeated this many times; N distinct = rows / dup.
    dup: usize,
    /// Add the constant 1e6 to every input.
    offset: f64,
}

fn unit(n: usize) -> Input {
    Input::Box(vec![0.0; n], vec![1.0; n])
}

fn draw_x(input: &Input, n: usize, rng: &mut ChaCha8Rng, x: &mut Vec<f64>) {
    match input {
        Input::Box(lo, hi) => {
            for a in 0..n {
                x.push(lo[a] + (hi[a] - lo[a]) * rng.random::<f64>());
            }
        }
        Input::Gauss => {
            for _ in 0..n {
                x.push(normal(rng));
            }
        }
        Input::Clusters => {
            // Fixed centres from their own seed.
            let mut crng = ChaCha8Rng::seed_from_u64(777);
            let centres: Vec<f64> = (0..6 * n).map(|_| crng.random::<f64>()).collect();
            let k = rng.random_range(0..6);
            for a in 0..n {
                x.push(centres[k * n + a] + 0.04 * normal(rng));
            }
        }
        Input::Manifold => {
            let (u, v): (f64, f64) = (rng.random(), rng.random());
            x.extend([
                (1.0 + u) * (3.0 * u).cos(),
                (1.0 + u) * (3.0 * u).sin(),
                v,
                u * v,
                (2.0 * v).sin() + u * u,
            ]);
        }
    }
}

// ---- functions ----------------------------------------------------------------------------
fn sin1d(x: &[f64], y: &mut [f64]) {
    y[0] = (2.0 * PI * x[0]).sin() + 0.5 * x[0];
}
fn kink1d(x: &[f64], y: &mut [f64]) {
    y[0] = (x[0] - 0.3).abs() + 0.2 * (5.0 * x[0]).sin();
}
fn ridge3(x: &[f64], y: &mut [f64]) {
    y[0] = (x[0] - x[1]).abs() + 0.5 * x[2] * x[2];
}
/// Varies only along the direction (cos 30°, sin 30°) of (x1, x2); x3 a nuisance input.
fn aniso3(x: &[f64], y: &mut [f64]) {
    let t = x[0] * (PI / 6.0).cos() + x[1] * (PI / 6.0).sin();
    y[0] = (3.0 * PI * t).sin();
}
/// Borehole (Harper & Gupta 1983), 8-D, standard ranges.
fn borehole(x: &[f64], y: &mut [f64]) {
    let (rw, r, tu, hu, tl, hl, l, kw) = (x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]);
    let lr = (r / rw).ln();
    y[0] = 2.0 * PI * tu * (hu - hl) / (lr * (1.0 + 2.0 * l * tu / (lr * rw * rw * kw) + tu / tl));
}
const BORE_LO: [f64; 8] = [0.05, 100.0, 63070.0, 990.0, 63.1, 700.0, 1120.0, 9855.0];
const BORE_HI: [f64; 8] = [
    0.15, 50000.0, 115600.0, 1110.0, 116.0, 820.0, 1680.0, 12045.0,
];
/// OTL circuit (Ben-Ari & Steinberg 2007), 6-D.
fn otl(x: &[f64], y: &mut [f64]) {
    let (rb1, rb2, rf, rc1, rc2, beta) = (x[0], x[1], x[2], x[3], x[4], x[5]);
    let vb1 = 12.0 * rb2 / (rb1 + rb2);
    let d = beta * (rc2 + 9.0) + rf;
    y[0] = (vb1 + 0.74) * beta * (rc2 + 9.0) / d
        + 11.35 * rf / d
        + 0.74 * rf * beta * (rc2 + 9.0) / (d * rc1);
}
const OTL_LO: [f64; 6] = [50.0, 25.0, 0.5, 1.2, 0.25, 50.0];
const OTL_HI: [f64; 6] = [150.0, 70.0, 3.0, 2.5, 1.2, 300.0];
/// Piston cycle time (Kenett & Zacks 1998), 7-D.
fn piston(x: &[f64], y: &mut [f64]) {
    let (mm, s, v0, k, p0, ta, t0) = (x[0], x[1], x[2], x[3], x[4], x[5], x[6]);
    let a = p0 * s + 19.62 * mm - k * v0 / s;
    let v = s / (2.0 * k) * ((a * a + 4.0 * k * p0 * v0 / t0 * ta).sqrt() - a);
    y[0] = 2.0 * PI * (mm / (k + s * s * p0 * v0 / t0 * ta / (v * v))).sqrt();
}
const PIS_LO: [f64; 7] = [30.0, 0.005, 0.002, 1000.0, 90000.0, 290.0, 340.0];
const PIS_HI: [f64; 7] = [60.0, 0.020, 0.010, 5000.0, 110000.0, 296.0, 360.0];
/// 5-D Rosenbrock on [−1, 1]⁵ (smooth, large dynamic range).
fn rosen5(x: &[f64], y: &mut [f64]) {
    y[0] = (0..4)
        .map(|i| 100.0 * (x[i + 1] - x[i] * x[i]).powi(2) + (1.0 - x[i]).powi(2))
        .sum();
}
/// Genz product peak, 5-D (a = 3, u = 0.4…0.6).
fn prodpeak5(x: &[f64], y: &mut [f64]) {
    y[0] = (0..5)
        .map(|i| 1.0 / (1.0 / 9.0 + (x[i] - 0.4 - 0.05 * i as f64).powi(2)))
        .product::<f64>()
        / 9f64.powi(5);
}
/// A sharp Gaussian peak (sd 0.04) on a gentle slope.
fn peak2(x: &[f64], y: &mut [f64]) {
    let r2 = (x[0] - 0.3).powi(2) + (x[1] - 0.6).powi(2);
    y[0] = (-r2 / (2.0 * 0.04 * 0.04)).exp() + 0.2 * x[0];
}
/// High-frequency sinusoid: 5 × 4 periods on the unit square.
fn hifreq2(x: &[f64], y: &mut [f64]) {
    y[0] = (2.0 * PI * 5.0 * x[0]).sin() * (2.0 * PI * 4.0 * x[1]).sin();
}
/// Discontinuous 3-D: a ball indicator plus a smooth part.
fn disc3(x: &[f64], y: &mut [f64]) {
    let r2 = (x[0] - 0.5).powi(2) + (x[1] - 0.5).powi(2) + (x[2] - 0.5).powi(2);
    y[0] = if r2 < 0.1 { 1.0 } else { 0.0 } + 0.5 * x[0] * x[1];
}
/// For Gaussian inputs, 4-D.
fn gauss4(x: &[f64], y: &mut [f64]) {
    let r2: f64 = x.iter().map(|v| v * v).sum();
    y[0] = (-r2 / 8.0).exp() * (2.0 * x[0]).sin() + 0.3 * x[1] * x[2] + x[3].tanh();
}
/// For clustered inputs, 3-D: varies within the clusters.
fn clus3(x: &[f64], y: &mut [f64]) {
    y[0] = (8.0 * x[0]).sin() + (6.0 * x[1]).cos() * x[2];
}
/// For the 5-D manifold inputs.
fn mani5(x: &[f64], y: &mut [f64]) {
    y[0] = (2.0 * x[0]).sin() + x[2] * x[3] + (3.0 * x[4]).cos();
}
/// Two outputs of three inputs.
fn multi3(x: &[f64], y: &mut [f64]) {
    y[0] = (PI * x[0]).sin() * (PI * x[1]).cos();
    y[1] = 4.0 * x[2] * x[2] + x[0] * x[1];
}
/// With a constant input column (x3 ≡ 1 is set by the case's box).
fn constcol(x: &[f64], y: &mut [f64]) {
    y[0] = (5.0 * x[0]).sin() * (4.0 * x[1]).cos() + x[0] + 0.0 * x[2];
}
/// Smooth 2-D (for the offset and edge cases).
fn smooth2(x: &[f64], y: &mut [f64]) {
    y[0] = (3.0 * x[0]).sin() * (2.0 + x[1]).ln() + x[1] * x[1];
}

fn cases() -> Vec<Case> {
    let c = |name, n, m, input, f: F, noise| Case {
        name,
        n,
        m,
        input,
        f,
        noise,
        dup: 1,
        offset: 0.0,
    };
    let bx = |lo: &[f64], hi: &[f64]| Input::Box(lo.to_vec(), hi.to_vec());
    use Noise::*;
    let mut v = vec![
        c("sin1d", 1, 1, unit(1), sin1d, None),
        c("sin1d-n30", 1, 1, unit(1), sin1d, Gauss(0.3)),
        c("kink1d", 1, 1, unit(1), kink1d, None),
        c("ridge3", 3, 1, unit(3), ridge3, None),
        c("ridge3-n10", 3, 1, unit(3), ridge3, Gauss(0.1)),
        c("aniso3", 3, 1, unit(3), aniso3, None),
        c("aniso3-t3", 3, 1, unit(3), aniso3, T3(0.3)),
        c("borehole8", 8, 1, bx(&BORE_LO, &BORE_HI), borehole, None),
        c(
            "borehole8-n10",
            8,
            1,
            bx(&BORE_LO, &BORE_HI),
            borehole,
            Gauss(0.1),
        ),
        c(
            "borehole8-n30",
            8,
            1,
            bx(&BORE_LO, &BORE_HI),
            borehole,
            Gauss(0.3),
        ),
        c("otl6", 6, 1, bx(&OTL_LO, &OTL_HI), otl, None),
        c("otl6-t3", 6, 1, bx(&OTL_LO, &OTL_HI), otl, T3(0.3)),
        c("piston7", 7, 1, bx(&PIS_LO, &PIS_HI), piston, None),
        c("rosen5", 5, 1, bx(&[-1.0; 5], &[1.0; 5]), rosen5, None),
        c("prodpeak5", 5, 1, unit(5), prodpeak5, None),
        c("peak2", 2, 1, unit(2), peak2, None),
        c("peak2-n10", 2, 1, unit(2), peak2, Gauss(0.1)),
        c("hifreq2", 2, 1, unit(2), hifreq2, None),
        c("hifreq2-n30", 2, 1, unit(2), hifreq2, Gauss(0.3)),
        c("disc3", 3, 1, unit(3), disc3, None),
        c("gaussin4", 4, 1, Input::Gauss, gauss4, None),
        c("gaussin4-n30", 4, 1, Input::Gauss, gauss4, Gauss(0.3)),
        c("clusters3", 3, 1, Input::Clusters, clus3, None),
        c("manifold5", 5, 1, Input::Manifold, mani5, None),
        c("multi3", 3, 2, unit(3), multi3, None),
        c("multi3-n10", 3, 2, unit(3), multi3, Gauss(0.1)),
        c(
            "constcol3",
            3,
            1,
            bx(&[0.0, 0.0, 1.0], &[1.0, 1.0, 1.0]),
            constcol,
            None,
        ),
        c("smooth2", 2, 1, unit(2), smooth2, None),
        c("smooth2-n10", 2, 1, unit(2), smooth2, Gauss(0.1)),
    ];
    let mut d = c("dup3-smooth2-n10", 2, 1, unit(2), smooth2, Gauss(0.1));
    d.dup = 3;
    v.push(d);
    let mut o = c("offset-smooth2", 2, 1, unit(2), smooth2, None);
    o.offset = 1e6;
    v.push(o);
    let mut o = c("offset-smooth2-n10", 2, 1, unit(2), smooth2, Gauss(0.1));
    o.offset = 1e6;
    v.push(o);
    v
}

/// `rows` inputs and targets (noise on the targets when `noisy`), and the std of each output
/// of the noise-free function (estimated from the same draw).
fn sample(case: &Case, rows: usize, noisy: bool, seed: u64, sd_f: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let (n, m) = (case.n, case.m);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let distinct = rows.div_ceil(case.dup.max(1));
    let mut x = Vec::with_capacity(rows * n);
    let mut y = Vec::with_capacity(rows * m);
    let mut out = vec![0.0; m];
    for _ in 0..distinct {
        let start = x.len();
        draw_x(&case.input, n, &mut rng, &mut x);
        (case.f)(&x[start..], &mut out);
        for (c, v) in out.iter_mut().enumerate() {
            if noisy {
                *v += sd_f[c]
                    * match case.noise {
                        Noise::None => 0.0,
                        Noise::Gauss(s) => s * normal(&mut rng),
                        Noise::T3(s) => {
                            let z = normal(&mut rng);
                            let chi: f64 = (0..3).map(|_| normal(&mut rng).powi(2)).sum();
                            s * z / (chi / 3.0).sqrt() / 3f64.sqrt()
                        }
                    };
            }
        }
        for a in start..x.len() {
            x[a] += case.offset;
        }
        let row: Vec<f64> = x[start..].to_vec();
        for _ in 1..case.dup {
            x.extend_from_slice(&row);
            y.extend_from_slice(&out);
        }
        y.extend_from_slice(&out);
    }
    // Interleave-free: duplicates are adjacent; the fits shuffle rows themselves.
    x.truncate(rows * n);
    y.truncate(rows * m);
    (x, y)
}

fn col_sd(y: &[f64], m: usize) -> Vec<f64> {
    let rows = (y.len() / m) as f64;
    (0..m)
        .map(|c| {
            let mean = y.iter().skip(c).step_by(m).sum::<f64>() / rows;
            (y.iter()
                .skip(c)
                .step_by(m)
                .map(|v| (v - mean).powi(2))
                .sum::<f64>()
                / rows)
                .sqrt()
        })
        .collect()
}

fn rms_over_sd(pred: &[f64], truth: &[f64], m: usize) -> Vec<f64> {
    let sd = col_sd(truth, m);
    let rows = (truth.len() / m) as f64;
    (0..m)
        .map(|c| {
            let mse = pred
                .iter()
                .skip(c)
                .step_by(m)
                .zip(truth.iter().skip(c).step_by(m))
                .map(|(p, t)| (p - t).powi(2))
                .sum::<f64>()
                / rows;
            mse.sqrt() / sd[c]
        })
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn dump(dir: &str, name: &str, tag: &str, x: &[f64], y: &[f64], n: usize, m: usize) {
    let path = format!("{dir}/{name}.{tag}.csv");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&path).expect("dump file"));
    for (xr, yr) in x.chunks_exact(n).zip(y.chunks_exact(m)) {
        let cols: Vec<String> = xr.iter().chain(yr).map(|v| format!("{v:.17e}")).collect();
        writeln!(f, "{}", cols.join(",")).expect("write");
    }
}

fn edge_cases(seed: u64) {
    let base = RegressorParams {
        seed,
        ..RegressorParams::default()
    };
    let smooth = Case {
        name: "smooth2",
        n: 2,
        m: 1,
        input: unit(2),
        f: smooth2,
        noise: Noise::None,
        dup: 1,
        offset: 0.0,
    };
    let sd = [1.0];
    let (tx, ty) = sample(&smooth, 20_000, false, seed + 1000, &sd);
    let run = |label: &str, p: &RegressorParams, x: &[f64], y: &[f64], n: usize| {
        let t = Instant::now();
        let r = std::panic::catch_unwind(|| Regressor::fit(p, x, y, n, 1));
        let dt = t.elapsed().as_secs_f64();
        match r {
            Err(_) => println!("EDGE {label:40} PANIC ({dt:.2}s)"),
            Ok(Err(e)) => println!("EDGE {label:40} error: {e} ({dt:.2}s)"),
            Ok(Ok(model)) => {
                let mut extra = String::new();
                if n == 2 {
                    let mut out = vec![0.0; ty.len()];
                    model.predict(&tx, &mut out).unwrap();
                    let e = rms_over_sd(&out, &ty, 1)[0];
                    let rbf = std::panic::catch_unwind(|| {
                        KMeansRbf::fit(x, y, n, 1, p.max_cells, p.seed)
                    });
                    let er = match rbf {
                        Ok(Ok(r)) => {
                            r.predict(&tx, &mut out).unwrap();
                            format!("{:.4}", rms_over_sd(&out, &ty, 1)[0])
                        }
                        Ok(Err(e)) => format!("err {e}"),
                        Err(_) => "PANIC".into(),
                    };
                    extra = format!("rms/σ {e:.4} rbf {er}");
                }
                let r = model.report();
                println!(
                    "EDGE {label:40} ok ({dt:.2}s) cells {} k {} mult {:.2} ridge {:.1e} dof {:.1} blend {:.2} {extra}",
                    model.len(),
                    r.topology_dim,
                    r.width_multiplier,
                    r.ridge,
                    r.dof,
                    r.blend_share
                );
            }
        }
    };
    let (x, y) = sample(&smooth, 100, true, seed, &sd);
    run(
        "N=100, max_cells 30",
        &RegressorParams {
            max_cells: 30,
            ..base.clone()
        },
        &x,
        &y,
        2,
    );
    run(
        "N=100, max_cells 100 (= N)",
        &RegressorParams {
            max_cells: 100,
            ..base.clone()
        },
        &x,
        &y,
        2,
    );
    run(
        "N=100, max_cells 101 (> N)",
        &RegressorParams {
            max_cells: 101,
            ..base.clone()
        },
        &x,
        &y,
        2,
    );
    let (x3, y3) = sample(&smooth, 300, true, seed, &sd);
    run(
        "N=300, max_cells 300 (= N)",
        &RegressorParams {
            max_cells: 300,
            ..base.clone()
        },
        &x3,
        &y3,
        2,
    );
    let (x4, y4) = sample(&smooth, 40, true, seed, &sd);
    run(
        "N=40, max_cells 10",
        &RegressorParams {
            max_cells: 10,
            ..base.clone()
        },
        &x4,
        &y4,
        2,
    );
    run(
        "N=40, max_cells 3",
        &RegressorParams {
            max_cells: 3,
            ..base.clone()
        },
        &x4,
        &y4,
        2,
    );
    let (x5, y5) = sample(&smooth, 10, true, seed, &sd);
    run(
        "N=10, max_cells 5",
        &RegressorParams {
            max_cells: 5,
            ..base.clone()
        },
        &x5,
        &y5,
        2,
    );
    let mut xn = x.clone();
    xn[2 * 17 + 1] = f64::NAN;
    run(
        "NaN in input row 17",
        &RegressorParams {
            max_cells: 30,
            ..base.clone()
        },
        &xn,
        &y,
        2,
    );
    let mut yn = y.clone();
    yn[5] = f64::INFINITY;
    run(
        "inf in target row 5",
        &RegressorParams {
            max_cells: 30,
            ..base.clone()
        },
        &x,
        &yn,
        2,
    );
    // All rows identical inputs.
    let xs_same = vec![0.5; 200];
    let ys_same: Vec<f64> = (0..100).map(|i| i as f64).collect();
    run(
        "all inputs identical (N=100)",
        &RegressorParams {
            max_cells: 30,
            ..base.clone()
        },
        &xs_same,
        &ys_same,
        2,
    );
    // Constant target.
    let yc = vec![3.0; 100];
    run(
        "constant target (N=100)",
        &RegressorParams {
            max_cells: 30,
            ..base.clone()
        },
        &x,
        &yc,
        2,
    );
    // Near-constant column with a huge offset (1e6 + 1e-9 jitter).
    let mut xj = Vec::new();
    for (i, r) in x.chunks_exact(2).enumerate() {
        xj.extend([r[0], 1e6 + 1e-9 * (i % 7) as f64]);
    }
    let yj: Vec<f64> = x.chunks_exact(2).map(|r| (3.0 * r[0]).sin()).collect();
    run(
        "near-const col 1e6+1e-9 jitter",
        &RegressorParams {
            max_cells: 30,
            ..base.clone()
        },
        &xj,
        &yj,
        2,
    );
    // Integer-valued (grid, heavily tied) input.
    let xg: Vec<f64> = (0..3000)
        .flat_map(|i| [(i % 5) as f64, ((i * 7) % 3000) as f64 / 3000.0])
        .collect();
    let yg: Vec<f64> = xg
        .chunks_exact(2)
        .map(|r| r[0].sin() + (3.0 * r[1]).cos())
        .collect();
    run(
        "x1 ∈ {0..4} (5 levels), 3000 rows, 300",
        &RegressorParams {
            max_cells: 300,
            ..base.clone()
        },
        &xg,
        &yg,
        2,
    );
    // Predict with NaN.
    let (xa, ya) = sample(&smooth, 1000, false, seed, &sd);
    let model = Regressor::fit(
        &RegressorParams {
            max_cells: 50,
            ..base.clone()
        },
        &xa,
        &ya,
        2,
        1,
    )
    .unwrap();
    let mut out = [0.0; 2];
    let r = model.predict(&[0.5, f64::NAN, 1e9, 1e9], &mut out);
    println!("EDGE predict([0.5,NaN],[1e9,1e9]) -> {r:?} {out:?}");
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let Run {
        cells,
        rows,
        seed,
        only,
    } = Run::from_args(&args);
    let exact: String = arg(&args, "--exact", String::new());
    let dumpdir: String = arg(&args, "--dump", String::new());
    let norbf = arg::<u8>(&args, "--norbf", 0) == 1;
    if arg::<u8>(&args, "--edge", 0) == 1 {
        edge_cases(seed);
        return Ok(());
    }
    let params = regressor_params(&args, cells, seed);
    println!(
        "{:20} {:>8} {:>6} {:>8} {:>6} {:>6} {:>5} {:>6} {:>8} {:>6} {:>5} {:>5} rbf(μ,ρ) / per-output",
        "case", "isgcs", "t(s)", "rbf", "t(s)", "ratio", "tR", "mult", "ridge", "dof", "blend", "k",
    );
    for case in cases() {
        if !only.is_empty() && !case.name.contains(&only) {
            continue;
        }
        if !exact.is_empty() && case.name != exact {
            continue;
        }
        let (n, m) = (case.n, case.m);
        // σ of the noise-free function under the input distribution (for the noise scale).
        let (_, yref) = sample(&case, 20_000, false, 4242, &vec![1.0; m]);
        let sd_f = col_sd(&yref, m);
        let (x, y) = sample(&case, rows, true, seed, &sd_f);
        let (tx, ty) = sample(&case, 20_000, false, seed + 1000, &sd_f);
        if !dumpdir.is_empty() {
            dump(&dumpdir, case.name, "train", &x, &y, n, m);
            dump(&dumpdir, case.name, "test", &tx, &ty, n, m);
        }
        let t = Instant::now();
        let fitted = std::panic::catch_unwind(|| Regressor::fit(&params, &x, &y, n, m));
        let ts = t.elapsed().as_secs_f64();
        let model = match fitted {
            Err(_) => {
                println!("{:20} PANIC in Regressor::fit", case.name);
                continue;
            }
            Ok(Err(e)) => {
                println!("{:20} error: {e}", case.name);
                continue;
            }
            Ok(Ok(model)) => model,
        };
        let mut out = vec![0.0; ty.len()];
        model.predict(&tx, &mut out)?;
        let e = rms_over_sd(&out, &ty, m);
        if std::env::var("DIAG").is_ok() {
            // Centre covariance (in the fit's coordinates: T·standardized x) and width spread.
            let net = model.network();
            let z = net.len();
            let mut mu = vec![0.0; n];
            for i in 0..z {
                for a in 0..n {
                    mu[a] += net.centre(i)[a] / z as f64;
                }
            }
            let mut cov = vec![0.0; n * n];
            for i in 0..z {
                let c = net.centre(i);
                for a in 0..n {
                    for b in 0..n {
                        cov[a * n + b] += (c[a] - mu[a]) * (c[b] - mu[b]) / z as f64;
                    }
                }
            }
            let w = model.widths();
            let mut ws = w.clone();
            ws.sort_by(f64::total_cmp);
            let hits: Vec<u64> = (0..z).map(|i| net.hits(i) as u64).collect();
            eprintln!(
                "DIAG centre cov {:.3?} widths min/med/max {:.4} {:.4} {:.4} hits max {}",
                cov,
                ws[0],
                ws[z / 2],
                ws[z - 1],
                hits.iter().max().unwrap()
            );
        }
        let r = *model.report();
        let (er, tr, chosen) = if norbf {
            (vec![f64::NAN; m], f64::NAN, (f64::NAN, f64::NAN))
        } else {
            let t = Instant::now();
            let rbf = KMeansRbf::fit(&x, &y, n, m, cells, seed)?;
            let tr = t.elapsed().as_secs_f64();
            rbf.predict(&tx, &mut out)?;
            (rms_over_sd(&out, &ty, m), tr, rbf.chosen())
        };
        let per = if m > 1 {
            format!(" isgcs {e:.4?} rbf {er:.4?}")
        } else {
            String::new()
        };
        let (em, erm) = (mean(&e), mean(&er));
        println!(
            "{:20} {em:8.4} {ts:6.2} {erm:8.4} {tr:6.2} {:6.3} {:5.2} {:6.2} {:8.1e} {:6.1} {:5.2} {:5} ({:.1},{:.0e}){per}",
            case.name,
            em / erm,
            ts / tr,
            r.width_multiplier,
            r.ridge,
            r.dof,
            r.blend_share,
            r.topology_dim,
            chosen.0,
            chosen.1
        );
    }
    Ok(())
}
