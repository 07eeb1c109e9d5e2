//! Spring lattices: from a NURBS surface (docs/math.md §5, paper Figure 1 and eq. (19)) or from any
//! node and spring lists.

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::representable;

use crate::element::grid_elements;
use crate::spring::sub;
use crate::stiffness::Coefficient;
use crate::topology::Topology;
use crate::{
    Class, Constants, LinearElement, LinearKind, MAX_NODES, MsmError, Region, Spring, SpringKind,
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
/// springs between them, and linear isotropic elements (docs/math.md §8).
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
        let fixed = match &options.fixed {
            FixedNodes::Auto
                if options.grid == ParameterGrid::Greville
                    && (us.len(), vs.len()) == (surface.n_u(), surface.n_v()) =>
            {
                control_point_fixed(n, fixed_control_points)?
            }
            FixedNodes::Auto => auto_fixed(surface, &us, &vs, fixed_control_points)?,
            FixedNodes::List(list) => listed_fixed(n, list)?,
        };
        Self::on_grid(&us, &vs, positions, fixed, options)
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
    /// masses `> 0`, damping `≥ 0`, springs naming existing nodes, `k ≥ 0`, rest length `≥ 0`,
    /// every value finite, and no spring of zero length at the initial positions. Also
    /// `params` and `grid`, when present, must match the number of nodes.
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
        }
    }

    /// Number of springs and linear elements.
    pub fn n_elements(&self) -> usize {
        self.springs.len() + self.elements.len()
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
    /// interleaved) into `out` (overwritten): `f_a = Σ_b k (l − |d|) d/|d|`, `d = x_a − x_b`.
    /// This is the restoring force `−∇E`. Panics when a length is not `3N`.
    ///
    /// ```
    /// use nurbspring_msm::{Spring, SpringKind, SpringLattice};
    /// let s = Spring { a: 0, b: 1, kind: SpringKind::Structural, k: 4.0, rest_length: 1.0 };
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

    /// Elastic energy `E = Σ k (|d| − l)² / 2` at positions `x` (docs/math.md §5). Panics when
    /// `x.len() ≠ 3N`.
    pub fn elastic_energy(&self, x: &[f64]) -> f64 {
        assert_eq!(
            x.len(),
            self.n_dofs(),
            "positions: expected {} entries",
            self.n_dofs()
        );
        let springs: f64 = self.springs.iter().map(|s| s.energy(x)).sum();
        if self.elements.is_empty() {
            return springs;
        }
        let u = self.displacements(x);
        springs + self.elements.iter().map(|e| e.energy(&u)).sum::<f64>()
    }

    /// The tangent stiffness `K_T = −∂f_elastic/∂x` at `x`, full `3N × 3N` (paper eqs. (9)–(10),
    /// docs/math.md §5): for each spring the block `B = k [ (l/|d|) n nᵀ + (1 − l/|d|) I ]` enters
    /// `(a, a)`, `(b, b)` with `+` and `(a, b)`, `(b, a)` with `−`. The pattern holds a full
    /// 3 × 3 block for every node and every pair joined by a spring (explicit zeros kept), the
    /// same at every `x`. Panics when `x.len() ≠ 3N`.
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
    /// elements of `class` with `k = 1` (for springs the geometric term included; both terms
    /// of eq. (9) are proportional to `k`). When every element of class `c` has constant `k_c`,
    /// `K_T = Σ_c k_c G_c` (docs/math.md §5). Same pattern as [`SpringLattice::tangent_stiffness`].
    pub fn unit_stiffness(&self, class: Class, x: &[f64]) -> SparseMatrix {
        let kind = match class {
            Class::Spring(kind) => kind,
            Class::Linear(..) => return self.linear_matrix(Some(class)).kron_identity(3),
        };
        assert_eq!(
            x.len(),
            self.n_dofs(),
            "positions: expected {} entries",
            self.n_dofs()
        );
        let topology = Topology::all_nodes(self);
        let pattern = topology.pattern();
        let mut g = pattern.template.clone();
        topology.fill(&pattern, x, &Coefficient::Unit(kind), g.values_mut());
        g
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
            Spring {
                a,
                b,
                kind,
                k,
                rest_length: scale * length,
            }
        })
        .collect()
}
