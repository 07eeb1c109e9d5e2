//! The `modal` derivation (the default; docs/math.md §8.3): the constants of the linear
//! elements and the node masses fitted, non-negative, to the D-NURBS modes the lattice
//! resolves, then one mass scale so that the lowest frequency matches exactly.
//!
//! Every element `e` has a *consistent* constant `k⁰_e` (the D-NURBS coefficient it stands
//! for, corrected for the leading error of its stencil on a uniform lattice; 0 for a kind the
//! material has no term for) and a scale `σ_e` (`k⁰_e`, or where it is 0 the size such an
//! element would have at the lattice's spacing), [`element_priors`]. The fit scales the
//! constants of each *group* (an element kind in one band of the lattice: the first
//! [`RINGS`] lines from an edge, or the inside, in each direction, [`FitGroup`]) by one
//! factor, `k_e = y_g σ_e`, `y_g ≥ 0` (its consistent value `y⁰_g` is 1, or 0), and each
//! free node's mass `m̄_n` by `x_n ≥ MASS_FLOOR`. With `Φ_i` the i-th fitted D-NURBS mode at
//! the free nodes (`λ_i = ω_i²`), `L(y) = Σ_e y_{g(e)} σ_e w_e c_e c_eᵀ` and `m = m̄ ∘ x`,
//! they minimize
//!
//! `Σ_i ‖L Φ_i − λ_i m ∘ Φ_i‖² / ‖λ_i m̄ ∘ Φ_i‖²`                      (the eigen-equations)
//! `+ W_f² Σ_i (Φ_iᵀ L Φ_i − λ_i Φ_iᵀ (m ∘ Φ_i))² / (λ_i Φ_iᵀ (m̄ ∘ Φ_i))²`  (the Rayleigh quotients;
//!   over a repeated frequency, every entry `Φ_iᵀ (L − λ m) Φ_j` of its block)
//! `+ W_t² (Σ_n m_n / Σ_n m̄_n − 1)²`                                    (the total mass)
//! `+ λ_k Σ_g (y_g − y⁰_g)² + λ_m Σ_n (x_n − 1)²`                      (the consistent model)
//!
//! Then `m ← m (ω₁^S/ω₁^D)²` with `ω₁^S` the lowest frequency of `L x = ω² diag(m) x`.

use std::collections::BTreeMap;

use nurbspring_linalg::{
    DenseMatrix, SparseMatrix, cholesky_solve_dense_columns, generalized_eigen_sparse_lowest,
};
use nurbspring_msm::{Class, Constants, LinearKind, SpringLattice};
use serde::Serialize;

use crate::error::{DeriveError, Input};
use crate::fnnls::BlockQp;
use crate::modal_solution::ModalBasis;
use crate::validation::match_modes;

mod priors;
use priors::*;
pub use priors::{ElementPrior, element_priors, modes_within, resolved_modes};

/// Lines from each edge of the lattice whose elements form groups of their own: the
/// Greville abscissae of a cubic are uneven over the first three, and a clamp (two fixed
/// rings) is carried there.
pub const RINGS: usize = 3;
/// At most this many D-NURBS modes are fitted: a fixed set of low modes, which a finer
/// lattice resolves better (a cap growing with the lattice keeps each mode's accuracy
/// where it is; measured in docs/derivations.md).
pub const FITTED_MODES: usize = 80;
/// Every mode with at most this many half-waves along each direction is fitted, however few
/// lines the lattice has (all of them on a lattice with fewer free lines).
pub const MIN_HALF_WAVES: usize = 3;
/// `W_f`: the weight of the Rayleigh-quotient rows. A relative frequency error ε costs about
/// `ε ω T/√6` of relative RMS over a horizon T, so the frequencies must be matched far more
/// closely than the shapes.
pub const FREQUENCY_WEIGHT: f64 = 100.0;
/// `W_t`: the weight of the total mass (the rows above are homogeneous in `(y, x)`: without
/// it the regularization would shrink both).
pub const TOTAL_MASS_WEIGHT: f64 = 100.0;
/// `λ_k`: the pull of each group factor towards its consistent value (1, or 0 for a kind
/// the material has no term for). Weak: on coarse lattices the boundary groups must move
/// far from the consistent constants (docs/derivations.md).
pub const CONSTANT_REGULARIZATION: f64 = 1e-5;
/// `λ_m`: the pull of each node mass towards its reference.
pub const MASS_REGULARIZATION: f64 = 1e-2;
/// Lower bound of a node mass relative to its reference. Near clamped ends the modes barely
/// move the nodes, so the fit could drive their masses towards zero, which shrinks the
/// explicit step limit without helping the fit.
pub const MASS_FLOOR: f64 = 0.1;
/// The fitted set is widened (one half-wave more along u or v) only while the MSM still
/// reproduces every fitted mode to this relative frequency error.
pub const ACCEPTED_MODE_ERROR: f64 = 1e-3;
/// Two modes whose frequencies differ by less than this (relative) are one repeated
/// frequency: they are fitted together or not at all.
pub const REPEATED: f64 = 1e-6;

