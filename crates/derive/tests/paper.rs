//! The paper's experiment built in code (docs/math.md §7): invariants of the derivation that hold
//! whatever the paper's numbers turn out to be.

use nurbspring_derive::paper::paper_constants;
use nurbspring_derive::paper::{greville_net, reproduce};
use nurbspring_derive::{Config, FitDofs, FitOptions, InitialConditions, TimeSettings, derive_msm};
use nurbspring_dnurbs::{Constraints, DnurbsOptions, Loads, Material, RestShape};
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_msm::{Constants, LatticeOptions};
use nurbspring_sim::IntegratorKind;

fn paper_config() -> Config {
    let ku = KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap();
    let kv = KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap();
    let px = [0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.];
    let py = [0., 0.83, 2.5, 4.16, 5.];
    let pts: Vec<[f64; 3]> = px
        .iter()
        .flat_map(|&x| py.iter().map(move |&y| [x, y, 2.0]))
        .collect();
    let surface = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 35]).unwrap();
    Config {
        method: nurbspring_derive::Method::Paper,
        geometry: nurbspring_dnurbs::Geometry::Surface(surface),
        material: Material {
            mu: 25.0,
            beta11: 0.01,
            beta22: 0.01,
            ..Material::default()
        },
        loads: Loads::default(),
        constraints: Constraints {
            fixed_rings: 2,
            ..Constraints::default()
        },
        dnurbs: DnurbsOptions::default(),
        lattice: LatticeOptions {
            constants: paper_constants(),
            mass: 0.005,
            ..LatticeOptions::default()
        },
        initial: InitialConditions {
            velocities: vec![[0.0, 0.0, -0.2]],
            ..InitialConditions::default()
        },
        time: TimeSettings {
            dt: 0.08,
            t_end: 4.0,
            dnurbs_integrator: IntegratorKind::TerzopoulosQin,
            msm_integrator: IntegratorKind::SymplecticEuler,
        },
        fit: FitOptions::default(),
        probes: vec![(0.5, 0.5)],
        given: Some((paper_constants(), 0.005)),
        node_damping: None,
    }
}

#[test]
fn derivation_invariants() {
    let config = paper_config();
    let (d, setup) = derive_msm(&config, None, &mut |_, _| {}).unwrap();
    // 5 × 3 lattice, 3 free nodes (the interior row), 45 × 45 K_S.
    let lattice = d.lattice().unwrap();
    assert_eq!(lattice.n_nodes(), 15);
    assert_eq!(lattice.fixed.iter().filter(|&&f| !f).count(), 3);
    let fit = d.paper_fit().unwrap();
    // The optimum is no worse than the paper's constants on the same reading.
    let given = d.given.as_ref().unwrap();
    // The given (paper's) constants' residuals, recomputed on each reading's fit problem.
    for (dofs, reported) in [
        (FitDofs::All, given.relative_residual_all_dofs),
        (FitDofs::Free, given.relative_residual_free_dofs),
    ] {
        let problem = setup.fit(dofs).unwrap();
        let k = paper_constants().values_of(problem.classes());
        assert_eq!(reported, Some(problem.relative_residual(&k).unwrap()));
    }
    assert!(fit.all_dofs.relative_residual <= given.relative_residual_all_dofs.unwrap() + 1e-12);
    assert!(fit.free_dofs.relative_residual <= given.relative_residual_free_dofs.unwrap() + 1e-12);
    assert!(fit.trust_region.max_relative_difference_to_closed_form < 1e-8);
    // … and is the largest relative difference of the trust region's constants to the closed
    // form's of the selected reading, recomputed.
    let recomputed = fit
        .classes
        .iter()
        .map(|&c| {
            let (a, b) = (
                fit.trust_region.result.constants.value(c),
                fit.selected.constants.value(c),
            );
            (a - b).abs() / b.abs()
        })
        .fold(0.0, f64::max);
    println!("max relative difference {recomputed:e}");
    assert_eq!(
        fit.trust_region.max_relative_difference_to_closed_form,
        recomputed
    );
    // The frequency table pairs the distinct non-zero frequencies by rank.
    assert!(!d.frequencies.is_empty());
    for row in &d.frequencies {
        assert!(row.dnurbs > 0.0 && row.msm > 0.0, "{row:?}");
    }
    // The flat lattice at rest has no out-of-plane stiffness: one zero frequency per free
    // node (its z), and the in-plane ones are not zero.
    let zeros = d.spectrum.msm.iter().filter(|&&w| w == 0.0).count();
    assert_eq!(zeros, 3, "{:?}", d.spectrum.msm);
    // M = S ⊗ I_3 with 35 distinct eigenvalues of S; they sum to trace(S) = trace(M)/3.
    let trace: f64 = setup.model().matrices().mass.diagonal().iter().sum();
    let sum: f64 = d.mass.eigenvalues.iter().sum();
    assert_eq!(d.mass.eigenvalues.len(), 35);
    assert!((3.0 * sum - trace).abs() < 1e-10 * trace);
    assert_eq!(d.mass.candidates.len(), 35);
    // The selected mass is the candidate with the smallest error.
    let best = d
        .mass
        .candidates
        .iter()
        .map(|c| c.rms)
        .fold(f64::INFINITY, f64::min);
    let chosen = d
        .mass
        .candidates
        .iter()
        .find(|c| c.m == d.mass.selected)
        .unwrap();
    assert_eq!(chosen.rms, best);
    // Displacement form: the central point does not move in x, y (the paper's remark).
    let c = &d.dnurbs_trajectory.probes[0];
    for p in c {
        assert!((p[0] - c[0][0]).abs() < 1e-12 && (p[1] - c[0][1]).abs() < 1e-12);
    }
    // It does move in z, and starts with the velocity Ω ṗ(0) < 0.
    assert!(c[1][2] < c[0][2]);
    // ω_max · Δt_crit = 2.
    assert!((d.derived.omega_max * d.derived.dt_critical - 2.0).abs() < 1e-12);
}

