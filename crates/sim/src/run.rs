//! Running a model: options, observers, the explicit stability limit and divergence detection.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_linalg::largest_generalized_eigenvalue;

use crate::integrators::make_stepper_with_options;
use crate::{DynamicModel, SimError};

/// Largest number of steps one run may take (10⁸): larger requests are refused up front.
pub const MAX_STEPS: f64 = 1e8;

/// Largest magnitude of any input number (10³⁰): matrices, energies and stability limits are
/// products of a few inputs, so larger values could overflow to infinity; no physical scene in
/// any unit system needs more.
pub const MAX_MAGNITUDE: f64 = 1e30;

/// Whether `x` is an acceptable input number: finite and at most [`MAX_MAGNITUDE`] in magnitude.
pub fn representable(x: f64) -> bool {
    x.is_finite() && x.abs() <= MAX_MAGNITUDE
}

/// The time integrators, each written once against [`DynamicModel`]. In files and on the
/// command line they go by [`IntegratorKind::name`] (serde uses the same names).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum IntegratorKind {
    /// Terzopoulos–Qin backward differences (docs/math.md §3); linear models; unconditionally stable.
    TerzopoulosQin,
    /// Newmark average acceleration (β = 1/4, γ = 1/2); energy conserving without damping.
    Newmark,
    /// Exact modal solution of the undamped linear system (small models).
    Modal,
    /// Symplectic (semi-implicit) Euler; explicit.
    SymplecticEuler,
    /// Velocity Verlet (= central difference); explicit.
    #[serde(rename = "verlet", alias = "velocity-verlet")]
    VelocityVerlet,
    /// Classical fourth-order Runge–Kutta; explicit.
    Rk4,
    /// Backward Euler with Newton iterations.
    BackwardEuler,
}

impl IntegratorKind {
    /// Every integrator.
    pub const ALL: [IntegratorKind; 7] = [
        IntegratorKind::TerzopoulosQin,
        IntegratorKind::Newmark,
        IntegratorKind::Modal,
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
        IntegratorKind::BackwardEuler,
    ];

    /// The name used in scenes and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::TerzopoulosQin => "terzopoulos-qin",
            IntegratorKind::Newmark => "newmark",
            IntegratorKind::Modal => "modal",
            IntegratorKind::SymplecticEuler => "symplectic-euler",
            IntegratorKind::VelocityVerlet => "verlet",
            IntegratorKind::Rk4 => "rk4",
            IntegratorKind::BackwardEuler => "backward-euler",
        }
    }

    /// Parses a [`Self::name`] (also `velocity-verlet`; case and `_`/`-` insensitive).
    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim().to_ascii_lowercase().replace('_', "-");
        if s == "velocity-verlet" {
            return Some(IntegratorKind::VelocityVerlet);
        }
        Self::ALL.into_iter().find(|k| k.name() == s)
    }

    /// True for the explicit schemes (symplectic Euler, Verlet, RK4), which are stable only
    /// below `Δt_crit = 2/ω_max` and need a diagonal mass matrix.
    pub fn is_explicit(self) -> bool {
        matches!(
            self,
            IntegratorKind::SymplecticEuler | IntegratorKind::VelocityVerlet | IntegratorKind::Rk4
        )
    }
}

impl std::fmt::Display for IntegratorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Time `t`, positions `q` and velocities `v` on the free dofs.
#[derive(Clone, Debug)]
pub struct State {
    /// Time.
    pub t: f64,
    /// Generalized coordinates.
    pub q: Vec<f64>,
    /// Generalized velocities.
    pub v: Vec<f64>,
}

impl State {
    /// State at time 0.
    pub fn new(q: Vec<f64>, v: Vec<f64>) -> Self {
        Self { t: 0.0, q, v }
    }
}

/// Options of [`simulate`].
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Time step Δt.
    pub dt: f64,
    /// End time; the run takes `⌈(t_end − t₀)/Δt⌉` steps of exactly Δt.
    pub t_end: f64,
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Run an explicit scheme above its stability limit anyway.
    pub force_unstable: bool,
    /// Newton tolerance on the relative residual (default 1e-10).
    pub newton_tolerance: f64,
    /// Newton iteration limit (default 30).
    pub max_newton_iterations: usize,
    /// Runaway when `‖q − q₀‖∞ > factor · max(1, ‖q₀‖∞)` (default 1e6).
    pub divergence_factor: f64,
    /// When set (e.g. by Ctrl-C), the run stops after the current step.
    pub cancel: Option<Arc<AtomicBool>>,
}