/// One D-NURBS mode sampled at the free nodes.
#[derive(Clone, Debug)]
pub struct SampledMode {
    /// Angular frequency (> 0).
    pub omega: f64,
    /// `Ω_ff φ`, one value per free node.
    pub shape: Vec<f64>,
}

/// Where an element sits along one direction of the lattice: within the first [`RINGS`]
/// lines from the low or the high edge (the line index counted from that edge), or inside.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Band {
    /// Its lowest line is `d < RINGS` from the low edge.
    Low(usize),
    /// Its highest line is `d < RINGS` from the high edge (and it is not `Low`).
    High(usize),
    /// Neither.
    Inside,
}

impl Band {
    /// The band of an element spanning lines `lo..=hi` of `n`.
    pub fn of(lo: usize, hi: usize, n: usize) -> Band {
        if lo < RINGS {
            Band::Low(lo)
        } else if hi + RINGS >= n {
            Band::High(n - 1 - hi)
        } else {
            Band::Inside
        }
    }

    pub(crate) fn name(self, axis: char) -> String {
        match self {
            Band::Low(d) => format!("{axis}{d}"),
            Band::High(d) => format!("{axis}-{d}"),
            Band::Inside => format!("{axis}in"),
        }
    }
}

/// The elements whose constants share one factor: one kind in one band along u and v.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct FitGroup {
    /// The element kind.
    pub kind: LinearKind,
    /// Its band along u.
    pub u: Band,
    /// Its band along v (always `Low(0)` on a chain).
    pub v: Band,
}

impl FitGroup {
    /// `"bend_u[u0,vin]"`: the kind, then the bands (`u0`…`u2` from the low edge, `u-0`…
    /// `u-2` from the high one, `uin` inside).
    pub fn name(&self) -> String {
        format!(
            "{}[{},{}]",
            self.kind.name(),
            self.u.name('u'),
            self.v.name('v')
        )
    }
}

/// One group of the fit.
#[derive(Clone, Debug, Serialize)]
pub struct GroupFit {
    /// [`FitGroup::name`].
    pub group: String,
    /// Its elements.
    pub elements: usize,
    /// The mean consistent constant of its elements (0: the material has no such term).
    pub consistent: f64,
    /// The fitted factor `y_g` (element constants are `y_g σ_e`).
    pub factor: f64,
}

