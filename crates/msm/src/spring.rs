//! Springs and the per-spring formulas of the paper's eqs. (5) and (9) (docs/math.md §5).
//!
//! For a spring `(a, b, k, l)` with `d = x_a − x_b`, `r = |d|`, `n = d / r`:
//! - force on `a` (eq. 5): `f_a = k (l − r) n = k (l/r − 1) d`, and `f_b = −f_a`;
//! - energy: `E = k (r − l)² / 2`, so that `f_a = −∂E/∂x_a`;
//! - linearization (eq. 9): `∂f_a/∂x_a = −B`, `∂f_a/∂x_b = B` with the symmetric block
//!   `B = k [ (l/r) n nᵀ + (1 − l/r) I ]`.  The tangent stiffness `K_T = −∂f/∂x` receives
//!   `+B` on the diagonal blocks `(a, a)`, `(b, b)` and `−B` on `(a, b)`, `(b, a)`.

use serde::{Deserialize, Serialize};

/// The class of a spring (Figure 1 of the paper and its "interleaving" bending springs).
///
/// Each class has one stiffness in the paper's fit, so `K_S = Σ_c k_c G_c` (docs/math.md §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpringKind {
    /// Between grid neighbours along u or v (`k_edge`).
    Structural,
    /// On both diagonals of each grid cell (`k_diag`).
    Shear,
    /// Between second neighbours along u or v (`k_bend`).
    Bend,
}

impl SpringKind {
    /// Every kind, in the order used for reports and fits.
    pub const ALL: [SpringKind; 3] = [SpringKind::Structural, SpringKind::Shear, SpringKind::Bend];

    /// Lower-case name, as in JSON files: `"structural"`, `"shear"`, `"bend"`.
    ///
    /// ```
    /// use nurbspring_msm::SpringKind;
    /// assert_eq!(SpringKind::Shear.name(), "shear");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            SpringKind::Structural => "structural",
            SpringKind::Shear => "shear",
            SpringKind::Bend => "bend",
        }
    }

    /// Parses a name given by [`SpringKind::name`] (also accepts `"bending"`, `"edge"`, `"diag"`).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "structural" | "edge" => Some(SpringKind::Structural),
            "shear" | "diag" | "diagonal" => Some(SpringKind::Shear),
            "bend" | "bending" => Some(SpringKind::Bend),
            _ => None,
        }
    }
}

impl std::fmt::Display for SpringKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A linear spring between nodes `a` and `b` (paper eq. (5)): class constant `k`, weight `w`
/// (its stiffness is `k w`), rest length `l`, and an optional dashpot `c` along it.
///
/// The weight carries what differs from spring to spring within a class (a derivation's
/// geometric factor); `K_S = Σ_c k_c G_c` with `G_c = Σ_{s ∈ c} w_s B_s(k = 1)`
/// (docs/math.md §5). Every builder makes `w = 1`, so a lattice without weights is the
/// paper's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spring {
    /// First node.
    pub a: usize,
    /// Second node.
    pub b: usize,
    /// Class of the spring.
    pub kind: SpringKind,
    /// Class constant `k ≥ 0`.
    pub k: f64,
    /// Rest length `l ≥ 0`.
    pub rest_length: f64,
    /// Weight `w > 0` (the stiffness is `k w`; 1 unless a derivation sets it).
    #[serde(default = "one")]
    pub weight: f64,
    /// Axial damping `c ≥ 0`: the force `−c ((v_a − v_b)·n) n` on `a` and its negative on `b`,
    /// `n` the spring's current direction (docs/math.md §5.1).
    #[serde(default)]
    pub damping: f64,
}

fn one() -> f64 {
    1.0
}

/// `x_a − x_b`.
#[inline(always)]
pub(crate) fn sub(xa: [f64; 3], xb: [f64; 3]) -> [f64; 3] {
    [xa[0] - xb[0], xa[1] - xb[1], xa[2] - xb[2]]
}

/// `|d|`.
#[inline(always)]
pub(crate) fn norm(d: [f64; 3]) -> f64 {
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// The scalar `s = k (1 − l/r)` such that the internal force on `a` is `s d`
/// (`f_int = −f_elastic`, paper eq. (5) with the sign of a stiffness).
#[inline(always)]
pub(crate) fn internal_coefficient(k: f64, l: f64, d: [f64; 3]) -> f64 {
    k * (1.0 - l / norm(d))
}

/// Spring energy `k (r − l)² / 2`.
#[inline(always)]
pub(crate) fn energy(k: f64, l: f64, d: [f64; 3]) -> f64 {
    let e = norm(d) - l;
    0.5 * k * e * e
}

/// The 3 × 3 block `B = k [ (l/r) n nᵀ + (1 − l/r) I ]` of paper eq. (9), row-major.
#[inline(always)]
pub(crate) fn stiffness_block(k: f64, l: f64, d: [f64; 3]) -> [[f64; 3]; 3] {
    stiffness_block_with(k, l, d, false)
}

/// [`stiffness_block`], or with `project` its positive semi-definite part: the geometric term
/// `k (1 − l/r) I` of a compressed spring (`r < l`, the only indefinite part) dropped, so that
/// `B = k [(l/r) n nᵀ + max(0, 1 − l/r) I]` (for `k ≥ 0`).
#[inline(always)]
pub(crate) fn stiffness_block_with(k: f64, l: f64, d: [f64; 3], project: bool) -> [[f64; 3]; 3] {
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let r = r2.sqrt();
    let ratio = l / r;
    // (l/r) n nᵀ = (l / r³) d dᵀ.
    let axial = k * ratio / r2;
    let geometric = if project {
        k * (1.0 - ratio).max(0.0)
    } else {
        k * (1.0 - ratio)
    };
    let mut block = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            block[i][j] = axial * d[i] * d[j];
        }
        block[i][i] += geometric;
    }
    block
}

