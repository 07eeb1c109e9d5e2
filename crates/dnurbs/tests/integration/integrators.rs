//! The sim integrators on the paper's scene (docs/math.md §3, §7): Newmark conserves energy with
//! D = 0, Terzopoulos–Qin converges at first order to the exact modal solution, and the three
//! agree at small Δt. Also the rest-shape readings and the modes.

use nurbspring_dnurbs::{DnurbsModel, DnurbsOptions, Geometry, Loads, RestShape};
use nurbspring_linalg::generalized_symmetric_eigen;
use nurbspring_sim::{DynamicModel, IntegratorKind, RunOptions, Sample, simulate};

use crate::support::{self, tol};

/// z of the surface point (½, ½) after every step (index 0 is t = 0).
fn centre_trajectory(model: &DnurbsModel, kind: IntegratorKind, dt: f64, t_end: f64) -> Vec<f64> {
    let initial = model.initial_state(&[[0.0, 0.0, -0.2]], 0.0);
    let mut z = Vec::new();
    let mut observer = |s: &Sample<'_>| {
        z.push(model.point(0.5, 0.5, &model.full_coordinates(s.q)).unwrap()[2]);
    };
    simulate(
        model,
        initial,
        &RunOptions::new(dt, t_end, kind),
        &mut observer,
    )
    .unwrap();
    z
}

/// `max_i |a[i·stride] − b[i]|` over the coarse samples.
fn max_error(fine: &[f64], stride: usize, coarse: &[f64]) -> f64 {
    coarse
        .iter()
        .enumerate()
        .map(|(i, &c)| (fine[i * stride] - c).abs())
        .fold(0.0, f64::max)
}

#[test]
fn newmark_conserves_energy_without_damping() {
    let model = support::paper_model(DnurbsOptions::default());
    assert!(model.damping().is_none());
    let initial = model.initial_state(&[[0.0, 0.0, -0.2]], 0.0);
    let mut energies = Vec::new();
    let mut observer = |s: &Sample<'_>| energies.push(s.kinetic + s.potential);
    let opts = RunOptions::new(0.08, 40.0, IntegratorKind::Newmark);
    simulate(&model, initial, &opts, &mut observer).unwrap();
    let e0 = energies[0];
    // ½ ṗᵀ M ṗ with ṗ_z = −0.2 on the three free points.
    assert!(e0 > 0.0);
    let drift = energies.iter().map(|e| (e - e0).abs()).fold(0.0, f64::max) / e0;
    eprintln!("Newmark energy drift over 500 steps: {drift:.3e} (E0 = {e0:.6e})");
    assert!(drift <= tol::ENERGY, "relative energy drift {drift:e}");
}

#[test]
fn terzopoulos_qin_converges_at_first_order_to_the_modal_solution() {
    let model = support::paper_model(DnurbsOptions::default());
    let t_end = 4.0;
    let dts = [0.02, 0.01, 0.005];
    let errors: Vec<f64> = dts
        .iter()
        .map(|&dt| {
            let tq = centre_trajectory(&model, IntegratorKind::TerzopoulosQin, dt, t_end);
            let modal = centre_trajectory(&model, IntegratorKind::Modal, dt, t_end);
            max_error(&tq, 1, &modal)
        })
        .collect();
    let r1 = support::rate(errors[0], errors[1]);
    let r2 = support::rate(errors[1], errors[2]);
    eprintln!(
        "Terzopoulos–Qin vs modal, max |Δz| over 4 s: {errors:?} for Δt = {dts:?}, rates {r1:.3}, {r2:.3}"
    );
    assert!(
        (r2 - 1.0).abs() <= tol::RATE_SLACK,
        "errors {errors:?}, rates {r1}, {r2}"
    );
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "{errors:?}");
}

#[test]
fn three_integrators_agree_at_small_time_steps() {
    let model = support::paper_model(DnurbsOptions::default());
    let (dt, t_end) = (0.002, 4.0);
    let modal = centre_trajectory(&model, IntegratorKind::Modal, dt, t_end);
    let newmark = centre_trajectory(&model, IntegratorKind::Newmark, dt, t_end);
    let tq = centre_trajectory(&model, IntegratorKind::TerzopoulosQin, dt, t_end);
    let amplitude = modal.iter().map(|z| (z - 2.0).abs()).fold(0.0, f64::max);
    assert!(amplitude > 1e-3, "the centre must move: {amplitude}");
    let e_newmark = max_error(&newmark, 1, &modal) / amplitude;
    let e_tq = max_error(&tq, 1, &modal) / amplitude;
    eprintln!(
        "Δt = {dt}: relative max deviation from modal: Newmark {e_newmark:.3e}, Terzopoulos–Qin {e_tq:.3e} (amplitude {amplitude:.4})"
    );
    // Newmark: second order, (ω Δt)² small; Terzopoulos–Qin: first order (dissipation ∝ ω² Δt t).
    assert!(
        e_newmark < tol::AGREE_NEWMARK,
        "Newmark vs modal: {e_newmark:e}"
    );
    assert!(e_tq < tol::AGREE_TQ, "Terzopoulos–Qin vs modal: {e_tq:e}");
}

