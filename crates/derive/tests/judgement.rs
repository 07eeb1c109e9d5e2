//! The numbers every derivation reports about itself (docs/math.md §8.6–8.7), recomputed
//! outside the pipeline: mass totals (the D-NURBS's by the partition of unity), the frequency
//! table against the eigenvalues of the lattice's own tangent stiffness and of the D-NURBS's
//! `modes`, the validation's horizon and RMS from the two trajectories, the warnings against
//! their thresholds, and the excitation fit's calibration, step limits and modal shares.

use nurbspring_derive::{
    Config, Derivation, DnurbsModes, FitDofs, FitOptions, InitialConditions, MassScan, Method,
    PERIODS, Setup, TimeSettings, WARN_FREQUENCY, WARN_MASS_FACTOR, WARN_RELATIVE_RMS, derive,
    derive_msm,
};
use nurbspring_dnurbs::{Constraints, DnurbsOptions, Geometry, Integration, Loads, Material};
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_linalg::generalized_symmetric_eigen;
use nurbspring_msm::{Class, Constants, LatticeOptions, LinearKind, MsmModel, ParameterGrid};
use nurbspring_sim::{DynamicModel, IntegratorKind};

/// A wavy bicubic sheet over `[0, 2] × [0, 1.5]` (parameter domain the unit square), 6 × 5
/// control points, the outer ring fixed, pushed down at 0.2.
fn config(method: Method) -> Config {
    // The linear derivations fit every element class (unit constants to start from), the
    // paper's the spring classes.
    let constants = if method == Method::Paper {
        nurbspring_derive::paper::paper_constants()
    } else {
        Constants::from_pairs(
            Class::linear(&LinearKind::ALL)
                .into_iter()
                .map(|c| (c, 1.0)),
        )
    };
    let ku = KnotVector::clamped_uniform(3, 3).unwrap();
    let kv = KnotVector::clamped_uniform(3, 2).unwrap();
    let (gu, gv) = (ku.greville(), kv.greville());
    let pts = gu
        .iter()
        .flat_map(|&u| {
            gv.iter()
                .map(move |&v| [2.0 * u, 1.5 * v, 0.1 * (3.0 * u).sin() * (2.0 * v).cos()])
        })
        .collect();
    let surface = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 30]).unwrap();
    Config {
        method,
        geometry: Geometry::Surface(surface),
        material: Material {
            mu: 2.0,
            alpha11: 1.0,
            alpha22: 1.0,
            beta11: 0.01,
            beta22: 0.01,
            ..Material::default()
        },
        loads: Loads::default(),
        constraints: Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        dnurbs: DnurbsOptions::default(),
        lattice: LatticeOptions {
            grid: ParameterGrid::Uniform {
                nodes_u: 7,
                nodes_v: 6,
            },
            constants,
            ..LatticeOptions::default()
        },
        initial: InitialConditions {
            velocities: vec![[0.0, 0.0, -0.2]],
            ..InitialConditions::default()
        },
        time: TimeSettings {
            dt: 0.01,
            t_end: 0.5,
            dnurbs_integrator: IntegratorKind::Newmark,
            msm_integrator: IntegratorKind::SymplecticEuler,
        },
        fit: FitOptions::default(),
        probes: vec![(0.5, 0.5)],
        given: None,
        node_damping: None,
    }
}

/// Distinct values of a list in which each appears three times (x, y, z), ascending.
fn distinct_of_triples(mut values: Vec<f64>) -> Vec<f64> {
    values.sort_by(f64::total_cmp);
    values.iter().step_by(3).copied().collect()
}

/// The distinct non-zero values, ascending (a spring lattice's modes are not triplets).
fn distinct_non_zero(mut values: Vec<f64>) -> Vec<f64> {
    values.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::new();
    for w in values.into_iter().filter(|&w| w > 1e-6) {
        if out.last().is_none_or(|&l| w - l > 1e-9 * w) {
            out.push(w);
        }
    }
    out
}

