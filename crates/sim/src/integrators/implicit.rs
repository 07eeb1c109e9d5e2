//! The implicit core shared by Newmark, generalized-α and backward Euler.
//!
//! Each scheme solves, for the end-of-step acceleration `a`,
//! `M a + D (v̂ + c_v a) + f_int(q̂ + c_q a) = f_ext(t_{n+1})`
//! with predictors `q̂, v̂` and coefficients `(c_q, c_v)` = `(κ_q Δt², κ_v Δt)`
//! ([`StepCoefficients`]): `(β, γ)` for Newmark, `(β, γ)(1 − α_f)/(1 − α_m)` for
//! generalized-α (where `a` is the acceleration of the equation of motion at `t_{n+1}`), `(1, 1)`
//! for backward Euler (where `a = (v_{n+1} − v_n)/Δt`). The Newton matrix is
//! `J = M + c_v D + c_q K_T(q̂ + c_q a)`. For a linear model J is constant: it is factored
//! once and one solve is exact.
//!
//! Otherwise the iteration is a **modified Newton** method: the factor of J is kept across
//! iterations and steps and refreshed only when it stops paying, that is when an iteration with
//! the kept factor reduces the residual by less than [`CONTRACTION`] (or on the first
//! iteration ever). A refreshed factor gives a full Newton step, so convergence stays at least
//! as fast as a contraction by `CONTRACTION` per iteration; near a smooth trajectory the kept
//! factor converges in one or two solves a step. J lives on one pattern
//! ([`ShiftedSum`]: `M + c_v D` and the tangent's pattern merged once, values refilled in
//! place); its factorization is sparse Cholesky ([`SpdSolver`], symbolic analysis once) while
//! J is positive definite. When Cholesky fails (compressed springs make `K_T` indefinite), the
//! model's positive semi-definite tangent ([`DynamicModel::projected_tangent_stiffness`])
//! takes the place of `K_T`, so the step is a descent direction of the step's energy; a model
//! without one is factored by sparse LU ([`LuSolver`]).
//!
//! A configuration damping `C(q) q̇` ([`crate::ConfigurationDamping`]) enters the residual at
//! the trial state, `R = M a + (D + C(q)) v + f_int(q) − f_ext`, and the Newton matrix as
//! `c_v C(q)` (its variation with `q` left out, which only slows a modified Newton step).
//!
//! **Line search.** The step's equation is the stationarity condition of the step energy
//! `Ψ(a) = E(q̂ + c_q a)/c_q + ½aᵀ(M + c_v D)a + (D v̂ − f_ext)ᵀa` (`∇Ψ = R`, the residual;
//! `E` is [`DynamicModel::potential_energy`]). A direction from a positive definite factor is a
//! descent direction of Ψ. When such a step raises the residual while it is still large
//! (Newton far from its quadratic regime, e.g. an indefinite J replaced by its projection),
//! the step is backtracked until Ψ falls by the Armijo fraction [`ARMIJO`] of its slope, so
//! the iteration cannot wander; a step that lowers the residual is taken whole, so the line
//! search costs nothing where Newton already converges.
//!
//! **Step halving.** A step on which Newton still fails (its iteration limit reached) is taken
//! again as two steps of half the size from the same state, each of them halved again when it
//! fails, down to `Δt / 2^MAX_HALVINGS_OF_A_STEP` ([`step_with_halving`]; each step size has its
//! own core, made when first needed). A fixed-step scheme keeps its time grid: the halves
//! only replace a step that would otherwise end the run, and
//! [`NewtonCounts::halved_steps`] counts them. Smaller steps bring the end-of-step state
//! closer to the start, where the predictor is a good Newton guess and the step energy more
//! nearly convex (`M/c_q` grows as `1/h²`), which is what rescues a step through a fast,
//! strongly nonlinear event such as a lattice snapping through.

use nurbspring_linalg::{LinalgError, LuSolver, ShiftedSum, SparseMatrix, SpdSolver};

use super::{NewtonSettings, check_fixed_dt, norm};
use crate::{DynamicModel, SimError, State};

/// Factorization of a Newton matrix: Cholesky when possible, LU fallback.
pub(crate) struct NewtonSolver {
    spd: Option<SpdSolver>,
    lu: Option<LuSolver>,
    use_lu: bool,
}

impl NewtonSolver {
    pub(crate) fn new() -> Self {
        Self {
            spd: None,
            lu: None,
            use_lu: false,
        }
    }

