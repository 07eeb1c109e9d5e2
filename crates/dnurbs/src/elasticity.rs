//! One contract for the elastic energies of a D-NURBS (docs/math.md §3, §10): the paper's
//! tension plate (quadratic, `½ (p − p_rest)ᵀ K (p − p_rest)`) and the Kirchhoff–Love shell
//! (nonlinear). Both are integrated on the same knot-span layout and Gauss rules
//! (`layout.rs`); a [`crate::DnurbsModel`] reduces either to its free dofs.

use nurbspring_linalg::SparseMatrix;

use crate::ShellEnergy;

/// An elastic energy `E(p)` over all generalized coordinates `p` (docs/math.md §1 ordering),
/// with its internal force `f = ∂E/∂p` (the sign of a stiffness) and tangent `∂²E/∂p²`.
pub trait ElasticEnergy: Sync {
    /// Number of generalized coordinates.
    fn n_dofs(&self) -> usize;
    /// `E(p)`.
    fn energy(&self, p: &[f64]) -> f64;
    /// `f(p) = ∂E/∂p` into `out` (overwritten).
    fn internal_force(&self, p: &[f64], out: &mut [f64]);
    /// `K_T(p) = ∂²E/∂p²`, on a pattern that does not depend on `p`.
    fn tangent(&self, p: &[f64]) -> SparseMatrix;
    /// `Some(K)` when the energy is quadratic with the constant tangent `K`.
    fn constant_tangent(&self) -> Option<&SparseMatrix> {
        None
    }
}

/// The paper's tension plate with constant weights (paper eq. (4)): `E = ½ (p − p_rest)ᵀ K
/// (p − p_rest)`, borrowed from the model's matrices.
#[derive(Clone, Copy, Debug)]
pub struct TensionPlate<'a> {
    /// K.
    pub stiffness: &'a SparseMatrix,
    /// `p_rest`.
    pub rest: &'a [f64],
}

impl ElasticEnergy for TensionPlate<'_> {
    fn n_dofs(&self) -> usize {
        self.rest.len()
    }
    fn energy(&self, p: &[f64]) -> f64 {
        let d: Vec<f64> = p.iter().zip(self.rest).map(|(a, b)| a - b).collect();
        0.5 * self.stiffness.quadratic_form(&d)
    }
    fn internal_force(&self, p: &[f64], out: &mut [f64]) {
        self.stiffness.mul_vec(p, out);
        self.stiffness.mul_vec_add(-1.0, self.rest, out);
    }
    fn tangent(&self, _p: &[f64]) -> SparseMatrix {
        self.stiffness.clone()
    }
    fn constant_tangent(&self) -> Option<&SparseMatrix> {
        Some(self.stiffness)
    }
}

impl ElasticEnergy for ShellEnergy {
    fn n_dofs(&self) -> usize {
        ShellEnergy::n_dofs(self)
    }
    fn energy(&self, p: &[f64]) -> f64 {
        ShellEnergy::energy(self, p)
    }
    fn internal_force(&self, p: &[f64], out: &mut [f64]) {
        ShellEnergy::internal_force(self, p, out)
    }
    fn tangent(&self, p: &[f64]) -> SparseMatrix {
        ShellEnergy::tangent(self, p)
    }
}

impl<T: ElasticEnergy + ?Sized> ElasticEnergy for &T {
    fn n_dofs(&self) -> usize {
        (**self).n_dofs()
    }
    fn energy(&self, p: &[f64]) -> f64 {
        (**self).energy(p)
    }
    fn internal_force(&self, p: &[f64], out: &mut [f64]) {
        (**self).internal_force(p, out)
    }
    fn tangent(&self, p: &[f64]) -> SparseMatrix {
        (**self).tangent(p)
    }
    fn constant_tangent(&self) -> Option<&SparseMatrix> {
        (**self).constant_tangent()
    }
}