/// The lattice's angular frequencies from its own tangent stiffness and masses.
fn lattice_frequencies(d: &Derivation) -> Vec<f64> {
    let model = MsmModel::new(d.lattice().cloned().unwrap()).unwrap();
    let q0 = model.initial_positions().to_vec();
    let k = model.tangent_stiffness(&q0).to_dense();
    let m = model.mass().to_sparse().to_dense();
    let e = generalized_symmetric_eigen(&k, &m).unwrap();
    let omega = e.values.iter().map(|l| l.max(0.0).sqrt()).collect();
    if d.method() == Method::Paper {
        distinct_non_zero(omega)
    } else {
        distinct_of_triples(omega)
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// The linear derivations give the fixed nodes the mass of their dual cell, `μ τ_u τ_v`
/// (dual spacings of the node parameters, half-cells at the ends), times the area element
/// `|c_u × c_v|` (central differences here) under area integration.
fn check_fixed_node_masses(d: &Derivation, config: &Config) {
    let lattice = d.lattice().unwrap();
    let params = lattice.params.as_ref().unwrap();
    let (n_u, n_v) = lattice.grid.unwrap();
    let dual = |t: &[f64], i: usize| {
        let left = if i > 0 { t[i] - t[i - 1] } else { 0.0 };
        let right = if i + 1 < t.len() {
            t[i + 1] - t[i]
        } else {
            0.0
        };
        0.5 * (left + right)
    };
    let us: Vec<f64> = (0..n_u).map(|i| params[i * n_v].0).collect();
    let vs: Vec<f64> = (0..n_v).map(|j| params[j].1).collect();
    let Geometry::Surface(s) = &config.geometry else {
        unreachable!()
    };
    let mut checked = 0;
    for a in (0..lattice.n_nodes()).filter(|&a| lattice.fixed[a]) {
        let (i, j) = (a / n_v, a % n_v);
        let (u, v) = params[a];
        let area = if config.dnurbs.integration == Integration::Area {
            let h = 1e-6;
            let point = |u: f64, v: f64| s.point(u.clamp(0.0, 1.0), v.clamp(0.0, 1.0)).unwrap();
            let diff = |p: [f64; 3], q: [f64; 3], d: f64| [0, 1, 2].map(|x| (p[x] - q[x]) / d);
            let (u0, u1, v0, v1) = (
                (u - h).max(0.0),
                (u + h).min(1.0),
                (v - h).max(0.0),
                (v + h).min(1.0),
            );
            let su = diff(point(u1, v), point(u0, v), u1 - u0);
            let sv = diff(point(u, v1), point(u, v0), v1 - v0);
            let c = [
                su[1] * sv[2] - su[2] * sv[1],
                su[2] * sv[0] - su[0] * sv[2],
                su[0] * sv[1] - su[1] * sv[0],
            ];
            (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
        } else {
            1.0
        };
        let expected = config.material.mu * dual(&us, i) * dual(&vs, j) * area;
        // Central differences (h = 10⁻⁶, one-sided at the edges) under area integration;
        // round-off of a three-factor product otherwise.
        let tolerance = if config.dnurbs.integration == Integration::Area {
            1e-5
        } else {
            1e-14
        };
        assert!(
            close(lattice.masses[a], expected, tolerance),
            "node {a}: {} vs {expected}",
            lattice.masses[a]
        );
        checked += 1;
    }
    assert!(checked > 0);
}

fn check_judgement(d: &Derivation, setup: &Setup, config: &Config) {
    assert_eq!(
        config.method.is_linear(),
        !matches!(config.method, Method::Paper | Method::Springs)
    );
    assert_eq!(
        nurbspring_derive::FitMethod::ClosedForm.label(),
        "closed form"
    );
    assert_eq!(
        nurbspring_derive::FitMethod::TrustRegion.label(),
        "trust region"
    );
    // The probe is the lattice node nearest the asked parameter, reported at its own.
    let lattice = d.lattice().unwrap();
    let params = lattice.params.as_ref().unwrap();
    assert_eq!(d.probe_nodes, setup.probe_nodes());
    assert_eq!(d.probes, setup.probes());
    assert_eq!(d.probes[0], params[d.probe_nodes[0]]);
    assert_eq!(d.probe_nodes[0], lattice.node_nearest(0.5, 0.5));
    // Masses. Σ_ij M_ij over one component is ∫∫ μ Σ_i N_i Σ_j N_j = μ × (parameter measure 1).
    let mass = &d.mass;
    assert!(
        close(mass.total_dnurbs, config.material.mu, 1e-12),
        "{}",
        mass.total_dnurbs
    );
    let lattice = d.lattice().unwrap();
    let total: f64 = lattice.masses.iter().sum();
    let free: f64 = (0..lattice.n_nodes())
        .filter(|&a| !lattice.fixed[a])
        .map(|a| lattice.masses[a])
        .sum();
    assert!(close(mass.total_msm, total, 1e-12) && close(mass.free_msm, free, 1e-12));
    let m = &setup.model().matrices().mass;
    let fixed = setup.model().fixed_points();
    let free_dnurbs: f64 = m
        .triplets()
        .filter(|&(i, _, _)| !fixed.contains(&(i / 3)))
        .map(|(_, _, v)| v)
        .sum::<f64>()
        / 3.0;
    assert!(close(mass.free_dnurbs, free_dnurbs, 1e-12));
    assert!(mass.free_dnurbs < mass.total_dnurbs);
    if config.method.is_linear() {
        check_fixed_node_masses(d, config);
        // The linear derivations report the mean free-node mass and how the masses came.
        let count = (0..lattice.n_nodes())
            .filter(|&a| !lattice.fixed[a])
            .count();
        assert!(close(mass.selected, free / count as f64, 1e-12));
        assert!(!mass.rule.is_empty());
    }

    // The frequency table: the D-NURBS's from its own modes, the lattice's from its own K_T.
    let dn_modes = setup.model().modes(3 * 8).unwrap();
    let dnurbs = distinct_of_triples(dn_modes.omega.clone());
    let msm = lattice_frequencies(d);
    assert_eq!(d.frequencies.len(), 8);
    for (i, row) in d.frequencies.iter().enumerate() {
        assert_eq!(row.mode, i + 1);
        assert!(
            close(row.dnurbs, dnurbs[i], 1e-8),
            "{i}: {} vs {}",
            row.dnurbs,
            dnurbs[i]
        );
        // The MSM mode matched to it (by MAC for linear elements, by rank for springs).
        if config.method == Method::Paper {
            assert_eq!(row.msm_mode, i + 1);
        }
        assert!(
            close(row.msm, msm[row.msm_mode - 1], 1e-8),
            "{i}: {} vs {}",
            row.msm,
            msm[row.msm_mode - 1]
        );
        assert!(close(
            row.relative_difference,
            row.msm / row.dnurbs - 1.0,
            1e-12
        ));
        // MAC only where the lattice's modes are isotropic triplets (linear elements).
        assert_eq!(row.mac.is_some(), config.method != Method::Paper);
        if let Some(mac) = row.mac {
            assert!((0.0..=1.0 + 1e-12).contains(&mac));
        }
    }

    // The stability figures: ω_max of the lattice itself, Δt_crit = 2/ω_max, and whether the
    // scene's step exceeds it.
    let p = &d.derived;
    let omega_max = *msm.last().unwrap();
    assert!(
        close(p.omega_max, omega_max, 1e-8),
        "{} vs {omega_max}",
        p.omega_max
    );
    assert!(close(p.dt_critical, 2.0 / omega_max, 1e-8));
    assert_eq!(p.dt_exceeds_explicit_limit, config.time.dt >= p.dt_critical);

    // The validation: the horizon covers PERIODS periods of the lowest mode, and the RMS is that
    // of the central probe's distance between the runs.
    let v = &d.derived.validation;
    let omega1 = dnurbs[0];
    let expected = config
        .time
        .t_end
        .max(PERIODS * 2.0 * std::f64::consts::PI / omega1);
    assert!(
        close(v.horizon, expected, 1e-9),
        "{} vs {expected}",
        v.horizon
    );
    assert!(close(
        DnurbsModes::new(setup, "test").unwrap().omega1(),
        omega1,
        1e-8
    ));
    let (r, o) = (&d.dnurbs_trajectory, &d.msm_trajectory);
    let n = r.t.len();
    assert_eq!(v.samples, n);
    let sum: f64 = (0..n)
        .map(|s| {
            (0..3)
                .map(|x| (r.probes[0][s][x] - o.probes[0][s][x]).powi(2))
                .sum::<f64>()
        })
        .sum();
    assert!(close(v.rms, (sum / n as f64).sqrt(), 1e-12));
    let amplitude = r.probes[0]
        .iter()
        .map(|p| {
            (0..3)
                .map(|x| (p[x] - r.probes[0][0][x]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max);
    assert!(close(v.dnurbs_amplitude, amplitude, 1e-12));
    assert!(close(v.relative_rms, v.rms / amplitude, 1e-12));
    // The z component alone: RMS of the z difference over the largest |z − z(0)|.
    let z_rms = ((0..n)
        .map(|s| (r.probes[0][s][2] - o.probes[0][s][2]).powi(2))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    let z_amplitude = r.probes[0]
        .iter()
        .map(|p| (p[2] - r.probes[0][0][2]).abs())
        .fold(0.0, f64::max);
    assert!(close(v.relative_rms_z, z_rms / z_amplitude, 1e-12));
    // Both runs start at the probe node's rest position (undisplaced scenes) or at the same
    // displaced point (the nodes start at Ω p(0)).
    let rest = if config.initial.displacement == [0.0; 3] {
        lattice.positions[d.probe_nodes[0]]
    } else {
        r.probes[0][0]
    };
    for traj in [r, o] {
        for x in 0..3 {
            assert!(
                (traj.probes[0][0][x] - rest[x]).abs() < 1e-12,
                "{:?} vs {rest:?}",
                traj.probes[0][0]
            );
        }
    }

    // The warnings, each present exactly when its threshold is crossed, with its numbers.
    let has = |text: &str| d.warnings.iter().any(|w| w.contains(text));
    assert_eq!(
        has("relative RMS against the D-NURBS"),
        v.relative_rms > WARN_RELATIVE_RMS,
        "{:?}",
        d.warnings
    );
    if v.relative_rms > WARN_RELATIVE_RMS {
        assert!(
            has(&format!("{:.1}%", 100.0 * v.relative_rms)),
            "{:?}",
            d.warnings
        );
    }
    let first = &d.frequencies[0];
    assert_eq!(
        has("the lowest frequency is off"),
        first.relative_difference.abs() > WARN_FREQUENCY
    );
    let ratio = mass.free_msm / mass.free_dnurbs;
    assert_eq!(
        has("the free nodes carry"),
        !(1.0 / WARN_MASS_FACTOR..=WARN_MASS_FACTOR).contains(&ratio)
    );
    assert_eq!(
        has("under the second excitation"),
        d.second_excitation.relative_rms > 2.0 * WARN_RELATIVE_RMS
    );
}

#[test]
fn the_modal_derivation_reports_its_own_numbers() {
    let config = config(Method::Modal);
    let (d, setup) = derive(&config, None, &mut |_, _| {}).unwrap();
    check_judgement(&d, &setup, &config);
    // The modal fit calibrates the lowest frequency.
    assert!(d.frequencies[0].relative_difference.abs() < 1e-8);
    // It fits the classes with an element acting on a free node, no other.
    let lattice = d.lattice().unwrap();
    let acting: Vec<Class> = Class::linear(&LinearKind::ALL)
        .into_iter()
        .filter(|&c| {
            lattice.elements.iter().any(|e| {
                Class::Linear(e.kind, e.region) == c
                    && e.weight > 0.0
                    && e.nodes
                        .iter()
                        .zip(&e.coefficients)
                        .any(|(&a, &coefficient)| !lattice.fixed[a] && coefficient != 0.0)
            })
        })
        .collect();
    let nurbspring_derive::FitDetail::Modal(report) = &d.fit else {
        panic!("a modal report expected");
    };
    assert_eq!(report.classes, acting);
}

/// The paper's rule on the same sheet: a lattice far too light, so the mass warning must be
/// there, with the ratio.
#[test]
fn the_paper_derivation_reports_its_own_numbers() {
    let mut config = config(Method::Paper);
    config.lattice.grid = ParameterGrid::Greville;
    // Bending springs too (their unconstrained constant comes out negative here).
    config
        .lattice
        .constants
        .set(Class::Spring(nurbspring_msm::SpringKind::Bend), 1.0);
    let (d, setup) = derive_msm(&config, None, &mut |_, _| {}).unwrap();
    let ratio = d.mass.free_msm / d.mass.free_dnurbs;
    assert!(ratio < 1.0 / WARN_MASS_FACTOR, "{ratio}");
    assert!(
        d.warnings
            .iter()
            .any(|w| w.contains(&format!("({ratio:.3}×)"))),
        "{:?}",
        d.warnings
    );
    // The paper's lattice has springs only: at rest the frequency table is of K_T too.
    check_judgement(&d, &setup, &config);
    // A spring cannot have a negative constant: the derived constants are the unconstrained
    // optimum of the selected dofs when it has none, the k ≥ 0 one otherwise, and each class
    // held at 0 is named.
    let fit = d.paper_fit().unwrap();
    let (unconstrained, nonnegative) = match config.fit.dofs {
        FitDofs::All => (&fit.all_dofs, &fit.all_dofs_nonnegative),
        FitDofs::Free => (&fit.free_dofs, &fit.free_dofs_nonnegative),
    };
    let negative: Vec<_> = fit
        .classes
        .iter()
        .filter(|&&c| unconstrained.constants.value(c) < 0.0)
        .collect();
    // With bending springs the unconstrained optimum on this sheet has a negative class (k_bend):
    // the rule is exercised.
    assert!(!negative.is_empty());
    let expected = if negative.is_empty() {
        unconstrained
    } else {
        nonnegative
    };
    for &c in &fit.classes {
        assert_eq!(
            d.derived.constants.value(c),
            expected.constants.value(c),
            "{c:?}"
        );
        assert!(d.derived.constants.value(c) >= 0.0);
    }
    // The scan's eigenvalues of the free block of M: distinct values of M_ff = S_ff ⊗ I₃.
    let free_dofs = setup.model().dof_map().free().to_vec();
    let m_ff = setup
        .model()
        .matrices()
        .mass
        .submatrix(&free_dofs, &free_dofs)
        .to_dense();
    let identity = nurbspring_linalg::DenseMatrix::from_fn(m_ff.nrows(), m_ff.nrows(), |i, j| {
        if i == j { 1.0 } else { 0.0 }
    });
    let e = generalized_symmetric_eigen(&m_ff, &identity).unwrap();
    let expected = distinct_of_triples(e.values.clone());
    assert_eq!(d.mass.eigenvalues_free_dofs.len(), expected.len());
    for (a, b) in d.mass.eigenvalues_free_dofs.iter().zip(&expected) {
        assert!(close(*a, *b, 1e-10), "{a} vs {b}");
    }
    assert!(d.mass.rule.contains("eigenvalue"), "{}", d.mass.rule);
    // The selected mass at an end of the scan is a warning; a scan of one candidate is not
    // a range.
    let candidates = &d.mass.candidates;
    let at_edge =
        d.mass.selected == candidates[0].m || d.mass.selected == candidates.last().unwrap().m;
    assert_eq!(
        d.warnings
            .iter()
            .any(|w| w.contains("at the edge of the scan")),
        at_edge
    );
    let mut one = config.clone();
    one.fit.max_candidates = 1;
    let (f, _) = derive_msm(&one, None, &mut |_, _| {}).unwrap();
    assert_eq!(f.mass.candidates.len(), 1);
    assert_eq!(f.mass.selected, f.mass.candidates[0].m);
    assert!(
        !f.warnings
            .iter()
            .any(|w| w.contains("at the edge of the scan")),
        "{:?}",
        f.warnings
    );
    // The pruned scan (the default) selects what the complete scan selects: a candidate it
    // stopped had, over its whole run, an RMS above the best, and above its reported bound.
    assert_eq!(config.fit.scan, MassScan::Pruned);
    let mut complete = config.clone();
    complete.fit.scan = MassScan::Complete;
    let (c, _) = derive_msm(&complete, None, &mut |_, _| {}).unwrap();
    assert_eq!(c.mass.selected, d.mass.selected);
    let best = c
        .mass
        .candidates
        .iter()
        .map(|c| c.rms)
        .fold(f64::INFINITY, f64::min);
    let mut pruned = 0;
    for (p, w) in d.mass.candidates.iter().zip(&c.mass.candidates) {
        assert_eq!(p.m, w.m);
        assert!(w.pruned.is_none() && w.rms.is_finite());
        match p.pruned.map(|r| (r.at, r.rms_at_least)) {
            Some((t, bound)) => {
                pruned += 1;
                assert!(!p.rms.is_finite() && t < config.time.t_end, "{p:?}");
                assert!(
                    bound > best && bound <= w.rms * (1.0 + 1e-12),
                    "{p:?} {w:?}"
                );
            }
            None => assert_eq!(p.rms, w.rms, "{p:?} {w:?}"),
        }
    }
    // Candidates after the first batch whose RMS is well above the best are pruned.
    let above = c.mass.candidates[nurbspring_derive::SCAN_BATCH..]
        .iter()
        .filter(|w| w.rms > 1.01 * best)
        .count();
    assert!(above > 0 && pruned >= above, "{pruned} of {above}");
    // The mass scan reports its progress once per candidate, in order.
    let mut calls = Vec::new();
    derive_msm(&config, None, &mut |k, n| calls.push((k, n))).unwrap();
    let n = d.mass.candidates.len();
    assert_eq!(calls, (1..=n).map(|k| (k, n)).collect::<Vec<_>>());
}

/// The excitation fit: after its calibration the lattice's lowest frequency is the D-NURBS's;
/// its step limits are `2/ω_max` of the modal fit's lattice and of its own; the modes it
/// weights are the most excited, with shares of the modal amplitudes of a free oscillation,
/// `a² = |φᵀM u₀ − φᵀf/λ|² + |φᵀM v₀|²/ω²`, summed over x, y, z, over all modes.
#[test]
fn the_excitation_derivation_reports_its_own_numbers() {
    check_excitation(&config(Method::Excitation));
    // Displaced and loaded as well: the amplitudes then combine `φᵀM u₀` and `φᵀf/λ`.
    let mut displaced = config(Method::Excitation);
    displaced.initial.displacement = [0.0, 0.0, 0.05];
    displaced.loads.gravity = [0.0, 0.0, -1.0];
    check_excitation(&displaced);
}

fn check_excitation(config: &Config) {
    let (d, setup) = derive(config, None, &mut |_, _| {}).unwrap();
    check_judgement(&d, &setup, config);
    assert!(d.frequencies[0].relative_difference.abs() < 1e-8);
    let nurbspring_derive::FitDetail::Excitation(report) = &d.fit else {
        panic!("an excitation report expected");
    };
    assert!(report.residual.1 <= report.residual.0);
    // The classes refined are those the modal fit kept non-zero, in class order.
    let kept: Vec<Class> = Class::linear(&LinearKind::ALL)
        .into_iter()
        .filter(|&c| report.modal_constants.value(c) > 0.0)
        .collect();
    assert_eq!(report.classes, kept);
    let omega_max = *lattice_frequencies(&d).last().unwrap();
    assert!(
        close(report.dt_critical.1, 2.0 / omega_max, 1e-6),
        "{} vs {}",
        report.dt_critical.1,
        2.0 / omega_max
    );

    let modes = DnurbsModes::new(&setup, "test").unwrap();
    let (sys, basis) = (&modes.system, &modes.basis);
    let apply = |v: &[[f64; 3]], x: usize| {
        let col: Vec<f64> = v.iter().map(|p| p[x]).collect();
        let mut y = vec![0.0; col.len()];
        sys.mass.mul_vec(&col, &mut y);
        y
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut amplitudes: Vec<(usize, f64)> = (0..basis.len())
        .filter(|&i| basis.omega[i] > 0.0)
        .map(|i| {
            let phi = basis.mode(i);
            let a2 = (0..3)
                .map(|x| {
                    let load: Vec<f64> = sys.load.iter().map(|f| f[x]).collect();
                    let e0 = dot(&phi, &apply(&sys.displacement, x))
                        - dot(&phi, &load) / basis.lambda[i];
                    let e1 = dot(&phi, &apply(&sys.velocity, x)) / basis.omega[i];
                    e0 * e0 + e1 * e1
                })
                .sum::<f64>();
            (i + 1, a2)
        })
        .collect();
    let total: f64 = amplitudes.iter().map(|a| a.1).sum();
    amplitudes.sort_by(|a, b| b.1.total_cmp(&a.1));
    assert_eq!(report.modes.len(), 8);
    for ((mode, share), (i, a2)) in report.modes.iter().zip(&amplitudes) {
        assert_eq!(mode, i);
        assert!(
            close(*share, a2 / total, 1e-9),
            "mode {mode}: {share} vs {}",
            a2 / total
        );
    }
    // The reported final residual is the objective at the final constants, recomputed here
    // (docs/math.md §8.4): for each weighted mode (ω, its shape at the free nodes Ω_ff φ, its
    // share) the MSM mode of best MAC among the lowest 2·8 of `L x = ω² m x` before the
    // calibration (masses / mass_scale), the weighted log ratio of the frequencies and the
    // difference of the normalized shapes.
    let lattice = d.lattice().unwrap();
    let free_nodes: Vec<usize> = (0..lattice.n_nodes())
        .filter(|&a| !lattice.fixed[a])
        .collect();
    let params: Vec<(f64, f64)> = free_nodes
        .iter()
        .map(|&a| lattice.params.as_ref().unwrap()[a])
        .collect();
    let omega = nurbspring_derive::Omega::new(&config.geometry, &params, false).unwrap();
    let cps: Vec<usize> = sys.free.iter().map(|&k| 3 * k).collect();
    let rows: Vec<usize> = (0..params.len()).map(|a| 3 * a).collect();
    let omega_ff = omega.matrix().submatrix(&rows, &cps).to_dense();
    // The x block of a lattice's K_T on the free nodes (every class acts alike on x, y, z).
    let scalar_stiffness = |lattice: &nurbspring_msm::SpringLattice| {
        let model = MsmModel::new(lattice.clone()).unwrap();
        let k_full = model
            .tangent_stiffness(model.initial_positions())
            .to_dense();
        let nf = free_nodes.len();
        nurbspring_linalg::DenseMatrix::from_fn(nf, nf, |a, b| k_full[(3 * a, 3 * b)])
    };
    let mac = nurbspring_derive::mac;
    let norm = |x: &[f64]| dot(x, x).sqrt();
    // The class scales of a lattice against the modal fit: its classes' mean constants over
    // the modal fit's (every element of a class carries the same scale).
    let class_mean = |lattice: &nurbspring_msm::SpringLattice, c: Class| {
        let k: Vec<f64> = lattice
            .elements
            .iter()
            .filter(|e| e.class() == c)
            .map(|e| e.k)
            .collect();
        k.iter().sum::<f64>() / k.len() as f64
    };
    let log_scales = |lattice: &nurbspring_msm::SpringLattice| -> Vec<f64> {
        report
            .classes
            .iter()
            .map(|&c| (class_mean(lattice, c) / report.modal_constants.value(c)).ln())
            .collect()
    };
    let objective =
        |l: &nurbspring_linalg::DenseMatrix, masses: &[f64], log_scales: &[f64]| {
            let nf = masses.len();
            let m = nurbspring_linalg::DenseMatrix::from_fn(nf, nf, |a, b| {
                if a == b { masses[a] } else { 0.0 }
            });
            let e = generalized_symmetric_eigen(l, &m).unwrap();
            let count = 16.min(nf);
            let mut residual = Vec::new();
            for &(mode, share) in &report.modes {
                let phi = basis.mode(mode - 1);
                let shape: Vec<f64> = (0..omega_ff.nrows())
                    .map(|a| (0..phi.len()).map(|k| omega_ff[(a, k)] * phi[k]).sum())
                    .collect();
                let best = (0..count)
                    .max_by(|&i, &j| {
                        mac(&shape, &e.vectors.column(i))
                            .total_cmp(&mac(&shape, &e.vectors.column(j)))
                    })
                    .unwrap();
                let psi = e.vectors.column(best);
                let weight = share.sqrt();
                let w = e.values[best].max(0.0).sqrt();
                residual.push(weight * (w.max(f64::MIN_POSITIVE) / basis.omega[mode - 1]).ln());
                let sign = if dot(&shape, &psi) < 0.0 { -1.0 } else { 1.0 };
                let (na, nb) = (norm(&shape), norm(&psi));
                for (a, b) in shape.iter().zip(&psi) {
                    residual.push(weight * (a / na - sign * b / nb));
                }
            }
            // The pull of each class scale towards the modal fit's.
            residual.extend(log_scales.iter().map(|t| 0.1 * t));
            norm(&residual)
        };
    let masses: Vec<f64> = free_nodes
        .iter()
        .map(|&a| lattice.masses[a] / report.mass_scale)
        .collect();
    let recomputed = objective(&scalar_stiffness(lattice), &masses, &log_scales(lattice));
    assert!(
        close(report.residual.1, recomputed, 1e-6),
        "reported {} vs recomputed {recomputed}",
        report.residual.1
    );
    // Levenberg–Marquardt stops early only where it can no longer descend: then no step of
    // 10⁻³ in any log class scale or in the log mass scale lowers the objective (beyond a
    // relative 10⁻⁶). Otherwise it has used all its 40 iterations.
    if report.iterations < 40 {
        let at = recomputed;
        let delta = 1e-3f64;
        for sign in [-1.0, 1.0] {
            let factor = (sign * delta).exp();
            for &c in &report.classes {
                let mut probe = lattice.clone();
                for e in probe.elements.iter_mut().filter(|e| e.class() == c) {
                    e.k *= factor;
                }
                let f = objective(&scalar_stiffness(&probe), &masses, &log_scales(&probe));
                assert!(f >= at * (1.0 - 1e-6), "{}: {f} below {at}", c.symbol());
            }
            let scaled: Vec<f64> = masses.iter().map(|m| factor * m).collect();
            let f = objective(&scalar_stiffness(lattice), &scaled, &log_scales(lattice));
            assert!(f >= at * (1.0 - 1e-6), "mass scale: {f} below {at}");
        }
    }
    // The start: the modal fit's constants and masses (the modal derivation's lattice), the
    // scales all 1.
    let mut modal_config = config.clone();
    modal_config.method = Method::Modal;
    let (modal, _) = derive(&modal_config, None, &mut |_, _| {}).unwrap();
    let modal_lattice = modal.lattice().unwrap();
    let start: Vec<f64> = free_nodes
        .iter()
        .map(|&a| modal_lattice.masses[a])
        .collect();
    let recomputed = objective(
        &scalar_stiffness(modal_lattice),
        &start,
        &vec![0.0; report.classes.len()],
    );
    assert!(
        close(report.residual.0, recomputed, 1e-9),
        "reported start {} vs recomputed {recomputed}",
        report.residual.0
    );
    // A warning for each class moved beyond 10³ either way of the modal fit's constant, and
    // one when the explicit step limit shrank more than ten times; no other.
    let has = |text: &str| d.warnings.iter().any(|w| w.contains(text));
    let mut expected = 0;
    for &c in &report.classes {
        let (k, k0) = (report.constants.value(c), report.modal_constants.value(c));
        let moved = k > 1e3 * k0 || k < k0 / 1e3;
        expected += usize::from(moved);
        assert_eq!(
            has(&format!("the excitation fit moved {} ", c.symbol())),
            moved,
            "{}: {k} from {k0}",
            c.symbol()
        );
    }
    let shrunk = report.dt_critical.1 < report.dt_critical.0 / 10.0;
    expected += usize::from(shrunk);
    assert_eq!(has("the excitation fit's explicit step limit"), shrunk);
    let overfit = d
        .warnings
        .iter()
        .filter(|w| w.contains("the excitation fit"))
        .count();
    assert_eq!(overfit, expected, "{:?}", d.warnings);
}

/// Under area integration the modal derivation's numbers hold the same way (the D-NURBS's total
/// mass is then `μ` times the surface's area, not checked here; the fixed nodes' dual cells
/// carry the area element).
#[test]
fn the_modal_derivation_under_area_integration() {
    let mut config = config(Method::Modal);
    config.dnurbs.integration = Integration::Area;
    // A skewed, strongly curved sheet: every component of c_u × c_v enters |c_u × c_v|.
    let Geometry::Surface(s) = &config.geometry else {
        unreachable!()
    };
    let pts = s
        .control_points()
        .iter()
        .map(|p| [p[0] + 0.3 * p[1], p[1] + 0.2 * p[0], 4.0 * p[2]])
        .collect();
    config.geometry = Geometry::Surface(s.with_control_points(pts).unwrap());
    let (d, _setup) = derive(&config, None, &mut |_, _| {}).unwrap();
    check_fixed_node_masses(&d, &config);
    assert!(d.frequencies[0].relative_difference.abs() < 1e-8);
}

/// The exact reduction onto a Greville lattice (as many free nodes as free control points):
/// its motion is the D-NURBS's at the nodes, its frequencies are the D-NURBS's, and its static response to gravity, `K_T⁻¹ f_T`, is the
/// D-NURBS's steady state seen at the free nodes.
#[test]
fn the_exact_reduction_reproduces_the_dnurbs_at_the_nodes() {
    let mut config = config(Method::Reduction);
    config.lattice.grid = ParameterGrid::Greville;
    config.loads.gravity = [0.0, 0.0, -1.0];
    let (d, setup) = derive(&config, None, &mut |_, _| {}).unwrap();
    // Started from the nodes' share of the D-NURBS's initial state (the scene's velocity), the
    // exact reduction follows the D-NURBS at the watched node to round-off.
    let v = &d.derived.validation;
    assert!(v.dnurbs_amplitude > 1e-3, "{}", v.dnurbs_amplitude);
    assert!(v.relative_rms < 1e-13, "{}", v.relative_rms);
    let r = d.reduction().expect("a reduction");
    let n = r.free.len();
    assert_eq!(n, 12);
    let e = generalized_symmetric_eigen(&r.stiffness, &r.mass).unwrap();
    let dnurbs = distinct_of_triples(setup.model().modes(3 * n).unwrap().omega);
    for i in 0..n {
        let w = e.values[i].sqrt();
        assert!(close(w, dnurbs[i], 1e-8), "{i}: {w} vs {}", dnurbs[i]);
    }
    // Static: K_T u = f_T per component, against the D-NURBS's steady state at the nodes.
    let p = setup.model().steady_state().unwrap();
    let Geometry::Surface(s) = setup.model().geometry() else {
        unreachable!()
    };
    let moved = s
        .with_control_points(p.chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
        .unwrap();
    for x in 0..3 {
        let f: Vec<f64> = r.loads.iter().map(|l| l[x]).collect();
        let u = nurbspring_linalg::solve_dense(&r.stiffness, &f).unwrap();
        for (i, &a) in r.free.iter().enumerate() {
            let (pu, pv) = r.params[a];
            let expected = moved.point(pu, pv).unwrap()[x] - r.positions[a][x];
            assert!(
                (u[i] - expected).abs() < 1e-9,
                "node {a}, {x}: {} vs {expected}",
                u[i]
            );
        }
    }
}

/// Under gravity alone the modal derivation's lattice sags like the D-NURBS: the nodes carry
/// `m g` (the validation's relative RMS stays under the warning threshold).
#[test]
fn the_modal_derivation_carries_gravity() {
    let mut config = config(Method::Modal);
    config.loads.gravity = [0.0, 0.0, -1.0];
    config.initial.velocities = Vec::new();
    let (d, _) = derive(&config, None, &mut |_, _| {}).unwrap();
    let v = &d.derived.validation;
    assert!(v.dnurbs_amplitude > 0.0);
    assert!(v.relative_rms < WARN_RELATIVE_RMS, "{}", v.relative_rms);
    // Gravity is carried by the masses: no other load is left to carry to the nodes.
    assert!(
        !d.warnings.iter().any(|w| w.contains("not carried")),
        "{:?}",
        d.warnings
    );
}

/// The reduction is exact when the free nodes are as many as the free control points (the
/// Greville lattice), the Guyan (static) one on fewer nodes, and refused on more.
#[test]
fn reductions_are_exact_guyan_or_refused_by_the_count_of_free_nodes() {
    let mut fewer = config(Method::Reduction);
    fewer.lattice.grid = ParameterGrid::Uniform {
        nodes_u: 4,
        nodes_v: 4,
    };
    let (d, _) = derive(&fewer, None, &mut |_, _| {}).unwrap();
    let r = d.reduction().unwrap();
    assert!(r.free.len() < 12 && r.guyan, "{} free nodes", r.free.len());
    let mut greville = config(Method::Reduction);
    greville.lattice.grid = ParameterGrid::Greville;
    let (d, _) = derive(&greville, None, &mut |_, _| {}).unwrap();
    assert!(!d.reduction().unwrap().guyan);
    assert!(derive(&config(Method::Reduction), None, &mut |_, _| {}).is_err());
}

/// A chain on a curve under area (arc-length) integration: its fixed end nodes carry
/// `μ τ_u |c′(u)|` (half-cells at the ends; |c′| by central differences).
#[test]
fn a_chain_under_arc_length_integration_has_its_dual_cell_masses() {
    use nurbspring_geom::NurbsCurve;
    let k = KnotVector::clamped_uniform(3, 4).unwrap();
    let g = k.greville();
    let pts: Vec<[f64; 3]> = g
        .iter()
        .map(|&u| [3.0 * u, 0.8 * u * u, 0.5 * (2.0 * u).sin()])
        .collect();
    let n = pts.len();
    let curve = NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap();
    let mut config = config(Method::Modal);
    config.geometry = Geometry::Curve(curve.clone());
    config.material = Material {
        mu: 2.0,
        alpha11: 1.0,
        beta11: 0.01,
        ..Material::default()
    };
    config.lattice.grid = ParameterGrid::Uniform {
        nodes_u: 9,
        nodes_v: 1,
    };
    config.lattice.constants = Constants::from_pairs(
        Class::linear(&LinearKind::CHAIN)
            .into_iter()
            .map(|c| (c, 1.0)),
    );
    config.dnurbs.integration = Integration::Area;
    let (d, _) = derive(&config, None, &mut |_, _| {}).unwrap();
    let lattice = d.lattice().unwrap();
    let h = 1e-6;
    for (a, u, tau) in [(0, 0.0f64, 0.0625), (8, 1.0, 0.0625)] {
        assert!(lattice.fixed[a]);
        let (u0, u1) = ((u - h).max(0.0), (u + h).min(1.0));
        let (p, q) = (curve.point(u1).unwrap(), curve.point(u0).unwrap());
        let speed = (0..3).map(|x| (p[x] - q[x]).powi(2)).sum::<f64>().sqrt() / (u1 - u0);
        let expected = 2.0 * tau * speed;
        assert!(
            close(lattice.masses[a], expected, 1e-5),
            "node {a}: {} vs {expected}",
            lattice.masses[a]
        );
    }
}

/// The scene's Δt against the derived lattice's explicit limit `2/ω_max`: below it at 0.01,
/// beyond it at 1.5 × the limit (the derived model itself does not depend on Δt).
#[test]
fn the_explicit_limit_is_judged_against_the_scenes_step() {
    let mut config = config(Method::Modal);
    let (d, _) = derive(&config, None, &mut |_, _| {}).unwrap();
    let limit = d.derived.dt_critical;
    assert!(config.time.dt < limit && !d.derived.dt_exceeds_explicit_limit);
    assert!(close(limit, 2.0 / d.derived.omega_max, 1e-15));
    config.time.dt = 1.5 * limit;
    config.time.t_end = 20.0 * config.time.dt;
    assert!(
        config.time.dt < 2.0,
        "a step beyond 2 s would not tell 2/ω from 2"
    );
    let (d, _) = derive(&config, None, &mut |_, _| {}).unwrap();
    assert!(close(d.derived.dt_critical, limit, 1e-12));
    assert!(d.derived.dt_exceeds_explicit_limit);
}

/// Four free control points in a row along u (a 6 × 3 net with its outer ring fixed) and four
/// free nodes in a row along v (a 3 × 6 grid): every node's row of Ω is a multiple of the same
/// vector, so `Ω K⁻¹ Ωᵀ` has rank one and the reduction is refused, naming the grid. The
/// material is soft (K⁻¹ large), so the null eigenvalues are far from 1 in absolute terms.
#[test]
fn a_reduction_whose_nodes_do_not_determine_the_surface_is_refused() {
    let mut config = config(Method::Reduction);
    let ku = KnotVector::clamped_uniform(3, 3).unwrap();
    let kv = KnotVector::clamped_uniform(2, 1).unwrap();
    let (gu, gv) = (ku.greville(), kv.greville());
    let pts = gu
        .iter()
        .flat_map(|&u| gv.iter().map(move |&v| [2.0 * u, 1.5 * v, 0.1 * u * v]))
        .collect();
    config.geometry = Geometry::Surface(NurbsSurface::try_new(ku, kv, pts, vec![1.0; 18]).unwrap());
    config.material = Material {
        mu: 1e-3,
        alpha11: 1e-4,
        alpha22: 1e-4,
        ..Material::default()
    };
    config.lattice.grid = ParameterGrid::Uniform {
        nodes_u: 3,
        nodes_v: 6,
    };
    let Err(e) = derive(&config, None, &mut |_, _| {}) else {
        panic!("a singular reduction must be refused");
    };
    let text = e.to_string();
    assert!(
        matches!(
            e,
            nurbspring_derive::DeriveError::InvalidInput {
                input: nurbspring_derive::Input::Grid,
                ..
            }
        ) && text.contains("the reduction is singular"),
        "{text}"
    );
    // The nodes named carry the null combination: at least two of them (no single node's
    // row of Ω is zero), all free.
    let named: Vec<usize> = text[text.find("nodes [").unwrap() + 7..]
        .split(']')
        .next()
        .unwrap()
        .split(", ")
        .map(|x| x.parse().unwrap())
        .collect();
    let setup = nurbspring_derive::Setup::new(&config).unwrap();
    assert!(named.len() >= 2, "{text}");
    assert!(named.iter().all(|&a| !setup.lattice().fixed[a]), "{text}");
}

/// The reduction's judgement of singularity is relative: a stiffer material (every stiffness
/// term × 10⁶, so `Ω K⁻¹ Ωᵀ` × 10⁻⁶) gives the same reduction with `K_T` × 10⁶ and the
/// frequencies × 10³.
#[test]
fn the_reduction_scales_with_the_material() {
    let mut config = config(Method::Reduction);
    config.lattice.grid = ParameterGrid::Greville;
    let (soft, _) = derive(&config, None, &mut |_, _| {}).unwrap();
    for a in [
        &mut config.material.alpha11,
        &mut config.material.alpha22,
        &mut config.material.beta11,
        &mut config.material.beta22,
    ] {
        *a *= 1e6;
    }
    let (stiff, _) = derive(&config, None, &mut |_, _| {}).unwrap();
    let (a, b) = (soft.reduction().unwrap(), stiff.reduction().unwrap());
    let n = a.free.len();
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (a.stiffness[(i, j)], b.stiffness[(i, j)]);
            assert!(
                (y - 1e6 * x).abs() < 1e-12 * 1e6 * a.stiffness[(i, i)].abs(),
                "{i} {j}: {y} vs {x}"
            );
        }
    }
    for (p, q) in soft.frequencies.iter().zip(&stiff.frequencies) {
        assert!(close(q.dnurbs, 1e3 * p.dnurbs, 1e-12) && close(q.msm, 1e3 * p.msm, 1e-12));
    }
}

/// A scene that neither moves nor loads the D-NURBS gives the excitation derivation nothing to
/// weight: refused, naming initial.velocity.
#[test]
fn the_excitation_derivation_refuses_a_scene_without_excitation() {
    let mut config = config(Method::Excitation);
    config.initial.velocities = Vec::new();
    let Err(e) = derive(&config, None, &mut |_, _| {}) else {
        panic!("a scene without excitation must be refused");
    };
    assert!(
        matches!(e, nurbspring_derive::DeriveError::NoExcitation),
        "{e}"
    );
}
