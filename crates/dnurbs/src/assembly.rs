//! Assembly of the D-NURBS matrices `M`, `D`, `K` and the load vector `f_p` by Gauss–Legendre
//! quadrature over the non-empty knot spans (paper eqs. (3)–(4), docs/math.md §3).
//!
//! The sparsity pattern is computed once per discretization through
//! [`AssemblyPattern`]: every element (knot span pair) owns a contiguous slice of the value
//! vector holding its dense local block, the element kernels fill those slices in parallel with
//! rayon (no locks: each element writes only its own slice), and `AssemblyPattern::assemble`
//! sums duplicates into CSC. With constant weights the kernels work on the scalar `N × N`
//! matrices `S` and the dof matrices are `S ⊗ I_3` (interleaved ordering, docs/math.md §1); with weights
//! as unknowns the kernels fill full `4N × 4N` blocks through the Jacobian with weight columns.

use nurbspring_geom::{
    BSplineBasis, BasisScratch, GaussLegendre, Jacobian, LocalRationalBasis, NurbsSurface,
    QuadratureElement,
};
use nurbspring_linalg::{AssemblyPattern, SparseMatrix};
use rayon::prelude::*;

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
                let unit = s.unit_mass.kron_identity(3);
                let mut mass = unit.clone();
                mass.scale(material.mu);
                let mut damping = unit;
                damping.scale(material.gamma);
                Ok(Matrices {
                    mass,
                    damping,
                    stiffness: s.stiffness.kron_identity(3),
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
        (cu[0] * cu[0] + cu[1] * cu[1] + cu[2] * cu[2]).sqrt()
    } else {
        let n = [
            cu[1] * cv[2] - cu[2] * cv[1],
            cu[2] * cv[0] - cu[0] * cv[2],
            cu[0] * cv[1] - cu[1] * cv[0],
        ];
        (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
    }
}

/// Elements (knot spans with their Gauss points) and the control points each one touches.
#[derive(Clone, Debug)]
pub(crate) struct ElementLayout {
    pub(crate) elements: Vec<QuadratureElement>,
    /// `n_local` flat control point indices per element, element after element.
    pub(crate) points: Vec<usize>,
    pub(crate) n_local: usize,
    pub(crate) n_control_points: usize,
}

impl ElementLayout {
    pub(crate) fn new(geometry: &Geometry, quadrature_points: usize) -> Result<Self, DnurbsError> {
        crate::options::check_quadrature_points(quadrature_points)?;
        let elements = geometry.quadrature(quadrature_points)?;
        let n_local = geometry.n_local();
        let mut points = Vec::with_capacity(elements.len() * n_local);
        let mut buf = Vec::with_capacity(n_local);
        for e in &elements {
            geometry.element_points(e.span_u, e.span_v, &mut buf);
            points.extend_from_slice(&buf);
        }
        Ok(Self {
            elements,
            points,
            n_local,
            n_control_points: geometry.n_control_points(),
        })
    }

    fn element(&self, e: usize) -> &[usize] {
        &self.points[e * self.n_local..(e + 1) * self.n_local]
    }

    /// Global `(row, col)` of every local entry: element after element, each element's local
    /// block row-major over its `n_local · m` dofs (`m` dofs per control point).
    fn entries(&self, m: usize) -> Vec<(usize, usize)> {
        let ld = self.n_local * m;
        let mut entries = vec![(0usize, 0usize); self.elements.len() * ld * ld];
        entries
            .par_chunks_mut(ld * ld)
            .enumerate()
            .for_each(|(e, chunk)| {
                let pts = self.element(e);
                for i in 0..ld {
                    let row = pts[i / m] * m + i % m;
                    for j in 0..ld {
                        chunk[i * ld + j] = (row, pts[j / m] * m + j % m);
                    }
                }
            });
        entries
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
    layout: ElementLayout,
    pattern: AssemblyPattern,
    quadrature_points: usize,
}

impl ScalarAssembler {
    /// Builds the element layout and the sparsity pattern (once).
    pub(crate) fn new(geometry: &Geometry, quadrature_points: usize) -> Result<Self, DnurbsError> {
        let layout = ElementLayout::new(geometry, quadrature_points)?;
        let n = layout.n_control_points;
        let pattern = AssemblyPattern::new(n, n, &layout.entries(1))?;
        Ok(Self {
            layout,
            pattern,
            quadrature_points,
        })
    }

    /// Fills the element blocks in parallel and sums them (paper eqs. (3)–(4) with `J = R ⊗ I_3`).
    ///
    /// A surface with uniform weights integrated over the parameter domain takes the tensor
    /// (sum-factorized) path: `R_ij = N_i(u) N_j(v)` and the tensor Gauss rule factorize every
    /// element integral into products of 1D span integrals, e.g. `∫∫ R_uu R_uu = (∫ N'' N'')(∫ N N)`.
    pub(crate) fn run(
        &self,
        geometry: &Geometry,
        material: &Material,
        integration: Integration,
    ) -> ScalarValues {
        if let (Geometry::Surface(surface), Integration::Parameter) = (geometry, integration)
            && geometry.has_uniform_weights()
        {
            return self.run_tensor(surface, material);
        }
        let terms = stiffness_terms(geometry, material);
        let order = derivative_order(&terms, integration);
        let nl = self.layout.n_local;
        let block = nl * nl;
        let n_el = self.layout.elements.len();
        let mut g0 = vec![0.0; n_el * block];
        let mut kv = vec![0.0; n_el * block];
        let mut rint = vec![0.0; n_el * nl];
        g0.par_chunks_mut(block)
            .zip(kv.par_chunks_mut(block))
            .zip(rint.par_chunks_mut(nl))
            .zip(self.layout.elements.par_iter())
            .for_each_init(
                || {
                    (
                        LocalRationalBasis::default(),
                        Jacobian::default(),
                        vec![0.0; terms.len() * nl],
                    )
                },
                |(buf, jac, scaled), (((g0e, ke), re), el)| {
                    for qp in &el.points {
                        geometry.jacobian_into(qp.u, qp.v, order, false, buf, jac);
                        let wt = match integration {
                            Integration::Parameter => qp.weight,
                            Integration::Area => qp.weight * area_factor(geometry, jac),
                        };
                        for (t, &(s, c)) in terms.iter().enumerate() {
                            for a in 0..nl {
                                scaled[t * nl + a] = wt * c * jac.r[a][s];
                            }
                        }
                        for a in 0..nl {
                            let ra = wt * jac.r[a][0];
                            re[a] += ra;
                            let row_m = &mut g0e[a * nl..(a + 1) * nl];
                            for b in a..nl {
                                row_m[b] += ra * jac.r[b][0];
                            }
                            let row_k = &mut ke[a * nl..(a + 1) * nl];
                            for (t, &(s, _)) in terms.iter().enumerate() {
                                let sa = scaled[t * nl + a];
                                for b in a..nl {
                                    row_k[b] += sa * jac.r[b][s];
                                }
                            }
                        }
                    }
                    mirror_upper(g0e, nl);
                    mirror_upper(ke, nl);
                },
            );
        let mut basis_integrals = vec![0.0; self.layout.n_control_points];
        for (e, re) in rint.chunks_exact(nl).enumerate() {
            for (&k, &r) in self.layout.element(e).iter().zip(re) {
                basis_integrals[k] += r;
            }
        }
        ScalarValues {
            unit_mass: self.pattern.assemble(&g0),
            stiffness: self.pattern.assemble(&kv),
            basis_integrals,
        }
    }
}

impl ScalarAssembler {
    /// The sum-factorized kernel for B-spline surfaces (uniform weights) over the parameter
    /// domain: element blocks are sums of Kronecker products of 1D span matrices
    /// (paper eq. (3)–(4) with `R_ij = N_i N_j`).
    fn run_tensor(&self, surface: &NurbsSurface, material: &Material) -> ScalarValues {
        let g = self.quadrature_points;
        let spans_u = span_matrices(surface.basis_u(), g);
        let spans_v = span_matrices(surface.basis_v(), g);
        let (wu, wv) = (
            surface.basis_u().degree() + 1,
            surface.basis_v().degree() + 1,
        );
        let coef = material.stiffness_by_slot();
        // (slot, u derivative order, v derivative order) of the active stiffness terms.
        let terms: Vec<(f64, usize, usize)> =
            [(1, 1, 0), (2, 0, 1), (3, 2, 0), (4, 1, 1), (5, 0, 2)]
                .iter()
                .filter(|&&(slot, _, _)| coef[slot] != 0.0)
                .map(|&(slot, du, dv)| (coef[slot], du, dv))
                .collect();
        let find = |spans: &[SpanMatrices], span: usize| {
            spans
                .binary_search_by_key(&span, |s| s.span)
                .expect("every element lies on a non-empty span")
        };
        let nl = self.layout.n_local;
        let block = nl * nl;
        let n_el = self.layout.elements.len();
        let mut g0 = vec![0.0; n_el * block];
        let mut kv = vec![0.0; n_el * block];
        let mut rint = vec![0.0; n_el * nl];
        g0.par_chunks_mut(block)
            .zip(kv.par_chunks_mut(block))
            .zip(rint.par_chunks_mut(nl))
            .zip(self.layout.elements.par_iter())
            .for_each(|(((g0e, ke), re), el)| {
                let a = &spans_u[find(&spans_u, el.span_u)];
                let b = &spans_v[find(&spans_v, el.span_v)];
                for l in 0..nl {
                    let (ia, ib) = (l / wv, l % wv);
                    re[l] = a.integrals[ia] * b.integrals[ib];
                    for c in 0..nl {
                        let (ic, id) = (c / wv, c % wv);
                        let (iu, iv) = (ia * wu + ic, ib * wv + id);
                        g0e[l * nl + c] = a.products[0][iu] * b.products[0][iv];
                        ke[l * nl + c] = terms
                            .iter()
                            .map(|&(k, du, dv)| k * a.products[du][iu] * b.products[dv][iv])
                            .sum();
                    }
                }
            });
        let mut basis_integrals = vec![0.0; self.layout.n_control_points];
        for (e, re) in rint.chunks_exact(nl).enumerate() {
            for (&k, &r) in self.layout.element(e).iter().zip(re) {
                basis_integrals[k] += r;
            }
        }
        ScalarValues {
            unit_mass: self.pattern.assemble(&g0),
            stiffness: self.pattern.assemble(&kv),
            basis_integrals,
        }
    }
}

/// 1D integrals over one non-empty knot span: `products[d]` is `∫ N^(d)_i N^(d)_j` (row-major
/// `(p+1)²`, d = 0, 1, 2) and `integrals` is `∫ N_i`, by the g-point Gauss rule.
struct SpanMatrices {
    span: usize,
    products: [Vec<f64>; 3],
    integrals: Vec<f64>,
}

/// [`SpanMatrices`] of every non-empty span of `basis` (The NURBS Book A2.3 at the Gauss points).
fn span_matrices(basis: &BSplineBasis, g: usize) -> Vec<SpanMatrices> {
    let p = basis.degree();
    let w = p + 1;
    let rule = GaussLegendre::new(g.max(1)).unwrap_or_else(|_| unreachable!("g ≥ 1 was checked"));
    let mut scratch = BasisScratch::default();
    let mut d = vec![0.0; 3 * w];
    basis
        .knots()
        .nonempty_spans()
        .into_iter()
        .map(|(span, a, b)| {
            let mut products = [vec![0.0; w * w], vec![0.0; w * w], vec![0.0; w * w]];
            let mut integrals = vec![0.0; w];
            for (x, weight) in rule.mapped(a, b) {
                basis.derivatives_into(span, x, 2, &mut d, &mut scratch);
                for i in 0..w {
                    integrals[i] += weight * d[i];
                    for (k, prod) in products.iter_mut().enumerate() {
                        let di = weight * d[k * w + i];
                        for j in 0..w {
                            prod[i * w + j] += di * d[k * w + j];
                        }
                    }
                }
            }
            SpanMatrices {
                span,
                products,
                integrals,
            }
        })
        .collect()
}

/// Copies the upper triangle of a row-major `n × n` block onto the lower one.
fn mirror_upper(a: &mut [f64], n: usize) {
    for i in 0..n {
        for j in 0..i {
            a[i * n + j] = a[j * n + i];
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
    layout: ElementLayout,
    pattern: AssemblyPattern,
    m: usize,
}

impl GeneralAssembler {
    /// Builds the element layout and the `mN × mN` sparsity pattern (once).
    pub(crate) fn new(
        geometry: &Geometry,
        quadrature_points: usize,
        m: usize,
    ) -> Result<Self, DnurbsError> {
        let layout = ElementLayout::new(geometry, quadrature_points)?;
        let n = layout.n_control_points * m;
        let pattern = AssemblyPattern::new(n, n, &layout.entries(m))?;
        Ok(Self { layout, pattern, m })
    }

    /// Number of dofs (rows and columns) of the matrices `run` returns.
    pub(crate) fn n_dofs(&self) -> usize {
        self.layout.n_control_points * self.m
    }

    /// Fills `∫∫ JᵀJ`, `K`, `∫∫ Jᵀ f` and (with `previous`) `∫∫ μ Jᵀ c_prev` at `geometry`
    /// (paper eqs. (3)–(4); docs/math.md §3, last bullet), element blocks in parallel.
    pub(crate) fn run(
        &self,
        geometry: &Geometry,
        material: &Material,
        loads: &Loads,
        integration: Integration,
        previous: Option<&Geometry>,
    ) -> GeneralValues {
        let m = self.m;
        let weights_as_dofs = m == 4;
        let terms = stiffness_terms(geometry, material);
        let order = derivative_order(&terms, integration);
        let nl = self.layout.n_local;
        let ld = nl * m;
        let block = ld * ld;
        let n_el = self.layout.elements.len();
        let density = loads.density(material.mu);
        let mu = material.mu;
        let mut g0 = vec![0.0; n_el * block];
        let mut kv = vec![0.0; n_el * block];
        let mut fl = vec![0.0; n_el * ld];
        let mut hl = vec![0.0; if previous.is_some() { n_el * ld } else { 0 }];
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
        let previous_ref = previous;
        let per_element = |e: usize,
                           g0e: &mut [f64],
                           ke: &mut [f64],
                           fe: &mut [f64],
                           he: Option<&mut [f64]>,
                           buf: &mut LocalRationalBasis,
                           buf_prev: &mut LocalRationalBasis,
                           jac: &mut Jacobian,
                           cols: &mut Vec<[f64; 3]>| {
            let el = &self.layout.elements[e];
            let mut he = he;
            for qp in &el.points {
                geometry.jacobian_into(qp.u, qp.v, order, weights_as_dofs, buf, jac);
                let wt = match integration {
                    Integration::Parameter => qp.weight,
                    Integration::Area => qp.weight * area_factor(geometry, jac),
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
                let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
                for i in 0..ld {
                    let ci = cols[i];
                    fe[i] += wt * dot(ci, density);
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
                if let (Some(prev), Some(he)) = (previous_ref, he.as_deref_mut()) {
                    let c_prev = prev.point_with(qp.u, qp.v, buf_prev);
                    for i in 0..ld {
                        he[i] += wt * mu * dot(cols[i], c_prev);
                    }
                }
            }
            mirror_upper(g0e, ld);
            mirror_upper(ke, ld);
        };
        let init = || {
            (
                LocalRationalBasis::default(),
                LocalRationalBasis::default(),
                Jacobian::default(),
                Vec::with_capacity(ld * (terms.len() + 1)),
            )
        };
        if previous.is_some() {
            g0.par_chunks_mut(block)
                .zip(kv.par_chunks_mut(block))
                .zip(fl.par_chunks_mut(ld))
                .zip(hl.par_chunks_mut(ld))
                .enumerate()
                .for_each_init(init, |(b, bp, jac, cols), (e, (((g0e, ke), fe), he))| {
                    per_element(e, g0e, ke, fe, Some(he), b, bp, jac, cols)
                });
        } else {
            g0.par_chunks_mut(block)
                .zip(kv.par_chunks_mut(block))
                .zip(fl.par_chunks_mut(ld))
                .enumerate()
                .for_each_init(init, |(b, bp, jac, cols), (e, ((g0e, ke), fe))| {
                    per_element(e, g0e, ke, fe, None, b, bp, jac, cols)
                });
        }
        let n = self.n_dofs();
        let scatter = |local: &[f64]| {
            let mut out = vec![0.0; n];
            for (e, le) in local.chunks_exact(ld).enumerate() {
                let pts = self.layout.element(e);
                for (i, &v) in le.iter().enumerate() {
                    out[pts[i / m] * m + i % m] += v;
                }
            }
            out
        };
        GeneralValues {
            unit_mass: self.pattern.assemble(&g0),
            stiffness: self.pattern.assemble(&kv),
            force: scatter(&fl),
            inertia: if previous.is_some() {
                scatter(&hl)
            } else {
                Vec::new()
            },
        }
    }
}
