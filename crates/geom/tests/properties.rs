//! Property tests of bases, curves, surfaces, Jacobians and quadrature (proptest).

mod support;

use nurbspring_geom::{
    BSplineBasis, Deriv, GaussLegendre, KnotVector, NurbsCurve, NurbsSurface, curve_rule,
    surface_rule,
};
use proptest::prelude::*;
use support::*;

/// `max(1, max |coordinate|)` of a control net: the size of the function being differenced.
fn max_abs(points: &[[f64; 3]]) -> f64 {
    points.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()))
}

fn fd_tol(rational: bool) -> f64 {
    if rational { FD_RATIONAL } else { FD_POLYNOMIAL }
}

// ---- bases ----------------------------------------------------------------------------------

proptest! {
    #![proptest_config(config())]

    /// Σ N_i = 1, N_i ≥ 0, Σ N_i^(k) = 0 for k ≥ 1, and N_i vanishes outside
    /// [u_i, u_{i+p+1}) but is positive in its open interior (local support).
    #[test]
    fn basis_partition_of_unity_and_local_support(k in arb_knots(5, 8), t in 0.0..=1.0f64) {
        let (a, b) = k.domain();
        let u = a + t * (b - a);
        let basis = BSplineBasis::new(k.clone());
        let all = basis.all_values(u).unwrap();
        let sum: f64 = all.iter().sum();
        prop_assert!((sum - 1.0).abs() <= 4.0 * f64::EPSILON, "Σ N = {sum}");
        prop_assert!(all.iter().all(|&x| x >= 0.0), "negative value in {all:?}");
        let p = k.degree();
        let knots = k.knots();
        for (i, &n) in all.iter().enumerate() {
            let (lo, hi) = (knots[i], knots[i + p + 1]);
            let inside = lo < u && u < hi;
            if !(lo <= u && u <= hi) {
                prop_assert_eq!(n, 0.0, "N_{} ≠ 0 at {} outside [{}, {}]", i, u, lo, hi);
            }
            if inside {
                prop_assert!(n > 0.0, "N_{} = 0 inside ({}, {})", i, lo, hi);
            }
        }
        let (_, d) = basis.derivatives(u, p + 1).unwrap();
        for order in 1..=p + 1 {
            let row = &d[order * (p + 1)..(order + 1) * (p + 1)];
            let scale: f64 = row.iter().map(|x| x.abs()).sum::<f64>().max(1.0);
            let s: f64 = row.iter().sum();
            prop_assert!(s.abs() <= 64.0 * f64::EPSILON * scale, "Σ N^({order}) = {s}");
        }
        // Order p + 1 and above are zero.
        prop_assert!(d[(p + 1) * (p + 1)..].iter().all(|&x| x == 0.0));
    }

    /// A2.3 derivatives vs fourth-order central differences of A2.2 values (and of the
    /// first derivatives), inside a span where the basis is a polynomial of degree ≤ 4.
    #[test]
    fn basis_derivatives_vs_differences(
        k in arb_knots(4, 8),
        pick in any::<prop::sample::Index>(),
        t in 0.0..1.0f64,
    ) {
        let (u, len) = param_in_span(&k, pick, t);
        let basis = BSplineBasis::new(k.clone());
        let p = k.degree();
        let (span, d) = basis.derivatives(u, 2).unwrap();
        let values = |x: f64| {
            let mut out = vec![0.0; p + 1];
            basis.values_into(span, x, &mut out, &mut Default::default());
            out
        };
        let first = |x: f64| {
            let mut out = vec![0.0; 2 * (p + 1)];
            basis.derivatives_into(span, x, 1, &mut out, &mut Default::default());
            out[p + 1..].to_vec()
        };
        let h = FD_STEP * len;
        let fd1 = diff1(values, u, h);
        check_scaled(&fd1, &d[p + 1..2 * (p + 1)], 1.0 / len, FD_POLYNOMIAL, "N' vs FD")?;
        let fd2 = diff2(values, u, h);
        check_scaled(&fd2, &d[2 * (p + 1)..], 1.0 / (len * len), FD_POLYNOMIAL, "N'' vs FD of N")?;
        let fd21 = diff1(first, u, h);
        check_scaled(&fd21, &d[2 * (p + 1)..], 1.0 / (len * len), FD_POLYNOMIAL, "N'' vs FD of N'")?;
    }

    /// Rational basis: Σ R = 1, R ≥ 0, Σ R_d = 0 for every derivative slot, and the slots
    /// vs differences of R.
    #[test]
    fn rational_basis_properties(
        s in arb_surface(3, true, 2.0),
        pu in any::<prop::sample::Index>(), tu in 0.0..1.0f64,
        pv in any::<prop::sample::Index>(), tv in 0.0..1.0f64,
    ) {
        let (u, lu) = param_in_span(s.basis_u().knots(), pu, tu);
        let (v, lv) = param_in_span(s.basis_v().knots(), pv, tv);
        let rb = s.rational_basis(u, v, 2).unwrap();
        let sum: f64 = rb.r.iter().map(|r| r[0]).sum();
        prop_assert!((sum - 1.0).abs() <= 16.0 * f64::EPSILON, "Σ R = {sum}");
        prop_assert!(rb.r.iter().all(|r| r[0] >= 0.0));
        for slot in 1..6 {
            let scale: f64 = rb.r.iter().map(|r| r[slot].abs()).sum::<f64>().max(1.0);
            let sd: f64 = rb.r.iter().map(|r| r[slot]).sum();
            prop_assert!(sd.abs() <= 1e-13 * scale, "Σ R_{} = {sd}", Deriv::ALL[slot].name());
        }
        let r_at = |x: f64, y: f64| s.rational_basis(x, y, 0).unwrap().r.iter().map(|r| r[0]).collect::<Vec<f64>>();
        let slot = |d: usize| rb.r.iter().map(|r| r[d]).collect::<Vec<f64>>();
        let (hu, hv) = (FD_STEP * lu, FD_STEP * lv);
        check_scaled(&diff1(|x| r_at(x, v), u, hu), &slot(1), 1.0 / lu, FD_RATIONAL, "R_u")?;
        check_scaled(&diff1(|y| r_at(u, y), v, hv), &slot(2), 1.0 / lv, FD_RATIONAL, "R_v")?;
        check_scaled(&diff2(|x| r_at(x, v), u, hu), &slot(3), 1.0 / (lu * lu), FD_RATIONAL, "R_uu")?;
        check_scaled(&diff_mixed(r_at, u, v, hu, hv), &slot(4), 1.0 / (lu * lv), FD_RATIONAL, "R_uv")?;
        check_scaled(&diff2(|y| r_at(u, y), v, hv), &slot(5), 1.0 / (lv * lv), FD_RATIONAL, "R_vv")?;
    }
}

