//! The `modal` derivation (docs/math.md §8): class constants and node masses fitted jointly,
//! non-negative, to the lowest D-NURBS modes sampled at the nodes, then one mass scale so the
//! lowest frequency matches exactly.
//!
//! With `Φ_i = Ω_ff φ_i` the i-th D-NURBS mode at the free nodes (`φ_i` M-orthonormal, angular
//! frequency `ω_i`), `L_c` the scalar stiffness of class `c` with unit constant (both on the
//! free nodes) and `m̄` reference masses, the unknowns `z = (k_c, m_n) ≥ 0` minimize
//!
//! `Σ_i ‖Σ_c k_c L_c Φ_i − ω_i² diag(Φ_i) m‖² / ω_i⁴ + Σ_i (Φ_iᵀ diag(m) Φ_i − 1)²
//!  + λ Σ_n (m_n / m̄_n − 1)²`
//!
//! (the eigen-equation residual, the mass normalization of the modes, a weak pull towards the
//! reference masses), with `m_n ≥ MASS_FLOOR · m̄_n`. Then `m ← m (ω₁^S/ω₁^D)²` with `ω₁^S` the lowest
//! frequency of `L x = ω² diag(m) x`, `L = Σ_c k_c L_c`.

use nurbspring_linalg::{DenseMatrix, SparseMatrix, generalized_eigen_sparse_lowest};
use nurbspring_msm::{Class, Constants};
use serde::Serialize;

use crate::DeriveError;
use crate::fnnls::BlockQp;

/// Modes fitted.
pub const MODES: usize = 8;
/// Weight of the pull towards the reference masses.
pub const MASS_REGULARIZATION: f64 = 1e-2;
/// Lower bound of a node mass relative to its reference. Near clamped ends the modes barely
/// move the nodes, so the fit can drive their masses towards zero, which shrinks the explicit
/// step limit without helping the fit (measured on a string: a floor of 10⁻³ gave
/// Δt_crit = 0.0024 s, 0.1 gave 0.024 s, rel. RMS 0.006 both; docs/derivations.md).
pub const MASS_FLOOR: f64 = 0.1;

/// One D-NURBS mode sampled at the free nodes.
#[derive(Clone, Debug)]
pub struct SampledMode {
    /// Angular frequency (> 0).
    pub omega: f64,
    /// `Ω_ff φ`, one value per free node.
    pub shape: Vec<f64>,
}

/// What the modal fit reports.
#[derive(Clone, Debug, Serialize)]
pub struct ModalFitReport {
    /// Classes fitted (those with stiffness on the free nodes).
    pub classes: Vec<Class>,
    /// Their constants (zero is normal: the fit's solution is sparse).
    pub constants: Constants,
    /// D-NURBS modes fitted.
    pub modes: usize,
    /// Their angular frequencies.
    pub mode_frequencies: Vec<f64>,
    /// `λ` of the mass regularization.
    pub mass_regularization: f64,
    /// `√(Σ_i ‖Σ_c k_c L_c Φ_i/ω_i² − diag(Φ_i) m‖²) / √(Σ_i ‖diag(Φ_i) m‖²)` before the
    /// calibration.
    pub relative_residual: f64,
    /// Lowest angular frequency of the D-NURBS.
    pub omega1_dnurbs: f64,
    /// Lowest angular frequency of the MSM before the calibration.
    pub omega1_fitted: f64,
    /// The calibration factor `(ω₁^S/ω₁^D)²` applied to every mass.
    pub mass_scale: f64,
}

/// The fitted constants and free-node masses.
pub struct ModalSolution {
    /// Constants by class.
    pub constants: Constants,
    /// One mass per free node, calibrated.
    pub masses: Vec<f64>,
    /// The report.
    pub report: ModalFitReport,
}

