//! Assembled matrices against integrals done by hand, one energy term at a time.
//!
//! A polynomial surface `c(u, v) = (u, v, u² + 3uv + 5v²)` lies in the bicubic spline space on
//! any knots, so its control points follow from the polar forms (blossoms) of the monomials
//! (Marsden's identity), without using the code under test. Because `J^(d) p = c^(d)`
//! (docs/math.md §2), `pᵀ K p = ∫∫ Σ coef |c^(d)|² du dv` and `pᵀ M p = μ ∫∫ |c|²`, which are
//! integrated by hand below. Each β (and α) term is checked alone with a different value
//! (`|c_uu|² = 4`, `|c_uv|² = 9`, `|c_vv|² = 100`), so scaling, dropping or swapping a term
//! changes a checked number. The Gauss rule is exact here (degree ≤ 2p per direction), so the
//! tolerance is round-off.

use nurbspring_dnurbs::{DnurbsOptions, Geometry, Loads, Material, assemble};
use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};

use crate::support::tol;

/// Polar-form coefficients of `1`, `t`, `t²` for basis function `i` of a degree-`p` knot
/// vector: `1`, the mean of `t_{i+1} … t_{i+p}`, and their second elementary symmetric
/// polynomial over `C(p, 2)`.
fn blossoms(k: &KnotVector) -> Vec<(f64, f64)> {
    let p = k.degree();
    let t = k.knots();
    (0..k.n_basis())
        .map(|i| {
            let s = &t[i + 1..=i + p];
            let mean = s.iter().sum::<f64>() / p as f64;
            let mut e2 = 0.0;
            for a in 0..p {
                for b in a + 1..p {
                    e2 += s[a] * s[b];
                }
            }
            (mean, e2 / (p * (p - 1) / 2) as f64)
        })
        .collect()
}

/// The bicubic patch `c = (u, v, u² + 3uv + 5v²)` on non-uniform knots over `[0, 1]²`.
fn quadratic_patch() -> NurbsSurface {
    let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.3, 0.7, 1., 1., 1., 1.], 3).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.4, 1., 1., 1., 1.], 3).unwrap();
    let (bu, bv) = (blossoms(&ku), blossoms(&kv));
    let pts: Vec<[f64; 3]> = bu
        .iter()
        .flat_map(|&(u, u2)| {
            bv.iter()
                .map(move |&(v, v2)| [u, v, u2 + 3.0 * u * v + 5.0 * v2])
        })
        .collect();
    let n = pts.len();
    NurbsSurface::try_new(ku, kv, pts, vec![1.0; n]).unwrap()
}

fn f(u: f64, v: f64) -> f64 {
    u * u + 3.0 * u * v + 5.0 * v * v
}

/// The blossom construction reproduces the polynomial (checks the fixture, not the library).
#[test]
fn the_fixture_is_the_polynomial() {
    let s = quadratic_patch();
    for &(u, v) in &[
        (0.0, 0.0),
        (0.13, 0.9),
        (0.5, 0.5),
        (0.81, 0.27),
        (1.0, 1.0),
    ] {
        let c = s.point(u, v).unwrap();
        assert!((c[0] - u).abs() < tol::EXACT_POINT, "{c:?}");
        assert!((c[1] - v).abs() < tol::EXACT_POINT, "{c:?}");
        assert!((c[2] - f(u, v)).abs() < tol::EXACT_POINT, "{c:?}");
    }
}

/// `pᵀ K p` with one coefficient set to 1 and the others 0, against the integral by hand.
fn energy_of_term(geometry: &Geometry, material: Material, weights_as_dofs: bool) -> f64 {
    let options = DnurbsOptions {
        weights_as_dofs,
        ..DnurbsOptions::default()
    };
    let m = assemble(geometry, &material, &Loads::default(), &options).unwrap();
    let p = geometry.coordinates(weights_as_dofs);
    m.stiffness.quadratic_form(&p)
}

fn assert_rel(name: &str, got: f64, want: f64) {
    assert!(
        ((got - want) / want).abs() < tol::EXACT_INTEGRAL,
        "{name}: pᵀKp = {got}, by hand {want}"
    );
}

