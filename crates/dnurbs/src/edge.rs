//! Loads on the boundary edges of a surface (docs/math.md §10.6): a force per unit length and a
//! moment per unit length about the edge, integrated along the rest edge by Gauss–Legendre
//! quadrature on its knot spans.

use nurbspring_geom::cross;
use nurbspring_geom::{Deriv, GaussLegendre, Jacobian};
use nurbspring_linalg::SparseMatrix;

use crate::{DnurbsError, Geometry};

/// A boundary edge of a surface's parameter domain `[u0, u1] × [v0, v1]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Edge {
    /// `u = u0`.
    U0,
    /// `u = u1`.
    U1,
    /// `v = v0`.
    V0,
    /// `v = v1`.
    V1,
}

impl Edge {
    /// "u0", "u1", "v0" or "v1", as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Edge::U0 => "u0",
            Edge::U1 => "u1",
            Edge::V0 => "v0",
            Edge::V1 => "v1",
        }
    }

    /// True for the edges `u = const` (which run along v).
    fn is_u(self) -> bool {
        matches!(self, Edge::U0 | Edge::U1)
    }
}

/// A load on a boundary edge, per unit length of the rest edge (docs/math.md §10.6):
///
/// - `force` `F` (force / length), constant in direction and size: the generalized force
///   `∫ J(s)ᵀ F ds`;
/// - `moment` `m` (force · length / length) about the edge's rest tangent `e` (the direction of
///   increasing v on `u0`/`u1`, of increasing u on `v0`/`v1`), right-handed: the potential
///   `−∫ m θ ds`, `θ` the angle by which the surface's cross tangent (`∂c/∂u` on a u-edge)
///   has turned about the fixed axis `e` since the rest shape. Conservative (not a follower
///   moment); for a straight edge that turns about its own direction it is the end moment of
///   beam theory. Only the Kirchhoff–Love shell takes moments.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EdgeLoad {
    /// The edge.
    pub edge: Edge,
    /// Force per unit length.
    pub force: [f64; 3],
    /// Moment per unit length about the edge.
    pub moment: f64,
}

/// One quadrature point of an edge.
#[derive(Clone, Debug)]
struct EdgePoint {
    /// `J` and `∂J/∂u`, `∂J/∂v` at the point.
    jacobian: Jacobian,
    /// Gauss weight × `|∂c/∂t|` at rest (the length element).
    length: f64,
    /// Slot of the cross derivative (`Deriv::U` on a u-edge).
    cross: Deriv,
    /// Rest cross tangent projected on the plane normal to the axis, unit.
    t0: [f64; 3],
    /// `e × t0`.
    n0: [f64; 3],
    /// The load of the point's edge.
    load: usize,
}

/// The edge loads of a model, with their quadrature points on the rest surface.
#[derive(Clone, Debug, Default)]
pub(crate) struct EdgeLoads {
    loads: Vec<EdgeLoad>,
    points: Vec<EdgePoint>,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    a.map(|x| x / n)
}

/// `x` wrapped into `(−π, π]`.
fn wrap(x: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    let y = x - two_pi * (x / two_pi).round();
    if y <= -std::f64::consts::PI {
        y + two_pi
    } else {
        y
    }
}

impl EdgeLoads {
    /// The quadrature of `loads` on the rest `geometry` with `points` Gauss points per span.
    pub(crate) fn new(
        geometry: &Geometry,
        loads: &[EdgeLoad],
        points: usize,
    ) -> Result<Self, DnurbsError> {
        if loads.is_empty() {
            return Ok(Self::default());
        }
        let Geometry::Surface(surface) = geometry else {
            return Err(DnurbsError::InvalidLoad {
                detail: "edge loads need a surface; a curve has no edges".into(),
            });
        };
        let rule = GaussLegendre::new(points)?;
        let ((u0, u1), (v0, v1)) = surface.domain();
        let mut out = Vec::new();
        for (index, load) in loads.iter().enumerate() {
            let edge = load.edge;
            if load.force.iter().any(|x| !x.is_finite()) || !load.moment.is_finite() {
                return Err(DnurbsError::InvalidLoad {
                    detail: format!(
                        "edge load {index} on {} is not finite (force {:?}, moment {})",
                        edge.name(),
                        load.force,
                        load.moment
                    ),
                });
            }
            let (basis, fixed) = match edge {
                Edge::U0 => (surface.basis_v(), u0),
                Edge::U1 => (surface.basis_v(), u1),
                Edge::V0 => (surface.basis_u(), v0),
                Edge::V1 => (surface.basis_u(), v1),
            };
            let cross_slot = if edge.is_u() { Deriv::U } else { Deriv::V };
            for (_, a, b) in basis.knots().nonempty_spans() {
                for (s, w) in rule.mapped(a, b) {
                    let (u, v) = if edge.is_u() { (fixed, s) } else { (s, fixed) };
                    let jacobian = surface.jacobian(u, v, 1, false)?;
                    let d = surface.derivatives(u, v, 1)?;
                    let (tangent, cross_tangent) =
                        if edge.is_u() { (d.v, d.u) } else { (d.u, d.v) };
                    let speed = dot(tangent, tangent).sqrt();
                    let e = unit(tangent);
                    let projected: [f64; 3] =
                        std::array::from_fn(|k| cross_tangent[k] - dot(cross_tangent, e) * e[k]);
                    let t0 = unit(projected);
                    if !(speed > 0.0 && t0.iter().all(|x| x.is_finite())) {
                        return Err(DnurbsError::InvalidLoad {
                            detail: format!(
                                "edge load {index}: the edge {} is degenerate at (u, v) = \
                                 ({u}, {v}) (no tangent or no cross direction)",
                                edge.name()
                            ),
                        });
                    }
                    out.push(EdgePoint {
                        jacobian,
                        length: w * speed,
                        cross: cross_slot,
                        t0,
                        n0: cross(e, t0),
                        load: index,
                    });
                }
            }
        }
        Ok(Self {
            loads: loads.to_vec(),
            points: out,
        })
    }

