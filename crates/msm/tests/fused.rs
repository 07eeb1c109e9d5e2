//! The fused symplectic-Euler step of grid lattices (`MsmModel` as a `FusedStep`) against an
//! independent step written from the spring list (`SpringLattice::elastic_forces`, one spring
//! at a time) and against the generic path of `nurbspring-sim` (forces per node, then the
//! update); the lattices it must decline; and its independence of the thread count.

mod support;

use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::{
    Class, Constants, FixedNodes, LatticeOptions, MsmModel, ParameterGrid, SpringKind,
    SpringLattice,
};
use nurbspring_sim::{
    DynamicModel, IntegratorKind, State, SystemMatrix, make_stepper, model::FusedStep,
};
use support::{Lcg, curved_lattice};

/// Largest difference between two steps, relative to the largest entry of the reference:
/// the same products summed in another order, so a few ulps of the largest force per step.
const ROUND_OFF: f64 = 1e-12;

/// The model with its fused step hidden: `nurbspring-sim`'s generic symplectic Euler runs it.
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

/// One symplectic-Euler step written from the lattice alone: the elastic force of every
/// spring from `SpringLattice::elastic_forces`, then `v += Δt/m (m g + F + f_el − γ v)`,
/// `q += Δt v` on the free nodes.
fn reference_step(model: &MsmModel, state: &mut State, dt: f64) {
    let lattice = model.lattice();
    let x = model.full_positions(&state.q);
    let mut f = vec![0.0; x.len()];
    lattice.elastic_forces(&x, &mut f);
    for (i, &a) in model.free_nodes().iter().enumerate() {
        let m = lattice.masses[a];
        for c in 0..3 {
            let node_force = lattice.forces.get(a).map_or(0.0, |f| f[c]);
            let force = m * lattice.gravity[c] + node_force + f[3 * a + c]
                - lattice.damping[a] * state.v[3 * i + c];
            state.v[3 * i + c] += dt * force / m;
            state.q[3 * i + c] += dt * state.v[3 * i + c];
        }
    }
    state.t += dt;
}

/// `max |a − b| / max |b|`.
fn max_relative(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// A perturbed state with random velocities.
fn moving_state(model: &MsmModel, seed: u64) -> State {
    let mut rng = Lcg(seed);
    let mut state = model.initial_state(&[]);
    rng.perturb(&mut state.q, 1e-3);
    rng.perturb(&mut state.v, 0.1);
    state
}

/// Runs `steps` fused steps, the same generic steps and reference steps from `state` and
/// checks that the three agree to round-off; returns the fused state.
fn check_against_references(model: &MsmModel, state: &State, dt: f64, steps: usize) -> State {
    assert!(
        model.fused_step().is_some(),
        "{model:?} should have a fused step"
    );
    let generic = Generic(model);
    let mut fused_state = state.clone();
    let mut generic_state = state.clone();
    let mut reference = state.clone();
    let mut fused = make_stepper(IntegratorKind::SymplecticEuler, model, state, dt).unwrap();
    let mut plain = make_stepper(IntegratorKind::SymplecticEuler, &generic, state, dt).unwrap();
    for step in 1..=steps {
        fused.step(model, &mut fused_state, dt).unwrap();
        plain.step(&generic, &mut generic_state, dt).unwrap();
        reference_step(model, &mut reference, dt);
        for (what, other) in [("generic", &generic_state), ("reference", &reference)] {
            let dv = max_relative(&fused_state.v, &other.v);
            let dq = max_relative(&fused_state.q, &other.q);
            assert!(
                dv < ROUND_OFF && dq < ROUND_OFF,
                "step {step}: fused vs {what}: velocities {dv:e}, positions {dq:e}"
            );
        }
        assert_eq!(fused_state.t, generic_state.t);
    }
    // The step did move the lattice: the check is not vacuous.
    assert!(max_relative(&fused_state.q, &state.q) > 1e-6);
    fused_state
}

/// A bilinear sheet on `n_u × n_v` uniform nodes with the given spring classes.
fn sheet(n_u: usize, n_v: usize, constants: Constants, fixed: FixedNodes) -> SpringLattice {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let pts = vec![[0., 0., 0.], [0., 1., 0.1], [1., 0., 0.1], [1., 1., 0.]];
    let surface = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 4]).unwrap();
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: n_u,
            nodes_v: n_v,
        },
        constants,
        mass: 1.0 / (n_u * n_v) as f64,
        fixed,
        gravity: [0.0, 0.0, -9.81],
        ..Default::default()
    };
    SpringLattice::from_surface(&surface, &options, &[]).unwrap()
}

fn structural_shear() -> Constants {
    Constants::from_pairs([
        (Class::Spring(SpringKind::Structural), 1000.0),
        (Class::Spring(SpringKind::Shear), 500.0),
    ])
}

#[test]
fn fused_step_matches_the_spring_list_on_a_small_sheet() {
    // Two fixed corners and gravity, as in the benchmark; serial (one band).
    let lattice = sheet(6, 5, structural_shear(), FixedNodes::List(vec![0, 25]));
    let model = MsmModel::new(lattice).unwrap();
    let state = moving_state(&model, 3);
    check_against_references(&model, &state, 1e-4, 20);
}

