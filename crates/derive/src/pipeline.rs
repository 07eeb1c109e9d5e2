//! The derivation of the paper's Section III as a pipeline of named steps over typed values:
//! [`fit_step`] (eq. (15), every reading) → [`reference_run`] (the D-NURBS) → [`mass_step`]
//! (the eigenvalue scan) → [`evaluate`] (stability, residuals and the side-by-side run of
//! Figure 3) → [`spectra`]. [`derive_msm`] runs them in order.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_dnurbs::{DnurbsModel, Loads};
use nurbspring_msm::{Class, Constants, MsmModel, SpringLattice};
use nurbspring_sim::{DynamicModel, IntegratorKind, RunOptions, Schedule, StabilityLimit, State};

use crate::DeriveError;
use crate::evaluation::{
    DnurbsModes, TABLE_MODES, dnurbs_impulse_run, dnurbs_watch, horizon, impulse, initial_speed,
    regime, validation, warnings, with_totals,
};
use crate::fit::{FitDofs, FitResult};
use crate::mass::{mass_eigenvalues, mass_eigenvalues_computable};
use crate::method::Method;
use crate::outcome::{
    Derivation, DerivedModel, FitDetail, FitReport, FrequencyRow, MassCandidate, MassReport,
    ParameterSet, PrunedRun, Spectrum, TrustRegionReport, Validation,
};
use crate::reference::{ReferenceKind, run_scalar, sample_times};
use crate::runner::{Watched, record_noted};
use crate::setup::{Config, FitMethod, FitOptions, MassChoice, MassScan, Setup};
use crate::validation::{Trajectory, compare};

/// The reading of eq. (15) the derived MSM uses.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectedReading {
    /// Dofs entering the fit.
    pub dofs: FitDofs,
    /// `k ≥ 0` imposed.
    pub nonnegative: bool,
    /// Solver.
    pub method: FitMethod,
    /// When `k ≥ 0` was imposed because the unconstrained optimum has negative constants
    /// (no spring can have one): those constants.
    pub imposed_by: Vec<(Class, f64)>,
}

impl std::fmt::Display for SelectedReading {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} dofs, {}, {}",
            self.dofs.name(),
            if self.nonnegative {
                "k >= 0"
            } else {
                "unconstrained"
            },
            self.method.label()
        )?;
        if !self.imposed_by.is_empty() {
            let list: Vec<String> = self
                .imposed_by
                .iter()
                .map(|(c, k)| format!("{} = {k:.6}", c.symbol()))
                .collect();
            write!(
                f,
                " (k >= 0 imposed because the unconstrained fit gives {}, which no spring can have)",
                list.join(", ")
            )?;
        }
        Ok(())
    }
}

/// Largest model whose full spectrum is reported (dense eigenproblems).
pub const MAX_SPECTRUM_DOFS: usize = 1500;

/// Eigenvalues below this fraction of the largest count as zero frequencies.
const ZERO_EIGENVALUE: f64 = 1e-12;

