//! Constraints (docs/math.md §4): fixed control points (by index and by outer rings), fixed weights,
//! and general linear constraints `A p = b` removed by the substitution `p = G q + g`.
//!
//! Internally every constrained model works on reduced coordinates `q` with
//! `p(q) = P q + o`: `P = E_f G` places the free dofs (`E_f`, from a [`DofMap`]: fixed dofs
//! removed, free first) through the null-space basis `G` of the linear constraints (identity
//! without them), and the offset `o` holds the fixed values and the particular solution `g`.
//! A matrix `A` becomes `Pᵀ A P`, a force `f` becomes `Pᵀ f`, and the coupling to the fixed
//! dofs moves to the right-hand side as `Pᵀ A o` (docs/math.md §4).

use nurbspring_linalg::{DenseMatrix, LinalgError, SparseMatrix, affine_solution_space};
use nurbspring_sim::DofMap;

use crate::{DnurbsError, Geometry, outer_ring_points};

/// One row of `A p = b`: `(global dof index, coefficient)` pairs and the right-hand side.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearConstraint {
    /// `(dof, coefficient)` pairs; a dof may appear more than once (coefficients add).
    pub terms: Vec<(usize, f64)>,
    /// The right-hand side b.
    pub rhs: f64,
}

/// A boundary condition along one edge of a surface's control net, resolved into held dofs
/// and linear constraints on the edge row (the control points of the edge) and the next row
/// inwards (docs/math.md §4, §10.7).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EdgeCondition {
    /// Both rows held: zero displacement and zero slope across the edge.
    Clamped,
    /// The edge row held: zero displacement, the rotation about the edge free (a hinge).
    Pinned,
    /// The components `[x, y, z]` marked `true` of the edge row held (y and z on an edge in
    /// the plane x = const: a rigid diaphragm).
    Hold([bool; 3]),
    /// A plane of symmetry through the edge, with normal `n` the direction from each edge point
    /// to its neighbour in the next row (the surface crosses the plane at right angles): every
    /// edge point stays on the plane (`n · p_a` held) and each next-row point moves with its
    /// edge point across the plane (`t · (p_b − p_a)` held for the two directions `t ⊥ n`), so
    /// the cross tangent stays normal to the plane. Exact for large deformations of a
    /// symmetric motion.
    Symmetry,
}

/// A condition on one edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeConstraint {
    /// The edge.
    pub edge: crate::Edge,
    /// The condition.
    pub condition: EdgeCondition,
}

/// Flat indices of the control points of `edge` (ascending along it) and of the next row
/// inwards, on an `n_u × n_v` net.
pub fn edge_rows(n_u: usize, n_v: usize, edge: crate::Edge) -> (Vec<usize>, Vec<usize>) {
    use crate::Edge;
    let row_u = |i: usize| (0..n_v).map(|j| i * n_v + j).collect::<Vec<_>>();
    let row_v = |j: usize| (0..n_u).map(|i| i * n_v + j).collect::<Vec<_>>();
    match edge {
        Edge::U0 => (row_u(0), row_u(1.min(n_u - 1))),
        Edge::U1 => (row_u(n_u - 1), row_u(n_u.saturating_sub(2))),
        Edge::V0 => (row_v(0), row_v(1.min(n_v - 1))),
        Edge::V1 => (row_v(n_v - 1), row_v(n_v.saturating_sub(2))),
    }
}

/// Which generalized coordinates are constrained (docs/math.md §4).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Constraints {
    /// Control points whose x, y, z are fixed at their initial values.
    pub fixed_points: Vec<usize>,
    /// Fix the control points of this many outer rings of the net (curves: end points).
    pub fixed_rings: usize,
    /// With weights as unknowns: keep every weight at its initial value.
    pub fixed_weights: bool,
    /// With weights as unknowns and `fixed_weights = false`: keep the weights of the fixed
    /// control points at their initial values too (default `false`: a fixed point fixes its
    /// x, y, z only and its weight stays free; docs/math.md §4).
    pub fixed_point_weights: bool,
    /// General linear constraints `A p = b` on the full generalized coordinates.
    pub linear: Vec<LinearConstraint>,
    /// Conditions along edges of a surface.
    pub edges: Vec<EdgeConstraint>,
}

