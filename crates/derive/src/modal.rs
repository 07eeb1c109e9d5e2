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

use crate::DeriveError;
use crate::fnnls::BlockQp;
use crate::modal_solution::ModalBasis;
use crate::validation::match_modes;

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

    fn name(self, axis: char) -> String {
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

/// What the fit knows of an element before it starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementPrior {
    /// Its consistent constant `k⁰_e` (0: the material has no such term).
    pub consistent: f64,
    /// The scale `σ_e` of its constant in the fit: `k⁰_e`, or where that is 0 the size of
    /// the material's terms at the element's spacing (0: the element is left out).
    pub scale: f64,
}

/// The consistent constant and the scale of each element of `lattice` (docs/math.md §8.3),
/// from the D-NURBS stiffness per derivative slot `[·, α11, α22, β11, β12, β22]`
/// (`Material::stiffness_by_slot`) and the area factor of each node (`|c_u × c_v|` under
/// area integration, else 1; the mean over an element's nodes scales it). With h the
/// element's spacing (its extent over its intervals):
///
/// - `spring_u`: `α11`; `spring_v`: `α22`;
/// - `bend_u`: `β11 + α11 h²/12` (the springs' second differences lack `α11 h² |c_uu|²/12`
///   on a uniform lattice); `bend_v` likewise;
/// - `third_u`: `β11 h²/6` (the bending stencil lacks `β11 h² |c_uuu|²/6`); `third_v`
///   likewise;
/// - `twist`: `β12`;
/// - `diagonal`: 0 when the lattice has springs along u or v (they carry α), else
///   `(α11 + α22)/2`.
///
/// Where the consistent constant is 0 the scale is, by the order of the stencil's
/// derivative, `ᾱ + β̄/h²` (springs, diagonals), `β̄ + ᾱ h²` (bends, twist) or
/// `β̄ h² + ᾱ h⁴` (third differences), with ᾱ, β̄ the means of the α and β terms.
///
/// ```
/// use nurbspring_derive::element_priors;
/// use nurbspring_geom::{KnotVector, NurbsCurve};
/// use nurbspring_msm::{Class, Constants, LatticeOptions, LinearKind, ParameterGrid, SpringLattice};
/// // A straight chain of 5 nodes, h = 0.25: springs α, bends β + α h²/12, thirds β h²/6.
/// let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
/// let c = NurbsCurve::try_new(k, vec![[0., 0., 0.], [1., 0., 0.]], vec![1.; 2]).unwrap();
/// let options = LatticeOptions {
///     grid: ParameterGrid::Uniform { nodes_u: 5, nodes_v: 1 },
///     constants: Constants::from_pairs(Class::linear(&LinearKind::CHAIN).into_iter().map(|c| (c, 1.0))),
///     ..LatticeOptions::default()
/// };
/// let l = SpringLattice::from_curve(&c, &options, &[]).unwrap();
/// let priors = element_priors(&l, [0.0, 2.0, 0.0, 0.5, 0.0, 0.0], &[1.0; 5]);
/// for (e, p) in l.elements.iter().zip(&priors) {
///     let want = match e.kind {
///         LinearKind::SpringU => 2.0,
///         LinearKind::BendU => 0.5 + 2.0 * 0.0625 / 12.0,
///         _ => 0.5 * 0.0625 / 6.0,
///     };
///     assert!((p.consistent - want).abs() < 1e-15 && p.scale == p.consistent);
/// }
/// // Without β the third differences have no consistent constant: their scale is α h⁴.
/// let priors = element_priors(&l, [0.0, 2.0, 0.0, 0.0, 0.0, 0.0], &[1.0; 5]);
/// let third = l.elements.iter().position(|e| e.kind == LinearKind::ThirdU).unwrap();
/// assert_eq!(priors[third].consistent, 0.0);
/// assert!((priors[third].scale - 2.0 * 0.25f64.powi(4)).abs() < 1e-15);
/// ```
pub fn element_priors(lattice: &SpringLattice, slots: [f64; 6], area: &[f64]) -> Vec<ElementPrior> {
    let [_, a11, a22, b11, b12, b22] = slots;
    let curve = lattice.grid.is_some_and(|(_, n_v)| n_v == 1);
    let (alpha, beta) = if curve {
        (a11, b11)
    } else {
        (0.5 * (a11 + a22), (b11 + b12 + b22) / 3.0)
    };
    let springs = lattice
        .elements
        .iter()
        .any(|e| matches!(e.kind, LinearKind::SpringU | LinearKind::SpringV));
    let params = lattice.params.as_deref().unwrap_or(&[]);
    lattice
        .elements
        .iter()
        .map(|e| {
            let extent = |along_u: bool| -> f64 {
                let t: Vec<f64> = e
                    .nodes
                    .iter()
                    .map(|&a| {
                        params
                            .get(a)
                            .map_or(0.0, |p| if along_u { p.0 } else { p.1 })
                    })
                    .collect();
                t.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                    - t.iter().copied().fold(f64::INFINITY, f64::min)
            };
            let along_u = !matches!(
                e.kind,
                LinearKind::SpringV | LinearKind::BendV | LinearKind::ThirdV
            );
            // The spacing: the extent over the intervals along the stencil's direction.
            let h = match e.kind {
                LinearKind::Diagonal | LinearKind::Twist => (extent(true) * extent(false)).sqrt(),
                _ => extent(along_u) / (e.nodes.len() - 1) as f64,
            };
            let h2 = h * h;
            let (consistent, order) = match e.kind {
                LinearKind::SpringU => (a11, 1),
                LinearKind::SpringV => (a22, 1),
                LinearKind::BendU => (b11 + a11 * h2 / 12.0, 2),
                LinearKind::BendV => (b22 + a22 * h2 / 12.0, 2),
                LinearKind::ThirdU => (b11 * h2 / 6.0, 3),
                LinearKind::ThirdV => (b22 * h2 / 6.0, 3),
                LinearKind::Twist => (b12, 2),
                LinearKind::Diagonal if springs => (0.0, 1),
                LinearKind::Diagonal => (0.5 * (a11 + a22), 1),
            };
            let natural = match order {
                1 => alpha + beta / h2,
                2 => beta + alpha * h2,
                _ => beta * h2 + alpha * h2 * h2,
            };
            let factor = e.nodes.iter().map(|&a| area[a]).sum::<f64>() / e.nodes.len() as f64;
            let consistent = consistent * factor;
            ElementPrior {
                consistent,
                scale: if consistent > 0.0 {
                    consistent
                } else if natural.is_finite() {
                    natural * factor
                } else {
                    0.0
                },
            }
        })
        .collect()
}

