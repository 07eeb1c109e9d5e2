//! The derivation pipeline of the paper's Section III, end to end: D-NURBS model, lattice,
//! Ω, stiffness fit, mass scan, and side-by-side simulation of both models.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material};
use nurbspring_geom::NurbsSurface;
use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::{LatticeOptions, MsmModel, SpringKind, SpringLattice};
use nurbspring_sim::{IntegratorKind, RunOptions, Sample, SimError, State, simulate};
use serde::Serialize;

use crate::DeriveError;
use crate::fit::{FitDofs, StiffnessFit};
use crate::mass::mass_eigenvalues;
use crate::omega::omega_matrix;
use crate::validation::{Comparison, Trajectory, compare};

/// How the stiffness fit is solved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FitMethod {
    /// Normal equations (SPEC §6).
    ClosedForm,
    /// The paper's trust-region iteration.
    TrustRegion,
}

/// How the node mass is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassChoice {
    /// Try every distinct non-null eigenvalue of M (Section III) and keep the best.
    EigenvalueScan,
    /// Use this mass.
    Fixed(f64),
}

/// Options of the fit and mass steps.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// Which dofs enter eq. (15).
    pub dofs: FitDofs,
    /// Constrain `k ≥ 0`.
    pub nonnegative: bool,
    /// Closed form or trust region.
    pub method: FitMethod,
    /// Mass choice.
    pub mass: MassChoice,
    /// Try at most this many eigenvalues, smallest first (0 = all).
    pub max_candidates: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            dofs: FitDofs::All,
            nonnegative: false,
            method: FitMethod::ClosedForm,
            mass: MassChoice::EigenvalueScan,
            max_candidates: 0,
        }
    }
}

/// Everything a derivation needs (a scene, converted).
#[derive(Clone, Debug)]
pub struct ExperimentConfig {
    /// The D-NURBS surface at t = 0.
    pub surface: NurbsSurface,
    /// Material.
    pub material: Material,
    /// Loads.
    pub loads: Loads,
    /// Constraints.
    pub constraints: Constraints,
    /// D-NURBS options.
    pub dnurbs: DnurbsOptions,
    /// Lattice options (their k and mass are overwritten by the fit).
    pub lattice: LatticeOptions,
    /// Initial velocity of every control point (fixed ones are zeroed by the model).
    pub initial_velocity: Vec<[f64; 3]>,
    /// Time step.
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// D-NURBS integrator.
    pub dnurbs_integrator: IntegratorKind,
    /// MSM integrator.
    pub msm_integrator: IntegratorKind,
    /// Fit options.
    pub fit: FitOptions,
    /// Extra probe points `(u, v)`; `(0.5, 0.5)` always comes first.
    pub probes: Vec<(f64, f64)>,
    /// Spring constants and mass given by the scene (for the paper's scene, the published
    /// ones), evaluated beside the derived ones.
    pub given: Option<(FitResult, f64)>,
}

/// Spring constants by class, as reported.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FitResult {
    /// Structural spring constant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_edge: Option<f64>,
    /// Shear spring constant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_diag: Option<f64>,
    /// Bending spring constant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_bend: Option<f64>,
    /// `‖Ωᵀ K_S Ω − K_D‖_F / ‖K_D‖_F` on the dofs of this fit.
    pub relative_residual: f64,
}

impl FitResult {
    /// Builds the result from `k` in the order of `kinds`.
    pub fn new(kinds: &[SpringKind], k: &[f64], relative_residual: f64) -> Self {
        let mut r = FitResult {
            relative_residual,
            ..Default::default()
        };
        for (kind, &kc) in kinds.iter().zip(k) {
            match kind {
                SpringKind::Structural => r.k_edge = Some(kc),
                SpringKind::Shear => r.k_diag = Some(kc),
                SpringKind::Bend => r.k_bend = Some(kc),
            }
        }
        r
    }

