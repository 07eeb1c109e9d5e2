//! Knot insertion, refinement and degree elevation (The NURBS Book A5.1, A5.4, A5.9): the
//! geometry is unchanged, the matrices reproduce the old basis from the new one, and the
//! Gram ("mass") matrix satisfies `Cᵀ M_fine C = M_coarse`.

mod support;

use nurbspring_geom::{
    BSplineBasis, GeomError, KnotVector, NurbsCurve, NurbsSurface, RefinementMatrix, curve_rule,
    elevate_degree, insert_knot, refine_knots, refine_uniform, span_subdivision_knots,
    to_homogeneous,
};
use proptest::prelude::*;
use support::*;

fn flat4(v: &[[f64; 4]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

fn max_abs(points: &[[f64; 3]]) -> f64 {
    points.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()))
}

fn min_span(k: &KnotVector) -> f64 {
    k.nonempty_spans()
        .iter()
        .fold(f64::INFINITY, |m, &(_, a, b)| m.min(b - a))
}

/// Knots to insert: fractions of the domain, some of them repeated or on existing knots.
fn arb_insertions() -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(
        prop_oneof![
            0.001..0.999f64,
            (1u32..20).prop_map(|k| f64::from(k) / 20.0)
        ],
        0..6,
    )
}

/// Maps fractions into the domain and drops values whose multiplicity would exceed p.
fn admissible(k: &KnotVector, fractions: &[f64]) -> Vec<f64> {
    let (a, b) = k.domain();
    let mut out: Vec<f64> = Vec::new();
    for &t in fractions {
        let x = a + t * (b - a);
        if x > a
            && x < b
            && k.multiplicity(x) + out.iter().filter(|&&y| y == x).count() < k.degree()
        {
            out.push(x);
        }
    }
    out
}

/// Same curve: points and first two derivatives at every sample parameter (ends and knots of
/// both representations included), to `tol` of their natural scales: [`ROUNDOFF`] after knot
/// insertion, [`ELEVATION`] after degree elevation, whose knot removals amplify rounding with
/// the ratio of neighbouring spans (a degree 5 → 6 curve on spans of ratio 19 measured
/// 1.06e-13 of its size at a point).
fn same_curve(a: &NurbsCurve, b: &NurbsCurve, tol: f64, what: &str) -> Result<(), TestCaseError> {
    let size = max_abs(a.control_points());
    let len = min_span(a.basis().knots()).min(min_span(b.basis().knots()));
    let mut params = sample_params(a.basis().knots(), 33);
    params.extend(b.basis().knots().distinct());
    for u in params {
        let (da, db) = (a.derivatives(u, 2).unwrap(), b.derivatives(u, 2).unwrap());
        check_scaled(&db.point, &da.point, size, tol, &format!("{what}: c({u})"))?;
        check_scaled(&db.u, &da.u, size / len, tol, &format!("{what}: c'({u})"))?;
        check_scaled(
            &db.uu,
            &da.uu,
            size / (len * len),
            tol,
            &format!("{what}: c''({u})"),
        )?;
    }
    Ok(())
}

/// [`same_curve`] for surfaces.
fn same_surface(
    a: &NurbsSurface,
    b: &NurbsSurface,
    tol: f64,
    what: &str,
) -> Result<(), TestCaseError> {
    let size = max_abs(a.control_points());
    let lu = min_span(a.basis_u().knots()).min(min_span(b.basis_u().knots()));
    let lv = min_span(a.basis_v().knots()).min(min_span(b.basis_v().knots()));
    let natural = [
        size,
        size / lu,
        size / lv,
        size / (lu * lu),
        size / (lu * lv),
        size / (lv * lv),
    ];
    for u in sample_params(b.basis_u().knots(), 9) {
        for v in sample_params(b.basis_v().knots(), 9) {
            let (da, db) = (
                a.derivatives(u, v, 2).unwrap(),
                b.derivatives(u, v, 2).unwrap(),
            );
            for slot in nurbspring_geom::Deriv::ALL {
                check_scaled(
                    &db.get(slot),
                    &da.get(slot),
                    natural[slot.slot()],
                    tol,
                    &format!("{what}: {} at ({u}, {v})", slot.name()),
                )?;
            }
        }
    }
    Ok(())
}

