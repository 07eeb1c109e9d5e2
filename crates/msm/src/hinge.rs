//! Hinges: bending by the dihedral angle of two triangles sharing an edge (docs/math.md §5.2).
//!
//! A hinge on the nodes `[x0, x1, x2, x3]` is the edge `x0 → x1` with the triangle
//! `(x0, x1, x2)` on one side and `(x1, x0, x3)` on the other, both oriented the same way.
//! With `e = x1 − x0`, `l = |e|`, `N1 = e × (x2 − x0)`, `N2 = (x3 − x0) × e` (the two
//! triangles' normals, `|N_i| = l h_i`, `h_i` the height of wing `x_{i+1}` over the edge):
//!
//! - the signed dihedral angle `θ = atan2(ê · (N1 × N2), N1 · N2)`, zero when the two
//!   triangles are coplanar and unfolded, in `(−π, π]`;
//! - the energy `E = ½ k w (θ − θ0)²` with the class constant `k`, the hinge's weight `w` and
//!   its rest angle `θ0` (so a curved rest shape is stress-free);
//! - its gradient (Bridson et al. 2003, Wardetzky et al. 2007): `∂θ/∂x2 = −(l/|N1|²) N1`,
//!   `∂θ/∂x3 = −(l/|N2|²) N2`, `∂θ/∂x1 = −t2 ∂θ/∂x2 − t3 ∂θ/∂x3`,
//!   `∂θ/∂x0 = −(1 − t2) ∂θ/∂x2 − (1 − t3) ∂θ/∂x3`, where `t_i = (x_i − x0)·e / l²` is where
//!   wing `x_i` projects onto the edge. So the internal force is `k w (θ − θ0) ∇θ`;
//! - its Hessian `k w (∇θ ∇θᵀ + (θ − θ0) ∇²θ)`, `∇²θ` by differentiating the gradient above
//!   (docs/math.md §5.2 writes out the terms), symmetrized to round-off.
//!
//! The energy is the bending term of the discrete shells of Grinspun et al. 2003,
//! `Σ_e (θ_e − θ̄_e)² |ē_e| / h̄_e`, when `k w = 2 k_B |ē| / h̄`: the weight carries the
//! geometry of the rest mesh, the class constant the material.

use nurbspring_geom::cross;
use serde::{Deserialize, Serialize};

use crate::spring::{norm, sub};

/// The kind of a hinge, by the edge it sits on (each kind is a class with one constant).
/// Serialized as its [`HingeKind::name`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum HingeKind {
    /// On an edge along a grid line (u or v) of a triangulated grid (`k_hinge`).
    #[serde(rename = "hinge")]
    Grid,
    /// On the diagonal edge of a grid cell (`k_hinge_diag`).
    #[serde(rename = "hinge_diagonal")]
    Diagonal,
}

impl HingeKind {
    /// Every kind, in report order.
    pub const ALL: [HingeKind; 2] = [HingeKind::Grid, HingeKind::Diagonal];

    /// `"hinge"` or `"hinge_diagonal"`: its class name in files and messages.
    ///
    /// ```
    /// use nurbspring_msm::HingeKind;
    /// assert_eq!(HingeKind::Diagonal.name(), "hinge_diagonal");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            HingeKind::Grid => "hinge",
            HingeKind::Diagonal => "hinge_diagonal",
        }
    }

    /// Parses a [`HingeKind::name`] (also `"hinge_grid"`).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "hinge" | "hinge_grid" | "grid" => Some(HingeKind::Grid),
            "hinge_diagonal" | "diagonal" => Some(HingeKind::Diagonal),
            _ => None,
        }
    }

    /// The symbol of its constant, `k_hinge` or `k_hinge_diag`.
    pub fn symbol(self) -> &'static str {
        match self {
            HingeKind::Grid => "k_hinge",
            HingeKind::Diagonal => "k_hinge_diag",
        }
    }
}