impl RunOptions {
    /// Checks the time settings from `t0`: Δt positive and finite, t_end finite and not before
    /// `t0`, at most [`MAX_STEPS`] steps. The one place these rules live.
    pub fn validate(&self, t0: f64) -> Result<(), SimError> {
        check_time(self.dt, self.t_end, t0)
    }

    /// Defaults for everything but Δt, t_end and the integrator.
    pub fn new(dt: f64, t_end: f64, integrator: IntegratorKind) -> Self {
        Self {
            dt,
            t_end,
            integrator,
            force_unstable: false,
            newton_tolerance: 1e-10,
            max_newton_iterations: 30,
            divergence_factor: 1e6,
            cancel: None,
        }
    }
}

/// What an [`Observer`] sees at t = 0 (step 0) and after every step.
#[derive(Clone, Copy, Debug)]
pub struct Sample<'a> {
    /// Steps taken so far.
    pub step: usize,
    /// Time.
    pub t: f64,
    /// Positions.
    pub q: &'a [f64],
    /// Velocities.
    pub v: &'a [f64],
    /// Kinetic energy `½ vᵀ M v`.
    pub kinetic: f64,
    /// Potential energy: `elastic + external`, so `kinetic + potential` is the total energy.
    pub potential: f64,
    /// The model's elastic energy ([`DynamicModel::potential_energy`]).
    pub elastic: f64,
    /// The potential of the load ([`DynamicModel::external_potential`]).
    pub external: f64,
}

/// Receives samples during [`simulate`].
pub trait Observer {
    /// Called at t = 0 and after every step.
    fn observe(&mut self, s: &Sample<'_>);
}

impl<F: FnMut(&Sample<'_>)> Observer for F {
    fn observe(&mut self, s: &Sample<'_>) {
        self(s)
    }
}

/// An observer that ignores everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct NullObserver;

impl Observer for NullObserver {
    fn observe(&mut self, _s: &Sample<'_>) {}
}

/// Outcome of [`simulate`].
#[derive(Clone, Debug, PartialEq)]
pub struct RunSummary {
    /// Steps taken.
    pub steps: usize,
    /// Time reached.
    pub t_final: f64,
    /// True when the cancel flag stopped the run.
    pub cancelled: bool,
    /// ω_max of the linearized model at the initial state (explicit schemes only).
    pub omega_max: Option<f64>,
    /// `2/ω_max` (explicit schemes only).
    pub dt_critical: Option<f64>,
}

/// The largest angular frequency of the model linearized at a state and the explicit stability
/// limit it implies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StabilityLimit {
    /// `ω_max = √λ_max(K_T φ = λ M φ)`.
    pub omega_max: f64,
    /// `Δt_crit = 2/ω_max` (infinite when ω_max = 0).
    pub dt_critical: f64,
}

/// `ω_max` of the model linearized at `q` — the square root of the largest eigenvalue of
/// `K_T(q) φ = λ M φ`, by Lanczos ([`largest_generalized_eigenvalue`], relative tolerance 1e-8) —
/// and `Δt_crit = 2/ω_max`, the stability limit of the central-difference family (symplectic
/// Euler and Verlet: exactly; RK4, whose limit is `2√2/ω_max`: conservatively). Damping is
/// ignored (it only lowers the limit of symplectic Euler slightly).
pub fn stability_limit(model: &dyn DynamicModel, q: &[f64]) -> Result<StabilityLimit, SimError> {
    let n = model.n_dofs();
    if q.len() != n {
        return Err(SimError::DimensionMismatch {
            what: "q given to stability_limit",
            expected: n,
            found: q.len(),
        });
    }
    let k = model.tangent_stiffness(q);
    let m = model.mass().to_sparse();
    let lambda = largest_generalized_eigenvalue(&k, &m, 1e-8)?.max(0.0);
    let omega_max = lambda.sqrt();
    let dt_critical = if omega_max > 0.0 {
        2.0 / omega_max
    } else {
        f64::INFINITY
    };
    Ok(StabilityLimit {
        omega_max,
        dt_critical,
    })
}

/// The time rules of [`RunOptions::validate`] on plain values.
pub fn check_time(dt: f64, t_end: f64, t0: f64) -> Result<(), SimError> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(SimError::InvalidTimeStep { dt });
    }
    if !t_end.is_finite() || t_end < t0 {
        return Err(SimError::InvalidDuration { t_end });
    }
    let steps = ((t_end - t0) / dt).ceil();
    if steps > MAX_STEPS {
        return Err(SimError::TooManySteps {
            dt,
            t_end,
            steps,
            max: MAX_STEPS,
        });
    }
    Ok(())
}

