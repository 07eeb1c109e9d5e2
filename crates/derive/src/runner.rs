//! One simulation runner for both models: runs a D-NURBS or an MSM and records its probe
//! points and energies into a [`Trajectory`].

use nurbspring_dnurbs::DnurbsModel;
use nurbspring_msm::MsmModel;
use nurbspring_sim::{RunOptions, RunSummary, Sample, SimError, State, simulate};

use crate::{DeriveError, Omega, Trajectory};

/// A model to run, with the points it is watched at.
#[derive(Clone, Copy)]
pub enum Watched<'a> {
    /// A D-NURBS; its probes are the surface points `c(p(t))` at the probe parameters
    /// ([`Omega::positions`]: `Ω_probes p`, paper eq. (11), with constant weights).
    Dnurbs {
        /// The model.
        model: &'a DnurbsModel,
        /// Ω of the probe parameters.
        probes: &'a Omega,
    },
    /// An MSM; its probes are these nodes.
    Msm {
        /// The model.
        model: &'a MsmModel,
        /// The probe nodes.
        nodes: &'a [usize],
    },
}

impl Watched<'_> {
    /// Number of probes.
    pub fn n_probes(&self) -> usize {
        match self {
            Watched::Dnurbs { probes, .. } => probes.n_points(),
            Watched::Msm { nodes, .. } => nodes.len(),
        }
    }
}

/// What [`record`] keeps.
#[derive(Clone, Copy, Debug)]
pub struct Recording {
    /// Keep every n-th sample (≥ 1; step 0 is always kept).
    pub every: usize,
}

impl Default for Recording {
    fn default() -> Self {
        Self { every: 1 }
    }
}

/// Runs `watched` from `initial` with `opts`, keeping every `recording.every`-th sample, and
/// calls `hook(sample, full coordinates)` on each kept sample (the full control-point vector
/// `p` for a D-NURBS, all `3N` node coordinates for an MSM). Returns what was recorded and
/// how the run ended: a run that stops early still returns the samples before it stopped.
pub fn record(
    watched: Watched<'_>,
    initial: State,
    opts: &RunOptions,
    recording: Recording,
    hook: &mut dyn FnMut(&Sample<'_>, &[f64]),
) -> (Trajectory, Result<RunSummary, DeriveError>) {
    let every = recording.every.max(1);
    let mut traj = Trajectory::new(watched.n_probes());
    let mut points = vec![0.0; 3 * watched.n_probes()];
    let mut keep = |s: &Sample<'_>, full: &[f64], points: &[f64], traj: &mut Trajectory| {
        traj.t.push(s.t);
        for (i, probe) in traj.probes.iter_mut().enumerate() {
            probe.push([points[3 * i], points[3 * i + 1], points[3 * i + 2]]);
        }
        traj.energy.push([s.kinetic, s.elastic, s.external]);
        hook(s, full);
    };
    let outcome = match watched {
        Watched::Dnurbs { model, probes } => {
            let mut failed = None;
            let mut observer = |s: &Sample<'_>| {
                if s.step.is_multiple_of(every) && failed.is_none() {
                    let p = model.full_coordinates(s.q);
                    match probes.positions_into(&p, &mut points) {
                        Ok(()) => keep(s, &p, &points, &mut traj),
                        Err(e) => failed = Some(e),
                    }
                }
            };
            let outcome = model
                .simulate(initial, opts, &mut observer)
                .map_err(DeriveError::from);
            match failed {
                Some(e) => Err(e),
                None => outcome,
            }
        }
        Watched::Msm { model, nodes } => {
            let mut observer = |s: &Sample<'_>| {
                if s.step.is_multiple_of(every) {
                    let x = model.full_positions(s.q);
                    for (i, &a) in nodes.iter().enumerate() {
                        points[3 * i..3 * i + 3].copy_from_slice(&x[3 * a..3 * a + 3]);
                    }
                    keep(s, &x, &points, &mut traj);
                }
            };
            simulate(model, initial, opts, &mut observer).map_err(DeriveError::from)
        }
    };
    if let Ok(summary) = &outcome {
        traj.halved_steps = summary.halved_steps;
    }
    (traj, outcome)
}

/// [`record`] for validation runs: divergence, instability and Newton failures become a note
/// on the trajectory (`stopped`), cancellation is [`DeriveError::Cancelled`], other errors
/// propagate.
pub fn record_noted(
    watched: Watched<'_>,
    initial: State,
    opts: &RunOptions,
) -> Result<Trajectory, DeriveError> {
    let (traj, outcome) = record(watched, initial, opts, Recording::default(), &mut |_, _| {});
    noted(traj, outcome)
}

