//! The spring model against the shell (docs/math.md §11.2): the map from the shell's reduced
//! coordinates to the lattice nodes, work-equivalent node forces, a small-motion run, and the
//! large-motion runs (static load path and dynamic step load).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_dnurbs::{
    Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, PathSettings, ShellMaterial,
};
use nurbspring_geom::norm;
use nurbspring_linalg::{
    DenseMatrix, LuSolver, SparseMatrix, SpdSolver, generalized_eigen_sparse_lowest,
    generalized_symmetric_eigen,
};
use nurbspring_msm::{MsmModel, SpringLattice};
use nurbspring_sim::{
    DynamicModel, EnergyWatch, IntegratorKind, LinearModel, RunOptions, Sample, State,
    SystemMatrix, simulate,
};
use serde::Serialize;

use crate::{DeriveError, InitialConditions, compare_points};

/// Time steps per period of the lowest mode in the validation runs.
pub const STEPS_PER_PERIOD: usize = 100;
/// Periods of the lowest mode the small-motion run covers.
pub const SMALL_MOTION_PERIODS: f64 = 5.0;
/// Periods of the lowest mode the dynamic large-motion run covers.
pub const LARGE_MOTION_PERIODS: f64 = 3.0;
/// The spectral radius at infinity of the generalized-α the dynamic large-motion runs use (both
/// models). At 0.8 the cloth's shell run (quadratic 14², Δt = 5 ms) gains energy from about 1 s
/// on (+8.8 J at 1 s, +615 J at 3.5 s, for a cloth whose fall releases about 0.1 J); at 0.5 and
/// at 0 its energy decays and the two runs agree (examples/shell_self_check.rs).
pub const LARGE_MOTION_RHO_INFINITY: f64 = 0.5;
/// The largest displacement of the large-motion runs, over the size.
pub const LARGE_MOTION: f64 = 0.25;
/// Load levels recorded on the static load path.
pub const LOAD_LEVELS: usize = 4;
/// Dense eigensolver up to this many free dofs of the lattice.
const DENSE_LIMIT: usize = 600;

/// The linear map from the shell's reduced coordinates to the lattice nodes:
/// `x_nodes = Ω p`, `p = P q + offset` (Ω of paper eq. (14) at the nodes' parameters).
pub struct NodeMap {
    omega: SparseMatrix,
    all: SparseMatrix,
    free: SparseMatrix,
    free_rows: Vec<usize>,
}

impl NodeMap {
    /// Ω at the lattice's parameters and `A = Ω P`.
    pub fn new(
        geometry: &Geometry,
        lattice: &SpringLattice,
        model: &DnurbsModel,
    ) -> Result<Self, DeriveError> {
        let params = lattice
            .params
            .as_ref()
            .ok_or(DeriveError::LatticeWithoutParameters)?;
        let omega = geometry.stacked_jacobian(params, false)?;
        let n_q = model.n_free();
        let n = model.p0().len();
        let mut triplets = Vec::new();
        let mut e = vec![0.0; n_q];
        for j in 0..n_q {
            e[j] = 1.0;
            for (i, &x) in model.full_velocity(&e).iter().enumerate() {
                if x != 0.0 {
                    triplets.push((i, j, x));
                }
            }
            e[j] = 0.0;
        }
        let p = SparseMatrix::from_triplets(n, n_q, &triplets)?;
        let all = omega.matmul(&p)?;
        let free_rows: Vec<usize> = (0..lattice.n_nodes())
            .filter(|&a| !lattice.fixed[a])
            .flat_map(|a| 3 * a..3 * a + 3)
            .collect();
        let cols: Vec<usize> = (0..n_q).collect();
        let free = all.submatrix(&free_rows, &cols);
        Ok(Self {
            omega,
            all,
            free,
            free_rows,
        })
    }

    /// `A = Ω P` on the free nodes' coordinates (rows) and the shell's reduced ones (columns).
    pub fn free_matrix(&self) -> &SparseMatrix {
        &self.free
    }

