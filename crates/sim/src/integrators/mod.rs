//! Time integrators for `M q̈ + D q̇ + f_int(q) = f_ext(t)`, each written once against
//! [`DynamicModel`].
//!
//! Sign convention (as in [`crate::model`]): `f_int` sits on the left-hand side with the sign of
//! a stiffness (`f_int = K (q − q_rest)` for a linear model) and `K_T = ∂f_int/∂q`, so the
//! acceleration is `q̈ = M⁻¹ (f_ext(t) − f_int(q) − D q̇)`.
//!
//! | scheme | kind | order | stability |
//! |---|---|---|---|
//! | [`TerzopoulosQin`] | implicit, linear models | 1 | unconditional, dissipative: `(1 + ω²Δt²)^{-1/2}` per step |
//! | [`Newmark`] (β = ¼, γ = ½) | implicit, Newton | 2 | unconditional, energy conserving for D = 0 (linear; bounded O(Δt²) error when nonlinear) |
//! | [`GeneralizedAlpha`] (ρ∞ ∈ [0, 1]) | implicit, Newton | 2 | unconditional; spectral radius → ρ∞ as ωΔt → ∞ (as `(ωΔt)^{-2/3}`); ρ∞ = 1 is Newmark |
//! | [`Modal`] | exact (undamped linear) | exact | — |
//! | [`SymplecticEuler`] | explicit | 1 | `Δt < 2/ω_max` |
//! | [`VelocityVerlet`] (= central difference) | explicit | 2 | `Δt < 2/ω_max` |
//! | [`Rk4`] | explicit | 4 | `Δt < 2√2/ω_max` (checked against `2/ω_max`) |
//! | [`BackwardEuler`] | implicit, Newton | 1 | unconditional, dissipative |
//!
//! `ω_max² = λ_max(K_T φ = λ M φ)` with the model's mass as it is. The implicit Newton schemes
//! share one core (`implicit.rs`: modified Newton on `M + c_v D + c_q K_T`, energy line search,
//! step halving; linear models factor once). The explicit schemes apply `M⁻¹` by a
//! [`MassInverse`]: entrywise for a diagonal (lumped) mass, by a sparse Cholesky factor made
//! once for a consistent one; all buffers live in the stepper, and a step with a diagonal mass
//! allocates nothing.

mod backward_euler;
mod explicit;
mod generalized_alpha;
mod implicit;
mod modal;
mod newmark;
mod terzopoulos_qin;

pub use backward_euler::BackwardEuler;
pub use explicit::{MassInverse, Rk4, SymplecticEuler, VelocityVerlet};
pub use generalized_alpha::{DEFAULT_RHO_INFINITY, GeneralizedAlpha, GeneralizedAlphaParameters};
pub use implicit::NewtonCounts;
pub use modal::Modal;
pub use newmark::Newmark;
pub use terzopoulos_qin::TerzopoulosQin;

use crate::{DynamicModel, IntegratorKind, RunOptions, SimError, State};

/// One integrator advancing a [`State`] by Δt. A stepper is built for one model, one Δt and one
/// initial state by [`make_stepper`]; it may keep history (previous positions, accelerations,
/// factorizations) between calls. Each call advances `state.t` by `dt`; `dt` must be the step
/// the stepper was built with when it factors matrices (Terzopoulos–Qin, Newmark, backward
/// Euler on linear models, modal use the Δt given at construction and reject another).
pub trait Stepper {
    /// Advances `state` by one step of `dt`.
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError>;

    /// Steps so far that were taken in halves after Newton failed on them (the implicit
    /// schemes' step halving; 0 for the others).
    fn halved_steps(&self) -> usize {
        0
    }
}

/// Builds the stepper of `kind` for `model`, starting from `initial`, with step `dt` and the
/// default Newton settings (tolerance 1e-10, 30 iterations).
pub fn make_stepper(
    kind: IntegratorKind,
    model: &dyn DynamicModel,
    initial: &State,
    dt: f64,
) -> Result<Box<dyn Stepper>, SimError> {
    let opts = RunOptions::new(dt, initial.t, kind);
    make_stepper_with_options(kind, model, initial, &opts)
}

/// [`make_stepper`] with Δt (`opts.dt`), the Newton settings and generalized-α's ρ∞ taken from
/// `opts`.
pub fn make_stepper_with_options(
    kind: IntegratorKind,
    model: &dyn DynamicModel,
    initial: &State,
    opts: &RunOptions,
) -> Result<Box<dyn Stepper>, SimError> {
    let dt = opts.dt;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(SimError::InvalidTimeStep { dt });
    }
    check_state_dims(model, initial)?;
    let newton = NewtonSettings {
        tolerance: opts.newton_tolerance,
        max_iterations: opts.max_newton_iterations,
    };
    Ok(match kind {
        IntegratorKind::TerzopoulosQin => Box::new(TerzopoulosQin::new(model, initial, dt)?),
        IntegratorKind::Newmark => Box::new(Newmark::new(model, initial, dt, newton)?),
        IntegratorKind::GeneralizedAlpha => Box::new(GeneralizedAlpha::new(
            model,
            initial,
            dt,
            opts.rho_infinity,
            newton,
        )?),
        IntegratorKind::Modal => Box::new(Modal::new(model, dt)?),
        IntegratorKind::SymplecticEuler => Box::new(SymplecticEuler::new(model)?),
        IntegratorKind::VelocityVerlet => Box::new(VelocityVerlet::new(model, initial)?),
        IntegratorKind::Rk4 => Box::new(Rk4::new(model)?),
        IntegratorKind::BackwardEuler => Box::new(BackwardEuler::new(model, dt, newton)?),
    })
}

/// Newton settings of the implicit schemes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonSettings {
    /// Relative residual tolerance.
    pub tolerance: f64,
    /// Iteration limit.
    pub max_iterations: usize,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 30,
        }
    }
}

/// Checks that the model's matrices and the state have `n_dofs` entries.
pub(crate) fn check_state_dims(model: &dyn DynamicModel, s: &State) -> Result<(), SimError> {
    let n = model.n_dofs();
    let check = |what: &'static str, found: usize| {
        if found == n {
            Ok(())
        } else {
            Err(SimError::DimensionMismatch {
                what,
                expected: n,
                found,
            })
        }
    };
    check("positions q", s.q.len())?;
    check("velocities v", s.v.len())?;
    check("mass matrix", model.mass().dim())?;
    if let Some(d) = model.damping() {
        check("damping matrix", d.dim())?;
    }
    Ok(())
}

/// Checks that a stepper built for `built` is called with the same step.
pub(crate) fn check_fixed_dt(name: &'static str, built: f64, dt: f64) -> Result<(), SimError> {
    if (dt - built).abs() > 1e-12 * built {
        return Err(SimError::NotSupported {
            integrator: name,
            reason: format!("built for Δt = {built:e}, called with Δt = {dt:e}"),
        });
    }
    Ok(())
}

pub(crate) fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}
