//! Explicit schemes: symplectic Euler, velocity Verlet (the central difference) and classical
//! RK4.
//!
//! ODE: `M q̈ + D q̇ + f_int(q) = f_ext(t)`, so `q̈ = M⁻¹ (f_ext(t) − f_int(q) − D q̇)` (f_int
//! with the sign of a stiffness). `M⁻¹` is applied by a [`MassInverse`]: entrywise for a
//! diagonal (lumped) mass, the fast path of the mass-spring model, and by a sparse Cholesky
//! factor for any other symmetric positive definite (consistent) mass, its symbolic analysis and
//! numeric factorization done once when the stepper is built and two triangular solves a force
//! evaluation. All three are conditionally stable: Δt must stay below `2/ω_max` (symplectic
//! Euler, Verlet) or `2√2/ω_max` (RK4), `ω_max² = λ_max(K_T φ = λ M φ)` with the mass as it is
//! (a consistent mass raises ω_max over the lumped one); [`crate::simulate`] checks `2/ω_max`
//! before running. Every buffer is allocated when the stepper is built; a step with a diagonal
//! mass allocates nothing (a factored solve takes faer's scratch space per call).

use nurbspring_linalg::{LinalgError, SparseMatrix, SpdSolver};

use crate::{DynamicModel, SimError, State, SystemMatrix};

/// How an explicit scheme applies `M⁻¹`.
///
/// ```
/// use nurbspring_linalg::SparseMatrix;
/// use nurbspring_sim::SystemMatrix;
/// use nurbspring_sim::integrators::MassInverse;
/// // The consistent mass of one linear element, (m/6)[2 1; 1 2] with m = 6: M⁻¹(3, 3) = (1, 1).
/// let m = SparseMatrix::from_triplets(2, 2, &[(0, 0, 2.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 2.0)]).unwrap();
/// let inverse = MassInverse::of(&SystemMatrix::Sparse(m)).unwrap();
/// assert!(!inverse.is_diagonal());
/// let mut x = [3.0, 3.0];
/// inverse.apply(&mut x);
/// assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
/// ```
#[derive(Clone, Debug)]
pub enum MassInverse {
    /// `1/m_i` of a diagonal (lumped) mass, applied entrywise.
    Diagonal(Vec<f64>),
    /// The sparse Cholesky factor of a symmetric positive definite mass, applied by forward and
    /// back substitution.
    Factored(SpdSolver),
}

impl MassInverse {
    /// The inverse of `mass`: [`MassInverse::Diagonal`] when it is diagonal
    /// ([`SystemMatrix::as_diagonal`]: a `Diagonal`, or a `Sparse` whose off-diagonal values are
    /// zero), [`MassInverse::Factored`] otherwise. [`SimError::NotSupported`] (naming the entry
    /// or the failed pivot) unless the mass is positive definite.
    pub fn of(mass: &SystemMatrix) -> Result<Self, SimError> {
        let Some(d) = mass.as_diagonal() else {
            return Self::factored(&mass.to_sparse());
        };
        if let Some(i) = d.iter().position(|&m| !(m > 0.0 && m.is_finite())) {
            return Err(not_positive(format!(
                "mass entry {i} is {}, not positive",
                d[i]
            )));
        }
        Ok(MassInverse::Diagonal(d.iter().map(|m| 1.0 / m).collect()))
    }

    /// The Cholesky factor of `mass` whatever its pattern (a diagonal mass included: the
    /// factored path of the explicit schemes on any mass). [`SimError::NotSupported`] unless
    /// `mass` is symmetric positive definite.
    pub fn factored(mass: &SparseMatrix) -> Result<Self, SimError> {
        match SpdSolver::new(mass) {
            Ok(solver) => Ok(MassInverse::Factored(solver)),
            Err(e @ (LinalgError::NotPositiveDefinite { .. } | LinalgError::NonFinite { .. })) => {
                Err(not_positive(format!(
                    "the mass matrix cannot be factored: {e}"
                )))
            }
            Err(e) => Err(e.into()),
        }
    }

    /// Whether `M⁻¹` is applied entrywise.
    pub fn is_diagonal(&self) -> bool {
        matches!(self, MassInverse::Diagonal(_))
    }

