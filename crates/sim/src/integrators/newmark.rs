//! Newmark average acceleration (β = 1/4, γ = 1/2; Newmark 1959).
//!
//! ODE: `M q̈ + D q̇ + f_int(q) = f_ext(t)` (f_int with the sign of a stiffness). With
//! `a_n = q̈(t_n)`:
//! `q_{n+1} = q_n + Δt v_n + Δt² ((½ − β) a_n + β a_{n+1})`,
//! `v_{n+1} = v_n + Δt ((1 − γ) a_n + γ a_{n+1})`,
//! and `a_{n+1}` from the equation of motion at `t_{n+1}`. Linear models factor
//! `M + γΔt D + βΔt² K` once; nonlinear models run Newton on the tangent each step (see
//! [`super::implicit`]), and a step on which Newton fails is taken in halves
//! ([`super::implicit`]'s step halving). Second order, unconditionally stable, and for D = 0 it conserves the
//! energy `½vᵀMv + ½(q − q_rest)ᵀK(q − q_rest)` of a linear model exactly (up to round-off).

use nurbspring_linalg::SpdSolver;

use super::NewtonSettings;
use super::implicit::{CoreLadder, HalvableStep, StepCoefficients};
use crate::{DynamicModel, SimError, State};

const BETA: f64 = 0.25;
const GAMMA: f64 = 0.5;

/// Newmark average-acceleration stepper.
pub struct Newmark {
    cores: CoreLadder,
    a: Vec<f64>,
    a_new: Vec<f64>,
    q_hat: Vec<f64>,
    v_hat: Vec<f64>,
}

/// `M⁻¹ (f_ext(t) − f_int(q) − D v − C(q) v)`: the acceleration of the equation of motion.
pub(crate) fn initial_acceleration(
    model: &dyn DynamicModel,
    state: &State,
) -> Result<Vec<f64>, SimError> {
    let n = model.n_dofs();
    let mut f = vec![0.0; n];
    let mut fint = vec![0.0; n];
    model.external_force(state.t, &mut f);
    model.internal_force(&state.q, &mut fint);
    if let Some(c) = model.configuration_damping() {
        c.add_damping_force(&state.q, &state.v, &mut fint);
    }
    for i in 0..n {
        f[i] -= fint[i];
    }
    if let Some(d) = model.damping() {
        d.mul_vec_add(-1.0, &state.v, &mut f);
    }
    match model.mass().as_diagonal() {
        Some(m) => Ok(f.iter().zip(&m).map(|(f, m)| f / m).collect()),
        None => Ok(SpdSolver::new(&model.mass().to_sparse())?.solve(&f)),
    }
}

impl Newmark {
    /// Builds the stepper: initial acceleration from the equation of motion; for a linear
    /// model, the factorization of `M + γΔtD + βΔt²K`.
    pub fn new(
        model: &dyn DynamicModel,
        initial: &State,
        dt: f64,
        newton: NewtonSettings,
    ) -> Result<Self, SimError> {
        let n = model.n_dofs();
        let cores = CoreLadder::new("newmark", model, dt, COEFFICIENTS, newton)?;
        let a = initial_acceleration(model, initial)?;
        Ok(Self {
            cores,
            a_new: a.clone(),
            a,
            q_hat: vec![0.0; n],
            v_hat: vec![0.0; n],
        })
    }

    /// How many Newton matrices were factored, Newton iterations run and steps halved so far.
    pub fn newton_counts(&self) -> super::NewtonCounts {
        self.cores.counts()
    }
}

/// `(c_q, c_v) = (βh², γh)`.
const COEFFICIENTS: StepCoefficients = StepCoefficients {
    kappa_q: BETA,
    kappa_v: GAMMA,
};

impl HalvableStep for Newmark {
    fn substep(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        level: u32,
    ) -> Result<(), SimError> {
        let (dt, step) = (self.cores.h(level), self.cores.steps);
        for i in 0..state.q.len() {
            self.q_hat[i] = state.q[i] + dt * state.v[i] + (0.5 - BETA) * dt * dt * self.a[i];
            self.v_hat[i] = state.v[i] + (1.0 - GAMMA) * dt * self.a[i];
        }
        self.a_new.copy_from_slice(&self.a);
        let t_new = state.t + dt;
        let core = self.cores.core(model, level)?;
        core.solve(
            model,
            &state.q,
            &self.q_hat,
            &self.v_hat,
            t_new,
            &mut self.a_new,
            step,
        )?;
        for i in 0..state.q.len() {
            state.q[i] = self.q_hat[i] + core.cq * self.a_new[i];
            state.v[i] = self.v_hat[i] + core.cv * self.a_new[i];
        }
        std::mem::swap(&mut self.a, &mut self.a_new);
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
