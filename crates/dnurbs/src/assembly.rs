//! Assembly of the D-NURBS matrices `M`, `D`, `K` and the load vector `f_p` by Gauss–Legendre
//! quadrature over the non-empty knot spans (paper eqs. (3)–(4), docs/math.md §3).
//!
//! The sparsity pattern is written once per discretization from the knot spans
//! ([`TensorLayout`], a [`KroneckerPattern`] `A_u ⊗ A_v ⊗ 1_{m×m}`: no sort, arithmetic
//! positions). Element blocks are summed into the CSC values in place; element rows (one `u`
//! span, every `v` span) `p + 1` spans apart touch disjoint columns and run in parallel with
//! rayon, without locks. With constant weights the kernels work on the scalar `N × N` matrices
//! `S` and the dof matrices are `S ⊗ I_3` (interleaved ordering, docs/math.md §1); a B-spline
//! integrated over the parameter domain takes the exact Kronecker form `S = Σ c_t G_u ⊗ G_v` of
//! 1-D Gram matrices, anything else the Gauss-point kernel. With weights as unknowns the
//! kernels fill full `4N × 4N` blocks through the Jacobian with weight columns.

use nurbspring_geom::{
    BSplineBasis, BasisScratch, Jacobian, LocalRationalBasis, area_element, line_element,
};
use nurbspring_linalg::{KroneckerPattern, SparseMatrix};
use nurbspring_sim::PointDofs;
use rayon::prelude::*;

use crate::layout::{
    Span1d, SpanBases, TensorLayout, local_area_factor, mirror_upper, rational_basis, split_ranges,
};
use crate::{DnurbsError, DnurbsOptions, Geometry, Integration, Loads, Material};

/// Full-size matrices on all dofs (ordering docs/math.md §1), evaluated at the geometry given.
///
/// `mass = ∫∫ μ JᵀJ`, `damping = ∫∫ γ JᵀJ`, `stiffness` = paper eq. (4), `force = f_p`
/// (gravity `μ g`, distributed and point loads; docs/math.md §3).
#[derive(Clone, Debug)]
pub struct Matrices {
    /// M (paper eq. (3)).
    pub mass: SparseMatrix,
    /// D (paper eq. (3)).
    pub damping: SparseMatrix,
    /// K (paper eq. (4)).
    pub stiffness: SparseMatrix,
    /// f_p, the generalized external force (docs/math.md §3).
    pub force: Vec<f64>,
    /// 3 (constant weights) or 4 (weights as unknowns).
    pub dofs_per_point: usize,
}

impl Matrices {
    /// Number of generalized coordinates (rows of every matrix).
    pub fn n_dofs(&self) -> usize {
        self.force.len()
    }
}

/// Scalar `N × N` matrices of the constant-weight case: `M = S_M ⊗ I_3`, `D = S_D ⊗ I_3`,
/// `K = S_K ⊗ I_3` (docs/math.md §3; `S_M = ∫∫ μ R Rᵀ`, `S_K = ∫∫ α11 R_u R_uᵀ + … + β22 R_vv R_vvᵀ`).
#[derive(Clone, Debug)]
pub struct ScalarMatrices {
    /// S_M.
    pub mass: SparseMatrix,
    /// S_D.
    pub damping: SparseMatrix,
    /// S_K.
    pub stiffness: SparseMatrix,
}