    /// `x ← M⁻¹ x`.
    ///
    /// # Panics
    /// If `x` does not have the size of the mass.
    pub fn apply(&self, x: &mut [f64]) {
        match self {
            MassInverse::Diagonal(inv_m) => {
                assert_eq!(x.len(), inv_m.len(), "MassInverse::apply: size mismatch");
                for (o, w) in x.iter_mut().zip(inv_m) {
                    *o *= w;
                }
            }
            MassInverse::Factored(solver) => solver.solve_in_place(x),
        }
    }

    fn dim(&self) -> usize {
        match self {
            MassInverse::Diagonal(inv_m) => inv_m.len(),
            MassInverse::Factored(solver) => solver.dim(),
        }
    }
}

/// The error of a mass that is not positive definite (the integrator is named by the caller).
fn not_positive(reason: String) -> SimError {
    SimError::NotSupported {
        integrator: "explicit schemes",
        reason: format!("{reason}; M must be symmetric positive definite"),
    }
}

/// [`MassInverse::of`] the model's mass, with the scheme named in the error, and of the size
/// of the model.
fn model_mass_inverse(
    model: &dyn DynamicModel,
    inverse: Option<MassInverse>,
    name: &'static str,
) -> Result<MassInverse, SimError> {
    let inverse = match inverse {
        Some(inverse) => inverse,
        None => MassInverse::of(model.mass()).map_err(|e| match e {
            SimError::NotSupported { reason, .. } => SimError::NotSupported {
                integrator: name,
                reason,
            },
            other => other,
        })?,
    };
    if inverse.dim() != model.n_dofs() {
        return Err(SimError::DimensionMismatch {
            what: "mass inverse",
            expected: model.n_dofs(),
            found: inverse.dim(),
        });
    }
    Ok(inverse)
}

/// `out = M⁻¹ (f_ext(t) − f_int(q) − D v − C(q) v)` using the buffer `fint`.
fn acceleration(
    model: &dyn DynamicModel,
    inv_m: &MassInverse,
    t: f64,
    q: &[f64],
    v: &[f64],
    fint: &mut [f64],
    out: &mut [f64],
) {
    model.external_force(t, out);
    model.internal_force(q, fint);
    if let Some(c) = model.configuration_damping() {
        c.add_damping_force(q, v, fint);
    }
    for (o, f) in out.iter_mut().zip(fint.iter()) {
        *o -= f;
    }
    if let Some(d) = model.damping() {
        d.mul_vec_add(-1.0, v, out);
    }
    inv_m.apply(out);
}

/// Symplectic (semi-implicit) Euler: `v⁺ = v + Δt M⁻¹(f_ext(t) − f_int(q) − D v)`, then
/// `q⁺ = q + Δt v⁺`. First order; symplectic, so without damping the energy error stays
/// bounded (no drift); stable for `Δt < 2/ω_max`. A model with a fused step
/// ([`DynamicModel::fused_step`]) runs its own; otherwise the forces come first and, with a
/// diagonal mass, the update is one pass over the dofs; with a consistent mass the acceleration
/// is one solve with the mass factor.
pub struct SymplecticEuler {
    inv_m: MassInverse,
    /// Diagonal damping, when the model's damping is diagonal (then the update is one fused
    /// pass over the dofs).
    damping_diag: Option<Vec<f64>>,
    a: Vec<f64>,
    fint: Vec<f64>,
    /// Workspace of the model's fused step ([`DynamicModel::fused_step`]), when it has one.
    fused: Vec<f64>,
}

/// Dofs per parallel chunk of the fused update (below two chunks the update runs serially).
const UPDATE_CHUNK: usize = 16 * 1024;

impl SymplecticEuler {
    /// Builds the stepper with the model's [`MassInverse::of`] (a consistent mass is factored
    /// here, once); NotSupported unless M is positive definite.
    pub fn new(model: &dyn DynamicModel) -> Result<Self, SimError> {
        Self::build(model, None)
    }

    /// Builds the stepper with a given `M⁻¹` of the model's mass (e.g.
    /// [`MassInverse::factored`] to run a diagonal mass through the factored path).
    pub fn with_mass_inverse(
        model: &dyn DynamicModel,
        inverse: MassInverse,
    ) -> Result<Self, SimError> {
        Self::build(model, Some(inverse))
    }