/// The null-space substitution of the linear constraints on the free dofs.
#[derive(Clone, Debug)]
pub(crate) struct Affine {
    /// `G`, `n_free × n_q`.
    pub(crate) basis: SparseMatrix,
    /// `Gᵀ`.
    pub(crate) basis_t: SparseMatrix,
    /// The particular solution `g` on the free dofs.
    pub(crate) particular: Vec<f64>,
}

/// Reduced coordinates `q` with `p = P q + o` (see the module docs).
#[derive(Clone, Debug)]
pub(crate) struct Reduction {
    pub(crate) dof_map: DofMap,
    pub(crate) affine: Option<Affine>,
    /// `o = p(0)` in the reduced sense: fixed values on fixed dofs, `g` (or 0) on free ones.
    pub(crate) offset: Vec<f64>,
    /// Number of reduced coordinates.
    pub(crate) n_q: usize,
    /// Control points with all of x, y, z fixed, ascending.
    pub(crate) fixed_points: Vec<usize>,
    /// The weight dof pinned to remove the scaling gauge of homogeneous weights, if any.
    pub(crate) gauge_weight: Option<usize>,
}

impl Reduction {
    /// Resolves `constraints` for `geometry` with initial coordinates `p0` (docs/math.md §4).
    ///
    /// With weights as unknowns and no weight fixed (by `fixed_weights`, `fixed_point_weights`
    /// with at least one fixed point, or a linear constraint on a weight), scaling every weight by the same factor leaves the surface unchanged, so
    /// `M` and `K` are singular along that direction. The weight of the first fixed control
    /// point (or of point 0) is then pinned at its initial value: a gauge choice that leaves
    /// the motion of the surface unchanged and makes every system solved SPD.
    pub(crate) fn new(
        geometry: &Geometry,
        constraints: &Constraints,
        weights_as_dofs: bool,
        p0: &[f64],
    ) -> Result<Self, DnurbsError> {
        let n = geometry.n_control_points();
        let m = geometry.dofs_per_point(weights_as_dofs);
        let n_total = n * m;
        let mut is_fixed_point = vec![false; n];
        for &k in &constraints.fixed_points {
            if k >= n {
                return Err(DnurbsError::MissingControlPoint { index: k, count: n });
            }
            is_fixed_point[k] = true;
        }
        let (n_u, n_v) = geometry.net_shape();
        for k in outer_ring_points(n_u, n_v, constraints.fixed_rings) {
            is_fixed_point[k] = true;
        }
        let (held, edge_rows) = resolve_edges(geometry, &constraints.edges, m, p0)?;
        for &k in &held.points {
            is_fixed_point[k] = true;
        }
        let fixed_points: Vec<usize> = (0..n).filter(|&k| is_fixed_point[k]).collect();
        let mut fixed: Vec<usize> = fixed_points
            .iter()
            .flat_map(|&k| (0..3).map(move |x| k * m + x))
            .collect();
        fixed.extend(held.dofs.iter().copied());
        fixed.sort_unstable();
        fixed.dedup();
        let linear: Vec<LinearConstraint> = constraints
            .linear
            .iter()
            .cloned()
            .chain(edge_rows)
            .collect();
        for (r, c) in constraints.linear.iter().enumerate() {
            if !c.rhs.is_finite() {
                return Err(DnurbsError::InvalidConstraint {
                    detail: format!(
                        "linear constraint {r} has a non-finite right-hand side {}",
                        c.rhs
                    ),
                });
            }
            for &(dof, coef) in &c.terms {
                if dof >= n_total {
                    return Err(DnurbsError::InvalidConstraint {
                        detail: format!(
                            "linear constraint {r} names dof {dof}, but there are {n_total} dofs \
                             ({n} control points × {m})"
                        ),
                    });
                }
                if !coef.is_finite() {
                    return Err(DnurbsError::InvalidConstraint {
                        detail: format!(
                            "linear constraint {r} has a non-finite coefficient {coef} on dof {dof}"
                        ),
                    });
                }
            }
        }
        let mut gauge_weight = None;
        if m == 4 {
            if constraints.fixed_weights {
                fixed.extend((0..n).map(|k| 4 * k + 3));
            } else if constraints.fixed_point_weights && !fixed_points.is_empty() {
                fixed.extend(fixed_points.iter().map(|&k| 4 * k + 3));
            } else {
                let weight_constrained = constraints
                    .linear
                    .iter()
                    .any(|c| c.terms.iter().any(|&(d, coef)| d % 4 == 3 && coef != 0.0));
                if !weight_constrained {
                    let k = fixed_points.first().copied().unwrap_or(0);
                    gauge_weight = Some(4 * k + 3);
                    fixed.push(4 * k + 3);
                }
            }
        }
        let dof_map = DofMap::new(n_total, &fixed)?;
        let n_free = dof_map.n_free();
        let mut offset = vec![0.0; n_total];
        for &d in dof_map.fixed() {
            offset[d] = p0[d];
        }
        let mut affine = None;
        let mut n_q = n_free;
        if !linear.is_empty() {
            let a = build_affine(&dof_map, &linear, p0)?;
            if let Some(a) = a {
                for (i, &g) in a.particular.iter().enumerate() {
                    offset[dof_map.free()[i]] = g;
                }
                n_q = a.basis.ncols();
                affine = Some(a);
            }
        }
        Ok(Self {
            dof_map,
            affine,
            offset,
            n_q,
            fixed_points,
            gauge_weight,
        })
    }

