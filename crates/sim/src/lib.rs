//! The dynamics contract of nurbspring and every time integrator, written once.
//!
//! A model implements [`DynamicModel`]: `M q̈ + D q̇ + f_int(q) = f_ext(t)` on the free dofs,
//! with `f_int` carrying the sign of a stiffness (`f_int(q) = K (q − q_rest)` for a linear
//! model) and `K_T = ∂f_int/∂q`. [`DofMap`] removes fixed dofs (free first). [`simulate`] runs
//! any [`IntegratorKind`], checks the explicit stability limit `Δt < 2/ω_max`, detects divergence,
//! reports energies to an [`Observer`] and honours a cancel flag.
//!
//! ```
//! use nurbspring_linalg::SparseMatrix;
//! use nurbspring_sim::{simulate, IntegratorKind, LinearModel, RunOptions, Sample, State, SystemMatrix};
//! // One mass m = 1 on a spring k = 4: ω = 2, q(t) = cos 2t.
//! let model = LinearModel::new(SystemMatrix::Diagonal(vec![1.0]), SparseMatrix::from_diagonal(&[4.0]));
//! let opts = RunOptions::new(1e-3, 1.0, IntegratorKind::Newmark);
//! let mut max_energy_error = 0.0_f64;
//! let mut observer = |s: &Sample<'_>| max_energy_error = max_energy_error.max((s.kinetic + s.potential - 2.0).abs());
//! let summary = simulate(&model, State::new(vec![1.0], vec![0.0]), &opts, &mut observer).unwrap();
//! assert_eq!(summary.steps, 1000);
//! assert!(max_energy_error < 1e-12); // Newmark conserves the energy ½kq² + ½mv² = 2
//! ```
#![warn(missing_docs)]

mod dofmap;
mod error;
pub mod integrators;
pub mod model;
mod run;

pub use dofmap::{DofMap, DofSlot, PointDofs};
pub use error::{ErrorKind, SimError};
pub use integrators::{NewtonSettings, Stepper, make_stepper, make_stepper_with_options};
pub use model::{ConfigurationDamping, DynamicModel, FusedStep, LinearModel, SystemMatrix};
pub use nurbspring_linalg::{LinalgError, SparseMatrix};
pub use run::{
    ENERGY_GAIN_LIMIT, EnergyWatch, IMPLICIT_FALLBACK, IntegratorKind, MAX_MAGNITUDE, MAX_STEPS,
    MAX_SUBSTEPS, NullObserver, Observer, RunOptions, RunSummary, SUBSTEP_MARGIN, Sample, Schedule,
    StabilityLimit, State, check_time, explicit_substeps, representable, simulate, stability_limit,
    step_count, uniform_stability_limit,
};