/// Step 1, eq. (15) under its four readings, then the selected one (closed form or trust
/// region). A spring cannot have a negative constant: when the unconstrained optimum of the
/// selected dofs has one, the derived MSM uses the `k ≥ 0` optimum, and the reading says so.
pub fn fit_step(setup: &Setup, options: &FitOptions) -> Result<FitReport, DeriveError> {
    let all_dofs = setup.solve(FitDofs::All, false)?;
    let free_dofs = setup.solve(FitDofs::Free, false)?;
    let all_dofs_nonnegative = setup.solve(FitDofs::All, true)?;
    let free_dofs_nonnegative = setup.solve(FitDofs::Free, true)?;
    let (unconstrained, constrained) = match options.dofs {
        FitDofs::All => (&all_dofs, &all_dofs_nonnegative),
        FitDofs::Free => (&free_dofs, &free_dofs_nonnegative),
    };
    let negative: Vec<(Class, f64)> = unconstrained
        .constants
        .iter()
        .filter(|&(_, k)| k < 0.0)
        .collect();
    let nonnegative = options.nonnegative || !negative.is_empty();
    let selected_closed = if nonnegative {
        constrained.clone()
    } else {
        unconstrained.clone()
    };
    let fit = setup.fit(options.dofs)?;
    let start = vec![1.0; fit.classes().len()];
    let tr = fit.trust_region(&start, nonnegative, 500)?;
    let tr_result = FitResult {
        constants: fit.constants(&tr.k),
        relative_residual: fit.relative_residual(&tr.k)?,
    };
    let max_rel = fit
        .classes()
        .iter()
        .map(|&c| {
            let (a, b) = (
                tr_result.constants.value(c),
                selected_closed.constants.value(c),
            );
            (a - b).abs() / b.abs().max(1e-300)
        })
        .fold(0.0, f64::max);
    let selected = match options.method {
        FitMethod::ClosedForm => selected_closed,
        FitMethod::TrustRegion => tr_result.clone(),
    };
    let reading = SelectedReading {
        dofs: options.dofs,
        nonnegative,
        method: options.method,
        imposed_by: if options.nonnegative {
            Vec::new()
        } else {
            negative
        },
    };
    Ok(FitReport {
        classes: fit.classes().to_vec(),
        all_dofs,
        free_dofs,
        all_dofs_nonnegative,
        free_dofs_nonnegative,
        trust_region: TrustRegionReport {
            result: tr_result,
            iterations: tr.iterations,
            max_relative_difference_to_closed_form: max_rel,
        },
        selected_reading: reading.to_string(),
        selected,
    })
}

/// Step 2, the D-NURBS reference run with the scene's integrator and time settings.
pub fn reference_run(
    setup: &Setup,
    config: &Config,
    cancel: Option<Arc<AtomicBool>>,
) -> Result<Trajectory, DeriveError> {
    setup.run_dnurbs(
        config.time.dnurbs_integrator,
        config.time.dt,
        config.time.t_end,
        cancel,
    )
}