#[test]
fn greville_net_is_linear_parametrization() {
    let nurbspring_dnurbs::Geometry::Surface(surface) = paper_config().geometry else {
        unreachable!()
    };
    let s = greville_net(&surface).unwrap();
    for &(u, v) in &[(0.1, 0.2), (0.5, 0.5), (0.9, 0.7)] {
        let p = s.point(u, v).unwrap();
        assert!(
            (p[0] - 3.0 * u).abs() < 1e-13 && (p[1] - 5.0 * v).abs() < 1e-13 && p[2] == 2.0,
            "{p:?}"
        );
    }
}

#[test]
fn reproduction_reports_every_reading() {
    let (main, report) = reproduce(&paper_config(), &mut |_, _| {}).unwrap();
    // The verdicts of the two constants: graded on the closest of all readings.
    use nurbspring_derive::paper::{PARTLY, REPRODUCED, Verdict};
    use nurbspring_msm::{Class, SpringKind};
    for (symbol, class, paper) in [
        ("k_edge", Class::Spring(SpringKind::Structural), 2.7225),
        ("k_diag", Class::Spring(SpringKind::Shear), 0.8661),
    ] {
        let line = report
            .verdicts
            .iter()
            .find(|v| v.quantity == symbol)
            .unwrap();
        let closest = report
            .fits
            .iter()
            .map(|r| (r.result.constants.value(class) - paper).abs() / paper)
            .fold(f64::INFINITY, f64::min);
        let grade = if closest <= REPRODUCED {
            Verdict::Reproduced
        } else if closest <= PARTLY {
            Verdict::Partly
        } else {
            Verdict::NotReproduced
        };
        assert_eq!(line.verdict, grade, "{symbol}: closest {closest}");
        assert!(
            line.why.contains(&format!("({:.2}% off)", 100.0 * closest)),
            "{}",
            line.why
        );
    }
    // The eigenvalue of M nearest the paper's mass 0.005, by rank, in each listing.
    for (nearest, list) in report
        .mass_nearest
        .iter()
        .zip([&main.mass.eigenvalues, &main.mass.eigenvalues_free_dofs])
    {
        let (rank, value) = list
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - 0.005).abs().total_cmp(&(b.1 - 0.005).abs()))
            .unwrap();
        assert_eq!(
            (nearest.rank, nearest.value, nearest.count),
            (rank + 1, *value, list.len())
        );
    }
    assert_eq!(report.fits.len(), 12);
    assert_eq!(report.dynamics.len(), 20);
    // Only the default reading (printed net, p_rest = p(0)) also runs over the long horizon.
    use nurbspring_derive::paper::{ControlNet, LONG_HORIZON};
    let t_end = paper_config().time.t_end;
    for d in &report.dynamics {
        let default = d.net == ControlNet::Printed && d.rest_shape == RestShape::Initial;
        let long = d.t_end == LONG_HORIZON * t_end;
        assert!(long || d.t_end == t_end, "{}", d.t_end);
        assert!(
            !long || default,
            "{:?} {:?} over {}",
            d.net,
            d.rest_shape,
            d.t_end
        );
    }
    assert!(report.dynamics.iter().any(|d| d.t_end > t_end));
    assert!(report.verdicts.len() >= 6);
    for line in &report.verdicts {
        println!(
            "{}: {} | {} | {:?} | {}",
            line.quantity, line.paper, line.obtained, line.verdict, line.why
        );
    }
    for f in &report.fits {
        println!("{:?}", f);
    }
    for dline in &report.dynamics {
        println!("{:?}", dline);
    }
}

