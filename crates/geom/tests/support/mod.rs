//! Shared test support for nurbspring-geom: every tolerance used by the integration tests,
//! the closed-form geometries (also used by the reference script in `tests/data/`), exact
//! conics, proptest strategies and finite-difference stencils.
//!
//! Tolerances are relative (to `max(1, ‖expected‖∞)` unless a test says otherwise) and sized
//! to the real error of what they check, not to whatever makes a test pass.
#![allow(dead_code)]

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use proptest::prelude::*;

// ---- tolerances -----------------------------------------------------------------------------

/// Identities evaluated in floating point along two paths of O(p²) operations each
/// (refinement and degree elevation leave points unchanged, `J p = c`, `grid` = `point`):
/// a few hundred ulps.
pub const ROUNDOFF: f64 = 1e-13;
/// Agreement with values printed by geomdl / splipy (`tests/data/reference_values.rs`): the
/// algorithms differ (A2.2 vs de Boor–Cox, A4.4 vs splipy's quotient rule) and derivatives
/// carry factors up to ~1/span², so a few hundred ulps of the largest value.
pub const REFERENCE: f64 = 1e-12;
/// Points of exact conics (rational quadratics): distance to the unit circle or sphere. The
/// evaluation is a convex combination followed by one division, so a few ulps.
pub const CONIC_RADIUS: f64 = 1e-15;
/// Gauss–Legendre sums of monomials up to degree 2g − 1 against their exact integrals, relative
/// to `∫|f|`.
pub const QUADRATURE: f64 = 1e-13;
/// Entries of refinement / elevation matrices that should be exactly zero, or row sums that
/// should be exactly one, after O(p) lerps.
pub const MATRIX_ENTRY: f64 = 1e-14;
/// Entries and row sums of degree-elevation matrices (A5.9). Its knot-removal steps combine
/// points with coefficients `α > 1` (and `1 − α < 0`), which amplifies rounding with the ratio
/// of neighbouring span lengths (≤ 19 in the strategies below). Measured: A5.9 in f64 against
/// the same algorithm in exact rational arithmetic, degree 5 → 7 on spans of ratio 15,
/// 9.4e-14; `E₁E₁` vs `E₂` up to 1.3e-13.
pub const ELEVATION: f64 = 3e-13;
/// Sixth-order central differences (step [`FD_STEP`] of the knot span) of a non-rational
/// quantity inside one knot span: the stencils are exact for polynomials of degree ≤ 6, so only
/// rounding remains, `~6ε‖f‖/h²` for second derivatives, i.e. ~1e-10 of the natural scale
/// `‖f‖/span²` (see [`check_scaled`]).
pub const FD_POLYNOMIAL: f64 = 1e-9;
/// Sixth-order central differences of rational quantities (weights in [1/2, 2]). A rational
/// function has complex poles at a distance ρ that can be a fraction of the span, so the
/// truncation is `~(h/ρ)⁶ · 7!/140`, about 1e-10 with h = 3e-3 span; plus the rounding above.
/// (Fourth-order stencils with h = 1e-2 span gave errors up to 4e-6 here: truncation.)
pub const FD_RATIONAL: f64 = 1e-8;
/// Step of the difference stencils, as a fraction of the knot span.
pub const FD_STEP: f64 = 3e-3;

// ---- comparisons ----------------------------------------------------------------------------

/// `‖a − b‖∞ ≤ tol · max(1, ‖b‖∞)`, with a message naming `what`.
pub fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths differ");
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let err = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        err <= tol * scale,
        "{what}: error {err:.3e} > {tol:.1e} × {scale:.3e}\n  got      {a:?}\n  expected {b:?}"
    );
}

/// [`assert_close`] for 3-vectors.
pub fn assert_close3(a: [f64; 3], b: [f64; 3], tol: f64, what: &str) {
    assert_close(&a, &b, tol, what);
}

/// `Err` instead of a panic, for proptest bodies (shrinking needs `prop_assert`-style errors).
pub fn check_close(a: &[f64], b: &[f64], tol: f64, what: &str) -> Result<(), TestCaseError> {
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let err = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    if a.len() == b.len() && err <= tol * scale {
        Ok(())
    } else {
        Err(TestCaseError::fail(format!(
            "{what}: error {err:.3e} > {tol:.1e} × {scale:.3e}\n  got      {a:?}\n  expected {b:?}"
        )))
    }
}

