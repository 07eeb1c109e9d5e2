//! Knot insertion, knot refinement and degree elevation as matrices (The NURBS Book §5.2,
//! §5.3, §5.5; docs/math.md §2).
//!
//! Each operation returns the new knot vector and a sparse matrix `C` with
//! `P^w_new = C P^w_old` in homogeneous coordinates `P^w = (w x, w y, w z, w)`. `C` depends only
//! on the knot vectors, not on the control points, and the new basis reproduces the old one:
//! `N_old_j = Σ_i C_ij N_new_i`. `C` is non-negative with rows summing to one, so the new
//! weights `w_new = C w_old` are convex combinations of the old ones (positive), and for
//! non-rational geometry (all weights 1) `P_new = C P_old` directly. Surfaces use `C = C_u ⊗ C_v` with the flat index `i · n_v + j`.
//!
//! The algorithms (A5.1, A5.4, A5.9) are run once on the unit rows `e_j` of the old control net
//! — they are linear in the control points — which yields the rows of `C`; the geometry is then
//! `C` applied to the homogeneous control points.
//!
//! ```
//! use nurbspring_geom::{KnotVector, NurbsCurve};
//! // A cubic Bézier segment split at u = 1/2 gives the de Casteljau points.
//! let k = KnotVector::try_new(vec![0., 0., 0., 0., 1., 1., 1., 1.], 3).unwrap();
//! let pts = vec![[0., 0., 0.], [1., 2., 0.], [3., 2., 0.], [4., 0., 0.]];
//! let c = NurbsCurve::try_new(k, pts, vec![1.0; 4]).unwrap();
//! let (fine, matrix) = c.refine_knots(&[0.5; 3]).unwrap();
//! assert_eq!(fine.basis().knots().knots(), &[0., 0., 0., 0., 0.5, 0.5, 0.5, 1., 1., 1., 1.]);
//! // The middle control point is (P0 + 3 P1 + 3 P2 + P3) / 8 = c(1/2).
//! assert_eq!(fine.control_points()[3], [2.0, 1.5, 0.0]);
//! assert_eq!(matrix.get(3, 1), 3.0 / 8.0);
//! ```

use crate::{GeomError, KnotVector, NurbsCurve, NurbsSurface};

mod matrix;
pub use matrix::{RefinementMatrix, from_homogeneous, to_homogeneous};

/// `P_new = C · P_old` for the Cartesian points and weights of a curve or surface. Equal
/// weights `w` stay exactly `w` (the rows of C sum to one, so the homogeneous route would
/// only add round-off to them and make a B-spline look rational): the points are then
/// transformed directly.
fn apply_to_net(
    c: &RefinementMatrix,
    points: &[[f64; 3]],
    weights: &[f64],
) -> (Vec<[f64; 3]>, Vec<f64>) {
    let uniform = weights.iter().all(|&w| w == weights[0]);
    if uniform && !weights.is_empty() {
        let h: Vec<[f64; 4]> = points.iter().map(|p| [p[0], p[1], p[2], 1.0]).collect();
        let moved = c.apply(&h);
        let points = moved.iter().map(|h| [h[0], h[1], h[2]]).collect();
        (points, vec![weights[0]; moved.len()])
    } else {
        from_homogeneous(&c.apply(&to_homogeneous(points, weights)))
    }
}

/// A sparse row vector (column, value), columns ascending: the "control point" the
/// algorithms below operate on when they build a matrix.
#[derive(Clone, Debug, Default)]
struct Row(Vec<(usize, f64)>);

impl Row {
    fn unit(j: usize) -> Self {
        Self(vec![(j, 1.0)])
    }

    /// `alpha a + (1 − alpha) b`, the step of every algorithm of The NURBS Book ch. 5.
    fn lerp(alpha: f64, a: &Row, b: &Row) -> Row {
        let mut out = Row(Vec::with_capacity(a.0.len().max(b.0.len()) + 1));
        out.add_scaled(alpha, a);
        out.add_scaled(1.0 - alpha, b);
        out
    }

