//! Explicit schemes for the lumped-mass case (the mass-spring model): symplectic Euler,
//! velocity Verlet and classical RK4.
//!
//! ODE: `M q̈ + D q̇ + f_int(q) = f_ext(t)` with diagonal M, so
//! `q̈ = M⁻¹ (f_ext(t) − f_int(q) − D q̇)` (f_int with the sign of a stiffness). All three are
//! conditionally stable: Δt must stay below `2/ω_max` (symplectic Euler, Verlet) or `2√2/ω_max`
//! (RK4); [`crate::simulate`] checks `2/ω_max` before running. Every buffer is allocated when
//! the stepper is built; a step allocates nothing.

use super::inverse_diagonal_mass;
use crate::{DynamicModel, SimError, State};

/// `out = M⁻¹ (f_ext(t) − f_int(q) − D v)` using the buffer `fint`.
fn acceleration(
    model: &dyn DynamicModel,
    inv_m: &[f64],
    t: f64,
    q: &[f64],
    v: &[f64],
    fint: &mut [f64],
    out: &mut [f64],
) {
    model.external_force(t, out);
    model.internal_force(q, fint);
    for (o, f) in out.iter_mut().zip(fint.iter()) {
        *o -= f;
    }
    if let Some(d) = model.damping() {
        d.mul_vec_add(-1.0, v, out);
    }
    for (o, w) in out.iter_mut().zip(inv_m) {
        *o *= w;
    }
}

/// Symplectic (semi-implicit) Euler: `v⁺ = v + Δt M⁻¹(f_ext(t) − f_int(q) − D v)`, then
/// `q⁺ = q + Δt v⁺`. First order; symplectic, so without damping the energy error stays
/// bounded (no drift); stable for `Δt < 2/ω_max`. A model with a fused step
/// ([`DynamicModel::fused_step`]) runs its own; otherwise the forces come first and the update
/// is one pass over the dofs.
pub struct SymplecticEuler {
    inv_m: Vec<f64>,
    /// Diagonal damping, when the model's damping is diagonal (then the update is one fused
    /// pass over the dofs).
    damping_diag: Option<Vec<f64>>,
    a: Vec<f64>,
    fint: Vec<f64>,
    /// Workspace of the model's fused step ([`DynamicModel::fused_step`]), when it has one.
    fused: Vec<f64>,
}

/// Dofs per parallel chunk of the fused update (below two chunks the update runs serially).
const UPDATE_CHUNK: usize = 16 * 1024;

impl SymplecticEuler {
    /// Builds the stepper; NotSupported unless M is diagonal.
    pub fn new(model: &dyn DynamicModel) -> Result<Self, SimError> {
        let inv_m = inverse_diagonal_mass(model, "symplectic-euler")?;
        let n = inv_m.len();
        let damping_diag = match model.damping() {
            None => Some(vec![0.0; n]),
            Some(d) => d.as_diagonal(),
        };
        let fused = vec![0.0; model.fused_step().map_or(0, |f| f.workspace_len())];
        Ok(Self {
            inv_m,
            damping_diag,
            a: vec![0.0; n],
            fint: vec![0.0; n],
            fused,
        })
    }
}

impl super::Stepper for SymplecticEuler {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        if let Some(fused) = model.fused_step() {
            let len = fused.workspace_len();
            if self.fused.len() < len {
                // Only when called with another model than the one it was built for.
                self.fused.resize(len, 0.0);
            }
            fused.symplectic_euler(state.t, dt, &mut state.q, &mut state.v, &mut self.fused);
            state.t += dt;
            return Ok(());
        }
        let Some(d) = &self.damping_diag else {
            acceleration(
                model,
                &self.inv_m,
                state.t,
                &state.q,
                &state.v,
                &mut self.fint,
                &mut self.a,
            );
            for i in 0..state.q.len() {
                state.v[i] += dt * self.a[i];
                state.q[i] += dt * state.v[i];
            }
            state.t += dt;
            return Ok(());
        };
        // Forces first (the model parallelizes them), then one fused pass:
        // v += Δt M⁻¹ (f_ext − f_int − D v), q += Δt v.
        model.external_force(state.t, &mut self.a);
        model.internal_force(&state.q, &mut self.fint);
        let (fext, fint, inv_m) = (&self.a, &self.fint, &self.inv_m);
        let update = |offset: usize, v: &mut [f64], q: &mut [f64]| {
            for k in 0..v.len() {
                let i = offset + k;
                let f = fext[i] - fint[i] - d[i] * v[k];
                v[k] += dt * inv_m[i] * f;
                q[k] += dt * v[k];
            }
        };
        if state.q.len() >= 2 * UPDATE_CHUNK {
            use rayon::prelude::*;
            state
                .v
                .par_chunks_mut(UPDATE_CHUNK)
                .zip(state.q.par_chunks_mut(UPDATE_CHUNK))
                .enumerate()
                .for_each(|(c, (v, q))| update(c * UPDATE_CHUNK, v, q));
        } else {
            update(0, &mut state.v, &mut state.q);
        }
        state.t += dt;
        Ok(())
    }
}