/// How [`record_noted`] ends a run that [`record`] returned.
pub(crate) fn noted(
    mut traj: Trajectory,
    outcome: Result<RunSummary, DeriveError>,
) -> Result<Trajectory, DeriveError> {
    match outcome {
        Ok(summary) if summary.cancelled => Err(DeriveError::Cancelled),
        Ok(_) => Ok(traj),
        Err(e) if is_stop(&e) => {
            traj.stopped = Some(e.to_string());
            Ok(traj)
        }
        Err(e) => Err(e),
    }
}

/// Errors that end a validation run early without ending the derivation.
fn is_stop(e: &DeriveError) -> bool {
    let sim = match e {
        DeriveError::Sim(s) => s,
        DeriveError::Dnurbs(nurbspring_dnurbs::DnurbsError::Sim(s)) => s,
        DeriveError::Msm(nurbspring_msm::MsmError::Sim(s)) => s,
        _ => return false,
    };
    matches!(
        sim,
        SimError::Diverged { .. } | SimError::Unstable { .. } | SimError::NewtonFailed { .. }
    )
}

#[cfg(test)]
mod tests {
    use nurbspring_dnurbs::Geometry;
    use nurbspring_geom::{KnotVector, NurbsSurface};
    use nurbspring_sim::IntegratorKind;

    use super::*;

    /// Every third step of a D-NURBS run and of an MSM run is kept (steps 0, 3, 6, 9 of ten),
    /// with its probe points (two on the D-NURBS, each starting at its surface point).
    #[test]
    fn every_nth_sample_is_kept() {
        let ku = KnotVector::clamped_uniform(3, 2).unwrap();
        let (g, n) = (ku.greville(), ku.n_basis());
        let pts = g
            .iter()
            .flat_map(|&u| g.iter().map(move |&v| [u, v, 0.1 * u * v]))
            .collect();
        let s = NurbsSurface::try_new(ku.clone(), ku, pts, vec![1.0; n * n]).unwrap();
        let setup = crate::test_scenes::setup(Geometry::Surface(s.clone()));
        let opts = RunOptions::new(0.01, 0.1, IntegratorKind::Newmark);
        let every = Recording { every: 3 };
        let expected = [0.0, 0.03, 0.06, 0.09];
        let same = |t: &[f64]| {
            t.len() == expected.len() && t.iter().zip(&expected).all(|(a, b)| (a - b).abs() < 1e-12)
        };
        let omega = Omega::new(
            &Geometry::Surface(s.clone()),
            &[(0.5, 0.5), (0.25, 0.75)],
            false,
        )
        .unwrap();
        let (traj, outcome) = record(
            Watched::Dnurbs {
                model: setup.model(),
                probes: &omega,
            },
            setup.dnurbs_initial().clone(),
            &opts,
            every,
            &mut |_, _| {},
        );
        outcome.unwrap();
        assert!(same(&traj.t), "{:?}", traj.t);
        assert_eq!(traj.probes.len(), 2);
        assert_eq!(traj.probes[0].len(), 4);
        assert_eq!(traj.probes[1].len(), 4);
        for (probe, (u, v)) in traj.probes.iter().zip([(0.5, 0.5), (0.25, 0.75)]) {
            let p = s.point(u, v).unwrap();
            assert!(
                (0..3).all(|x| (probe[0][x] - p[x]).abs() < 1e-14),
                "{:?} vs {p:?}",
                probe[0]
            );
        }
        let model = MsmModel::new(setup.lattice().clone()).unwrap();
        let initial = model.initial_state(&[]);
        let (traj, outcome) = record(
            Watched::Msm {
                model: &model,
                nodes: &[0],
            },
            initial,
            &opts,
            every,
            &mut |_, _| {},
        );
        outcome.unwrap();
        assert!(same(&traj.t), "{:?}", traj.t);
    }

    /// A run that diverges, is unstable or whose Newton iteration fails ends the validation
    /// early; any other error ends the derivation.
    #[test]
    fn which_errors_stop_a_run() {
        let diverged = SimError::Diverged {
            step: 3,
            time: 0.3,
            reason: "test".into(),
        };
        assert!(is_stop(&DeriveError::Sim(diverged)));
        assert!(!is_stop(&DeriveError::LatticeWithoutParameters));
    }
}
