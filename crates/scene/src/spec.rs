//! The sections of a scene file as Rust types. Every table is `deny_unknown_fields`, every
//! section has a `Default` (the values documented in `docs/scenes.md`). Where a model type
//! is the table key for key it is used directly (`[material]` is read as [`RawMaterial`] and
//! validated into `nurbspring_dnurbs::MaterialModel`), `[dnurbs]` is `nurbspring_dnurbs::DnurbsOptions`, integrators are
//! `nurbspring_sim::IntegratorKind`.

use std::path::PathBuf;

use nurbspring_derive::{FitDofs, FitMethod, MassScan, Method};
use nurbspring_dnurbs::{DnurbsOptions, Edge, MaterialModel};
use nurbspring_msm::{LinearKind, ParameterGrid};
use nurbspring_sim::IntegratorKind;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::ser::Serializer;
use serde::{Deserialize, Serialize};

/// The geometry: exactly one of `[surface]` or `[curve]`.
#[derive(Clone, Debug, PartialEq)]
pub enum GeometrySpec {
    /// A tensor-product NURBS surface (`[surface]`).
    Surface(SurfaceSpec),
    /// A NURBS curve (`[curve]`), the one-parameter case.
    Curve(CurveSpec),
}

impl GeometrySpec {
    /// Control points along u and along v (`n_v = 1` for a curve).
    pub fn net_dims(&self) -> (usize, usize) {
        match self {
            GeometrySpec::Surface(s) => (s.n_u(), s.n_v()),
            GeometrySpec::Curve(c) => (c.control_points.len(), 1),
        }
    }

    /// Number of control points.
    pub fn n_control_points(&self) -> usize {
        let (a, b) = self.net_dims();
        a * b
    }

    /// True for `[surface]`.
    pub fn is_surface(&self) -> bool {
        matches!(self, GeometrySpec::Surface(_))
    }

    /// The section name, `"surface"` or `"curve"`.
    pub fn section(&self) -> &'static str {
        match self {
            GeometrySpec::Surface(_) => "surface",
            GeometrySpec::Curve(_) => "curve",
        }
    }
}

/// `[surface]`: a NURBS surface (docs/math.md §1–2). Control point `(i, j)` is `control_points[i][j]`,
/// `i` along u (rows), `j` along v; flat index `k = i · n_v + j`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceSpec {
    /// Degree along u (≥ 1; the paper's order is degree + 1).
    pub degree_u: usize,
    /// Degree along v (≥ 1).
    pub degree_v: usize,
    /// Knot vector along u, non-decreasing, `n_u + degree_u + 1` values.
    pub knots_u: Vec<f64>,
    /// Knot vector along v, `n_v + degree_v + 1` values.
    pub knots_v: Vec<f64>,
    /// `n_u` rows of `n_v` points `[x, y, z]`.
    pub control_points: Vec<Vec<[f64; 3]>>,
    /// Weights with the shape of `control_points` (all 1 when absent); positive.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weights: Option<Vec<Vec<f64>>>,
}

impl SurfaceSpec {
    /// Control points along u (rows).
    pub fn n_u(&self) -> usize {
        self.control_points.len()
    }

    /// Control points along v (length of the first row).
    pub fn n_v(&self) -> usize {
        self.control_points.first().map_or(0, Vec::len)
    }

    /// Control points in flat order `k = i · n_v + j`.
    pub fn flat_control_points(&self) -> Vec<[f64; 3]> {
        self.control_points.iter().flatten().copied().collect()
    }

    /// Weights in flat order (1 where the scene gives none).
    pub fn flat_weights(&self) -> Vec<f64> {
        match &self.weights {
            Some(w) => w.iter().flatten().copied().collect(),
            None => vec![1.0; self.n_u() * self.n_v()],
        }
    }
}

/// `[curve]`: a NURBS curve.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CurveSpec {
    /// Degree (≥ 1).
    pub degree: usize,
    /// Knot vector, `n + degree + 1` values.
    pub knots: Vec<f64>,
    /// `n` points `[x, y, z]`.
    pub control_points: Vec<[f64; 3]>,
    /// `n` positive weights (all 1 when absent).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weights: Option<Vec<f64>>,
}

