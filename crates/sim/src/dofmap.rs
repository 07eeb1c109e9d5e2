//! Elimination of fixed degrees of freedom (G+Smo's `gsDofMapper`): free dofs first, in
//! increasing original order; the coupling `A_fc q_c` of fixed values moves to the right-hand side.

use nurbspring_linalg::SparseMatrix;

use crate::SimError;

/// How the dofs of points are laid out: the `components` coordinates of point `k` are dofs
/// `components · k + x`, interleaved. A model whose matrices act alike on every coordinate is
/// `S ⊗ I` in this layout, with `S` its scalar matrix over the points; this type owns that
/// correspondence (both models' points are [`PointDofs::XYZ`]).
///
/// ```
/// use nurbspring_sim::{PointDofs, SparseMatrix};
/// let s = SparseMatrix::from_triplets(2, 2, &[(0, 0, 2.0), (0, 1, -1.0), (1, 1, 3.0)]).unwrap();
/// let full = PointDofs::XYZ.expand(&s);
/// assert_eq!((full.nrows(), full.get(4, 4), full.get(3, 4)), (6, 3.0, 0.0));
/// assert_eq!(PointDofs::XYZ.dof(1, 2), 5);
/// assert_eq!(PointDofs::XYZ.scalar_part(&full).get(0, 1), -1.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointDofs {
    /// Coordinates per point.
    pub components: usize,
}

impl PointDofs {
    /// Three coordinates per point, x, y, z.
    pub const XYZ: PointDofs = PointDofs { components: 3 };

    /// The dof of coordinate `component` of `point`.
    pub fn dof(self, point: usize, component: usize) -> usize {
        self.components * point + component
    }

    /// The dofs of the first coordinate of each of `n_points` points: the rows of the scalar
    /// system.
    pub fn scalar_rows(self, n_points: usize) -> Vec<usize> {
        (0..n_points).map(|k| self.dof(k, 0)).collect()
    }

    /// The scalar matrix `S` of a matrix `S ⊗ I` in this layout: its entries between the
    /// first coordinates (rows and columns).
    pub fn scalar_part(self, a: &SparseMatrix) -> SparseMatrix {
        let rows = self.scalar_rows(a.nrows() / self.components);
        let cols = self.scalar_rows(a.ncols() / self.components);
        a.submatrix(&rows, &cols)
    }

    /// `S ⊗ I`: the scalar matrix `s` acting alike on every coordinate.
    pub fn expand(self, s: &SparseMatrix) -> SparseMatrix {
        s.kron_identity(self.components)
    }

    /// `S` when `a` is `S ⊗ I` in this layout, else `None`.
    pub fn scalar_factor(self, a: &SparseMatrix) -> Option<SparseMatrix> {
        a.kron_identity_factor(self.components)
    }
}

/// Where a dof of the full vector goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DofSlot {
    /// Free dof with its index in the reduced vector.
    Free(usize),
    /// Fixed dof with its index in [`DofMap::fixed`].
    Fixed(usize),
}

/// The split of `n_total` dofs into free and fixed ones.
///
/// ```
/// use nurbspring_sim::DofMap;
/// let map = DofMap::new(4, &[2, 0, 2]).unwrap();
/// assert_eq!(map.free(), &[1, 3]);
/// assert_eq!(map.restrict(&[10.0, 11.0, 12.0, 13.0]), vec![11.0, 13.0]);
/// assert_eq!(map.extend(&[1.0, 3.0], &[7.0, 0.0, 9.0, 0.0]), vec![7.0, 1.0, 9.0, 3.0]);
/// ```
#[derive(Clone, Debug)]
pub struct DofMap {
    n_total: usize,
    free: Vec<usize>,
    fixed: Vec<usize>,
    position: Vec<DofSlot>,
}

impl DofMap {
    /// Fixes the dofs in `fixed` (duplicates allowed). Errors when an index is `≥ n_total`.
    pub fn new(n_total: usize, fixed: &[usize]) -> Result<Self, SimError> {
        let mut is_fixed = vec![false; n_total];
        for &d in fixed {
            if d >= n_total {
                return Err(SimError::DimensionMismatch {
                    what: "fixed dof index (must be below the number of dofs)",
                    expected: n_total,
                    found: d,
                });
            }
            is_fixed[d] = true;
        }
        let mut free = Vec::new();
        let mut fixed = Vec::new();
        let mut position = Vec::with_capacity(n_total);
        for (d, &f) in is_fixed.iter().enumerate() {
            if f {
                position.push(DofSlot::Fixed(fixed.len()));
                fixed.push(d);
            } else {
                position.push(DofSlot::Free(free.len()));
                free.push(d);
            }
        }
        Ok(Self {
            n_total,
            free,
            fixed,
            position,
        })
    }

