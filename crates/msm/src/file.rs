//! `msm.json`: a lattice as nodes and springs, so users can bring their own mesh.
//!
//! ```json
//! {"nodes": [{"position": [0, 0, 0], "mass": 1, "fixed": true, "damping": 0, "uv": [0, 0]}, …],
//!  "springs": [{"a": 0, "b": 1, "kind": "structural", "k": 1, "rest_length": 0.5}, …],
//!  "gravity": [0, 0, -9.81], "grid": [n_u, n_v]}
//! ```
//! `fixed`, `damping`, `uv`, `gravity` and `grid` may be left out (false, 0, none, zero, none);
//! a spring's `kind` defaults to `"structural"` and its `rest_length` to its initial length.
//! Unknown keys are refused.

use serde::{Deserialize, Serialize};

use crate::spring::{norm, sub};
use crate::{MAX_NODES, MsmError, Spring, SpringKind, SpringLattice};

/// One node of a [`LatticeFile`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeRecord {
    /// Initial position.
    pub position: [f64; 3],
    /// Mass (> 0).
    pub mass: f64,
    /// Held at its initial position.
    #[serde(default)]
    pub fixed: bool,
    /// Damping factor γ ≥ 0 (force −γ ẋ).
    #[serde(default)]
    pub damping: f64,
    /// Surface parameters `(u, v)` it was sampled at, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uv: Option<[f64; 2]>,
}

/// One spring of a [`LatticeFile`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringRecord {
    /// First node.
    pub a: usize,
    /// Second node.
    pub b: usize,
    /// Class (default structural).
    #[serde(default = "structural")]
    pub kind: SpringKind,
    /// Stiffness (≥ 0).
    pub k: f64,
    /// Rest length; the initial length when left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_length: Option<f64>,
}

fn structural() -> SpringKind {
    SpringKind::Structural
}

/// The JSON form of a [`SpringLattice`] (module docs give the format).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LatticeFile {
    /// Nodes; node `a` is the `a`-th entry.
    pub nodes: Vec<NodeRecord>,
    /// Springs.
    pub springs: Vec<SpringRecord>,
    /// Gravity g (default zero).
    #[serde(default)]
    pub gravity: [f64; 3],
    /// `[n_u, n_v]` when the nodes form a grid (`a = i · n_v + j`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<[usize; 2]>,
}

impl LatticeFile {
    /// Parses JSON text.
    pub fn from_json_str(text: &str) -> Result<Self, MsmError> {
        Ok(serde_json::from_str(text)?)
    }

    /// Pretty-printed JSON text.
    pub fn to_json_string(&self) -> String {
        serde_json::to_string_pretty(self).expect("a lattice file always serializes")
    }
}

impl SpringLattice {
    /// The file form of this lattice (every rest length written).
    pub fn to_json(&self) -> LatticeFile {
        LatticeFile {
            nodes: (0..self.n_nodes())
                .map(|a| NodeRecord {
                    position: self.positions[a],
                    mass: self.masses[a],
                    fixed: self.fixed[a],
                    damping: self.damping[a],
                    uv: self.params.as_ref().map(|p| [p[a].0, p[a].1]),
                })
                .collect(),
            springs: self
                .springs
                .iter()
                .map(|s| SpringRecord {
                    a: s.a,
                    b: s.b,
                    kind: s.kind,
                    k: s.k,
                    rest_length: Some(s.rest_length),
                })
                .collect(),
            gravity: self.gravity,
            grid: self.grid.map(|(u, v)| [u, v]),
        }
    }

    /// A lattice from its file form, validated like [`SpringLattice::from_parts`]. `uv` must be
    /// given for every node or for none.
    ///
    /// ```
    /// use nurbspring_msm::{LatticeFile, SpringLattice};
    /// let text = r#"{"nodes": [{"position": [0, 0, 0], "mass": 1, "fixed": true},
    ///                          {"position": [2, 0, 0], "mass": 1}],
    ///               "springs": [{"a": 0, "b": 1, "k": 3}]}"#;
    /// let lattice = SpringLattice::from_json(&LatticeFile::from_json_str(text).unwrap()).unwrap();
    /// assert_eq!(lattice.springs[0].rest_length, 2.0);
    /// assert_eq!(lattice.fixed, vec![true, false]);
    /// ```
    pub fn from_json(file: &LatticeFile) -> Result<Self, MsmError> {
        let n = file.nodes.len();
        if n > MAX_NODES {
            return Err(MsmError::TooLarge { nodes: n });
        }
        let positions: Vec<[f64; 3]> = file.nodes.iter().map(|r| r.position).collect();
        let with_uv = file.nodes.iter().filter(|r| r.uv.is_some()).count();
        let params = match with_uv {
            0 => None,
            m if m == n => Some(
                file.nodes
                    .iter()
                    .map(|r| r.uv.map(|[u, v]| (u, v)).unwrap_or_default())
                    .collect(),
            ),
            m => {
                return Err(MsmError::LengthMismatch {
                    what: "nodes with \"uv\" (all or none)",
                    expected: n,
                    found: m,
                });
            }
        };
        let mut springs = Vec::with_capacity(file.springs.len());
        for (i, s) in file.springs.iter().enumerate() {
            for node in [s.a, s.b] {
                if node >= n {
                    return Err(MsmError::MissingNode {
                        spring: i,
                        node,
                        n_nodes: n,
                    });
                }
            }
            springs.push(Spring {
                a: s.a,
                b: s.b,
                kind: s.kind,
                k: s.k,
                rest_length: s
                    .rest_length
                    .unwrap_or_else(|| norm(sub(positions[s.a], positions[s.b]))),
            });
        }
        let lattice = SpringLattice {
            masses: file.nodes.iter().map(|r| r.mass).collect(),
            damping: file.nodes.iter().map(|r| r.damping).collect(),
            fixed: file.nodes.iter().map(|r| r.fixed).collect(),
            positions,
            springs,
            params,
            grid: file.grid.map(|[u, v]| (u, v)),
            gravity: file.gravity,
        };
        lattice.validate()?;
        Ok(lattice)
    }

    /// Parses `msm.json` text into a validated lattice.
    pub fn from_json_str(text: &str) -> Result<Self, MsmError> {
        Self::from_json(&LatticeFile::from_json_str(text)?)
    }

    /// This lattice as pretty-printed `msm.json` text.
    pub fn to_json_string(&self) -> String {
        self.to_json().to_json_string()
    }
}