    /// The constant of one class (0 when absent).
    pub fn k(&self, kind: SpringKind) -> f64 {
        match kind {
            SpringKind::Structural => self.k_edge,
            SpringKind::Shear => self.k_diag,
            SpringKind::Bend => self.k_bend,
        }
        .unwrap_or(0.0)
    }
}

/// The four readings of eq. (15) plus the trust-region check.
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    /// Classes fitted.
    pub classes: Vec<SpringKind>,
    /// Every dof, unconstrained (the literal equation).
    pub all_dofs: FitResult,
    /// Free dofs only, unconstrained.
    pub free_dofs: FitResult,
    /// Every dof, `k ≥ 0`.
    pub all_dofs_nonnegative: FitResult,
    /// Free dofs only, `k ≥ 0`.
    pub free_dofs_nonnegative: FitResult,
    /// The trust-region solution for the selected reading and its agreement with the closed form.
    pub trust_region: TrustRegionReport,
    /// The reading used for the derived MSM.
    pub selected_reading: String,
    /// The constants used for the derived MSM.
    pub selected: FitResult,
}

/// The trust-region solve of the selected reading.
#[derive(Clone, Debug, Serialize)]
pub struct TrustRegionReport {
    /// Its constants.
    pub result: FitResult,
    /// Iterations.
    pub iterations: usize,
    /// Largest relative difference to the closed form.
    pub max_relative_difference_to_closed_form: f64,
}

/// One mass candidate of the scan.
#[derive(Clone, Debug, Serialize)]
pub struct MassCandidate {
    /// Node mass tried.
    pub m: f64,
    /// RMS of the central-node z difference to the D-NURBS run (∞ when the MSM run failed).
    pub rms: f64,
    /// Max abs of that difference.
    pub max_abs: f64,
    /// Integrator used for this candidate.
    pub integrator: String,
    /// Why the run stopped early, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

/// The mass step.
#[derive(Clone, Debug, Serialize)]
pub struct MassReport {
    /// Distinct non-null eigenvalues of the full M, ascending.
    pub eigenvalues: Vec<f64>,
    /// Distinct eigenvalues of M restricted to the free dofs, ascending.
    pub eigenvalues_free_dofs: Vec<f64>,
    /// Every candidate tried with its error.
    pub candidates: Vec<MassCandidate>,
    /// The mass selected (smallest RMS among the runs that finished).
    pub selected: f64,
    /// How it was chosen.
    pub rule: String,
}

/// Stability of an MSM parameter set.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterSet {
    /// Structural constant.
    pub k_edge: f64,
    /// Shear constant.
    pub k_diag: f64,
    /// Bending constant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_bend: Option<f64>,
    /// Node mass.
    pub m: f64,
    /// ω_max of the linearized MSM at rest.
    pub omega_max: f64,
    /// Explicit stability limit 2/ω_max.
    pub dt_critical: f64,
    /// Whether the scene's Δt exceeds it.
    pub dt_exceeds_explicit_limit: bool,
    /// Relative residual of eq. (15), every dof.
    pub relative_residual_all_dofs: f64,
    /// Relative residual of eq. (15), free dofs.
    pub relative_residual_free_dofs: f64,
    /// Central node z: comparison with the D-NURBS run, with the scene's MSM integrator when
    /// it is stable at the scene's Δt, Newmark otherwise.
    pub validation: ValidationReport,
    /// When the scene's integrator is explicit and Δt exceeds its limit: what that run does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub explicit_run: Option<ValidationReport>,
}

/// Figure 3 numbers.
#[derive(Clone, Debug, Serialize)]
pub struct ValidationReport {
    /// Integrator of the MSM run.
    pub integrator: String,
    /// RMS of the central node's z difference.
    pub rms: f64,
    /// Max abs of that difference.
    pub max_abs: f64,
    /// RMS relative to the D-NURBS amplitude.
    pub relative_rms: f64,
    /// D-NURBS central-node amplitude `max |z − z₀|`.
    pub dnurbs_amplitude: f64,
    /// Dominant period of the D-NURBS central node.
    pub dnurbs_period: Option<f64>,
    /// Dominant period of the MSM central node.
    pub msm_period: Option<f64>,
    /// Samples compared.
    pub samples: usize,
    /// Why the MSM run stopped early, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm_stopped: Option<String>,
}

