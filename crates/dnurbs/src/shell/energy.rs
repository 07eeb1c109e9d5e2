//! The Kirchhoff–Love shell energy, its internal force and its consistent tangent, assembled
//! over the knot spans of the surface (docs/math.md §10.2–10.3).

use nurbspring_linalg::SparseMatrix;
use rayon::prelude::*;

use super::kinematics::{Frame, RestPoint, Resultants, SECOND, dot};
use crate::layout::{RowOutputs, SpanBases, TensorLayout, rational_basis};
use crate::{DnurbsError, Geometry, ShellMaterial};

/// The energy `E(p) = ∫ ½ t ε:C:ε + ½ (t³/12) κ:C:κ dA` of a Kirchhoff–Love shell (Kiendl,
/// Bletzinger, Linhard, Wüchner 2009; total Lagrangian, St. Venant–Kirchhoff, plane stress;
/// docs/math.md §10) over the control points `p = [x, y, z]` per point of a NURBS surface whose
/// weights and knots are fixed. The rest shape is the surface given to [`ShellEnergy::new`];
/// the integral runs over its area by Gauss–Legendre quadrature on each non-empty knot span.
///
/// The internal force `∂E/∂p` and the consistent tangent `∂²E/∂p²` are exact (closed-form
/// variations of the metric and curvature, docs/math.md §10.3), assembled on the
/// `A_u ⊗ A_v ⊗ 1₃ₓ₃` pattern with element rows in parallel.
#[derive(Clone, Debug)]
pub struct ShellEnergy {
    layout: TensorLayout,
    bases_u: SpanBases,
    bases_v: SpanBases,
    weights: Vec<f64>,
    rest: Vec<RestPoint>,
    material: ShellMaterial,
    points_per_span: usize,
}

/// Per-thread buffers of the point kernel.
#[derive(Default)]
struct Scratch {
    r: Vec<f64>,
    local: Vec<(usize, f64)>,
    x: Vec<[f64; 3]>,
    /// `ψ_a` per local point.
    psi: Vec<f64>,
    /// The components of `v_a = R_{a,γ} a^γ`, one array over the points each.
    dual: [Vec<f64>; 3],
    /// `(t³/12) C β_a` per point.
    bending: Vec<[f64; 3]>,
    /// `β_a` (Voigt, the 12 entry doubled) per point.
    beta: Vec<[f64; 3]>,
    /// The two columns of `t C C_a` (3 components each), one array over the points each.
    membrane: [Vec<f64>; 6],
    /// Arrays over b of one row a: Q00, Q01, Q10, Q11, σ, the a_3 ⊗ a_3 coefficient.
    q: [Vec<f64>; 6],
    /// The element tangent, component-major (see `add_point`).
    kcomp: Vec<f64>,
    /// The element tangent in the layout of `TensorLayout::add_block`.
    block: Vec<f64>,
    force: Vec<f64>,
}

impl Scratch {
    fn new(nl: usize, tangent: bool) -> Self {
        let ld = 3 * nl;
        let arrays3 = || std::array::from_fn(|_| vec![0.0; nl]);
        let arrays6 = || std::array::from_fn(|_| vec![0.0; nl]);
        Self {
            r: vec![0.0; 6 * nl],
            local: vec![(0, 0.0); nl],
            x: vec![[0.0; 3]; nl],
            psi: vec![0.0; nl],
            dual: arrays3(),
            bending: vec![[0.0; 3]; nl],
            beta: vec![[0.0; 3]; nl],
            membrane: arrays6(),
            q: arrays6(),
            kcomp: vec![0.0; if tangent { 9 * nl * nl } else { 0 }],
            block: vec![0.0; if tangent { ld * ld } else { 0 }],
            force: vec![0.0; ld],
        }
    }

    /// `block[(3a + i)·3n + 3b + j] = kcomp[((i·3 + j)·n + a)·n + b]` for `i ≤ j`, and the
    /// mirror image `block[(3b + j)·3n + 3a + i]` of the same value (the tangent is
    /// symmetric; `add_point` fills only `i ≤ j`).
    fn block_from_components(&mut self) {
        let nl = self.x.len();
        let ld = 3 * nl;
        for i in 0..3 {
            for j in i..3 {
                for a in 0..nl {
                    let start = ((i * 3 + j) * nl + a) * nl;
                    let src = &self.kcomp[start..start + nl];
                    for (b, &v) in src.iter().enumerate() {
                        self.block[(3 * a + i) * ld + 3 * b + j] = v;
                        self.block[(3 * b + j) * ld + 3 * a + i] = v;
                    }
                }
            }
        }
    }
}