/// The number of half-waves of a mode along u and along v: one more than the most sign
/// changes along any grid line (values below 10⁻³ of the largest, and fixed nodes, skipped).
fn half_waves(grid: (usize, usize), position: &[usize], shape: &[f64]) -> [usize; 2] {
    let (n_u, n_v) = grid;
    let top = shape.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let value = |i: usize, j: usize| -> Option<f64> {
        let p = position[i * n_v + j];
        (p != usize::MAX && shape[p].abs() > 1e-3 * top).then(|| shape[p])
    };
    let changes = |line: &mut dyn Iterator<Item = Option<f64>>| -> usize {
        let signs: Vec<bool> = line.flatten().map(|v| v > 0.0).collect();
        signs.windows(2).filter(|w| w[0] != w[1]).count()
    };
    let along_u = (0..n_v)
        .map(|j| changes(&mut (0..n_u).map(|i| value(i, j))))
        .max()
        .unwrap_or(0);
    let along_v = (0..n_u)
        .map(|i| changes(&mut (0..n_v).map(|j| value(i, j))))
        .max()
        .unwrap_or(0);
    [along_u + 1, along_v + 1]
}

/// The free lines of the lattice along u and v.
fn free_lines(grid: (usize, usize), free: &[usize]) -> [usize; 2] {
    let (n_u, n_v) = grid;
    let (mut lines_u, mut lines_v) = (vec![false; n_u], vec![false; n_v]);
    for &a in free {
        lines_u[a / n_v] = true;
        lines_v[a % n_v] = true;
    }
    let count = |lines: &[bool]| lines.iter().filter(|&&f| f).count();
    [count(&lines_u), count(&lines_v)]
}

/// The modes the lattice resolves, by rank in `modes` (ascending frequency): at most
/// `K_u` half-waves along u and `K_v` along v, `K = max(⌈(N + 1)/2⌉, min(N, MIN_HALF_WAVES))`
/// with N the free lines in that direction (a wave of `⌈(N + 1)/2⌉` half-waves has four
/// nodes per wavelength), until `min(K_u K_v, FITTED_MODES)` are taken ([`modes_within`]).
/// Returns the ranks and `[K_u, K_v]`.
pub fn resolved_modes(
    grid: (usize, usize),
    free: &[usize],
    modes: &[SampledMode],
) -> (Vec<usize>, [usize; 2]) {
    let k = free_lines(grid, free).map(|n| (n + 1).div_ceil(2).max(n.min(MIN_HALF_WAVES)));
    (modes_within(grid, free, modes, k), k)
}

