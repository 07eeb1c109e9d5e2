//! External loads (docs/math.md §3): gravity as a force density `μ g`, a constant distributed force
//! density, and point loads `J(u0, v0)ᵀ F`.

use crate::{DnurbsError, EdgeLoad, Geometry};

/// A concentrated force `F` at the surface point `c(u, v)`: generalized force `J(u, v)ᵀ F`
/// (docs/math.md §3). For curves `v` is ignored.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PointLoad {
    /// Parameter u.
    pub u: f64,
    /// Parameter v (ignored for curves).
    pub v: f64,
    /// The force vector.
    pub force: [f64; 3],
}

/// All external loads; they are constant in time.
///
/// The distributed force density is `f(u, v) = μ g + distributed`, integrated as
/// `f_p = ∫∫ Jᵀ f du dv` (or over the area, see `Integration`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Loads {
    /// Gravitational acceleration `g`; the force density is `μ g`.
    pub gravity: [f64; 3],
    /// A constant force density per unit parameter area (or surface area).
    pub distributed: [f64; 3],
    /// Point loads.
    pub point: Vec<PointLoad>,
    /// Loads on boundary edges (surfaces, constant weights; moments only on the shell).
    pub edges: Vec<EdgeLoad>,
}

impl Loads {
    /// Every load times `s` (gravity, distributed density, point and edge forces, edge
    /// moments): the load level `s` of a load path.
    ///
    /// ```
    /// use nurbspring_dnurbs::Loads;
    /// let l = Loads { gravity: [0.0, 0.0, -9.81], ..Loads::default() };
    /// assert_eq!(l.scaled(2.0).gravity, [0.0, 0.0, -19.62]);
    /// ```
    pub fn scaled(&self, s: f64) -> Loads {
        let times = |f: [f64; 3]| f.map(|x| s * x);
        Loads {
            gravity: times(self.gravity),
            distributed: times(self.distributed),
            point: self
                .point
                .iter()
                .map(|p| PointLoad {
                    force: times(p.force),
                    ..p.clone()
                })
                .collect(),
            edges: self
                .edges
                .iter()
                .map(|e| EdgeLoad {
                    force: times(e.force),
                    moment: s * e.moment,
                    ..e.clone()
                })
                .collect(),
        }
    }

    /// True when there is no load at all.
    pub fn is_zero(&self) -> bool {
        self.gravity == [0.0; 3]
            && self.distributed == [0.0; 3]
            && self.point.iter().all(|p| p.force == [0.0; 3])
            && self
                .edges
                .iter()
                .all(|e| e.force == [0.0; 3] && e.moment == 0.0)
    }

    /// The constant force density `μ g + distributed` (docs/math.md §3).
    pub fn density(&self, mu: f64) -> [f64; 3] {
        std::array::from_fn(|x| mu * self.gravity[x] + self.distributed[x])
    }

    /// Checks that every value is finite and every point load lies in the parameter domain.
    pub fn validate(&self, geometry: &Geometry) -> Result<(), DnurbsError> {
        for (name, v) in [("gravity", self.gravity), ("distributed", self.distributed)] {
            if v.iter().any(|x| !x.is_finite()) {
                return Err(DnurbsError::InvalidLoad {
                    detail: format!("{name} = {v:?} is not finite"),
                });
            }
        }
        for (i, p) in self.point.iter().enumerate() {
            if p.force.iter().any(|x| !x.is_finite()) {
                return Err(DnurbsError::InvalidLoad {
                    detail: format!("point load {i} has a non-finite force {:?}", p.force),
                });
            }
            if let Err(e) = geometry.check_parameters(p.u, p.v) {
                return Err(DnurbsError::InvalidLoad {
                    detail: format!("point load {i} at (u, v) = ({}, {}): {e}", p.u, p.v),
                });
            }
        }
        Ok(())
    }
}