impl CurveSpec {
    /// Weights (1 where the scene gives none).
    pub fn flat_weights(&self) -> Vec<f64> {
        self.weights
            .clone()
            .unwrap_or_else(|| vec![1.0; self.control_points.len()])
    }
}

/// `[loads]`: external forces (default: none).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoadsSpec {
    /// Gravitational acceleration g; the force density is μ g.
    pub gravity: [f64; 3],
    /// Constant force per unit parameter area (per unit parameter length for a curve).
    pub distributed: [f64; 3],
    /// Point loads (`[[loads.point]]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub point: Vec<PointLoadSpec>,
    /// Edge loads (`[[loads.edge]]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub edge: Vec<EdgeLoadSpec>,
}

/// `[material]` as written: the keys of both models, each optional, so that every rule can
/// name its key (the model's own rules come from `Material::problems` and
/// `ShellMaterial::problems`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMaterial {
    pub(crate) model: Option<String>,
    pub(crate) mu: Option<f64>,
    pub(crate) gamma: Option<f64>,
    pub(crate) alpha11: Option<f64>,
    pub(crate) alpha22: Option<f64>,
    pub(crate) beta11: Option<f64>,
    pub(crate) beta12: Option<f64>,
    pub(crate) beta22: Option<f64>,
    pub(crate) young: Option<f64>,
    pub(crate) poisson: Option<f64>,
    pub(crate) thickness: Option<f64>,
    pub(crate) density: Option<f64>,
}

/// One `[[loads.edge]]`: a force and a moment per unit length on a boundary edge of a surface
/// (docs/math.md §10.6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeLoadSpec {
    /// `"u0"`, `"u1"`, `"v0"` or `"v1"`.
    pub edge: Edge,
    /// Force per unit length of the rest edge.
    #[serde(default)]
    pub force: [f64; 3],
    /// Moment per unit length about the edge's rest tangent (the shell only).
    #[serde(default)]
    pub moment: f64,
}

/// One `[[loads.point]]`: a force applied at a parameter point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLoadSpec {
    /// Parameter u (inside the knot domain).
    pub u: f64,
    /// Parameter v (surfaces only; required there).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v: Option<f64>,
    /// The force vector.
    pub force: [f64; 3],
}

/// `[constraints]`: fixed control points and general linear constraints (docs/math.md §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConstraintsSpec {
    /// Fix the `k` outer rings of control points (0 = none); for a curve, `k` points at each end.
    pub fixed_rings: usize,
    /// Further fixed control points, `[i, j]` (curves: `[i]`).
    pub fixed: Vec<Vec<usize>>,
    /// Hold the weights fixed when weights are unknowns (default true).
    pub fixed_weights: bool,
    /// With weights as unknowns and `fixed_weights = false`: whether the weights of the fixed
    /// control points are `free` (default) or `held` at their initial values.
    pub fixed_point_weights: FixedPointWeights,
    /// General constraints `A p = b`, one row each (`[[constraints.linear]]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub linear: Vec<LinearConstraintSpec>,
    /// Conditions along surface edges (`[[constraints.edge]]`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub edge: Vec<EdgeConstraintSpec>,
}

/// One `[[constraints.edge]]`: a boundary condition along an edge of the control net, given
/// by `condition` or by the components to `hold` (docs/math.md §10.7).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeConstraintSpec {
    /// `"u0"`, `"u1"`, `"v0"` or `"v1"`.
    pub edge: Edge,
    /// `"clamped"`, `"pinned"` or `"symmetry"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition: Option<EdgeConditionName>,
    /// Components of the edge's control points to hold, e.g. `["y", "z"]` (a rigid diaphragm).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hold: Vec<Component>,
}

/// The named edge conditions of `[[constraints.edge]]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EdgeConditionName {
    /// The edge row and the next row held (zero displacement and slope).
    Clamped,
    /// The edge row held (zero displacement, free rotation about the edge).
    Pinned,
    /// A plane of symmetry through the edge.
    Symmetry,
}

impl Default for ConstraintsSpec {
    fn default() -> Self {
        Self {
            fixed_rings: 0,
            fixed: Vec::new(),
            fixed_weights: true,
            fixed_point_weights: FixedPointWeights::Free,
            linear: Vec::new(),
            edge: Vec::new(),
        }
    }
}

