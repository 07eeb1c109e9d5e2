//! The generalized-α method (Chung & Hulbert 1993) with a user-chosen high-frequency
//! spectral radius ρ∞.
//!
//! ODE: `M q̈ + D q̇ + f_int(q) = f_ext(t)` (f_int with the sign of a stiffness, on the
//! left-hand side; `K_T = ∂f_int/∂q`). From ρ∞ ∈ [0, 1] (Chung & Hulbert 1993, §3: second
//! order, and the roots at ωΔt → ∞ all equal to −ρ∞):
//!
//! ```text
//! α_m = (2ρ∞ − 1)/(ρ∞ + 1),   α_f = ρ∞/(ρ∞ + 1),   γ = ½ − α_m + α_f,   β = ¼(1 − α_m + α_f)².
//! ```
//!
//! The scheme carries, besides `q_n` and `v_n`, the algorithmic acceleration `a_n` and the
//! acceleration `q̈_n` of the equation of motion at `t_n`:
//!
//! ```text
//! q_{n+1} = q_n + Δt v_n + Δt² ((½ − β) a_n + β a_{n+1})
//! v_{n+1} = v_n + Δt ((1 − γ) a_n + γ a_{n+1})
//! (1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) q̈_{n+1} + α_f q̈_n
//! M q̈_{n+1} + D v_{n+1} + f_int(q_{n+1}) = f_ext(t_{n+1})            (the residual)
//! ```
//!
//! Multiplied by M, the third line is Chung & Hulbert's balance with the forces interpolated
//! (the generalized trapezoidal form):
//! `(1 − α_m) M a_{n+1} + α_m M a_n + (1 − α_f)(D v_{n+1} + f_int(q_{n+1})) + α_f (D v_n +
//! f_int(q_n)) = (1 − α_f) f_ext(t_{n+1}) + α_f f_ext(t_n)`; for a linear model it is their
//! `K q_{n+1−α_f}` form exactly (with the load interpolated in the same way). Written with
//! `q̈` as the unknown (Arnold & Brüls 2007) the step is the equation of motion at
//! `t_{n+1}`, **residual** `R(q̈) = M q̈ + D v_{n+1}(q̈) + f_int(q_{n+1}(q̈)) − f_ext(t_{n+1})`
//! (zero at the solution; `f_int` enters with a plus sign) with
//!
//! ```text
//! q_{n+1} = q̂ + c_q q̈,  v_{n+1} = v̂ + c_v q̈,   c_q = βΔt²/μ,  c_v = γΔt/μ,  μ = (1 − α_m)/(1 − α_f),
//! q̂ = q_n + Δt v_n + Δt² ((½ − β) a_n + β â),   v̂ = v_n + Δt ((1 − γ) a_n + γ â),
//! â = (α_f q̈_n − α_m a_n)/(1 − α_m),             a_{n+1} = q̈_{n+1}/μ + â,
//! ```
//!
//! which is the step equation of the implicit core ([`super::implicit`]): its consistent
//! Newton matrix is `∂R/∂q̈ = M + c_v D + c_q K_T(q_{n+1})`. Nonlinear models run the core's
//! modified Newton with the energy line search, and a step on which Newton fails is taken in
//! halves; linear models factor `M + c_v D + c_q K` once. The start is `a_0 = q̈_0`, the
//! acceleration of the equation of motion at `t_0`.
//!
//! Properties (linear analysis, Chung & Hulbert §3): second order in q and v for every ρ∞
//! (γ = ½ − α_m + α_f), unconditionally stable, the spectral radius of the step tends to ρ∞
//! as ωΔt → ∞ (the three roots meet at −ρ∞, so it approaches ρ∞ only as `(ωΔt)^{−2/3}`:
//! 0.8077 at ωΔt = 10³ for ρ∞ = 0.8). ρ∞ = 1 is Newmark's average acceleration: α_m = α_f = ½,
//! β = ¼, γ = ½, `a_n = q̈_n` at every step, and the steps are [`super::Newmark`]'s bit for bit
//! (the same predictor, coefficients and Newton guess). Arnold & Brüls prove second-order
//! convergence of this form on nonlinear problems.

