//! Dynamics of the shell through the implicit schemes of nurbspring-sim: second-order
//! convergence of Newmark on a large-amplitude (nonlinear) run, and the energy error of
//! undamped average acceleration bounded and shrinking with Δt.

use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, EdgeCondition, EdgeConstraint};
use nurbspring_dnurbs::{Edge, Geometry, Loads, ShellMaterial};
use nurbspring_sim::{DynamicModel, IntegratorKind, RunOptions, Sample, State, simulate};

use crate::support::{rectangle, refined};

/// A cantilever strip 1 × 0.1, t = 0.01, clamped at u = 0, thrown upwards (every free control
/// point at 2 m/s, far beyond the linear range: the tip swings through about a third of the
/// length).
fn strip() -> (DnurbsModel, State) {
    let s = refined(&rectangle(1.0, 0.1), 2, (6, 1));
    let material = ShellMaterial {
        young: 1e6,
        poisson: 0.3,
        thickness: 0.01,
        density: 100.0,
        gamma: 0.0,
    };
    let constraints = Constraints {
        edges: vec![EdgeConstraint {
            edge: Edge::U0,
            condition: EdgeCondition::Clamped,
        }],
        ..Constraints::default()
    };
    let model = DnurbsModel::kirchhoff_love(
        Geometry::Surface(s),
        material,
        Loads::default(),
        &constraints,
        DnurbsOptions::default(),
    )
    .unwrap();
    let state = model.initial_state(&[[0.0, 0.0, 2.0]], 0.0);
    (model, state)
}

/// The state at `t_end` and the largest deviation of the total energy from its start.
fn run(
    model: &DnurbsModel,
    state: &State,
    dt: f64,
    t_end: f64,
    kind: IntegratorKind,
) -> (Vec<f64>, f64, f64) {
    let opts = RunOptions::new(dt, t_end, kind);
    let mut q = Vec::new();
    let mut start = None;
    let mut drift = 0.0_f64;
    let mut tip = 0.0_f64;
    let mut observer = |s: &Sample<'_>| {
        let e = s.kinetic + s.potential;
        let e0 = *start.get_or_insert(e);
        drift = drift.max((e - e0).abs() / e0);
        let p = model.full_coordinates(s.q);
        tip = tip.max(model.point(1.0, 0.05, &p).unwrap()[2]);
        q = s.q.to_vec();
    };
    simulate(model, state.clone(), &opts, &mut observer).unwrap();
    (q, drift, tip)
}

#[test]
fn newmark_converges_at_second_order_and_its_energy_error_shrinks() {
    let (model, state) = strip();
    let t_end = 0.2;
    // The reference: Δt/16 of the finest step below.
    let (reference, _, tip) = run(
        &model,
        &state,
        0.25e-3 / 4.0,
        t_end,
        IntegratorKind::Newmark,
    );
    assert!(
        tip > 0.2,
        "the tip rose by {tip}: the run must be nonlinear"
    );
    let mut errors = Vec::new();
    let mut drifts = Vec::new();
    for dt in [2e-3, 1e-3, 0.5e-3, 0.25e-3] {
        let (q, drift, _) = run(&model, &state, dt, t_end, IntegratorKind::Newmark);
        let e = q
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        errors.push(e);
        drifts.push(drift);
    }
    let rates: Vec<f64> = errors
        .windows(2)
        .map(|w| (w[0] / w[1]).ln() / 2f64.ln())
        .collect();
    eprintln!(
        "Newmark on the thrown strip: errors {errors:?}, rates {rates:?}, energy drift {drifts:?}"
    );
    assert!(rates.iter().all(|&r| (r - 2.0).abs() < 0.3), "{rates:?}");
    // The energy error is bounded (here below 1 %) and falls with Δt.
    assert!(drifts[0] < 1e-2, "{drifts:?}");
    assert!(drifts.windows(2).all(|w| w[1] < w[0]), "{drifts:?}");
    let _ = model.n_dofs();
}