    /// Factors `j` (Cholesky, refactoring with the stored symbolic analysis; LU if not SPD).
    pub(crate) fn factor(&mut self, j: &SparseMatrix) -> Result<(), SimError> {
        if self.factor_spd(j)? {
            return Ok(());
        }
        self.lu = Some(LuSolver::new(j)?);
        self.use_lu = true;
        Ok(())
    }

    /// Factors `j` by Cholesky; `false` (and nothing factored) when `j` is not positive
    /// definite.
    fn factor_spd(&mut self, j: &SparseMatrix) -> Result<bool, SimError> {
        let result = match &mut self.spd {
            Some(s) => s.refactor(j),
            None => SpdSolver::new(j).map(|s| {
                self.spd = Some(s);
            }),
        };
        match result {
            Ok(()) => {
                self.use_lu = false;
                Ok(true)
            }
            Err(LinalgError::NotPositiveDefinite { .. }) => Ok(false),
            Err(e) => Err(e.into()),
        }
    }

    pub(crate) fn solve_in_place(&self, x: &mut [f64]) {
        match (self.use_lu, &self.spd, &self.lu) {
            (false, Some(s), _) => s.solve_in_place(x),
            (true, _, Some(l)) => l.solve_in_place(x),
            _ => unreachable!("NewtonSolver used before factor"),
        }
    }
}

/// Largest residual ratio (this iteration's over the previous one's) accepted from an
/// iteration with a kept factor; a slower iteration refreshes the factor. At 0.2 the kept factor
/// needs at most about 14 iterations from a residual of 1 to 1e-10, and a refreshed factor
/// converges quadratically.
pub(crate) const CONTRACTION: f64 = 0.2;

/// Armijo's sufficient-decrease fraction: a backtracked step `α p` is accepted when
/// `Ψ(a + α p) ≤ Ψ(a) + ARMIJO · α · Rᵀp` (the customary 1e-4; Nocedal & Wright, §3.1).
pub(crate) const ARMIJO: f64 = 1e-4;

/// Most halvings of a step in the line search (the smallest step is `2⁻²⁰ ≈ 1e-6` of the full
/// one); when none gives sufficient decrease the full step is kept, as without a line search.
const MAX_HALVINGS: usize = 20;

/// The last Newton step, kept so it can be backtracked: taken from `a − p` along `p` with
/// slope `Rᵀp < 0` there.
struct LastStep {
    slope: f64,
}

/// `K + (c_v/c_q) C(q)`: the tangent `k` with a configuration damping folded in, so that
/// `M + c_v D + c_q (K + (c_v/c_q) C)` is the Newton matrix (module docs); `k` itself when the
/// model has none.
fn with_damping(
    model: &dyn DynamicModel,
    q: &[f64],
    k: SparseMatrix,
    cq: f64,
    cv: f64,
) -> Result<SparseMatrix, SimError> {
    Ok(match model.configuration_damping() {
        Some(c) => SparseMatrix::linear_combination(1.0, &k, cv / cq, &c.damping_matrix(q))?,
        None => k,
    })
}

/// `M + c_v D`, the constant part of the Newton matrix.
fn constant_part(
    model: &dyn DynamicModel,
    m: &SparseMatrix,
    cv: f64,
) -> Result<SparseMatrix, SimError> {
    Ok(match model.damping() {
        Some(d) => SparseMatrix::linear_combination(1.0, m, cv, &d.to_sparse())?,
        None => m.clone(),
    })
}

/// How often the implicit core factored and solved (for tests and benchmarks).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NewtonCounts {
    /// Numeric factorizations of the Newton matrix.
    pub factorizations: usize,
    /// Newton iterations (each one solve with the current factor).
    pub iterations: usize,
    /// Steps whose Newton iteration failed and that were taken in halves instead
    /// ([`step_with_halving`]).
    pub halved_steps: usize,
}

/// Most halvings of a step whose Newton iteration failed: the smallest step tried is
/// `Δt / 2^MAX_HALVINGS_OF_A_STEP`.
pub(crate) const MAX_HALVINGS_OF_A_STEP: u32 = 6;

/// The coefficients of a scheme's step equation for a step `h`: `c_q = κ_q h²`, `c_v = κ_v h`
/// (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StepCoefficients {
    /// `κ_q`.
    pub(crate) kappa_q: f64,
    /// `κ_v`.
    pub(crate) kappa_v: f64,
}

impl StepCoefficients {
    /// `(c_q, c_v) = (κ_q h², κ_v h)`.
    pub(crate) fn at(self, h: f64) -> (f64, f64) {
        (self.kappa_q * h * h, self.kappa_v * h)
    }
}