/// The weights of fixed control points when weights are unknowns (docs/math.md §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FixedPointWeights {
    /// A fixed point fixes its x, y, z; its weight moves (the surface near it can still move).
    #[default]
    Free,
    /// A fixed point fixes its weight too (with its neighbours fixed, the boundary stays put).
    Held,
}

impl FixedPointWeights {
    /// "free" or "held", as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            FixedPointWeights::Free => "free",
            FixedPointWeights::Held => "held",
        }
    }
}

/// One row `Σ coefficient · p[point].component = rhs` of a linear constraint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearConstraintSpec {
    /// The terms of the row (at least one).
    pub terms: Vec<LinearTermSpec>,
    /// Right-hand side b (default 0).
    #[serde(default)]
    pub rhs: f64,
}

/// One term of a linear constraint row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearTermSpec {
    /// Control point `[i, j]` (curves: `[i]`).
    pub point: Vec<usize>,
    /// Which coordinate.
    pub component: Component,
    /// Coefficient (default 1).
    #[serde(default = "one")]
    pub coefficient: f64,
}

fn one() -> f64 {
    1.0
}

/// A generalized coordinate of a control point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    /// x.
    X,
    /// y.
    Y,
    /// z.
    Z,
    /// The weight (only when `dnurbs.weights_as_dofs = true`).
    W,
}

impl Component {
    /// Offset within a control point's dofs: x 0, y 1, z 2, w 3.
    pub fn offset(self) -> usize {
        match self {
            Component::X => 0,
            Component::Y => 1,
            Component::Z => 2,
            Component::W => 3,
        }
    }
}

/// `[initial]`: initial state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InitialSpec {
    /// Velocity of every free control point (fixed ones get zero).
    pub velocity: [f64; 3],
    /// Velocity of every free weight (weights as unknowns only).
    pub weight_velocity: f64,
    /// Per-control-point velocities in flat order `k = i · n_v + j`; in the file they have the
    /// shape of `control_points`. Replaces `velocity` (which must then be left at zero).
    pub velocities: Option<Vec<[f64; 3]>>,
    /// Constant offset added to the free control points at t = 0.
    pub displacement: [f64; 3],
}

/// `[simulation]`: time stepping and probes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimulationSpec {
    /// Time step Δt in seconds (> 0; default 0.08, the paper's).
    pub dt: f64,
    /// End time in seconds (> 0; default 4).
    pub t_end: f64,
    /// Integrator of the D-NURBS model (one of `DnurbsModel::INTEGRATORS`).
    pub dnurbs_integrator: IntegratorKind,
    /// Integrator of the mass-spring model (one of `MsmModel::INTEGRATORS`).
    pub msm_integrator: IntegratorKind,
    /// Record a sample every n steps (≥ 1).
    pub save_every: usize,
    /// Extra probe points `[u, v]` (curves: `[u]`); `(0.5, 0.5)` is always probed first.
    pub probes: Vec<Vec<f64>>,
    /// Spectral radius at infinite frequency of the generalized-α scheme (0 ≤ ρ∞ ≤ 1,
    /// default 0.8).
    pub rho_infinity: f64,
}

impl Default for SimulationSpec {
    fn default() -> Self {
        Self {
            dt: 0.08,
            t_end: 4.0,
            dnurbs_integrator: IntegratorKind::TerzopoulosQin,
            msm_integrator: IntegratorKind::SymplecticEuler,
            save_every: 1,
            probes: Vec::new(),
            rho_infinity: nurbspring_sim::integrators::DEFAULT_RHO_INFINITY,
        }
    }
}

