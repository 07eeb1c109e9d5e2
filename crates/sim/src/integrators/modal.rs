//! Exact modal solution of the undamped linear system (the reference solution).
//!
//! ODE: `M q̈ + K q + f_int(0) = f_ext(t)` (linear `f_int(q) = K q + f_int(0)`, no damping).
//! With the dense generalized eigenproblem `K φ_i = λ_i M φ_i`, `ΦᵀMΦ = I`, the modal
//! coordinates `η = ΦᵀM q` obey the decoupled `η̈_i + λ_i η_i = g_i`, `g = Φᵀ(f_ext − f_int(0))`,
//! solved in closed form over each step:
//! `η⁺ = cos(ω h) η + h sinc(ω h) η̇ + (h²/2) sinc²(ω h/2) g`,
//! `η̇⁺ = −λ h sinc(ω h) η + cos(ω h) η̇ + h sinc(ω h) g` (`ω = √λ`; the hyperbolic analogue
//! for λ < 0, the limit `η⁺ = η + hη̇ + ½h²g` for λ = 0). Exact for loads constant in time; a
//! time-varying load is held at its mid-step value. Dense, so limited to 3000 dofs.

use nurbspring_linalg::{DenseMatrix, generalized_symmetric_eigen};

use super::check_fixed_dt;
use crate::{DynamicModel, SimError, State};

/// Largest model the modal integrator accepts.
pub const MODAL_MAX_DOFS: usize = 3000;

/// Modal stepper.
pub struct Modal {
    dt: f64,
    /// Mode shapes Φ (columns), M-orthonormal.
    phi: DenseMatrix,
    /// `ΦᵀM`, the projection onto modal coordinates.
    projection: DenseMatrix,
    /// Eigenvalues λ_i = ω_i².
    lambda: Vec<f64>,
    cos: Vec<f64>,
    s_over_omega: Vec<f64>,
    one_minus_cos_over_lambda: Vec<f64>,
    fint0: Vec<f64>,
    eta: Vec<f64>,
    eta_dot: Vec<f64>,
    g: Vec<f64>,
    f: Vec<f64>,
}

/// `sin x / x` (1 at 0).
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0 + x.powi(4) / 120.0
    } else {
        x.sin() / x
    }
}

/// `sinh x / x` (1 at 0).
fn sinhc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 + x * x / 6.0 + x.powi(4) / 120.0
    } else {
        x.sinh() / x
    }
}

fn mat_vec_into(a: &DenseMatrix, x: &[f64], y: &mut [f64]) {
    for (i, yi) in y.iter_mut().enumerate() {
        *yi = a.row(i).iter().zip(x).map(|(a, b)| a * b).sum();
    }
}

fn mat_t_vec_into(a: &DenseMatrix, x: &[f64], y: &mut [f64]) {
    y.fill(0.0);
    for (i, &xi) in x.iter().enumerate() {
        for (yj, aij) in y.iter_mut().zip(a.row(i)) {
            *yj += aij * xi;
        }
    }
}

impl Modal {
    /// Solves the dense eigenproblem. NotSupported when the model is nonlinear, damped, or has
    /// more than [`MODAL_MAX_DOFS`] dofs.
    pub fn new(model: &dyn DynamicModel, dt: f64) -> Result<Self, SimError> {
        let unsupported = |reason: String| SimError::NotSupported {
            integrator: "modal",
            reason,
        };
        let k = model
            .linear_stiffness()
            .ok_or_else(|| unsupported("the model is nonlinear (no constant stiffness)".into()))?;
        if model.configuration_damping().is_some()
            || model
                .damping()
                .is_some_and(|d| d.to_sparse().values().iter().any(|&v| v != 0.0))
        {
            return Err(unsupported(
                "the model is damped; the modal solution is for undamped systems".into(),
            ));
        }
        let n = model.n_dofs();
        if n > MODAL_MAX_DOFS {
            return Err(unsupported(format!(
                "{n} dofs exceed the dense limit of {MODAL_MAX_DOFS}"
            )));
        }
        let m = model.mass().to_sparse().to_dense();
        let eig = generalized_symmetric_eigen(&k.to_dense(), &m)?;
        let phi = eig.vectors;
        let projection = phi.transpose().matmul(&m);
        let lambda = eig.values;
        let mut cos = Vec::with_capacity(n);
        let mut s_over_omega = Vec::with_capacity(n);
        let mut omc = Vec::with_capacity(n);
        for &l in &lambda {
            let w = l.abs().sqrt();
            if l >= 0.0 {
                cos.push((w * dt).cos());
                s_over_omega.push(dt * sinc(w * dt));
                omc.push(0.5 * dt * dt * sinc(0.5 * w * dt).powi(2));
            } else {
                cos.push((w * dt).cosh());
                s_over_omega.push(dt * sinhc(w * dt));
                omc.push(0.5 * dt * dt * sinhc(0.5 * w * dt).powi(2));
            }
        }
        let mut fint0 = vec![0.0; n];
        model.internal_force(&vec![0.0; n], &mut fint0);
        Ok(Self {
            dt,
            phi,
            projection,
            lambda,
            cos,
            s_over_omega,
            one_minus_cos_over_lambda: omc,
            fint0,
            eta: vec![0.0; n],
            eta_dot: vec![0.0; n],
            g: vec![0.0; n],
            f: vec![0.0; n],
        })
    }

