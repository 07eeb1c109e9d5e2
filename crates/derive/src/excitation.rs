//! The `excitation` derivation (docs/math.md §8.4): the modal fit refined on the D-NURBS modes
//! that the scene's own initial velocity and loads excite. The masses are the modal fit's
//! masses times one scale; the unknowns are `log s_c`, one scale of the modal fit's element
//! constants per element class, and the log mass scale; the residuals, over the `q` most
//! excited modes, are the log ratio of each mode's frequency to that of the MSM mode of best
//! MAC and the difference of their normalized shapes at the nodes, weighted by the square root
//! of the mode's share of the motion, and a pull of each `log s_c` towards 0.
//! Levenberg–Marquardt from the modal fit, then the calibration of the lowest frequency. It
//! can over-fit: scales far from 1, or a much smaller explicit step, are reported as warnings.

use nurbspring_linalg::{
    DenseMatrix, SparseMatrix, cholesky_solve_dense, generalized_eigen_sparse_lowest,
    largest_generalized_eigenvalue,
};
use nurbspring_msm::{Class, Constants};
use nurbspring_sim::StabilityLimit;

use crate::DeriveError;
use crate::evaluation::DnurbsModes;
use crate::modal::{ModalSolution, lowest_frequency};
use crate::nodes::NodeMap;
use crate::outcome::ExcitationReport;
use crate::validation::mac;

/// Modes weighted.
pub const EXCITED_MODES: usize = 8;
/// Constants beyond this factor of the modal fit's (either way) are suspicious.
pub const CONSTANT_RANGE: f64 = 1e3;
/// An explicit step limit this many times smaller than the modal fit's is suspicious.
pub const STEP_SHRINK: f64 = 10.0;
/// Levenberg–Marquardt iterations.
const ITERATIONS: usize = 40;
/// The weight of the rows `log s_c` that keep each class scale near the modal fit's: a 10%
/// change costs as much as a 1% frequency error of a mode carrying the whole motion.
const SCALE_REGULARIZATION: f64 = 0.1;

/// The refined model.
pub struct ExcitationSolution {
    /// The scale of the modal fit's element constants, by class.
    pub scales: Constants,
    /// Calibrated masses of the free nodes.
    pub masses: Vec<f64>,
    /// The report.
    pub report: ExcitationReport,
    /// Signs of over-fitting.
    pub warnings: Vec<String>,
}

/// The squared amplitude of one mode's motion along one direction (docs/math.md §8.4): with
/// `e0 = φᵀ M u₀`, `e1 = φᵀ M v₀` and `g = φᵀ f` of an M-orthonormal mode `φ` of eigenvalue
/// `λ = ω²`, `(e0 − g/λ)² + (e1/ω)²`.
pub(crate) fn amplitude2(e0: f64, e1: f64, g: f64, lambda: f64, omega: f64) -> f64 {
    (e0 - g / lambda).powi(2) + (e1 / omega).powi(2)
}

/// The modes of `L x = ω² diag(m) x`, lowest `count`.
fn msm_modes(
    l: &SparseMatrix,
    masses: &[f64],
    count: usize,
) -> Result<(Vec<f64>, DenseMatrix), DeriveError> {
    let m = SparseMatrix::from_diagonal(masses);
    let tl: f64 = l.diagonal().iter().sum();
    let shift = -1e-6 * tl / masses.iter().sum::<f64>();
    let e = generalized_eigen_sparse_lowest(l, &m, count, shift)?;
    Ok((
        e.values.iter().map(|v| v.max(0.0).sqrt()).collect(),
        e.vectors,
    ))
}

/// The largest angular frequency of `L x = ω² diag(m) x` (Lanczos on `diag(m)⁻¹ L`).
fn highest_frequency(l: &SparseMatrix, masses: &[f64]) -> Result<f64, DeriveError> {
    let top = largest_generalized_eigenvalue(l, &SparseMatrix::from_diagonal(masses), 1e-10)?;
    Ok(top.max(0.0).sqrt())
}

