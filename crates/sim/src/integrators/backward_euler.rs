//! Backward (implicit) Euler with Newton iterations.
//!
//! ODE: `M q̈ + D q̇ + f_int(q) = f_ext(t)` (f_int with the sign of a stiffness). The step
//! `v_{n+1} = v_n + Δt a`, `q_{n+1} = q_n + Δt v_{n+1}` with
//! `M a + D v_{n+1} + f_int(q_{n+1}) = f_ext(t_{n+1})`, i.e. Newton on
//! `(M + ΔtD + Δt²K_T) Δv = …` for `Δv = Δt a`. The Newton matrix is factored by sparse
//! Cholesky ([`nurbspring_linalg::SpdSolver`], symbolic analysis once) while it is positive
//! definite; when Cholesky fails — compressed springs make `K_T` indefinite — the step falls
//! back to a sparse LU ([`nurbspring_linalg::LuSolver`]). Linear models factor once. A step on
//! which Newton fails is taken in halves ([`super::implicit`]'s step halving).
//! First order, unconditionally stable, numerically dissipative.

use super::NewtonSettings;
use super::implicit::{CoreLadder, HalvableStep, StepCoefficients};
use crate::{DynamicModel, SimError, State};

/// Backward Euler stepper.
pub struct BackwardEuler {
    cores: CoreLadder,
    /// The last step's acceleration, the Newton initial guess.
    a: Vec<f64>,
    a_new: Vec<f64>,
    q_hat: Vec<f64>,
}

impl BackwardEuler {
    /// Builds the stepper (and, for a linear model, factors `M + ΔtD + Δt²K` once).
    pub fn new(
        model: &dyn DynamicModel,
        dt: f64,
        newton: NewtonSettings,
    ) -> Result<Self, SimError> {
        let n = model.n_dofs();
        let cores = CoreLadder::new("backward-euler", model, dt, COEFFICIENTS, newton)?;
        Ok(Self {
            cores,
            a: vec![0.0; n],
            a_new: vec![0.0; n],
            q_hat: vec![0.0; n],
        })
    }

    /// How many Newton matrices were factored, Newton iterations run and steps halved so far.
    pub fn newton_counts(&self) -> super::NewtonCounts {
        self.cores.counts()
    }
}

/// `(c_q, c_v) = (h², h)`.
const COEFFICIENTS: StepCoefficients = StepCoefficients {
    kappa_q: 1.0,
    kappa_v: 1.0,
};

impl HalvableStep for BackwardEuler {
    fn substep(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        level: u32,
    ) -> Result<(), SimError> {
        let (dt, step) = (self.cores.h(level), self.cores.steps);
        for i in 0..state.q.len() {
            self.q_hat[i] = state.q[i] + dt * state.v[i];
        }
        let t_new = state.t + dt;
        // The previous step's acceleration is the Newton initial guess.
        self.a_new.copy_from_slice(&self.a);
        self.cores.core(model, level)?.solve(
            model,
            &state.q,
            &self.q_hat,
            &state.v,
            t_new,
            &mut self.a_new,
            step,
        )?;
        std::mem::swap(&mut self.a, &mut self.a_new);
        for i in 0..state.q.len() {
            state.v[i] += dt * self.a[i];
            state.q[i] = self.q_hat[i] + dt * dt * self.a[i];
        }
        state.t = t_new;
        Ok(())
    }

    fn carried(&mut self) -> &mut [Vec<f64>] {
        std::slice::from_mut(&mut self.a)
    }

    fn ladder(&self) -> &CoreLadder {
        &self.cores
    }

    fn ladder_mut(&mut self) -> &mut CoreLadder {
        &mut self.cores
    }
}
