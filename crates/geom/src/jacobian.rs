//! The Jacobian `J(u, v) = ∂c/∂p` of a NURBS point with respect to the generalized
//! coordinates (docs/math.md §2), stored sparsely, and its parametric derivatives.

/// Which parametric derivative of `J` (or of `c`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Deriv {
    /// J itself.
    Value = 0,
    /// ∂/∂u.
    U = 1,
    /// ∂/∂v.
    V = 2,
    /// ∂²/∂u².
    UU = 3,
    /// ∂²/∂u∂v.
    UV = 4,
    /// ∂²/∂v².
    VV = 5,
}

impl Deriv {
    /// All six, in slot order.
    pub const ALL: [Deriv; 6] = [
        Deriv::Value,
        Deriv::U,
        Deriv::V,
        Deriv::UU,
        Deriv::UV,
        Deriv::VV,
    ];

    /// The slot index 0..6.
    pub fn slot(self) -> usize {
        self as usize
    }

    /// Derivative order (0, 1 or 2).
    pub fn order(self) -> usize {
        match self {
            Deriv::Value => 0,
            Deriv::U | Deriv::V => 1,
            _ => 2,
        }
    }

    /// Short name: "value", "u", "v", "uu", "uv", "vv".
    pub fn name(self) -> &'static str {
        ["value", "u", "v", "uu", "uv", "vv"][self as usize]
    }
}

/// `J(u, v)` and its derivatives at one parameter, as the non-zero blocks only.
///
/// With constant weights (3 dofs per control point), the block of control point `k` in
/// `J^{(d)}` is `R_k^{(d)} I_3`. With weights as unknowns (4 dofs) the block gains the column
/// `∂c^{(d)}/∂w_k`. For curves the v slots are zero.
///
/// ```
/// use nurbspring_geom::{Deriv, KnotVector, NurbsSurface};
/// let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
/// let pts: Vec<[f64; 3]> = (0..9).map(|i| [(i / 3) as f64, (i % 3) as f64, (i * i) as f64]).collect();
/// let s = NurbsSurface::try_new(k.clone(), k, pts.clone(), vec![1.0; 9]).unwrap();
/// let j = s.jacobian(0.3, 0.6, 2, false).unwrap();
/// let p: Vec<f64> = pts.iter().flatten().copied().collect();
/// let c = s.point(0.3, 0.6).unwrap();
/// let jp = j.apply(Deriv::Value, &p);
/// for x in 0..3 { assert!((jp[x] - c[x]).abs() < 1e-13); } // J p = c
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Jacobian {
    /// Number of control points of the whole surface or curve.
    pub n_control_points: usize,
    /// 3 (constant weights) or 4 (weights as unknowns).
    pub dofs_per_point: usize,
    /// Highest derivative order filled (0, 1 or 2).
    pub order: usize,
    /// Flat control point indices of the non-zero blocks.
    pub indices: Vec<usize>,
    /// For each block, `[R, R_u, R_v, R_uu, R_uv, R_vv]`.
    pub r: Vec<[f64; 6]>,
    /// For each block (only with 4 dofs), `∂c^{(d)}/∂w_k` for the six slots.
    pub weight_columns: Vec<[[f64; 3]; 6]>,
}

/// The Jacobian of a surface point.
pub type SurfaceJacobian = Jacobian;

impl Jacobian {
    /// Number of non-zero blocks.
    pub fn n_local(&self) -> usize {
        self.indices.len()
    }

    /// Total number of generalized coordinates (columns of J).
    pub fn n_dofs(&self) -> usize {
        self.n_control_points * self.dofs_per_point
    }

    /// Global dof index of component `c` (0..dofs_per_point) of local block `l`.
    pub fn dof(&self, l: usize, c: usize) -> usize {
        self.indices[l] * self.dofs_per_point + c
    }

    /// The 3-vector column `J^{(d)}[:, dof(l, c)]`.
    pub fn column(&self, l: usize, c: usize, d: Deriv) -> [f64; 3] {
        if c == 3 {
            return self.weight_columns[l][d.slot()];
        }
        let mut col = [0.0; 3];
        col[c] = self.r[l][d.slot()];
        col
    }

    /// `J^{(d)} p` for a full generalized coordinate vector `p` (length `n_dofs()`).
    pub fn apply(&self, d: Deriv, p: &[f64]) -> [f64; 3] {
        let s = d.slot();
        let m = self.dofs_per_point;
        let mut out = [0.0; 3];
        for (l, &k) in self.indices.iter().enumerate() {
            let r = self.r[l][s];
            for x in 0..3 {
                out[x] += r * p[k * m + x];
            }
            if m == 4 {
                let col = self.weight_columns[l][s];
                for x in 0..3 {
                    out[x] += col[x] * p[k * m + 3];
                }
            }
        }
        out
    }

    /// `J^{(d)ᵀ} f` accumulated into `out` (length `n_dofs()`), scaled by `alpha`.
    pub fn apply_transpose_add(&self, d: Deriv, f: [f64; 3], alpha: f64, out: &mut [f64]) {
        let s = d.slot();
        let m = self.dofs_per_point;
        for (l, &k) in self.indices.iter().enumerate() {
            let r = alpha * self.r[l][s];
            for x in 0..3 {
                out[k * m + x] += r * f[x];
            }
            if m == 4 {
                let col = self.weight_columns[l][s];
                out[k * m + 3] += alpha * (col[0] * f[0] + col[1] * f[1] + col[2] * f[2]);
            }
        }
    }

    /// Appends the non-zero entries of `J^{(d)}` as `(row0 + x, dof, value)` triplets: the block
    /// of one point in a stacked Jacobian whose rows `row0 .. row0 + 3` belong to it (paper
    /// eq. (14) stacks these for every lattice node).
    pub fn push_triplets(&self, d: Deriv, row0: usize, out: &mut Vec<(usize, usize, f64)>) {
        for l in 0..self.n_local() {
            for c in 0..self.dofs_per_point {
                let col = self.column(l, c, d);
                let j = self.dof(l, c);
                for (x, &value) in col.iter().enumerate() {
                    if value != 0.0 {
                        out.push((row0 + x, j, value));
                    }
                }
            }
        }
    }

    /// `J^{(d)}` as a dense row-major `3 × n_dofs()` matrix (tests and small problems).
    pub fn to_dense(&self, d: Deriv) -> Vec<f64> {
        let n = self.n_dofs();
        let mut out = vec![0.0; 3 * n];
        for l in 0..self.n_local() {
            for c in 0..self.dofs_per_point {
                let col = self.column(l, c, d);
                let j = self.dof(l, c);
                for x in 0..3 {
                    out[x * n + j] = col[x];
                }
            }
        }
        out
    }
}
