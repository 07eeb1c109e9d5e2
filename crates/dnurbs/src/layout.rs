//! The tensor-product element layout shared by every D-NURBS energy (docs/math.md §3): non-empty
//! knot spans with their Gauss–Legendre rules, the Kronecker sparsity pattern built once, the
//! parallel loop over element rows, and the rational basis at the Gauss points from 1-D
//! B-spline values (The NURBS Book eq. (4.9)–(4.10)).

use nurbspring_geom::{
    BSplineBasis, BasisScratch, GaussLegendre, area_element, line_element, quotient_rule,
};
use nurbspring_linalg::KroneckerPattern;
use rayon::prelude::*;

use crate::{DnurbsError, Geometry};

/// One non-empty knot span of one direction with its mapped Gauss–Legendre rule.
#[derive(Clone, Debug)]
pub(crate) struct Span1d {
    /// Index of the span in the knot vector (its functions are `span − p ..= span`).
    pub(crate) span: usize,
    /// `(parameter, weight)` of the Gauss points on the span.
    pub(crate) points: Vec<(f64, f64)>,
}

/// The tensor-product structure of a discretization, built from the knot vectors alone:
/// non-empty spans with their Gauss rules in each direction and the sparsity pattern of the
/// matrices, `A_u ⊗ A_v ⊗ 1_{m×m}` with `A_u`, `A_v` the 1-D patterns (functions overlapping
/// on a non-empty span), written directly without sorting. A curve is the case of one `v`
/// function of degree 0 (`n_v = 1`, one span with the point `(0, 1)`).
///
/// Elements are span pairs; an element row is one `u` span with every `v` span. The values of
/// the columns of the control points `(i, ·)` with `i` in `span_u − p ..= span_u` are
/// contiguous in CSC, so element rows `p + 1` spans apart never write the same values: they
/// are filled in parallel in `p + 1` rounds ([`TensorLayout::for_each_element_row`]).
#[derive(Clone, Debug)]
pub(crate) struct TensorLayout {
    pub(crate) spans_u: Vec<Span1d>,
    pub(crate) spans_v: Vec<Span1d>,
    pub(crate) degrees: (usize, usize),
    pub(crate) n_v: usize,
    pub(crate) n_control_points: usize,
    pub(crate) pattern: KroneckerPattern,
}

/// The mutable outputs of one element row: CSC values of the columns it touches (from
/// `value_base`) and per-dof vectors on its dofs (from `dof_base`; empty when not wanted).
pub(crate) struct RowOutputs<'a> {
    pub(crate) row: usize,
    pub(crate) value_base: usize,
    pub(crate) dof_base: usize,
    pub(crate) mass: &'a mut [f64],
    pub(crate) stiffness: &'a mut [f64],
    pub(crate) vector: &'a mut [f64],
    pub(crate) vector2: &'a mut [f64],
}

/// Splits `data` into the disjoint, increasing ranges `ranges` (an empty `data` gives empty
/// slices).
pub(crate) fn split_ranges<'a>(
    data: &'a mut [f64],
    ranges: &[(usize, usize)],
) -> Vec<&'a mut [f64]> {
    if data.is_empty() {
        return ranges.iter().map(|_| Default::default()).collect();
    }
    let mut out = Vec::with_capacity(ranges.len());
    let mut rest = data;
    let mut offset = 0;
    for &(start, end) in ranges {
        let tail = std::mem::take(&mut rest);
        let (_, tail) = tail.split_at_mut(start - offset);
        let (mid, tail) = tail.split_at_mut(end - start);
        out.push(mid);
        rest = tail;
        offset = end;
    }
    out
}

/// Half-open row ranges of the 1-D pattern: function `k` overlaps `range.0 .. range.1` on a
/// non-empty span (a function with no non-empty span in the domain overlaps nothing).
fn pattern_ranges(n: usize, degree: usize, spans: &[Span1d]) -> Vec<(usize, usize)> {
    let mut r = vec![(usize::MAX, 0usize); n];
    for s in spans {
        let (lo, hi) = (s.span - degree, s.span + 1);
        for range in &mut r[lo..hi] {
            *range = (range.0.min(lo), range.1.max(hi));
        }
    }
    r.into_iter()
        .map(|(a, b)| if a == usize::MAX { (0, 0) } else { (a, b) })
        .collect()
}

fn spans_1d(basis: &BSplineBasis, rule: &GaussLegendre) -> Vec<Span1d> {
    basis
        .knots()
        .nonempty_spans()
        .into_iter()
        .map(|(span, a, b)| Span1d {
            span,
            points: rule.mapped(a, b).collect(),
        })
        .collect()
}