impl Spring {
    /// A spring of class constant `k` and rest length `l`, weight 1, no damping.
    ///
    /// ```
    /// use nurbspring_msm::{Spring, SpringKind};
    /// let s = Spring::new(0, 1, SpringKind::Shear, 2.0, 1.5);
    /// assert_eq!((s.weight, s.damping, s.stiffness()), (1.0, 0.0, 2.0));
    /// ```
    pub fn new(a: usize, b: usize, kind: SpringKind, k: f64, rest_length: f64) -> Self {
        Self {
            a,
            b,
            kind,
            k,
            rest_length,
            weight: 1.0,
            damping: 0.0,
        }
    }

    /// Its stiffness `k w`.
    pub fn stiffness(&self) -> f64 {
        self.k * self.weight
    }

    /// Current length `|x_a − x_b|` for interleaved positions `x` (docs/math.md §1 ordering). Like every
    /// per-spring method, panics when a node index is out of range of `x`.
    pub fn length(&self, x: &[f64]) -> f64 {
        norm(sub(node(x, self.a), node(x, self.b)))
    }

    /// Elastic force on node `a` (paper eq. (5)): `k w (l − |d|) d/|d|`; node `b` gets its negative.
    ///
    /// ```
    /// use nurbspring_msm::{Spring, SpringKind};
    /// let s = Spring::new(0, 1, SpringKind::Structural, 2.0, 1.0);
    /// // Stretched to length 1.5 along x: the force pulls a towards b.
    /// let f = s.force_on_a(&[1.5, 0., 0., 0., 0., 0.]);
    /// assert!((f[0] + 1.0).abs() < 1e-15 && f[1] == 0.0 && f[2] == 0.0);
    /// ```
    pub fn force_on_a(&self, x: &[f64]) -> [f64; 3] {
        let d = sub(node(x, self.a), node(x, self.b));
        let s = -internal_coefficient(self.stiffness(), self.rest_length, d);
        [s * d[0], s * d[1], s * d[2]]
    }

    /// Elastic energy `k w (|d| − l)² / 2` (docs/math.md §5).
    pub fn energy(&self, x: &[f64]) -> f64 {
        energy(
            self.stiffness(),
            self.rest_length,
            sub(node(x, self.a), node(x, self.b)),
        )
    }

    /// The block `B = −∂f_a/∂x_a = k w [ (l/|d|) n nᵀ + (1 − l/|d|) I ]` of paper eq. (9)
    /// (docs/math.md §5), row-major.
    pub fn stiffness_block(&self, x: &[f64]) -> [[f64; 3]; 3] {
        stiffness_block(
            self.stiffness(),
            self.rest_length,
            sub(node(x, self.a), node(x, self.b)),
        )
    }
}

/// Position of node `a` in an interleaved vector.
#[inline(always)]
pub(crate) fn node(x: &[f64], a: usize) -> [f64; 3] {
    [x[3 * a], x[3 * a + 1], x[3 * a + 2]]
}

#[cfg(test)]
mod tests {
    use super::stiffness_block_with;

    /// A spring of k = 2, l = 1 compressed to r = 0.5 along x: by hand, the block is
    /// `2 [2 e eᵀ − I] = diag(2, −2, −2)` (indefinite) and its projection drops `−2 I`,
    /// leaving `diag(4, 0, 0)`; stretched to r = 2 the projection changes nothing.
    #[test]
    fn the_projected_block_drops_only_the_compressed_geometric_term() {
        let exact = stiffness_block_with(2.0, 1.0, [0.5, 0.0, 0.0], false);
        let projected = stiffness_block_with(2.0, 1.0, [0.5, 0.0, 0.0], true);
        let diag = |b: [[f64; 3]; 3]| [b[0][0], b[1][1], b[2][2]];
        assert_eq!(diag(exact), [2.0, -2.0, -2.0]);
        assert_eq!(diag(projected), [4.0, 0.0, 0.0]);
        let d = [1.2, -1.6, 0.0];
        assert_eq!(
            stiffness_block_with(2.0, 1.0, d, false),
            stiffness_block_with(2.0, 1.0, d, true)
        );
    }
}