impl ValidationReport {
    fn new(integrator: IntegratorKind, c: &Comparison, stopped: Option<String>) -> Self {
        Self {
            integrator: integrator.name().to_string(),
            rms: c.rms,
            max_abs: c.max_abs,
            relative_rms: c.relative_rms,
            dnurbs_amplitude: c.reference_amplitude,
            dnurbs_period: c.reference_period,
            msm_period: c.other_period,
            samples: c.samples,
            msm_stopped: stopped,
        }
    }
}

/// Result of [`derive_msm`].
#[derive(Clone, Debug)]
pub struct Derivation {
    /// The derived lattice (fitted k, selected mass, zero damping).
    pub lattice: SpringLattice,
    /// Fit step.
    pub fit: FitReport,
    /// Mass step.
    pub mass: MassReport,
    /// The derived parameters with their stability and validation.
    pub derived: ParameterSet,
    /// The scene's own parameters, evaluated the same way.
    pub given: Option<ParameterSet>,
    /// The MSM run with the scene's own parameters.
    pub given_trajectory: Option<Trajectory>,
    /// Probe parameters `(u, v)`, `(0.5, 0.5)` first.
    pub probes: Vec<(f64, f64)>,
    /// Lattice node of each probe.
    pub probe_nodes: Vec<usize>,
    /// The D-NURBS run.
    pub dnurbs_trajectory: Trajectory,
    /// The derived MSM run.
    pub msm_trajectory: Trajectory,
    /// Ω.
    pub omega: SparseMatrix,
    /// Initial node velocities `Ω ṗ(0)` (eq. 18), per node.
    pub node_velocities: Vec<[f64; 3]>,
    /// Angular frequencies of both linearized models, lowest first.
    pub spectrum: Spectrum,
}

/// Angular frequencies (rad/s) of the constrained D-NURBS and of the derived MSM linearized at
/// rest, lowest first (the MSM's zero frequencies are its directions without linear stiffness).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Spectrum {
    /// D-NURBS: `K φ = ω² M φ` on the free dofs.
    pub dnurbs: Vec<f64>,
    /// MSM: `K_T φ = ω² M_S φ` on the free node dofs.
    pub msm: Vec<f64>,
}

/// Largest model whose full spectrum is reported (dense eigenproblems).
const MAX_SPECTRUM_DOFS: usize = 1500;

fn msm_spectrum(lattice: &SpringLattice) -> Result<Vec<f64>, DeriveError> {
    use nurbspring_sim::DynamicModel;
    let model = MsmModel::new(lattice.clone())?;
    let n = model.n_dofs();
    if n == 0 || n > MAX_SPECTRUM_DOFS {
        return Ok(Vec::new());
    }
    let q0 = model.initial_positions().to_vec();
    let k = model.tangent_stiffness(&q0).to_dense();
    let m = model.mass().to_sparse().to_dense();
    let eig = nurbspring_linalg::generalized_symmetric_eigen(&k, &m)?;
    let scale = eig.values.iter().map(|x| x.abs()).fold(0.0, f64::max);
    Ok(eig
        .values
        .iter()
        .map(|&l| {
            if l.abs() <= 1e-12 * scale {
                0.0
            } else {
                l.max(0.0).sqrt()
            }
        })
        .collect())
}

