//! The shape a D-NURBS model is built on: a NURBS surface or curve (paper eq. (1)), with
//! conversions between the shape and the generalized coordinates `p` (docs/math.md §1).

use nurbspring_geom::{Deriv, GeomError, Jacobian, LocalRationalBasis, NurbsCurve, NurbsSurface};

use nurbspring_linalg::SparseMatrix;

use crate::DnurbsError;

/// A NURBS surface or curve. Curves are the one-parameter case of everything (docs/math.md §2).
#[derive(Clone, Debug)]
pub enum Geometry {
    /// A tensor-product surface, control point `(i, j)` at flat index `i · n_v + j`.
    Surface(NurbsSurface),
    /// A curve.
    Curve(NurbsCurve),
}

impl From<NurbsSurface> for Geometry {
    fn from(s: NurbsSurface) -> Self {
        Geometry::Surface(s)
    }
}

impl From<NurbsCurve> for Geometry {
    fn from(c: NurbsCurve) -> Self {
        Geometry::Curve(c)
    }
}

impl Geometry {
    /// Number of control points N.
    pub fn n_control_points(&self) -> usize {
        match self {
            Geometry::Surface(s) => s.n_control_points(),
            Geometry::Curve(c) => c.n_control_points(),
        }
    }

    /// Generalized coordinates per control point: 3, or 4 with weights as unknowns.
    pub fn dofs_per_point(&self, weights_as_dofs: bool) -> usize {
        if weights_as_dofs { 4 } else { 3 }
    }

    /// True for a curve.
    pub fn is_curve(&self) -> bool {
        matches!(self, Geometry::Curve(_))
    }

    /// The control net's shape `(n_u, n_v)`; a curve is `(n, 1)`.
    pub fn net_shape(&self) -> (usize, usize) {
        match self {
            Geometry::Surface(s) => (s.n_u(), s.n_v()),
            Geometry::Curve(c) => (c.n_control_points(), 1),
        }
    }

    /// Degrees `(p, q)`; a curve is `(p, 0)`.
    pub fn degrees(&self) -> (usize, usize) {
        match self {
            Geometry::Surface(s) => (s.basis_u().degree(), s.basis_v().degree()),
            Geometry::Curve(c) => (c.basis().degree(), 0),
        }
    }

    /// Control points.
    pub fn control_points(&self) -> &[[f64; 3]] {
        match self {
            Geometry::Surface(s) => s.control_points(),
            Geometry::Curve(c) => c.control_points(),
        }
    }

    /// Weights.
    pub fn weights(&self) -> &[f64] {
        match self {
            Geometry::Surface(s) => s.weights(),
            Geometry::Curve(c) => c.weights(),
        }
    }

    /// True when every weight equals the first (a B-spline up to scale).
    pub fn has_uniform_weights(&self) -> bool {
        let w = self.weights();
        w.iter().all(|&x| x == w[0])
    }