/// Assembles `M`, `D`, `K` and `f_p` on all dofs (paper eqs. (3)–(4), docs/math.md §3) by Gauss
/// quadrature over knot spans, pattern computed once, element values in parallel.
///
/// With constant weights (3 dofs per control point) this is [`assemble_scalar`] expanded with
/// `⊗ I_3`; with `options.weights_as_dofs` the full `4N × 4N` matrices are assembled through the
/// Jacobian with weight columns at the geometry given. To assemble repeatedly on the same
/// knots, build an [`Assembler`] once.
///
/// The mass of a constant-weight patch sums to `3 μ · (parameter area)`, because the rational
/// basis is a partition of unity:
/// ```
/// use nurbspring_dnurbs::{assemble, DnurbsOptions, Geometry, Loads, Material};
/// use nurbspring_geom::{KnotVector, NurbsSurface};
/// let k = KnotVector::clamped_uniform(2, 3).unwrap();
/// let pts: Vec<[f64; 3]> = (0..25).map(|i| [(i / 5) as f64, (i % 5) as f64, 0.0]).collect();
/// let s = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 25]).unwrap();
/// let material = Material { mu: 2.0, alpha11: 1.0, alpha22: 1.0, ..Material::default() };
/// let m = assemble(&Geometry::Surface(s), &material, &Loads::default(), &DnurbsOptions::default()).unwrap();
/// assert!((m.mass.sum() - 3.0 * 2.0).abs() < 1e-13);
/// ```
pub fn assemble(
    geometry: &Geometry,
    material: &Material,
    loads: &Loads,
    options: &DnurbsOptions,
) -> Result<Matrices, DnurbsError> {
    Assembler::new(geometry, options)?.assemble(geometry, material, loads)
}

/// The scalar matrices `S_M`, `S_D`, `S_K` with `M = S_M ⊗ I_3` etc. (docs/math.md §3, constant
/// weights; the fast path of [`assemble`]). `options.weights_as_dofs` is ignored.
pub fn assemble_scalar(
    geometry: &Geometry,
    material: &Material,
    options: &DnurbsOptions,
) -> Result<ScalarMatrices, DnurbsError> {
    let options = DnurbsOptions {
        weights_as_dofs: false,
        ..options.clone()
    };
    Assembler::new(geometry, &options)?.assemble_scalar(geometry, material)
}

/// Reusable assembly on fixed knot vectors: the element layout and the sparsity pattern are
/// built once in [`Assembler::new`] (the expensive, value-independent part), then
/// [`Assembler::assemble`] fills and sums element blocks for any control points, weights,
/// material and loads on the same knots (paper eqs. (3)–(4), docs/math.md §3).
pub struct Assembler {
    options: DnurbsOptions,
    knots: (Vec<f64>, Vec<f64>, (usize, usize)),
    kind: AssemblerKind,
}

enum AssemblerKind {
    Scalar(ScalarAssembler),
    General(GeneralAssembler),
}

impl Assembler {
    /// Element layout and pattern for `geometry`'s knots: scalar `N × N` with constant weights,
    /// `4N × 4N` with `options.weights_as_dofs`. Without `quadrature_points` the rule is
    /// [`DnurbsOptions::quadrature_for`] of `geometry`; [`Assembler::options`] holds the
    /// resolved count.
    pub fn new(geometry: &Geometry, options: &DnurbsOptions) -> Result<Self, DnurbsError> {
        options.validate()?;
        let points = match options.quadrature_points {
            Some(points) => points,
            None => options.quadrature_for(geometry)?.points,
        };
        let kind = if options.weights_as_dofs {
            AssemblerKind::General(GeneralAssembler::new(geometry, points, 4)?)
        } else {
            AssemblerKind::Scalar(ScalarAssembler::new(geometry, points)?)
        };
        Ok(Self {
            options: DnurbsOptions {
                quadrature_points: Some(points),
                ..options.clone()
            },
            knots: knots_of(geometry),
            kind,
        })
    }

    /// The options the assembler was built with.
    pub fn options(&self) -> &DnurbsOptions {
        &self.options
    }

    fn check_geometry(&self, geometry: &Geometry) -> Result<(), DnurbsError> {
        if knots_of(geometry) != self.knots {
            return Err(DnurbsError::InvalidOption {
                name: "geometry",
                value: format!("{} control points", geometry.n_control_points()),
                reason: "the assembler was built for other knot vectors".into(),
            });
        }
        Ok(())
    }