// ---- finite differences ---------------------------------------------------------------------

/// Sixth-order central first difference
/// `(−f₋₃ + 9f₋₂ − 45f₋₁ + 45f₁ − 9f₂ + f₃) / 60h`, componentwise. Exact for degree ≤ 6.
pub fn diff1(f: impl Fn(f64) -> Vec<f64>, x: f64, h: f64) -> Vec<f64> {
    const C: [f64; 6] = [-1.0, 9.0, -45.0, 45.0, -9.0, 1.0];
    const OFFSETS: [f64; 6] = [-3.0, -2.0, -1.0, 1.0, 2.0, 3.0];
    stencil(&f, x, h, &OFFSETS, &C, 60.0 * h)
}

/// Sixth-order central second difference
/// `(2f₋₃ − 27f₋₂ + 270f₋₁ − 490f₀ + 270f₁ − 27f₂ + 2f₃) / 180h²`. Exact for degree ≤ 7.
pub fn diff2(f: impl Fn(f64) -> Vec<f64>, x: f64, h: f64) -> Vec<f64> {
    const C: [f64; 7] = [2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0];
    const OFFSETS: [f64; 7] = [-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0];
    stencil(&f, x, h, &OFFSETS, &C, 180.0 * h * h)
}

fn stencil(
    f: &impl Fn(f64) -> Vec<f64>,
    x: f64,
    h: f64,
    offsets: &[f64],
    c: &[f64],
    den: f64,
) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for (o, w) in offsets.iter().zip(c) {
        let v = f(x + o * h);
        if out.is_empty() {
            out = vec![0.0; v.len()];
        }
        for (acc, y) in out.iter_mut().zip(&v) {
            *acc += w * y;
        }
    }
    out.iter().map(|a| a / den).collect()
}

/// Mixed difference `∂²f/∂u∂v` as `diff1` in u of `diff1` in v.
pub fn diff_mixed(f: impl Fn(f64, f64) -> Vec<f64>, u: f64, v: f64, hu: f64, hv: f64) -> Vec<f64> {
    diff1(|uu| diff1(|vv| f(uu, vv), v, hv), u, hu)
}

/// A check against a natural scale (finite differences, and identities whose rounding comes
/// from cancelling derivative terms): `‖fd − exact‖∞ ≤ tol · max(‖exact‖∞, natural)`, where
/// `natural = max(1, ‖f‖∞) / (span_u^a span_v^b)` is the scale of an (a, b)-th derivative of a
/// function of size ‖f‖ on those spans — the scale of both the truncation and the rounding
/// error of the stencil.
pub fn check_scaled(
    fd: &[f64],
    exact: &[f64],
    natural: f64,
    tol: f64,
    what: &str,
) -> Result<(), TestCaseError> {
    let scale = exact.iter().fold(natural, |m, x| m.max(x.abs()));
    let err = fd
        .iter()
        .zip(exact)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    if fd.len() == exact.len() && err <= tol * scale {
        Ok(())
    } else {
        Err(TestCaseError::fail(format!(
            "{what}: error {err:.3e} > {tol:.1e} × {scale:.3e}\n  fd    {fd:?}\n  exact {exact:?}"
        )))
    }
}

// ---- closed-form geometry (repeated in tests/data/reference_values.py) ----------------------

/// `KU` of the reference script: cubic, 7 functions, a double knot at 0.5.
pub const REF_KU: [f64; 11] = [0.0, 0.0, 0.0, 0.0, 0.3, 0.5, 0.5, 1.0, 1.0, 1.0, 1.0];
/// `KV`: quadratic, 4 functions.
pub const REF_KV: [f64; 7] = [0.0, 0.0, 0.0, 0.4, 1.0, 1.0, 1.0];
/// `KC`: cubic curve, 7 functions, a double knot at 0.6.
pub const REF_KC: [f64; 11] = [0.0, 0.0, 0.0, 0.0, 0.25, 0.6, 0.6, 1.0, 1.0, 1.0, 1.0];

/// `surf_point(i, j)` of the script.
pub fn ref_surface_point(i: usize, j: usize) -> [f64; 3] {
    let (fi, fj) = (i as f64, j as f64);
    [
        fi + 0.125 * fj,
        fj - 0.25 * fi,
        ((3 * i + 5 * j) % 7) as f64 * 0.25 - 0.75,
    ]
}