    /// No dof fixed.
    pub fn all_free(n_total: usize) -> Self {
        Self {
            n_total,
            free: (0..n_total).collect(),
            fixed: Vec::new(),
            position: (0..n_total).map(DofSlot::Free).collect(),
        }
    }

    /// Number of dofs of the full vector.
    pub fn n_total(&self) -> usize {
        self.n_total
    }

    /// Number of free dofs.
    pub fn n_free(&self) -> usize {
        self.free.len()
    }

    /// Free dofs (original indices, increasing).
    pub fn free(&self) -> &[usize] {
        &self.free
    }

    /// Fixed dofs (original indices, increasing).
    pub fn fixed(&self) -> &[usize] {
        &self.fixed
    }

    /// Where `dof` goes.
    pub fn slot(&self, dof: usize) -> DofSlot {
        self.position[dof]
    }

    /// True when `dof` is fixed.
    pub fn is_fixed(&self, dof: usize) -> bool {
        matches!(self.position.get(dof), Some(DofSlot::Fixed(_)))
    }

    /// Index of `dof` in the reduced vector, if free.
    pub fn free_index(&self, dof: usize) -> Option<usize> {
        match self.position.get(dof) {
            Some(DofSlot::Free(i)) => Some(*i),
            _ => None,
        }
    }

    /// The free entries of a full vector.
    ///
    /// # Panics
    /// If `full.len() != n_total`.
    pub fn restrict(&self, full: &[f64]) -> Vec<f64> {
        assert_eq!(
            full.len(),
            self.n_total,
            "DofMap::restrict: vector of length {} for {} dofs",
            full.len(),
            self.n_total
        );
        self.free.iter().map(|&d| full[d]).collect()
    }

    /// The full vector with free entries from `free` and fixed entries from `fixed_values`
    /// (a full-length vector of which only the fixed entries are read).
    ///
    /// # Panics
    /// On size mismatch.
    pub fn extend(&self, free: &[f64], fixed_values: &[f64]) -> Vec<f64> {
        assert_eq!(
            fixed_values.len(),
            self.n_total,
            "DofMap::extend: fixed_values of length {} for {} dofs",
            fixed_values.len(),
            self.n_total
        );
        let mut out = fixed_values.to_vec();
        self.extend_into(free, &mut out);
        out
    }

    /// Writes the free entries of `out` from `free`; fixed entries are left untouched.
    ///
    /// # Panics
    /// On size mismatch.
    pub fn extend_into(&self, free: &[f64], out: &mut [f64]) {
        assert_eq!(
            free.len(),
            self.free.len(),
            "DofMap::extend_into: {} free values for {} free dofs",
            free.len(),
            self.free.len()
        );
        assert_eq!(
            out.len(),
            self.n_total,
            "DofMap::extend_into: output of length {} for {} dofs",
            out.len(),
            self.n_total
        );
        for (&d, &v) in self.free.iter().zip(free) {
            out[d] = v;
        }
    }

    /// `A_ff`: free rows and free columns.
    ///
    /// # Panics
    /// If A is not `n_total × n_total`.
    pub fn restrict_matrix(&self, a: &SparseMatrix) -> SparseMatrix {
        self.check_matrix(a);
        a.submatrix(&self.free, &self.free)
    }

    /// `A_fc`: free rows, fixed columns (its product with the fixed values moves to the
    /// right-hand side).
    ///
    /// # Panics
    /// If A is not `n_total × n_total`.
    pub fn coupling_matrix(&self, a: &SparseMatrix) -> SparseMatrix {
        self.check_matrix(a);
        a.submatrix(&self.free, &self.fixed)
    }

    fn check_matrix(&self, a: &SparseMatrix) {
        assert!(
            a.nrows() == self.n_total && a.ncols() == self.n_total,
            "DofMap: a {}×{} matrix for {} dofs",
            a.nrows(),
            a.ncols(),
            self.n_total
        );
    }
}
