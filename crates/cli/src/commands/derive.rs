//! `nurbspring derive SCENE --out DIR`: the derived MSM and its validation.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use nurbspring_derive::paper::PaperReport;
use nurbspring_derive::{Derivation, FitResult, ParameterSet};
use nurbspring_io::scene::Scene;
use nurbspring_msm::SpringKind;
use serde::Serialize;

use crate::convert;
use crate::progress::Progress;
use crate::{CmdResult, Context, Failure, prepare_out_dir};

/// Flags of `nurbspring derive`.
#[derive(Args, Debug)]
pub struct DeriveArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Derives the MSM of a scene and writes every output.
pub fn run(ctx: &Context, args: DeriveArgs) -> CmdResult {
    let scene = convert::load_scene(&args.scene)?;
    let config = convert::experiment(&scene)?;
    let out = prepare_out_dir(&args.out)?;
    let bar = Progress::new(ctx.global.quiet, "mass scan", 1);
    let (derivation, _) =
        nurbspring_derive::derive_msm(&config, Some(ctx.cancel.clone()), &mut |d, t| {
            bar.set_total(t as u64);
            bar.set(d as u64);
        })
        .map_err(convert::derive_failure)?;
    bar.finish();
    write_derivation(
        &out,
        &args.scene.display().to_string(),
        &scene,
        &derivation,
        None,
        "",
    )?;
    if !ctx.global.quiet {
        let d = &derivation.derived;
        println!(
            "derived MSM: k_edge = {:.6}, k_diag = {:.6}{}, m = {:.6}; dt_critical = {:.5}; central node rel. RMS = {:.4} ({})",
            d.k_edge,
            d.k_diag,
            d.k_bend
                .map(|k| format!(", k_bend = {k:.6}"))
                .unwrap_or_default(),
            d.m,
            d.dt_critical,
            d.validation.relative_rms,
            d.validation.integrator
        );
        println!("Outputs in {}", out.display());
    }
    Ok(())
}

/// `msm.json`: the lattice file plus where it came from and how to run it.
#[derive(Serialize)]
struct MsmFile<'a> {
    #[serde(flatten)]
    lattice: nurbspring_msm::LatticeFile,
    scene: &'a str,
    initial_velocities: &'a [[f64; 3]],
    simulation: SimulationBlock,
}

#[derive(Serialize)]
struct SimulationBlock {
    dt: f64,
    t_end: f64,
    integrator: String,
}

fn fit_json(f: &FitResult) -> serde_json::Value {
    serde_json::to_value(f).unwrap_or_default()
}

