//! Rational tensor-product surfaces (paper eq. 1; The NURBS Book §4.4–4.5).

use rayon::prelude::*;

use crate::basis::BasisScratch;
use crate::jacobian::{Deriv, SurfaceJacobian};
use crate::{BSplineBasis, GeomError, KnotVector, cross, norm, quotient_rule};

/// Degrees below this use stack buffers on the point-evaluation path.
const STACK: usize = 16;

/// A NURBS surface `c(u,v) = Σ R_ij(u,v) P_ij`, `R_ij = w_ij N_i(u) N_j(v) / W(u,v)`.
///
/// Control point `(i, j)` (i along u) has flat index `k = i · n_v + j`.
///
/// ```
/// use nurbspring_geom::{KnotVector, NurbsSurface};
/// // A bilinear patch spanning [0,3] × [0,5] at height 2.
/// let ku = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
/// let kv = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
/// let s = NurbsSurface::try_new(ku, kv,
///     vec![[0., 0., 2.], [0., 5., 2.], [3., 0., 2.], [3., 5., 2.]], vec![1.0; 4]).unwrap();
/// let c = s.point(0.5, 0.2).unwrap();
/// assert!((c[0] - 1.5).abs() < 1e-15 && (c[1] - 1.0).abs() < 1e-15 && c[2] == 2.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsSurface {
    basis_u: BSplineBasis,
    basis_v: BSplineBasis,
    control_points: Vec<[f64; 3]>,
    weights: Vec<f64>,
}

/// A point of a surface and its parametric derivatives up to second order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceDerivatives {
    /// c(u, v).
    pub point: [f64; 3],
    /// ∂c/∂u.
    pub u: [f64; 3],
    /// ∂c/∂v.
    pub v: [f64; 3],
    /// ∂²c/∂u².
    pub uu: [f64; 3],
    /// ∂²c/∂u∂v.
    pub uv: [f64; 3],
    /// ∂²c/∂v².
    pub vv: [f64; 3],
}

impl SurfaceDerivatives {
    /// The derivative selected by `d`.
    pub fn get(&self, d: Deriv) -> [f64; 3] {
        match d {
            Deriv::Value => self.point,
            Deriv::U => self.u,
            Deriv::V => self.v,
            Deriv::UU => self.uu,
            Deriv::UV => self.uv,
            Deriv::VV => self.vv,
        }
    }

    fn slot(&mut self, d: usize) -> &mut [f64; 3] {
        match d {
            0 => &mut self.point,
            1 => &mut self.u,
            2 => &mut self.v,
            3 => &mut self.uu,
            4 => &mut self.uv,
            _ => &mut self.vv,
        }
    }
}

/// The non-zero rational basis functions `R_k` at one `(u, v)` and their derivatives, in a
/// reusable buffer (no allocation after the first use at a given degree).
#[derive(Clone, Debug, Default)]
pub struct LocalRationalBasis {
    /// Knot span in u.
    pub span_u: usize,
    /// Knot span in v.
    pub span_v: usize,
    /// Flat control point indices of the `(p+1)(q+1)` non-zero functions.
    pub indices: Vec<usize>,
    /// For each of them: `[R, R_u, R_v, R_uu, R_uv, R_vv]` (entries beyond the requested order are 0).
    pub r: Vec<[f64; 6]>,
    /// For each of them: `[A, A_u, …]` with `A_k = N_k / W = R_k / w_k` (used by ∂c/∂w).
    pub a: Vec<[f64; 6]>,
    nu: Vec<f64>,
    nv: Vec<f64>,
    scratch: BasisScratch,
}