/// Row sums 1, no negative entries (beyond rounding), the shape `new × old`, and the old
/// B-spline basis reproduced from the new one: `N_old(u) = Cᵀ N_new(u)`.
fn check_matrix(
    old: &KnotVector,
    new: &KnotVector,
    c: &RefinementMatrix,
    tol: f64,
) -> Result<(), TestCaseError> {
    prop_assert_eq!((c.nrows, c.ncols), (new.n_basis(), old.n_basis()));
    prop_assert_eq!(c.row_sums().len(), c.nrows);
    for (r, s) in c.row_sums().iter().enumerate() {
        prop_assert!((s - 1.0).abs() <= tol, "row {} sums to {}", r, s);
    }
    prop_assert!(
        c.triplets.iter().all(|&(_, _, v)| v >= -tol),
        "negative entry"
    );
    prop_assert!(
        c.triplets
            .windows(2)
            .all(|w| (w[0].0, w[0].1) < (w[1].0, w[1].1)),
        "unsorted"
    );
    let (bo, bn) = (
        BSplineBasis::new(old.clone()),
        BSplineBasis::new(new.clone()),
    );
    for u in sample_params(new, 21) {
        let reproduced = c.apply_transpose(&bn.all_values(u).unwrap());
        check_close(
            &reproduced,
            &bo.all_values(u).unwrap(),
            tol,
            &format!("N_old({u}) = Cᵀ N_new"),
        )?;
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    /// A5.4 refinement of a rational curve: same curve, merged knots, a valid matrix, and
    /// `C P^w_old` = the new homogeneous points. A5.1 repeated gives the same matrix.
    #[test]
    fn curve_refinement_keeps_the_curve(c in arb_curve(5, true, 4.0), xs in arb_insertions()) {
        let k = c.basis().knots();
        let xs = admissible(k, &xs);
        let (fine, m) = c.refine_knots(&xs).unwrap();
        let mut merged = k.knots().to_vec();
        merged.extend(&xs);
        merged.sort_by(f64::total_cmp);
        prop_assert_eq!(fine.basis().knots().knots(), &merged[..]);
        check_matrix(k, fine.basis().knots(), &m, MATRIX_ENTRY)?;
        same_curve(&c, &fine, ROUNDOFF, "refined")?;
        let h = m.apply(&to_homogeneous(c.control_points(), c.weights()));
        check_close(&flat4(&h), &flat4(&to_homogeneous(fine.control_points(), fine.weights())), ROUNDOFF, "C P^w")?;
        // One knot at a time with A5.1, composed, gives the same matrix.
        let mut step = c.clone();
        let mut total = RefinementMatrix::identity(c.n_control_points());
        for &x in &xs {
            let (next, mi) = step.insert_knot(x, 1).unwrap();
            total = mi.compose(&total);
            step = next;
        }
        prop_assert_eq!(step.basis().knots(), fine.basis().knots());
        check_close(&total.to_dense(), &m.to_dense(), MATRIX_ENTRY, "A5.1 steps vs A5.4")?;
    }

    /// Rational basis reproduction with the Cartesian matrix of fixed weights:
    /// `R_old(u) = C_cartᵀ R_new(u)` and `P_new = C_cart P_old`.
    #[test]
    fn cartesian_matrix_reproduces_the_rational_basis(c in arb_curve(4, true, 4.0), xs in arb_insertions()) {
        let xs = admissible(c.basis().knots(), &xs);
        let (fine, m) = c.refine_knots(&xs).unwrap();
        let (cart, w_new) = m.to_cartesian(c.weights());
        check_close(&w_new, fine.weights(), ROUNDOFF, "w_new")?;
        for x in 0..3 {
            let old: Vec<f64> = c.control_points().iter().map(|p| p[x]).collect();
            let new: Vec<f64> = fine.control_points().iter().map(|p| p[x]).collect();
            check_close(&cart.apply_to(&old), &new, ROUNDOFF, "P_new = C_cart P_old")?;
        }
        for s in cart.row_sums() {
            prop_assert!((s - 1.0).abs() <= ROUNDOFF);
        }
        let dense_r = |curve: &NurbsCurve, u: f64| {
            let j = curve.jacobian(u, 0, false).unwrap();
            let mut out = vec![0.0; curve.n_control_points()];
            for (l, &k) in j.indices.iter().enumerate() {
                out[k] = j.r[l][0];
            }
            out
        };
        for u in sample_params(fine.basis().knots(), 17) {
            check_close(&cart.apply_transpose(&dense_r(&fine, u)), &dense_r(&c, u), ROUNDOFF, "R_old = C_cartᵀ R_new")?;
        }
    }

    /// A5.9 degree elevation of a rational curve: same curve, every distinct knot gains
    /// multiplicity t, one more control point per Bézier segment and degree; elevating twice
    /// by one equals elevating by two.
    #[test]
    fn curve_degree_elevation_keeps_the_curve(c in arb_curve(5, true, 4.0), t in 1usize..=3) {
        let k = c.basis().knots();
        let (up, m) = c.elevate_degree(t).unwrap();
        let ku = up.basis().knots();
        prop_assert_eq!(ku.degree(), k.degree() + t);
        let segments = k.nonempty_spans().len();
        prop_assert_eq!(up.n_control_points(), c.n_control_points() + t * segments);
        let before = k.distinct_with_multiplicity();
        let after = ku.distinct_with_multiplicity();
        prop_assert_eq!(before.len(), after.len());
        for ((x, m0), (y, m1)) in before.iter().zip(&after) {
            prop_assert_eq!(x, y);
            prop_assert_eq!(*m1, m0 + t);
        }
        check_matrix(k, ku, &m, ELEVATION)?;
        same_curve(&c, &up, ELEVATION, "elevated")?;
        let (once, m1) = c.elevate_degree(1).unwrap();
        let (twice, m2) = once.elevate_degree(1).unwrap();
        let (direct, m12) = c.elevate_degree(2).unwrap();
        prop_assert_eq!(twice.basis().knots(), direct.basis().knots());
        check_close(&m2.compose(&m1).to_dense(), &m12.to_dense(), ELEVATION, "E1 E1 = E2")?;
    }

    /// Surfaces: refinement (A5.4 per direction), uniform refinement and degree elevation
    /// leave every point and derivative unchanged, and `C = C_u ⊗ C_v`.
    #[test]
    fn surface_refinement_and_elevation_keep_the_surface(
        s in arb_surface(3, true, 4.0),
        xu in arb_insertions(), xv in arb_insertions(),
        tu in 0usize..=2, tv in 0usize..=2,
    ) {
        let (ku, kv) = (s.basis_u().knots(), s.basis_v().knots());
        let (xu, xv) = (admissible(ku, &xu), admissible(kv, &xv));
        let (fine, c) = s.refine_knots(&xu, &xv).unwrap();
        let (_, cu) = refine_knots(ku, &xu).unwrap();
        let (_, cv) = refine_knots(kv, &xv).unwrap();
        prop_assert_eq!(&c, &cu.kron(&cv));
        let h = c.apply(&to_homogeneous(s.control_points(), s.weights()));
        check_close(&flat4(&h), &flat4(&to_homogeneous(fine.control_points(), fine.weights())), ROUNDOFF, "C P^w")?;
        same_surface(&s, &fine, ROUNDOFF, "refined")?;
        let (uniform, cuni) = s.refine_uniform(1).unwrap();
        prop_assert_eq!(uniform.n_u(), s.n_u() + ku.nonempty_spans().len());
        prop_assert_eq!(uniform.n_v(), s.n_v() + kv.nonempty_spans().len());
        prop_assert_eq!(cuni.nrows, uniform.n_control_points());
        same_surface(&s, &uniform, ROUNDOFF, "uniformly refined")?;
        let (up, e) = s.elevate_degree(tu, tv).unwrap();
        prop_assert_eq!(up.basis_u().degree(), ku.degree() + tu);
        prop_assert_eq!(up.basis_v().degree(), kv.degree() + tv);
        prop_assert_eq!(e.nrows, up.n_control_points());
        same_surface(&s, &up, ELEVATION, "elevated")?;
    }

    /// Refining twice equals refining once with the union (knots and composed matrices).
    #[test]
    fn refinement_composes(k in arb_knots(4, 6), xa in arb_insertions(), xb in arb_insertions()) {
        let xa = admissible(&k, &xa);
        let (ka, ca) = refine_knots(&k, &xa).unwrap();
        let xb = admissible(&ka, &xb);
        let (kab, cb) = refine_knots(&ka, &xb).unwrap();
        let all: Vec<f64> = xa.iter().chain(&xb).copied().collect();
        let (kall, call) = refine_knots(&k, &all).unwrap();
        prop_assert_eq!(&kab, &kall);
        check_close(&cb.compose(&ca).to_dense(), &call.to_dense(), MATRIX_ENTRY, "C_b C_a")?;
    }
}

/// `Cᵀ M_fine C = M_coarse` for the Gram matrix `M = ∫ N Nᵀ du` of B-spline bases (docs/math.md §2),
/// with Gauss rules exact for the degree-2p integrands; for refinement and for elevation.
#[test]
fn gram_matrix_is_preserved() {
    fn gram(k: &KnotVector) -> Vec<f64> {
        let b = BSplineBasis::new(k.clone());
        let n = b.len();
        let mut m = vec![0.0; n * n];
        for e in curve_rule(&b, k.degree() + 1).unwrap() {
            for q in e.points {
                let v = b.all_values(q.u).unwrap();
                for i in 0..n {
                    for j in 0..n {
                        m[i * n + j] += q.weight * v[i] * v[j];
                    }
                }
            }
        }
        m
    }
    let k = KnotVector::try_new(REF_KU.to_vec(), 3).unwrap();
    let coarse = gram(&k);
    let (kr, cr) = refine_uniform(&k, 2).unwrap();
    let (ke, ce) = elevate_degree(&k, 2).unwrap();
    for (kf, c) in [(kr, cr), (ke, ce)] {
        let fine = gram(&kf);
        let (nf, nc) = (c.nrows, c.ncols);
        let dc = c.to_dense();
        let mut ctmc = vec![0.0; nc * nc];
        for a in 0..nc {
            for b in 0..nc {
                let mut s = 0.0;
                for i in 0..nf {
                    for j in 0..nf {
                        s += dc[i * nc + a] * fine[i * nf + j] * dc[j * nc + b];
                    }
                }
                ctmc[a * nc + b] = s;
            }
        }
        assert_close(&ctmc, &coarse, ROUNDOFF, "Cᵀ M_fine C");
    }
}

#[test]
fn uniform_refinement_counts() {
    let k = KnotVector::try_new(REF_KU.to_vec(), 3).unwrap(); // 3 non-empty spans
    assert_eq!(span_subdivision_knots(&k, 1), Vec::<f64>::new());
    for levels in 0..4u32 {
        let (kf, c) = refine_uniform(&k, levels).unwrap();
        assert_eq!(kf.nonempty_spans().len(), 3 << levels);
        assert_eq!(c.nrows, 7 + 3 * ((1 << levels) - 1));
    }
    let s = reference_surface(true);
    let (fine, c) = s.refine_uniform(2).unwrap();
    assert_eq!((fine.n_u(), fine.n_v()), (7 + 9, 4 + 6));
    assert_eq!((c.nrows, c.ncols), (16 * 10, 28));
}

/// Unclamped (periodic-style) knot vectors refine too: the domain is `[u_p, u_{n+1}]`.
#[test]
fn unclamped_refinement() {
    let k = KnotVector::try_new((0..10).map(f64::from).collect(), 3).unwrap();
    let pts: Vec<[f64; 3]> = (0..6)
        .map(|i| [i as f64, (i * i % 4) as f64, 0.5 * i as f64])
        .collect();
    let ws = vec![1.0, 2.0, 0.5, 1.5, 1.0, 0.75];
    let c = NurbsCurve::try_new(k, pts, ws).unwrap();
    let (fine, _) = c.refine_knots(&[3.5, 4.0, 4.25, 5.5]).unwrap();
    for i in 0..=60 {
        let u = 3.0 + 3.0 * i as f64 / 60.0;
        assert_close3(
            fine.point(u).unwrap(),
            c.point(u).unwrap(),
            ROUNDOFF,
            "unclamped",
        );
    }
    assert!(matches!(
        c.elevate_degree(1),
        Err(GeomError::UnsupportedKnots { .. })
    ));
    // Outside the domain [3, 6] even though inside the knot range.
    assert!(matches!(
        c.insert_knot(1.0, 1),
        Err(GeomError::InvalidInsertion { .. })
    ));
}

/// A knot vector is clamped at an end only when its p + 1 knots there coincide: clamped at
/// the start and not at the end (and the reverse), and degree elevation, which needs both,
/// refuses either.
#[test]
fn knot_vectors_clamped_at_one_end_only() {
    let start = KnotVector::try_new(vec![0., 0., 0., 0., 1., 2., 3., 4.], 3).unwrap();
    let end = KnotVector::try_new(vec![0., 1., 2., 3., 4., 4., 4., 4.], 3).unwrap();
    assert_eq!(
        (start.is_clamped_start(), start.is_clamped_end()),
        (true, false)
    );
    assert_eq!(
        (end.is_clamped_start(), end.is_clamped_end()),
        (false, true)
    );
    for k in [&start, &end] {
        assert!(matches!(
            elevate_degree(k, 1),
            Err(GeomError::UnsupportedKnots { .. })
        ));
    }
}

#[test]
fn surface_insertion_errors_and_single_direction() {
    let s = reference_surface(true);
    assert!(matches!(
        s.insert_knot_u(1.0, 1),
        Err(GeomError::InvalidInsertion { .. })
    ));
    assert!(matches!(
        s.insert_knot_v(-0.5, 1),
        Err(GeomError::InvalidInsertion { .. })
    ));
    // 0.5 has multiplicity 2 in u (p = 3): one more is fine, two more are not.
    assert!(s.insert_knot_u(0.5, 1).is_ok());
    let err = s.insert_knot_u(0.5, 2).unwrap_err();
    assert!(err.to_string().contains("2 + 2 = 4"), "{err}");
    let (su, cu) = s.insert_knot_u(0.7, 2).unwrap();
    assert_eq!((su.n_u(), su.n_v()), (9, 4));
    let (_, c1) = insert_knot(s.basis_u().knots(), 0.7, 2).unwrap();
    assert_eq!(cu, c1.kron(&RefinementMatrix::identity(4)));
    let (sv, _) = s.insert_knot_v(0.4, 1).unwrap();
    assert_eq!((sv.n_u(), sv.n_v()), (7, 5));
    for (u, v) in [(0.1, 0.2), (0.5, 0.5), (0.7, 0.4), (1.0, 1.0)] {
        let p = s.point(u, v).unwrap();
        assert_close3(su.point(u, v).unwrap(), p, ROUNDOFF, "u insertion");
        assert_close3(sv.point(u, v).unwrap(), p, ROUNDOFF, "v insertion");
    }
}

/// A rational cubic with simple interior knots 0.2, 0.45, 0.7.
fn rational_cubic() -> NurbsCurve {
    let k = KnotVector::try_new(vec![0., 0., 0., 0., 0.2, 0.45, 0.7, 1., 1., 1., 1.], 3).unwrap();
    let pts: Vec<[f64; 3]> = (0..7)
        .map(|i| [i as f64, ((i * 5) % 7) as f64 * 0.3, (i as f64 * 0.9).sin()])
        .collect();
    let w = vec![1.0, 0.8, 1.3, 1.0, 0.7, 1.1, 1.0];
    NurbsCurve::try_new(k, pts, w).unwrap()
}

/// Degree elevation of a cubic with simple interior knots (A5.9's knot-removal steps run at
/// every interior knot) by 1 and 2: the same curve at 201 parameters, to round-off.
#[test]
fn elevating_a_cubic_with_simple_knots_keeps_it() {
    let c = rational_cubic();
    for t in [1, 2] {
        let (up, _) = c.elevate_degree(t).unwrap();
        assert_eq!(up.basis().degree(), 3 + t);
        for s in 0..=200 {
            let u = s as f64 / 200.0;
            let (a, b) = (c.point(u).unwrap(), up.point(u).unwrap());
            for x in 0..3 {
                assert!(
                    (a[x] - b[x]).abs() < 1e-12,
                    "t = {t}, u = {u}: {a:?} vs {b:?}"
                );
            }
        }
    }
}

/// Degree elevation where a knot's multiplicity jumps by two or more over the previous one (a
/// simple knot at 0.3, then a triple one at 0.45), at degrees 10 and 11: A5.9's knot removal
/// at 0.45 then reaches points that depend on the knots loaded before 0.3 (the book's
/// shortcut, which takes the last loaded knot there, moved the curve by 0.09 at degree 10 and
/// made a weight negative at degree 12). The same rational curve at 201 parameters.
#[test]
fn elevation_across_a_jump_in_knot_multiplicity_keeps_the_curve() {
    for p in [10, 11] {
        let interior = [0.15, 0.3, 0.45, 0.45, 0.45, 0.6, 0.8];
        let mut knots = vec![0.0; p + 1];
        knots.extend(interior);
        knots.extend(vec![1.0; p + 1]);
        let n = knots.len() - p - 1;
        let k = KnotVector::try_new(knots, p).unwrap();
        let pts: Vec<[f64; 3]> = (0..n)
            .map(|i| [i as f64, ((i * 5) % 7) as f64 * 0.3, (i as f64 * 0.9).sin()])
            .collect();
        let w: Vec<f64> = (0..n).map(|i| 0.8 + 0.3 * ((i * 3) % 4) as f64).collect();
        let c = NurbsCurve::try_new(k, pts, w).unwrap();
        for t in [1, 2] {
            let (up, _) = c.elevate_degree(t).unwrap();
            assert_eq!(up.basis().degree(), p + t);
            for s in 0..=200 {
                let u = s as f64 / 200.0;
                assert_close3(
                    up.point(u).unwrap(),
                    c.point(u).unwrap(),
                    ELEVATION,
                    &format!("degree {p} + {t} at u = {u}"),
                );
            }
        }
    }
}

/// `row_sums` of a matrix by hand (not one of this module's, whose rows all sum to 1): one
/// sum per row, empty rows 0.
#[test]
fn row_sums_by_hand() {
    let c = RefinementMatrix {
        nrows: 4,
        ncols: 2,
        triplets: vec![
            (0, 0, 2.0),
            (0, 1, -0.5),
            (2, 1, 3.0),
            (3, 0, 0.25),
            (3, 1, 0.5),
        ],
    };
    assert_eq!(c.row_sums(), vec![1.5, 0.0, 3.0, 0.75]);
    assert_eq!(RefinementMatrix::identity(3).row_sums(), vec![1.0; 3]);
}

#[test]
fn surface_control_points_are_indexed_row_by_row() {
    let k = KnotVector::try_new(vec![0., 0., 0.5, 1., 1.], 1).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0.3, 0.6, 1., 1.], 1).unwrap();
    let pts: Vec<[f64; 3]> = (0..12)
        .map(|k| [(k / 4) as f64, (k % 4) as f64, 0.0])
        .collect();
    let s = nurbspring_geom::NurbsSurface::try_new(k, kv, pts.clone(), vec![1.0; 12]).unwrap();
    assert_eq!((s.n_u(), s.n_v()), (3, 4));
    for i in 0..3 {
        for j in 0..4 {
            assert_eq!(s.index(i, j), 4 * i + j);
            assert_eq!(s.control_points()[s.index(i, j)], [i as f64, j as f64, 0.0]);
        }
    }
}