    /// The rows of the free nodes' coordinates in the `3N` node coordinates (the order of
    /// [`MsmModel`]'s free coordinates).
    pub fn free_rows(&self) -> &[usize] {
        &self.free_rows
    }

    /// `A φ` at the free nodes: a shell motion `φ` (reduced) sampled at the free nodes.
    pub fn sample_free(&self, phi: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.free.nrows()];
        self.free.mul_vec(phi, &mut out);
        out
    }

    /// The node masses of the free coordinates.
    pub fn free_masses(&self, lattice: &SpringLattice) -> Vec<f64> {
        self.free_rows
            .iter()
            .map(|&r| lattice.masses[r / 3])
            .collect()
    }

    /// The lattice's tangent at rest on the free coordinates.
    pub fn free_stiffness(&self, lattice: &SpringLattice) -> SparseMatrix {
        lattice
            .tangent_stiffness(&lattice.flat_positions())
            .submatrix(&self.free_rows, &self.free_rows)
    }

    /// Node velocities `A q̇` of a shell state (fixed nodes at rest).
    pub fn node_velocities(&self, state: &State) -> Vec<[f64; 3]> {
        let mut v = vec![0.0; self.all.nrows()];
        self.all.mul_vec(&state.v, &mut v);
        let mut out: Vec<[f64; 3]> = v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        let free: std::collections::HashSet<usize> = self.free_rows.iter().map(|r| r / 3).collect();
        for (a, x) in out.iter_mut().enumerate() {
            if !free.contains(&a) {
                *x = [0.0; 3];
            }
        }
        out
    }

    /// The surface points `Ω p` of every node.
    pub fn positions(&self, p_full: &[f64]) -> Vec<[f64; 3]> {
        let mut x = vec![0.0; self.omega.nrows()];
        self.omega.mul_vec(p_full, &mut x);
        x.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
    }

    /// Node forces on the free nodes doing the shell's virtual work: `Aᵀ f = F` for every
    /// reduced motion, `f = A (AᵀA)⁻¹ F` (the least-norm solution) when the free nodes carry
    /// at least as many coordinates as the shell, else the least-squares `f = (AAᵀ)⁻¹ A F`.
    pub fn work_equivalent(&self, force: &[f64]) -> Result<Vec<f64>, DeriveError> {
        let at = self.free.transpose();
        let singular = |e| DeriveError::SingularFit {
            detail: format!(
                "the free lattice nodes do not determine the shell's motion, so no node forces \
                 do the loads' work ({e}); refine the lattice grid"
            ),
        };
        if self.free.nrows() >= self.free.ncols() {
            let solver = SpdSolver::new(&at.matmul(&self.free)?).map_err(singular)?;
            let z = solver.solve(force);
            Ok(self.sample_free(&z))
        } else {
            let mut af = vec![0.0; self.free.nrows()];
            self.free.mul_vec(force, &mut af);
            let solver = SpdSolver::new(&self.free.matmul(&at)?).map_err(singular)?;
            Ok(solver.solve(&af))
        }
    }
}

/// The lowest `count` modes of `K y = ω² diag(m) y` (dense below a size, shift-invert Lanczos
/// above), shapes as columns, each ω the Rayleigh quotient of its shape.
pub fn lowest_modes(
    k: &SparseMatrix,
    masses: &[f64],
    count: usize,
) -> Result<(Vec<f64>, Vec<Vec<f64>>), DeriveError> {
    let n = masses.len();
    let count = count.min(n);
    let m = SparseMatrix::from_diagonal(masses);
    let e = if n <= DENSE_LIMIT {
        let e = generalized_symmetric_eigen(&k.to_dense(), &m.to_dense())?;
        nurbspring_linalg::SymmetricEigen {
            values: e.values[..count].to_vec(),
            vectors: DenseMatrix::from_fn(n, count, |i, j| e.vectors[(i, j)]),
        }
    } else {
        let tk: f64 = k.diagonal().iter().sum();
        let tm: f64 = masses.iter().sum();
        let shift = if tk > 0.0 { -1e-6 * tk / tm } else { -1.0 };
        generalized_eigen_sparse_lowest(k, &m, count, shift)?
    };
    // Each frequency from the Rayleigh quotient of its vector: accurate to the square of the
    // vector's error, where the eigenvalue itself carries round-off of order ε ω_max².
    let shapes: Vec<Vec<f64>> = (0..e.values.len()).map(|j| e.vectors.column(j)).collect();
    let omega = shapes
        .iter()
        .map(|y| {
            let inertia: f64 = y.iter().zip(masses).map(|(y, m)| m * y * y).sum();
            (k.quadratic_form(y) / inertia).max(0.0).sqrt()
        })
        .collect();
    Ok((omega, shapes))
}

