//! # nurbspring-dnurbs
//!
//! Dynamic NURBS (D-NURBS, Terzopoulos & Qin 1994; the paper's Section II): a NURBS surface or
//! curve with mass, damping and elastic energy, discretized on its control points
//! (paper eqs. (2)–(4), (8); docs/math.md §3–4).
//!
//! - [`Material`] (μ, γ, α11, α22, β11, β12, β22) and [`Loads`] (gravity `μ g`, constant
//!   distributed force, point loads `J(u0, v0)ᵀ F`);
//! - [`assemble`] / [`assemble_scalar`]: `M`, `D`, `K`, `f_p` by Gauss quadrature over knot
//!   spans, pattern built once, element blocks filled in parallel; `M = S ⊗ I_3` for constant
//!   weights, full `4N × 4N` matrices with weights as unknowns;
//! - [`Constraints`]: fixed control points (by index or outer rings), fixed weights, linear
//!   constraints `A p = b` (substitution `p = G q + g`);
//! - [`DnurbsModel`]: the constrained model as a `nurbspring_sim::DynamicModel` (every
//!   integrator of `nurbspring-sim` applies), steady state (eq. (8)) and modes;
//! - [`RationalStepper`]: weights as unknowns, matrices re-evaluated every step.
//!
//! The paper's experiment (Section IV, docs/math.md §7): a bicubic 7 × 5 patch, two outer rings of
//! control points fixed, μ = 25, β11 = β22 = 0.01, the free points pushed down at 0.2 m/s.
//!
//! ```
//! use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material};
//! use nurbspring_geom::{KnotVector, NurbsSurface};
//! use nurbspring_sim::{IntegratorKind, RunOptions, Sample, simulate};
//!
//! let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap();
//! let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap();
//! let (px, py) = ([0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.], [0., 0.83, 2.5, 4.16, 5.]);
//! let pts: Vec<[f64; 3]> = px.iter().flat_map(|&x| py.iter().map(move |&y| [x, y, 2.0])).collect();
//! let surface = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 35]).unwrap();
//!
//! let material = Material { mu: 25.0, beta11: 0.01, beta22: 0.01, ..Material::default() };
//! let constraints = Constraints { fixed_rings: 2, ..Constraints::default() };
//! let model = DnurbsModel::new(Geometry::Surface(surface), material, Loads::default(),
//!     &constraints, DnurbsOptions::default()).unwrap();
//! assert_eq!(model.fixed_points().len(), 32);
//! // Σ_ij M_ij = 3 μ · (parameter area) = 75 (partition of unity).
//! assert!((model.matrices().mass.sum() - 75.0).abs() < 1e-11);
//!
//! // Terzopoulos–Qin with Δt = 0.08 s over 4 s from ṗ = (0, 0, −0.2) on the free points.
//! let initial = model.initial_state(&[[0.0, 0.0, -0.2]], 0.0);
//! let opts = RunOptions::new(0.08, 4.0, IntegratorKind::TerzopoulosQin);
//! let mut lowest = f64::INFINITY;
//! let mut observer = |s: &Sample<'_>| {
//!     let p = model.full_coordinates(s.q);
//!     lowest = lowest.min(model.point(0.5, 0.5, &p).unwrap()[2]);
//! };
//! simulate(&model, initial, &opts, &mut observer).unwrap();
//! assert!(lowest < 2.0 - 1e-3 && lowest > 1.5); // the centre dips, then swings back
//! ```

mod assembly;
mod constraints;
mod edge;
mod elasticity;
mod equilibrium;
mod error;
mod geometry;
mod layout;
mod loads;
mod material;
mod model;
mod options;
mod rational;
mod run;
mod shell;

pub use assembly::{Assembler, Matrices, ScalarMatrices, assemble, assemble_scalar};
pub use constraints::{Constraints, EdgeCondition, EdgeConstraint, LinearConstraint, edge_rows};
pub use edge::{Edge, EdgeLoad};
pub use elasticity::{ElasticEnergy, TensionPlate};
pub use equilibrium::{Cancel, EquilibriumPath, LoadLevel, PathSettings};
pub use error::DnurbsError;
pub use geometry::{Geometry, outer_ring_points};
pub use loads::{Loads, PointLoad};
pub use material::{Material, MaterialModel};
pub use model::{
    ANDERSON_DEPTH, DENSE_MODES_LIMIT, DnurbsModel, Modes, SteadySettings, SteadyState,
};
pub use options::{
    AUTO_SPAN, DnurbsOptions, Integration, MAX_QUADRATURE_POINTS, QUADRATURE_TOLERANCE,
    QUADRATURE_WARNING, QuadratureChoice, RestShape,
};
pub use rational::{DEFAULT_MIN_WEIGHT_RATIO, RationalStepper};
pub use run::{integrator_problem, names as integrator_names};
pub use shell::{ShellEnergy, ShellMaterial, obstacle};
