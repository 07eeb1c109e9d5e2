//! Derivation results → files: `msm.json` (or `reduction.json`), `report.json` (serde from
//! the typed results, with the inputs that produced them, so a report stands on its own),
//! `report.md`, `central_node.csv`, plots, and the lattice as VTK and OBJ.

use std::path::Path;

use nurbspring_derive::paper::PaperReport;
use nurbspring_derive::{
    Derivation, FitDetail, FrequencyRow, InitialConditions, MassReport, Method, NodeReduction,
    ParameterSet, Regime, Spectrum, TimeSettings, Trajectory, Validation,
};
use nurbspring_dnurbs::{DnurbsOptions, Loads, MaterialModel};
use nurbspring_io::output::{write_csv, write_json};
use nurbspring_io::plot::{PlotOptions, Series, plot_series_with, plot_spectrum};
use nurbspring_msm::{Class, Constants, FileSimulation, MsmFile, SpringKind};
use nurbspring_sim::IntegratorKind;
use serde::Serialize;

use crate::export::{write_lattice_obj, write_lattice_vtu};
use crate::markdown::report_markdown;
use crate::msm_file::msm_file;
use crate::spec::{ConstraintsSpec, FitSpec, MsmSpec};
use crate::{Error, Scene};

/// The inputs of a derivation, as the models saw them.
#[derive(Serialize)]
pub struct Inputs<'a> {
    /// `[material]`.
    pub material: &'a MaterialModel,
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
    /// Parameter u (of the node, where the D-NURBS is watched).
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
    /// The derivation.
    pub derivation: Method,
    /// What produced it.
    pub inputs: Inputs<'a>,
    /// The fit.
    pub fit: &'a FitDetail,
    /// The masses and their totals.
    pub mass: &'a MassReport,
    /// The derived parameters, their stability and validation.
    pub derived: &'a ParameterSet,
    /// The derived model's validation (as in `derived`).
    pub validation: &'a Validation,
    /// The validation under an impulse the model was not derived for.
    pub second_excitation: &'a Validation,
    /// The lowest frequencies of both models.
    pub frequencies: &'a [FrequencyRow],
    /// The regime the model may be used in (report.md's verdict).
    pub regime: &'a Regime,
    /// Frequencies of both models.
    pub spectrum: &'a Spectrum,
    /// Probe points.
    pub probes: Vec<Probe>,
    /// The scene's own `[msm]` parameters, evaluated the same way (the paper's derivation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_parameters: Option<&'a ParameterSet>,
    /// The paper's reproduction (`nurbspring paper` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper: Option<&'a PaperReport>,
    /// Every sign of a bad model.
    pub warnings: &'a [String],
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
            derivation: d.method(),
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
            second_excitation: &d.second_excitation,
            frequencies: &d.frequencies,
            regime: &d.regime,
            spectrum: &d.spectrum,
            probes: d
                .probes
                .iter()
                .zip(&d.probe_nodes)
                .map(|(&(u, v), &node)| Probe { u, v, node })
                .collect(),
            paper_parameters: d.given.as_ref(),
            paper,
            warnings: &d.warnings,
        }
    }
}

/// `reduction.json`: the node-space model `M_T ẍ + (γ/μ) M_T ẋ + K_T x = F_T` of the
/// `reduction` derivation on the free nodes: scalar and the same in x, y and z (the tension
/// plate), or on their x, y and z interleaved (a shell), as `ordering` says.
#[derive(Serialize)]
pub struct ReductionFile<'a> {
    /// The scene.
    pub scene: &'a str,
    /// `"exact"` (one free node per free control point) or `"guyan"`.
    pub kind: &'static str,
    /// What the matrices act on.
    pub ordering: &'static str,
    /// Every node: rest position, parameters, fixed flag.
    pub nodes: Vec<ReductionNode>,
    /// The free nodes, in the order of the matrices' rows.
    pub free: &'a [usize],
    /// `K_T`, row by row.
    pub stiffness: Vec<Vec<f64>>,
    /// `M_T`, row by row.
    pub mass: Vec<Vec<f64>>,
    /// `γ/μ`.
    pub damping_ratio: f64,
    /// `F_T` per free node.
    pub loads: &'a [[f64; 3]],
    /// Initial node velocities `Ω ṗ(0)`, every node.
    pub initial_velocities: &'a [[f64; 3]],
}

