#![allow(missing_docs)]
//! The explicit step of a 256 × 256 spring + hinge cloth (issue 31's speed target; run:
//! `cargo bench -p nurbspring-msm --bench cloth`), the peer of Newton's (NVIDIA Warp's) cloth
//! step on the same mesh and elements in `bench-peers/run_cloth.sh`:
//!
//! - `cloth/symplectic_euler_step/256x256`: one step of `nurbspring-sim`'s symplectic Euler
//!   (forces of every spring and hinge, gravity, the update of q and v);
//! - `cloth/internal_force/256x256`: the spring and hinge forces alone.
//!
//! The cloth (`benches/support/lattices.rs`): 65,536 nodes, 195,585 springs, 194,565 hinges.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nurbspring_sim::{DynamicModel, IntegratorKind, make_stepper};

#[path = "support/lattices.rs"]
mod support;

fn cloth_step(c: &mut Criterion) {
    let model = support::cloth(256);
    let lattice = model.lattice();
    eprintln!(
        "256 x 256 cloth: {} springs, {} hinges, {} free dofs",
        lattice.springs.len(),
        lattice.hinges.len(),
        model.n_dofs()
    );
    let state = support::perturbed_state(&model);
    let mut out = vec![0.0; model.n_dofs()];
    let mut group = c.benchmark_group("cloth");
    group
        .sample_size(50)
        .measurement_time(Duration::from_secs(5));
    group.throughput(Throughput::Elements(
        (lattice.springs.len() + lattice.hinges.len()) as u64,
    ));
    group.bench_function("internal_force/256x256", |b| {
        b.iter(|| model.internal_force(black_box(&state.q), &mut out))
    });
    let dt = support::DT;
    let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, &model, &state, dt).unwrap();
    let mut s = state.clone();
    group.bench_function("symplectic_euler_step/256x256", |b| {
        b.iter(|| stepper.step(&model, &mut s, dt).unwrap())
    });
    group.finish();
}

criterion_group!(benches, cloth_step);
criterion_main!(benches);
