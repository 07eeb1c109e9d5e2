//! Linear isotropic elements (docs/math.md §8): zero-rest-length ("vector") springs along u,
//! along v and on both diagonals of each cell, 3-node bending stencils along u and v, 4-node
//! third-difference stencils along u and v, and a 4-node twist stencil per cell.
//!
//! An element acts on the displacements `u_i = x_i − x_i(0)` of its nodes with the energy
//! `E = ½ k w |Σ_i c_i u_i|²`: `k` is its class constant, `w` its weight and `c` its stencil
//! coefficients. Its internal force on node `i` is `k w c_i (Σ_j c_j u_j)` and its stiffness
//! `k w c_i c_j I₃`, the same in every direction. Over a lattice these sum to `L ⊗ I₃` with
//! the scalar `L = Σ_e k_e w_e c_e c_eᵀ`.
//!
//! Weights on a lattice of parameters `u_a` (`h_u(a) = u_{a+1} − u_a`, the dual spacing
//! `τ_u(a) = ½ (h_u(a−1) + h_u(a))`, one-sided at the ends), likewise in v:
//! - spring along u between `(a, b)`, `(a+1, b)`: `c = (1, −1)`, `w = τ_v(b) / h_u(a)`;
//! - diagonals of cell `(a, b)`: `c = (1, −1)`, `w = h_u h_v / (h_u² + h_v²)`;
//! - bending along u over `(a−1, b), (a, b), (a+1, b)`: `c` the second divided difference
//!   `(2/(h₁(h₁+h₂)), −2/(h₁h₂), 2/(h₂(h₁+h₂)))`, `w = τ_u(a) τ_v(b)`;
//! - twist of cell `(a, b)` over `(a, b), (a+1, b), (a, b+1), (a+1, b+1)`:
//!   `c = (1, −1, −1, 1) / (h_u h_v)`, `w = h_u h_v`;
//! - third difference along u over `(a−1, b), …, (a+2, b)`: `c` the third derivative of the
//!   cubic through the four nodes (`6 ×` the third divided difference), `w = h'_u(a) τ_v(b)`
//!   with `h'_u(a) = h_u(a)`, plus `h_u(0)` for the first stencil and the last interval's
//!   length for the last (the stencils sit on the inner intervals; the two end intervals
//!   are counted with their neighbours, so that the sum stays a second-order quadrature).
//!
//! With these weights the energy of a smooth displacement field tends to the D-NURBS energy
//! `½ ∫∫ α11 |c_u|² + α22 |c_v|² + β11 |c_uu|² + β12 |c_uv|² + β22 |c_vv|²` when the constants
//! are `k = α11, α22, β11, β22, β12` (and a diagonal class with `k = α` stands for
//! `α11 = α22 = α` on a square cell). A third-difference element stands for `|c_uuu|²`, a
//! term the D-NURBS does not have: with `k = β11 h²/6` it cancels the leading error
//! `−β11 h² |c_uuu|²/6` of the bending stencil on a uniform lattice (docs/math.md §8.3).

use serde::{Deserialize, Serialize};

/// The kind of a linear element.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearKind {
    /// Zero-rest-length spring between neighbours along u.
    SpringU,
    /// Zero-rest-length spring between neighbours along v.
    SpringV,
    /// Zero-rest-length springs on both diagonals of a cell.
    Diagonal,
    /// Second difference along u over three nodes.
    BendU,
    /// Second difference along v over three nodes.
    BendV,
    /// Mixed difference over the four nodes of a cell.
    Twist,
    /// Third difference along u over four nodes.
    ThirdU,
    /// Third difference along v over four nodes.
    ThirdV,
}

impl LinearKind {
    /// Every kind, in report order.
    pub const ALL: [LinearKind; 8] = [
        LinearKind::SpringU,
        LinearKind::SpringV,
        LinearKind::Diagonal,
        LinearKind::BendU,
        LinearKind::BendV,
        LinearKind::Twist,
        LinearKind::ThirdU,
        LinearKind::ThirdV,
    ];

    /// The kinds that exist on a chain (a curve's lattice).
    pub const CHAIN: [LinearKind; 3] = [LinearKind::SpringU, LinearKind::BendU, LinearKind::ThirdU];

