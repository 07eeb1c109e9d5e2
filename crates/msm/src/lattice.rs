//! Spring lattices: from a NURBS surface (docs/math.md §5, paper Figure 1 and eq. (19)) or from any
//! node and spring lists.

use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};
use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::{PointDofs, representable};

use crate::element::grid_elements;
use crate::hinge::angle;
use crate::spring::sub;
use crate::stiffness::Coefficient;
use crate::topology::Topology;

mod invariants;
mod layout;
use crate::{
    Class, Constants, Hinge, HingeKind, LinearElement, LinearKind, MAX_NODES, MsmError, Region,
    Spring, SpringKind,
};
pub use layout::grid_triangles;
use layout::*;

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
        let l = PointDofs::XYZ.expand(&self.linear_matrix(None));
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
            return PointDofs::XYZ.expand(&self.linear_matrix(Some(class)));
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