    /// `self += s · x` (sorted merge).
    fn add_scaled(&mut self, s: f64, x: &Row) {
        if x.0.is_empty() {
            return;
        }
        let mut merged = Vec::with_capacity(self.0.len() + x.0.len());
        let (mut i, mut j) = (0, 0);
        let (a, b) = (&self.0, &x.0);
        while i < a.len() || j < b.len() {
            if j == b.len() || (i < a.len() && a[i].0 < b[j].0) {
                merged.push(a[i]);
                i += 1;
            } else if i == a.len() || b[j].0 < a[i].0 {
                merged.push((b[j].0, s * b[j].1));
                j += 1;
            } else {
                merged.push((a[i].0, a[i].1 + s * b[j].1));
                i += 1;
                j += 1;
            }
        }
        self.0 = merged;
    }
}

fn matrix_from_rows(rows: Vec<Row>, ncols: usize) -> RefinementMatrix {
    RefinementMatrix::from_rows(rows.into_iter().map(|r| r.0).collect(), ncols)
}

fn invalid(value: f64, reason: String) -> GeomError {
    GeomError::InvalidInsertion { value, reason }
}

/// Checks that `u` may be inserted `times` more times: inside the open domain, and the
/// resulting multiplicity at most p.
fn check_insertion(knots: &KnotVector, u: f64, times: usize) -> Result<(), GeomError> {
    let (a, b) = knots.domain();
    if !(u.is_finite() && u > a && u < b) {
        return Err(invalid(
            u,
            format!("it is not inside the open parameter domain ({a}, {b})"),
        ));
    }
    let s = knots.multiplicity(u);
    let p = knots.degree();
    if s + times > p {
        return Err(invalid(
            u,
            format!(
                "its multiplicity would become {s} + {times} = {}, more than the degree {p}",
                s + times
            ),
        ));
    }
    Ok(())
}

/// Inserts `u` into `knots` `times` times (The NURBS Book A5.1, `CurveKnotIns`).
///
/// Returns the new knot vector and `C` (`(n + 1 + times) × (n + 1)`) with
/// `P^w_new = C P^w_old`. `u` must lie strictly inside the domain, and its multiplicity `s` after
/// insertion must not exceed p (`s + times ≤ p`); otherwise [`GeomError::InvalidInsertion`].
/// `times = 0` gives the identity.
///
/// The NURBS Book Ex. 5.1 (cubic, `U = {0,0,0,0,1,2,3,4,5,5,5,5}`, `u = 5/2`):
/// `Q_i = α_i P_i + (1 − α_i) P_{i−1}` with `α_3 = 5/6`, `α_4 = 1/2`, `α_5 = 1/6`.
/// ```
/// use nurbspring_geom::{KnotVector, insert_knot};
/// let u = KnotVector::try_new(vec![0., 0., 0., 0., 1., 2., 3., 4., 5., 5., 5., 5.], 3).unwrap();
/// let (new, c) = insert_knot(&u, 2.5, 1).unwrap();
/// assert_eq!(new.knots()[5..8], [2.0, 2.5, 3.0]);
/// assert_eq!((c.nrows, c.ncols), (9, 8));
/// assert!((c.get(3, 3) - 5. / 6.).abs() < 1e-15 && (c.get(3, 2) - 1. / 6.).abs() < 1e-15);
/// assert!((c.get(4, 4) - 0.5).abs() < 1e-15 && (c.get(4, 3) - 0.5).abs() < 1e-15);
/// assert!((c.get(5, 5) - 1. / 6.).abs() < 1e-15 && (c.get(5, 4) - 5. / 6.).abs() < 1e-15);
/// assert_eq!(c.get(6, 5), 1.0); // Q_6 = P_5
/// ```
pub fn insert_knot(
    knots: &KnotVector,
    u: f64,
    times: usize,
) -> Result<(KnotVector, RefinementMatrix), GeomError> {
    check_insertion(knots, u, times)?;
    let np = knots.n_basis() - 1;
    if times == 0 {
        return Ok((knots.clone(), RefinementMatrix::identity(np + 1)));
    }
    let p = knots.degree();
    let up = knots.knots();
    let k = knots.find_span(u);
    let s = knots.multiplicity(u);
    let r = times;
    let mp = np + p + 1;
    let nq = np + r;
    // New knot vector.
    let mut uq = Vec::with_capacity(mp + r + 1);
    uq.extend_from_slice(&up[..=k]);
    uq.extend(std::iter::repeat_n(u, r));
    uq.extend_from_slice(&up[k + 1..=mp]);
    // Unaltered control points.
    let pw: Vec<Row> = (0..=np).map(Row::unit).collect();
    let mut qw = vec![Row::default(); nq + 1];
    qw[..=k - p].clone_from_slice(&pw[..=k - p]);
    qw[k - s + r..=np + r].clone_from_slice(&pw[k - s..=np]);
    let mut rw: Vec<Row> = (0..=p - s).map(|i| pw[k - p + i].clone()).collect();
    let mut l = 0;
    for j in 1..=r {
        l = k - p + j;
        for i in 0..=p - j - s {
            let alpha = (u - up[l + i]) / (up[i + k + 1] - up[l + i]);
            rw[i] = Row::lerp(alpha, &rw[i + 1], &rw[i]);
        }
        qw[l] = rw[0].clone();
        qw[k + r - j - s] = rw[p - j - s].clone();
    }
    if l + 1 < k - s {
        qw[l + 1..k - s].clone_from_slice(&rw[1..k - s - l]);
    }
    Ok((KnotVector::try_new(uq, p)?, matrix_from_rows(qw, np + 1)))
}