/// What the modal fit reports.
#[derive(Clone, Debug, Serialize)]
pub struct ModalFitReport {
    /// The element classes the model keeps (with an element of positive constant).
    pub classes: Vec<Class>,
    /// The mean constant of each class's elements in the model (every element's own is in
    /// `msm.json`).
    pub constants: Constants,
    /// The groups, their consistent constants and factors.
    pub groups: Vec<GroupFit>,
    /// D-NURBS modes fitted.
    pub modes: usize,
    /// Their ranks among the D-NURBS modes (1 = lowest).
    pub fitted_modes: Vec<usize>,
    /// Their angular frequencies.
    pub mode_frequencies: Vec<f64>,
    /// The most half-waves along u and v of a fitted mode.
    pub half_waves: [usize; 2],
    /// `λ_m`.
    pub mass_regularization: f64,
    /// `λ_k`.
    pub constant_regularization: f64,
    /// `W_f`.
    pub frequency_weight: f64,
    /// `√(Σ_i ‖L Φ_i/ω_i² − m ∘ Φ_i‖²) / √(Σ_i ‖m ∘ Φ_i‖²)` over the fitted modes before the
    /// calibration.
    pub relative_residual: f64,
    /// The root mean square over the fitted modes of `Φ_iᵀ L Φ_i / (ω_i² Φ_iᵀ (m ∘ Φ_i)) − 1`
    /// (relative error of the Rayleigh quotients) before the calibration.
    pub frequency_residual: f64,
    /// Lowest angular frequency of the D-NURBS.
    pub omega1_dnurbs: f64,
    /// Lowest angular frequency of the MSM before the calibration.
    pub omega1_fitted: f64,
    /// The calibration factor `(ω₁^S/ω₁^D)²` applied to every mass.
    pub mass_scale: f64,
    /// The largest relative frequency error, after the calibration, of a fitted mode against
    /// the MSM mode matched to it by MAC.
    pub worst_fitted_mode: f64,
}

/// The fitted element constants and free-node masses.
pub struct ModalSolution {
    /// One constant per element of the lattice (0: not fitted).
    pub constants: Vec<f64>,
    /// One mass per free node, calibrated.
    pub masses: Vec<f64>,
    /// The modes of the fitted model on the free nodes (those the validation runs).
    pub basis: ModalBasis,
    /// The report.
    pub report: ModalFitReport,
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

/// One element in the fit: its group, `σ_e w_e`, and its (free node, coefficient) pairs.
struct Fitted {
    element: usize,
    group: usize,
    scale: f64,
    nodes: Vec<(usize, f64)>,
}

/// The modal fit (module docs) of the elements of `lattice` with their priors (one per
/// element, [`element_priors`]) to the modes of `candidates` the lattice resolves
/// ([`resolved_modes`]), with reference masses `reference` of the free nodes `free`
/// (ascending lattice indices), then the calibration.
pub fn modal_fit(
    lattice: &SpringLattice,
    free: &[usize],
    priors: &[ElementPrior],
    candidates: &[SampledMode],
    reference: &[f64],
) -> Result<ModalSolution, DeriveError> {
    let refused = |reason: &str| DeriveError::InvalidInput {
        input: Input::Derivation,
        value: "\"modal\"".into(),
        reason: reason.to_string(),
    };
    if candidates.is_empty() {
        return Err(refused(
            "the D-NURBS has no elastic mode to fit (no stiffness, or nothing fixed)",
        ));
    }
    let mut position = vec![usize::MAX; lattice.n_nodes()];
    for (p, &a) in free.iter().enumerate() {
        position[a] = p;
    }
    let grid = lattice.grid.unwrap_or((lattice.n_nodes(), 1));
    let line = |a: usize| (a / grid.1, a % grid.1);
    // The elements with a scale that act on a free node, by group.
    let mut groups: BTreeMap<FitGroup, usize> = BTreeMap::new();
    let mut fitted: Vec<Fitted> = Vec::new();
    for (element, e) in lattice.elements.iter().enumerate() {
        let nodes: Vec<(usize, f64)> = e
            .nodes
            .iter()
            .zip(&e.coefficients)
            .filter(|&(&a, &c)| position[a] != usize::MAX && c != 0.0)
            .map(|(&a, &c)| (position[a], c))
            .collect();
        if priors[element].scale <= 0.0 || nodes.is_empty() {
            continue;
        }
        let (us, vs): (Vec<usize>, Vec<usize>) = e.nodes.iter().map(|&a| line(a)).unzip();
        let span = |t: &[usize]| (*t.iter().min().unwrap_or(&0), *t.iter().max().unwrap_or(&0));
        let ((ulo, uhi), (vlo, vhi)) = (span(&us), span(&vs));
        let key = FitGroup {
            kind: e.kind,
            u: Band::of(ulo, uhi, grid.0),
            v: Band::of(vlo, vhi, grid.1),
        };
        let next = groups.len();
        let group = *groups.entry(key).or_insert(next);
        fitted.push(Fitted {
            element,
            group,
            scale: priors[element].scale * e.weight,
            nodes,
        });
    }
    if fitted.is_empty() {
        return Err(DeriveError::InvalidInput {
            input: Input::Elements,
            value: format!("{} elements", lattice.elements.len()),
            reason: "no element acts on a free node, or the material has no stiffness".into(),
        });
    }
    let problem = Problem {
        lattice,
        free,
        priors,
        reference,
        fitted,
        groups,
    };
    let lines = free_lines(grid, free);
    let (selected, mut k) = resolved_modes(grid, free, candidates);
    let mut best = problem.fit(candidates, &selected, k)?;
    // Widen the fitted set, one half-wave along u or v at a time, while the wider fit still
    // reproduces every mode it fits (docs/math.md §8.3).
    loop {
        let mut widened: Option<(ModalSolution, [usize; 2])> = None;
        for axis in 0..2 {
            let mut wider = k;
            wider[axis] += 1;
            if wider[axis] > lines[axis] {
                continue;
            }
            let selected = modes_within(grid, free, candidates, wider);
            if selected.len() <= best.report.modes {
                continue;
            }
            let trial = problem.fit(candidates, &selected, wider)?;
            if trial.report.worst_fitted_mode <= ACCEPTED_MODE_ERROR
                && widened
                    .as_ref()
                    .is_none_or(|(w, _)| trial.report.modes > w.report.modes)
            {
                widened = Some((trial, wider));
            }
        }
        match widened {
            Some((trial, wider)) => {
                best = trial;
                k = wider;
            }
            None => return Ok(best),
        }
    }
}

/// The fit's fixed parts: the elements with a scale acting on a free node, by group.
struct Problem<'a> {
    lattice: &'a SpringLattice,
    free: &'a [usize],
    priors: &'a [ElementPrior],
    reference: &'a [f64],
    fitted: Vec<Fitted>,
    groups: BTreeMap<FitGroup, usize>,
}

