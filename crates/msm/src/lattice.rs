//! Spring lattices: from a NURBS surface (docs/math.md §5, paper Figure 1 and eq. (19)) or from any
//! node and spring lists.

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::representable;

use crate::element::grid_elements;
use crate::hinge::angle;
use crate::spring::sub;
use crate::stiffness::Coefficient;
use crate::topology::Topology;
use crate::{
    Class, Constants, Hinge, HingeKind, LinearElement, LinearKind, MAX_NODES, MsmError, Region,
    Spring, SpringKind,
};

/// Where the lattice nodes sit in the parameter domain.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum ParameterGrid {
    /// The distinct knot values of each direction (the paper's "u_i ∈ U"; default).
    #[default]
    Knots,
    /// `nodes_u × nodes_v` uniformly spaced parameters, domain ends included (each ≥ 2).
    Uniform {
        /// Nodes along u.
        nodes_u: usize,
        /// Nodes along v.
        nodes_v: usize,
    },
    /// The Greville abscissae of each direction (repeated values merged).
    Greville,
}

/// Which nodes are fixed.
#[derive(Clone, Debug, PartialEq, Default)]
pub enum FixedNodes {
    /// docs/math.md §5: a node is fixed when every control point with a non-zero basis value at its
    /// `(u, v)` is fixed (the fixed control points are given to [`SpringLattice::from_surface`]).
    #[default]
    Auto,
    /// These node indices (`a = i · n_v + j`).
    List(Vec<usize>),
}

/// How to build a lattice from a surface ([`SpringLattice::from_surface`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LatticeOptions {
    /// Parameter grid of the nodes.
    pub grid: ParameterGrid,
    /// The spring classes to build, each with its constant: structural springs between grid
    /// neighbours along u and v (`k_edge`), shear springs on both diagonals of each cell
    /// (`k_diag`), bending springs between second neighbours along u and v (`k_bend`).
    pub constants: Constants,
    /// Mass of every node.
    pub mass: f64,
    /// Damping factor `γ` of every node (force `−γ ẋ`, docs/math.md §5).
    pub damping: f64,
    /// Rest lengths are `(1 − pre_strain) ×` the initial lengths; `pre_strain > 0` puts the
    /// lattice under tension (geometric stiffness), `< 0` under compression. Must be `< 1`.
    pub pre_strain: f64,
    /// Fixed nodes.
    pub fixed: FixedNodes,
    /// Gravity `g` (force `m_a g` on each node, paper eq. (6)).
    pub gravity: [f64; 3],
}

