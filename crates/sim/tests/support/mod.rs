//! Shared test support for nurbspring-sim: tolerances, test models and closed-form solutions.
#![allow(dead_code)]

use std::sync::atomic::{AtomicUsize, Ordering};

use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::{DynamicModel, LinearModel, SystemMatrix};

/// Tolerances, in one place, each near the real error of the method it checks.
pub mod tol {
    /// Exact schemes (modal) vs closed form: round-off accumulated over ~10³ steps of dense
    /// mat-vecs on well-conditioned mode shapes.
    pub const MODAL: f64 = 1e-11;
    /// Relative energy drift of Newmark with D = 0 over 2000 steps: round-off only.
    pub const ENERGY_ROUNDOFF: f64 = 1e-11;
    /// Observed convergence ratio err(Δt)/err(Δt/2) must be within this factor of 2^p.
    pub const ORDER_RATIO: f64 = 0.12;
    /// Per-step amplification of a single mode vs its formula: round-off.
    pub const AMPLIFICATION: f64 = 1e-9;
    /// Exact linear algebra in a few operations.
    pub const EXACT: f64 = 1e-13;
    /// ω_max from Lanczos vs analytic (Lanczos tolerance 1e-8 in λ).
    pub const OMEGA: f64 = 1e-6;
    /// A spectral radius identified from a scheme's output (a least-squares fit of its
    /// three-term recurrence) vs the closed form, for ωΔt up to 10⁵: the fit loses digits as
    /// the roots cluster near −ρ∞ (measured 8e-11 at ωΔt = 10³, 1.3e-9 at 10⁴, 3.5e-7 at 10⁵).
    pub const IDENTIFIED_RADIUS: f64 = 1e-6;
    /// An explicit scheme with a diagonal mass through its Cholesky factor vs the diagonal
    /// path, 2000 steps of a chain whose motion is of order 1: `x/√m/√m` against `x·(1/m)`
    /// differs by an ulp or two a step, and undamped the difference accumulates along the
    /// modes (measured 2.3e-13 for symplectic Euler, 1.9e-13 Verlet, 3.8e-14 RK4; damped
    /// 1.7e-15).
    pub const FACTORED_MASS: f64 = 1e-12;
    /// Observed convergence order `log₂(e(Δt)/e(Δt/2))` over three or more halvings must lie
    /// within this of the scheme's order.
    pub const RATE: f64 = 0.2;
}