/// Writes msm.json, report.json, report.md, central_node.csv and the plots.
pub fn write_derivation(
    out: &Path,
    scene_label: &str,
    scene: &Scene,
    d: &Derivation,
    paper: Option<&PaperReport>,
    paper_table: &str,
) -> Result<(), Failure> {
    let sim = convert::simulation(scene)?;
    let io = |e: nurbspring_io::OutputError| Failure::run(e);

    let msm = MsmFile {
        lattice: d.lattice.to_json(),
        scene: scene_label,
        initial_velocities: &d.node_velocities,
        simulation: SimulationBlock {
            dt: sim.dt,
            t_end: sim.t_end,
            integrator: d.derived.validation.integrator.clone(),
        },
    };
    nurbspring_io::output::write_json(out.join("msm.json"), &msm).map_err(io)?;

    let mut report = serde_json::json!({
        "scene": scene_label,
        "fit": {
            "classes": d.fit.classes.iter().map(|c| c.name()).collect::<Vec<_>>(),
            "all_dofs": fit_json(&d.fit.all_dofs),
            "free_dofs": fit_json(&d.fit.free_dofs),
            "all_dofs_nonnegative": fit_json(&d.fit.all_dofs_nonnegative),
            "free_dofs_nonnegative": fit_json(&d.fit.free_dofs_nonnegative),
            "trust_region": d.fit.trust_region,
            "selected_reading": d.fit.selected_reading,
            "selected": fit_json(&d.fit.selected),
        },
        "mass": d.mass,
        "derived": d.derived,
        "validation": d.derived.validation,
        "spectrum": d.spectrum,
        "probes": d.probes.iter().zip(&d.probe_nodes).map(|(p, n)| serde_json::json!({"u": p.0, "v": p.1, "node": n})).collect::<Vec<_>>(),
    });
    if let Some(g) = &d.given {
        report["paper_parameters"] = serde_json::to_value(g).unwrap_or_default();
    }
    if let Some(p) = paper {
        report["paper"] = serde_json::to_value(p).unwrap_or_default();
    }
    nurbspring_io::output::write_json(out.join("report.json"), &report).map_err(io)?;

    // Central node, z over time.
    let t = &d.dnurbs_trajectory.t;
    let zd = d.dnurbs_trajectory.component(0, 2);
    let zm = d.msm_trajectory.component(0, 2);
    let n = t.len();
    let rows = (0..n).map(|s| vec![t[s], zd[s], zm.get(s).copied().unwrap_or(f64::NAN)]);
    nurbspring_io::output::write_csv(
        out.join("central_node.csv"),
        &["t", "dnurbs_z", "msm_z"],
        rows,
    )
    .map_err(io)?;

    let mut series = vec![
        nurbspring_io::plot::Series::line(
            "D-NURBS",
            t.iter().copied().zip(zd.iter().copied()).collect(),
        ),
        nurbspring_io::plot::Series::line(
            format!("derived MSM ({})", d.derived.validation.integrator),
            t.iter().copied().zip(zm.iter().copied()).collect(),
        ),
    ];
    if let (Some(g), Some(gt)) = (&d.given, &d.given_trajectory) {
        let zg = gt.component(0, 2);
        series.push(nurbspring_io::plot::Series::line(
            format!(
                "scene's MSM k_edge={}, k_diag={}, m={} ({})",
                g.k_edge, g.k_diag, g.m, g.validation.integrator
            ),
            gt.t.iter().copied().zip(zg.iter().copied()).collect(),
        ));
    }
    let title = "Central node z(t): D-NURBS vs MSM (paper Figure 3)";
    for ext in ["svg", "png"] {
        crate::output::plot(
            &out.join(format!("central_node.{ext}")),
            title,
            "t [s]",
            "z [m]",
            &series,
            false,
        )
        .map_err(io)?;
    }
    if !d.mass.candidates.is_empty() {
        let pts: Vec<(f64, f64)> = d
            .mass
            .candidates
            .iter()
            .filter(|c| c.rms.is_finite() && c.rms > 0.0)
            .map(|c| (c.m, c.rms))
            .collect();
        if !pts.is_empty() {
            for ext in ["svg", "png"] {
                crate::output::plot(
                    &out.join(format!("mass_scan.{ext}")),
                    "Mass candidates: eigenvalues of M vs RMS error of the central node",
                    "m (eigenvalue of M)",
                    "RMS error [m]",
                    &[nurbspring_io::plot::Series::points(
                        "candidates",
                        pts.clone(),
                    )],
                    true,
                )
                .map_err(io)?;
            }
        }
    }
    let energy_series = vec![
        nurbspring_io::plot::Series::line(
            "D-NURBS kinetic + elastic",
            d.dnurbs_trajectory
                .t
                .iter()
                .zip(&d.dnurbs_trajectory.energy)
                .map(|(t, e)| (*t, e[0] + e[1]))
                .collect(),
        ),
        nurbspring_io::plot::Series::line(
            "derived MSM kinetic + elastic",
            d.msm_trajectory
                .t
                .iter()
                .zip(&d.msm_trajectory.energy)
                .map(|(t, e)| (*t, e[0] + e[1]))
                .collect(),
        ),
    ];
    for ext in ["svg", "png"] {
        crate::output::plot(
            &out.join(format!("energy.{ext}")),
            "Energy over time",
            "t [s]",
            "energy [J]",
            &energy_series,
            false,
        )
        .map_err(io)?;
    }
    if !d.spectrum.dnurbs.is_empty() {
        for ext in ["svg", "png"] {
            nurbspring_io::plot::plot_spectrum(
                out.join(format!("spectrum.{ext}")),
                "Angular frequencies: D-NURBS vs derived MSM (linearized at rest)",
                "omega [rad/s]",
                &[
                    ("D-NURBS", &d.spectrum.dnurbs),
                    ("derived MSM", &d.spectrum.msm),
                ],
            )
            .map_err(io)?;
        }
    }
    let obj = nurbspring_io::output::ObjMesh::lattice(
        d.lattice.positions.clone(),
        d.lattice.springs.iter().map(|s| [s.a, s.b]).collect(),
    );
    nurbspring_io::output::write_obj(out.join("lattice.obj"), &obj, "nurbspring derived lattice")
        .map_err(io)?;
    crate::output::write_lattice_vtu(&out.join("lattice.vtu"), &d.lattice)?;

    let md = report_markdown(scene_label, d, paper_table);
    nurbspring_io::atomic::write_atomic_bytes(out.join("report.md"), md.as_bytes()).map_err(io)?;
    Ok(())
}

fn fmt_k(f: &FitResult, kind: SpringKind) -> String {
    match kind {
        SpringKind::Structural => f.k_edge,
        SpringKind::Shear => f.k_diag,
        SpringKind::Bend => f.k_bend,
    }
    .map(|k| format!("{k:.6}"))
    .unwrap_or_else(|| "-".into())
}

fn param_rows(s: &mut String, label: &str, p: &ParameterSet) {
    let v = &p.validation;
    let _ = writeln!(
        s,
        "| {label} | {:.6} | {:.6} | {:.6} | {:.5} | {} | {:.4} | {:.4} | {} | {:.4e} | {:.4} | {} / {} |",
        p.k_edge,
        p.k_diag,
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
        v.dnurbs_period
            .map(|x| format!("{x:.3}"))
            .unwrap_or_else(|| "-".into()),
        v.msm_period
            .map(|x| format!("{x:.3}"))
            .unwrap_or_else(|| "-".into()),
    );
}

fn report_markdown(scene_label: &str, d: &Derivation, paper_table: &str) -> String {
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
            fmt_k(f, SpringKind::Structural),
            fmt_k(f, SpringKind::Shear),
            fmt_k(f, SpringKind::Bend),
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
    param_rows(&mut s, "derived", &d.derived);
    if let Some(g) = &d.given {
        param_rows(&mut s, "scene's", g);
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
