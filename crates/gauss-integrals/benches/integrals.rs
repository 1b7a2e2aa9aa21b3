//! `cargo bench -p gauss-integrals --bench integrals`: one triangle integral, old (Owen's T) against
//! new (tabulated right-triangle function) in the same run, and one segment integral.

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use gauss_integrals::{segment, triangle, triangle_fast, triangle_reference};

type V = [f64; 3];

/// Triangles about one width across, centres inside and within a few widths outside: what the
/// gcr kernel Gram matrix asks for. Width 1 (a = 1).
fn cases() -> Vec<(V, [V; 3])> {
    let t = [[0.0, 0.0, 0.0], [1.2, 0.1, 0.05], [0.3, 0.9, -0.1]];
    let centres = [
        [0.45, 0.35, 0.2],
        [0.1, 0.2, 0.6],
        [1.5, 0.9, 0.3],
        [-1.0, 0.4, -0.5],
        [2.5, -1.0, 0.4],
        [0.6, 2.2, 1.0],
    ];
    centres.iter().map(|c| (*c, t)).collect()
}

fn bench_triangle(cr: &mut Criterion) {
    gauss_integrals::wedge::init();
    let cases = cases();
    let mut g = cr.benchmark_group("triangle");
    g.bench_function("reference_owens_t", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for (c, [p, q, r]) in &cases {
                s += triangle_reference(black_box(*c), black_box(1.0), *p, *q, *r);
            }
            s
        })
    });
    g.bench_function("fast_table", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for (c, [p, q, r]) in &cases {
                s += triangle_fast(black_box(*c), black_box(1.0), *p, *q, *r);
            }
            s
        })
    });
    g.bench_function("accurate", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for (c, [p, q, r]) in &cases {
                s += triangle(black_box(*c), black_box(1.0), *p, *q, *r);
            }
            s
        })
    });
    g.bench_function("wedge_r_x6", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for k in 0..6 {
                s += gauss_integrals::wedge::r(black_box(0.3 + 0.2 * k as f64), black_box(1.1));
            }
            s
        })
    });
    g.finish();
}

fn bench_segment(cr: &mut Criterion) {
    cr.bench_function("segment", |b| {
        b.iter(|| {
            segment(
                black_box([0.3, 0.4, 0.0]),
                black_box(2.0),
                [0.0, 0.0, 0.0],
                [1.0, 0.2, 0.0],
            )
        })
    });
}

criterion_group!(benches, bench_triangle, bench_segment);
criterion_main!(benches);
