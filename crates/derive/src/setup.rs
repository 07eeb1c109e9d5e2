//! What a derivation starts from ([`Config`], with its [`Method`]) and what every step of it
//! shares ([`Setup`]): the D-NURBS model, the lattice sampled from its surface or curve, Ω, the
//! probes, and for the paper's derivation the two fit problems of eq. (15).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material};
use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::{Class, Constants, LatticeOptions, MsmModel, SpringLattice};
use nurbspring_sim::{
    IntegratorKind, RunOptions, Schedule, StabilityLimit, State, uniform_stability_limit,
};
use serde::{Deserialize, Serialize};

use crate::fit::{FitDofs, FitResult, StiffnessFit};
use crate::method::Method;
use crate::omega::NodeState;
use crate::runner::{Recording, Watched, noted, record, record_noted};
use crate::{DeriveError, Omega, Trajectory};

/// How the stiffness fit is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FitMethod {
    /// Normal equations (docs/math.md §6).
    #[default]
    ClosedForm,
    /// The paper's trust-region iteration.
    TrustRegion,
}

impl FitMethod {
    /// "closed form" or "trust region".
    pub fn label(self) -> &'static str {
        match self {
            FitMethod::ClosedForm => "closed form",
            FitMethod::TrustRegion => "trust region",
        }
    }
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

/// How far each candidate of the eigenvalue scan is run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassScan {
    /// A candidate stops as soon as its error's running sum of squares shows that its RMS
    /// over the whole run exceeds the best complete candidate's of the batches before it: the
    /// selected mass is the same as with [`MassScan::Complete`], the stopped candidates report
    /// a lower bound of their RMS (docs/math.md §6).
    #[default]
    Pruned,
    /// Every candidate runs to the end (its whole RMS is reported).
    Complete,
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
    /// Whether a candidate that can no longer win stops early.
    pub scan: MassScan,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            dofs: FitDofs::All,
            nonnegative: false,
            method: FitMethod::ClosedForm,
            mass: MassChoice::EigenvalueScan,
            max_candidates: 0,
            scan: MassScan::Pruned,
        }
    }
}

/// The initial state of a scene: velocities of the control points (one for all, or one per
/// point; fixed points get zero), of the weights (weights as unknowns), and a displacement of
/// every free control point.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct InitialConditions {
    /// One velocity for every control point, or one per control point.
    pub velocities: Vec<[f64; 3]>,
    /// `ẇ` of every free weight.
    pub weight_velocity: f64,
    /// Added to every free control point at t = 0.
    pub displacement: [f64; 3],
}

impl InitialConditions {
    /// The D-NURBS state at t = 0 (reduced coordinates).
    pub fn state(&self, model: &DnurbsModel) -> State {
        model.initial_state_displaced(&self.velocities, self.weight_velocity, self.displacement)
    }
}

/// Time stepping of both models.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TimeSettings {
    /// Time step [s].
    pub dt: f64,
    /// End time [s].
    pub t_end: f64,
    /// D-NURBS integrator.
    pub dnurbs_integrator: IntegratorKind,
    /// MSM integrator.
    pub msm_integrator: IntegratorKind,
}

/// Everything a derivation needs (a scene, translated).
#[derive(Clone, Debug)]
pub struct Config {
    /// The derivation.
    pub method: Method,
    /// The D-NURBS surface or curve at t = 0.
    pub geometry: Geometry,
    /// Material.
    pub material: Material,
    /// Loads.
    pub loads: Loads,
    /// Constraints.
    pub constraints: Constraints,
    /// D-NURBS options.
    pub dnurbs: DnurbsOptions,
    /// Lattice options (their constants and mass are replaced by the fit).
    pub lattice: LatticeOptions,
    /// Initial state.
    pub initial: InitialConditions,
    /// Time stepping.
    pub time: TimeSettings,
    /// Fit options.
    pub fit: FitOptions,
    /// Probe parameters `(u, v)`, the centre of the domain first.
    pub probes: Vec<(f64, f64)>,
    /// Constants and node mass given by the scene (for the paper's scene, the published
    /// ones), evaluated beside the derived ones.
    pub given: Option<(Constants, f64)>,
    /// The damping coefficient of every node of the paper's lattice when the scene gives one;
    /// `None`: the D-NURBS's damping per unit mass, `γ/μ` times the node
    /// mass (the D-NURBS's `D = (γ/μ) M`, as the linear derivations' nodes carry it).
    pub node_damping: Option<f64>,
}