    /// `p = P q + o`.
    pub(crate) fn to_full(&self, q: &[f64]) -> Vec<f64> {
        let mut p = self.offset.clone();
        self.add_embedded(q, &mut p);
        p
    }

    /// `out += P x`.
    pub(crate) fn add_embedded(&self, x: &[f64], out: &mut [f64]) {
        match &self.affine {
            None => {
                for (i, &d) in self.dof_map.free().iter().enumerate() {
                    out[d] += x[i];
                }
            }
            Some(a) => {
                let mut y = vec![0.0; self.dof_map.n_free()];
                a.basis.mul_vec(x, &mut y);
                for (i, &d) in self.dof_map.free().iter().enumerate() {
                    out[d] += y[i];
                }
            }
        }
    }

    /// `P x` (a velocity: zero on fixed dofs).
    pub(crate) fn embed(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.dof_map.n_total()];
        self.add_embedded(x, &mut out);
        out
    }

    /// `Pᵀ f` (a force, or the projection of a velocity since `G` is orthonormal).
    pub(crate) fn reduce_vector(&self, f: &[f64]) -> Vec<f64> {
        let ff = self.dof_map.restrict(f);
        match &self.affine {
            None => ff,
            Some(a) => {
                let mut out = vec![0.0; self.n_q];
                a.basis_t.mul_vec(&ff, &mut out);
                out
            }
        }
    }

    /// Reduced coordinates of a full `p`: `q = Gᵀ (p_f − g)` (exact when `p` satisfies the
    /// constraints, the orthogonal projection otherwise).
    pub(crate) fn reduce_coordinates(&self, p: &[f64]) -> Vec<f64> {
        let diff: Vec<f64> = p.iter().zip(&self.offset).map(|(a, b)| a - b).collect();
        self.reduce_vector(&diff)
    }

    /// `Pᵀ A P`.
    pub(crate) fn reduce_matrix(&self, a: &SparseMatrix) -> Result<SparseMatrix, DnurbsError> {
        let aff = self.dof_map.restrict_matrix(a);
        match &self.affine {
            None => Ok(aff),
            Some(af) => Ok(af.basis_t.matmul(&aff.matmul(&af.basis)?)?),
        }
    }
}

/// What edge conditions hold outright: whole control points and single dofs.
#[derive(Default)]
struct Held {
    points: Vec<usize>,
    dofs: Vec<usize>,
}