/// Inserts all of `new_knots` (any order, repeats allowed) at once (The NURBS Book A5.4,
/// `RefineKnotVectCurve`).
///
/// Every value must lie strictly inside the domain and no multiplicity may exceed p after
/// insertion ([`GeomError::InvalidInsertion`]). An empty list gives the identity.
///
/// ```
/// use nurbspring_geom::{KnotVector, refine_knots};
/// // Linear B-splines: inserting 1/4 and 1/2 adds hat functions; C interpolates old values.
/// let u = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
/// let (new, c) = refine_knots(&u, &[0.5, 0.25]).unwrap();
/// assert_eq!(new.knots(), &[0., 0., 0.25, 0.5, 1., 1.]);
/// assert_eq!(c.apply_to(&[0.0, 4.0]), vec![0.0, 1.0, 2.0, 4.0]);
/// ```
pub fn refine_knots(
    knots: &KnotVector,
    new_knots: &[f64],
) -> Result<(KnotVector, RefinementMatrix), GeomError> {
    let n = knots.n_basis() - 1;
    if new_knots.is_empty() {
        return Ok((knots.clone(), RefinementMatrix::identity(n + 1)));
    }
    let mut x = new_knots.to_vec();
    for &xi in &x {
        check_insertion(knots, xi, 0)?;
    }
    x.sort_by(f64::total_cmp);
    let mut i = 0;
    while i < x.len() {
        let mut j = i;
        while j < x.len() && x[j] == x[i] {
            j += 1;
        }
        check_insertion(knots, x[i], j - i)?;
        i = j;
    }
    let p = knots.degree();
    let u = knots.knots();
    let m = n + p + 1;
    let r = x.len() - 1;
    let a = knots.find_span(x[0]);
    let b = knots.find_span(x[r]) + 1;
    let pw: Vec<Row> = (0..=n).map(Row::unit).collect();
    let mut qw = vec![Row::default(); n + r + 2];
    let mut ubar = vec![0.0; m + r + 2];
    qw[..=a - p].clone_from_slice(&pw[..=a - p]);
    qw[b + r..=n + r + 1].clone_from_slice(&pw[b - 1..=n]);
    ubar[..=a].copy_from_slice(&u[..=a]);
    for j in b + p..=m {
        ubar[j + r + 1] = u[j];
    }
    let mut i = b + p - 1;
    let mut k = b + p + r;
    for j in (0..=r).rev() {
        while x[j] <= u[i] && i > a {
            qw[k - p - 1] = pw[i - p - 1].clone();
            ubar[k] = u[i];
            k -= 1;
            i -= 1;
        }
        qw[k - p - 1] = qw[k - p].clone();
        for l in 1..=p {
            let ind = k - p + l;
            let alpha = ubar[k + l] - x[j];
            if alpha.abs() == 0.0 {
                qw[ind - 1] = qw[ind].clone();
            } else {
                let alpha = alpha / (ubar[k + l] - u[i - p + l]);
                qw[ind - 1] = Row::lerp(alpha, &qw[ind - 1], &qw[ind]);
            }
        }
        ubar[k] = x[j];
        k -= 1;
    }
    Ok((KnotVector::try_new(ubar, p)?, matrix_from_rows(qw, n + 1)))
}

