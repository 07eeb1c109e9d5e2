//! The geometrically nonlinear benchmarks tabulated by Sze, Liu and Lo (2004, Finite Elements
//! in Analysis and Design 40:1551), every tabulated load level within 1 %.

use nurbspring_dnurbs::{PathSettings, obstacle};

use crate::support::displacement;

/// Sze et al. Table 1 (§3.1, cantilever under end shear, 16 × 1 S4R): `P/P_max`, `−u_tip`,
/// `w_tip`.
const CANTILEVER: [(f64, f64, f64); 20] = [
    (0.05, 0.026, 0.663),
    (0.10, 0.103, 1.309),
    (0.15, 0.224, 1.922),
    (0.20, 0.381, 2.493),
    (0.25, 0.563, 3.015),
    (0.30, 0.763, 3.488),
    (0.35, 0.971, 3.912),
    (0.40, 1.184, 4.292),
    (0.45, 1.396, 4.631),
    (0.50, 1.604, 4.933),
    (0.55, 1.807, 5.202),
    (0.60, 2.002, 5.444),
    (0.65, 2.190, 5.660),
    (0.70, 2.370, 5.855),
    (0.75, 2.541, 6.031),
    (0.80, 2.705, 6.190),
    (0.85, 2.861, 6.335),
    (0.90, 3.010, 6.467),
    (0.95, 3.151, 6.588),
    (1.00, 3.286, 6.698),
];

/// §3.1: L = 10, b = 1, t = 0.1, E = 1.2e6, ν = 0, clamped at x = 0, end shear P_max = 4 spread
/// over the tip edge. Every level of the table within 1 % of the tip deflection w and of −u
/// (relative to w, the larger: −u is 0.026 at the first level).
#[test]
fn cantilever_under_end_shear_follows_the_sze_table() {
    let bench = obstacle::sze_cantilever(3, 16).unwrap();
    let model = &bench.model;
    let settings = PathSettings {
        levels: 20,
        ..PathSettings::default()
    };
    let path = model
        .equilibrium_path(&settings, &|| false, &mut |_| {})
        .unwrap();
    eprintln!(
        "Sze cantilever: {} increments, {} iterations",
        path.increments, path.iterations
    );
    let mut worst = 0.0_f64;
    for (level, &(load, u_ref, w_ref)) in path.levels.iter().zip(&CANTILEVER) {
        assert!((level.lambda - load).abs() < 1e-12);
        let d = displacement(model, 1.0, 0.5, &level.p);
        let (eu, ew) = ((-d[0] - u_ref).abs() / w_ref, (d[2] - w_ref).abs() / w_ref);
        eprintln!(
            "P/Pmax {load:.2}: -u {:.4} ({u_ref}), w {:.4} ({w_ref})",
            -d[0], d[2]
        );
        worst = worst.max(eu).max(ew);
    }
    eprintln!("worst relative difference {worst:.2e}");
    assert!(worst < 0.01, "{worst}");
}

/// Sze et al. Table 3 (§3.3, slit annular plate under a lifting line force, 10 × 80 S4R):
/// `P/P_max`, `w_A` (inner radius), `w_B` (outer radius) at the loaded edge of the slit.
const SLIT_ANNULAR: [(f64, f64, f64); 23] = [
    (0.025, 1.305, 1.789),
    (0.05, 2.455, 3.370),
    (0.075, 3.435, 4.720),
    (0.10, 4.277, 5.876),
    (0.125, 5.007, 6.872),
    (0.15, 5.649, 7.736),
    (0.20, 6.725, 9.160),
    (0.25, 7.602, 10.288),
    (0.30, 8.340, 11.213),
    (0.35, 8.974, 11.992),
    (0.40, 9.529, 12.661),
    (0.45, 10.023, 13.247),
    (0.50, 10.468, 13.768),
    (0.55, 10.876, 14.240),
    (0.60, 11.257, 14.674),
    (0.65, 11.620, 15.081),
    (0.70, 11.970, 15.469),
    (0.75, 12.310, 15.842),
    (0.80, 12.642, 16.202),
    (0.85, 12.966, 16.550),
    (0.90, 13.282, 16.886),
    (0.95, 13.590, 17.212),
    (1.00, 13.891, 17.528),
];

