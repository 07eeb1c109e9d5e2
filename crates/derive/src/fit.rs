//! The stiffness fit of the paper's eq. (15): `min_k ‖Ωᵀ K_S(k) Ω − K_D‖_F²`.
//!
//! `K_S` is linear in the class constants, `K_S = Σ_c k_c G_c` (docs/math.md §5), so with
//! `H_c = Ωᵀ G_c Ω` the problem is linear least squares in `k`: the normal equations
//! `A k = b` with `A_cd = ⟨H_c, H_d⟩_F` and `b_c = ⟨H_c, K_D⟩_F` (docs/math.md §6). The products are
//! formed sparse (never a dense `3N × 3N` product). The paper solved (15) with a trust-region
//! method; [`StiffnessFit::trust_region`] does the same and must land on the closed form.

use nurbspring_linalg::{
    DenseMatrix, SparseMatrix, nonnegative_least_squares, symmetric_eigen,
    symmetric_extreme_eigenvalues,
};
use nurbspring_msm::{Class, Constants};
use serde::{Deserialize, Serialize};

use crate::DeriveError;

/// Which rows and columns of `K_D` (and of `Ωᵀ K_S Ω`) enter the fit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitDofs {
    /// Every generalized coordinate: the paper's literal eq. (15).
    #[default]
    All,
    /// Only the free (unconstrained) generalized coordinates.
    Free,
}

impl FitDofs {
    /// "all" or "free".
    pub fn name(self) -> &'static str {
        match self {
            FitDofs::All => "all",
            FitDofs::Free => "free",
        }
    }
}

/// Constants by class with the residual of eq. (15) they leave.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FitResult {
    /// The constants (`k_edge`, `k_diag`, `k_bend` in files).
    #[serde(flatten)]
    pub constants: Constants,
    /// `‖Ωᵀ K_S Ω − K_D‖_F / ‖K_D‖_F` on the dofs of this fit.
    pub relative_residual: f64,
}

/// The fit problem: the matrices `H_c`, the target `K_D` and the normal equations.
#[derive(Clone, Debug)]
pub struct StiffnessFit {
    classes: Vec<Class>,
    h: Vec<SparseMatrix>,
    k_d: SparseMatrix,
    gram: DenseMatrix,
    rhs: Vec<f64>,
    k_d_norm: f64,
    /// `‖K_D‖₂` and the dense `H_c` and `K_D`, made on first use: the spectral fit evaluates
    /// its residual hundreds of times.
    spectral: std::sync::OnceLock<SpectralForm>,
}

/// The dense form of the fit for spectral norms.
#[derive(Clone, Debug)]
struct SpectralForm {
    h: Vec<DenseMatrix>,
    k_d: DenseMatrix,
    k_d_norm: f64,
}

/// Outcome of the trust-region iteration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrustRegionOutcome {
    /// Spring constants found.
    pub k: Vec<f64>,
    /// Iterations taken.
    pub iterations: usize,
    /// Norm of the (projected) gradient at the end.
    pub gradient_norm: f64,
}

