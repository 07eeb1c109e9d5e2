//! Linear isotropic elements: forces and stiffness against finite differences, the split into
//! classes, the Greville fixing rule, and the continuum limit of the stencil weights.

mod support;

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use nurbspring_msm::{
    Class, Constants, FixedNodes, LatticeOptions, LinearKind, MsmFile, MsmModel, ParameterGrid,
    Region, SpringKind, SpringLattice,
};
use nurbspring_sim::DynamicModel;
use support::{Lcg, curved_surface, relative_error};

/// The energy is quadratic, so central differences are exact up to round-off
/// (ε |E| / h ≈ 1e-11 at h = 1e-5 on O(1) values).
const FD_QUADRATIC: f64 = 1e-8;

/// Every linear class with distinct constants, plus structural springs when `springs`.
fn all_linear(springs: bool) -> Constants {
    let mut c = Constants::new();
    for (i, class) in Class::linear(&LinearKind::ALL).into_iter().enumerate() {
        c.set(class, 0.3 + 0.17 * i as f64);
    }
    if springs {
        c.set(Class::Spring(SpringKind::Structural), 2.0);
    }
    c
}

fn lattice(springs: bool, fixed: Vec<usize>) -> SpringLattice {
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 5,
            nodes_v: 4,
        },
        constants: all_linear(springs),
        fixed: FixedNodes::List(fixed),
        ..LatticeOptions::default()
    };
    SpringLattice::from_surface(&curved_surface(), &options, &[]).unwrap()
}

#[test]
fn element_counts_and_regions() {
    let l = lattice(false, vec![0, 1, 2, 3]);
    let count = |kind| {
        Region::ALL
            .iter()
            .map(|&r| l.count(Class::Linear(kind, r)))
            .sum::<usize>()
    };
    // 5 × 4 nodes: 4·4 springs along u, 5·3 along v, 2·4·3 diagonals, 3·4 bending along u,
    // 5·2 along v, 4·3 twist cells, 2·4 third differences along u, 5·1 along v.
    assert_eq!(count(LinearKind::SpringU), 16);
    assert_eq!(count(LinearKind::SpringV), 15);
    assert_eq!(count(LinearKind::Diagonal), 24);
    assert_eq!(count(LinearKind::BendU), 12);
    assert_eq!(count(LinearKind::BendV), 10);
    assert_eq!(count(LinearKind::Twist), 12);
    assert_eq!(count(LinearKind::ThirdU), 8);
    assert_eq!(count(LinearKind::ThirdV), 5);
    // Row i = 0 (nodes 0..3) is fixed: exactly the elements touching it are boundary ones.
    for e in &l.elements {
        let touches = e.nodes.iter().any(|&a| a < 4);
        assert_eq!(e.region == Region::Boundary, touches, "{e:?}");
    }
    // Stencils annihilate constants; second differences annihilate linear functions.
    for e in &l.elements {
        let sum: f64 = e.coefficients.iter().sum();
        let scale: f64 = e.coefficients.iter().map(|c| c.abs()).sum();
        assert!(sum.abs() <= 1e-14 * scale, "{e:?}");
    }
}

#[test]
fn forces_and_stiffness_match_finite_differences() {
    for springs in [false, true] {
        let l = lattice(springs, vec![0, 5, 19]);
        let model = MsmModel::new(l.clone()).unwrap();
        let mut q = model.initial_positions().to_vec();
        Lcg(7).perturb(&mut q, 0.05);
        let n = q.len();
        let h = 1e-5;
        let mut f = vec![0.0; n];
        model.internal_force(&q, &mut f);
        let mut fd = vec![0.0; n];
        let mut col_err: f64 = 0.0;
        let k = model.tangent_stiffness(&q).to_dense();
        for i in 0..n {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[i] += h;
            qm[i] -= h;
            fd[i] = (model.potential_energy(&qp) - model.potential_energy(&qm)) / (2.0 * h);
            let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
            model.internal_force(&qp, &mut fp);
            model.internal_force(&qm, &mut fm);
            let column: Vec<f64> = (0..n).map(|r| (fp[r] - fm[r]) / (2.0 * h)).collect();
            let analytic: Vec<f64> = (0..n).map(|r| k[(r, i)]).collect();
            col_err = col_err.max(relative_error(&analytic, &column));
        }
        // The spring part is nonlinear: its central differences carry an h² error.
        let tol = if springs { 1e-6 } else { FD_QUADRATIC };
        assert!(
            relative_error(&f, &fd) <= tol,
            "force vs −∇E: {}",
            relative_error(&f, &fd)
        );
        assert!(col_err <= tol, "stiffness vs ∂f/∂q: {col_err}");
        // All-node forms agree with the model's.
        let x = model.full_positions(&q);
        let mut fe = vec![0.0; 3 * l.n_nodes()];
        l.elastic_forces(&x, &mut fe);
        let restricted = model.dof_map().restrict(&fe);
        let minus: Vec<f64> = restricted.iter().map(|v| -v).collect();
        assert!(relative_error(&minus, &f) <= 1e-13);
    }
}