    /// `M`, `D`, `K`, `f_p` at `geometry` (same knots as at construction), see [`assemble`].
    pub fn assemble(
        &self,
        geometry: &Geometry,
        material: &Material,
        loads: &Loads,
    ) -> Result<Matrices, DnurbsError> {
        material.validate(geometry.is_curve())?;
        loads.validate(geometry)?;
        self.check_geometry(geometry)?;
        match &self.kind {
            AssemblerKind::General(assembler) => {
                let v = assembler.run(geometry, material, loads, self.options.integration, None);
                let mut mass = v.unit_mass.clone();
                mass.scale(material.mu);
                let mut damping = v.unit_mass;
                damping.scale(material.gamma);
                if !loads.edges.is_empty() {
                    return Err(DnurbsError::InvalidLoad {
                        detail: "edge loads need constant weights (weights_as_dofs = false)".into(),
                    });
                }
                let mut force = v.force;
                add_point_loads(geometry, loads, true, &mut force)?;
                Ok(Matrices {
                    mass,
                    damping,
                    stiffness: v.stiffness,
                    force,
                    dofs_per_point: 4,
                })
            }
            AssemblerKind::Scalar(assembler) => {
                let s = assembler.run(geometry, material, self.options.integration);
                let density = loads.density(material.mu);
                let mut force = vec![0.0; 3 * geometry.n_control_points()];
                for (k, &r) in s.basis_integrals.iter().enumerate() {
                    for x in 0..3 {
                        force[3 * k + x] = r * density[x];
                    }
                }
                add_point_loads(geometry, loads, false, &mut force)?;
                let points = self.options.quadrature_points.unwrap_or(1);
                crate::edge::EdgeLoads::new(geometry, &loads.edges, points)?.add_forces(&mut force);
                let unit = PointDofs::XYZ.expand(&s.unit_mass);
                let mut mass = unit.clone();
                mass.scale(material.mu);
                let mut damping = unit;
                damping.scale(material.gamma);
                Ok(Matrices {
                    mass,
                    damping,
                    stiffness: PointDofs::XYZ.expand(&s.stiffness),
                    force,
                    dofs_per_point: 3,
                })
            }
        }
    }

    /// `S_M`, `S_D`, `S_K` at `geometry` (constant weights only), see [`assemble_scalar`].
    pub fn assemble_scalar(
        &self,
        geometry: &Geometry,
        material: &Material,
    ) -> Result<ScalarMatrices, DnurbsError> {
        material.validate(geometry.is_curve())?;
        self.check_geometry(geometry)?;
        let AssemblerKind::Scalar(assembler) = &self.kind else {
            return Err(DnurbsError::InvalidOption {
                name: "weights_as_dofs",
                value: "true".into(),
                reason: "scalar matrices exist for constant weights only".into(),
            });
        };
        let s = assembler.run(geometry, material, self.options.integration);
        let mut mass = s.unit_mass.clone();
        mass.scale(material.mu);
        let mut damping = s.unit_mass;
        damping.scale(material.gamma);
        Ok(ScalarMatrices {
            mass,
            damping,
            stiffness: s.stiffness,
        })
    }
}

/// The knot vectors and degrees of a geometry (curves: empty v knots).
fn knots_of(geometry: &Geometry) -> (Vec<f64>, Vec<f64>, (usize, usize)) {
    let degrees = geometry.degrees();
    match geometry {
        Geometry::Surface(s) => (
            s.basis_u().knots().knots().to_vec(),
            s.basis_v().knots().knots().to_vec(),
            degrees,
        ),
        Geometry::Curve(c) => (c.basis().knots().knots().to_vec(), Vec::new(), degrees),
    }
}