/// Resolves edge conditions (docs/math.md §10.7) into held points and dofs and linear rows on
/// the generalized coordinates (`m` per control point).
fn resolve_edges(
    geometry: &Geometry,
    edges: &[EdgeConstraint],
    m: usize,
    p0: &[f64],
) -> Result<(Held, Vec<LinearConstraint>), DnurbsError> {
    let mut held = Held::default();
    let mut rows = Vec::new();
    if edges.is_empty() {
        return Ok((held, rows));
    }
    if geometry.is_curve() {
        return Err(DnurbsError::InvalidConstraint {
            detail: "edge conditions need a surface; a curve has no edges".into(),
        });
    }
    let (n_u, n_v) = geometry.net_shape();
    let point = |k: usize| [p0[m * k], p0[m * k + 1], p0[m * k + 2]];
    for (e, c) in edges.iter().enumerate() {
        let (edge, next) = edge_rows(n_u, n_v, c.edge);
        match c.condition {
            EdgeCondition::Clamped => {
                held.points.extend(&edge);
                held.points.extend(&next);
            }
            EdgeCondition::Pinned => held.points.extend(&edge),
            EdgeCondition::Hold(components) => {
                for &k in &edge {
                    for (x, _) in components.iter().enumerate().filter(|(_, on)| **on) {
                        held.dofs.push(m * k + x);
                    }
                }
            }
            EdgeCondition::Symmetry => {
                for (&a, &b) in edge.iter().zip(&next) {
                    let (pa, pb) = (point(a), point(b));
                    let d: [f64; 3] = std::array::from_fn(|x| pb[x] - pa[x]);
                    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    if len.is_nan() || len <= 0.0 || a == b {
                        return Err(DnurbsError::InvalidConstraint {
                            detail: format!(
                                "symmetry on edge {} (condition {e}): control point {b} of the \
                                 next row coincides with edge point {a}, so the plane's normal \
                                 is undefined",
                                c.edge.name()
                            ),
                        });
                    }
                    let n = d.map(|x| x / len);
                    // Two unit directions orthogonal to n.
                    let helper = if n[0].abs() < 0.9 {
                        [1.0, 0.0, 0.0]
                    } else {
                        [0.0, 1.0, 0.0]
                    };
                    let t1 = {
                        let c = [
                            n[1] * helper[2] - n[2] * helper[1],
                            n[2] * helper[0] - n[0] * helper[2],
                            n[0] * helper[1] - n[1] * helper[0],
                        ];
                        let l = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                        c.map(|x| x / l)
                    };
                    let t2 = [
                        n[1] * t1[2] - n[2] * t1[1],
                        n[2] * t1[0] - n[0] * t1[2],
                        n[0] * t1[1] - n[1] * t1[0],
                    ];
                    let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
                    rows.push(LinearConstraint {
                        terms: (0..3).map(|x| (m * a + x, n[x])).collect(),
                        rhs: dot(n, pa),
                    });
                    // t ⊥ d exactly, so the right-hand side is 0 (the rest state's t · d is
                    // round-off, which would make redundant rows at corners look
                    // inconsistent).
                    for t in [t1, t2] {
                        rows.push(LinearConstraint {
                            terms: (0..3)
                                .flat_map(|x| [(m * b + x, t[x]), (m * a + x, -t[x])])
                                .collect(),
                            rhs: 0.0,
                        });
                    }
                }
            }
        }
    }
    Ok((held, rows))
}

