//! How a lattice is laid on its surface or curve: the node parameters of each grid
//! ([`ParameterGrid`]), the fixed nodes (automatic, listed, or by the fixed control points),
//! and the springs, triangles and hinges of a grid.

use super::*;

pub(super) fn argmin(values: impl Iterator<Item = f64>) -> usize {
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
    pub(super) fn axis(&self, knots: &KnotVector, name: &str) -> Result<Vec<f64>, MsmError> {
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
pub(super) fn surface_fixed(
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
pub(super) fn degenerate(x: &[[f64; 3]; 4]) -> bool {
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
pub(super) fn triangulated_springs(
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
pub(super) fn without_shear(o: &LatticeOptions) -> LatticeOptions {
    let mut o = o.clone();
    o.constants.remove(Class::Spring(SpringKind::Shear));
    o
}

/// A hinge on every edge shared by two of `triangles` (consistently oriented), of kind
/// [`HingeKind::Grid`] on a grid line of the `· × n_v` grid and [`HingeKind::Diagonal`]
/// otherwise, each kind when `constants` holds it, with the rest angle of `positions`;
/// sorted by kind, then by the edge's nodes.
pub(super) fn triangle_hinges(
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
pub(super) fn listed_fixed(n: usize, list: &[usize]) -> Result<Vec<bool>, MsmError> {
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
pub(super) fn control_point_fixed(
    n: usize,
    fixed_control_points: &[usize],
) -> Result<Vec<bool>, MsmError> {
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
pub(super) fn support(
    basis: &nurbspring_geom::BSplineBasis,
    t: f64,
) -> Result<Vec<usize>, MsmError> {
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
pub(super) fn auto_fixed(
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
pub(super) fn grid_springs(
    n_u: usize,
    n_v: usize,
    o: &LatticeOptions,
    positions: &[[f64; 3]],
) -> Vec<Spring> {
    let idx = |i: usize, j: usize| i * n_v + j;
    let has = |kind| o.constants.contains(Class::Spring(kind));
    let mut pairs: Vec<(usize, usize, SpringKind)> = Vec::new();
    // Along the grid lines, `step` nodes apart.
    let along = |step: usize, kind: SpringKind, pairs: &mut Vec<_>| {
        for i in 0..n_u {
            for j in 0..n_v {
                if j + step < n_v {
                    pairs.push((idx(i, j), idx(i, j + step), kind));
                }
                if i + step < n_u {
                    pairs.push((idx(i, j), idx(i + step, j), kind));
                }
            }
        }
    };
    if has(SpringKind::Structural) {
        along(1, SpringKind::Structural, &mut pairs);
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
        along(2, SpringKind::Bend, &mut pairs);
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