/// The small-motion run: both models linearized at rest under the scene's excitation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SmallMotion {
    /// What moved the models.
    pub excitation: String,
    /// Time step [s].
    pub dt: f64,
    /// Duration [s].
    pub t_end: f64,
    /// Periods of the lowest mode covered.
    pub periods: f64,
    /// The probe node.
    pub probe_node: usize,
    /// Relative RMS of the probe node's 3-D displacement against the shell's at its (u, v).
    pub relative_rms: f64,
}

/// One level of the static load path.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LoadLevelError {
    /// Load factor on the scene's loads.
    pub load_factor: f64,
    /// The shell's largest node displacement over the size.
    pub shell_displacement: f64,
    /// Largest node distance to its surface point, over the size.
    pub max_error: f64,
    /// RMS over the nodes of that distance, over the size.
    pub rms_error: f64,
}

/// The dynamic large-motion run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DynamicRun {
    /// The integrator of both models.
    pub integrator: String,
    /// Time step [s].
    pub dt: f64,
    /// Duration [s].
    pub t_end: f64,
    /// Periods of the lowest elastic mode covered.
    pub periods: f64,
    /// Largest node distance to its surface point over the run, over the size.
    pub max_error: f64,
    /// RMS over nodes and time of that distance, over the size.
    pub rms_error: f64,
    /// The shell's largest node displacement during the run, over the size.
    pub shell_displacement: f64,
    /// The spectral radius at infinity of the generalized-α ([`LARGE_MOTION_RHO_INFINITY`]).
    pub rho_infinity: f64,
    /// The largest rise of the shell's total energy over its start, over its largest kinetic
    /// energy ([`EnergyWatch::gain`], at most [`nurbspring_sim::ENERGY_GAIN_LIMIT`]: else the
    /// run is no reference and is not compared).
    pub shell_energy_gain: f64,
}

/// The large-motion runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LargeMotion {
    /// The largest load factor on the scene's loads.
    pub load_factor: f64,
    /// The shell's largest node displacement at that factor on the static path, over the size.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub largest_displacement: Option<f64>,
    /// The static load path.
    pub levels: Vec<LoadLevelError>,
    /// Largest `max_error` over the levels.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_error: Option<f64>,
    /// Why the static path stopped, when it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_failure: Option<String>,
    /// The step load at the largest factor from rest.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dynamic: Option<DynamicRun>,
    /// Why the dynamic run stopped, when it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dynamic_failure: Option<String>,
    /// The load factor where the shell's own load path stops (a limit point: it snaps through
    /// or buckles) before its farthest node moves [`LARGE_MOTION`] of the size; the runs are
    /// then at [`BELOW_LIMIT`] of it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shell_limit: Option<f64>,
}

/// The share of the shell's limit load the large-motion runs take when the shell has a limit
/// point before it moves [`LARGE_MOTION`] of the size.
pub const BELOW_LIMIT: f64 = 0.9;

