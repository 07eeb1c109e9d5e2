//! The nonlinear equilibrium of a D-NURBS under its loads, followed along the load path by
//! Newton's method with adaptive load increments and a line search (docs/math.md §10.5).

use nurbspring_linalg::{LinalgError, LuSolver, SparseMatrix, SpdSolver};
use nurbspring_sim::DynamicModel;

use crate::{DnurbsError, DnurbsModel};

/// The Armijo fraction of the line search.
const ARMIJO: f64 = 1e-4;
/// Halvings of a Newton step before the smallest is taken.
const MAX_HALVINGS: usize = 12;
/// A step that multiplies the residual by at most this is accepted without the potential.
const RESIDUAL_HALVING: f64 = 0.5;

/// An increment converged in at most this many Newton iterations lets the next grow by 1.5.
const EASY_ITERATIONS: usize = 6;
/// An increment that needed at least this many halves the next.
const HARD_ITERATIONS: usize = 12;

/// Settings of [`DnurbsModel::equilibrium_path`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Load levels recorded, equally spaced: `λ = 1/levels, 2/levels, …, 1` (≥ 1).
    pub levels: usize,
    /// Relative residual `|f_int − λ f| / max(|f_int|, |λ f|)` at which Newton stops.
    pub tolerance: f64,
    /// Newton iterations per increment before the increment is halved.
    pub max_iterations: usize,
    /// Smallest increment, as a fraction of the full load, before the path gives up.
    pub min_increment: f64,
}

impl Default for PathSettings {
    fn default() -> Self {
        Self {
            levels: 1,
            tolerance: 1e-10,
            max_iterations: 30,
            min_increment: 1e-7,
        }
    }
}

/// One converged state of the path.
#[derive(Clone, Debug)]
pub struct LoadLevel {
    /// The load factor λ (1 = the scene's loads).
    pub lambda: f64,
    /// The full generalized coordinates at equilibrium.
    pub p: Vec<f64>,
    /// Relative residual reached.
    pub residual: f64,
}

/// The result of [`DnurbsModel::equilibrium_path`].
#[derive(Clone, Debug)]
pub struct EquilibriumPath {
    /// The recorded levels, `λ` ascending; the last is `λ = 1`.
    pub levels: Vec<LoadLevel>,
    /// Load increments solved (recorded or not).
    pub increments: usize,
    /// Newton iterations in all.
    pub iterations: usize,
    /// Increments that failed and were retried at half size.
    pub cut_backs: usize,
}

/// What stops a path early: a cancel request.
pub type Cancel<'a> = &'a (dyn Fn() -> bool + Sync);

/// A factorization of the tangent: Cholesky while it is positive definite, LU after.
struct Factor {
    spd: Option<SpdSolver>,
    lu: Option<LuSolver>,
}

