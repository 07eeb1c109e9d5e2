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
    let (mut traj, outcome) = record(watched, initial, opts, Recording::default(), &mut |_, _| {});
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