/// `surf_weight(i, j)` of the script.
pub fn ref_surface_weight(i: usize, j: usize) -> f64 {
    1.0 + ((2 * i + j) % 4) as f64 * 0.25
}

/// The reference surface (cubic × quadratic, 7 × 4 control points), rational or with all
/// weights 1.
pub fn reference_surface(rational: bool) -> NurbsSurface {
    let ku = KnotVector::try_new(REF_KU.to_vec(), 3).unwrap();
    let kv = KnotVector::try_new(REF_KV.to_vec(), 2).unwrap();
    let (nu, nv) = (ku.n_basis(), kv.n_basis());
    let mut pts = Vec::new();
    let mut ws = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            pts.push(ref_surface_point(i, j));
            ws.push(if rational {
                ref_surface_weight(i, j)
            } else {
                1.0
            });
        }
    }
    NurbsSurface::try_new(ku, kv, pts, ws).unwrap()
}

/// The reference rational cubic curve (7 control points).
pub fn reference_curve() -> NurbsCurve {
    let k = KnotVector::try_new(REF_KC.to_vec(), 3).unwrap();
    let pts = (0..7)
        .map(|i| [i as f64, (i % 3) as f64 * 0.5, ((i * i) % 5) as f64 * 0.25])
        .collect();
    let ws = (0..7).map(|i| 1.0 + (i % 3) as f64 * 0.5).collect();
    NurbsCurve::try_new(k, pts, ws).unwrap()
}

// ---- exact conics ---------------------------------------------------------------------------

/// `√2 / 2`, the middle weight of a 90° rational quadratic arc.
pub const W45: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The unit circle as a rational quadratic with 9 control points on the square
/// (The NURBS Book §7.5, Fig. 7.16): knots `{0,0,0,¼,¼,½,½,¾,¾,1,1,1}`.
pub fn full_circle() -> NurbsCurve {
    let k = KnotVector::try_new(
        vec![0., 0., 0., 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1., 1., 1.],
        2,
    )
    .unwrap();
    let pts = vec![
        [1., 0., 0.],
        [1., 1., 0.],
        [0., 1., 0.],
        [-1., 1., 0.],
        [-1., 0., 0.],
        [-1., -1., 0.],
        [0., -1., 0.],
        [1., -1., 0.],
        [1., 0., 0.],
    ];
    let ws = vec![1., W45, 1., W45, 1., W45, 1., W45, 1.];
    NurbsCurve::try_new(k, pts, ws).unwrap()
}

/// An octant of the unit sphere: the meridian quarter arc from the equator to the north pole
/// revolved by 90° about z (tensor product of two rational quadratic arcs, weights
/// `w_i w_j`; the last row collapses to the pole).
pub fn sphere_octant() -> NurbsSurface {
    let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
    // Meridian in the (r, z) plane with its weights.
    let meridian = [(1.0, 0.0, 1.0), (1.0, 1.0, W45), (0.0, 1.0, 1.0)];
    // Unit quarter circle in the xy plane.
    let arc = [(1.0, 0.0, 1.0), (1.0, 1.0, W45), (0.0, 1.0, 1.0)];
    let mut pts = Vec::new();
    let mut ws = Vec::new();
    for &(r, z, wm) in &meridian {
        for &(x, y, wa) in &arc {
            pts.push([r * x, r * y, z]);
            ws.push(wm * wa);
        }
    }
    NurbsSurface::try_new(k.clone(), k, pts, ws).unwrap()
}

/// A unit cylinder of height 2: the full circle along u (9 control points) times a straight
/// line along v, `c(u, v) = (cos θ(u), sin θ(u), 2v)`.
pub fn cylinder() -> NurbsSurface {
    let circle = full_circle();
    let kv = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let mut pts = Vec::new();
    let mut ws = Vec::new();
    for (p, &w) in circle.control_points().iter().zip(circle.weights()) {
        for z in [0.0, 2.0] {
            pts.push([p[0], p[1], z]);
            ws.push(w);
        }
    }
    NurbsSurface::try_new(circle.basis().knots().clone(), kv, pts, ws).unwrap()
}

/// Euclidean norm.
pub fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

// ---- proptest strategies --------------------------------------------------------------------