/// What the checks share.
pub struct Check<'a> {
    /// The shell at the scene's loads.
    pub model: &'a DnurbsModel,
    /// The calibrated lattice.
    pub lattice: &'a SpringLattice,
    /// The node map.
    pub map: &'a NodeMap,
    /// The size.
    pub size: f64,
    /// The shell's lowest elastic frequency [rad/s].
    pub omega1: f64,
    /// True when the shell has rigid modes (a mechanism of its constraints).
    pub mechanism: bool,
    /// The scene's time settings (the dynamic run of a mechanism).
    pub time: &'a crate::TimeSettings,
    /// Cancellation.
    pub cancel: Option<Arc<AtomicBool>>,
}

impl Check<'_> {
    fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }

    fn options(&self, dt: f64, t_end: f64) -> RunOptions {
        let mut opts = RunOptions::new(dt, t_end, IntegratorKind::Newmark);
        opts.cancel = self.cancel.clone();
        opts
    }

    /// The lattice linearized at rest on its free coordinates, loaded by the node forces doing
    /// the work of the shell's reduced load `force` ([`NodeMap::work_equivalent`]).
    pub fn lattice_at_rest(&self, force: &[f64]) -> Result<LinearModel, DeriveError> {
        Ok(self.linear_lattice(self.map.work_equivalent(force)?))
    }

    /// The lattice (no node forces) as a linear model on its free coordinates.
    fn linear_lattice(&self, force: Vec<f64>) -> LinearModel {
        let masses = self.map.free_masses(self.lattice);
        let damping: Vec<f64> = self
            .map
            .free_rows()
            .iter()
            .map(|&r| self.lattice.damping[r / 3])
            .collect();
        let rest: Vec<f64> = {
            let x = self.lattice.flat_positions();
            self.map.free_rows().iter().map(|&r| x[r]).collect()
        };
        LinearModel {
            mass: SystemMatrix::Diagonal(masses),
            damping: damping
                .iter()
                .any(|&c| c > 0.0)
                .then_some(SystemMatrix::Diagonal(damping)),
            stiffness: self.map.free_stiffness(self.lattice),
            rest,
            force,
        }
    }

    /// Both models linearized at rest, from the scene's initial velocity and displacement under
    /// its loads (or, when the scene has none of these, from the lowest mode as the initial
    /// velocity), over [`SMALL_MOTION_PERIODS`] periods; the probe node against the shell's
    /// point at its (u, v). `node_model` is the node model at rest on the free node
    /// coordinates under a reduced shell load ([`Check::lattice_at_rest`], or a reduction).
    ///
    /// A shell with rigid modes (a mechanism of its constraints, e.g. a cloth held at two
    /// corners) has no linear response to a constant load: its small motion is then the
    /// scene's initial velocity without its rigid part, and the loads are left out.
    pub fn small_motion(
        &self,
        initial: &InitialConditions,
        probe: usize,
        rigid: &[Vec<f64>],
        first_elastic: &[f64],
        node_model: &dyn Fn(&[f64]) -> Result<LinearModel, DeriveError>,
    ) -> Result<SmallMotion, DeriveError> {
        let model = self.model;
        let q_rest = model.reduced_coordinates(model.p0());
        let mut state = initial.state(model);
        let mut force = model.reduced_force().to_vec();
        let mut excitation = "the scene's initial state and loads".to_string();
        if !rigid.is_empty() {
            force.iter_mut().for_each(|f| *f = 0.0);
            let m = model.mass();
            let mut mv = vec![0.0; state.v.len()];
            for phi in rigid {
                m.mul_vec(&state.v, &mut mv);
                let c: f64 = phi.iter().zip(&mv).map(|(a, b)| a * b).sum();
                state.v.iter_mut().zip(phi).for_each(|(v, p)| *v -= c * p);
            }
            state.q.clone_from(&q_rest);
            excitation = format!(
                "the scene's initial velocity without its part in the shell's {} rigid modes \
                 (the constraints leave a mechanism, so the loads have no small-motion \
                 response)",
                rigid.len()
            );
        }
        let speed = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let given = speed(&initial.state(model).v);
        let moves = speed(&state.v) > 1e-9 * given
            || state.q.iter().zip(&q_rest).any(|(a, b)| a != b)
            || force.iter().any(|&f| f != 0.0);
        if !moves {
            state.v = first_elastic.to_vec();
            excitation = "the lowest elastic shell mode as the initial velocity (the scene \
                          gives no small-motion excitation)"
                .to_string();
        }
        let shell = LinearModel {
            mass: model.mass().clone(),
            damping: model.damping().cloned(),
            stiffness: model.reduced_stiffness().clone(),
            rest: q_rest.clone(),
            force: force.clone(),
        };
        let msm = node_model(&force)?;
        let u0: Vec<f64> = state.q.iter().zip(&q_rest).map(|(a, b)| a - b).collect();
        let msm_state = State {
            t: 0.0,
            q: msm
                .rest
                .iter()
                .zip(self.map.sample_free(&u0))
                .map(|(x, u)| x + u)
                .collect(),
            v: self.map.sample_free(&state.v),
        };
        let period = 2.0 * std::f64::consts::PI / self.omega1;
        let dt = period / STEPS_PER_PERIOD as f64;
        let t_end = SMALL_MOTION_PERIODS * period;
        let opts = self.options(dt, t_end);
        // The shell's probe: rows of A at the probe node.
        let rows: Vec<usize> = (3 * probe..3 * probe + 3).collect();
        let cols: Vec<usize> = (0..model.n_free()).collect();
        let a_probe = self.map.all.submatrix(&rows, &cols);
        let mut t = Vec::new();
        let mut reference = Vec::new();
        simulate(&shell, state, &opts, &mut |s: &Sample<'_>| {
            let d: Vec<f64> = s.q.iter().zip(&q_rest).map(|(a, b)| a - b).collect();
            let mut x = [0.0; 3];
            a_probe.mul_vec(&d, &mut x);
            t.push(s.t);
            reference.push(x);
        })?;
        let slot = self.map.free_rows().iter().position(|&r| r == 3 * probe);
        let mut other = Vec::new();
        let rest = msm.rest.clone();
        simulate(&msm, msm_state, &opts, &mut |s: &Sample<'_>| {
            other.push(match slot {
                Some(i) => std::array::from_fn(|k| s.q[i + k] - rest[i + k]),
                None => [0.0; 3],
            });
        })?;
        if self.cancelled() {
            return Err(DeriveError::Cancelled);
        }
        Ok(SmallMotion {
            excitation,
            dt,
            t_end,
            periods: SMALL_MOTION_PERIODS,
            probe_node: probe,
            relative_rms: compare_points(&t, &reference, &other).relative_rms,
        })
    }

    /// The scene's loads scaled until the shell's largest node displacement is at least
    /// [`LARGE_MOTION`] of the size (or the scene's own loads when they move it more): the
    /// static load path at [`LOAD_LEVELS`] levels and a step load over
    /// [`LARGE_MOTION_PERIODS`] periods, every node against its surface point.
    pub fn large_motion(
        &self,
        shell: &ShellMaterial,
        loads: &Loads,
        geometry: &Geometry,
        constraints: &Constraints,
        options: &DnurbsOptions,
    ) -> Result<LargeMotion, DeriveError> {
        let model = self.model;
        let rest = self.map.positions(model.p0());
        let largest = |p: &[f64]| {
            self.map
                .positions(p)
                .iter()
                .zip(&rest)
                .map(|(x, r)| norm(sub(*x, *r)))
                .fold(0.0, f64::max)
                / self.size
        };
        let build = |factor: f64| {
            DnurbsModel::kirchhoff_love(
                geometry.clone(),
                *shell,
                loads.scaled(factor),
                constraints,
                options.clone(),
            )
        };
        // The linear estimate of the factor (none for a mechanism), then the shell's answer.
        let mut factor = match model.linearized_steady_state() {
            Ok(linear) => {
                let d = largest(&linear);
                if d > 0.0 {
                    (LARGE_MOTION / d).max(1.0)
                } else {
                    1.0
                }
            }
            Err(_) => 1.0,
        };
        let settings = PathSettings {
            levels: LOAD_LEVELS,
            ..PathSettings::default()
        };
        let cancel = || self.cancelled();
        let mut out = LargeMotion {
            load_factor: factor,
            largest_displacement: None,
            levels: Vec::new(),
            static_error: None,
            static_failure: None,
            dynamic: None,
            dynamic_failure: None,
            shell_limit: None,
        };
        let mut attempt = 0;
        let (scaled, path) = loop {
            let scaled = build(factor)?;
            match scaled.equilibrium_path(&settings, &cancel, &mut |_| {}) {
                Ok(path) => {
                    let d = largest(&path.levels.last().expect("levels ≥ 1").p);
                    attempt += 1;
                    // Below a limit point the path is taken as it is: a larger load would
                    // pass the limit again.
                    if d >= LARGE_MOTION || attempt == 3 || out.shell_limit.is_some() {
                        break (scaled, Some(path));
                    }
                    factor *= 1.05 * LARGE_MOTION / d.max(1e-12);
                }
                Err(nurbspring_dnurbs::DnurbsError::Cancelled) => {
                    return Err(DeriveError::Cancelled);
                }
                // The shell itself stops at a limit point on the way: the runs are made
                // below it (once; a mechanism, stopped at 0, has no such load).
                Err(nurbspring_dnurbs::DnurbsError::PathStopped { lambda, .. })
                    if lambda > 0.0 && out.shell_limit.is_none() =>
                {
                    out.shell_limit = Some(factor * lambda);
                    factor *= BELOW_LIMIT * lambda;
                }
                Err(e) => {
                    out.static_failure = Some(format!("the shell's load path stopped: {e}"));
                    break (scaled, None);
                }
            }
        };
        out.load_factor = factor;
        let node_force = self
            .map
            .work_equivalent(scaled.reduced_force())
            .map(|f| self.full_forces(&f))?;
        let mut lattice = self.lattice.clone();
        lattice.forces = node_force;
        let msm = MsmModel::new(lattice)?;
        if let Some(path) = path {
            let lambdas: Vec<f64> = path.levels.iter().map(|l| l.lambda).collect();
            match static_path(&msm, &lambdas, &cancel) {
                Ok(lattice_path) => {
                    // The levels both models reached (all of them unless the lattice stops).
                    for (level, q) in path.levels.iter().zip(&lattice_path.states) {
                        let target = self.map.positions(&level.p);
                        let (max_error, rms_error) =
                            node_errors(&msm.full_positions(q), &target, self.size);
                        out.levels.push(LoadLevelError {
                            load_factor: factor * level.lambda,
                            shell_displacement: largest(&level.p),
                            max_error,
                            rms_error,
                        });
                    }
                    out.largest_displacement = out.levels.last().map(|l| l.shell_displacement);
                    out.static_error = out.levels.iter().map(|l| l.max_error).reduce(f64::max);
                    out.static_failure = lattice_path.stopped;
                }
                Err(DeriveError::Cancelled) => return Err(DeriveError::Cancelled),
                Err(e) => out.static_failure = Some(reason(e)),
            }
        }
        match self.step_load(&scaled, &msm, &largest) {
            Ok(run) => out.dynamic = Some(run),
            Err(DeriveError::Cancelled) => return Err(DeriveError::Cancelled),
            Err(e) => out.dynamic_failure = Some(reason(e)),
        }
        Ok(out)
    }

    /// Both models from rest under the loads of `shell` (applied at once) by generalized-α
    /// over [`LARGE_MOTION_PERIODS`] periods of the lowest elastic mode with
    /// [`STEPS_PER_PERIOD`] steps a period, every node against its surface point. A mechanism
    /// (a shell with rigid modes, e.g. a cloth held at two corners) swings through large
    /// rotations at the pace of its loads, not of its elastic modes: it runs with the scene's
    /// own Δt and end time.
    fn step_load(
        &self,
        shell: &DnurbsModel,
        msm: &MsmModel,
        largest: &dyn Fn(&[f64]) -> f64,
    ) -> Result<DynamicRun, DeriveError> {
        let period = 2.0 * std::f64::consts::PI / self.omega1;
        let (dt, t_end) = if self.mechanism {
            (self.time.dt, self.time.t_end)
        } else {
            (
                period / STEPS_PER_PERIOD as f64,
                LARGE_MOTION_PERIODS * period,
            )
        };
        let mut opts = self.options(dt, t_end);
        opts.integrator = IntegratorKind::GeneralizedAlpha;
        opts.rho_infinity = LARGE_MOTION_RHO_INFINITY;
        let q_rest = shell.reduced_coordinates(shell.p0());
        let shell_state = State {
            t: 0.0,
            v: vec![0.0; q_rest.len()],
            q: q_rest,
        };
        let mut targets = Vec::new();
        let mut shell_largest: f64 = 0.0;
        let mut energy = EnergyWatch::default();
        simulate(shell, shell_state, &opts, &mut |s: &Sample<'_>| {
            let p = shell.full_coordinates(s.q);
            shell_largest = shell_largest.max(largest(&p));
            targets.push(self.map.positions(&p));
            energy.observe(s.kinetic, s.potential);
        })
        .map_err(|e| DeriveError::SingularFit {
            detail: format!("the shell's run stopped: {e}"),
        })?;
        let gain = energy.gain();
        if energy.unstable() {
            return Err(DeriveError::SingularFit {
                detail: format!(
                    "the shell's own run gains energy ({:.3} of its largest kinetic energy, \
                     generalized-α with ρ∞ = {LARGE_MOTION_RHO_INFINITY}, Δt = {dt:e} s): its \
                     integrator is unstable here, so it is no reference",
                    gain
                ),
            });
        }
        let mut max_error: f64 = 0.0;
        let mut sum = 0.0;
        let mut count = 0usize;
        let mut step = 0;
        simulate(msm, msm.initial_state(&[]), &opts, &mut |s: &Sample<'_>| {
            if let Some(target) = targets.get(step) {
                let x = msm.full_positions(s.q);
                for (a, b) in x.chunks(3).zip(target) {
                    let e = norm(sub([a[0], a[1], a[2]], *b)) / self.size;
                    max_error = max_error.max(e);
                    sum += e * e;
                    count += 1;
                }
            }
            step += 1;
        })
        .map_err(|e| DeriveError::SingularFit {
            detail: format!("the spring model's run stopped: {e}"),
        })?;
        if self.cancelled() {
            return Err(DeriveError::Cancelled);
        }
        Ok(DynamicRun {
            integrator: opts.integrator.name().to_string(),
            dt,
            t_end,
            periods: t_end / period,
            max_error,
            rms_error: (sum / count.max(1) as f64).sqrt(),
            shell_displacement: shell_largest,
            rho_infinity: LARGE_MOTION_RHO_INFINITY,
            shell_energy_gain: gain,
        })
    }

    /// Free-node forces as one force per node (fixed nodes none).
    fn full_forces(&self, free: &[f64]) -> Vec<[f64; 3]> {
        let mut out = vec![[0.0; 3]; self.lattice.n_nodes()];
        for (&r, &f) in self.map.free_rows().iter().zip(free) {
            out[r / 3][r % 3] = f;
        }
        out
    }
}