/// The pieces shared by every reading: model, lattice, Ω, unit matrices, fits.
pub struct Setup {
    /// D-NURBS model.
    pub model: DnurbsModel,
    /// Lattice sampled from the surface (k and mass as in the options).
    pub lattice: SpringLattice,
    /// Ω.
    pub omega: SparseMatrix,
    /// `(class, G_c)` at rest.
    pub unit: Vec<(SpringKind, SparseMatrix)>,
    /// Fit over every dof.
    pub fit_all: StiffnessFit,
    /// Fit over free dofs.
    pub fit_free: StiffnessFit,
    /// Full initial generalized velocity ṗ(0) (fixed dofs zero).
    pub p_dot0: Vec<f64>,
    /// Initial D-NURBS state on the free dofs.
    pub dnurbs_initial: State,
    /// Initial node velocities (eq. 18).
    pub node_velocities: Vec<[f64; 3]>,
    /// Probe parameters, (0.5, 0.5) first.
    pub probes: Vec<(f64, f64)>,
    /// J at each probe stacked (3 rows per probe), for D-NURBS probe positions.
    pub probe_omega: SparseMatrix,
}

impl Setup {
    /// Builds the model, lattice, Ω, the unit matrices and both fit problems.
    pub fn new(config: &ExperimentConfig) -> Result<Self, DeriveError> {
        if !(config.dt > 0.0 && config.dt.is_finite()) {
            return Err(SimError::InvalidTimeStep { dt: config.dt }.into());
        }
        if !(config.t_end > 0.0 && config.t_end.is_finite()) {
            return Err(SimError::InvalidDuration {
                t_end: config.t_end,
            }
            .into());
        }
        let model = DnurbsModel::new(
            Geometry::Surface(config.surface.clone()),
            config.material.clone(),
            config.loads.clone(),
            &config.constraints,
            config.dnurbs.clone(),
        )?;
        let lattice =
            SpringLattice::from_surface(&config.surface, &config.lattice, model.fixed_points())?;
        let params = lattice
            .params
            .clone()
            .ok_or(DeriveError::LatticeWithoutParameters)?;
        let weights_as_dofs = config.dnurbs.weights_as_dofs;
        let omega = omega_matrix(&config.surface, &params, weights_as_dofs)?;
        let x0 = lattice.flat_positions();
        let unit: Vec<(SpringKind, SparseMatrix)> = lattice
            .kinds_present()
            .into_iter()
            .map(|kind| (kind, lattice.unit_stiffness(kind, &x0)))
            .collect();
        let k_d = &model.matrices().stiffness;
        let n_springs = lattice.springs.len();
        let fit_all = StiffnessFit::new(k_d, &omega, &unit, n_springs, None)?;
        let fit_free =
            StiffnessFit::new(k_d, &omega, &unit, n_springs, Some(model.dof_map().free()))?;

        let dnurbs_initial = model.initial_state(&config.initial_velocity, 0.0);
        let p_dot0 = model.full_velocity(&dnurbs_initial.v);
        let mut xdot = vec![0.0; omega.nrows()];
        omega.mul_vec(&p_dot0, &mut xdot);
        let node_velocities: Vec<[f64; 3]> = xdot.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();

        let mut probes = vec![(0.5, 0.5)];
        probes.extend(config.probes.iter().copied().filter(|&p| p != (0.5, 0.5)));
        let probe_omega = omega_matrix(&config.surface, &probes, weights_as_dofs)?;
        Ok(Self {
            model,
            lattice,
            omega,
            unit,
            fit_all,
            fit_free,
            p_dot0,
            dnurbs_initial,
            node_velocities,
            probes,
            probe_omega,
        })
    }

    /// The fit problem of a reading.
    pub fn fit(&self, dofs: FitDofs) -> &StiffnessFit {
        match dofs {
            FitDofs::All => &self.fit_all,
            FitDofs::Free => &self.fit_free,
        }
    }

    /// Solves one reading in closed form.
    pub fn solve(&self, dofs: FitDofs, nonnegative: bool) -> Result<FitResult, DeriveError> {
        let fit = self.fit(dofs);
        let k = fit.solve(nonnegative)?;
        Ok(FitResult::new(fit.kinds(), &k, fit.relative_residual(&k)?))
    }