impl StiffnessFit {
    /// Sets up the fit. `unit` holds `(class, G_c)` for every class present (3N_nodes
    /// square); `omega` is Ω (3N_nodes × n); `k_d` is n × n; `dofs` selects the generalized
    /// coordinates that enter (None = all).
    pub fn new(
        k_d: &SparseMatrix,
        omega: &SparseMatrix,
        unit: &[(Class, SparseMatrix)],
        n_elements: usize,
        dofs: Option<&[usize]>,
    ) -> Result<Self, DeriveError> {
        if unit.is_empty() || n_elements < unit.len() {
            return Err(DeriveError::TooFewElements {
                classes: unit.len(),
                elements: n_elements,
            });
        }
        if k_d.nrows() != omega.ncols() || k_d.ncols() != omega.ncols() {
            return Err(DeriveError::DimensionMismatch {
                what: "K_D against the columns of Ω",
                expected: omega.ncols(),
                found: k_d.nrows(),
            });
        }
        let omega_sel = match dofs {
            Some(d) => {
                let rows: Vec<usize> = (0..omega.nrows()).collect();
                omega.submatrix(&rows, d)
            }
            None => omega.clone(),
        };
        let k_d = match dofs {
            Some(d) => k_d.submatrix(d, d),
            None => k_d.clone(),
        };
        let omega_t = omega_sel.transpose();
        let mut classes = Vec::with_capacity(unit.len());
        let mut h = Vec::with_capacity(unit.len());
        for (class, g) in unit {
            if g.nrows() != omega.nrows() {
                return Err(DeriveError::DimensionMismatch {
                    what: "G_c against the rows of Ω",
                    expected: omega.nrows(),
                    found: g.nrows(),
                });
            }
            let hc = omega_t.matmul(&g.matmul(&omega_sel)?)?;
            classes.push(*class);
            h.push(hc);
        }
        let c = classes.len();
        let gram = DenseMatrix::from_fn(c, c, |i, j| h[i].frobenius_dot(&h[j]));
        let rhs: Vec<f64> = h.iter().map(|hc| hc.frobenius_dot(&k_d)).collect();
        let k_d_norm = k_d.frobenius_norm();
        let fit = Self {
            classes,
            h,
            k_d,
            gram,
            rhs,
            k_d_norm,
            spectral: std::sync::OnceLock::new(),
        };
        fit.check_identifiable()?;
        Ok(fit)
    }