    /// `"spring_u"`, `"spring_v"`, `"diagonal"`, `"bend_u"`, `"bend_v"`, `"twist"`,
    /// `"third_u"`, `"third_v"`.
    pub fn name(self) -> &'static str {
        match self {
            LinearKind::SpringU => "spring_u",
            LinearKind::SpringV => "spring_v",
            LinearKind::Diagonal => "diagonal",
            LinearKind::BendU => "bend_u",
            LinearKind::BendV => "bend_v",
            LinearKind::Twist => "twist",
            LinearKind::ThirdU => "third_u",
            LinearKind::ThirdV => "third_v",
        }
    }

    /// Parses a [`LinearKind::name`].
    pub fn parse(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// Where an element sits: touching a fixed node (`boundary`) or not (`interior`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// No node of the element is fixed.
    Interior,
    /// At least one node is fixed.
    Boundary,
}

impl Region {
    /// Both regions.
    pub const ALL: [Region; 2] = [Region::Interior, Region::Boundary];

    /// `"interior"` or `"boundary"`.
    pub fn name(self) -> &'static str {
        match self {
            Region::Interior => "interior",
            Region::Boundary => "boundary",
        }
    }
}

/// One linear element: energy `½ k weight |Σ_i coefficients_i u_{nodes_i}|²`.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearElement {
    /// Its kind.
    pub kind: LinearKind,
    /// Its region.
    pub region: Region,
    /// Its nodes (2 to 4).
    pub nodes: Vec<usize>,
    /// Stencil coefficients, one per node.
    pub coefficients: Vec<f64>,
    /// Weight `w > 0`.
    pub weight: f64,
    /// Its constant `k ≥ 0` (the class's, unless a derivation set each element's own).
    pub k: f64,
}

impl LinearElement {
    /// Its class.
    pub fn class(&self) -> crate::Class {
        crate::Class::Linear(self.kind, self.region)
    }

    /// `Σ_i c_i u_i` for displacements `u` (interleaved, all nodes).
    pub fn strain(&self, u: &[f64]) -> [f64; 3] {
        let mut s = [0.0; 3];
        for (&a, &c) in self.nodes.iter().zip(&self.coefficients) {
            for x in 0..3 {
                s[x] += c * u[3 * a + x];
            }
        }
        s
    }

    /// `½ k w |Σ_i c_i u_i|²`.
    pub fn energy(&self, u: &[f64]) -> f64 {
        let s = self.strain(u);
        0.5 * self.k * self.weight * (s[0] * s[0] + s[1] * s[1] + s[2] * s[2])
    }
}

/// Spacings `h(a) = t_{a+1} − t_a` and dual spacings `τ(a)` (one-sided at the ends) of the
/// parameters `t`.
fn spacings(t: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let n = t.len();
    let tau = (0..n)
        .map(|a| {
            let left = if a > 0 { h[a - 1] } else { 0.0 };
            let right = if a + 1 < n { h[a] } else { 0.0 };
            0.5 * (left + right)
        })
        .collect();
    (h, tau)
}

