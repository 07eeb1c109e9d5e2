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
    psi: Vec<f64>,
    dual: Vec<[f64; 3]>,
    bending: Vec<[f64; 3]>,
    membrane: Vec<[[f64; 3]; 2]>,
    beta: Vec<[f64; 3]>,
    block: Vec<f64>,
    force: Vec<f64>,
}

impl Scratch {
    fn new(nl: usize, tangent: bool) -> Self {
        let ld = 3 * nl;
        Self {
            r: vec![0.0; 6 * nl],
            local: vec![(0, 0.0); nl],
            x: vec![[0.0; 3]; nl],
            psi: vec![0.0; nl],
            dual: vec![[0.0; 3]; nl],
            bending: vec![[0.0; 3]; nl],
            membrane: vec![[[0.0; 3]; 2]; nl],
            beta: vec![[0.0; 3]; nl],
            block: vec![0.0; if tangent { ld * ld } else { 0 }],
            force: vec![0.0; ld],
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
        let g = self.points_per_span;
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
                    s.block.fill(0.0);
                    let base = self.element_base(t, e_v);
                    for x in 0..g {
                        for y in 0..g {
                            self.basis_at(t, e_v, x, y, s);
                            add_point(&self.rest[base + x * g + y], tangent, s);
                        }
                    }
                    for (a, &(k, _)) in s.local.iter().enumerate() {
                        for i in 0..3 {
                            out.vector[3 * k + i - out.dof_base] += s.force[3 * a + i];
                        }
                    }
                    if tangent {
                        let (su, sv) = (&layout.spans_u[t], &layout.spans_v[e_v]);
                        layout.add_block(su.span, sv.span, &[], &s.block, out);
                    }
                }
            },
        );
    }
}

/// Adds one quadrature point's force (and tangent) to `s.force` (and `s.block`), with
/// `s.r` the rational basis, `s.x` the current local control points (docs/math.md §10.3).
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
            s.beta[a] = beta;
            s.dual[a] = std::array::from_fn(|k| r1 * dual[0][k] + r2 * dual[1][k]);
            let bv = [beta[0], beta[1], 2.0 * beta[2]];
            s.bending[a] = super::kinematics::mat_vec(&rest.bending, bv);
            // Columns of t C C_a with C_a = [[R1, 0], [0, R2], [R2, R1]].
            let m = &rest.membrane;
            s.membrane[a] = [
                std::array::from_fn(|i| m[i][0] * r1 + m[i][2] * r2),
                std::array::from_fn(|i| m[i][1] * r2 + m[i][2] * r1),
            ];
        }
    }
    if !tangent {
        return;
    }
    let ld = 3 * nl;
    let [g11, g22, g12] = frame.inverse_metric;
    let hb = cw[0] * frame.curvature[0] + cw[1] * frame.curvature[1] + cw[2] * frame.curvature[2];
    let outer = |x: [f64; 3], y: [f64; 3]| -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| x[i] * y[j]))
    };
    let a3a3 = outer(a3, a3);
    for a in 0..nl {
        let (r1a, r2a) = (r[nl + a], r[2 * nl + a]);
        let (psi_a, va) = (s.psi[a], s.dual[a]);
        let ga = [r1a * g11 + r2a * g12, r1a * g12 + r2a * g22];
        for b in a..nl {
            let (r1b, r2b) = (r[nl + b], r[2 * nl + b]);
            let mb = &s.membrane[b];
            // Q_{αβ} = (C_a column α) · (t C C_b column β).
            let q = [
                [
                    r1a * mb[0][0] + r2a * mb[0][2],
                    r1a * mb[1][0] + r2a * mb[1][2],
                ],
                [
                    r2a * mb[0][1] + r1a * mb[0][2],
                    r2a * mb[1][1] + r1a * mb[1][2],
                ],
            ];
            let u1: [f64; 3] = std::array::from_fn(|k| q[0][0] * a1[k] + q[0][1] * a2[k]);
            let u2: [f64; 3] = std::array::from_fn(|k| q[1][0] * a1[k] + q[1][1] * a2[k]);
            let sigma = n[0] * r1a * r1b + n[1] * r2a * r2b + n[2] * (r1a * r2b + r2a * r1b);
            let bb = s.beta[b];
            let bending = dot(s.bending[a], [bb[0], bb[1], 2.0 * bb[2]]);
            let s_ab = ga[0] * r1b + ga[1] * r2b;
            let c33 = bending + s_ab * hb;
            let (psi_b, vb) = (s.psi[b], s.dual[b]);
            for i in 0..3 {
                for j in 0..3 {
                    let mut kij = a1[i] * u1[j]
                        + a2[i] * u2[j]
                        + c33 * a3a3[i][j]
                        + psi_a * vb[i] * a3[j]
                        + psi_b * a3[i] * va[j];
                    if i == j {
                        kij += sigma;
                    }
                    let kij = w * kij;
                    s.block[(3 * a + i) * ld + 3 * b + j] += kij;
                    if b != a {
                        s.block[(3 * b + j) * ld + 3 * a + i] += kij;
                    }
                }
            }
        }
    }
}