    /// Residuals of eq. (15) at given constants, (every dof, free dofs).
    pub fn residuals_at(&self, params: &FitResult) -> Result<(f64, f64), DeriveError> {
        let k_all: Vec<f64> = self.fit_all.kinds().iter().map(|&c| params.k(c)).collect();
        let k_free: Vec<f64> = self.fit_free.kinds().iter().map(|&c| params.k(c)).collect();
        Ok((
            self.fit_all.relative_residual(&k_all)?,
            self.fit_free.relative_residual(&k_free)?,
        ))
    }

    /// The lattice with the given constants and uniform node mass.
    pub fn lattice_with(&self, params: &FitResult, m: f64) -> SpringLattice {
        let mut lattice = self.lattice.clone();
        for kind in lattice.kinds_present() {
            lattice.set_stiffness(kind, params.k(kind));
        }
        lattice.set_mass(m);
        lattice
    }

    /// Runs the D-NURBS model, recording the probes.
    pub fn run_dnurbs(
        &self,
        integrator: IntegratorKind,
        dt: f64,
        t_end: f64,
        cancel: Option<Arc<AtomicBool>>,
        every_sample: &mut dyn FnMut(&Sample<'_>, &[f64]),
    ) -> Result<Trajectory, DeriveError> {
        let mut traj = Trajectory::new(self.probes.len());
        let mut opts = RunOptions::new(dt, t_end, integrator);
        opts.cancel = cancel;
        let mut pos = vec![0.0; self.probe_omega.nrows()];
        let model = &self.model;
        let probe_omega = &self.probe_omega;
        let mut observer = |s: &Sample<'_>| {
            let p = model.full_coordinates(s.q);
            probe_omega.mul_vec(&p, &mut pos);
            traj.t.push(s.t);
            for (i, probe) in traj.probes.iter_mut().enumerate() {
                probe.push([pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]]);
            }
            traj.energy.push([s.kinetic, s.potential]);
            every_sample(s, &p);
        };
        let result = simulate(
            &self.model,
            self.dnurbs_initial.clone(),
            &opts,
            &mut observer,
        );
        finish(result, &mut traj)?;
        Ok(traj)
    }

    /// Runs an MSM built from this setup's lattice with the given parameters.
    pub fn run_msm(
        &self,
        lattice: SpringLattice,
        integrator: IntegratorKind,
        dt: f64,
        t_end: f64,
        force_unstable: bool,
        cancel: Option<Arc<AtomicBool>>,
        every_sample: &mut dyn FnMut(&Sample<'_>, &[f64]),
    ) -> Result<(Trajectory, Vec<usize>), DeriveError> {
        let probe_nodes: Vec<usize> = self
            .probes
            .iter()
            .map(|&(u, v)| lattice.node_nearest(u, v))
            .collect();
        let model = MsmModel::new(lattice)?;
        let initial = model.initial_state(&self.node_velocities);
        let mut traj = Trajectory::new(self.probes.len());
        let mut opts = RunOptions::new(dt, t_end, integrator);
        opts.force_unstable = force_unstable;
        opts.cancel = cancel;
        let model_ref = &model;
        let nodes = &probe_nodes;
        let mut observer = |s: &Sample<'_>| {
            let x = model_ref.full_positions(s.q);
            traj.t.push(s.t);
            for (i, &a) in nodes.iter().enumerate() {
                traj.probes[i].push([x[3 * a], x[3 * a + 1], x[3 * a + 2]]);
            }
            traj.energy.push([s.kinetic, s.potential]);
            every_sample(s, &x);
        };
        let result = simulate(&model, initial, &opts, &mut observer);
        finish(result, &mut traj)?;
        Ok((traj, probe_nodes))
    }

    /// ω_max and 2/ω_max of the MSM with these parameters.
    pub fn stability(&self, params: &FitResult, m: f64) -> Result<(f64, f64), DeriveError> {
        let model = MsmModel::new(self.lattice_with(params, m))?;
        let s = model.stability()?;
        Ok((s.omega_max, s.dt_critical))
    }

    /// The candidate loop of Section III: simulates the MSM with `m = λ` for each candidate and
    /// compares the central node's z with the D-NURBS run. Each run uses the scene's integrator
    /// when it is stable at Δt, Newmark otherwise (recorded per candidate).
    pub fn mass_scan(
        &self,
        params: &FitResult,
        masses: &[f64],
        config: &ExperimentConfig,
        dnurbs: &Trajectory,
        cancel: Option<Arc<AtomicBool>>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Vec<MassCandidate>, DeriveError> {
        let z_ref = dnurbs.component(0, 2);
        let mut candidates = Vec::with_capacity(masses.len());
        for (i, &m) in masses.iter().enumerate() {
            if cancel.as_ref().is_some_and(|c| c.load(Ordering::Relaxed)) {
                return Err(DeriveError::Cancelled);
            }
            let (_, dt_crit) = self.stability(params, m)?;
            let integrator = scan_integrator(config.msm_integrator, config.dt, dt_crit);
            let (traj, _) = self.run_msm(
                self.lattice_with(params, m),
                integrator,
                config.dt,
                config.t_end,
                false,
                cancel.clone(),
                &mut |_, _| {},
            )?;
            let c = compare(&dnurbs.t, &z_ref, &traj.component(0, 2));
            let complete = traj.stopped.is_none() && c.samples == z_ref.len();
            candidates.push(MassCandidate {
                m,
                rms: if complete { c.rms } else { f64::INFINITY },
                max_abs: if complete { c.max_abs } else { f64::INFINITY },
                integrator: integrator.name().to_string(),
                stopped: traj.stopped.clone(),
            });
            progress(i + 1, masses.len());
        }
        Ok(candidates)
    }

    /// Evaluates a parameter set: stability, residuals and the central-node comparison. The
    /// comparison uses `integrator` when it is stable at the scene's Δt, Newmark otherwise; in
    /// that case the requested explicit run is also made (forced past its limit) and reported
    /// in `explicit_run`, to show what it does.
    pub fn evaluate(
        &self,
        params: &FitResult,
        m: f64,
        integrator: IntegratorKind,
        config: &ExperimentConfig,
        dnurbs: &Trajectory,
    ) -> Result<(ParameterSet, Trajectory), DeriveError> {
        let (omega_max, dt_critical) = self.stability(params, m)?;
        let (res_all, res_free) = self.residuals_at(params)?;
        let used = scan_integrator(integrator, config.dt, dt_critical);
        let z_ref = dnurbs.component(0, 2);
        let run = |kind: IntegratorKind| -> Result<(ValidationReport, Trajectory), DeriveError> {
            let (traj, _) = self.run_msm(
                self.lattice_with(params, m),
                kind,
                config.dt,
                config.t_end,
                true,
                None,
                &mut |_, _| {},
            )?;
            let c = compare(&dnurbs.t, &z_ref, &traj.component(0, 2));
            Ok((ValidationReport::new(kind, &c, traj.stopped.clone()), traj))
        };
        let (validation, traj) = run(used)?;
        let explicit_run = if used != integrator {
            Some(run(integrator)?.0)
        } else {
            None
        };
        Ok((
            ParameterSet {
                k_edge: params.k(SpringKind::Structural),
                k_diag: params.k(SpringKind::Shear),
                k_bend: params.k_bend,
                m,
                omega_max,
                dt_critical,
                dt_exceeds_explicit_limit: config.dt >= dt_critical,
                relative_residual_all_dofs: res_all,
                relative_residual_free_dofs: res_free,
                validation,
                explicit_run,
            },
            traj,
        ))
    }
}

