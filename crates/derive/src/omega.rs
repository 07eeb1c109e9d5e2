//! Ω, the map from generalized coordinates to lattice node positions (paper eqs. (11), (14),
//! (18); docs/math.md §6). Everything that needs node positions, velocities or probe points
//! from control points goes through [`Omega`].

use nurbspring_dnurbs::{DnurbsModel, Geometry};
use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::State;

use crate::DeriveError;

/// Ω (paper eq. (14)): the Jacobians `J(u_a, v_a)` stacked for every point `a`, a sparse
/// `3 N_points × d N_cp` matrix (`d` = 3, or 4 with weights as unknowns). Point `a` has rows
/// `3a .. 3a + 3`; `Ω p(0) = x(0)` (eq. 11) and `ẋ(0) = Ω ṗ(0)` (eq. 18).
///
/// ```
/// use nurbspring_dnurbs::Geometry;
/// use nurbspring_geom::{KnotVector, NurbsSurface};
/// use nurbspring_derive::Omega;
/// let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
/// let pts: Vec<[f64; 3]> = (0..9).map(|i| [(i / 3) as f64, (i % 3) as f64, 0.0]).collect();
/// let s = NurbsSurface::try_new(k.clone(), k, pts.clone(), vec![1.0; 9]).unwrap();
/// let omega = Omega::new(&Geometry::Surface(s), &[(0.5, 0.5), (0.0, 1.0)], false).unwrap();
/// let p: Vec<f64> = pts.iter().flatten().copied().collect();
/// let x = omega.apply(&p);
/// assert!((x[0][0] - 1.0).abs() < 1e-15 && (x[0][1] - 1.0).abs() < 1e-15);
/// assert!((x[1][0] - 0.0).abs() < 1e-15 && (x[1][1] - 2.0).abs() < 1e-15);
/// ```
///
/// Ω is the Jacobian at the shape it was built from. With constant weights `J` does not depend
/// on `p` and `Ω p` is the surface point for every `p`; with weights as unknowns it is not, and
/// [`Omega::positions`] evaluates `c(p)` itself (docs/math.md §3).
#[derive(Clone, Debug)]
pub struct Omega {
    matrix: SparseMatrix,
    params: Vec<(f64, f64)>,
    /// The geometry, kept with weights as unknowns to evaluate `c(p)` at any state.
    rational: Option<Geometry>,
}

impl Omega {
    /// Ω of the points at parameters `params` (`v` ignored on a curve).
    pub fn new(
        geometry: &Geometry,
        params: &[(f64, f64)],
        weights_as_dofs: bool,
    ) -> Result<Self, DeriveError> {
        Ok(Self {
            matrix: geometry.stacked_jacobian(params, weights_as_dofs)?,
            params: params.to_vec(),
            rational: weights_as_dofs.then(|| geometry.clone()),
        })
    }

    /// The parameters of the points.
    pub fn params(&self) -> &[(f64, f64)] {
        &self.params
    }

    /// The surface points `c(u_a, v_a)` of the shape with full coordinates `p`: `Ω p` with
    /// constant weights (exact there), `c(p)` evaluated from the control points and weights in
    /// `p` with weights as unknowns, where `Ω p` is only the first-order estimate
    /// `J(p(0)) p` (docs/math.md §3).
    pub fn positions(&self, p: &[f64]) -> Result<Vec<[f64; 3]>, DeriveError> {
        let mut out = vec![0.0; self.matrix.nrows()];
        self.positions_into(p, &mut out)?;
        Ok(out.chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// [`Omega::positions`] into a flat buffer of `3 N_points` values.
    pub fn positions_into(&self, p: &[f64], out: &mut [f64]) -> Result<(), DeriveError> {
        match &self.rational {
            None => {
                if p.len() != self.matrix.ncols() {
                    return Err(DeriveError::Dnurbs(
                        nurbspring_dnurbs::DnurbsError::DimensionMismatch {
                            what: "generalized coordinates p",
                            expected: self.matrix.ncols(),
                            found: p.len(),
                        },
                    ));
                }
                self.apply_into(p, out);
            }
            Some(geometry) => {
                let shape = geometry.with_coordinates(p, true)?;
                for (a, &(u, v)) in self.params.iter().enumerate() {
                    let x = shape
                        .point(u, v)
                        .map_err(nurbspring_dnurbs::DnurbsError::from)?;
                    out[3 * a..3 * a + 3].copy_from_slice(&x);
                }
            }
        }
        Ok(())
    }

    /// The matrix.
    pub fn matrix(&self) -> &SparseMatrix {
        &self.matrix
    }

    /// Number of points.
    pub fn n_points(&self) -> usize {
        self.matrix.nrows() / 3
    }

    /// `Ω y` per point: velocities from `ṗ` at the initial shape (eq. 18), displacements
    /// from `Δp`, positions from `p` with constant weights (use [`Omega::positions`] for the
    /// points of a state).
    pub fn apply(&self, y: &[f64]) -> Vec<[f64; 3]> {
        let mut out = vec![0.0; self.matrix.nrows()];
        self.apply_into(y, &mut out);
        out.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
    }

    /// `Ω y` into a flat buffer of `3 N_points` values.
    pub fn apply_into(&self, y: &[f64], out: &mut [f64]) {
        self.matrix.mul_vec(y, out);
    }
}

/// The initial state of the lattice nodes mapped from a D-NURBS state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeState {
    /// `ẋ(0) = Ω ṗ(0)` (paper eq. (18)), one per node.
    pub velocities: Vec<[f64; 3]>,
    /// `Ω (p(0) − p_initial)`: how far the D-NURBS initial state moves the nodes from their
    /// rest positions `Ω p_initial` (paper eq. (11)); empty when it does not move them.
    pub displacements: Vec<[f64; 3]>,
}

impl Omega {
    /// The nodes' initial state for the D-NURBS state `initial` of `model` (reduced
    /// coordinates): the one place paper eqs. (11) and (18) are applied.
    pub fn node_state(&self, model: &DnurbsModel, initial: &State) -> NodeState {
        let velocities = self.apply(&model.full_velocity(&initial.v));
        let p = model.full_coordinates(&initial.q);
        let dp: Vec<f64> = p.iter().zip(model.p0()).map(|(a, b)| a - b).collect();
        let displacements = if dp.iter().all(|&d| d == 0.0) {
            Vec::new()
        } else {
            self.apply(&dp)
        };
        NodeState {
            velocities,
            displacements,
        }
    }
}
