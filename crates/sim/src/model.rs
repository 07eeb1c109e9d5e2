//! The dynamics contract: `M q̈ + D q̇ + f_int(q) = f_ext(t)` on the free dofs.
//!
//! Sign convention: `f_int` is the internal (elastic) force with the sign of a stiffness, i.e.
//! it appears on the left-hand side. A linear model has `f_int(q) = K (q − q_rest)`; a spring
//! model has `f_int = −Σ f_elastic` (the paper's eq. 5 gives the restoring force). The tangent
//! stiffness is `K_T(q) = ∂f_int/∂q` (symmetric positive semidefinite for a stable linear model).

use nurbspring_linalg::SparseMatrix;

/// Mass or damping operator on the free dofs: a diagonal (lumped) or a sparse matrix.
#[derive(Clone, Debug, PartialEq)]
pub enum SystemMatrix {
    /// `diag(d)`.
    Diagonal(Vec<f64>),
    /// A general sparse symmetric matrix.
    Sparse(SparseMatrix),
}

impl SystemMatrix {
    /// Dimension (the matrix is square).
    pub fn dim(&self) -> usize {
        match self {
            SystemMatrix::Diagonal(d) => d.len(),
            SystemMatrix::Sparse(s) => s.nrows(),
        }
    }

    /// `y = A x`.
    ///
    /// # Panics
    /// On size mismatch.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        match self {
            SystemMatrix::Diagonal(d) => {
                assert!(
                    x.len() == d.len() && y.len() == d.len(),
                    "SystemMatrix::mul_vec: size mismatch"
                );
                y.iter_mut()
                    .zip(d)
                    .zip(x)
                    .for_each(|((y, d), x)| *y = d * x);
            }
            SystemMatrix::Sparse(s) => s.mul_vec(x, y),
        }
    }

    /// `y += α A x`.
    ///
    /// # Panics
    /// On size mismatch.
    pub fn mul_vec_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        match self {
            SystemMatrix::Diagonal(d) => {
                assert!(
                    x.len() == d.len() && y.len() == d.len(),
                    "SystemMatrix::mul_vec_add: size mismatch"
                );
                y.iter_mut()
                    .zip(d)
                    .zip(x)
                    .for_each(|((y, d), x)| *y += alpha * d * x);
            }
            SystemMatrix::Sparse(s) => s.mul_vec_add(alpha, x, y),
        }
    }

    /// The matrix in sparse form (a diagonal becomes `SparseMatrix::from_diagonal`).
    pub fn to_sparse(&self) -> SparseMatrix {
        match self {
            SystemMatrix::Diagonal(d) => SparseMatrix::from_diagonal(d),
            SystemMatrix::Sparse(s) => s.clone(),
        }
    }

    /// `xᵀ A x` (allocation free).
    pub fn quadratic_form(&self, x: &[f64]) -> f64 {
        match self {
            SystemMatrix::Diagonal(d) => d.iter().zip(x).map(|(d, x)| d * x * x).sum(),
            SystemMatrix::Sparse(s) => s.quadratic_form(x),
        }
    }

    /// The diagonal when the operator is diagonal (a `Diagonal`, or a `Sparse` whose stored
    /// off-diagonal values are all zero); `None` otherwise.
    pub fn as_diagonal(&self) -> Option<Vec<f64>> {
        match self {
            SystemMatrix::Diagonal(d) => Some(d.clone()),
            SystemMatrix::Sparse(s) if s.is_diagonal() => Some(s.diagonal()),
            SystemMatrix::Sparse(_) => None,
        }
    }
}