#[test]
fn tangent_is_the_sum_of_unit_matrices_and_linear_model_is_linear() {
    let l = lattice(false, vec![0]);
    let model = MsmModel::new(l.clone()).unwrap();
    assert!(model.is_linear());
    let q = model.initial_positions().to_vec();
    let k = model.tangent_stiffness(&q);
    let constants = l.constants();
    let mut sum = nurbspring_linalg::SparseMatrix::zeros(k.nrows(), k.ncols());
    for (class, kc) in constants.iter() {
        sum = nurbspring_linalg::SparseMatrix::linear_combination(
            1.0,
            &sum,
            kc,
            &model.unit_stiffness(class, &q),
        )
        .unwrap();
    }
    let diff = nurbspring_linalg::SparseMatrix::linear_combination(1.0, &k, -1.0, &sum).unwrap();
    assert!(diff.frobenius_norm() <= 1e-14 * k.frobenius_norm());
    assert_eq!(model.linear_stiffness().map(|m| m.nnz()), Some(k.nnz()));
    // Isotropic: the stiffness is L ⊗ I₃, so x, y and z blocks are equal and uncoupled.
    let d = k.to_dense();
    for a in 0..k.nrows() / 3 {
        for b in 0..k.nrows() / 3 {
            for (r, c) in [(1, 0), (2, 0), (0, 1), (2, 1), (0, 2), (1, 2)] {
                assert_eq!(d[(3 * a + r, 3 * b + c)], 0.0);
            }
            assert_eq!(d[(3 * a, 3 * b)], d[(3 * a + 2, 3 * b + 2)]);
        }
    }
}

#[test]
fn greville_lattice_fixes_nodes_of_fixed_control_points() {
    let s = curved_surface();
    let options = LatticeOptions {
        grid: ParameterGrid::Greville,
        constants: all_linear(false),
        ..LatticeOptions::default()
    };
    let l = SpringLattice::from_surface(&s, &options, &[0, 1, 2]).unwrap();
    assert_eq!(l.grid, Some((3, 3)));
    let fixed: Vec<usize> = (0..9).filter(|&a| l.fixed[a]).collect();
    assert_eq!(fixed, vec![0, 1, 2]);
}

#[test]
fn msm_json_round_trip_keeps_elements() {
    let l = lattice(true, vec![0, 7]);
    let text = l.to_json_string();
    let back = SpringLattice::from_file(&MsmFile::from_json_str(&text).unwrap()).unwrap();
    assert_eq!(back.elements.len(), l.elements.len());
    for (a, b) in l.elements.iter().zip(&back.elements) {
        assert_eq!((a.kind, a.region, &a.nodes), (b.kind, b.region, &b.nodes));
        assert_eq!((a.k, a.weight), (b.k, b.weight));
        assert_eq!(a.coefficients, b.coefficients);
    }
    let bad = text.replacen("@interior", "@nowhere", 1);
    assert!(SpringLattice::from_json_str(&bad).is_err());
}