/// The mass scan's schedule scales the unit-mass uniform limit by √m: the same schedule as
/// the model built with that mass, for masses across the scan and beyond (plain steps, a few
/// substeps, Newmark), and the limit within Lanczos' tolerance of the direct one.
#[test]
fn the_scaled_uniform_limit_schedules_like_the_model_of_each_mass() {
    use nurbspring_msm::MsmModel;
    use nurbspring_sim::{Schedule, uniform_stability_limit};
    let config = paper_config();
    let setup = nurbspring_derive::Setup::new(&config).unwrap();
    let constants = paper_constants();
    for m in [1e-9, 1e-4, 0.005, 0.0123, 1.0, 50.0] {
        let (scaled, limit) = setup
            .schedule(&constants, m, IntegratorKind::SymplecticEuler, 0.08)
            .unwrap();
        let model = MsmModel::new(setup.lattice_with(&constants, m)).unwrap();
        let direct = uniform_stability_limit(&model).unwrap().unwrap();
        let (expected, _) = Schedule::below(IntegratorKind::SymplecticEuler, 0.08, direct);
        assert_eq!(scaled, expected, "m = {m}");
        if let Some(limit) = limit {
            let rel = (limit.dt_critical - direct.dt_critical).abs() / direct.dt_critical;
            assert!(
                rel < 1e-7,
                "m = {m}: {} vs {}",
                limit.dt_critical,
                direct.dt_critical
            );
            let rel = (limit.omega_max - direct.omega_max).abs() / direct.omega_max;
            assert!(
                rel < 1e-7,
                "m = {m}: {} vs {}",
                limit.omega_max,
                direct.omega_max
            );
        }
    }
    // Other constants on the same setup (after the paper's are cached): their own limit,
    // as a fresh setup computes it (stiffer springs: a smaller step).
    let stiffer = Constants::from_pairs(paper_constants().iter().map(|(c, k)| (c, 9.0 * k)));
    let cached = setup
        .schedule(&stiffer, 0.005, IntegratorKind::SymplecticEuler, 0.08)
        .unwrap();
    let fresh = nurbspring_derive::Setup::new(&config)
        .unwrap()
        .schedule(&stiffer, 0.005, IntegratorKind::SymplecticEuler, 0.08)
        .unwrap();
    assert_eq!(cached, fresh);
    let paper = setup
        .schedule(&constants, 0.005, IntegratorKind::SymplecticEuler, 0.08)
        .unwrap();
    let (a, b) = (paper.1.unwrap(), cached.1.unwrap());
    assert!(
        (b.omega_max / a.omega_max - 3.0).abs() < 1e-7,
        "{a:?} vs {b:?}"
    );
    // Implicit schemes run as they are, without a limit.
    let (implicit, limit) = setup
        .schedule(&constants, 0.005, IntegratorKind::Newmark, 0.08)
        .unwrap();
    assert_eq!(
        (implicit, limit),
        (Schedule::plain(IntegratorKind::Newmark), None)
    );
}

