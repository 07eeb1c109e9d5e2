//! How far the shell itself drifts from its own run over a long large-motion swing: the cloth
//! of docs/derivations.md (quadratic 14², pinned at two corners, gravity, generalized-α at the
//! scene's Δt = 0.005 s over 3.5 s, ρ∞ = [`LARGE_MOTION_RHO_INFINITY`] unless `RHO` says
//! otherwise, `INTEGRATOR` another integrator) against the same shell at Δt/2: every lattice
//! node against its surface point, the largest distance over the size, the farthest node's
//! reach and the total energy's change, at each half second (`ENERGY_ONLY=1`: the Δt run's
//! reach and energy alone). It bounds what any model can be asked to follow there, and showed
//! that at ρ∞ = 0.8 the shell's run gains energy (docs/derivations.md, math.md §11.2).
//!
//! ```text
//! cargo run --release -p nurbspring-derive --example shell_self_check [-- T_END]
//! ```

use nurbspring_derive::{LARGE_MOTION_RHO_INFINITY, NodeMap, rule_lattice};
use nurbspring_dnurbs::obstacle::{rectangle, refined};
use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, ShellMaterial};
use nurbspring_geom::norm;
use nurbspring_msm::{FixedNodes, LatticeOptions, ParameterGrid};
use nurbspring_sim::{IntegratorKind, RunOptions, Sample, State, simulate};

fn main() {
    let t_end: f64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(3.5);
    let spans = 12;
    let surface = refined(&rectangle(0.5, 0.5), 2, (spans, spans)).unwrap();
    let shell = ShellMaterial {
        young: 5.0e6,
        poisson: 0.3,
        thickness: 0.0003,
        density: 500.0,
        gamma: 0.02,
    };
    let loads = Loads {
        gravity: [0.0, 0.0, -9.81],
        ..Loads::default()
    };
    let constraints = Constraints {
        fixed_points: vec![0, spans + 1],
        ..Constraints::default()
    };
    let geometry = Geometry::Surface(surface.clone());
    let model = DnurbsModel::kirchhoff_love(
        geometry.clone(),
        shell,
        loads,
        &constraints,
        DnurbsOptions::default(),
    )
    .unwrap();
    let options = LatticeOptions {
        grid: ParameterGrid::Greville,
        fixed: FixedNodes::Auto,
        ..LatticeOptions::default()
    };
    let (lattice, _) = rule_lattice(&surface, &shell, &options, model.fixed_points()).unwrap();
    let map = NodeMap::new(&geometry, &lattice, &model).unwrap();
    let size = {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &lattice.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        norm([hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]])
    };
    let run = |dt: f64| -> Vec<(f64, Vec<[f64; 3]>, f64)> {
        let mut opts = RunOptions::new(dt, t_end, IntegratorKind::GeneralizedAlpha);
        opts.rho_infinity = std::env::var("RHO")
            .ok()
            .and_then(|r| r.parse().ok())
            .unwrap_or(LARGE_MOTION_RHO_INFINITY);
        if let Some(k) = std::env::var("INTEGRATOR")
            .ok()
            .and_then(|k| IntegratorKind::parse(&k))
        {
            opts.integrator = k;
        }
        let q = model.reduced_coordinates(model.p0());
        let state = State {
            t: 0.0,
            v: vec![0.0; q.len()],
            q,
        };
        let mut out = Vec::new();
        simulate(&model, state, &opts, &mut |s: &Sample<'_>| {
            out.push((
                s.t,
                map.positions(&model.full_coordinates(s.q)),
                s.kinetic + s.potential,
            ));
        })
        .unwrap();
        out
    };
    let start = std::time::Instant::now();
    let coarse = run(0.005);
    if std::env::var_os("ENERGY_ONLY").is_some() {
        let e0 = coarse[0].2;
        let rest = &coarse[0].1;
        let mut next = 0.5;
        for (t, x, e) in &coarse {
            if *t >= next - 1e-9 {
                let reach = x
                    .iter()
                    .zip(rest)
                    .map(|(a, b)| norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]]))
                    .fold(0.0, f64::max)
                    / size;
                println!("| {t:.2} | {:.1} % | {:+.3e} |", 100.0 * reach, e - e0);
                next += 0.5;
            }
        }
        return;
    }
    let fine = run(0.0025);
    println!(
        "| t [s] | largest node distance, Δt against Δt/2, over the size | farthest node from rest, Δt | Δt/2 | energy − start [J], Δt | Δt/2 |"
    );
    println!("|---|---|---|---|---|---|");
    let rest = &coarse[0].1;
    let reach = |x: &[[f64; 3]]| {
        x.iter()
            .zip(rest)
            .map(|(a, b)| norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]]))
            .fold(0.0, f64::max)
            / size
    };
    let mut worst: f64 = 0.0;
    let mut next = 0.5;
    let (e0, f0) = (coarse[0].2, fine[0].2);
    for (t, x, e) in &coarse {
        let Some((_, y, f)) = fine.iter().find(|(s, _, _)| (s - t).abs() < 1e-9) else {
            continue;
        };
        let d = x
            .iter()
            .zip(y)
            .map(|(a, b)| norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]]))
            .fold(0.0, f64::max)
            / size;
        worst = worst.max(d);
        if *t >= next - 1e-9 {
            println!(
                "| {t:.2} | {:.2} % (worst so far {:.2} %) | {:.1} % | {:.1} % | {:+.3e} | {:+.3e} |",
                100.0 * d,
                100.0 * worst,
                100.0 * reach(x),
                100.0 * reach(y),
                e - e0,
                f - f0
            );
            next += 0.5;
        }
    }
    eprintln!("{:.0} s", start.elapsed().as_secs_f64());
}