impl LatticeOptions {
    /// Every rule on the options, each problem naming its field (docs/math.md §5): at least
    /// one spring class; spring constants finite and `≥ 0`; the node mass finite and `> 0`;
    /// damping finite and `≥ 0`; `pre_strain` in `(−1, 1)` (rest lengths positive and at most
    /// twice the initial ones); gravity finite. Empty when the options are valid.
    pub fn problems(&self) -> Vec<MsmError> {
        let mut out = Vec::new();
        let mut check = |name: &str, value: f64, ok: bool, rule: &'static str| {
            if !representable(value) {
                out.push(MsmError::InvalidOption {
                    name: name.to_string(),
                    value,
                    rule: "must be a finite number of magnitude at most 1e30 (larger values overflow)",
                });
            } else if !ok {
                out.push(MsmError::InvalidOption {
                    name: name.to_string(),
                    value,
                    rule,
                });
            }
        };
        for (class, k) in self.constants.iter() {
            check(
                &class.symbol(),
                k,
                k >= 0.0,
                "spring constants must not be negative",
            );
        }
        check(
            "mass",
            self.mass,
            self.mass > 0.0,
            "the node mass must be positive",
        );
        check(
            "damping",
            self.damping,
            self.damping >= 0.0,
            "the damping coefficient must not be negative",
        );
        check(
            "pre_strain",
            self.pre_strain,
            self.pre_strain > -1.0 && self.pre_strain < 1.0,
            "must lie in (-1, 1)",
        );
        for (c, &g) in self.gravity.iter().enumerate() {
            check(&format!("gravity[{c}]"), g, true, "");
        }
        if self.constants.is_empty() {
            out.push(MsmError::NoSprings);
        }
        out
    }

    /// The first of [`LatticeOptions::problems`], if any.
    pub fn validate(&self) -> Result<(), MsmError> {
        match self.problems().into_iter().next() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

impl Default for LatticeOptions {
    /// Distinct knots, structural and shear springs with `k = 1`, mass 1, no damping, no
    /// pre-strain, fixed nodes by the docs/math.md §5 rule, no gravity.
    fn default() -> Self {
        Self {
            grid: ParameterGrid::Knots,
            constants: Constants::from_pairs([
                (Class::Spring(SpringKind::Structural), 1.0),
                (Class::Spring(SpringKind::Shear), 1.0),
            ]),
            mass: 1.0,
            damping: 0.0,
            pre_strain: 0.0,
            fixed: FixedNodes::Auto,
            gravity: [0.0; 3],
        }
    }
}

/// A mass-spring model (paper eqs. (5)–(7)): nodes with masses, damping and fixed flags,
/// springs between them, hinges (docs/math.md §5.2), and linear isotropic elements
/// (docs/math.md §8).
///
/// Node positions are the initial (rest) positions. Generalized coordinates are interleaved
/// `[x_0, y_0, z_0, x_1, …]` (docs/math.md §1); on a grid, node `a = i · n_v + j`.
#[derive(Clone, Debug, PartialEq)]
pub struct SpringLattice {
    /// Initial node positions.
    pub positions: Vec<[f64; 3]>,
    /// Node masses `m_a > 0`.
    pub masses: Vec<f64>,
    /// Node damping factors `γ_a ≥ 0`.
    pub damping: Vec<f64>,
    /// Fixed nodes (all three coordinates held at their initial values).
    pub fixed: Vec<bool>,
    /// The springs.
    pub springs: Vec<Spring>,
    /// The linear isotropic elements (docs/math.md §8).
    pub elements: Vec<LinearElement>,
    /// The hinges (dihedral-angle bending, docs/math.md §5.2).
    pub hinges: Vec<Hinge>,
    /// The triangles of a triangulated lattice ([`SpringLattice::triangulated`]), each
    /// counter-clockwise in the parameter plane; empty otherwise. Only for exports and for
    /// people: no force depends on them.
    pub triangles: Vec<[usize; 3]>,
    /// Constant external force on each node besides gravity (empty: none).
    pub forces: Vec<[f64; 3]>,
    /// `(u, v)` of each node when sampled from a surface.
    pub params: Option<Vec<(f64, f64)>>,
    /// `(n_u, n_v)` when the nodes form a grid, node `a = i · n_v + j`.
    pub grid: Option<(usize, usize)>,
    /// Gravity `g`.
    pub gravity: [f64; 3],
}

/// Basis values below this count as zero in the docs/math.md §5 fixed-node rule (the Cox–de Boor
/// recursion gives exact zeros at knots; this only absorbs round-off).
const BASIS_ZERO: f64 = 1e-14;

impl SpringLattice {
    /// Nodes `x_ab = c(u_a, v_b)` on the parameter grid of `options` (paper eq. (19)), springs
    /// by kind (docs/math.md §5), rest lengths `(1 − pre_strain) ×` the initial lengths. With
    /// [`FixedNodes::Auto`] a node is fixed when every control point with a non-zero basis
    /// value at its `(u, v)` is in `fixed_control_points` (flat indices `k = i · n_v + j`).
    ///
    /// ```
    /// use nurbspring_geom::{KnotVector, NurbsSurface};
    /// use nurbspring_msm::{LatticeOptions, ParameterGrid, SpringLattice};
    /// let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    /// let s = NurbsSurface::try_new(k.clone(), k, vec![[0., 0., 0.], [0., 1., 0.], [1., 0., 0.], [1., 1., 0.]], vec![1.; 4]).unwrap();
    /// let opts = LatticeOptions { grid: ParameterGrid::Uniform { nodes_u: 3, nodes_v: 3 }, ..Default::default() };
    /// let lattice = SpringLattice::from_surface(&s, &opts, &[]).unwrap();
    /// // 12 structural springs and 8 shear springs on a 3 × 3 grid.
    /// assert_eq!((lattice.n_nodes(), lattice.springs.len()), (9, 20));
    /// ```
    pub fn from_surface(
        surface: &NurbsSurface,
        options: &LatticeOptions,
        fixed_control_points: &[usize],
    ) -> Result<Self, MsmError> {
        options.validate()?;
        let (us, vs) = options.grid.parameters(surface)?;
        let n = us.len().saturating_mul(vs.len());
        if n > MAX_NODES {
            return Err(MsmError::TooLarge { nodes: n });
        }
        let positions = surface.grid(&us, &vs)?;
        let fixed = surface_fixed(surface, options, &us, &vs, fixed_control_points)?;
        Self::on_grid(&us, &vs, positions, fixed, options)
    }

    /// A triangulated lattice on a surface (docs/math.md §5.3): nodes `x_ab = c(u_a, v_b)` on
    /// the parameter grid of `options` and fixed nodes as in [`SpringLattice::from_surface`];
    /// each grid cell cut into two triangles along one diagonal, the diagonals alternating
    /// like a checkerboard (cell `(i, j)` along `(i, j)–(i+1, j+1)` when `i + j` is even,
    /// along `(i+1, j)–(i, j+1)` otherwise), so the mesh has no preferred direction.
    ///
    /// Elements, each class built when `options.constants` holds it, with that constant and
    /// weight 1: structural springs on the grid-line edges, shear springs on the cells'
    /// diagonals (one per cell), bending springs between second neighbours as in
    /// [`SpringLattice::from_surface`], a [`HingeKind::Grid`] hinge on every interior
    /// grid-line edge and a [`HingeKind::Diagonal`] hinge on every diagonal, with the rest
    /// angle of the positions, so that the lattice is stress-free at rest (spring rest lengths
    /// are `(1 − pre_strain) ×` the initial lengths). [`SpringLattice::triangles`] lists the
    /// triangles.
    ///
    /// ```
    /// use nurbspring_geom::{KnotVector, NurbsSurface};
    /// use nurbspring_msm::{Class, Constants, HingeKind, LatticeOptions, ParameterGrid, SpringKind, SpringLattice};
    /// let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    /// let s = NurbsSurface::try_new(k.clone(), k, vec![[0., 0., 0.], [0., 1., 0.], [1., 0., 0.], [1., 1., 0.]], vec![1.; 4]).unwrap();
    /// let constants = Constants::from_pairs([
    ///     (Class::Spring(SpringKind::Structural), 1.0),
    ///     (Class::Spring(SpringKind::Shear), 1.0),
    ///     (Class::Hinge(HingeKind::Grid), 0.1),
    ///     (Class::Hinge(HingeKind::Diagonal), 0.1),
    /// ]);
    /// let opts = LatticeOptions { grid: ParameterGrid::Uniform { nodes_u: 3, nodes_v: 3 }, constants, ..Default::default() };
    /// let lattice = SpringLattice::triangulated(&s, &opts, &[]).unwrap();
    /// // 3 × 3 nodes: 12 grid edges and 4 diagonals, 8 triangles, 4 + 4 interior edges.
    /// assert_eq!((lattice.springs.len(), lattice.triangles.len(), lattice.hinges.len()), (16, 8, 8));
    /// // Flat at rest: every rest angle is zero, and the lattice is stress-free.
    /// assert!(lattice.hinges.iter().all(|h| h.rest_angle.abs() < 1e-15));
    /// ```
    pub fn triangulated(
        surface: &NurbsSurface,
        options: &LatticeOptions,
        fixed_control_points: &[usize],
    ) -> Result<Self, MsmError> {
        options.validate()?;
        let (us, vs) = options.grid.parameters(surface)?;
        for (name, count) in [("nodes_u", us.len()), ("nodes_v", vs.len())] {
            if count < 2 {
                return Err(MsmError::InvalidOption {
                    name: name.to_string(),
                    value: count as f64,
                    rule: "a triangulated lattice needs at least 2 nodes along each direction",
                });
            }
        }
        let (n_u, n_v) = (us.len(), vs.len());
        let positions = surface.grid(&us, &vs)?;
        let fixed = surface_fixed(surface, options, &us, &vs, fixed_control_points)?;
        let n = n_u * n_v;
        let params: Vec<(f64, f64)> = us
            .iter()
            .flat_map(|&u| vs.iter().map(move |&v| (u, v)))
            .collect();
        let triangles = grid_triangles(n_u, n_v);
        let springs = triangulated_springs(n_u, n_v, options, &positions);
        let hinges = triangle_hinges(&triangles, n_v, &positions, &options.constants);
        let lattice = Self {
            positions,
            masses: vec![options.mass; n],
            damping: vec![options.damping; n],
            fixed,
            springs,
            elements: Vec::new(),
            hinges,
            triangles,
            forces: Vec::new(),
            params: Some(params),
            grid: Some((n_u, n_v)),
            gravity: options.gravity,
        };
        lattice.validate()?;
        Ok(lattice)
    }

    /// A chain of nodes `x_a = c(u_a)` on a curve (the one-parameter case of
    /// [`SpringLattice::from_surface`]): springs and linear elements along u only; with
    /// [`FixedNodes::Auto`] on the Greville grid node `a` is fixed when control point `a` is,
    /// elsewhere when every control point with a non-zero basis value at `u_a` is.
    pub fn from_curve(
        curve: &NurbsCurve,
        options: &LatticeOptions,
        fixed_control_points: &[usize],
    ) -> Result<Self, MsmError> {
        options.validate()?;
        let us = options.grid.parameters_along(curve.basis().knots())?;
        let n = us.len();
        let positions = us
            .iter()
            .map(|&u| curve.point(u))
            .collect::<Result<Vec<_>, _>>()?;
        let fixed = match &options.fixed {
            FixedNodes::Auto
                if options.grid == ParameterGrid::Greville && n == curve.n_control_points() =>
            {
                control_point_fixed(n, fixed_control_points)?
            }
            FixedNodes::Auto => {
                let mut cp_fixed = vec![false; curve.n_control_points()];
                for &k in fixed_control_points {
                    if let Some(f) = cp_fixed.get_mut(k) {
                        *f = true;
                    }
                }
                let any = !fixed_control_points.is_empty();
                us.iter()
                    .map(|&u| Ok(any && support(curve.basis(), u)?.iter().all(|&k| cp_fixed[k])))
                    .collect::<Result<Vec<bool>, MsmError>>()?
            }
            FixedNodes::List(list) => listed_fixed(n, list)?,
        };
        Self::on_grid(&us, &[0.0], positions, fixed, options)
    }

    /// The lattice on the tensor grid `us × vs` with these positions and fixed nodes.
    fn on_grid(
        us: &[f64],
        vs: &[f64],
        positions: Vec<[f64; 3]>,
        fixed: Vec<bool>,
        options: &LatticeOptions,
    ) -> Result<Self, MsmError> {
        let (n_u, n_v) = (us.len(), vs.len());
        let n = n_u * n_v;
        let params: Vec<(f64, f64)> = us
            .iter()
            .flat_map(|&u| vs.iter().map(move |&v| (u, v)))
            .collect();
        let springs = grid_springs(n_u, n_v, options, &positions);
        let kinds: Vec<LinearKind> = LinearKind::ALL
            .into_iter()
            .filter(|&k| {
                Region::ALL
                    .iter()
                    .any(|&r| options.constants.contains(Class::Linear(k, r)))
            })
            .collect();
        let elements = grid_elements(us, vs, &fixed, &kinds, &|kind, region| {
            options.constants.value(Class::Linear(kind, region))
        });
        let lattice = Self {
            positions,
            masses: vec![options.mass; n],
            damping: vec![options.damping; n],
            fixed,
            springs,
            elements,
            hinges: Vec::new(),
            triangles: Vec::new(),
            forces: Vec::new(),
            params: Some(params),
            grid: Some((n_u, n_v)),
            gravity: options.gravity,
        };
        lattice.validate()?;
        Ok(lattice)
    }

    /// A lattice from any node and spring lists, validated (see [`SpringLattice::validate`]).
    pub fn from_parts(
        positions: Vec<[f64; 3]>,
        masses: Vec<f64>,
        damping: Vec<f64>,
        fixed: Vec<bool>,
        springs: Vec<Spring>,
        gravity: [f64; 3],
    ) -> Result<Self, MsmError> {
        if positions.len() > MAX_NODES {
            return Err(MsmError::TooLarge {
                nodes: positions.len(),
            });
        }
        let lattice = Self {
            positions,
            masses,
            damping,
            fixed,
            springs,
            elements: Vec::new(),
            hinges: Vec::new(),
            triangles: Vec::new(),
            forces: Vec::new(),
            params: None,
            grid: None,
            gravity,
        };
        lattice.validate()?;
        Ok(lattice)
    }

    /// Checks the invariants every computation relies on: at least one and at most
    /// [`MAX_NODES`] nodes, per-node arrays of one length, finite positions and gravity,
    /// masses `> 0`, damping `≥ 0`, springs naming existing nodes, `k ≥ 0`, weight `> 0`,
    /// axial damping `≥ 0`, rest length `≥ 0`, every value finite, and no spring of zero length
    /// at the initial positions; hinges on four distinct existing nodes, `k ≥ 0`, weight `> 0`,
    /// rest angle in `[−π, π]`, both triangles of positive area at the initial positions;
    /// triangles on three distinct existing nodes. Also `params` and `grid`, when present,
    /// must match the number of nodes.
    pub fn validate(&self) -> Result<(), MsmError> {
        let n = self.positions.len();
        if n > MAX_NODES {
            return Err(MsmError::TooLarge { nodes: n });
        }
        if n == 0 {
            return Err(MsmError::InvalidParameter {
                name: "number of nodes".into(),
                value: 0.0,
            });
        }
        for (what, len) in [
            ("masses", self.masses.len()),
            ("damping", self.damping.len()),
            ("fixed", self.fixed.len()),
        ] {
            if len != n {
                return Err(MsmError::LengthMismatch {
                    what,
                    expected: n,
                    found: len,
                });
            }
        }
        if let Some(p) = &self.params
            && p.len() != n
        {
            return Err(MsmError::LengthMismatch {
                what: "params",
                expected: n,
                found: p.len(),
            });
        }
        if let Some((n_u, n_v)) = self.grid
            && n_u.checked_mul(n_v) != Some(n)
        {
            return Err(MsmError::LengthMismatch {
                what: "grid n_u × n_v",
                expected: n,
                found: n_u.saturating_mul(n_v),
            });
        }
        for (a, x) in self.positions.iter().enumerate() {
            if let Some(&v) = x.iter().find(|v| !representable(**v)) {
                return Err(MsmError::NonFinite {
                    what: "position of node",
                    index: a,
                    value: v,
                });
            }
        }
        for (a, &m) in self.masses.iter().enumerate() {
            if !representable(m) {
                return Err(MsmError::NonFinite {
                    what: "mass of node",
                    index: a,
                    value: m,
                });
            }
            if m <= 0.0 {
                return Err(MsmError::NonPositiveMass { node: a, mass: m });
            }
        }
        for (a, &g) in self.damping.iter().enumerate() {
            if !representable(g) {
                return Err(MsmError::NonFinite {
                    what: "damping of node",
                    index: a,
                    value: g,
                });
            }
            if g < 0.0 {
                return Err(MsmError::InvalidParameter {
                    name: format!("damping of node {a} (must be ≥ 0)"),
                    value: g,
                });
            }
        }
        if let Some(&g) = self.gravity.iter().find(|g| !representable(**g)) {
            return Err(MsmError::NonFinite {
                what: "gravity component",
                index: 0,
                value: g,
            });
        }
        for (s, spring) in self.springs.iter().enumerate() {
            for node in [spring.a, spring.b] {
                if node >= n {
                    return Err(MsmError::MissingNode {
                        of: "spring",
                        index: s,
                        node,
                        n_nodes: n,
                    });
                }
            }
            if !representable(spring.k) {
                return Err(MsmError::NonFinite {
                    what: "stiffness of spring",
                    index: s,
                    value: spring.k,
                });
            }
            if spring.k < 0.0 {
                return Err(MsmError::NegativeStiffness {
                    spring: s,
                    k: spring.k,
                });
            }
            if !representable(spring.rest_length) {
                return Err(MsmError::NonFinite {
                    what: "rest length of spring",
                    index: s,
                    value: spring.rest_length,
                });
            }
            if spring.rest_length < 0.0 {
                return Err(MsmError::InvalidParameter {
                    name: format!("rest length of spring {s} (must be ≥ 0)"),
                    value: spring.rest_length,
                });
            }
            if !(representable(spring.weight) && spring.weight > 0.0) {
                return Err(MsmError::InvalidParameter {
                    name: format!("weight of spring {s} (must be in (0, 1e30])"),
                    value: spring.weight,
                });
            }
            if !(representable(spring.damping) && spring.damping >= 0.0) {
                return Err(MsmError::InvalidParameter {
                    name: format!("axial damping of spring {s} (must be in [0, 1e30])"),
                    value: spring.damping,
                });
            }
            let d = sub(self.positions[spring.a], self.positions[spring.b]);
            if d == [0.0; 3] {
                return Err(MsmError::ZeroLengthSpring {
                    spring: s,
                    a: spring.a,
                    b: spring.b,
                });
            }
        }
        for (e, el) in self.elements.iter().enumerate() {
            let bad = |what: String, value: f64| MsmError::InvalidElement {
                element: e,
                what,
                value,
            };
            if !(2..=4).contains(&el.nodes.len()) || el.coefficients.len() != el.nodes.len() {
                return Err(bad(
                    format!(
                        "{} nodes and {} coefficients (2 to 4 nodes, one coefficient each)",
                        el.nodes.len(),
                        el.coefficients.len()
                    ),
                    el.nodes.len() as f64,
                ));
            }
            for (i, &a) in el.nodes.iter().enumerate() {
                if a >= n {
                    return Err(MsmError::MissingNode {
                        of: "linear element",
                        index: e,
                        node: a,
                        n_nodes: n,
                    });
                }
                if el.nodes[..i].contains(&a) {
                    return Err(bad(format!("node {a} listed twice"), a as f64));
                }
            }
            if let Some(&c) = el.coefficients.iter().find(|c| !representable(**c)) {
                return Err(bad("coefficient (must be finite, |c| ≤ 1e30)".into(), c));
            }
            if !(representable(el.weight) && el.weight > 0.0) {
                return Err(bad("weight (must be in (0, 1e30])".into(), el.weight));
            }
            if !(representable(el.k) && el.k >= 0.0) {
                return Err(bad("constant k (must be in [0, 1e30])".into(), el.k));
            }
        }
        for (i, h) in self.hinges.iter().enumerate() {
            let bad = |what: String, value: f64| MsmError::InvalidHinge {
                hinge: i,
                what,
                value,
            };
            for (slot, &a) in h.nodes.iter().enumerate() {
                if a >= n {
                    return Err(MsmError::MissingNode {
                        of: "hinge",
                        index: i,
                        node: a,
                        n_nodes: n,
                    });
                }
                if h.nodes[..slot].contains(&a) {
                    return Err(bad(format!("nodes (node {a} listed twice)"), a as f64));
                }
            }
            if !(representable(h.k) && h.k >= 0.0) {
                return Err(bad("constant k (must be in [0, 1e30])".into(), h.k));
            }
            if !(representable(h.weight) && h.weight > 0.0) {
                return Err(bad("weight (must be in (0, 1e30])".into(), h.weight));
            }
            if h.rest_angle.is_nan() || h.rest_angle.abs() > std::f64::consts::PI {
                return Err(bad(
                    "rest_angle (radians, must be in [-pi, pi])".into(),
                    h.rest_angle,
                ));
            }
            let x = h.nodes.map(|a| self.positions[a]);
            if !angle(&x).is_finite() || degenerate(&x) {
                return Err(bad(
                    "triangles (one of its two triangles has zero area at the initial positions)"
                        .into(),
                    f64::NAN,
                ));
            }
        }
        for (i, t) in self.triangles.iter().enumerate() {
            for (slot, &a) in t.iter().enumerate() {
                if a >= n {
                    return Err(MsmError::MissingNode {
                        of: "triangle",
                        index: i,
                        node: a,
                        n_nodes: n,
                    });
                }
                if t[..slot].contains(&a) {
                    return Err(MsmError::InvalidParameter {
                        name: format!("triangle {i}: node {a} listed twice"),
                        value: a as f64,
                    });
                }
            }
        }
        if !self.forces.is_empty() && self.forces.len() != n {
            return Err(MsmError::LengthMismatch {
                what: "node forces",
                expected: n,
                found: self.forces.len(),
            });
        }
        if let Some((a, &v)) = self
            .forces
            .iter()
            .enumerate()
            .find_map(|(a, f)| f.iter().find(|x| !representable(**x)).map(|v| (a, v)))
        {
            return Err(MsmError::NonFinite {
                what: "force on node",
                index: a,
                value: v,
            });
        }
        Ok(())
    }

    /// Number of nodes N.
    pub fn n_nodes(&self) -> usize {
        self.positions.len()
    }

    /// Number of coordinates, `3 N`.
    pub fn n_dofs(&self) -> usize {
        3 * self.positions.len()
    }

    /// The classes with at least one element, ascending.
    pub fn classes(&self) -> Vec<Class> {
        let mut out: Vec<Class> = self
            .springs
            .iter()
            .map(|s| Class::Spring(s.kind))
            .chain(self.elements.iter().map(LinearElement::class))
            .chain(self.hinges.iter().map(|h| Class::Hinge(h.kind)))
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Number of elements of a class.
    pub fn count(&self, class: Class) -> usize {
        match class {
            Class::Spring(kind) => self.springs.iter().filter(|s| s.kind == kind).count(),
            Class::Linear(..) => self.elements.iter().filter(|e| e.class() == class).count(),
            Class::Hinge(kind) => self.hinges.iter().filter(|h| h.kind == kind).count(),
        }
    }

    /// Number of springs, hinges and linear elements.
    pub fn n_elements(&self) -> usize {
        self.springs.len() + self.hinges.len() + self.elements.len()
    }

    /// The weights of the elements of `class`, in the order they appear in the lattice's list
    /// of springs, hinges or linear elements.
    pub fn weights(&self, class: Class) -> Vec<f64> {
        match class {
            Class::Spring(kind) => self
                .springs
                .iter()
                .filter(|s| s.kind == kind)
                .map(|s| s.weight)
                .collect(),
            Class::Hinge(kind) => self
                .hinges
                .iter()
                .filter(|h| h.kind == kind)
                .map(|h| h.weight)
                .collect(),
            Class::Linear(..) => self
                .elements
                .iter()
                .filter(|e| e.class() == class)
                .map(|e| e.weight)
                .collect(),
        }
    }

    /// Sets the weights of the elements of `class` (one per element, in the order of
    /// [`SpringLattice::weights`]): element `e` then has the stiffness `k_c w_e`, so the
    /// tangent stays `Σ_c k_c G_c` with the weights inside `G_c` (docs/math.md §5). Refused
    /// (and nothing changed) when the count differs or a weight is not finite and positive.
    ///
    /// ```
    /// use nurbspring_msm::{Class, SpringKind, SpringLattice, Spring};
    /// let mut l = SpringLattice::from_parts(vec![[0.; 3], [1., 0., 0.]], vec![1.; 2], vec![0.; 2],
    ///     vec![false; 2], vec![Spring::new(0, 1, SpringKind::Structural, 3.0, 1.0)], [0.; 3]).unwrap();
    /// l.set_weights(Class::Spring(SpringKind::Structural), &[0.5]).unwrap();
    /// assert_eq!(l.springs[0].stiffness(), 1.5);
    /// assert!(l.set_weights(Class::Spring(SpringKind::Structural), &[0.0]).is_err());
    /// ```
    pub fn set_weights(&mut self, class: Class, weights: &[f64]) -> Result<(), MsmError> {
        let count = self.count(class);
        if weights.len() != count {
            return Err(MsmError::WeightCount {
                class: class.name(),
                expected: count,
                found: weights.len(),
            });
        }
        if let Some((i, &w)) = weights
            .iter()
            .enumerate()
            .find(|(_, w)| !(representable(**w) && **w > 0.0))
        {
            return Err(MsmError::InvalidParameter {
                name: format!(
                    "weight {i} of class {} (must be in (0, 1e30])",
                    class.name()
                ),
                value: w,
            });
        }
        let mut w = weights.iter();
        match class {
            Class::Spring(kind) => {
                for s in self.springs.iter_mut().filter(|s| s.kind == kind) {
                    s.weight = *w.next().expect("counted");
                }
            }
            Class::Hinge(kind) => {
                for h in self.hinges.iter_mut().filter(|h| h.kind == kind) {
                    h.weight = *w.next().expect("counted");
                }
            }
            Class::Linear(..) => {
                for e in self.elements.iter_mut().filter(|e| e.class() == class) {
                    e.weight = *w.next().expect("counted");
                }
            }
        }
        Ok(())
    }

    /// Sets the axial damping `c` (docs/math.md §5.1) of every spring of `kind` (`None`:
    /// every spring); not validated here, [`crate::MsmModel::new`] validates.
    pub fn set_axial_damping(&mut self, kind: Option<SpringKind>, c: f64) {
        for s in &mut self.springs {
            if kind.is_none_or(|k| k == s.kind) {
                s.damping = c;
            }
        }
    }

    /// Sets the constant of every element of each class in `constants` (classes not in it are
    /// left alone; not validated here, [`crate::MsmModel::new`] validates).
    pub fn set_constants(&mut self, constants: &Constants) {
        for s in &mut self.springs {
            if let Some(k) = constants.get(Class::Spring(s.kind)) {
                s.k = k;
            }
        }
        for e in &mut self.elements {
            if let Some(k) = constants.get(e.class()) {
                e.k = k;
            }
        }
        for h in &mut self.hinges {
            if let Some(k) = constants.get(Class::Hinge(h.kind)) {
                h.k = k;
            }
        }
    }

    /// The constants of the classes present, read from the first element of each (the
    /// lattice's own constants when every element of a class shares one).
    pub fn constants(&self) -> Constants {
        let mut out = Constants::new();
        for s in self.springs.iter().rev() {
            out.set(Class::Spring(s.kind), s.k);
        }
        for e in self.elements.iter().rev() {
            out.set(e.class(), e.k);
        }
        for h in self.hinges.iter().rev() {
            out.set(Class::Hinge(h.kind), h.k);
        }
        out
    }

    /// The scalar `N × N` matrix `L = Σ_e k_e w_e c_e c_eᵀ` of the linear elements of `class`
    /// with unit constants (`class = None`: every element with its own constant), so that
    /// their stiffness is `L ⊗ I₃` (docs/math.md §8).
    pub fn linear_matrix(&self, class: Option<Class>) -> SparseMatrix {
        let mut triplets = Vec::new();
        for e in &self.elements {
            let scale = match class {
                None => e.k * e.weight,
                Some(c) if c == e.class() => e.weight,
                Some(_) => continue,
            };
            for (&a, &ca) in e.nodes.iter().zip(&e.coefficients) {
                for (&b, &cb) in e.nodes.iter().zip(&e.coefficients) {
                    triplets.push((a, b, scale * ca * cb));
                }
            }
        }
        let n = self.n_nodes();
        SparseMatrix::from_triplets(n, n, &triplets).expect("element nodes are validated")
    }

    /// Displacements `x − x(0)`, interleaved.
    fn displacements(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(self.positions.iter().flatten())
            .map(|(a, b)| a - b)
            .collect()
    }

    /// Sets every node mass to `m` (not validated here).
    pub fn set_mass(&mut self, m: f64) {
        self.masses.fill(m);
    }

    /// Sets one mass per node, validated (length, `> 0`, finite).
    pub fn set_masses(&mut self, masses: Vec<f64>) -> Result<(), MsmError> {
        let old = std::mem::replace(&mut self.masses, masses);
        if let Err(e) = self.validate() {
            self.masses = old;
            return Err(e);
        }
        Ok(())
    }

    /// Sets every node's damping factor `γ` (force `−γ ẋ`, docs/math.md §5; not validated here).
    pub fn set_damping(&mut self, gamma: f64) {
        self.damping.fill(gamma);
    }

    /// The node nearest to parameter `(u, v)`: by parameter distance when `params` exist; else,
    /// on a grid, node `(round(u (n_u − 1)), round(v (n_v − 1)))` for `u, v ∈ [0, 1]`; else the
    /// node nearest in the x-y plane to the point at fractions `(u, v)` of the nodes'
    /// bounding box. Ties go to the lower index.
    pub fn node_nearest(&self, u: f64, v: f64) -> usize {
        if let Some(params) = &self.params {
            return argmin(
                params
                    .iter()
                    .map(|&(pu, pv)| (pu - u).powi(2) + (pv - v).powi(2)),
            );
        }
        if let Some((n_u, n_v)) = self.grid {
            let i = (u.clamp(0.0, 1.0) * (n_u - 1) as f64).round() as usize;
            let j = (v.clamp(0.0, 1.0) * (n_v - 1) as f64).round() as usize;
            return i.min(n_u - 1) * n_v + j.min(n_v - 1);
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for x in &self.positions {
            for c in 0..2 {
                lo[c] = lo[c].min(x[c]);
                hi[c] = hi[c].max(x[c]);
            }
        }
        let target = [lo[0] + u * (hi[0] - lo[0]), lo[1] + v * (hi[1] - lo[1])];
        argmin(
            self.positions
                .iter()
                .map(|x| (x[0] - target[0]).powi(2) + (x[1] - target[1]).powi(2)),
        )
    }

    /// Indices of the fixed nodes, ascending.
    pub fn fixed_nodes(&self) -> Vec<usize> {
        (0..self.n_nodes()).filter(|&a| self.fixed[a]).collect()
    }

    /// The fixed coordinates `3a, 3a + 1, 3a + 2` of every fixed node `a`, ascending.
    pub fn fixed_dofs(&self) -> Vec<usize> {
        self.fixed_nodes()
            .into_iter()
            .flat_map(|a| [3 * a, 3 * a + 1, 3 * a + 2])
            .collect()
    }

    /// Initial positions as one interleaved vector `[x_0, y_0, z_0, x_1, …]`.
    pub fn flat_positions(&self) -> Vec<f64> {
        self.positions.iter().flatten().copied().collect()
    }

    /// External forces: gravity `m_a g` (paper eq. (6)) plus the node forces, full `3N`
    /// vector.
    pub fn gravity_forces(&self) -> Vec<f64> {
        self.masses
            .iter()
            .enumerate()
            .flat_map(|(a, &m)| {
                let f = self.forces.get(a).copied().unwrap_or([0.0; 3]);
                [0, 1, 2].map(|x| m * self.gravity[x] + f[x])
            })
            .collect()
    }

    /// The elastic forces of paper eq. (5) summed per node at positions `x` (length `3N`,
    /// interleaved) into `out` (overwritten): `f_a = Σ_b k w (l − |d|) d/|d|`, `d = x_a − x_b`,
    /// plus the hinges' `−k w (θ − θ0) ∂θ/∂x_a` (docs/math.md §5.2) and the linear elements.
    /// This is the restoring force `−∇E`. Panics when a length is not `3N`.
    ///
    /// ```
    /// use nurbspring_msm::{Spring, SpringKind, SpringLattice};
    /// let s = Spring::new(0, 1, SpringKind::Structural, 4.0, 1.0);
    /// let lattice = SpringLattice::from_parts(vec![[0.; 3], [1., 0., 0.]], vec![1.; 2], vec![0.; 2], vec![false; 2], vec![s], [0.; 3]).unwrap();
    /// let mut f = vec![0.0; 6];
    /// lattice.elastic_forces(&[0., 0., 0., 1.5, 0., 0.], &mut f);  // stretched by 0.5
    /// assert_eq!(f, vec![2., 0., 0., -2., 0., 0.]);
    /// ```
    pub fn elastic_forces(&self, x: &[f64], out: &mut [f64]) {
        let n3 = self.n_dofs();
        assert_eq!(x.len(), n3, "positions: expected {n3} entries");
        assert_eq!(out.len(), n3, "forces: expected {n3} entries");
        out.fill(0.0);
        for s in &self.springs {
            let f = s.force_on_a(x);
            for c in 0..3 {
                out[3 * s.a + c] += f[c];
                out[3 * s.b + c] -= f[c];
            }
        }
        for h in &self.hinges {
            let f = h.forces(x);
            for (&a, fa) in h.nodes.iter().zip(&f) {
                for c in 0..3 {
                    out[3 * a + c] += fa[c];
                }
            }
        }
        if !self.elements.is_empty() {
            let u = self.displacements(x);
            for e in &self.elements {
                let s = e.strain(&u);
                for (&a, &c) in e.nodes.iter().zip(&e.coefficients) {
                    for x in 0..3 {
                        out[3 * a + x] -= e.k * e.weight * c * s[x];
                    }
                }
            }
        }
    }

    /// Elastic energy `E = Σ k w (|d| − l)² / 2 + Σ ½ k w (θ − θ0)²` plus the linear elements'
    /// at positions `x` (docs/math.md §5). Panics when `x.len() ≠ 3N`.
    pub fn elastic_energy(&self, x: &[f64]) -> f64 {
        assert_eq!(
            x.len(),
            self.n_dofs(),
            "positions: expected {} entries",
            self.n_dofs()
        );
        let springs: f64 = self.springs.iter().map(|s| s.energy(x)).sum::<f64>()
            + self.hinges.iter().map(|h| h.energy(x)).sum::<f64>();
        if self.elements.is_empty() {
            return springs;
        }
        let u = self.displacements(x);
        springs + self.elements.iter().map(|e| e.energy(&u)).sum::<f64>()
    }

    /// The tangent stiffness `K_T = −∂f_elastic/∂x` at `x`, full `3N × 3N` (paper eqs. (9)–(10),
    /// docs/math.md §5): for each spring the block `B = k w [ (l/|d|) n nᵀ + (1 − l/|d|) I ]`
    /// enters `(a, a)`, `(b, b)` with `+` and `(a, b)`, `(b, a)` with `−`; each hinge adds its
    /// Hessian `k w (∇θ ∇θᵀ + (θ − θ0) ∇²θ)` (§5.2). The pattern holds a full 3 × 3 block for
    /// every node and every pair joined by a spring or sharing a hinge (explicit zeros kept),
    /// the same at every `x`. Panics when `x.len() ≠ 3N`.
    pub fn tangent_stiffness(&self, x: &[f64]) -> SparseMatrix {
        assert_eq!(
            x.len(),
            self.n_dofs(),
            "positions: expected {} entries",
            self.n_dofs()
        );
        let topology = Topology::all_nodes(self);
        let pattern = topology.pattern();
        let mut k = pattern.template.clone();
        topology.fill(&pattern, x, &Coefficient::Stiffness, k.values_mut());
        if self.elements.is_empty() {
            return k;
        }
        let l = self.linear_matrix(None).kron_identity(3);
        SparseMatrix::linear_combination(1.0, &k, 1.0, &l).expect("both are 3N × 3N")
    }

    /// The unit-stiffness matrix `G_c` of one class at `x`: the tangent stiffness of the
    /// elements of `class` with `k = 1` and their own weights (for springs the geometric term
    /// included, both terms of eq. (9) being proportional to `k`; for hinges
    /// `w (∇θ ∇θᵀ + (θ − θ0) ∇²θ)`, which at rest is `w ∇θ ∇θᵀ`). When every element of class
    /// `c` has constant `k_c`, `K_T = Σ_c k_c G_c` (docs/math.md §5). Same pattern as
    /// [`SpringLattice::tangent_stiffness`].
    ///
    /// ```
    /// use nurbspring_msm::{Class, Hinge, HingeKind, SpringLattice};
    /// // One flat hinge, edge along x of length 1, wings at heights 1: at rest
    /// // G = w ∇θ ∇θᵀ, whose only non-zero entries are in z.
    /// let x = vec![[0., 0., 0.], [1., 0., 0.], [0.5, 1., 0.], [0.5, -1., 0.]];
    /// let mut l = SpringLattice::from_parts(x, vec![1.; 4], vec![0.; 4], vec![false; 4], vec![], [0.; 3]).unwrap();
    /// l.hinges.push(Hinge { nodes: [0, 1, 2, 3], kind: HingeKind::Grid, k: 5.0, weight: 2.0, rest_angle: 0.0 });
    /// let g = l.unit_stiffness(Class::Hinge(HingeKind::Grid), &l.flat_positions());
    /// // ∂θ/∂z of wing 2 is −1/h = −1: G(8, 8) = w · 1 = 2.
    /// assert!((g.get(8, 8) - 2.0).abs() < 1e-15 && g.get(6, 6) == 0.0);
    /// ```
    pub fn unit_stiffness(&self, class: Class, x: &[f64]) -> SparseMatrix {
        if let Class::Linear(..) = class {
            return self.linear_matrix(Some(class)).kron_identity(3);
        }
        assert_eq!(
            x.len(),
            self.n_dofs(),
            "positions: expected {} entries",
            self.n_dofs()
        );
        let topology = Topology::all_nodes(self);
        let pattern = topology.pattern();
        let mut g = pattern.template.clone();
        topology.fill(&pattern, x, &Coefficient::Unit(class), g.values_mut());
        g
    }

    /// The hinges' dihedral angles `θ` at `x` (interleaved), in the order of
    /// [`SpringLattice::hinges`].
    pub fn hinge_angles(&self, x: &[f64]) -> Vec<f64> {
        self.hinges.iter().map(|h| h.angle(x)).collect()
    }

    /// Current spring lengths at `x`.
    pub fn spring_lengths(&self, x: &[f64]) -> Vec<f64> {
        self.springs.iter().map(|s| s.length(x)).collect()
    }
}

fn argmin(values: impl Iterator<Item = f64>) -> usize {
    let mut best = (0, f64::INFINITY);
    for (i, d) in values.enumerate() {
        if d < best.1 {
            best = (i, d);
        }
    }
    best.0
}

impl ParameterGrid {
    /// The node parameters along u and along v on `surface` (the lattice is their tensor
    /// product, node `a = i · n_v + j`). Errors: a uniform grid with fewer than 2 nodes along
    /// a direction, or more than [`MAX_NODES`] nodes.
    pub fn parameters(&self, surface: &NurbsSurface) -> Result<(Vec<f64>, Vec<f64>), MsmError> {
        let us = self.axis(surface.basis_u().knots(), "nodes_u")?;
        let vs = self.axis(surface.basis_v().knots(), "nodes_v")?;
        let total = us.len().saturating_mul(vs.len());
        if total > MAX_NODES {
            return Err(MsmError::TooLarge { nodes: total });
        }
        Ok((us, vs))
    }

    /// The node parameters along one direction with knot vector `knots`: its distinct knots,
    /// its Greville abscissae (repeated values merged), or `nodes_u` uniform values (a curve
    /// uses only `nodes_u`).
    pub fn parameters_along(&self, knots: &KnotVector) -> Result<Vec<f64>, MsmError> {
        self.axis(knots, "nodes_u")
    }

    /// The parameters along the direction whose uniform count is the field `name`.
    fn axis(&self, knots: &KnotVector, name: &str) -> Result<Vec<f64>, MsmError> {
        let out = match *self {
            ParameterGrid::Knots => knots.distinct(),
            ParameterGrid::Greville => {
                let mut g = knots.greville();
                g.dedup();
                g
            }
            ParameterGrid::Uniform { nodes_u, nodes_v } => {
                let n = if name == "nodes_v" { nodes_v } else { nodes_u };
                if n < 2 {
                    return Err(MsmError::InvalidOption {
                        name: name.to_string(),
                        value: n as f64,
                        rule: "a uniform lattice needs at least 2 nodes along each direction",
                    });
                }
                if n > MAX_NODES {
                    return Err(MsmError::TooLarge { nodes: n });
                }
                let (a, b) = knots.domain();
                nurbspring_geom::linspace(a, b, n)
            }
        };
        Ok(out)
    }
}

/// The fixed nodes of a lattice on `surface` at the parameters `us × vs` (the rule of
/// [`SpringLattice::from_surface`]).
fn surface_fixed(
    surface: &NurbsSurface,
    options: &LatticeOptions,
    us: &[f64],
    vs: &[f64],
    fixed_control_points: &[usize],
) -> Result<Vec<bool>, MsmError> {
    let n = us.len() * vs.len();
    match &options.fixed {
        FixedNodes::Auto
            if options.grid == ParameterGrid::Greville
                && (us.len(), vs.len()) == (surface.n_u(), surface.n_v()) =>
        {
            control_point_fixed(n, fixed_control_points)
        }
        FixedNodes::Auto => auto_fixed(surface, us, vs, fixed_control_points),
        FixedNodes::List(list) => listed_fixed(n, list),
    }
}

/// True when a triangle of the hinge at `x` has zero area or its edge zero length.
fn degenerate(x: &[[f64; 3]; 4]) -> bool {
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let e = sub(x[1], x[0]);
    let n1 = cross(e, sub(x[2], x[0]));
    let n2 = cross(sub(x[3], x[0]), e);
    e == [0.0; 3] || n1 == [0.0; 3] || n2 == [0.0; 3]
}

/// The triangles of an `n_u × n_v` grid (node `i · n_v + j`), two per cell, cell `(i, j)` cut
/// along `(i, j)–(i+1, j+1)` when `i + j` is even and along `(i+1, j)–(i, j+1)` otherwise;
/// each triangle counter-clockwise in the `(u, v)` plane. Cells in node order, the triangle
/// below the diagonal first.
///
/// ```
/// use nurbspring_msm::grid_triangles;
/// // 2 × 3 nodes, two cells: the first cut along (0,0)–(1,1), the second along (1,1)–(0,2).
/// assert_eq!(grid_triangles(2, 3), vec![[0, 3, 4], [0, 4, 1], [1, 4, 2], [4, 5, 2]]);
/// ```
pub fn grid_triangles(n_u: usize, n_v: usize) -> Vec<[usize; 3]> {
    let idx = |i: usize, j: usize| i * n_v + j;
    let mut out = Vec::with_capacity(2 * n_u.saturating_sub(1) * n_v.saturating_sub(1));
    for i in 0..n_u.saturating_sub(1) {
        for j in 0..n_v.saturating_sub(1) {
            let (p00, p10, p11, p01) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            if (i + j) % 2 == 0 {
                out.push([p00, p10, p11]);
                out.push([p00, p11, p01]);
            } else {
                out.push([p00, p10, p01]);
                out.push([p10, p11, p01]);
            }
        }
    }
    out
}

/// Springs on the edges of [`grid_triangles`]: structural `(i, j)–(i, j+1)` and
/// `(i, j)–(i+1, j)`, then one shear spring per cell on its diagonal, then bending springs as
/// in `grid_springs`; each group in node order, each class when `o.constants` holds it.
fn triangulated_springs(
    n_u: usize,
    n_v: usize,
    o: &LatticeOptions,
    positions: &[[f64; 3]],
) -> Vec<Spring> {
    let idx = |i: usize, j: usize| i * n_v + j;
    let mut springs = grid_springs(n_u, n_v, &without_shear(o), positions);
    if !o.constants.contains(Class::Spring(SpringKind::Shear)) {
        return springs;
    }
    let k = o.constants.value(Class::Spring(SpringKind::Shear));
    let scale = 1.0 - o.pre_strain;
    let mut shear = Vec::new();
    for i in 0..n_u.saturating_sub(1) {
        for j in 0..n_v.saturating_sub(1) {
            let (a, b) = if (i + j) % 2 == 0 {
                (idx(i, j), idx(i + 1, j + 1))
            } else {
                (idx(i + 1, j), idx(i, j + 1))
            };
            let l = crate::spring::norm(sub(positions[a], positions[b]));
            shear.push(Spring::new(a, b, SpringKind::Shear, k, scale * l));
        }
    }
    // Structural first, then shear, then bending (the order of `grid_springs`).
    let split = springs
        .iter()
        .position(|s| s.kind == SpringKind::Bend)
        .unwrap_or(springs.len());
    springs.splice(split..split, shear);
    springs
}

/// `o` without its shear class.
fn without_shear(o: &LatticeOptions) -> LatticeOptions {
    let mut o = o.clone();
    o.constants.remove(Class::Spring(SpringKind::Shear));
    o
}

/// A hinge on every edge shared by two of `triangles` (consistently oriented), of kind
/// [`HingeKind::Grid`] on a grid line of the `· × n_v` grid and [`HingeKind::Diagonal`]
/// otherwise, each kind when `constants` holds it, with the rest angle of `positions`;
/// sorted by kind, then by the edge's nodes.
fn triangle_hinges(
    triangles: &[[usize; 3]],
    n_v: usize,
    positions: &[[f64; 3]],
    constants: &Constants,
) -> Vec<Hinge> {
    use std::collections::HashMap;
    // Edge (low, high) → (from, to, opposite node) of the first triangle holding it.
    let mut first: HashMap<(usize, usize), (usize, usize, usize)> = HashMap::new();
    let mut hinges = Vec::new();
    for t in triangles {
        for c in 0..3 {
            let (from, to, opposite) = (t[c], t[(c + 1) % 3], t[(c + 2) % 3]);
            let key = (from.min(to), from.max(to));
            match first.remove(&key) {
                None => {
                    first.insert(key, (from, to, opposite));
                }
                Some((f0, t0, o0)) => {
                    debug_assert_eq!((f0, t0), (to, from), "consistently oriented triangles");
                    let on_grid_line = f0 / n_v == t0 / n_v || f0 % n_v == t0 % n_v;
                    let kind = if on_grid_line {
                        HingeKind::Grid
                    } else {
                        HingeKind::Diagonal
                    };
                    let Some(k) = constants.get(Class::Hinge(kind)) else {
                        continue;
                    };
                    let nodes = [f0, t0, o0, opposite];
                    hinges.push(Hinge {
                        nodes,
                        kind,
                        k,
                        weight: 1.0,
                        rest_angle: angle(&nodes.map(|a| positions[a])),
                    });
                }
            }
        }
    }
    hinges.sort_by_key(|h| {
        let [a, b, ..] = h.nodes;
        (h.kind, a.min(b), a.max(b))
    });
    hinges
}

/// The fixed flags of an explicit node list.
fn listed_fixed(n: usize, list: &[usize]) -> Result<Vec<bool>, MsmError> {
    let mut fixed = vec![false; n];
    for (position, &node) in list.iter().enumerate() {
        if node >= n {
            return Err(MsmError::FixedNodeOutside {
                position,
                node,
                n_nodes: n,
            });
        }
        fixed[node] = true;
    }
    Ok(fixed)
}

/// One node per control point (the Greville lattice): node `a` is fixed iff control point `a`
/// is.
fn control_point_fixed(n: usize, fixed_control_points: &[usize]) -> Result<Vec<bool>, MsmError> {
    let mut fixed = vec![false; n];
    for &k in fixed_control_points {
        match fixed.get_mut(k) {
            Some(f) => *f = true,
            None => {
                return Err(MsmError::InvalidParameter {
                    name: format!("fixed control point index (the net has {n} control points)"),
                    value: k as f64,
                });
            }
        }
    }
    Ok(fixed)
}

/// Indices of the basis functions non-zero at `t`.
fn support(basis: &nurbspring_geom::BSplineBasis, t: f64) -> Result<Vec<usize>, MsmError> {
    let (span, values) = basis.values(t)?;
    let p = basis.degree();
    Ok(values
        .iter()
        .enumerate()
        .filter(|(_, v)| v.abs() > BASIS_ZERO)
        .map(|(a, _)| span - p + a)
        .collect())
}

/// docs/math.md §5 fixed rule on a tensor grid: node `(i, j)` is fixed when every control point
/// `(k, l)` with `N_k(u_i) ≠ 0` and `N_l(v_j) ≠ 0` is fixed (weights are positive, so the
/// rational basis value `R_kl` is non-zero exactly when `N_k N_l` is).
fn auto_fixed(
    surface: &NurbsSurface,
    us: &[f64],
    vs: &[f64],
    fixed_control_points: &[usize],
) -> Result<Vec<bool>, MsmError> {
    let n = us.len() * vs.len();
    if fixed_control_points.is_empty() {
        return Ok(vec![false; n]);
    }
    let n_cp = surface.n_control_points();
    let mut cp_fixed = vec![false; n_cp];
    for &k in fixed_control_points {
        if k >= n_cp {
            return Err(MsmError::InvalidParameter {
                name: format!("fixed control point index (the surface has {n_cp} control points)"),
                value: k as f64,
            });
        }
        cp_fixed[k] = true;
    }
    let su: Vec<Vec<usize>> = us
        .iter()
        .map(|&u| support(surface.basis_u(), u))
        .collect::<Result<_, _>>()?;
    let sv: Vec<Vec<usize>> = vs
        .iter()
        .map(|&v| support(surface.basis_v(), v))
        .collect::<Result<_, _>>()?;
    let n_v_cp = surface.n_v();
    let mut fixed = Vec::with_capacity(n);
    for ku in &su {
        for kv in &sv {
            fixed.push(
                ku.iter()
                    .all(|&k| kv.iter().all(|&l| cp_fixed[k * n_v_cp + l])),
            );
        }
    }
    Ok(fixed)
}

/// Springs on an `n_u × n_v` grid: structural `(i, j)–(i, j+1)` and `(i, j)–(i+1, j)`, then
/// shear `(i, j)–(i+1, j+1)` and `(i+1, j)–(i, j+1)`, then bending `(i, j)–(i, j+2)` and
/// `(i, j)–(i+2, j)`; each group in node order.
fn grid_springs(n_u: usize, n_v: usize, o: &LatticeOptions, positions: &[[f64; 3]]) -> Vec<Spring> {
    let idx = |i: usize, j: usize| i * n_v + j;
    let has = |kind| o.constants.contains(Class::Spring(kind));
    let mut pairs: Vec<(usize, usize, SpringKind)> = Vec::new();
    if has(SpringKind::Structural) {
        for i in 0..n_u {
            for j in 0..n_v {
                if j + 1 < n_v {
                    pairs.push((idx(i, j), idx(i, j + 1), SpringKind::Structural));
                }
                if i + 1 < n_u {
                    pairs.push((idx(i, j), idx(i + 1, j), SpringKind::Structural));
                }
            }
        }
    }
    if has(SpringKind::Shear) {
        for i in 0..n_u.saturating_sub(1) {
            for j in 0..n_v.saturating_sub(1) {
                pairs.push((idx(i, j), idx(i + 1, j + 1), SpringKind::Shear));
                pairs.push((idx(i + 1, j), idx(i, j + 1), SpringKind::Shear));
            }
        }
    }
    if has(SpringKind::Bend) {
        for i in 0..n_u {
            for j in 0..n_v {
                if j + 2 < n_v {
                    pairs.push((idx(i, j), idx(i, j + 2), SpringKind::Bend));
                }
                if i + 2 < n_u {
                    pairs.push((idx(i, j), idx(i + 2, j), SpringKind::Bend));
                }
            }
        }
    }
    let scale = 1.0 - o.pre_strain;
    pairs
        .into_iter()
        .map(|(a, b, kind)| {
            let k = o.constants.value(Class::Spring(kind));
            let length = crate::spring::norm(sub(positions[a], positions[b]));
            Spring::new(a, b, kind, k, scale * length)
        })
        .collect()
}
