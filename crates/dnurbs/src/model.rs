//! The constrained D-NURBS model (docs/math.md §3–4) as a [`DynamicModel`] on the reduced (free)
//! coordinates, with its steady state (paper eq. (8)) and modes.
//!
//! Sign convention of `nurbspring-sim`: `M q̈ + D q̇ + f_int(q) = f_ext(t)` on the free dofs,
//! with `f_int(q) = K_ff q + K_fc p_fixed − (K p_rest)_f` (a stiffness sign) and
//! `f_ext = f_f`; with linear constraints `p = G q + g` everything is projected by `Gᵀ`.
//! With constant weights the matrices are constant and `linear_stiffness` is `Some(K_ff)`, so
//! every integrator of `nurbspring-sim` applies. With weights as unknowns the matrices of the
//! `DynamicModel` and of [`DnurbsModel::modes`] are frozen at `p(0)` (a linearization); the
//! nonlinear motion is [`crate::RationalStepper`]'s and the nonlinear steady state is
//! [`DnurbsModel::steady_state_with`]'s (docs/math.md §3).

use nurbspring_linalg::{
    DenseMatrix, LinalgError, SparseMatrix, SpdSolver, generalized_eigen_sparse_lowest,
    generalized_symmetric_eigen,
};
use nurbspring_sim::{DofMap, DynamicModel, State, SystemMatrix};

use std::sync::Arc;

use crate::constraints::Reduction;
use crate::edge::EdgeLoads;
use crate::elasticity::{ElasticEnergy, TensionPlate};
use crate::{
    Constraints, DnurbsError, DnurbsOptions, Geometry, Integration, Loads, Material, Matrices,
    QuadratureChoice, RestShape, ShellEnergy, ShellMaterial, assemble,
};

/// Largest reduced system for which [`DnurbsModel::modes`] uses the dense generalized
/// eigensolver; above it, sparse shift-invert Lanczos.
pub const DENSE_MODES_LIMIT: usize = 2000;

/// Eigenpairs of `K φ = ω² M φ` on the free dofs (docs/math.md §3), ascending.
#[derive(Clone, Debug)]
pub struct Modes {
    /// Angular frequencies ω (rad/s), `√max(λ, 0)`.
    pub omega: Vec<f64>,
    /// Mode shapes on the free (reduced) dofs, one column per mode, M-orthonormal.
    pub vectors: DenseMatrix,
}

impl Modes {
    /// Periods `2π/ω` (infinite for rigid modes).
    pub fn periods(&self) -> Vec<f64> {
        self.omega
            .iter()
            .map(|&w| {
                if w > 0.0 {
                    2.0 * std::f64::consts::PI / w
                } else {
                    f64::INFINITY
                }
            })
            .collect()
    }
}

/// Settings of the nonlinear steady-state iteration ([`DnurbsModel::steady_state_with`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteadySettings {
    /// Relative residual at which the iteration stops (default 1e-13).
    pub tolerance: f64,
    /// Iteration limit (default 200).
    pub max_iterations: usize,
}

impl Default for SteadySettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-13,
            max_iterations: 200,
        }
    }
}

/// The result of [`DnurbsModel::steady_state_with`].
#[derive(Clone, Debug)]
pub struct SteadyState {
    /// The full generalized coordinates at rest.
    pub p: Vec<f64>,
    /// Iterates assembled (1 for constant weights).
    pub iterations: usize,
    /// Relative residual of the equilibrium at `p` (0 for constant weights).
    pub residual: f64,
}

/// Iterates mixed by [`DnurbsModel::steady_state_with`].
pub const ANDERSON_DEPTH: usize = 5;

/// The Anderson update `G_k − ΔG γ` with `γ` minimizing `|F_k − ΔF γ|` over the differences of
/// the history `(G_j, F_j = G_j − q_j)`; `None` with fewer than two entries or a singular fit.
fn anderson(history: &[(Vec<f64>, Vec<f64>)]) -> Option<Vec<f64>> {
    let m = history.len().checked_sub(1).filter(|&m| m > 0)?;
    let (g_k, f_k) = history.last()?;
    let n = f_k.len();
    let df = DenseMatrix::from_fn(n, m, |i, j| history[j + 1].1[i] - history[j].1[i]);
    let gamma = nurbspring_linalg::least_squares(&df, f_k).ok()?;
    if gamma.iter().any(|g| !g.is_finite()) {
        return None;
    }
    let mut out = g_k.clone();
    for (j, &c) in gamma.iter().enumerate() {
        for (i, o) in out.iter_mut().enumerate() {
            *o -= c * (history[j + 1].0[i] - history[j].0[i]);
        }
    }
    Some(out)
}