impl TensorLayout {
    pub(crate) fn new(
        geometry: &Geometry,
        quadrature_points: usize,
        m: usize,
    ) -> Result<Self, DnurbsError> {
        crate::options::check_quadrature_points(quadrature_points)?;
        let rule = GaussLegendre::new(quadrature_points)?;
        let (p, q) = geometry.degrees();
        let (n_u, n_v) = geometry.net_shape();
        let (spans_u, spans_v) = match geometry {
            Geometry::Surface(s) => (spans_1d(s.basis_u(), &rule), spans_1d(s.basis_v(), &rule)),
            Geometry::Curve(c) => (
                spans_1d(c.basis(), &rule),
                vec![Span1d {
                    span: 0,
                    points: vec![(0.0, 1.0)],
                }],
            ),
        };
        let pattern = KroneckerPattern::new(
            &pattern_ranges(n_u, p, &spans_u),
            &pattern_ranges(n_v, q, &spans_v),
            m,
        )?;
        Ok(Self {
            spans_u,
            spans_v,
            degrees: (p, q),
            n_v,
            n_control_points: n_u * n_v,
            pattern,
        })
    }

    pub(crate) fn n_local(&self) -> usize {
        (self.degrees.0 + 1) * (self.degrees.1 + 1)
    }

    /// Flat index of local control point `a` of the element `(span_u, span_v)`, in the order of
    /// `Jacobian::indices` (u major).
    #[inline]
    pub(crate) fn point(&self, span_u: usize, span_v: usize, a: usize) -> usize {
        let (p, q) = self.degrees;
        (span_u - p + a / (q + 1)) * self.n_v + span_v - q + a % (q + 1)
    }

    /// Runs `kernel(scratch, outputs)` for every element row, rows `p + 1` apart in parallel
    /// (they touch disjoint columns and dofs), `p + 1` rounds. `vector` and `vector2` are
    /// per-dof outputs (may be empty); `mass` and `stiffness` are CSC values of the pattern.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn for_each_element_row<T, I, F>(
        &self,
        mass: &mut [f64],
        stiffness: &mut [f64],
        vector: &mut [f64],
        vector2: &mut [f64],
        init: I,
        kernel: F,
    ) where
        I: Fn() -> T + Sync + Send,
        F: Fn(&mut T, &mut RowOutputs<'_>) + Sync + Send,
    {
        let p = self.degrees.0;
        let m = self.pattern.dofs_per_point();
        let per_u = self.n_v * m;
        let col_ptr = self.pattern.col_ptr();
        for round in 0..=p {
            let rows: Vec<usize> = (round..self.spans_u.len()).step_by(p + 1).collect();
            let dofs: Vec<(usize, usize)> = rows
                .iter()
                .map(|&t| {
                    let s = self.spans_u[t].span;
                    ((s - p) * per_u, (s + 1) * per_u)
                })
                .collect();
            let values: Vec<(usize, usize)> = dofs
                .iter()
                .map(|&(a, b)| (col_ptr[a], col_ptr[b]))
                .collect();
            let outputs: Vec<RowOutputs<'_>> = rows
                .iter()
                .zip(&dofs)
                .zip(&values)
                .zip(split_ranges(mass, &values))
                .zip(split_ranges(stiffness, &values))
                .zip(split_ranges(vector, &dofs))
                .zip(split_ranges(vector2, &dofs))
                .map(
                    |(
                        (((((&row, &(dof_base, _)), &(value_base, _)), mass), stiffness), vector),
                        vector2,
                    )| {
                        RowOutputs {
                            row,
                            value_base,
                            dof_base,
                            mass,
                            stiffness,
                            vector,
                            vector2,
                        }
                    },
                )
                .collect();
            outputs
                .into_par_iter()
                .for_each_init(&init, |scratch, mut out| kernel(scratch, &mut out));
        }
    }

    /// Adds the symmetric local blocks `mass_block`, `stiffness_block` (row-major, `ld × ld`
    /// over the element's local dofs `a · m + x`) of element `(span_u, span_v)` into `out`. By
    /// symmetry column `c` of a block is its row `c`, and the rows of one `u` function of the
    /// element are one contiguous run of the CSC column: slice additions.
    pub(crate) fn add_block(
        &self,
        span_u: usize,
        span_v: usize,
        mass_block: &[f64],
        stiffness_block: &[f64],
        out: &mut RowOutputs<'_>,
    ) {
        let (p, q) = self.degrees;
        let m = self.pattern.dofs_per_point();
        let run = (q + 1) * m;
        let ld = self.n_local() * m;
        for c in 0..ld {
            let col = self.point(span_u, span_v, c / m) * m + c % m;
            let (base, stride) = self.pattern.column_origin(col, span_u - p, span_v - q);
            let base = base - out.value_base;
            let kc = &stiffness_block[c * ld..(c + 1) * ld];
            // An empty mass block: the stiffness alone (the shell's tangent).
            let mc = mass_block.get(c * ld..(c + 1) * ld);
            for ia in 0..=p {
                let dst = base + ia * stride;
                let src = ia * run;
                if let Some(mc) = mc {
                    for (x, &y) in out.mass[dst..dst + run].iter_mut().zip(&mc[src..src + run]) {
                        *x += y;
                    }
                }
                for (x, &y) in out.stiffness[dst..dst + run]
                    .iter_mut()
                    .zip(&kc[src..src + run])
                {
                    *x += y;
                }
            }
        }
    }
}

