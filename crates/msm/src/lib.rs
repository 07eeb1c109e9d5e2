//! # nurbspring-msm
//!
//! Mass-spring models (MSM) for nurbspring: lattices sampled from a NURBS surface or given as
//! node and spring lists, the spring forces and energy of paper eqs. (5)–(7), the tangent
//! stiffness and the unit-stiffness matrices `G_c` of eqs. (9)–(10) (docs/math.md §5), and the model as
//! a [`nurbspring_sim::DynamicModel`], so every integrator of `nurbspring-sim` runs it.
//!
//! ```
//! use nurbspring_geom::{KnotVector, NurbsSurface};
//! use nurbspring_msm::{Class, Constants, LatticeOptions, MsmModel, SpringKind, SpringLattice};
//! use nurbspring_sim::{DynamicModel, IntegratorKind, RunOptions, Sample, simulate};
//!
//! // The paper's bicubic patch (Section IV, docs/math.md §7), flat at z = 2.
//! let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap();
//! let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap();
//! let (px, py) = ([0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.], [0., 0.83, 2.5, 4.16, 5.]);
//! let pts: Vec<[f64; 3]> = px.iter().flat_map(|&x| py.iter().map(move |&y| [x, y, 2.0])).collect();
//! let surface = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 35]).unwrap();
//! // The two outer rings of control points are fixed: all but (2, 2), (3, 2), (4, 2).
//! let fixed: Vec<usize> = (0..35).filter(|&k| !matches!(k, 12 | 17 | 22)).collect();
//!
//! // 5 × 3 nodes at the distinct knots, structural and shear springs (paper Figure 1).
//! let springs = Constants::from_pairs([
//!     (Class::Spring(SpringKind::Structural), 2.7225),
//!     (Class::Spring(SpringKind::Shear), 0.8661),
//! ]);
//! let options = LatticeOptions { constants: springs, mass: 0.005, ..Default::default() };
//! let lattice = SpringLattice::from_surface(&surface, &options, &fixed).unwrap();
//! assert_eq!((lattice.n_nodes(), lattice.count(Class::Spring(SpringKind::Structural))), (15, 22));
//! // The docs/math.md §5 rule leaves the three interior nodes free.
//! assert_eq!(lattice.fixed.iter().filter(|f| !**f).count(), 3);
//!
//! // K_S is 45 × 45 and linear in the spring constants: K_S = k_edge G_edge + k_diag G_diag.
//! let x0 = lattice.flat_positions();
//! let k_s = lattice.tangent_stiffness(&x0);
//! assert_eq!(k_s.nrows(), 45);
//! // A flat lattice at rest has no out-of-plane stiffness (docs/math.md §5).
//! assert!((0..15).all(|a| (0..45).all(|j| k_s.get(3 * a + 2, j) == 0.0)));
//!
//! // Run it with velocity Verlet at a tenth of the explicit limit 2/ω_max: energy is kept.
//! let model = MsmModel::new(lattice).unwrap();
//! let limit = model.stability().unwrap();
//! let mut v0 = vec![[0.0; 3]; 15];
//! v0[7] = [0.01, 0.0, 0.0];
//! let opts = RunOptions::new(0.1 * limit.dt_critical, 1.0, IntegratorKind::VelocityVerlet);
//! let mut energy = Vec::new();
//! let mut observer = |s: &Sample<'_>| energy.push(s.kinetic + s.potential);
//! simulate(&model, model.initial_state(&v0), &opts, &mut observer).unwrap();
//! let e0 = energy[0];
//! assert!(energy.iter().all(|e| (e - e0).abs() < 0.01 * e0));
//! # assert_eq!(model.n_dofs(), 9);
//! ```
//!
//! Layout: [`SpringLattice`] (builders, forces, stiffness on all `3N` coordinates),
//! [`MsmFile`] (`msm.json`), [`Constants`] by [`Class`], [`MsmModel`] (the free coordinates, for `nurbspring-sim`).
//! The force kernel sums per node over a node-to-spring incidence (CSR), in parallel and
//! without allocation; on grid lattices the symplectic-Euler step is one fused pass over the
//! rows with the topology implicit in the grid; the tangent stiffness is filled per node into a block pattern computed
//! once.

mod constants;
mod element;
mod error;
mod file;
mod grid;
mod hinge;
mod lattice;
mod model;
mod spring;
mod stiffness;
mod topology;

pub use constants::{Class, Constants};
pub use element::{LinearElement, LinearKind, Region, dual_spacing};
pub use error::MsmError;
pub use file::{ElementRecord, FileSimulation, HingeRecord, MsmFile, NodeRecord, SpringRecord};
pub use hinge::{Hinge, HingeKind};
pub use lattice::{FixedNodes, LatticeOptions, ParameterGrid, SpringLattice, grid_triangles};
pub use model::MsmModel;
pub use spring::{Spring, SpringKind};

/// The largest lattice accepted (nodes); larger requests are refused before allocating.
pub const MAX_NODES: usize = 10_000_000;