/// The knots that split every non-empty span of the domain into `parts` equal sub-spans
/// (`parts = 2`: the midpoints). `parts ≤ 1` gives none.
///
/// ```
/// use nurbspring_geom::{KnotVector, span_subdivision_knots};
/// let u = KnotVector::try_new(vec![0., 0., 0., 0.5, 0.5, 1., 1., 1.], 2).unwrap();
/// assert_eq!(span_subdivision_knots(&u, 2), vec![0.25, 0.75]);
/// assert_eq!(span_subdivision_knots(&u, 4), vec![0.125, 0.25, 0.375, 0.625, 0.75, 0.875]);
/// ```
pub fn span_subdivision_knots(knots: &KnotVector, parts: usize) -> Vec<f64> {
    let mut out = Vec::new();
    for (_, a, b) in knots.nonempty_spans() {
        for k in 1..parts {
            out.push(a + (b - a) * k as f64 / parts as f64);
        }
    }
    out
}

/// Uniform refinement: `levels` rounds of midpoint insertion, i.e. every non-empty span split
/// into `2^levels` equal sub-spans, inserted at once by [`refine_knots`] (A5.4).
///
/// ```
/// use nurbspring_geom::{KnotVector, refine_uniform};
/// let u = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
/// let (new, c) = refine_uniform(&u, 2).unwrap();
/// assert_eq!(new.knots(), &[0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1.]);
/// assert_eq!((c.nrows, c.ncols), (6, 3));
/// ```
///
/// # Panics
/// If `2^levels` overflows `usize`.
pub fn refine_uniform(
    knots: &KnotVector,
    levels: u32,
) -> Result<(KnotVector, RefinementMatrix), GeomError> {
    let parts = 1usize
        .checked_shl(levels)
        .filter(|&p| p != 0)
        .expect("refine_uniform: 2^levels overflows usize");
    refine_knots(knots, &span_subdivision_knots(knots, parts))
}

fn binomial(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    let k = k.min(n - k);
    let mut r = 1.0;
    for i in 1..=k {
        r = r * (n - k + i) as f64 / i as f64;
    }
    r
}

