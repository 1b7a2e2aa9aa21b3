//! `cargo xtask bench --only isgcs-peers`: the default ISGCS regressor (only `max_cells` and
//! `seed` set) against the k-means Gaussian RBF reference at equal centres (width and ridge
//! chosen on a holdout), and, through `xtask/py/isgcs_peers.py`, against scipy's
//! `RBFInterpolator` and scikit-learn (KNN, MLP, Gaussian process, gradient boosting) when
//! they are installed. Every problem of `isgcs::test_functions::suite`, at 300 cells on 3000
//! rows and 1000 cells on 10 000 rows; rms/σ on 20 000 noise-free test points, fit and
//! predict seconds (two rayon threads; fit seconds of the two Rust models the shortest of
//! `ISGCS_PEERS_REPEAT` (default 3) interleaved fits). Writes `benchmarks-isgcs-peers.md` and
//! `figures/isgcs-peers-<cells>.png` (one per size). `ISGCS_PEERS_CELLS=300` (a comma list) runs only those sizes;
//! `ISGCS_PEERS_PYTHON_CACHE=FILE` keeps the Python results in FILE and reruns only the cases
//! it lacks (`python_peers`).

use crate::ctx::Ctx;
use anyhow::Result;
use isgcs::rbf::KMeansRbf;
use isgcs::regressor::{Regressor, RegressorParams};
use isgcs::test_functions::{Problem, suite};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::time::Instant;

/// One measured fit.
struct Row {
    problem: &'static str,
    cells: usize,
    method: String,
    rms: f64,
    fit: f64,
    predict: f64,
}

/// An rms/σ for the tables: four decimals, or two significant digits below 0.001 (the
/// smooth problems reach 10⁻⁶, which four decimals showed as 0.0000).
fn fmt_rms(v: f64) -> String {
    if v.abs() < 1e-3 && v != 0.0 {
        format!("{v:.1e}")
    } else {
        format!("{v:.4}")
    }
}

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

