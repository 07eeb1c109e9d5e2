//! Ω with weights as unknowns (paper eqs. (14), (18); docs/math.md §2): every column of the
//! stacked Jacobian against central differences of the rational surface point with respect to
//! that coordinate (a control point coordinate or a weight), recomputed from the definition
//! `c = Σ w_k N_k P_k / Σ w_k N_k` through the geometry only.

use nurbspring_dnurbs::Geometry;

use crate::support::{self, tol};

fn params() -> Vec<(f64, f64)> {
    vec![
        (0.0, 0.0),
        (0.17, 0.62),
        (0.5, 0.35),
        (0.83, 0.91),
        (1.0, 0.4),
    ]
}

#[test]
fn omega_weight_columns_match_central_differences_of_the_point() {
    for geometry in [
        Geometry::Surface(support::wavy_rational_patch()),
        Geometry::Curve(support::straight_curve(3, 4, 2.0)),
    ] {
        let params = params();
        let omega = geometry.stacked_jacobian(&params, true).unwrap();
        let p = geometry.coordinates(true);
        assert_eq!(omega.nrows(), 3 * params.len());
        assert_eq!(omega.ncols(), p.len());
        let h = 1e-5;
        let mut worst: f64 = 0.0;
        let mut largest: f64 = 0.0;
        for col in 0..p.len() {
            let shifted = |s: f64| {
                let mut q = p.clone();
                q[col] += s;
                geometry.with_coordinates(&q, true).unwrap()
            };
            let (plus, minus) = (shifted(h), shifted(-h));
            for (a, &(u, v)) in params.iter().enumerate() {
                let (cp, cm) = (plus.point(u, v).unwrap(), minus.point(u, v).unwrap());
                for x in 0..3 {
                    let fd = (cp[x] - cm[x]) / (2.0 * h);
                    let got = omega.get(3 * a + x, col);
                    worst = worst.max((fd - got).abs());
                    largest = largest.max(fd.abs());
                }
            }
        }
        assert!(largest > 0.1, "the weight columns must not all vanish");
        assert!(
            worst < tol::CENTRAL_DIFFERENCE,
            "max |Ω − FD| = {worst:e} (largest entry {largest})"
        );
        // eq. (11): Ω p are the surface points.
        let mut x = vec![0.0; omega.nrows()];
        omega.mul_vec(&p, &mut x);
        for (a, &(u, v)) in params.iter().enumerate() {
            let c = geometry.point(u, v).unwrap();
            for k in 0..3 {
                assert!(
                    (x[3 * a + k] - c[k]).abs() < tol::EXACT_POINT,
                    "{x:?} vs {c:?}"
                );
            }
        }
    }
}

/// eq. (18): `ẋ(0) = Ω ṗ(0)` is the time derivative of the node positions along a motion
/// `p(t) = p + t ṗ` that moves control points and weights together.
#[test]
fn omega_times_velocity_is_the_derivative_of_the_node_positions() {
    let geometry = Geometry::Surface(support::wavy_rational_patch());
    let params = params();
    let omega = geometry.stacked_jacobian(&params, true).unwrap();
    let p = geometry.coordinates(true);
    let pdot: Vec<f64> = (0..p.len())
        .map(|i| 0.3 * ((i as f64) * 0.77).sin() + if i % 4 == 3 { 0.2 } else { 0.0 })
        .collect();
    let mut xdot = vec![0.0; omega.nrows()];
    omega.mul_vec(&pdot, &mut xdot);
    let h = 1e-5;
    let at = |t: f64| {
        let q: Vec<f64> = p.iter().zip(&pdot).map(|(a, b)| a + t * b).collect();
        geometry.with_coordinates(&q, true).unwrap()
    };
    let (plus, minus) = (at(h), at(-h));
    for (a, &(u, v)) in params.iter().enumerate() {
        let (cp, cm) = (plus.point(u, v).unwrap(), minus.point(u, v).unwrap());
        for x in 0..3 {
            let fd = (cp[x] - cm[x]) / (2.0 * h);
            assert!(
                (fd - xdot[3 * a + x]).abs() < tol::CENTRAL_DIFFERENCE,
                "node {a} axis {x}: Ω ṗ = {}, d/dt = {fd}",
                xdot[3 * a + x]
            );
        }
    }
}