// ---- curves and surfaces --------------------------------------------------------------------

fn check_surface_derivatives(
    s: &NurbsSurface,
    rational: bool,
    (u, lu): (f64, f64),
    (v, lv): (f64, f64),
) -> Result<(), TestCaseError> {
    let tol = fd_tol(rational);
    let d = s.derivatives(u, v, 2).unwrap();
    let c = |x: f64, y: f64| s.point(x, y).unwrap().to_vec();
    let (hu, hv) = (FD_STEP * lu, FD_STEP * lv);
    let size = max_abs(s.control_points());
    check_scaled(&diff1(|x| c(x, v), u, hu), &d.u, size / lu, tol, "c_u")?;
    check_scaled(&diff1(|y| c(u, y), v, hv), &d.v, size / lv, tol, "c_v")?;
    check_scaled(
        &diff2(|x| c(x, v), u, hu),
        &d.uu,
        size / (lu * lu),
        tol,
        "c_uu",
    )?;
    check_scaled(
        &diff_mixed(c, u, v, hu, hv),
        &d.uv,
        size / (lu * lv),
        tol,
        "c_uv",
    )?;
    check_scaled(
        &diff2(|y| c(u, y), v, hv),
        &d.vv,
        size / (lv * lv),
        tol,
        "c_vv",
    )?;
    check_close(
        &d.point,
        &c(u, v),
        ROUNDOFF,
        "derivatives().point vs point()",
    )?;
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    /// Surface c_u, c_v, c_uu, c_uv, c_vv vs central differences of the point (non-rational).
    #[test]
    fn surface_derivatives_vs_differences_polynomial(
        s in arb_surface(4, false, 1.0),
        pu in any::<prop::sample::Index>(), tu in 0.0..1.0f64,
        pv in any::<prop::sample::Index>(), tv in 0.0..1.0f64,
    ) {
        let a = param_in_span(s.basis_u().knots(), pu, tu);
        let b = param_in_span(s.basis_v().knots(), pv, tv);
        check_surface_derivatives(&s, false, a, b)?;
    }

    /// The same for rational surfaces (weights in [1/2, 2]).
    #[test]
    fn surface_derivatives_vs_differences_rational(
        s in arb_surface(3, true, 2.0),
        pu in any::<prop::sample::Index>(), tu in 0.0..1.0f64,
        pv in any::<prop::sample::Index>(), tv in 0.0..1.0f64,
    ) {
        let a = param_in_span(s.basis_u().knots(), pu, tu);
        let b = param_in_span(s.basis_v().knots(), pv, tv);
        check_surface_derivatives(&s, true, a, b)?;
    }

    /// Curve c', c'' vs differences, rational.
    #[test]
    fn curve_derivatives_vs_differences(
        c in arb_curve(4, true, 2.0),
        pick in any::<prop::sample::Index>(), t in 0.0..1.0f64,
    ) {
        let (u, len) = param_in_span(c.basis().knots(), pick, t);
        let d = c.derivatives(u, 2).unwrap();
        let f = |x: f64| c.point(x).unwrap().to_vec();
        let size = max_abs(c.control_points());
        check_scaled(&diff1(f, u, FD_STEP * len), &d.u, size / len, FD_RATIONAL, "c'")?;
        check_scaled(&diff2(f, u, FD_STEP * len), &d.uu, size / (len * len), FD_RATIONAL, "c''")?;
    }

    /// grid() equals pointwise point(); points() and derivatives_batch() equal their
    /// single-point versions.
    #[test]
    fn grid_equals_pointwise(
        s in arb_surface(4, true, 4.0),
        us in prop::collection::vec(0.0..=1.0f64, 1..12),
        vs in prop::collection::vec(0.0..=1.0f64, 1..12),
    ) {
        let ((u0, u1), (v0, v1)) = s.domain();
        let us: Vec<f64> = us.iter().map(|t| (u0 + t * (u1 - u0)).min(u1)).collect();
        let mut vs: Vec<f64> = vs.iter().map(|t| (v0 + t * (v1 - v0)).min(v1)).collect();
        vs.extend(s.basis_v().knots().distinct());
        let grid = s.grid(&us, &vs).unwrap();
        let params: Vec<(f64, f64)> = us.iter().flat_map(|&u| vs.iter().map(move |&v| (u, v))).collect();
        let batch = s.points(&params).unwrap();
        let dbatch = s.derivatives_batch(&params, 1).unwrap();
        for (l, &(u, v)) in params.iter().enumerate() {
            let p = s.point(u, v).unwrap();
            check_close(&grid[l], &p, ROUNDOFF, "grid vs point")?;
            prop_assert_eq!(batch[l], p);
            prop_assert_eq!(dbatch[l], s.derivatives(u, v, 1).unwrap());
            check_close(&dbatch[l].point, &p, ROUNDOFF, "derivatives vs point")?;
        }
    }
}