/// Velocity Verlet (Störmer–Verlet; equivalent to the central difference):
/// `v½ = v + ½Δt a`, `q⁺ = q + Δt v½`, `a⁺ = M⁻¹(f_ext(t⁺) − f_int(q⁺) − D v⁺)`,
/// `v⁺ = v½ + ½Δt a⁺`. A diagonal D is treated implicitly in that last half step,
/// `(M + ½ΔtD) v⁺ = M v½ + ½Δt (f_ext − f_int)`, which is explicit for diagonal matrices; a
/// non-diagonal D is evaluated at `v½` (first order in the damping term). Second order,
/// symplectic without damping, stable for `Δt < 2/ω_max`.
pub struct VelocityVerlet {
    inv_m: Vec<f64>,
    mass: Vec<f64>,
    damping_diag: Option<Vec<f64>>,
    a: Vec<f64>,
    f: Vec<f64>,
    fint: Vec<f64>,
}

impl VelocityVerlet {
    /// Builds the stepper with the initial acceleration; NotSupported unless M is diagonal.
    pub fn new(model: &dyn DynamicModel, initial: &State) -> Result<Self, SimError> {
        let inv_m = inverse_diagonal_mass(model, "verlet")?;
        let n = inv_m.len();
        let mass = inv_m.iter().map(|w| 1.0 / w).collect();
        let damping_diag = model.damping().and_then(|d| d.as_diagonal());
        let mut a = vec![0.0; n];
        let mut fint = vec![0.0; n];
        acceleration(
            model, &inv_m, initial.t, &initial.q, &initial.v, &mut fint, &mut a,
        );
        Ok(Self {
            inv_m,
            mass,
            damping_diag,
            a,
            f: vec![0.0; n],
            fint,
        })
    }
}

impl super::Stepper for VelocityVerlet {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        let n = state.q.len();
        let h = 0.5 * dt;
        for i in 0..n {
            state.v[i] += h * self.a[i];
            state.q[i] += dt * state.v[i];
        }
        let t_new = state.t + dt;
        model.external_force(t_new, &mut self.f);
        model.internal_force(&state.q, &mut self.fint);
        for i in 0..n {
            self.f[i] -= self.fint[i];
        }
        match (&self.damping_diag, model.damping()) {
            (Some(d), _) => {
                for i in 0..n {
                    let v_new =
                        (self.mass[i] * state.v[i] + h * self.f[i]) / (self.mass[i] + h * d[i]);
                    self.a[i] = (v_new - state.v[i]) / h;
                    state.v[i] = v_new;
                }
            }
            (None, damping) => {
                if let Some(d) = damping {
                    d.mul_vec_add(-1.0, &state.v, &mut self.f);
                }
                for i in 0..n {
                    self.a[i] = self.f[i] * self.inv_m[i];
                    state.v[i] += h * self.a[i];
                }
            }
        }
        state.t = t_new;
        Ok(())
    }
}

/// Classical fourth-order Runge–Kutta on the first-order system `(q̇, v̇) = (v, q̈(t, q, v))`.
/// Fourth order; not symplectic (slight energy decay); stable for `Δt < 2√2/ω_max`.
pub struct Rk4 {
    inv_m: Vec<f64>,
    kq: [Vec<f64>; 4],
    kv: [Vec<f64>; 4],
    q_stage: Vec<f64>,
    v_stage: Vec<f64>,
    fint: Vec<f64>,
}

impl Rk4 {
    /// Builds the stepper; NotSupported unless M is diagonal.
    pub fn new(model: &dyn DynamicModel) -> Result<Self, SimError> {
        let inv_m = inverse_diagonal_mass(model, "rk4")?;
        let n = inv_m.len();
        let z = || vec![0.0; n];
        Ok(Self {
            inv_m,
            kq: [z(), z(), z(), z()],
            kv: [z(), z(), z(), z()],
            q_stage: z(),
            v_stage: z(),
            fint: z(),
        })
    }
}

impl super::Stepper for Rk4 {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        let n = state.q.len();
        let offsets = [0.0, 0.5 * dt, 0.5 * dt, dt];
        for s in 0..4 {
            if s == 0 {
                self.q_stage.copy_from_slice(&state.q);
                self.v_stage.copy_from_slice(&state.v);
            } else {
                let c = offsets[s];
                for i in 0..n {
                    self.q_stage[i] = state.q[i] + c * self.kq[s - 1][i];
                    self.v_stage[i] = state.v[i] + c * self.kv[s - 1][i];
                }
            }
            self.kq[s].copy_from_slice(&self.v_stage);
            acceleration(
                model,
                &self.inv_m,
                state.t + offsets[s],
                &self.q_stage,
                &self.v_stage,
                &mut self.fint,
                &mut self.kv[s],
            );
        }
        let w = dt / 6.0;
        for i in 0..n {
            state.q[i] +=
                w * (self.kq[0][i] + 2.0 * self.kq[1][i] + 2.0 * self.kq[2][i] + self.kq[3][i]);
            state.v[i] +=
                w * (self.kv[0][i] + 2.0 * self.kv[1][i] + 2.0 * self.kv[2][i] + self.kv[3][i]);
        }
        state.t += dt;
        Ok(())
    }
}
