//! Shared helpers of the integration tests.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use nurbspring_exchange::Shape;
use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};

/// `tests/data/…`.
pub fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(rel)
}

/// A committed text fixture.
pub fn text(rel: &str) -> String {
    std::fs::read_to_string(data(rel)).unwrap_or_else(|e| panic!("{}: {e}", data(rel).display()))
}

/// A committed JSON fixture.
pub fn json(rel: &str) -> serde_json::Value {
    serde_json::from_str(&text(rel)).unwrap()
}

/// With `NURBSPRING_BLESS=1` writes `contents` to the fixture `rel`; otherwise checks that the
/// committed fixture is exactly `contents` (so checks made on it by the fixture scripts apply
/// to what the writers produce now).
pub fn blessed(rel: &str, contents: &str) {
    let path = data(rel);
    if std::env::var_os("NURBSPRING_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, contents).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; run NURBSPRING_BLESS=1 cargo test -p nurbspring-exchange",
            path.display()
        )
    });
    assert!(
        committed == contents,
        "{} differs from what the writer produces now; bless it (NURBSPRING_BLESS=1) and rerun \
         the fixture script that checks it",
        path.display()
    );
}

pub fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap()
}

pub fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(f).collect()
}

/// |a − b|∞ over three coordinates.
pub fn dist(a: [f64; 3], b: &[f64]) -> f64 {
    (0..3)
        .map(|i| (a[i] - b.get(i).copied().unwrap_or(0.0)).abs())
        .fold(0.0, f64::max)
}

fn kv(k: &[f64], p: usize) -> KnotVector {
    KnotVector::try_new(k.to_vec(), p).unwrap()
}

const S: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// A rational quadratic 270° arc on knots 0..3 in the plane z = 1 + x/2.
pub fn arc270() -> NurbsCurve {
    let square = [
        (1., 0.),
        (1., 1.),
        (0., 1.),
        (-1., 1.),
        (-1., 0.),
        (-1., -1.),
        (0., -1.),
    ];
    let pts = square
        .iter()
        .map(|&(x, y)| {
            let (x, y) = (1.5 * x + 0.25, 1.5 * y - 0.5);
            [x, y, 1.0 + 0.5 * x]
        })
        .collect();
    NurbsCurve::try_new(
        kv(&[0., 0., 0., 1., 1., 2., 2., 3., 3., 3.], 2),
        pts,
        vec![1., S, 1., S, 1., S, 1.],
    )
    .unwrap()
}

/// A rational cubic with non-uniform knots on [−1, 2] and a double knot.
pub fn cubic() -> NurbsCurve {
    NurbsCurve::try_new(
        kv(&[-1., -1., -1., -1., -0.25, 0.5, 0.5, 2., 2., 2., 2.], 3),
        vec![
            [0., 0., 0.],
            [1., 2., 0.5],
            [2.5, 2.2, -0.3],
            [3.1, 0.4, 1.2],
            [4.0, -1.0, 0.7],
            [5.2, 0.3, 0.0],
            [6.0, 1.5, -0.4],
        ],
        vec![1.0, 0.8, 1.7, 0.6, 1.3, 0.9, 1.0],
    )
    .unwrap()
}

/// A rational quarter cylinder (radius 2, height 4) on [0, 2] × [−1, 3].
pub fn quarter_cylinder() -> NurbsSurface {
    let arc = [(2., 0., 1.0), (2., 2., S), (0., 2., 1.0)];
    let mut pts = Vec::new();
    let mut w = Vec::new();
    for &(x, y, wi) in &arc {
        for z in [0.0, 4.0] {
            pts.push([x, y, z]);
            w.push(wi);
        }
    }
    NurbsSurface::try_new(
        kv(&[0., 0., 0., 2., 2., 2.], 2),
        kv(&[-1., -1., 3., 3.], 1),
        pts,
        w,
    )
    .unwrap()
}

/// A rational degree 3 × 2 surface, 6 × 5 control points, non-uniform knots with a double knot.
pub fn wavy() -> NurbsSurface {
    let (nu, nv) = (6, 5);
    let mut pts = Vec::new();
    let mut w = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (fi, fj) = (i as f64, j as f64);
            pts.push([
                fi * 0.8,
                fj * 1.1 + 0.2 * fi.sin(),
                0.3 * (1.3 * fi + 0.7 * fj).cos() + 0.1 * fi * fj,
            ]);
            w.push(0.7 + 0.15 * ((3 * i + 5 * j) % 7) as f64);
        }
    }
    NurbsSurface::try_new(
        kv(&[0., 0., 0., 0., 0.45, 0.45, 1.5, 1.5, 1.5, 1.5], 3),
        kv(&[0., 0., 0., 1., 2.5, 4., 4., 4.], 2),
        pts,
        w,
    )
    .unwrap()
}

pub fn sample_curves() -> Vec<Shape> {
    vec![Shape::Curve(arc270()), Shape::Curve(cubic())]
}

pub fn sample_surfaces() -> Vec<Shape> {
    vec![Shape::Surface(quarter_cylinder()), Shape::Surface(wavy())]
}

/// Bitwise equality of two shapes (knots, weights, points), `-0.0 ≠ 0.0`.
pub fn same_bits(a: &Shape, b: &Shape) -> bool {
    fn bits(v: impl IntoIterator<Item = f64>) -> Vec<u64> {
        v.into_iter().map(f64::to_bits).collect()
    }
    match (a, b) {
        (Shape::Curve(a), Shape::Curve(b)) => {
            a.basis().degree() == b.basis().degree()
                && bits(a.basis().knots().knots().iter().copied())
                    == bits(b.basis().knots().knots().iter().copied())
                && bits(a.weights().iter().copied()) == bits(b.weights().iter().copied())
                && bits(a.control_points().iter().flatten().copied())
                    == bits(b.control_points().iter().flatten().copied())
        }
        (Shape::Surface(a), Shape::Surface(b)) => {
            a.basis_u().degree() == b.basis_u().degree()
                && a.basis_v().degree() == b.basis_v().degree()
                && bits(a.basis_u().knots().knots().iter().copied())
                    == bits(b.basis_u().knots().knots().iter().copied())
                && bits(a.basis_v().knots().knots().iter().copied())
                    == bits(b.basis_v().knots().knots().iter().copied())
                && bits(a.weights().iter().copied()) == bits(b.weights().iter().copied())
                && bits(a.control_points().iter().flatten().copied())
                    == bits(b.control_points().iter().flatten().copied())
        }
        _ => false,
    }
}