// ---- Jacobians ------------------------------------------------------------------------------

fn generalized(s_points: &[[f64; 3]], weights: &[f64], four: bool) -> Vec<f64> {
    s_points
        .iter()
        .zip(weights)
        .flat_map(|(p, &w)| {
            let mut v = p.to_vec();
            if four {
                v.push(w);
            }
            v
        })
        .collect()
}

/// The local blocks of `J^{(d)}` flattened (3 × dofs per block), for differencing.
fn local_blocks(s: &NurbsSurface, u: f64, v: f64, four: bool, d: Deriv) -> Vec<f64> {
    let j = s.jacobian(u, v, 2, four).unwrap();
    let m = j.dofs_per_point;
    let mut out = Vec::with_capacity(3 * m * j.n_local());
    for l in 0..j.n_local() {
        for c in 0..m {
            out.extend_from_slice(&j.column(l, c, d));
        }
    }
    out
}

proptest! {
    #![proptest_config(config())]

    /// `J^{(d)} p = c^{(d)}` for all six slots, 3 and 4 dofs per control point; the dense form
    /// agrees with `apply`; `Jᵀ` is the adjoint of `J`.
    #[test]
    fn jacobian_times_coordinates_is_the_point(
        s in arb_surface(4, true, 4.0),
        tu in 0.0..=1.0f64, tv in 0.0..=1.0f64,
        f in arb_point(),
    ) {
        let ((u0, u1), (v0, v1)) = s.domain();
        let (u, v) = ((u0 + tu * (u1 - u0)).min(u1), (v0 + tv * (v1 - v0)).min(v1));
        let d = s.derivatives(u, v, 2).unwrap();
        // Rounding scales with the size of the derivative terms that cancel: ‖P‖ / span^order.
        let min_span = |k: &KnotVector| k.nonempty_spans().iter().fold(f64::INFINITY, |m, &(_, a, b)| m.min(b - a));
        let (lu, lv) = (min_span(s.basis_u().knots()), min_span(s.basis_v().knots()));
        let size = max_abs(s.control_points());
        let natural = [size, size / lu, size / lv, size / (lu * lu), size / (lu * lv), size / (lv * lv)];
        for four in [false, true] {
            let j = s.jacobian(u, v, 2, four).unwrap();
            let p = generalized(s.control_points(), s.weights(), four);
            prop_assert_eq!(j.n_dofs(), p.len());
            for slot in Deriv::ALL {
                let jp = j.apply(slot, &p);
                check_scaled(&jp, &d.get(slot), natural[slot.slot()], ROUNDOFF, &format!("J_{} p, four = {four}", slot.name()))?;
                let dense = j.to_dense(slot);
                let n = j.n_dofs();
                let dp: Vec<f64> = (0..3).map(|x| (0..n).map(|c| dense[x * n + c] * p[c]).sum()).collect();
                check_close(&dp, &jp, ROUNDOFF, "dense J p")?;
                // The triplets of the block of a point stacked at rows 5, 6, 7: those rows
                // only, and summed they are J (so J p = c again).
                let mut stacked = Vec::new();
                j.push_triplets(slot, 5, &mut stacked);
                prop_assert!(!stacked.is_empty() || jp.iter().all(|&x| x == 0.0));
                let mut tp = [0.0; 3];
                for &(row, col, value) in &stacked {
                    prop_assert!((5..8).contains(&row) && col < n, "triplet ({row}, {col})");
                    tp[row - 5] += value * p[col];
                }
                check_scaled(&tp, &d.get(slot), natural[slot.slot()], ROUNDOFF, &format!("triplets of J_{} p", slot.name()))?;
                // ⟨J p, f⟩ = ⟨p, Jᵀ f⟩.
                let mut jt = vec![0.0; n];
                j.apply_transpose_add(slot, f, 1.0, &mut jt);
                let lhs: f64 = (0..3).map(|x| jp[x] * f[x]).sum();
                let rhs: f64 = jt.iter().zip(&p).map(|(a, b)| a * b).sum();
                let scale = 1.0 + jt.iter().zip(&p).map(|(a, b)| (a * b).abs()).sum::<f64>();
                prop_assert!((lhs - rhs).abs() <= ROUNDOFF * scale, "adjoint: {lhs} vs {rhs}");
                // And Jᵀ f column by column against the dense J (the weight column too, which
                // the adjoint identity does not see: Σ_k w_k ∂c/∂w_k = 0).
                let dense_t: Vec<f64> = (0..n).map(|c| (0..3).map(|x| dense[x * n + c] * f[x]).sum()).collect();
                check_close(&jt, &dense_t, ROUNDOFF, "Jᵀ f")?;
            }
        }
    }

    /// `J_u, J_v, J_uu, J_uv, J_vv` (3 and 4 dofs, the weight column included) vs finite
    /// differences of `J`, and the weight column vs differences of `c` in `w_k`.
    #[test]
    fn jacobian_derivatives_vs_differences(
        s in arb_surface(3, true, 2.0),
        pu in any::<prop::sample::Index>(), tu in 0.0..1.0f64,
        pv in any::<prop::sample::Index>(), tv in 0.0..1.0f64,
        pick in any::<prop::sample::Index>(),
    ) {
        let (u, lu) = param_in_span(s.basis_u().knots(), pu, tu);
        let (v, lv) = param_in_span(s.basis_v().knots(), pv, tv);
        let (hu, hv) = (FD_STEP * lu, FD_STEP * lv);
        // J holds R_k (≤ 1) and N_k (P_k − c) / W (≤ 2 max|P| / min w).
        let w_min = s.weights().iter().fold(f64::INFINITY, |m, &w| m.min(w));
        let size = 2.0 * max_abs(s.control_points()) / w_min;
        for four in [false, true] {
            let value = |x: f64, y: f64| local_blocks(&s, x, y, four, Deriv::Value);
            let exact = |d: Deriv| local_blocks(&s, u, v, four, d);
            check_scaled(&diff1(|x| value(x, v), u, hu), &exact(Deriv::U), size / lu, FD_RATIONAL, "J_u")?;
            check_scaled(&diff1(|y| value(u, y), v, hv), &exact(Deriv::V), size / lv, FD_RATIONAL, "J_v")?;
            check_scaled(&diff2(|x| value(x, v), u, hu), &exact(Deriv::UU), size / (lu * lu), FD_RATIONAL, "J_uu")?;
            check_scaled(&diff_mixed(value, u, v, hu, hv), &exact(Deriv::UV), size / (lu * lv), FD_RATIONAL, "J_uv")?;
            check_scaled(&diff2(|y| value(u, y), v, hv), &exact(Deriv::VV), size / (lv * lv), FD_RATIONAL, "J_vv")?;
        }
        // ∂c/∂w_k = N_k (P_k − c) / W vs a difference in w_k (c is smooth in w_k > 0).
        let j = s.jacobian(u, v, 0, true).unwrap();
        let l = pick.index(j.n_local());
        let k = j.indices[l];
        let at = |w: f64| {
            let mut ws = s.weights().to_vec();
            ws[k] = w;
            s.with_control_points_and_weights(s.control_points().to_vec(), ws).unwrap().point(u, v).unwrap().to_vec()
        };
        let wk = s.weights()[k];
        // c is a Möbius function of w_k with its pole at relative distance W / (N_k w_k) ≥ 1.
        let fd = diff1(at, wk, 1e-2 * wk);
        let size = max_abs(s.control_points()) / wk;
        check_scaled(&fd, &j.column(l, 3, Deriv::Value), size, FD_RATIONAL, "∂c/∂w_k")?;
    }

    /// Curves: `J p = c`, `J' p = c'`, `J'' p = c''` with 3 and 4 dofs.
    #[test]
    fn curve_jacobian(c in arb_curve(4, true, 4.0), t in 0.0..=1.0f64) {
        let (a, b) = c.domain();
        let u = (a + t * (b - a)).min(b);
        let d = c.derivatives(u, 2).unwrap();
        let len = c.basis().knots().nonempty_spans().iter().fold(f64::INFINITY, |m, &(_, a, b)| m.min(b - a));
        let size = max_abs(c.control_points());
        for four in [false, true] {
            let j = c.jacobian(u, 2, four).unwrap();
            let p = generalized(c.control_points(), c.weights(), four);
            check_scaled(&j.apply(Deriv::Value, &p), &d.point, size, ROUNDOFF, "J p")?;
            check_scaled(&j.apply(Deriv::U, &p), &d.u, size / len, ROUNDOFF, "J' p")?;
            check_scaled(&j.apply(Deriv::UU, &p), &d.uu, size / (len * len), ROUNDOFF, "J'' p")?;
            prop_assert_eq!(j.apply(Deriv::V, &p), [0.0; 3]);
        }
    }
}