/// The observed orders `log₂(e_i / e_{i+1})` of errors at successively halved steps.
pub fn observed_rates(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// `[1.234e-5, …]`: a list of numbers in scientific notation, 4 digits.
pub fn sci(xs: &[f64]) -> String {
    let items: Vec<String> = xs.iter().map(|x| format!("{x:.3e}")).collect();
    format!("[{}]", items.join(", "))
}

/// Checks that every observed order of `errors` (at successively halved steps, at least three
/// halvings) lies within [`tol::RATE`] of `order`.
pub fn assert_rates(name: &str, errors: &[f64], order: f64) {
    assert!(
        errors.len() >= 4,
        "{name}: {} errors, at least 4 needed",
        errors.len()
    );
    let rates = observed_rates(errors);
    assert!(
        rates.iter().all(|r| (r - order).abs() < tol::RATE),
        "{name}: observed orders {rates:.3?} (errors {}), expected {order} ± {}",
        sci(errors),
        tol::RATE
    );
}

/// Checks that `ratio` ≈ 2^order within [`tol::ORDER_RATIO`] relative.
pub fn assert_order(name: &str, ratio: f64, order: i32) {
    let expected = 2f64.powi(order);
    assert!(
        (ratio / expected - 1.0).abs() < tol::ORDER_RATIO,
        "{name}: error ratio {ratio:.4} for halved Δt, expected ≈ {expected} (order {order})"
    );
}

/// A chain of `n` masses `m` joined by springs `k`, both ends fixed: `K = k·tridiag(−1, 2, −1)`,
/// `M = m I`. Modes `φ_j(i) = sin(i jπ/(n+1))`, `ω_j = 2√(k/m) sin(jπ/(2(n+1)))`.
pub struct Chain {
    pub n: usize,
    pub k: f64,
    pub m: f64,
}

impl Chain {
    pub fn stiffness(&self) -> SparseMatrix {
        let mut t = Vec::new();
        for i in 0..self.n {
            t.push((i, i, 2.0 * self.k));
            if i + 1 < self.n {
                t.push((i, i + 1, -self.k));
                t.push((i + 1, i, -self.k));
            }
        }
        SparseMatrix::from_triplets(self.n, self.n, &t).unwrap()
    }

    pub fn model(&self) -> LinearModel {
        LinearModel::new(
            SystemMatrix::Diagonal(vec![self.m; self.n]),
            self.stiffness(),
        )
    }

    pub fn omega(&self, j: usize) -> f64 {
        2.0 * (self.k / self.m).sqrt()
            * ((j as f64) * std::f64::consts::PI / (2.0 * (self.n as f64 + 1.0))).sin()
    }

    fn mode(&self, j: usize, i: usize) -> f64 {
        (((i + 1) * j) as f64 * std::f64::consts::PI / (self.n as f64 + 1.0)).sin()
    }

    /// Closed-form free vibration about `q_eq`: `q(t) = q_eq + Σ_j φ_j (a_j cos ω_j t + b_j/ω_j sin ω_j t)`.
    pub fn exact(&self, q_eq: &[f64], q0: &[f64], v0: &[f64], t: f64) -> Vec<f64> {
        let n = self.n;
        let norm = 2.0 / (n as f64 + 1.0);
        let mut q = q_eq.to_vec();
        for j in 1..=n {
            let a: f64 = norm
                * (0..n)
                    .map(|i| self.mode(j, i) * (q0[i] - q_eq[i]))
                    .sum::<f64>();
            let b: f64 = norm * (0..n).map(|i| self.mode(j, i) * v0[i]).sum::<f64>();
            let w = self.omega(j);
            let c = a * (w * t).cos() + b / w * (w * t).sin();
            for i in 0..n {
                q[i] += c * self.mode(j, i);
            }
        }
        q
    }
}

impl Chain {
    /// Time derivative of [`Chain::exact`]:
    /// `q̇(t) = Σ_j φ_j (−a_j ω_j sin ω_j t + b_j cos ω_j t)`, differentiated by hand.
    pub fn exact_velocity(&self, q_eq: &[f64], q0: &[f64], v0: &[f64], t: f64) -> Vec<f64> {
        let n = self.n;
        let norm = 2.0 / (n as f64 + 1.0);
        let mut v = vec![0.0; n];
        for j in 1..=n {
            let a: f64 = norm
                * (0..n)
                    .map(|i| self.mode(j, i) * (q0[i] - q_eq[i]))
                    .sum::<f64>();
            let b: f64 = norm * (0..n).map(|i| self.mode(j, i) * v0[i]).sum::<f64>();
            let w = self.omega(j);
            let c = -a * w * (w * t).sin() + b * (w * t).cos();
            for (i, vi) in v.iter_mut().enumerate() {
                *vi += c * self.mode(j, i);
            }
        }
        v
    }
}

impl Chain {
    /// The consistent mass of the chain's linear elements, `(m/6)·tridiag(1, 4, 1)` (each
    /// element of mass m contributes `(m/6)[2 1; 1 2]`; the rows of the free masses sum to m).
    pub fn consistent_mass(&self) -> SparseMatrix {
        let (d, o) = (4.0 * self.m / 6.0, self.m / 6.0);
        let mut t = Vec::new();
        for i in 0..self.n {
            t.push((i, i, d));
            if i + 1 < self.n {
                t.push((i, i + 1, o));
                t.push((i + 1, i, o));
            }
        }
        SparseMatrix::from_triplets(self.n, self.n, &t).unwrap()
    }

    /// The angular frequencies with the consistent mass: K and M share the modes
    /// `sin(i jπ/(n+1))`, so `ω_j² = k(2 − 2cos θ_j) / ((m/6)(4 + 2cos θ_j))`,
    /// `θ_j = jπ/(n+1)`.
    pub fn consistent_omega(&self, j: usize) -> f64 {
        let c = (j as f64 * std::f64::consts::PI / (self.n as f64 + 1.0)).cos();
        (self.k * (2.0 - 2.0 * c) / (self.m / 6.0 * (4.0 + 2.0 * c))).sqrt()
    }
}

/// Deterministic, non-symmetric initial data exciting every mode.
pub fn initial_positions(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 0.3 * ((i as f64 + 1.0) * 1.7).sin() + 0.05 * i as f64)
        .collect()
}

