//! The lattice's free nodes as seen from the D-NURBS: which nodes move, and the scalar Ω
//! (paper eq. (14)) between them and the free control points.

use nurbspring_linalg::SparseMatrix;

use crate::error::{DeriveError, Input};
use crate::evaluation::DnurbsModes;
use crate::reference::scalar_rows;
use crate::setup::Setup;

/// The lattice's free nodes and the scalar Ω between them and the free control points.
pub(crate) struct NodeMap {
    /// Free nodes, ascending.
    pub free: Vec<usize>,
    /// Scalar Ω, free nodes × free control points.
    pub omega_ff: SparseMatrix,
}

impl NodeMap {
    pub fn new(setup: &Setup, modes: &DnurbsModes) -> Result<Self, DeriveError> {
        let lattice = setup.lattice();
        let free: Vec<usize> = (0..lattice.n_nodes())
            .filter(|&a| !lattice.fixed[a])
            .collect();
        if free.is_empty() {
            return Err(DeriveError::InvalidInput {
                input: Input::Grid,
                value: format!("{} nodes, all fixed", lattice.n_nodes()),
                reason: "the derivation needs free lattice nodes".into(),
            });
        }
        let omega_ff = scalar_rows(setup.omega().matrix()).submatrix(&free, &modes.system.free);
        Ok(Self { free, omega_ff })
    }

    /// `Ω_ff x`.
    pub fn at_nodes(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.omega_ff.nrows()];
        self.omega_ff.mul_vec(x, &mut y);
        y
    }

    /// True when Ω_ff is square (a Greville lattice: one free node per free control point).
    pub fn is_square(&self) -> bool {
        self.omega_ff.nrows() == self.omega_ff.ncols()
    }
}