/// Linear constraints on the free dofs: `A_f p_f = b − A_c p_c`, solved as `p_f = G q + g`
/// (docs/math.md §4). Only the free dofs that appear in a constraint are substituted (`G` is the
/// identity elsewhere), so the reduced matrices stay sparse. `None` when no constraint touches
/// a free dof.
fn build_affine(
    dof_map: &DofMap,
    linear: &[LinearConstraint],
    p0: &[f64],
) -> Result<Option<Affine>, DnurbsError> {
    let n_free = dof_map.n_free();
    // Free part of every row, the fixed part moved to the right-hand side.
    let mut touched: Vec<usize> = Vec::new();
    let mut rows: Vec<(Vec<(usize, f64)>, f64)> = Vec::new();
    for (r, c) in linear.iter().enumerate() {
        let mut free_terms: Vec<(usize, f64)> = Vec::new();
        let mut rhs = c.rhs;
        let mut scale = c.rhs.abs();
        for &(dof, coef) in &c.terms {
            match dof_map.free_index(dof) {
                Some(i) => free_terms.push((i, coef)),
                None => {
                    rhs -= coef * p0[dof];
                    scale += (coef * p0[dof]).abs();
                }
            }
        }
        free_terms.retain(|&(_, coef)| coef != 0.0);
        if free_terms.is_empty() {
            if rhs.abs() > 1e-10 * scale.max(1.0) {
                return Err(DnurbsError::InvalidConstraint {
                    detail: format!(
                        "linear constraint {r} involves only fixed dofs and is violated by \
                         {rhs:e} (b = {}): it conflicts with the fixed control points",
                        c.rhs
                    ),
                });
            }
            continue;
        }
        touched.extend(free_terms.iter().map(|&(i, _)| i));
        rows.push((free_terms, rhs));
    }
    if rows.is_empty() {
        return Ok(None);
    }
    touched.sort_unstable();
    touched.dedup();
    // Rows that share no dof are independent: each connected group of rows and dofs is solved
    // on its own, so that G stays block-diagonal (a null space of all rows at once may mix
    // independent groups whose singular values coincide, and fill the reduced matrices).
    let mut parent: Vec<usize> = (0..n_free).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for (terms, _) in &rows {
        let first = root(&mut parent, terms[0].0);
        for &(i, _) in &terms[1..] {
            let r = root(&mut parent, i);
            parent[r] = first;
        }
    }
    let mut groups: Vec<(Vec<usize>, Vec<usize>)> = Vec::new(); // (dofs, rows)
    let mut group_of = vec![usize::MAX; n_free];
    for &i in &touched {
        let r = root(&mut parent, i);
        if group_of[r] == usize::MAX {
            group_of[r] = groups.len();
            groups.push((Vec::new(), Vec::new()));
        }
        groups[group_of[r]].0.push(i);
    }
    for (k, (terms, _)) in rows.iter().enumerate() {
        let r = root(&mut parent, terms[0].0);
        groups[group_of[r]].1.push(k);
    }
    let mut is_touched = vec![false; n_free];
    for &i in &touched {
        is_touched[i] = true;
    }
    // G: identity columns for untouched free dofs, then each group's null-space basis.
    let mut triplets = Vec::new();
    let mut col = 0;
    for i in 0..n_free {
        if !is_touched[i] {
            triplets.push((i, col, 1.0));
            col += 1;
        }
    }
    let mut particular = vec![0.0; n_free];
    let mut local = vec![usize::MAX; n_free];
    for (dofs, group_rows) in &groups {
        for (t, &i) in dofs.iter().enumerate() {
            local[i] = t;
        }
        let mut a = DenseMatrix::zeros(group_rows.len(), dofs.len());
        let mut b = vec![0.0; group_rows.len()];
        for (r, &k) in group_rows.iter().enumerate() {
            let (terms, rhs) = &rows[k];
            for &(i, coef) in terms {
                a[(r, local[i])] += coef;
            }
            b[r] = *rhs;
        }
        // The right-hand sides hold coordinates of the rest state: their size bounds the
        // round-off that can separate redundant rows.
        let x_scale = p0.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let (g_t, particular_t) =
            affine_solution_space(&a, &b, 1e-12, x_scale).map_err(|e| match e {
                LinalgError::Singular { detail } => DnurbsError::InvalidConstraint {
                    detail: format!(
                        "the {} linear constraints on the free dofs are inconsistent: {detail}",
                        rows.len()
                    ),
                },
                other => DnurbsError::Linalg(other),
            })?;
        // A consistent system is solved exactly by the particular solution.
        let ag = a.mul_vec(&particular_t);
        let b_norm = b.iter().map(|x| x * x).sum::<f64>().sqrt();
        let residual = ag
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt();
        if residual.is_nan() || residual > 1e-9 * b_norm.max(1.0) {
            return Err(DnurbsError::InvalidConstraint {
                detail: format!(
                    "the {} linear constraints are inconsistent: ‖A g − b‖ = {residual:e} (‖b‖ = {b_norm:e})",
                    rows.len()
                ),
            });
        }
        for j in 0..g_t.ncols() {
            for (t, &i) in dofs.iter().enumerate() {
                let v = g_t[(t, j)];
                if v != 0.0 {
                    triplets.push((i, col, v));
                }
            }
            col += 1;
        }
        for (t, &i) in dofs.iter().enumerate() {
            particular[i] = particular_t[t];
        }
    }
    let basis = SparseMatrix::from_triplets(n_free, col, &triplets)?;
    Ok(Some(Affine {
        basis_t: basis.transpose(),
        basis,
        particular,
    }))
}