fn sub(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

fn norm(a: &[f64]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn mul(a: &SparseMatrix, x: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.nrows()];
    a.mul_vec(x, &mut out);
    out
}

/// A D-NURBS surface or curve with material, loads and constraints, reduced to its free dofs
/// (docs/math.md §3–4). Implements [`DynamicModel`].
#[derive(Clone, Debug)]
pub struct DnurbsModel {
    pub(crate) geometry: Geometry,
    pub(crate) material: Material,
    pub(crate) loads: Loads,
    pub(crate) options: DnurbsOptions,
    pub(crate) quadrature: QuadratureChoice,
    pub(crate) matrices: Matrices,
    pub(crate) reduction: Reduction,
    pub(crate) p0: Vec<f64>,
    pub(crate) p_rest: Vec<f64>,
    mass_r: SystemMatrix,
    damping_r: Option<SystemMatrix>,
    stiffness_r: SparseMatrix,
    /// `Pᵀ K (o − p_rest)`: `f_int(0)` (the shell: of its linearization at rest).
    f_int0: Vec<f64>,
    /// `Pᵀ f`.
    pub(crate) f_ext: Vec<f64>,
    /// The Kirchhoff–Love shell energy, when the model is a shell (docs/math.md §10); `None`:
    /// the tension plate of `material`.
    pub(crate) shell: Option<Arc<ShellEnergy>>,
    /// The edge loads' quadrature (their forces are in `f_ext`; the shell's moments enter the
    /// equilibrium path).
    pub(crate) edge_loads: EdgeLoads,
}

impl DnurbsModel {
    /// Assembles the matrices at `geometry` (paper eqs. (3)–(4)), resolves the constraints
    /// (docs/math.md §4) and reduces everything to the free dofs.
    pub fn new(
        geometry: Geometry,
        material: Material,
        loads: Loads,
        constraints: &Constraints,
        options: DnurbsOptions,
    ) -> Result<Self, DnurbsError> {
        material.validate(geometry.is_curve())?;
        loads.validate(&geometry)?;
        options.validate()?;
        if let Some((i, e)) = loads
            .edges
            .iter()
            .enumerate()
            .find(|(_, e)| e.moment != 0.0)
        {
            return Err(DnurbsError::InvalidLoad {
                detail: format!(
                    "edge load {i} on {} has a moment ({}): moments need the Kirchhoff–Love \
                     shell (the tension plate has no rotations)",
                    e.edge.name(),
                    e.moment
                ),
            });
        }
        let quadrature = options.quadrature_for(&geometry)?;
        let options = DnurbsOptions {
            quadrature_points: Some(quadrature.points),
            ..options
        };
        let wad = options.weights_as_dofs;
        let p0 = geometry.coordinates(wad);
        let reduction = Reduction::new(&geometry, constraints, wad, &p0)?;
        let matrices = assemble(&geometry, &material, &loads, &options)?;
        let p_rest = match options.rest_shape {
            RestShape::Initial => p0.clone(),
            RestShape::Zero => vec![0.0; p0.len()],
        };
        let ReducedSystem {
            mass_r,
            damping_r,
            stiffness_r,
            f_ext,
            f_int0,
        } = ReducedSystem::new(&reduction, &matrices, material.gamma, &p_rest)?;
        Ok(Self {
            geometry,
            material,
            loads,
            options,
            quadrature,
            matrices,
            reduction,
            p0,
            p_rest,
            mass_r,
            damping_r,
            stiffness_r,
            f_int0,
            f_ext,
            shell: None,
            edge_loads: EdgeLoads::default(),
        })
    }

    /// A Kirchhoff–Love shell (docs/math.md §10): the energy of [`ShellEnergy`] over the
    /// control points of `geometry` (a surface, its own rest shape), the mass
    /// `ρt ∫ R Rᵀ dA ⊗ I₃`, damping `γ ∫ R Rᵀ dA ⊗ I₃`, gravity `ρt g` and distributed loads
    /// per unit area (all integrated over the rest surface), point loads as for the tension
    /// plate; constraints as for the tension plate.
    ///
    /// The options' `integrate_over` is set to the area and the quadrature rule is chosen for
    /// the shell (docs/math.md §10.4); `weights_as_dofs` (the weights are geometry) and
    /// `rest_shape = "zero"` (the rest shape is the surface) are refused. The model is
    /// nonlinear: [`DynamicModel::internal_force`] and [`DynamicModel::tangent_stiffness`]
    /// evaluate the shell at the state, [`DnurbsModel::modes`] and
    /// [`DnurbsModel::reduced_stiffness`] use the tangent at rest, and
    /// [`DnurbsModel::equilibrium_path`] solves the nonlinear equilibrium.
    pub fn kirchhoff_love(
        geometry: Geometry,
        shell: ShellMaterial,
        loads: Loads,
        constraints: &Constraints,
        options: DnurbsOptions,
    ) -> Result<Self, DnurbsError> {
        shell.validate()?;
        if geometry.is_curve() {
            return Err(DnurbsError::InvalidOption {
                name: "model",
                value: "kirchhoff-love".into(),
                reason: "the Kirchhoff–Love shell needs a surface, not a curve".into(),
            });
        }
        if options.weights_as_dofs {
            return Err(DnurbsError::InvalidOption {
                name: "weights_as_dofs",
                value: "true".into(),
                reason: "the shell's weights are part of its geometry, not unknowns".into(),
            });
        }
        if options.rest_shape != RestShape::Initial {
            return Err(DnurbsError::InvalidOption {
                name: "rest_shape",
                value: options.rest_shape.name().into(),
                reason: "the shell's rest shape is the surface given".into(),
            });
        }
        loads.validate(&geometry)?;
        options.validate()?;
        let options = DnurbsOptions {
            integration: Integration::Area,
            ..options
        };
        let quadrature = crate::shell::quadrature(&geometry, &shell, &options)?;
        let options = DnurbsOptions {
            quadrature_points: Some(quadrature.points),
            ..options
        };
        let energy = ShellEnergy::new(&geometry, &shell, quadrature.points)?;
        let material = Material {
            mu: shell.mass_per_area(),
            gamma: shell.gamma,
            ..Material::default()
        };
        let p0 = geometry.coordinates(false);
        let reduction = Reduction::new(&geometry, constraints, false, &p0)?;
        let mut matrices = assemble(&geometry, &material, &loads, &options)?;
        matrices.stiffness = energy.tangent(&p0);
        let edge_loads = EdgeLoads::new(&geometry, &loads.edges, quadrature.points)?;
        // The linearization at rest: f_int(q) ≈ K_r q + Pᵀ K_T (o − p0).
        let ReducedSystem {
            mass_r,
            damping_r,
            stiffness_r,
            f_ext,
            f_int0,
        } = ReducedSystem::new(&reduction, &matrices, material.gamma, &p0)?;
        Ok(Self {
            geometry,
            material,
            loads,
            options,
            quadrature,
            matrices,
            f_int0,
            reduction,
            p_rest: p0.clone(),
            p0,
            mass_r,
            damping_r,
            stiffness_r,
            f_ext,
            shell: Some(Arc::new(energy)),
            edge_loads,
        })
    }

    /// The model of `material`: [`DnurbsModel::new`] for the tension plate,
    /// [`DnurbsModel::kirchhoff_love`] for the shell.
    pub fn build(
        geometry: Geometry,
        material: &crate::MaterialModel,
        loads: Loads,
        constraints: &Constraints,
        options: DnurbsOptions,
    ) -> Result<Self, DnurbsError> {
        match material {
            crate::MaterialModel::TensionPlate(m) => {
                Self::new(geometry, m.clone(), loads, constraints, options)
            }
            crate::MaterialModel::KirchhoffLove(m) => {
                Self::kirchhoff_love(geometry, *m, loads, constraints, options)
            }
        }
    }

    /// The material model: the tension plate's coefficients, or the shell's material.
    pub fn material_model(&self) -> crate::MaterialModel {
        match &self.shell {
            Some(s) => crate::MaterialModel::KirchhoffLove(*s.material()),
            None => crate::MaterialModel::TensionPlate(self.material.clone()),
        }
    }

    /// The shell's energy, when the model is a Kirchhoff–Love shell.
    pub fn shell(&self) -> Option<&ShellEnergy> {
        self.shell.as_deref()
    }

    /// The elastic energy over all generalized coordinates: the shell's, or the tension
    /// plate's `½ (p − p_rest)ᵀ K (p − p_rest)` (constant weights; with weights as unknowns
    /// the plate of the initial shape).
    pub fn elasticity(&self) -> Box<dyn ElasticEnergy + '_> {
        match &self.shell {
            Some(shell) => Box::new(shell.as_ref()),
            None => Box::new(TensionPlate {
                stiffness: &self.matrices.stiffness,
                rest: &self.p_rest,
            }),
        }
    }

    /// The geometry at `t = 0`.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The material.
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// The loads.
    pub fn loads(&self) -> &Loads {
        &self.loads
    }

    /// The options, with `quadrature_points` resolved ([`DnurbsModel::quadrature`]).
    pub fn options(&self) -> &DnurbsOptions {
        &self.options
    }

    /// The Gauss–Legendre rule of the model and its estimated error (docs/math.md §3).
    pub fn quadrature(&self) -> &QuadratureChoice {
        &self.quadrature
    }

    /// The full, unconstrained matrices at `p(0)`.
    pub fn matrices(&self) -> &Matrices {
        &self.matrices
    }

    /// The map of fixed dofs (free first). With linear constraints the model's coordinates are
    /// `q` with `p_free = G q + g`, see [`DnurbsModel::full_coordinates`].
    pub fn dof_map(&self) -> &DofMap {
        &self.reduction.dof_map
    }

    /// Control points all of whose x, y, z dofs are fixed, ascending.
    pub fn fixed_points(&self) -> &[usize] {
        &self.reduction.fixed_points
    }

    /// With weights as unknowns and no weight fixed: the weight dof pinned to remove the
    /// common-scale gauge (see [`Constraints`] and docs/math.md §3), else `None`.
    pub fn gauge_weight(&self) -> Option<usize> {
        self.reduction.gauge_weight
    }

    /// True when linear constraints are substituted (`p_free = G q + g`).
    pub fn has_linear_constraints(&self) -> bool {
        self.reduction.affine.is_some()
    }

    /// Number of reduced coordinates (free dofs, or null-space coordinates with linear
    /// constraints).
    pub fn n_free(&self) -> usize {
        self.reduction.n_q
    }

    /// Full initial generalized coordinates `p(0)` (docs/math.md §1 ordering).
    pub fn p0(&self) -> &[f64] {
        &self.p0
    }

    /// The rest shape `p_rest` (docs/math.md §3).
    pub fn p_rest(&self) -> &[f64] {
        &self.p_rest
    }

    /// Reduced mass matrix `Pᵀ M P`.
    pub fn reduced_mass(&self) -> &SparseMatrix {
        match &self.mass_r {
            SystemMatrix::Sparse(m) => m,
            SystemMatrix::Diagonal(_) => unreachable!("D-NURBS mass is sparse"),
        }
    }

    /// Reduced stiffness matrix `Pᵀ K P` (`K_ff` without linear constraints).
    pub fn reduced_stiffness(&self) -> &SparseMatrix {
        &self.stiffness_r
    }

    /// Reduced external force `Pᵀ f_p`.
    pub fn reduced_force(&self) -> &[f64] {
        &self.f_ext
    }

    /// Full `p` from reduced coordinates: free dofs from `q` (through `p = G q + g` with linear
    /// constraints), fixed dofs at their `p(0)` values (docs/math.md §4).
    pub fn full_coordinates(&self, q_free: &[f64]) -> Vec<f64> {
        self.reduction.to_full(q_free)
    }

    /// Full velocity `ṗ` from a reduced one (zero on fixed dofs).
    pub fn full_velocity(&self, v_free: &[f64]) -> Vec<f64> {
        self.reduction.embed(v_free)
    }

    /// Reduced coordinates of a full `p` (the orthogonal projection with linear constraints).
    pub fn reduced_coordinates(&self, p_full: &[f64]) -> Vec<f64> {
        self.reduction.reduce_coordinates(p_full)
    }

    /// Initial state on the free dofs from per-control-point velocities (docs/math.md §4: fixed dofs
    /// get zero). `velocity` has one entry per control point, or a single entry applied to
    /// every point (missing entries count as zero, extra ones are ignored);
    /// `weight_velocity` is `ẇ` of every free weight (4 dofs only).
    pub fn initial_state(&self, velocity: &[[f64; 3]], weight_velocity: f64) -> State {
        let m = self.matrices.dofs_per_point;
        let n = self.geometry.n_control_points();
        let mut v = vec![0.0; n * m];
        for k in 0..n {
            let vk = match velocity.len() {
                1 => velocity[0],
                len if k < len => velocity[k],
                _ => [0.0; 3],
            };
            v[k * m..k * m + 3].copy_from_slice(&vk);
            if m == 4 {
                v[k * m + 3] = weight_velocity;
            }
        }
        State {
            t: 0.0,
            q: self.reduction.reduce_coordinates(&self.p0),
            v: self.reduction.reduce_vector(&v),
        }
    }

    /// [`DnurbsModel::initial_state`] with every free control point moved by `displacement` at
    /// t = 0 (fixed points stay; with linear constraints the moved net is projected onto them).
    pub fn initial_state_displaced(
        &self,
        velocity: &[[f64; 3]],
        weight_velocity: f64,
        displacement: [f64; 3],
    ) -> State {
        let mut state = self.initial_state(velocity, weight_velocity);
        if displacement != [0.0; 3] {
            let m = self.matrices.dofs_per_point;
            let mut p = self.full_coordinates(&state.q);
            let fixed = self.fixed_points();
            for k in 0..self.geometry.n_control_points() {
                if !fixed.contains(&k) {
                    for x in 0..3 {
                        p[m * k + x] += displacement[x];
                    }
                }
            }
            state.q = self.reduced_coordinates(&p);
        }
        state
    }

    /// The elastic energy of a full `p`: `½ (p − p_rest)ᵀ K (p − p_rest)` (docs/math.md §3), or
    /// the shell's (§10).
    pub fn elastic_energy(&self, p_full: &[f64]) -> f64 {
        self.elasticity().energy(p_full)
    }

    /// The shell's internal force on the reduced coordinates, `Pᵀ f(P q + o)`.
    fn shell_force(&self, shell: &ShellEnergy, q: &[f64]) -> Vec<f64> {
        let p = self.reduction.to_full(q);
        let mut f = vec![0.0; p.len()];
        shell.internal_force(&p, &mut f);
        self.reduction.reduce_vector(&f)
    }

    /// The shell's tangent on the reduced coordinates, `Pᵀ K_T(P q + o) P`.
    fn shell_tangent(&self, shell: &ShellEnergy, q: &[f64]) -> SparseMatrix {
        let k = shell.tangent(&self.reduction.to_full(q));
        self.reduction
            .reduce_matrix(&k)
            .expect("the reduction of a matrix on the model's own pattern")
    }

    /// Steady state (paper eq. (8), docs/math.md §3): the full `p` at rest, solving
    /// `K(p) (p − p_rest) = f_p(p)` on the free dofs (projected by `Gᵀ` with linear
    /// constraints); for the shell, `f_int(p) = f` by [`DnurbsModel::equilibrium_path`].
    ///
    /// With constant weights K and f are constant and this is one linear solve,
    /// [`DnurbsModel::linearized_steady_state`]. With weights as unknowns K and f depend on the
    /// shape and the nonlinear equilibrium is found by the fixed-point iteration of
    /// [`DnurbsModel::steady_state_with`] started from the linearized solution.
    ///
    /// Returns [`DnurbsError::Singular`] when the reduced stiffness is singular, e.g. a
    /// free-floating body (nothing fixed: rigid translations cost no energy).
    pub fn steady_state(&self) -> Result<Vec<f64>, DnurbsError> {
        if self.shell.is_some() {
            return Ok(self.steady_state_with(SteadySettings::default())?.p);
        }
        if self.options.weights_as_dofs {
            Ok(self.steady_state_with(SteadySettings::default())?.p)
        } else {
            self.linearized_steady_state()
        }
    }

    /// The linear steady state with the matrices of the initial shape: `K(p(0)) (p − p_rest) =
    /// f_p(p(0))` on the free dofs. With constant weights it is the steady state; with weights
    /// as unknowns it is the first iterate of [`DnurbsModel::steady_state_with`].
    pub fn linearized_steady_state(&self) -> Result<Vec<f64>, DnurbsError> {
        self.solve_at(&self.stiffness_r, &self.f_ext, &self.f_int0)
    }

    /// The nonlinear steady state with weights as unknowns (docs/math.md §3): the fixed point
    /// of `G(p) = p⁺` with `K(p) (p⁺ − p_rest) = f_p(p)` on the free dofs, M, K and f
    /// assembled at each iterate, started from the linearized solution and accelerated by
    /// Anderson mixing over the last [`ANDERSON_DEPTH`] iterates. It stops when the relative
    /// residual `|Pᵀ (f_p(p) − K(p)(p − p_rest))| / (|Pᵀ f_p(p)| + |Pᵀ K(p)(p − p_rest)|)` is at
    /// most `settings.tolerance`, or when the update falls to round-off (`|G(p) − p| ≤ 10⁻¹⁴ |p|`);
    /// it fails with [`DnurbsError::Singular`] when neither happens within
    /// `settings.max_iterations` or a weight becomes non-positive. With constant weights the
    /// first iterate is exact (`iterations = 1`).
    pub fn steady_state_with(&self, settings: SteadySettings) -> Result<SteadyState, DnurbsError> {
        if self.shell.is_some() {
            // The shell: the equilibrium path to the full load (docs/math.md §10.5).
            let path = self.equilibrium_path(
                &crate::PathSettings {
                    tolerance: settings
                        .tolerance
                        .max(crate::PathSettings::default().tolerance),
                    ..crate::PathSettings::default()
                },
                &|| false,
                &mut |_| {},
            )?;
            let last = path.levels.last().expect("the path ends at the full load");
            return Ok(SteadyState {
                p: last.p.clone(),
                iterations: path.iterations,
                residual: last.residual,
            });
        }
        let p1 = self.linearized_steady_state()?;
        let wad = self.options.weights_as_dofs;
        if !wad || self.reduction.n_q == 0 {
            return Ok(SteadyState {
                p: p1,
                iterations: 1,
                residual: 0.0,
            });
        }
        let assembler = crate::Assembler::new(&self.geometry, &self.options)?;
        let mut q = self.reduction.reduce_coordinates(&p1);
        let mut residual = f64::INFINITY;
        // Anderson history: (G(q_j), G(q_j) − q_j).
        let mut history: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
        for k in 1..=settings.max_iterations {
            let p = self.reduction.to_full(&q);
            if let Some(d) = (0..p.len() / 4).map(|i| 4 * i + 3).find(|&d| p[d] <= 0.0) {
                return Err(DnurbsError::Singular {
                    detail: format!(
                        "the steady-state iteration reached weight {:e} of control point {} \
                         (iteration {k}); the nonlinear equilibrium with weights as unknowns is \
                         not reachable from the initial shape under these loads (hold weights \
                         with constraints.fixed_weights or constraints.fixed_point_weights)",
                        p[d],
                        d / 4
                    ),
                });
            }
            let geo = self.geometry.with_coordinates(&p, true)?;
            let mats = assembler.assemble(&geo, &self.material, &self.loads)?;
            let k_r = self.reduction.reduce_matrix(&mats.stiffness)?;
            let f_r = self.reduction.reduce_vector(&mats.force);
            let elastic = self
                .reduction
                .reduce_vector(&mul(&mats.stiffness, &sub(&p, &self.p_rest)));
            let scale = norm(&f_r) + norm(&elastic);
            residual = if scale > 0.0 {
                norm(&sub(&f_r, &elastic)) / scale
            } else {
                0.0
            };
            if residual <= settings.tolerance {
                return Ok(SteadyState {
                    p,
                    iterations: k,
                    residual,
                });
            }
            let f_int0 = self.reduction.reduce_vector(&mul(
                &mats.stiffness,
                &sub(&self.reduction.offset, &self.p_rest),
            ));
            let g = self
                .reduction
                .reduce_coordinates(&self.solve_at(&k_r, &f_r, &f_int0)?);
            let f = sub(&g, &q);
            if norm(&f) <= 1e-14 * norm(&p) {
                return Ok(SteadyState {
                    p,
                    iterations: k,
                    residual,
                });
            }
            history.push((g.clone(), f.clone()));
            if history.len() > ANDERSON_DEPTH + 1 {
                history.remove(0);
            }
            q = anderson(&history).unwrap_or(g);
        }
        Err(DnurbsError::Singular {
            detail: format!(
                "the steady-state iteration with weights as unknowns did not converge in {} \
                 iterations (relative residual {residual:e}, tolerance {:e}); the loads are too \
                 large for the iteration from the initial shape",
                settings.max_iterations, settings.tolerance
            ),
        })
    }

    /// Solves `k_r q = f − f_int0` with the singularity checks of [`DnurbsModel::steady_state`]
    /// and returns the full `p`.
    fn solve_at(
        &self,
        k_r: &SparseMatrix,
        f_ext: &[f64],
        f_int0: &[f64],
    ) -> Result<Vec<f64>, DnurbsError> {
        let n = self.reduction.n_q;
        if n == 0 {
            return Ok(self.reduction.to_full(&[]));
        }
        if k_r.frobenius_norm() == 0.0 {
            return Err(DnurbsError::Singular {
                detail: "the stiffness matrix is zero: every alpha and beta coefficient is 0"
                    .into(),
            });
        }
        // Rigid translations are in the null space of K (partition of unity); they stay in the
        // reduced space when no dof fixes them.
        let m = self.matrices.dofs_per_point;
        let n_total = self.p0.len();
        for (x, name) in ["x", "y", "z"].iter().enumerate() {
            let t: Vec<f64> = (0..n_total)
                .map(|d| if d % m == x { 1.0 } else { 0.0 })
                .collect();
            let back = self.reduction.embed(&self.reduction.reduce_vector(&t));
            let err: f64 = back
                .iter()
                .zip(&t)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if err < 1e-9 {
                return Err(DnurbsError::Singular {
                    detail: format!(
                        "no constraint holds the body in {name}: a rigid translation along {name} \
                         costs no elastic energy, so K is singular on the free dofs (free-floating \
                         body; fix control points, e.g. fixed_rings = 1)"
                    ),
                });
            }
        }
        let solver = SpdSolver::new(k_r).map_err(|e| match e {
            LinalgError::NotPositiveDefinite { detail } => DnurbsError::Singular {
                detail: format!(
                    "the stiffness on the {n} free dofs is not positive definite ({detail}); \
                     the constraints leave a zero-energy motion free"
                ),
            },
            other => DnurbsError::Linalg(other),
        })?;
        // A singular PSD matrix can factor with tiny pivots: check that the factorization
        // reproduces a known solution.
        let y: Vec<f64> = (0..n)
            .map(|i| 1.0 + ((i * 7919) % 13) as f64 / 13.0)
            .collect();
        let mut ky = vec![0.0; n];
        k_r.mul_vec(&y, &mut ky);
        let x = solver.solve(&ky);
        let rel = norm(&sub(&x, &y)) / norm(&y);
        if rel.is_nan() || rel >= 1e-6 {
            return Err(DnurbsError::Singular {
                detail: format!(
                    "the stiffness on the {n} free dofs is numerically singular (a test solve \
                     has relative error {rel:e}); the constraints leave a zero-energy motion free"
                ),
            });
        }
        let q = solver.solve(&sub(f_ext, f_int0));
        if q.iter().any(|v| !v.is_finite()) {
            return Err(DnurbsError::Singular {
                detail: "the steady-state solve produced non-finite values".into(),
            });
        }
        Ok(self.reduction.to_full(&q))
    }

    /// The `count` lowest modes `K φ = ω² M φ` on the free dofs (docs/math.md §3): the dense
    /// generalized eigensolver when `n_free ≤ DENSE_MODES_LIMIT`, sparse shift-invert Lanczos
    /// otherwise (`μ > 0` is a rule of [`Material`], so M is positive definite).
    pub fn modes(&self, count: usize) -> Result<Modes, DnurbsError> {
        let n = self.reduction.n_q;
        let count = count.min(n);
        if count == 0 {
            return Ok(Modes {
                omega: Vec::new(),
                vectors: DenseMatrix::zeros(n, 0),
            });
        }
        let mass = self.reduced_mass();
        let eig = if n <= DENSE_MODES_LIMIT {
            let e = generalized_symmetric_eigen(&self.stiffness_r.to_dense(), &mass.to_dense())?;
            let vectors = DenseMatrix::from_fn(n, count, |i, j| e.vectors[(i, j)]);
            nurbspring_linalg::SymmetricEigen {
                values: e.values[..count].to_vec(),
                vectors,
            }
        } else {
            // A small negative shift keeps K − σM positive definite even with rigid modes.
            let tk: f64 = self.stiffness_r.diagonal().iter().sum();
            let tm: f64 = mass.diagonal().iter().sum();
            let shift = if tk > 0.0 { -1e-6 * tk / tm } else { -1.0 };
            generalized_eigen_sparse_lowest(&self.stiffness_r, mass, count, shift)?
        };
        Ok(Modes {
            omega: eig.values.iter().map(|&l| l.max(0.0).sqrt()).collect(),
            vectors: eig.vectors,
        })
    }

    /// The point `J(u, v) p = c(u, v)` of the shape with full coordinates `p_full` (with 4 dofs
    /// the weights are taken from `p_full`); paper eqs. (1), (11).
    pub fn point(&self, u: f64, v: f64, p_full: &[f64]) -> Result<[f64; 3], DnurbsError> {
        if p_full.len() != self.p0.len() {
            return Err(DnurbsError::DimensionMismatch {
                what: "generalized coordinates p",
                expected: self.p0.len(),
                found: p_full.len(),
            });
        }
        if self.options.weights_as_dofs {
            Ok(self.geometry.with_coordinates(p_full, true)?.point(u, v)?)
        } else {
            let j = self.geometry.jacobian(u, v, 0, false)?;
            Ok(j.apply(nurbspring_geom::Deriv::Value, p_full))
        }
    }
}

