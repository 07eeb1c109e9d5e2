//! Runs that every derived model is judged by: the D-NURBS and linear node models through
//! their exact modes when undamped, through Newmark otherwise (docs/math.md §8.6), watched at
//! the probes.

use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::{
    IntegratorKind, LinearModel, PointDofs, RunOptions, Sample, State, SystemMatrix, simulate,
};
use serde::Serialize;

use crate::modal_solution::ModalBasis;
use crate::scalar::ScalarSystem;
use crate::validation::ModalTruncation;
use crate::{DeriveError, Trajectory};

/// Largest number of samples of a validation run.
pub const MAX_SAMPLES: usize = 20_000;

/// How a reference trajectory was computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReferenceKind {
    /// The exact modal solution (undamped linear model, constant loads).
    Modal,
    /// The modal solution on the lowest modes of a large system, with the static correction
    /// of the rest (`validation.dnurbs_truncation` says how much motion they carry).
    TruncatedModal,
    /// Newmark average acceleration at the sampling step.
    Newmark,
}

impl ReferenceKind {
    /// The name report.json gives it: `"modal"`, `"truncated-modal"` or `"newmark"`.
    pub fn name(self) -> &'static str {
        match self {
            ReferenceKind::Modal => "modal",
            ReferenceKind::TruncatedModal => "truncated-modal",
            ReferenceKind::Newmark => "newmark",
        }
    }
}

/// A point watched on a scalar system: its rest position and its weights on the unknowns
/// (its displacement is `Σ_a w_a u_a`).
#[derive(Clone, Debug, Default)]
pub struct Watch {
    /// Rest position.
    pub base: [f64; 3],
    /// `(unknown, weight)`.
    pub weights: Vec<(usize, f64)>,
}

/// Sample times `0, Δt, …` up to `horizon`, Δt the scene's step or coarser to keep at most
/// [`MAX_SAMPLES`] samples.
pub fn sample_times(horizon: f64, dt: f64) -> (f64, Vec<f64>) {
    let steps = (horizon / dt).ceil().max(1.0);
    let (steps, dt) = if steps > MAX_SAMPLES as f64 {
        (MAX_SAMPLES, horizon / MAX_SAMPLES as f64)
    } else {
        (steps as usize, dt)
    };
    (dt, (0..=steps).map(|k| k as f64 * dt).collect())
}

/// Runs the scalar system `sys` and records the watched points and the energies (as the model
/// it stands for counts them, [`crate::scalar::EnergyOrigin`]) at `times` (spaced `dt`):
/// exactly by `basis` when undamped, by Newmark otherwise.
pub fn run_scalar(
    sys: &ScalarSystem,
    basis: &ModalBasis,
    watch: &[Watch],
    times: &[f64],
    dt: f64,
) -> Result<(Trajectory, ReferenceKind), DeriveError> {
    let mut traj = Trajectory::new(watch.len());
    traj.t = times.to_vec();
    if sys.damping_ratio == 0.0 {
        let weights: Vec<Vec<(usize, f64)>> = watch.iter().map(|w| w.weights.clone()).collect();
        let (response, energy) = basis.response(
            &weights,
            times,
            &sys.displacement,
            &sys.velocity,
            &sys.load,
            Some(&sys.energy),
        );
        traj.energy = energy;
        let kind = if basis.is_complete() {
            ReferenceKind::Modal
        } else {
            traj.truncation = Some(ModalTruncation {
                modes: basis.len(),
                unknowns: basis.unknowns(),
                left_out: basis.left_out(&sys.displacement, &sys.velocity, &sys.load),
            });
            ReferenceKind::TruncatedModal
        };
        for (p, (w, r)) in watch.iter().zip(response).enumerate() {
            traj.probes[p] = r
                .iter()
                .map(|d| [w.base[0] + d[0], w.base[1] + d[1], w.base[2] + d[2]])
                .collect();
        }
        return Ok((traj, kind));
    }
    // Damped: Newmark on the 3-D system M ü + c M u̇ + K u = f.
    let m3 = PointDofs::XYZ.expand(&sys.mass);
    let mut d3 = m3.clone();
    d3.scale(sys.damping_ratio);
    let n3 = m3.nrows();
    let model = LinearModel {
        mass: SystemMatrix::Sparse(m3),
        damping: Some(SystemMatrix::Sparse(d3)),
        stiffness: PointDofs::XYZ.expand(&sys.stiffness),
        rest: vec![0.0; n3],
        force: sys.load.iter().flatten().copied().collect(),
    };
    let initial = State::new(
        sys.displacement.iter().flatten().copied().collect(),
        sys.velocity.iter().flatten().copied().collect(),
    );
    let t_end = times.last().copied().unwrap_or(0.0);
    let opts = RunOptions::new(dt, t_end, IntegratorKind::Newmark);
    let mut probes = vec![Vec::with_capacity(times.len()); watch.len()];
    let mut energy = Vec::with_capacity(times.len());
    let mut observer = |s: &Sample<'_>| {
        energy.push(sys.energies(&crate::scalar::points(s.q), &crate::scalar::points(s.v)));
        for (p, w) in watch.iter().enumerate() {
            let mut x = w.base;
            for &(a, c) in &w.weights {
                for k in 0..3 {
                    x[k] += c * s.q[3 * a + k];
                }
            }
            probes[p].push(x);
        }
    };
    simulate(&model, initial, &opts, &mut observer)?;
    traj.probes = probes;
    traj.energy = energy;
    traj.t.truncate(traj.probes.first().map_or(0, Vec::len));
    Ok((traj, ReferenceKind::Newmark))
}