    /// True when some load has a moment.
    pub(crate) fn has_moments(&self) -> bool {
        self.loads.iter().any(|l| l.moment != 0.0)
    }

    /// Adds `∫ J(s)ᵀ F ds` of every edge force to `force` (3 dofs per point).
    pub(crate) fn add_forces(&self, force: &mut [f64]) {
        for pt in &self.points {
            let f = self.loads[pt.load].force;
            if f != [0.0; 3] {
                pt.jacobian
                    .apply_transpose_add(Deriv::Value, f, pt.length, force);
            }
        }
    }

    /// `c = ∂c/∂(cross)` of the point at `p`, and `(X, Y) = (c·t0, c·n0)`.
    fn cross_coordinates(pt: &EdgePoint, p: &[f64]) -> (f64, f64) {
        let c = pt.jacobian.apply(pt.cross, p);
        (dot(c, pt.t0), dot(c, pt.n0))
    }

    /// The moments' work from `from` to `to`, `Σ m ds (θ(to) − θ(from))`, each angle change
    /// taken in `(−π, π]` (the states of one Newton step are close).
    pub(crate) fn work_between(&self, from: &[f64], to: &[f64]) -> f64 {
        self.points
            .iter()
            .filter(|pt| self.loads[pt.load].moment != 0.0)
            .map(|pt| {
                let (xa, ya) = Self::cross_coordinates(pt, from);
                let (xb, yb) = Self::cross_coordinates(pt, to);
                self.loads[pt.load].moment * pt.length * wrap(yb.atan2(xb) - ya.atan2(xa))
            })
            .sum()
    }

    /// Adds `∂W/∂p` (the moments' generalized force) at `p` to `out`.
    pub(crate) fn add_moment_force(&self, p: &[f64], out: &mut [f64]) {
        for pt in &self.points {
            let m = self.loads[pt.load].moment;
            if m == 0.0 {
                continue;
            }
            let (x, y) = Self::cross_coordinates(pt, p);
            let rho2 = x * x + y * y;
            let g: [f64; 3] = std::array::from_fn(|k| (x * pt.n0[k] - y * pt.t0[k]) / rho2);
            pt.jacobian
                .apply_transpose_add(pt.cross, g, m * pt.length, out);
        }
    }

    /// `∂²W/∂p²` at `p` (3 dofs per point, `n_dofs` rows), or `None` without moments.
    pub(crate) fn moment_hessian(
        &self,
        p: &[f64],
        n_dofs: usize,
    ) -> Result<Option<SparseMatrix>, DnurbsError> {
        if !self.has_moments() {
            return Ok(None);
        }
        let mut triplets = Vec::new();
        for pt in &self.points {
            let m = self.loads[pt.load].moment;
            if m == 0.0 {
                continue;
            }
            let (x, y) = Self::cross_coordinates(pt, p);
            let rho4 = (x * x + y * y).powi(2);
            let (hxx, hyy, hxy) = (
                2.0 * x * y / rho4,
                -2.0 * x * y / rho4,
                (y * y - x * x) / rho4,
            );
            let (t0, n0) = (pt.t0, pt.n0);
            let h: [[f64; 3]; 3] = std::array::from_fn(|i| {
                std::array::from_fn(|j| {
                    hxx * t0[i] * t0[j]
                        + hyy * n0[i] * n0[j]
                        + hxy * (t0[i] * n0[j] + n0[i] * t0[j])
                })
            });
            let jac = &pt.jacobian;
            let slot = pt.cross.slot();
            for (a, &ka) in jac.indices.iter().enumerate() {
                for (b, &kb) in jac.indices.iter().enumerate() {
                    let s = m * pt.length * jac.r[a][slot] * jac.r[b][slot];
                    if s == 0.0 {
                        continue;
                    }
                    for i in 0..3 {
                        for j in 0..3 {
                            triplets.push((3 * ka + i, 3 * kb + j, s * h[i][j]));
                        }
                    }
                }
            }
        }
        Ok(Some(SparseMatrix::from_triplets(
            n_dofs, n_dofs, &triplets,
        )?))
    }
}
