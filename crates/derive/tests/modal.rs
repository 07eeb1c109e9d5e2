//! The modal fit on problems whose answer is known.

use nurbspring_derive::{SampledMode, element_priors, mac, modal_fit};
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_linalg::{SparseMatrix, generalized_symmetric_eigen};
use nurbspring_msm::{
    Class, Constants, FixedNodes, LatticeOptions, LinearKind, ParameterGrid, SpringLattice,
};

/// The fit solves its normal equations, whose condition number reaches `W_f² / λ_k`
/// (10⁴ / 10⁻⁵ = 10⁹): round-off times that (measured: 1.5·10⁻⁷ on the stiffness).
const RECOVERY: f64 = 1e-6;

/// The lattice of `recovers_a_synthetic_lattice`: a 1.5 × 1 plane, a uniform 8 × 7 grid with
/// every linear kind, the nodes of two edges fixed.
fn plane_lattice() -> (SpringLattice, Vec<usize>) {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let pts = vec![[0., 0., 0.], [0., 1., 0.], [1.5, 0., 0.], [1.5, 1., 0.]];
    let plane = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 4]).unwrap();
    let (nu, nv) = (8, 7);
    let fixed: Vec<usize> = (0..nu * nv)
        .filter(|a| a / nv == 0 || a % nv == 0)
        .collect();
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: nu,
            nodes_v: nv,
        },
        constants: Constants::from_pairs(
            Class::linear(&LinearKind::ALL)
                .into_iter()
                .map(|c| (c, 1.0)),
        ),
        fixed: FixedNodes::List(fixed.clone()),
        ..LatticeOptions::default()
    };
    let lattice = SpringLattice::from_surface(&plane, &options, &[]).unwrap();
    let free: Vec<usize> = (0..nu * nv).filter(|a| !fixed.contains(a)).collect();
    (lattice, free)
}

