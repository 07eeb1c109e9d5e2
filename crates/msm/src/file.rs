//! `msm.json`: a mass-spring model as nodes and springs, with how to run it. This is the one
//! schema of the file: `derive` writes it, `simulate` and `stability` read it, users bring
//! their own mesh in it.
//!
//! ```json
//! {"nodes": [{"position": [0, 0, 0], "mass": 1, "fixed": true, "damping": 0, "uv": [0, 0]}, …],
//!  "springs": [{"a": 0, "b": 1, "kind": "structural", "k": 1, "rest_length": 0.5,
//!               "weight": 1, "damping": 0}, …],
//!  "hinges": [{"nodes": [0, 1, 5, 7], "class": "hinge", "k": 0.1, "weight": 1,
//!              "rest_angle": 0}, …],
//!  "triangles": [[0, 4, 5], …],
//!  "gravity": [0, 0, -9.81], "grid": [n_u, n_v],
//!  "scene": "examples/paper.toml", "initial_velocities": [[0, 0, 0], …],
//!  "simulation": {"dt": 0.08, "t_end": 4, "integrator": "newmark"}, "probe_nodes": [12, 3]}
//! ```
//! `fixed`, `damping`, `uv`, `gravity` and `grid` may be left out (false, 0, none, zero, none);
//! a spring's `kind` defaults to `"structural"`, its `rest_length` to its initial length, its
//! `weight` to 1 and its axial `damping` (docs/math.md §5.1) to 0. `hinges` (docs/math.md §5.2:
//! the edge `nodes[0] → nodes[1]`, the wings `nodes[2]`, `nodes[3]`; `class` `"hinge"` or
//! `"hinge_diagonal"`, default `"hinge"`; `weight` default 1; `rest_angle` in radians, default
//! the angle at the initial positions) and `triangles` may be left out (none). A file without
//! the keys of later versions (weights, damping, hinges) is the same model as before.
//! `scene` (where the model came from), `initial_velocities` (one per node; zero when left
//! out; ignored at fixed nodes), `simulation` and `probe_nodes` (the nodes `simulate` records;
//! the node nearest the centre when left out) are optional. Unknown keys are refused.

use nurbspring_sim::IntegratorKind;
use serde::{Deserialize, Serialize};

use crate::hinge::angle;
use crate::spring::{norm, sub};
use crate::{
    Class, Hinge, HingeKind, LinearElement, LinearKind, MAX_NODES, MsmError, Spring, SpringKind,
    SpringLattice,
};

/// One node of an [`MsmFile`].
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
    /// A constant external force on the node besides gravity, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<[f64; 3]>,
}

/// One linear element of an [`MsmFile`]: energy `½ k weight |Σ coefficients_i u_{nodes_i}|²`
/// on the displacements `u` of its nodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElementRecord {
    /// `"spring_u"`, `"spring_v"`, `"diagonal"`, `"bend_u"`, `"bend_v"`, `"twist"`, `"third_u"` or
    /// `"third_v"`.
    pub kind: LinearKind,
    /// The class sharing its constant, `"kind@interior"` or `"kind@boundary"`.
    pub class: String,
    /// Its nodes (2 to 4).
    pub nodes: Vec<usize>,
    /// Class constant (≥ 0).
    pub k: f64,
    /// Weight (> 0).
    pub weight: f64,
    /// Stencil coefficients, one per node.
    pub coefficients: Vec<f64>,
}

/// One spring of an [`MsmFile`].
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
    /// Weight (> 0; the stiffness is `k · weight`); 1 when left out.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub weight: f64,
    /// Axial damping c (≥ 0, docs/math.md §5.1); 0 when left out.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub damping: f64,
}

fn structural() -> SpringKind {
    SpringKind::Structural
}

fn one() -> f64 {
    1.0
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn grid_hinge() -> HingeKind {
    HingeKind::Grid
}

/// One hinge of an [`MsmFile`] (docs/math.md §5.2): energy `½ k weight (θ − rest_angle)²`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HingeRecord {
    /// The edge `nodes[0] → nodes[1]`, then the wing of the triangle `(nodes[0], nodes[1],
    /// nodes[2])` and the wing of `(nodes[1], nodes[0], nodes[3])`.
    pub nodes: [usize; 4],
    /// `"hinge"` or `"hinge_diagonal"` (default `"hinge"`).
    #[serde(default = "grid_hinge")]
    pub class: HingeKind,
    /// Class constant (≥ 0).
    pub k: f64,
    /// Weight (> 0); 1 when left out.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub weight: f64,
    /// Rest angle [rad] in `[−π, π]`; the angle at the initial positions when left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_angle: Option<f64>,
}