/// `[msm]`: the mass-spring lattice (docs/math.md §5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MsmSpec {
    /// Where the nodes sit in parameter space (default: the distinct knots for the paper's
    /// derivation, the Greville abscissae for the others).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grid: Option<LatticeGrid>,
    /// Nodes along u for `grid = "uniform"` (≥ 2).
    pub nodes_u: usize,
    /// Nodes along v for `grid = "uniform"` (≥ 2; ignored for curves).
    pub nodes_v: usize,
    /// Springs between grid neighbours.
    pub structural: bool,
    /// Springs on both diagonals of each cell.
    pub shear: bool,
    /// Springs to the second neighbour along each grid line.
    pub bending: bool,
    /// Structural spring constant (≥ 0); `None` when the scene gives none (a derivation fits
    /// it; `simulate` and `export` of the scene's own lattice refuse, [`MsmSpec::missing`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_edge: Option<f64>,
    /// Shear spring constant (≥ 0); `None` when not given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_diag: Option<f64>,
    /// Bending spring constant (≥ 0); `None` when not given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_bend: Option<f64>,
    /// Mass of every node (> 0); `None` when not given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// Damping coefficient per node (≥ 0); `None` when not given: the D-NURBS's damping per
    /// unit mass, `γ/μ` times the node's mass ([`MsmSpec::node_damping`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Rest length = (1 − pre_strain) × initial length; in (−1, 1).
    pub pre_strain: f64,
    /// Fixed nodes: `"auto"` (docs/math.md §5 rule; on the Greville grid a node is fixed iff
    /// its control point is) or a list `[[a, b], …]` (curves `[[a], …]`).
    pub fixed: MsmFixed,
    /// The kinds of linear elements of the modal, excitation and reduction derivations
    /// (default: every kind the lattice has; each split into interior and boundary classes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub elements: Option<Vec<LinearKind>>,
}

/// Spring constant of a spring kind `[msm]` turns on without giving its constant, where a
/// lattice is built before its constants are fitted (the fit replaces it).
pub const PLACEHOLDER_K: f64 = 1.0;

/// Node mass of a lattice built before its mass is chosen (the derivation replaces it).
pub const PLACEHOLDER_MASS: f64 = 1.0;

impl MsmSpec {
    /// The constant of each spring kind the lattice has (`structural`, `shear`, `bending`),
    /// with its key: `(key, kind on, given value)`.
    pub fn spring_keys(&self) -> [(&'static str, bool, Option<f64>); 3] {
        [
            ("k_edge", self.structural, self.k_edge),
            ("k_diag", self.shear, self.k_diag),
            ("k_bend", self.bending, self.k_bend),
        ]
    }

    /// The keys of the scene's own lattice that `[msm]` leaves out (`msm.k_edge`, …,
    /// `msm.mass`): the spring constants of the kinds it turns on and the node mass. A lattice
    /// missing any of them is not a model (`simulate --model msm` and `export --format
    /// sofa|npz` of the scene refuse it; a derivation fits them).
    pub fn missing(&self) -> Vec<&'static str> {
        let mut out: Vec<&'static str> = self
            .spring_keys()
            .into_iter()
            .filter(|&(_, on, k)| on && k.is_none())
            .map(|(key, _, _)| key)
            .collect();
        if self.mass.is_none() {
            out.push("mass");
        }
        out
    }

    /// The node mass, or [`PLACEHOLDER_MASS`] when not given.
    pub fn mass_or_placeholder(&self) -> f64 {
        self.mass.unwrap_or(PLACEHOLDER_MASS)
    }

    /// The damping coefficient of a node of mass `m`: `msm.damping` when given, else the
    /// D-NURBS's damping per unit mass `γ/μ` times `m` (its damping matrix is `D = (γ/μ) M`,
    /// docs/math.md §3), so a lattice always carries the material's damping.
    pub fn node_damping(&self, material: &MaterialModel, m: f64) -> f64 {
        self.damping
            .unwrap_or_else(|| material.damping_per_mass() * m)
    }

    /// The grid a derivation uses: the scene's, else the method's own
    /// ([`Method::default_grid`]).
    pub fn grid_for(&self, method: Method) -> LatticeGrid {
        self.grid
            .unwrap_or_else(|| LatticeGrid::of(&method.default_grid()))
    }
}

impl Default for MsmSpec {
    fn default() -> Self {
        Self {
            grid: None,
            nodes_u: 5,
            nodes_v: 3,
            structural: true,
            shear: true,
            bending: false,
            k_edge: None,
            k_diag: None,
            k_bend: None,
            mass: None,
            damping: None,
            pre_strain: 0.0,
            fixed: MsmFixed::Auto,
            elements: None,
        }
    }
}