#[test]
fn fused_step_handles_bending_pre_strain_damping_and_varying_nodes() {
    // Every kind of spring (row offsets up to 2), pre-strain, a fixed first row and scattered
    // fixed nodes, per-node masses, damping and node forces, and a few springs with their own
    // constant.
    let mut lattice = curved_lattice(9, 7, 0.05);
    for a in (0..7).chain([17, 30, 48, 62]) {
        lattice.fixed[a] = true;
    }
    let mut rng = Lcg(5);
    let masses = (0..lattice.n_nodes())
        .map(|_| 1.0 + 0.5 * rng.next())
        .collect();
    lattice.set_masses(masses).unwrap();
    lattice.damping = (0..lattice.n_nodes())
        .map(|_| 0.2 + 0.1 * rng.next())
        .collect();
    lattice.forces = (0..lattice.n_nodes())
        .map(|_| [rng.next(), rng.next(), rng.next()])
        .collect();
    lattice.gravity = [0.3, -0.2, -9.81];
    for s in lattice.springs.iter_mut().step_by(7) {
        s.k *= 1.5;
    }
    let model = MsmModel::new(lattice).unwrap();
    let state = moving_state(&model, 8);
    check_against_references(&model, &state, 2e-3, 30);
}

#[test]
fn fused_step_matches_in_parallel_bands_and_is_the_same_on_any_thread_count() {
    // 96 rows: three bands of 32 rows, and enough springs to run them in parallel; fixed
    // nodes next to the cuts between the bands and bending springs that reach across them.
    let mut lattice = curved_lattice(96, 48, 0.02);
    for a in [
        0,
        47,
        31 * 48 + 5,
        32 * 48 + 6,
        63 * 48,
        64 * 48 + 47,
        95 * 48 + 20,
    ] {
        lattice.fixed[a] = true;
    }
    let model = MsmModel::new(lattice).unwrap();
    assert!(model.lattice().springs.len() > 20_000);
    let state = moving_state(&model, 21);
    let expected = check_against_references(&model, &state, 1e-3, 3);
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let got = pool.install(|| {
            let mut s = state.clone();
            let mut stepper =
                make_stepper(IntegratorKind::SymplecticEuler, &model, &s, 1e-3).unwrap();
            for _ in 0..3 {
                stepper.step(&model, &mut s, 1e-3).unwrap();
            }
            s
        });
        assert_eq!(got.q, expected.q, "{threads} threads");
        assert_eq!(got.v, expected.v, "{threads} threads");
    }
}

#[test]
fn lattices_off_the_grid_step_take_the_generic_path() {
    let base = || sheet(6, 5, structural_shear(), FixedNodes::List(vec![0]));
    // A missing spring: a direction is incomplete.
    let mut missing = base();
    missing.springs.remove(7);
    // Two springs between the same nodes.
    let mut doubled = base();
    let extra = doubled.springs[3];
    doubled.springs.push(extra);
    // A spring three columns long.
    let mut long = base();
    long.springs[0].b = 3;
    long.springs[0].rest_length = 0.6;
    // No grid (the same lattice from its parts).
    let l = base();
    let parts = SpringLattice::from_parts(
        l.positions.clone(),
        l.masses.clone(),
        l.damping.clone(),
        l.fixed.clone(),
        l.springs.clone(),
        l.gravity,
    )
    .unwrap();
    // Rows of three nodes.
    let short = sheet(6, 3, structural_shear(), FixedNodes::List(vec![0]));
    for (what, lattice) in [
        ("missing spring", missing),
        ("doubled spring", doubled),
        ("long spring", long),
        ("no grid", parts),
        ("short rows", short),
    ] {
        let model = MsmModel::new(lattice).unwrap();
        assert!(model.fused_step().is_none(), "{what}");
        assert!(model.fused_step_traffic().is_none(), "{what}");
        // The generic path still agrees with the spring list.
        let state = moving_state(&model, 2);
        let mut s = state.clone();
        let mut r = state.clone();
        let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, &model, &s, 1e-4).unwrap();
        for _ in 0..5 {
            stepper.step(&model, &mut s, 1e-4).unwrap();
            reference_step(&model, &mut r, 1e-4);
        }
        assert!(max_relative(&s.v, &r.v) < ROUND_OFF, "{what}");
        assert!(max_relative(&s.q, &r.q) < ROUND_OFF, "{what}");
    }
}

#[test]
fn fused_step_traffic_counts_the_minimal_data() {
    // 6 × 5 nodes, 2 fixed: 28 free nodes, positions and velocities read and written once
    // (4 × 24 B each); structural 6·4 + 5·5 = 49 and shear 2·5·4 = 40 springs, one f64 rest
    // length each; the constants are the same everywhere, so nothing per node.
    let lattice = sheet(6, 5, structural_shear(), FixedNodes::List(vec![0, 25]));
    let model = MsmModel::new(lattice).unwrap();
    assert_eq!(model.fused_step_traffic(), Some(28 * 96 + (49 + 40) * 8));
    let fused: &dyn FusedStep = model.fused_step().unwrap();
    assert!(fused.workspace_len() > 0);

    // Per-node masses, damping and forces that vary are read once per free node (8 B, 8 B and
    // 24 B); a structural direction whose springs no longer share a constant reads one per
    // spring: the 6·4 springs along v, (j, j + 1) in a row, 8 B more each.
    let mut lattice = sheet(6, 5, structural_shear(), FixedNodes::List(vec![0, 25]));
    let n = lattice.n_nodes();
    lattice
        .set_masses((0..n).map(|a| 0.1 + 0.01 * a as f64).collect())
        .unwrap();
    lattice.damping = (0..n).map(|a| 0.2 + 0.01 * a as f64).collect();
    lattice.forces = (0..n).map(|a| [0.0, 0.0, 0.1 * a as f64]).collect();
    let along_v = lattice
        .springs
        .iter()
        .position(|s| s.kind == SpringKind::Structural && s.b == s.a + 1)
        .unwrap();
    lattice.springs[along_v].k *= 2.0;
    let model = MsmModel::new(lattice).unwrap();
    let expected = 28 * 96 + (49 + 40) * 8 + 28 * (8 + 8 + 24) + 24 * 8;
    assert_eq!(model.fused_step_traffic(), Some(expected));
}