impl Problem<'_> {
    /// The fit to the modes `selected` of `candidates` (ranks), with half-wave bounds `k`,
    /// then the calibration and the check of the fitted modes.
    fn fit(
        &self,
        candidates: &[SampledMode],
        selected: &[usize],
        half_waves: [usize; 2],
    ) -> Result<ModalSolution, DeriveError> {
        let Problem {
            lattice,
            free,
            priors,
            reference,
            fitted,
            groups,
        } = self;
        let (lattice, priors, reference, fitted) =
            (*lattice, *priors, *reference, fitted.as_slice());
        let n = free.len();
        let refused = |reason: &str| DeriveError::InvalidInput {
            input: Input::Derivation,
            value: "\"modal\"".into(),
            reason: reason.to_string(),
        };
        let c = groups.len();
        let modes: Vec<&SampledMode> = selected.iter().map(|&i| &candidates[i]).collect();
        let r = modes.len();
        // The Rayleigh-quotient rows: one per pair (i, j) of modes of one frequency, so that the
        // rows do not depend on how the eigensolver rotated a repeated pair.
        let mut pairs: Vec<(usize, usize)> = Vec::new();
        let mut first = 0;
        for i in 0..r {
            if (modes[i].omega - modes[first].omega).abs() > REPEATED * modes[i].omega {
                first = i;
            }
            pairs.extend((first..=i).map(|j| (j, i)));
        }
        // Normal equations of the rows in the module docs, unknowns (y, x).
        let lambda_k = CONSTANT_REGULARIZATION;
        let lambda_m = MASS_REGULARIZATION;
        let mut hkk = DenseMatrix::zeros(c, c);
        let mut hkm = DenseMatrix::zeros(c, n);
        let mut d = vec![lambda_m; n];
        // The rows of the mass block beyond its diagonal: the Rayleigh quotients, the total.
        let rows = pairs.len();
        let mut s = DenseMatrix::zeros(rows + 1, n);
        // y⁰: 1 for a group whose elements have consistent constants, else 0.
        let mut gk = vec![0.0; c];
        for el in fitted {
            if priors[el.element].consistent > 0.0 {
                gk[el.group] = lambda_k;
            }
        }
        let mut gm = vec![lambda_m; n];
        let mut at_node: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for (f, el) in fitted.iter().enumerate() {
            for &(p, coefficient) in &el.nodes {
                at_node[p].push((f, coefficient));
            }
        }
        let strains: Vec<Vec<f64>> = modes
            .iter()
            .map(|mode| {
                fitted
                    .iter()
                    .map(|el| el.nodes.iter().map(|&(p, cf)| cf * mode.shape[p]).sum())
                    .collect()
            })
            .collect();
        for (row, &(i, j)) in pairs.iter().enumerate() {
            let lambda = modes[j].omega * modes[j].omega;
            let (phi, psi) = (&modes[i].shape, &modes[j].shape);
            let scale: f64 = lambda
                * (0..n)
                    .map(|p| reference[p] * 0.5 * (phi[p] * phi[p] + psi[p] * psi[p]))
                    .sum::<f64>();
            // Off-diagonal entries count twice in the Frobenius norm of the pair's block.
            let w = FREQUENCY_WEIGHT / scale * if i == j { 1.0 } else { 2.0_f64.sqrt() };
            let mut f = vec![0.0; c];
            for (e, el) in fitted.iter().enumerate() {
                f[el.group] += w * el.scale * strains[i][e] * strains[j][e];
            }
            for p in 0..n {
                s[(row, p)] = -w * lambda * reference[p] * phi[p] * psi[p];
            }
            for g in 0..c {
                for h in 0..c {
                    hkk[(g, h)] += f[g] * f[h];
                }
                for p in 0..n {
                    hkm[(g, p)] += f[g] * s[(row, p)];
                }
            }
        }
        let mut a_row = vec![0.0; c];
        let mut touched: Vec<usize> = Vec::new();
        let mut marked = vec![false; c];
        for (mode, strain) in modes.iter().zip(&strains) {
            let lambda = mode.omega * mode.omega;
            let phi = &mode.shape;
            let eigen_scale: f64 = (0..n)
                .map(|p| (lambda * reference[p] * phi[p]).powi(2))
                .sum();
            // The eigen-equation rows, node by node.
            let inv = 1.0 / eigen_scale;
            for p in 0..n {
                for &(e, coefficient) in &at_node[p] {
                    let g = fitted[e].group;
                    if !marked[g] {
                        marked[g] = true;
                        touched.push(g);
                    }
                    a_row[g] += fitted[e].scale * coefficient * strain[e];
                }
                let mass = -lambda * reference[p] * phi[p];
                for &g in &touched {
                    for &h in &touched {
                        hkk[(g, h)] += inv * a_row[g] * a_row[h];
                    }
                    hkm[(g, p)] += inv * a_row[g] * mass;
                }
                d[p] += inv * mass * mass;
                for &g in &touched {
                    a_row[g] = 0.0;
                    marked[g] = false;
                }
                touched.clear();
            }
        }
        for g in 0..c {
            hkk[(g, g)] += lambda_k;
        }
        let total: f64 = reference.iter().sum();
        for p in 0..n {
            let e = TOTAL_MASS_WEIGHT * reference[p] / total;
            s[(rows, p)] = e;
            gm[p] += TOTAL_MASS_WEIGHT * e;
        }
        let (y, x) = solve_with_floor(&hkk, &hkm, &d, &s, &gk, &gm)?;
        // The element constants and the masses before the calibration.
        let mut constants = vec![0.0; lattice.elements.len()];
        for el in fitted {
            constants[el.element] = priors[el.element].scale * y[el.group];
        }
        let mut masses: Vec<f64> = reference.iter().zip(&x).map(|(m, x)| m * x).collect();
        let mut triplets = Vec::new();
        for el in fitted {
            let k = y[el.group] * el.scale;
            for &(p, cp) in &el.nodes {
                for &(q, cq) in &el.nodes {
                    triplets.push((p, q, k * cp * cq));
                }
            }
        }
        let l = SparseMatrix::from_triplets(n, n, &triplets)?;
        let (mut num, mut den, mut rayleigh) = (0.0, 0.0, 0.0);
        for mode in &modes {
            let lambda = mode.omega * mode.omega;
            let mut lp = vec![0.0; n];
            l.mul_vec(&mode.shape, &mut lp);
            let mut quotient_den = 0.0;
            for p in 0..n {
                let target = mode.shape[p] * masses[p];
                num += (lp[p] / lambda - target).powi(2);
                den += target * target;
                quotient_den += target * mode.shape[p];
            }
            rayleigh += (dot(&lp, &mode.shape) / (lambda * quotient_den) - 1.0).powi(2);
        }
        let omega1_dnurbs = candidates[0].omega;
        let omega1_fitted = lowest_frequency(&l, &masses)?;
        if omega1_fitted <= 0.0 {
            return Err(refused(
                "the fitted lattice has no stiffness on its free nodes (every constant is 0)",
            ));
        }
        let mass_scale = (omega1_fitted / omega1_dnurbs).powi(2);
        masses.iter_mut().for_each(|m| *m *= mass_scale);
        // Reports by group and by class.
        let mut group_reports: Vec<GroupFit> = groups
            .keys()
            .map(|g| GroupFit {
                group: g.name(),
                elements: 0,
                consistent: 0.0,
                factor: 0.0,
            })
            .collect();
        let order: Vec<usize> = groups.values().copied().collect();
        let mut by_index = vec![0; c];
        for (slot, &g) in order.iter().enumerate() {
            by_index[g] = slot;
        }
        let mut class_sums: BTreeMap<Class, (f64, usize)> = BTreeMap::new();
        for el in fitted {
            let report = &mut group_reports[by_index[el.group]];
            report.elements += 1;
            report.consistent += priors[el.element].consistent;
            report.factor = y[el.group];
            // The model keeps the elements with a positive constant.
            if constants[el.element] > 0.0 {
                let entry = class_sums
                    .entry(lattice.elements[el.element].class())
                    .or_insert((0.0, 0));
                entry.0 += constants[el.element];
                entry.1 += 1;
            }
        }
        for g in &mut group_reports {
            g.consistent /= g.elements.max(1) as f64;
        }
        let class_constants =
            Constants::from_pairs(class_sums.iter().map(|(&c, &(s, n))| (c, s / n as f64)));
        // How closely the fitted model's own modes reproduce the fitted ones (matched by MAC).
        let msm = ModalBasis::new(&l, &SparseMatrix::from_diagonal(&masses))?;
        let window: Vec<usize> = (0..msm.len())
            .filter(|&j| msm.omega[j] > 0.0)
            .take(2 * r + 8)
            .collect();
        let shapes: Vec<Vec<f64>> = modes.iter().map(|m| m.shape.clone()).collect();
        let omegas: Vec<f64> = modes.iter().map(|m| m.omega).collect();
        let worst_fitted_mode = match_modes(
            &shapes,
            &omegas,
            &window.iter().map(|&j| msm.mode(j)).collect::<Vec<_>>(),
        )
        .iter()
        .zip(&omegas)
        .map(|(m, w)| {
            m.map_or(f64::INFINITY, |(j, _)| {
                (msm.omega[window[j]] / w - 1.0).abs()
            })
        })
        .fold(0.0, f64::max);
        Ok(ModalSolution {
            report: ModalFitReport {
                classes: class_sums.keys().copied().collect(),
                constants: class_constants,
                groups: group_reports,
                modes: r,
                fitted_modes: selected.iter().map(|i| i + 1).collect(),
                mode_frequencies: modes.iter().map(|m| m.omega).collect(),
                half_waves,
                mass_regularization: lambda_m,
                constant_regularization: lambda_k,
                frequency_weight: FREQUENCY_WEIGHT,
                relative_residual: (num / den.max(f64::MIN_POSITIVE)).sqrt(),
                frequency_residual: (rayleigh / r.max(1) as f64).sqrt(),
                omega1_dnurbs,
                omega1_fitted,
                mass_scale,
                worst_fitted_mode,
            },
            constants,
            masses,
            basis: msm,
        })
    }
}

