//! Greville abscissae `ξ_i = (u_{i+1} + … + u_{i+p}) / p` by hand, and the linear precision
//! they exist for: `Σ_i ξ_i N_i(u) = u`.

mod support;

use nurbspring_geom::{BSplineBasis, KnotVector};
use support::{ROUNDOFF, assert_close};

#[test]
fn greville_abscissae_by_hand() {
    // Cubic, non-uniform: (0+0+0)/3, (0+0+.3)/3, (0+.3+.7)/3, (.3+.7+1)/3, (.7+1+1)/3, (1+1+1)/3.
    let k = KnotVector::try_new(vec![0., 0., 0., 0., 0.3, 0.7, 1., 1., 1., 1.], 3).unwrap();
    assert_close(
        &k.greville(),
        &[0.0, 0.1, 1.0 / 3.0, 2.0 / 3.0, 0.9, 1.0],
        ROUNDOFF,
        "cubic",
    );
    // Quadratic on [2, 6] with a double interior knot: (u1+u2)/2 …
    let k = KnotVector::try_new(vec![2., 2., 2., 3., 3., 5., 6., 6., 6.], 2).unwrap();
    assert_close(
        &k.greville(),
        &[2.0, 2.5, 3.0, 4.0, 5.5, 6.0],
        ROUNDOFF,
        "quadratic",
    );
    // Linear: the interior knots themselves.
    let k = KnotVector::try_new(vec![0., 0., 0.25, 0.5, 1., 1.], 1).unwrap();
    assert_close(&k.greville(), &[0.0, 0.25, 0.5, 1.0], ROUNDOFF, "linear");
    // Unclamped uniform cubic: ξ_i = i + 2 on knots 0 … 7.
    let k = KnotVector::try_new((0..8).map(f64::from).collect(), 3).unwrap();
    assert_close(&k.greville(), &[2.0, 3.0, 4.0, 5.0], ROUNDOFF, "unclamped");
}

#[test]
fn greville_abscissae_reproduce_the_parameter() {
    for (knots, p) in [
        (vec![0., 0., 0., 0., 0.3, 0.7, 1., 1., 1., 1.], 3),
        (vec![2., 2., 2., 3., 3., 5., 6., 6., 6.], 2),
        (vec![0., 0., 0., 0., 0., 0.5, 1., 1., 1., 1., 1.], 4),
    ] {
        let k = KnotVector::try_new(knots, p).unwrap();
        let g = k.greville();
        let (a, b) = k.domain();
        let basis = BSplineBasis::new(k);
        for s in 0..=20 {
            let u = a + (b - a) * s as f64 / 20.0;
            let n = basis.all_values(u).unwrap();
            let x: f64 = n.iter().zip(&g).map(|(ni, xi)| ni * xi).sum();
            assert_close(&[x], &[u], ROUNDOFF, "Σ ξ_i N_i(u) = u");
        }
    }
}

/// A decreasing knot vector is refused naming both knots; derivative slots have their order.
#[test]
fn decreasing_knots_are_named_and_slots_have_orders() {
    match nurbspring_geom::KnotVector::try_new(vec![0.0, 0.0, 0.5, 0.25, 1.0, 1.0], 1) {
        Err(nurbspring_geom::GeomError::DecreasingKnots {
            index,
            value,
            prev_index,
            prev,
        }) => assert_eq!((index, value, prev_index, prev), (3, 0.25, 2, 0.5)),
        other => panic!("expected DecreasingKnots, got {other:?}"),
    }
    use nurbspring_geom::Deriv;
    let orders: Vec<usize> = Deriv::ALL.iter().map(|d| d.order()).collect();
    assert_eq!(orders, vec![0, 1, 1, 2, 2, 2]);
}
