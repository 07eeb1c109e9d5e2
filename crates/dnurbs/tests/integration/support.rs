//! Shared scenes, helpers and every tolerance of the test suite (one place, each relative to the
//! real error of the method it checks).

#![allow(dead_code)]

use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material};
use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use nurbspring_linalg::{DenseMatrix, SparseMatrix};

/// Tolerances. Round-off ones are small multiples of ε times the sizes involved; discretization
/// ones follow the method's order.
pub mod tol {
    /// A point of a polynomial patch built from polar forms, |c| ≤ 10: a few dozen products
    /// and sums of O(1) numbers, so a small multiple of ε·|c|.
    pub const EXACT_POINT: f64 = 64.0 * f64::EPSILON * 10.0;
    /// `pᵀ A p` of an assembled matrix against an integral by hand when the Gauss rule is exact:
    /// round-off of O(10⁴) quadrature terms, relative (≈ 10⁴ ε, rounded up to 10⁻¹¹).
    pub const EXACT_INTEGRAL: f64 = 1e-11;
    /// Central differences `(c(p + h e) − c(p − h e)) / 2h` with h = 10⁻⁵ of a smooth rational
    /// point (|c| ~ 5): truncation ~ h² |c'''| / 6 ≈ 10⁻¹⁰ plus round-off ε |c| / h ≈ 10⁻¹⁰.
    pub const CENTRAL_DIFFERENCE: f64 = 1e-8;
    /// Central differences (h = 10⁻⁴) of a quadratic energy computed by quadrature: no
    /// truncation, round-off ~ 10 ε E / h ≈ 10⁻¹⁰ of the largest force for E ~ 10 |f|.
    pub const ENERGY_DIFFERENCE: f64 = 1e-9;
    /// `‖A − Aᵀ‖_F / ‖A‖_F` of an assembled matrix: every entry is summed in the same order for
    /// (i, j) and (j, i), so symmetry is exact up to the mirrored element blocks.
    pub const SYMMETRY: f64 = 1e-15;
    /// Relative error of a sum of O(10³) positive quadrature terms (e.g. Σ M = 3 μ A).
    pub const SUM: f64 = 1e-13;
    /// `‖K t‖ / ‖K‖_F` for a rigid translation t (partition of unity, round-off only).
    pub const TRANSLATION: f64 = 1e-13;
    /// Smallest eigenvalue of K over its largest: PSD up to round-off.
    pub const PSD: f64 = 1e-12;
    /// `‖Cᵀ A_fine C − A_coarse‖_F / ‖A_coarse‖_F` (exact Gauss quadrature, round-off only).
    pub const REFINEMENT: f64 = 1e-12;
    /// Agreement of two computations that are algebraically identical (different code paths).
    pub const SAME: f64 = 1e-12;
    /// Two implementations of one time-stepping scheme in absolute coordinates (|p| ~ 5) whose
    /// right-hand sides cancel down to displacements ~ 10⁻³ per step: the round-off,
    /// amplified by cond(M) of a cubic B-spline mass matrix, accumulates over the run
    /// (~1e-11 · |p| observed after 60 steps).
    pub const SCHEME_ROUNDOFF: f64 = 1e-10;
    /// Pointwise error of the string's steady state against the parabola, which lies in the
    /// spline space for p ≥ 2 (Galerkin reproduces it up to the solve's round-off).
    pub const STEADY_STATE: f64 = 1e-11;
    /// Observed convergence rates must lie within this distance of the theoretical 2p (h-refinement
    /// of eigenvalues) or 1 (Terzopoulos–Qin in Δt), measured on the pre-asymptotic grids used.
    pub const RATE_SLACK: f64 = 0.2;
    /// Relative error of the lowest string frequencies with 700 quadratic elements: the
    /// discretization error is ~3e-13 and Lanczos converges θ to 1e-12.
    pub const SPARSE_EIGEN: f64 = 1e-9;
    /// Relative max deviation of Newmark from the exact modal solution on the paper's scene at
    /// Δt = 0.002 over 4 s (second order; 4.3e-7 observed).
    pub const AGREE_NEWMARK: f64 = 2e-6;
    /// The same for Terzopoulos–Qin (first order, dissipative; 1.4e-3 observed).
    pub const AGREE_TQ: f64 = 5e-3;
    /// Relative error of the clamped membrane's centre sag with 16 × 16 quadratic elements
    /// (8.8e-6 observed).
    pub const MEMBRANE_SAG: f64 = 5e-5;
    /// Central differences of a quadratic energy with h = 1e-4: exact up to the round-off
    /// ε·E/h of the energy differences, relative to the largest force component.
    pub const FINITE_DIFFERENCE: f64 = 1e-7;
    /// Relative energy drift of Newmark average acceleration with D = 0 over the whole run
    /// (conserved exactly in exact arithmetic; the solves leave ~1e-15 per step).
    pub const ENERGY: f64 = 1e-11;
}

/// Relative Frobenius distance `‖a − b‖ / ‖b‖`.
pub fn rel_diff(a: &SparseMatrix, b: &SparseMatrix) -> f64 {
    let d = SparseMatrix::linear_combination(1.0, a, -1.0, b).unwrap();
    d.frobenius_norm() / b.frobenius_norm()
}

