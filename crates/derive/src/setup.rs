//! What a derivation starts from ([`Config`]) and what every step of it shares ([`Setup`]):
//! the D-NURBS model, the lattice sampled from its surface, Ω, the unit matrices `G_c` and the
//! two fit problems of eq. (15).

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material};
use nurbspring_geom::NurbsSurface;
use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::{Class, Constants, LatticeOptions, MsmModel, SpringLattice};
use nurbspring_sim::{IntegratorKind, RunOptions, State};
use serde::{Deserialize, Serialize};

use crate::fit::{FitDofs, FitResult, StiffnessFit};
use crate::omega::NodeState;
use crate::runner::{Watched, record_noted};
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
}

/// The pieces shared by every step and every reading: model, lattice, Ω, unit matrices, fits.
pub struct Setup {
    model: DnurbsModel,
    lattice: SpringLattice,
    omega: Omega,
    fit_all: StiffnessFit,
    fit_free: StiffnessFit,
    dnurbs_initial: State,
    nodes: NodeState,
    probes: Vec<(f64, f64)>,
    probe_omega: Omega,
    probe_nodes: Vec<usize>,
}

impl Setup {
    /// Builds the model, the lattice, Ω, the unit matrices and both fit problems.
    pub fn new(config: &Config) -> Result<Self, DeriveError> {
        RunOptions::new(
            config.time.dt,
            config.time.t_end,
            config.time.msm_integrator,
        )
        .validate(0.0)?;
        let geometry = Geometry::Surface(config.surface.clone());
        let model = DnurbsModel::new(
            geometry.clone(),
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
        let omega = Omega::new(&geometry, &params, weights_as_dofs)?;
        let x0 = lattice.flat_positions();
        let unit: Vec<(Class, SparseMatrix)> = lattice
            .classes()
            .into_iter()
            .map(|class| (class, lattice.unit_stiffness(class, &x0)))
            .collect();
        let k_d = &model.matrices().stiffness;
        let n_elements = lattice.springs.len();
        let fit_all = StiffnessFit::new(k_d, omega.matrix(), &unit, n_elements, None)?;
        let fit_free = StiffnessFit::new(
            k_d,
            omega.matrix(),
            &unit,
            n_elements,
            Some(model.dof_map().free()),
        )?;
        let dnurbs_initial = config.initial.state(&model);
        let nodes = omega.node_state(&model, &dnurbs_initial);
        let probe_omega = Omega::new(&geometry, &config.probes, weights_as_dofs)?;
        let probe_nodes = config
            .probes
            .iter()
            .map(|&(u, v)| lattice.node_nearest(u, v))
            .collect();
        Ok(Self {
            model,
            lattice,
            omega,
            fit_all,
            fit_free,
            dnurbs_initial,
            nodes,
            probes: config.probes.clone(),
            probe_omega,
            probe_nodes,
        })
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

    /// Probe parameters, the centre first.
    pub fn probes(&self) -> &[(f64, f64)] {
        &self.probes
    }

    /// The lattice node nearest each probe.
    pub fn probe_nodes(&self) -> &[usize] {
        &self.probe_nodes
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
        Ok(FitResult {
            constants: fit.constants(&k),
            relative_residual: fit.relative_residual(&k)?,
        })
    }

    /// Residuals of eq. (15) at given constants, (every dof, free dofs).
    pub fn residuals_at(&self, constants: &Constants) -> Result<(f64, f64), DeriveError> {
        let at = |fit: &StiffnessFit| fit.relative_residual(&constants.values_of(fit.classes()));
        Ok((at(&self.fit_all)?, at(&self.fit_free)?))
    }

    /// The lattice with the given constants and uniform node mass.
    pub fn lattice_with(&self, constants: &Constants, m: f64) -> SpringLattice {
        let mut lattice = self.lattice.clone();
        lattice.set_constants(constants);
        lattice.set_mass(m);
        lattice
    }

    /// ω_max and 2/ω_max of the MSM with these parameters.
    pub fn stability(&self, constants: &Constants, m: f64) -> Result<(f64, f64), DeriveError> {
        let model = MsmModel::new(self.lattice_with(constants, m))?;
        let s = model.stability()?;
        Ok((s.omega_max, s.dt_critical))
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
        integrator: IntegratorKind,
        dt: f64,
        t_end: f64,
        force_unstable: bool,
        cancel: Option<Arc<AtomicBool>>,
    ) -> Result<Trajectory, DeriveError> {
        let model = MsmModel::new(lattice)?;
        let initial =
            model.initial_state_displaced(&self.nodes.velocities, &self.nodes.displacements);
        let mut opts = RunOptions::new(dt, t_end, integrator);
        opts.force_unstable = force_unstable;
        opts.cancel = cancel;
        let watched = Watched::Msm {
            model: &model,
            nodes: &self.probe_nodes,
        };
        record_noted(watched, initial, &opts)
    }
}
