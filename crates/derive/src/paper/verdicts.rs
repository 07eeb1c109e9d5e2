//! The verdict on each of the paper's claims, built from the readings' data.

use super::*;

pub(super) fn grade(relative_difference: f64) -> Verdict {
    if relative_difference <= REPRODUCED {
        Verdict::Reproduced
    } else if relative_difference <= PARTLY {
        Verdict::Partly
    } else {
        Verdict::NotReproduced
    }
}

pub(super) fn stiffness_sentence(facts: &LatticeFacts) -> String {
    if facts.normal_stiffness_share < NO_NORMAL_STIFFNESS {
        "the lattice's linearized stiffness has no component along the surface normal, so only the in-plane blocks of K_D can be matched".to_string()
    } else {
        format!(
            "{:.2}% of the lattice's linearized stiffness acts along the surface normal",
            100.0 * facts.normal_stiffness_share
        )
    }
}

pub(super) fn constant_verdict(
    paper: f64,
    class: Class,
    fits: &[FitReading],
    facts: &LatticeFacts,
) -> VerdictLine {
    let obtained = fits
        .iter()
        .map(|r| format!("{:.4} ({})", r.result.constants.value(class), r.label()))
        .collect::<Vec<_>>()
        .join("; ");
    let best = fits.iter().min_by(|a, b| {
        (a.result.constants.value(class) - paper)
            .abs()
            .total_cmp(&(b.result.constants.value(class) - paper).abs())
    });
    let (verdict, why) = match best {
        Some(best) => {
            let k = best.result.constants.value(class);
            let rel = (k - paper).abs() / paper;
            (
                grade(rel),
                format!(
                    "closest: {k:.6} under {} ({:.2}% off). Relative residual of eq. (15) there: {:.6} at the optimum vs {:.6} at the paper's constants; {}",
                    best.label(),
                    100.0 * rel,
                    best.result.relative_residual,
                    best.residual_at_paper_values,
                    stiffness_sentence(facts)
                ),
            )
        }
        None => (Verdict::NotReproduced, "no reading was fitted".to_string()),
    };
    VerdictLine {
        quantity: class.symbol().to_string(),
        paper: format!("{paper}"),
        obtained,
        verdict,
        why,
    }
}

pub(super) fn mass_verdict(mass: &MassReport, nearest: &[NearestEigenvalue]) -> VerdictLine {
    let best = nearest
        .iter()
        .min_by(|a, b| a.relative_difference.total_cmp(&b.relative_difference));
    let scan_selected = mass.selected;
    let (verdict, why) = match best {
        Some(b) if b.relative_difference < MASS_MATCH => {
            let selected_too = (scan_selected - PAPER_M).abs() / PAPER_M < MASS_MATCH;
            (
                if selected_too {
                    Verdict::Reproduced
                } else {
                    Verdict::Partly
                },
                format!(
                    "{} has the eigenvalue {:.6} (rank {} of {}), {:.1}% from 0.005; the scan {} it (it selects m = {:.6})",
                    b.matrix.name(),
                    b.value,
                    b.rank,
                    b.count,
                    100.0 * b.relative_difference,
                    if selected_too {
                        "selects"
                    } else {
                        "does not select"
                    },
                    scan_selected
                ),
            )
        }
        Some(b) => (
            Verdict::NotReproduced,
            format!(
                "no eigenvalue of M is near 0.005: the nearest is {:.6} in {} ({:.1}% off); the scan selects m = {:.6}",
                b.value,
                b.matrix.name(),
                100.0 * b.relative_difference,
                scan_selected
            ),
        ),
        None => (
            Verdict::NotReproduced,
            "M has no non-null eigenvalue".to_string(),
        ),
    };
    VerdictLine {
        quantity: "m (an eigenvalue of M, chosen by the scan)".to_string(),
        paper: "0.005".to_string(),
        obtained: format!(
            "smallest eigenvalues {}; scan selects {:.6}",
            mass.eigenvalues
                .iter()
                .take(4)
                .map(|v| format!("{v:.5}"))
                .collect::<Vec<_>>()
                .join(", "),
            scan_selected
        ),
        verdict,
        why,
    }
}

