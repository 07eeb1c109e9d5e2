//! Errors of the derivation.

use nurbspring_dnurbs::DnurbsError;
use nurbspring_geom::GeomError;
use nurbspring_linalg::LinalgError;
use nurbspring_msm::MsmError;
use nurbspring_sim::{ErrorKind, SimError};

/// Everything that can stop a derivation; messages carry the offending values.
#[derive(Debug, thiserror::Error)]
pub enum DeriveError {
    /// The lattice carries no parameters (it was not sampled from a surface).
    #[error(
        "the lattice has no (u, v) parameters per node: Ω needs a lattice sampled from the surface"
    )]
    LatticeWithoutParameters,
    /// Fewer elements than classes to fit, or no class at all.
    #[error("cannot fit {classes} element classes with {elements} elements")]
    TooFewElements {
        /// Number of classes.
        classes: usize,
        /// Number of elements.
        elements: usize,
    },
    /// The normal equations of the fit are singular.
    #[error("the stiffness fit is singular: {detail}")]
    SingularFit {
        /// Which classes cannot be told apart.
        detail: String,
    },
    /// Mismatched sizes between the D-NURBS and the lattice (a caller's bug).
    #[error("size mismatch in {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// What was compared.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Found size.
        found: usize,
    },
    /// A derivation option with an invalid value; `name` is the option.
    #[error("{name} = {value}: {reason}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Its value as text.
        value: String,
        /// Why it is refused.
        reason: String,
    },
    /// Every mass candidate of the scan failed to run.
    #[error(
        "every mass candidate failed to run ({tried} tried; the first: {first}); give a mass with fit.mass = \"fixed\" and msm.mass"
    )]
    NoMassCandidate {
        /// Candidates tried.
        tried: usize,
        /// Why the first one stopped.
        first: String,
    },
    /// The run was cancelled (Ctrl-C).
    #[error("cancelled")]
    Cancelled,
    /// Geometry error.
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// Linear algebra error.
    #[error(transparent)]
    Linalg(#[from] LinalgError),
    /// Simulation error.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// D-NURBS model error.
    #[error(transparent)]
    Dnurbs(#[from] DnurbsError),
    /// Mass-spring model error.
    #[error(transparent)]
    Msm(#[from] MsmError),
}

impl DeriveError {
    /// Input: the lattice, the options, a fit the input leaves singular, the geometry. Run:
    /// failed candidates, linear algebra, size mismatches. Wrapped errors keep their kind.
    pub fn kind(&self) -> ErrorKind {
        match self {
            DeriveError::LatticeWithoutParameters
            | DeriveError::TooFewElements { .. }
            | DeriveError::SingularFit { .. }
            | DeriveError::InvalidOption { .. }
            | DeriveError::Geom(_) => ErrorKind::Input,
            DeriveError::DimensionMismatch { .. }
            | DeriveError::NoMassCandidate { .. }
            | DeriveError::Linalg(_) => ErrorKind::Run,
            DeriveError::Cancelled => ErrorKind::Cancelled,
            DeriveError::Sim(e) => e.kind(),
            DeriveError::Dnurbs(e) => e.kind(),
            DeriveError::Msm(e) => e.kind(),
        }
    }
}