impl Factor {
    /// `K x = rhs` by a fresh numeric factorization of `k` (the symbolic one reused):
    /// Cholesky while `k` is positive definite, LU once it is not.
    fn solve(&mut self, k: &SparseMatrix, rhs: &[f64]) -> Result<Vec<f64>, DnurbsError> {
        let spd = match self.spd.as_mut() {
            Some(s) => s.refactor(k).map(|_| ()),
            None => SpdSolver::new(k).map(|s| {
                self.spd = Some(s);
            }),
        };
        let apply = |x: &[f64], this: &Factor| -> Vec<f64> {
            match (&this.spd, &this.lu) {
                (Some(s), _) => s.solve(x),
                (None, Some(lu)) => lu.solve(x),
                (None, None) => unreachable!("a factor was made"),
            }
        };
        match spd {
            Ok(()) => self.lu = None,
            Err(LinalgError::NotPositiveDefinite { .. }) => {
                self.spd = None;
                self.lu = Some(LuSolver::new(k)?);
            }
            Err(e) => return Err(e.into()),
        }
        Ok(apply(rhs, self))
    }
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

/// Newton's outcome on one increment.
enum Newton {
    Converged { residual: f64, iterations: usize },
    Failed { iterations: usize },
}

impl DnurbsModel {
    /// The equilibrium `f_int(q) = λ f` on the free dofs along `λ ∈ (0, 1]`, recorded at
    /// `settings.levels` equal steps (docs/math.md §10.5).
    ///
    /// A linear model (the tension plate with constant weights) is solved once and scaled. A
    /// nonlinear one (the shell) is followed by load increments: each starts from a predictor
    /// (the tangent at the last state, then the secant of the last two), Newton's method
    /// with the consistent tangent (Cholesky, LU once it is indefinite) and a backtracking line
    /// search on the total potential `E(q) − λ fᵀq − λ W(q)` whenever a full step raises the
    /// residual. After at most 6 iterations the next increment grows by 1.5, after 12 or more
    /// it is halved (never past the next recorded level); an increment that fails is halved
    /// and retried, down to `settings.min_increment`.
    /// `progress(λ)` is called after each increment; `cancel()` is polled between Newton
    /// iterations.
    pub fn equilibrium_path(
        &self,
        settings: &PathSettings,
        cancel: Cancel<'_>,
        progress: &mut dyn FnMut(f64),
    ) -> Result<EquilibriumPath, DnurbsError> {
        let levels = settings.levels.max(1);
        let mut out = EquilibriumPath {
            levels: Vec::with_capacity(levels),
            increments: 0,
            iterations: 0,
            cut_backs: 0,
        };
        if self.shell.is_none() {
            if self.options.weights_as_dofs {
                return Err(DnurbsError::InvalidOption {
                    name: "weights_as_dofs",
                    value: "true".into(),
                    reason: "the load path of weights as unknowns is not followed; use the \
                             steady state"
                        .into(),
                });
            }
            let p1 = self.linearized_steady_state()?;
            let q1 = self.reduction.reduce_coordinates(&p1);
            for l in 1..=levels {
                let lambda = l as f64 / levels as f64;
                let q: Vec<f64> = q1.iter().map(|x| lambda * x).collect();
                out.levels.push(LoadLevel {
                    lambda,
                    p: self.reduction.to_full(&q),
                    residual: 0.0,
                });
                progress(lambda);
            }
            out.increments = 1;
            return Ok(out);
        }
        let mut factor = Factor {
            spd: None,
            lu: None,
        };
        let q_rest = self.reduction.reduce_coordinates(&self.p0);
        let mut q = q_rest.clone();
        let mut q_previous: Option<(Vec<f64>, f64)> = None;
        let mut lambda = 0.0;
        let mut increment = 1.0 / levels as f64;
        let mut next_level = 1;
        while next_level <= levels {
            if cancel() {
                return Err(DnurbsError::Cancelled);
            }
            let target = next_level as f64 / levels as f64;
            let step = increment.min(target - lambda);
            let lambda_new = if target - lambda - step <= 1e-12 {
                target
            } else {
                lambda + step
            };
            let step = lambda_new - lambda;
            let mut trial = self.predict(&q, q_previous.as_ref(), lambda, step, &mut factor)?;
            match self.newton(
                &mut trial,
                &q_rest,
                lambda_new,
                settings,
                cancel,
                &mut factor,
            )? {
                Newton::Converged {
                    residual,
                    iterations,
                } => {
                    out.increments += 1;
                    out.iterations += iterations;
                    q_previous = Some((std::mem::replace(&mut q, trial), step));
                    lambda = lambda_new;
                    progress(lambda);
                    if lambda_new == target {
                        out.levels.push(LoadLevel {
                            lambda,
                            p: self.reduction.to_full(&q),
                            residual,
                        });
                        next_level += 1;
                    }
                    // Few iterations: the next increment may grow; many: it shrinks.
                    increment = if iterations <= EASY_ITERATIONS {
                        (1.5 * step).max(increment)
                    } else if iterations >= HARD_ITERATIONS {
                        (0.5 * step).max(settings.min_increment)
                    } else {
                        increment.max(step)
                    };
                }
                Newton::Failed { iterations } => {
                    out.iterations += iterations;
                    out.cut_backs += 1;
                    increment = 0.5 * step;
                    if increment < settings.min_increment {
                        return Err(DnurbsError::PathStopped {
                            lambda,
                            increment: step,
                        });
                    }
                }
            }
        }
        Ok(out)
    }

    /// The starting guess at `λ + step`: the secant through the last two states when there
    /// are two, otherwise one Newton step from `q` at the new load.
    fn predict(
        &self,
        q: &[f64],
        previous: Option<&(Vec<f64>, f64)>,
        lambda: f64,
        step: f64,
        factor: &mut Factor,
    ) -> Result<Vec<f64>, DnurbsError> {
        if let Some((q_prev, prev_step)) = previous {
            let s = step / prev_step;
            return Ok(q.iter().zip(q_prev).map(|(a, b)| a + s * (a - b)).collect());
        }
        let k = self.path_tangent(q, lambda + step)?;
        let (mut rhs, _) = self.residual(q, lambda + step);
        for r in rhs.iter_mut() {
            *r = -*r;
        }
        let dq = factor.solve(&k, &rhs)?;
        Ok(q.iter().zip(&dq).map(|(a, b)| a + b).collect())
    }

    /// `f_int(q) − λ (f + g_m(q))` and its scale `max(|f_int|, |λ (f + g_m)|)`, `g_m` the edge
    /// moments' generalized force (docs/math.md §10.6).
    fn residual(&self, q: &[f64], lambda: f64) -> (Vec<f64>, f64) {
        let mut r = vec![0.0; q.len()];
        self.internal_force(q, &mut r);
        let mut load = self.f_ext.clone();
        if self.edge_loads.has_moments() {
            let p = self.reduction.to_full(q);
            let mut g = vec![0.0; p.len()];
            self.edge_loads.add_moment_force(&p, &mut g);
            for (l, g) in load.iter_mut().zip(self.reduction.reduce_vector(&g)) {
                *l += g;
            }
        }
        let scale = norm(&r).max(lambda * norm(&load));
        for (r, f) in r.iter_mut().zip(&load) {
            *r -= lambda * f;
        }
        (r, scale)
    }