impl NurbsSurface {
    /// Validates and builds a surface. `control_points.len()` must be `n_u · n_v` where
    /// `n_u`, `n_v` are the numbers of basis functions; weights positive and finite.
    pub fn try_new(
        knots_u: KnotVector,
        knots_v: KnotVector,
        control_points: Vec<[f64; 3]>,
        weights: Vec<f64>,
    ) -> Result<Self, GeomError> {
        let (nu, nv) = (knots_u.n_basis(), knots_v.n_basis());
        if control_points.len() != nu * nv {
            return Err(GeomError::ControlPointCount {
                expected: nu * nv,
                found: control_points.len(),
                detail: format!(
                    "{nu} along u from {} knots of degree {}, times {nv} along v from {} knots of degree {}",
                    knots_u.knots().len(),
                    knots_u.degree(),
                    knots_v.knots().len(),
                    knots_v.degree()
                ),
            });
        }
        if weights.len() != nu * nv {
            return Err(GeomError::WeightCount {
                expected: nu * nv,
                found: weights.len(),
            });
        }
        check_points_and_weights(&control_points, &weights)?;
        Ok(Self {
            basis_u: BSplineBasis::new(knots_u),
            basis_v: BSplineBasis::new(knots_v),
            control_points,
            weights,
        })
    }

    /// The u basis.
    pub fn basis_u(&self) -> &BSplineBasis {
        &self.basis_u
    }

    /// The v basis.
    pub fn basis_v(&self) -> &BSplineBasis {
        &self.basis_v
    }

    /// Number of control points along u.
    pub fn n_u(&self) -> usize {
        self.basis_u.len()
    }

    /// Number of control points along v.
    pub fn n_v(&self) -> usize {
        self.basis_v.len()
    }

    /// Total number of control points.
    pub fn n_control_points(&self) -> usize {
        self.control_points.len()
    }

    /// Control points, flat index `i · n_v + j`.
    pub fn control_points(&self) -> &[[f64; 3]] {
        &self.control_points
    }

    /// Weights, flat index `i · n_v + j`.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Flat index of control point `(i, j)`.
    pub fn index(&self, i: usize, j: usize) -> usize {
        i * self.n_v() + j
    }