/// How to run the model, as `derive` records it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FileSimulation {
    /// Time step [s].
    pub dt: f64,
    /// End time [s].
    pub t_end: f64,
    /// Integrator.
    pub integrator: IntegratorKind,
}

/// The file `msm.json` (module docs give the format).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MsmFile {
    /// Nodes; node `a` is the `a`-th entry.
    pub nodes: Vec<NodeRecord>,
    /// Springs.
    pub springs: Vec<SpringRecord>,
    /// Linear isotropic elements (none when left out).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub elements: Vec<ElementRecord>,
    /// Hinges (none when left out).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hinges: Vec<HingeRecord>,
    /// Triangles of a triangulated lattice, counter-clockwise in the parameter plane (none
    /// when left out; for exports and viewers, no force depends on them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub triangles: Vec<[usize; 3]>,
    /// Gravity g (default zero).
    #[serde(default)]
    pub gravity: [f64; 3],
    /// `[n_u, n_v]` when the nodes form a grid (`a = i · n_v + j`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<[usize; 2]>,
    /// Where the model came from (a scene file), for people reading the file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    /// Initial node velocities, one per node (`Ω ṗ(0)`, paper eq. (18), for a derived model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial_velocities: Option<Vec<[f64; 3]>>,
    /// How to run it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simulation: Option<FileSimulation>,
    /// The nodes whose motion `simulate` records (`trajectory.csv`'s probes, in order): for a
    /// derived model the node nearest each of the scene's probes, the centre first. Left out:
    /// the node nearest the centre of the nodes' parameters.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probe_nodes: Option<Vec<usize>>,
}

impl MsmFile {
    /// Parses JSON text (errors give the line and column).
    pub fn from_json_str(text: &str) -> Result<Self, MsmError> {
        Ok(serde_json::from_str(text)?)
    }

    /// Pretty-printed JSON text.
    pub fn to_json_string(&self) -> String {
        serde_json::to_string_pretty(self).expect("an msm.json file always serializes")
    }

    /// The initial velocities, one per node (zero when the file gives none); a list of the
    /// wrong length or with a non-finite value is refused.
    pub fn velocities(&self) -> Result<Vec<[f64; 3]>, MsmError> {
        let n = self.nodes.len();
        match &self.initial_velocities {
            None => Ok(vec![[0.0; 3]; n]),
            Some(v) if v.len() != n => Err(MsmError::LengthMismatch {
                what: "initial_velocities",
                expected: n,
                found: v.len(),
            }),
            Some(v) => {
                for (a, x) in v.iter().enumerate() {
                    if let Some(&bad) = x.iter().find(|c| !nurbspring_sim::representable(**c)) {
                        return Err(MsmError::NonFinite {
                            what: "initial velocity of node",
                            index: a,
                            value: bad,
                        });
                    }
                }
                Ok(v.clone())
            }
        }
    }
}

impl SpringLattice {
    /// The file form of this lattice (every rest length written; no scene, velocities or run
    /// settings).
    pub fn to_file(&self) -> MsmFile {
        MsmFile {
            nodes: (0..self.n_nodes())
                .map(|a| NodeRecord {
                    position: self.positions[a],
                    mass: self.masses[a],
                    fixed: self.fixed[a],
                    damping: self.damping[a],
                    uv: self.params.as_ref().map(|p| [p[a].0, p[a].1]),
                    force: self.forces.get(a).copied(),
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
                    weight: s.weight,
                    damping: s.damping,
                })
                .collect(),
            elements: self
                .elements
                .iter()
                .map(|e| ElementRecord {
                    kind: e.kind,
                    class: e.class().name(),
                    nodes: e.nodes.clone(),
                    k: e.k,
                    weight: e.weight,
                    coefficients: e.coefficients.clone(),
                })
                .collect(),
            hinges: self
                .hinges
                .iter()
                .map(|h| HingeRecord {
                    nodes: h.nodes,
                    class: h.kind,
                    k: h.k,
                    weight: h.weight,
                    rest_angle: Some(h.rest_angle),
                })
                .collect(),
            triangles: self.triangles.clone(),
            gravity: self.gravity,
            grid: self.grid.map(|(u, v)| [u, v]),
            scene: None,
            initial_velocities: None,
            simulation: None,
            probe_nodes: None,
        }
    }

