//! The files of a spring derivation (docs/math.md §11): `msm.json` (springs, hinges, masses,
//! damping), `report.json`, `report.md` with the verdict on top, `load_path.csv` and
//! `load_path.svg` of the large-motion load path, and the lattice as OBJ and VTK; and of a
//! shell's reduction (§11.4): `reduction.json`, `report.json` and `report.md`.

use std::fmt::Write as _;
use std::path::Path;

use nurbspring_derive::{
    LARGE_MOTION, ShellReduction, SmallMotion, SpringFrequency, SpringsDerivation,
};
use nurbspring_io::output::{write_csv, write_json};
use nurbspring_io::plot::{PlotOptions, Series, plot_series_with};
use nurbspring_msm::{FileSimulation, MsmFile};
use nurbspring_sim::IntegratorKind;
use serde::Serialize;

use crate::export::{write_lattice_obj, write_lattice_vtu};
use crate::msm_file::msm_file;
use crate::{DerivationChoice, Error, Scene};

/// Derives the spring model of a Kirchhoff–Love scene; errors name the scene key they come
/// from. `stage` is told each stage as it begins.
pub fn derive_springs(
    scene: &Scene,
    choice: &DerivationChoice,
    cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    stage: &mut dyn FnMut(&str),
) -> Result<SpringsDerivation, Error> {
    let config = scene.springs_config(choice.method, choice.key)?;
    nurbspring_derive::derive_springs(&config, cancel, stage)
        .map_err(|e| scene.derive_error(crate::derivation::DERIVATION_KEY, e))
}

/// report.json of a spring derivation.
#[derive(Serialize)]
pub struct SpringsReport<'a> {
    scene: &'a str,
    derivation: &'static str,
    nodes: usize,
    springs: usize,
    hinges: usize,
    fixed_nodes: usize,
    #[serde(flatten)]
    derivation_detail: &'a SpringsDerivation,
}

impl<'a> SpringsReport<'a> {
    /// The report of `d`, derived from the scene `scene_label`.
    pub fn new(scene_label: &'a str, d: &'a SpringsDerivation) -> Self {
        Self {
            scene: scene_label,
            derivation: d.method.name(),
            nodes: d.lattice.n_nodes(),
            springs: d.lattice.springs.len(),
            hinges: d.lattice.hinges.len(),
            fixed_nodes: d.lattice.fixed.iter().filter(|f| **f).count(),
            derivation_detail: d,
        }
    }
}

/// The msm.json of a spring derivation: run by `simulate msm.json` with the scene's Δt and
/// end time, Newmark, from the scene's initial velocities.
pub fn springs_msm_file(scene_label: &str, scene: &Scene, d: &SpringsDerivation) -> MsmFile {
    let time = scene.time_settings();
    let run = FileSimulation {
        dt: time.dt,
        t_end: time.t_end,
        integrator: IntegratorKind::Newmark,
    };
    msm_file(
        &d.lattice,
        scene_label,
        &d.node_velocities,
        run,
        &d.probe_nodes,
    )
}

/// Writes every file of a spring derivation into `out` (each atomically).
pub fn write_springs(
    out: &Path,
    scene_label: &str,
    scene: &Scene,
    d: &SpringsDerivation,
) -> Result<(), Error> {
    write_json(
        out.join("msm.json"),
        &springs_msm_file(scene_label, scene, d),
    )?;
    write_lattice_obj(&out.join("lattice.obj"), &d.lattice)?;
    write_lattice_vtu(&out.join("lattice.vtu"), &d.lattice)?;
    write_json(out.join("report.json"), &SpringsReport::new(scene_label, d))?;
    // The load path's table and plot, when the static comparison has levels.
    if let Some(l) = d.large_motion.as_ref().filter(|l| !l.levels.is_empty()) {
        write_csv(
            out.join("load_path.csv"),
            &[
                "load_factor",
                "shell_displacement",
                "max_node_error",
                "rms_node_error",
            ],
            l.levels.iter().map(|r| {
                vec![
                    r.load_factor,
                    r.shell_displacement,
                    r.max_error,
                    r.rms_error,
                ]
            }),
        )?;
        let series = vec![
            Series::line(
                "shell: largest displacement / size",
                l.levels
                    .iter()
                    .map(|r| (r.load_factor, r.shell_displacement))
                    .collect(),
            ),
            Series::line(
                "springs: largest node error / size",
                l.levels
                    .iter()
                    .map(|r| (r.load_factor, r.max_error))
                    .collect(),
            ),
        ];
        let options = PlotOptions::new(
            "Large motion: the spring model on the shell's load path",
            "load factor on the scene's loads",
            "fraction of the size",
        );
        plot_series_with(out.join("load_path.svg"), &options, &series)?;
    }
    write_markdown(out, scene_label, d)
}

fn write_markdown(out: &Path, scene_label: &str, d: &SpringsDerivation) -> Result<(), Error> {
    nurbspring_io::atomic::write_atomic_bytes(
        out.join("report.md"),
        springs_markdown(scene_label, d).as_bytes(),
    )?;
    Ok(())
}

