//! Times `Orthonormal::new` against the plain column-major loop on a 1000×1000 Gaussian Gram
//! matrix (`cargo run --release -p gauss-integrals --example chol_timing`).
use gauss_integrals::Orthonormal;
use nalgebra::DMatrix;
use std::time::Instant;

fn plain(gram: &DMatrix<f64>) -> DMatrix<f64> {
    let n = gram.nrows();
    let mut l = DMatrix::<f64>::zeros(n, n);
    for k in 0..n {
        let mut d = gram[(k, k)];
        for j in 0..k {
            d -= l[(k, j)] * l[(k, j)];
        }
        if d <= 1e-12 * gram[(k, k)] {
            continue;
        }
        let lkk = d.sqrt();
        l[(k, k)] = lkk;
        for i in k + 1..n {
            let mut s = gram[(i, k)];
            for j in 0..k {
                s -= l[(i, j)] * l[(k, j)];
            }
            l[(i, k)] = s / lkk;
        }
    }
    l
}

fn main() {
    let n = 1000;
    let c: Vec<[f64; 2]> = (0..n).map(|i| [(i % 32) as f64, (i / 32) as f64]).collect();
    let g = DMatrix::from_fn(n, n, |i, j| {
        let d2 = (c[i][0] - c[j][0]).powi(2) + (c[i][1] - c[j][1]).powi(2);
        std::f64::consts::PI / 2.0 * 1.3 * (-d2 / 2.6).exp()
    });
    for _ in 0..3 {
        let t = Instant::now();
        let o = Orthonormal::new(&g, 1e-12);
        let t_new = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let l = plain(&g);
        let t_plain = t.elapsed().as_secs_f64();
        println!(
            "n={n}: Orthonormal::new {t_new:.3} s, plain loop {t_plain:.3} s, ratio {:.2}, rejected {} ({} threads)",
            t_plain / t_new,
            o.rejected(),
            rayon::current_num_threads(),
        );
        std::hint::black_box(l);
    }
}