pub(super) fn explicit_verdict(base: &Config, dynamics: &[DynamicsReading]) -> Option<VerdictLine> {
    let default_reading = |d: &&DynamicsReading| {
        d.parameters == Parameters::Paper
            && d.net == ControlNet::Printed
            && d.rest_shape == RestShape::Initial
    };
    let first = dynamics.iter().find(default_reading)?;
    let explicit = dynamics
        .iter()
        .filter(default_reading)
        .find(|d| d.integrator.is_explicit());
    let exceeds = base.time.dt >= first.dt_critical;
    let outcome = explicit.map(|e| match &e.msm_stopped {
        Some(s) => format!("{}: {}", e.integrator, s),
        None => format!("{} stays bounded", e.integrator),
    });
    let why = match (exceeds, explicit.and_then(|e| e.msm_stopped.as_ref())) {
        (true, Some(_)) => format!(
            "Δt = {} exceeds the explicit stability limit and the explicit run diverges, so it gives no Figure 3 at that step; an implicit one (Newmark) is used for the comparison",
            base.time.dt
        ),
        (true, None) => format!(
            "Δt = {} exceeds the explicit stability limit (the explicit run happened to stay bounded over the horizon)",
            base.time.dt
        ),
        (false, _) => "Δt is below the explicit stability limit".to_string(),
    };
    Some(VerdictLine {
        quantity: "explicit MSM run at the paper's Δt".to_string(),
        paper: format!("Δt = {} s with the FDM of ref. [8]", base.time.dt),
        obtained: format!(
            "Δt_critical = 2/ω_max = {:.5} s with k_edge = {PAPER_K_EDGE}, k_diag = {PAPER_K_DIAG}, m = {PAPER_M}{}",
            first.dt_critical,
            outcome.map(|o| format!("; {o}")).unwrap_or_default()
        ),
        verdict: if exceeds {
            Verdict::NotReproduced
        } else {
            Verdict::Reproduced
        },
        why,
    })
}