/// The excitation-aware refinement of `modal`: `classes` with `stiffness`, each class's
/// stiffness on the free nodes with the modal fit's element constants.
pub fn excitation_fit(
    modes: &DnurbsModes,
    map: &NodeMap,
    classes: &[Class],
    stiffness: &[SparseMatrix],
    modal: &ModalSolution,
    reference: &[f64],
) -> Result<ExcitationSolution, DeriveError> {
    let units = stiffness;
    let sys = &modes.system;
    let basis = &modes.basis;
    // Each mode's oscillation amplitude from the initial state and the load.
    let mass_dot = |v: &[[f64; 3]], i: usize| -> [f64; 3] {
        let phi = basis.mode(i);
        let mut mv = vec![[0.0; 3]; v.len()];
        for x in 0..3 {
            let col: Vec<f64> = v.iter().map(|p| p[x]).collect();
            let mut y = vec![0.0; col.len()];
            sys.mass.mul_vec(&col, &mut y);
            for (a, val) in y.into_iter().enumerate() {
                mv[a][x] = val;
            }
        }
        [0, 1, 2].map(|x| phi.iter().zip(&mv).map(|(p, m)| p * m[x]).sum())
    };
    let mut amplitude: Vec<(usize, f64)> = Vec::new();
    for i in 0..basis.len() {
        let (w, l) = (basis.omega[i], basis.lambda[i]);
        if w <= 0.0 {
            continue;
        }
        let (e0, e1) = (mass_dot(&sys.displacement, i), mass_dot(&sys.velocity, i));
        let phi = basis.mode(i);
        let g: [f64; 3] = [0, 1, 2].map(|x| phi.iter().zip(&sys.load).map(|(p, f)| p * f[x]).sum());
        let a2: f64 = (0..3).map(|x| amplitude2(e0[x], e1[x], g[x], l, w)).sum();
        amplitude.push((i, a2));
    }
    let total: f64 = amplitude.iter().map(|a| a.1).sum();
    if total.is_nan() || total <= 0.0 {
        return Err(DeriveError::NoExcitation);
    }
    amplitude.sort_by(|a, b| b.1.total_cmp(&a.1));
    amplitude.truncate(EXCITED_MODES);
    let targets: Vec<(f64, Vec<f64>, f64)> = amplitude
        .iter()
        .map(|&(i, a2)| (basis.omega[i], map.at_nodes(&basis.mode(i)), a2 / total))
        .collect();
    let active: Vec<usize> = (0..classes.len())
        .filter(|&c| units[c].frobenius_norm() > 0.0)
        .collect();
    let active_units: Vec<&SparseMatrix> = active.iter().map(|&c| &units[c]).collect();
    let n = reference.len();
    let count = (2 * EXCITED_MODES).min(n);
    // θ = (log s_c, log s); masses s · m̄.
    let residual = |theta: &[f64]| -> Result<Vec<f64>, DeriveError> {
        let k: Vec<f64> = theta[..active.len()].iter().map(|t| t.exp()).collect();
        let s = theta[active.len()].exp();
        let l = combine(&active_units, &k, n)?;
        let masses: Vec<f64> = modal.masses.iter().map(|m| s * m).collect();
        let (omega, vectors) = msm_modes(&l, &masses, count)?;
        let mut r = Vec::new();
        for (w, shape, share) in &targets {
            let (best, _) = (0..omega.len())
                .map(|j| (j, mac(shape, &vectors.column(j))))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((0, 0.0));
            let weight = share.sqrt();
            r.push(weight * (omega[best].max(f64::MIN_POSITIVE) / w).ln());
            let psi = vectors.column(best);
            let (na, nb) = (norm(shape), norm(&psi));
            let sign = if dot(shape, &psi) < 0.0 { -1.0 } else { 1.0 };
            for (a, b) in shape.iter().zip(&psi) {
                r.push(weight * (a / na - sign * b / nb));
            }
        }
        // The pull of each class scale towards the modal fit's (log 1).
        r.extend(
            theta[..active.len()]
                .iter()
                .map(|t| SCALE_REGULARIZATION * t),
        );
        Ok(r)
    };
    let mut theta: Vec<f64> = vec![0.0; active.len()];
    // The modal fit's masses, scaled.
    theta.push(0.0);
    let mut r = residual(&theta)?;
    let start = norm(&r);
    let mut damping = 1e-3;
    let mut iterations = 0;
    let p = theta.len();
    for _ in 0..ITERATIONS {
        iterations += 1;
        // Forward-difference Jacobian.
        let h = 1e-6;
        let mut jac = DenseMatrix::zeros(r.len(), p);
        for j in 0..p {
            let mut t = theta.clone();
            t[j] += h;
            let rj = residual(&t)?;
            for i in 0..r.len() {
                jac[(i, j)] = (rj[i] - r[i]) / h;
            }
        }
        let jtj = jac.transpose().matmul(&jac);
        let jtr: Vec<f64> = (0..p)
            .map(|j| (0..r.len()).map(|i| jac[(i, j)] * r[i]).sum())
            .collect();
        let mut improved = false;
        for _ in 0..8 {
            let a = DenseMatrix::from_fn(p, p, |i, j| {
                jtj[(i, j)]
                    + if i == j {
                        damping * (jtj[(i, i)] + 1e-12)
                    } else {
                        0.0
                    }
            });
            let rhs: Vec<f64> = jtr.iter().map(|v| -v).collect();
            let Ok(step) = cholesky_solve_dense(&a, &rhs) else {
                damping *= 10.0;
                continue;
            };
            let trial: Vec<f64> = theta
                .iter()
                .zip(&step)
                .map(|(t, s)| t + s.clamp(-2.0, 2.0))
                .collect();
            let rt = residual(&trial)?;
            if norm(&rt) < norm(&r) {
                theta = trial;
                r = rt;
                damping = (damping / 3.0).max(1e-9);
                improved = true;
                break;
            }
            damping *= 10.0;
        }
        if !improved || norm(&jtr) <= 1e-10 * start.max(1e-300) {
            break;
        }
    }
    let k: Vec<f64> = theta[..active.len()].iter().map(|t| t.exp()).collect();
    let s = theta[active.len()].exp();
    let l = combine(&active_units, &k, n)?;
    let mut masses: Vec<f64> = modal.masses.iter().map(|m| s * m).collect();
    let omega1 = lowest_frequency(&l, &masses)?;
    let omega1_dnurbs = modal.report.omega1_dnurbs;
    let mass_scale = (omega1 / omega1_dnurbs).powi(2);
    masses.iter_mut().for_each(|m| *m *= mass_scale);
    let mut scales = Constants::new();
    for &c in classes {
        scales.set(c, 0.0);
    }
    for (&c, &kc) in active.iter().zip(&k) {
        scales.set(classes[c], kc);
    }
    let modal_constants = &modal.report.constants;
    let constants = Constants::from_pairs(
        classes
            .iter()
            .map(|&c| (c, scales.value(c) * modal_constants.value(c))),
    );
    let l_modal = combine(
        &units.iter().collect::<Vec<_>>(),
        &vec![1.0; units.len()],
        n,
    )?;
    let dt_modal =
        StabilityLimit::from_omega_max(highest_frequency(&l_modal, &modal.masses)?).dt_critical;
    let dt_here = StabilityLimit::from_omega_max(highest_frequency(&l, &masses)?).dt_critical;
    let refined: Vec<Class> = active.iter().map(|&c| classes[c]).collect();
    let warnings = overfit_warnings(
        &refined,
        &refined
            .iter()
            .map(|&c| constants.value(c))
            .collect::<Vec<_>>(),
        modal_constants,
        (dt_modal, dt_here),
    );
    Ok(ExcitationSolution {
        report: ExcitationReport {
            classes: refined,
            constants,
            modal_constants: modal_constants.clone(),
            modes: amplitude
                .iter()
                .map(|&(i, a2)| (i + 1, a2 / total))
                .collect(),
            residual: (start, norm(&r)),
            iterations,
            mass_scale,
            dt_critical: (dt_modal, dt_here),
        },
        scales,
        masses,
        warnings,
    })
}

