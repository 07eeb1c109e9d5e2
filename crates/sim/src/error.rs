//! The error type of `nurbspring-sim`.

use nurbspring_linalg::LinalgError;

/// What a failure means for whoever asked for the work. Every error enum of nurbspring answers
/// `kind()`; the command-line tool maps the kinds to its exit codes (2, 1, 130) in one table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// The input (scene, file, option) is not acceptable: fix it and run again.
    Input,
    /// The run failed although the input was accepted (divergence, a failed solve, I/O).
    Run,
    /// The run was interrupted on request (Ctrl-C, a signal, a cancel flag).
    Cancelled,
}

/// Everything that can go wrong while setting up or running a simulation.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The time step is zero, negative or not finite.
    #[error("invalid time step Δt = {dt} (must be positive and finite)")]
    InvalidTimeStep {
        /// The rejected step.
        dt: f64,
    },
    /// [`crate::RunOptions::substeps`] is zero.
    #[error("invalid substep count 0 (at least one step of Δt/substeps per Δt)")]
    InvalidSubsteps,
    /// The end time is not finite or lies before the initial time.
    #[error("invalid end time t_end = {t_end} (must be finite and not before the initial time)")]
    InvalidDuration {
        /// The rejected end time.
        t_end: f64,
    },
    /// The run would take more than [`crate::MAX_STEPS`] steps.
    #[error(
        "t_end / Δt = {t_end:e} / {dt:e} asks for {steps:e} steps; at most {max:e} are allowed"
    )]
    TooManySteps {
        /// The step.
        dt: f64,
        /// The end time.
        t_end: f64,
        /// Steps asked for.
        steps: f64,
        /// The limit.
        max: f64,
    },
    /// An explicit scheme was asked to run above its stability limit `Δt_crit = 2/ω_max`.
    #[error(
        "{integrator} is unstable at Δt = {dt:e}: the explicit stability limit is Δt_crit = 2/ω_max = {dt_critical:e} \
         (reduce Δt, use an implicit integrator, or force the run)"
    )]
    Unstable {
        /// The integrator's name.
        integrator: &'static str,
        /// The requested step.
        dt: f64,
        /// The stability limit.
        dt_critical: f64,
    },
    /// The state became non-finite or ran away.
    #[error("simulation diverged at step {step} (t = {time:e}): {reason}")]
    Diverged {
        /// Step at which divergence was detected (1-based count of steps taken).
        step: usize,
        /// Time reached at that step.
        time: f64,
        /// What was detected.
        reason: String,
    },
    /// Newton's method did not reach its tolerance in an implicit step.
    #[error(
        "Newton iteration failed at step {step} (t = {time:e}) after {iterations} iterations; relative residual {residual:e}{}",
        halving_note(*.halvings)
    )]
    NewtonFailed {
        /// Step being computed (1-based).
        step: usize,
        /// Time at the end of that step.
        time: f64,
        /// Iterations performed (in the whole step, the first attempt).
        iterations: usize,
        /// Final relative residual (of the whole step, the first attempt).
        residual: f64,
        /// How many times the step was halved after that attempt without success (the
        /// smallest step tried is `Δt / 2^halvings`; 0 when it was not retried).
        halvings: u32,
    },
    /// The high-frequency spectral radius of generalized-α lies outside [0, 1].
    #[error(
        "invalid high-frequency spectral radius ρ∞ = {rho_infinity} for generalized-alpha (must lie in [0, 1])"
    )]
    InvalidSpectralRadius {
        /// The rejected ρ∞.
        rho_infinity: f64,
    },
    /// A vector or matrix has the wrong size.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// The offending quantity.
        what: &'static str,
        /// The size it should have.
        expected: usize,
        /// The size it has.
        found: usize,
    },
    /// A linear-algebra failure (factorization, eigenproblem).
    #[error(transparent)]
    Linalg(#[from] LinalgError),
    /// The integrator cannot handle this model.
    #[error("{integrator} does not support this model: {reason}")]
    NotSupported {
        /// The integrator's name.
        integrator: &'static str,
        /// Why not.
        reason: String,
    },
}

impl SimError {
    /// Input problems: the time settings, generalized-α's ρ∞, an integrator that does not apply
    /// to the model, an explicit scheme above its stability limit (the chosen Δt is the
    /// problem). Run failures: divergence, a Newton failure, linear algebra. A size mismatch is
    /// a caller's bug: a run failure.
    pub fn kind(&self) -> ErrorKind {
        match self {
            SimError::InvalidTimeStep { .. }
            | SimError::InvalidDuration { .. }
            | SimError::InvalidSubsteps
            | SimError::InvalidSpectralRadius { .. }
            | SimError::TooManySteps { .. }
            | SimError::Unstable { .. }
            | SimError::NotSupported { .. } => ErrorKind::Input,
            SimError::Diverged { .. }
            | SimError::NewtonFailed { .. }
            | SimError::DimensionMismatch { .. }
            | SimError::Linalg(_) => ErrorKind::Run,
        }
    }
}

/// The end of [`SimError::NewtonFailed`]'s message: the halvings tried after the whole step.
fn halving_note(halvings: u32) -> String {
    match halvings {
        0 => String::new(),
        h => format!(
            "; the step tried again in halves down to Δt/{} did not converge either",
            1u64 << h
        ),
    }
}
