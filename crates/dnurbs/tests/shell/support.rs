//! Shared shell scenes, helpers and the tolerances of the shell tests, each relative to the
//! error of the method it checks.

#![allow(dead_code)]

use nurbspring_dnurbs::{Geometry, ShellMaterial};
use nurbspring_geom::{KnotVector, NurbsSurface};

pub mod tol {
    /// Central differences with step h of a smooth energy: truncation ~ h² |E'''| and round-off
    /// ~ ε |E| / h, relative to the largest force (measured: see the tests).
    pub const FORCE_DIFFERENCE: f64 = 5e-9;
    /// Central differences of the force, relative to the largest tangent entry.
    pub const TANGENT_DIFFERENCE: f64 = 1e-9;
    /// Rotation invariance: the same sums in another frame, relative to |E| or max |f|.
    pub const ROTATION: f64 = 1e-12;
    /// Symmetry of the assembled tangent: mirrored element blocks summed in the same order.
    pub const SYMMETRY: f64 = 1e-14;
}

/// A small deterministic generator (splitmix64) for reproducible random states.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [−1, 1).
    pub fn symmetric(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// A doubly curved, rational, non-uniform patch: degrees (2, 3), uneven knots, weights in
/// [0.7, 1.3], over roughly [0, 2] × [0, 1.5] with a bump of height ~0.4.
pub fn curved_patch() -> Geometry {
    let ku = KnotVector::try_new(vec![0., 0., 0., 0.3, 0.55, 1., 1., 1.], 2).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.4, 1., 1., 1., 1.], 3).unwrap();
    let (gu, gv) = (ku.greville(), kv.greville());
    let mut pts = Vec::new();
    let mut weights = Vec::new();
    for (i, &u) in gu.iter().enumerate() {
        for (j, &v) in gv.iter().enumerate() {
            pts.push([
                2.0 * u + 0.1 * v * v,
                1.5 * v + 0.05 * u,
                0.4 * (std::f64::consts::PI * u).sin() * (1.0 + v)
                    + 0.03 * ((i + 2 * j) % 3) as f64,
            ]);
            weights.push(1.0 + 0.3 * (((3 * i + 5 * j) % 7) as f64 / 3.0 - 1.0));
        }
    }
    Geometry::Surface(NurbsSurface::try_new(ku, kv, pts, weights).unwrap())
}

/// A steel-like material with a thickness that makes bending and membrane terms comparable
/// on a patch of size ~1 (t = 0.05, so t²/12 ~ 2e-4 against strains ~ curvature² · ...).
pub fn material() -> ShellMaterial {
    ShellMaterial {
        young: 1000.0,
        poisson: 0.3,
        thickness: 0.05,
        density: 2.0,
        gamma: 0.0,
    }
}

/// `p0 + scale · random`, per coordinate.
pub fn perturbed(p0: &[f64], scale: f64, seed: u64) -> Vec<f64> {
    let mut rng = Rng(seed);
    p0.iter().map(|x| x + scale * rng.symmetric()).collect()
}

/// The rotation by `angle` about the unit axis of `axis` (Rodrigues).
pub fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|c| c / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

/// Applies `r` to every point of `p` (3 per point) and adds `shift`.
pub fn rotate(r: &[[f64; 3]; 3], p: &[f64], shift: [f64; 3]) -> Vec<f64> {
    p.chunks_exact(3)
        .flat_map(|x| {
            (0..3).map(move |i| r[i][0] * x[0] + r[i][1] * x[1] + r[i][2] * x[2] + shift[i])
        })
        .collect()
}

pub fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

// ---- Geometries of the benchmarks ----

pub use nurbspring_dnurbs::obstacle::{rectangle, refined as refine_exact};
use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, LinearConstraint, Loads};

/// [`refine_exact`] of a patch that refines (the benchmark patches do).
pub fn refined(coarse: &NurbsSurface, degree: usize, spans: (usize, usize)) -> NurbsSurface {
    refine_exact(coarse, degree, spans).unwrap()
}

/// `p0` values of the generalized coordinates of `s` (3 per point).
pub fn coordinates(s: &NurbsSurface) -> Vec<f64> {
    s.control_points()
        .iter()
        .flat_map(|x| x.iter().copied())
        .collect()
}

/// Holds dof `component` of control point `k` at its value in `p0`.
pub fn hold(k: usize, component: usize, p0: &[f64]) -> LinearConstraint {
    LinearConstraint {
        terms: vec![(3 * k + component, 1.0)],
        rhs: p0[3 * k + component],
    }
}

/// Keeps the displacement `component` of points `a` and `b` equal.
pub fn tie(a: usize, b: usize, component: usize, p0: &[f64]) -> LinearConstraint {
    LinearConstraint {
        terms: vec![(3 * a + component, 1.0), (3 * b + component, -1.0)],
        rhs: p0[3 * a + component] - p0[3 * b + component],
    }
}

/// A symmetry plane through the edge row `first` (its points), normal to axis `normal`, with
/// `second` the next row inwards (docs/math.md §10.7): the first row stays on the plane and the
/// in-plane displacements of the second row follow the first's, so the cross tangent stays
/// normal to the plane.
pub fn symmetry(
    first: &[usize],
    second: &[usize],
    normal: usize,
    p0: &[f64],
) -> Vec<LinearConstraint> {
    let mut out = Vec::new();
    for (&a, &b) in first.iter().zip(second) {
        out.push(hold(a, normal, p0));
        for c in (0..3).filter(|&c| c != normal) {
            out.push(tie(b, a, c, p0));
        }
    }
    out
}

/// Flat indices of row `i` (fixed u index) of an `n_u × n_v` net.
pub fn row_u(s: &NurbsSurface, i: usize) -> Vec<usize> {
    (0..s.n_v()).map(|j| i * s.n_v() + j).collect()
}

/// Flat indices of column `j` (fixed v index).
pub fn row_v(s: &NurbsSurface, j: usize) -> Vec<usize> {
    (0..s.n_u()).map(|i| i * s.n_v() + j).collect()
}

/// A shell model of `s` with the linear constraints and loads given.
pub fn shell_model(
    s: NurbsSurface,
    material: ShellMaterial,
    loads: Loads,
    linear: Vec<LinearConstraint>,
    fixed_points: Vec<usize>,
) -> DnurbsModel {
    let constraints = Constraints {
        fixed_points,
        linear,
        ..Constraints::default()
    };
    DnurbsModel::kirchhoff_love(
        Geometry::Surface(s),
        material,
        loads,
        &constraints,
        DnurbsOptions::default(),
    )
    .unwrap()
}

/// The displacement of the surface point `(u, v)` in the state `p`.
pub fn displacement(model: &DnurbsModel, u: f64, v: f64, p: &[f64]) -> [f64; 3] {
    let a = model.point(u, v, p).unwrap();
    let b = model.point(u, v, model.p0()).unwrap();
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