impl std::fmt::Display for HingeKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A hinge (module docs): the edge `nodes[0] → nodes[1]`, the wing `nodes[2]` of the triangle
/// `(nodes[0], nodes[1], nodes[2])` and the wing `nodes[3]` of `(nodes[1], nodes[0], nodes[3])`;
/// energy `½ k w (θ − θ0)²`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hinge {
    /// `[x0, x1, x2, x3]`: the edge's two nodes, then the two wings.
    pub nodes: [usize; 4],
    /// Its class.
    pub kind: HingeKind,
    /// Class constant `k ≥ 0`.
    pub k: f64,
    /// Weight `w > 0` (the stiffness is `k w`).
    pub weight: f64,
    /// Rest angle `θ0` in `(−π, π]`.
    pub rest_angle: f64,
}

/// The dihedral angle, its gradient and (optionally) its Hessian at four points.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HingeAngle {
    /// `θ`.
    pub theta: f64,
    /// `∂θ/∂x_i`.
    pub grad: [[f64; 3]; 4],
}

#[inline(always)]
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
fn scale(s: f64, a: [f64; 3]) -> [f64; 3] {
    [s * a[0], s * a[1], s * a[2]]
}

/// `atan(t)` to within one unit in the last place: Cephes' `atan` (S. L. Moshier), the
/// argument reduced to `|t| ≤ 0.66` by `atan(t) = π/4 + atan((t − 1)/(t + 1))` and
/// `atan(t) = π/2 − atan(1/t)`, then `t + t z P(z)/Q(z)`, `z = t²`, with its degree-4/5
/// rational approximation. Inlined into the hinge kernels (libm's `atan2` is a call that took a
/// quarter of the cloth step's time, docs/benchmarks.md).
#[inline(always)]
fn atan(t: f64) -> f64 {
    const P: [f64; 5] = [
        -8.750_608_600_031_904e-1,
        -1.615_753_718_733_365e1,
        -7.500_855_792_314_705e1,
        -1.228_866_684_490_136_2e2,
        -6.485_021_904_942_025e1,
    ];
    const Q: [f64; 5] = [
        2.485_846_490_142_306_3e1,
        1.650_270_098_316_988_6e2,
        4.328_810_604_912_903e2,
        4.853_903_996_359_137e2,
        1.945_506_571_482_614e2,
    ];
    // π/2 − fl(π/2), the bits of π/2 beyond an f64.
    const MORE_BITS: f64 = 6.123_233_995_736_766e-17;
    const TAN_3PI_8: f64 = 2.414_213_562_373_095;
    let a = t.abs();
    let (base, r, extra) = if a > TAN_3PI_8 {
        (std::f64::consts::FRAC_PI_2, -1.0 / a, MORE_BITS)
    } else if a <= 0.66 {
        (0.0, a, 0.0)
    } else {
        (
            std::f64::consts::FRAC_PI_4,
            (a - 1.0) / (a + 1.0),
            0.5 * MORE_BITS,
        )
    };
    let z = r * r;
    let p = (((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z + P[4];
    let q = ((((z + Q[0]) * z + Q[1]) * z + Q[2]) * z + Q[3]) * z + Q[4];
    let y = base + (r * (z * p / q) + r + extra);
    if t < 0.0 { -y } else { y }
}

/// `atan2(y, x)` in `(−π, π]` from [`atan`], with `f64::atan2`'s values on the axes
/// (`atan2(±0, x > 0) = ±0`, `atan2(0, x < 0) = π`, `atan2(y, 0) = ±π/2`, `atan2(0, 0) = 0`);
/// within a few units in the last place of `f64::atan2` (tested).
#[inline(always)]
pub(crate) fn atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    if x > 0.0 {
        atan(y / x)
    } else if x < 0.0 {
        if y < 0.0 {
            atan(y / x) - PI
        } else {
            atan(y / x) + PI
        }
    } else if x == 0.0 {
        if y > 0.0 {
            FRAC_PI_2
        } else if y < 0.0 {
            -FRAC_PI_2
        } else if y.is_nan() {
            f64::NAN
        } else {
            0.0
        }
    } else {
        f64::NAN
    }
}

/// The signed dihedral angle `θ = atan2(ê · (N1 × N2), N1 · N2)` of the hinge at `x`
/// (module docs); NaN when a triangle is degenerate.
#[inline(always)]
pub(crate) fn angle(x: &[[f64; 3]; 4]) -> f64 {
    let e = sub(x[1], x[0]);
    let n1 = cross(e, sub(x[2], x[0]));
    let n2 = cross(sub(x[3], x[0]), e);
    let l = norm(e);
    atan2(dot(e, cross(n1, n2)), l * dot(n1, n2))
}

/// `θ` and the terms of `∇θ` at `x` (module docs): `(θ, ∂θ/∂x2, ∂θ/∂x3, t2, t3)`, from which
/// `∂θ/∂x1 = −t2 ∂θ/∂x2 − t3 ∂θ/∂x3` and `∂θ/∂x0 = −(1 − t2) ∂θ/∂x2 − (1 − t3) ∂θ/∂x3`
/// ([`edge_gradients`]).
#[inline(always)]
pub(crate) fn angle_terms(x: &[[f64; 3]; 4]) -> (f64, [f64; 3], [f64; 3], f64, f64) {
    let e = sub(x[1], x[0]);
    let a = sub(x[2], x[0]);
    let b = sub(x[3], x[0]);
    let n1 = cross(e, a);
    let n2 = cross(b, e);
    let l2 = dot(e, e);
    let l = l2.sqrt();
    let theta = atan2(dot(e, cross(n1, n2)), l * dot(n1, n2));
    let g2 = scale(-l / dot(n1, n1), n1);
    let g3 = scale(-l / dot(n2, n2), n2);
    let t2 = dot(a, e) / l2;
    let t3 = dot(b, e) / l2;
    (theta, g2, g3, t2, t3)
}

/// The gradients at the edge's nodes from those at the wings (module docs): `[∂/∂x0, ∂/∂x1]`
/// `= [−(1 − t2) g2 − (1 − t3) g3, −t2 g2 − t3 g3]`.
#[inline(always)]
pub(crate) fn edge_gradients(g2: [f64; 3], g3: [f64; 3], t2: f64, t3: f64) -> [[f64; 3]; 2] {
    let mut out = [[0.0; 3]; 2];
    for c in 0..3 {
        out[0][c] = -(1.0 - t2) * g2[c] - (1.0 - t3) * g3[c];
        out[1][c] = -t2 * g2[c] - t3 * g3[c];
    }
    out
}

/// `θ` and `∇θ` at `x` (module docs).
#[inline(always)]
pub(crate) fn angle_gradient(x: &[[f64; 3]; 4]) -> HingeAngle {
    let (theta, g2, g3, t2, t3) = angle_terms(x);
    let [g0, g1] = edge_gradients(g2, g3, t2, t3);
    HingeAngle {
        theta,
        grad: [g0, g1, g2, g3],
    }
}

type Block = [[f64; 3]; 3];

/// `[v]×`, the matrix of `u ↦ v × u`.
#[inline(always)]
fn cross_matrix(v: [f64; 3]) -> Block {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

#[inline(always)]
fn matmul(a: &Block, b: &Block) -> Block {
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    out
}

#[inline(always)]
fn outer(a: [f64; 3], b: [f64; 3]) -> Block {
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = a[i] * b[j];
        }
    }
    out
}

#[inline(always)]
fn lincomb(terms: &[(f64, &Block)]) -> Block {
    let mut out = [[0.0; 3]; 3];
    for (s, m) in terms {
        for i in 0..3 {
            for j in 0..3 {
                out[i][j] += s * m[i][j];
            }
        }
    }
    out
}

/// `θ`, `∇θ` and the Hessian `∇²θ` as 4 × 4 blocks `H[i][j] = ∂²θ/∂x_i∂x_j` (row-major
/// 3 × 3), symmetric to round-off (docs/math.md §5.2).
pub(crate) fn angle_hessian(x: &[[f64; 3]; 4]) -> (HingeAngle, [[Block; 4]; 4]) {
    let e = sub(x[1], x[0]);
    let a = sub(x[2], x[0]);
    let b = sub(x[3], x[0]);
    let n1 = cross(e, a);
    let n2 = cross(b, e);
    let (s1, s2) = (dot(n1, n1), dot(n2, n2));
    let l2 = dot(e, e);
    let l = l2.sqrt();
    let e_hat = scale(1.0 / l, e);
    let theta = atan2(dot(e, cross(n1, n2)), l * dot(n1, n2));
    let g2 = scale(-l / s1, n1);
    let g3 = scale(-l / s2, n2);
    let t2 = dot(a, e) / l2;
    let t3 = dot(b, e) / l2;
    let mut grad = [[0.0; 3]; 4];
    for c in 0..3 {
        grad[0][c] = -(1.0 - t2) * g2[c] - (1.0 - t3) * g3[c];
        grad[1][c] = -t2 * g2[c] - t3 * g3[c];
        grad[2][c] = g2[c];
        grad[3][c] = g3[c];
    }
    // P_i = I − 2 n̂_i n̂_iᵀ.
    let reflect = |n: [f64; 3], s: f64| -> Block {
        let mut p = outer(n, n);
        for i in 0..3 {
            for j in 0..3 {
                p[i][j] *= -2.0 / s;
            }
            p[i][i] += 1.0;
        }
        p
    };
    let (p1, p2) = (reflect(n1, s1), reflect(n2, s2));
    let (ea, eb, ee) = (cross_matrix(a), cross_matrix(b), cross_matrix(e));
    // ∂g2/∂e, ∂g2/∂a, ∂g3/∂e, ∂g3/∂b (docs/math.md §5.2).
    let d2e = lincomb(&[(l / s1, &matmul(&p1, &ea)), (-1.0 / s1, &outer(n1, e_hat))]);
    let d2a = lincomb(&[(-l / s1, &matmul(&p1, &ee))]);
    let d3e = lincomb(&[(-l / s2, &matmul(&p2, &eb)), (-1.0 / s2, &outer(n2, e_hat))]);
    let d3b = lincomb(&[(l / s2, &matmul(&p2, &ee))]);
    let zero = [[0.0; 3]; 3];
    // By node: e = x1 − x0, a = x2 − x0, b = x3 − x0.
    let dg2 = [lincomb(&[(-1.0, &d2e), (-1.0, &d2a)]), d2e, d2a, zero];
    let dg3 = [lincomb(&[(-1.0, &d3e), (-1.0, &d3b)]), d3e, zero, d3b];
    // ∂t2/∂e = (a − 2 t2 e)/l², ∂t2/∂a = e/l²; likewise t3 with b.
    let t2e = scale(1.0 / l2, sub(a, scale(2.0 * t2, e)));
    let t3e = scale(1.0 / l2, sub(b, scale(2.0 * t3, e)));
    let el = scale(1.0 / l2, e);
    let neg = |v: [f64; 3], w: [f64; 3]| [-v[0] - w[0], -v[1] - w[1], -v[2] - w[2]];
    let dt2 = [neg(t2e, el), t2e, el, [0.0; 3]];
    let dt3 = [neg(t3e, el), t3e, [0.0; 3], el];
    let mut h = [[zero; 4]; 4];
    for j in 0..4 {
        // g1 = −t2 g2 − t3 g3.
        let dg1 = lincomb(&[
            (-1.0, &outer(g2, dt2[j])),
            (-t2, &dg2[j]),
            (-1.0, &outer(g3, dt3[j])),
            (-t3, &dg3[j]),
        ]);
        // g0 = −g1 − g2 − g3.
        h[0][j] = lincomb(&[(-1.0, &dg1), (-1.0, &dg2[j]), (-1.0, &dg3[j])]);
        h[1][j] = dg1;
        h[2][j] = dg2[j];
        h[3][j] = dg3[j];
    }
    // Symmetric analytically: average the two halves so it is symmetric to the last bit.
    for i in 0..4 {
        for j in i..4 {
            for r in 0..3 {
                for c in 0..3 {
                    let s = 0.5 * (h[i][j][r][c] + h[j][i][c][r]);
                    h[i][j][r][c] = s;
                    h[j][i][c][r] = s;
                }
            }
        }
    }
    (HingeAngle { theta, grad }, h)
}

/// `θ − θ0` wrapped into `(−π, π]`, so a hinge whose rest angle is near ±π does not see a jump
/// of 2π where `θ` crosses the branch cut.
#[inline(always)]
pub(crate) fn angle_difference(theta: f64, rest: f64) -> f64 {
    let d = theta - rest;
    if d > std::f64::consts::PI {
        d - 2.0 * std::f64::consts::PI
    } else if d <= -std::f64::consts::PI {
        d + 2.0 * std::f64::consts::PI
    } else {
        d
    }
}

/// The positions of a hinge's nodes in an interleaved vector.
#[inline(always)]
fn gather(x: &[f64], nodes: &[usize; 4]) -> [[f64; 3]; 4] {
    nodes.map(|a| [x[3 * a], x[3 * a + 1], x[3 * a + 2]])
}

impl Hinge {
    /// Its stiffness `k w`.
    pub fn stiffness(&self) -> f64 {
        self.k * self.weight
    }

    /// The signed dihedral angle `θ` at interleaved positions `x` (module docs). Like every
    /// per-hinge method, panics when a node index is out of range of `x`.
    ///
    /// ```
    /// use nurbspring_msm::{Hinge, HingeKind};
    /// // The edge along x, one wing at +y, the other folded up by 90°: θ = −π/2.
    /// let x = [0., 0., 0., 1., 0., 0., 0.5, 1., 0., 0.5, 0., 1.];
    /// let h = Hinge { nodes: [0, 1, 2, 3], kind: HingeKind::Grid, k: 1.0, weight: 1.0, rest_angle: 0.0 };
    /// assert!((h.angle(&x) + std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    /// ```
    pub fn angle(&self, x: &[f64]) -> f64 {
        angle(&gather(x, &self.nodes))
    }

    /// Elastic energy `½ k w (θ − θ0)²`.
    pub fn energy(&self, x: &[f64]) -> f64 {
        let d = angle_difference(self.angle(x), self.rest_angle);
        0.5 * self.stiffness() * d * d
    }

    /// The elastic (restoring) forces on its four nodes, `−k w (θ − θ0) ∂θ/∂x_i`.
    pub fn forces(&self, x: &[f64]) -> [[f64; 3]; 4] {
        let g = angle_gradient(&gather(x, &self.nodes));
        let s = -self.stiffness() * angle_difference(g.theta, self.rest_angle);
        g.grad.map(|gi| scale(s, gi))
    }

    /// The tangent stiffness `∂²E/∂x_i∂x_j = k w (∇θ ∇θᵀ + (θ − θ0) ∇²θ)` as 4 × 4 blocks
    /// (row-major 3 × 3); with `gauss_newton`, only `k w ∇θ ∇θᵀ` (positive semi-definite, and
    /// the exact tangent at rest, where `θ = θ0`).
    pub fn stiffness_blocks(&self, x: &[f64], gauss_newton: bool) -> [[Block; 4]; 4] {
        hinge_blocks(
            &gather(x, &self.nodes),
            self.stiffness(),
            self.rest_angle,
            gauss_newton,
        )
    }
}

/// `kw (∇θ ∇θᵀ + (θ − θ0) ∇²θ)` (or its Gauss–Newton part) at the four points `x`.
pub(crate) fn hinge_blocks(
    x: &[[f64; 3]; 4],
    kw: f64,
    rest: f64,
    gauss_newton: bool,
) -> [[Block; 4]; 4] {
    let (g, mut h) = if gauss_newton {
        (angle_gradient(x), [[[[0.0; 3]; 3]; 4]; 4])
    } else {
        angle_hessian(x)
    };
    let d = if gauss_newton {
        0.0
    } else {
        angle_difference(g.theta, rest)
    };
    for i in 0..4 {
        for j in 0..4 {
            for r in 0..3 {
                for c in 0..3 {
                    h[i][j][r][c] = kw * (g.grad[i][r] * g.grad[j][c] + d * h[i][j][r][c]);
                }
            }
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inlined `atan2` against `f64::atan2`: within 4 ε of the value (both are rounded
    /// results; the reduction and the division each round once) over magnitudes 1e-12 … 1e12 of
    /// both arguments and every sign, and the same values on the axes.
    #[test]
    fn atan2_agrees_with_std_to_a_few_ulp() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut worst = 0.0_f64;
        for _ in 0..200_000 {
            let y = 10f64.powf(24.0 * uniform() - 12.0) * if uniform() < 0.5 { -1.0 } else { 1.0 };
            let x = 10f64.powf(24.0 * uniform() - 12.0) * if uniform() < 0.5 { -1.0 } else { 1.0 };
            let (ours, std) = (atan2(y, x), y.atan2(x));
            worst = worst.max((ours - std).abs() / (f64::EPSILON * std.abs()));
        }
        assert!(worst <= 4.0, "{worst} ε");
        for (y, x) in [
            (0.0, 1.0),
            (0.0, -1.0),
            (1.0, 0.0),
            (-1.0, 0.0),
            (0.0, 0.0),
            (1.0, 1.0),
        ] {
            assert_eq!(atan2(y, x), f64::atan2(y, x), "atan2({y}, {x})");
        }
        assert!(atan2(f64::NAN, 1.0).is_nan() && atan2(1.0, f64::NAN).is_nan());
        assert!(atan2(0.0, f64::NAN).is_nan() && atan2(f64::NAN, 0.0).is_nan());
    }

    /// A flat hinge folded by hand: wings at height h1 = 1 and h2 = 2 over an edge of length
    /// 2, wing 2 lifted by a small δ out of the plane turns θ by −δ/h2; the gradient says
    /// `∂θ/∂x3 = −ẑ/h2`, `∂θ/∂x2 = −ẑ/h1` (module docs).
    #[test]
    fn the_gradient_of_a_flat_hinge_by_hand() {
        let x = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [1.5, -2.0, 0.0],
        ];
        let g = angle_gradient(&x);
        assert_eq!(g.theta, 0.0);
        assert_eq!(g.grad[2], [0.0, 0.0, -1.0]);
        assert_eq!(g.grad[3], [0.0, 0.0, -0.5]);
        // t2 = 0.25, t3 = 0.75: x1 gets −(0.25 g2 + 0.75 g3), x0 the rest.
        assert_eq!(g.grad[1], [0.0, 0.0, 0.25 + 0.375]);
        assert_eq!(g.grad[0], [0.0, 0.0, 0.75 + 0.125]);
    }

    #[test]
    fn the_angle_difference_wraps_across_the_branch_cut() {
        let pi = std::f64::consts::PI;
        assert!((angle_difference(-pi + 0.1, pi - 0.1) - 0.2).abs() < 1e-15);
        assert!((angle_difference(pi - 0.1, -pi + 0.1) + 0.2).abs() < 1e-15);
        assert_eq!(angle_difference(0.3, 0.1), 0.3 - 0.1);
    }
}
