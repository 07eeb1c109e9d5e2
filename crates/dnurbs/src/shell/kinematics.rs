//! Kinematics of the Kirchhoff–Love shell at one quadrature point (docs/math.md §10.2): the
//! covariant frame of a NURBS surface, its metric and curvature, the strains, and their first
//! and second variations with respect to the control points.
//!
//! Notation: `a_α = x_{,α}` (α = 1, 2 for u, v), `a_3 = a_1 × a_2 / ℓ` with `ℓ = |a_1 × a_2|`,
//! metric `a_{αβ} = a_α · a_β`, curvature `b_{αβ} = x_{,αβ} · a_3`; capitals for the rest shape.
//! Voigt order `(11, 22, 12)`; strains `ε = [ε11, ε22, 2ε12]` with `ε_{αβ} = ½ (a_{αβ} − A_{αβ})`
//! and `κ = [κ11, κ22, 2κ12]` with `κ_{αβ} = B_{αβ} − b_{αβ}` (Kiendl et al. 2009's sign: a
//! positive κ is a curvature lost).

/// Slots of the rational basis derivatives in the slot-major buffer `r[s · n_local + a]` of
/// [`crate::layout::rational_basis`]: `∂u`, `∂v` and the second derivatives in Voigt order
/// `(uu, vv, uv)`.
pub(crate) const FIRST: [usize; 2] = [1, 2];
/// Second-derivative slots in Voigt order `(11, 22, 12)`.
pub(crate) const SECOND: [usize; 3] = [3, 5, 4];

/// The surface's frame at one point (docs/math.md §10.2).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Frame {
    /// `a_1`, `a_2`.
    pub(crate) tangents: [[f64; 3]; 2],
    /// `a_3`, the unit normal.
    pub(crate) normal: [f64; 3],
    /// `ℓ = |a_1 × a_2|`, the area element of the parameter domain.
    pub(crate) area: f64,
    /// `x_{,11}`, `x_{,22}`, `x_{,12}`.
    pub(crate) second: [[f64; 3]; 3],
    /// `[a_11, a_22, a_12]`.
    pub(crate) metric: [f64; 3],
    /// `[b_11, b_22, b_12]`.
    pub(crate) curvature: [f64; 3],
    /// `[a^11, a^22, a^12]`, the inverse metric.
    pub(crate) inverse_metric: [f64; 3],
}

#[inline]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl Frame {
    /// The frame of `x = Σ_a R_a x_a` from the slot-major rational basis `r` of `n_local`
    /// points and the local control points `points`.
    #[inline(always)]
    pub(crate) fn new(r: &[f64], points: &[[f64; 3]]) -> Self {
        let nl = points.len();
        let mut tangents = [[0.0; 3]; 2];
        let mut second = [[0.0; 3]; 3];
        for (a, x) in points.iter().enumerate() {
            for (t, &s) in tangents.iter_mut().zip(&FIRST) {
                let c = r[s * nl + a];
                for k in 0..3 {
                    t[k] += c * x[k];
                }
            }
            for (t, &s) in second.iter_mut().zip(&SECOND) {
                let c = r[s * nl + a];
                for k in 0..3 {
                    t[k] += c * x[k];
                }
            }
        }
        let [a1, a2] = tangents;
        let n = cross(a1, a2);
        let area = dot(n, n).sqrt();
        let normal = n.map(|c| c / area);
        let metric = [dot(a1, a1), dot(a2, a2), dot(a1, a2)];
        let det = metric[0] * metric[1] - metric[2] * metric[2];
        let inverse_metric = [metric[1] / det, metric[0] / det, -metric[2] / det];
        let curvature = second.map(|s| dot(s, normal));
        Self {
            tangents,
            normal,
            area,
            second,
            metric,
            curvature,
            inverse_metric,
        }
    }

    /// The contravariant base vectors `a^α = a^{αβ} a_β`.
    pub(crate) fn dual_tangents(&self) -> [[f64; 3]; 2] {
        let [g11, g22, g12] = self.inverse_metric;
        let [a1, a2] = self.tangents;
        [
            std::array::from_fn(|k| g11 * a1[k] + g12 * a2[k]),
            std::array::from_fn(|k| g12 * a1[k] + g22 * a2[k]),
        ]
    }
}

/// The rest state of one quadrature point (docs/math.md §10.1–10.2).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RestPoint {
    /// Gauss weight × `|A_1 × A_2|`: the point's share of the rest area.
    pub(crate) weight: f64,
    /// `[A_11, A_22, A_12]`.
    pub(crate) metric: [f64; 3],
    /// `[B_11, B_22, B_12]`.
    pub(crate) curvature: [f64; 3],
    /// `t C` (Voigt), the membrane stiffness.
    pub(crate) membrane: [[f64; 3]; 3],
    /// `t³/12 C` (Voigt), the bending stiffness.
    pub(crate) bending: [[f64; 3]; 3],
}

#[inline]
pub(crate) fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// Strains and stress resultants at one point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Resultants {
    /// Membrane strain `[ε11, ε22, 2ε12]`.
    pub(crate) strain: [f64; 3],
    /// Curvature change `[κ11, κ22, 2κ12]`.
    pub(crate) curvature_change: [f64; 3],
    /// Normal forces `n = t C ε` (Voigt).
    pub(crate) forces: [f64; 3],
    /// Moments `m = t³/12 C κ` (Voigt).
    pub(crate) moments: [f64; 3],
}

impl Resultants {
    #[inline(always)]
    pub(crate) fn new(frame: &Frame, rest: &RestPoint) -> Self {
        let strain = [
            0.5 * (frame.metric[0] - rest.metric[0]),
            0.5 * (frame.metric[1] - rest.metric[1]),
            frame.metric[2] - rest.metric[2],
        ];
        let curvature_change = [
            rest.curvature[0] - frame.curvature[0],
            rest.curvature[1] - frame.curvature[1],
            2.0 * (rest.curvature[2] - frame.curvature[2]),
        ];
        Self {
            strain,
            curvature_change,
            forces: mat_vec(&rest.membrane, strain),
            moments: mat_vec(&rest.bending, curvature_change),
        }
    }

    /// The energy density per rest area, `½ ε·n + ½ κ·m`.
    pub(crate) fn energy_density(&self) -> f64 {
        0.5 * (dot(self.strain, self.forces) + dot(self.curvature_change, self.moments))
    }

    /// The weights `w_{αβ}` with `m · δκ = −Σ w_{αβ} δb_{αβ}`, Voigt order: `[m1, m2, 2 m3]`.
    pub(crate) fn curvature_weights(&self) -> [f64; 3] {
        [self.moments[0], self.moments[1], 2.0 * self.moments[2]]
    }
}