/// A model `M q̈ + D q̇ + f_int(q) = f_ext(t)` on the free dofs (see the module docs for the
/// sign convention). Implemented by the D-NURBS and mass-spring models; every integrator in
/// [`crate::integrators`] is written once against it.
pub trait DynamicModel: Sync {
    /// Number of (free) degrees of freedom.
    fn n_dofs(&self) -> usize;
    /// The mass matrix M (symmetric positive definite).
    fn mass(&self) -> &SystemMatrix;
    /// The damping matrix D; `None` means undamped.
    fn damping(&self) -> Option<&SystemMatrix>;
    /// Overwrites `out` with `f_int(q)`.
    fn internal_force(&self, q: &[f64], out: &mut [f64]);
    /// Overwrites `out` with `f_ext(t)`.
    fn external_force(&self, t: f64, out: &mut [f64]);
    /// `K_T(q) = ∂f_int/∂q`, always with the same sparsity pattern.
    fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix;
    /// Elastic energy `E(q)` with `∇E = f_int` (external work not included).
    fn potential_energy(&self, q: &[f64]) -> f64;
    /// A positive semi-definite approximation of `K_T(q)` on the same pattern, used by the
    /// implicit schemes when `M + c_v D + c_q K_T` is not positive definite (a Newton step with
    /// an indefinite matrix need not lower the step's energy and can wander). `None` (the
    /// default): the indefinite matrix is factored by LU instead.
    fn projected_tangent_stiffness(&self, _q: &[f64]) -> Option<SparseMatrix> {
        None
    }
    /// `Some(K)` when `f_int(q) = K q + f_int(0)` exactly (constant stiffness): lets implicit
    /// schemes factor once and the modal solver apply.
    fn linear_stiffness(&self) -> Option<&SparseMatrix> {
        None
    }
    /// A matrix `K̄` that bounds the tangent stiffness at every configuration,
    /// `K_T(q) ⪯ K̄` (Loewner order: `xᵀK_T(q)x ≤ xᵀK̄x` for all `q` and `x`), so that
    /// `2/√λ_max(K̄, M)` is a stability limit of the explicit schemes along any trajectory
    /// ([`crate::uniform_stability_limit`]). The default is the constant stiffness of a linear
    /// model ([`DynamicModel::linear_stiffness`]) and `None` otherwise (no bound known).
    fn stiffness_bound(&self) -> Option<SparseMatrix> {
        self.linear_stiffness().cloned()
    }
    /// Potential of the external force for energy bookkeeping (e.g. `−qᵀ f_ext` for a constant
    /// load), so that kinetic + potential + external potential is conserved without damping.
    fn external_potential(&self, _t: f64, _q: &[f64]) -> f64 {
        0.0
    }
    /// The model's own symplectic-Euler step, when it has one that is faster than the generic
    /// path (forces through [`DynamicModel::internal_force`], then the update): the
    /// [`crate::integrators::SymplecticEuler`] stepper calls it instead. `None` (the default)
    /// means the generic path.
    fn fused_step(&self) -> Option<&dyn FusedStep> {
        None
    }
    /// Damping that depends on the configuration, beside the constant `D`
    /// ([`ConfigurationDamping`]): the equation of motion is then
    /// `M q̈ + (D + C(q)) q̇ + f_int(q) = f_ext(t)`. `None` (the default): no such damping.
    fn configuration_damping(&self) -> Option<&dyn ConfigurationDamping> {
        None
    }
}

/// A damping force `C(q) q̇` whose matrix depends on the configuration (a dashpot along a
/// spring's current direction, `C = c n nᵀ` on its two nodes), offered by
/// [`DynamicModel::configuration_damping`]. `C(q)` is symmetric positive semi-definite.
///
/// How the integrators take it: the explicit schemes evaluate it with the forces, at the
/// state where they evaluate `D q̇` (velocity Verlet at the half-step velocity, as it does a
/// non-diagonal `D`); the implicit schemes put `C(q) v` of the trial state in the residual,
/// which is what converges, and `c_v C(q)` in the Newton matrix (the variation of `C` with
/// `q` left out: a modified Newton method that the residual test keeps exact); their line
/// search's step energy holds `C` at the predicted positions.
pub trait ConfigurationDamping: Sync {
    /// `out += C(q) v`.
    fn add_damping_force(&self, q: &[f64], v: &[f64], out: &mut [f64]);
    /// `C(q)`, always with the same sparsity pattern.
    fn damping_matrix(&self, q: &[f64]) -> SparseMatrix;
}