/// The two fit problems of eq. (15): every dof, free dofs.
pub struct Fits {
    all: StiffnessFit,
    free: StiffnessFit,
}

/// The pieces shared by every step and every reading: model, lattice, Ω, probes; the fit
/// problems of eq. (15) are built on first use.
pub struct Setup {
    model: DnurbsModel,
    lattice: SpringLattice,
    omega: Omega,
    fits: std::sync::OnceLock<Fits>,
    /// The uniform stability limit of the lattice with unit node masses, per set of
    /// constants (the mass scan asks for it with one set and many masses).
    unit_mass_limits: std::sync::Mutex<Vec<(Constants, Option<StabilityLimit>)>>,
    dnurbs_initial: State,
    nodes: NodeState,
    probe_nodes: Vec<usize>,
    probe_params: Vec<(f64, f64)>,
    probe_omega: Omega,
    /// `Config::node_damping`, and `γ/μ` for the nodes whose damping follows their mass.
    node_damping: Option<f64>,
    damping_ratio: f64,
}

impl Setup {
    /// Builds the model, the lattice and Ω; each probe is watched at the lattice node nearest
    /// to it, on the D-NURBS at that node's own parameters.
    pub fn new(config: &Config) -> Result<Self, DeriveError> {
        RunOptions::new(
            config.time.dt,
            config.time.t_end,
            config.time.msm_integrator,
        )
        .validate(0.0)?;
        let model = DnurbsModel::new(
            config.geometry.clone(),
            config.material.clone(),
            config.loads.clone(),
            &config.constraints,
            config.dnurbs.clone(),
        )?;
        let lattice = match &config.geometry {
            Geometry::Surface(s) => {
                SpringLattice::from_surface(s, &config.lattice, model.fixed_points())?
            }
            Geometry::Curve(c) => {
                SpringLattice::from_curve(c, &config.lattice, model.fixed_points())?
            }
        };
        let params = lattice
            .params
            .clone()
            .ok_or(DeriveError::LatticeWithoutParameters)?;
        let weights_as_dofs = config.dnurbs.weights_as_dofs;
        let omega = Omega::new(&config.geometry, &params, weights_as_dofs)?;
        let dnurbs_initial = config.initial.state(&model);
        let nodes = omega.node_state(&model, &dnurbs_initial);
        let probe_nodes: Vec<usize> = config
            .probes
            .iter()
            .map(|&(u, v)| lattice.node_nearest(u, v))
            .collect();
        let probe_params: Vec<(f64, f64)> = probe_nodes.iter().map(|&a| params[a]).collect();
        let probe_omega = Omega::new(&config.geometry, &probe_params, weights_as_dofs)?;
        Ok(Self {
            model,
            lattice,
            omega,
            fits: std::sync::OnceLock::new(),
            unit_mass_limits: std::sync::Mutex::new(Vec::new()),
            dnurbs_initial,
            nodes,
            probe_nodes,
            probe_params,
            probe_omega,
            node_damping: config.node_damping,
            damping_ratio: config.material.gamma / config.material.mu,
        })
    }

    /// The fit problems of eq. (15), built on first use.
    fn fits(&self) -> Result<&Fits, DeriveError> {
        if let Some(f) = self.fits.get() {
            return Ok(f);
        }
        let x0 = self.lattice.flat_positions();
        let unit: Vec<(Class, SparseMatrix)> = self
            .lattice
            .classes()
            .into_iter()
            .map(|class| (class, self.lattice.unit_stiffness(class, &x0)))
            .collect();
        let k_d = &self.model.matrices().stiffness;
        let n = self.lattice.n_elements();
        let all = StiffnessFit::new(k_d, self.omega.matrix(), &unit, n, None)?;
        let free = StiffnessFit::new(
            k_d,
            self.omega.matrix(),
            &unit,
            n,
            Some(self.model.dof_map().free()),
        )?;
        Ok(self.fits.get_or_init(|| Fits { all, free }))
    }

    /// The D-NURBS model.
    pub fn model(&self) -> &DnurbsModel {
        &self.model
    }

    /// The lattice sampled from the surface (constants and mass as in the options).
    pub fn lattice(&self) -> &SpringLattice {
        &self.lattice
    }

    /// Ω of the lattice nodes.
    pub fn omega(&self) -> &Omega {
        &self.omega
    }