/// One node of `reduction.json`.
#[derive(Serialize)]
pub struct ReductionNode {
    /// Rest position.
    pub position: [f64; 3],
    /// Parameters.
    pub uv: [f64; 2],
    /// Held at its rest position.
    pub fixed: bool,
}

/// The `reduction.json` of a node reduction `r` derived from the scene `scene`, with every
/// node's initial velocity.
pub fn reduction_file<'a>(
    scene: &'a str,
    r: &'a NodeReduction,
    velocities: &'a [[f64; 3]],
) -> ReductionFile<'a> {
    let rows = |m: &nurbspring_linalg::DenseMatrix| -> Vec<Vec<f64>> {
        (0..m.nrows()).map(|i| m.row(i).to_vec()).collect()
    };
    ReductionFile {
        scene,
        kind: if r.guyan { "guyan" } else { "exact" },
        ordering: r.coordinates.ordering(),
        nodes: r
            .positions
            .iter()
            .zip(&r.params)
            .enumerate()
            .map(|(a, (&position, &(u, v)))| ReductionNode {
                position,
                uv: [u, v],
                fixed: r.free.binary_search(&a).is_err(),
            })
            .collect(),
        free: &r.free,
        stiffness: rows(&r.stiffness),
        mass: rows(&r.mass),
        damping_ratio: r.damping_ratio,
        loads: &r.loads,
        initial_velocities: velocities,
    }
}