/// The lowest modes of `modes` (by rank) with at most `k[0]` half-waves along u and `k[1]`
/// along v, until `min(k[0] k[1], FITTED_MODES)` are taken. A repeated frequency (within
/// [`REPEATED`]) is taken whole or not at all: its modes are any rotation of the repeated
/// pair, so each must pass.
pub fn modes_within(
    grid: (usize, usize),
    free: &[usize],
    modes: &[SampledMode],
    k: [usize; 2],
) -> Vec<usize> {
    let mut position = vec![usize::MAX; grid.0 * grid.1];
    for (p, &a) in free.iter().enumerate() {
        position[a] = p;
    }
    let count = (k[0] * k[1]).min(FITTED_MODES);
    let mut out: Vec<usize> = Vec::new();
    let mut start = 0;
    while start < modes.len() && out.len() < count {
        let mut end = start + 1;
        while end < modes.len()
            && (modes[end].omega - modes[start].omega).abs() <= REPEATED * modes[end].omega
        {
            end += 1;
        }
        let resolved = modes[start..end].iter().all(|m| {
            let w = half_waves(grid, &position, &m.shape);
            w[0] <= k[0] && w[1] <= k[1]
        });
        if resolved {
            out.extend(start..end);
        }
        start = end;
    }
    out
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
    let refused = |reason: &str| DeriveError::InvalidOption {
        name: "fit.derivation",
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
        return Err(DeriveError::InvalidOption {
            name: "msm.elements",
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
        let refused = |reason: &str| DeriveError::InvalidOption {
            name: "fit.derivation",
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
pub(crate) mod tests {
    use super::*;

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

    /// The reduced solve (masses eliminated by Woodbury and a Schur complement, the factors by
    /// non-negative least squares) against the optimality conditions of the dense problem
    /// (H assembled from its blocks): the gradient `Hz − g` vanishes on every positive factor
    /// and every mass above the floor, is ≥ 0 on a factor at 0; a mass pulled below the floor
    /// is held at it.
    #[test]
    fn the_reduced_solve_against_a_dense_one() {
        let mut seed = 11u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let (c, n, rows) = (3, 5, 2);
        let a = DenseMatrix::from_fn(7, c + n, |_, _| rnd());
        let gram = a.transpose().matmul(&a);
        let hkk = DenseMatrix::from_fn(c, c, |i, j| gram[(i, j)] + if i == j { 0.5 } else { 0.0 });
        let hkm = DenseMatrix::from_fn(c, n, |i, j| 0.3 * gram[(i, c + j)]);
        let d: Vec<f64> = (0..n).map(|_| 2.0 + rnd()).collect();
        let s = DenseMatrix::from_fn(rows, n, |_, _| rnd());
        let dense = |gm: &[f64], gk: &[f64]| {
            let t = c + n;
            let h = DenseMatrix::from_fn(t, t, |i, j| match (i < c, j < c) {
                (true, true) => hkk[(i, j)],
                (true, false) => hkm[(i, j - c)],
                (false, true) => hkm[(j, i - c)],
                (false, false) => {
                    let (p, q) = (i - c, j - c);
                    (0..rows).map(|r| s[(r, p)] * s[(r, q)]).sum::<f64>()
                        + if p == q { d[p] } else { 0.0 }
                }
            });
            let g: Vec<f64> = gk.iter().chain(gm).copied().collect();
            (h, g)
        };
        for trial in 0..20 {
            let gk: Vec<f64> = (0..c).map(|_| rnd()).collect();
            let gm: Vec<f64> = (0..n).map(|_| 3.0 + rnd()).collect();
            let (h, g) = dense(&gm, &gk);
            let (y, x) = solve_with_floor(&hkk, &hkm, &d, &s, &gk, &gm).unwrap();
            let z: Vec<f64> = y.iter().chain(&x).copied().collect();
            let hz = h.mul_vec(&z);
            let floored: Vec<bool> = (0..n).map(|p| x[p] == MASS_FLOOR).collect();
            for j in 0..c + n {
                let grad = hz[j] - g[j];
                if j < c && y[j] == 0.0 {
                    assert!(
                        grad >= -1e-10,
                        "{trial}: factor {j} at 0 with gradient {grad}"
                    );
                } else if j >= c && floored[j - c] {
                    assert!(x[j - c] == MASS_FLOOR);
                } else {
                    assert!(grad.abs() < 1e-10, "{trial}: unknown {j} gradient {grad}");
                }
            }
            assert!(y.iter().all(|&v| v >= 0.0) && x.iter().all(|&v| v >= MASS_FLOOR));
        }
        // A right-hand side that pulls mass 0 below the floor.
        let gk = vec![0.1; c];
        let mut gm = vec![3.0; n];
        gm[0] = -50.0;
        let (_, x) = solve_with_floor(&hkk, &hkm, &d, &s, &gk, &gm).unwrap();
        assert_eq!(x[0], MASS_FLOOR);
    }

    /// Bands by hand on 10 lines: the first three from each edge by their distance, the
    /// rest inside; an element is banded by its line nearest an edge, the low edge first.
    #[test]
    fn bands_of_elements() {
        assert_eq!(Band::of(0, 1, 10), Band::Low(0));
        assert_eq!(Band::of(2, 4, 10), Band::Low(2));
        assert_eq!(Band::of(3, 5, 10), Band::Inside);
        assert_eq!(Band::of(5, 7, 10), Band::High(2));
        assert_eq!(Band::of(8, 9, 10), Band::High(0));
        // On a short lattice the low edge wins.
        assert_eq!(Band::of(2, 3, 4), Band::Low(2));
        let g = FitGroup {
            kind: LinearKind::BendU,
            u: Band::Low(1),
            v: Band::High(0),
        };
        assert_eq!(g.name(), "bend_u[u1,v-0]");
    }

    /// Half-waves of separable shapes `sin(a π i/(N+1)) sin(b π j/(N+1))` on a 9 × 7 grid whose
    /// outer ring is fixed; and the selection: `K = max(⌈(N+1)/2⌉, min(N, 3))` per direction,
    /// the count capped at `K_u K_v`, a repeated frequency taken whole or not at all.
    #[test]
    fn half_waves_and_resolved_modes() {
        let (n_u, n_v) = (9, 7);
        let free: Vec<usize> = (0..n_u * n_v)
            .filter(|a| {
                let (i, j) = (a / n_v, a % n_v);
                i > 0 && j > 0 && i + 1 < n_u && j + 1 < n_v
            })
            .collect();
        let shape = |a: usize, b: usize| -> Vec<f64> {
            free.iter()
                .map(|&x| {
                    let (i, j) = ((x / n_v) as f64, (x % n_v) as f64);
                    (a as f64 * std::f64::consts::PI * i / (n_u - 1) as f64).sin()
                        * (b as f64 * std::f64::consts::PI * j / (n_v - 1) as f64).sin()
                })
                .collect()
        };
        let mut position = vec![usize::MAX; n_u * n_v];
        for (p, &a) in free.iter().enumerate() {
            position[a] = p;
        }
        for (a, b) in [(1, 1), (3, 2), (5, 4), (7, 1)] {
            assert_eq!(
                half_waves((n_u, n_v), &position, &shape(a, b)),
                [a, b],
                "{a}, {b}"
            );
        }
        // 7 free lines along u: K_u = 4; 5 along v: K_v = 3; at most 12 modes. Frequencies
        // `√(a² + 1.7 b²)`, none repeated.
        let mut modes = Vec::new();
        for a in 1..=7 {
            for b in 1..=5 {
                modes.push((((a * a) as f64 + 1.7 * (b * b) as f64).sqrt(), a, b));
            }
        }
        modes.sort_by(|x, y| x.0.total_cmp(&y.0));
        let sampled: Vec<SampledMode> = modes
            .iter()
            .map(|&(w, a, b)| SampledMode {
                omega: w,
                shape: shape(a, b),
            })
            .collect();
        let (picked, k) = resolved_modes((n_u, n_v), &free, &sampled);
        assert_eq!(k, [4, 3]);
        let labels: Vec<(usize, usize)> =
            picked.iter().map(|&i| (modes[i].1, modes[i].2)).collect();
        assert!(labels.iter().all(|&(a, b)| a <= 4 && b <= 3), "{labels:?}");
        // (1,1) … (4,3): 12 modes.
        assert_eq!(labels.len(), 12, "{labels:?}");
        for w in picked.windows(2) {
            assert!(w[0] < w[1]);
        }
        // A repeated frequency with a member beyond K is left out whole: (1,2) paired with a
        // copy of (5,1) at its frequency.
        let mut paired = sampled.clone();
        let at = modes.iter().position(|m| (m.1, m.2) == (1, 2)).unwrap();
        paired.insert(
            at + 1,
            SampledMode {
                omega: paired[at].omega,
                shape: shape(5, 1),
            },
        );
        let (picked, _) = resolved_modes((n_u, n_v), &free, &paired);
        assert!(
            !picked.contains(&at) && !picked.contains(&(at + 1)),
            "{picked:?}"
        );
    }
}