/// The elements of `kinds` on the tensor grid of parameters `us × vs` (node `a = i·n_v + j`;
/// a chain when `vs` has one value, where only the kinds along u exist). `fixed` decides each
/// element's region; `k(kind, region)` gives its constant.
pub(crate) fn grid_elements(
    us: &[f64],
    vs: &[f64],
    fixed: &[bool],
    kinds: &[LinearKind],
    k: &dyn Fn(LinearKind, Region) -> f64,
) -> Vec<LinearElement> {
    let (n_u, n_v) = (us.len(), vs.len());
    let (hu, tu) = spacings(us);
    let (hv, tv) = spacings(vs);
    // A chain has unit extent across it, so that its constants are per unit length.
    let tv: Vec<f64> = if n_v == 1 { vec![1.0] } else { tv };
    let idx = |i: usize, j: usize| i * n_v + j;
    let mut out = Vec::new();
    let mut push = |kind: LinearKind, nodes: Vec<usize>, coefficients: Vec<f64>, weight: f64| {
        let region = if nodes.iter().any(|&a| fixed[a]) {
            Region::Boundary
        } else {
            Region::Interior
        };
        out.push(LinearElement {
            kind,
            region,
            k: k(kind, region),
            nodes,
            coefficients,
            weight,
        });
    };
    let second = |h1: f64, h2: f64| {
        vec![
            2.0 / (h1 * (h1 + h2)),
            -2.0 / (h1 * h2),
            2.0 / (h2 * (h1 + h2)),
        ]
    };
    // The third derivative of the cubic through four nodes at parameters `t`: 6 × the third
    // divided difference, `6 / Π_{j≠i} (t_i − t_j)` on node i.
    // The intervals a third difference on the interval `a` stands for: its own, and the end
    // interval next to it when it is the first or the last.
    let covered = |h: &[f64], a: usize| -> f64 {
        let mut w = h[a];
        if a == 1 {
            w += h[0];
        }
        if a + 2 == h.len() {
            w += h[a + 1];
        }
        w
    };
    let third = |t: &[f64]| -> Vec<f64> {
        (0..4)
            .map(|i| {
                6.0 / (0..4)
                    .filter(|&j| j != i)
                    .map(|j| t[i] - t[j])
                    .product::<f64>()
            })
            .collect()
    };
    for &kind in kinds {
        match kind {
            LinearKind::SpringU => {
                for i in 0..n_u.saturating_sub(1) {
                    for j in 0..n_v {
                        push(
                            kind,
                            vec![idx(i, j), idx(i + 1, j)],
                            vec![1.0, -1.0],
                            tv[j] / hu[i],
                        );
                    }
                }
            }
            LinearKind::SpringV if n_v > 1 => {
                for i in 0..n_u {
                    for j in 0..n_v - 1 {
                        push(
                            kind,
                            vec![idx(i, j), idx(i, j + 1)],
                            vec![1.0, -1.0],
                            tu[i] / hv[j],
                        );
                    }
                }
            }
            LinearKind::Diagonal if n_v > 1 => {
                for i in 0..n_u.saturating_sub(1) {
                    for j in 0..n_v - 1 {
                        let w = hu[i] * hv[j] / (hu[i] * hu[i] + hv[j] * hv[j]);
                        push(kind, vec![idx(i, j), idx(i + 1, j + 1)], vec![1.0, -1.0], w);
                        push(kind, vec![idx(i + 1, j), idx(i, j + 1)], vec![1.0, -1.0], w);
                    }
                }
            }
            LinearKind::BendU => {
                for i in 1..n_u.saturating_sub(1) {
                    for j in 0..n_v {
                        push(
                            kind,
                            vec![idx(i - 1, j), idx(i, j), idx(i + 1, j)],
                            second(hu[i - 1], hu[i]),
                            tu[i] * tv[j],
                        );
                    }
                }
            }
            LinearKind::BendV if n_v > 2 => {
                for i in 0..n_u {
                    for j in 1..n_v - 1 {
                        push(
                            kind,
                            vec![idx(i, j - 1), idx(i, j), idx(i, j + 1)],
                            second(hv[j - 1], hv[j]),
                            tu[i] * tv[j],
                        );
                    }
                }
            }
            LinearKind::Twist if n_v > 1 => {
                for i in 0..n_u.saturating_sub(1) {
                    for j in 0..n_v - 1 {
                        let a = hu[i] * hv[j];
                        push(
                            kind,
                            vec![idx(i, j), idx(i + 1, j), idx(i, j + 1), idx(i + 1, j + 1)],
                            vec![1.0 / a, -1.0 / a, -1.0 / a, 1.0 / a],
                            a,
                        );
                    }
                }
            }
            LinearKind::ThirdU => {
                for i in 1..n_u.saturating_sub(2) {
                    for j in 0..n_v {
                        push(
                            kind,
                            (i - 1..i + 3).map(|a| idx(a, j)).collect(),
                            third(&us[i - 1..i + 3]),
                            covered(&hu, i) * tv[j],
                        );
                    }
                }
            }
            LinearKind::ThirdV if n_v > 3 => {
                for i in 0..n_u {
                    for j in 1..n_v - 2 {
                        push(
                            kind,
                            (j - 1..j + 3).map(|b| idx(i, b)).collect(),
                            third(&vs[j - 1..j + 3]),
                            tu[i] * covered(&hv, j),
                        );
                    }
                }
            }
            _ => {}
        }
    }
    out
}
