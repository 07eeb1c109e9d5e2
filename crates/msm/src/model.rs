//! The mass-spring model as a [`DynamicModel`] on the free node coordinates.
//!
//! Equation of motion (paper eq. (7), docs/math.md §5, with the damping sign fixed to `−γ ẋ`):
//! ```text
//! m_a ẍ_a = f_elastic,a(x) − γ_a ẋ_a − Σ_springs c ((ẋ_a − ẋ_b)·n) n + m_a g
//! ```
//! In the form of the dynamics contract, `M q̈ + (D + C(q)) q̇ + f_int(q) = f_ext(t)` on the free
//! coordinates `q` (fixed nodes held at their initial positions): `M = diag(m_a) ⊗ I_3`,
//! `D = diag(γ_a) ⊗ I_3` (the constant [`DynamicModel::damping`]), `C(q)` the springs' axial
//! dashpots along their current directions (docs/math.md §5.1, the model's
//! [`DynamicModel::configuration_damping`]), `f_int = −f_elastic` (springs and hinges, the
//! sign of a stiffness) and `f_ext = m_a g` (constant). The tangent `∂f_int/∂q` is `K_T` of
//! paper eqs. (9)–(10) and the hinges' Hessians restricted to the free coordinates.

use std::sync::OnceLock;

use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::{
    ConfigurationDamping, DofMap, DynamicModel, FusedStep, IntegratorKind, PointDofs,
    StabilityLimit, State, SystemMatrix, stability_limit,
};

use crate::grid::GridStep;
use crate::stiffness::{Coefficient, TangentPattern};
use crate::topology::Topology;
use crate::{Class, MsmError, SpringLattice};

/// A validated [`SpringLattice`] as a [`DynamicModel`] on the free node coordinates (diagonal
/// mass and damping; `f_int = −f_elastic`; gravity as `f_ext`). See the module docs for the
/// equation and its signs.
///
/// The free coordinates are those of the free nodes, in increasing node order, three per node
/// (`[x, y, z]`), as [`DofMap`] orders them.
pub struct MsmModel {
    lattice: SpringLattice,
    dof_map: DofMap,
    topology: Topology,
    pattern: OnceLock<TangentPattern>,
    mass: SystemMatrix,
    damping: Option<SystemMatrix>,
    external: Vec<f64>,
    x0: Vec<f64>,
    q0: Vec<f64>,
    /// `L_ff ⊗ I₃` of the linear elements on the free coordinates (`None` without elements).
    linear: Option<SparseMatrix>,
    /// The fused symplectic-Euler step of a grid lattice (`None`: the generic path).
    grid_step: Option<GridStep>,
}

impl MsmModel {
    /// The integrators an MSM runs with (`modal`, its exact solution, only when it is linear
    /// and undamped: a lattice of linear elements without springs).
    pub const INTEGRATORS: [IntegratorKind; 6] = [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
        IntegratorKind::BackwardEuler,
        IntegratorKind::Newmark,
        IntegratorKind::Modal,
    ];