/// What a pass over the elements computes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Pass {
    Force,
    ForceAndTangent,
}

impl ShellEnergy {
    /// The shell of `geometry` (a surface; its control points are the rest shape) made of
    /// `material`, integrated with `quadrature_points` Gauss–Legendre points per span and
    /// direction. Fails on a curve, an invalid material, or a rest surface that is degenerate
    /// at a quadrature point (`|A_1 × A_2| = 0`: no normal, no metric to measure strain from).
    pub fn new(
        geometry: &Geometry,
        material: &ShellMaterial,
        quadrature_points: usize,
    ) -> Result<Self, DnurbsError> {
        material.validate()?;
        let Geometry::Surface(surface) = geometry else {
            return Err(DnurbsError::InvalidOption {
                name: "model",
                value: "kirchhoff-love".into(),
                reason: "the Kirchhoff–Love shell needs a surface, not a curve".into(),
            });
        };
        let layout = TensorLayout::new(geometry, quadrature_points, 3)?;
        let bases_u = SpanBases::new(Some(surface.basis_u()), &layout.spans_u);
        let bases_v = SpanBases::new(Some(surface.basis_v()), &layout.spans_v);
        let mut energy = Self {
            layout,
            bases_u,
            bases_v,
            weights: surface.weights().to_vec(),
            rest: Vec::new(),
            material: *material,
            points_per_span: quadrature_points,
        };
        let t = material.thickness;
        let points = surface.control_points();
        let nl = energy.layout.n_local();
        let mut scratch = Scratch::new(nl, false);
        let mut rest = Vec::with_capacity(energy.n_points());
        let mut degenerate = None;
        energy.for_each_point_serial(&mut scratch, |scratch, (u, v), gauss_weight| {
            for (a, &(k, _)) in scratch.local.iter().enumerate() {
                scratch.x[a] = points[k];
            }
            let frame = Frame::new(&scratch.r, &scratch.x);
            if !(frame.area > 0.0 && frame.area.is_finite()) {
                degenerate.get_or_insert((u, v));
            }
            let c = material.voigt_tensor(frame.inverse_metric);
            rest.push(RestPoint {
                weight: gauss_weight * frame.area,
                metric: frame.metric,
                curvature: frame.curvature,
                membrane: c.map(|row| row.map(|x| t * x)),
                bending: c.map(|row| row.map(|x| t * t * t / 12.0 * x)),
            });
        });
        if let Some((u, v)) = degenerate {
            return Err(DnurbsError::Singular {
                detail: format!(
                    "the surface is degenerate at (u, v) = ({u}, {v}): |c_u × c_v| = 0 at a \
                     quadrature point, so the shell has no normal or metric there (a collapsed \
                     edge or a pole inside an element); split the surface or move the control \
                     points"
                ),
            });
        }
        energy.rest = rest;
        Ok(energy)
    }

    /// The material.
    pub fn material(&self) -> &ShellMaterial {
        &self.material
    }

    /// Gauss–Legendre points per span and direction.
    pub fn quadrature_points(&self) -> usize {
        self.points_per_span
    }

    /// Number of generalized coordinates (3 per control point).
    pub fn n_dofs(&self) -> usize {
        3 * self.layout.n_control_points
    }

    fn n_points(&self) -> usize {
        self.layout.spans_u.len()
            * self.layout.spans_v.len()
            * self.points_per_span
            * self.points_per_span
    }

    /// Index of the first rest point of element `(t, e_v)`.
    fn element_base(&self, t: usize, e_v: usize) -> usize {
        (t * self.layout.spans_v.len() + e_v) * self.points_per_span * self.points_per_span
    }

    /// Fills `scratch.local` (flat index, weight) of element `(t, e_v)`.
    fn fill_local(&self, t: usize, e_v: usize, scratch: &mut Scratch) {
        let (su, sv) = (&self.layout.spans_u[t], &self.layout.spans_v[e_v]);
        for (a, l) in scratch.local.iter_mut().enumerate() {
            let k = self.layout.point(su.span, sv.span, a);
            *l = (k, self.weights[k]);
        }
    }