/// report.md of a spring derivation.
pub fn springs_markdown(scene_label: &str, d: &SpringsDerivation) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Spring model of {scene_label} (derivation `{}`)\n",
        d.method.name()
    );
    let _ = writeln!(s, "**Verdict.** {}.\n", d.verdict);
    let _ = writeln!(
        s,
        "Rest-length springs and dihedral hinges on a triangulated lattice of {} nodes ({} \
         fixed), {} springs, {} hinges; total mass {:.6e} kg; size (bounding-box diagonal) \
         {:.6e} m (docs/math.md §11).\n",
        d.lattice.n_nodes(),
        d.lattice.fixed.iter().filter(|f| **f).count(),
        d.lattice.springs.len(),
        d.lattice.hinges.len(),
        d.total_mass,
        d.size
    );
    let _ = writeln!(s, "## Constants\n");
    let _ = writeln!(s, "| class | elements | rule | calibrated |");
    let _ = writeln!(s, "|---|---|---|---|");
    for c in &d.constants {
        let _ = writeln!(
            s,
            "| {} | {} | {:.6e} | {:.6e} |",
            c.class, c.count, c.rule, c.calibrated
        );
    }
    let groups = if d.groups.is_empty() {
        "one scale per class".to_string()
    } else {
        let (lo, hi) = d
            .groups
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), g| {
                (lo.min(g.scale), hi.max(g.scale))
            });
        format!(
            "one scale per class and band of the lattice ({} groups, scales {lo:.4} to {hi:.4}, \
             each in report.json `groups`; an element's stiffness is its class constant times \
             the rule's weight times its group's scale)",
            d.groups.len()
        )
    };
    let fitted = if d.excited_modes.is_empty() {
        format!("the shell's lowest {} modes", d.fitted_modes)
    } else {
        let list: Vec<String> = d
            .excited_modes
            .iter()
            .map(|m| format!("{} ({:.1} %)", m.mode, 100.0 * m.share))
            .collect();
        format!(
            "the {} shell modes the scene's initial state and loads move most, each weighted by \
             its share of that motion: {}",
            d.excited_modes.len(),
            list.join(", ")
        )
    };
    let _ = writeln!(
        s,
        "\nCalibrated on {fitted} with {groups} (Gauss–Newton on the log frequency ratios of the modes matched by MAC, RMS {:.3e}); \
         every constant then times {:.6} for the exact lowest frequency.\n",
        d.fit_residual, d.frequency_factor
    );
    s.push_str(&frequency_section(
        &d.frequencies,
        "spring mode",
        "ω springs",
    ));
    s.push_str(&small_motion_section(&d.small_motion));
    let _ = writeln!(s, "## Large motion\n");
    match (&d.large_motion, &d.large_motion_skipped) {
        (Some(l), _) => {
            let _ = writeln!(
                s,
                "The scene's loads times {:.4} (target: the shell's farthest node at ≥ {:.0} % \
                 of the size). Static load path, each node against the surface point of its \
                 (u, v):\n",
                l.load_factor,
                100.0 * LARGE_MOTION
            );
            if let Some(limit) = l.shell_limit {
                let _ = writeln!(
                    s,
                    "The shell's own load path stops at the load factor {limit:.4} (a limit \
                     point: it snaps through or buckles) before moving that far, so the runs \
                     are at {:.0} % of that load.\n",
                    100.0 * nurbspring_derive::BELOW_LIMIT
                );
            }
            if !l.levels.is_empty() {
                let _ = writeln!(
                    s,
                    "| load factor | shell displacement / size | largest node error / size | RMS |"
                );
                let _ = writeln!(s, "|---|---|---|---|");
                for r in &l.levels {
                    let _ = writeln!(
                        s,
                        "| {:.4} | {:.2} % | {:.2} % | {:.2} % |",
                        r.load_factor,
                        100.0 * r.shell_displacement,
                        100.0 * r.max_error,
                        100.0 * r.rms_error
                    );
                }
            }
            if let Some(why) = &l.static_failure {
                let _ = writeln!(s, "\nStatic comparison incomplete: {why}.");
            }
            match (&l.dynamic, &l.dynamic_failure) {
                (Some(r), _) => {
                    let _ = writeln!(
                        s,
                        "\nDynamic: the same loads applied at once, both models by {} (ρ∞ = {}) with Δt = \
                         {:.4e} s over {:.4e} s ({:.0} periods of the lowest elastic mode; the \
                         shell's farthest node reaches {:.1} % of the size): largest node error \
                         {:.2} % of the size, RMS over nodes and time {:.2} %.",
                        r.integrator,
                        r.rho_infinity,
                        r.dt,
                        r.t_end,
                        r.periods,
                        100.0 * r.shell_displacement,
                        100.0 * r.max_error,
                        100.0 * r.rms_error
                    );
                }
                (None, Some(why)) => {
                    let _ = writeln!(s, "\nDynamic comparison not made: {why}.");
                }
                (None, None) => {}
            }
        }
        (None, Some(why)) => {
            let _ = writeln!(s, "Not run: {why}.");
        }
        (None, None) => {}
    }
    s
}

