//! Closed-form solutions: plate and strip frequencies, the cantilever rolled into a circle by
//! an end moment (docs/math.md §10).

use nurbspring_dnurbs::{DnurbsModel, Edge, EdgeLoad, Loads, PathSettings, ShellMaterial};

use crate::support::*;

fn steel_sheet() -> ShellMaterial {
    ShellMaterial {
        young: 1e7,
        poisson: 0.3,
        thickness: 0.01,
        density: 1.0,
        gamma: 0.0,
    }
}

/// Relative errors of the lowest `count` frequencies against `exact`.
fn errors(model: &DnurbsModel, exact: &[f64]) -> Vec<f64> {
    let modes = model.modes(exact.len()).unwrap();
    modes
        .omega
        .iter()
        .zip(exact)
        .map(|(w, e)| (w - e).abs() / e)
        .collect()
}

/// Observed convergence rates `log(e_k / e_{k+1}) / log 2` of errors on nets halving h.
fn rates(errors: &[f64]) -> Vec<f64> {
    errors
        .windows(2)
        .map(|w| (w[0] / w[1]).ln() / 2f64.ln())
        .collect()
}

/// A simply supported square plate, a = 1: `ω_mn = π² (m² + n²) / a² √(D / ρt)`. With
/// displacement-only unknowns the simple support holds the boundary control points (w = 0
/// on the edges, the slope free). The frequency error of degree p converges as
/// `h^{2(p−1)}` (a fourth-order problem); the lowest mode is checked on three nets per
/// degree.
#[test]
fn simply_supported_plate_frequencies_converge_at_the_rate_of_the_degree() {
    let m = steel_sheet();
    let scale = (m.bending_stiffness() / m.mass_per_area()).sqrt();
    let pi2 = std::f64::consts::PI.powi(2);
    // (1,1), (1,2) and (2,1) twice, (2,2).
    let exact = [
        2.0 * pi2 * scale,
        5.0 * pi2 * scale,
        5.0 * pi2 * scale,
        8.0 * pi2 * scale,
    ];
    for (degree, nets, expected_rate) in [(2, [4, 8, 16], 2.0), (3, [4, 8, 16], 4.0)] {
        let mut lowest = Vec::new();
        for spans in nets {
            let s = refined(&rectangle(1.0, 1.0), degree, (spans, spans));
            let boundary: Vec<usize> = (0..s.n_control_points())
                .filter(|&k| {
                    let (i, j) = (k / s.n_v(), k % s.n_v());
                    i == 0 || j == 0 || i == s.n_u() - 1 || j == s.n_v() - 1
                })
                .collect();
            let model = shell_model(s, m, Loads::default(), vec![], boundary);
            let e = errors(&model, &exact);
            eprintln!("plate p = {degree}, {spans}²: errors {e:?}");
            lowest.push(e[0]);
            if spans == 16 {
                assert!(e.iter().all(|&x| x < 2e-2), "{e:?}");
            }
        }
        let r = rates(&lowest);
        eprintln!("plate p = {degree}: rates {r:.2?}");
        assert!(r.iter().all(|&x| (x - expected_rate).abs() < 0.3), "{r:?}");
    }
}

/// A cantilever strip, L = 1, width b = 0.05, t = 0.001, ν = 0: Euler–Bernoulli
/// `ω_n = (β_n L)² / L² √(D / ρt)` with `β_n L` = 1.875104, 4.694091, 7.854757. The lowest
/// three modes are bending (ω_3 = 17.5 ω_1): the strip's first torsion mode lies near
/// `(π/2) √2 (t/b) √(E/ρ)` ≈ 44 ω_1 and its first in-plane bending mode at `(b/t) ω_1` = 50 ω_1.
#[test]
fn cantilever_strip_frequencies_match_euler_bernoulli() {
    let m = ShellMaterial {
        thickness: 0.001,
        poisson: 0.0,
        ..steel_sheet()
    };
    let scale = (m.bending_stiffness() / m.mass_per_area()).sqrt();
    let exact: Vec<f64> = [
        1.875_104_068_711_961_f64,
        4.694_091_132_974_174,
        7.854_757_438_237_613,
    ]
    .iter()
    .map(|b| b * b * scale)
    .collect();
    let mut last = Vec::new();
    for spans in [8, 16, 32] {
        let s = refined(&rectangle(1.0, 0.05), 3, (spans, 1));
        let clamp: Vec<usize> = row_u(&s, 0).into_iter().chain(row_u(&s, 1)).collect();
        let model = shell_model(s, m, Loads::default(), vec![], clamp);
        last = errors(&model, &exact);
        eprintln!("strip {spans} spans: errors {last:?}");
    }
    assert!(last.iter().all(|&e| e < 1e-4), "{last:?}");
}

/// A cantilever strip (L = 10, width 1, t = 0.1, E = 1.2e6, ν = 0) under the end moment
/// `M = 2π D b / L` rolls into a full circle: under `λ M` the tip lies on the circle of radius
/// `L / (2π λ)`, at `x = R sin(2πλ)`, `z = R (1 − cos 2πλ)` (exact large rotation).
#[test]
fn an_end_moment_rolls_the_cantilever_into_a_circle() {
    let m = ShellMaterial {
        young: 1.2e6,
        poisson: 0.0,
        thickness: 0.1,
        density: 1.0,
        gamma: 0.0,
    };
    let length = 10.0;
    let moment = 2.0 * std::f64::consts::PI * m.bending_stiffness() / length;
    let s = refined(&rectangle(length, 1.0), 4, (16, 1));
    let clamp: Vec<usize> = row_u(&s, 0).into_iter().chain(row_u(&s, 1)).collect();
    let loads = Loads {
        edges: vec![EdgeLoad {
            edge: Edge::U1,
            force: [0.0; 3],
            moment: -moment,
        }],
        ..Loads::default()
    };
    let model = shell_model(s, m, loads, vec![], clamp);
    let settings = PathSettings {
        levels: 8,
        ..PathSettings::default()
    };
    let path = model
        .equilibrium_path(&settings, &|| false, &mut |_| {})
        .unwrap();
    eprintln!(
        "roll-up: {} increments, {} iterations, {} cut backs",
        path.increments, path.iterations, path.cut_backs
    );
    let mut worst = 0.0_f64;
    for level in &path.levels {
        let tip = model.point(1.0, 0.5, &level.p).unwrap();
        let a = 2.0 * std::f64::consts::PI * level.lambda;
        let r = length / a;
        let exact = [r * a.sin(), r * (1.0 - a.cos())];
        let e = ((tip[0] - exact[0]).powi(2) + (tip[2] - exact[1]).powi(2)).sqrt() / length;
        eprintln!(
            "λ = {:.3}: tip ({:.5}, {:.5}) exact ({:.5}, {:.5})",
            level.lambda, tip[0], tip[2], exact[0], exact[1]
        );
        worst = worst.max(e);
    }
    assert!(worst < 1e-3, "{worst:e}");
}
