//! `report.md` and the paper's verdict table.

use std::fmt::Write as _;

use nurbspring_derive::paper::PaperReport;
use nurbspring_derive::{
    Derivation, FitDetail, FitReport, FitResult, LINEAR_RANGE, ParameterSet, REGIME_FREQUENCY,
    Regime, Validation,
};
use nurbspring_msm::{Class, SpringKind};

fn fmt_k(f: &FitResult, class: Class) -> String {
    f.constants
        .get(class)
        .map(|k| format!("{k:.6}"))
        .unwrap_or_else(|| "-".into())
}

fn fmt_period(p: Option<f64>) -> String {
    p.map(|x| format!("{x:.3}")).unwrap_or_else(|| "-".into())
}

fn param_row(s: &mut String, label: &str, p: &ParameterSet) {
    let v = &p.validation;
    let _ = writeln!(
        s,
        "| {label} | {:.6} | {:.6} | {:.6} | {:.5} | {} | {:.4} | {:.4} | {} | {:.4e} | {:.4} | {} / {} |",
        p.constants.value(Class::Spring(SpringKind::Structural)),
        p.constants.value(Class::Spring(SpringKind::Shear)),
        p.m,
        p.dt_critical,
        if p.dt_exceeds_explicit_limit {
            "yes"
        } else {
            "no"
        },
        p.relative_residual_all_dofs.unwrap_or(f64::NAN),
        p.relative_residual_free_dofs.unwrap_or(f64::NAN),
        v.integrator,
        v.rms,
        v.relative_rms,
        fmt_period(v.dnurbs_period),
        fmt_period(v.msm_period),
    );
}