/// Number of steps of size `dt` to reach `t_end` from `t0`: `⌈(t_end − t0)/dt⌉`, with a ratio
/// within 1e-9 (relative) of an integer rounded to it.
pub fn step_count(t0: f64, t_end: f64, dt: f64) -> usize {
    let r = (t_end - t0) / dt;
    if r <= 0.0 {
        return 0;
    }
    let nearest = r.round();
    if (r - nearest).abs() <= 1e-9 * nearest.max(1.0) {
        nearest as usize
    } else {
        r.ceil() as usize
    }
}

/// `(kinetic, elastic, external)` energies of a state.
fn sample_energy(model: &dyn DynamicModel, t: f64, q: &[f64], v: &[f64]) -> (f64, f64, f64) {
    let kinetic = 0.5 * model.mass().quadratic_form(v);
    (
        kinetic,
        model.potential_energy(q),
        model.external_potential(t, q),
    )
}

fn check_state(q: &[f64], v: &[f64], q0: &[f64], limit: f64) -> Option<String> {
    if let Some(i) = q.iter().position(|x| !x.is_finite()) {
        return Some(format!("non-finite position q[{i}] = {}", q[i]));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Some(format!("non-finite velocity v[{i}] = {}", v[i]));
    }
    let (mut worst, mut at) = (0.0_f64, 0);
    for (i, (a, b)) in q.iter().zip(q0).enumerate() {
        let d = (a - b).abs();
        if d > worst {
            worst = d;
            at = i;
        }
    }
    (worst > limit)
        .then(|| format!("runaway displacement |q[{at}] − q₀[{at}]| = {worst:e} exceeds {limit:e}"))
}

/// Runs `model` from `initial` to `opts.t_end` with `opts.integrator`.
///
/// Explicit schemes first check `Δt < 2/ω_max` ([`stability_limit`] at the initial state) and
/// return [`SimError::Unstable`] unless `force_unstable`. After every step the state is checked:
/// NaN/infinity or a runaway (`‖q − q₀‖∞ > divergence_factor · max(1, ‖q₀‖∞)`) returns
/// [`SimError::Diverged`] naming the step and time. The observer is called at t = 0 and after
/// every step; when the cancel flag is set the run stops after the current step with
/// `cancelled = true`. Step `k` ends at `t₀ + kΔt` exactly (no accumulated round-off).
pub fn simulate(
    model: &dyn DynamicModel,
    initial: State,
    opts: &RunOptions,
    observer: &mut dyn Observer,
) -> Result<RunSummary, SimError> {
    let dt = opts.dt;
    opts.validate(initial.t)?;
    let n = model.n_dofs();
    crate::integrators::check_state_dims(model, &initial)?;
    let (mut omega_max, mut dt_critical) = (None, None);
    if opts.integrator.is_explicit() {
        let limit = stability_limit(model, &initial.q)?;
        omega_max = Some(limit.omega_max);
        dt_critical = Some(limit.dt_critical);
        if dt >= limit.dt_critical && !opts.force_unstable {
            return Err(SimError::Unstable {
                integrator: opts.integrator.name(),
                dt,
                dt_critical: limit.dt_critical,
            });
        }
    }
    let mut stepper = make_stepper_with_options(opts.integrator, model, &initial, opts)?;
    let t0 = initial.t;
    let n_steps = step_count(t0, opts.t_end, dt);
    let q0 = initial.q.clone();
    let scale = q0.iter().fold(0.0_f64, |m, x| m.max(x.abs())).max(1.0);
    let runaway = opts.divergence_factor * scale;
    let mut state = initial;
    debug_assert_eq!(state.q.len(), n);

    let (kinetic, elastic, external) = sample_energy(model, state.t, &state.q, &state.v);
    observer.observe(&Sample {
        step: 0,
        t: state.t,
        q: &state.q,
        v: &state.v,
        kinetic,
        potential: elastic + external,
        elastic,
        external,
    });
    let mut summary = RunSummary {
        steps: 0,
        t_final: t0,
        cancelled: false,
        omega_max,
        dt_critical,
    };
    for k in 1..=n_steps {
        if opts
            .cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
        {
            summary.cancelled = true;
            break;
        }
        stepper.step(model, &mut state, dt)?;
        state.t = t0 + k as f64 * dt;
        if let Some(reason) = check_state(&state.q, &state.v, &q0, runaway) {
            return Err(SimError::Diverged {
                step: k,
                time: state.t,
                reason,
            });
        }
        let (kinetic, elastic, external) = sample_energy(model, state.t, &state.q, &state.v);
        observer.observe(&Sample {
            step: k,
            t: state.t,
            q: &state.q,
            v: &state.v,
            kinetic,
            potential: elastic + external,
            elastic,
            external,
        });
        summary.steps = k;
        summary.t_final = state.t;
    }
    Ok(summary)
}
