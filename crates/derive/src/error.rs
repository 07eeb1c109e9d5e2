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
    /// An input the derivation refuses: `input` says which (the scene layer names its key),
    /// `value` what it was.
    #[error("{input} = {value}: {reason}")]
    InvalidInput {
        /// The input at fault.
        input: Input,
        /// Its value as text.
        value: String,
        /// Why it is refused.
        reason: String,
    },
    /// A derivation that works on the scalar system (the linear derivations, the exact modal
    /// reference) given a model that is not three identical scalar systems.
    #[error("the {method} derivation {obstacle}")]
    NotScalar {
        /// The derivation's name.
        method: &'static str,
        /// What makes the model other than scalar.
        obstacle: ScalarObstacle,
    },
    /// The reduction onto more free nodes than free control points.
    #[error(
        "{free_nodes} free nodes: the reduction needs at most as many free nodes as free control points ({control_points}); use the Greville grid"
    )]
    TooManyNodes {
        /// Free lattice nodes.
        free_nodes: usize,
        /// Free control points.
        control_points: usize,
    },
    /// The excitation derivation on a scene that excites no mode.
    #[error(
        "the excitation derivation weights the modes the initial velocity, initial displacement and loads excite, and this model excites none"
    )]
    NoExcitation,
    /// Every mass candidate of the scan failed to run.
    #[error(
        "every mass candidate failed to run ({tried} tried; the first: {first}); give a fixed node mass"
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

/// The inputs of a derivation an error can blame ([`DeriveError::InvalidInput`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// The derivation chosen: it cannot take this model.
    Derivation,
    /// The lattice's parameter grid.
    Grid,
    /// The lattice's element classes.
    Elements,
    /// How the node mass is chosen.
    Mass,
    /// The constraints.
    Constraints,
    /// The material.
    Material,
    /// The modal fit's iteration.
    ModalFit,
    /// Loads on the surface's edges.
    EdgeLoads,
}

impl std::fmt::Display for Input {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Input::Derivation => "derivation",
            Input::Grid => "lattice grid",
            Input::Elements => "lattice elements",
            Input::Mass => "node mass",
            Input::Constraints => "constraints",
            Input::Material => "material",
            Input::ModalFit => "modal fit",
            Input::EdgeLoads => "edge loads",
        })
    }
}

/// What makes a model other than three identical scalar systems ([`DeriveError::NotScalar`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScalarObstacle {
    /// The weights are unknowns.
    WeightsAsDofs,
    /// Linear constraints couple the components.
    LinearConstraints,
    /// Every control point is fixed.
    NoFreeControlPoint,
}

impl std::fmt::Display for ScalarObstacle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ScalarObstacle::WeightsAsDofs => "needs constant weights (weights are unknowns here)",
            ScalarObstacle::LinearConstraints => "needs a model without linear constraints",
            ScalarObstacle::NoFreeControlPoint => "needs at least one free control point",
        })
    }
}

impl DeriveError {
    /// Input: the lattice, the options, a fit the input leaves singular, the geometry. Run:
    /// failed candidates, linear algebra, size mismatches. Wrapped errors keep their kind.
    pub fn kind(&self) -> ErrorKind {
        match self {
            DeriveError::LatticeWithoutParameters
            | DeriveError::TooFewElements { .. }
            | DeriveError::SingularFit { .. }
            | DeriveError::InvalidInput { .. }
            | DeriveError::NotScalar { .. }
            | DeriveError::TooManyNodes { .. }
            | DeriveError::NoExcitation
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