use super::NewtonSettings;
use super::implicit::{CoreLadder, HalvableStep, StepCoefficients};
use super::newmark::initial_acceleration;
use crate::{DynamicModel, SimError, State};

/// ρ∞ of [`crate::RunOptions::new`]: damps the highest frequencies by 20 % per step while
/// keeping the lowest ones nearly undamped (Chung & Hulbert's customary choice).
pub const DEFAULT_RHO_INFINITY: f64 = 0.8;

/// The parameters of the generalized-α method derived from the high-frequency spectral radius
/// ρ∞ (Chung & Hulbert 1993, §3); see the module docs.
///
/// ```
/// use nurbspring_sim::integrators::GeneralizedAlphaParameters;
/// // ρ∞ = 1 is Newmark's average acceleration; ρ∞ = 0.5 by hand.
/// let p = GeneralizedAlphaParameters::from_rho_infinity(1.0).unwrap();
/// assert_eq!((p.alpha_m, p.alpha_f, p.beta, p.gamma), (0.5, 0.5, 0.25, 0.5));
/// let p = GeneralizedAlphaParameters::from_rho_infinity(0.5).unwrap();
/// assert!((p.alpha_m - 0.0).abs() < 1e-16 && (p.alpha_f - 1.0 / 3.0).abs() < 1e-16);
/// assert!((p.gamma - 5.0 / 6.0).abs() < 1e-15 && (p.beta - 4.0 / 9.0).abs() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeneralizedAlphaParameters {
    /// The high-frequency spectral radius ρ∞ ∈ [0, 1].
    pub rho_infinity: f64,
    /// `α_m = (2ρ∞ − 1)/(ρ∞ + 1)`.
    pub alpha_m: f64,
    /// `α_f = ρ∞/(ρ∞ + 1)`.
    pub alpha_f: f64,
    /// `β = ¼(1 − α_m + α_f)²`.
    pub beta: f64,
    /// `γ = ½ − α_m + α_f`.
    pub gamma: f64,
}

impl GeneralizedAlphaParameters {
    /// The parameters for ρ∞; [`SimError::InvalidSpectralRadius`] unless `0 ≤ ρ∞ ≤ 1`.
    pub fn from_rho_infinity(rho_infinity: f64) -> Result<Self, SimError> {
        if !(0.0..=1.0).contains(&rho_infinity) {
            return Err(SimError::InvalidSpectralRadius { rho_infinity });
        }
        let alpha_m = (2.0 * rho_infinity - 1.0) / (rho_infinity + 1.0);
        let alpha_f = rho_infinity / (rho_infinity + 1.0);
        let gamma = 0.5 - alpha_m + alpha_f;
        let beta = 0.25 * (1.0 - alpha_m + alpha_f).powi(2);
        Ok(Self {
            rho_infinity,
            alpha_m,
            alpha_f,
            beta,
            gamma,
        })
    }

    /// `(κ_q, κ_v) = (β, γ)/μ`, `μ = (1 − α_m)/(1 − α_f)`: the step's `c_q = κ_q Δt²`,
    /// `c_v = κ_v Δt`.
    fn coefficients(&self) -> StepCoefficients {
        let ratio = (1.0 - self.alpha_f) / (1.0 - self.alpha_m);
        StepCoefficients {
            kappa_q: self.beta * ratio,
            kappa_v: self.gamma * ratio,
        }
    }
}

/// Generalized-α stepper (see the module docs).
pub struct GeneralizedAlpha {
    parameters: GeneralizedAlphaParameters,
    cores: CoreLadder,
    /// `[a_n, q̈_n]`: the algorithmic acceleration and the acceleration of the equation of
    /// motion at the current time.
    carried: [Vec<f64>; 2],
    /// `q̈_{n+1}` being solved for (the Newton guess on entry: `q̈_n`).
    qdd_new: Vec<f64>,
    /// `â = (α_f q̈_n − α_m a_n)/(1 − α_m)`.
    a_known: Vec<f64>,
    q_hat: Vec<f64>,
    v_hat: Vec<f64>,
}

