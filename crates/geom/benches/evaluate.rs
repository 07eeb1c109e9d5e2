//! Surface evaluation benchmarks (docs/benchmarks.md, "Geometry").
//!
//! - `point/rational_bicubic`: `NurbsSurface::point` at 4096 scattered parameters, one thread.
//! - `grid/1000x1000`: `NurbsSurface::grid` on a 1000 × 1000 tensor grid (rayon, all cores),
//!   and the same inside a one-thread rayon pool.
//!
//! The patch is the one of `bench-peers/` (curvo and splipy are measured there): bicubic, 8 × 8
//! control points, knots `{0,0,0,0, 0.2, 0.4, 0.6, 0.8, 1,1,1,1}` in both directions,
//! `P_ij = (i/7, j/7, ((3i + 5j) mod 7) / 14)`, `w_ij = 1 + ((i + 2j) mod 3) / 4`.
//!
//! Run: `cargo bench -p nurbspring-geom --bench evaluate -- --warm-up-time 1 --measurement-time 3`.

// `criterion_group!` generates an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nurbspring_geom::{KnotVector, NurbsSurface, linspace};

fn patch() -> NurbsSurface {
    let knots = vec![0., 0., 0., 0., 0.2, 0.4, 0.6, 0.8, 1., 1., 1., 1.];
    let k = KnotVector::try_new(knots, 3).unwrap();
    let mut pts = Vec::new();
    let mut ws = Vec::new();
    for i in 0..8 {
        for j in 0..8 {
            pts.push([
                i as f64 / 7.0,
                j as f64 / 7.0,
                ((3 * i + 5 * j) % 7) as f64 / 14.0,
            ]);
            ws.push(1.0 + ((i + 2 * j) % 3) as f64 / 4.0);
        }
    }
    NurbsSurface::try_new(k.clone(), k, pts, ws).unwrap()
}

/// 4096 parameters from a 64-bit LCG (the same sequence as bench-peers).
fn params(n: usize) -> Vec<(f64, f64)> {
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n).map(|_| (next(), next())).collect()
}

fn bench_point(c: &mut Criterion) {
    let s = patch();
    let ps = params(4096);
    let mut g = c.benchmark_group("point");
    g.throughput(Throughput::Elements(ps.len() as u64));
    g.bench_function("rational_bicubic", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(u, v) in black_box(&ps) {
                let p = s.point(u, v).unwrap();
                acc += p[0] + p[1] + p[2];
            }
            acc
        })
    });
    g.bench_function("rational_bicubic_derivatives1", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(u, v) in black_box(&ps) {
                let d = s.derivatives(u, v, 1).unwrap();
                acc += d.point[2] + d.u[2] + d.v[2];
            }
            acc
        })
    });
    g.finish();
}

fn bench_grid(c: &mut Criterion) {
    let s = patch();
    let us = linspace(0.0, 1.0, 1000);
    let vs = linspace(0.0, 1.0, 1000);
    let mut g = c.benchmark_group("grid");
    g.throughput(Throughput::Elements(1_000_000));
    g.sample_size(10);
    g.bench_function("1000x1000", |b| {
        b.iter(|| s.grid(black_box(&us), black_box(&vs)).unwrap())
    });
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    g.bench_function("1000x1000_one_thread", |b| {
        b.iter(|| one.install(|| s.grid(black_box(&us), black_box(&vs)).unwrap()))
    });
    g.finish();
}

criterion_group!(benches, bench_point, bench_grid);
criterion_main!(benches);