/// The implicit cores of one scheme for the step sizes `Δt / 2^l`, `l = 0, 1, …` (level `l`),
/// each made when a step is first halved that far.
pub(crate) struct CoreLadder {
    name: &'static str,
    dt: f64,
    /// `(c_q, c_v)` of the scheme for a step `h`.
    coefficients: StepCoefficients,
    newton: NewtonSettings,
    cores: Vec<ImplicitCore>,
    /// Steps begun (whole steps of `dt`; the step number in error reports).
    pub(crate) steps: usize,
    halved_steps: usize,
}

impl CoreLadder {
    /// The ladder with the core of the whole step `dt` (level 0).
    pub(crate) fn new(
        name: &'static str,
        model: &dyn DynamicModel,
        dt: f64,
        coefficients: StepCoefficients,
        newton: NewtonSettings,
    ) -> Result<Self, SimError> {
        let (cq, cv) = coefficients.at(dt);
        let core = ImplicitCore::new(name, model, cq, cv, newton)?;
        Ok(Self {
            name,
            dt,
            coefficients,
            newton,
            cores: vec![core],
            steps: 0,
            halved_steps: 0,
        })
    }

    /// The step size of level `level`.
    pub(crate) fn h(&self, level: u32) -> f64 {
        self.dt / f64::from(1u32 << level)
    }

    /// The core of level `level`.
    pub(crate) fn core(
        &mut self,
        model: &dyn DynamicModel,
        level: u32,
    ) -> Result<&mut ImplicitCore, SimError> {
        while self.cores.len() <= level as usize {
            let h = self.h(self.cores.len() as u32);
            let (cq, cv) = self.coefficients.at(h);
            self.cores
                .push(ImplicitCore::new(self.name, model, cq, cv, self.newton)?);
        }
        Ok(&mut self.cores[level as usize])
    }

    /// The counts of all levels together.
    pub(crate) fn counts(&self) -> NewtonCounts {
        let mut counts = NewtonCounts {
            halved_steps: self.halved_steps,
            ..Default::default()
        };
        for core in &self.cores {
            counts.factorizations += core.counts.factorizations;
            counts.iterations += core.counts.iterations;
        }
        counts
    }
}

/// A fixed-step implicit scheme whose steps can be halved.
pub(crate) trait HalvableStep {
    /// One step of size `Δt / 2^level` from `state`, with the core of that level. On an error
    /// it leaves `state` and whatever the scheme carries from step to step as they were.
    fn substep(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        level: u32,
    ) -> Result<(), SimError>;

    /// What the scheme carries from step to step besides the state (Newmark's acceleration,
    /// generalized-α's two accelerations), saved before a halved step and restored when it
    /// fails.
    fn carried(&mut self) -> &mut [Vec<f64>];

    fn ladder(&self) -> &CoreLadder;

    fn ladder_mut(&mut self) -> &mut CoreLadder;
}

/// Every halvable scheme is a stepper of its fixed `Δt`: a step is [`step_with_halving`].
impl<T: HalvableStep> super::Stepper for T {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        let ladder = self.ladder_mut();
        check_fixed_dt(ladder.name, ladder.dt, dt)?;
        ladder.steps += 1;
        step_with_halving(self, model, state)
    }

    fn halved_steps(&self) -> usize {
        self.ladder().halved_steps
    }
}

/// One step of `Δt`. When Newton fails on it, the step is taken as two steps of `Δt/2`, each of
/// them halved again on failure, down to `Δt / 2^MAX_HALVINGS_OF_A_STEP` (a step cut back, as
/// finite-element codes do with a load increment): the time grid seen by the caller stays that
/// of `Δt`, the halves only replace a step that would otherwise end the run. If the halves fail
/// too, the state is left as it was and the error is the whole step's, with the halvings
/// tried.
pub(crate) fn step_with_halving(
    scheme: &mut dyn HalvableStep,
    model: &dyn DynamicModel,
    state: &mut State,
) -> Result<(), SimError> {
    let (step, time, iterations, residual) = match scheme.substep(model, state, 0) {
        Err(SimError::NewtonFailed {
            step,
            time,
            iterations,
            residual,
            ..
        }) => (step, time, iterations, residual),
        other => return other,
    };
    let (saved, carried) = (state.clone(), scheme.carried().to_vec());
    let t_end = state.t + scheme.ladder().h(0);
    let mut deepest = 1;
    match halves(scheme, model, state, 1, &mut deepest) {
        Ok(()) => {
            // The time of the whole step, as an unhalved step computes it.
            state.t = t_end;
            scheme.ladder_mut().halved_steps += 1;
            Ok(())
        }
        Err(_) => {
            *state = saved;
            scheme.carried().clone_from_slice(&carried);
            Err(SimError::NewtonFailed {
                step,
                time,
                iterations,
                residual,
                halvings: deepest,
            })
        }
    }
}

