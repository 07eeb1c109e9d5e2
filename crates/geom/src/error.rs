//! Errors of the geometry crate.

/// Everything that can be wrong with geometric input. Messages carry the offending values.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeomError {
    /// Degree below 1.
    #[error("degree must be at least 1, got {degree}")]
    DegreeTooLow {
        /// The degree given.
        degree: usize,
    },
    /// A knot vector with too few entries for its degree.
    #[error("a knot vector of degree {degree} needs at least {needed} knots, got {found}")]
    TooFewKnots {
        /// Degree.
        degree: usize,
        /// Minimum number of knots, 2 (p + 1).
        needed: usize,
        /// Number given.
        found: usize,
    },
    /// A knot that is NaN or infinite.
    #[error("knot {index} is not finite ({value})")]
    NonFiniteKnot {
        /// Position in the knot vector.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A knot vector that decreases.
    #[error(
        "knots must be non-decreasing, but knot {index} = {value} is less than knot {prev_index} = {prev}"
    )]
    DecreasingKnots {
        /// Index of the offending knot.
        index: usize,
        /// Its value.
        value: f64,
        /// Index of the knot before it.
        prev_index: usize,
        /// The knot before it.
        prev: f64,
    },
    /// A knot repeated more than p + 1 times.
    #[error("knot {value} has multiplicity {multiplicity}, more than degree + 1 = {max}")]
    MultiplicityTooHigh {
        /// Knot value.
        value: f64,
        /// Its multiplicity.
        multiplicity: usize,
        /// The maximum allowed, p + 1.
        max: usize,
    },
    /// The parameter domain `[u_p, u_{n+1}]` is empty.
    #[error("the parameter domain [{start}, {end}] is empty")]
    EmptyDomain {
        /// u_p.
        start: f64,
        /// u_{n+1}.
        end: f64,
    },
    /// Wrong number of control points for the knot vectors.
    #[error("expected {expected} control points ({detail}), got {found}")]
    ControlPointCount {
        /// Number required by the knot vectors.
        expected: usize,
        /// Number given.
        found: usize,
        /// How the expected number arises.
        detail: String,
    },
    /// Wrong number of weights.
    #[error("expected {expected} weights, got {found}")]
    WeightCount {
        /// Number required.
        expected: usize,
        /// Number given.
        found: usize,
    },
    /// A weight that is zero, negative or not finite.
    #[error("weight {index} must be positive and finite, got {value}")]
    InvalidWeight {
        /// Flat control point index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A control point coordinate that is NaN or infinite.
    #[error("control point {index} has a non-finite coordinate {value}")]
    NonFiniteControlPoint {
        /// Flat control point index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A parameter outside the domain (or not finite).
    #[error("parameter {name} = {value} is outside the domain [{start}, {end}]")]
    ParameterOutOfDomain {
        /// "u" or "v".
        name: &'static str,
        /// The value given.
        value: f64,
        /// Start of the domain.
        start: f64,
        /// End of the domain.
        end: f64,
    },
    /// The surface normal is undefined (degenerate tangents).
    #[error("the normal at ({u}, {v}) is undefined: the tangents are parallel or zero")]
    DegenerateNormal {
        /// Parameter u.
        u: f64,
        /// Parameter v.
        v: f64,
    },
    /// A knot to insert lies outside the domain or would exceed multiplicity p.
    #[error("cannot insert knot {value}: {reason}")]
    InvalidInsertion {
        /// The knot value.
        value: f64,
        /// Why not.
        reason: String,
    },
    /// An operation that needs knot-vector properties this one lacks (for example degree
    /// elevation, which needs clamped ends and interior multiplicities of at most p).
    #[error("{operation} is not supported for this knot vector: {reason}")]
    UnsupportedKnots {
        /// The operation, e.g. "degree elevation".
        operation: &'static str,
        /// What is wrong, with the offending values.
        reason: String,
    },
    /// Zero quadrature points requested.
    #[error("a Gauss–Legendre rule needs at least one point, got {points}")]
    InvalidQuadrature {
        /// The number requested.
        points: usize,
    },
}