    /// The eigenvalues `ω_i²`, ascending.
    pub fn eigenvalues(&self) -> &[f64] {
        &self.lambda
    }
}

impl super::Stepper for Modal {
    fn step(
        &mut self,
        model: &dyn DynamicModel,
        state: &mut State,
        dt: f64,
    ) -> Result<(), SimError> {
        check_fixed_dt("modal", self.dt, dt)?;
        model.external_force(state.t + 0.5 * dt, &mut self.f);
        for (f, f0) in self.f.iter_mut().zip(&self.fint0) {
            *f -= f0;
        }
        mat_t_vec_into(&self.phi, &self.f, &mut self.g);
        mat_vec_into(&self.projection, &state.q, &mut self.eta);
        mat_vec_into(&self.projection, &state.v, &mut self.eta_dot);
        for i in 0..self.lambda.len() {
            let (eta, eta_dot, g) = (self.eta[i], self.eta_dot[i], self.g[i]);
            let (c, so, omc) = (
                self.cos[i],
                self.s_over_omega[i],
                self.one_minus_cos_over_lambda[i],
            );
            self.eta[i] = c * eta + so * eta_dot + omc * g;
            self.eta_dot[i] = -self.lambda[i] * so * eta + c * eta_dot + so * g;
        }
        mat_vec_into(&self.phi, &self.eta, &mut state.q);
        mat_vec_into(&self.phi, &self.eta_dot, &mut state.v);
        state.t += dt;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{sinc, sinhc};

    /// The series below 10⁻⁴ and the quotients above agree with `sin x / x`, `sinh x / x` to
    /// round-off (the series' first neglected term is x⁶/5040 < 10⁻²⁷), and both are 1 at 0.
    #[test]
    fn sinc_and_sinhc_by_their_definitions() {
        assert_eq!((sinc(0.0), sinhc(0.0)), (1.0, 1.0));
        for x in [1e-8f64, 3e-5, 9.9e-5, 1e-4, 2e-4, 0.5, 3.0] {
            let (s, sh) = (x.sin() / x, x.sinh() / x);
            assert!((sinc(x) - s).abs() <= 2.0 * f64::EPSILON, "sinc({x})");
            assert!(
                (sinhc(x) - sh).abs() <= 4.0 * f64::EPSILON * sh,
                "sinhc({x})"
            );
            assert_eq!((sinc(-x), sinhc(-x)), (sinc(x), sinhc(x)));
        }
    }

    /// Below 10⁻⁴ the series of `sinc` is correctly rounded. By the alternating series,
    /// `sin x / x` lies between `1 − x²/6` and `1 − x²/6 + x⁴/120` (x⁴/120 < 10⁻¹⁸, a hundredth of
    /// an ulp of 1), so the nearest f64 is within half an ulp of numbers just below 1 (2⁻⁵⁴ = ε/4)
    /// of `1 − x²/6`; `sinc(x) − 1` is exact (Sterbenz) and `x²/6` carries a relative error of
    /// 2ε. Between 2^−13.5 ≈ 8.6·10⁻⁵ and 10⁻⁴, x⁴ itself is more than half an ulp, so a fourth-
    /// order term of the wrong size moves the result by an ulp.
    #[test]
    fn sinc_series_is_correctly_rounded_below_the_switch() {
        for x in [8.8e-5f64, 9e-5, 9.2e-5, 9.5e-5, 9.7e-5, 9.9e-5, 9.99e-5] {
            let second_order = x * x / 6.0;
            let bound = 0.25 * f64::EPSILON + x.powi(4) / 120.0 + 2.0 * f64::EPSILON * second_order;
            for y in [x, -x] {
                let off = (sinc(y) - 1.0) + second_order;
                assert!(
                    off.abs() <= bound,
                    "sinc({y}) is {} ulp from 1 − x²/6",
                    off / (0.5 * f64::EPSILON)
                );
            }
        }
    }
}