/// Bézier patches of degree 15 and 16 in u (either side of the stack buffers of point
/// evaluation) and 1 in v, with the control points of `(u, v, u²)`: the Bernstein coefficients
/// of u are i/n and of u² are i(i − 1)/(n(n − 1)), so the points are `(u, v, u²)`.
#[test]
fn high_degree_bezier_patch_points_by_hand() {
    for n in [15usize, 16] {
        let mut ku = vec![0.0; n + 1];
        ku.extend(vec![1.0; n + 1]);
        let ku = KnotVector::try_new(ku, n).unwrap();
        let kv = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
        let nf = n as f64;
        let pts: Vec<[f64; 3]> = (0..=n)
            .flat_map(|i| {
                let f = i as f64;
                [0.0, 1.0].map(|v| [f / nf, v, f * (f - 1.0) / (nf * (nf - 1.0))])
            })
            .collect();
        let s = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 2 * (n + 1)]).unwrap();
        for (u, v) in [(0.0, 0.0), (0.3, 0.25), (0.5, 1.0), (0.77, 0.6), (1.0, 0.5)] {
            assert_close3(
                s.point(u, v).unwrap(),
                [u, v, u * u],
                ROUNDOFF,
                &format!("degree {n} at ({u}, {v})"),
            );
        }
    }
}

