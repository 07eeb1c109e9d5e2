//! Weights as unknowns (docs/math.md §3, last bullet): a time stepper for the nonlinear D-NURBS whose
//! `M`, `D`, `K` and `J` depend on the generalized coordinates.
//!
//! Equation of motion (paper eq. (2)): `M p̈ + D ṗ + K (p − p_rest) = f_p − I ṗ`. Using
//! `M p̈ + I ṗ = ∫∫ μ Jᵀ c̈`, every step evaluates the matrices at the extrapolation
//! `p̂ = 2pᵗ − pᵗ⁻ᐞᵗ` and solves
//!
//! `(4M + 2ΔtD + 4Δt²K) pᵗ⁺ᐞᵗ = 4Δt² (f_p + K p_rest) + 8M pᵗ − (2M − 2ΔtD) pᵗ⁻ᐞᵗ − 2 ∫∫ μ Jᵀ cᵗ⁻ᐞᵗ`
//!
//! with `cᵗ⁻ᐞᵗ` the surface of the previous step, then projects the weights to `w ≥ w_min`.
//! The reported velocity at `t + Δt` is `(3pᵗ⁺ᐞᵗ − 4pᵗ + pᵗ⁻ᐞᵗ)/(2Δt)`.
//! With constant weights `∫∫ μ Jᵀ cᵗ⁻ᐞᵗ = M pᵗ⁻ᐞᵗ` and this is Terzopoulos–Qin's scheme.
//! Constraints are applied as in the model (fixed dofs at their initial values, linear
//! constraints through `p = G q + g`); the state is on the model's reduced coordinates.

use nurbspring_linalg::{AssemblyPattern, SparseMatrix, SpdSolver};
use nurbspring_sim::{DofMap, State};

use crate::assembly::{GeneralAssembler, add_point_loads};
use crate::constraints::Reduction;
use crate::{DnurbsError, DnurbsModel, Geometry, Integration, Loads, Material};

/// Default lower bound of the weights, relative to the smallest initial weight.
pub const DEFAULT_MIN_WEIGHT_RATIO: f64 = 1e-3;

/// The restriction `A ↦ A_ff` for matrices that share one sparsity pattern, with a fixed output
/// pattern so that one symbolic Cholesky serves every step.
struct Restriction {
    positions: Vec<usize>,
    nnz: usize,
    pattern: AssemblyPattern,
}

impl Restriction {
    fn new(a: &SparseMatrix, dof_map: &DofMap) -> Result<Self, DnurbsError> {
        let mut positions = Vec::new();
        let mut entries = Vec::new();
        let (col_ptr, row_idx) = (a.col_ptr(), a.row_idx());
        for j in 0..a.ncols() {
            let Some(fj) = dof_map.free_index(j) else {
                continue;
            };
            for k in col_ptr[j]..col_ptr[j + 1] {
                if let Some(fi) = dof_map.free_index(row_idx[k]) {
                    positions.push(k);
                    entries.push((fi, fj));
                }
            }
        }
        let nf = dof_map.n_free();
        Ok(Self {
            positions,
            nnz: a.nnz(),
            pattern: AssemblyPattern::new(nf, nf, &entries)?,
        })
    }

    fn apply(&self, a: &SparseMatrix) -> SparseMatrix {
        debug_assert_eq!(a.nnz(), self.nnz);
        let values = a.values();
        let gathered: Vec<f64> = self.positions.iter().map(|&k| values[k]).collect();
        self.pattern.assemble(&gathered)
    }
}

/// The weights-as-unknowns D-NURBS time stepper (docs/math.md §3, last bullet).
///
/// Works for 3 dofs per control point too (then it reproduces Terzopoulos–Qin).
pub struct RationalStepper {
    geometry: Geometry,
    material: Material,
    loads: Loads,
    integration: Integration,
    weights_as_dofs: bool,
    reduction: Reduction,
    p_rest: Vec<f64>,
    assembler: GeneralAssembler,
    restriction: Option<Restriction>,
    solver: Option<SpdSolver>,
    dt: f64,
    w_min: f64,
    p_prev: Vec<f64>,
    p_curr: Vec<f64>,
    state: State,
    steps: usize,
}