/// `greville_net` puts control point (i, j) at the Greville abscissae (ξ_i, η_j) mapped
/// affinely from the parameter domain onto the net's x-y bounding box, z kept: by hand on a
/// net over a domain that does not start at 0, `[1, 3] × [2, 5]`.
#[test]
fn greville_net_maps_the_abscissae_onto_the_bounding_box() {
    let ku = KnotVector::try_new(vec![1., 1., 1., 2., 3., 3., 3.], 2).unwrap();
    let kv = KnotVector::try_new(vec![2., 2., 5., 5.], 1).unwrap();
    // x in [−1, 4], y in [0.5, 2.5] (the extremes at scattered points).
    let pts: Vec<[f64; 3]> = (0..8)
        .map(|k| {
            let (i, j) = (k / 2, k % 2);
            let x = [-1.0, 1.0, 4.0, 2.0][i];
            let y = [0.5, 2.5][j] + 0.1 * (i % 2) as f64 * (1 - j) as f64;
            [x, y, 0.3 * k as f64]
        })
        .collect();
    let s = NurbsSurface::try_new(ku, kv, pts.clone(), vec![1.0; 8]).unwrap();
    let g = greville_net(&s).unwrap();
    // Greville abscissae: u (1, 1.5, 2.5, 3), v (2, 5).
    let xi = [1.0, 1.5, 2.5, 3.0];
    let eta = [2.0, 5.0];
    for (k, p) in g.control_points().iter().enumerate() {
        let (i, j) = (k / 2, k % 2);
        let x = -1.0 + 5.0 * (xi[i] - 1.0) / 2.0;
        let y = 0.5 + 2.0 * (eta[j] - 2.0) / 3.0;
        assert!(
            (p[0] - x).abs() < 1e-14 && (p[1] - y).abs() < 1e-14,
            "{k}: {p:?}"
        );
        assert_eq!(p[2], pts[k][2]);
    }
}

/// The "beyond" table's row of a derivation: its free masses, lowest frequencies and, for each
/// horizon, the central probe's relative RMS over the samples up to it, recomputed from the
/// two trajectories (RMS of the 3-D distance over the largest distance from the start).
#[test]
fn beyond_rows_recomputed_from_the_trajectories() {
    let config = paper_config();
    let (d, _) = derive_msm(&config, None, &mut |_, _| {}).unwrap();
    let table = nurbspring_derive::beyond::beyond(&config, &d).unwrap();
    assert_eq!(table.rows.len(), 2);
    let row = &table.rows[0];
    assert_eq!(row.free_mass, (d.mass.free_msm, d.mass.free_dnurbs));
    assert_eq!(
        row.omega1,
        (Some(d.frequencies[0].msm), d.frequencies[0].dnurbs)
    );
    assert_eq!(row.lattice, "5 x 3 nodes, 3 free");
    let (r, o) = (&d.dnurbs_trajectory, &d.msm_trajectory);
    for (k, &(h, rel)) in row.relative_rms.iter().enumerate() {
        assert_eq!(h, nurbspring_derive::beyond::HORIZONS[k]);
        let n = r.t.iter().filter(|&&t| t <= h + 1e-9).count();
        let dist = |s: usize, a: &[[f64; 3]], b: &[[f64; 3]]| {
            (0..3)
                .map(|x| (a[s][x] - b[s][x]).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let rms = ((0..n)
            .map(|s| dist(s, &r.probes[0], &o.probes[0]).powi(2))
            .sum::<f64>()
            / n as f64)
            .sqrt();
        let start = [r.probes[0][0]];
        let amplitude = (0..n)
            .map(|s| dist(0, &start, &r.probes[0][s..]))
            .fold(0.0, f64::max);
        assert!(
            (rel - rms / amplitude).abs() <= 1e-12 * rel,
            "{h}: {rel} vs {}",
            rms / amplitude
        );
    }
    // The horizons cut the run at different lengths.
    assert!(row.relative_rms[0].1 != row.relative_rms[1].1 || r.t.last().unwrap() <= &4.0);
    assert_eq!(table.rows[1].derivation, nurbspring_derive::Method::Modal);
}

/// With the mass given, the derivation still lists the eigenvalues of M when their dense
/// solve can take the net (here 35, as with the scan), and selects the given mass.
#[test]
fn a_given_mass_still_lists_the_eigenvalues() {
    let mut config = paper_config();
    config.fit.mass = nurbspring_derive::MassChoice::Fixed(0.004);
    let (d, _) = derive_msm(&config, None, &mut |_, _| {}).unwrap();
    assert_eq!(d.mass.selected, 0.004);
    assert_eq!(d.mass.eigenvalues.len(), 35);
    assert!(d.mass.candidates.is_empty());
}