#[test]
fn each_stiffness_term_alone_matches_the_integral_by_hand() {
    let g = Geometry::Surface(quadratic_patch());
    let unit = Material::default();
    // |c_u|² = 1 + (2u + 3v)², |c_v|² = 1 + (3u + 10v)², c_uu = 2, c_uv = 3, c_vv = 10 (z only).
    let cases = [
        (
            "alpha11",
            Material {
                alpha11: 1.0,
                ..unit.clone()
            },
            1.0 + 4.0 / 3.0 + 3.0 + 3.0,
        ),
        (
            "alpha22",
            Material {
                alpha22: 1.0,
                ..unit.clone()
            },
            1.0 + 3.0 + 15.0 + 100.0 / 3.0,
        ),
        (
            "beta11",
            Material {
                beta11: 1.0,
                ..unit.clone()
            },
            4.0,
        ),
        (
            "beta12",
            Material {
                beta12: 1.0,
                ..unit.clone()
            },
            9.0,
        ),
        (
            "beta22",
            Material {
                beta22: 1.0,
                ..unit.clone()
            },
            100.0,
        ),
    ];
    for weights_as_dofs in [false, true] {
        for (name, material, want) in &cases {
            assert_rel(
                name,
                energy_of_term(&g, material.clone(), weights_as_dofs),
                *want,
            );
        }
    }
    // All terms at once, with distinct coefficients: the weighted sum of the above.
    let all = Material {
        alpha11: 0.7,
        alpha22: 1.1,
        beta11: 0.013,
        beta12: 0.029,
        beta22: 0.041,
        ..unit
    };
    let want = 0.7 * 25.0 / 3.0 + 1.1 * 157.0 / 3.0 + 0.013 * 4.0 + 0.029 * 9.0 + 0.041 * 100.0;
    assert_rel("all terms", energy_of_term(&g, all, false), want);
}

/// `c = (u, v, uv)`: only the twist term bends it (`c_uu = c_vv = 0`, `c_uv = (0, 0, 1)`).
#[test]
fn the_saddle_uv_has_only_twist_energy() {
    let s = quadratic_patch();
    let ku = s.basis_u().knots().clone();
    let kv = s.basis_v().knots().clone();
    let (bu, bv) = (blossoms(&ku), blossoms(&kv));
    let pts: Vec<[f64; 3]> = bu
        .iter()
        .flat_map(|&(u, _)| bv.iter().map(move |&(v, _)| [u, v, u * v]))
        .collect();
    let g = Geometry::Surface(s.with_control_points(pts).unwrap());
    let unit = Material::default();
    let e = |m: Material| energy_of_term(&g, m, false);
    assert_rel(
        "beta12",
        e(Material {
            beta12: 2.5,
            ..unit.clone()
        }),
        2.5,
    );
    let scale = e(Material {
        beta12: 1.0,
        ..unit.clone()
    });
    for m in [
        Material {
            beta11: 1.0,
            ..unit.clone()
        },
        Material {
            beta22: 1.0,
            ..unit.clone()
        },
    ] {
        let em = e(m);
        assert!(em.abs() < tol::EXACT_INTEGRAL * scale, "{em:e}");
    }
    // |c_u|² = 1 + v², |c_v|² = 1 + u²: 4/3 each.
    assert_rel(
        "alpha11",
        e(Material {
            alpha11: 1.0,
            ..unit.clone()
        }),
        4.0 / 3.0,
    );
    assert_rel(
        "alpha22",
        e(Material {
            alpha22: 1.0,
            ..unit.clone()
        }),
        4.0 / 3.0,
    );
}

/// `pᵀ M p = μ ∫∫ |c|²`, `pᵀ D p = γ ∫∫ |c|²` and `pᵀ f = ∫∫ μ g · c` (gravity, paper eq. (3)).
#[test]
fn mass_damping_and_gravity_match_the_integrals_by_hand() {
    let g = Geometry::Surface(quadratic_patch());
    let material = Material {
        mu: 2.5,
        gamma: 0.4,
        ..Material::default()
    };
    let loads = Loads {
        gravity: [0.3, -0.2, -9.81],
        ..Loads::default()
    };
    let m = assemble(&g, &material, &loads, &DnurbsOptions::default()).unwrap();
    let p = g.coordinates(false);
    // ∫∫ u² + v² + (u² + 3uv + 5v²)² = 1/3 + 1/3 + 1/5 + 6/8 + 19/9 + 30/8 + 5.
    let c2 = 2.0 / 3.0 + 1.0 / 5.0 + 6.0 / 8.0 + 19.0 / 9.0 + 30.0 / 8.0 + 5.0;
    assert_rel("mass", m.mass.quadratic_form(&p), 2.5 * c2);
    assert_rel("damping", m.damping.quadratic_form(&p), 0.4 * c2);
    // ∫∫ c = (1/2, 1/2, 1/3 + 3/4 + 5/3).
    let int_c = [0.5, 0.5, 1.0 / 3.0 + 0.75 + 5.0 / 3.0];
    let want: f64 = (0..3).map(|x| 2.5 * loads.gravity[x] * int_c[x]).sum();
    let got: f64 = m.force.iter().zip(&p).map(|(a, b)| a * b).sum();
    assert!(
        (got - want).abs() < tol::EXACT_INTEGRAL * want.abs(),
        "{got} vs {want}"
    );
}

