//! Unit tests of `refine`.

use super::*;

fn ex51() -> KnotVector {
    KnotVector::try_new(vec![0., 0., 0., 0., 1., 2., 3., 4., 5., 5., 5., 5.], 3).unwrap()
}

#[test]
fn sparse_row_merge() {
    let mut a = Row(vec![(0, 1.0), (2, 2.0)]);
    a.add_scaled(2.0, &Row(vec![(1, 1.0), (2, 1.0), (5, 1.0)]));
    assert_eq!(a.0, vec![(0, 1.0), (1, 2.0), (2, 4.0), (5, 2.0)]);
    let l = Row::lerp(0.25, &Row::unit(3), &Row::unit(1));
    assert_eq!(l.0, vec![(1, 0.75), (3, 0.25)]);
}

#[test]
fn insertion_errors() {
    let u = ex51();
    for bad in [0.0, 5.0, -1.0, 6.0, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(
                insert_knot(&u, bad, 1),
                Err(GeomError::InvalidInsertion { .. })
            ),
            "{bad}"
        );
    }
    assert!(insert_knot(&u, 2.0, 2).is_ok());
    assert!(matches!(
        insert_knot(&u, 2.0, 3),
        Err(GeomError::InvalidInsertion { .. })
    ));
    assert!(matches!(
        refine_knots(&u, &[2.5, 2.5, 2.5, 2.5]),
        Err(GeomError::InvalidInsertion { .. })
    ));
    assert!(matches!(
        refine_knots(&u, &[1.0, 1.0, 1.0]),
        Err(GeomError::InvalidInsertion { .. })
    ));
    assert!(refine_knots(&u, &[1.0, 1.0, 2.5]).is_ok());
    let msg = insert_knot(&u, 7.0, 1).unwrap_err().to_string();
    assert!(msg.contains('7') && msg.contains("(0, 5)"), "{msg}");
}

#[test]
fn insertion_equals_refinement() {
    let u = ex51();
    for (x, times) in [(2.5, 1), (2.5, 3), (2.0, 2), (0.5, 1), (4.5, 2)] {
        let (k1, c1) = insert_knot(&u, x, times).unwrap();
        let (k2, c2) = refine_knots(&u, &vec![x; times]).unwrap();
        assert_eq!(k1, k2);
        let (d1, d2) = (c1.to_dense(), c2.to_dense());
        for (a, b) in d1.iter().zip(&d2) {
            assert!((a - b).abs() < 1e-15, "{x} x{times}: {a} vs {b}");
        }
    }
}

#[test]
fn elevation_errors_and_identity() {
    let unclamped = KnotVector::try_new((0..8).map(f64::from).collect(), 3).unwrap();
    assert!(matches!(
        elevate_degree(&unclamped, 1),
        Err(GeomError::UnsupportedKnots { .. })
    ));
    let broken = KnotVector::try_new(vec![0., 0., 0.5, 0.5, 1., 1.], 1).unwrap();
    assert!(matches!(
        elevate_degree(&broken, 1),
        Err(GeomError::UnsupportedKnots { .. })
    ));
    let (k, c) = elevate_degree(&ex51(), 0).unwrap();
    assert_eq!(k, ex51());
    assert_eq!(c, RefinementMatrix::identity(8));
}

#[test]
fn elevation_knots_gain_multiplicity() {
    let u = KnotVector::try_new(vec![0., 0., 0., 0., 1., 2., 2., 3., 3., 3., 3.], 3).unwrap();
    let (k, c) = elevate_degree(&u, 2).unwrap();
    assert_eq!(
        k.knots(),
        &[
            0., 0., 0., 0., 0., 0., 1., 1., 1., 2., 2., 2., 2., 3., 3., 3., 3., 3., 3.
        ]
    );
    assert_eq!((c.nrows, c.ncols), (13, 7));
    for s in c.row_sums() {
        assert!((s - 1.0).abs() < 1e-14);
    }
}

#[test]
fn matrix_algebra() {
    let (_, c) = refine_uniform(&ex51(), 1).unwrap();
    let t = c.transpose();
    assert_eq!(t.transpose(), c);
    let x: Vec<f64> = (0..c.ncols).map(|i| i as f64 * 0.5 - 1.0).collect();
    let y: Vec<f64> = (0..c.nrows).map(|i| (i as f64).sin()).collect();
    let lhs: f64 = c.apply_to(&x).iter().zip(&y).map(|(a, b)| a * b).sum();
    let rhs: f64 = c
        .apply_transpose(&y)
        .iter()
        .zip(&x)
        .map(|(a, b)| a * b)
        .sum();
    assert!((lhs - rhs).abs() < 1e-13);
    let i3 = c.kron_identity(3);
    assert_eq!(
        (i3.nrows, i3.ncols, i3.nnz()),
        (3 * c.nrows, 3 * c.ncols, 3 * c.nnz())
    );
    assert_eq!(i3.get(3 * 4 + 2, 3 * 3 + 2), c.get(4, 3));
    assert_eq!(RefinementMatrix::identity(c.nrows).compose(&c), c);
}
