//! Running a model: options, observers, the explicit stability limit and divergence detection.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_linalg::largest_generalized_eigenvalue;

use crate::integrators::make_stepper_with_options;
use crate::{DynamicModel, PointDofs, SimError};

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
    /// Generalized-α (Chung & Hulbert 1993) with the high-frequency spectral radius
    /// [`RunOptions::rho_infinity`]; second order, unconditionally stable, damps the highest
    /// frequencies by ρ∞ per step (ρ∞ = 1: Newmark's average acceleration).
    GeneralizedAlpha,
    /// Exact modal solution of the undamped linear system (small models).
    Modal,
    /// Symplectic (semi-implicit) Euler; explicit.
    SymplecticEuler,
    /// Velocity Verlet (= central difference); explicit. Also accepted as `velocity-verlet`
    /// and `central-difference`.
    #[serde(
        rename = "verlet",
        alias = "velocity-verlet",
        alias = "central-difference"
    )]
    VelocityVerlet,
    /// Classical fourth-order Runge–Kutta; explicit.
    Rk4,
    /// Backward Euler with Newton iterations.
    BackwardEuler,
}

impl IntegratorKind {
    /// Every integrator.
    pub const ALL: [IntegratorKind; 8] = [
        IntegratorKind::TerzopoulosQin,
        IntegratorKind::Newmark,
        IntegratorKind::GeneralizedAlpha,
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
            IntegratorKind::GeneralizedAlpha => "generalized-alpha",
            IntegratorKind::Modal => "modal",
            IntegratorKind::SymplecticEuler => "symplectic-euler",
            IntegratorKind::VelocityVerlet => "verlet",
            IntegratorKind::Rk4 => "rk4",
            IntegratorKind::BackwardEuler => "backward-euler",
        }
    }

    /// Parses a [`Self::name`] (also `velocity-verlet` and `central-difference` for `verlet`;
    /// case and `_`/`-` insensitive).
    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim().to_ascii_lowercase().replace('_', "-");
        if s == "velocity-verlet" || s == "central-difference" {
            return Some(IntegratorKind::VelocityVerlet);
        }
        Self::ALL.into_iter().find(|k| k.name() == s)
    }

    /// True for the explicit schemes (symplectic Euler, Verlet, RK4), which are stable only
    /// below `Δt_crit = 2/ω_max`, `ω_max² = λ_max(K_T φ = λ M φ)`. They apply `M⁻¹` entrywise
    /// to a diagonal (lumped) mass and by a sparse Cholesky factor, made once, to any other
    /// (consistent) mass.
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
    /// Steps of `Δt / substeps` taken for each step of Δt (default 1); the observer still sees
    /// the state once per Δt. An explicit scheme whose limit is below Δt runs stably this way
    /// ([`explicit_substeps`]).
    pub substeps: usize,
    /// An explicit scheme's stability limit when the caller already has one that holds for
    /// this run (from [`Schedule::stable`], [`uniform_stability_limit`] or
    /// [`stability_limit`] at the initial state): [`simulate`] then checks against it instead
    /// of running Lanczos again.
    pub stability: Option<StabilityLimit>,
    /// Newton tolerance on the relative residual (default 1e-10).
    pub newton_tolerance: f64,
    /// Newton iteration limit (default 30).
    pub max_newton_iterations: usize,
    /// The high-frequency spectral radius ρ∞ ∈ [0, 1] of [`IntegratorKind::GeneralizedAlpha`]
    /// (default [`crate::integrators::DEFAULT_RHO_INFINITY`] = 0.8; 1 is Newmark's average
    /// acceleration, 0 annihilates the highest frequencies in one step). The other schemes
    /// ignore it.
    pub rho_infinity: f64,
    /// Runaway when `‖q − q₀‖∞ > factor · max(1, ‖q₀‖∞)` (default 1e6).
    pub divergence_factor: f64,
    /// When set (e.g. by Ctrl-C), the run stops after the current step.
    pub cancel: Option<Arc<AtomicBool>>,
}

