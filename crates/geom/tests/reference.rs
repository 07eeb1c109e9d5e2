//! Known values: The NURBS Book examples and values printed by geomdl 5.4.0 (NURBS-Python)
//! and splipy 1.10.1 for the geometries of `tests/data/reference_values.py` (the script that
//! generated `tests/data/reference_values.rs`; Python is not run by the tests).

mod support;

#[rustfmt::skip]
#[path = "data/reference_values.rs"]
mod data;

use nurbspring_geom::{
    BSplineBasis, Deriv, KnotVector, elevate_degree, insert_knot, refine_knots, to_homogeneous,
};
use support::*;

fn flat4(v: &[[f64; 4]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

/// The NURBS Book Ex. 5.1: cubic, `U = {0,0,0,0,1,2,3,4,5,5,5,5}`, insert `u = 5/2` once
/// (span k = 5). `Q_i = α_i P_i + (1 − α_i) P_{i−1}` with `α_3 = 5/6, α_4 = 1/2, α_5 = 1/6`
/// (the book indexes the three new points i = k − p + 1 … k = 3, 4, 5); `Q_0..2 = P_0..2`,
/// `Q_6..8 = P_5..7`.
#[test]
fn nurbs_book_example_5_1() {
    let u = KnotVector::try_new(vec![0., 0., 0., 0., 1., 2., 3., 4., 5., 5., 5., 5.], 3).unwrap();
    let (new, c) = insert_knot(&u, 2.5, 1).unwrap();
    assert_eq!(
        new.knots(),
        &[0., 0., 0., 0., 1., 2., 2.5, 3., 4., 5., 5., 5., 5.]
    );
    let mut expected = vec![0.0; 9 * 8];
    for i in 0..3 {
        expected[i * 8 + i] = 1.0;
    }
    for (i, alpha) in [(3, 5.0 / 6.0), (4, 0.5), (5, 1.0 / 6.0)] {
        expected[i * 8 + i] = alpha;
        expected[i * 8 + i - 1] = 1.0 - alpha;
    }
    for i in 6..9 {
        expected[i * 8 + i - 1] = 1.0;
    }
    assert_close(&c.to_dense(), &expected, MATRIX_ENTRY, "Ex. 5.1 matrix");
    // Refinement (A5.4) gives the same matrix.
    let (new4, c4) = refine_knots(&u, &[2.5]).unwrap();
    assert_eq!(new4, new);
    assert_close(&c4.to_dense(), &expected, MATRIX_ENTRY, "Ex. 5.1 by A5.4");
}

/// Inserting a knot up to multiplicity p makes the curve interpolate a control point there:
/// at a knot of multiplicity p the curve point is a control point.
#[test]
fn full_multiplicity_insertion_interpolates() {
    let c = reference_curve();
    let (fine, _) = c.insert_knot(0.4, 3).unwrap();
    let k = fine.basis().knots().knots();
    let first = k.iter().position(|&x| x == 0.4).unwrap();
    // With u = u_{first} of multiplicity p the point is Q_{first − 1}.
    assert_close3(
        fine.control_points()[first - 1],
        c.point(0.4).unwrap(),
        ROUNDOFF,
        "c(0.4) = Q",
    );
}

#[test]
fn basis_matches_splipy() {
    let basis = BSplineBasis::new(KnotVector::try_new(REF_KU.to_vec(), 3).unwrap());
    for (t, rows) in data::SPLIPY_BASIS_KU {
        let (span, d) = basis.derivatives(*t, 2).unwrap();
        for (order, row) in rows.iter().enumerate() {
            let mut full = [0.0; 7];
            for a in 0..4 {
                full[span - 3 + a] = d[order * 4 + a];
            }
            assert_close(&full, row, REFERENCE, &format!("N^({order}) at {t}"));
        }
        assert_close(
            &basis.all_values(*t).unwrap(),
            &rows[0],
            REFERENCE,
            "all_values",
        );
    }
}

#[test]
fn basis_derivatives_match_geomdl() {
    let basis = BSplineBasis::new(KnotVector::try_new(REF_KV.to_vec(), 2).unwrap());
    for (t, span, rows) in data::GEOMDL_BASIS_DERS_KV {
        let (s, d) = basis.derivatives(*t, 2).unwrap();
        assert_eq!(s, *span);
        assert_close(&d, &rows.concat(), REFERENCE, &format!("A2.3 at {t}"));
    }
}

fn check_surface(rational: bool, table: &[(f64, f64, [[f64; 3]; 6])], slots: usize, who: &str) {
    let s = reference_surface(rational);
    for (u, v, expected) in table {
        let d = s.derivatives(*u, *v, 2).unwrap();
        for (slot, e) in Deriv::ALL.iter().zip(expected).take(slots) {
            assert_close3(
                d.get(*slot),
                *e,
                REFERENCE,
                &format!("{who} {} at ({u}, {v})", slot.name()),
            );
        }
        assert_close3(s.point(*u, *v).unwrap(), expected[0], REFERENCE, "point()");
    }
}

#[test]
fn surface_matches_geomdl() {
    check_surface(false, data::GEOMDL_SURFACE_POLY, 6, "geomdl");
    check_surface(true, data::GEOMDL_SURFACE_RATIONAL, 6, "geomdl rational");
}

#[test]
fn surface_matches_splipy() {
    check_surface(false, data::SPLIPY_SURFACE_POLY, 6, "splipy");
    let table: Vec<(f64, f64, [[f64; 3]; 6])> = data::SPLIPY_SURFACE_RATIONAL
        .iter()
        .map(|(u, v, e)| (*u, *v, [e[0], e[1], e[2], [0.0; 3], [0.0; 3], [0.0; 3]]))
        .collect();
    check_surface(true, &table, 3, "splipy rational");
}

#[test]
fn rational_curve_matches_geomdl() {
    let c = reference_curve();
    for (u, expected) in data::GEOMDL_CURVE_RATIONAL {
        let d = c.derivatives(*u, 2).unwrap();
        assert_close3(d.point, expected[0], REFERENCE, &format!("C({u})"));
        assert_close3(d.u, expected[1], REFERENCE, &format!("C'({u})"));
        assert_close3(d.uu, expected[2], REFERENCE, &format!("C''({u})"));
    }
}

#[test]
fn knot_insertion_matches_geomdl() {
    let c = reference_curve();
    let (fine, m) = c.insert_knot(0.4, 2).unwrap();
    assert_eq!(
        fine.basis().knots().knots(),
        data::GEOMDL_CURVE_INSERT_KNOTS
    );
    let h = to_homogeneous(fine.control_points(), fine.weights());
    assert_close(
        &flat4(&h),
        &flat4(data::GEOMDL_CURVE_INSERT_POINTS_W),
        REFERENCE,
        "Q^w",
    );
    // And the matrix reproduces them from the old homogeneous points.
    let again = m.apply(&to_homogeneous(c.control_points(), c.weights()));
    assert_close(
        &flat4(&again),
        &flat4(data::GEOMDL_CURVE_INSERT_POINTS_W),
        REFERENCE,
        "C P^w",
    );
}

#[test]
fn degree_elevation_matches_splipy() {
    let c = reference_curve();
    let (up, _) = c.elevate_degree(1).unwrap();
    assert_eq!(up.basis().degree(), 4);
    assert_eq!(up.basis().knots().knots(), data::SPLIPY_CURVE_ELEVATE_KNOTS);
    let h = to_homogeneous(up.control_points(), up.weights());
    assert_close(
        &flat4(&h),
        &flat4(data::SPLIPY_CURVE_ELEVATE_POINTS_W),
        REFERENCE,
        "elevated Q^w",
    );
}

#[test]
fn insertion_matrix_matches_splipy() {
    let ku = KnotVector::try_new(REF_KU.to_vec(), 3).unwrap();
    for (x, expected) in [
        (0.5, data::SPLIPY_INSERT_MATRIX_KU),
        (0.8, data::SPLIPY_INSERT_MATRIX_KU_08),
    ] {
        let (_, c) = insert_knot(&ku, x, 1).unwrap();
        assert_eq!((c.nrows, c.ncols), (8, 7));
        assert_close(
            &c.to_dense(),
            expected,
            REFERENCE,
            &format!("C for u = {x}"),
        );
    }
}

#[test]
fn surface_degree_elevation_matches_splipy() {
    let s = reference_surface(true);
    let (up, c) = s.elevate_degree(1, 1).unwrap();
    assert_eq!(up.basis_u().knots().knots(), data::SPLIPY_ELEVATE_KNOTS_U);
    assert_eq!(up.basis_v().knots().knots(), data::SPLIPY_ELEVATE_KNOTS_V);
    assert_eq!(c.nrows, up.n_control_points());
    let h = to_homogeneous(up.control_points(), up.weights());
    // splipy raises the order by interpolation at Greville points (a linear solve), so its
    // points carry the solve's rounding: compare at REFERENCE relative to the largest value.
    assert_close(
        &flat4(&h),
        &flat4(data::SPLIPY_ELEVATE_POINTS_W),
        REFERENCE,
        "elevated surface",
    );
    // The matrix is E_u ⊗ E_v of the curve matrices.
    let (_, eu) = elevate_degree(s.basis_u().knots(), 1).unwrap();
    let (_, ev) = elevate_degree(s.basis_v().knots(), 1).unwrap();
    assert_eq!(eu.kron(&ev), c);
}
