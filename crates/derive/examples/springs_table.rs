//! The spring derivation on a family of shell scenes (docs/derivations.md, "The spring
//! derivation"): flat, cylindrical and doubly curved; clamped, pinned at corners, free edges;
//! 9² to 33² nets. Prints one Markdown row per scene, of the derivation METHOD (`springs`, the
//! default, `modal`, `excitation` or `reduction`).
//!
//! ```text
//! cargo run --release -p nurbspring-derive --example springs_table [-- NAME_FILTER [METHOD]]
//! ```

use std::time::Instant;

use nurbspring_derive::{
    InitialConditions, Method, SpringsConfig, TimeSettings, derive_springs, reduce_shell,
};
use nurbspring_dnurbs::obstacle::{cylinder_sector, rectangle, refined, sphere_zone};
use nurbspring_dnurbs::{
    Constraints, DnurbsOptions, Edge, EdgeCondition, EdgeConstraint, EdgeLoad, Loads, PointLoad,
    ShellMaterial,
};
use nurbspring_geom::NurbsSurface;
use nurbspring_msm::{FixedNodes, LatticeOptions, ParameterGrid};
use nurbspring_sim::IntegratorKind;

struct Case {
    name: String,
    /// The scene's end time (a mechanism's dynamic run covers it).
    t_end: f64,
    surface: NurbsSurface,
    shell: ShellMaterial,
    loads: Loads,
    constraints: Constraints,
}

fn clamp(edges: &[Edge]) -> Constraints {
    Constraints {
        edges: edges
            .iter()
            .map(|&edge| EdgeConstraint {
                edge,
                condition: EdgeCondition::Clamped,
            })
            .collect(),
        ..Constraints::default()
    }
}

fn pin(edges: &[Edge]) -> Constraints {
    Constraints {
        edges: edges
            .iter()
            .map(|&edge| EdgeConstraint {
                edge,
                condition: EdgeCondition::Pinned,
            })
            .collect(),
        ..Constraints::default()
    }
}

fn cases() -> Vec<Case> {
    let steel = ShellMaterial {
        young: 2.1e11,
        poisson: 0.3,
        thickness: 0.002,
        density: 7800.0,
        gamma: 0.0,
    };
    let cloth = ShellMaterial {
        young: 5.0e6,
        poisson: 0.3,
        thickness: 0.0003,
        density: 500.0,
        gamma: 0.02,
    };
    let mut out = Vec::new();
    // Sze's cantilever (end shear up to P_max = 4).
    out.push(Case {
        t_end: 0.5,
        name: "Sze cantilever, cubic 16×1 spans".into(),
        surface: refined(&rectangle(10.0, 1.0), 3, (16, 1)).unwrap(),
        shell: ShellMaterial {
            young: 1.2e6,
            poisson: 0.0,
            thickness: 0.1,
            density: 500.0,
            gamma: 0.0,
        },
        loads: Loads {
            edges: vec![EdgeLoad {
                edge: Edge::U1,
                force: [0.0, 0.0, 4.0],
                moment: 0.0,
            }],
            ..Loads::default()
        },
        constraints: clamp(&[Edge::U0]),
    });
    for spans in [6, 14, 30] {
        let n = spans + 3;
        out.push(Case {
            t_end: 0.5,
            name: format!("flat plate clamped on one edge, point load at a free corner, {n}²"),
            surface: refined(&rectangle(0.4, 0.3), 3, (spans, spans)).unwrap(),
            shell: steel,
            loads: Loads {
                point: vec![PointLoad {
                    u: 1.0,
                    v: 1.0,
                    force: [0.0, 0.0, 5.0],
                }],
                ..Loads::default()
            },
            constraints: clamp(&[Edge::U0]),
        });
        out.push(Case {
            t_end: 0.5,
            name: format!("cylindrical panel pinned on its straight edges, gravity, {n}²"),
            surface: refined(
                &cylinder_sector(0.5, 0.6, 0.9, std::f64::consts::PI - 0.9),
                3,
                (spans, spans),
            )
            .unwrap(),
            shell: steel,
            loads: Loads {
                gravity: [0.0, 0.0, -9.81 * 40.0],
                ..Loads::default()
            },
            constraints: pin(&[Edge::V0, Edge::V1]),
        });
        out.push(Case {
            t_end: 0.5,
            name: format!("spherical zone clamped at its equator, gravity, {n}²"),
            surface: refined(&sphere_zone(0.5, 1.0), 3, (spans, spans)).unwrap(),
            shell: steel,
            loads: Loads {
                gravity: [0.0, 0.0, -9.81 * 200.0],
                ..Loads::default()
            },
            constraints: clamp(&[Edge::U0]),
        });
    }
    // The cloth swings about its corners like a pendulum of period about 2π √(2L/3g) = 1.16 s:
    // over the example's 0.5 s, and over three swings.
    for (spans, t_end) in [(6, 0.5), (12, 0.5), (12, 3.5)] {
        let n = spans + 2;
        out.push(Case {
            t_end,
            name: format!("cloth pinned at two corners, gravity, quadratic {n}², {t_end} s"),
            surface: refined(&rectangle(0.5, 0.5), 2, (spans, spans)).unwrap(),
            shell: cloth,
            loads: Loads {
                gravity: [0.0, 0.0, -9.81],
                ..Loads::default()
            },
            constraints: Constraints {
                fixed_points: vec![0, spans + 1],
                ..Constraints::default()
            },
        });
    }
    out
}