/// Two steps of level `level`, each halved again when its Newton iteration fails; `deepest`
/// records the deepest level tried.
fn halves(
    scheme: &mut dyn HalvableStep,
    model: &dyn DynamicModel,
    state: &mut State,
    level: u32,
    deepest: &mut u32,
) -> Result<(), SimError> {
    *deepest = (*deepest).max(level);
    for _ in 0..2 {
        match scheme.substep(model, state, level) {
            Err(SimError::NewtonFailed { .. }) if level < MAX_HALVINGS_OF_A_STEP => {
                halves(scheme, model, state, level + 1, deepest)?
            }
            other => other?,
        }
    }
    Ok(())
}

/// Solver state for `M a + D (v̂ + c_v a) + f_int(q̂ + c_q a) = f_ext`.
pub(crate) struct ImplicitCore {
    pub(crate) name: &'static str,
    pub(crate) cq: f64,
    pub(crate) cv: f64,
    linear: bool,
    mass: SparseMatrix,
    /// `J = (M + c_v D) + c_q K_T`, on one pattern.
    jacobian: Option<ShiftedSum>,
    constant: SparseMatrix,
    solver: NewtonSolver,
    /// Whether `solver` holds a factor of a recent J (kept across iterations and steps).
    factored: bool,
    newton: NewtonSettings,
    pub(crate) counts: NewtonCounts,
    // buffers
    q_trial: Vec<f64>,
    v_trial: Vec<f64>,
    fext: Vec<f64>,
    fint: Vec<f64>,
    residual: Vec<f64>,
    work: Vec<f64>,
    /// The last step `p` (for the line search).
    direction: Vec<f64>,
}

impl ImplicitCore {
    pub(crate) fn new(
        name: &'static str,
        model: &dyn DynamicModel,
        cq: f64,
        cv: f64,
        newton: NewtonSettings,
    ) -> Result<Self, SimError> {
        let n = model.n_dofs();
        let mass = model.mass().to_sparse();
        let constant = constant_part(model, &mass, cv)?;
        let mut solver = NewtonSolver::new();
        let mut counts = NewtonCounts::default();
        let linear = match model
            .linear_stiffness()
            .filter(|_| model.configuration_damping().is_none())
        {
            Some(k) => {
                solver.factor(&SparseMatrix::linear_combination(1.0, &constant, cq, k)?)?;
                counts.factorizations += 1;
                true
            }
            None => false,
        };
        Ok(Self {
            name,
            cq,
            cv,
            linear,
            mass,
            jacobian: None,
            constant,
            solver,
            factored: linear,
            newton,
            counts,
            q_trial: vec![0.0; n],
            v_trial: vec![0.0; n],
            fext: vec![0.0; n],
            fint: vec![0.0; n],
            residual: vec![0.0; n],
            work: vec![0.0; n],
            direction: vec![0.0; n],
        })
    }

    /// Factors `J = M + c_v D + c_q K_T(q)` at the trial point `q`. When J is not positive
    /// definite (compressed springs), the model's positive semi-definite tangent takes the
    /// place of `K_T` where it has one, so the step is a descent direction of the step's
    /// energy; otherwise J is factored by LU.
    fn refresh_factor(&mut self, model: &dyn DynamicModel) -> Result<(), SimError> {
        let kt = with_damping(
            model,
            &self.q_trial,
            model.tangent_stiffness(&self.q_trial),
            self.cq,
            self.cv,
        )?;
        let j = match &mut self.jacobian {
            Some(plan) => plan.update(self.cq, &kt)?,
            None => self
                .jacobian
                .insert(ShiftedSum::new(&self.constant, self.cq, &kt)?)
                .matrix(),
        };
        if !self.solver.factor_spd(j)? {
            let plan = self.jacobian.as_mut().expect("set above");
            match model.projected_tangent_stiffness(&self.q_trial) {
                Some(kp) => {
                    let kp = with_damping(model, &self.q_trial, kp, self.cq, self.cv)?;
                    self.solver.factor(plan.update(self.cq, &kp)?)?
                }
                None => self.solver.factor(plan.matrix())?,
            }
        }
        self.factored = true;
        self.counts.factorizations += 1;
        Ok(())
    }