/// A curve `c(u) = (L u, 0, u²)`: `∫ |c''|² = 4` and `∫ |c'|² = L² + 4/3`.
#[test]
fn curve_z_equals_u_squared_has_the_bending_energy_by_hand() {
    let k = KnotVector::try_new(vec![0., 0., 0., 0., 0.2, 0.55, 1., 1., 1., 1.], 3).unwrap();
    let l = 2.5;
    let pts: Vec<[f64; 3]> = blossoms(&k)
        .iter()
        .map(|&(u, u2)| [l * u, 0.0, u2])
        .collect();
    let n = pts.len();
    let g = Geometry::Curve(NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap());
    let unit = Material::default();
    for weights_as_dofs in [false, true] {
        let e = |m: Material| energy_of_term(&g, m, weights_as_dofs);
        assert_rel(
            "beta11",
            e(Material {
                beta11: 1.0,
                ..unit.clone()
            }),
            4.0,
        );
        assert_rel(
            "alpha11",
            e(Material {
                alpha11: 1.0,
                ..unit.clone()
            }),
            l * l + 4.0 / 3.0,
        );
    }
}

/// The coefficient of each derivative slot `[value, u, v, uu, uv, vv]` (paper eq. (4)).
#[test]
fn stiffness_by_slot_puts_each_coefficient_in_its_slot() {
    let m = Material {
        mu: 9.0,
        gamma: 8.0,
        alpha11: 1.0,
        alpha22: 2.0,
        beta11: 3.0,
        beta12: 4.0,
        beta22: 5.0,
    };
    assert_eq!(m.stiffness_by_slot(), [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
    use nurbspring_geom::Deriv;
    for (slot, want) in [
        (Deriv::U, 1.0),
        (Deriv::V, 2.0),
        (Deriv::UU, 3.0),
        (Deriv::UV, 4.0),
        (Deriv::VV, 5.0),
    ] {
        assert_eq!(m.stiffness_by_slot()[slot as usize], want, "{slot:?}");
    }
}

/// The bending energy `½ ∫∫ Σ coef |c^(d)|²` integrated here from the surface's own derivatives
/// (geometry only, its own 5-point Gauss rule per span; exact for these polynomial integrands).
fn energy_by_quadrature(surface: &NurbsSurface, m: &Material) -> f64 {
    use nurbspring_geom::GaussLegendre;
    let g = GaussLegendre::new(5).unwrap();
    let mut e = 0.0;
    let sq = |a: [f64; 3]| a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    for (_, u0, u1) in surface.basis_u().knots().nonempty_spans() {
        for (_, v0, v1) in surface.basis_v().knots().nonempty_spans() {
            for (u, wu) in g.mapped(u0, u1) {
                for (v, wv) in g.mapped(v0, v1) {
                    let d = surface.derivatives(u, v, 2).unwrap();
                    e += wu
                        * wv
                        * (m.alpha11 * sq(d.u)
                            + m.alpha22 * sq(d.v)
                            + m.beta11 * sq(d.uu)
                            + m.beta12 * sq(d.uv)
                            + m.beta22 * sq(d.vv));
                }
            }
        }
    }
    0.5 * e
}

/// The model's elastic force against central differences of an energy computed without K
/// (`energy_by_quadrature`), and its potential energy against that energy, at a shape away
/// from the rest shape (`p_rest = 0`, nothing fixed).
#[test]
fn internal_force_is_the_gradient_of_an_energy_computed_without_k() {
    use nurbspring_dnurbs::{Constraints, DnurbsModel, RestShape};
    use nurbspring_sim::DynamicModel;
    let surface = quadratic_patch();
    let material = Material {
        alpha11: 0.5,
        alpha22: 0.7,
        beta11: 0.11,
        beta12: 0.05,
        beta22: 0.23,
        ..Material::default()
    };
    let model = DnurbsModel::new(
        Geometry::Surface(surface.clone()),
        material.clone(),
        Loads::default(),
        &Constraints::default(),
        DnurbsOptions {
            rest_shape: RestShape::Zero,
            ..DnurbsOptions::default()
        },
    )
    .unwrap();
    let n = model.n_dofs();
    assert_eq!(n, 3 * surface.n_control_points(), "nothing is fixed");
    let p: Vec<f64> = Geometry::Surface(surface.clone())
        .coordinates(false)
        .iter()
        .enumerate()
        .map(|(i, x)| x + 0.2 * (i as f64 * 0.9).sin())
        .collect();
    let q = model.reduced_coordinates(&p);
    let energy = |q: &[f64]| {
        let pts: Vec<[f64; 3]> = model
            .full_coordinates(q)
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        energy_by_quadrature(&surface.with_control_points(pts).unwrap(), &material)
    };
    let e = energy(&q);
    assert!(
        (model.potential_energy(&q) - e).abs() < tol::EXACT_INTEGRAL * e,
        "{} vs {e}",
        model.potential_energy(&q)
    );
    let mut f = vec![0.0; n];
    model.internal_force(&q, &mut f);
    let scale = f.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let h = 1e-4;
    for i in 0..n {
        let (mut qp, mut qm) = (q.clone(), q.clone());
        qp[i] += h;
        qm[i] -= h;
        // The energy is quadratic: central differences are exact up to round-off ε E / h.
        let fd = (energy(&qp) - energy(&qm)) / (2.0 * h);
        assert!(
            (fd - f[i]).abs() <= tol::ENERGY_DIFFERENCE * scale,
            "dof {i}: ∂E/∂q = {fd}, f_int = {}",
            f[i]
        );
    }
}

/// Virtual work of the loads: `pᵀ f_p = F · c(u₀, v₀) + f_d · ∫∫ c` for the polynomial patch
/// (point load: `f = J(u₀, v₀)ᵀ F` and `J p = c`), against the polynomial by hand; and for a
/// perturbation δp of one control point, `δpᵀ f = F · R_k(u₀, v₀) δP` with the basis value
/// from the points of two shapes.
#[test]
fn point_and_distributed_loads_do_the_work_by_hand() {
    use nurbspring_dnurbs::PointLoad;
    let g = Geometry::Surface(quadratic_patch());
    let (u0, v0) = (0.3, 0.6);
    let force = [1.0, -2.0, 3.0];
    let distributed = [0.5, 0.25, -1.5];
    let loads = Loads {
        distributed,
        point: vec![PointLoad {
            u: u0,
            v: v0,
            force,
        }],
        ..Loads::default()
    };
    let m = assemble(&g, &Material::default(), &loads, &DnurbsOptions::default()).unwrap();
    let p = g.coordinates(false);
    let c0 = [u0, v0, f(u0, v0)];
    let int_c = [0.5, 0.5, 1.0 / 3.0 + 0.75 + 5.0 / 3.0];
    let want: f64 = (0..3)
        .map(|x| force[x] * c0[x] + distributed[x] * int_c[x])
        .sum();
    let got: f64 = m.force.iter().zip(&p).map(|(a, b)| a * b).sum();
    assert!(
        (got - want).abs() < tol::EXACT_INTEGRAL * want.abs(),
        "{got} vs {want}"
    );

    let only_point = Loads {
        point: loads.point.clone(),
        ..Loads::default()
    };
    let f = assemble(
        &g,
        &Material::default(),
        &only_point,
        &DnurbsOptions::default(),
    )
    .unwrap()
    .force;
    let s = quadratic_patch();
    for k in [0, 7, 13, 20] {
        // Moving control point k by e_z moves c(u₀, v₀) by R_k(u₀, v₀) e_z (linear in P).
        let mut pts = s.control_points().to_vec();
        pts[k][2] += 1.0;
        let moved = s.with_control_points(pts).unwrap().point(u0, v0).unwrap();
        let r_k = moved[2] - s.point(u0, v0).unwrap()[2];
        for x in 0..3 {
            assert!(
                (f[3 * k + x] - force[x] * r_k).abs() < tol::EXACT_POINT,
                "point {k} axis {x}: {} vs {}",
                f[3 * k + x],
                force[x] * r_k
            );
        }
    }
}