/// `f(u, v) = sin πu sin πv` out of the plane of a flat unit square: each class's energy with
/// unit constants against the continuum integral it stands for, on refined lattices (second
/// order: the error falls by about 4 when the spacing halves).
#[test]
fn stencil_weights_tend_to_the_continuum_energies() {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let pts = vec![[0., 0., 0.], [0., 1., 0.], [1., 0., 0.], [1., 1., 0.]];
    let plane = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 4]).unwrap();
    let pi = std::f64::consts::PI;
    let exact = |kind| match kind {
        // ∫∫ f_u², ∫∫ f_v², ∫∫ (f_u² + f_v²), ∫∫ f_uu², ∫∫ f_vv², ∫∫ f_uv².
        LinearKind::SpringU | LinearKind::SpringV => pi * pi / 4.0,
        LinearKind::Diagonal => pi * pi / 2.0,
        // ∫∫ f_uuu², ∫∫ f_vvv².
        LinearKind::ThirdU | LinearKind::ThirdV => pi.powi(6) / 4.0,
        _ => pi.powi(4) / 4.0,
    };
    for kind in LinearKind::ALL {
        let mut errors = Vec::new();
        for n in [17, 33, 65] {
            let options = LatticeOptions {
                grid: ParameterGrid::Uniform {
                    nodes_u: n,
                    nodes_v: n,
                },
                constants: Constants::from_pairs(
                    Region::ALL.map(|r| (Class::Linear(kind, r), 1.0)),
                ),
                ..LatticeOptions::default()
            };
            let l = SpringLattice::from_surface(&plane, &options, &[]).unwrap();
            let mut x = l.flat_positions();
            for (a, &(u, v)) in l.params.as_ref().unwrap().iter().enumerate() {
                x[3 * a + 2] += (pi * u).sin() * (pi * v).sin();
            }
            let e = 2.0 * l.elastic_energy(&x);
            errors.push((e - exact(kind)).abs() / exact(kind));
        }
        assert!(errors[2] < 2e-3, "{kind:?}: {errors:?}");
        for w in errors.windows(2) {
            let rate = (w[0] / w[1]).log2();
            assert!(rate > 1.8, "{kind:?}: errors {errors:?}, rate {rate}");
        }
    }
}

/// A chain on a straight curve: a string of unit parameter length with `k = α` on the
/// springs has the frequencies of `α f_uu = μ f_tt` discretized by second differences.
#[test]
fn chain_lattice_on_a_curve() {
    let knots = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let curve = NurbsCurve::try_new(knots, vec![[0., 0., 0.], [2., 0., 0.]], vec![1.0; 2]).unwrap();
    let n = 11;
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: n,
            nodes_v: 1,
        },
        constants: Constants::from_pairs(
            Class::linear(&LinearKind::CHAIN)
                .into_iter()
                .map(|c| (c, 1.0)),
        ),
        fixed: FixedNodes::List(vec![0, n - 1]),
        ..LatticeOptions::default()
    };
    let l = SpringLattice::from_curve(&curve, &options, &[]).unwrap();
    assert_eq!(l.grid, Some((n, 1)));
    assert_eq!(
        l.count(Class::Linear(LinearKind::SpringU, Region::Boundary)),
        2
    );
    assert_eq!(
        l.count(Class::Linear(LinearKind::SpringU, Region::Interior)),
        n - 3
    );
    assert_eq!(
        l.count(Class::Linear(LinearKind::BendU, Region::Interior))
            + l.count(Class::Linear(LinearKind::BendU, Region::Boundary)),
        n - 2
    );
    assert!(l.elements.iter().all(|e| e.kind != LinearKind::SpringV));
    // Springs only, mass h per node: ω_j = (2/h) sin(jπh/2) of the discrete string.
    let mut springs_only = l.clone();
    springs_only
        .elements
        .retain(|e| e.kind == LinearKind::SpringU);
    let h = 1.0 / (n - 1) as f64;
    springs_only.set_mass(h);
    let model = MsmModel::new(springs_only).unwrap();
    let q = model.initial_positions().to_vec();
    let kd = model.tangent_stiffness(&q).to_dense();
    let md = model.mass().to_sparse().to_dense();
    let eig = nurbspring_linalg::generalized_symmetric_eigen(&kd, &md).unwrap();
    for j in 1..=3 {
        let expected = 2.0 / h * (j as f64 * std::f64::consts::PI * h / 2.0).sin();
        // Each frequency three times (x, y, z).
        let got = eig.values[3 * (j - 1)].sqrt();
        assert!(
            (got - expected).abs() <= 1e-12 * expected,
            "{j}: {got} vs {expected}"
        );
    }
}

