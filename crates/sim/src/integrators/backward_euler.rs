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

use super::implicit::{CoreLadder, HalvableStep, step_with_halving};
use super::{NewtonSettings, check_fixed_dt};
use crate::{DynamicModel, SimError, State};

/// Backward Euler stepper.
pub struct BackwardEuler {
    dt: f64,
    cores: CoreLadder,
    /// The last step's acceleration, the Newton initial guess.
    a: Vec<f64>,
    a_new: Vec<f64>,
    q_hat: Vec<f64>,
    steps: usize,
}

impl BackwardEuler {
    /// Builds the stepper (and, for a linear model, factors `M + ΔtD + Δt²K` once).
    pub fn new(
        model: &dyn DynamicModel,
        dt: f64,
        newton: NewtonSettings,
    ) -> Result<Self, SimError> {
        let n = model.n_dofs();
        let cores = CoreLadder::new("backward-euler", model, dt, coefficients, newton)?;
        Ok(Self {
            dt,
            cores,
            a: vec![0.0; n],
            a_new: vec![0.0; n],
            q_hat: vec![0.0; n],
            steps: 0,
        })
    }

    /// How many Newton matrices were factored, Newton iterations run and steps halved so far.
    pub fn newton_counts(&self) -> super::NewtonCounts {
        self.cores.counts()
    }
}

/// `(c_q, c_v) = (h², h)`.
fn coefficients(h: f64) -> (f64, f64) {
    (h * h, h)
}

impl HalvableStep for BackwardEuler {
    fn substep(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        level: u32,
    ) -> Result<(), SimError> {
        let dt = self.cores.h(level);
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
            self.steps,
        )?;
        std::mem::swap(&mut self.a, &mut self.a_new);
        for i in 0..state.q.len() {
            state.v[i] += dt * self.a[i];
            state.q[i] = self.q_hat[i] + dt * dt * self.a[i];
        }
        state.t = t_new;
        Ok(())
    }

    fn carried(&mut self) -> &mut Vec<f64> {
        &mut self.a
    }

    fn ladder(&mut self) -> &mut CoreLadder {
        &mut self.cores
    }
}

impl super::Stepper for BackwardEuler {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        check_fixed_dt("backward-euler", self.dt, dt)?;
        self.steps += 1;
        step_with_halving(self, model, state)
    }

    fn halved_steps(&self) -> usize {
        self.cores.counts().halved_steps
    }
}