/// The scalar rows of a 3-D interleaved matrix with identical x, y, z blocks
/// ([`PointDofs::scalar_part`]; the Ω of constant weights is `R ⊗ I₃`).
pub fn scalar_rows(a: &SparseMatrix) -> SparseMatrix {
    PointDofs::XYZ.scalar_part(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `⌈horizon/Δt⌉` steps of the scene's Δt, the last at or past the horizon; past
    /// [`MAX_SAMPLES`] steps, that many steps of `horizon / MAX_SAMPLES`.
    #[test]
    fn sample_times_by_hand() {
        let (dt, t) = sample_times(1.0, 0.25);
        assert_eq!((dt, t), (0.25, vec![0.0, 0.25, 0.5, 0.75, 1.0]));
        let (dt, t) = sample_times(1.0, 0.3);
        assert_eq!(dt, 0.3);
        assert_eq!(t.len(), 5);
        assert!((t[4] - 1.2).abs() < 1e-15);
        let (dt, t) = sample_times(4.0, 1e-5);
        assert_eq!(dt, 4.0 / MAX_SAMPLES as f64);
        assert_eq!(t.len(), MAX_SAMPLES + 1);
        assert!((t[MAX_SAMPLES] - 4.0).abs() < 1e-12);
    }

    /// One damped oscillator `ü + c u̇ + ω² u = 0` (unit mass, ω = 2, c = 0.4) from
    /// `u₀ = (0.1, −0.2, 0.3)`, `v₀ = (0.5, 0, −0.1)`, watched at a base point with weight 2:
    /// the Newmark reference is `base + 2 u(t)` with the closed form
    /// `u = e^{−ct/2} (u₀ cos ω_d t + (v₀ + c u₀/2)/ω_d sin ω_d t)`, to Newmark's phase error
    /// `O((ω Δt)²)` (here Δt = 10⁻³ over 2 s: about 10⁻⁶).
    #[test]
    fn the_damped_reference_against_the_closed_form() {
        let (w, c) = (2.0f64, 0.4);
        let u0 = [0.1, -0.2, 0.3];
        let v0 = [0.5, 0.0, -0.1];
        let sys = ScalarSystem {
            free: vec![0],
            mass: SparseMatrix::identity(1),
            stiffness: SparseMatrix::from_diagonal(&[w * w]),
            damping_ratio: c,
            load: vec![[0.0; 3]],
            displacement: vec![u0],
            velocity: vec![v0],
            energy: crate::scalar::EnergyOrigin {
                elastic: 0.0,
                internal: vec![[0.0; 3]],
                external: 0.0,
                force: vec![[0.0; 3]],
            },
        };
        let basis = ModalBasis::new(&sys.stiffness, &sys.mass).unwrap();
        let base = [1.0, 2.0, 3.0];
        let watch = [Watch {
            base,
            weights: vec![(0, 2.0)],
        }];
        let (dt, times) = sample_times(2.0, 1e-3);
        let (traj, kind) = run_scalar(&sys, &basis, &watch, &times, dt).unwrap();
        assert_eq!(kind, ReferenceKind::Newmark);
        let wd = (w * w - 0.25 * c * c).sqrt();
        for (s, &t) in times.iter().enumerate() {
            for x in 0..3 {
                let u = (-0.5 * c * t).exp()
                    * (u0[x] * (wd * t).cos() + (v0[x] + 0.5 * c * u0[x]) / wd * (wd * t).sin());
                let got = traj.probes[0][s][x];
                assert!(
                    (got - (base[x] + 2.0 * u)).abs() < 2e-6,
                    "t {t}, x {x}: {got} vs {u}"
                );
            }
        }
    }
}