/// Proptest configuration: 256 cases per property (about a second for the whole suite), or
/// `PROPTEST_CASES` from the environment for longer runs.
pub fn config() -> ProptestConfig {
    let default = ProptestConfig::default();
    ProptestConfig {
        cases: if std::env::var_os("PROPTEST_CASES").is_some() {
            default.cases
        } else {
            256
        },
        ..default
    }
}

/// A clamped knot vector of degree 1..=`max_degree` on `[a, a + len]` with up to
/// `max_interior` interior knots drawn from a grid of 20 (so spans are ≥ len/20), interior
/// multiplicities capped at p (continuous curves).
pub fn arb_knots(max_degree: usize, max_interior: usize) -> impl Strategy<Value = KnotVector> {
    (
        1..=max_degree,
        prop::collection::vec(1u32..20, 0..=max_interior),
        prop_oneof![Just((0.0, 1.0)), (-2.0..2.0f64, 0.5..4.0f64)],
    )
        .prop_map(|(p, mut ks, (a, len))| {
            ks.sort_unstable();
            let mut interior: Vec<u32> = Vec::new();
            for k in ks {
                if interior.iter().filter(|&&x| x == k).count() < p {
                    interior.push(k);
                }
            }
            let map = |t: f64| if t == 1.0 { a + len } else { a + len * t };
            let mut knots = vec![map(0.0); p + 1];
            knots.extend(interior.iter().map(|&k| map(f64::from(k) / 20.0)));
            knots.extend(std::iter::repeat_n(map(1.0), p + 1));
            KnotVector::try_new(knots, p).unwrap()
        })
}

/// A control point in `[-2, 2]³`.
pub fn arb_point() -> impl Strategy<Value = [f64; 3]> {
    [-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64]
}

/// Weights: 1 when not rational, else log-uniform in `[1/range, range]`.
pub fn arb_weight(rational: bool, range: f64) -> BoxedStrategy<f64> {
    if rational {
        (-range.ln()..range.ln()).prop_map(f64::exp).boxed()
    } else {
        Just(1.0).boxed()
    }
}

/// A random NURBS curve.
pub fn arb_curve(
    max_degree: usize,
    rational: bool,
    weight_range: f64,
) -> impl Strategy<Value = NurbsCurve> {
    arb_knots(max_degree, 6)
        .prop_flat_map(move |k| {
            let n = k.n_basis();
            (
                Just(k),
                prop::collection::vec(arb_point(), n),
                prop::collection::vec(arb_weight(rational, weight_range), n),
            )
        })
        .prop_map(|(k, p, w)| NurbsCurve::try_new(k, p, w).unwrap())
}

/// A random NURBS surface.
pub fn arb_surface(
    max_degree: usize,
    rational: bool,
    weight_range: f64,
) -> impl Strategy<Value = NurbsSurface> {
    (arb_knots(max_degree, 4), arb_knots(max_degree, 4))
        .prop_flat_map(move |(ku, kv)| {
            let n = ku.n_basis() * kv.n_basis();
            (
                Just(ku),
                Just(kv),
                prop::collection::vec(arb_point(), n),
                prop::collection::vec(arb_weight(rational, weight_range), n),
            )
        })
        .prop_map(|(ku, kv, p, w)| NurbsSurface::try_new(ku, kv, p, w).unwrap())
}

/// A parameter strictly inside a non-empty span chosen by `pick`, at relative position
/// `t ∈ [0.2, 0.8]`; returns `(u, span length)`. Stencils of half-width ≤ 0.1 span stay inside.
pub fn param_in_span(k: &KnotVector, pick: prop::sample::Index, t: f64) -> (f64, f64) {
    let spans = k.nonempty_spans();
    let (_, a, b) = spans[pick.index(spans.len())];
    let t = 0.2 + 0.6 * t;
    (a + t * (b - a), b - a)
}

/// `n` parameters across the domain including both ends and every knot.
pub fn sample_params(k: &KnotVector, n: usize) -> Vec<f64> {
    let (a, b) = k.domain();
    let mut out: Vec<f64> = (0..n)
        .map(|i| {
            if i + 1 == n {
                b
            } else {
                a + (b - a) * i as f64 / (n - 1) as f64
            }
        })
        .collect();
    out.extend(k.distinct());
    out
}