    /// The parameter domain `((u0, u1), (v0, v1))`.
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        (self.basis_u.knots().domain(), self.basis_v.knots().domain())
    }

    /// A copy with other control points (same count), e.g. a deformed state `p(t)`.
    pub fn with_control_points(&self, control_points: Vec<[f64; 3]>) -> Result<Self, GeomError> {
        Self::try_new(
            self.basis_u.knots().clone(),
            self.basis_v.knots().clone(),
            control_points,
            self.weights.clone(),
        )
    }

    /// A copy with other control points and weights.
    pub fn with_control_points_and_weights(
        &self,
        control_points: Vec<[f64; 3]>,
        weights: Vec<f64>,
    ) -> Result<Self, GeomError> {
        Self::try_new(
            self.basis_u.knots().clone(),
            self.basis_v.knots().clone(),
            control_points,
            weights,
        )
    }

    /// Checks `(u, v)` against the domain.
    pub fn check_parameters(&self, u: f64, v: f64) -> Result<(), GeomError> {
        self.basis_u.knots().check_parameter("u", u)?;
        self.basis_v.knots().check_parameter("v", v)
    }

    /// Fills `out` with the rational basis at `(u, v)` and its derivatives up to `order`
    /// (0, 1 or 2) by the quotient rule (The NURBS Book eq. 4.8 and A4.4 applied to `R`).
    /// Parameters are not checked (call [`NurbsSurface::check_parameters`] first).
    pub fn rational_basis_into(&self, u: f64, v: f64, order: usize, out: &mut LocalRationalBasis) {
        let order = order.min(2);
        let (p, q) = (self.basis_u.degree(), self.basis_v.degree());
        let (wu, wv) = (p + 1, q + 1);
        let su = self.basis_u.find_span(u);
        let sv = self.basis_v.find_span(v);
        out.span_u = su;
        out.span_v = sv;
        out.nu.resize((order + 1) * wu, 0.0);
        out.nv.resize((order + 1) * wv, 0.0);
        self.basis_u
            .derivatives_into(su, u, order, &mut out.nu, &mut out.scratch);
        self.basis_v
            .derivatives_into(sv, v, order, &mut out.nv, &mut out.scratch);
        let n_local = wu * wv;
        out.indices.resize(n_local, 0);
        out.r.resize(n_local, [0.0; 6]);
        out.a.resize(n_local, [0.0; 6]);
        let n_v = self.n_v();
        // Tensor derivative orders (du, dv) of the six slots.
        const ORDERS: [(usize, usize); 6] = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)];
        let n_slots = match order {
            0 => 1,
            1 => 3,
            _ => 6,
        };
        let mut big_w = [0.0; 6];
        for a in 0..wu {
            for b in 0..wv {
                let l = a * wv + b;
                let k = (su - p + a) * n_v + (sv - q + b);
                out.indices[l] = k;
                let w = self.weights[k];
                let mut nn = [0.0; 6];
                for s in 0..n_slots {
                    let (du, dv) = ORDERS[s];
                    nn[s] = out.nu[du * wu + a] * out.nv[dv * wv + b];
                    big_w[s] += w * nn[s];
                }
                out.a[l] = nn; // temporarily the non-rational tensor basis and derivatives
            }
        }
        let inv_w = 1.0 / big_w[0];
        for l in 0..n_local {
            let n = out.a[l];
            // A = N / W and its derivatives by the quotient rule.
            let a = quotient_rule(&n, &big_w, inv_w, order);
            let w = self.weights[out.indices[l]];
            out.a[l] = a;
            out.r[l] = a.map(|x| w * x);
        }
    }

    /// The rational basis at `(u, v)` up to `order`, parameters checked.
    pub fn rational_basis(
        &self,
        u: f64,
        v: f64,
        order: usize,
    ) -> Result<LocalRationalBasis, GeomError> {
        self.check_parameters(u, v)?;
        let mut out = LocalRationalBasis::default();
        self.rational_basis_into(u, v, order, &mut out);
        Ok(out)
    }

    fn combine(&self, basis: &LocalRationalBasis, order: usize) -> SurfaceDerivatives {
        let n_slots = match order {
            0 => 1,
            1 => 3,
            _ => 6,
        };
        let mut d = SurfaceDerivatives::default();
        for (l, &k) in basis.indices.iter().enumerate() {
            let pk = self.control_points[k];
            for s in 0..n_slots {
                let r = basis.r[l][s];
                let slot = d.slot(s);
                slot[0] += r * pk[0];
                slot[1] += r * pk[1];
                slot[2] += r * pk[2];
            }
        }
        d
    }

    /// Point and derivatives up to `order` (0, 1, 2) at `(u, v)` with a caller-owned buffer;
    /// parameters not checked.
    pub fn derivatives_with(
        &self,
        u: f64,
        v: f64,
        order: usize,
        buffer: &mut LocalRationalBasis,
    ) -> SurfaceDerivatives {
        self.rational_basis_into(u, v, order, buffer);
        self.combine(buffer, order)
    }

    /// `c(u, v)`.
    pub fn point(&self, u: f64, v: f64) -> Result<[f64; 3], GeomError> {
        self.check_parameters(u, v)?;
        Ok(self.point_unchecked(u, v))
    }

    /// `c(u, v)` without the domain check (parameters outside are clamped to the end spans).
    ///
    /// This is the hot path of [`NurbsSurface::point`] and [`NurbsSurface::points`]: A2.1 spans,
    /// A2.2 values in stack buffers (unrolled for degrees 1–4 in each direction), then
    /// `Σ N_a N_b w_ab P_ab / Σ N_a N_b w_ab` over the `(p+1)(q+1)` non-zero terms. No
    /// allocation.
    #[inline]
    pub fn point_unchecked(&self, u: f64, v: f64) -> [f64; 3] {
        macro_rules! fixed {
            ($(($p:literal, $q:literal)),* $(,)?) => {
                match (self.basis_u.degree(), self.basis_v.degree()) {
                    $(($p, $q) => return self.point_fixed::<{ $p + 1 }, { $q + 1 }>(u, v),)*
                    _ => {}
                }
            };
        }
        fixed!(
            (1, 1),
            (1, 2),
            (1, 3),
            (1, 4),
            (2, 1),
            (2, 2),
            (2, 3),
            (2, 4),
            (3, 1),
            (3, 2),
            (3, 3),
            (3, 4),
            (4, 1),
            (4, 2),
            (4, 3),
            (4, 4),
        );
        let (p, q) = (self.basis_u.degree(), self.basis_v.degree());
        let su = self.basis_u.find_span(u);
        let sv = self.basis_v.find_span(v);
        if p < STACK && q < STACK {
            let nu = self.basis_u.values_stack::<STACK>(su, u);
            let nv = self.basis_v.values_stack::<STACK>(sv, v);
            return self.point_from_bases(su, sv, &nu[..=p], &nv[..=q]);
        }
        let mut scratch = BasisScratch::default();
        let mut nu = vec![0.0; p + 1];
        let mut nv = vec![0.0; q + 1];
        self.basis_u.values_into(su, u, &mut nu, &mut scratch);
        self.basis_v.values_into(sv, v, &mut nv, &mut scratch);
        self.point_from_bases(su, sv, &nu, &nv)
    }

    /// [`NurbsSurface::point_unchecked`] for degrees `WU − 1`, `WV − 1` known at compile time:
    /// the same operations in the same order as the generic path (bit-identical results).
    #[inline(always)]
    fn point_fixed<const WU: usize, const WV: usize>(&self, u: f64, v: f64) -> [f64; 3] {
        let su = self.basis_u.find_span(u);
        let sv = self.basis_v.find_span(v);
        let nu = self.basis_u.values_stack::<WU>(su, u);
        let nv = self.basis_v.values_stack::<WV>(sv, v);
        let n_v = self.n_v();
        let mut h = [0.0; 4];
        for (a, &na) in nu.iter().enumerate() {
            let start = (su + 1 + a - WU) * n_v + sv + 1 - WV;
            let weights = &self.weights[start..start + WV];
            let points = &self.control_points[start..start + WV];
            for b in 0..WV {
                let c = na * nv[b] * weights[b];
                let pk = points[b];
                h[0] += c * pk[0];
                h[1] += c * pk[1];
                h[2] += c * pk[2];
                h[3] += c;
            }
        }
        [h[0] / h[3], h[1] / h[3], h[2] / h[3]]
    }

    fn point_from_bases(&self, su: usize, sv: usize, nu: &[f64], nv: &[f64]) -> [f64; 3] {
        let (p, q) = (nu.len() - 1, nv.len() - 1);
        let n_v = self.n_v();
        let mut h = [0.0; 4];
        for (a, &na) in nu.iter().enumerate() {
            let row = (su - p + a) * n_v + sv - q;
            for (b, &nb) in nv.iter().enumerate() {
                let k = row + b;
                let c = na * nb * self.weights[k];
                let pk = self.control_points[k];
                h[0] += c * pk[0];
                h[1] += c * pk[1];
                h[2] += c * pk[2];
                h[3] += c;
            }
        }
        [h[0] / h[3], h[1] / h[3], h[2] / h[3]]
    }

    /// Point and derivatives up to `order` (0, 1 or 2; higher is treated as 2) at `(u, v)`.
    pub fn derivatives(
        &self,
        u: f64,
        v: f64,
        order: usize,
    ) -> Result<SurfaceDerivatives, GeomError> {
        self.check_parameters(u, v)?;
        // A per-thread buffer: no allocation after the first call on a thread.
        thread_local! {
            static BUFFER: std::cell::RefCell<LocalRationalBasis> =
                std::cell::RefCell::new(LocalRationalBasis::default());
        }
        Ok(BUFFER.with(|b| self.derivatives_with(u, v, order, &mut b.borrow_mut())))
    }

    /// Unit normal `c_u × c_v / |c_u × c_v|`.
    pub fn normal(&self, u: f64, v: f64) -> Result<[f64; 3], GeomError> {
        let d = self.derivatives(u, v, 1)?;
        let n = cross(d.u, d.v);
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let scale = norm(d.u) * norm(d.v);
        // Written so that a NaN length also counts as degenerate.
        let regular = len > 1e-12 * scale && len > 0.0;
        if !regular {
            return Err(GeomError::DegenerateNormal { u, v });
        }
        Ok([n[0] / len, n[1] / len, n[2] / len])
    }

    /// Points at many parameters, in parallel; every parameter checked first.
    pub fn points(&self, params: &[(f64, f64)]) -> Result<Vec<[f64; 3]>, GeomError> {
        for &(u, v) in params {
            self.check_parameters(u, v)?;
        }
        Ok(params
            .par_iter()
            .map(|&(u, v)| self.point_unchecked(u, v))
            .collect())
    }

    /// Points and derivatives up to `order` at many parameters, in parallel.
    pub fn derivatives_batch(
        &self,
        params: &[(f64, f64)],
        order: usize,
    ) -> Result<Vec<SurfaceDerivatives>, GeomError> {
        for &(u, v) in params {
            self.check_parameters(u, v)?;
        }
        Ok(params
            .par_iter()
            .map_init(LocalRationalBasis::default, |buffer, &(u, v)| {
                self.derivatives_with(u, v, order, buffer)
            })
            .collect())
    }

    /// Points on the tensor grid `us × vs` (row `i` is `us[i]`, point index `i · vs.len() + j`).
    ///
    /// Uses the tensor structure: the u and v bases are evaluated once per row and column, and
    /// each row first contracts the control net along u into one homogeneous curve in v
    /// (`(p+1) · n_v` operations), then evaluates that curve at every `v` (`q + 1` each).
    /// Rows run in parallel.
    pub fn grid(&self, us: &[f64], vs: &[f64]) -> Result<Vec<[f64; 3]>, GeomError> {
        // The row loops are compiled for the widest vector unit of the CPU (pulp's runtime
        // dispatch); they are the same IEEE operations in the same order at any width, so
        // every width gives the same bits.
        self.grid_with(us, vs, &|row| pulp::Arch::new().dispatch(row))
    }

    /// [`NurbsSurface::grid`] with each row filled by `fill` (a vector width chosen).
    fn grid_with(
        &self,
        us: &[f64],
        vs: &[f64],
        fill: &(dyn Fn(GridRow<'_>) + Sync),
    ) -> Result<Vec<[f64; 3]>, GeomError> {
        for &u in us {
            self.basis_u.knots().check_parameter("u", u)?;
        }
        for &v in vs {
            self.basis_v.knots().check_parameter("v", v)?;
        }
        let (p, q) = (self.basis_u.degree(), self.basis_v.degree());
        let n_v = self.n_v();
        let mut scratch = BasisScratch::default();
        // v bases once per column, stored by basis index (`nv[b · n + j]`, so that a run of
        // columns reads each basis function's values contiguously), and the columns grouped
        // into runs of one knot span.
        let n = vs.len();
        let mut runs: Vec<(usize, usize, usize)> = Vec::new(); // (first column, end, span)
        let mut nv = vec![0.0; n * (q + 1)];
        let mut values = vec![0.0; q + 1];
        for (j, &v) in vs.iter().enumerate() {
            let s = self.basis_v.find_span(v);
            match runs.last_mut() {
                Some(run) if run.2 == s && run.1 == j => run.1 = j + 1,
                _ => runs.push((j, j + 1, s)),
            }
            self.basis_v.values_into(s, v, &mut values, &mut scratch);
            for (b, &value) in values.iter().enumerate() {
                nv[b * n + j] = value;
            }
        }
        // Homogeneous control net.
        let hw: Vec<[f64; 4]> = self
            .control_points
            .iter()
            .zip(&self.weights)
            .map(|(c, &w)| [c[0] * w, c[1] * w, c[2] * w, w])
            .collect();
        let mut out = vec![[0.0; 3]; us.len() * n];
        out.par_chunks_mut(n.max(1))
            .zip(us.par_iter())
            .for_each_init(
                || {
                    (
                        BasisScratch::default(),
                        vec![0.0; p + 1],
                        vec![[0.0; 4]; n_v],
                    )
                },
                |(scratch, nu, curve), (row, &u)| {
                    let su = self.basis_u.find_span(u);
                    self.basis_u.values_into(su, u, nu, scratch);
                    let (nu, curve) = (&*nu, &mut *curve);
                    fill(GridRow {
                        nu,
                        su,
                        p,
                        q,
                        n_v,
                        hw: &hw,
                        nv: &nv,
                        runs: &runs,
                        curve,
                        row,
                    });
                },
            );
        Ok(out)
    }

    /// `nu × nv` uniformly spaced parameters over the domain (endpoints included) and the
    /// points there; see [`NurbsSurface::grid`].
    pub fn uniform_grid(
        &self,
        nu: usize,
        nv: usize,
    ) -> Result<(Vec<f64>, Vec<f64>, Vec<[f64; 3]>), GeomError> {
        let ((u0, u1), (v0, v1)) = self.domain();
        let us = linspace(u0, u1, nu);
        let vs = linspace(v0, v1, nv);
        let pts = self.grid(&us, &vs)?;
        Ok((us, vs, pts))
    }

    /// The Jacobian `J(u, v) = ∂c/∂p` and its parametric derivatives (docs/math.md §2), with 3 dofs
    /// per control point, or 4 when `weights_as_dofs` (the extra column of point k is
    /// `∂c/∂w_k = N_k (P_k − c) / W`). Only the `(p+1)(q+1)` non-zero blocks are stored.
    pub fn jacobian(
        &self,
        u: f64,
        v: f64,
        order: usize,
        weights_as_dofs: bool,
    ) -> Result<SurfaceJacobian, GeomError> {
        self.check_parameters(u, v)?;
        let mut buffer = LocalRationalBasis::default();
        let mut out = SurfaceJacobian::default();
        self.jacobian_into(u, v, order, weights_as_dofs, &mut buffer, &mut out);
        Ok(out)
    }

    /// [`NurbsSurface::jacobian`] into caller buffers, parameters unchecked (hot loops).
    pub fn jacobian_into(
        &self,
        u: f64,
        v: f64,
        order: usize,
        weights_as_dofs: bool,
        buffer: &mut LocalRationalBasis,
        out: &mut SurfaceJacobian,
    ) {
        let order = order.min(2);
        self.rational_basis_into(u, v, order, buffer);
        out.n_control_points = self.n_control_points();
        out.dofs_per_point = if weights_as_dofs { 4 } else { 3 };
        out.order = order;
        out.indices.clear();
        out.indices.extend_from_slice(&buffer.indices);
        out.r.clear();
        out.r.extend_from_slice(&buffer.r);
        out.weight_columns.clear();
        if weights_as_dofs {
            let c = self.combine(buffer, order);
            for (l, &k) in buffer.indices.iter().enumerate() {
                out.weight_columns.push(weight_column(
                    &buffer.a[l],
                    self.control_points[k],
                    &c,
                    order,
                ));
            }
        }
    }
}

/// One row of [`NurbsSurface::grid`]: the u bases `nu` of span `su`, the homogeneous net `hw`,
/// the v bases `nv` by basis index, the column runs of one v span, a curve buffer and the row
/// of points to fill.
struct GridRow<'a> {
    nu: &'a [f64],
    su: usize,
    p: usize,
    q: usize,
    n_v: usize,
    hw: &'a [[f64; 4]],
    nv: &'a [f64],
    runs: &'a [(usize, usize, usize)],
    curve: &'a mut [[f64; 4]],
    row: &'a mut [[f64; 3]],
}