    /// A lattice from its file form, validated like [`SpringLattice::from_parts`]. `uv` must be
    /// given for every node or for none.
    ///
    /// ```
    /// use nurbspring_msm::{MsmFile, SpringLattice};
    /// let text = r#"{"nodes": [{"position": [0, 0, 0], "mass": 1, "fixed": true},
    ///                          {"position": [2, 0, 0], "mass": 1}],
    ///               "springs": [{"a": 0, "b": 1, "k": 3}]}"#;
    /// let lattice = SpringLattice::from_file(&MsmFile::from_json_str(text).unwrap()).unwrap();
    /// assert_eq!(lattice.springs[0].rest_length, 2.0);
    /// assert_eq!(lattice.fixed, vec![true, false]);
    /// ```
    pub fn from_file(file: &MsmFile) -> Result<Self, MsmError> {
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
        // (nodes, kind, rest length) → the first spring with them.
        let mut seen: std::collections::HashMap<(usize, usize, SpringKind, Option<u64>), usize> =
            std::collections::HashMap::with_capacity(file.springs.len());
        for (i, s) in file.springs.iter().enumerate() {
            let key = (
                s.a.min(s.b),
                s.a.max(s.b),
                s.kind,
                s.rest_length.map(f64::to_bits),
            );
            if let Some(&first) = seen.get(&key) {
                return Err(MsmError::DuplicateSpring {
                    spring: i,
                    first,
                    a: s.a,
                    b: s.b,
                });
            }
            seen.insert(key, i);
            for node in [s.a, s.b] {
                if node >= n {
                    return Err(MsmError::MissingNode {
                        of: "spring",
                        index: i,
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
                weight: s.weight,
                damping: s.damping,
            });
        }
        let mut elements = Vec::with_capacity(file.elements.len());
        for (i, e) in file.elements.iter().enumerate() {
            let region = match Class::parse(&e.class) {
                Some(Class::Linear(kind, region)) if kind == e.kind => region,
                _ => {
                    return Err(MsmError::InvalidElement {
                        element: i,
                        what: format!(
                            "class \"{}\" (expected \"{kind}@interior\" or \"{kind}@boundary\")",
                            e.class,
                            kind = e.kind.name()
                        ),
                        value: f64::NAN,
                    });
                }
            };
            elements.push(LinearElement {
                kind: e.kind,
                region,
                nodes: e.nodes.clone(),
                coefficients: e.coefficients.clone(),
                weight: e.weight,
                k: e.k,
            });
        }
        let mut hinges = Vec::with_capacity(file.hinges.len());
        for (i, h) in file.hinges.iter().enumerate() {
            if let Some(&node) = h.nodes.iter().find(|&&a| a >= n) {
                return Err(MsmError::MissingNode {
                    of: "hinge",
                    index: i,
                    node,
                    n_nodes: n,
                });
            }
            hinges.push(Hinge {
                nodes: h.nodes,
                kind: h.class,
                k: h.k,
                weight: h.weight,
                rest_angle: h
                    .rest_angle
                    .unwrap_or_else(|| angle(&h.nodes.map(|a| positions[a]))),
            });
        }
        let with_force = file.nodes.iter().filter(|r| r.force.is_some()).count();
        let forces = if with_force == 0 {
            Vec::new()
        } else {
            file.nodes
                .iter()
                .map(|r| r.force.unwrap_or([0.0; 3]))
                .collect()
        };
        let lattice = SpringLattice {
            elements,
            hinges,
            triangles: file.triangles.clone(),
            forces,
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
        Self::from_file(&MsmFile::from_json_str(text)?)
    }

    /// This lattice as pretty-printed `msm.json` text.
    pub fn to_json_string(&self) -> String {
        self.to_file().to_json_string()
    }
}