impl RunOptions {
    /// Checks the time settings from `t0`: Δt positive and finite, t_end finite and not before
    /// `t0`, at least one substep, at most [`MAX_STEPS`] steps (substeps counted); and, for
    /// generalized-α, `0 ≤ ρ∞ ≤ 1`. The one place these rules live.
    pub fn validate(&self, t0: f64) -> Result<(), SimError> {
        if self.substeps == 0 {
            return Err(SimError::InvalidSubsteps);
        }
        if self.integrator == IntegratorKind::GeneralizedAlpha {
            crate::integrators::GeneralizedAlphaParameters::from_rho_infinity(self.rho_infinity)?;
        }
        check_time(self.dt, self.t_end, t0)?;
        check_time(self.substep(), self.t_end, t0)
    }

    /// The step actually taken, `Δt / substeps`.
    pub fn substep(&self) -> f64 {
        self.dt / self.substeps.max(1) as f64
    }

    /// [`RunOptions::new`] with a [`Schedule`]'s integrator and substeps and the stability
    /// limit that came with it.
    pub fn scheduled(
        dt: f64,
        t_end: f64,
        schedule: Schedule,
        stability: Option<StabilityLimit>,
    ) -> Self {
        Self {
            substeps: schedule.substeps,
            stability,
            ..Self::new(dt, t_end, schedule.integrator)
        }
    }

    /// Defaults for everything but Δt, t_end and the integrator.
    pub fn new(dt: f64, t_end: f64, integrator: IntegratorKind) -> Self {
        Self {
            dt,
            t_end,
            integrator,
            force_unstable: false,
            substeps: 1,
            stability: None,
            newton_tolerance: 1e-10,
            max_newton_iterations: 30,
            rho_infinity: crate::integrators::DEFAULT_RHO_INFINITY,
            divergence_factor: 1e6,
            cancel: None,
        }
    }
}

/// The largest [`EnergyWatch::gain`] of a run that can be trusted: its loads are dead and its
/// damping only removes energy, so a lasting rise of its total energy is its integrator's. An
/// implicit scheme's energy is not monotone from step to step (generalized-α on an undamped
/// plate under a step load rises by 1.2 % of its largest kinetic energy); an unstable run is far
/// beyond (a thin cloth's shell at ρ∞ = 0.8 gains about a hundred times its kinetic energy
/// within 1.5 s; docs/math.md §11.2).
pub const ENERGY_GAIN_LIMIT: f64 = 0.1;

/// Follows a run's total energy (kinetic + potential, [`Sample`]) for a rise the dynamics
/// cannot make.
///
/// ```
/// use nurbspring_sim::EnergyWatch;
/// let mut w = EnergyWatch::default();
/// w.observe(0.0, 1.0);
/// w.observe(2.0, -1.0); // energy exchanged, the total kept
/// w.observe(1.0, 0.5); // the total rises by 0.5: a quarter of the largest kinetic energy
/// assert!((w.gain() - 0.25).abs() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct EnergyWatch {
    start: Option<f64>,
    top: f64,
    kinetic: f64,
}

impl EnergyWatch {
    /// One sample's kinetic and potential energy.
    pub fn observe(&mut self, kinetic: f64, potential: f64) {
        let total = kinetic + potential;
        if self.start.is_none() {
            self.start = Some(total);
            self.top = total;
        }
        self.top = self.top.max(total);
        self.kinetic = self.kinetic.max(kinetic);
    }

    /// The largest rise of the total energy over its start, over the largest kinetic energy
    /// (0 for a run that never moved or never rose).
    pub fn gain(&self) -> f64 {
        match self.start {
            Some(e0) if self.kinetic > 0.0 => ((self.top - e0) / self.kinetic).max(0.0),
            _ => 0.0,
        }
    }