/// `a − b`.
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Why a validation run stopped, in the report's words.
fn reason(e: DeriveError) -> String {
    match e {
        DeriveError::SingularFit { detail } => detail,
        other => other.to_string(),
    }
}

/// `max_a |x_a − y_a| / size` and its RMS over the nodes.
fn node_errors(x: &[f64], target: &[[f64; 3]], size: f64) -> (f64, f64) {
    let mut max: f64 = 0.0;
    let mut sum = 0.0;
    for (a, b) in x.chunks(3).zip(target) {
        let e = norm(sub([a[0], a[1], a[2]], *b)) / size;
        max = max.max(e);
        sum += e * e;
    }
    (max, (sum / target.len().max(1) as f64).sqrt())
}

/// Newton iterations of one increment before it is cut back.
const STATIC_ITERATIONS: usize = 25;
/// Relative residual at which an increment has converged.
const STATIC_TOLERANCE: f64 = 1e-9;
/// Relative residual below which a Newton step at round-off of the positions also counts as
/// converged.
const LOOSE_TOLERANCE: f64 = 1e-6;
/// A Newton step this small against the largest coordinate is at round-off.
const STEP_ROUND_OFF: f64 = 1e-13;

/// The equilibria of a lattice along a load path ([`static_path`]).
#[derive(Clone, Debug, PartialEq)]
pub struct StaticPath {
    /// The positions at each level reached, in order.
    pub states: Vec<Vec<f64>>,
    /// Why the path stopped before the last level, when it did.
    pub stopped: Option<String>,
}

