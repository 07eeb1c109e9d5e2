//! Rational curves (paper eq. 1; The NURBS Book §4.2).

use rayon::prelude::*;

use crate::basis::BasisScratch;
use crate::jacobian::Jacobian;
use crate::surface::{SurfaceDerivatives, check_points_and_weights, weight_column};
use crate::{BSplineBasis, GeomError, KnotVector, quotient_rule};

/// A NURBS curve `c(u) = Σ R_i(u) P_i`, `R_i = w_i N_i / Σ w_j N_j`.
///
/// A rational quadratic with weights `(1, √2/2, 1)` is an exact quarter circle:
/// ```
/// use nurbspring_geom::{KnotVector, NurbsCurve};
/// let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
/// let c = NurbsCurve::try_new(k, vec![[1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
///     vec![1.0, std::f64::consts::FRAC_1_SQRT_2, 1.0]).unwrap();
/// let p = c.point(0.37).unwrap();
/// assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-15);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsCurve {
    basis: BSplineBasis,
    control_points: Vec<[f64; 3]>,
    weights: Vec<f64>,
}

/// A point of a curve and its first two derivatives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CurveDerivatives {
    /// c(u).
    pub point: [f64; 3],
    /// c'(u).
    pub u: [f64; 3],
    /// c''(u).
    pub uu: [f64; 3],
}

impl NurbsCurve {
    /// Validates and builds a curve.
    pub fn try_new(
        knots: KnotVector,
        control_points: Vec<[f64; 3]>,
        weights: Vec<f64>,
    ) -> Result<Self, GeomError> {
        let n = knots.n_basis();
        if control_points.len() != n {
            return Err(GeomError::ControlPointCount {
                expected: n,
                found: control_points.len(),
                detail: format!(
                    "{} knots of degree {} give {n} basis functions",
                    knots.knots().len(),
                    knots.degree()
                ),
            });
        }
        if weights.len() != n {
            return Err(GeomError::WeightCount {
                expected: n,
                found: weights.len(),
            });
        }
        check_points_and_weights(&control_points, &weights)?;
        Ok(Self {
            basis: BSplineBasis::new(knots),
            control_points,
            weights,
        })
    }

    /// The basis.
    pub fn basis(&self) -> &BSplineBasis {
        &self.basis
    }

    /// Control points.
    pub fn control_points(&self) -> &[[f64; 3]] {
        &self.control_points
    }

    /// Weights.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Number of control points.
    pub fn n_control_points(&self) -> usize {
        self.control_points.len()
    }

    /// The parameter domain.
    pub fn domain(&self) -> (f64, f64) {
        self.basis.knots().domain()
    }

    /// A copy with other control points.
    pub fn with_control_points(&self, control_points: Vec<[f64; 3]>) -> Result<Self, GeomError> {
        Self::try_new(
            self.basis.knots().clone(),
            control_points,
            self.weights.clone(),
        )
    }

    /// Rational basis at `u` up to order 2: `(indices, [R, R_u, 0, R_uu, 0, 0], [A, …])`
    /// with `A = N / W`.
    fn rational_basis(
        &self,
        u: f64,
        order: usize,
        scratch: &mut BasisScratch,
    ) -> (Vec<usize>, Vec<[f64; 6]>, Vec<[f64; 6]>) {
        let p = self.basis.degree();
        let span = self.basis.find_span(u);
        let order = order.min(2);
        let mut nd = vec![0.0; (order + 1) * (p + 1)];
        self.basis
            .derivatives_into(span, u, order, &mut nd, scratch);
        let mut w = [0.0; 3];
        let indices: Vec<usize> = (span - p..=span).collect();
        for (a, &k) in indices.iter().enumerate() {
            for o in 0..=order {
                w[o] += self.weights[k] * nd[o * (p + 1) + a];
            }
        }
        let inv = 1.0 / w[0];
        let mut r = Vec::with_capacity(p + 1);
        let mut aa = Vec::with_capacity(p + 1);
        for (a, &k) in indices.iter().enumerate() {
            // The u slots of the quotient rule; a curve has no v.
            let at = |o: usize| if o <= order { nd[o * (p + 1) + a] } else { 0.0 };
            let n = [at(0), at(1), 0.0, at(2), 0.0, 0.0];
            let mut av = quotient_rule(&n, &[w[0], w[1], 0.0, w[2], 0.0, 0.0], inv, order);
            av[2] = 0.0;
            av[4] = 0.0;
            av[5] = 0.0;
            aa.push(av);
            r.push(av.map(|x| x * self.weights[k]));
        }
        (indices, r, aa)
    }

    fn combine(&self, indices: &[usize], r: &[[f64; 6]]) -> CurveDerivatives {
        let mut d = CurveDerivatives::default();
        for (l, &k) in indices.iter().enumerate() {
            let pk = self.control_points[k];
            for x in 0..3 {
                d.point[x] += r[l][0] * pk[x];
                d.u[x] += r[l][1] * pk[x];
                d.uu[x] += r[l][3] * pk[x];
            }
        }
        d
    }

    /// `c(u)`.
    pub fn point(&self, u: f64) -> Result<[f64; 3], GeomError> {
        Ok(self.derivatives(u, 0)?.point)
    }

    /// Point and derivatives up to `order` (≤ 2).
    pub fn derivatives(&self, u: f64, order: usize) -> Result<CurveDerivatives, GeomError> {
        self.basis.knots().check_parameter("u", u)?;
        let (i, r, _) = self.rational_basis(u, order, &mut BasisScratch::default());
        Ok(self.combine(&i, &r))
    }

    /// Points and derivatives at many parameters, in parallel.
    pub fn derivatives_batch(
        &self,
        us: &[f64],
        order: usize,
    ) -> Result<Vec<CurveDerivatives>, GeomError> {
        for &u in us {
            self.basis.knots().check_parameter("u", u)?;
        }
        Ok(us
            .par_iter()
            .map_init(BasisScratch::default, |s, &u| {
                let (i, r, _) = self.rational_basis(u, order, s);
                self.combine(&i, &r)
            })
            .collect())
    }

    /// `J(u) = ∂c/∂p` and its derivatives (slots Value, U, UU), 3 or 4 dofs per control point.
    pub fn jacobian(
        &self,
        u: f64,
        order: usize,
        weights_as_dofs: bool,
    ) -> Result<Jacobian, GeomError> {
        self.basis.knots().check_parameter("u", u)?;
        let order = order.min(2);
        let (indices, r, a) = self.rational_basis(u, order, &mut BasisScratch::default());
        let mut weight_columns = Vec::new();
        if weights_as_dofs {
            let cd = self.combine(&indices, &r);
            let sd = SurfaceDerivatives {
                point: cd.point,
                u: cd.u,
                uu: cd.uu,
                ..Default::default()
            };
            for (l, &k) in indices.iter().enumerate() {
                weight_columns.push(weight_column(&a[l], self.control_points[k], &sd, order));
            }
        }
        Ok(Jacobian {
            n_control_points: self.n_control_points(),
            dofs_per_point: if weights_as_dofs { 4 } else { 3 },
            order,
            indices,
            r,
            weight_columns,
        })
    }
}