    /// Solves for `a` (initial guess in `a`, overwritten by the solution) at time `t_new`;
    /// `q_prev` is the position at the start of the step. `step` is only used in error reports.
    ///
    /// A nonlinear step starts from whichever of the guess and the acceleration that keeps
    /// `q_prev` (`(q_prev − q̂)/c_q`) has the lower step energy Ψ: Newton with the line search
    /// then ends no higher than `Ψ` there, so a step cannot jump to a far stationary point of
    /// Ψ that a guess extrapolated from a fast previous step happens to lie near (a damped body
    /// would otherwise cycle between two wells).
    pub(crate) fn solve(
        &mut self,
        model: &dyn DynamicModel,
        q_prev: &[f64],
        q_hat: &[f64],
        v_hat: &[f64],
        t_new: f64,
        a: &mut [f64],
        step: usize,
    ) -> Result<(), SimError> {
        model.external_force(t_new, &mut self.fext);
        if self.linear {
            // rhs = f_ext − f_int(q̂) − D v̂; J a = rhs exactly, since f_int is affine.
            model.internal_force(q_hat, &mut self.fint);
            for i in 0..a.len() {
                a[i] = self.fext[i] - self.fint[i];
            }
            if let Some(d) = model.damping() {
                d.mul_vec_add(-1.0, v_hat, a);
            }
            self.solver.solve_in_place(a);
            return Ok(());
        }
        self.start_low(model, q_prev, q_hat, v_hat, a);
        let mut last = f64::INFINITY;
        let mut previous = f64::INFINITY;
        // Whether the iterate was reached by a full Newton step (a factor made at the previous
        // iterate): only then does a stalled residual mean the round-off floor.
        let mut full_step = false;
        // The step that led to this iterate, when it may be backtracked.
        let mut last_step: Option<LastStep> = None;
        for it in 0..=self.newton.max_iterations {
            let (mut r, mut scale) = self.evaluate(model, q_hat, v_hat, a);
            if !r.is_finite() && last_step.is_none() {
                return Err(self.non_finite(step, t_new));
            }
            last = if scale > 0.0 { r / scale } else { 0.0 };
            // A descent step that raised a residual still far from converged is backtracked
            // on the step energy Ψ (see the module docs).
            if let Some(ls) = last_step.take()
                && (!r.is_finite() || (last > previous && last > self.newton.tolerance.sqrt()))
            {
                if self.backtrack(model, q_hat, v_hat, a, &ls) {
                    full_step = false;
                }
                // The line search used the buffers: the trial state is rebuilt at `a`.
                (r, scale) = self.evaluate(model, q_hat, v_hat, a);
                last = if scale > 0.0 { r / scale } else { 0.0 };
            }
            if !r.is_finite() {
                return Err(self.non_finite(step, t_new));
            }
            if r <= self.newton.tolerance * scale {
                return Ok(());
            }
            // Stagnation at round-off: the terms of f_int can be much larger than f_int itself
            // (stiff springs whose forces nearly cancel at a node), so the relative residual
            // may bottom out above the tolerance. A full Newton step converges quadratically,
            // so a residual that stops falling after one while already small is the floor.
            if full_step && last <= self.newton.tolerance.sqrt() && last > 0.5 * previous {
                return Ok(());
            }
            if it == self.newton.max_iterations {
                break;
            }
            // A kept factor that no longer contracts well is refreshed at this iterate.
            full_step = !self.factored || last > CONTRACTION * previous;
            if full_step {
                self.refresh_factor(model)?;
            }
            previous = last;
            for i in 0..a.len() {
                self.direction[i] = -self.residual[i];
            }
            self.solver.solve_in_place(&mut self.direction);
            self.counts.iterations += 1;
            // Stagnation at round-off, seen in the step: a full Newton step that moves q by
            // less than the tolerance relative to q is at the floor of f_int's round-off (a
            // residual whose terms cancel, as in a lattice at rest, has a meaningless relative
            // size; the correction does not), and the error after it is of the order of its
            // square.
            if full_step
                && self.cq * norm(&self.direction) <= self.newton.tolerance * norm(&self.q_trial)
            {
                for i in 0..a.len() {
                    a[i] += self.direction[i];
                }
                return Ok(());
            }
            let slope = dot(&self.residual, &self.direction);
            // Only a positive definite factor guarantees a descent direction.
            if !self.solver.use_lu && slope < 0.0 {
                last_step = Some(LastStep { slope });
            }
            for i in 0..a.len() {
                a[i] += self.direction[i];
            }
        }
        Err(SimError::NewtonFailed {
            step,
            time: t_new,
            iterations: self.newton.max_iterations,
            residual: last,
            halvings: 0,
        })
    }