    /// The tangent of the residual: `K_T(q) − λ ∂g_m/∂q`.
    fn path_tangent(&self, q: &[f64], lambda: f64) -> Result<SparseMatrix, DnurbsError> {
        let k = self.tangent_stiffness(q);
        let p = self.reduction.to_full(q);
        match self.edge_loads.moment_hessian(&p, p.len())? {
            None => Ok(k),
            Some(h) => {
                let h = self.reduction.reduce_matrix(&h)?;
                Ok(SparseMatrix::linear_combination(1.0, &k, -lambda, &h)?)
            }
        }
    }

    /// The change of the total potential `E(q) − λ fᵀq − λ W(q)` from `q` to `t`.
    fn potential_change(&self, q: &[f64], t: &[f64], lambda: f64) -> f64 {
        let d: Vec<f64> = t.iter().zip(q).map(|(a, b)| a - b).collect();
        let mut change =
            self.potential_energy(t) - self.potential_energy(q) - lambda * dot(&self.f_ext, &d);
        if self.edge_loads.has_moments() {
            let (pq, pt) = (self.reduction.to_full(q), self.reduction.to_full(t));
            change -= lambda * self.edge_loads.work_between(&pq, &pt);
        }
        change
    }

    fn newton(
        &self,
        q: &mut [f64],
        q_rest: &[f64],
        lambda: f64,
        settings: &PathSettings,
        cancel: Cancel<'_>,
        factor: &mut Factor,
    ) -> Result<Newton, DnurbsError> {
        let (mut r, mut scale) = self.residual(q, lambda);
        let first = norm(&r);
        for it in 0..settings.max_iterations {
            if cancel() {
                return Err(DnurbsError::Cancelled);
            }
            let rn = norm(&r);
            if !rn.is_finite() || rn > 1e6 * first.max(f64::MIN_POSITIVE) {
                return Ok(Newton::Failed { iterations: it });
            }
            if rn <= settings.tolerance * scale {
                return Ok(Newton::Converged {
                    residual: if scale > 0.0 { rn / scale } else { 0.0 },
                    iterations: it,
                });
            }
            let k = self.path_tangent(q, lambda)?;
            if !k.all_finite() {
                return Ok(Newton::Failed { iterations: it + 1 });
            }
            let minus_r: Vec<f64> = r.iter().map(|x| -x).collect();
            let dq = factor.solve(&k, &minus_r)?;
            if dq.iter().any(|x| !x.is_finite()) {
                return Ok(Newton::Failed { iterations: it + 1 });
            }
            // The residual's floor is the round-off of f_int, whose terms can be far larger
            // than the load (a stiff membrane under a small load): a Newton correction below
            // the tolerance relative to the displacement from rest is convergence too.
            let moved = norm(
                &q.iter()
                    .zip(q_rest)
                    .map(|(a, b)| a - b)
                    .collect::<Vec<f64>>(),
            );
            if norm(&dq) <= settings.tolerance * moved {
                for (a, b) in q.iter_mut().zip(&dq) {
                    *a += b;
                }
                let (r, scale) = self.residual(q, lambda);
                return Ok(Newton::Converged {
                    residual: if scale > 0.0 { norm(&r) / scale } else { 0.0 },
                    iterations: it + 1,
                });
            }
            // The step is accepted when it lowers the total potential by the Armijo fraction
            // of its slope (a descent direction), or when it halves the residual (Newton near
            // convergence, where the potential's changes are round-off, and along a direction
            // of ascent); otherwise it is halved, at most MAX_HALVINGS times.
            let slope = dot(&r, &dq);
            let mut alpha = 1.0;
            let mut accepted = None;
            for _ in 0..=MAX_HALVINGS {
                let t: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + alpha * b).collect();
                let (r_t, scale_t) = self.residual(&t, lambda);
                let rt = norm(&r_t);
                let lowers = slope < 0.0
                    && rt.is_finite()
                    && self.potential_change(q, &t, lambda) <= ARMIJO * alpha * slope;
                if rt <= RESIDUAL_HALVING * rn || lowers {
                    accepted = Some((t, r_t, scale_t));
                    break;
                }
                alpha *= 0.5;
            }
            match accepted {
                Some((t, r_t, scale_t)) => {
                    q.copy_from_slice(&t);
                    (r, scale) = (r_t, scale_t);
                }
                None => return Ok(Newton::Failed { iterations: it + 1 }),
            }
        }
        let rn = norm(&r);
        if rn <= settings.tolerance * scale {
            return Ok(Newton::Converged {
                residual: rn / scale,
                iterations: settings.max_iterations,
            });
        }
        Ok(Newton::Failed {
            iterations: settings.max_iterations,
        })
    }
}