impl GeneralizedAlpha {
    /// Builds the stepper for ρ∞ = `rho_infinity`: `a_0 = q̈_0` from the equation of motion
    /// at `initial`; for a linear model, the factorization of `M + c_v D + c_q K`.
    /// [`SimError::InvalidSpectralRadius`] unless `0 ≤ ρ∞ ≤ 1`.
    pub fn new(
        model: &dyn DynamicModel,
        initial: &State,
        dt: f64,
        rho_infinity: f64,
        newton: NewtonSettings,
    ) -> Result<Self, SimError> {
        let parameters = GeneralizedAlphaParameters::from_rho_infinity(rho_infinity)?;
        let n = model.n_dofs();
        let cores = CoreLadder::new(
            "generalized-alpha",
            model,
            dt,
            parameters.coefficients(),
            newton,
        )?;
        let qdd = initial_acceleration(model, initial)?;
        Ok(Self {
            parameters,
            cores,
            qdd_new: qdd.clone(),
            carried: [qdd.clone(), qdd],
            a_known: vec![0.0; n],
            q_hat: vec![0.0; n],
            v_hat: vec![0.0; n],
        })
    }

    /// α_m, α_f, β, γ of this stepper.
    pub fn parameters(&self) -> GeneralizedAlphaParameters {
        self.parameters
    }

    /// The algorithmic acceleration `a_n` at the current time (it differs from the equation
    /// of motion's `q̈_n` unless ρ∞ = 1).
    pub fn algorithmic_acceleration(&self) -> &[f64] {
        &self.carried[0]
    }

    /// The acceleration of the equation of motion `q̈_n` at the current time.
    pub fn acceleration(&self) -> &[f64] {
        &self.carried[1]
    }

    /// How many Newton matrices were factored, Newton iterations run and steps halved so far.
    pub fn newton_counts(&self) -> super::NewtonCounts {
        self.cores.counts()
    }
}

impl HalvableStep for GeneralizedAlpha {
    fn substep(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        level: u32,
    ) -> Result<(), SimError> {
        let (dt, step) = (self.cores.h(level), self.cores.steps);
        let GeneralizedAlphaParameters {
            alpha_m,
            alpha_f,
            beta,
            gamma,
            ..
        } = self.parameters;
        let [a, qdd] = &self.carried;
        for i in 0..state.q.len() {
            self.a_known[i] = (alpha_f * qdd[i] - alpha_m * a[i]) / (1.0 - alpha_m);
            // Newmark's predictor, then the known part of β a_{n+1} (zero when ρ∞ = 1).
            self.q_hat[i] = state.q[i] + dt * state.v[i] + (0.5 - beta) * dt * dt * a[i];
            self.q_hat[i] += beta * dt * dt * self.a_known[i];
            self.v_hat[i] = state.v[i] + (1.0 - gamma) * dt * a[i];
            self.v_hat[i] += gamma * dt * self.a_known[i];
        }
        self.qdd_new.copy_from_slice(qdd);
        let t_new = state.t + dt;
        let core = self.cores.core(model, level)?;
        core.solve(
            model,
            &state.q,
            &self.q_hat,
            &self.v_hat,
            t_new,
            &mut self.qdd_new,
            step,
        )?;
        let inverse_mu = (1.0 - alpha_f) / (1.0 - alpha_m);
        let [a, qdd] = &mut self.carried;
        for i in 0..state.q.len() {
            state.q[i] = self.q_hat[i] + core.cq * self.qdd_new[i];
            state.v[i] = self.v_hat[i] + core.cv * self.qdd_new[i];
            a[i] = inverse_mu * self.qdd_new[i] + self.a_known[i];
        }
        std::mem::swap(qdd, &mut self.qdd_new);
        state.t = t_new;
        Ok(())
    }

    fn carried(&mut self) -> &mut [Vec<f64>] {
        &mut self.carried
    }

    fn ladder(&self) -> &CoreLadder {
        &self.cores
    }

    fn ladder_mut(&mut self) -> &mut CoreLadder {
        &mut self.cores
    }
}