    fn build(model: &dyn DynamicModel, inverse: Option<MassInverse>) -> Result<Self, SimError> {
        let inv_m = model_mass_inverse(model, inverse, "symplectic-euler")?;
        let n = model.n_dofs();
        let damping_diag = match model.damping() {
            None => Some(vec![0.0; n]),
            Some(d) => d.as_diagonal(),
        };
        let fused = vec![0.0; model.fused_step().map_or(0, |f| f.workspace_len())];
        Ok(Self {
            inv_m,
            damping_diag,
            a: vec![0.0; n],
            fint: vec![0.0; n],
            fused,
        })
    }
}

impl super::Stepper for SymplecticEuler {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        if let Some(fused) = model.fused_step() {
            let len = fused.workspace_len();
            if self.fused.len() < len {
                // Only when called with another model than the one it was built for.
                self.fused.resize(len, 0.0);
            }
            fused.symplectic_euler(state.t, dt, &mut state.q, &mut state.v, &mut self.fused);
            state.t += dt;
            return Ok(());
        }
        let (MassInverse::Diagonal(inv_m), Some(d)) = (&self.inv_m, &self.damping_diag) else {
            acceleration(
                model,
                &self.inv_m,
                state.t,
                &state.q,
                &state.v,
                &mut self.fint,
                &mut self.a,
            );
            for i in 0..state.q.len() {
                state.v[i] += dt * self.a[i];
                state.q[i] += dt * state.v[i];
            }
            state.t += dt;
            return Ok(());
        };
        // Forces first (the model parallelizes them), then one fused pass:
        // v += Δt M⁻¹ (f_ext − f_int − C(q) v − D v), q += Δt v.
        model.external_force(state.t, &mut self.a);
        model.internal_force(&state.q, &mut self.fint);
        if let Some(c) = model.configuration_damping() {
            c.add_damping_force(&state.q, &state.v, &mut self.fint);
        }
        let (fext, fint) = (&self.a, &self.fint);
        let update = |offset: usize, v: &mut [f64], q: &mut [f64]| {
            for k in 0..v.len() {
                let i = offset + k;
                let f = fext[i] - fint[i] - d[i] * v[k];
                v[k] += dt * inv_m[i] * f;
                q[k] += dt * v[k];
            }
        };
        if state.q.len() >= 2 * UPDATE_CHUNK {
            use rayon::prelude::*;
            state
                .v
                .par_chunks_mut(UPDATE_CHUNK)
                .zip(state.q.par_chunks_mut(UPDATE_CHUNK))
                .enumerate()
                .for_each(|(c, (v, q))| update(c * UPDATE_CHUNK, v, q));
        } else {
            update(0, &mut state.v, &mut state.q);
        }
        state.t += dt;
        Ok(())
    }
}

/// Velocity Verlet (Störmer–Verlet; the central difference
/// `M (q⁺ − 2q + q⁻)/Δt² + f_int(q) = f_ext(t)` written with velocities):
/// `v½ = v + ½Δt a`, `q⁺ = q + Δt v½`, `a⁺ = M⁻¹(f_ext(t⁺) − f_int(q⁺) − D v⁺)`,
/// `v⁺ = v½ + ½Δt a⁺`. Second order, symplectic without damping, stable for
/// `Δt < 2/ω_max`. A configuration damping `C(q⁺)` ([`crate::ConfigurationDamping`]) is
/// evaluated at `v½` (first order in that term).
///
/// With a diagonal mass, a diagonal D is treated implicitly in that last half step,
/// `(M + ½ΔtD) v⁺ = M v½ + ½Δt (f_ext − f_int)`, which is explicit for diagonal matrices; a
/// non-diagonal D is evaluated at `v½` (first order in the damping term). With a consistent
/// (factored) mass every D is implicit there: `(M + ½ΔtD) a⁺ = f_ext − f_int − D v½`, one solve
/// with the factor of `M + ½ΔtD` (symbolic analysis once; refactored numerically only when
/// Δt changes), so the damped scheme stays second order.
pub struct VelocityVerlet {
    inv_m: MassInverse,
    /// The diagonal mass (diagonal path only; empty otherwise).
    mass: Vec<f64>,
    damping_diag: Option<Vec<f64>>,
    /// Factored path with damping: `M + ½hD` and its factor for the step `h` it was made for.
    damped: Option<DampedMass>,
    a: Vec<f64>,
    f: Vec<f64>,
    fint: Vec<f64>,
}