/// A lattice whose constants are the consistent ones and whose masses are the references:
/// its own modes fed to the fit give them back (every row and both pulls vanish there, and
/// the calibration factor is 1), and the fit reproduces the modes it fitted.
#[test]
fn recovers_a_synthetic_lattice() {
    let (mut lattice, free) = plane_lattice();
    let slots = [0.0, 1.3, 0.7, 0.02, 0.01, 0.03];
    let priors = element_priors(&lattice, slots, &vec![1.0; lattice.n_nodes()]);
    for (e, p) in lattice.elements.iter_mut().zip(&priors) {
        e.k = p.consistent;
    }
    let masses: Vec<f64> = (0..free.len())
        .map(|i| 1.0 + 0.3 * ((i * 7) % 5) as f64)
        .collect();
    let l = lattice.linear_matrix(None).submatrix(&free, &free);
    let eig = generalized_symmetric_eigen(
        &l.to_dense(),
        &SparseMatrix::from_diagonal(&masses).to_dense(),
    )
    .unwrap();
    let modes: Vec<SampledMode> = (0..free.len())
        .map(|i| SampledMode {
            omega: eig.values[i].sqrt(),
            shape: eig.vectors.column(i),
        })
        .collect();
    let sol = modal_fit(&lattice, &free, &priors, &modes, &masses).unwrap();
    assert!(
        (sol.report.mass_scale - 1.0).abs() < RECOVERY,
        "{}",
        sol.report.mass_scale
    );
    // On a uniform grid the kinds are not independent (the parallelogram law makes the twist
    // stencil a combination of the springs along u, v and the diagonals), so what the modes
    // determine is the stiffness L itself, not each constant.
    let mut fitted = lattice.clone();
    for (e, &k) in fitted.elements.iter_mut().zip(&sol.constants) {
        e.k = k;
    }
    let diff = SparseMatrix::linear_combination(
        1.0,
        &fitted.linear_matrix(None).submatrix(&free, &free),
        -1.0,
        &l,
    )
    .unwrap();
    assert!(
        diff.frobenius_norm() <= RECOVERY * l.frobenius_norm(),
        "{} of {}",
        diff.frobenius_norm(),
        l.frobenius_norm()
    );
    // Elements on fixed nodes only are not fitted.
    for (k, e) in sol.constants.iter().zip(&lattice.elements) {
        if e.nodes.iter().all(|a| !free.contains(a)) {
            assert_eq!(*k, 0.0);
        }
    }
    for (a, b) in sol.masses.iter().zip(&masses) {
        assert!((a - b).abs() <= RECOVERY * b, "{a} vs {b}");
    }
    assert!(sol.report.relative_residual < RECOVERY);
    assert!(sol.report.frequency_residual < RECOVERY);
    assert!(sol.report.worst_fitted_mode < RECOVERY);
    // 6 free lines along u, 5 along v: K = (4, 3) to start with, widened while every fitted
    // mode is reproduced, which it is here up to every mode of the lattice.
    assert!(sol.report.modes >= 12, "{}", sol.report.modes);
    assert_eq!(sol.report.fitted_modes[0], 1);

    // Frequencies no lattice of these kinds has: the reported residual of the eigen-equations,
    // `√(Σ_modes Σ_nodes (L φ/ω² − m φ)² / Σ (m φ)²)` at the fitted constants and the masses
    // before the calibration (the reported masses / mass_scale), recomputed.
    let detuned: Vec<SampledMode> = modes
        .iter()
        .enumerate()
        .map(|(i, m)| SampledMode {
            omega: m.omega * (1.0 + 0.05 * i as f64),
            shape: m.shape.clone(),
        })
        .collect();
    let sol = modal_fit(&lattice, &free, &priors, &detuned, &masses).unwrap();
    let mut fitted = lattice.clone();
    for (e, &k) in fitted.elements.iter_mut().zip(&sol.constants) {
        e.k = k;
    }
    let l = fitted.linear_matrix(None).submatrix(&free, &free);
    let before: Vec<f64> = sol
        .masses
        .iter()
        .map(|m| m / sol.report.mass_scale)
        .collect();
    let (mut num, mut den) = (0.0, 0.0);
    for &rank in &sol.report.fitted_modes {
        let m = &detuned[rank - 1];
        let mut lp = vec![0.0; free.len()];
        l.mul_vec(&m.shape, &mut lp);
        for node in 0..free.len() {
            let target = m.shape[node] * before[node];
            num += (lp[node] / (m.omega * m.omega) - target).powi(2);
            den += target * target;
        }
    }
    let residual = (num / den).sqrt();
    assert!(residual > 1e-3, "{residual}");
    assert!(
        (sol.report.relative_residual - residual).abs() < 1e-12 * residual,
        "{} vs {residual}",
        sol.report.relative_residual
    );
}

/// The MAC is scale- and sign-free and 0 for orthogonal shapes.
#[test]
fn mac_of_modes() {
    assert!((mac(&[1.0, 2.0, 3.0], &[-2.0, -4.0, -6.0]) - 1.0).abs() < 1e-15);
    assert_eq!(mac(&[1.0, -1.0], &[1.0, 1.0]), 0.0);
}

