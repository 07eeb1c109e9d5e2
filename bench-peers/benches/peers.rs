//! nurbspring-geom vs curvo, measured side by side in one run (docs/benchmarks.md, "Geometry").
//!
//! The patch is the one of `crates/geom/benches/evaluate.rs` and `splipy_grid.py`: rational
//! bicubic, 8 × 8 control points, knots `{0,0,0,0, 0.2, 0.4, 0.6, 0.8, 1,1,1,1}` in both
//! directions, `P_ij = (i/7, j/7, ((3i + 5j) mod 7) / 14)`, `w_ij = 1 + ((i + 2j) mod 3) / 4`.
//! Before timing, both libraries are evaluated at the same parameters and must agree.
//!
//! Run: `cargo bench --manifest-path bench-peers/Cargo.toml -- --warm-up-time 1 --measurement-time 3`.

// `criterion_group!` generates an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use curvo::prelude::NurbsSurface3D;
use nalgebra::Point4;
use nurbspring_geom::{KnotVector, NurbsSurface, linspace};

const KNOTS: [f64; 12] = [0., 0., 0., 0., 0.2, 0.4, 0.6, 0.8, 1., 1., 1., 1.];

fn point(i: usize, j: usize) -> ([f64; 3], f64) {
    (
        [
            i as f64 / 7.0,
            j as f64 / 7.0,
            ((3 * i + 5 * j) % 7) as f64 / 14.0,
        ],
        1.0 + ((i + 2 * j) % 3) as f64 / 4.0,
    )
}

fn ours() -> NurbsSurface {
    let k = KnotVector::try_new(KNOTS.to_vec(), 3).unwrap();
    let (mut pts, mut ws) = (Vec::new(), Vec::new());
    for i in 0..8 {
        for j in 0..8 {
            let (p, w) = point(i, j);
            pts.push(p);
            ws.push(w);
        }
    }
    NurbsSurface::try_new(k.clone(), k, pts, ws).unwrap()
}

/// curvo stores homogeneous points `(w x, w y, w z, w)`, `control_points[i][j]` with i along u.
fn theirs() -> NurbsSurface3D<f64> {
    let net: Vec<Vec<Point4<f64>>> = (0..8)
        .map(|i| {
            (0..8)
                .map(|j| {
                    let (p, w) = point(i, j);
                    Point4::new(w * p[0], w * p[1], w * p[2], w)
                })
                .collect()
        })
        .collect();
    NurbsSurface3D::new(3, 3, KNOTS.to_vec(), KNOTS.to_vec(), net)
}

/// The same 64-bit LCG as crates/geom/benches/evaluate.rs.
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

fn agree(a: [f64; 3], b: [f64; 3], tol: f64, what: &str) -> f64 {
    let err = (0..3).fold(0.0f64, |m, x| m.max((a[x] - b[x]).abs()));
    assert!(err <= tol, "{what}: nurbspring {a:?} vs curvo {b:?}");
    err
}

fn bench_point(c: &mut Criterion) {
    let (s, t) = (ours(), theirs());
    let ps = params(4096);
    let mut worst = 0.0f64;
    for &(u, v) in &ps {
        let q = t.point_at(u, v);
        worst = worst.max(agree(
            s.point(u, v).unwrap(),
            [q.x, q.y, q.z],
            1e-14,
            "point",
        ));
    }
    println!(
        "point: nurbspring and curvo agree at {} parameters to {worst:.1e}",
        ps.len()
    );
    let mut g = c.benchmark_group("peers_point");
    g.throughput(Throughput::Elements(ps.len() as u64));
    g.bench_function("nurbspring", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(u, v) in black_box(&ps) {
                let p = s.point(u, v).unwrap();
                acc += p[0] + p[1] + p[2];
            }
            acc
        })
    });
    g.bench_function("curvo", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(u, v) in black_box(&ps) {
                let p = t.point_at(u, v);
                acc += p.x + p.y + p.z;
            }
            acc
        })
    });
    g.finish();
}

fn bench_grid(c: &mut Criterion) {
    let (s, t) = (ours(), theirs());
    let n = 1000;
    let us = linspace(0.0, 1.0, n);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let grid = s.grid(&us, &us).unwrap();
    let sampled = t.regular_sample_points(n - 1, n - 1);
    let mut worst = 0.0f64;
    for i in (0..n).step_by(37) {
        for j in (0..n).step_by(41) {
            let q = sampled[i][j];
            // curvo steps u by accumulation (u += 1/999), so allow that rounding.
            worst = worst.max(agree(grid[i * n + j], [q.x, q.y, q.z], 1e-12, "grid"));
        }
    }
    println!("grid: nurbspring grid() and curvo regular_sample_points agree to {worst:.1e}");
    // The same figures splipy_grid.py prints, to compare the three libraries' grids.
    let checksum: f64 = grid.iter().map(|p| p[0] + p[1] + p[2]).sum();
    println!("grid: nurbspring checksum sum(x + y + z) = {checksum:.15e}");
    for (i, j) in [(0, 0), (123, 456), (500, 500), (999, 1), (999, 999)] {
        println!("  point[{i}][{j}] = {:?}", grid[i * n + j]);
    }
    let mut g = c.benchmark_group("peers_grid_1000x1000");
    g.throughput(Throughput::Elements((n * n) as u64));
    g.sample_size(10);
    g.bench_function("nurbspring_grid_one_thread", |b| {
        b.iter(|| one.install(|| s.grid(black_box(&us), black_box(&us)).unwrap()))
    });
    g.bench_function("nurbspring_grid_rayon", |b| {
        b.iter(|| s.grid(black_box(&us), black_box(&us)).unwrap())
    });
    g.bench_function("curvo_regular_sample_points", |b| {
        b.iter(|| t.regular_sample_points(black_box(n - 1), n - 1))
    });
    g.finish();
}

criterion_group!(benches, bench_point, bench_grid);
criterion_main!(benches);