/// Step 3, the mass of Section III: the distinct non-null eigenvalues of M, and unless the
/// scene fixes the mass, the candidate loop (each candidate simulated and compared with the
/// D-NURBS on the central node's z; the smallest RMS among the runs that finished wins).
pub fn mass_step(
    setup: &Setup,
    config: &Config,
    constants: &Constants,
    dnurbs: &Trajectory,
    cancel: Option<Arc<AtomicBool>>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<MassReport, DeriveError> {
    // With the mass fixed the eigenvalues are only listed: a net too large for their dense
    // solve lists none instead of failing.
    let listed = |m: &nurbspring_linalg::SparseMatrix| -> Result<Vec<f64>, DeriveError> {
        match config.fit.mass {
            MassChoice::Fixed(_) if !mass_eigenvalues_computable(m) => Ok(Vec::new()),
            _ => mass_eigenvalues(m),
        }
    };
    let eigenvalues = listed(&setup.model().matrices().mass)?;
    let eigenvalues_free_dofs = listed(setup.model().reduced_mass())?;
    let (candidates, selected, rule) = match config.fit.mass {
        MassChoice::Fixed(m) => (Vec::new(), m, format!("fixed by the scene: m = {m}")),
        MassChoice::EigenvalueScan => {
            let take = match config.fit.max_candidates {
                0 => eigenvalues.len(),
                n => n,
            };
            let list: Vec<f64> = eigenvalues.iter().copied().take(take).collect();
            let candidates =
                mass_candidates(setup, config, constants, &list, dnurbs, cancel, progress)?;
            let best = candidates
                .iter()
                .filter(|c| c.rms.is_finite())
                .min_by(|a, b| a.rms.total_cmp(&b.rms))
                .map(|c| c.m)
                .ok_or_else(|| DeriveError::NoMassCandidate {
                    tried: candidates.len(),
                    first: candidates
                        .first()
                        .and_then(|c| c.stopped.clone())
                        .unwrap_or_else(|| "M has no non-null eigenvalue".to_string()),
                })?;
            (
                candidates,
                best,
                "every distinct non-null eigenvalue of M tried, smallest first; the one with the smallest RMS error of the central node's z against the D-NURBS run is kept".to_string(),
            )
        }
    };
    Ok(MassReport {
        eigenvalues,
        eigenvalues_free_dofs,
        candidates,
        selected,
        rule,
        ..MassReport::default()
    })
}

/// Candidates of the eigenvalue scan run in batches of this many, in parallel within a batch.
/// A pruned scan bounds each batch by the best complete candidate of the batches before it, so
/// what is pruned, and every number reported, does not depend on the number of threads.
pub const SCAN_BATCH: usize = 4;

/// The candidate loop: simulates the MSM with `m = λ` for each candidate. Each run uses the
/// scene's integrator, in substeps when it is explicit and Δt is above its stability limit
/// (Newmark when that would take more than [`nurbspring_sim::MAX_SUBSTEPS`]; recorded per
/// candidate, [`Setup::schedule`]).
///
/// With [`MassScan::Pruned`] a run stops as soon as the running sum of its squared errors
/// exceeds the best complete candidate's whole sum (the error sum only grows, so it could not
/// be selected; docs/math.md §6). The candidates run in batches of [`SCAN_BATCH`] on rayon's
/// pool; `progress` is called on the calling thread as runs finish.
fn mass_candidates(
    setup: &Setup,
    config: &Config,
    constants: &Constants,
    masses: &[f64],
    dnurbs: &Trajectory,
    cancel: Option<Arc<AtomicBool>>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<MassCandidate>, DeriveError> {
    use rayon::prelude::*;
    let z_ref = dnurbs.component(0, 2);
    let centre = setup.probe_nodes()[0];
    let samples = z_ref.len();
    // `bound`: the error sum beyond which the run stops (∞: it runs to the end).
    let run = |m: f64, bound: f64| -> Result<MassCandidate, DeriveError> {
        if cancel.as_ref().is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(DeriveError::Cancelled);
        }
        let (schedule, limit) =
            setup.schedule(constants, m, config.time.msm_integrator, config.time.dt)?;
        let mut sum = 0.0;
        let (traj, pruned) = setup.run_msm_watched(
            setup.lattice_with(constants, m),
            (schedule, limit),
            (config.time.dt, config.time.t_end),
            cancel.as_deref(),
            &mut |step, x| {
                if let Some(z) = z_ref.get(step) {
                    let d = z - x[3 * centre + 2];
                    sum += d * d;
                }
                sum <= bound || !sum.is_finite()
            },
        )?;
        let mut candidate = MassCandidate {
            m,
            rms: f64::INFINITY,
            max_abs: f64::INFINITY,
            pruned: None,
            integrator: schedule.integrator,
            substeps: schedule.substeps,
            stopped: traj.stopped.clone(),
        };
        if pruned {
            candidate.pruned = Some(PrunedRun {
                at: traj.t.last().copied().unwrap_or(0.0),
                rms_at_least: (sum / samples as f64).sqrt(),
            });
            return Ok(candidate);
        }
        let c = compare(&dnurbs.t, &z_ref, &traj.component(0, 2));
        if traj.stopped.is_none() && c.samples == samples {
            (candidate.rms, candidate.max_abs) = (c.rms, c.max_abs);
        }
        Ok(candidate)
    };
    let pruned = config.fit.scan == MassScan::Pruned;
    let (done_tx, done_rx) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|scope| {
        let worker = scope.spawn(move || {
            let mut candidates: Vec<MassCandidate> = Vec::with_capacity(masses.len());
            for batch in masses.chunks(SCAN_BATCH) {
                // The best whole error sum so far, with a margin for its rounding as rms².
                let bound = candidates
                    .iter()
                    .filter(|c| pruned && c.rms.is_finite())
                    .map(|c| c.rms * c.rms * samples as f64 * (1.0 + 1e-9))
                    .fold(f64::INFINITY, f64::min);
                let done = batch
                    .par_iter()
                    .map(|&m| {
                        let candidate = run(m, bound);
                        // The receiver outlives the worker unless the caller panicked.
                        let _ = done_tx.send(());
                        candidate
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                candidates.extend(done);
            }
            Ok(candidates)
        });
        // The channel closes when the worker's sender is dropped, that is when it returns.
        for (k, ()) in done_rx.iter().enumerate() {
            progress(k + 1, masses.len());
        }
        worker
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    })
}

/// The D-NURBS watched at the probes over the validation horizon: the exact modal solution
/// of its scalar system when it has one and is undamped, Newmark otherwise; `state` the
/// initial state (`None`: the scene's) and `loaded` whether the scene's loads act.
pub struct Judge<'a> {
    setup: &'a Setup,
    config: &'a Config,
    modes: Option<DnurbsModes>,
    /// Validation horizon.
    pub horizon: f64,
    /// Sampling step.
    pub dt: f64,
    /// Sample times.
    pub times: Vec<f64>,
}

impl<'a> Judge<'a> {
    /// The judge of `setup`'s derived models; `modes` the D-NURBS's scalar system and modes
    /// when it has them.
    pub fn new(
        setup: &'a Setup,
        config: &'a Config,
        modes: Option<DnurbsModes>,
    ) -> Result<Self, DeriveError> {
        let omega1 = match &modes {
            Some(m) => m.omega1(),
            None => {
                let m = setup.model().modes(1)?;
                m.omega.first().copied().unwrap_or(0.0)
            }
        };
        let horizon = horizon(config.time.t_end, omega1);
        let (dt, times) = sample_times(horizon, config.time.dt);
        Ok(Self {
            setup,
            config,
            modes,
            horizon,
            dt,
            times,
        })
    }

    /// The D-NURBS's scalar system and modes, when it has them.
    pub fn modes(&self) -> Option<&DnurbsModes> {
        self.modes.as_ref()
    }

    /// The reference run from the scene's state.
    pub fn reference(&self) -> Result<(Trajectory, ReferenceKind), DeriveError> {
        match &self.modes {
            Some(m) => run_scalar(
                &m.system,
                &m.basis,
                &dnurbs_watch(self.setup, &m.system),
                &self.times,
                self.dt,
            ),
            None => Ok((
                self.setup
                    .run_dnurbs(IntegratorKind::Newmark, self.dt, self.horizon, None)?,
                ReferenceKind::Newmark,
            )),
        }
    }

    /// The reference run of the second excitation from `impulse`, without loads.
    pub fn impulse_reference(
        &self,
        impulse: &State,
    ) -> Result<(Trajectory, ReferenceKind), DeriveError> {
        match &self.modes {
            Some(m) => dnurbs_impulse_run(self.setup, m, impulse, &self.times, self.dt),
            None => {
                let c = self.config;
                let model = DnurbsModel::new(
                    c.geometry.clone(),
                    c.material.clone(),
                    Loads::default(),
                    &c.constraints,
                    c.dnurbs.clone(),
                )?;
                let opts = RunOptions::new(self.dt, self.horizon, IntegratorKind::Newmark);
                let watched = Watched::Dnurbs {
                    model: &model,
                    probes: self.setup.probe_omega(),
                };
                Ok((
                    record_noted(watched, impulse.clone(), &opts)?,
                    ReferenceKind::Newmark,
                ))
            }
        }
    }
}

/// Step 4, a parameter set evaluated: stability, residuals, and the 3-D comparison of the
/// probes with the D-NURBS reference over the validation horizon. The MSM runs with
/// `integrator` when it is stable at the sampling step, in substeps below its stability limit
/// when it is explicit and the step is above it (Newmark when that would take more than
/// [`nurbspring_sim::MAX_SUBSTEPS`]; [`Setup::schedule`]); in that case the requested explicit
/// run with plain steps is also made (forced past its limit) and reported in `explicit_run`,
/// to show what it does.
pub fn evaluate(
    setup: &Setup,
    config: &Config,
    judge: &Judge<'_>,
    reference: &(Trajectory, ReferenceKind),
    constants: &Constants,
    m: f64,
    integrator: IntegratorKind,
) -> Result<(ParameterSet, Trajectory), DeriveError> {
    let (omega_max, dt_critical) = setup.stability(constants, m)?;
    let (used, limit) = setup.schedule(constants, m, integrator, judge.dt)?;
    let (res_all, res_free) = setup.residuals_at(constants)?;
    let run = |(schedule, limit): (Schedule, Option<StabilityLimit>)| {
        let traj = setup.run_msm(
            setup.lattice_with(constants, m),
            (schedule, limit),
            judge.dt,
            judge.horizon,
            true,
            None,
        )?;
        let v = validation(
            setup,
            &reference.0,
            reference.1,
            &traj,
            schedule.integrator.name().to_string(),
            schedule.substeps,
            judge.horizon,
            judge.dt,
        );
        Ok::<_, DeriveError>((v, traj))
    };
    let (validation, traj) = run((used, limit))?;
    let explicit_run = if !used.is_plain(integrator) {
        Some(run((Schedule::plain(integrator), None))?.0)
    } else {
        None
    };
    Ok((
        ParameterSet {
            constants: constants.clone(),
            m,
            omega_max,
            dt_critical,
            dt_exceeds_explicit_limit: config.time.dt >= dt_critical,
            relative_residual_all_dofs: Some(res_all),
            relative_residual_free_dofs: Some(res_free),
            validation,
            explicit_run,
        },
        traj,
    ))
}

/// Step 5, the spectra of both models linearized at rest (empty above
/// [`MAX_SPECTRUM_DOFS`] free dofs).
pub fn spectra(setup: &Setup, lattice: &SpringLattice) -> Result<Spectrum, DeriveError> {
    let model = setup.model();
    let dnurbs = if model.n_free() <= MAX_SPECTRUM_DOFS {
        model.modes(model.n_free())?.omega
    } else {
        Vec::new()
    };
    Ok(Spectrum {
        dnurbs,
        msm: msm_spectrum(lattice)?,
    })
}

/// Angular frequencies of the MSM linearized at rest, ascending, with exact zeros for the
/// directions without linear stiffness.
pub fn msm_spectrum(lattice: &SpringLattice) -> Result<Vec<f64>, DeriveError> {
    let model = MsmModel::new(lattice.clone())?;
    let n = model.n_dofs();
    if n == 0 || n > MAX_SPECTRUM_DOFS {
        return Ok(Vec::new());
    }
    let k = model
        .tangent_stiffness(model.initial_positions())
        .to_dense();
    let m = model.mass().to_sparse().to_dense();
    let eig = nurbspring_linalg::generalized_symmetric_eigen(&k, &m)?;
    let scale = eig.values.iter().map(|x| x.abs()).fold(0.0, f64::max);
    Ok(eig
        .values
        .iter()
        .map(|&l| {
            if l.abs() <= ZERO_EIGENVALUE * scale {
                0.0
            } else {
                l.max(0.0).sqrt()
            }
        })
        .collect())
}

/// Derives the MSM that mimics the D-NURBS model by the paper's method (Section III) and
/// validates it: the steps of this module in order. `cancel` stops long runs (Ctrl-C);
/// `progress(done, total)` reports the mass scan.
pub fn derive_msm(
    config: &Config,
    cancel: Option<Arc<AtomicBool>>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Derivation, Setup), DeriveError> {
    let setup = Setup::new(config)?;
    let fit = fit_step(&setup, &config.fit)?;
    let scan_reference = reference_run(&setup, config, cancel.clone())?;
    let mass = mass_step(
        &setup,
        config,
        &fit.selected.constants,
        &scan_reference,
        cancel.clone(),
        progress,
    )?;
    let judge = Judge::new(&setup, config, DnurbsModes::new(&setup, "paper").ok())?;
    let reference = judge.reference()?;
    if cancel.as_ref().is_some_and(|c| c.load(Ordering::Relaxed)) {
        return Err(DeriveError::Cancelled);
    }
    let integrator = config.time.msm_integrator;
    let constants = fit.selected.constants.clone();
    let lattice = setup.lattice_with(&constants, mass.selected);
    // The validation of the derived (and the scene's) model, the second excitation and the
    // spectra are independent: they run in parallel (rayon's pool; each result is the same
    // as when run alone).
    let validations = || -> Result<_, DeriveError> {
        let derived = evaluate(
            &setup,
            config,
            &judge,
            &reference,
            &constants,
            mass.selected,
            integrator,
        )?;
        let given = match &config.given {
            Some((constants, m)) => Some(evaluate(
                &setup, config, &judge, &reference, constants, *m, integrator,
            )?),
            None => None,
        };
        Ok((derived, given))
    };
    // The second excitation: an impulse, no loads.
    let second = || -> Result<Validation, DeriveError> {
        let impulse = impulse(&setup, initial_speed(setup.dnurbs_initial()))?;
        let impulse_reference = judge.impulse_reference(&impulse)?;
        let mut unloaded = lattice.clone();
        unloaded.gravity = [0.0; 3];
        unloaded.forces.clear();
        let nodes = setup.omega().node_state(setup.model(), &impulse);
        let (used, limit) = setup.schedule(&constants, mass.selected, integrator, judge.dt)?;
        let mut opts = RunOptions::scheduled(judge.dt, judge.horizon, used, limit);
        opts.force_unstable = true;
        let impulse_run = setup.run_msm_from(unloaded, &nodes, &opts)?;
        Ok(validation(
            &setup,
            &impulse_reference.0,
            impulse_reference.1,
            &impulse_run,
            used.integrator.name().to_string(),
            used.substeps,
            judge.horizon,
            judge.dt,
        ))
    };
    let (validated, (second_excitation, spectrum)) = rayon::join(validations, || {
        rayon::join(second, || spectra(&setup, &lattice))
    });
    let ((derived, msm_trajectory), given) = validated?;
    let (given, given_trajectory) = match given {
        Some((p, t)) => (Some(p), Some(t)),
        None => (None, None),
    };
    let (second_excitation, spectrum) = (second_excitation?, spectrum?);
    let frequencies = paper_frequencies(&spectrum);
    let mass = with_totals(mass, setup.model(), &lattice.masses, &lattice.fixed);
    let clamped: Vec<String> = fit
        .selected
        .constants
        .iter()
        .filter(|&(_, k)| k == 0.0)
        .map(|(c, _)| c.symbol())
        .collect();
    let regime = regime(&setup, &reference.0, &frequencies);
    let warnings = warnings(
        Method::Paper,
        &derived.validation,
        &second_excitation,
        &frequencies,
        &mass,
        &clamped,
        &regime,
    );
    let derivation = Derivation {
        model: DerivedModel::Lattice(lattice),
        fit: FitDetail::Paper(fit),
        mass,
        derived,
        given,
        given_trajectory,
        second_excitation,
        frequencies,
        regime,
        probes: setup.probes().to_vec(),
        probe_nodes: setup.probe_nodes().to_vec(),
        dnurbs_trajectory: reference.0,
        msm_trajectory,
        node_velocities: setup.node_velocities().to_vec(),
        spectrum,
        warnings,
    };
    Ok((derivation, setup))
}

/// The frequency table of a spring lattice: the distinct non-zero frequencies of both
/// spectra by rank (no MAC: a spring lattice's modes are not isotropic triplets).
fn paper_frequencies(spectrum: &Spectrum) -> Vec<FrequencyRow> {
    let distinct = |v: &[f64]| -> Vec<f64> {
        let mut out: Vec<f64> = Vec::new();
        for &w in v.iter().filter(|&&w| w > 0.0) {
            if out.last().is_none_or(|&l| (w - l).abs() > 1e-9 * w) {
                out.push(w);
            }
        }
        out
    };
    let (a, b) = (distinct(&spectrum.dnurbs), distinct(&spectrum.msm));
    a.iter()
        .zip(&b)
        .take(TABLE_MODES)
        .enumerate()
        .map(|(i, (&d, &m))| FrequencyRow {
            mode: i + 1,
            dnurbs: d,
            msm_mode: i + 1,
            msm: m,
            relative_difference: m / d - 1.0,
            mac: None,
        })
        .collect()
}