pub fn initial_velocities(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 0.2 * ((i as f64 + 0.5) * 2.3).cos())
        .collect()
}

/// A Duffing chain: the linear chain plus a cubic grounding spring at every mass,
/// `f_int(q) = K q + ε q³`, `K_T = K + diag(3ε q²)`, `E = ½qᵀKq + ¼ε Σ q⁴`; optional diagonal
/// damping and a load, constant or switched to another at a time `t₁` (`t > t₁`). Nonlinear:
/// `linear_stiffness()` is `None`.
pub struct Duffing {
    pub k: SparseMatrix,
    pub epsilon: f64,
    pub mass: SystemMatrix,
    pub damping: Option<SystemMatrix>,
    pub force: Vec<f64>,
    /// `(t₁, load after t₁)`.
    pub force_after: Option<(f64, Vec<f64>)>,
}

impl Duffing {
    pub fn new(chain: &Chain, epsilon: f64) -> Self {
        Self {
            k: chain.stiffness(),
            epsilon,
            mass: SystemMatrix::Diagonal(vec![chain.m; chain.n]),
            damping: None,
            force: vec![0.0; chain.n],
            force_after: None,
        }
    }

    fn load(&self, t: f64) -> &[f64] {
        match &self.force_after {
            Some((t1, after)) if t > *t1 => after,
            _ => &self.force,
        }
    }
}

impl DynamicModel for Duffing {
    fn n_dofs(&self) -> usize {
        self.k.nrows()
    }
    fn mass(&self) -> &SystemMatrix {
        &self.mass
    }
    fn damping(&self) -> Option<&SystemMatrix> {
        self.damping.as_ref()
    }
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        self.k.mul_vec(q, out);
        for (o, x) in out.iter_mut().zip(q) {
            *o += self.epsilon * x * x * x;
        }
    }
    fn external_force(&self, t: f64, out: &mut [f64]) {
        out.copy_from_slice(self.load(t));
    }
    fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix {
        let d: Vec<f64> = q.iter().map(|x| 3.0 * self.epsilon * x * x).collect();
        SparseMatrix::linear_combination(1.0, &self.k, 1.0, &SparseMatrix::from_diagonal(&d))
            .unwrap()
    }
    fn potential_energy(&self, q: &[f64]) -> f64 {
        0.5 * self.k.quadratic_form(q)
            + 0.25 * self.epsilon * q.iter().map(|x| x.powi(4)).sum::<f64>()
    }
    fn external_potential(&self, t: f64, q: &[f64]) -> f64 {
        -q.iter().zip(self.load(t)).map(|(a, b)| a * b).sum::<f64>()
    }
}

/// A linear model hidden behind the nonlinear interface (`linear_stiffness()` is `None`), so
/// the Newton paths run on it; `stiffness` may be indefinite.
pub struct Opaque(pub LinearModel);

impl DynamicModel for Opaque {
    fn n_dofs(&self) -> usize {
        self.0.n_dofs()
    }
    fn mass(&self) -> &SystemMatrix {
        self.0.mass()
    }
    fn damping(&self) -> Option<&SystemMatrix> {
        self.0.damping()
    }
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        self.0.internal_force(q, out)
    }
    fn external_force(&self, t: f64, out: &mut [f64]) {
        self.0.external_force(t, out)
    }
    fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix {
        self.0.tangent_stiffness(q)
    }
    fn potential_energy(&self, q: &[f64]) -> f64 {
        self.0.potential_energy(q)
    }
}

pub fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