/// Parameter grid of the lattice nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LatticeGrid {
    /// The distinct knot values in the domain (the paper's).
    #[default]
    Knots,
    /// `nodes_u × nodes_v` uniformly spaced parameters.
    Uniform,
    /// The Greville abscissae (one node per control point).
    Greville,
}

impl LatticeGrid {
    /// The scene's name for a lattice's parameter grid.
    pub fn of(grid: &ParameterGrid) -> LatticeGrid {
        match grid {
            ParameterGrid::Knots => LatticeGrid::Knots,
            ParameterGrid::Uniform { .. } => LatticeGrid::Uniform,
            ParameterGrid::Greville => LatticeGrid::Greville,
        }
    }

    /// `"knots"`, `"uniform"` or `"greville"`.
    pub fn name(self) -> &'static str {
        match self {
            LatticeGrid::Knots => "knots",
            LatticeGrid::Uniform => "uniform",
            LatticeGrid::Greville => "greville",
        }
    }
}

/// Which lattice nodes are fixed.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum MsmFixed {
    /// A node is fixed when every control point with a non-zero basis value there is fixed.
    #[default]
    Auto,
    /// Explicit node indices `[a, b]` (`a` along u), or `[a]` for curves.
    Nodes(Vec<Vec<usize>>),
}

impl Serialize for MsmFixed {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            MsmFixed::Auto => s.serialize_str("auto"),
            MsmFixed::Nodes(n) => n.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for MsmFixed {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = MsmFixed;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("\"auto\" or a list of node indices [[a, b], …]")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<MsmFixed, E> {
                if v == "auto" {
                    Ok(MsmFixed::Auto)
                } else {
                    Err(E::custom(format!(
                        "unknown value `{v}`, expected \"auto\" or a list of node indices [[a, b], …]"
                    )))
                }
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<MsmFixed, A::Error> {
                let mut nodes = Vec::new();
                while let Some(n) = seq.next_element::<Vec<usize>>()? {
                    nodes.push(n);
                }
                Ok(MsmFixed::Nodes(nodes))
            }
        }
        d.deserialize_any(V)
    }
}

/// `[fit]`: derivation of the spring constants and the mass (docs/math.md §6).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FitSpec {
    /// Which derivation: `"modal"`, `"paper"`, `"excitation"` or `"reduction"`; absent, see
    /// [`crate::Scene::derivation`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub derivation: Option<Method>,
    /// Which dofs enter eq. (15).
    pub dofs: FitDofs,
    /// Constrain the spring constants to k ≥ 0.
    pub nonnegative: bool,
    /// Solver of the least-squares fit.
    pub method: FitMethod,
    /// How the node mass is chosen.
    pub mass: MassMethod,
    /// Candidate masses tried (0 = every distinct eigenvalue).
    pub max_candidates: usize,
    /// Whether a candidate that can no longer be selected stops early.
    pub mass_scan: MassScan,
}

impl FitSpec {
    /// The derivation a scene asks for: `fit.derivation`, else `springs` for a Kirchhoff–Love
    /// `material` (`shell`), else `modal`, or `paper` (with the reason) for a scene the linear
    /// derivations cannot take: weights as unknowns, or `[[constraints.linear]]` rows (the
    /// D-NURBS is then not three identical scalar systems, docs/math.md §8.2).
    pub fn derivation_for(
        &self,
        shell: bool,
        dnurbs: &DnurbsOptions,
        constraints: &ConstraintsSpec,
    ) -> (Method, Option<&'static str>) {
        if let Some(m) = self.derivation {
            (m, None)
        } else if shell {
            (Method::Springs, None)
        } else if dnurbs.weights_as_dofs {
            (
                Method::Paper,
                Some(
                    "the scene has weights as unknowns (dnurbs.weights_as_dofs), which the modal derivation cannot take: using the paper's (choose one with fit.derivation or --derivation)",
                ),
            )
        } else if !constraints.linear.is_empty() {
            (
                Method::Paper,
                Some(
                    "the scene has constraints.linear rows, which the modal derivation cannot take: using the paper's (choose one with fit.derivation or --derivation)",
                ),
            )
        } else {
            (Method::Modal, None)
        }
    }
}

