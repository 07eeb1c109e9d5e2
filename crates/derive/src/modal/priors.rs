//! What the modal fit starts from: each element's consistent constant and scale (`element_priors`), and which D-NURBS modes the lattice resolves (`resolved_modes`).

use super::*;

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
pub(super) fn half_waves(grid: (usize, usize), position: &[usize], shape: &[f64]) -> [usize; 2] {
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
pub(super) fn free_lines(grid: (usize, usize), free: &[usize]) -> [usize; 2] {
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