/// Raises the degree of a clamped knot vector by `t` (The NURBS Book A5.9,
/// `DegreeElevateCurve`): every distinct knot gains multiplicity `t`. Returns the new knot
/// vector (degree `p + t`) and `C` with `P^w_new = C P^w_old`.
///
/// Needs clamped ends and interior multiplicities of at most p, otherwise
/// [`GeomError::UnsupportedKnots`]. `t = 0` gives the identity.
///
/// A straight line of degree 1 elevated to degree 2 gets its midpoint as middle control point:
/// ```
/// use nurbspring_geom::{KnotVector, elevate_degree};
/// let u = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
/// let (new, c) = elevate_degree(&u, 1).unwrap();
/// assert_eq!(new.knots(), &[0., 0., 0., 1., 1., 1.]);
/// assert_eq!(c.to_dense(), vec![1.0, 0.0, 0.5, 0.5, 0.0, 1.0]);
/// ```
pub fn elevate_degree(
    knots: &KnotVector,
    t: usize,
) -> Result<(KnotVector, RefinementMatrix), GeomError> {
    let p = knots.degree();
    let n = knots.n_basis() - 1;
    if t == 0 {
        return Ok((knots.clone(), RefinementMatrix::identity(n + 1)));
    }
    let u = knots.knots();
    if !(knots.is_clamped_start() && knots.is_clamped_end()) {
        return Err(GeomError::UnsupportedKnots {
            operation: "degree elevation",
            reason: format!(
                "the knot vector {u:?} of degree {p} is not clamped (first and last {} knots equal)",
                p + 1
            ),
        });
    }
    let m = n + p + 1;
    let interior: Vec<(f64, usize)> = knots.distinct_with_multiplicity()[1..]
        .split_last()
        .map(|(_, rest)| rest.to_vec())
        .unwrap_or_default();
    if let Some(&(value, mult)) = interior.iter().find(|&&(_, mult)| mult > p) {
        return Err(GeomError::UnsupportedKnots {
            operation: "degree elevation",
            reason: format!("interior knot {value} has multiplicity {mult} > degree {p}"),
        });
    }
    let ph = p + t;
    let ph2 = ph / 2;
    let n_new = n + 1 + t * (interior.len() + 1);
    // Bézier degree elevation coefficients.
    let mut bezalfs = vec![vec![0.0; p + 1]; ph + 1];
    bezalfs[0][0] = 1.0;
    bezalfs[ph][p] = 1.0;
    for i in 1..=ph2 {
        let inv = 1.0 / binomial(ph, i);
        for j in i.saturating_sub(t)..=p.min(i) {
            bezalfs[i][j] = inv * binomial(p, j) * binomial(t, i - j);
        }
    }
    for i in ph2 + 1..ph {
        for j in i.saturating_sub(t)..=p.min(i) {
            bezalfs[i][j] = bezalfs[ph - i][p - j];
        }
    }
    let pw: Vec<Row> = (0..=n).map(Row::unit).collect();
    let mut qw = vec![Row::default(); n_new];
    let mut uh = vec![0.0; n_new + ph + 1];
    let mut bpts: Vec<Row> = pw[..=p].to_vec();
    let mut next_bpts = vec![Row::default(); p];
    let mut ebpts = vec![Row::default(); ph + 1];
    let mut alfs = vec![0.0; p];
    let mut mh = ph;
    let mut kind = ph + 1;
    let mut r: isize = -1;
    let mut a = p;
    let mut b = p + 1;
    let mut cind = 1;
    let mut ua = u[0];
    qw[0] = pw[0].clone();
    uh[..=ph].fill(ua);
    while b < m {
        let i0 = b;
        while b < m && u[b] == u[b + 1] {
            b += 1;
        }
        let mul = b - i0 + 1;
        mh += mul + t;
        let ub = u[b];
        let oldr = r;
        r = p as isize - mul as isize;
        let lbz = if oldr > 0 {
            ((oldr + 2) / 2) as usize
        } else {
            1
        };
        let rbz = if r > 0 {
            ph - ((r + 1) / 2) as usize
        } else {
            ph
        };
        if r > 0 {
            // Insert ub r times to get the Bézier segment [ua, ub].
            let numer = ub - ua;
            for k in (mul + 1..=p).rev() {
                alfs[k - mul - 1] = numer / (u[a + k] - ua);
            }
            for j in 1..=r as usize {
                let save = r as usize - j;
                let s = mul + j;
                for k in (s..=p).rev() {
                    bpts[k] = Row::lerp(alfs[k - s], &bpts[k], &bpts[k - 1]);
                }
                next_bpts[save] = bpts[p].clone();
            }
        }
        // Degree-elevate the Bézier segment (only points lbz..=ph are used below).
        for i in lbz..=ph {
            let mut e = Row::default();
            for j in i.saturating_sub(t)..=p.min(i) {
                e.add_scaled(bezalfs[i][j], &bpts[j]);
            }
            ebpts[i] = e;
        }
        if oldr > 1 {
            // Remove the knot ua oldr − 1 times.
            let oldr_u = oldr as usize;
            let den = ub - ua;
            for tr in 1..oldr_u {
                // `first` and `last` of the book: kind − 2 and kind, widened by one per pass.
                let (mut i, mut j) = (kind - 1 - tr, kind - 1 + tr);
                let mut kj = j + 1 - kind;
                while j - i > tr {
                    if i < cind {
                        let alf = (ub - uh[i]) / (ua - uh[i]);
                        qw[i] = Row::lerp(alf, &qw[i], &qw[i - 1]);
                    }
                    if j >= lbz {
                        // A5.8's right-hand point `(P_j − α_j Q_{j+1}) / (1 − α_j)` with
                        // `α_j = (ua − U_{j−tr}) / (ub − U_{j−tr})` (the knot `j + ph + 1` is ub).
                        // `U_{j−tr}` is a knot already loaded into uh (j − tr < kind). The book
                        // takes `uh[kind − 1]` instead when `j − tr > kind − ph + oldr`, which
                        // holds only while the previous knot has at least `t + mul − 1` copies:
                        // after a knot of lower multiplicity (a simple knot, then a triple one,
                        // at degree ≥ 10 for t = 1) it moved the curve.
                        let coef = (ub - uh[j - tr]) / den;
                        ebpts[kj] = Row::lerp(coef, &ebpts[kj], &ebpts[kj + 1]);
                    }
                    i += 1;
                    j -= 1;
                    kj -= 1;
                }
            }
        }
        if a != p {
            // Load the knot ua.
            for _ in 0..(ph as isize - oldr) {
                uh[kind] = ua;
                kind += 1;
            }
        }
        for j in lbz..=rbz {
            qw[cind] = ebpts[j].clone();
            cind += 1;
        }
        if b < m {
            let r_u = r.max(0) as usize;
            bpts[..r_u].clone_from_slice(&next_bpts[..r_u]);
            for j in r_u..=p {
                bpts[j] = pw[b - p + j].clone();
            }
            a = b;
            b += 1;
            ua = ub;
        } else {
            uh[kind..=kind + ph].fill(ub);
        }
    }
    debug_assert_eq!(mh - ph, n_new);
    debug_assert_eq!(cind, n_new);
    let mut c = matrix_from_rows(qw, n + 1);
    // The knot-removal steps above extrapolate (coefficients α > 1), so entries that are zero in
    // exact arithmetic come out as rounding noise (~1e-15). The exact matrix is non-negative
    // and `N_old_j = Σ_i C_ij N_new_i`, so `C_ij ≠ 0` only where the support of the new
    // function lies inside the support of the old one: drop every other entry.
    c.triplets
        .retain(|&(i, j, _)| uh[i] >= u[j] && uh[i + ph + 1] <= u[j + p + 1]);
    Ok((KnotVector::try_new(uh, ph)?, c))
}