/// `M + ½hD` on one pattern and its Cholesky factor, for the step `h`.
struct DampedMass {
    mass: SparseMatrix,
    damping: SparseMatrix,
    sum: Option<(f64, nurbspring_linalg::ShiftedSum, SpdSolver)>,
}

impl DampedMass {
    /// The factor of `M + ½hD`, made or refactored when `h` differs from the last one.
    fn solver(&mut self, h: f64) -> Result<&SpdSolver, SimError> {
        let half = 0.5 * h;
        match &mut self.sum {
            Some((made_for, plan, solver)) => {
                if *made_for != h {
                    solver.refactor(plan.update(half, &self.damping)?)?;
                    *made_for = h;
                }
            }
            None => {
                let plan = nurbspring_linalg::ShiftedSum::new(&self.mass, half, &self.damping)?;
                let solver = SpdSolver::new(plan.matrix())?;
                self.sum = Some((h, plan, solver));
            }
        }
        Ok(&self.sum.as_ref().expect("made above").2)
    }
}

impl VelocityVerlet {
    /// Builds the stepper with the initial acceleration and the model's [`MassInverse::of`]
    /// (a consistent mass is factored here, once); NotSupported unless M is positive definite.
    pub fn new(model: &dyn DynamicModel, initial: &State) -> Result<Self, SimError> {
        Self::build(model, initial, None)
    }

    /// Builds the stepper with a given `M⁻¹` of the model's mass (e.g.
    /// [`MassInverse::factored`] to run a diagonal mass through the factored path).
    pub fn with_mass_inverse(
        model: &dyn DynamicModel,
        initial: &State,
        inverse: MassInverse,
    ) -> Result<Self, SimError> {
        Self::build(model, initial, Some(inverse))
    }

    fn build(
        model: &dyn DynamicModel,
        initial: &State,
        inverse: Option<MassInverse>,
    ) -> Result<Self, SimError> {
        let inv_m = model_mass_inverse(model, inverse, "verlet")?;
        let n = model.n_dofs();
        let (mass, damping_diag, damped) = match &inv_m {
            MassInverse::Diagonal(inv) => (
                inv.iter().map(|w| 1.0 / w).collect(),
                model.damping().and_then(|d| d.as_diagonal()),
                None,
            ),
            MassInverse::Factored(_) => (
                Vec::new(),
                None,
                model.damping().map(|d| DampedMass {
                    mass: model.mass().to_sparse(),
                    damping: d.to_sparse(),
                    sum: None,
                }),
            ),
        };
        let mut a = vec![0.0; n];
        let mut fint = vec![0.0; n];
        acceleration(
            model, &inv_m, initial.t, &initial.q, &initial.v, &mut fint, &mut a,
        );
        Ok(Self {
            inv_m,
            mass,
            damping_diag,
            damped,
            a,
            f: vec![0.0; n],
            fint,
        })
    }
}