    /// The parameter domain `((u0, u1), (v0, v1))`; a curve has `(v0, v1) = (0, 0)`.
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        match self {
            Geometry::Surface(s) => s.domain(),
            Geometry::Curve(c) => (c.domain(), (0.0, 0.0)),
        }
    }

    /// Measure of the parameter domain: `(u1 − u0)(v1 − v0)`, or `u1 − u0` for a curve.
    pub fn parameter_measure(&self) -> f64 {
        let ((u0, u1), (v0, v1)) = self.domain();
        match self {
            Geometry::Surface(_) => (u1 - u0) * (v1 - v0),
            Geometry::Curve(_) => u1 - u0,
        }
    }

    /// The generalized coordinates `p` of this shape (docs/math.md §1): `[x, y, z]` per control point,
    /// or `[x, y, z, w]` with weights as unknowns.
    pub fn coordinates(&self, weights_as_dofs: bool) -> Vec<f64> {
        let m = self.dofs_per_point(weights_as_dofs);
        let mut p = Vec::with_capacity(m * self.n_control_points());
        for (c, &w) in self.control_points().iter().zip(self.weights()) {
            p.extend_from_slice(c);
            if weights_as_dofs {
                p.push(w);
            }
        }
        p
    }

    /// The same knots with the control points (and, with 4 dofs, the weights) taken from `p`.
    pub fn with_coordinates(
        &self,
        p: &[f64],
        weights_as_dofs: bool,
    ) -> Result<Geometry, DnurbsError> {
        let m = self.dofs_per_point(weights_as_dofs);
        let n = self.n_control_points();
        if p.len() != m * n {
            return Err(DnurbsError::DimensionMismatch {
                what: "generalized coordinates p",
                expected: m * n,
                found: p.len(),
            });
        }
        let points: Vec<[f64; 3]> = p.chunks_exact(m).map(|c| [c[0], c[1], c[2]]).collect();
        let weights: Vec<f64> = if weights_as_dofs {
            p.chunks_exact(4).map(|c| c[3]).collect()
        } else {
            self.weights().to_vec()
        };
        Ok(match self {
            Geometry::Surface(s) => {
                Geometry::Surface(s.with_control_points_and_weights(points, weights)?)
            }
            Geometry::Curve(c) => Geometry::Curve(NurbsCurve::try_new(
                c.basis().knots().clone(),
                points,
                weights,
            )?),
        })
    }

    /// Checks `(u, v)` against the domain (`v` is ignored for curves).
    pub fn check_parameters(&self, u: f64, v: f64) -> Result<(), GeomError> {
        match self {
            Geometry::Surface(s) => s.check_parameters(u, v),
            Geometry::Curve(c) => c.basis().knots().check_parameter("u", u),
        }
    }

    /// The point `c(u, v)` (paper eq. (1)); `v` is ignored for curves.
    pub fn point(&self, u: f64, v: f64) -> Result<[f64; 3], GeomError> {
        match self {
            Geometry::Surface(s) => s.point(u, v),
            Geometry::Curve(c) => c.point(u),
        }
    }

    /// `J(u, v) = ∂c/∂p` and its parametric derivatives up to `order` (docs/math.md §2).
    pub fn jacobian(
        &self,
        u: f64,
        v: f64,
        order: usize,
        weights_as_dofs: bool,
    ) -> Result<Jacobian, GeomError> {
        match self {
            Geometry::Surface(s) => s.jacobian(u, v, order, weights_as_dofs),
            Geometry::Curve(c) => c.jacobian(u, order, weights_as_dofs),
        }
    }

    /// The Jacobians `J(u_a, v_a)` stacked for every parameter point `a` (rows `3a .. 3a + 3`):
    /// a `3 n_points × d N` matrix, `d` = 3 or 4 with weights as unknowns. Multiplied by `p` it
    /// gives the points; for lattice nodes it is Ω of paper eq. (14), with `x(0) = Ω p(0)`
    /// (eq. 11) and `ẋ(0) = Ω ṗ(0)` (eq. 18). `v` is ignored for curves. Errors name the first
    /// parameter outside the domain.
    pub fn stacked_jacobian(
        &self,
        params: &[(f64, f64)],
        weights_as_dofs: bool,
    ) -> Result<SparseMatrix, DnurbsError> {
        let mut triplets = Vec::new();
        for (a, &(u, v)) in params.iter().enumerate() {
            let j = self.jacobian(u, v, 0, weights_as_dofs)?;
            j.push_triplets(Deriv::Value, 3 * a, &mut triplets);
        }
        let d = self.dofs_per_point(weights_as_dofs);
        Ok(SparseMatrix::from_triplets(
            3 * params.len(),
            d * self.n_control_points(),
            &triplets,
        )?)
    }

    /// [`Geometry::jacobian`] into caller buffers, parameters unchecked (assembly loops).
    pub(crate) fn jacobian_into(
        &self,
        u: f64,
        v: f64,
        order: usize,
        weights_as_dofs: bool,
        buffer: &mut LocalRationalBasis,
        out: &mut Jacobian,
    ) {
        match self {
            Geometry::Surface(s) => s.jacobian_into(u, v, order, weights_as_dofs, buffer, out),
            Geometry::Curve(c) => {
                // Parameters come from the quadrature rule, inside the domain.
                if let Ok(j) = c.jacobian(u, order, weights_as_dofs) {
                    *out = j;
                }
            }
        }
    }

    /// `c(u, v)` with a caller buffer, parameters unchecked (assembly loops).
    pub(crate) fn point_with(&self, u: f64, v: f64, buffer: &mut LocalRationalBasis) -> [f64; 3] {
        match self {
            Geometry::Surface(s) => s.derivatives_with(u, v, 0, buffer).point,
            Geometry::Curve(c) => c.point(u).unwrap_or([f64::NAN; 3]),
        }
    }
}

/// Flat indices of the control points in the `rings` outer rings of an `n_u × n_v` net
/// (ascending). For curves (`n_v = 1`) the `rings` first and the `rings` last points.
///
/// ```
/// use nurbspring_dnurbs::outer_ring_points;
/// // The paper's 7 × 5 net: two rings fix 32 of 35 points, 3 interior ones stay free.
/// let fixed = outer_ring_points(7, 5, 2);
/// assert_eq!(fixed.len(), 32);
/// let free: Vec<usize> = (0..35).filter(|k| !fixed.contains(k)).collect();
/// assert_eq!(free, vec![12, 17, 22]); // (i, j) = (2, 2), (3, 2), (4, 2)
/// assert_eq!(outer_ring_points(6, 1, 1), vec![0, 5]);
/// ```
pub fn outer_ring_points(n_u: usize, n_v: usize, rings: usize) -> Vec<usize> {
    if rings == 0 {
        return Vec::new();
    }
    if n_v == 1 {
        return (0..n_u)
            .filter(|&i| i < rings || i + rings >= n_u)
            .collect();
    }
    (0..n_u)
        .flat_map(|i| (0..n_v).map(move |j| (i, j)))
        .filter(|&(i, j)| i < rings || i + rings >= n_u || j < rings || j + rings >= n_v)
        .map(|(i, j)| i * n_v + j)
        .collect()
}