/// Adds `J(u0, v0)ᵀ F` for every point load (docs/math.md §3) to `force`.
pub(crate) fn add_point_loads(
    geometry: &Geometry,
    loads: &Loads,
    weights_as_dofs: bool,
    force: &mut [f64],
) -> Result<(), DnurbsError> {
    for p in &loads.point {
        let j = geometry.jacobian(p.u, p.v, 0, weights_as_dofs)?;
        j.apply_transpose_add(nurbspring_geom::Deriv::Value, p.force, 1.0, force);
    }
    Ok(())
}

/// Active stiffness terms `(slot, coefficient)` of paper eq. (4) for this geometry
/// (curves: α11 on `u`, β11 on `uu` only).
fn stiffness_terms(geometry: &Geometry, material: &Material) -> Vec<(usize, f64)> {
    let coef = material.stiffness_by_slot();
    let slots: &[usize] = if geometry.is_curve() {
        &[1, 3]
    } else {
        &[1, 2, 3, 4, 5]
    };
    slots
        .iter()
        .filter(|&&s| coef[s] != 0.0)
        .map(|&s| (s, coef[s]))
        .collect()
}

/// Highest parametric derivative the integrands need.
fn derivative_order(terms: &[(usize, f64)], integration: Integration) -> usize {
    let from_terms = terms
        .iter()
        .map(|&(s, _)| if s >= 3 { 2 } else { 1 })
        .max()
        .unwrap_or(0);
    match integration {
        Integration::Parameter => from_terms,
        Integration::Area => from_terms.max(1),
    }
}

/// `|c_u × c_v|` (surface) or `|c_u|` (curve) from the rational basis derivatives: the factor
/// of the area measure (docs/math.md §3, `Integration::Area`).
fn area_factor(geometry: &Geometry, jac: &Jacobian) -> f64 {
    let pts = geometry.control_points();
    let mut cu = [0.0; 3];
    let mut cv = [0.0; 3];
    for (l, &k) in jac.indices.iter().enumerate() {
        let (ru, rv) = (jac.r[l][1], jac.r[l][2]);
        for x in 0..3 {
            cu[x] += ru * pts[k][x];
            cv[x] += rv * pts[k][x];
        }
    }
    if geometry.is_curve() {
        line_element(cu)
    } else {
        area_element(cu, cv)
    }
}

/// Output of the scalar kernels.
pub(crate) struct ScalarValues {
    /// `∫∫ R Rᵀ` (unit density).
    pub(crate) unit_mass: SparseMatrix,
    /// `S_K`.
    pub(crate) stiffness: SparseMatrix,
    /// `∫∫ R_k`, the load of a unit force density on control point k.
    pub(crate) basis_integrals: Vec<f64>,
}

/// Scalar (`N × N`) assembly for constant weights with a pattern built once.
pub(crate) struct ScalarAssembler {
    layout: TensorLayout,
}

impl ScalarAssembler {
    /// Builds the span layout and the sparsity pattern (once, from the knots).
    pub(crate) fn new(geometry: &Geometry, quadrature_points: usize) -> Result<Self, DnurbsError> {
        Ok(Self {
            layout: TensorLayout::new(geometry, quadrature_points, 1)?,
        })
    }

    /// Fills the values (paper eqs. (3)–(4) with `J = R ⊗ I_3`).
    ///
    /// Uniform weights integrated over the parameter domain take the exact Kronecker form:
    /// `R_ij = N_i(u) N_j(v)` and the tensor Gauss rule factorize every integral, so
    /// `S_M = G0_u ⊗ G0_v` and `S_K = α11 G1_u ⊗ G0_v + α22 G0_u ⊗ G1_v + β11 G2_u ⊗ G0_v +
    /// β12 G1_u ⊗ G1_v + β22 G0_u ⊗ G2_v` with the 1-D Gram matrices `Gd = ∫ N^(d)_i N^(d)_k`
    /// (docs/math.md §3), written straight into the pattern. Otherwise (unequal weights, area
    /// integration) the Gauss-point kernel runs element by element.
    pub(crate) fn run(
        &self,
        geometry: &Geometry,
        material: &Material,
        integration: Integration,
    ) -> ScalarValues {
        if integration == Integration::Parameter && geometry.has_uniform_weights() {
            self.run_kronecker(geometry, material)
        } else {
            self.run_gauss(geometry, material, integration)
        }
    }