/// The equilibrium `f_int(q) = λ f_ext` of a lattice at each `λ` of `lambdas` (ascending, in
/// (0, 1]): load increments, Newton's method with the consistent tangent (LU) and a residual
/// line search, an increment that fails halved (down to 1/1024 of a level). A path that
/// cannot be followed further keeps the levels it reached and says where it stopped.
pub fn static_path(
    model: &MsmModel,
    lambdas: &[f64],
    cancel: &dyn Fn() -> bool,
) -> Result<StaticPath, DeriveError> {
    let n = model.n_dofs();
    let mut f = vec![0.0; n];
    model.external_force(0.0, &mut f);
    let f_norm = f
        .iter()
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt()
        .max(f64::MIN_POSITIVE);
    let residual = |q: &[f64], lambda: f64| -> Vec<f64> {
        let mut r = vec![0.0; n];
        model.internal_force(q, &mut r);
        r.iter_mut().zip(&f).for_each(|(r, f)| *r -= lambda * f);
        r
    };
    let size = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut q = model.initial_positions().to_vec();
    let length = q
        .iter()
        .fold(0.0_f64, |m, x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    let mut lambda = 0.0;
    let mut out = Vec::new();
    for &target in lambdas {
        let mut step = target - lambda;
        while lambda < target {
            if cancel() {
                return Err(DeriveError::Cancelled);
            }
            let next = (lambda + step).min(target);
            let mut trial = q.clone();
            let mut converged = false;
            for _ in 0..STATIC_ITERATIONS {
                let r = residual(&trial, next);
                let r0 = size(&r);
                if r0 <= STATIC_TOLERANCE * f_norm {
                    converged = true;
                    break;
                }
                let lu = match LuSolver::new(&model.tangent_stiffness(&trial)) {
                    Ok(lu) => lu,
                    Err(_) => break,
                };
                let dq = lu.solve(&r);
                if dq.iter().any(|x| !x.is_finite()) {
                    break;
                }
                let mut alpha = 1.0;
                let mut accepted = false;
                for _ in 0..20 {
                    let cand: Vec<f64> =
                        trial.iter().zip(&dq).map(|(q, d)| q - alpha * d).collect();
                    if size(&residual(&cand, next)) < r0 {
                        trial = cand;
                        accepted = true;
                        break;
                    }
                    alpha *= 0.5;
                }
                // A full step at round-off of the positions: the residual's floor is the
                // round-off of the internal forces (stiff springs), not the tolerance.
                let moved = dq.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
                if moved <= STEP_ROUND_OFF * length && r0 <= LOOSE_TOLERANCE * f_norm {
                    converged = true;
                    break;
                }
                if !accepted {
                    break;
                }
            }
            if converged {
                q = trial;
                lambda = next;
                step *= 1.5;
            } else {
                step *= 0.5;
                if step < target / 1024.0 * 1e-3 {
                    return Ok(StaticPath {
                        states: out,
                        stopped: Some(format!(
                            "the spring model's equilibrium was not found past load factor \
                             {lambda:.4} of the large-motion load (the lattice buckles or \
                             folds where the shell does not)"
                        )),
                    });
                }
            }
        }
        out.push(q.clone());
    }
    Ok(StaticPath {
        states: out,
        stopped: None,
    })
}
