//! Exact conics from rational quadratics (The NURBS Book §7.5): circles, a sphere octant and a
//! cylinder keep radius 1 to rounding — through refinement and degree elevation too.

mod support;

use nurbspring_geom::{KnotVector, NurbsCurve, linspace};
use support::*;

fn on_unit_circle(c: &NurbsCurve, n: usize, what: &str) {
    for u in linspace(0.0, 1.0, n) {
        let p = c.point(u).unwrap();
        let r = p[0].hypot(p[1]);
        assert!(
            (r - 1.0).abs() <= CONIC_RADIUS,
            "{what}: radius {r} at u = {u} (error {:.2e})",
            r - 1.0
        );
        assert_eq!(p[2], 0.0);
    }
}

#[test]
fn quarter_circle_points_and_curvature() {
    let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
    let c = NurbsCurve::try_new(
        k,
        vec![[1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
        vec![1., W45, 1.],
    )
    .unwrap();
    on_unit_circle(&c, 1001, "quarter circle");
    assert_eq!(c.point(0.0).unwrap(), [1., 0., 0.]);
    assert_eq!(c.point(1.0).unwrap(), [0., 1., 0.]);
    // The midpoint is at 45°.
    let m = c.point(0.5).unwrap();
    assert_close3(m, [W45, W45, 0.0], 2.0 * f64::EPSILON, "c(1/2)");
    for u in linspace(0.0, 1.0, 101) {
        let d = c.derivatives(u, 2).unwrap();
        // Tangent ⟂ radius, curvature |c' × c''| / |c'|³ = 1.
        let dot = d.point[0] * d.u[0] + d.point[1] * d.u[1];
        assert!(dot.abs() <= 4.0 * f64::EPSILON * norm(d.u), "c·c' = {dot}");
        let cross = d.u[0] * d.uu[1] - d.u[1] * d.uu[0];
        let kappa = cross / norm(d.u).powi(3);
        assert!((kappa - 1.0).abs() < 1e-14, "curvature {kappa} at {u}");
    }
}

/// `derivatives_batch` on the full circle: one result per parameter, in order (the knots at
/// quarters interpolate (1, 0), (0, 1), (−1, 0), (0, −1)), every point on the unit circle,
/// tangent ⟂ radius and curvature 1.
#[test]
fn full_circle_derivatives_in_a_batch() {
    let c = full_circle();
    let us = linspace(0.0, 1.0, 201);
    let batch = c.derivatives_batch(&us, 2).unwrap();
    assert_eq!(batch.len(), us.len());
    for (k, quarter) in [
        [1., 0., 0.],
        [0., 1., 0.],
        [-1., 0., 0.],
        [0., -1., 0.],
        [1., 0., 0.],
    ]
    .iter()
    .enumerate()
    {
        assert_close3(
            batch[50 * k].point,
            *quarter,
            CONIC_RADIUS,
            "c at a quarter",
        );
    }
    for (d, &u) in batch.iter().zip(&us) {
        let r = d.point[0].hypot(d.point[1]);
        assert!((r - 1.0).abs() <= CONIC_RADIUS, "radius {r} at u = {u}");
        let dot = d.point[0] * d.u[0] + d.point[1] * d.u[1];
        assert!(
            dot.abs() <= 4.0 * f64::EPSILON * norm(d.u),
            "c·c' = {dot} at u = {u}"
        );
        let kappa = (d.u[0] * d.uu[1] - d.u[1] * d.uu[0]) / norm(d.u).powi(3);
        assert!((kappa - 1.0).abs() < 1e-14, "curvature {kappa} at u = {u}");
    }
}

#[test]
fn full_circle_nine_points() {
    let c = full_circle();
    on_unit_circle(&c, 4001, "full circle");
    // Quarter parameters hit the axes exactly.
    for (u, e) in [
        (0.0, [1., 0., 0.]),
        (0.25, [0., 1., 0.]),
        (0.5, [-1., 0., 0.]),
        (0.75, [0., -1., 0.]),
        (1.0, [1., 0., 0.]),
    ] {
        assert_close3(c.point(u).unwrap(), e, f64::EPSILON, "axis point");
    }
    // The angle is monotone in u, and the curve is G1 at the double knots: the unit tangent is
    // continuous across u = 1/4.
    let left = c.derivatives(0.25 - 1e-12, 1).unwrap().u;
    let right = c.derivatives(0.25, 1).unwrap().u;
    let (nl, nr) = (norm(left), norm(right));
    assert_close3(
        [left[0] / nl, left[1] / nl, 0.0],
        [right[0] / nr, right[1] / nr, 0.0],
        1e-11,
        "unit tangent",
    );
}

#[test]
fn circle_survives_refinement_and_elevation() {
    let c = full_circle();
    let (fine, _) = c.refine_uniform(2).unwrap();
    assert_eq!(fine.n_control_points(), 9 + 4 * 3);
    on_unit_circle(&fine, 2001, "refined circle");
    let (cubic, _) = c.elevate_degree(1).unwrap();
    assert_eq!(cubic.basis().degree(), 3);
    assert_eq!(cubic.n_control_points(), 9 + 4); // one more per Bézier segment
    on_unit_circle(&cubic, 2001, "elevated circle");
    let (quartic, _) = fine.elevate_degree(2).unwrap();
    on_unit_circle(&quartic, 2001, "refined then elevated circle");
}

#[test]
fn sphere_octant_has_unit_radius() {
    let s = sphere_octant();
    let (fine, _) = s.refine_uniform(1).unwrap();
    let (up, _) = s.elevate_degree(1, 2).unwrap();
    for (surface, what) in [
        (&s, "octant"),
        (&fine, "refined octant"),
        (&up, "elevated octant"),
    ] {
        let (us, vs, pts) = surface.uniform_grid(41, 41).unwrap();
        for (i, &u) in us.iter().enumerate() {
            for (j, &v) in vs.iter().enumerate() {
                let p = pts[i * vs.len() + j];
                let r = norm(p);
                assert!(
                    (r - 1.0).abs() <= CONIC_RADIUS,
                    "{what}: radius {r} at ({u}, {v})"
                );
                assert!(
                    p.iter().all(|&x| x >= -1e-16),
                    "{what}: left the octant: {p:?}"
                );
                let q = surface.point(u, v).unwrap();
                assert!((norm(q) - 1.0).abs() <= CONIC_RADIUS);
            }
        }
    }
    // Away from the pole the unit normal is ± the position.
    for u in linspace(0.0, 0.9, 7) {
        for v in linspace(0.0, 1.0, 7) {
            let p = s.point(u, v).unwrap();
            let n = s.normal(u, v).unwrap();
            let dot = p[0] * n[0] + p[1] * n[1] + p[2] * n[2];
            assert!((dot.abs() - 1.0).abs() < 1e-14, "n·c = {dot} at ({u}, {v})");
        }
    }
    // The pole row collapses.
    assert_close3(
        s.point(1.0, 0.3).unwrap(),
        [0., 0., 1.],
        f64::EPSILON,
        "pole",
    );
}

#[test]
fn cylinder_has_unit_radius_and_linear_height() {
    let s = cylinder();
    let (fine, _) = s.refine_knots(&[0.1, 0.6], &[0.5]).unwrap();
    for surface in [&s, &fine] {
        for u in linspace(0.0, 1.0, 201) {
            for v in linspace(0.0, 1.0, 11) {
                let d = surface.derivatives(u, v, 2).unwrap();
                let r = d.point[0].hypot(d.point[1]);
                assert!((r - 1.0).abs() <= CONIC_RADIUS, "radius {r} at ({u}, {v})");
                assert!(
                    (d.point[2] - 2.0 * v).abs() <= 1e-15,
                    "z {} at v = {v}",
                    d.point[2]
                );
                assert_close3(d.v, [0., 0., 2.], ROUNDOFF, "c_v");
                assert_close3(d.vv, [0., 0., 0.], ROUNDOFF, "c_vv");
                assert_close3(d.uv, [0., 0., 0.], ROUNDOFF, "c_uv");
            }
        }
    }
}
