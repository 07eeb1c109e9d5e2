//! Writes nurbspring's reference for the "Mass-spring step" benchmark (docs/benchmarks.md) so
//! that the numpy, Taichi and Warp steps in `bench-peers/msm_step_*.py` can be checked against
//! it before they are timed.
//!
//! The lattice is `sheet(256)` of `crates/msm/benches/step.rs`: the bilinear sheet with corners
//! (0,0,0), (0,1,0.1), (1,0,0.1), (1,1,0), 256 × 256 uniform nodes, structural (k = 1000) and
//! shear (k = 500) springs with rest length = initial length, node mass 1/256², gravity
//! (0, 0, −9.81), nodes 0 and 255·256 fixed; the free coordinates perturbed by
//! `1e-4 sin(0.7 i)`. Written (little-endian f64): `x0` (all node positions, the unperturbed
//! lattice), `q0`/`v0` (perturbed free coordinates and zero velocity), and `q{N}`/`v{N}` after
//! N = 1 and 100 symplectic-Euler steps of Δt = 1e-5.
//!
//! For the backward-Euler peer (`bench-peers/msm_step_scipy_be.py`), the same sheet at 128 × 128
//! nodes (node mass 1/128², nodes 0 and 127·128 fixed), perturbed the same way, after one
//! backward-Euler step of Δt = 1e-3 with Newton to 1e-8 relative (the settings of
//! `msm/backward_euler_step/128x128` in `crates/msm/benches/step.rs`): `be128_q0`, `be128_q1`,
//! `be128_v1`.
//!
//! Run: `cargo run --release --manifest-path bench-peers/Cargo.toml --example dump_msm -- DIR`.

use std::io::Write;

use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_msm::{
    Class, Constants, FixedNodes, LatticeOptions, MsmModel, ParameterGrid, SpringKind, SpringLattice,
};
use nurbspring_sim::{IntegratorKind, RunOptions, make_stepper, make_stepper_with_options};

fn sheet(n: usize) -> MsmModel {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let pts = vec![[0., 0., 0.], [0., 1., 0.1], [1., 0., 0.1], [1., 1., 0.]];
    let surface = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 4]).unwrap();
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: n,
            nodes_v: n,
        },
        constants: Constants::from_pairs([
            (Class::Spring(SpringKind::Structural), 1000.0),
            (Class::Spring(SpringKind::Shear), 500.0),
        ]),
        mass: 1.0 / (n * n) as f64,
        fixed: FixedNodes::List(vec![0, (n - 1) * n]),
        gravity: [0.0, 0.0, -9.81],
        ..Default::default()
    };
    let lattice = SpringLattice::from_surface(&surface, &options, &[]).unwrap();
    MsmModel::new(lattice).unwrap()
}

fn put(dir: &std::path::Path, name: &str, v: &[f64]) {
    let mut f = std::fs::File::create(dir.join(format!("{name}.f64"))).unwrap();
    f.write_all(&v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>())
        .unwrap();
}

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "/tmp/nurbspring-agree".into());
    let dir = std::path::PathBuf::from(dir);
    std::fs::create_dir_all(&dir).unwrap();
    let model = sheet(256);
    println!(
        "256 x 256 lattice: {} nodes, {} springs, free nodes {}",
        model.lattice().n_nodes(),
        model.lattice().springs.len(),
        model.free_nodes().len()
    );
    put(&dir, "x0", &model.lattice().flat_positions());
    let mut state = model.initial_state(&[]);
    for (i, q) in state.q.iter_mut().enumerate() {
        *q += 1e-4 * ((i as f64) * 0.7).sin();
    }
    put(&dir, "q0", &state.q);
    put(&dir, "v0", &state.v);
    let dt = 1e-5;
    let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, &model, &state, dt).unwrap();
    for n in 1..=100 {
        stepper.step(&model, &mut state, dt).unwrap();
        if n == 1 || n == 100 {
            put(&dir, &format!("q{n}"), &state.q);
            put(&dir, &format!("v{n}"), &state.v);
        }
    }
    let vmax = state.v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!("after 100 steps: max |v| = {vmax:e}");

    let model = sheet(128);
    let mut state = model.initial_state(&[]);
    for (i, q) in state.q.iter_mut().enumerate() {
        *q += 1e-4 * ((i as f64) * 0.7).sin();
    }
    put(&dir, "be128_q0", &state.q);
    let dt = 1e-3;
    let mut opts = RunOptions::new(dt, 1.0, IntegratorKind::BackwardEuler);
    opts.newton_tolerance = 1e-8;
    let mut stepper =
        make_stepper_with_options(IntegratorKind::BackwardEuler, &model, &state, &opts).unwrap();
    stepper.step(&model, &mut state, dt).unwrap();
    put(&dir, "be128_q1", &state.q);
    put(&dir, "be128_v1", &state.v);
    let vmax = state.v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!("128 x 128, one backward-Euler step of 1e-3: max |v| = {vmax:e}");
}
