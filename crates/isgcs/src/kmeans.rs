//! Lloyd's k-means, for the centres of the k-means RBF reference and of the metric pilots.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn dist2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum()
}

/// Lloyd's k-means: `k` centres (k × n) of the N × n points, from k distinct random points
/// (seeded), at most `iterations` assignment/update rounds (assignment in parallel).
pub fn kmeans(points: &[f64], n: usize, k: usize, iterations: usize, seed: u64) -> Vec<f64> {
    use rayon::prelude::*;
    let count = points.len() / n;
    let k = k.min(count);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut order: Vec<usize> = (0..count).collect();
    for i in 0..k {
        let j = rng.random_range(i..count);
        order.swap(i, j);
    }
    let mut c: Vec<f64> = order[..k]
        .iter()
        .flat_map(|&s| points[s * n..(s + 1) * n].iter().copied())
        .collect();
    let mut assign = vec![usize::MAX; count];
    for _ in 0..iterations {
        let next: Vec<usize> = points
            .par_chunks(n)
            .with_min_len(64)
            .map(|x| {
                let mut best = (0, f64::INFINITY);
                for j in 0..k {
                    let d = dist2(x, &c[j * n..(j + 1) * n]);
                    if d < best.1 {
                        best = (j, d);
                    }
                }
                best.0
            })
            .collect();
        let changed = next != assign;
        assign = next;
        if !changed {
            break;
        }
        let mut sum = vec![0.0; k * n];
        let mut cnt = vec![0usize; k];
        for (s, x) in points.chunks_exact(n).enumerate() {
            cnt[assign[s]] += 1;
            for a in 0..n {
                sum[assign[s] * n + a] += x[a];
            }
        }
        for j in 0..k {
            if cnt[j] > 0 {
                for a in 0..n {
                    c[j * n + a] = sum[j * n + a] / cnt[j] as f64;
                }
            }
        }
    }
    c
}