/// On a flat sheet with uneven knots (nodes at u ∈ {0, 0.1, 0.4, 1}, v ∈ {0, 0.25, 1}), the
/// displacement `(f/2, −f/4, f)`, `f = u² + 3v² + 5uv`, has the difference quotients of each element
/// kind exactly: `f_uu = 2`, `f_vv = 6`, `f_uv = 5` for the three-point and four-point
/// stencils (exact for quadratics at any spacing), and the plain difference `f_b − f_a` for
/// springs. Each element's weight is its share of the domain by hand (dual spacings
/// τ_u = (0.05, 0.2, 0.45, 0.3), τ_v = (0.125, 0.5, 0.375)), and its energy `½ k w |s|²`
/// with `|s|² = (1/4 + 1/16 + 1) s_z²`.
#[test]
fn stencils_on_uneven_spacing_are_exact_for_quadratics() {
    let ku = KnotVector::try_new(vec![0., 0., 0.1, 0.4, 1., 1.], 1).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0.25, 1., 1.], 1).unwrap();
    let (us, vs) = ([0.0, 0.1, 0.4, 1.0], [0.0, 0.25, 1.0]);
    let mut pts = Vec::new();
    for &u in &us {
        for &v in &vs {
            pts.push([u, v, 0.0]);
        }
    }
    let plane = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 12]).unwrap();
    let options = LatticeOptions {
        grid: ParameterGrid::Knots,
        constants: all_linear(false),
        ..LatticeOptions::default()
    };
    let l = SpringLattice::from_surface(&plane, &options, &[]).unwrap();
    assert_eq!(l.grid, Some((4, 3)));
    let f = |u: f64, v: f64| u * u + 3.0 * v * v + 5.0 * u * v;
    let params = l.params.clone().unwrap();
    let mut disp = vec![0.0; 3 * l.n_nodes()];
    for (a, &(u, v)) in params.iter().enumerate() {
        // Out of the plane, half as much along x and a quarter against y (powers of two, so
        // the components' ratios are exact): every component of a strain is seen.
        disp[3 * a] = 0.5 * f(u, v);
        disp[3 * a + 1] = -0.25 * f(u, v);
        disp[3 * a + 2] = f(u, v);
    }
    let (tau_u, tau_v) = ([0.05, 0.2, 0.45, 0.3], [0.125, 0.5, 0.375]);
    // Node a = i·3 + j sits at (us[i], vs[j]).
    let ij = |a: usize| (a / 3, a % 3);
    let mut counts = [0usize; 8];
    for e in &l.elements {
        let n = &e.nodes;
        let (i, j) = ij(n[0]);
        let (expected_strain, expected_weight) = match e.kind {
            LinearKind::SpringU | LinearKind::SpringV | LinearKind::Diagonal => {
                let ((ua, va), (ub, vb)) = (params[n[0]], params[n[1]]);
                let (du, dv) = (ub - ua, vb - va);
                let w = match e.kind {
                    LinearKind::SpringU => tau_v[j] / du,
                    LinearKind::SpringV => tau_u[i] / dv,
                    _ => (du * dv / (du * du + dv * dv)).abs(),
                };
                (f(ua, va) - f(ub, vb), w)
            }
            LinearKind::BendU => (2.0, tau_u[ij(n[1]).0] * tau_v[j]),
            LinearKind::BendV => (6.0, tau_u[i] * tau_v[ij(n[1]).1]),
            LinearKind::Twist => {
                let (i1, j1) = ij(n[3]);
                (5.0, (us[i1] - us[i]) * (vs[j1] - vs[j]))
            }
            // A quadratic has no third derivative. The one stencil along u (nodes 0..3 of four)
            // covers all three intervals: its weight is the whole extent 1 times τ_v.
            LinearKind::ThirdU => (0.0, tau_v[j]),
            LinearKind::ThirdV => unreachable!("three nodes along v have no third difference"),
        };
        counts[LinearKind::ALL.iter().position(|&k| k == e.kind).unwrap()] += 1;
        let s = e.strain(&disp);
        assert_eq!((s[0], s[1]), (0.5 * s[2], -0.25 * s[2]));
        // The round-off of `Σ c_i f_i`: the third differences' coefficients reach 10³ here.
        let roundoff: f64 = n
            .iter()
            .zip(&e.coefficients)
            .map(|(&a, c)| (c * disp[3 * a + 2]).abs())
            .sum();
        let scale = expected_strain.abs().max(1.0).max(roundoff);
        assert!(
            (s[2] - expected_strain).abs() <= 1e-13 * scale,
            "{:?} at {n:?}: strain {}, by hand {expected_strain}",
            e.kind,
            s[2]
        );
        assert!(
            (e.weight - expected_weight).abs() <= 1e-15 * expected_weight,
            "{:?} at {n:?}: weight {}, by hand {expected_weight}",
            e.kind,
            e.weight
        );
        let energy = 0.5 * e.k * expected_weight * 1.3125 * expected_strain * expected_strain;
        assert!((e.energy(&disp) - energy).abs() <= 1e-12 * energy.max(1e-12));
    }
    // spring_u 3·3, spring_v 4·2, diagonal 2·3·2, bend_u 2·3, bend_v 4·1, twist 3·2,
    // third_u 1·3, third_v none (three nodes along v).
    assert_eq!(counts, [9, 8, 12, 6, 4, 6, 3, 0]);
}