/// `L_c x` for a scalar matrix and a vector.
fn mul(a: &SparseMatrix, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    a.mul_vec(x, &mut y);
    y
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The lowest angular frequency of `L x = ω² diag(m) x`.
pub fn lowest_frequency(l: &SparseMatrix, masses: &[f64]) -> Result<f64, DeriveError> {
    let m = SparseMatrix::from_diagonal(masses);
    let tl: f64 = l.diagonal().iter().sum();
    let tm: f64 = masses.iter().sum();
    let shift = if tl > 0.0 { -1e-6 * tl / tm } else { -1.0 };
    let e = generalized_eigen_sparse_lowest(l, &m, 1, shift)?;
    Ok(e.values.first().copied().unwrap_or(0.0).max(0.0).sqrt())
}

/// The modal fit of `classes` (their scalar unit matrices `units` on the free nodes) to
/// `modes`, with reference masses `reference` (free nodes), then the calibration.
pub fn modal_fit(
    classes: &[Class],
    units: &[SparseMatrix],
    modes: &[SampledMode],
    reference: &[f64],
) -> Result<ModalSolution, DeriveError> {
    let n = reference.len();
    if modes.is_empty() {
        return Err(DeriveError::InvalidOption {
            name: "fit.derivation",
            value: "\"modal\"".into(),
            reason: "the D-NURBS has no elastic mode to fit (no stiffness, or nothing fixed)"
                .into(),
        });
    }
    // Keep the classes that act on the free nodes.
    let keep: Vec<usize> = (0..classes.len())
        .filter(|&c| units[c].frobenius_norm() > 0.0)
        .collect();
    if keep.is_empty() {
        return Err(DeriveError::InvalidOption {
            name: "msm.elements",
            value: format!("{} classes", classes.len()),
            reason: "no element class has stiffness on the free nodes".into(),
        });
    }
    let c = keep.len();
    let floor: Vec<f64> = reference.iter().map(|m| MASS_FLOOR * m).collect();
    // a[c][i] = L_c Φ_i / ω_i² over the free nodes.
    let a: Vec<Vec<Vec<f64>>> = keep
        .iter()
        .map(|&cl| {
            modes
                .iter()
                .map(|m| {
                    mul(&units[cl], &m.shape)
                        .into_iter()
                        .map(|v| v / (m.omega * m.omega))
                        .collect()
                })
                .collect()
        })
        .collect();
    let hkk = DenseMatrix::from_fn(c, c, |p, q| {
        (0..modes.len()).map(|i| dot(&a[p][i], &a[q][i])).sum()
    });
    let hkm = DenseMatrix::from_fn(c, n, |p, node| {
        -(0..modes.len())
            .map(|i| a[p][i][node] * modes[i].shape[node])
            .sum::<f64>()
    });
    let lambda = MASS_REGULARIZATION;
    let d: Vec<f64> = (0..n)
        .map(|node| {
            modes.iter().map(|m| m.shape[node].powi(2)).sum::<f64>()
                + lambda / (reference[node] * reference[node])
        })
        .collect();
    let s = DenseMatrix::from_fn(modes.len(), n, |i, node| modes[i].shape[node].powi(2));
    let s_fl: Vec<f64> = (0..modes.len())
        .map(|i| (0..n).map(|node| s[(i, node)] * floor[node]).sum())
        .collect();
    let mut g = vec![0.0; c + n];
    for p in 0..c {
        g[p] = (0..modes.len())
            .map(|i| {
                (0..n)
                    .map(|node| a[p][i][node] * modes[i].shape[node] * floor[node])
                    .sum::<f64>()
            })
            .sum();
    }
    for node in 0..n {
        let mut v = 0.0;
        for (i, m) in modes.iter().enumerate() {
            let phi2 = m.shape[node].powi(2);
            v += -phi2 * floor[node] + phi2 * (1.0 - s_fl[i]);
        }
        v += lambda / reference[node] * (1.0 - floor[node] / reference[node]);
        g[c + node] = v;
    }
    // Scale every unknown so that the diagonal of H is 1.
    let diag: Vec<f64> = (0..c)
        .map(|p| hkk[(p, p)])
        .chain(
            (0..n)
                .map(|node| d[node] + (0..modes.len()).map(|i| s[(i, node)].powi(2)).sum::<f64>()),
        )
        .collect();
    let scale: Vec<f64> = diag
        .iter()
        .map(|&h| if h > 0.0 { 1.0 / h.sqrt() } else { 1.0 })
        .collect();
    let qp = BlockQp {
        hkk: DenseMatrix::from_fn(c, c, |p, q| scale[p] * hkk[(p, q)] * scale[q]),
        hkm: DenseMatrix::from_fn(c, n, |p, node| scale[p] * hkm[(p, node)] * scale[c + node]),
        d: (0..n)
            .map(|node| d[node] * scale[c + node].powi(2))
            .collect(),
        s: DenseMatrix::from_fn(modes.len(), n, |i, node| s[(i, node)] * scale[c + node]),
        g: g.iter().zip(&scale).map(|(g, s)| g * s).collect(),
    };
    let mut start = vec![0.0; c + n];
    for node in 0..n {
        start[c + node] = (reference[node] - floor[node]) / scale[c + node];
    }
    let y = qp.solve_nonnegative(start)?;
    let k: Vec<f64> = (0..c).map(|p| y[p] * scale[p]).collect();
    let mut masses: Vec<f64> = (0..n)
        .map(|node| floor[node] + y[c + node] * scale[c + node])
        .collect();
    // The residual of the eigen-equations before the calibration.
    let l = combine(
        &keep.iter().map(|&cl| &units[cl]).collect::<Vec<_>>(),
        &k,
        n,
    )?;
    let (mut num, mut den) = (0.0, 0.0);
    for m in modes {
        let lp = mul(&l, &m.shape);
        for node in 0..n {
            let target = m.shape[node] * masses[node];
            num += (lp[node] / (m.omega * m.omega) - target).powi(2);
            den += target * target;
        }
    }
    let omega1_dnurbs = modes[0].omega;
    let omega1_fitted = lowest_frequency(&l, &masses)?;
    if omega1_fitted <= 0.0 {
        return Err(DeriveError::InvalidOption {
            name: "fit.derivation",
            value: "\"modal\"".into(),
            reason: "the fitted lattice has no stiffness on its free nodes (every constant is 0)"
                .into(),
        });
    }
    let mass_scale = (omega1_fitted / omega1_dnurbs).powi(2);
    masses.iter_mut().for_each(|m| *m *= mass_scale);
    let fitted: Vec<Class> = keep.iter().map(|&cl| classes[cl]).collect();
    let mut constants = Constants::from_values(&fitted, &k);
    // Classes without stiffness on the free nodes carry no constant.
    for (cl, &class) in classes.iter().enumerate() {
        if !keep.contains(&cl) {
            constants.set(class, 0.0);
        }
    }
    Ok(ModalSolution {
        report: ModalFitReport {
            classes: fitted,
            constants: constants.clone(),
            modes: modes.len(),
            mode_frequencies: modes.iter().map(|m| m.omega).collect(),
            mass_regularization: lambda,
            relative_residual: (num / den.max(f64::MIN_POSITIVE)).sqrt(),
            omega1_dnurbs,
            omega1_fitted,
            mass_scale,
        },
        constants,
        masses,
    })
}

/// `Σ_c k_c L_c`.
pub(crate) fn combine(
    units: &[&SparseMatrix],
    k: &[f64],
    n: usize,
) -> Result<SparseMatrix, DeriveError> {
    let mut acc = SparseMatrix::zeros(n, n);
    for (u, &kc) in units.iter().zip(k) {
        acc = SparseMatrix::linear_combination(1.0, &acc, kc, u)?;
    }
    Ok(acc)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use nurbspring_linalg::nonnegative_least_squares;
    use nurbspring_msm::{LinearKind, Region};

    /// A tiny problem whose least-squares matrix is written out: the structured solve must
    /// land on the dense NNLS optimum of the same objective.
    #[test]
    fn structured_nnls_matches_dense_nnls() {
        let n = 6;
        let mut seed = 3u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        // Three classes: random symmetric positive semi-definite scalar matrices.
        let mut units = Vec::new();
        for _ in 0..3 {
            let v: Vec<f64> = (0..n).map(|_| rnd()).collect();
            let w: Vec<f64> = (0..n).map(|_| rnd()).collect();
            let mut t = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    t.push((
                        i,
                        j,
                        v[i] * v[j] + 0.5 * w[i] * w[j] + if i == j { 0.2 } else { 0.0 },
                    ));
                }
            }
            units.push(SparseMatrix::from_triplets(n, n, &t).unwrap());
        }
        let classes = vec![
            Class::Linear(LinearKind::SpringU, Region::Interior),
            Class::Linear(LinearKind::BendU, Region::Interior),
            Class::Linear(LinearKind::Twist, Region::Boundary),
        ];
        let modes: Vec<SampledMode> = (0..3)
            .map(|i| SampledMode {
                omega: 1.0 + i as f64,
                shape: (0..n).map(|_| rnd()).collect(),
            })
            .collect();
        let reference: Vec<f64> = (0..n).map(|_| 1.0 + 0.5 * rnd()).collect();
        let sol = modal_fit(&classes, &units, &modes, &reference).unwrap();
        // Undo the calibration to compare with the raw optimum.
        let k = sol.constants.values_of(&classes);
        let m_raw: Vec<f64> = sol
            .masses
            .iter()
            .map(|m| m / sol.report.mass_scale)
            .collect();
        // Dense formulation in z = (k, m − floor).
        let floor: Vec<f64> = reference.iter().map(|m| MASS_FLOOR * m).collect();
        let c = classes.len();
        let mut rows: Vec<Vec<f64>> = Vec::new();
        let mut rhs = Vec::new();
        for m in &modes {
            let a: Vec<Vec<f64>> = units
                .iter()
                .map(|u| {
                    mul(u, &m.shape)
                        .iter()
                        .map(|v| v / (m.omega * m.omega))
                        .collect()
                })
                .collect();
            for node in 0..n {
                let mut r = vec![0.0; c + n];
                for p in 0..c {
                    r[p] = a[p][node];
                }
                r[c + node] = -m.shape[node];
                rows.push(r);
                rhs.push(m.shape[node] * floor[node]);
            }
        }
        for m in &modes {
            let mut r = vec![0.0; c + n];
            let mut b = 1.0;
            for node in 0..n {
                r[c + node] = m.shape[node].powi(2);
                b -= m.shape[node].powi(2) * floor[node];
            }
            rows.push(r);
            rhs.push(b);
        }
        let sl = MASS_REGULARIZATION.sqrt();
        for node in 0..n {
            let mut r = vec![0.0; c + n];
            r[c + node] = sl / reference[node];
            rows.push(r);
            rhs.push(sl * (1.0 - floor[node] / reference[node]));
        }
        let a = DenseMatrix::from_fn(rows.len(), c + n, |i, j| rows[i][j]);
        let z = nonnegative_least_squares(&a, &rhs).unwrap();
        let objective = |z: &[f64]| -> f64 {
            rows.iter()
                .zip(&rhs)
                .map(|(r, b)| (dot(r, z) - b).powi(2))
                .sum()
        };
        let mut mine = k.clone();
        mine.extend(m_raw.iter().zip(&floor).map(|(m, f)| m - f));
        let (o_mine, o_ref) = (objective(&mine), objective(&z));
        assert!(
            o_mine <= o_ref * (1.0 + 1e-10) + 1e-14,
            "{o_mine} vs {o_ref}"
        );
        for (x, y) in mine.iter().zip(&z) {
            assert!((x - y).abs() <= 1e-7 * (1.0 + y.abs()), "{mine:?} vs {z:?}");
        }
    }

    /// `k · tridiag(−1, 2, −1)` of a chain of `n` nodes between two fixed ends.
    pub(crate) fn chain(n: usize, k: f64) -> SparseMatrix {
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 2.0 * k));
            if i + 1 < n {
                t.push((i, i + 1, -k));
                t.push((i + 1, i, -k));
            }
        }
        SparseMatrix::from_triplets(n, n, &t).unwrap()
    }

    /// Without stiffness the lowest frequency is 0 (no shift of 0 is tried on a zero matrix).
    #[test]
    fn no_stiffness_has_a_zero_lowest_frequency() {
        let l =
            SparseMatrix::from_triplets(3, 3, &[(0, 0, 0.0), (1, 1, 0.0), (2, 2, 0.0)]).unwrap();
        assert_eq!(lowest_frequency(&l, &[1.0, 2.0, 3.0]).unwrap(), 0.0);
    }

    /// The fixed-fixed chain's lowest frequency `2 √(k/m) sin(π / (2(n + 1)))` at stiffness
    /// scales from 1e-10 to 1e10: the shift of the shift-invert solve must follow the scale of
    /// `L` (a fixed shift of −1 cannot resolve eigenvalues of 1e-10 against 1). The chain is
    /// long enough that the Krylov space does not cover it.
    #[test]
    fn the_lowest_frequency_of_a_chain_at_every_scale() {
        let n = 300;
        for k in [1e-10, 1.0, 1e10] {
            for m in [1e-3, 1.0] {
                let w = lowest_frequency(&chain(n, k), &vec![m; n]).unwrap();
                let exact =
                    2.0 * (k / m).sqrt() * (std::f64::consts::PI / (2.0 * (n + 1) as f64)).sin();
                assert!(
                    (w - exact).abs() < 1e-12 * exact,
                    "k {k}, m {m}: {w} vs {exact}"
                );
            }
        }
    }
}