    /// The Gauss-point kernel: the rational basis and its derivatives at every point from the
    /// 1-D B-spline values of the spans (evaluated once per span and point, [`SpanBases`]) and
    /// the quotient rule (The NURBS Book eq. (4.9)–(4.10)), element blocks summed into the
    /// pattern in place.
    fn run_gauss(
        &self,
        geometry: &Geometry,
        material: &Material,
        integration: Integration,
    ) -> ScalarValues {
        let layout = &self.layout;
        let terms = stiffness_terms(geometry, material);
        let order = derivative_order(&terms, integration);
        let nl = layout.n_local();
        let nnz = layout.pattern.nnz();
        let (bases_u, bases_v) = match geometry {
            Geometry::Surface(s) => (
                SpanBases::new(Some(s.basis_u()), &layout.spans_u),
                SpanBases::new(Some(s.basis_v()), &layout.spans_v),
            ),
            Geometry::Curve(c) => (
                SpanBases::new(Some(c.basis()), &layout.spans_u),
                SpanBases::new(None, &layout.spans_v),
            ),
        };
        let (weights, points) = (geometry.weights(), geometry.control_points());
        let curve = geometry.is_curve();
        let mut g0 = vec![0.0; nnz];
        let mut kv = vec![0.0; nnz];
        let mut rint = vec![0.0; layout.n_control_points];
        let init = || {
            (
                vec![0.0; 6 * nl],
                vec![0.0; terms.len() * nl],
                vec![0.0; nl * nl],
                vec![0.0; nl * nl],
                vec![(0usize, 0.0); nl],
            )
        };
        layout.for_each_element_row(
            &mut g0,
            &mut kv,
            &mut rint,
            &mut [],
            init,
            |(r, scaled, g0e, ke, local), out| {
                let t = out.row;
                let su = &layout.spans_u[t];
                for (e_v, sv) in layout.spans_v.iter().enumerate() {
                    g0e.fill(0.0);
                    ke.fill(0.0);
                    for (a, l) in local.iter_mut().enumerate() {
                        let k = layout.point(su.span, sv.span, a);
                        *l = (k, weights[k]);
                    }
                    for (x, &(_, wu)) in su.points.iter().enumerate() {
                        let nu = bases_u.at(t, x);
                        for (y, &(_, wv)) in sv.points.iter().enumerate() {
                            let nv = bases_v.at(e_v, y);
                            rational_basis(nu, nv, local, order, r);
                            let weight = wu * wv;
                            let wt = match integration {
                                Integration::Parameter => weight,
                                Integration::Area => {
                                    weight * local_area_factor(points, local, r, curve)
                                }
                            };
                            for (t, &(s, c)) in terms.iter().enumerate() {
                                let rs = &r[s * nl..(s + 1) * nl];
                                for (x, &y) in scaled[t * nl..(t + 1) * nl].iter_mut().zip(rs) {
                                    *x = wt * c * y;
                                }
                            }
                            let r0 = &r[..nl];
                            for a in 0..nl {
                                let ra = wt * r0[a];
                                out.vector[local[a].0 - out.dof_base] += ra;
                                let row_m = &mut g0e[a * nl + a..(a + 1) * nl];
                                for (x, &y) in row_m.iter_mut().zip(&r0[a..]) {
                                    *x += ra * y;
                                }
                                let row_k = &mut ke[a * nl + a..(a + 1) * nl];
                                for (t, &(s, _)) in terms.iter().enumerate() {
                                    let sa = scaled[t * nl + a];
                                    let rs = &r[s * nl + a..(s + 1) * nl];
                                    for (x, &y) in row_k.iter_mut().zip(rs) {
                                        *x += sa * y;
                                    }
                                }
                            }
                        }
                    }
                    mirror_upper(g0e, nl);
                    mirror_upper(ke, nl);
                    layout.add_block(su.span, sv.span, g0e, ke, out);
                }
            },
        );
        ScalarValues {
            unit_mass: layout.pattern.matrix(g0),
            stiffness: layout.pattern.matrix(kv),
            basis_integrals: rint,
        }
    }

