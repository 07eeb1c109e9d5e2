//! # nurbspring-derive
//!
//! Derives a mass-spring model (MSM) that mimics a Dynamic NURBS (D-NURBS) surface, following
//! the paper's Section III, and reproduces its Section IV:
//!
//! - [`omega_matrix`]: Ω, the stacked Jacobians of the lattice nodes (eq. 14), with
//!   `x(0) = Ω p(0)` (eq. 11) and `ẋ(0) = Ω ṗ(0)` (eq. 18);
//! - [`StiffnessFit`]: `min_k ‖Ωᵀ K_S(k) Ω − K_D‖_F²` (eq. 15), in closed form through
//!   Frobenius inner products of sparse matrices, with `k ≥ 0` as an option, and by the
//!   trust-region method the paper used;
//! - [`mass_eigenvalues`]: the candidate node masses (the non-null eigenvalues of M);
//! - [`derive_msm`]: the pipeline, with the candidate loop and the side-by-side validation of
//!   both models (Figure 3);
//! - [`paper::reproduce`]: every number of Section IV beside what nurbspring obtains under each
//!   reading of the paper, with a verdict per line.
//!
//! ```
//! use nurbspring_derive::{FitDofs, StiffnessFit};
//! use nurbspring_linalg::SparseMatrix;
//! use nurbspring_msm::SpringKind;
//! // Two classes with known constants: the fit recovers them exactly.
//! let g1 = SparseMatrix::from_triplets(2, 2, &[(0, 0, 1.0), (1, 1, 1.0)]).unwrap();
//! let g2 = SparseMatrix::from_triplets(2, 2, &[(0, 1, 1.0), (1, 0, 1.0)]).unwrap();
//! let omega = SparseMatrix::identity(2);
//! let k_d = SparseMatrix::linear_combination(3.0, &g1, 0.5, &g2).unwrap();
//! let fit = StiffnessFit::new(&k_d, &omega, &[(SpringKind::Structural, g1), (SpringKind::Shear, g2)], 2, None).unwrap();
//! let k = fit.solve(false).unwrap();
//! assert!((k[0] - 3.0).abs() < 1e-14 && (k[1] - 0.5).abs() < 1e-14);
//! # let _ = FitDofs::All;
//! ```

mod error;
mod experiment;
mod fit;
mod mass;
mod omega;
pub mod paper;
mod validation;

pub use error::DeriveError;
pub use experiment::{
    Derivation, ExperimentConfig, FitMethod, FitOptions, FitReport, FitResult, MassCandidate,
    MassChoice, MassReport, ParameterSet, Setup, Spectrum, TrustRegionReport, ValidationReport,
    derive_msm,
};
pub use fit::{FitDofs, StiffnessFit, TrustRegionOutcome};
pub use mass::{distinct_non_null, mass_eigenvalues};
pub use omega::omega_matrix;
pub use validation::{Comparison, Trajectory, compare, dominant_period};