    /// Initial node velocities `Ω ṗ(0)` (paper eq. (18)).
    pub fn node_velocities(&self) -> &[[f64; 3]] {
        &self.nodes.velocities
    }

    /// The parameters the probes are watched at: those of their lattice nodes, the centre's
    /// first.
    pub fn probes(&self) -> &[(f64, f64)] {
        &self.probe_params
    }

    /// Ω of the probes (the D-NURBS points at the probe nodes' parameters).
    pub fn probe_omega(&self) -> &Omega {
        &self.probe_omega
    }

    /// The D-NURBS state at t = 0 (reduced coordinates).
    pub fn dnurbs_initial(&self) -> &State {
        &self.dnurbs_initial
    }

    /// The nodes' initial state (paper eqs. (11), (18)).
    pub fn node_state(&self) -> &NodeState {
        &self.nodes
    }

    /// The lattice node nearest each probe.
    pub fn probe_nodes(&self) -> &[usize] {
        &self.probe_nodes
    }

    /// The fit problem of a reading.
    pub fn fit(&self, dofs: FitDofs) -> Result<&StiffnessFit, DeriveError> {
        let fits = self.fits()?;
        Ok(match dofs {
            FitDofs::All => &fits.all,
            FitDofs::Free => &fits.free,
        })
    }

    /// Solves one reading in closed form.
    pub fn solve(&self, dofs: FitDofs, nonnegative: bool) -> Result<FitResult, DeriveError> {
        let fit = self.fit(dofs)?;
        let k = fit.solve(nonnegative)?;
        Ok(FitResult {
            constants: fit.constants(&k),
            relative_residual: fit.relative_residual(&k)?,
        })
    }

    /// Residuals of eq. (15) at given constants, (every dof, free dofs).
    pub fn residuals_at(&self, constants: &Constants) -> Result<(f64, f64), DeriveError> {
        let at = |fit: &StiffnessFit| fit.relative_residual(&constants.values_of(fit.classes()));
        let fits = self.fits()?;
        Ok((at(&fits.all)?, at(&fits.free)?))
    }

    /// The lattice with the given constants and uniform node mass, every node damped by
    /// [`Setup::node_damping`] of that mass.
    pub fn lattice_with(&self, constants: &Constants, m: f64) -> SpringLattice {
        let mut lattice = self.lattice.clone();
        lattice.set_constants(constants);
        lattice.set_mass(m);
        lattice.set_damping(self.node_damping(m));
        lattice
    }

    /// The damping coefficient of a node of mass `m`: the scene's node damping when it gives
    /// one, else `γ/μ · m` (the D-NURBS's damping per unit mass).
    pub fn node_damping(&self, m: f64) -> f64 {
        self.node_damping.unwrap_or(self.damping_ratio * m)
    }

    /// ω_max and 2/ω_max of the MSM with these parameters.
    pub fn stability(&self, constants: &Constants, m: f64) -> Result<(f64, f64), DeriveError> {
        let model = MsmModel::new(self.lattice_with(constants, m))?;
        let s = model.stability()?;
        Ok((s.omega_max, s.dt_critical))
    }

    /// The stable way to run the MSM with these parameters with `requested` at Δt, and the
    /// stability limit that holds for that run ([`Schedule::stable`]: an explicit scheme in
    /// substeps below the lattice's uniform limit).
    ///
    /// Every node has the mass m, so `M = m M₁` and the uniform limit is that of unit masses
    /// times `√m`: it is computed once per set of constants.
    pub fn schedule(
        &self,
        constants: &Constants,
        m: f64,
        requested: IntegratorKind,
        dt: f64,
    ) -> Result<(Schedule, Option<StabilityLimit>), DeriveError> {
        if !requested.is_explicit() {
            return Ok((Schedule::plain(requested), None));
        }
        let known = {
            let cache = self.unit_mass_limits.lock().expect("no panic while held");
            cache.iter().find(|(c, _)| c == constants).map(|(_, l)| *l)
        };
        let unit = match known {
            Some(limit) => limit,
            None => {
                let model = MsmModel::new(self.lattice_with(constants, 1.0))?;
                let limit = uniform_stability_limit(&model)?;
                self.unit_mass_limits
                    .lock()
                    .expect("no panic while held")
                    .push((constants.clone(), limit));
                limit
            }
        };
        match unit {
            Some(unit) => {
                let scale = m.sqrt();
                let uniform = StabilityLimit {
                    omega_max: unit.omega_max / scale,
                    dt_critical: unit.dt_critical * scale,
                };
                Ok(Schedule::below(requested, dt, uniform))
            }
            None => {
                let model = MsmModel::new(self.lattice_with(constants, m))?;
                Ok(Schedule::stable(
                    &model,
                    model.initial_positions(),
                    requested,
                    dt,
                )?)
            }
        }
    }