#[test]
fn modes_match_the_dense_generalized_eigenproblem() {
    let model = support::paper_model(DnurbsOptions::default());
    assert_eq!(model.n_free(), 9);
    let modes = model.modes(9).unwrap();
    let eig = generalized_symmetric_eigen(
        &model.reduced_stiffness().to_dense(),
        &model.reduced_mass().to_dense(),
    )
    .unwrap();
    for (w, l) in modes.omega.iter().zip(&eig.values) {
        assert!(
            (w * w - l).abs() <= tol::SAME * l.abs().max(1.0),
            "{w} vs √{l}"
        );
    }
    assert!(modes.omega.windows(2).all(|w| w[0] <= w[1]));
    assert!(modes.omega[0] > 0.0);
    assert_eq!((modes.vectors.nrows(), modes.vectors.ncols()), (9, 9));
}

/// docs/math.md §3 and §7: with `p_rest = 0` the printed net is not in equilibrium (in x) at t = 0,
/// while the Greville net (an affine sheet, zero bending energy) is.
#[test]
fn literal_rest_shape_is_in_equilibrium_only_on_the_greville_net() {
    let options = DnurbsOptions {
        rest_shape: RestShape::Zero,
        ..DnurbsOptions::default()
    };
    let force_at_start = |surface| {
        let model = DnurbsModel::new(
            Geometry::Surface(surface),
            support::paper_material(),
            Loads::default(),
            &support::paper_constraints(),
            options.clone(),
        )
        .unwrap();
        let q0 = model.initial_state(&[[0.0; 3]], 0.0).q;
        let mut f = vec![0.0; q0.len()];
        model.internal_force(&q0, &mut f);
        f
    };
    let printed = force_at_start(support::paper_surface());
    let greville = force_at_start(support::paper_surface_greville());
    let x_force: f64 = printed.iter().step_by(3).map(|v| v.abs()).sum();
    assert!(x_force > 1e-4, "printed net: f_int,x = {x_force:e}");
    assert!(
        printed.iter().skip(2).step_by(3).all(|v| v.abs() < 1e-14),
        "no z force on the flat net"
    );
    let max = greville.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(max <= 1e-14, "Greville net: max |f_int| = {max:e}");
    // The displacement form is in equilibrium for both.
    let model = support::paper_model(DnurbsOptions::default());
    let q0 = model.initial_state(&[[0.0; 3]], 0.0).q;
    let mut f = vec![0.0; q0.len()];
    model.internal_force(&q0, &mut f);
    assert!(f.iter().all(|v| v.abs() <= 1e-15));
}

/// The modes checked without an eigensolver: each pair's residual `‖Kφ − ω²Mφ‖` recomputed
/// from the matrices, M-orthonormality, and completeness `Σ ω² = tr(M⁻¹K)` (the trace from
/// n Cholesky solves, not from an eigen-decomposition).
#[test]
fn modes_have_small_recomputed_residuals_and_sum_to_the_trace() {
    use nurbspring_linalg::SpdSolver;
    let model = support::paper_model(DnurbsOptions::default());
    let n = model.n_free();
    let modes = model.modes(n).unwrap();
    let (k, m) = (model.reduced_stiffness(), model.reduced_mass());
    let k_norm = k.frobenius_norm();
    let m_norm = m.frobenius_norm();
    let column = |j: usize| modes.vectors.column(j);
    for j in 0..n {
        let phi = column(j);
        let (mut kp, mut mp) = (vec![0.0; n], vec![0.0; n]);
        k.mul_vec(&phi, &mut kp);
        m.mul_vec(&phi, &mut mp);
        let l = modes.omega[j] * modes.omega[j];
        let r: f64 = kp
            .iter()
            .zip(&mp)
            .map(|(a, b)| (a - l * b).powi(2))
            .sum::<f64>()
            .sqrt();
        let phi_norm = phi.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(
            r <= tol::SAME * (k_norm + l * m_norm) * phi_norm,
            "mode {j}: residual {r:e}"
        );
        for i in 0..=j {
            let mij: f64 = column(i).iter().zip(&mp).map(|(a, b)| a * b).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((mij - want).abs() < tol::SAME, "φ_{i}ᵀ M φ_{j} = {mij}");
        }
    }
    let solver = SpdSolver::new(m).unwrap();
    let dense_k = k.to_dense();
    let trace: f64 = (0..n).map(|j| solver.solve(&dense_k.column(j))[j]).sum();
    let sum: f64 = modes.omega.iter().map(|w| w * w).sum();
    assert!(
        (sum - trace).abs() < tol::SAME * trace,
        "Σω² = {sum}, tr(M⁻¹K) = {trace}"
    );
}