/// A buckling chain: the linear chain with a double-well grounding at every mass,
/// `f_int(q) = K q − κ q + ε q³`, `E = ½qᵀKq + Σ (¼ε q⁴ − ½κ q²)`,
/// `K_T = K + diag(3ε q² − κ)`. For κ above K's smallest eigenvalue the straight chain q = 0 is
/// an unstable equilibrium (like a compressed spring lattice), and K_T is indefinite near it.
/// With `project`, the model offers the positive semi-definite tangent
/// `K + diag(max(3ε q² − κ, 0))`. Counts the calls of the projection and of the energy.
pub struct DoubleWell {
    pub k: SparseMatrix,
    pub kappa: f64,
    pub epsilon: f64,
    pub mass: SystemMatrix,
    pub damping: Option<SystemMatrix>,
    pub project: bool,
    pub projections: AtomicUsize,
    pub energies: AtomicUsize,
}

impl DoubleWell {
    fn grounding(&self, q: &[f64], clip: bool) -> SparseMatrix {
        let d: Vec<f64> = q
            .iter()
            .map(|x| {
                let s = 3.0 * self.epsilon * x * x - self.kappa;
                if clip { s.max(0.0) } else { s }
            })
            .collect();
        SparseMatrix::linear_combination(1.0, &self.k, 1.0, &SparseMatrix::from_diagonal(&d))
            .unwrap()
    }
}

impl DynamicModel for DoubleWell {
    fn n_dofs(&self) -> usize {
        self.k.nrows()
    }
    fn mass(&self) -> &SystemMatrix {
        &self.mass
    }
    fn damping(&self) -> Option<&SystemMatrix> {
        self.damping.as_ref()
    }
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        self.k.mul_vec(q, out);
        for (o, x) in out.iter_mut().zip(q) {
            *o += self.epsilon * x * x * x - self.kappa * x;
        }
    }
    fn external_force(&self, _t: f64, out: &mut [f64]) {
        out.fill(0.0);
    }
    fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix {
        self.grounding(q, false)
    }
    fn projected_tangent_stiffness(&self, q: &[f64]) -> Option<SparseMatrix> {
        self.projections.fetch_add(1, Ordering::Relaxed);
        self.project.then(|| self.grounding(q, true))
    }
    fn potential_energy(&self, q: &[f64]) -> f64 {
        self.energies.fetch_add(1, Ordering::Relaxed);
        0.5 * self.k.quadratic_form(q)
            + q.iter()
                .map(|x| 0.25 * self.epsilon * x.powi(4) - 0.5 * self.kappa * x * x)
                .sum::<f64>()
    }
}

/// A prestressed chain: `n` masses between fixed ends, joined by springs that each carry the
/// tension `T = P + k s` (`s` the spring's stretch beyond its prestressed length, `s_j = q_j −
/// q_{j−1}`, `q_{−1} = q_n = 0`). The force on mass i is computed as the difference of the two
/// tensions, `f_int,i = T_i − T_{i+1}`, as a spring lattice computes it: mathematically
/// `(K q)_i` with the chain's `K = k·tridiag(−1, 2, −1)` (P cancels), numerically `K q` plus
/// a round-off of a few ulps of P that changes erratically as q moves. `E = ½ qᵀKq` (the
/// prestress does work `P Σ s_j = 0` between fixed ends), `K_T = K`, behind the nonlinear
/// interface.
pub struct Prestressed {
    pub chain: Chain,
    pub prestress: f64,
    pub mass: SystemMatrix,
}

impl Prestressed {
    fn tension(&self, q: &[f64], j: usize) -> f64 {
        let right = if j < q.len() { q[j] } else { 0.0 };
        let left = if j > 0 { q[j - 1] } else { 0.0 };
        self.prestress + self.chain.k * (right - left)
    }
}

impl DynamicModel for Prestressed {
    fn n_dofs(&self) -> usize {
        self.chain.n
    }
    fn mass(&self) -> &SystemMatrix {
        &self.mass
    }
    fn damping(&self) -> Option<&SystemMatrix> {
        None
    }
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.tension(q, i) - self.tension(q, i + 1);
        }
    }
    fn external_force(&self, _t: f64, out: &mut [f64]) {
        out.fill(0.0);
    }
    fn tangent_stiffness(&self, _q: &[f64]) -> SparseMatrix {
        self.chain.stiffness()
    }
    fn potential_energy(&self, q: &[f64]) -> f64 {
        0.5 * self.chain.stiffness().quadratic_form(q)
    }
}
