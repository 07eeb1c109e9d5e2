//! The Terzopoulos–Qin scheme for D-NURBS (docs/math.md §3; Terzopoulos & Qin 1994, Qin & Terzopoulos
//! 1996).
//!
//! ODE: `M q̈ + D q̇ + f_int(q) = f_ext(t)` with a linear `f_int(q) = K q + f_int(0)`
//! (`f_int(0) = −K q_rest`). Backward differences at `t + Δt`,
//! `q̈ ≈ (q⁺ − 2q + q⁻)/Δt²`, `q̇ ≈ (q⁺ − q⁻)/(2Δt)`, K and f at `t + Δt`, give
//! `(2M + ΔtD + 2Δt²K) q⁺ = 2Δt² f̃ + 4M q − (2M − ΔtD) q⁻`, `f̃ = f_ext(t + Δt) − f_int(0)`,
//! started with `q⁻ = q⁰ − Δt v⁰`. The reported velocity is the one at the new time `t + Δt`,
//! the second-order backward difference `(3q⁺ − 4q + q⁻)/(2Δt)` (the central difference
//! `(q⁺ − q⁻)/(2Δt)` is the velocity at t, one step behind the state). The matrix is
//! factored once. First order; unconditionally stable and dissipative: each undamped mode is
//! multiplied by `(1 + ω²Δt²)^{-1/2}` per step (periods lengthen; energy is not conserved).

use nurbspring_linalg::{SparseMatrix, SpdSolver};

use super::check_fixed_dt;
use crate::{DynamicModel, SimError, State, SystemMatrix};

/// Terzopoulos–Qin stepper (linear models only).
pub struct TerzopoulosQin {
    dt: f64,
    solver: SpdSolver,
    fint0: Vec<f64>,
    q_prev: Vec<f64>,
    rhs: Vec<f64>,
    fext: Vec<f64>,
}

impl TerzopoulosQin {
    /// Factors `2M + ΔtD + 2Δt²K` and sets `q⁻ = q⁰ − Δt v⁰`. NotSupported for nonlinear models.
    pub fn new(model: &dyn DynamicModel, initial: &State, dt: f64) -> Result<Self, SimError> {
        let k = model.linear_stiffness().ok_or_else(|| SimError::NotSupported {
            integrator: "terzopoulos-qin",
            reason: "the scheme needs a constant stiffness (a linear model); use newmark or backward-euler".into(),
        })?;
        if model.configuration_damping().is_some() {
            return Err(SimError::NotSupported {
                integrator: "terzopoulos-qin",
                reason: "the model's damping depends on its configuration; use newmark or backward-euler".into(),
            });
        }
        let n = model.n_dofs();
        let m = model.mass().to_sparse();
        let mut a = SparseMatrix::linear_combination(2.0, &m, 2.0 * dt * dt, k)?;
        if let Some(d) = model.damping() {
            a = SparseMatrix::linear_combination(1.0, &a, dt, &d.to_sparse())?;
        }
        let solver = SpdSolver::new(&a)?;
        let mut fint0 = vec![0.0; n];
        model.internal_force(&vec![0.0; n], &mut fint0);
        let q_prev = initial
            .q
            .iter()
            .zip(&initial.v)
            .map(|(q, v)| q - dt * v)
            .collect();
        Ok(Self {
            dt,
            solver,
            fint0,
            q_prev,
            rhs: vec![0.0; n],
            fext: vec![0.0; n],
        })
    }
}

impl super::Stepper for TerzopoulosQin {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        check_fixed_dt("terzopoulos-qin", self.dt, dt)?;
        let n = state.q.len();
        let t_new = state.t + dt;
        model.external_force(t_new, &mut self.fext);
        let h2 = 2.0 * dt * dt;
        for i in 0..n {
            self.rhs[i] = h2 * (self.fext[i] - self.fint0[i]);
        }
        // + 4M q − 2M q⁻ = M (4q − 2q⁻), done without a temporary by two products.
        let mass: &SystemMatrix = model.mass();
        mass.mul_vec_add(4.0, &state.q, &mut self.rhs);
        mass.mul_vec_add(-2.0, &self.q_prev, &mut self.rhs);
        if let Some(d) = model.damping() {
            d.mul_vec_add(dt, &self.q_prev, &mut self.rhs);
        }
        self.solver.solve_in_place(&mut self.rhs);
        for i in 0..n {
            let q_new = self.rhs[i];
            state.v[i] = (3.0 * q_new - 4.0 * state.q[i] + self.q_prev[i]) / (2.0 * dt);
            self.q_prev[i] = state.q[i];
            state.q[i] = q_new;
        }
        state.t = t_new;
        Ok(())
    }
}