/// B-spline values and first and second derivatives of the `p + 1` functions of every span at
/// its Gauss points, `values[((span · g + point) · 3 + order) · (p + 1) + a]` (The NURBS Book
/// A2.3); without a basis, the constant function 1 (the `v` direction of a curve).
#[derive(Clone, Debug)]
pub(crate) struct SpanBases {
    w: usize,
    g: usize,
    values: Vec<f64>,
}

impl SpanBases {
    pub(crate) fn new(basis: Option<&BSplineBasis>, spans: &[Span1d]) -> Self {
        let g = spans.first().map_or(0, |s| s.points.len());
        let Some(basis) = basis else {
            let mut values = vec![0.0; spans.len() * g * 3];
            for chunk in values.chunks_exact_mut(3) {
                chunk[0] = 1.0;
            }
            return Self { w: 1, g, values };
        };
        let w = basis.degree() + 1;
        let mut values = vec![0.0; spans.len() * g * 3 * w];
        let mut scratch = BasisScratch::default();
        for (s, chunk) in spans.iter().zip(values.chunks_exact_mut(g * 3 * w)) {
            for (&(x, _), out) in s.points.iter().zip(chunk.chunks_exact_mut(3 * w)) {
                basis.derivatives_into(s.span, x, 2, out, &mut scratch);
            }
        }
        Self { w, g, values }
    }

    /// `[N_a; N'_a; N''_a]` (3 rows of `p + 1`) of span `span` (its index among the non-empty
    /// spans) at its Gauss point `point`.
    #[inline]
    pub(crate) fn at(&self, span: usize, point: usize) -> &[f64] {
        let len = 3 * self.w;
        let start = (span * self.g + point) * len;
        &self.values[start..start + len]
    }
}

/// The rational basis `R, R_u, R_v, R_uu, R_uv, R_vv` of the local control points (u major,
/// `local[a] = (index, weight)`), slot-major: `r[s · n_local + a]`, from the 1-D B-spline rows
/// `nu`, `nv` of [`SpanBases::at`], up to `order` (slots above it hold no derivative): `A = w
/// N_a(u) N_b(v)` and its derivatives, `W = Σ A`, and the quotient rule (The NURBS Book eq.
/// (4.9)–(4.10)).
#[inline]
pub(crate) fn rational_basis(
    nu: &[f64],
    nv: &[f64],
    local: &[(usize, f64)],
    order: usize,
    r: &mut [f64],
) {
    let (wu, wv) = (nu.len() / 3, nv.len() / 3);
    let nl = local.len();
    let mut sum = [0.0; 6];
    for (a, &(_, w)) in local.iter().enumerate() {
        let (i, j) = (a / wv, a % wv);
        let (n0, n1, n2) = (nu[i], nu[wu + i], nu[2 * wu + i]);
        let (m0, m1, m2) = (nv[j], nv[wv + j], nv[2 * wv + j]);
        let x = [
            w * n0 * m0,
            w * n1 * m0,
            w * n0 * m1,
            w * n2 * m0,
            w * n1 * m1,
            w * n0 * m2,
        ];
        for s in 0..6 {
            r[s * nl + a] = x[s];
            sum[s] += x[s];
        }
    }
    let inv = 1.0 / sum[0];
    for a in 0..nl {
        let n = [0, 1, 2, 3, 4, 5].map(|s| r[s * nl + a]);
        let q = quotient_rule(&n, &sum, inv, order);
        // Slots above `order` keep what they held.
        let slots = match order {
            0 => 1,
            1 => 3,
            _ => 6,
        };
        for (s, &x) in q.iter().enumerate().take(slots) {
            r[s * nl + a] = x;
        }
    }
}

/// `|c_u × c_v|` (surface) or `|c_u|` (curve) from the local rational basis: the factor of the
/// area measure (docs/math.md §3, `Integration::Area`).
#[inline]
pub(crate) fn local_area_factor(
    points: &[[f64; 3]],
    local: &[(usize, f64)],
    r: &[f64],
    curve: bool,
) -> f64 {
    let nl = local.len();
    let mut cu = [0.0; 3];
    let mut cv = [0.0; 3];
    for (a, &(k, _)) in local.iter().enumerate() {
        let (ru, rv) = (r[nl + a], r[2 * nl + a]);
        for x in 0..3 {
            cu[x] += ru * points[k][x];
            cv[x] += rv * points[k][x];
        }
    }
    if curve {
        line_element(cu)
    } else {
        area_element(cu, cv)
    }
}

/// Copies the upper triangle of a row-major `n × n` block onto the lower one.
pub(crate) fn mirror_upper(a: &mut [f64], n: usize) {
    for i in 0..n {
        for j in 0..i {
            a[i * n + j] = a[j * n + i];
        }
    }
}