    /// Runs `f(scratch, (u, v), gauss_weight)` at every quadrature point in storage order, with
    /// `scratch.r` the rational basis and `scratch.local` the element's points (serial).
    fn for_each_point_serial<F>(&self, scratch: &mut Scratch, mut f: F)
    where
        F: FnMut(&mut Scratch, (f64, f64), f64),
    {
        for t in 0..self.layout.spans_u.len() {
            for e_v in 0..self.layout.spans_v.len() {
                self.fill_local(t, e_v, scratch);
                let (su, sv) = (&self.layout.spans_u[t], &self.layout.spans_v[e_v]);
                for (x, &(u, wu)) in su.points.iter().enumerate() {
                    for (y, &(v, wv)) in sv.points.iter().enumerate() {
                        let (nu, nv) = (self.bases_u.at(t, x), self.bases_v.at(e_v, y));
                        rational_basis(nu, nv, &scratch.local, 2, &mut scratch.r);
                        f(scratch, (u, v), wu * wv);
                    }
                }
            }
        }
    }

    /// The rational basis of element `(t, e_v)` at its quadrature point `(x, y)` into `s.r`.
    #[inline(always)]
    fn basis_at(&self, t: usize, e_v: usize, x: usize, y: usize, s: &mut Scratch) {
        let (nu, nv) = (self.bases_u.at(t, x), self.bases_v.at(e_v, y));
        rational_basis(nu, nv, &s.local, 2, &mut s.r);
    }

    /// The element's current control points from `p` into `s.x`.
    fn gather(&self, p: &[f64], s: &mut Scratch) {
        for (a, &(k, _)) in s.local.iter().enumerate() {
            s.x[a] = [p[3 * k], p[3 * k + 1], p[3 * k + 2]];
        }
    }

    /// The elastic energy `E(p)` (docs/math.md §10.2).
    ///
    /// # Panics
    /// When `p.len()` is not [`ShellEnergy::n_dofs`].
    pub fn energy(&self, p: &[f64]) -> f64 {
        assert_eq!(p.len(), self.n_dofs(), "ShellEnergy::energy: size mismatch");
        let nl = self.layout.n_local();
        let g = self.points_per_span;
        (0..self.layout.spans_u.len())
            .into_par_iter()
            .map_init(
                || Scratch::new(nl, false),
                |s, t| {
                    let mut sum = 0.0;
                    for e_v in 0..self.layout.spans_v.len() {
                        self.fill_local(t, e_v, s);
                        self.gather(p, s);
                        let base = self.element_base(t, e_v);
                        for x in 0..g {
                            for y in 0..g {
                                self.basis_at(t, e_v, x, y, s);
                                let rest = &self.rest[base + x * g + y];
                                let frame = Frame::new(&s.r, &s.x);
                                sum += rest.weight * Resultants::new(&frame, rest).energy_density();
                            }
                        }
                    }
                    sum
                },
            )
            .sum()
    }

    /// The internal force `f = ∂E/∂p` into `out` (overwritten; docs/math.md §10.3).
    ///
    /// # Panics
    /// When `p` or `out` is not [`ShellEnergy::n_dofs`] long.
    pub fn internal_force(&self, p: &[f64], out: &mut [f64]) {
        assert!(
            p.len() == self.n_dofs() && out.len() == self.n_dofs(),
            "ShellEnergy::internal_force: size mismatch"
        );
        out.fill(0.0);
        self.run(p, Pass::Force, &mut [], out);
    }

    /// The consistent tangent `K_T = ∂²E/∂p²` (docs/math.md §10.3), symmetric, on the
    /// pattern `A_u ⊗ A_v ⊗ 1₃ₓ₃`.
    pub fn tangent(&self, p: &[f64]) -> SparseMatrix {
        self.force_and_tangent(p).1
    }

    /// The internal force and the consistent tangent in one pass over the elements.
    ///
    /// # Panics
    /// When `p` is not [`ShellEnergy::n_dofs`] long.
    pub fn force_and_tangent(&self, p: &[f64]) -> (Vec<f64>, SparseMatrix) {
        assert_eq!(
            p.len(),
            self.n_dofs(),
            "ShellEnergy::tangent: size mismatch"
        );
        let mut values = vec![0.0; self.layout.pattern.nnz()];
        let mut force = vec![0.0; self.n_dofs()];
        self.run(p, Pass::ForceAndTangent, &mut values, &mut force);
        (force, self.layout.pattern.matrix(values))
    }