    /// True when the run gained more than [`ENERGY_GAIN_LIMIT`].
    pub fn unstable(&self) -> bool {
        self.gain() > ENERGY_GAIN_LIMIT
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
    /// The ω_max the run was checked against (explicit schemes only): the linearized
    /// model's at the initial state, or the one given in [`RunOptions::stability`].
    pub omega_max: Option<f64>,
    /// `2/ω_max` (explicit schemes only).
    pub dt_critical: Option<f64>,
    /// Steps taken in halves after Newton failed on them (implicit schemes only; see
    /// [`crate::integrators::Stepper::halved_steps`]).
    pub halved_steps: usize,
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

impl StabilityLimit {
    /// The limit of a highest angular frequency `ω_max`: `Δt_crit = 2/ω_max`, infinite when
    /// `ω_max` is not positive (nothing oscillates).
    pub fn from_omega_max(omega_max: f64) -> Self {
        Self {
            omega_max,
            dt_critical: if omega_max > 0.0 {
                2.0 / omega_max
            } else {
                f64::INFINITY
            },
        }
    }
}

/// `ω_max` of the model linearized at `q` — the square root of the largest eigenvalue of
/// `K_T(q) φ = λ M φ`, by Lanczos ([`largest_generalized_eigenvalue`], relative tolerance 1e-8) —
/// and `Δt_crit = 2/ω_max`, the stability limit of the central-difference family (symplectic
/// Euler and Verlet: exactly; RK4, whose limit is `2√2/ω_max`: conservatively). Damping is
/// ignored (it only lowers the limit of symplectic Euler slightly). M is the model's mass as it
/// is: a diagonal one enters the Lanczos operator `M⁻¹K_T` entrywise, any other (a consistent
/// mass) through its sparse Cholesky factor, so the limit is that of the mass the explicit
/// schemes step with.
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
    Ok(StabilityLimit::from_omega_max(lambda.sqrt()))
}

/// The stability limit that holds along any trajectory: `ω̄ = √λ_max(K̄ φ = λ M φ)` for the
/// model's stiffness bound `K̄ ⪰ K_T(q)` ([`DynamicModel::stiffness_bound`]) and `2/ω̄`;
/// `None` when the model has no bound. Since `K_T(q) ⪯ K̄` at every `q`, the linearization's
/// largest frequency never exceeds `ω̄` ([`stability_limit`] gives it at one state only).
/// The mass enters as in [`stability_limit`] (diagonal or consistent); when both `K̄` and M
/// are of the form `S ⊗ I₃` the pencil of their factors is solved, which has the same
/// eigenvalues.
pub fn uniform_stability_limit(
    model: &dyn DynamicModel,
) -> Result<Option<StabilityLimit>, SimError> {
    let Some(k) = model.stiffness_bound() else {
        return Ok(None);
    };
    let m = model.mass().to_sparse();
    // A bound and a mass of the form S ⊗ I₃ (a lattice's per-node masses and isotropic
    // blocks) have the eigenvalues of their factors: the pencil of the factors is a third the
    // size.
    let xyz = PointDofs::XYZ;
    let lambda = match (xyz.scalar_factor(&k), xyz.scalar_factor(&m)) {
        (Some(k3), Some(m3)) => largest_generalized_eigenvalue(&k3, &m3, 1e-8)?,
        _ => largest_generalized_eigenvalue(&k, &m, 1e-8)?,
    }
    .max(0.0);
    Ok(Some(StabilityLimit::from_omega_max(lambda.sqrt())))
}

/// Fraction of the uniform stability limit a substep may reach: the margin covers damping
/// (which lowers symplectic Euler's limit slightly below `2/ω`) and Lanczos' tolerance.
pub const SUBSTEP_MARGIN: f64 = 0.9;

/// Most substeps per step of Δt that [`explicit_substeps`] proposes; beyond it an implicit
/// scheme is cheaper than resolving the fastest frequency.
pub const MAX_SUBSTEPS: usize = 4096;

/// How many substeps of `Δt / n` keep an explicit scheme below `dt_uniform` (the
/// [`uniform_stability_limit`]) with the [`SUBSTEP_MARGIN`]: `n = ⌈Δt / (margin · dt_uniform)⌉`,
/// 1 when Δt is already below; `None` when `n` would exceed [`MAX_SUBSTEPS`] or the limit is
/// not positive.
pub fn explicit_substeps(dt: f64, dt_uniform: f64) -> Option<usize> {
    if dt_uniform.is_nan() || dt_uniform <= 0.0 {
        return None;
    }
    let n = (dt / (SUBSTEP_MARGIN * dt_uniform)).ceil().max(1.0);
    (n <= MAX_SUBSTEPS as f64).then_some(n as usize)
}

/// The implicit scheme a run falls back to when an explicit one cannot be run stably at Δt
/// (no stiffness bound, or more than [`MAX_SUBSTEPS`] substeps): Newmark's average
/// acceleration, unconditionally stable and without numerical damping.
pub const IMPLICIT_FALLBACK: IntegratorKind = IntegratorKind::Newmark;

/// How a run at Δt is integrated: the scheme and the steps of `Δt / substeps` per Δt.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Schedule {
    /// The scheme.
    pub integrator: IntegratorKind,
    /// Steps per Δt (1: plain steps of Δt).
    pub substeps: usize,
}