/// Choice of the node mass (Section III).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MassMethod {
    /// Try the eigenvalues of M as candidate masses (the paper's).
    #[default]
    EigenvalueScan,
    /// Use `msm.mass`.
    Fixed,
}

/// `[output]`: what is written during runs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSpec {
    /// Write a VTK frame every n saved frames (≥ 1); unset: at most [`DEFAULT_MAX_FRAMES`]
    /// frames ([`OutputSpec::frame_every`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vtk_every: Option<usize>,
}

/// Most ParaView frames a run writes when `output.vtk_every` is not set: enough to play the
/// motion in a viewer, about 7 MB for the paper's lattice.
pub const DEFAULT_MAX_FRAMES: usize = 200;

impl OutputSpec {
    /// A ParaView frame every n of a run's `samples` recorded samples: `vtk_every` when set,
    /// otherwise the smallest n that writes at most [`DEFAULT_MAX_FRAMES`] frames.
    pub fn frame_every(&self, samples: usize) -> usize {
        self.vtk_every
            .unwrap_or_else(|| default_frame_every(samples))
    }
}

/// The smallest n ≥ 1 with `⌈samples / n⌉ ≤ DEFAULT_MAX_FRAMES`.
pub fn default_frame_every(samples: usize) -> usize {
    samples.div_ceil(DEFAULT_MAX_FRAMES).max(1)
}

/// Largest number of probes a scene may ask for (`simulation.probes`).
pub const MAX_PROBES: usize = 1000;

/// Largest number of control points, lattice nodes or array entries a scene may ask for
/// (10⁷); larger requests are refused before anything is allocated.
pub const MAX_ITEMS: usize = 10_000_000;

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The file it came from (used in messages).
    pub path: PathBuf,
    /// `[surface]` or `[curve]`.
    pub geometry: GeometrySpec,
    /// `[material]`: the tension plate (the default) or the Kirchhoff–Love shell.
    pub material: MaterialModel,
    /// `[loads]`.
    pub loads: LoadsSpec,
    /// `[constraints]`.
    pub constraints: ConstraintsSpec,
    /// `[dnurbs]`.
    pub dnurbs: DnurbsOptions,
    /// `[initial]`.
    pub initial: InitialSpec,
    /// `[simulation]`.
    pub simulation: SimulationSpec,
    /// `[msm]`.
    pub msm: MsmSpec,
    /// `[fit]`.
    pub fit: FitSpec,
    /// `[output]`.
    pub output: OutputSpec,
}

/// The file as deserialized, before validation.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    pub(crate) surface: Option<RawGeometry<RawSurface>>,
    pub(crate) curve: Option<RawGeometry<RawCurve>>,
    #[serde(default)]
    pub(crate) material: RawMaterial,
    #[serde(default)]
    pub(crate) loads: LoadsSpec,
    #[serde(default)]
    pub(crate) constraints: ConstraintsSpec,
    #[serde(default)]
    pub(crate) dnurbs: DnurbsOptions,
    #[serde(default)]
    pub(crate) initial: RawInitial,
    #[serde(default)]
    pub(crate) simulation: SimulationSpec,
    #[serde(default)]
    pub(crate) msm: MsmSpec,
    #[serde(default)]
    pub(crate) fit: FitSpec,
    #[serde(default)]
    pub(crate) output: OutputSpec,
}

/// `[surface]` or `[curve]` as written: the geometry inline, or `file = "…"` (with an optional
/// `index`) naming a geomdl JSON, IGES or OBJ file, its path relative to the scene file.
pub(crate) enum RawGeometry<T> {
    /// The keys of the table.
    Inline(T),
    /// `file` and `index`.
    File {
        /// As written in the scene.
        file: String,
        /// Which surface (or curve) of the file, 0-based (default 0).
        index: usize,
    },
}

/// `[surface]` with points as plain lists, so that their shapes are checked with key paths.
pub(crate) struct RawSurface {
    pub(crate) degree_u: usize,
    pub(crate) degree_v: usize,
    pub(crate) knots_u: Vec<f64>,
    pub(crate) knots_v: Vec<f64>,
    pub(crate) control_points: Vec<Vec<Vec<f64>>>,
    pub(crate) weights: Option<Vec<Vec<f64>>>,
}