    fn run(&self, p: &[f64], pass: Pass, values: &mut [f64], force: &mut [f64]) {
        let layout = &self.layout;
        let nl = layout.n_local();
        let tangent = pass == Pass::ForceAndTangent;
        layout.for_each_element_row(
            &mut [],
            values,
            force,
            &mut [],
            || Scratch::new(nl, tangent),
            |s, out: &mut RowOutputs<'_>| {
                let t = out.row;
                for e_v in 0..layout.spans_v.len() {
                    self.fill_local(t, e_v, s);
                    self.gather(p, s);
                    s.force.fill(0.0);
                    s.kcomp.fill(0.0);
                    // The element's points compiled for the widest vector unit of the CPU
                    // (pulp's runtime dispatch; no fused multiply-adds, so the same
                    // operations in the same order at every width).
                    pulp::Arch::new().dispatch(ElementPoints {
                        energy: self,
                        t,
                        e_v,
                        tangent,
                        scratch: s,
                    });
                    for (a, &(k, _)) in s.local.iter().enumerate() {
                        for i in 0..3 {
                            out.vector[3 * k + i - out.dof_base] += s.force[3 * a + i];
                        }
                    }
                    if tangent {
                        s.block_from_components();
                        let (su, sv) = (&layout.spans_u[t], &layout.spans_v[e_v]);
                        layout.add_block(su.span, sv.span, &[], &s.block, out);
                    }
                }
            },
        );
    }
}

/// The quadrature points of element `(t, e_v)`, added to the scratch's force and tangent.
struct ElementPoints<'a> {
    energy: &'a ShellEnergy,
    t: usize,
    e_v: usize,
    tangent: bool,
    scratch: &'a mut Scratch,
}

impl pulp::WithSimd for ElementPoints<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let ElementPoints {
            energy,
            t,
            e_v,
            tangent,
            scratch,
        } = self;
        let g = energy.points_per_span;
        let base = energy.element_base(t, e_v);
        for x in 0..g {
            for y in 0..g {
                energy.basis_at(t, e_v, x, y, scratch);
                add_point(&energy.rest[base + x * g + y], tangent, scratch);
            }
        }
    }
}