    /// Fills the trial state, `f_int` and the residual `R = M a + D v + f_int − f_ext` at `a`;
    /// returns `(|R|, scale)`, the scale being the largest of the terms' norms (for the relative
    /// test).
    fn evaluate(
        &mut self,
        model: &dyn DynamicModel,
        q_hat: &[f64],
        v_hat: &[f64],
        a: &[f64],
    ) -> (f64, f64) {
        for i in 0..a.len() {
            self.q_trial[i] = q_hat[i] + self.cq * a[i];
            self.v_trial[i] = v_hat[i] + self.cv * a[i];
        }
        model.internal_force(&self.q_trial, &mut self.fint);
        self.mass.mul_vec(a, &mut self.residual);
        let mut scale = norm(&self.residual)
            .max(norm(&self.fint))
            .max(norm(&self.fext));
        if let Some(d) = model.damping() {
            d.mul_vec(&self.v_trial, &mut self.work);
            scale = scale.max(norm(&self.work));
            for i in 0..a.len() {
                self.residual[i] += self.work[i];
            }
        }
        if let Some(c) = model.configuration_damping() {
            self.work.fill(0.0);
            c.add_damping_force(&self.q_trial, &self.v_trial, &mut self.work);
            scale = scale.max(norm(&self.work));
            for i in 0..a.len() {
                self.residual[i] += self.work[i];
            }
        }
        for i in 0..a.len() {
            self.residual[i] += self.fint[i] - self.fext[i];
        }
        (norm(&self.residual), scale)
    }

    /// The step energy `Ψ(a) = E(q̂ + c_q a)/c_q + ½aᵀ(M + c_v D)a + (D v̂ − f_ext)ᵀa`, whose
    /// gradient is the residual (overwrites the `q_trial`, `work` and `fint` buffers).
    fn step_energy(
        &mut self,
        model: &dyn DynamicModel,
        q_hat: &[f64],
        v_hat: &[f64],
        a: &[f64],
    ) -> f64 {
        for i in 0..a.len() {
            self.q_trial[i] = q_hat[i] + self.cq * a[i];
        }
        let mut psi = model.potential_energy(&self.q_trial) / self.cq
            + 0.5 * model.mass().quadratic_form(a)
            - dot(&self.fext, a);
        if let Some(d) = model.damping() {
            // ½ c_v aᵀDa + (D v̂)ᵀa = aᵀD(½ c_v a + v̂).
            for i in 0..a.len() {
                self.work[i] = 0.5 * self.cv * a[i] + v_hat[i];
            }
            d.mul_vec(&self.work, &mut self.fint);
            psi += dot(a, &self.fint);
        }
        if let Some(c) = model.configuration_damping() {
            // The same with C held at the predicted positions q̂ (module docs).
            for i in 0..a.len() {
                self.work[i] = 0.5 * self.cv * a[i] + v_hat[i];
            }
            self.fint.fill(0.0);
            c.add_damping_force(q_hat, &self.work, &mut self.fint);
            psi += dot(a, &self.fint);
        }
        psi
    }

    /// Backtracks the last step: `a` holds `a₀ + p` (`p` in `direction`, slope `Rᵀp` at `a₀`);
    /// halves the step until `Ψ(a₀ + αp) ≤ Ψ(a₀) + ARMIJO·α·Rᵀp`. Returns whether `a` was
    /// changed; `false` (full step kept) when the full step already decreases Ψ enough or no
    /// halving does.
    fn backtrack(
        &mut self,
        model: &dyn DynamicModel,
        q_hat: &[f64],
        v_hat: &[f64],
        a: &mut [f64],
        last: &LastStep,
    ) -> bool {
        for i in 0..a.len() {
            a[i] -= self.direction[i];
        }
        let psi0 = self.step_energy(model, q_hat, v_hat, a);
        let mut alpha = 1.0;
        for halving in 0..=MAX_HALVINGS {
            for i in 0..a.len() {
                a[i] += alpha * self.direction[i];
            }
            let psi = self.step_energy(model, q_hat, v_hat, a);
            if psi <= psi0 + ARMIJO * alpha * last.slope {
                return halving > 0;
            }
            for i in 0..a.len() {
                a[i] -= alpha * self.direction[i];
            }
            alpha *= 0.5;
        }
        // No sufficient decrease (Ψ's round-off, or an inexact energy): keep the full step.
        for i in 0..a.len() {
            a[i] += self.direction[i];
        }
        false
    }