impl DynamicModel for DnurbsModel {
    fn n_dofs(&self) -> usize {
        self.reduction.n_q
    }

    fn mass(&self) -> &SystemMatrix {
        &self.mass_r
    }

    fn damping(&self) -> Option<&SystemMatrix> {
        self.damping_r.as_ref()
    }

    /// `f_int(q) = K_r q + Pᵀ K (o − p_rest)` (docs/math.md §3–4); the shell's `Pᵀ f(P q + o)`
    /// (§10).
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        match &self.shell {
            None => {
                out.copy_from_slice(&self.f_int0);
                self.stiffness_r.mul_vec_add(1.0, q, out);
            }
            Some(shell) => out.copy_from_slice(&self.shell_force(shell, q)),
        }
    }

    fn external_force(&self, _t: f64, out: &mut [f64]) {
        out.copy_from_slice(&self.f_ext);
    }

    fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix {
        match &self.shell {
            None => self.stiffness_r.clone(),
            Some(shell) => self.shell_tangent(shell, q),
        }
    }

    fn potential_energy(&self, q: &[f64]) -> f64 {
        self.elastic_energy(&self.reduction.to_full(q))
    }

    fn linear_stiffness(&self) -> Option<&SparseMatrix> {
        match &self.shell {
            None => Some(&self.stiffness_r),
            Some(_) => None,
        }
    }

    fn external_potential(&self, _t: f64, q: &[f64]) -> f64 {
        -q.iter().zip(&self.f_ext).map(|(a, b)| a * b).sum::<f64>()
    }
}