/// Adds one quadrature point's force (and tangent) to `s.force` (and `s.kcomp`), with
/// `s.r` the rational basis, `s.x` the current local control points (docs/math.md §10.3).
///
/// The tangent is accumulated component-major, `kcomp[((i·3 + j)·n + a)·n + b]` for dofs
/// `(a, i)`, `(b, j)`: for fixed `(a, i, j)` every term is a combination of arrays over `b`
/// with scalar coefficients, a loop the compiler vectorizes.
#[inline(always)]
fn add_point(rest: &RestPoint, tangent: bool, s: &mut Scratch) {
    let nl = s.x.len();
    let w = rest.weight;
    let frame = Frame::new(&s.r, &s.x);
    let res = Resultants::new(&frame, rest);
    let [a1, a2] = frame.tangents;
    let a3 = frame.normal;
    let dual = frame.dual_tangents();
    // Christoffel symbols Γ^γ_V = x_{,V} · a^γ, V in Voigt order.
    let christoffel: [[f64; 2]; 3] =
        std::array::from_fn(|v| [dot(frame.second[v], dual[0]), dot(frame.second[v], dual[1])]);
    let cw = res.curvature_weights();
    let n = res.forces;
    let r = &s.r;
    for a in 0..nl {
        let (r1, r2) = (r[nl + a], r[2 * nl + a]);
        // δb_V = a_3[i] β_V with β_V = R_{,V} − Γ^γ_V R_{,γ}.
        let beta: [f64; 3] = std::array::from_fn(|v| {
            r[SECOND[v] * nl + a] - christoffel[v][0] * r1 - christoffel[v][1] * r2
        });
        let psi = cw[0] * beta[0] + cw[1] * beta[1] + cw[2] * beta[2];
        for i in 0..3 {
            s.force[3 * a + i] += w
                * (n[0] * r1 * a1[i] + n[1] * r2 * a2[i] + n[2] * (r1 * a2[i] + r2 * a1[i])
                    - psi * a3[i]);
        }
        if tangent {
            s.psi[a] = psi;
            let bv = [beta[0], beta[1], 2.0 * beta[2]];
            s.beta[a] = bv;
            s.bending[a] = super::kinematics::mat_vec(&rest.bending, bv);
            for k in 0..3 {
                s.dual[k][a] = r1 * dual[0][k] + r2 * dual[1][k];
            }
            // Columns of t C C_a with C_a = [[R1, 0], [0, R2], [R2, R1]].
            let m = &rest.membrane;
            for k in 0..3 {
                s.membrane[k][a] = m[k][0] * r1 + m[k][2] * r2;
                s.membrane[3 + k][a] = m[k][1] * r2 + m[k][2] * r1;
            }
        }
    }
    if !tangent {
        return;
    }
    let [g11, g22, g12] = frame.inverse_metric;
    let hb = cw[0] * frame.curvature[0] + cw[1] * frame.curvature[1] + cw[2] * frame.curvature[2];
    let (r1s, rest_r) = r[nl..].split_at(nl);
    let r2s = &rest_r[..nl];
    // Products of the frame vectors' components, the scalar coefficients of the b-loops.
    let frame_vectors = [a1, a2, a3];
    let prod = |x: usize, i: usize, y: usize, j: usize| frame_vectors[x][i] * frame_vectors[y][j];
    let Scratch {
        kcomp,
        q,
        psi,
        dual: vb,
        bending,
        beta,
        membrane,
        ..
    } = s;
    for a in 0..nl {
        let (r1a, r2a) = (r1s[a], r2s[a]);
        let psi_a = psi[a];
        let va = [vb[0][a], vb[1][a], vb[2][a]];
        let ga = [r1a * g11 + r2a * g12, r1a * g12 + r2a * g22];
        let ka = bending[a];
        // Arrays over b: Q_{αβ}(a, b) (membrane), σ_ab (membrane geometric), the a_3 ⊗ a_3
        // coefficient (bending material + geometric).
        let [q00, q01, q10, q11, sigma, c33] = q;
        for b in 0..nl {
            let (r1b, r2b) = (r1s[b], r2s[b]);
            // Q_{αβ} = (C_a column α) · (t C C_b column β).
            q00[b] = r1a * membrane[0][b] + r2a * membrane[2][b];
            q01[b] = r1a * membrane[3][b] + r2a * membrane[5][b];
            q10[b] = r2a * membrane[1][b] + r1a * membrane[2][b];
            q11[b] = r2a * membrane[4][b] + r1a * membrane[5][b];
            sigma[b] = n[0] * r1a * r1b + n[1] * r2a * r2b + n[2] * (r1a * r2b + r2a * r1b);
            let bb = beta[b];
            c33[b] =
                ka[0] * bb[0] + ka[1] * bb[1] + ka[2] * bb[2] + (ga[0] * r1b + ga[1] * r2b) * hb;
        }
        // K[j][i][b][a] = K[i][j][a][b]: the blocks below the component diagonal are
        // mirrored when the element block is written (`block_from_components`).
        for i in 0..3 {
            for j in i..3 {
                let c00 = w * prod(0, i, 0, j);
                let c01 = w * prod(0, i, 1, j);
                let c10 = w * prod(1, i, 0, j);
                let c11 = w * prod(1, i, 1, j);
                let c3 = w * prod(2, i, 2, j);
                let cv = w * psi_a * a3[j];
                let cp = w * a3[i] * va[j];
                let cs = if i == j { w } else { 0.0 };
                // Every array re-sliced to the row's length: the loop has no bounds checks
                // and vectorizes.
                let start = ((i * 3 + j) * nl + a) * nl;
                let row = &mut kcomp[start..start + nl];
                let (q00, q01, q10, q11) = (&q00[..nl], &q01[..nl], &q10[..nl], &q11[..nl]);
                let (c33s, vbi, psis, sig) = (&c33[..nl], &vb[i][..nl], &psi[..nl], &sigma[..nl]);
                for b in 0..nl {
                    row[b] += c00 * q00[b]
                        + c01 * q01[b]
                        + c10 * q10[b]
                        + c11 * q11[b]
                        + c3 * c33s[b]
                        + cv * vbi[b]
                        + cp * psis[b]
                        + cs * sig[b];
                }
            }
        }
    }
}