/// Fits per model in [`measure`] (`ISGCS_PEERS_REPEAT`, default 3).
fn repeats() -> usize {
    std::env::var("ISGCS_PEERS_REPEAT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3usize)
        .max(1)
}

/// Fits both models `repeats()` times, interleaved (isgcs, RBF, isgcs, RBF, …), and records
/// the shortest fit time of each: the fits are deterministic (equal models every time), so
/// the spread is the shared machine's load, and the shortest fit is the least disturbed one;
/// interleaving exposes both models to the same load.
fn measure(p: &Problem, cells: usize, rows: usize, seed: u64, out: &mut Vec<Row>) -> Result<()> {
    let n = p.dim();
    let (x, y) = p.sample(rows, true, seed);
    let (tx, ty) = p.sample(20_000, false, seed + 1000);
    let mut pred = vec![0.0; ty.len()];
    let params = RegressorParams {
        max_cells: cells,
        seed,
        ..RegressorParams::default()
    };
    let (mut fit_isgcs, mut fit_rbf) = (f64::INFINITY, f64::INFINITY);
    let (mut model, mut rbf) = (None, None);
    for _ in 0..repeats() {
        let t = Instant::now();
        model = Some(Regressor::fit(&params, &x, &y, n, 1)?);
        fit_isgcs = fit_isgcs.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        rbf = Some(KMeansRbf::fit(&x, &y, n, 1, cells, seed)?);
        fit_rbf = fit_rbf.min(t.elapsed().as_secs_f64());
    }
    let (model, rbf) = (model.expect("one fit"), rbf.expect("one fit"));
    let t = Instant::now();
    model.predict(&tx, &mut pred)?;
    let predict = t.elapsed().as_secs_f64();
    out.push(Row {
        problem: p.name,
        cells,
        method: "isgcs".into(),
        rms: rms_over_sd(&pred, &ty),
        fit: fit_isgcs,
        predict,
    });
    let t = Instant::now();
    rbf.predict(&tx, &mut pred)?;
    let predict = t.elapsed().as_secs_f64();
    out.push(Row {
        problem: p.name,
        cells,
        method: "kmeans-rbf".into(),
        rms: rms_over_sd(&pred, &ty),
        fit: fit_rbf,
        predict,
    });
    Ok(())
}

/// FNV-1a (64 bit): the cache key of a Python case (stable across Rust versions, unlike the
/// standard library's hasher).
fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        for &b in *part {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// Parses one result line of `isgcs_peers.py` (`None` for anything else).
fn python_row(v: &serde_json::Value) -> Option<Row> {
    let name = v.get("problem")?.as_str()?;
    let problem = suite().into_iter().find(|p| p.name == name)?.name;
    Some(Row {
        problem,
        cells: v["cells"].as_u64()? as usize,
        method: v["method"].as_str()?.to_string(),
        rms: v["rms"].as_f64().unwrap_or(f64::NAN),
        fit: v["fit"].as_f64().unwrap_or(f64::NAN),
        predict: v["predict"].as_f64().unwrap_or(f64::NAN),
    })
}

/// The Python peers on the same samples: `Ok((rows, cached))` or `Err(note)` when skipped.
///
/// The Python models do not depend on this crate's code, so with
/// `ISGCS_PEERS_PYTHON_CACHE=FILE` their results are kept in FILE (JSON lines, each with a key
/// hashing the script and the case's data) and only cases without a result are run; `cached`
/// counts the rows taken from FILE. Results are appended as they arrive, so an interrupted run
/// keeps what it finished.
fn python_peers(
    ctx: &Ctx,
    cases: &[(Problem, usize, usize)],
    seed: u64,
) -> Result<(Vec<Row>, usize), String> {
    use std::io::{BufRead, Write};
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("py/isgcs_peers.py");
    let script_text = std::fs::read(&script).map_err(|e| format!("{}: {e}", script.display()))?;
    let cache_path = std::env::var_os("ISGCS_PEERS_PYTHON_CACHE").map(std::path::PathBuf::from);
    let cached_lines: Vec<serde_json::Value> = cache_path
        .as_ref()
        .and_then(|p| std::fs::read_to_string(p).ok())
        .map(|t| {
            t.lines()
                .filter_map(|l| serde_json::from_str(l).ok())
                .collect()
        })
        .unwrap_or_default();
    let dir = ctx.out.join("isgcs-peers-data");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let mut rows = Vec::new();
    let mut cached = 0;
    // (problem, cells) → key of the cases to run.
    let mut pending: Vec<(&'static str, usize, String)> = Vec::new();
    for (p, cells, n_rows) in cases {
        let (x, y) = p.sample(*n_rows, true, seed);
        let (tx, ty) = p.sample(20_000, false, seed + 1000);
        let json = serde_json::json!({
            "problem": p.name, "cells": cells, "n": p.dim(),
            "x": x, "y": y, "tx": tx, "ty": ty,
        })
        .to_string();
        let key = format!("{:016x}", fnv1a(&[&script_text, json.as_bytes()]));
        let hits: Vec<Row> = cached_lines
            .iter()
            .filter(|v| v["key"].as_str() == Some(key.as_str()))
            .filter_map(python_row)
            .collect();
        if cache_path.is_some() && !hits.is_empty() {
            cached += hits.len();
            rows.extend(hits);
            continue;
        }
        std::fs::write(dir.join(format!("{}-{cells}.json", p.name)), json)
            .map_err(|e| e.to_string())?;
        pending.push((p.name, *cells, key));
    }
    if pending.is_empty() {
        let _ = std::fs::remove_dir_all(&dir);
        return Ok((rows, cached));
    }
    let mut child = std::process::Command::new("python3")
        .arg(&script)
        .arg(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| format!("python3 not runnable: {e}"))?;
    let stdout = child.stdout.take().expect("piped");
    let mut cache = cache_path.as_ref().and_then(|p| {
        std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(p)
            .ok()
    });
    let mut skipped = None;
    for line in std::io::BufReader::new(stdout).lines() {
        let line = line.map_err(|e| e.to_string())?;
        let Ok(mut v) = serde_json::from_str::<serde_json::Value>(&line) else {
            continue;
        };
        if let Some(note) = v.get("skipped") {
            skipped = Some(note.as_str().unwrap_or("skipped").to_string());
            continue;
        }
        let Some(row) = python_row(&v) else {
            continue;
        };
        println!(
            "isgcs-peers: {} {}: {} {} ({:.2} s)",
            row.problem,
            row.cells,
            row.method,
            fmt_rms(row.rms),
            row.fit
        );
        if let (Some(file), Some((_, _, key))) = (
            cache.as_mut(),
            pending
                .iter()
                .find(|(p, c, _)| *p == row.problem && *c == row.cells),
        ) {
            v["key"] = serde_json::Value::String(key.clone());
            let _ = writeln!(file, "{v}");
        }
        rows.push(row);
    }
    let output = child.wait_with_output().map_err(|e| e.to_string())?;
    let _ = std::fs::remove_dir_all(&dir);
    if let Some(note) = skipped {
        return Err(note);
    }
    if !output.status.success() {
        return Err(format!(
            "isgcs_peers.py failed: {}",
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    Ok((rows, cached))
}

fn plot(path: &std::path::Path, rows: &[Row], cells: usize) -> Result<()> {
    let e = |m: String| anyhow::anyhow!("plotting: {m}");
    let names: Vec<&str> = suite().iter().map(|p| p.name).collect();
    let mut methods: Vec<String> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method) {
            methods.push(r.method.clone());
        }
    }
    crate::plot::png(path, 1100, 520, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!("rms/σ at {cells} centres (log scale)"),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(
                // One empty column on the right for the legend.
                -0.5f64..names.len() as f64 + 0.7,
                (1e-6f64..2.0).log_scale(),
            )
            .map_err(|x| e(x.to_string()))?;
        chart
            .configure_mesh()
            // Enough label slots that every integer (problem) position gets one.
            .x_labels(4 * names.len())
            .x_label_formatter(&|v| {
                let i = v.round() as usize;
                if (v - i as f64).abs() < 0.01 {
                    names.get(i).copied().unwrap_or("").to_string()
                } else {
                    String::new()
                }
            })
            .y_desc("rms / σ")
            .draw()
            .map_err(|x| e(x.to_string()))?;
        for (k, method) in methods.iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            let off = (k as f64 - methods.len() as f64 / 2.0) * 0.08;
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| &r.method == method && r.cells == cells && r.rms.is_finite())
                .filter_map(|r| {
                    let i = names.iter().position(|n| *n == r.problem)?;
                    Some((i as f64 + off, r.rms.clamp(1e-6, 2.0)))
                })
                .collect();
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 5, colour.filled())))
                .map_err(|x| e(x.to_string()))?
                .label(method.as_str())
                .legend(move |(x, y)| Circle::new((x, y), 5, colour.filled()));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|x| e(x.to_string()))?;
        Ok(())
    })?;
    image::open(path)?.to_rgb8().save(path)?;
    Ok(())
}