    fn check_identifiable(&self) -> Result<(), DeriveError> {
        let c = self.classes.len();
        let norms: Vec<f64> = (0..c).map(|i| self.gram[(i, i)].sqrt()).collect();
        let scale = norms.iter().cloned().fold(0.0, f64::max);
        let mut problems = Vec::new();
        for i in 0..c {
            if norms[i] <= 1e-12 * scale.max(f64::MIN_POSITIVE) {
                problems.push(format!(
                    "{} elements contribute nothing on the selected dofs (Ωᵀ G Ω = 0)",
                    self.classes[i].name()
                ));
            }
        }
        if problems.is_empty() && c > 1 {
            // Normalized Gram matrix: its smallest eigenvalue measures linear dependence.
            let normalized =
                DenseMatrix::from_fn(c, c, |i, j| self.gram[(i, j)] / (norms[i] * norms[j]));
            let eig = symmetric_eigen(&normalized)?;
            if eig.values[0] < 1e-10 {
                let v = eig.vectors.column(0);
                let involved: Vec<String> = (0..c)
                    .filter(|&i| v[i].abs() > 1e-3)
                    .map(|i| self.classes[i].name())
                    .collect();
                problems.push(format!(
                    "the classes {} give linearly dependent stiffness on the selected dofs (smallest normalized Gram eigenvalue {:.3e})",
                    involved.join(", "),
                    eig.values[0]
                ));
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(DeriveError::SingularFit {
                detail: problems.join("; "),
            })
        }
    }

    /// The classes, in the order of `k`.
    pub fn classes(&self) -> &[Class] {
        &self.classes
    }

    /// `k` in class order as [`Constants`].
    pub fn constants(&self, k: &[f64]) -> Constants {
        Constants::from_values(&self.classes, k)
    }

    /// The Gram matrix `A_cd = ⟨H_c, H_d⟩_F`.
    pub fn gram(&self) -> &DenseMatrix {
        &self.gram
    }

    /// The right-hand side `b_c = ⟨H_c, K_D⟩_F`.
    pub fn rhs(&self) -> &[f64] {
        &self.rhs
    }

    /// `H_c = Ωᵀ G_c Ω` on the selected dofs.
    pub fn h(&self, class: usize) -> &SparseMatrix {
        &self.h[class]
    }

    /// `‖K_D‖_F` on the selected dofs.
    pub fn k_d_norm(&self) -> f64 {
        self.k_d_norm
    }

    /// `Ωᵀ K_S(k) Ω` on the selected dofs.
    pub fn model_matrix(&self, k: &[f64]) -> Result<SparseMatrix, DeriveError> {
        let mut acc = SparseMatrix::zeros(self.k_d.nrows(), self.k_d.ncols());
        for (hc, &kc) in self.h.iter().zip(k) {
            acc = SparseMatrix::linear_combination(1.0, &acc, kc, hc)?;
        }
        Ok(acc)
    }

    /// Relative residual `‖Ωᵀ K_S(k) Ω − K_D‖_F / ‖K_D‖_F`, formed explicitly (no cancellation).
    pub fn relative_residual(&self, k: &[f64]) -> Result<f64, DeriveError> {
        let m = self.model_matrix(k)?;
        let diff = SparseMatrix::linear_combination(1.0, &m, -1.0, &self.k_d)?;
        Ok(diff.frobenius_norm() / self.k_d_norm.max(f64::MIN_POSITIVE))
    }

    /// Closed-form solution of the normal equations (docs/math.md §6); with `nonnegative`, the exact
    /// solution of the convex quadratic program over `k ≥ 0`: Lawson–Hanson NNLS
    /// ([`nonnegative_least_squares`]) on the square-root form `min ‖R k − R⁻ᵀ b‖` of the
    /// normal equations (`A = RᵀR` from the eigen-decomposition of the Gram matrix) finds the
    /// active set, and the normal equations restricted to its free classes give the solution.
    pub fn solve(&self, nonnegative: bool) -> Result<Vec<f64>, DeriveError> {
        let c = self.classes.len();
        let all: Vec<usize> = (0..c).collect();
        if !nonnegative {
            return self.solve_subset(&all);
        }
        let eig = symmetric_eigen(&self.gram)?;
        let root: Vec<f64> = eig.values.iter().map(|&l| l.max(0.0).sqrt()).collect();
        let r = DenseMatrix::from_fn(c, c, |i, j| root[i] * eig.vectors[(j, i)]);
        let d: Vec<f64> = (0..c)
            .map(|i| {
                let vb: f64 = (0..c).map(|j| eig.vectors[(j, i)] * self.rhs[j]).sum();
                if root[i] > 0.0 { vb / root[i] } else { 0.0 }
            })
            .collect();
        let x = nonnegative_least_squares(&r, &d)?;
        let passive: Vec<usize> = all.into_iter().filter(|&j| x[j] > 0.0).collect();
        if passive.is_empty() {
            return Ok(vec![0.0; c]);
        }
        match self.solve_subset(&passive) {
            Ok(k) if k.iter().all(|&v| v >= 0.0) => Ok(k),
            _ => Ok(x),
        }
    }

    fn solve_subset(&self, subset: &[usize]) -> Result<Vec<f64>, DeriveError> {
        let n = subset.len();
        let a = DenseMatrix::from_fn(n, n, |i, j| self.gram[(subset[i], subset[j])]);
        let b: Vec<f64> = subset.iter().map(|&i| self.rhs[i]).collect();
        let ks = nurbspring_linalg::cholesky_solve_dense(&a, &b)?;
        let mut k = vec![0.0; self.classes.len()];
        for (i, &s) in subset.iter().enumerate() {
            k[s] = ks[i];
        }
        Ok(k)
    }

    /// `f(k) = (kᵀ A k − 2 bᵀ k) / ‖K_D‖²`, which is the squared relative residual minus 1.
    fn objective(&self, k: &[f64]) -> f64 {
        let ak = self.gram.mul_vec(k);
        let quad: f64 = k.iter().zip(&ak).map(|(x, y)| x * y).sum();
        let lin: f64 = k.iter().zip(&self.rhs).map(|(x, y)| x * y).sum();
        (quad - 2.0 * lin) / (self.k_d_norm * self.k_d_norm).max(f64::MIN_POSITIVE)
    }

    fn gradient(&self, k: &[f64]) -> Vec<f64> {
        let s = 2.0 / (self.k_d_norm * self.k_d_norm).max(f64::MIN_POSITIVE);
        let ak = self.gram.mul_vec(k);
        ak.iter().zip(&self.rhs).map(|(a, b)| s * (a - b)).collect()
    }

    /// The trust-region method the paper used (its ref. [9]): each step minimizes the
    /// quadratic model within a ball of radius Δ exactly (eigen-decomposition of the Hessian
    /// and a bisection on the secular equation `‖(H + λI)⁻¹ g‖ = Δ`, Moré–Sorensen), with the
    /// usual ratio test for Δ. With `nonnegative`, steps are taken on the variables not held
    /// at their bound and projected onto `k ≥ 0` (a projected trust-region method).
    pub fn trust_region(
        &self,
        start: &[f64],
        nonnegative: bool,
        max_iterations: usize,
    ) -> Result<TrustRegionOutcome, DeriveError> {
        let c = self.classes.len();
        let scale = 2.0 / (self.k_d_norm * self.k_d_norm).max(f64::MIN_POSITIVE);
        let mut k: Vec<f64> = start.to_vec();
        if nonnegative {
            k.iter_mut().for_each(|x| *x = x.max(0.0));
        }
        let mut radius = 1.0f64.max(k.iter().map(|x| x.abs()).fold(0.0, f64::max));
        let g0 = norm(&self.gradient(&k)).max(f64::MIN_POSITIVE);
        let mut iterations = 0;
        let mut gnorm = g0;
        while iterations < max_iterations {
            let g = self.gradient(&k);
            // Variables free to move: not at the bound with the gradient pushing outward.
            let free: Vec<usize> = (0..c)
                .filter(|&i| !nonnegative || k[i] > 0.0 || g[i] < 0.0)
                .collect();
            let gf: Vec<f64> = free.iter().map(|&i| g[i]).collect();
            gnorm = norm(&gf);
            if gnorm <= 1e-13 * g0 || free.is_empty() {
                break;
            }
            iterations += 1;
            let hf = DenseMatrix::from_fn(free.len(), free.len(), |i, j| {
                scale * self.gram[(free[i], free[j])]
            });
            let step = trust_region_step(&hf, &gf, radius)?;
            let mut trial = k.clone();
            for (i, &fi) in free.iter().enumerate() {
                trial[fi] += step[i];
                if nonnegative {
                    trial[fi] = trial[fi].max(0.0);
                }
            }
            let actual = self.objective(&k) - self.objective(&trial);
            let s: Vec<f64> = free.iter().map(|&i| trial[i] - k[i]).collect();
            let hs = hf.mul_vec(&s);
            let predicted = -(dot(&gf, &s) + 0.5 * dot(&s, &hs));
            let rho = if predicted > 0.0 {
                actual / predicted
            } else {
                0.0
            };
            let snorm = norm(&s);
            if rho < 0.25 {
                radius = 0.25 * snorm.max(1e-300);
            } else if rho > 0.75 && snorm >= 0.99 * radius {
                radius *= 2.0;
            }
            if rho > 1e-4 || (actual >= 0.0 && snorm < 1e-15 * (1.0 + norm(&k))) {
                k = trial;
            }
            if radius < 1e-300 {
                break;
            }
        }
        Ok(TrustRegionOutcome {
            k,
            iterations,
            gradient_norm: gnorm,
        })
    }
}

impl StiffnessFit {
    /// `‖Ωᵀ K_S(k) Ω − K_D‖₂ / ‖K_D‖₂` with the spectral norm (largest |eigenvalue| of the
    /// symmetric residual), the other reading of the paper's `‖·‖₂²` in eq. (15).
    pub fn relative_spectral_residual(&self, k: &[f64]) -> Result<f64, DeriveError> {
        let form = match self.spectral.get() {
            Some(form) => form,
            None => {
                let k_d = self.k_d.to_dense();
                let form = SpectralForm {
                    h: self.h.iter().map(SparseMatrix::to_dense).collect(),
                    k_d_norm: spectral_norm(&k_d)?,
                    k_d,
                };
                self.spectral.get_or_init(|| form)
            }
        };
        // Σ k_c H_c − K_D, summed in the order of `model_matrix` then the difference.
        let mut diff = DenseMatrix::zeros(self.k_d.nrows(), self.k_d.ncols());
        for (hc, &kc) in form.h.iter().zip(k) {
            for (d, &h) in diff.data_mut().iter_mut().zip(hc.data()) {
                *d += kc * h;
            }
        }
        for (d, &t) in diff.data_mut().iter_mut().zip(form.k_d.data()) {
            *d -= t;
        }
        Ok(spectral_norm(&diff)? / form.k_d_norm.max(f64::MIN_POSITIVE))
    }