impl Schedule {
    /// `integrator` with plain steps of Δt.
    pub fn plain(integrator: IntegratorKind) -> Self {
        Self {
            integrator,
            substeps: 1,
        }
    }

    /// A stable way to run `requested` on `model` at Δt from the positions `q`, with the
    /// stability limit that holds for that run (`None` for implicit schemes). Implicit schemes
    /// run as they are. An explicit scheme runs in the fewest substeps below the model's
    /// [`uniform_stability_limit`] ([`explicit_substeps`]; one when Δt is already below it),
    /// so it is stable along the whole trajectory, not only at `q`; with
    /// [`IMPLICIT_FALLBACK`] when that takes more than [`MAX_SUBSTEPS`]. A model without a
    /// stiffness bound runs plain steps below its limit at `q` ([`stability_limit`]) and
    /// [`IMPLICIT_FALLBACK`] above it.
    pub fn stable(
        model: &dyn DynamicModel,
        q: &[f64],
        requested: IntegratorKind,
        dt: f64,
    ) -> Result<(Self, Option<StabilityLimit>), SimError> {
        if !requested.is_explicit() {
            return Ok((Self::plain(requested), None));
        }
        match uniform_stability_limit(model)? {
            Some(uniform) => Ok(Self::below(requested, dt, uniform)),
            None => {
                let at_q = stability_limit(model, q)?;
                Ok(if dt < at_q.dt_critical {
                    (Self::plain(requested), Some(at_q))
                } else {
                    (Self::plain(IMPLICIT_FALLBACK), None)
                })
            }
        }
    }

    /// [`Schedule::stable`] for a model whose [`uniform_stability_limit`] is known:
    /// `requested` (explicit) in [`explicit_substeps`] of it, [`IMPLICIT_FALLBACK`] beyond
    /// [`MAX_SUBSTEPS`].
    pub fn below(
        requested: IntegratorKind,
        dt: f64,
        uniform: StabilityLimit,
    ) -> (Self, Option<StabilityLimit>) {
        match explicit_substeps(dt, uniform.dt_critical) {
            Some(substeps) => (
                Self {
                    integrator: requested,
                    substeps,
                },
                Some(uniform),
            ),
            None => (Self::plain(IMPLICIT_FALLBACK), None),
        }
    }

    /// Whether this is `requested` with plain steps.
    pub fn is_plain(&self, requested: IntegratorKind) -> bool {
        *self == Self::plain(requested)
    }
}

impl std::fmt::Display for Schedule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.substeps == 1 {
            write!(f, "{}", self.integrator)
        } else {
            write!(
                f,
                "{} ({} substeps per step)",
                self.integrator, self.substeps
            )
        }
    }
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
/// Each step of Δt is taken as `opts.substeps` steps of `h = Δt / substeps` (one, by default).
/// Explicit schemes first check `h < 2/ω_max` ([`RunOptions::stability`], or
/// [`stability_limit`] at the initial state) and
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
    let h = opts.substep();
    let n = model.n_dofs();
    crate::integrators::check_state_dims(model, &initial)?;
    let (mut omega_max, mut dt_critical) = (None, None);
    if opts.integrator.is_explicit() {
        let limit = match opts.stability {
            Some(known) => known,
            None => stability_limit(model, &initial.q)?,
        };
        omega_max = Some(limit.omega_max);
        dt_critical = Some(limit.dt_critical);
        if h >= limit.dt_critical && !opts.force_unstable {
            return Err(SimError::Unstable {
                integrator: opts.integrator.name(),
                dt: h,
                dt_critical: limit.dt_critical,
            });
        }
    }
    let stepper_opts = RunOptions {
        dt: h,
        cancel: None,
        ..opts.clone()
    };
    let mut stepper = make_stepper_with_options(opts.integrator, model, &initial, &stepper_opts)?;
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
        halved_steps: 0,
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
        for _ in 0..opts.substeps {
            stepper.step(model, &mut state, h)?;
        }
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
        summary.halved_steps = stepper.halved_steps();
    }
    Ok(summary)
}
