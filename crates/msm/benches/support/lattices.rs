//! The lattices of the mass-spring benchmarks, one definition each so that every bench,
//! example and peer dump sees the same mesh and elements: the sheet of `benches/step.rs` (and
//! `examples/step_blocks.rs`) and the cloth of `benches/cloth.rs` (and its dump for the peers,
//! `examples/cloth_dump.rs`).
// Each includer uses some of these.
#![allow(dead_code)]

use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_msm::{
    Class, Constants, FixedNodes, HingeKind, LatticeOptions, MsmModel, ParameterGrid, SpringKind,
    SpringLattice,
};
use nurbspring_sim::State;

/// A gently curved bilinear sheet and the options of an `n × n` uniform lattice on it with
/// `constants`: spacing ≈ 1 / (n − 1), the two corners of the `v = 0` edge fixed, gravity on.
fn bilinear_sheet(n: usize, constants: Constants) -> (NurbsSurface, LatticeOptions) {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let pts = vec![[0., 0., 0.], [0., 1., 0.1], [1., 0., 0.1], [1., 1., 0.]];
    let surface = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 4]).unwrap();
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: n,
            nodes_v: n,
        },
        constants,
        mass: 1.0 / (n * n) as f64,
        fixed: FixedNodes::List(vec![0, (n - 1) * n]),
        gravity: [0.0, 0.0, -9.81],
        ..Default::default()
    };
    (surface, options)
}

/// The sheet of the mass-spring step: structural and shear springs on the grid.
pub fn sheet(n: usize) -> MsmModel {
    let (surface, options) = bilinear_sheet(
        n,
        Constants::from_pairs([
            (Class::Spring(SpringKind::Structural), 1000.0),
            (Class::Spring(SpringKind::Shear), 500.0),
        ]),
    );
    MsmModel::new(SpringLattice::from_surface(&surface, &options, &[]).unwrap()).unwrap()
}

/// The cloth: the same sheet triangulated with alternating diagonals
/// (`SpringLattice::triangulated`), a spring on every edge (structural on the grid lines,
/// shear on the diagonals) and a hinge on every interior edge with its rest angle.
pub fn cloth(n: usize) -> MsmModel {
    let (surface, options) = bilinear_sheet(
        n,
        Constants::from_pairs([
            (Class::Spring(SpringKind::Structural), 1000.0),
            (Class::Spring(SpringKind::Shear), 500.0),
            (Class::Hinge(HingeKind::Grid), 1e-3),
            (Class::Hinge(HingeKind::Diagonal), 5e-4),
        ]),
    );
    MsmModel::new(SpringLattice::triangulated(&surface, &options, &[]).unwrap()).unwrap()
}

/// The rest state with every coordinate moved by `1e-4 sin(0.7 i)`, so that every spring and
/// hinge carries a force.
pub fn perturbed_state(model: &MsmModel) -> State {
    let mut state = model.initial_state(&[]);
    for (i, q) in state.q.iter_mut().enumerate() {
        *q += 1e-4 * ((i as f64) * 0.7).sin();
    }
    state
}

/// The time step of the benchmark.
pub const DT: f64 = 1e-5;