impl pulp::WithSimd for GridRow<'_> {
    type Output = ();

    /// Fills the row; inlined into pulp's dispatcher, so its loops are compiled for the CPU
    /// found at run time.
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        grid_row(simd, self)
    }
}

/// Fills one grid row with the vectors of `simd`.
#[inline(always)]
fn grid_row<S: pulp::Simd>(simd: S, g: GridRow<'_>) {
    let GridRow {
        nu,
        su,
        p,
        q,
        n_v,
        hw,
        nv,
        runs,
        curve,
        row,
    } = g;
    let n = row.len();
    for c in curve.iter_mut() {
        *c = [0.0; 4];
    }
    for (a, &na) in nu.iter().enumerate() {
        let base = (su - p + a) * n_v;
        for (c, h) in curve.iter_mut().zip(&hw[base..base + n_v]) {
            c[0] += na * h[0];
            c[1] += na * h[1];
            c[2] += na * h[2];
            c[3] += na * h[3];
        }
    }
    // Within a run of one span every point combines the same q + 1 curve coefficients: the
    // homogeneous sums run over the points of the run in vectors of `S::F64_LANES` (the rest
    // one by one), in the order b = 0..q of a single point, and so do the divisions: the same
    // IEEE operations as one point at a time, so the same bits at any vector width.
    let lanes = S::F64_LANES;
    for &(j0, j1, s) in runs {
        let coefficients = &curve[s - q..=s];
        let mut j = j0;
        while j + lanes <= j1 {
            let zero = simd.splat_f64s(0.0);
            let mut h = [zero; 4];
            for (b, c) in coefficients.iter().enumerate() {
                let w = S::as_simd_f64s(&nv[b * n + j..b * n + j + lanes]).0[0];
                for x in 0..4 {
                    h[x] = simd.add_f64s(h[x], simd.mul_f64s(w, simd.splat_f64s(c[x])));
                }
            }
            let mut xyz = [[0.0; MAX_LANES]; 3];
            for x in 0..3 {
                S::as_mut_simd_f64s(&mut xyz[x][..lanes]).0[0] = simd.div_f64s(h[x], h[3]);
            }
            for (t, point) in row[j..j + lanes].iter_mut().enumerate() {
                *point = [xyz[0][t], xyz[1][t], xyz[2][t]];
            }
            j += lanes;
        }
        for (j, point) in row.iter_mut().enumerate().take(j1).skip(j) {
            let mut h = [0.0; 4];
            for (b, c) in coefficients.iter().enumerate() {
                let w = nv[b * n + j];
                for x in 0..4 {
                    h[x] += w * c[x];
                }
            }
            *point = [h[0] / h[3], h[1] / h[3], h[2] / h[3]];
        }
    }
}

