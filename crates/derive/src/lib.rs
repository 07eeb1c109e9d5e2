//! # nurbspring-derive
//!
//! Derives a mass-spring model (MSM) that mimics a Dynamic NURBS (D-NURBS) surface, following
//! the paper's Section III, and reproduces its Section IV:
//!
//! - [`Omega`]: Ω, the stacked Jacobians of the lattice nodes (paper eq. (14)), with
//!   `x(0) = Ω p(0)` (eq. 11) and `ẋ(0) = Ω ṗ(0)` (eq. 18);
//! - [`StiffnessFit`]: `min_k ‖Ωᵀ K_S(k) Ω − K_D‖_F²` (eq. 15), in closed form through
//!   Frobenius inner products of sparse matrices, with `k ≥ 0` by NNLS, and by the
//!   trust-region method the paper used;
//! - [`mass_eigenvalues`]: the candidate node masses (the non-null eigenvalues of M);
//! - [`derive`]: runs the derivation a [`Config`] names ([`Method`]), the one place that
//!   chooses between them;
//! - [`derive_msm`]: the paper's pipeline of named steps ([`fit_step`] → [`reference_run`] →
//!   [`mass_step`] → [`evaluate`] → [`spectra`]) over a [`Setup`] built once from a
//!   [`Config`];
//! - [`record`]: one runner for both models, recording probe points and energies;
//! - [`paper::reproduce`]: every number of Section IV beside what nurbspring obtains under each
//!   reading of the paper, with a verdict per line.
//!
//! ```
//! use nurbspring_derive::{FitDofs, StiffnessFit};
//! use nurbspring_linalg::SparseMatrix;
//! use nurbspring_msm::{Class, SpringKind};
//! // Two classes with known constants: the fit recovers them exactly.
//! let g1 = SparseMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 1.0)]).unwrap();
//! let g2 = SparseMatrix::from_triplets(2, 2, &[(0, 1, 1.0), (1, 0, 1.0)]).unwrap();
//! let omega = SparseMatrix::identity(2);
//! let k_d = SparseMatrix::linear_combination(3.0, &g1, 0.5, &g2).unwrap();
//! let classes = [(Class::Spring(SpringKind::Structural), g1), (Class::Spring(SpringKind::Shear), g2)];
//! let fit = StiffnessFit::new(&k_d, &omega, &classes, 2, None).unwrap();
//! let k = fit.solve(false).unwrap();
//! assert!((k[0] - 3.0).abs() < 1e-14 && (k[1] - 0.5).abs() < 1e-14);
//! # let _ = FitDofs::All;
//! ```

pub mod beyond;
mod dispatch;
mod error;
mod evaluation;
mod excitation;
mod fit;
mod fnnls;
mod linear;
mod mass;
mod method;
mod modal;
mod modal_solution;
mod nodes;
mod omega;
mod outcome;
pub mod paper;
mod pipeline;
mod reference;
mod runner;
mod scalar;
mod setup;
mod shell_reduction;
mod springs;
mod springs_check;
#[cfg(test)]
mod test_scenes;
mod validation;

pub use dispatch::derive;
pub use error::{DeriveError, Input, ScalarObstacle};
pub use evaluation::{
    DnurbsModes, LINEAR_RANGE, MATCH_WINDOW, PERIODS, REGIME_FREQUENCY, REGIME_MODES, TABLE_MODES,
    WARN_FREQUENCY, WARN_MASS_FACTOR, WARN_MODE_FREQUENCY, WARN_RELATIVE_RMS, horizon,
};
pub use fit::{FitDofs, FitResult, StiffnessFit, TrustRegionOutcome};
pub use mass::{distinct_non_null, mass_eigenvalues};
pub use method::{ElementClasses, LinearMethod, Method, SpringGroups};
pub use modal::{
    Band, CONSTANT_REGULARIZATION, ElementPrior, FITTED_MODES, FREQUENCY_WEIGHT, FitGroup,
    GroupFit, MASS_FLOOR, MASS_REGULARIZATION, MIN_HALF_WAVES, ModalFitReport, ModalSolution,
    RINGS, SampledMode, TOTAL_MASS_WEIGHT, element_priors, lowest_frequency, modal_fit,
    resolved_modes,
};
pub use modal_solution::{DENSE_MODES, ModalBasis, TRUNCATED_MODES};
pub use omega::{NodeState, Omega};
pub use outcome::{
    Derivation, DerivedModel, ExcitationReport, FitDetail, FitReport, FrequencyRow, MassCandidate,
    MassReport, NodeReduction, ParameterSet, ProbeError, PrunedRun, ReductionCoordinates,
    ReductionReport, Regime, Spectrum, TrustRegionReport, Validation,
};
pub use pipeline::{
    Judge, MAX_SPECTRUM_DOFS, SCAN_BATCH, SelectedReading, derive_msm, evaluate, fit_step,
    mass_step, msm_spectrum, reference_run, spectra,
};
pub use reference::ReferenceKind;
pub use runner::{Recording, Watched, record, record_noted};
pub use scalar::{EnergyOrigin, ScalarSystem};
pub use setup::{
    Config, FitMethod, FitOptions, Fits, InitialConditions, MassChoice, MassScan, Setup,
    TimeSettings,
};
pub use shell_reduction::{ShellReduction, reduce_shell};
pub use springs::{
    BAND_PULL, BAND_SPRING_MODES, CALIBRATION_ITERATIONS, ClassConstant, EXCITATION_CANDIDATES,
    ExcitedMode, GroupScale, RIGID_FREQUENCY, RIGID_MODES, SPRING_CLASSES, SPRING_MODES,
    SPRING_PULL, STEP_HALVINGS, SpringFrequency, SpringsConfig, SpringsDerivation,
    TABLE_SPRING_MODES, derive_springs, rule_lattice,
};
pub use springs_check::{
    BELOW_LIMIT, DynamicRun, LARGE_MOTION, LARGE_MOTION_PERIODS, LARGE_MOTION_RHO_INFINITY,
    LOAD_LEVELS, LargeMotion, LoadLevelError, NodeMap, SMALL_MOTION_PERIODS, STEPS_PER_PERIOD,
    SmallMotion, StaticPath, lowest_modes, static_path,
};
pub use validation::{
    Comparison, ModalTruncation, REPEATED_FREQUENCY, Trajectory, compare, compare_points,
    dominant_period, mac, match_modes,
};
