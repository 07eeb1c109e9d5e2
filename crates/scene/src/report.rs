//! Derivation results → files: `msm.json`, `report.json` (serde from the typed results, with
//! the inputs that produced them, so a report stands on its own), `report.md`,
//! `central_node.csv`, plots, and the lattice as VTK and OBJ; the paper's verdict table.

use std::fmt::Write as _;
use std::path::Path;

use nurbspring_derive::paper::PaperReport;
use nurbspring_derive::{
    Derivation, FitReport, FitResult, InitialConditions, MassReport, ParameterSet, Spectrum,
    TimeSettings, ValidationReport,
};
use nurbspring_dnurbs::{DnurbsOptions, Loads, Material};
use nurbspring_io::output::{write_csv, write_json};
use nurbspring_io::plot::{PlotOptions, Series, plot_series_with, plot_spectrum};
use nurbspring_msm::{Class, Constants, FileSimulation, SpringKind};
use serde::Serialize;

use crate::export::{write_lattice_obj, write_lattice_vtu};
use crate::msm_file::msm_file;
use crate::spec::{ConstraintsSpec, FitSpec, MsmSpec};
use crate::{Error, Scene};

/// The inputs of a derivation, as the models saw them.
#[derive(Serialize)]
pub struct Inputs<'a> {
    /// `[material]`.
    pub material: &'a Material,
    /// `[loads]`.
    pub loads: Loads,
    /// `[constraints]`.
    pub constraints: &'a ConstraintsSpec,
    /// `[dnurbs]`.
    pub dnurbs: &'a DnurbsOptions,
    /// `[initial]`.
    pub initial: InitialConditions,
    /// `[simulation]` time stepping.
    pub simulation: TimeSettings,
    /// `[msm]`.
    pub msm: &'a MsmSpec,
    /// `[fit]`.
    pub fit: &'a FitSpec,
}

/// One probe: its parameters and the lattice node that stands for it.
#[derive(Serialize)]
pub struct Probe {
    /// Parameter u.
    pub u: f64,
    /// Parameter v.
    pub v: f64,
    /// Lattice node.
    pub node: usize,
}

/// `report.json`.
#[derive(Serialize)]
pub struct Report<'a> {
    /// The scene it came from.
    pub scene: &'a str,
    /// What produced it.
    pub inputs: Inputs<'a>,
    /// The stiffness fit of eq. (15), every reading.
    pub fit: &'a FitReport,
    /// The mass step.
    pub mass: &'a MassReport,
    /// The derived parameters, their stability and validation.
    pub derived: &'a ParameterSet,
    /// The derived MSM's validation (as in `derived`).
    pub validation: &'a ValidationReport,
    /// Frequencies of both models.
    pub spectrum: &'a Spectrum,
    /// Probe points.
    pub probes: Vec<Probe>,
    /// The scene's own `[msm]` parameters, evaluated the same way.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_parameters: Option<&'a ParameterSet>,
    /// The paper's reproduction (`nurbspring paper` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper: Option<&'a PaperReport>,
}

impl<'a> Report<'a> {
    /// The report of `d`, derived from `scene`.
    pub fn new(
        scene_label: &'a str,
        scene: &'a Scene,
        d: &'a Derivation,
        paper: Option<&'a PaperReport>,
    ) -> Self {
        Self {
            scene: scene_label,
            inputs: Inputs {
                material: &scene.material,
                loads: scene.build_loads(),
                constraints: &scene.constraints,
                dnurbs: &scene.dnurbs,
                initial: scene.initial_conditions(),
                simulation: scene.time_settings(),
                msm: &scene.msm,
                fit: &scene.fit,
            },
            fit: &d.fit,
            mass: &d.mass,
            derived: &d.derived,
            validation: &d.derived.validation,
            spectrum: &d.spectrum,
            probes: d
                .probes
                .iter()
                .zip(&d.probe_nodes)
                .map(|(&(u, v), &node)| Probe { u, v, node })
                .collect(),
            paper_parameters: d.given.as_ref(),
            paper,
        }
    }
}