    /// Replaces the guess `a` by the acceleration that keeps `q_prev` when Ψ is lower there
    /// (see [`ImplicitCore::solve`]); uses `direction` as scratch.
    fn start_low(
        &mut self,
        model: &dyn DynamicModel,
        q_prev: &[f64],
        q_hat: &[f64],
        v_hat: &[f64],
        a: &mut [f64],
    ) {
        let mut stay = std::mem::take(&mut self.direction);
        for i in 0..a.len() {
            stay[i] = (q_prev[i] - q_hat[i]) / self.cq;
        }
        let psi_guess = self.step_energy(model, q_hat, v_hat, a);
        let psi_stay = self.step_energy(model, q_hat, v_hat, &stay);
        if psi_stay < psi_guess {
            a.copy_from_slice(&stay);
        }
        self.direction = stay;
    }

    fn non_finite(&self, step: usize, time: f64) -> SimError {
        SimError::Diverged {
            step,
            time,
            reason: format!("non-finite Newton residual in {}", self.name),
        }
    }
}

fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

#[cfg(test)]
mod tests {
    //! The private pieces of the line search against hand computations: the step energy Ψ and
    //! the halving of a step.

    use super::*;
    use crate::SystemMatrix;

    /// `M = diag(m)`, `D = diag(d)` (optional), `f_int = K q + ε q³` with
    /// `E = ½ qᵀKq + ¼ε Σ q⁴`, a constant load `f`.
    struct Quartic {
        mass: SystemMatrix,
        damping: Option<SystemMatrix>,
        k: SparseMatrix,
        epsilon: f64,
        force: Vec<f64>,
    }

    impl DynamicModel for Quartic {
        fn n_dofs(&self) -> usize {
            self.k.nrows()
        }
        fn mass(&self) -> &SystemMatrix {
            &self.mass
        }
        fn damping(&self) -> Option<&SystemMatrix> {
            self.damping.as_ref()
        }
        fn internal_force(&self, q: &[f64], out: &mut [f64]) {
            self.k.mul_vec(q, out);
            for (o, x) in out.iter_mut().zip(q) {
                *o += self.epsilon * x * x * x;
            }
        }
        fn external_force(&self, _t: f64, out: &mut [f64]) {
            out.copy_from_slice(&self.force);
        }
        fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix {
            let d: Vec<f64> = q.iter().map(|x| 3.0 * self.epsilon * x * x).collect();
            SparseMatrix::linear_combination(1.0, &self.k, 1.0, &SparseMatrix::from_diagonal(&d))
                .unwrap()
        }
        fn potential_energy(&self, q: &[f64]) -> f64 {
            0.5 * self.k.quadratic_form(q)
                + 0.25 * self.epsilon * q.iter().map(|x| x.powi(4)).sum::<f64>()
        }
    }

    fn two_masses() -> Quartic {
        Quartic {
            mass: SystemMatrix::Diagonal(vec![1.0, 2.0]),
            damping: Some(SystemMatrix::Diagonal(vec![0.3, 0.5])),
            k: SparseMatrix::from_triplets(
                2,
                2,
                &[(0, 0, 3.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 2.0)],
            )
            .unwrap(),
            epsilon: 4.0,
            force: vec![0.7, -0.4],
        }
    }

