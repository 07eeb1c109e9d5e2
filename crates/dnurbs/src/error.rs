//! Errors of the D-NURBS crate. Every message carries the offending values.

use nurbspring_geom::GeomError;
use nurbspring_linalg::LinalgError;
use nurbspring_sim::{ErrorKind, SimError};

/// Everything that can go wrong when building or running a D-NURBS model.
#[derive(Debug, thiserror::Error)]
pub enum DnurbsError {
    /// A material coefficient that breaks a rule of [`crate::Material::problems`].
    #[error("material.{name} = {value}: {rule}")]
    InvalidMaterial {
        /// Field name: "mu", "gamma", "alpha11", "alpha22", "beta11", "beta12" or "beta22".
        name: &'static str,
        /// The value given.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// A constraint names a control point that does not exist.
    #[error(
        "constraint names control point {index}, but the geometry has {count} control points (0..{count})"
    )]
    MissingControlPoint {
        /// The index given.
        index: usize,
        /// Number of control points.
        count: usize,
    },
    /// A system that must be solved is singular (e.g. steady state of a free-floating body).
    #[error("singular system: {detail}")]
    Singular {
        /// What is singular and why.
        detail: String,
    },
    /// A time step that is zero, negative or not finite.
    #[error("time step must be positive and finite, got dt = {dt}")]
    InvalidTimeStep {
        /// The step given.
        dt: f64,
    },
    /// A load that is not finite or is applied outside the parameter domain.
    #[error("invalid load: {detail}")]
    InvalidLoad {
        /// What is wrong, with the values.
        detail: String,
    },
    /// A linear constraint that names a missing dof, is not finite, or conflicts with others.
    #[error("invalid constraint: {detail}")]
    InvalidConstraint {
        /// What is wrong, with the values.
        detail: String,
    },
    /// An option out of range (e.g. zero quadrature points, w_min ≤ 0).
    #[error("invalid option {name} = {value}: {reason}")]
    InvalidOption {
        /// Option name.
        name: &'static str,
        /// Its value, formatted.
        value: String,
        /// Why it is rejected.
        reason: String,
    },
    /// A vector of the wrong length.
    #[error("{what}: expected length {expected}, got {found}")]
    DimensionMismatch {
        /// Which vector.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A state that became non-finite during a run.
    #[error("non-finite value in {what} at step {step} (t = {time})")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
        /// Step number.
        step: usize,
        /// Time.
        time: f64,
    },
    /// The equilibrium path could not be followed beyond a load factor.
    #[error(
        "the equilibrium path stopped at load factor {lambda:.6}: Newton did not converge with \
         load increments down to {increment:.1e} of the load (a limit point, a buckling, or a \
         load the structure cannot carry)"
    )]
    PathStopped {
        /// The last load factor reached.
        lambda: f64,
        /// The last increment tried.
        increment: f64,
    },
    /// The run was cancelled (Ctrl-C).
    #[error("cancelled")]
    Cancelled,
    /// An error from the geometry crate.
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// An error from the linear algebra crate.
    #[error(transparent)]
    Linalg(#[from] LinalgError),
    /// An error from the simulation crate.
    #[error(transparent)]
    Sim(#[from] SimError),
}

impl DnurbsError {
    /// Input: the material, loads, constraints, options, geometry, or a system the input
    /// leaves singular. Run: a state that became non-finite, linear algebra, a caller's size
    /// mismatch. Simulation errors keep their own kind.
    pub fn kind(&self) -> ErrorKind {
        match self {
            DnurbsError::InvalidMaterial { .. }
            | DnurbsError::MissingControlPoint { .. }
            | DnurbsError::Singular { .. }
            | DnurbsError::InvalidTimeStep { .. }
            | DnurbsError::InvalidLoad { .. }
            | DnurbsError::InvalidConstraint { .. }
            | DnurbsError::InvalidOption { .. }
            | DnurbsError::Geom(_) => ErrorKind::Input,
            DnurbsError::DimensionMismatch { .. }
            | DnurbsError::PathStopped { .. }
            | DnurbsError::NonFinite { .. }
            | DnurbsError::Linalg(_) => ErrorKind::Run,
            DnurbsError::Cancelled => ErrorKind::Cancelled,
            DnurbsError::Sim(e) => e.kind(),
        }
    }
}