/// The frequency table of a shell's node model: each shell mode and the model mode of largest
/// MAC (`model` and `omega` name the model's columns).
fn frequency_section(rows: &[SpringFrequency], model: &str, omega: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "## Frequencies (matched by MAC)\n");
    let _ = writeln!(
        s,
        "| shell mode | ω shell [rad/s] | {model} | {omega} [rad/s] | MAC | error |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for r in rows {
        let opt = |x: Option<f64>, f: &dyn Fn(f64) -> String| x.map_or("—".to_string(), f);
        let _ = writeln!(
            s,
            "| {} | {:.6} | {} | {} | {} | {} |",
            r.mode,
            r.shell,
            r.msm_mode.map_or("—".to_string(), |m| m.to_string()),
            opt(r.msm, &|w| format!("{w:.6}")),
            opt(r.mac, &|m| format!("{m:.3}")),
            opt(r.relative_error, &|e| relative(e, true)),
        );
    }
    s
}

/// The small-motion section of a shell's node model.
fn small_motion_section(m: &SmallMotion) -> String {
    format!(
        "\n## Small motion\n\nBoth models linearized at rest, moved by {}, Newmark with Δt = \
         {:.4e} s over {:.0} periods of the lowest mode ({:.4e} s): the probe node {} against \
         the shell's point at its (u, v), relative RMS **{}**.\n\n",
        m.excitation,
        m.dt,
        m.periods,
        m.t_end,
        m.probe_node,
        relative(m.relative_rms, false)
    )
}

/// A relative error in percent, or in powers of ten below 10⁻⁴ (a reduction's round-off);
/// `signed` shows its sign.
fn relative(e: f64, signed: bool) -> String {
    match (e.abs() >= 1e-4, signed) {
        (true, true) => format!("{:+.2} %", 100.0 * e),
        (true, false) => format!("{:.2} %", 100.0 * e),
        (false, true) => format!("{e:+.1e}"),
        (false, false) => format!("{e:.1e}"),
    }
}

/// Reduces the shell of a Kirchhoff–Love scene onto its lattice nodes (`derive --derivation
/// reduction`); errors name the scene key they come from.
pub fn reduce_shell(
    scene: &Scene,
    choice: &DerivationChoice,
    cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
) -> Result<ShellReduction, Error> {
    let config = scene.springs_config(choice.method, choice.key)?;
    nurbspring_derive::reduce_shell(&config, cancel)
        .map_err(|e| scene.derive_error(crate::derivation::DERIVATION_KEY, e))
}

/// report.json of a shell's reduction.
#[derive(Serialize)]
pub struct ShellReductionReport<'a> {
    scene: &'a str,
    derivation: &'static str,
    #[serde(flatten)]
    detail: &'a ShellReduction,
}

impl<'a> ShellReductionReport<'a> {
    /// The report of `r`, derived from the scene `scene_label`.
    pub fn new(scene_label: &'a str, r: &'a ShellReduction) -> Self {
        Self {
            scene: scene_label,
            derivation: nurbspring_derive::Method::Reduction.name(),
            detail: r,
        }
    }
}

/// Writes every file of a shell's reduction into `out` (each atomically): `reduction.json`,
/// `report.json` and `report.md`.
pub fn write_shell_reduction(
    out: &Path,
    scene_label: &str,
    r: &ShellReduction,
) -> Result<(), Error> {
    write_json(
        out.join("reduction.json"),
        &crate::report::reduction_file(scene_label, &r.reduction, &r.node_velocities),
    )?;
    write_json(
        out.join("report.json"),
        &ShellReductionReport::new(scene_label, r),
    )?;
    let mut s = String::new();
    let _ = writeln!(s, "# Reduction of {scene_label} (derivation `reduction`)\n");
    let _ = writeln!(s, "**Verdict.** {}.\n", r.verdict);
    let _ = writeln!(
        s,
        "The Kirchhoff–Love shell linearized at rest (its tangent, consistent mass and damping \
         at the rest state) reduced {} onto the {} free lattice nodes' x, y and z ({} shell \
         unknowns; docs/math.md §11.4), written to `reduction.json`: a linear node-space model \
         with dense matrices, not a spring model. Size (bounding-box diagonal) {:.6e} m.\n",
        r.how(),
        r.free_nodes,
        r.shell_dofs,
        r.size
    );
    s.push_str(&frequency_section(
        &r.frequencies,
        "reduced mode",
        "ω reduced",
    ));
    s.push_str(&small_motion_section(&r.small_motion));
    let _ = writeln!(s, "## Large motion\n\nNot run: {}.", r.large_motion_skipped);
    nurbspring_io::atomic::write_atomic_bytes(out.join("report.md"), s.as_bytes())?;
    Ok(())
}