/// Minimizes `½ zᵀ H z − gᵀ z` over `z = (y, x)`, `y ≥ 0`, `x ≥ MASS_FLOOR`, with
/// `H = [[hkk, hkm], [hkmᵀ, diag(d) + sᵀ s]]`: the masses are eliminated (Woodbury on their
/// block, a Schur complement on the factors), the factors solved by non-negative least
/// squares on the reduced problem, the masses recovered; a mass below the floor is held at
/// it and the rest solved again.
fn solve_with_floor(
    hkk: &DenseMatrix,
    hkm: &DenseMatrix,
    d: &[f64],
    s: &DenseMatrix,
    gk: &[f64],
    gm: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), DeriveError> {
    let (c, n, rows) = (hkk.nrows(), d.len(), s.nrows());
    let mut held = vec![false; n];
    loop {
        let open: Vec<usize> = (0..n).filter(|&p| !held[p]).collect();
        let m = open.len();
        // The held masses move to the right-hand side.
        let s_held: Vec<f64> = (0..rows)
            .map(|i| {
                (0..n)
                    .filter(|&p| held[p])
                    .map(|p| s[(i, p)] * MASS_FLOOR)
                    .sum()
            })
            .collect();
        let g_k: Vec<f64> = (0..c)
            .map(|g| {
                gk[g]
                    - (0..n)
                        .filter(|&p| held[p])
                        .map(|p| hkm[(g, p)] * MASS_FLOOR)
                        .sum::<f64>()
            })
            .collect();
        let g_m: Vec<f64> = open
            .iter()
            .map(|&p| gm[p] - (0..rows).map(|i| s[(i, p)] * s_held[i]).sum::<f64>())
            .collect();
        // (diag(d) + SᵀS)⁻¹ on the open masses by Woodbury: B = [H_mk | g_m] → solved.
        let mut b = DenseMatrix::zeros(m, c + 1);
        for (q, &p) in open.iter().enumerate() {
            for g in 0..c {
                b[(q, g)] = hkm[(g, p)] / d[p];
            }
            b[(q, c)] = g_m[q] / d[p];
        }
        let s_open = DenseMatrix::from_fn(rows, m, |i, q| s[(i, open[q])]);
        let cap = DenseMatrix::from_fn(rows, rows, |i, j| {
            let v: f64 = open
                .iter()
                .enumerate()
                .map(|(q, &p)| s_open[(i, q)] * s_open[(j, q)] / d[p])
                .sum();
            if i == j { v + 1.0 } else { v }
        });
        let t = s_open.matmul(&b);
        let w = cholesky_solve_dense_columns(&cap, &t)?;
        let correction = s_open.transpose().matmul(&w);
        for (q, &p) in open.iter().enumerate() {
            for col in 0..=c {
                b[(q, col)] -= correction[(q, col)] / d[p];
            }
        }
        // The reduced problem in y.
        let hkm_open = DenseMatrix::from_fn(c, m, |g, q| hkm[(g, open[q])]);
        let product = hkm_open.matmul(&b);
        let reduced = DenseMatrix::from_fn(c, c, |g, h| {
            0.5 * (hkk[(g, h)] + hkk[(h, g)] - product[(g, h)] - product[(h, g)])
        });
        let g_red: Vec<f64> = (0..c).map(|g| g_k[g] - product[(g, c)]).collect();
        let scale: Vec<f64> = (0..c)
            .map(|g| {
                let h = reduced[(g, g)];
                if h > 0.0 { 1.0 / h.sqrt() } else { 1.0 }
            })
            .collect();
        let qp = BlockQp {
            hkk: DenseMatrix::from_fn(c, c, |g, h| scale[g] * reduced[(g, h)] * scale[h]),
            hkm: DenseMatrix::zeros(c, 0),
            d: Vec::new(),
            s: DenseMatrix::zeros(0, 0),
            g: g_red.iter().zip(&scale).map(|(g, s)| g * s).collect(),
        };
        let start: Vec<f64> = scale.iter().map(|s| 1.0 / s).collect();
        let y: Vec<f64> = qp
            .solve_nonnegative(start)?
            .iter()
            .zip(&scale)
            .map(|(z, s)| z * s)
            .collect();
        let mut x = vec![MASS_FLOOR; n];
        let mut low = false;
        for (q, &p) in open.iter().enumerate() {
            let v = b[(q, c)] - (0..c).map(|g| b[(q, g)] * y[g]).sum::<f64>();
            if v < MASS_FLOOR {
                held[p] = true;
                low = true;
            } else {
                x[p] = v;
            }
        }
        if !low {
            return Ok((y, x));
        }
    }
}

#[cfg(test)]
pub(crate) mod tests;