/// Writes a plot (SVG or PNG by extension), optionally with a logarithmic y axis.
fn plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_y: bool,
) -> Result<(), Error> {
    let mut options = PlotOptions::new(title, x_label, y_label);
    options.log_y = log_y;
    plot_series_with(path, &options, series)?;
    Ok(())
}

/// `k_edge = 1.5, k_diag = 0.5` of the classes present.
pub fn constants_text(constants: &Constants, precision: usize) -> String {
    constants
        .iter()
        .map(|(c, k)| format!("{} = {k:.precision$}", c.symbol()))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes msm.json, report.json, report.md, central_node.csv, the plots and the lattice into
/// `out` (each file atomically). `paper_table` is the text of the reproduction table (empty
/// unless this is the paper's experiment).
pub fn write_derivation(
    out: &Path,
    scene_label: &str,
    scene: &Scene,
    d: &Derivation,
    paper: Option<&PaperReport>,
    paper_table: &str,
) -> Result<(), Error> {
    let time = scene.time_settings();
    let msm = msm_file(
        &d.lattice,
        scene_label,
        &d.node_velocities,
        FileSimulation {
            dt: time.dt,
            t_end: time.t_end,
            integrator: d.derived.validation.integrator,
        },
    );
    write_json(out.join("msm.json"), &msm)?;
    write_json(
        out.join("report.json"),
        &Report::new(scene_label, scene, d, paper),
    )?;
    write_central_node(out, d)?;
    write_plots(out, d)?;
    write_lattice_obj(&out.join("lattice.obj"), &d.lattice)?;
    write_lattice_vtu(&out.join("lattice.vtu"), &d.lattice)?;
    let md = report_markdown(scene_label, d, paper_table);
    nurbspring_io::atomic::write_atomic_bytes(out.join("report.md"), md.as_bytes())?;
    Ok(())
}

/// `central_node.csv`: t, D-NURBS z, MSM z.
fn write_central_node(out: &Path, d: &Derivation) -> Result<(), Error> {
    let t = &d.dnurbs_trajectory.t;
    let zd = d.dnurbs_trajectory.component(0, 2);
    let zm = d.msm_trajectory.component(0, 2);
    let rows = (0..t.len()).map(|s| vec![t[s], zd[s], zm.get(s).copied().unwrap_or(f64::NAN)]);
    write_csv(
        out.join("central_node.csv"),
        &["t", "dnurbs_z", "msm_z"],
        rows,
    )?;
    Ok(())
}

fn xy(t: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    t.iter().copied().zip(y.iter().copied()).collect()
}

/// central_node, mass_scan, energy and spectrum plots, SVG and PNG.
fn write_plots(out: &Path, d: &Derivation) -> Result<(), Error> {
    let t = &d.dnurbs_trajectory.t;
    let mut series = vec![
        Series::line("D-NURBS", xy(t, &d.dnurbs_trajectory.component(0, 2))),
        Series::line(
            format!("derived MSM ({})", d.derived.validation.integrator),
            xy(t, &d.msm_trajectory.component(0, 2)),
        ),
    ];
    if let (Some(g), Some(gt)) = (&d.given, &d.given_trajectory) {
        let k = |class| g.constants.value(class);
        series.push(Series::line(
            format!(
                "scene's MSM k_edge={}, k_diag={}, m={} ({})",
                k(Class::Spring(SpringKind::Structural)),
                k(Class::Spring(SpringKind::Shear)),
                g.m,
                g.validation.integrator
            ),
            xy(&gt.t, &gt.component(0, 2)),
        ));
    }
    let title = "Central node z(t): D-NURBS vs MSM (paper Figure 3)";
    for ext in ["svg", "png"] {
        plot(
            &out.join(format!("central_node.{ext}")),
            title,
            "t [s]",
            "z [m]",
            &series,
            false,
        )?;
    }
    let scan: Vec<(f64, f64)> = d
        .mass
        .candidates
        .iter()
        .filter(|c| c.rms.is_finite() && c.rms > 0.0)
        .map(|c| (c.m, c.rms))
        .collect();
    if !scan.is_empty() {
        for ext in ["svg", "png"] {
            plot(
                &out.join(format!("mass_scan.{ext}")),
                "Mass candidates: eigenvalues of M vs RMS error of the central node",
                "m (eigenvalue of M)",
                "RMS error [m]",
                &[Series::points("candidates", scan.clone())],
                true,
            )?;
        }
    }
    let total = |traj: &nurbspring_derive::Trajectory| -> Vec<(f64, f64)> {
        traj.t
            .iter()
            .zip(&traj.energy)
            .map(|(t, e)| (*t, e[0] + e[1]))
            .collect()
    };
    let energy = vec![
        Series::line("D-NURBS kinetic + elastic", total(&d.dnurbs_trajectory)),
        Series::line("derived MSM kinetic + elastic", total(&d.msm_trajectory)),
    ];
    for ext in ["svg", "png"] {
        plot(
            &out.join(format!("energy.{ext}")),
            "Energy over time",
            "t [s]",
            "energy [J]",
            &energy,
            false,
        )?;
    }
    if !d.spectrum.dnurbs.is_empty() {
        for ext in ["svg", "png"] {
            plot_spectrum(
                out.join(format!("spectrum.{ext}")),
                "Angular frequencies: D-NURBS vs derived MSM (linearized at rest)",
                "omega [rad/s]",
                &[
                    ("D-NURBS", &d.spectrum.dnurbs),
                    ("derived MSM", &d.spectrum.msm),
                ],
            )?;
        }
    }
    Ok(())
}

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
        p.relative_residual_all_dofs,
        p.relative_residual_free_dofs,
        v.integrator,
        v.rms,
        v.relative_rms,
        fmt_period(v.dnurbs_period),
        fmt_period(v.msm_period),
    );
}

