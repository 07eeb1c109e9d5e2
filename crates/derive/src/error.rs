//! Errors of the derivation.

use nurbspring_dnurbs::DnurbsError;
use nurbspring_geom::GeomError;
use nurbspring_linalg::LinalgError;
use nurbspring_msm::MsmError;
use nurbspring_sim::SimError;

/// Everything that can stop a derivation; messages carry the offending values.
#[derive(Debug, thiserror::Error)]
pub enum DeriveError {
    /// A lattice node whose parameters lie outside the surface's domain.
    #[error(
        "lattice node {node} has parameters ({u}, {v}) outside the surface domain [{u0}, {u1}] × [{v0}, {v1}]"
    )]
    NodeOutsideDomain {
        /// Node index.
        node: usize,
        /// Its u.
        u: f64,
        /// Its v.
        v: f64,
        /// Domain start in u.
        u0: f64,
        /// Domain end in u.
        u1: f64,
        /// Domain start in v.
        v0: f64,
        /// Domain end in v.
        v1: f64,
    },
    /// The lattice carries no parameters (it was not sampled from a surface).
    #[error(
        "the lattice has no (u, v) parameters per node: Ω needs a lattice sampled from the surface"
    )]
    LatticeWithoutParameters,
    /// Fewer springs than spring classes to fit, or no class at all.
    #[error("cannot fit {classes} spring classes with {springs} springs")]
    TooFewSprings {
        /// Number of classes.
        classes: usize,
        /// Number of springs.
        springs: usize,
    },
    /// The normal equations of the fit are singular.
    #[error("the stiffness fit is singular: {detail}")]
    SingularFit {
        /// Which classes cannot be told apart.
        detail: String,
    },
    /// Mismatched sizes between the D-NURBS and the lattice.
    #[error("size mismatch in {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// What was compared.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Found size.
        found: usize,
    },
    /// An option with an invalid value.
    #[error("invalid {name}: {value}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Its value as text.
        value: String,
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
    /// True when the error comes from the input (scene, options) rather than from the run.
    pub fn is_input_error(&self) -> bool {
        match self {
            DeriveError::NodeOutsideDomain { .. }
            | DeriveError::LatticeWithoutParameters
            | DeriveError::TooFewSprings { .. }
            | DeriveError::DimensionMismatch { .. }
            | DeriveError::InvalidOption { .. }
            | DeriveError::Geom(_) => true,
            DeriveError::Dnurbs(e) => !matches!(
                e,
                DnurbsError::Singular { .. } | DnurbsError::Sim(_) | DnurbsError::Linalg(_)
            ),
            DeriveError::Msm(e) => !matches!(e, MsmError::Sim(_) | MsmError::Linalg(_)),
            DeriveError::Sim(e) => matches!(
                e,
                SimError::InvalidTimeStep { .. }
                    | SimError::InvalidDuration { .. }
                    | SimError::Unstable { .. }
            ),
            _ => false,
        }
    }
}