/// The signs of over-fitting: a refined constant `k` of `classes` more than [`CONSTANT_RANGE`]
/// either way from the modal fit's, an explicit step limit `dt.1` more than [`STEP_SHRINK`]
/// times smaller than the modal fit's `dt.0`.
fn overfit_warnings(
    classes: &[Class],
    k: &[f64],
    modal: &Constants,
    (dt_modal, dt_here): (f64, f64),
) -> Vec<String> {
    let mut warnings = Vec::new();
    for (&class, &kc) in classes.iter().zip(k) {
        let k0 = modal.value(class);
        if kc > CONSTANT_RANGE * k0 || kc < k0 / CONSTANT_RANGE {
            warnings.push(format!(
                "the excitation fit moved {} to {kc:.4e}, more than {CONSTANT_RANGE:e}× from the modal fit's {k0:.4e}",
                class.symbol()
            ));
        }
    }
    if dt_here < dt_modal / STEP_SHRINK {
        warnings.push(format!(
            "the excitation fit's explicit step limit {dt_here:.4e} s is more than {STEP_SHRINK}× smaller than the modal fit's {dt_modal:.4e} s"
        ));
    }
    warnings
}

/// `Σ_c k_c L_c`.
fn combine(units: &[&SparseMatrix], k: &[f64], n: usize) -> Result<SparseMatrix, DeriveError> {
    let mut acc = SparseMatrix::zeros(n, n);
    for (u, &kc) in units.iter().zip(k) {
        acc = SparseMatrix::linear_combination(1.0, &acc, kc, u)?;
    }
    Ok(acc)
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
    use crate::modal::tests::chain;
    use nurbspring_msm::{LinearKind, Region};

    /// A warning for each constant beyond 10³ of the modal fit's, up or down, none within;
    /// one for a step limit more than ten times smaller, none for five times.
    #[test]
    fn overfit_warnings_against_their_thresholds() {
        let classes = [
            Class::Linear(LinearKind::SpringU, Region::Interior),
            Class::Linear(LinearKind::SpringV, Region::Interior),
            Class::Linear(LinearKind::BendU, Region::Interior),
        ];
        let modal = Constants::from_pairs(classes.iter().map(|&c| (c, 2.0)));
        let w = overfit_warnings(&classes, &[2.5e3, 1e-3, 1.5e3], &modal, (1.0, 0.2));
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].starts_with("the excitation fit moved spring_u@interior to 2.5000e3"),
            "{w:?}"
        );
        assert!(
            w[1].starts_with("the excitation fit moved spring_v@interior to 1.0000e-3"),
            "{w:?}"
        );
        assert!(overfit_warnings(&classes, &[1.9e3, 3e-3, 2.0], &modal, (1.0, 0.2)).is_empty());
        let w = overfit_warnings(&classes, &[2.0; 3], &modal, (1.0, 0.05));
        assert_eq!(w.len(), 1);
        assert!(
            w[0].starts_with("the excitation fit's explicit step limit 5.0000e-2 s"),
            "{w:?}"
        );
    }

    /// The fixed-fixed chain's frequencies `2 √(k/m) sin(jπ / (2(n + 1)))`, the lowest few
    /// and the highest, at stiffness scales from 1e-10 to 1e10.
    #[test]
    fn chain_frequencies_at_every_scale() {
        let n = 12;
        let exact = |k: f64, m: f64, j: usize| {
            2.0 * (k / m).sqrt() * (j as f64 * std::f64::consts::PI / (2.0 * (n + 1) as f64)).sin()
        };
        for k in [1e-10, 1.0, 1e10] {
            for m in [1e-3, 1.0] {
                let l = chain(n, k);
                let (omega, vectors) = msm_modes(&l, &vec![m; n], 4).unwrap();
                assert_eq!((omega.len(), vectors.ncols()), (4, 4));
                for (j, w) in omega.iter().enumerate() {
                    let e = exact(k, m, j + 1);
                    assert!(
                        (w - e).abs() < 1e-12 * e,
                        "k {k}, m {m}, mode {j}: {w} vs {e}"
                    );
                }
                let top = highest_frequency(&l, &vec![m; n]).unwrap();
                let e = exact(k, m, n);
                assert!((top - e).abs() < 1e-6 * e, "k {k}, m {m}: {top} vs {e}");
            }
        }
    }
}