pub(super) fn figure3_verdict(
    base: &Config,
    parameters: Parameters,
    dynamics: &[DynamicsReading],
    lowest_dnurbs: f64,
    facts: &LatticeFacts,
) -> VerdictLine {
    let runs: Vec<&DynamicsReading> = dynamics
        .iter()
        .filter(|d| d.parameters == parameters && d.integrator == IntegratorKind::Newmark)
        .collect();
    let obtained = runs
        .iter()
        .map(|d| {
            format!(
                "rel. RMS {:.3} over {} s ({} net, rest {}; periods D-NURBS {} / MSM {}{})",
                d.relative_rms,
                d.t_end,
                d.net.name(),
                d.rest_shape.name(),
                fmt_period(d.dnurbs_period),
                fmt_period(d.msm_period),
                if d.msm_stopped.is_some() {
                    "; MSM run failed"
                } else {
                    ""
                }
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let long_t = LONG_HORIZON * base.time.t_end;
    let best = |long: bool| {
        runs.iter()
            .filter(|d| (d.t_end > base.time.t_end) == long)
            .map(|d| d.relative_rms)
            .filter(|x| x.is_finite())
            .fold(f64::INFINITY, f64::min)
    };
    let (short, long) = (best(false), best(true));
    let verdict = if short < AGREEMENT && long < AGREEMENT {
        Verdict::Reproduced
    } else if short < AGREEMENT {
        Verdict::Partly
    } else {
        Verdict::NotReproduced
    };
    let why = match verdict {
        Verdict::Reproduced => format!(
            "relative RMS {short:.3} over {} s and {long:.3} over {long_t} s (agreement below {AGREEMENT})",
            base.time.t_end
        ),
        Verdict::Partly => format!(
            "relative RMS {short:.3} over the paper's {} s, a fraction of the D-NURBS period, but {long:.3} over {long_t} s: the derived MSM linearized at rest has {} zero frequencies among its {} (directions with no linear restoring force; {}), while the lowest D-NURBS frequency is {lowest_dnurbs:.4} rad/s, so the two drift apart",
            base.time.t_end,
            facts.msm_zero_frequencies,
            facts.msm_frequencies,
            stiffness_sentence(facts)
        ),
        _ => format!(
            "no run with these parameters follows the D-NURBS (best relative RMS {short:.3} over {} s; infinite means the MSM run failed)",
            base.time.t_end
        ),
    };
    VerdictLine {
        quantity: format!(
            "Figure 3 agreement of the central node's z ({} parameters, Newmark)",
            parameters.name()
        ),
        paper: "suitable agreement over 4 s".to_string(),
        obtained,
        verdict,
        why,
    }
}

pub(super) fn drift_verdict(dynamics: &[DynamicsReading]) -> VerdictLine {
    let drift = |rest: RestShape, net: ControlNet| {
        dynamics
            .iter()
            .find(|d| d.rest_shape == rest && d.net == net)
            .map(|d| d.dnurbs_in_plane_drift)
            .unwrap_or(f64::NAN)
    };
    let readings = [
        (ControlNet::Printed, RestShape::Initial),
        (ControlNet::Printed, RestShape::Zero),
        (ControlNet::Greville, RestShape::Initial),
        (ControlNet::Greville, RestShape::Zero),
    ];
    let measured: Vec<(ControlNet, RestShape, f64)> = readings
        .iter()
        .map(|&(net, rest)| (net, rest, drift(rest, net)))
        .collect();
    let holds: Vec<String> = measured
        .iter()
        .filter(|m| m.2 < NO_DRIFT)
        .map(|m| format!("{} net with {}", m.0.name(), rest_formula(m.1)))
        .collect();
    let fails: Vec<String> = measured
        .iter()
        .filter(|m| m.2.is_nan() || m.2 >= NO_DRIFT)
        .map(|m| format!("{} net with {}", m.0.name(), rest_formula(m.1)))
        .collect();
    let (d_init, d_zero) = (measured[0].2, measured[1].2);
    VerdictLine {
        quantity: "x, y of the central node remain unchanged".to_string(),
        paper: "yes".to_string(),
        obtained: format!(
            "max in-plane drift {d_init:.3e} (printed net, p_rest = p(0)); {d_zero:.3e} (printed net, p_rest = 0); {:.3e} (Greville net, p_rest = 0)",
            measured[3].2
        ),
        verdict: if fails.is_empty() {
            Verdict::Reproduced
        } else if !holds.is_empty() {
            Verdict::Partly
        } else {
            Verdict::NotReproduced
        },
        why: format!(
            "no drift (below {NO_DRIFT:e}) on: {}; drift on: {}",
            if holds.is_empty() {
                "none".to_string()
            } else {
                holds.join(", ")
            },
            if fails.is_empty() {
                "none".to_string()
            } else {
                fails.join(", ")
            }
        ),
    }
}

pub(super) fn verdicts(
    base: &Config,
    main: &Derivation,
    fits: &[FitReading],
    nearest: &[NearestEigenvalue],
    dynamics: &[DynamicsReading],
    facts: &LatticeFacts,
) -> Vec<VerdictLine> {
    let mut out = vec![
        constant_verdict(
            PAPER_K_EDGE,
            Class::Spring(SpringKind::Structural),
            fits,
            facts,
        ),
        constant_verdict(PAPER_K_DIAG, Class::Spring(SpringKind::Shear), fits, facts),
        mass_verdict(&main.mass, nearest),
    ];
    out.extend(explicit_verdict(base, dynamics));
    for parameters in [Parameters::Paper, Parameters::Derived] {
        out.push(figure3_verdict(
            base,
            parameters,
            dynamics,
            main.spectrum.dnurbs.first().copied().unwrap_or(f64::NAN),
            facts,
        ));
    }
    out.push(drift_verdict(dynamics));
    out
}

pub(super) fn rest_formula(rest: RestShape) -> &'static str {
    match rest {
        RestShape::Initial => "p_rest = p(0)",
        RestShape::Zero => "p_rest = 0",
    }
}

pub(super) fn fmt_period(p: Option<f64>) -> String {
    p.map(|x| format!("{x:.3} s"))
        .unwrap_or_else(|| "none".to_string())
}
