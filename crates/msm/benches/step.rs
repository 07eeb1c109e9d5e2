#![allow(missing_docs)]
//! Benchmarks of the mass-spring model (run: `cargo bench -p nurbspring-msm --bench step`).
//!
//! - `memory/*`: the machine's memory bandwidth (a 256 MiB f64 copy and sum on one thread; the
//!   STREAM triad `a = b + s c` on the rayon pool, over 3 × 128 MiB, far beyond the caches, and
//!   over 3 × 3 MiB, about the data of the step below), so that the figures below can be set
//!   against it;
//! - `msm/internal_force/256x256`: the spring forces of paper eq. (5) on a 256 × 256 lattice
//!   with structural and shear springs (≈ 261k springs), f64;
//! - `msm/symplectic_euler_step/256x256`: one step of `nurbspring-sim`'s symplectic Euler on
//!   that lattice, the model's fused step (forces, gravity and the update of q and v in one
//!   pass); its throughput is in bytes, those of `MsmModel::fused_step_traffic` (positions
//!   and velocities read and written once, one rest length per spring), so criterion's GB/s
//!   is the achieved bandwidth to set against the triad;
//! - `msm/spring_arithmetic/256x256`: the arithmetic floor of that step, the square root and
//!   division of each spring's `k (1 − l/|d|)` and nothing else (the same count of springs,
//!   in blocks of 1024 that stay in the L1 cache, on the rayon pool, compiled for the CPU's
//!   vector unit as the fused step is): no exact f64 step can be faster;
//! - `msm/symplectic_euler_step_generic/256x256`: the same step by the generic path (the
//!   model's fused step hidden: forces per node, then the update), for comparison;
//! - `msm/backward_euler_step/128x128`: one backward-Euler step (Newton on the sparse tangent
//!   stiffness) on a 128 × 128 lattice, stepping on from the previous step's state (the
//!   Newton factor is kept while it converges), and `msm/newton_factorization/128x128`: one
//!   numeric Cholesky factorization of that step's Newton matrix `M + Δt² K_T`, the unit the
//!   step is measured in, and `msm/newton_solve/128x128`: one solve with that factor.
//!
//! Criterion reports the force and implicit benches' throughput in springs per second (the
//! spring counts are printed first; ns per spring is its inverse), the fused step's and the
//! memory benches' in bytes per second.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nurbspring_linalg::{ShiftedSum, SparseMatrix, SpdSolver};
use nurbspring_msm::MsmModel;
use nurbspring_sim::{
    DynamicModel, IntegratorKind, RunOptions, SystemMatrix, make_stepper, make_stepper_with_options,
};
use rayon::prelude::*;

#[path = "support/lattices.rs"]
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

/// STREAM triad `a = b + s c` over chunks of the rayon pool.
fn triad(a: &mut [f64], b: &[f64], c: &[f64], s: f64) {
    const CHUNK: usize = 1 << 15;
    a.par_chunks_mut(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .zip(c.par_chunks(CHUNK))
        .for_each(|((a, b), c)| {
            for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                *a = b + s * c;
            }
        });
}

fn memory(c: &mut Criterion) {
    const LEN: usize = 32 << 20; // 32 Mi f64 = 256 MiB
    let src: Vec<f64> = (0..LEN).map(|i| i as f64).collect();
    let mut dst = vec![0.0; LEN];
    let mut group = c.benchmark_group("memory");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(3));
    group.throughput(Throughput::Bytes((2 * LEN * 8) as u64));
    group.bench_function("copy_256MiB", |b| {
        b.iter(|| {
            dst.copy_from_slice(black_box(&src));
            black_box(&dst);
        })
    });
    group.throughput(Throughput::Bytes((LEN * 8) as u64));
    group.bench_function("sum_256MiB", |b| {
        b.iter(|| black_box(black_box(&src).iter().sum::<f64>()))
    });
    drop((src, dst));
    for (name, len) in [("triad_3x128MiB", 16 << 20), ("triad_3x3MiB", 3 << 17)] {
        let (b_in, c_in) = (vec![1.0; len], vec![2.0; len]);
        let mut a_out = vec![0.0; len];
        group.throughput(Throughput::Bytes((3 * len * 8) as u64));
        group.bench_function(name, |b| {
            b.iter(|| {
                triad(&mut a_out, black_box(&b_in), black_box(&c_in), 3.0);
                black_box(&a_out);
            })
        });
    }
    group.finish();
}

/// Springs per block of the arithmetic floor: 3 × 8 KiB of data, in the L1 cache.
const FLOOR_BLOCK: usize = 1024;

/// `out = k (1 − l / √(d²))` over one block, compiled for the CPU's vector unit (pulp's
/// dispatch, as the fused step's bands are).
struct SpringArithmetic<'a> {
    k: f64,
    d2: &'a [f64],
    rest: &'a [f64],
    out: &'a mut [f64],
}

impl pulp::WithSimd for SpringArithmetic<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let SpringArithmetic { k, d2, rest, out } = self;
        for ((o, d2), l) in out.iter_mut().zip(d2).zip(rest) {
            *o = k * (1.0 - l / d2.sqrt());
        }
    }
}