impl super::Stepper for VelocityVerlet {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        let n = state.q.len();
        let h = 0.5 * dt;
        for i in 0..n {
            state.v[i] += h * self.a[i];
            state.q[i] += dt * state.v[i];
        }
        let t_new = state.t + dt;
        model.external_force(t_new, &mut self.f);
        model.internal_force(&state.q, &mut self.fint);
        // Configuration damping at v½, like a non-diagonal D (first order in that term).
        if let Some(c) = model.configuration_damping() {
            c.add_damping_force(&state.q, &state.v, &mut self.fint);
        }
        for i in 0..n {
            self.f[i] -= self.fint[i];
        }
        match (&self.inv_m, &self.damping_diag, model.damping()) {
            (MassInverse::Diagonal(_), Some(d), _) => {
                for i in 0..n {
                    let v_new =
                        (self.mass[i] * state.v[i] + h * self.f[i]) / (self.mass[i] + h * d[i]);
                    self.a[i] = (v_new - state.v[i]) / h;
                    state.v[i] = v_new;
                }
            }
            (MassInverse::Diagonal(inv_m), None, damping) => {
                if let Some(d) = damping {
                    d.mul_vec_add(-1.0, &state.v, &mut self.f);
                }
                for i in 0..n {
                    self.a[i] = self.f[i] * inv_m[i];
                    state.v[i] += h * self.a[i];
                }
            }
            (MassInverse::Factored(solver), _, damping) => {
                match (damping, &mut self.damped) {
                    // (M + ½ΔtD) a⁺ = f_ext − f_int − D v½.
                    (Some(d), Some(damped)) => {
                        d.mul_vec_add(-1.0, &state.v, &mut self.f);
                        damped.solver(dt)?.solve_in_place(&mut self.f);
                    }
                    // Undamped (or called with another model than it was built for: damping
                    // at v½).
                    (damping, _) => {
                        if let Some(d) = damping {
                            d.mul_vec_add(-1.0, &state.v, &mut self.f);
                        }
                        solver.solve_in_place(&mut self.f);
                    }
                }
                for i in 0..n {
                    self.a[i] = self.f[i];
                    state.v[i] += h * self.a[i];
                }
            }
        }
        state.t = t_new;
        Ok(())
    }
}

/// Classical fourth-order Runge–Kutta on the first-order system `(q̇, v̇) = (v, q̈(t, q, v))`.
/// Fourth order; not symplectic (slight energy decay); stable for `Δt < 2√2/ω_max`.
pub struct Rk4 {
    inv_m: MassInverse,
    kq: [Vec<f64>; 4],
    kv: [Vec<f64>; 4],
    q_stage: Vec<f64>,
    v_stage: Vec<f64>,
    fint: Vec<f64>,
}

impl Rk4 {
    /// Builds the stepper with the model's [`MassInverse::of`] (a consistent mass is factored
    /// here, once); NotSupported unless M is positive definite.
    pub fn new(model: &dyn DynamicModel) -> Result<Self, SimError> {
        Self::build(model, None)
    }

    /// Builds the stepper with a given `M⁻¹` of the model's mass (e.g.
    /// [`MassInverse::factored`] to run a diagonal mass through the factored path).
    pub fn with_mass_inverse(
        model: &dyn DynamicModel,
        inverse: MassInverse,
    ) -> Result<Self, SimError> {
        Self::build(model, Some(inverse))
    }

    fn build(model: &dyn DynamicModel, inverse: Option<MassInverse>) -> Result<Self, SimError> {
        let inv_m = model_mass_inverse(model, inverse, "rk4")?;
        let n = model.n_dofs();
        let z = || vec![0.0; n];
        Ok(Self {
            inv_m,
            kq: [z(), z(), z(), z()],
            kv: [z(), z(), z(), z()],
            q_stage: z(),
            v_stage: z(),
            fint: z(),
        })
    }
}

impl super::Stepper for Rk4 {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        let n = state.q.len();
        let offsets = [0.0, 0.5 * dt, 0.5 * dt, dt];
        for s in 0..4 {
            if s == 0 {
                self.q_stage.copy_from_slice(&state.q);
                self.v_stage.copy_from_slice(&state.v);
            } else {
                let c = offsets[s];
                for i in 0..n {
                    self.q_stage[i] = state.q[i] + c * self.kq[s - 1][i];
                    self.v_stage[i] = state.v[i] + c * self.kv[s - 1][i];
                }
            }
            self.kq[s].copy_from_slice(&self.v_stage);
            acceleration(
                model,
                &self.inv_m,
                state.t + offsets[s],
                &self.q_stage,
                &self.v_stage,
                &mut self.fint,
                &mut self.kv[s],
            );
        }
        let w = dt / 6.0;
        for i in 0..n {
            state.q[i] +=
                w * (self.kq[0][i] + 2.0 * self.kq[1][i] + 2.0 * self.kq[2][i] + self.kq[3][i]);
            state.v[i] +=
                w * (self.kv[0][i] + 2.0 * self.kv[1][i] + 2.0 * self.kv[2][i] + self.kv[3][i]);
        }
        state.t += dt;
        Ok(())
    }
}