fn main() {
    let filter = std::env::args().nth(1).unwrap_or_default();
    let method = std::env::args()
        .nth(2)
        .map_or(Some(Method::Springs), |m| Method::parse(&m))
        .filter(|&m| m.takes(true))
        .unwrap_or_else(|| {
            eprintln!("METHOD: springs, modal, excitation or reduction");
            std::process::exit(2)
        });
    println!(
        "| scene | nodes | lowest 6 within 3 % (worst) | small motion | large static (reach) | large dynamic | time |"
    );
    println!("|---|---|---|---|---|---|---|");
    for case in cases() {
        if !case.name.contains(&filter) {
            continue;
        }
        let config = SpringsConfig {
            surface: case.surface.clone(),
            shell: case.shell,
            loads: case.loads.clone(),
            constraints: case.constraints.clone(),
            dnurbs: DnurbsOptions::default(),
            lattice: LatticeOptions {
                grid: ParameterGrid::Greville,
                fixed: FixedNodes::Auto,
                ..LatticeOptions::default()
            },
            initial: InitialConditions::default(),
            time: TimeSettings {
                dt: 0.005,
                t_end: case.t_end,
                dnurbs_integrator: IntegratorKind::GeneralizedAlpha,
                msm_integrator: IntegratorKind::GeneralizedAlpha,
            },
            probes: vec![(0.5, 0.5)],
            method,
        };
        let start = Instant::now();
        if method == Method::Reduction {
            match reduce_shell(&config, None) {
                Ok(r) => {
                    let worst = r
                        .frequencies
                        .iter()
                        .filter_map(|f| f.relative_error)
                        .fold(0.0_f64, |a, e| a.max(e.abs()));
                    println!(
                        "| {} | {} free | {} ({:.1e}) | {:.1e} | — | — | {:.1} s |",
                        case.name,
                        r.free_nodes,
                        r.kind,
                        worst,
                        r.small_motion.relative_rms,
                        start.elapsed().as_secs_f64()
                    );
                }
                Err(e) => println!("| {} | error: {e} |", case.name),
            }
            continue;
        }
        match derive_springs(&config, None, &mut |_| {}) {
            Ok(d) => {
                if std::env::var_os("SPRINGS_VERBOSE").is_some() {
                    for c in &d.constants {
                        eprintln!(
                            "  {} rule {:.4e} calibrated {:.4e}",
                            c.class, c.rule, c.calibrated
                        );
                    }
                    for r in &d.frequencies {
                        eprintln!(
                            "  mode {} shell {:.5} msm {:?} mac {:?} err {:?}",
                            r.mode, r.shell, r.msm_mode, r.mac, r.relative_error
                        );
                    }
                    eprintln!(
                        "  factor {:.4} residual {:.4}",
                        d.frequency_factor, d.fit_residual
                    );
                    for g in &d.groups {
                        eprintln!("  {} ({}): scale {:.4}", g.group, g.elements, g.scale);
                    }
                    if let Some(l) = &d.large_motion {
                        eprintln!(
                            "  static: {:?}; dynamic: {:?}",
                            l.static_failure, l.dynamic_failure
                        );
                    }
                }
                let within = d
                    .frequencies
                    .iter()
                    .filter(|r| r.relative_error.is_some_and(|e| e.abs() <= 0.03))
                    .count();
                let worst = d
                    .frequencies
                    .iter()
                    .filter_map(|r| r.relative_error)
                    .fold(0.0_f64, |a, e| if e.abs() > a.abs() { e } else { a });
                let (stat, dynamic) = match &d.large_motion {
                    Some(l) => (
                        match (l.static_error, l.largest_displacement) {
                            (Some(e), Some(r)) => format!(
                                "{:.2} % ({:.0} %{}{})",
                                100.0 * e,
                                100.0 * r,
                                if l.shell_limit.is_some() {
                                    ", below the shell's limit point"
                                } else {
                                    ""
                                },
                                if l.static_failure.is_some() {
                                    ", the lattice buckles beyond"
                                } else {
                                    ""
                                }
                            ),
                            _ => "stopped".into(),
                        },
                        match &l.dynamic {
                            Some(r) => format!(
                                "{:.2} % over {:.4} s (reach {:.0} %)",
                                100.0 * r.max_error,
                                r.t_end,
                                100.0 * r.shell_displacement
                            ),
                            None => "stopped".into(),
                        },
                    ),
                    None => ("—".into(), "—".into()),
                };
                println!(
                    "| {} | {} | {}/{} ({:+.1} %) | {:.2} % | {} | {} | {:.1} s |",
                    case.name,
                    d.lattice.n_nodes(),
                    within,
                    d.frequencies.len(),
                    100.0 * worst,
                    100.0 * d.small_motion.relative_rms,
                    stat,
                    dynamic,
                    start.elapsed().as_secs_f64()
                );
            }
            Err(e) => println!("| {} | error: {e} |", case.name),
        }
    }
}