/// The test for a degenerate normal is relative to `|c_u| |c_v|`: a plane patch of side 10⁻⁷
/// (`|c_u × c_v|` = 10⁻¹⁴) has the normal (0, 0, 1); the pole of the sphere octant (u = 1,
/// where the meridians meet and `c_v = 0`) has none.
#[test]
fn a_small_patch_has_a_normal_and_a_pole_has_none() {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let h = 1e-7;
    let pts = vec![[0.0, 0.0, 0.0], [0.0, h, 0.0], [h, 0.0, 0.0], [h, h, 0.0]];
    let s = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 4]).unwrap();
    assert_eq!(s.normal(0.5, 0.5).unwrap(), [0.0, 0.0, 1.0]);
    let octant = sphere_octant();
    let ((_, u1), _) = octant.domain();
    assert!(matches!(
        octant.normal(u1, 0.5),
        Err(GeomError::DegenerateNormal { .. })
    ));
}

/// `uniform_grid` on a bilinear patch over `[1, 3] × [0, 2]`: parameters evenly spaced with
/// both ends, points of the plane `z = x + 2y` there, and its unit normal `(−1, −2, 1)/√6`.
#[test]
fn uniform_grid_and_normal_of_a_plane_by_hand() {
    use nurbspring_geom::{NurbsSurface, linspace};
    let ku = KnotVector::try_new(vec![1., 1., 3., 3.], 1).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 2., 2.], 1).unwrap();
    let plane = |x: f64, y: f64| [x, y, x + 2.0 * y];
    let pts = vec![
        plane(0.0, 0.0),
        plane(0.0, 1.0),
        plane(2.0, 0.0),
        plane(2.0, 1.0),
    ];
    let s = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 4]).unwrap();
    let (us, vs, grid) = s.uniform_grid(3, 5).unwrap();
    assert_eq!(us, vec![1.0, 2.0, 3.0]);
    assert_eq!(vs, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
    assert_eq!(linspace(0.0, 1.0, 1), vec![0.0]);
    assert_eq!(grid.len(), 15);
    for (i, &u) in us.iter().enumerate() {
        for (j, &v) in vs.iter().enumerate() {
            let expected = plane(u - 1.0, 0.5 * v);
            for x in 0..3 {
                assert!((grid[i * 5 + j][x] - expected[x]).abs() < 1e-14);
            }
        }
    }
    let n = s.normal(1.7, 0.4).unwrap();
    let e = [-1.0 / 6f64.sqrt(), -2.0 / 6f64.sqrt(), 1.0 / 6f64.sqrt()];
    for x in 0..3 {
        assert!((n[x] - e[x]).abs() < 1e-15, "{n:?}");
    }
}