/// The square root and division of `springs` springs, in blocks of [`FLOOR_BLOCK`] taken from
/// `d2` and `rest`, on the rayon pool.
fn spring_arithmetic(springs: usize, d2: &[f64], rest: &[f64]) {
    let arch = pulp::Arch::new();
    (0..springs.div_ceil(FLOOR_BLOCK))
        .into_par_iter()
        .with_min_len(16)
        .for_each(|b| {
            let len = FLOOR_BLOCK.min(springs - b * FLOOR_BLOCK);
            let mut out = [0.0; FLOOR_BLOCK];
            arch.dispatch(SpringArithmetic {
                k: 1000.0,
                d2: &d2[..len],
                rest: &rest[..len],
                out: &mut out[..len],
            });
            black_box(&out);
        });
}

fn explicit(c: &mut Criterion) {
    let model = sheet(256);
    let springs = model.lattice().springs.len();
    let traffic = model
        .fused_step_traffic()
        .expect("the sheet is a grid lattice");
    eprintln!(
        "256 x 256 lattice: {springs} springs, {} free dofs; the fused step moves {traffic} bytes at least",
        model.n_dofs()
    );
    let state = perturbed_state(&model);
    let mut out = vec![0.0; model.n_dofs()];
    let mut group = c.benchmark_group("msm");
    group
        .sample_size(50)
        .measurement_time(Duration::from_secs(3));
    group.throughput(Throughput::Elements(springs as u64));
    group.bench_function("internal_force/256x256", |b| {
        b.iter(|| model.internal_force(black_box(&state.q), &mut out))
    });
    let dt = 1e-5;
    let generic = Generic(&model);
    let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, &generic, &state, dt).unwrap();
    let mut s = state.clone();
    group.bench_function("symplectic_euler_step_generic/256x256", |b| {
        b.iter(|| stepper.step(&generic, &mut s, dt).unwrap())
    });
    // The squared lengths and rest lengths of the sheet's first block of springs.
    let lattice = model.lattice();
    let (d2, rest): (Vec<f64>, Vec<f64>) = lattice.springs[..FLOOR_BLOCK]
        .iter()
        .map(|sp| {
            let (xa, xb) = (lattice.positions[sp.a], lattice.positions[sp.b]);
            let d2: f64 = (0..3).map(|c| (xa[c] - xb[c]).powi(2)).sum();
            (d2, sp.rest_length)
        })
        .unzip();
    group.bench_function("spring_arithmetic/256x256", |b| {
        b.iter(|| spring_arithmetic(springs, black_box(&d2), black_box(&rest)))
    });
    let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, &model, &state, dt).unwrap();
    let mut s = state.clone();
    group.throughput(Throughput::Bytes(traffic as u64));
    group.bench_function("symplectic_euler_step/256x256", |b| {
        b.iter(|| stepper.step(&model, &mut s, dt).unwrap())
    });
    group.finish();
}

fn implicit(c: &mut Criterion) {
    let model = sheet(128);
    let springs = model.lattice().springs.len();
    eprintln!(
        "128 x 128 lattice: {springs} springs, {} free dofs",
        model.n_dofs()
    );
    let state = perturbed_state(&model);
    let dt = 1e-3;
    // Newton to 1e-8 relative: with k = 1000 and net forces far below the single spring
    // forces, the residual's round-off floor on this lattice is ≈ 2e-10, above sim's default
    // tolerance of 1e-10.
    let mut opts = RunOptions::new(dt, 1.0, IntegratorKind::BackwardEuler);
    opts.newton_tolerance = 1e-8;
    let mut stepper =
        make_stepper_with_options(IntegratorKind::BackwardEuler, &model, &state, &opts).unwrap();
    let mut s = state.clone();
    let mut group = c.benchmark_group("msm");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    group.throughput(Throughput::Elements(springs as u64));
    group.bench_function("backward_euler_step/128x128", |b| {
        b.iter(|| stepper.step(&model, &mut s, dt).unwrap())
    });
    group.bench_function("tangent_stiffness/128x128", |b| {
        b.iter(|| black_box(model.tangent_stiffness(black_box(&state.q))))
    });
    // One numeric Cholesky factorization of the step's Newton matrix J = M + Δt² K_T (symbolic
    // analysis done once, outside): the unit issue 12 measures the step against.
    let mass = model.mass().to_sparse();
    let jacobian = ShiftedSum::new(&mass, dt * dt, &model.tangent_stiffness(&state.q)).unwrap();
    let mut solver = SpdSolver::new(jacobian.matrix()).unwrap();
    group.bench_function("newton_factorization/128x128", |b| {
        b.iter(|| solver.refactor(black_box(jacobian.matrix())).unwrap())
    });
    // One solve with that factor (forward and back substitution; the right-hand side is
    // copied in first, 0.4 MB, so that repeated solves do not grow it).
    let rhs = vec![1.0; model.n_dofs()];
    let mut x = rhs.clone();
    group.bench_function("newton_solve/128x128", |b| {
        b.iter(|| {
            x.copy_from_slice(&rhs);
            solver.solve_in_place(black_box(&mut x))
        })
    });
    group.finish();
}

criterion_group!(benches, memory, explicit, implicit);
criterion_main!(benches);