/// Turns divergence, instability and cancellation into a note on the trajectory; other
/// errors propagate.
fn finish<T>(result: Result<T, SimError>, traj: &mut Trajectory) -> Result<(), DeriveError> {
    match result {
        Ok(_) => Ok(()),
        Err(
            e @ (SimError::Diverged { .. }
            | SimError::Unstable { .. }
            | SimError::NewtonFailed { .. }),
        ) => {
            traj.stopped = Some(e.to_string());
            Ok(())
        }
        Err(e) => Err(e.into()),
    }
}

/// The integrator to use for a candidate: the scene's, unless it is explicit and Δt is above
/// its stability limit, in which case Newmark (implicit, energy conserving) is used instead.
fn scan_integrator(requested: IntegratorKind, dt: f64, dt_critical: f64) -> IntegratorKind {
    if requested.is_explicit() && dt >= dt_critical {
        IntegratorKind::Newmark
    } else {
        requested
    }
}

/// Derives the MSM that mimics the D-NURBS model (paper Section III) and validates it
/// (Figure 3). `cancel` stops long runs (Ctrl-C); `progress(done, total)` reports the scan.
pub fn derive_msm(
    config: &ExperimentConfig,
    cancel: Option<Arc<AtomicBool>>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Derivation, Setup), DeriveError> {
    let setup = Setup::new(config)?;
    let is_cancelled = || cancel.as_ref().is_some_and(|c| c.load(Ordering::Relaxed));

    // Fit: the four readings, then the selected one (closed form or trust region).
    let all_dofs = setup.solve(FitDofs::All, false)?;
    let free_dofs = setup.solve(FitDofs::Free, false)?;
    let all_dofs_nonnegative = setup.solve(FitDofs::All, true)?;
    let free_dofs_nonnegative = setup.solve(FitDofs::Free, true)?;
    // A spring cannot have a negative constant: when the unconstrained optimum has one, the
    // derived MSM uses the k ≥ 0 optimum of the same reading, and the report says so.
    let unconstrained = match config.fit.dofs {
        FitDofs::All => &all_dofs,
        FitDofs::Free => &free_dofs,
    };
    let negative: Vec<String> = [
        ("k_edge", unconstrained.k_edge),
        ("k_diag", unconstrained.k_diag),
        ("k_bend", unconstrained.k_bend),
    ]
    .into_iter()
    .filter_map(|(name, k)| k.filter(|&k| k < 0.0).map(|k| format!("{name} = {k:.6}")))
    .collect();
    let nonnegative = config.fit.nonnegative || !negative.is_empty();
    let selected_closed = match (config.fit.dofs, nonnegative) {
        (FitDofs::All, false) => all_dofs.clone(),
        (FitDofs::Free, false) => free_dofs.clone(),
        (FitDofs::All, true) => all_dofs_nonnegative.clone(),
        (FitDofs::Free, true) => free_dofs_nonnegative.clone(),
    };
    let fit = setup.fit(config.fit.dofs);
    let start = vec![1.0; fit.kinds().len()];
    let tr = fit.trust_region(&start, nonnegative, 500)?;
    let tr_result = FitResult::new(fit.kinds(), &tr.k, fit.relative_residual(&tr.k)?);
    let max_rel = fit
        .kinds()
        .iter()
        .map(|&c| {
            let (a, b) = (tr_result.k(c), selected_closed.k(c));
            (a - b).abs() / b.abs().max(1e-300)
        })
        .fold(0.0, f64::max);
    let selected = match config.fit.method {
        FitMethod::ClosedForm => selected_closed.clone(),
        FitMethod::TrustRegion => tr_result.clone(),
    };
    let fit_report = FitReport {
        classes: fit.kinds().to_vec(),
        all_dofs,
        free_dofs,
        all_dofs_nonnegative,
        free_dofs_nonnegative,
        trust_region: TrustRegionReport {
            result: tr_result,
            iterations: tr.iterations,
            max_relative_difference_to_closed_form: max_rel,
        },
        selected_reading: format!(
            "{} dofs, {}, {}{}",
            config.fit.dofs.name(),
            if nonnegative {
                "k >= 0"
            } else {
                "unconstrained"
            },
            match config.fit.method {
                FitMethod::ClosedForm => "closed form",
                FitMethod::TrustRegion => "trust region",
            },
            if config.fit.nonnegative || negative.is_empty() {
                String::new()
            } else {
                format!(
                    " (k >= 0 imposed because the unconstrained fit gives {}, which no spring can have)",
                    negative.join(", ")
                )
            }
        ),
        selected: selected.clone(),
    };

    // The D-NURBS reference run.
    let dnurbs = setup.run_dnurbs(
        config.dnurbs_integrator,
        config.dt,
        config.t_end,
        cancel.clone(),
        &mut |_, _| {},
    )?;
    if is_cancelled() {
        return Err(DeriveError::Cancelled);
    }

    // Mass: eigenvalues of M and the candidate loop.
    let m_full = &setup.model.matrices().mass;
    let eigenvalues = mass_eigenvalues(m_full)?;
    let eigenvalues_free_dofs = mass_eigenvalues(setup.model.reduced_mass())?;
    let mut candidates = Vec::new();
    let (selected_m, rule) = match config.fit.mass {
        MassChoice::Fixed(m) => (m, format!("fixed by the scene: m = {m}")),
        MassChoice::EigenvalueScan => {
            let list: Vec<f64> = if config.fit.max_candidates > 0 {
                eigenvalues
                    .iter()
                    .copied()
                    .take(config.fit.max_candidates)
                    .collect()
            } else {
                eigenvalues.clone()
            };
            candidates =
                setup.mass_scan(&selected, &list, config, &dnurbs, cancel.clone(), progress)?;
            let best = candidates
                .iter()
                .filter(|c| c.rms.is_finite())
                .min_by(|a, b| a.rms.total_cmp(&b.rms))
                .map(|c| c.m)
                .or_else(|| eigenvalues.first().copied())
                .unwrap_or(1.0);
            (
                best,
                "every distinct non-null eigenvalue of M tried, smallest first; the one with the smallest RMS error of the central node's z against the D-NURBS run is kept".to_string(),
            )
        }
    };

    // The derived MSM, validated with a stable integrator (and the explicit run shown).
    let (derived, msm_traj) = setup.evaluate(
        &selected,
        selected_m,
        config.msm_integrator,
        config,
        &dnurbs,
    )?;
    let (given, given_trajectory) = match &config.given {
        Some((params, m)) => {
            let (p, t) = setup.evaluate(params, *m, config.msm_integrator, config, &dnurbs)?;
            (Some(p), Some(t))
        }
        None => (None, None),
    };
    let lattice = setup.lattice_with(&selected, selected_m);
    let spectrum = Spectrum {
        dnurbs: if setup.model.n_free() <= MAX_SPECTRUM_DOFS {
            setup.model.modes(setup.model.n_free())?.omega
        } else {
            Vec::new()
        },
        msm: msm_spectrum(&lattice)?,
    };
    let probe_nodes: Vec<usize> = setup
        .probes
        .iter()
        .map(|&(u, v)| lattice.node_nearest(u, v))
        .collect();
    let derivation = Derivation {
        lattice,
        fit: fit_report,
        mass: MassReport {
            eigenvalues,
            eigenvalues_free_dofs,
            candidates,
            selected: selected_m,
            rule,
        },
        derived,
        given,
        given_trajectory,
        probes: setup.probes.clone(),
        probe_nodes,
        dnurbs_trajectory: dnurbs,
        msm_trajectory: msm_traj,
        omega: setup.omega.clone(),
        node_velocities: setup.node_velocities.clone(),
        spectrum,
    };
    Ok((derivation, setup))
}