impl NurbsCurve {
    fn transformed(
        &self,
        knots: KnotVector,
        c: RefinementMatrix,
    ) -> Result<(NurbsCurve, RefinementMatrix), GeomError> {
        let (points, weights) = apply_to_net(&c, self.control_points(), self.weights());
        Ok((NurbsCurve::try_new(knots, points, weights)?, c))
    }

    /// Inserts `u` `times` times (The NURBS Book A5.1); the curve is unchanged. Returns the
    /// refined curve and `C` (see [`insert_knot`]).
    ///
    /// ```
    /// use nurbspring_geom::{KnotVector, NurbsCurve};
    /// let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
    /// let c = NurbsCurve::try_new(k, vec![[1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
    ///     vec![1.0, std::f64::consts::FRAC_1_SQRT_2, 1.0]).unwrap();
    /// let (fine, _) = c.insert_knot(0.5, 1).unwrap();
    /// assert_eq!(fine.n_control_points(), 4);
    /// let p = fine.point(0.3).unwrap();
    /// assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-15); // still the unit circle
    /// ```
    pub fn insert_knot(
        &self,
        u: f64,
        times: usize,
    ) -> Result<(NurbsCurve, RefinementMatrix), GeomError> {
        let (k, c) = insert_knot(self.basis().knots(), u, times)?;
        self.transformed(k, c)
    }

    /// Inserts all of `new_knots` at once (The NURBS Book A5.4); see [`refine_knots`].
    pub fn refine_knots(
        &self,
        new_knots: &[f64],
    ) -> Result<(NurbsCurve, RefinementMatrix), GeomError> {
        let (k, c) = refine_knots(self.basis().knots(), new_knots)?;
        self.transformed(k, c)
    }

    /// Splits every non-empty span into `2^levels` equal spans (A5.4); see [`refine_uniform`].
    pub fn refine_uniform(&self, levels: u32) -> Result<(NurbsCurve, RefinementMatrix), GeomError> {
        let (k, c) = refine_uniform(self.basis().knots(), levels)?;
        self.transformed(k, c)
    }

    /// Raises the degree by `t` (The NURBS Book A5.9); the curve is unchanged. See
    /// [`elevate_degree`].
    ///
    /// ```
    /// use nurbspring_geom::{KnotVector, NurbsCurve};
    /// // A quarter circle raised to degree 3 stays on the unit circle.
    /// let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
    /// let c = NurbsCurve::try_new(k, vec![[1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
    ///     vec![1.0, std::f64::consts::FRAC_1_SQRT_2, 1.0]).unwrap();
    /// let (cubic, _) = c.elevate_degree(1).unwrap();
    /// assert_eq!(cubic.basis().degree(), 3);
    /// let p = cubic.point(0.7).unwrap();
    /// assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-15);
    /// ```
    pub fn elevate_degree(&self, t: usize) -> Result<(NurbsCurve, RefinementMatrix), GeomError> {
        let (k, c) = elevate_degree(self.basis().knots(), t)?;
        self.transformed(k, c)
    }
}