/// Writes a plot (SVG or PNG by extension), optionally with a logarithmic y axis.
fn plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    (log_x, log_y): (bool, bool),
) -> Result<(), Error> {
    let mut options = PlotOptions::new(title, x_label, y_label);
    options.log_x = log_x;
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

/// How the derived MSM is run by `simulate msm.json`: as it was validated.
fn run_settings(scene: &Scene, d: &Derivation) -> FileSimulation {
    let time = scene.time_settings();
    FileSimulation {
        dt: time.dt,
        t_end: time.t_end,
        integrator: IntegratorKind::parse(&d.derived.validation.integrator)
            .unwrap_or(IntegratorKind::Newmark),
    }
}

/// The `msm.json` of a derivation with a lattice (`None` for a node reduction): the lattice,
/// the scene it came from, its initial velocities and the run settings it was validated with.
pub fn derived_msm_file(scene_label: &str, scene: &Scene, d: &Derivation) -> Option<MsmFile> {
    d.lattice().map(|lattice| {
        msm_file(
            lattice,
            scene_label,
            &d.node_velocities,
            run_settings(scene, d),
            &d.probe_nodes,
        )
    })
}

/// Writes msm.json (or reduction.json), report.json, report.md, central_node.csv, the plots
/// and the lattice into `out` (each file atomically). `paper_table` is the text of the
/// reproduction table (empty unless this is the paper's experiment).
pub fn write_derivation(
    out: &Path,
    scene_label: &str,
    scene: &Scene,
    d: &Derivation,
    paper: Option<&PaperReport>,
    paper_table: &str,
) -> Result<(), Error> {
    write_derived_files(out, scene_label, scene, d)?;
    write_reports(out, scene_label, scene, d, paper, paper_table)
}

/// The files of [`write_derivation`] that depend on the derivation alone: `msm.json` and the
/// lattice (or `reduction.json`), `central_node.csv` and the plots. `paper` writes them while
/// its readings run.
pub fn write_derived_files(
    out: &Path,
    scene_label: &str,
    scene: &Scene,
    d: &Derivation,
) -> Result<(), Error> {
    write_derived_files_with(out, scene_label, scene, d, &[])
}

/// [`write_derived_files`] with more curves on the central node's figure, `(legend, run)`
/// (the paper job adds the default derivation's MSM).
pub fn write_derived_files_with(
    out: &Path,
    scene_label: &str,
    scene: &Scene,
    d: &Derivation,
    extra: &[(String, &Trajectory)],
) -> Result<(), Error> {
    if let Some(lattice) = d.lattice() {
        let msm = derived_msm_file(scene_label, scene, d).expect("the derivation has a lattice");
        write_json(out.join("msm.json"), &msm)?;
        write_lattice_obj(&out.join("lattice.obj"), lattice)?;
        write_lattice_vtu(&out.join("lattice.vtu"), lattice)?;
    }
    if let Some(r) = d.reduction() {
        write_json(
            out.join("reduction.json"),
            &reduction_file(scene_label, r, &d.node_velocities),
        )?;
    }
    write_central_node(out, d, !scene.geometry.is_surface())?;
    write_plots(out, scene_label, d, extra)
}

/// The reports of [`write_derivation`]: `report.json` and `report.md` (with the paper's
/// readings and verdict table when given).
pub fn write_reports(
    out: &Path,
    scene_label: &str,
    scene: &Scene,
    d: &Derivation,
    paper: Option<&PaperReport>,
    paper_table: &str,
) -> Result<(), Error> {
    write_json(
        out.join("report.json"),
        &Report::new(scene_label, scene, d, paper),
    )?;
    let md = report_markdown(scene_label, d, paper_table);
    nurbspring_io::atomic::write_atomic_bytes(out.join("report.md"), md.as_bytes())?;
    Ok(())
}

/// `central_node.csv`: t, then the D-NURBS point and the MSM node, x, y, z.
fn write_central_node(out: &Path, d: &Derivation, curve: bool) -> Result<(), Error> {
    let t = &d.dnurbs_trajectory.t;
    let (a, b) = (&d.dnurbs_trajectory.probes[0], &d.msm_trajectory.probes[0]);
    let rows = (0..t.len().min(a.len()).min(b.len())).map(|s| {
        let mut row = vec![t[s]];
        row.extend_from_slice(&a[s]);
        row.extend_from_slice(&b[s]);
        row
    });
    // Where both are watched: the D-NURBS at the central node's own parameters.
    let uv = d.probes.first().copied();
    let at = crate::run::probe_label(None, uv, curve);
    let node = crate::run::probe_label(d.probe_nodes.first().copied(), uv, curve);
    let mut header = vec!["t".to_string()];
    for (name, label) in [("dnurbs", &at), ("msm", &node)] {
        for c in ["x", "y", "z"] {
            header.push(format!("{name}_{c}[{label}]"));
        }
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    write_csv(out.join("central_node.csv"), &header, rows)?;
    Ok(())
}

fn xy(t: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    t.iter().copied().zip(y.iter().copied()).collect()
}

/// The coordinate in which the D-NURBS central point moves most.
fn main_axis(traj: &Trajectory) -> usize {
    let p = &traj.probes[0];
    let p0 = p.first().copied().unwrap_or([0.0; 3]);
    (0..3)
        .max_by(|&x, &y| {
            let span = |c: usize| p.iter().map(|q| (q[c] - p0[c]).abs()).fold(0.0, f64::max);
            span(x).total_cmp(&span(y))
        })
        .unwrap_or(2)
}

/// The mass-scan point of the selected mass `m`: the candidate nearest to it (`None` when the
/// scan is empty or `m` is not finite).
fn selected_point(scan: &[(f64, f64)], m: f64) -> Option<(f64, f64)> {
    if !m.is_finite() {
        return None;
    }
    scan.iter()
        .copied()
        .min_by(|a, b| (a.0 - m).abs().total_cmp(&(b.0 - m).abs()))
}

/// The energy plot's two curves of one model: the total (kinetic + elastic + load potential)
/// and the kinetic energy, both divided by the model's largest kinetic + elastic energy over
/// the run, so models whose masses differ by orders of magnitude share one axis (an MSM's
/// energy no longer a flat line at 0 next to the D-NURBS'); a model that never moves is not
/// scaled.
fn energy_series(name: &str, traj: &Trajectory) -> Vec<Series> {
    let scale = traj
        .energy
        .iter()
        .map(|e| e[0] + e[1])
        .filter(|x| x.is_finite())
        .fold(0.0_f64, f64::max);
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let curve = |f: &dyn Fn(&[f64; 3]) -> f64| -> Vec<(f64, f64)> {
        traj.t
            .iter()
            .zip(&traj.energy)
            .map(|(t, e)| (*t, f(e) / scale))
            .collect()
    };
    vec![
        Series::line(
            format!("{name} total (kinetic + elastic + load)"),
            curve(&|e| e[0] + e[1] + e[2]),
        ),
        Series::line(format!("{name} kinetic"), curve(&|e| e[0])),
    ]
}

/// The result line of `derive`: what was derived, its constants and masses, the explicit
/// step limit and the validation.
pub fn derivation_line(derivation: &Derivation) -> String {
    let d = &derivation.derived;
    // What was derived: an MSM, or the exact reduction (a linear model, not an MSM).
    let what = match derivation.method() {
        Method::Reduction => format!(
            "exact reduction onto {} free nodes (reduction.json: a linear node-space model, not an MSM; the reference an MSM is judged against)",
            derivation.reduction().map_or(0, |r| r.free.len())
        ),
        m => format!("derived MSM ({})", m.name()),
    };
    let mut parts = Vec::new();
    let constants = constants_text(&d.constants, 6);
    if !constants.is_empty() {
        parts.push(constants);
    }
    parts.push(mass_text(derivation, d.m));
    format!(
        "{what}: {}; dt_critical = {:.5}; central node rel. RMS = {} over {:.3} s ({}), second excitation {:.4}",
        parts.join(", "),
        d.dt_critical,
        if d.validation.relative_rms.is_nan() {
            "n/a".to_string()
        } else {
            format!("{:.4}", d.validation.relative_rms)
        },
        d.validation.horizon,
        d.validation.integrator,
        derivation.second_excitation.relative_rms
    )
}

/// The node masses of a derivation's result: one `m` when every free node has it, else their
/// range and mean (the linear derivations fit one mass per node); the reduction's total.
fn mass_text(derivation: &Derivation, m: f64) -> String {
    let free: Vec<f64> = match derivation.lattice() {
        Some(l) => l
            .masses
            .iter()
            .zip(&l.fixed)
            .filter(|(_, f)| !**f)
            .map(|(m, _)| *m)
            .collect(),
        None => {
            return format!(
                "free mass {:.6} (M_T, against the D-NURBS's {:.6})",
                derivation.mass.free_msm, derivation.mass.free_dnurbs
            );
        }
    };
    let (lo, hi) = free
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if free.is_empty() || lo == hi {
        format!("m = {m:.6}")
    } else {
        format!(
            "node masses {lo:.6} to {hi:.6} (mean {:.6} over {} free nodes)",
            free.iter().sum::<f64>() / free.len() as f64,
            free.len()
        )
    }
}

/// How a parameter set's validation run was made, as the figures say it: the integrator, its
/// substeps when an explicit scheme was kept below its stability limit, and what plain steps
/// did (`symplectic-euler in 3 substeps of dt/3 (plain steps diverge)`).
pub fn how_run(p: &nurbspring_derive::ParameterSet) -> String {
    let v = &p.validation;
    let mut s = if v.substeps > 1 {
        format!(
            "{} in {} substeps of dt/{}",
            v.integrator, v.substeps, v.substeps
        )
    } else {
        v.integrator.clone()
    };
    if let Some(plain) = &p.explicit_run {
        if plain.relative_rms.is_finite() {
            s.push_str(&format!(
                " (plain steps: rel. RMS {:.3})",
                plain.relative_rms
            ));
        } else {
            s.push_str(" (plain steps diverge)");
        }
    }
    s.push_str(&format!(", rel. RMS {:.3}", v.relative_rms));
    s
}

/// One plot file to write.
type PlotJob<'a> = Box<dyn Fn() -> Result<(), Error> + Send + Sync + 'a>;

/// The spectrum figure shows at most this many modes (the count is in its title).
const SPECTRUM_SHOWN: usize = 50;

/// central_node, mass_scan, energy and spectrum plots, SVG and PNG. The eight files are
/// independent, so they are drawn in parallel (rayon's pool); the first error in the order
/// above is returned.
fn write_plots(
    out: &Path,
    scene_label: &str,
    d: &Derivation,
    extra: &[(String, &Trajectory)],
) -> Result<(), Error> {
    use rayon::prelude::*;
    let axis = main_axis(&d.dnurbs_trajectory);
    let name = ["x", "y", "z"][axis];
    let t = &d.dnurbs_trajectory.t;
    let mut central = vec![
        Series::line("D-NURBS", xy(t, &d.dnurbs_trajectory.component(0, axis))),
        Series::line(
            format!(
                "MSM of the {} derivation: {}",
                d.method().name(),
                how_run(&d.derived)
            ),
            xy(&d.msm_trajectory.t, &d.msm_trajectory.component(0, axis)),
        ),
    ];
    if let (Some(g), Some(gt)) = (&d.given, &d.given_trajectory) {
        let k = |class| g.constants.value(class);
        central.push(Series::line(
            format!(
                "scene's MSM k_edge={}, k_diag={}, k_bend={}, m={}: {}",
                k(Class::Spring(SpringKind::Structural)),
                k(Class::Spring(SpringKind::Shear)),
                k(Class::Spring(SpringKind::Bend)),
                g.m,
                how_run(g)
            ),
            xy(&gt.t, &gt.component(0, axis)),
        ));
    }
    for (name, run) in extra {
        central.push(Series::line(
            name.clone(),
            xy(&run.t, &run.component(0, axis)),
        ));
    }
    let central_title = format!("Central node {name}(t) of {scene_label}: D-NURBS vs MSM");
    let y_label = format!("{name} [m]");
    let scan: Vec<(f64, f64)> = d
        .mass
        .candidates
        .iter()
        .filter(|c| c.rms.is_finite() && c.rms > 0.0)
        .map(|c| (c.m, c.rms))
        .collect();
    let pruned: Vec<(f64, f64)> = d
        .mass
        .candidates
        .iter()
        .filter_map(|c| c.pruned.map(|p| (c.m, p.rms_at_least)))
        .filter(|&(_, bound)| bound.is_finite() && bound > 0.0)
        .collect();
    let mut scan_series = vec![Series::points("candidates", scan.clone())];
    if !pruned.is_empty() {
        scan_series.push(Series::points(
            "stopped early: lower bound of the RMS",
            pruned,
        ));
    }
    if let Some(chosen) = selected_point(&scan, d.mass.selected) {
        scan_series.push(Series::points(
            format!("selected m = {:.6}", d.mass.selected),
            vec![chosen],
        ));
    }
    let energy: Vec<Series> = [
        ("D-NURBS", &d.dnurbs_trajectory),
        ("MSM", &d.msm_trajectory),
    ]
    .into_iter()
    .filter(|(_, t)| !t.energy.is_empty())
    .flat_map(|(name, t)| energy_series(name, t))
    .collect();
    let energy_title =
        format!("Energy over time, {scene_label}, each model relative to its own scale");
    let modes = d.spectrum.dnurbs.len().max(d.spectrum.msm.len());
    let spectrum_title = if modes > SPECTRUM_SHOWN {
        format!(
            "Lowest {SPECTRUM_SHOWN} of {modes} angular frequencies of {scene_label}: D-NURBS vs MSM (at rest)"
        )
    } else {
        format!("Angular frequencies of {scene_label}: D-NURBS vs MSM (at rest)")
    };
    // A model above the dense eigen-solve's size has no spectrum: it is named in the title
    // rather than left as an empty legend entry.
    let spectrum_title = if d.spectrum.msm.is_empty() {
        format!(
            "{spectrum_title}; MSM not computed (over {} dofs)",
            nurbspring_derive::MAX_SPECTRUM_DOFS
        )
    } else {
        spectrum_title
    };
    let shown = |v: &[f64]| v[..v.len().min(SPECTRUM_SHOWN)].to_vec();
    let (spectrum_dnurbs, spectrum_msm) = (shown(&d.spectrum.dnurbs), shown(&d.spectrum.msm));
    let msm_name = format!("MSM of the {} derivation", d.method().name());

    let mut jobs: Vec<PlotJob<'_>> = Vec::new();
    for ext in ["svg", "png"] {
        let (central, central_title, y_label) = (&central, &central_title, &y_label);
        jobs.push(Box::new(move || {
            plot(
                &out.join(format!("central_node.{ext}")),
                central_title,
                "t [s]",
                y_label,
                central,
                (false, false),
            )
        }));
    }
    if !scan.is_empty() {
        for ext in ["svg", "png"] {
            let scan_series = &scan_series;
            jobs.push(Box::new(move || {
                plot(
                    &out.join(format!("mass_scan.{ext}")),
                    "Mass candidates: eigenvalues of M vs RMS error of the central node",
                    "node mass m [kg] (an eigenvalue of M)",
                    "RMS error [m]",
                    scan_series,
                    (true, true),
                )
            }));
        }
    }
    if !energy.is_empty() {
        for ext in ["svg", "png"] {
            let (energy, energy_title) = (&energy, &energy_title);
            jobs.push(Box::new(move || {
                plot(
                    &out.join(format!("energy.{ext}")),
                    energy_title,
                    "t [s]",
                    "energy / largest kinetic + elastic energy of the model",
                    energy,
                    (false, false),
                )
            }));
        }
    }
    if !d.spectrum.dnurbs.is_empty() {
        for ext in ["svg", "png"] {
            let (spectrum_title, spectrum_dnurbs, spectrum_msm, msm_name) =
                (&spectrum_title, &spectrum_dnurbs, &spectrum_msm, &msm_name);
            jobs.push(Box::new(move || {
                plot_spectrum(
                    out.join(format!("spectrum.{ext}")),
                    spectrum_title,
                    "omega [rad/s]",
                    &[
                        ("D-NURBS", spectrum_dnurbs.as_slice()),
                        (msm_name.as_str(), spectrum_msm.as_slice()),
                    ]
                    .into_iter()
                    .filter(|(_, values)| !values.is_empty())
                    .collect::<Vec<_>>(),
                )?;
                Ok(())
            }));
        }
    }
    jobs.par_iter()
        .map(|job| job())
        .collect::<Vec<_>>()
        .into_iter()
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both curves of a model are divided by its largest kinetic + elastic energy; the total
    /// includes the load potential.
    #[test]
    fn energy_series_are_relative_to_the_model_scale() {
        let traj = Trajectory {
            t: vec![0.0, 1.0, 2.0],
            probes: vec![],
            energy: vec![[4.0, 0.0, 0.0], [1.0, 2.0, -1.0], [0.0, 5.0, -2.0]],
            ..Trajectory::default()
        };
        let s = energy_series("MSM", &traj);
        assert_eq!(s[0].name, "MSM total (kinetic + elastic + load)");
        assert_eq!(s[0].points, vec![(0.0, 0.8), (1.0, 0.4), (2.0, 0.6)]);
        assert_eq!(s[1].name, "MSM kinetic");
        assert_eq!(s[1].points, vec![(0.0, 0.8), (1.0, 0.2), (2.0, 0.0)]);
        // A model at rest throughout is not scaled.
        let rest = Trajectory {
            energy: vec![[0.0, 0.0, 0.0]; 3],
            ..traj
        };
        assert_eq!(energy_series("x", &rest)[0].points[2], (2.0, 0.0));
    }

    #[test]
    fn selected_point_is_the_nearest_candidate() {
        let scan = [(0.001, 3.0), (0.005, 1.0), (0.02, 2.0)];
        assert_eq!(selected_point(&scan, 0.0049), Some((0.005, 1.0)));
        assert_eq!(selected_point(&scan, f64::NAN), None);
        assert_eq!(selected_point(&[], 1.0), None);
    }
}