    /// Why `integrator` cannot run an MSM; `None` when it can.
    pub fn integrator_problem(integrator: IntegratorKind) -> Option<String> {
        (!Self::INTEGRATORS.contains(&integrator)).then(|| {
            format!(
                "not an integrator of the mass-spring model; expected one of {}",
                Self::INTEGRATORS
                    .iter()
                    .map(|k| k.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
    }

    /// Validates the lattice ([`SpringLattice::validate`]) and precomputes the node-to-spring
    /// incidence of the free nodes and, for a grid lattice, the data of its fused
    /// symplectic-Euler step ([`DynamicModel::fused_step`]). The tangent pattern is built on
    /// first use.
    pub fn new(lattice: SpringLattice) -> Result<Self, MsmError> {
        lattice.validate()?;
        let dof_map = DofMap::new(lattice.n_dofs(), &lattice.fixed_dofs())?;
        let active: Vec<bool> = lattice.fixed.iter().map(|&f| !f).collect();
        let topology = Topology::new(&lattice, &active);
        let free_nodes = &topology.active_nodes;
        let per_dof = |values: &[f64]| -> Vec<f64> {
            free_nodes.iter().flat_map(|&a| [values[a]; 3]).collect()
        };
        let mass = SystemMatrix::Diagonal(per_dof(&lattice.masses));
        let gamma = per_dof(&lattice.damping);
        let damping = gamma
            .iter()
            .any(|&g| g != 0.0)
            .then_some(SystemMatrix::Diagonal(gamma));
        let external = dof_map.restrict(&lattice.gravity_forces());
        let x0 = lattice.flat_positions();
        let q0 = dof_map.restrict(&x0);
        let linear = (!lattice.elements.is_empty()).then(|| {
            let l = lattice.linear_matrix(None);
            PointDofs::XYZ.expand(&l.submatrix(free_nodes, free_nodes))
        });
        let grid_step = GridStep::new(&lattice, &external);
        Ok(Self {
            lattice,
            dof_map,
            topology,
            pattern: OnceLock::new(),
            mass,
            damping,
            external,
            x0,
            q0,
            linear,
            grid_step,
        })
    }

    /// The lattice.
    pub fn lattice(&self) -> &SpringLattice {
        &self.lattice
    }

    /// The map between all node coordinates and the free ones.
    pub fn dof_map(&self) -> &DofMap {
        &self.dof_map
    }

    /// Indices of the free nodes, ascending (free node `i` owns free coordinates `3i .. 3i + 3`).
    pub fn free_nodes(&self) -> &[usize] {
        &self.topology.active_nodes
    }

    /// The free coordinates at the initial positions.
    pub fn initial_positions(&self) -> &[f64] {
        &self.q0
    }

    /// Initial state at the initial positions with node velocities `velocities` (one per node;
    /// fixed nodes get zero; an empty slice means at rest, missing entries count as zero).
    pub fn initial_state(&self, velocities: &[[f64; 3]]) -> State {
        let v = self
            .free_nodes()
            .iter()
            .flat_map(|&a| velocities.get(a).copied().unwrap_or([0.0; 3]))
            .collect();
        State {
            t: 0.0,
            q: self.q0.clone(),
            v,
        }
    }

    /// [`MsmModel::initial_state`] with every free node moved by `displacements[a]` at t = 0
    /// (one entry per node; an empty slice moves nothing).
    pub fn initial_state_displaced(
        &self,
        velocities: &[[f64; 3]],
        displacements: &[[f64; 3]],
    ) -> State {
        let mut state = self.initial_state(velocities);
        for (i, &a) in self.free_nodes().iter().enumerate() {
            if let Some(d) = displacements.get(a) {
                for x in 0..3 {
                    state.q[3 * i + x] += d[x];
                }
            }
        }
        state
    }

    /// All `3N` node coordinates from the free ones (fixed nodes at their initial positions).
    pub fn full_positions(&self, q_free: &[f64]) -> Vec<f64> {
        let mut x = self.x0.clone();
        self.dof_map.extend_into(q_free, &mut x);
        x
    }

    /// `ω_max` of the linearized model at the initial positions and the explicit limit
    /// `Δt_crit = 2/ω_max` (docs/math.md §5), by [`nurbspring_sim::stability_limit`].
    pub fn stability(&self) -> Result<StabilityLimit, MsmError> {
        Ok(stability_limit(self, &self.q0)?)
    }

    /// The unit-stiffness matrix `G_c` of one class on the free coordinates at `q` (so that
    /// `tangent_stiffness(q) = Σ_c k_c G_c` when every element of class `c` has constant `k_c`).
    pub fn unit_stiffness(&self, class: Class, q: &[f64]) -> SparseMatrix {
        match class {
            Class::Spring(_) | Class::Hinge(_) => self.assemble(q, &Coefficient::Unit(class)),
            Class::Linear(..) => {
                let free = self.free_nodes();
                PointDofs::XYZ.expand(
                    &self
                        .lattice
                        .linear_matrix(Some(class))
                        .submatrix(free, free),
                )
            }
        }
    }

    /// Bytes one fused symplectic-Euler step must read and write at least, `None` when the model
    /// has no fused step: the positions and velocities of the free nodes read and written once,
    /// one rest length per spring (and its stiffness where the springs of a direction do not
    /// share one), the per-node mass, damping and external force where they vary. The step's
    /// time against this count is its achieved bandwidth.
    pub fn fused_step_traffic(&self) -> Option<usize> {
        self.grid_step.as_ref().map(GridStep::traffic_bytes)
    }

    /// True when the model has no springs and no hinges: its force is linear,
    /// `f_int = (L_ff ⊗ I₃)(q − q₀)`.
    pub fn is_linear(&self) -> bool {
        self.lattice.springs.is_empty() && self.lattice.hinges.is_empty()
    }

    fn tangent_pattern(&self) -> &TangentPattern {
        self.pattern.get_or_init(|| self.topology.pattern())
    }

    fn assemble(&self, q: &[f64], coef: &Coefficient) -> SparseMatrix {
        let pattern = self.tangent_pattern();
        let mut k = pattern.template.clone();
        self.topology.fill(pattern, q, coef, k.values_mut());
        k
    }

    /// The springs' blocks with `coef` plus the linear elements.
    fn tangent(&self, q: &[f64], coef: &Coefficient) -> SparseMatrix {
        match &self.linear {
            Some(l) if self.is_linear() => l.clone(),
            Some(l) => SparseMatrix::linear_combination(1.0, &self.assemble(q, coef), 1.0, l)
                .expect("both are on the free coordinates"),
            None => self.assemble(q, coef),
        }
    }

    fn check_len(&self, what: &str, len: usize) {
        let n = self.q0.len();
        assert_eq!(len, n, "{what}: expected {n} free coordinates, got {len}");
    }
}

impl std::fmt::Debug for MsmModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MsmModel")
            .field("nodes", &self.lattice.n_nodes())
            .field("free_nodes", &self.topology.n_active())
            .field("springs", &self.lattice.springs.len())
            .field("hinges", &self.lattice.hinges.len())
            .field("damped", &self.damping.is_some())
            .field("fused_step", &self.grid_step.is_some())
            .finish()
    }
}

impl DynamicModel for MsmModel {
    fn n_dofs(&self) -> usize {
        self.q0.len()
    }

    fn mass(&self) -> &SystemMatrix {
        &self.mass
    }

    /// `diag(γ_a) ⊗ I_3`, or `None` when every free node has `γ = 0`.
    fn damping(&self) -> Option<&SystemMatrix> {
        self.damping.as_ref()
    }

    /// `f_int(q) = −f_elastic(q)` (paper eq. (5) and docs/math.md §5.2): `Σ_b k w (1 − l/|d|) d`
    /// per free node plus the hinges' `k w (θ − θ0) ∂θ/∂x`. Parallel over chunks of nodes.
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        self.check_len("internal_force q", q.len());
        self.check_len("internal_force out", out.len());
        let (x, _) = q.as_chunks::<3>();
        let (f, _) = out.as_chunks_mut::<3>();
        self.topology.internal_forces(x, f);
        if let Some(l) = &self.linear {
            let u: Vec<f64> = q.iter().zip(&self.q0).map(|(a, b)| a - b).collect();
            l.mul_vec_add(1.0, &u, out);
        }
    }

    /// `f_ext = m_a g` plus the node forces, on the free nodes (constant in time).
    fn external_force(&self, _t: f64, out: &mut [f64]) {
        out.copy_from_slice(&self.external);
    }

    /// `K_T(q) = ∂f_int/∂q` on the free coordinates (paper eqs. (9)–(10), geometric term
    /// included), always with the same pattern.
    fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix {
        self.check_len("tangent_stiffness q", q.len());
        self.tangent(q, &Coefficient::Stiffness)
    }

    /// `K_T` with the geometric term of compressed springs dropped and the hinges'
    /// Gauss–Newton part `k w ∇θ ∇θᵀ` only (positive semi-definite; the linear elements are
    /// kept as they are).
    fn projected_tangent_stiffness(&self, q: &[f64]) -> Option<SparseMatrix> {
        self.check_len("projected_tangent_stiffness q", q.len());
        Some(self.tangent(q, &Coefficient::ProjectedStiffness))
    }

    /// `Σ_springs k w (I on the diagonal blocks, −I off them)` plus the linear elements: each
    /// spring's block `B = k w [(l/r) n nᵀ + (1 − l/r) I]` has the eigenvalues `k w` and
    /// `k w (1 − l/r) < k w`, so `B ⪯ k w I` (for `k w ≥ 0`, which [`MsmModel::new`] requires)
    /// and `K_T(q) ⪯ K̄` at every configuration (docs/math.md §5). `None` with hinges: a hinge's
    /// Hessian grows without bound as a triangle flattens (`∂θ/∂x` scales as `1/h`), so the
    /// explicit schemes run below the limit at a state instead.
    fn stiffness_bound(&self) -> Option<SparseMatrix> {
        self.lattice
            .hinges
            .is_empty()
            .then(|| self.tangent(&self.q0, &Coefficient::Bound))
    }

    /// `L_ff ⊗ I₃` when the model has no springs (docs/math.md §8).
    fn linear_stiffness(&self) -> Option<&SparseMatrix> {
        self.linear.as_ref().filter(|_| self.is_linear())
    }

    /// Elastic energy of every spring and hinge, those among fixed nodes included.
    fn potential_energy(&self, q: &[f64]) -> f64 {
        self.check_len("potential_energy q", q.len());
        let (x, _) = q.as_chunks::<3>();
        let springs = self.topology.energy(x);
        match &self.linear {
            None => springs,
            Some(l) => {
                let u: Vec<f64> = q.iter().zip(&self.q0).map(|(a, b)| a - b).collect();
                springs + 0.5 * l.quadratic_form(&u)
            }
        }
    }

    /// On a grid lattice without linear elements whose springs join `(i, j)` to
    /// `(i + di, j + dj)`, `di ≤ 2`, `|dj| ≤ 2`, each offset on every node that has the
    /// partner (the lattices built from surfaces): one pass that evaluates every spring once
    /// and updates velocities and positions row by row (crates/msm/src/grid.rs). Its result
    /// is the generic path's up to the order of the force sums, and the same on any number of
    /// threads.
    fn fused_step(&self) -> Option<&dyn FusedStep> {
        self.grid_step.as_ref().map(|g| g as &dyn FusedStep)
    }

    /// The springs' axial dashpots (docs/math.md §5.1), when a spring has one.
    fn configuration_damping(&self) -> Option<&dyn ConfigurationDamping> {
        self.topology
            .is_damped()
            .then_some(self as &dyn ConfigurationDamping)
    }

    /// `−(q − q_0)ᵀ f_ext`: the potential of the constant gravity load, zero at the initial
    /// positions (so the total energy starts at the elastic plus kinetic energy).
    fn external_potential(&self, _t: f64, q: &[f64]) -> f64 {
        -q.iter()
            .zip(&self.q0)
            .zip(&self.external)
            .map(|((q, q0), f)| (q - q0) * f)
            .sum::<f64>()
    }
}

/// The springs' axial dashpots: `C(q) v` with `C = c n nᵀ` on each damped spring's two nodes
/// (`+` on the diagonal blocks, `−` off them), `n` its current direction (docs/math.md §5.1).
impl ConfigurationDamping for MsmModel {
    fn add_damping_force(&self, q: &[f64], v: &[f64], out: &mut [f64]) {
        self.check_len("add_damping_force q", q.len());
        self.check_len("add_damping_force v", v.len());
        self.check_len("add_damping_force out", out.len());
        let (x, _) = q.as_chunks::<3>();
        let (v, _) = v.as_chunks::<3>();
        let (f, _) = out.as_chunks_mut::<3>();
        self.topology.add_damping_forces(x, v, f);
    }

    /// On the pattern of the tangent stiffness.
    fn damping_matrix(&self, q: &[f64]) -> SparseMatrix {
        self.check_len("damping_matrix q", q.len());
        self.assemble(q, &Coefficient::AxialDamping)
    }
}
