//! Errors of the mass-spring crate.

use nurbspring_geom::GeomError;
use nurbspring_linalg::LinalgError;
use nurbspring_sim::{ErrorKind, SimError};

/// Everything that can be wrong with a lattice or a mass-spring run. Messages carry the
/// offending values.
#[derive(Debug, thiserror::Error)]
pub enum MsmError {
    /// A spring whose end nodes coincide at the initial positions: its direction `d/|d|`
    /// (paper eq. (5)) is undefined.
    #[error("spring {spring} between nodes {a} and {b} has zero length at the initial positions")]
    ZeroLengthSpring {
        /// Spring index.
        spring: usize,
        /// First node.
        a: usize,
        /// Second node.
        b: usize,
    },
    /// A spring, linear element or probe naming a node that does not exist.
    #[error("{of} {index} names node {node}, but the lattice has {n_nodes} nodes")]
    MissingNode {
        /// What names it: `"spring"`, `"linear element"`, `"hinge"`, `"triangle"` or `"probe"`
        /// (`probe_nodes`).
        of: &'static str,
        /// Its index.
        index: usize,
        /// The node named.
        node: usize,
        /// Number of nodes.
        n_nodes: usize,
    },
    /// A spring of an msm.json joining the same two nodes as an earlier one, of the same kind
    /// and rest length: one spring of the summed constant is the same model.
    #[error(
        "spring {spring} joins nodes {a} and {b} like spring {first} (same kind and rest length): merge them into one spring of k = the sum of their constants"
    )]
    DuplicateSpring {
        /// The later spring.
        spring: usize,
        /// The earlier one.
        first: usize,
        /// Its nodes.
        a: usize,
        /// Its nodes.
        b: usize,
    },
    /// A node mass that is zero or negative.
    #[error("node {node} has mass {mass}; masses must be positive")]
    NonPositiveMass {
        /// Node index.
        node: usize,
        /// The mass given.
        mass: f64,
    },
    /// A spring constant below zero.
    #[error("spring {spring} has stiffness k = {k}; spring constants must be ≥ 0")]
    NegativeStiffness {
        /// Spring index.
        spring: usize,
        /// The constant given.
        k: f64,
    },
    /// A parameter outside its range (pre-strain ≥ 1, negative damping or rest length, a grid
    /// with fewer than two nodes along a direction, …).
    #[error("invalid {name}: {value}")]
    InvalidParameter {
        /// What the parameter is.
        name: String,
        /// The value given.
        value: f64,
    },
    /// A lattice option that breaks a rule of [`crate::LatticeOptions::problems`]; `name` is the
    /// field (`mass`, `damping`, `pre_strain`, `gravity[2]`, a constant's symbol such as
    /// `k_edge`, or `nodes_u` / `nodes_v` of a uniform grid).
    #[error("{name} = {value}: {rule}")]
    InvalidOption {
        /// The field.
        name: String,
        /// The value given.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// Lattice options without any spring class.
    #[error("no spring class is enabled: the lattice has no springs")]
    NoSprings,
    /// An entry of an explicit fixed-node list that names no node.
    #[error(
        "fixed node {position} of the list is node {node}, but the lattice has {n_nodes} nodes"
    )]
    FixedNodeOutside {
        /// Position in the list.
        position: usize,
        /// The node named.
        node: usize,
        /// Number of nodes.
        n_nodes: usize,
    },
    /// A linear element that breaks a rule of [`crate::SpringLattice::validate`].
    #[error("linear element {element}: invalid {what}: {value}")]
    InvalidElement {
        /// Element index.
        element: usize,
        /// What is wrong.
        what: String,
        /// The value.
        value: f64,
    },
    /// A hinge that breaks a rule of [`crate::SpringLattice::validate`].
    #[error("hinge {hinge}: invalid {what}: {value}")]
    InvalidHinge {
        /// Hinge index.
        hinge: usize,
        /// What is wrong.
        what: String,
        /// The value.
        value: f64,
    },
    /// Per-element weights of the wrong count for a class.
    #[error("class {class} has {expected} elements, but {found} weights were given")]
    WeightCount {
        /// The class name.
        class: String,
        /// Its number of elements.
        expected: usize,
        /// Weights given.
        found: usize,
    },
    /// A NaN or infinite input value, or one beyond ±[`MAX_MAGNITUDE`](nurbspring_sim::MAX_MAGNITUDE).
    #[error("{what} {index} is not a finite number of magnitude at most 1e30 ({value})")]
    NonFinite {
        /// What kind of value ("node position", "spring stiffness", …).
        what: &'static str,
        /// Index of the node or spring (0 for global values).
        index: usize,
        /// The value.
        value: f64,
    },
    /// Per-node arrays of different lengths.
    #[error("{what}: expected {expected} entries (one per node), got {found}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Number of nodes.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// More nodes than [`crate::MAX_NODES`]; refused before allocating.
    #[error(
        "a lattice of {nodes} nodes is larger than the limit of {} nodes",
        crate::MAX_NODES
    )]
    TooLarge {
        /// Number of nodes requested (saturated at `usize::MAX`).
        nodes: usize,
    },
    /// Geometry error (surface evaluation).
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// Linear algebra error.
    #[error(transparent)]
    Linalg(#[from] LinalgError),
    /// Dynamics error.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// An `msm.json` text that does not parse or does not fit the schema.
    #[error("not a valid msm.json at line {line}, column {column}: {message}")]
    Json {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
}

impl From<serde_json::Error> for MsmError {
    fn from(e: serde_json::Error) -> Self {
        MsmError::Json {
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        }
    }
}

impl MsmError {
    /// Input: everything about the lattice, its options and its file. Run: linear algebra.
    /// Simulation errors keep their own kind.
    pub fn kind(&self) -> ErrorKind {
        match self {
            MsmError::Linalg(_) => ErrorKind::Run,
            MsmError::Sim(e) => e.kind(),
            _ => ErrorKind::Input,
        }
    }
}