    /// The exact Kronecker form of a B-spline (uniform weights) over the parameter domain, see
    /// [`ScalarAssembler::run`]: every stored entry `((i, j), (k, l))` is
    /// `Σ_t c_t Gdu_t[i, k] Gdv_t[j, l]`, columns grouped by `k` in parallel.
    fn run_kronecker(&self, geometry: &Geometry, material: &Material) -> ScalarValues {
        let layout = &self.layout;
        let pattern = &layout.pattern;
        let (gu, gv) = match geometry {
            Geometry::Surface(s) => (
                Gram1d::new(s.basis_u(), &layout.spans_u, pattern, true),
                Gram1d::new(s.basis_v(), &layout.spans_v, pattern, false),
            ),
            Geometry::Curve(c) => (
                Gram1d::new(c.basis(), &layout.spans_u, pattern, true),
                Gram1d::point(),
            ),
        };
        let coef = material.stiffness_by_slot();
        // (coefficient, u derivative order, v derivative order) of the active stiffness terms,
        // in slot order (paper eq. (4)).
        let terms: Vec<(f64, usize, usize)> =
            [(1, 1, 0), (2, 0, 1), (3, 2, 0), (4, 1, 1), (5, 0, 2)]
                .iter()
                .filter(|&&(slot, _, _)| coef[slot] != 0.0)
                .map(|&(slot, du, dv)| (coef[slot], du, dv))
                .collect();
        let n_v = layout.n_v;
        let n_u = layout.n_control_points / n_v;
        let col_ptr = pattern.col_ptr();
        let groups: Vec<(usize, usize)> = (0..n_u)
            .map(|k| (col_ptr[k * n_v], col_ptr[(k + 1) * n_v]))
            .collect();
        let mut g0 = vec![0.0; pattern.nnz()];
        let mut kv = vec![0.0; pattern.nnz()];
        split_ranges(&mut g0, &groups)
            .into_par_iter()
            .zip(split_ranges(&mut kv, &groups))
            .enumerate()
            .for_each(|(k, (g0k, kk))| {
                let (a0, a1) = pattern.range_a(k);
                let mut pos = 0;
                for l in 0..n_v {
                    let (b0, b1) = pattern.range_b(l);
                    for i in a0..a1 {
                        let a = |d: usize| gu.products[d][gu.offsets[k] + i - a0];
                        let (a_0, a_1, a_2) = (a(0), a(1), a(2));
                        let a_d = [a_0, a_1, a_2];
                        let bl = gv.offsets[l];
                        for j in 0..b1 - b0 {
                            let b_d = [
                                gv.products[0][bl + j],
                                gv.products[1][bl + j],
                                gv.products[2][bl + j],
                            ];
                            g0k[pos] = a_0 * b_d[0];
                            kk[pos] = terms.iter().map(|&(c, du, dv)| c * a_d[du] * b_d[dv]).sum();
                            pos += 1;
                        }
                    }
                }
            });
        let basis_integrals = (0..layout.n_control_points)
            .map(|kl| gu.integrals[kl / n_v] * gv.integrals[kl % n_v])
            .collect();
        ScalarValues {
            unit_mass: pattern.matrix(g0),
            stiffness: pattern.matrix(kv),
            basis_integrals,
        }
    }
}