/// The third-difference stencils on uneven spacing (nodes at u ∈ {0, 0.1, 0.4, 0.5, 1},
/// v ∈ {0, 0.3, 0.35, 0.8, 1}) give the third derivatives of a cubic exactly:
/// `f = u³ − 2v³ + 3u²v + uv² + u²`, `f_uuu = 6`, `f_vvv = −12`, at any spacing.
#[test]
fn third_differences_are_exact_for_cubics() {
    let ku = KnotVector::try_new(vec![0., 0., 0.1, 0.4, 0.5, 1., 1.], 1).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0.3, 0.35, 0.8, 1., 1.], 1).unwrap();
    let (us, vs) = ([0.0, 0.1, 0.4, 0.5, 1.0], [0.0, 0.3, 0.35, 0.8, 1.0]);
    let mut pts = Vec::new();
    for &u in &us {
        for &v in &vs {
            pts.push([u, v, 0.0]);
        }
    }
    let plane = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 25]).unwrap();
    let options = LatticeOptions {
        grid: ParameterGrid::Knots,
        constants: Constants::from_pairs(
            Class::linear(&[LinearKind::ThirdU, LinearKind::ThirdV])
                .into_iter()
                .map(|c| (c, 1.0)),
        ),
        ..LatticeOptions::default()
    };
    let l = SpringLattice::from_surface(&plane, &options, &[]).unwrap();
    let f = |u: f64, v: f64| u.powi(3) - 2.0 * v.powi(3) + 3.0 * u * u * v + u * v * v + u * u;
    let params = l.params.clone().unwrap();
    let mut disp = vec![0.0; 3 * l.n_nodes()];
    for (a, &(u, v)) in params.iter().enumerate() {
        disp[3 * a + 2] = f(u, v);
    }
    // 5 × 5 nodes: 2 · 5 stencils along each direction.
    assert_eq!(l.elements.len(), 20);
    for e in &l.elements {
        let expected = if e.kind == LinearKind::ThirdU {
            6.0
        } else {
            -12.0
        };
        let s = e.strain(&disp)[2];
        assert!((s - expected).abs() <= 1e-11, "{e:?}: {s}");
        // Constants and linear functions are annihilated too (the strain of f is exact).
        let sum: f64 = e.coefficients.iter().sum();
        assert!(sum.abs() <= 1e-12 * e.coefficients[0].abs(), "{e:?}");
    }
}