/// The most f64 lanes of a vector register (AVX-512).
const MAX_LANES: usize = 8;

/// Derivatives of `∂c/∂w_k = A_k (P_k − c)` with `A_k = N_k / W`:
/// `∂_u = A_u (P − c) − A c_u`, `∂_uu = A_uu (P − c) − 2 A_u c_u − A c_uu`,
/// `∂_uv = A_uv (P − c) − A_u c_v − A_v c_u − A c_uv`, and likewise in v.
pub(crate) fn weight_column(
    a: &[f64; 6],
    pk: [f64; 3],
    c: &SurfaceDerivatives,
    order: usize,
) -> [[f64; 3]; 6] {
    let mut col = [[0.0; 3]; 6];
    for x in 0..3 {
        let diff = pk[x] - c.point[x];
        col[0][x] = a[0] * diff;
        if order >= 1 {
            col[1][x] = a[1] * diff - a[0] * c.u[x];
            col[2][x] = a[2] * diff - a[0] * c.v[x];
        }
        if order >= 2 {
            col[3][x] = a[3] * diff - 2.0 * a[1] * c.u[x] - a[0] * c.uu[x];
            col[4][x] = a[4] * diff - a[1] * c.v[x] - a[2] * c.u[x] - a[0] * c.uv[x];
            col[5][x] = a[5] * diff - 2.0 * a[2] * c.v[x] - a[0] * c.vv[x];
        }
    }
    col
}