/// The 1-D Gram matrices `Gd[i, k] = ∫ N^(d)_i N^(d)_k` (d = 0, 1, 2) of one direction on the
/// pattern's band (column `k` from `offsets[k]`, rows in the pattern's range of `k`), and
/// `integrals[k] = ∫ N_k`, by the spans' Gauss rules (The NURBS Book A2.3 at the points).
struct Gram1d {
    products: [Vec<f64>; 3],
    offsets: Vec<usize>,
    integrals: Vec<f64>,
}

impl Gram1d {
    fn new(basis: &BSplineBasis, spans: &[Span1d], pattern: &KroneckerPattern, u: bool) -> Self {
        let p = basis.degree();
        let w = p + 1;
        let n = basis.knots().n_basis();
        let range = |k: usize| {
            if u {
                pattern.range_a(k)
            } else {
                pattern.range_b(k)
            }
        };
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0);
        for k in 0..n {
            let (a, b) = range(k);
            offsets.push(offsets[k] + b - a);
        }
        let len = offsets[n];
        let mut products = [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
        let mut integrals = vec![0.0; n];
        let mut scratch = BasisScratch::default();
        let mut d = vec![0.0; 3 * w];
        for s in spans {
            let first = s.span - p;
            for &(x, weight) in &s.points {
                basis.derivatives_into(s.span, x, 2, &mut d, &mut scratch);
                for kk in 0..w {
                    let k = first + kk;
                    integrals[k] += weight * d[kk];
                    let column = offsets[k] + first - range(k).0;
                    for (order, prod) in products.iter_mut().enumerate() {
                        let dk = weight * d[order * w + kk];
                        for ii in 0..w {
                            prod[column + ii] += dk * d[order * w + ii];
                        }
                    }
                }
            }
        }
        Self {
            products,
            offsets,
            integrals,
        }
    }

    /// The `v` factor of a curve: one function equal to 1, no derivatives.
    fn point() -> Self {
        Self {
            products: [vec![1.0], vec![0.0], vec![0.0]],
            offsets: vec![0, 1],
            integrals: vec![1.0],
        }
    }
}

/// Output of the general (dof-level) kernels.
pub(crate) struct GeneralValues {
    /// `∫∫ JᵀJ` (unit density); `M = μ ·` this, `D = γ ·` this.
    pub(crate) unit_mass: SparseMatrix,
    /// K (paper eq. (4)).
    pub(crate) stiffness: SparseMatrix,
    /// `∫∫ Jᵀ (μ g + f_d)` (distributed loads only; point loads are added separately).
    pub(crate) force: Vec<f64>,
    /// `∫∫ μ Jᵀ c_prev` with `c_prev` the surface of a previous state (docs/math.md §3, last bullet);
    /// empty when no previous geometry was given.
    pub(crate) inertia: Vec<f64>,
}

/// Dof-level assembly (`m` = 3 or 4 dofs per control point) with a pattern built once; the
/// matrices depend on the geometry (weights as unknowns), so `run` is called at every step.
pub(crate) struct GeneralAssembler {
    layout: TensorLayout,
    m: usize,
}

impl GeneralAssembler {
    /// Builds the span layout and the `mN × mN` sparsity pattern (once, from the knots).
    pub(crate) fn new(
        geometry: &Geometry,
        quadrature_points: usize,
        m: usize,
    ) -> Result<Self, DnurbsError> {
        Ok(Self {
            layout: TensorLayout::new(geometry, quadrature_points, m)?,
            m,
        })
    }

    /// Number of dofs (rows and columns) of the matrices `run` returns.
    pub(crate) fn n_dofs(&self) -> usize {
        self.layout.n_control_points * self.m
    }