/// A5.4 inserting values equal to an existing interior knot (0.45 twice, raising it to a
/// triple knot, with 0.7 and 0.8 after): the same knots and matrix as A5.1 one knot at a time,
/// and the same curve at 201 parameters.
#[test]
fn refinement_at_an_existing_knot_equals_insertion_one_at_a_time() {
    let c = rational_cubic();
    let xs = [0.45, 0.45, 0.7, 0.8];
    let (fine, m) = c.refine_knots(&xs).unwrap();
    let mut step = c.clone();
    let mut total = RefinementMatrix::identity(c.n_control_points());
    for &x in &xs {
        let (next, mi) = step.insert_knot(x, 1).unwrap();
        total = mi.compose(&total);
        step = next;
    }
    assert_eq!(step.basis().knots(), fine.basis().knots());
    let (a, b) = (total.to_dense(), m.to_dense());
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!((x - y).abs() < 1e-14, "entry {i}: {x} vs {y}");
    }
    for s in 0..=200 {
        let u = s as f64 / 200.0;
        let (p, q) = (c.point(u).unwrap(), fine.point(u).unwrap());
        assert!(
            (0..3).all(|x| (p[x] - q[x]).abs() < 1e-12),
            "u = {u}: {p:?} vs {q:?}"
        );
    }
}

/// A surface refuses a weight that is negative, zero, infinite or NaN, naming its index.
#[test]
fn surface_weights_must_be_positive_and_finite() {
    let k = KnotVector::clamped_uniform(1, 1).unwrap();
    let pts = vec![
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    assert!(NurbsSurface::try_new(k.clone(), k.clone(), pts.clone(), vec![1.0; 4]).is_ok());
    for bad in [-1.0, 0.0, f64::INFINITY, f64::NAN] {
        let err =
            NurbsSurface::try_new(k.clone(), k.clone(), pts.clone(), vec![1.0, 1.0, bad, 1.0])
                .unwrap_err();
        assert!(
            matches!(err, GeomError::InvalidWeight { index: 2, .. }),
            "{bad}: {err}"
        );
    }
}