    /// Runs the D-NURBS model from the scene's initial state, recording the probes.
    pub fn run_dnurbs(
        &self,
        integrator: IntegratorKind,
        dt: f64,
        t_end: f64,
        cancel: Option<Arc<AtomicBool>>,
    ) -> Result<Trajectory, DeriveError> {
        let mut opts = RunOptions::new(dt, t_end, integrator);
        opts.cancel = cancel;
        let watched = Watched::Dnurbs {
            model: &self.model,
            probes: &self.probe_omega,
        };
        record_noted(watched, self.dnurbs_initial.clone(), &opts)
    }

    /// Runs an MSM on this setup's lattice from the initial state mapped by Ω (eqs. 11, 18),
    /// recording the nodes nearest the probes.
    pub fn run_msm(
        &self,
        lattice: SpringLattice,
        (schedule, stability): (Schedule, Option<StabilityLimit>),
        dt: f64,
        t_end: f64,
        force_unstable: bool,
        cancel: Option<Arc<AtomicBool>>,
    ) -> Result<Trajectory, DeriveError> {
        let mut opts = RunOptions::scheduled(dt, t_end, schedule, stability);
        opts.force_unstable = force_unstable;
        opts.cancel = cancel;
        self.run_msm_from(lattice, &self.nodes, &opts)
    }

    /// [`Setup::run_msm`] (not forced above a stability limit) with `watch(step, coordinates
    /// of every node)` called on each step of Δt, step 0 included: when it returns `false` the
    /// run ends there, and the trajectory so far is returned with `true`. A cancellation by
    /// `cancel` is [`DeriveError::Cancelled`].
    pub fn run_msm_watched(
        &self,
        lattice: SpringLattice,
        (schedule, stability): (Schedule, Option<StabilityLimit>),
        (dt, t_end): (f64, f64),
        cancel: Option<&AtomicBool>,
        watch: &mut dyn FnMut(usize, &[f64]) -> bool,
    ) -> Result<(Trajectory, bool), DeriveError> {
        let stop = Arc::new(AtomicBool::new(false));
        let mut opts = RunOptions::scheduled(dt, t_end, schedule, stability);
        opts.cancel = Some(stop.clone());
        let (model, initial) = self.msm_start(lattice, &self.nodes)?;
        let watched = Watched::Msm {
            model: &model,
            nodes: &self.probe_nodes,
        };
        let mut ended = false;
        let (traj, outcome) = record(
            watched,
            initial,
            &opts,
            Recording::default(),
            &mut |sample, x| {
                let cancelled = cancel.is_some_and(|c| c.load(Ordering::Relaxed));
                ended = ended || (!cancelled && !watch(sample.step, x));
                if cancelled || ended {
                    stop.store(true, Ordering::Relaxed);
                }
            },
        );
        if ended && matches!(&outcome, Ok(summary) if summary.cancelled) {
            return Ok((traj, true));
        }
        noted(traj, outcome).map(|traj| (traj, false))
    }

    /// An MSM of `lattice` and its state at t = 0 from the node state `nodes`.
    fn msm_start(
        &self,
        lattice: SpringLattice,
        nodes: &NodeState,
    ) -> Result<(MsmModel, State), DeriveError> {
        let model = MsmModel::new(lattice)?;
        let initial = model.initial_state_displaced(&nodes.velocities, &nodes.displacements);
        Ok((model, initial))
    }

    /// Runs an MSM on this setup's lattice from the node state `nodes`, recording the probe
    /// nodes.
    pub fn run_msm_from(
        &self,
        lattice: SpringLattice,
        nodes: &NodeState,
        opts: &RunOptions,
    ) -> Result<Trajectory, DeriveError> {
        let (model, initial) = self.msm_start(lattice, nodes)?;
        let watched = Watched::Msm {
            model: &model,
            nodes: &self.probe_nodes,
        };
        record_noted(watched, initial, opts)
    }
}
