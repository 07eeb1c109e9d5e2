//! # nurbspring-scene
//!
//! The upper floor of nurbspring: both translations between what users write and read and the
//! models below.
//!
//! - **Scene files** ([`Scene`]): the TOML schema ([`spec`]), its validation (file shape,
//!   sizes, finiteness; every value rule comes from the model type that owns it, and every
//!   problem is named by its key path), and scene → models ([`Scene::build_dnurbs`],
//!   [`Scene::lattice_options`], [`Scene::derivation_config`]).
//! - **`msm.json`** ([`msm_file`]): read into a runnable MSM, written from a derivation, one
//!   schema ([`nurbspring_msm::MsmFile`]).
//! - **Results → files**: ParaView and OBJ frames of both models ([`export`]), the derivation
//!   reports `report.json` (typed, by serde), `report.md` and plots ([`report`]), simulation
//!   outputs ([`run`]).
//!
//! ```
//! use nurbspring_scene::Scene;
//! let text = r#"
//! [curve]
//! degree = 2
//! knots = [0, 0, 0, 1, 1, 1]
//! control_points = [[0, 0, 0], [1, 1, 0], [2, 0, 0]]
//!
//! [material]
//! mu = 2.0
//! alpha11 = 1.0
//!
//! [constraints]
//! fixed_rings = 1
//! "#;
//! let scene = Scene::from_str(text, "string.toml").unwrap();
//! let model = scene.build_dnurbs().unwrap();
//! assert_eq!(model.fixed_points(), &[0, 2]);
//! ```

mod build;
mod derivation;
mod error;
pub mod export;
pub mod geometry_file;
pub mod keys;
pub mod markdown;
pub mod msm_export;
pub mod msm_file;
pub mod paper;
mod parse;
pub mod report;
pub mod resources;
pub mod run;
pub mod runtime;
mod scene;
mod scene_error;
pub mod spec;
pub mod springs_report;
pub mod summary;
mod text_file;
mod validate;

pub use build::{MsmOverrides, spring_constants};
pub use derivation::{DERIVATION_KEY, DerivationChoice, PreparedDerivation};
pub use error::Error;
pub use scene::{MAX_FILE_BYTES, PAPER_SCENE};
pub use scene_error::{Problem, SceneError, SceneErrorKind};
pub use spec::*;

// The model types the command line and the bindings name: they reach the crates below only
// through this one.
pub use nurbspring_derive::paper::PaperReport;
pub use nurbspring_derive::{Derivation, Method, Trajectory};
pub use nurbspring_dnurbs::{Geometry, integrator_names};
pub use nurbspring_exchange::Shape;
pub use nurbspring_geom::{CurveDerivatives, GeomError, SurfaceDerivatives};
pub use nurbspring_linalg::SparseMatrix;
pub use nurbspring_msm::{Class, Constants, SpringKind};
pub use nurbspring_sim::{ErrorKind, IntegratorKind, RunSummary, Schedule};