/// `‖x − y‖₂ / ‖y‖₂`.
pub fn rel_vec(x: &[f64], y: &[f64]) -> f64 {
    let d: f64 = x
        .iter()
        .zip(y)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt();
    d / y.iter().map(|b| b * b).sum::<f64>().sqrt()
}

/// `max |x − y|`.
pub fn max_abs_diff(x: &[f64], y: &[f64]) -> f64 {
    x.iter()
        .zip(y)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// The paper's control net (docs/math.md §7), as printed.
pub fn paper_surface() -> NurbsSurface {
    let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap();
    let px = [0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.];
    let py = [0., 0.83, 2.5, 4.16, 5.];
    let pts = px
        .iter()
        .flat_map(|&x| py.iter().map(move |&y| [x, y, 2.0]))
        .collect();
    NurbsSurface::try_new(ku, kv, pts, vec![1.0; 35]).unwrap()
}

/// The "Greville" reading of the paper's net: the flat sheet `c(u, v) = (3u, 5v, 2)`.
pub fn paper_surface_greville() -> NurbsSurface {
    let s = paper_surface();
    let gu = s.basis_u().knots().greville();
    let gv = s.basis_v().knots().greville();
    let pts = gu
        .iter()
        .flat_map(|&u| gv.iter().map(move |&v| [3.0 * u, 5.0 * v, 2.0]))
        .collect();
    s.with_control_points(pts).unwrap()
}

/// The paper's material: μ = 25, β11 = β22 = 0.01.
pub fn paper_material() -> Material {
    Material {
        mu: 25.0,
        beta11: 0.01,
        beta22: 0.01,
        ..Material::default()
    }
}

/// Two outer rings fixed (32 of 35 points).
pub fn paper_constraints() -> Constraints {
    Constraints {
        fixed_rings: 2,
        ..Constraints::default()
    }
}

/// The paper's model with the given options.
pub fn paper_model(options: DnurbsOptions) -> DnurbsModel {
    DnurbsModel::new(
        Geometry::Surface(paper_surface()),
        paper_material(),
        Loads::default(),
        &paper_constraints(),
        options,
    )
    .unwrap()
}

/// A degree-`p` B-spline curve with `elements` uniform spans along the x axis from 0 to
/// `length`, control points at the Greville abscissae (so x(u) = length · u exactly).
pub fn straight_curve(p: usize, elements: usize, length: f64) -> NurbsCurve {
    let k = KnotVector::clamped_uniform(p, elements).unwrap();
    let pts = k
        .greville()
        .iter()
        .map(|&g| [length * g, 0.0, 0.0])
        .collect();
    let n = k.n_basis();
    NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap()
}

/// A degree-`p` flat B-spline patch with `n_u × n_v` uniform elements covering
/// `[0, a] × [0, b]` at z = 0 (control points at the Greville abscissae: an affine map).
pub fn flat_patch(p: usize, n_u: usize, n_v: usize, a: f64, b: f64) -> NurbsSurface {
    let ku = KnotVector::clamped_uniform(p, n_u).unwrap();
    let kv = KnotVector::clamped_uniform(p, n_v).unwrap();
    let gu = ku.greville();
    let gv = kv.greville();
    let pts: Vec<[f64; 3]> = gu
        .iter()
        .flat_map(|&u| gv.iter().map(move |&v| [a * u, b * v, 0.0]))
        .collect();
    let n = pts.len();
    NurbsSurface::try_new(ku, kv, pts, vec![1.0; n]).unwrap()
}

/// A curved, non-uniform bicubic B-spline patch (unit weights) for invariance tests.
pub fn wavy_patch() -> NurbsSurface {
    let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.3, 0.7, 1., 1., 1., 1.], 3).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.4, 1., 1., 1., 1.], 3).unwrap();
    let (nu, nv) = (ku.n_basis(), kv.n_basis());
    let pts = (0..nu)
        .flat_map(|i| {
            (0..nv).map(move |j| {
                let (x, y) = (i as f64, j as f64 * 0.8);
                [
                    x + 0.1 * y,
                    y,
                    (0.7 * x).sin() * (0.5 * y).cos() + 0.05 * (i * j) as f64,
                ]
            })
        })
        .collect();
    NurbsSurface::try_new(ku, kv, pts, vec![1.0; nu * nv]).unwrap()
}

/// The same net with non-uniform weights (a genuinely rational surface).
pub fn wavy_rational_patch() -> NurbsSurface {
    let s = wavy_patch();
    let w: Vec<f64> = (0..s.n_control_points())
        .map(|k| 1.0 + 0.3 * ((k * 7) % 5) as f64 / 4.0)
        .collect();
    s.with_control_points_and_weights(s.control_points().to_vec(), w)
        .unwrap()
}

/// Rows/columns `keep` of a sparse matrix as a dense matrix.
pub fn dense_sub(a: &SparseMatrix, keep: &[usize]) -> DenseMatrix {
    a.submatrix(keep, keep).to_dense()
}

/// Convergence rate `log2(e_coarse / e_fine)` for a halving of h or Δt.
pub fn rate(e_coarse: f64, e_fine: f64) -> f64 {
    (e_coarse / e_fine).log2()
}