pub(crate) struct RawCurve {
    pub(crate) degree: usize,
    pub(crate) knots: Vec<f64>,
    pub(crate) control_points: Vec<Vec<f64>>,
    pub(crate) weights: Option<Vec<f64>>,
}

/// Every key `[surface]` may hold (the inline ones are required unless `file` is given).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SurfaceTable {
    file: Option<String>,
    index: Option<usize>,
    degree_u: Option<usize>,
    degree_v: Option<usize>,
    knots_u: Option<Vec<f64>>,
    knots_v: Option<Vec<f64>>,
    control_points: Option<Vec<Vec<Vec<f64>>>>,
    weights: Option<Vec<Vec<f64>>>,
}

/// Every key `[curve]` may hold.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CurveTable {
    file: Option<String>,
    index: Option<usize>,
    degree: Option<usize>,
    knots: Option<Vec<f64>>,
    control_points: Option<Vec<Vec<f64>>>,
    weights: Option<Vec<f64>>,
}

/// The `file` form, refusing inline keys next to it (`given` lists those present).
fn file_form<T, E: de::Error>(
    section: &str,
    file: Option<String>,
    index: Option<usize>,
    given: &[(&str, bool)],
) -> Result<Option<RawGeometry<T>>, E> {
    let Some(file) = file else {
        if index.is_some() {
            return Err(E::custom(format!(
                "`index` selects a shape of `file`; [{section}] has no `file` key"
            )));
        }
        return Ok(None);
    };
    let inline: Vec<&str> = given.iter().filter(|g| g.1).map(|g| g.0).collect();
    if !inline.is_empty() {
        return Err(E::custom(format!(
            "[{section}] gives `file` and also {}: give the geometry either from a file or inline, not both",
            inline
                .iter()
                .map(|k| format!("`{k}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(Some(RawGeometry::File {
        file,
        index: index.unwrap_or(0),
    }))
}

impl<'de> Deserialize<'de> for RawGeometry<RawSurface> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let t = SurfaceTable::deserialize(d)?;
        let given = [
            ("degree_u", t.degree_u.is_some()),
            ("degree_v", t.degree_v.is_some()),
            ("knots_u", t.knots_u.is_some()),
            ("knots_v", t.knots_v.is_some()),
            ("control_points", t.control_points.is_some()),
            ("weights", t.weights.is_some()),
        ];
        if let Some(g) = file_form("surface", t.file, t.index, &given)? {
            return Ok(g);
        }
        Ok(RawGeometry::Inline(RawSurface {
            degree_u: t
                .degree_u
                .ok_or_else(|| de::Error::missing_field("degree_u"))?,
            degree_v: t
                .degree_v
                .ok_or_else(|| de::Error::missing_field("degree_v"))?,
            knots_u: t
                .knots_u
                .ok_or_else(|| de::Error::missing_field("knots_u"))?,
            knots_v: t
                .knots_v
                .ok_or_else(|| de::Error::missing_field("knots_v"))?,
            control_points: t
                .control_points
                .ok_or_else(|| de::Error::missing_field("control_points"))?,
            weights: t.weights,
        }))
    }
}

impl<'de> Deserialize<'de> for RawGeometry<RawCurve> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let t = CurveTable::deserialize(d)?;
        let given = [
            ("degree", t.degree.is_some()),
            ("knots", t.knots.is_some()),
            ("control_points", t.control_points.is_some()),
            ("weights", t.weights.is_some()),
        ];
        if let Some(g) = file_form("curve", t.file, t.index, &given)? {
            return Ok(g);
        }
        Ok(RawGeometry::Inline(RawCurve {
            degree: t.degree.ok_or_else(|| de::Error::missing_field("degree"))?,
            knots: t.knots.ok_or_else(|| de::Error::missing_field("knots"))?,
            control_points: t
                .control_points
                .ok_or_else(|| de::Error::missing_field("control_points"))?,
            weights: t.weights,
        }))
    }
}

#[derive(Deserialize, Serialize, Default)]
#[serde(default, deny_unknown_fields)]
pub(crate) struct RawInitial {
    pub(crate) velocity: [f64; 3],
    pub(crate) weight_velocity: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) velocities: Option<toml::Value>,
    pub(crate) displacement: [f64; 3],
}

#[cfg(test)]
mod tests;
