//! The map Ω from generalized coordinates to lattice node positions (paper eqs. 11, 14, 18).

use nurbspring_geom::NurbsSurface;
use nurbspring_linalg::SparseMatrix;

use crate::DeriveError;

/// Ω (paper eq. 14): the rows of `J(u_a, v_a)` stacked for every node `a`, a sparse
/// `3 N_nodes × d N_cp` matrix with `d` = 3 (constant weights) or 4 (weights as unknowns).
/// `Ω p(0) = x(0)` (eq. 11) and `ẋ(0) = Ω ṗ(0)` (eq. 18). Node `a` has rows `3a..3a+3`.
///
/// ```
/// use nurbspring_geom::{KnotVector, NurbsSurface};
/// use nurbspring_derive::omega_matrix;
/// let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
/// let pts: Vec<[f64; 3]> = (0..9).map(|i| [(i / 3) as f64, (i % 3) as f64, 0.0]).collect();
/// let s = NurbsSurface::try_new(k.clone(), k, pts.clone(), vec![1.0; 9]).unwrap();
/// let omega = omega_matrix(&s, &[(0.5, 0.5), (0.0, 1.0)], false).unwrap();
/// let p: Vec<f64> = pts.iter().flatten().copied().collect();
/// let mut x = vec![0.0; 6];
/// omega.mul_vec(&p, &mut x);
/// assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
/// assert!((x[3] - 0.0).abs() < 1e-15 && (x[4] - 2.0).abs() < 1e-15);
/// ```
pub fn omega_matrix(
    surface: &NurbsSurface,
    params: &[(f64, f64)],
    weights_as_dofs: bool,
) -> Result<SparseMatrix, DeriveError> {
    let ((u0, u1), (v0, v1)) = surface.domain();
    for (node, &(u, v)) in params.iter().enumerate() {
        if surface.check_parameters(u, v).is_err() {
            return Err(DeriveError::NodeOutsideDomain {
                node,
                u,
                v,
                u0,
                u1,
                v0,
                v1,
            });
        }
    }
    let d = if weights_as_dofs { 4 } else { 3 };
    let mut triplets = Vec::new();
    for (node, &(u, v)) in params.iter().enumerate() {
        let j = surface.jacobian(u, v, 0, weights_as_dofs)?;
        for l in 0..j.n_local() {
            let k = j.indices[l];
            let r = j.r[l][0];
            if r != 0.0 {
                for x in 0..3 {
                    triplets.push((3 * node + x, d * k + x, r));
                }
            }
            if weights_as_dofs {
                let col = j.weight_columns[l][0];
                for x in 0..3 {
                    if col[x] != 0.0 {
                        triplets.push((3 * node + x, d * k + 3, col[x]));
                    }
                }
            }
        }
    }
    Ok(SparseMatrix::from_triplets(
        3 * params.len(),
        d * surface.n_control_points(),
        &triplets,
    )?)
}