/// `report.md`: the fit readings, the mass scan, the parameters with their stability and
/// validation, and the paper's table when given.
pub fn report_markdown(scene_label: &str, d: &Derivation, paper_table: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# nurbspring derivation report\n\nScene: `{scene_label}`\n"
    );
    let _ = writeln!(s, "## Stiffness fit (paper eq. 15)\n");
    let _ = writeln!(
        s,
        "| reading | k_edge | k_diag | k_bend | relative residual |\n|---|---|---|---|---|"
    );
    for (name, f) in [
        ("all dofs, unconstrained (literal)", &d.fit.all_dofs),
        ("free dofs, unconstrained", &d.fit.free_dofs),
        ("all dofs, k >= 0", &d.fit.all_dofs_nonnegative),
        ("free dofs, k >= 0", &d.fit.free_dofs_nonnegative),
        (
            "trust region (selected reading)",
            &d.fit.trust_region.result,
        ),
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
        d.fit.selected_reading,
        d.fit.trust_region.iterations,
        d.fit.trust_region.max_relative_difference_to_closed_form
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
            let _ = writeln!(
                s,
                "| {:.6} | {:.4e} | {:.4e} | {} | {} |",
                c.m,
                c.rms,
                c.max_abs,
                c.integrator,
                c.stopped.as_deref().unwrap_or("")
            );
        }
    }
    let _ = writeln!(s, "\nSelected mass: **{:.6}**\n", d.mass.selected);
    let _ = writeln!(s, "## Parameters, stability and validation (Figure 3)\n");
    let _ = writeln!(
        s,
        "| parameters | k_edge | k_diag | m | dt_critical | dt over limit | residual (all) | residual (free) | integrator | RMS | rel. RMS | periods D-NURBS / MSM |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    param_row(&mut s, "derived", &d.derived);
    if let Some(g) = &d.given {
        param_row(&mut s, "scene's", g);
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
    if !paper_table.is_empty() {
        let _ = writeln!(
            s,
            "\n## Reproduction of the paper\n\n```text\n{paper_table}```"
        );
    }
    s
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
                "  (MSM run stopped: diverged)"
            } else {
                ""
            }
        );
    }
    s
}