// ---- quadrature -----------------------------------------------------------------------------

proptest! {
    #![proptest_config(config())]

    /// The g-point rule mapped to [a, b] integrates every polynomial of degree ≤ 2g − 1
    /// exactly (relative to ∫|f|).
    #[test]
    fn gauss_exact_for_degree_2g_minus_1(
        g in 1usize..=12,
        a in -3.0..3.0f64, len in 0.1..4.0f64,
        coefficients in prop::collection::vec(-1.0..1.0f64, 24),
    ) {
        let b = a + len;
        let rule = GaussLegendre::new(g).unwrap();
        let deg = 2 * g - 1;
        let cs = &coefficients[..=deg];
        // Shifted monomials (x − a)^k keep the exact integral well conditioned.
        let f = |x: f64| cs.iter().enumerate().map(|(k, c)| c * (x - a).powi(k as i32)).sum::<f64>();
        let got: f64 = rule.mapped(a, b).map(|(x, w)| w * f(x)).sum();
        let exact: f64 = cs.iter().enumerate().map(|(k, c)| c * len.powi(k as i32 + 1) / (k as f64 + 1.0)).sum();
        let scale: f64 = cs.iter().enumerate().map(|(k, c)| c.abs() * len.powi(k as i32 + 1) / (k as f64 + 1.0)).sum();
        prop_assert!((got - exact).abs() <= QUADRATURE * scale.max(f64::MIN_POSITIVE), "g = {g}: {got} vs {exact}");
    }

    /// surface_rule and curve_rule integrate `u^i v^j` (i, j ≤ 2g − 1) exactly over the
    /// domain, element by element.
    #[test]
    fn tensor_rules_exact(ku in arb_knots(3, 5), kv in arb_knots(3, 5), g in 1usize..=5) {
        let (bu, bv) = (BSplineBasis::new(ku.clone()), BSplineBasis::new(kv.clone()));
        let ((u0, u1), (v0, v1)) = (ku.domain(), kv.domain());
        let rule = surface_rule(&bu, &bv, g).unwrap();
        let line = curve_rule(&bu, g).unwrap();
        prop_assert_eq!(rule.len(), ku.nonempty_spans().len() * kv.nonempty_spans().len());
        for i in 0..2 * g {
            let exact_u = (u1 - u0).powi(i as i32 + 1) / (i as f64 + 1.0);
            let got_u: f64 = line.iter().flat_map(|e| &e.points).map(|q| q.weight * (q.u - u0).powi(i as i32)).sum();
            prop_assert!((got_u - exact_u).abs() <= QUADRATURE * exact_u, "curve i = {i}");
            for j in 0..2 * g {
                let exact = exact_u * (v1 - v0).powi(j as i32 + 1) / (j as f64 + 1.0);
                let got: f64 = rule
                    .iter()
                    .flat_map(|e| &e.points)
                    .map(|q| q.weight * (q.u - u0).powi(i as i32) * (q.v - v0).powi(j as i32))
                    .sum();
                prop_assert!((got - exact).abs() <= QUADRATURE * exact, "i = {i}, j = {j}: {got} vs {exact}");
            }
        }
    }
}

#[test]
fn support_geometry_is_valid() {
    // The closed-form surfaces used across the tests build.
    let _: NurbsCurve = reference_curve();
    let _: KnotVector = KnotVector::try_new(REF_KU.to_vec(), 3).unwrap();
    assert_eq!(reference_surface(true).n_control_points(), 28);
}
