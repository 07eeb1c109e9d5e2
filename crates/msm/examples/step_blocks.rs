//! Times the symplectic-Euler step of the "Mass-spring step" benchmark (docs/benchmarks.md)
//! with the statistic of `bench-peers/msm_step_warp.py`: median and minimum of 40 blocks of 20
//! steps after 50 warm-up steps, for the model's fused step and for the generic path. On a
//! shared machine the minimum is the least disturbed figure, and the same statistic on both
//! sides keeps the ratio to the peer fair. The criterion bench (`benches/step.rs`) remains the
//! reference measurement.
//!
//! Run: `cargo run --release -p nurbspring-msm --example step_blocks` (threads:
//! `RAYON_NUM_THREADS`; `ONLY=fused` or `ONLY=generic` times one of the two, for A/B runs of
//! two builds in turn).

use std::time::Instant;

use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::MsmModel;
use nurbspring_sim::{DynamicModel, IntegratorKind, SystemMatrix, make_stepper};

#[path = "../benches/support/lattices.rs"]
mod support;
use support::{perturbed_state, sheet};

/// The model with its fused step hidden, so that `nurbspring-sim` takes the generic path.
struct Generic<'a>(&'a MsmModel);

impl DynamicModel for Generic<'_> {
    fn n_dofs(&self) -> usize {
        self.0.n_dofs()
    }
    fn mass(&self) -> &SystemMatrix {
        self.0.mass()
    }
    fn damping(&self) -> Option<&SystemMatrix> {
        self.0.damping()
    }
    fn internal_force(&self, q: &[f64], out: &mut [f64]) {
        self.0.internal_force(q, out)
    }
    fn external_force(&self, t: f64, out: &mut [f64]) {
        self.0.external_force(t, out)
    }
    fn tangent_stiffness(&self, q: &[f64]) -> SparseMatrix {
        self.0.tangent_stiffness(q)
    }
    fn potential_energy(&self, q: &[f64]) -> f64 {
        self.0.potential_energy(q)
    }
}

fn main() {
    let model = sheet(256);
    let state = perturbed_state(&model);
    let dt = 1e-5;
    let generic = Generic(&model);
    println!(
        "256 x 256 lattice, {} springs, {} rayon threads; load average {}",
        model.lattice().springs.len(),
        rayon::current_num_threads(),
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    for (name, m) in [
        ("fused", &model as &dyn DynamicModel),
        ("generic", &generic as &dyn DynamicModel),
    ] {
        if std::env::var("ONLY").is_ok_and(|only| only != name) {
            continue;
        }
        let mut s = state.clone();
        let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, m, &s, dt).unwrap();
        for _ in 0..50 {
            stepper.step(m, &mut s, dt).unwrap();
        }
        let mut times: Vec<f64> = (0..40)
            .map(|_| {
                let t0 = Instant::now();
                for _ in 0..20 {
                    stepper.step(m, &mut s, dt).unwrap();
                }
                t0.elapsed().as_secs_f64() / 20.0
            })
            .collect();
        times.sort_by(f64::total_cmp);
        println!(
            "{name} step: median {:.3} ms, min {:.3} ms (40 blocks of 20 steps)",
            times[20] * 1e3,
            times[0] * 1e3
        );
    }
}