#[cfg(test)]
mod tests;

/// The model's matrices and loads on its reduced coordinates: `M_r`, `D_r` (when γ > 0),
/// `K_r`, the reduced load and `f_int0 = Pᵀ K (o − p_rest)`, the elastic force of the
/// constraints' offset `o` (so that `f_int(q) = K_r q + f_int0`).
struct ReducedSystem {
    mass_r: SystemMatrix,
    damping_r: Option<SystemMatrix>,
    stiffness_r: SparseMatrix,
    f_ext: Vec<f64>,
    f_int0: Vec<f64>,
}

impl ReducedSystem {
    fn new(
        reduction: &Reduction,
        matrices: &Matrices,
        gamma: f64,
        rest: &[f64],
    ) -> Result<Self, DnurbsError> {
        let damping_r = if gamma > 0.0 {
            Some(SystemMatrix::Sparse(
                reduction.reduce_matrix(&matrices.damping)?,
            ))
        } else {
            None
        };
        let diff: Vec<f64> = reduction
            .offset
            .iter()
            .zip(rest)
            .map(|(o, r)| o - r)
            .collect();
        let mut k_diff = vec![0.0; diff.len()];
        matrices.stiffness.mul_vec(&diff, &mut k_diff);
        Ok(Self {
            mass_r: SystemMatrix::Sparse(reduction.reduce_matrix(&matrices.mass)?),
            damping_r,
            stiffness_r: reduction.reduce_matrix(&matrices.stiffness)?,
            f_ext: reduction.reduce_vector(&matrices.force),
            f_int0: reduction.reduce_vector(&k_diff),
        })
    }
}