/// `report.md`: the derivation, its fit, the masses, stability, the validation, the second
/// excitation, the frequency table, the warnings, and the paper's table when given.
pub fn report_markdown(scene_label: &str, d: &Derivation, paper_table: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# nurbspring derivation report\n\n{}\n\nScene: `{scene_label}`; derivation: `{}`\n",
        verdict(&d.regime),
        d.method().name()
    );
    if !d.warnings.is_empty() {
        let _ = writeln!(s, "## Warnings\n");
        for w in &d.warnings {
            let _ = writeln!(s, "- {w}");
        }
        let _ = writeln!(s);
    }
    match &d.fit {
        FitDetail::Paper(fit) => paper_sections(&mut s, d, fit),
        FitDetail::Modal(f) => {
            let _ = writeln!(
                s,
                "## Modal fit\n\n{} element groups in {} classes fitted to {} D-NURBS modes (those with at most {} × {} half-waves, ω up to {:.4}); relative residual of the eigen-equations {:.4e}, of the Rayleigh quotients {:.4e}; the worst fitted mode {:.3e} off after the calibration; lowest frequency {:.6} rad/s before the calibration, {:.6} after (mass scale {:.6}). Each element's constant is in msm.json; the table gives each class's mean.\n",
                f.groups.len(),
                f.classes.len(),
                f.modes,
                f.half_waves[0],
                f.half_waves[1],
                f.mode_frequencies.last().copied().unwrap_or(0.0),
                f.relative_residual,
                f.frequency_residual,
                f.worst_fitted_mode,
                f.omega1_fitted,
                f.omega1_dnurbs,
                f.mass_scale
            );
            constants_table(&mut s, &f.constants);
        }
        FitDetail::Excitation(f) => {
            let _ = writeln!(
                s,
                "## Excitation-aware fit\n\nModes weighted (mode, share): {}; residual {:.4e} → {:.4e} in {} iterations; mass scale {:.6}; explicit step limit {:.4e} s (modal fit {:.4e} s).\n",
                f.modes
                    .iter()
                    .map(|(m, w)| format!("{m}: {w:.3}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                f.residual.0,
                f.residual.1,
                f.iterations,
                f.mass_scale,
                f.dt_critical.1,
                f.dt_critical.0
            );
            constants_table(&mut s, &f.constants);
        }
        FitDetail::Reduction(r) => {
            let _ = writeln!(
                s,
                "## Reduction\n\nThe {} reduction of the D-NURBS onto {} free nodes ({} free control points); written to `reduction.json`.\n",
                r.kind, r.free_nodes, r.free_control_points
            );
        }
    }
    let m = &d.mass;
    let _ = writeln!(
        s,
        "## Masses\n\n{}.\n\n| | MSM | D-NURBS (Σ M / 3) |\n|---|---|---|\n| all nodes | {:.6} | {:.6} |\n| free nodes | {:.6} | {:.6} |\n",
        m.rule, m.total_msm, m.total_dnurbs, m.free_msm, m.free_dnurbs
    );
    let p = &d.derived;
    let _ = writeln!(
        s,
        "## Stability\n\nω_max = {:.6e} rad/s, explicit limit Δt_crit = 2/ω_max = {:.6e} s{}.\n",
        p.omega_max,
        p.dt_critical,
        if p.dt_exceeds_explicit_limit {
            " (the scene's Δt exceeds it: use an implicit integrator)"
        } else {
            ""
        }
    );
    let _ = writeln!(s, "## Validation against the D-NURBS\n");
    validation_table(
        &mut s,
        &[
            ("scene's excitation", &p.validation),
            ("second excitation", &d.second_excitation),
        ],
    );
    if !d.frequencies.is_empty() {
        let _ = writeln!(
            s,
            "\n## Frequencies\n\nEach D-NURBS mode beside the MSM mode matched to it (by MAC at the free nodes, a repeated frequency as a subspace; by rank where the MSM's modes are not isotropic).\n\n| mode | D-NURBS ω | MSM mode | MSM ω | difference | MAC |\n|---|---|---|---|---|---|"
        );
        for r in &d.frequencies {
            let _ = writeln!(
                s,
                "| {} | {:.6} | {} | {:.6} | {:+.3}% | {} |",
                r.mode,
                r.dnurbs,
                r.msm_mode,
                r.msm,
                100.0 * r.relative_difference,
                r.mac
                    .map(|m| format!("{m:.4}"))
                    .unwrap_or_else(|| "-".into())
            );
        }
    }
    if !paper_table.is_empty() {
        let _ = writeln!(
            s,
            "\n## Reproduction of the paper\n\n```text\n{paper_table}```"
        );
    }
    s
}

/// The one-line verdict: the frequencies and displacements the model may be used for, and
/// where the scene's own motion lies (docs/math.md §8.7).
fn verdict(r: &Regime) -> String {
    let frequencies = if r.modes == 0 {
        format!(
            "no frequency range (not even the lowest D-NURBS mode has an MSM mode within {:.0}%)",
            100.0 * REGIME_FREQUENCY
        )
    } else {
        format!(
            "frequencies up to ω = {:.4} rad/s (the {} lowest D-NURBS modes, each matched within {:.0}%)",
            r.frequency,
            r.modes,
            100.0 * REGIME_FREQUENCY
        )
    };
    let share = |x: f64| 100.0 * x / r.size;
    let motion = if r.motion > r.amplitude {
        format!(
            "the scene's own motion reaches {:.4} ({:.0}% of the size): **outside the linear range**, so the figures below compare two linear models of a motion neither describes",
            r.motion,
            share(r.motion)
        )
    } else {
        format!(
            "the scene's own motion reaches {:.4} ({:.1}% of the size), inside it",
            r.motion,
            share(r.motion)
        )
    };
    format!(
        "**Verdict:** use this model for {frequencies} and displacements up to {:.4} ({:.0}% of the surface's size {:.4}); {motion}.",
        r.amplitude,
        100.0 * LINEAR_RANGE,
        r.size
    )
}

fn constants_table(s: &mut String, constants: &nurbspring_msm::Constants) {
    let _ = writeln!(s, "| class | constant |\n|---|---|");
    for (c, k) in constants.iter() {
        let _ = writeln!(s, "| {} | {k:.6e} |", c.name());
    }
    let _ = writeln!(s);
}

fn validation_table(s: &mut String, rows: &[(&str, &Validation)]) {
    let _ = writeln!(
        s,
        "| run | MSM run | reference | horizon [s] | rel. RMS (3-D) | rel. RMS (z) | periods D-NURBS / MSM | energy drift D-NURBS / MSM |\n|---|---|---|---|---|---|---|---|"
    );
    let drift = |d: Option<f64>| d.map_or_else(|| "-".to_string(), |x| format!("{x:.2e}"));
    for (name, v) in rows {
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {:.3} | {:.4} | {:.4} | {} / {} | {} / {} |",
            v.integrator,
            v.reference.name(),
            v.horizon,
            v.relative_rms,
            v.relative_rms_z,
            fmt_period(v.dnurbs_period),
            fmt_period(v.msm_period),
            drift(v.dnurbs_energy_drift),
            drift(v.msm_energy_drift)
        );
    }
    for (name, v) in rows {
        for (model, t) in [
            ("D-NURBS", &v.dnurbs_truncation),
            ("MSM", &v.msm_truncation),
        ] {
            if let Some(t) = t {
                let share = t.left_out.map_or_else(
                    || "an unknown share".to_string(),
                    |x| format!("{:.2}%", 100.0 * x),
                );
                let _ = writeln!(
                    s,
                    "\n{name}: the {model} followed its lowest {} of {} modes, with the static correction of the rest; the modes left out carry {share} of its motion (docs/math.md §8.6).",
                    t.modes, t.unknowns
                );
            }
        }
    }
    let _ = writeln!(
        s,
        "\nEnergy drift: the largest change of each model's total energy (kinetic + elastic + load) over the run, relative to its largest kinetic + elastic energy (zero without damping up to the integrator's error; the dissipated share with damping; `energy.png` plots both)."
    );
}