/// The closed-form response of a rigid mode (λ = 0) is the free motion `u₀ + v₀ t + ½ f t²`
/// (unit mass), beside an oscillator of λ = 4 whose response is `u₀ cos 2t + v₀/2 sin 2t`;
/// the energies are those of these motions.
#[test]
fn modal_response_of_a_rigid_mode_and_an_oscillator() {
    let k = SparseMatrix::from_diagonal(&[0.0, 4.0]);
    let m = SparseMatrix::identity(2);
    let basis = nurbspring_derive::ModalBasis::new(&k, &m).unwrap();
    let times = [0.0, 0.5, 1.25];
    // The oscillator both displaced and moving along x (its velocity mixes the two).
    let u0 = [[0.1, 0.0, -0.2], [0.3, 0.0, 0.1]];
    let v0 = [[1.0, 0.5, 0.0], [0.2, -0.4, 0.0]];
    let f = [[0.0, 0.0, -2.0], [0.0; 3]];
    let watch = vec![vec![(0, 1.0)], vec![(1, 1.0)]];
    let origin = nurbspring_derive::EnergyOrigin {
        elastic: 0.0,
        internal: vec![[0.0; 3]; 2],
        external: 0.0,
        force: f.to_vec(),
    };
    let (points, energies) = basis.response(&watch, &times, &u0, &v0, &f, Some(&origin));
    // The energies from the motions above: kinetic ½ Σ |u̇|² (unit masses), elastic ½ · 4 |u₁|²,
    // load potential −f · u₀.
    for (s, &t) in times.iter().enumerate() {
        let (c, sn) = ((2.0 * t).cos(), (2.0 * t).sin());
        let (mut kinetic, mut elastic, mut external) = (0.0, 0.0, 0.0);
        for x in 0..3 {
            let rigid_rate = v0[0][x] + f[0][x] * t;
            let oscillator_rate = -2.0 * u0[1][x] * sn + v0[1][x] * c;
            kinetic += 0.5 * (rigid_rate * rigid_rate + oscillator_rate * oscillator_rate);
            let oscillator = u0[1][x] * c + v0[1][x] / 2.0 * sn;
            elastic += 0.5 * 4.0 * oscillator * oscillator;
            external -= f[0][x] * (u0[0][x] + v0[0][x] * t + 0.5 * f[0][x] * t * t);
        }
        let e = energies[s];
        for (got, expected) in e.iter().zip([kinetic, elastic, external]) {
            assert!(
                (got - expected).abs() < 1e-14,
                "at {t}: {e:?} vs {kinetic}, {elastic}, {external}"
            );
        }
    }
    for (s, &t) in times.iter().enumerate() {
        for x in 0..3 {
            let rigid = u0[0][x] + v0[0][x] * t + 0.5 * f[0][x] * t * t;
            let oscillator = u0[1][x] * (2.0 * t).cos() + v0[1][x] / 2.0 * (2.0 * t).sin();
            assert!(
                (points[0][s][x] - rigid).abs() < 1e-14,
                "rigid at {t}: {:?}",
                points[0][s]
            );
            assert!(
                (points[1][s][x] - oscillator).abs() < 1e-14,
                "oscillator at {t}"
            );
        }
    }
}

/// Ω of points on a rational patch with weights as unknowns: the positions of a moved shape are
/// the points of that shape (control points and weights from `p`), evaluated directly.
#[test]
fn omega_positions_of_a_moved_rational_shape() {
    use nurbspring_dnurbs::Geometry;
    use nurbspring_geom::KnotVector;
    let k = KnotVector::clamped_uniform(2, 1).unwrap();
    let pts: Vec<[f64; 3]> = (0..9)
        .map(|i| [(i / 3) as f64, (i % 3) as f64, 0.1 * i as f64])
        .collect();
    let w: Vec<f64> = (0..9).map(|i| 1.0 + 0.2 * (i % 2) as f64).collect();
    let s = NurbsSurface::try_new(k.clone(), k, pts.clone(), w.clone()).unwrap();
    let params = [(0.2, 0.7), (0.5, 0.5), (0.9, 0.1)];
    let omega =
        nurbspring_derive::Omega::new(&Geometry::Surface(s.clone()), &params, true).unwrap();
    assert_eq!(omega.params(), &params);
    // p: 4 per point (x, y, z, w), moved.
    let mut p = Vec::new();
    let (mut moved, mut moved_w) = (Vec::new(), Vec::new());
    for i in 0..9 {
        let x = [pts[i][0] + 0.05 * i as f64, pts[i][1], pts[i][2] - 0.1];
        let wi = w[i] * (1.0 + 0.1 * (i % 3) as f64);
        p.extend_from_slice(&[x[0], x[1], x[2], wi]);
        moved.push(x);
        moved_w.push(wi);
    }
    let shape = s.with_control_points_and_weights(moved, moved_w).unwrap();
    let got = omega.positions(&p).unwrap();
    for (a, &(u, v)) in params.iter().enumerate() {
        let x = shape.point(u, v).unwrap();
        for c in 0..3 {
            assert!(
                (got[a][c] - x[c]).abs() < 1e-14,
                "point {a}: {:?} vs {x:?}",
                got[a]
            );
        }
    }
}
