//! Old-against-new driver for the exact integrals (docs/design/gauss-integrals.md, "Speed"). Build it
//! at two commits, copy the binaries aside and run them one after the other:
//! - `gram_profile tri`: `triangle_fast` / `triangle` ns per call (the bench's 6 cases, median of 31);
//! - `gram_profile gram N` / `decision N`: Gram (+ orthonormalization) of 1000 Gaussians on 2000
//!   triangles, all element sums / the fig. 3.6 decision, median of N;
//! - `gram_profile dump FILE [quick]`: Gram entries and 200 000 random triangle integrals, to diff
//!   two versions (`quick`: `triangle` only for the first 20 000). `CASES=k1,k2` prints those
//!   cases against `triangle_reference`.
use gauss_integrals::gram::{Domain, Gaussian, GramConfig, gram};
use gauss_integrals::{Orthonormal, triangle, triangle_fast};
use std::hint::black_box;
use std::io::Write;
use std::time::Instant;

type V = [f64; 3];

fn height(x: f64, y: f64) -> f64 {
    0.3 * (0.7 * x).sin() * (0.5 * y).cos()
}

fn surface(nx: usize, ny: usize) -> Domain {
    Domain::height_field(nx, ny, 1.0, height).unwrap()
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn base(nx: usize, ny: usize, n: usize, rng: &mut Rng) -> Vec<Gaussian> {
    let h = ((nx * ny) as f64 / n as f64).sqrt();
    let (cx, cy) = ((nx as f64 / h) as usize, (ny as f64 / h) as usize);
    let mut g = Vec::new();
    'outer: for j in 0..cy + 1 {
        for i in 0..cx + 1 {
            if g.len() == n {
                break 'outer;
            }
            let x = ((i as f64 + 0.5 + 0.1 * (rng.next() - 0.5)) * h).min(nx as f64);
            let y = ((j as f64 + 0.5 + 0.1 * (rng.next() - 0.5)) * h).min(ny as f64);
            g.push(Gaussian::new([x, y, height(x, y)], 1.14 * h));
        }
    }
    g
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map(String::as_str).unwrap_or("gram");
    let reps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let (nx, ny, n) = (25, 40, 1000);
    let dom = surface(nx, ny);
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let g0 = base(nx, ny, n, &mut rng);
    let width = g0[0].width;
    let interior = |x: &Gaussian| {
        let c = x.centre;
        let m = 3.0 * width;
        c[0] >= m && c[1] >= m && c[0] <= nx as f64 - m && c[1] <= ny as f64 - m
    };
    gauss_integrals::wedge::init();
    match what {
        "gram" | "decision" => {
            let g: Vec<Gaussian> = g0
                .iter()
                .map(|x| Gaussian {
                    flat: what == "decision" && interior(x),
                    ..*x
                })
                .collect();
            let cfg = GramConfig::default();
            let mut tg = vec![];
            let mut to = vec![];
            let mut evals = 0;
            for _ in 0..reps {
                let s = Instant::now();
                let gm = gram(&dom, &g, &cfg).unwrap();
                tg.push(s.elapsed().as_secs_f64());
                evals = gm.element_integrals;
                let d = gm.matrix.to_dense();
                let s = Instant::now();
                let o = Orthonormal::new(&d, 1e-12);
                to.push(s.elapsed().as_secs_f64());
                black_box(o);
            }
            tg.sort_by(f64::total_cmp);
            to.sort_by(f64::total_cmp);
            println!(
                "{what}: gram {:.3} s (min {:.3}), orth {:.3} s, total {:.3} s, {evals} element integrals",
                tg[reps / 2],
                tg[0],
                to[reps / 2],
                tg[reps / 2] + to[reps / 2]
            );
        }
        "tri" => {
            let t = [[0.0, 0.0, 0.0], [1.2, 0.1, 0.05], [0.3, 0.9, -0.1]];
            let centres: [V; 6] = [
                [0.45, 0.35, 0.2],
                [0.1, 0.2, 0.6],
                [1.5, 0.9, 0.3],
                [-1.0, 0.4, -0.5],
                [2.5, -1.0, 0.4],
                [0.6, 2.2, 1.0],
            ];
            for (name, f) in [
                ("fast", triangle_fast as fn(V, f64, V, V, V) -> f64),
                ("accurate", triangle),
            ] {
                let mut ts = vec![];
                for _ in 0..31 {
                    let s = Instant::now();
                    let mut acc = 0.0;
                    for _ in 0..20000 {
                        for c in &centres {
                            acc += f(black_box(*c), black_box(1.0), t[0], t[1], t[2]);
                        }
                    }
                    black_box(acc);
                    ts.push(s.elapsed().as_secs_f64() * 1e9 / 120000.0);
                }
                ts.sort_by(f64::total_cmp);
                println!("triangle {name}: {:.1} ns (min {:.1})", ts[15], ts[0]);
            }
        }
        "dump" => {
            // Reference values: Gram entries (exact and decision) and random triangle integrals.
            let path = args.get(2).expect("path");
            let mut f = std::fs::File::create(path).unwrap();
            let gm = gram(&dom, &g0, &GramConfig::default()).unwrap().matrix;
            for i in 0..n {
                for (j, v) in gm.row(i) {
                    writeln!(f, "G {i} {j} {v:e}").unwrap();
                }
            }
            if args.get(3).is_none() {
                let acc = GramConfig {
                    accurate: true,
                    ..GramConfig::default()
                };
                let gm = gram(&dom, &g0[..40], &acc).unwrap().matrix;
                for i in 0..40 {
                    for (j, v) in gm.row(i) {
                        writeln!(f, "A {i} {j} {v:e}").unwrap();
                    }
                }
            }
            let mut r = Rng(0xdead_beef_cafe_f00d);
            for k in 0..200000 {
                let scale = 10f64.powf(4.0 * r.next() - 2.0);
                let mut v = [[0.0; 3]; 3];
                for p in v.iter_mut() {
                    for x in p.iter_mut() {
                        *x = (2.0 * r.next() - 1.0) * scale;
                    }
                }
                if k % 10 == 0 {
                    // sliver / near-degenerate
                    let w = 10f64.powf(-12.0 * r.next());
                    v[2] =
                        [0, 1, 2].map(|i| 0.5 * (v[0][i] + v[1][i]) + w * scale * (r.next() - 0.5));
                }
                let far = 10f64.powf(3.0 * r.next() - 1.0);
                let c = [0, 1, 2].map(|_| (2.0 * r.next() - 1.0) * scale * far);
                let a = 10f64.powf(4.0 * r.next() - 2.0);
                let t1 = if args.get(3).is_none() || k < 20000 {
                    triangle(c, a, v[0], v[1], v[2])
                } else {
                    f64::NAN
                };
                let t2 = triangle_fast(c, a, v[0], v[1], v[2]);
                if std::env::var("CASES").is_ok_and(|v| v.split(',').any(|x| x == k.to_string())) {
                    eprintln!(
                        "case {k}: plane {:e} fast {t2:e} reference {:e} cubature {:e}",
                        triangle(c, a, v[0], v[1], v[2]),
                        gauss_integrals::triangle_reference(c, a, v[0], v[1], v[2]),
                        gauss_integrals::triangle_cubature(
                            |x| (-a
                                * ((x[0] - c[0]).powi(2)
                                    + (x[1] - c[1]).powi(2)
                                    + (x[2] - c[2]).powi(2)))
                            .exp(),
                            v,
                            1e-17 * t2
                        )
                        .value
                    );
                }
                writeln!(f, "T {k} {a:e} {t1:e} {t2:e}").unwrap();
            }
        }
        _ => panic!("unknown"),
    }
}