    /// Ψ at one point by hand, and its gradient (central differences) against the residual.
    #[test]
    fn the_step_energy_is_the_potential_of_the_residual() {
        let model = two_masses();
        let (cq, cv) = (0.04, 0.2);
        let mut core =
            ImplicitCore::new("test", &model, cq, cv, NewtonSettings::default()).unwrap();
        core.fext.copy_from_slice(&model.force);
        let (q_hat, v_hat) = ([0.3, -0.2], [0.5, 0.1]);
        let a = [1.5, -2.5];
        // By hand: q = q̂ + c_q a = (0.36, −0.30);
        // E(q) = ½(3·0.36² − 2·0.36·(−0.30) + 2·0.30²) + (0.36⁴ + 0.30⁴)
        //      = ½(0.3888 + 0.216 + 0.18) + (0.01679616 + 0.0081) = 0.41729616;
        // ½aᵀMa = ½(2.25 + 2·6.25) = 7.375; ½c_v aᵀDa = 0.1(0.3·2.25 + 0.5·6.25) = 0.38;
        // (D v̂)ᵀa = 0.15·1.5 + 0.05·(−2.5) = 0.1; −fᵀa = −(1.05 + 1.0) = −2.05.
        let expected = 0.41729616 / cq + 7.375 + 0.38 + 0.1 - 2.05;
        let psi = core.step_energy(&model, &q_hat, &v_hat, &a);
        assert!(
            (psi - expected).abs() <= 1e-14 * expected.abs(),
            "Ψ = {psi}, by hand {expected}"
        );
        // ∇Ψ = R = M a + D(v̂ + c_v a) + f_int(q̂ + c_q a) − f: Ψ is a quartic in a, so the
        // central difference errs by h²/6·|Ψ'''| = h²·ε·c_q²·|q| ≈ 2e-11 (h = 1e-4) plus the
        // round-off ε·|Ψ|/h ≈ 4e-11.
        core.evaluate(&model, &q_hat, &v_hat, &a);
        let residual = core.residual.clone();
        let h = 1e-4;
        for i in 0..2 {
            let (mut ap, mut am) = (a, a);
            ap[i] += h;
            am[i] -= h;
            let fd = (core.step_energy(&model, &q_hat, &v_hat, &ap)
                - core.step_energy(&model, &q_hat, &v_hat, &am))
                / (2.0 * h);
            assert!(
                (fd - residual[i]).abs() < 1e-9,
                "{i}: {fd} vs {}",
                residual[i]
            );
        }
    }

    /// One mass, `E = ¼q⁴`, m = 1, c_q = c_v = 1, q̂ = v̂ = 0: `Ψ(a) = ¼a⁴ + ½a²`,
    /// `R(a) = a³ + a`. From a₀ = 1 (Ψ = 0.75, R = 2) along p with slope `R p`.
    fn one_mass() -> (Quartic, ImplicitCore) {
        let model = Quartic {
            mass: SystemMatrix::Diagonal(vec![1.0]),
            damping: None,
            k: SparseMatrix::from_diagonal(&[0.0]),
            epsilon: 1.0,
            force: vec![0.0],
        };
        let core = ImplicitCore::new("test", &model, 1.0, 1.0, NewtonSettings::default()).unwrap();
        (model, core)
    }

    /// Runs `backtrack` for the step p from a₀ = 1 (a holds a₀ + p on entry, as in `solve`).
    fn backtrack(p: f64, slope: f64) -> (bool, f64) {
        let (model, mut core) = one_mass();
        core.direction = vec![p];
        let mut a = [1.0 + p];
        let changed = core.backtrack(&model, &[0.0], &[0.0], &mut a, &LastStep { slope });
        (changed, a[0])
    }

    #[test]
    fn backtracking_halves_the_step_to_the_first_that_lowers_psi_by_the_armijo_fraction() {
        // p = −4, slope −8: α = 1 gives a = −3, Ψ = 24.75; α = ½ gives a = −1, Ψ = 0.75, equal
        // to Ψ(a₀) and so above the bound 0.75 − 1e-4·½·8; α = ¼ gives a = 0, Ψ = 0: taken.
        assert_eq!(backtrack(-4.0, -8.0), (true, 0.0));
        // p = −1.5 (the step to a = −0.5, Ψ = 0.140625 < 0.75 − 1e-4·3): the full step is kept.
        assert_eq!(backtrack(-1.5, -3.0), (false, -0.5));
        // An uphill p = +1 declared a descent: no α ≥ 2⁻²⁰ lowers Ψ, so the full step is kept.
        assert_eq!(backtrack(1.0, -2.0), (false, 2.0));
        // The bound scales with α and the slope. Near a = −1, where Ψ = Ψ(a₀) = 0.75 and
        // Ψ' = −2: `Ψ(−1 + δ) = 0.75 − 2δ + O(δ²)`.
        // p = −2 + 2⁻¹³ (slope R p ≈ −4): α = 1 lowers Ψ by 2·2⁻¹³ ≈ 2.4e-4, less than the
        // 4e-4 asked for, and α = ½ reaches a = 2⁻¹⁴, Ψ ≈ 0.
        let p = -2.0 + 2f64.powi(-13);
        assert_eq!(backtrack(p, 2.0 * p), (true, 2f64.powi(-14)));
        // p = −4 + 2⁻¹⁰ (slope ≈ −8): α = ½ reaches a = −1 + 2⁻¹¹, lowering Ψ by
        // 2·2⁻¹¹ ≈ 9.8e-4, more than the 4e-4 asked for at α = ½: taken.
        let p = -4.0 + 2f64.powi(-10);
        assert_eq!(backtrack(p, 2.0 * p), (true, -1.0 + 2f64.powi(-11)));
    }
}
