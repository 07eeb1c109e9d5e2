//! The cloth of the cloth benchmark (`benches/cloth.rs`) and of its dump for the peers
//! (`examples/cloth_dump.rs`): one definition, so both see the same mesh and elements.

use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_msm::{
    Class, Constants, FixedNodes, HingeKind, LatticeOptions, MsmModel, ParameterGrid, SpringKind,
    SpringLattice,
};
use nurbspring_sim::State;

/// A gently curved bilinear sheet (that of `benches/step.rs`), `n × n` nodes, triangulated with
/// alternating diagonals (`SpringLattice::triangulated`): a spring on every edge (structural on
/// the grid lines, shear on the diagonals) and a hinge on every interior edge with its rest
/// angle; the two corners of the `v = 0` edge fixed, gravity on.
pub fn cloth(n: usize) -> MsmModel {
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
            (Class::Hinge(HingeKind::Grid), 1e-3),
            (Class::Hinge(HingeKind::Diagonal), 5e-4),
        ]),
        mass: 1.0 / (n * n) as f64,
        fixed: FixedNodes::List(vec![0, (n - 1) * n]),
        gravity: [0.0, 0.0, -9.81],
        ..Default::default()
    };
    let lattice = SpringLattice::triangulated(&surface, &options, &[]).unwrap();
    MsmModel::new(lattice).unwrap()
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