pub(crate) fn check_points_and_weights(
    control_points: &[[f64; 3]],
    weights: &[f64],
) -> Result<(), GeomError> {
    for (index, p) in control_points.iter().enumerate() {
        for &value in p {
            if !value.is_finite() {
                return Err(GeomError::NonFiniteControlPoint { index, value });
            }
        }
    }
    for (index, &value) in weights.iter().enumerate() {
        if !(value.is_finite() && value > 0.0) {
            return Err(GeomError::InvalidWeight { index, value });
        }
    }
    Ok(())
}

/// `n` evenly spaced values from `a` to `b` inclusive (`[a]` when n = 1).
pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![a],
        _ => (0..n)
            .map(|i| {
                if i == n - 1 {
                    b
                } else {
                    a + (b - a) * i as f64 / (n - 1) as f64
                }
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pulp::WithSimd;

    #[test]
    fn grid_rows_give_the_same_bits_at_every_vector_width() {
        // A rational bicubic patch with interior knots (runs of several spans), on a grid
        // whose row length is not a multiple of any width (vector and one-by-one parts).
        let k =
            KnotVector::try_new(vec![0., 0., 0., 0., 0.15, 0.5, 0.7, 1., 1., 1., 1.], 3).unwrap();
        let mut pts = Vec::new();
        let mut ws = Vec::new();
        for i in 0..7 {
            for j in 0..7 {
                pts.push([
                    i as f64 / 6.0,
                    j as f64 / 6.0,
                    ((3 * i + 5 * j) % 7) as f64 / 9.0,
                ]);
                ws.push(1.0 + ((i + 2 * j) % 3) as f64 / 4.0);
            }
        }
        let s = NurbsSurface::try_new(k.clone(), k, pts, ws).unwrap();
        let us = linspace(0.0, 1.0, 13);
        let vs = linspace(0.0, 1.0, 37);
        // One point at a time (1 lane) is the reference; the A2.2 point agrees to round-off
        // (its sum runs over the tensor product in another order).
        let expected = s
            .grid_with(&us, &vs, &|row| row.with_simd(pulp::Scalar))
            .unwrap();
        let mut k = 0;
        for &u in &us {
            for &v in &vs {
                let p = point_reference(&s, u, v);
                for x in 0..3 {
                    assert!(
                        (expected[k][x] - p[x]).abs() <= 8.0 * f64::EPSILON,
                        "{u} {v}"
                    );
                }
                k += 1;
            }
        }
        let widths: [(&str, &(dyn Fn(GridRow<'_>) + Sync)); 5] = [
            ("dispatched", &|row| pulp::Arch::new().dispatch(row)),
            ("1 lane", &|row| row.with_simd(pulp::Scalar)),
            ("2 lanes", &|row| row.with_simd(pulp::Scalar128b)),
            ("4 lanes", &|row| row.with_simd(pulp::Scalar256b)),
            ("8 lanes", &|row| row.with_simd(pulp::Scalar512b)),
        ];
        for (name, fill) in widths {
            let got = s.grid_with(&us, &vs, fill).unwrap();
            assert_eq!(got, expected, "{name}");
        }
    }

    /// The reference path: A2.2 with heap scratch, then the same contraction.
    fn point_reference(s: &NurbsSurface, u: f64, v: f64) -> [f64; 3] {
        let (p, q) = (s.basis_u.degree(), s.basis_v.degree());
        let su = s.basis_u.find_span(u);
        let sv = s.basis_v.find_span(v);
        let mut scratch = BasisScratch::default();
        let mut nu = vec![0.0; p + 1];
        let mut nv = vec![0.0; q + 1];
        s.basis_u.values_into(su, u, &mut nu, &mut scratch);
        s.basis_v.values_into(sv, v, &mut nv, &mut scratch);
        s.point_from_bases(su, sv, &nu, &nv)
    }

    /// The specialised (const-degree, stack) evaluators are bit-identical to the generic one,
    /// for every degree pair up to 6 (the unrolled ones and the stack fallback).
    #[test]
    fn fast_point_paths_are_bit_identical() {
        for p in 1..=6 {
            for q in 1..=6 {
                let ku = KnotVector::clamped_uniform(p, 3).unwrap();
                let kv = KnotVector::try_new(
                    [vec![-1.0; q + 1], vec![-0.3, 0.2, 0.2], vec![2.0; q + 1]].concat(),
                    q,
                )
                .unwrap();
                let n = ku.n_basis() * kv.n_basis();
                let pts: Vec<[f64; 3]> = (0..n)
                    .map(|i| {
                        let x = i as f64;
                        [x.sin(), (0.7 * x).cos(), 0.1 * x]
                    })
                    .collect();
                let ws: Vec<f64> = (0..n).map(|i| 0.5 + (i % 5) as f64 * 0.3).collect();
                let s = NurbsSurface::try_new(ku, kv, pts, ws).unwrap();
                for i in 0..=20 {
                    for j in 0..=20 {
                        let (u, v) = (i as f64 / 20.0, -1.0 + 3.0 * j as f64 / 20.0);
                        let fast = s.point(u, v).unwrap();
                        assert_eq!(
                            fast,
                            point_reference(&s, u, v),
                            "p = {p}, q = {q}, ({u}, {v})"
                        );
                    }
                }
            }
        }
    }
}