/// A symplectic-Euler step fused into one pass over a model's data (spring forces, velocity
/// and position update together), offered by [`DynamicModel::fused_step`].
///
/// It must compute what the generic path computes, `v⁺ = v + Δt M⁻¹ (f_ext(t) − f_int(q) −
/// D v)` and `q⁺ = q + Δt v⁺` on the free dofs, up to the order of floating-point sums.
pub trait FusedStep: Sync {
    /// Length of the `f64` workspace [`FusedStep::symplectic_euler`] needs (allocated once by
    /// the stepper).
    fn workspace_len(&self) -> usize;
    /// Advances `(q, v)` at time `t` by one symplectic-Euler step of `dt`, in place.
    /// `workspace` has at least [`FusedStep::workspace_len`] entries; its contents on entry do
    /// not matter.
    fn symplectic_euler(
        &self,
        t: f64,
        dt: f64,
        q: &mut [f64],
        v: &mut [f64],
        workspace: &mut [f64],
    );
}

/// A linear model on free dofs: constant M, D, K, `f_int(q) = K (q − rest)`, constant
/// `f_ext = force`. Used by constant-weight D-NURBS and by tests.
#[derive(Clone, Debug)]
pub struct LinearModel {
    /// Mass matrix M.
    pub mass: SystemMatrix,
    /// Damping matrix D (`None`: undamped).
    pub damping: Option<SystemMatrix>,
    /// Stiffness matrix K (symmetric).
    pub stiffness: SparseMatrix,
    /// Rest configuration `q_rest`.
    pub rest: Vec<f64>,
    /// Constant external force.
    pub force: Vec<f64>,
}

impl LinearModel {
    /// An undamped, unloaded model with rest configuration 0.
    pub fn new(mass: SystemMatrix, stiffness: SparseMatrix) -> Self {
        let n = stiffness.nrows();
        Self {
            mass,
            damping: None,
            stiffness,
            rest: vec![0.0; n],
            force: vec![0.0; n],
        }
    }

    /// Checks that every part has the size `n_dofs`.
    pub fn validate(&self) -> Result<(), crate::SimError> {
        let n = self.stiffness.nrows();
        let check = |what: &'static str, found: usize| {
            if found == n {
                Ok(())
            } else {
                Err(crate::SimError::DimensionMismatch {
                    what,
                    expected: n,
                    found,
                })
            }
        };
        check("stiffness columns", self.stiffness.ncols())?;
        check("mass matrix", self.mass.dim())?;
        if let Some(d) = &self.damping {
            check("damping matrix", d.dim())?;
        }
        check("rest configuration", self.rest.len())?;
        check("external force", self.force.len())
    }
}

impl DynamicModel for LinearModel {
    fn n_dofs(&self) -> usize {
        self.stiffness.nrows()
    }
    fn mass(&self) -> &SystemMatrix {
        &self.mass
    }
    fn damping(&self) -> Option<&SystemMatrix> {
        self.damping.as_ref()
    }
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        self.stiffness.mul_vec(q, out);
        self.stiffness.mul_vec_add(-1.0, &self.rest, out);
    }
    fn external_force(&self, _t: f64, out: &mut [f64]) {
        out.copy_from_slice(&self.force);
    }
    fn tangent_stiffness(&self, _q: &[f64]) -> SparseMatrix {
        self.stiffness.clone()
    }
    /// `½ (q − rest)ᵀ K (q − rest)`.
    fn potential_energy(&self, q: &[f64]) -> f64 {
        0.5 * self
            .stiffness
            .triplets()
            .map(|(i, j, k)| k * (q[i] - self.rest[i]) * (q[j] - self.rest[j]))
            .sum::<f64>()
    }
    fn linear_stiffness(&self) -> Option<&SparseMatrix> {
        Some(&self.stiffness)
    }
    /// `−qᵀ f` (constant load).
    fn external_potential(&self, _t: f64, q: &[f64]) -> f64 {
        -q.iter().zip(&self.force).map(|(q, f)| q * f).sum::<f64>()
    }
}