/// §3.3: R_i = 6, R_o = 10, t = 0.03, E = 21e6, ν = 0, clamped along one side of the slit, a
/// vertical line force of up to 0.8 per unit length along the other. Every tabulated level
/// within 1 % of w_A and w_B.
#[test]
fn slit_annular_plate_follows_the_sze_table() {
    let bench = obstacle::slit_annular_plate(3, (6, 48)).unwrap();
    let model = &bench.model;
    let settings = PathSettings {
        levels: 40,
        ..PathSettings::default()
    };
    let path = model
        .equilibrium_path(&settings, &|| false, &mut |_| {})
        .unwrap();
    eprintln!(
        "slit annular plate: {} increments, {} iterations",
        path.increments, path.iterations
    );
    let mut worst = 0.0_f64;
    for &(load, wa_ref, wb_ref) in &SLIT_ANNULAR {
        let level = path
            .levels
            .iter()
            .find(|l| (l.lambda - load).abs() < 1e-9)
            .unwrap();
        let (wa, wb) = (
            displacement(model, 0.0, 1.0, &level.p)[2],
            displacement(model, 1.0, 1.0, &level.p)[2],
        );
        let e = ((wa - wa_ref).abs() / wa_ref).max((wb - wb_ref).abs() / wb_ref);
        eprintln!("P/Pmax {load:.3}: w_A {wa:.4} ({wa_ref}), w_B {wb:.4} ({wb_ref}), {e:.2e}");
        worst = worst.max(e);
    }
    assert!(worst < 0.01, "{worst}");
}

/// Kratos Multiphysics 10.4.4 (IgaApplication's Shell3pElement, bench-peers/kratos) on the same
/// net: the hemisphere with an 18° hole under alternating radial forces (Sze et al. §3.4),
/// degree 4 on 8 × 8 spans, a quarter with symmetry ties: Sze's load `F` (each load point of the
/// quarter carries F/2), `u_A`, `−u_B`.
const HEMISPHERE_KRATOS_8: [(f64, f64, f64); 20] = [
    (20.0, 0.85125, 0.94550),
    (40.0, 1.49239, 1.81548),
    (60.0, 1.95768, 2.56446),
    (80.0, 2.30564, 3.20767),
    (100.0, 2.57567, 3.76650),
    (120.0, 2.79178, 4.25784),
    (140.0, 2.96891, 4.69411),
    (160.0, 3.11683, 5.08447),
    (180.0, 3.24223, 5.43593),
    (200.0, 3.34987, 5.75400),
    (220.0, 3.44323, 6.04312),
    (240.0, 3.52496, 6.30695),
    (260.0, 3.59709, 6.54855),
    (280.0, 3.66120, 6.77053),
    (300.0, 3.71855, 6.97511),
    (320.0, 3.77017, 7.16419),
    (340.0, 3.81687, 7.33944),
    (360.0, 3.85933, 7.50230),
    (380.0, 3.89811, 7.65400),
    (400.0, 3.93369, 7.79566),
];

/// §3.4 on the net and the Gauss rule of the Kratos run above (the same discrete problem, solved
/// independently): every level within 1e-5 of Kratos' displacements, the rounding of its five
/// decimals (measured at most 2e-6). On 16 × 16 spans both give u_A = 4.0667, −u_B = 8.1354 at
/// the full load (docs/shell.md).
#[test]
fn hemisphere_under_alternating_forces_matches_kratos() {
    // Kratos integrates with (p + 1)² Gauss points an element; the automatic rule (8² here, the
    // rational integrands to 1e-10) differs from it by up to 2.5e-4 at the full load.
    let bench = obstacle::hemisphere(4, 8, 200.0)
        .unwrap()
        .with_options(nurbspring_dnurbs::DnurbsOptions {
            quadrature_points: Some(5),
            ..Default::default()
        })
        .unwrap();
    let model = &bench.model;
    let settings = PathSettings {
        levels: 20,
        ..PathSettings::default()
    };
    let path = model
        .equilibrium_path(&settings, &|| false, &mut |_| {})
        .unwrap();
    let mut worst = 0.0_f64;
    for (level, &(force, ua_ref, ub_ref)) in path.levels.iter().zip(&HEMISPHERE_KRATOS_8) {
        assert!((level.lambda * 400.0 - force).abs() < 1e-9 * force);
        let ua = displacement(model, 0.0, 0.0, &level.p)[0];
        let ub = -displacement(model, 0.0, 1.0, &level.p)[1];
        let e = ((ua - ua_ref).abs() / ua_ref).max((ub - ub_ref).abs() / ub_ref);
        eprintln!("F {force}: u_A {ua:.5} ({ua_ref}), -u_B {ub:.5} ({ub_ref}), {e:.2e}");
        worst = worst.max(e);
    }
    assert!(worst < 1e-5, "{worst:e}");
}