impl RationalStepper {
    /// A stepper for `model` from `initial` (on the model's reduced coordinates) with step `dt`;
    /// started with `p⁻ᐞᵗ = p⁰ − Δt ṗ⁰` (docs/math.md §3). The weight floor is
    /// `w_min = DEFAULT_MIN_WEIGHT_RATIO · min w(0)`.
    pub fn new(model: &DnurbsModel, initial: State, dt: f64) -> Result<Self, DnurbsError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(DnurbsError::InvalidTimeStep { dt });
        }
        let n_q = model.reduction.n_q;
        for (what, len) in [
            ("initial q", initial.q.len()),
            ("initial v", initial.v.len()),
        ] {
            if len != n_q {
                return Err(DnurbsError::DimensionMismatch {
                    what,
                    expected: n_q,
                    found: len,
                });
            }
        }
        let wad = model.options.weights_as_dofs;
        let m = model.geometry.dofs_per_point(wad);
        let p_curr = model.reduction.to_full(&initial.q);
        let v_full = model.reduction.embed(&initial.v);
        let p_prev: Vec<f64> = p_curr
            .iter()
            .zip(&v_full)
            .map(|(p, v)| p - dt * v)
            .collect();
        let w0 = model
            .geometry
            .weights()
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        Ok(Self {
            geometry: model.geometry.clone(),
            material: model.material.clone(),
            loads: model.loads.clone(),
            integration: model.options.integration,
            weights_as_dofs: wad,
            reduction: model.reduction.clone(),
            p_rest: model.p_rest.clone(),
            assembler: GeneralAssembler::new(&model.geometry, model.quadrature.points, m)?,
            restriction: None,
            solver: None,
            dt,
            w_min: DEFAULT_MIN_WEIGHT_RATIO * w0,
            p_prev,
            p_curr,
            state: initial,
            steps: 0,
        })
    }

    /// Sets the weight floor `w_min > 0` of the projection after each step.
    pub fn with_min_weight(mut self, w_min: f64) -> Result<Self, DnurbsError> {
        if !(w_min.is_finite() && w_min > 0.0) {
            return Err(DnurbsError::InvalidOption {
                name: "w_min",
                value: w_min.to_string(),
                reason: "the weight floor must be positive and finite".into(),
            });
        }
        self.w_min = w_min;
        Ok(self)
    }

    /// The weight floor.
    pub fn min_weight(&self) -> f64 {
        self.w_min
    }

    /// The time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Steps taken so far.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The current state on the reduced coordinates; after a step `v` is the velocity at the
    /// state's own time `t`, `(3pᵗ − 4pᵗ⁻ᐞᵗ + pᵗ⁻²ᐞᵗ)/(2Δt)`.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The current full generalized coordinates `p(t)`.
    pub fn full_coordinates(&self) -> &[f64] {
        &self.p_curr
    }

    /// The current shape (control points and, with 4 dofs, weights from `p(t)`).
    pub fn geometry(&self) -> Result<Geometry, DnurbsError> {
        self.geometry
            .with_coordinates(&self.p_curr, self.weights_as_dofs)
    }

    fn clamp_weights(&self, p: &mut [f64]) {
        if self.weights_as_dofs {
            for w in p.iter_mut().skip(3).step_by(4) {
                *w = w.max(self.w_min);
            }
        }
    }

    /// One step of the scheme in the module docs (docs/math.md §3, last bullet).
    pub fn step(&mut self) -> Result<(), DnurbsError> {
        let dt = self.dt;
        let (mu, gamma) = (self.material.mu, self.material.gamma);
        let wad = self.weights_as_dofs;
        let mut p_hat: Vec<f64> = self
            .p_curr
            .iter()
            .zip(&self.p_prev)
            .map(|(c, p)| 2.0 * c - p)
            .collect();
        self.clamp_weights(&mut p_hat);
        let mut p_prev_eval = self.p_prev.clone();
        self.clamp_weights(&mut p_prev_eval);
        let geo_hat = self.geometry.with_coordinates(&p_hat, wad)?;
        let geo_prev = self.geometry.with_coordinates(&p_prev_eval, wad)?;
        let mut vals = self.assembler.run(
            &geo_hat,
            &self.material,
            &self.loads,
            self.integration,
            Some(&geo_prev),
        );
        add_point_loads(&geo_hat, &self.loads, wad, &mut vals.force)?;
        let n = self.p_curr.len();
        // Right-hand side on all dofs.
        let g0 = &vals.unit_mass;
        let k = &vals.stiffness;
        let mut rhs = vec![0.0; n];
        let mut tmp = vec![0.0; n];
        k.mul_vec(&self.p_rest, &mut tmp);
        for i in 0..n {
            rhs[i] = 4.0 * dt * dt * (vals.force[i] + tmp[i]) - 2.0 * vals.inertia[i];
        }
        g0.mul_vec_add(8.0 * mu, &self.p_curr, &mut rhs);
        g0.mul_vec_add(-(2.0 * mu - 2.0 * dt * gamma), &self.p_prev, &mut rhs);
        // System matrix (4μ + 2Δtγ) ∫JᵀJ + 4Δt² K on the common pattern.
        let mut a = g0.clone();
        let (cm, ck) = (4.0 * mu + 2.0 * dt * gamma, 4.0 * dt * dt);
        for (av, kv) in a.values_mut().iter_mut().zip(k.values()) {
            *av = cm * *av + ck * kv;
        }
        // Fixed dofs and the particular solution move to the right-hand side: Pᵀ (rhs − A o).
        a.mul_vec_add(-1.0, &self.reduction.offset, &mut rhs);
        let rhs_r = self.reduction.reduce_vector(&rhs);
        let a_r = match &self.reduction.affine {
            None => {
                if self.restriction.is_none() {
                    self.restriction = Some(Restriction::new(&a, &self.reduction.dof_map)?);
                }
                self.restriction
                    .as_ref()
                    .map(|r| r.apply(&a))
                    .unwrap_or_else(|| a.clone())
            }
            Some(_) => self.reduction.reduce_matrix(&a)?,
        };
        let not_spd = |e: nurbspring_linalg::LinalgError| match e {
            nurbspring_linalg::LinalgError::NotPositiveDefinite { detail } => {
                DnurbsError::Singular {
                    detail: format!(
                        "the step matrix 4M + 2ΔtD + 4Δt²K is not positive definite at step {} ({detail}); \
                     with weights as unknowns, fix at least one weight when linear constraints \
                     involve weights",
                        self.steps
                    ),
                }
            }
            other => DnurbsError::Linalg(other),
        };
        // One symbolic analysis serves every step when the reduced pattern is fixed.
        let reuse = self.reduction.affine.is_none();
        let solver = match self.solver.take() {
            Some(mut s) if reuse => {
                s.refactor(&a_r).map_err(not_spd)?;
                s
            }
            _ => SpdSolver::new(&a_r).map_err(not_spd)?,
        };
        let q_new = solver.solve(&rhs_r);
        self.solver = Some(solver);
        let mut p_new = self.reduction.to_full(&q_new);
        // Keep weights positive: project the free weights to w ≥ w_min.
        if wad {
            for k in 0..n / 4 {
                let d = 4 * k + 3;
                if !self.reduction.dof_map.is_fixed(d) && p_new[d] < self.w_min {
                    p_new[d] = self.w_min;
                }
            }
        }
        let q_new = self.reduction.reduce_coordinates(&p_new);
        let p_new = self.reduction.to_full(&q_new);
        let time = self.state.t + dt;
        if p_new.iter().any(|x| !x.is_finite()) {
            return Err(DnurbsError::NonFinite {
                what: "generalized coordinates",
                step: self.steps + 1,
                time,
            });
        }
        // The velocity at the new time t + Δt: the second-order backward difference
        // (3pᵗ⁺ᐞᵗ − 4pᵗ + pᵗ⁻ᐞᵗ)/(2Δt) (docs/math.md §3).
        let v_full: Vec<f64> = p_new
            .iter()
            .zip(self.p_curr.iter().zip(&self.p_prev))
            .map(|(a, (b, c))| (3.0 * a - 4.0 * b + c) / (2.0 * dt))
            .collect();
        self.state.v = self.reduction.reduce_vector(&v_full);
        self.state.q = q_new;
        self.state.t = time;
        self.p_prev = std::mem::replace(&mut self.p_curr, p_new);
        self.steps += 1;
        Ok(())
    }

    /// Steps until `t ≥ t_end − Δt/2`, calling `observe` after every step.
    pub fn run_until(
        &mut self,
        t_end: f64,
        mut observe: impl FnMut(&Self),
    ) -> Result<(), DnurbsError> {
        while self.state.t < t_end - 0.5 * self.dt {
            self.step()?;
            observe(self);
        }
        Ok(())
    }
}