impl NurbsSurface {
    fn transformed(
        &self,
        knots_u: KnotVector,
        c_u: &RefinementMatrix,
        knots_v: KnotVector,
        c_v: &RefinementMatrix,
    ) -> Result<(NurbsSurface, RefinementMatrix), GeomError> {
        let c = c_u.kron(c_v);
        let (points, weights) = apply_to_net(&c, self.control_points(), self.weights());
        Ok((NurbsSurface::try_new(knots_u, knots_v, points, weights)?, c))
    }

    /// Inserts `u` `times` times in the u direction (The NURBS Book A5.1 on every row of the
    /// net, §5.2 eq. 5.16). Returns the refined surface and `C = C_u ⊗ I` (flat index
    /// `i · n_v + j`).
    pub fn insert_knot_u(
        &self,
        u: f64,
        times: usize,
    ) -> Result<(NurbsSurface, RefinementMatrix), GeomError> {
        let (ku, cu) = insert_knot(self.basis_u().knots(), u, times)?;
        let kv = self.basis_v().knots().clone();
        self.transformed(ku, &cu, kv, &RefinementMatrix::identity(self.n_v()))
    }

    /// Inserts `v` `times` times in the v direction (A5.1); `C = I ⊗ C_v`.
    pub fn insert_knot_v(
        &self,
        v: f64,
        times: usize,
    ) -> Result<(NurbsSurface, RefinementMatrix), GeomError> {
        let (kv, cv) = insert_knot(self.basis_v().knots(), v, times)?;
        let ku = self.basis_u().knots().clone();
        self.transformed(ku, &RefinementMatrix::identity(self.n_u()), kv, &cv)
    }

    /// Inserts `new_u` in u and `new_v` in v at once (The NURBS Book A5.5, i.e. A5.4 in each
    /// direction); `C = C_u ⊗ C_v`.
    ///
    /// ```
    /// use nurbspring_geom::{KnotVector, NurbsSurface};
    /// // A bilinear patch: refining keeps it bilinear, the new points lie on the patch.
    /// let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    /// let s = NurbsSurface::try_new(k.clone(), k,
    ///     vec![[0., 0., 0.], [0., 1., 0.], [1., 0., 0.], [1., 1., 1.]], vec![1.0; 4]).unwrap();
    /// let (fine, c) = s.refine_knots(&[0.5], &[0.5]).unwrap();
    /// assert_eq!((fine.n_u(), fine.n_v()), (3, 3));
    /// assert_eq!((c.nrows, c.ncols), (9, 4));
    /// assert_eq!(fine.control_points()[4], [0.5, 0.5, 0.25]); // c(1/2, 1/2) = (1/2, 1/2, uv)
    /// ```
    pub fn refine_knots(
        &self,
        new_u: &[f64],
        new_v: &[f64],
    ) -> Result<(NurbsSurface, RefinementMatrix), GeomError> {
        let (ku, cu) = refine_knots(self.basis_u().knots(), new_u)?;
        let (kv, cv) = refine_knots(self.basis_v().knots(), new_v)?;
        self.transformed(ku, &cu, kv, &cv)
    }

    /// Splits every non-empty span in both directions into `2^levels` equal spans (A5.4).
    pub fn refine_uniform(
        &self,
        levels: u32,
    ) -> Result<(NurbsSurface, RefinementMatrix), GeomError> {
        let (ku, cu) = refine_uniform(self.basis_u().knots(), levels)?;
        let (kv, cv) = refine_uniform(self.basis_v().knots(), levels)?;
        self.transformed(ku, &cu, kv, &cv)
    }

    /// Raises the degree by `t_u` in u and `t_v` in v (The NURBS Book A5.10, i.e. A5.9 in each
    /// direction); the surface is unchanged. `C = E_u ⊗ E_v`.
    pub fn elevate_degree(
        &self,
        t_u: usize,
        t_v: usize,
    ) -> Result<(NurbsSurface, RefinementMatrix), GeomError> {
        let (ku, eu) = elevate_degree(self.basis_u().knots(), t_u)?;
        let (kv, ev) = elevate_degree(self.basis_v().knots(), t_v)?;
        self.transformed(ku, &eu, kv, &ev)
    }
}

#[cfg(test)]
mod tests;