    /// Fills `∫∫ JᵀJ`, `K`, `∫∫ Jᵀ f` and (with `previous`) `∫∫ μ Jᵀ c_prev` at `geometry`
    /// (paper eqs. (3)–(4); docs/math.md §3, last bullet), element blocks summed into the
    /// pattern in place, element rows in parallel.
    pub(crate) fn run(
        &self,
        geometry: &Geometry,
        material: &Material,
        loads: &Loads,
        integration: Integration,
        previous: Option<&Geometry>,
    ) -> GeneralValues {
        let layout = &self.layout;
        let m = self.m;
        let weights_as_dofs = m == 4;
        let terms = stiffness_terms(geometry, material);
        let order = derivative_order(&terms, integration);
        let nl = layout.n_local();
        let ld = nl * m;
        let density = loads.density(material.mu);
        let mu = material.mu;
        let nnz = layout.pattern.nnz();
        let n = self.n_dofs();
        let mut g0 = vec![0.0; nnz];
        let mut kv = vec![0.0; nnz];
        let mut force = vec![0.0; n];
        let mut inertia = vec![0.0; if previous.is_some() { n } else { 0 }];
        // Local column `i = a·m + c` of J^(s) is `R_a^(s) e_c` (c < 3) or the weight column.
        let column = |jac: &Jacobian, s: usize, i: usize| -> [f64; 3] {
            let (a, c) = (i / m, i % m);
            if c == 3 {
                jac.weight_columns[a][s]
            } else {
                let mut col = [0.0; 3];
                col[c] = jac.r[a][s];
                col
            }
        };
        let init = || {
            (
                LocalRationalBasis::default(),
                LocalRationalBasis::default(),
                Jacobian::default(),
                Vec::with_capacity(ld * (terms.len() + 1)),
                vec![0.0; ld * ld],
                vec![0.0; ld * ld],
            )
        };
        let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        layout.for_each_element_row(
            &mut g0,
            &mut kv,
            &mut force,
            &mut inertia,
            init,
            |(buf, buf_prev, jac, cols, g0e, ke), out| {
                let su = &layout.spans_u[out.row];
                for sv in &layout.spans_v {
                    g0e.fill(0.0);
                    ke.fill(0.0);
                    let dof = |i: usize| layout.point(su.span, sv.span, i / m) * m + i % m;
                    for &(u, wu) in &su.points {
                        for &(v, wv) in &sv.points {
                            geometry.jacobian_into(u, v, order, weights_as_dofs, buf, jac);
                            let weight = wu * wv;
                            let wt = match integration {
                                Integration::Parameter => weight,
                                Integration::Area => weight * area_factor(geometry, jac),
                            };
                            // Columns of J (slot 0) and of the active derivative slots.
                            cols.clear();
                            for i in 0..ld {
                                cols.push(column(jac, 0, i));
                            }
                            for &(s, _) in &terms {
                                for i in 0..ld {
                                    cols.push(column(jac, s, i));
                                }
                            }
                            for i in 0..ld {
                                let ci = cols[i];
                                out.vector[dof(i) - out.dof_base] += wt * dot(ci, density);
                                for j in i..ld {
                                    g0e[i * ld + j] += wt * dot(ci, cols[j]);
                                }
                                for (t, &(_, coef)) in terms.iter().enumerate() {
                                    let base = (t + 1) * ld;
                                    let cti = cols[base + i];
                                    let sc = wt * coef;
                                    for j in i..ld {
                                        ke[i * ld + j] += sc * dot(cti, cols[base + j]);
                                    }
                                }
                            }
                            if let Some(prev) = previous {
                                let c_prev = prev.point_with(u, v, buf_prev);
                                for i in 0..ld {
                                    out.vector2[dof(i) - out.dof_base] +=
                                        wt * mu * dot(cols[i], c_prev);
                                }
                            }
                        }
                    }
                    mirror_upper(g0e, ld);
                    mirror_upper(ke, ld);
                    layout.add_block(su.span, sv.span, g0e, ke, out);
                }
            },
        );
        GeneralValues {
            unit_mass: layout.pattern.matrix(g0),
            stiffness: layout.pattern.matrix(kv),
            force,
            inertia,
        }
    }
}

#[cfg(test)]
mod tests;