/// The paper's sections: the fit readings, the mass scan, the parameters with their
/// stability and validation.
fn paper_sections(s: &mut String, d: &Derivation, fit: &FitReport) {
    let _ = writeln!(s, "## Stiffness fit (paper eq. 15)\n");
    let _ = writeln!(
        s,
        "| reading | k_edge | k_diag | k_bend | relative residual |\n|---|---|---|---|---|"
    );
    for (name, f) in [
        ("all dofs, unconstrained (literal)", &fit.all_dofs),
        ("free dofs, unconstrained", &fit.free_dofs),
        ("all dofs, k >= 0", &fit.all_dofs_nonnegative),
        ("free dofs, k >= 0", &fit.free_dofs_nonnegative),
        ("trust region (selected reading)", &fit.trust_region.result),
    ] {
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {:.6} |",
            fmt_k(f, Class::Spring(SpringKind::Structural)),
            fmt_k(f, Class::Spring(SpringKind::Shear)),
            fmt_k(f, Class::Spring(SpringKind::Bend)),
            f.relative_residual
        );
    }
    let _ = writeln!(
        s,
        "\nSelected: {}. Trust region: {} iterations, largest relative difference to the closed form {:.2e}.\n",
        fit.selected_reading,
        fit.trust_region.iterations,
        fit.trust_region.max_relative_difference_to_closed_form
    );
    let _ = writeln!(s, "## Mass (Section III)\n\n{}.\n", d.mass.rule);
    let _ = writeln!(
        s,
        "Distinct non-null eigenvalues of M ({}): {}\n",
        d.mass.eigenvalues.len(),
        d.mass
            .eigenvalues
            .iter()
            .map(|v| format!("{v:.6}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if !d.mass.candidates.is_empty() {
        let _ = writeln!(
            s,
            "| m | RMS | max abs | integrator | note |\n|---|---|---|---|---|"
        );
        for c in &d.mass.candidates {
            let number = |x: f64| {
                if x.is_finite() {
                    format!("{x:.4e}")
                } else {
                    "–".to_string()
                }
            };
            let (rms, note) = match c.pruned {
                Some(p) => (
                    format!("≥ {:.4e}", p.rms_at_least),
                    format!("stopped at t = {:.4} s: above the best already", p.at),
                ),
                None => (number(c.rms), c.stopped.clone().unwrap_or_default()),
            };
            let _ = writeln!(
                s,
                "| {:.6} | {rms} | {} | {} | {note} |",
                c.m,
                number(c.max_abs),
                c.integrator,
            );
        }
    }
    let _ = writeln!(s, "\nSelected mass: **{:.6}**\n", d.mass.selected);
    let _ = writeln!(s, "## Parameters, stability and validation (Figure 3)\n");
    let _ = writeln!(
        s,
        "| parameters | k_edge | k_diag | m | dt_critical | dt over limit | residual (all) | residual (free) | integrator | RMS | rel. RMS | periods D-NURBS / MSM |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    param_row(s, "derived", &d.derived);
    if let Some(g) = &d.given {
        param_row(s, "scene's", g);
    }
    for (label, p) in [("derived", Some(&d.derived)), ("scene's", d.given.as_ref())] {
        if let Some(e) = p.and_then(|p| p.explicit_run.as_ref()) {
            let _ = writeln!(
                s,
                "\nThe scene's explicit integrator ({}) with the {label} parameters: {}",
                e.integrator,
                e.msm_stopped.as_deref().unwrap_or("finished")
            );
        }
    }
}

/// The human table of the reproduction: each paper number, what nurbspring obtains, the
/// verdict; then every reading of the fit and every side-by-side run.
pub fn verdict_table(report: &PaperReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Reproduction of Section IV (paper value | nurbspring | verdict)"
    );
    let _ = writeln!(s, "{}", "=".repeat(78));
    for v in &report.verdicts {
        let _ = writeln!(s, "{}", v.quantity);
        let _ = writeln!(s, "  paper:    {}", v.paper);
        let _ = writeln!(s, "  obtained: {}", v.obtained);
        let _ = writeln!(s, "  verdict:  {} - {}", v.verdict.label(), v.why);
    }
    let _ = writeln!(s, "{}", "-".repeat(78));
    let _ = writeln!(
        s,
        "Beyond the paper: the default derivation on the paper's scene (printed net), against the exact D-NURBS"
    );
    for r in &report.beyond.rows {
        let _ = writeln!(
            s,
            "  {:<10} {:<24} free mass {:.5} (D-NURBS {:.5})  lowest non-zero omega {} (D-NURBS {:.5})  rel. RMS {}",
            r.derivation.name(),
            r.lattice,
            r.free_mass.0,
            r.free_mass.1,
            r.omega1
                .0
                .map(|w| format!("{w:.5}"))
                .unwrap_or_else(|| "-".into()),
            r.omega1.1,
            r.relative_rms
                .iter()
                .map(|(h, e)| format!("{e:.4} over {h} s"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let _ = writeln!(s, "{}", "-".repeat(78));
    let _ = writeln!(
        s,
        "Stiffness fit, every reading (net, dofs, norm, constraint: k_edge, k_diag, relative residual; the same at the paper's k)"
    );
    for f in &report.fits {
        let k = |class| f.result.constants.value(class);
        let _ = writeln!(
            s,
            "  {:<8} {:<4} {:<9} {:<13} k_edge = {:>10.5}  k_diag = {:>10.5}  residual = {:.4}  (paper's k: {:.4})",
            f.net.name(),
            f.dofs.name(),
            f.norm.name(),
            if f.nonnegative {
                "k >= 0"
            } else {
                "unconstrained"
            },
            k(Class::Spring(SpringKind::Structural)),
            k(Class::Spring(SpringKind::Shear)),
            f.result.relative_residual,
            f.residual_at_paper_values
        );
    }
    let _ = writeln!(
        s,
        "Side-by-side runs, central node z (net, rest shape, parameters, integrator, horizon: dt_crit, rel. RMS, periods D-NURBS/MSM)"
    );
    for d in &report.dynamics {
        let _ = writeln!(
            s,
            "  {:<8} rest={:<7} {:<7} {:<16} {:>4} s  dt_crit = {:.4}  rel.RMS = {:>9.4}  T = {} / {}{}",
            d.net.name(),
            d.rest_shape.name(),
            d.parameters.name(),
            d.integrator.name(),
            d.t_end,
            d.dt_critical,
            d.relative_rms,
            fmt_period(d.dnurbs_period),
            fmt_period(d.msm_period),
            if d.msm_stopped.is_some() {
                "  (MSM run stopped early)"
            } else {
                ""
            }
        );
    }
    s
}