/// Runs the group (two rayon threads, the "2 cores").
pub fn run(ctx: &Ctx) -> Result<()> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    pool.install(|| body(ctx))
}

/// The one-minute load average of the shared machine (Linux; "?" elsewhere).
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "?".into())
}

fn body(ctx: &Ctx) -> Result<()> {
    let seed = 1;
    let all: &[(usize, usize)] = if ctx.quick {
        &[(60, 600)]
    } else {
        &[(300, 3000), (1000, 10_000)]
    };
    // ISGCS_PEERS_CELLS=300 (comma list) keeps only those sizes, for runs that must fit a
    // time budget; the report's command line says so.
    let only = std::env::var("ISGCS_PEERS_CELLS").ok();
    let sizes: Vec<(usize, usize)> = all
        .iter()
        .copied()
        .filter(|(cells, _)| {
            only.as_ref()
                .is_none_or(|o| o.split(',').any(|c| c.trim() == cells.to_string()))
        })
        .collect();
    if sizes.is_empty() {
        anyhow::bail!("ISGCS_PEERS_CELLS={only:?} selects none of {all:?}");
    }
    let mut cases = Vec::new();
    for &(cells, rows) in &sizes {
        for p in suite() {
            cases.push((p, cells, rows));
        }
    }
    let load_start = load_average();
    let mut rows = Vec::new();
    for (p, cells, n) in &cases {
        measure(p, *cells, *n, seed, &mut rows)?;
        let r = &rows[rows.len() - 2..];
        println!(
            "isgcs-peers: {} {cells}: isgcs {} ({:.2} s), kmeans-rbf {} ({:.2} s)",
            p.name,
            fmt_rms(r[0].rms),
            r[0].fit,
            fmt_rms(r[1].rms),
            r[1].fit
        );
    }
    let python = python_peers(ctx, &cases, seed);
    let note = match &python {
        Ok((extra, cached)) => {
            let note = if *cached > 0 {
                format!(
                    "\n{cached} of the {} Python results were taken from `ISGCS_PEERS_PYTHON_CACHE` \
                     (same script and data; they were measured in an earlier run, under its load).\n",
                    extra.len()
                )
            } else {
                String::new()
            };
            rows.extend(extra.iter().map(|r| Row {
                problem: r.problem,
                cells: r.cells,
                method: r.method.clone(),
                rms: r.rms,
                fit: r.fit,
                predict: r.predict,
            }));
            note
        }
        Err(note) => format!(
            "\n**Python peers skipped**: {note}. Install them with `pip install scikit-learn scipy` \
             and rerun.\n"
        ),
    };
    let dir = ctx.out.join("figures");
    std::fs::create_dir_all(&dir)?;
    for &(cells, _) in &sizes {
        plot(&dir.join(format!("isgcs-peers-{cells}.png")), &rows, cells)?;
    }

    let load_end = load_average();
    let mut md = format!(
        "# `isgcs` against its peers\n\n\
         Command: `{}cargo xtask bench --only isgcs-peers{}` (release, two rayon threads; the machine \
         is shared, so compare times within one run; one-minute load average {load_start} before the fits, {load_end} after; \
         fit seconds of isgcs and the k-means RBF: the shortest of {repeat} fits each, interleaved \
         (the fits are deterministic; `ISGCS_PEERS_REPEAT` sets the count); both models \
         solve one Cholesky per candidate ridge: the k-means RBF on its 7 × 7 grid, isgcs along \
         its width and ridge walks on a holdout of the rows). Problems from `isgcs::test_functions::suite` \
         (uniform samples; noisy variants add Gaussian noise to the training targets only), seed {seed}. \
         rms/σ: RMS error on 20 000 noise-free test points over the test targets' standard \
         deviation (1 = predicting the mean). `isgcs`: `Regressor::fit` with only `max_cells` and \
         `seed` set. `kmeans-rbf`: `isgcs::rbf::KMeansRbf` (standardized inputs, k-means centres, \
         plain Gaussians, width multiplier and ridge chosen on a 20 % holdout from 7 × 7 values, \
         refitted on all rows; the same design-matrix and Gram code). Targets of issue 19: ratio ≤ 0.8 and fit \
         time ≤ 2× the k-means RBF.\n{note}\n\
         | problem | cells | rows | isgcs rms/σ | k-means RBF rms/σ | ratio | isgcs fit s | RBF fit s | time ratio | isgcs predict s |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        only.as_ref()
            .map_or(String::new(), |o| format!("ISGCS_PEERS_CELLS={o} "))
            + &std::env::var("ISGCS_PEERS_PYTHON_CACHE")
                .map_or(String::new(), |c| format!("ISGCS_PEERS_PYTHON_CACHE={c} ")),
        if ctx.quick { " --quick" } else { "" },
        repeat = repeats(),
    );
    for (p, cells, n) in &cases {
        let find = |m: &str| {
            rows.iter()
                .find(|r| r.problem == p.name && r.cells == *cells && r.method == m)
        };
        if let (Some(a), Some(b)) = (find("isgcs"), find("kmeans-rbf")) {
            let _ = writeln!(
                md,
                "| {} | {cells} | {n} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.3} |",
                p.name,
                fmt_rms(a.rms),
                fmt_rms(b.rms),
                if a.rms / b.rms < 0.1 {
                    format!("{:.3}", a.rms / b.rms)
                } else {
                    format!("{:.2}", a.rms / b.rms)
                },
                a.fit,
                b.fit,
                a.fit / b.fit,
                a.predict
            );
        }
    }
    if python.is_ok() {
        md.push_str(
            "\n## All methods (rms/σ, fit seconds)\n\n| problem | cells | method | rms/σ | fit s | predict s |\n|---|---:|---|---:|---:|---:|\n",
        );
        for r in &rows {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.2} | {:.3} |",
                r.problem,
                r.cells,
                r.method,
                fmt_rms(r.rms),
                r.fit,
                r.predict
            );
        }
    }
    for &(cells, _) in &sizes {
        let _ = writeln!(
            md,
            "\n![rms/σ per problem at {cells} centres](figures/isgcs-peers-{cells}.png)"
        );
    }
    std::fs::write(ctx.out.join("benchmarks-isgcs-peers.md"), md)?;
    Ok(())
}