    /// Minimizes the spectral-norm residual (convex but not smooth) by Nelder–Mead from the
    /// Frobenius solution, restarted until it no longer improves. Returns `k` and the relative
    /// spectral residual there.
    pub fn solve_spectral(&self) -> Result<(Vec<f64>, f64), DeriveError> {
        let start = self.solve(false)?;
        let f = |k: &[f64]| self.relative_spectral_residual(k).unwrap_or(f64::INFINITY);
        let mut best = start.clone();
        let mut best_f = f(&best);
        for _ in 0..6 {
            let scale = best.iter().map(|x| x.abs()).fold(0.0, f64::max).max(1e-3);
            let (k, fk) = nelder_mead(&f, &best, 0.25 * scale, 400);
            if fk < best_f - 1e-12 * best_f.abs() {
                best = k;
                best_f = fk;
            } else {
                break;
            }
        }
        Ok((best, best_f))
    }
}

/// Largest |eigenvalue| of a symmetric matrix (the two ends of its spectrum).
fn spectral_norm(a: &DenseMatrix) -> Result<f64, DeriveError> {
    if a.nrows() == 0 {
        return Ok(0.0);
    }
    let (lo, hi) = symmetric_extreme_eigenvalues(a)?;
    Ok(lo.abs().max(hi.abs()))
}

/// Nelder–Mead simplex minimization (Lagarias et al. 1998 coefficients) from `x0` with an
/// initial simplex of size `step`, at most `max_evals` evaluations.
fn nelder_mead(
    f: &dyn Fn(&[f64]) -> f64,
    x0: &[f64],
    step: f64,
    max_evals: usize,
) -> (Vec<f64>, f64) {
    let n = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    simplex.push((x0.to_vec(), f(x0)));
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] += step;
        let fx = f(&x);
        simplex.push((x, fx));
    }
    let mut evals = n + 1;
    while evals < max_evals {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (fb, fw) = (simplex[0].1, simplex[n].1);
        let size = simplex
            .iter()
            .map(|(x, _)| {
                x.iter()
                    .zip(&simplex[0].0)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        if (fw - fb).abs() <= 1e-13 * fb.abs().max(1e-300)
            && size <= 1e-10 * (1.0 + norm(&simplex[0].0))
        {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|j| simplex[..n].iter().map(|(x, _)| x[j]).sum::<f64>() / n as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            centroid
                .iter()
                .zip(&simplex[n].0)
                .map(|(c, w)| c + t * (c - w))
                .collect()
        };
        let xr = along(1.0);
        let fr = f(&xr);
        evals += 1;
        if fr < simplex[0].1 {
            let xe = along(2.0);
            let fe = f(&xe);
            evals += 1;
            simplex[n] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < simplex[n - 1].1 {
            simplex[n] = (xr, fr);
        } else {
            let (xc, fc) = if fr < simplex[n].1 {
                let x = along(0.5);
                let fx = f(&x);
                (x, fx)
            } else {
                let x = along(-0.5);
                let fx = f(&x);
                (x, fx)
            };
            evals += 1;
            if fc < simplex[n].1.min(fr) {
                simplex[n] = (xc, fc);
            } else {
                let best = simplex[0].0.clone();
                for item in simplex.iter_mut().skip(1) {
                    let x: Vec<f64> = item
                        .0
                        .iter()
                        .zip(&best)
                        .map(|(a, b)| b + 0.5 * (a - b))
                        .collect();
                    let fx = f(&x);
                    *item = (x, fx);
                }
                evals += n;
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (x, fx) = simplex.swap_remove(0);
    (x, fx)
}

/// Exact minimizer of `gᵀs + ½ sᵀHs` subject to `‖s‖ ≤ Δ` for a small symmetric H
/// (Moré & Sorensen 1983; Nocedal & Wright, Algorithm 4.3 in eigen-coordinates).
fn trust_region_step(h: &DenseMatrix, g: &[f64], radius: f64) -> Result<Vec<f64>, DeriveError> {
    let n = g.len();
    let eig = symmetric_eigen(h)?;
    // g in the eigenbasis.
    let gt: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|r| eig.vectors[(r, i)] * g[r]).sum())
        .collect();
    let lam_min = eig.values[0];
    let step_norm = |lam: f64| -> f64 {
        gt.iter()
            .zip(&eig.values)
            .map(|(gi, ei)| (gi / (ei + lam)).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let lam = if lam_min > 0.0 && step_norm(0.0) <= radius {
        0.0
    } else {
        // Bisection on ‖s(λ)‖ = Δ for λ > max(0, −λ_min).
        let mut lo = (-lam_min).max(0.0);
        let mut hi = lo + norm(g) / radius + eig.values[n - 1].abs() + 1.0;
        while step_norm(hi) > radius {
            hi *= 2.0;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if step_norm(mid) > radius {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    };
    let st: Vec<f64> = gt
        .iter()
        .zip(&eig.values)
        .map(|(gi, ei)| {
            let d = ei + lam;
            if d.abs() < 1e-300 { 0.0 } else { -gi / d }
        })
        .collect();
    Ok((0..n)
        .map(|r| (0..n).map(|i| eig.vectors[(r, i)] * st[i]).sum())
        .collect())
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f(x, y) = (x − 1)² + 10 (y + 2)²` from the origin: the minimum (1, −2) to 1e-6 within
    /// 400 evaluations; Rosenbrock's `(1 − x)² + 100 (y − x²)²` from (−1.2, 1), its curved
    /// valley, to (1, 1) within 2000 evaluations (the Lagarias coefficients need about 300).
    #[test]
    fn nelder_mead_finds_the_minima_of_a_quadratic_and_of_rosenbrock() {
        let quadratic = |x: &[f64]| (x[0] - 1.0).powi(2) + 10.0 * (x[1] + 2.0).powi(2);
        let (x, fx) = nelder_mead(&quadratic, &[0.0, 0.0], 0.5, 400);
        assert!(
            (x[0] - 1.0).abs() < 1e-6 && (x[1] + 2.0).abs() < 1e-6,
            "{x:?}"
        );
        assert_eq!(fx, quadratic(&x));
        let rosenbrock = |x: &[f64]| (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2);
        let (x, fx) = nelder_mead(&rosenbrock, &[-1.2, 1.0], 0.5, 2000);
        assert!(
            (x[0] - 1.0).abs() < 1e-5 && (x[1] - 1.0).abs() < 1e-5,
            "{x:?}, f = {fx:e}"
        );
        // Too small a budget stops early, at the best point seen.
        let (x, fx) = nelder_mead(&rosenbrock, &[-1.2, 1.0], 0.5, 20);
        assert!(fx < rosenbrock(&[-1.2, 1.0]) && fx > 1e-3, "{x:?} {fx}");
    }

    /// A start whose simplex has equal values at every vertex, far from the minimum: the
    /// method must not take equal values for convergence while the simplex is large.
    /// `f = (x(x − 6))² + (y(y − 6))² + (x + y − 3)²` is 9 at (0, 0), (6, 0) and (0, 6); its
    /// minimum, where ∇f = 0, is found and checked by the gradient in closed form.
    #[test]
    fn nelder_mead_does_not_stop_on_a_level_simplex() {
        let f = |x: &[f64]| {
            (x[0] * (x[0] - 6.0)).powi(2)
                + (x[1] * (x[1] - 6.0)).powi(2)
                + (x[0] + x[1] - 3.0).powi(2)
        };
        assert_eq!(
            (f(&[0.0, 0.0]), f(&[6.0, 0.0]), f(&[0.0, 6.0])),
            (9.0, 9.0, 9.0)
        );
        let (x, fx) = nelder_mead(&f, &[0.0, 0.0], 6.0, 2000);
        let gradient = |x: &[f64]| {
            let s = 2.0 * (x[0] + x[1] - 3.0);
            [0, 1].map(|i| 2.0 * x[i] * (x[i] - 6.0) * (2.0 * x[i] - 6.0) + s)
        };
        let g = gradient(&x);
        assert!(
            fx < 9.0 && g[0].abs() < 1e-4 && g[1].abs() < 1e-4,
            "{x:?} {fx} {g:?}"
        );
    }

    /// Nelder–Mead keeps to its budget of evaluations: at most `max_evals + n + 1` (the last
    /// iteration starts one short of the budget and may spend a reflection, a contraction and a
    /// shrink of n points), counted on Rosenbrock's function, which it cannot finish in 50.
    #[test]
    fn nelder_mead_keeps_to_its_budget() {
        let count = std::cell::Cell::new(0usize);
        let rosenbrock = |x: &[f64]| {
            count.set(count.get() + 1);
            (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2)
        };
        for budget in [20, 50] {
            count.set(0);
            let (_, fx) = nelder_mead(&rosenbrock, &[-1.2, 1.0], 0.5, budget);
            assert!(fx > 1e-6, "{fx}");
            assert!(
                count.get() <= budget + 3,
                "{} evaluations for {budget}",
                count.get()
            );
        }
    }

    fn matrix(rows: [[f64; 2]; 2]) -> DenseMatrix {
        DenseMatrix::from_fn(2, 2, |i, j| rows[i][j])
    }

    /// Inside the radius the step is Newton's, `s = −H⁻¹g`; on the boundary `‖s‖ = Δ` and
    /// `(H + λI)s = −g` with `λ ≥ max(0, −λ_min(H))` (the optimality conditions of Moré and
    /// Sorensen), also for an indefinite H.
    #[test]
    fn trust_region_steps_satisfy_the_optimality_conditions() {
        let h = matrix([[4.0, 1.0], [1.0, 3.0]]);
        let g = [1.0, -2.0];
        // H⁻¹ = [[3, −1], [−1, 4]] / 11, so −H⁻¹g = (−5, 9)/11.
        let newton = [-5.0 / 11.0, 9.0 / 11.0];
        let s = trust_region_step(&h, &g, 10.0).unwrap();
        assert!((s[0] - newton[0]).abs() < 1e-15 && (s[1] - newton[1]).abs() < 1e-15);
        // The indefinite one's eigenvalues are (−1 ± √10)/2.
        let indefinite = matrix([[-2.0, 0.5], [0.5, 1.0]]);
        for (h, lam_min) in [(h, 0.0), (indefinite, (-1.0 - 10f64.sqrt()) / 2.0)] {
            for radius in [0.05, 0.3, 0.9] {
                let s = trust_region_step(&h, &g, radius).unwrap();
                assert!((norm(&s) - radius).abs() < 1e-12 * radius, "{s:?}");
                let hs = h.mul_vec(&s);
                // λ from the first component, then the second must agree.
                let lam = -(hs[0] + g[0]) / s[0];
                assert!((hs[1] + g[1] + lam * s[1]).abs() < 1e-9, "λ = {lam}");
                assert!(lam >= -lam_min - 1e-9 && lam >= 0.0, "λ = {lam}");
            }
        }
    }
}
