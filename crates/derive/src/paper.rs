//! Reproduction of the paper's Section IV: every number the paper reports beside what the
//! mathematics gives under each reading of the paper (docs/math.md §7), with a verdict per
//! line. Readings are enums, thresholds are named constants, and every sentence of a verdict
//! is built from the numbers measured here.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use nurbspring_dnurbs::{Geometry, RestShape};
use nurbspring_geom::{GeomError, NurbsSurface};
use nurbspring_msm::{Class, Constants, SpringKind};
use nurbspring_sim::{IntegratorKind, Schedule};
use rayon::prelude::*;
use serde::Serialize;

use crate::DeriveError;
use crate::beyond::{Beyond, beyond};
use crate::fit::FitDofs;
use crate::fit::FitResult;
use crate::outcome::{Derivation, MassReport};
use crate::pipeline::derive_msm;
use crate::setup::{Config, Setup};
use crate::validation::{compare, dominant_period};

mod verdicts;
use verdicts::*;

/// The paper's node mass.
pub const PAPER_M: f64 = 0.005;
/// The paper's structural spring constant.
pub const PAPER_K_EDGE: f64 = 2.7225;
/// The paper's shear spring constant.
pub const PAPER_K_DIAG: f64 = 0.8661;

/// A constant within this relative difference of the paper's is reproduced.
pub const REPRODUCED: f64 = 5e-4;
/// Within this relative difference it is partly reproduced.
pub const PARTLY: f64 = 0.05;
/// An eigenvalue of M within this relative difference of the paper's mass matches it.
pub const MASS_MATCH: f64 = 0.1;
/// Relative RMS of the central node below this is agreement.
pub const AGREEMENT: f64 = 0.1;
/// An in-plane drift below this is none.
pub const NO_DRIFT: f64 = 1e-9;
/// A share of the stiffness along the surface normal below this is none (round-off).
pub const NO_NORMAL_STIFFNESS: f64 = 1e-12;
/// The longer horizon, in multiples of the paper's 4 s.
pub const LONG_HORIZON: f64 = 10.0;

/// The paper's constants.
pub fn paper_constants() -> Constants {
    Constants::from_pairs([
        (Class::Spring(SpringKind::Structural), PAPER_K_EDGE),
        (Class::Spring(SpringKind::Shear), PAPER_K_DIAG),
    ])
}

/// Which control net: as printed in the paper, or at the Greville abscissae (docs/math.md §7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ControlNet {
    /// `P_x × P_y × {z}` as printed.
    Printed,
    /// Control points at the Greville abscissae, scaled to the net's extent: the flat sheet is
    /// then parametrized linearly, an exact rest state even for the literal energy.
    Greville,
}

impl ControlNet {
    /// Both nets, printed first.
    pub const ALL: [ControlNet; 2] = [ControlNet::Printed, ControlNet::Greville];

    /// "printed" or "greville".
    pub fn name(self) -> &'static str {
        match self {
            ControlNet::Printed => "printed",
            ControlNet::Greville => "greville",
        }
    }
}

/// The norm of eq. (15): Frobenius (docs/math.md §6) or spectral (the paper writes `‖·‖₂²`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Norm {
    /// `‖·‖_F`.
    Frobenius,
    /// The largest singular value.
    Spectral,
}

impl Norm {
    /// "frobenius" or "spectral".
    pub fn name(self) -> &'static str {
        match self {
            Norm::Frobenius => "frobenius",
            Norm::Spectral => "spectral",
        }
    }
}

/// Whose MSM parameters a run uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Parameters {
    /// The paper's k_edge, k_diag and m.
    Paper,
    /// The ones nurbspring derives.
    Derived,
}

impl Parameters {
    /// "paper" or "derived".
    pub fn name(self) -> &'static str {
        match self {
            Parameters::Paper => "paper",
            Parameters::Derived => "derived",
        }
    }
}

/// The surface with its control points moved to the Greville abscissae of its knot vectors,
/// scaled to the bounding box of the net in x and y (z kept).
pub fn greville_net(surface: &NurbsSurface) -> Result<NurbsSurface, DeriveError> {
    let cps = surface.control_points();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in cps {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let gu = surface.basis_u().knots().greville();
    let gv = surface.basis_v().knots().greville();
    let ((u0, u1), (v0, v1)) = surface.domain();
    let mut out = Vec::with_capacity(cps.len());
    for (i, xi) in gu.iter().enumerate() {
        for (j, eta) in gv.iter().enumerate() {
            let z = cps[surface.index(i, j)][2];
            out.push([
                x0 + (x1 - x0) * (xi - u0) / (u1 - u0),
                y0 + (y1 - y0) * (eta - v0) / (v1 - v0),
                z,
            ]);
        }
    }
    Ok(surface.with_control_points(out)?)
}

/// One reading of eq. (15).
#[derive(Clone, Debug, Serialize)]
pub struct FitReading {
    /// Control net.
    pub net: ControlNet,
    /// Dofs entering the fit.
    pub dofs: FitDofs,
    /// `k ≥ 0` imposed.
    pub nonnegative: bool,
    /// The norm.
    pub norm: Norm,
    /// Constants found.
    pub result: FitResult,
    /// Residual of the same reading at the paper's constants.
    pub residual_at_paper_values: f64,
}

impl FitReading {
    /// "printed net, free dofs, k>=0, spectral norm".
    pub fn label(&self) -> String {
        format!(
            "{} net, {} dofs{}{}",
            self.net.name(),
            self.dofs.name(),
            if self.nonnegative { ", k>=0" } else { "" },
            if self.norm == Norm::Spectral {
                ", spectral norm"
            } else {
                ""
            }
        )
    }
}

/// One side-by-side run of the two models.
#[derive(Clone, Debug, Serialize)]
pub struct DynamicsReading {
    /// Control net.
    pub net: ControlNet,
    /// D-NURBS rest shape: "initial" (displacement form) or "zero" (literal energy).
    pub rest_shape: RestShape,
    /// Whose MSM parameters.
    pub parameters: Parameters,
    /// The constants used (`k_edge`, `k_diag`).
    #[serde(flatten)]
    pub constants: Constants,
    /// Node mass used.
    pub m: f64,
    /// MSM integrator.
    pub integrator: IntegratorKind,
    /// Length of the run [s].
    pub t_end: f64,
    /// Explicit stability limit of this MSM.
    pub dt_critical: f64,
    /// RMS of the central node's z difference (left out of report.json when the MSM run
    /// stopped: see `msm_stopped`).
    #[serde(skip_serializing_if = "crate::outcome::not_finite")]
    pub rms: f64,
    /// RMS relative to the D-NURBS amplitude.
    #[serde(skip_serializing_if = "crate::outcome::not_finite")]
    pub relative_rms: f64,
    /// D-NURBS amplitude of the central node in z.
    pub dnurbs_amplitude: f64,
    /// D-NURBS period.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dnurbs_period: Option<f64>,
    /// MSM period.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm_period: Option<f64>,
    /// Largest in-plane drift of the D-NURBS central point, `max |(x, y) − (x₀, y₀)|`.
    pub dnurbs_in_plane_drift: f64,
    /// Why the MSM run stopped early, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm_stopped: Option<String>,
}

/// Verdict of one paper number.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Obtained to the precision printed.
    Reproduced,
    /// Obtained under some readings only, or approximately.
    Partly,
    /// Not obtained under any reading tried.
    NotReproduced,
}

impl Verdict {
    /// Text for tables.
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Reproduced => "reproduced",
            Verdict::Partly => "partly",
            Verdict::NotReproduced => "not reproduced",
        }
    }
}

/// One line of the reproduction table.
#[derive(Clone, Debug, Serialize)]
pub struct VerdictLine {
    /// The quantity.
    pub quantity: String,
    /// What the paper reports.
    pub paper: String,
    /// What nurbspring obtains, per reading.
    pub obtained: String,
    /// The verdict.
    pub verdict: Verdict,
    /// Why, with the evidence.
    pub why: String,
}

/// Which mass matrix an eigenvalue comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum MassMatrix {
    /// Every dof.
    #[serde(rename = "M (all dofs)")]
    AllDofs,
    /// The free dofs.
    #[serde(rename = "M (free dofs)")]
    FreeDofs,
}

impl MassMatrix {
    /// "M (all dofs)" or "M (free dofs)".
    pub fn name(self) -> &'static str {
        match self {
            MassMatrix::AllDofs => "M (all dofs)",
            MassMatrix::FreeDofs => "M (free dofs)",
        }
    }
}

/// Nearest eigenvalue of M to the paper's mass.
#[derive(Clone, Debug, Serialize)]
pub struct NearestEigenvalue {
    /// Which matrix.
    pub matrix: MassMatrix,
    /// The eigenvalue nearest to 0.005.
    pub value: f64,
    /// Its rank among the distinct eigenvalues, 1 = smallest.
    pub rank: usize,
    /// How many distinct eigenvalues there are.
    pub count: usize,
    /// `|λ − 0.005| / 0.005`.
    pub relative_difference: f64,
}

/// Facts about the lattice that the verdicts cite.
#[derive(Clone, Debug, Serialize)]
pub struct LatticeFacts {
    /// `‖N K_S N‖_F / ‖K_S‖_F` at the paper's constants, N projecting each node's
    /// displacement on the surface normal there: the share of the linearized stiffness that
    /// acts out of the surface.
    pub normal_stiffness_share: f64,
    /// Zero frequencies of the derived MSM linearized at rest.
    pub msm_zero_frequencies: usize,
    /// Frequencies of the derived MSM linearized at rest.
    pub msm_frequencies: usize,
}

/// The whole reproduction.
#[derive(Clone, Debug, Serialize)]
pub struct PaperReport {
    /// Every reading of eq. (15).
    pub fits: Vec<FitReading>,
    /// Eigenvalues of M nearest to the paper's mass.
    pub mass_nearest: Vec<NearestEigenvalue>,
    /// Every side-by-side run.
    pub dynamics: Vec<DynamicsReading>,
    /// Facts about the lattice.
    pub lattice: LatticeFacts,
    /// The verdicts, one per paper number.
    pub verdicts: Vec<VerdictLine>,
    /// The default derivation beside the paper's, on the paper's scene.
    pub beyond: Beyond,
}

fn with_net(base: &Config, net: ControlNet) -> Result<Config, DeriveError> {
    let mut c = base.clone();
    if net == ControlNet::Greville
        && let Geometry::Surface(s) = &base.geometry
    {
        c.geometry = Geometry::Surface(greville_net(s)?);
    }
    Ok(c)
}

/// Every reading of eq. (15) on one net.
fn fit_readings(setup: &Setup, net: ControlNet) -> Result<Vec<FitReading>, DeriveError> {
    let paper = paper_constants();
    // The two dof selections are independent: they run in parallel, in this order.
    let per_dofs = [FitDofs::All, FitDofs::Free]
        .par_iter()
        .map(|&dofs| -> Result<Vec<FitReading>, DeriveError> {
            let mut out = Vec::new();
            let fit = setup.fit(dofs)?;
            let paper_k = paper.values_of(fit.classes());
            let at_paper = fit.relative_residual(&paper_k)?;
            for nonnegative in [false, true] {
                out.push(FitReading {
                    net,
                    dofs,
                    nonnegative,
                    norm: Norm::Frobenius,
                    result: setup.solve(dofs, nonnegative)?,
                    residual_at_paper_values: at_paper,
                });
            }
            let (k, residual) = fit.solve_spectral()?;
            out.push(FitReading {
                net,
                dofs,
                nonnegative: false,
                norm: Norm::Spectral,
                result: FitResult {
                    constants: fit.constants(&k),
                    relative_residual: residual,
                },
                residual_at_paper_values: fit.relative_spectral_residual(&paper_k)?,
            });
            Ok(out)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(per_dofs.into_iter().flatten().collect())
}

/// The eigenvalue of each mass matrix nearest to the paper's mass.
fn nearest_eigenvalues(main: &Derivation) -> Vec<NearestEigenvalue> {
    [
        (MassMatrix::AllDofs, &main.mass.eigenvalues),
        (MassMatrix::FreeDofs, &main.mass.eigenvalues_free_dofs),
    ]
    .into_iter()
    .filter(|(_, ev)| !ev.is_empty())
    .map(|(matrix, ev)| {
        let (rank, value) = ev
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - PAPER_M).abs().total_cmp(&(b.1 - PAPER_M).abs()))
            .map(|(i, &v)| (i + 1, v))
            .unwrap_or((0, f64::NAN));
        NearestEigenvalue {
            matrix,
            value,
            rank,
            count: ev.len(),
            relative_difference: (value - PAPER_M).abs() / PAPER_M,
        }
    })
    .collect()
}

/// Side-by-side runs on one net and rest shape, with both parameter sets and both an
/// explicit and an implicit MSM integrator, over the paper's horizon (and, on the default
/// reading, [`LONG_HORIZON`] times longer).
fn dynamics_readings(
    base: &Config,
    net: ControlNet,
    rest: RestShape,
    derived: (&Constants, f64),
) -> Result<Vec<DynamicsReading>, DeriveError> {
    let mut config = with_net(base, net)?;
    config.dnurbs.rest_shape = rest;
    let setup = Setup::new(&config)?;
    let horizons: &[f64] = if net == ControlNet::Printed && rest == RestShape::Initial {
        &[config.time.t_end, LONG_HORIZON * config.time.t_end]
    } else {
        &[config.time.t_end]
    };
    let explicit = if base.time.msm_integrator.is_explicit() {
        base.time.msm_integrator
    } else {
        IntegratorKind::SymplecticEuler
    };
    let paper = paper_constants();
    let mut out = Vec::new();
    for &t_end in horizons {
        let dn = setup.run_dnurbs(config.time.dnurbs_integrator, config.time.dt, t_end, None)?;
        let z_ref = dn.component(0, 2);
        let p0 = dn.probes[0][0];
        let drift = dn.probes[0]
            .iter()
            .map(|p| (p[0] - p0[0]).hypot(p[1] - p0[1]))
            .fold(0.0, f64::max);
        for (parameters, constants, m) in [
            (Parameters::Paper, &paper, PAPER_M),
            (Parameters::Derived, derived.0, derived.1),
        ] {
            let (_, dt_critical) = setup.stability(constants, m)?;
            for integrator in [explicit, IntegratorKind::Newmark] {
                let traj = setup.run_msm(
                    setup.lattice_with(constants, m),
                    (Schedule::plain(integrator), None),
                    config.time.dt,
                    t_end,
                    true,
                    None,
                )?;
                let c = compare(&dn.t, &z_ref, &traj.component(0, 2));
                let failed = traj.stopped.is_some();
                out.push(DynamicsReading {
                    net,
                    rest_shape: rest,
                    parameters,
                    constants: constants.clone(),
                    m,
                    integrator,
                    t_end,
                    dt_critical,
                    rms: if failed { f64::INFINITY } else { c.rms },
                    relative_rms: if failed {
                        f64::INFINITY
                    } else {
                        c.relative_rms
                    },
                    dnurbs_amplitude: c.reference_amplitude,
                    dnurbs_period: dominant_period(&dn.t, &z_ref),
                    msm_period: if failed { None } else { c.other_period },
                    dnurbs_in_plane_drift: drift,
                    msm_stopped: traj.stopped.clone(),
                });
            }
        }
    }
    Ok(out)
}

/// The share of the lattice's linearized stiffness at the paper's constants that acts along
/// the surface normal at each node.
fn normal_stiffness_share(setup: &Setup) -> Result<f64, DeriveError> {
    let lattice = setup.lattice_with(&paper_constants(), PAPER_M);
    let Some(params) = &lattice.params else {
        return Err(DeriveError::LatticeWithoutParameters);
    };
    let nurbspring_dnurbs::Geometry::Surface(surface) = setup.model().geometry() else {
        return Ok(f64::NAN);
    };
    let mut normals = Vec::with_capacity(params.len());
    for &(u, v) in params {
        normals.push(match surface.normal(u, v) {
            Err(GeomError::DegenerateNormal { .. }) => [0.0; 3],
            n => n?,
        });
    }
    // (N K N)_ab = n_a (n_aᵀ K_ab n_b) n_bᵀ, whose Frobenius norm is |n_aᵀ K_ab n_b|.
    let k = lattice.tangent_stiffness(&lattice.flat_positions());
    let mut total = 0.0;
    let mut blocks = std::collections::HashMap::new();
    for (i, j, value) in k.triplets() {
        total += value * value;
        let (a, b) = (i / 3, j / 3);
        *blocks.entry((a, b)).or_insert(0.0) += normals[a][i % 3] * value * normals[b][j % 3];
    }
    let normal: f64 = blocks.values().map(|s| s * s).sum();
    Ok(if total > 0.0 {
        (normal / total).sqrt()
    } else {
        0.0
    })
}

/// Runs the paper's experiment from `base` (the paper's scene) under every reading of
/// docs/math.md §7 and returns the main derivation (printed net, the scene's options) and the
/// reproduction.
pub fn reproduce(
    base: &Config,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Derivation, PaperReport), DeriveError> {
    reproduce_cancellable(base, None, progress)
}

/// [`reproduce`] that stops with [`DeriveError::Cancelled`] soon after `cancel` is set: the
/// main derivation checks it at every step, the readings between them.
pub fn reproduce_cancellable(
    base: &Config,
    cancel: Option<Arc<AtomicBool>>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(Derivation, PaperReport), DeriveError> {
    let (main, main_setup) = derive_msm(base, cancel.clone(), progress)?;
    let report = readings(base, &main, &main_setup, cancel)?;
    Ok((main, report))
}

/// The second half of [`reproduce_cancellable`]: every reading of the paper's experiment
/// around the main derivation `main` (of [`derive_msm`] on `base`, with its setup), so that
/// a caller can write `main`'s files while they run.
pub fn readings(
    base: &Config,
    main: &Derivation,
    main_setup: &Setup,
    cancel: Option<Arc<AtomicBool>>,
) -> Result<PaperReport, DeriveError> {
    let cancelled = || -> Result<(), DeriveError> {
        match &cancel {
            Some(c) if c.load(Ordering::Relaxed) => Err(DeriveError::Cancelled),
            _ => Ok(()),
        }
    };
    cancelled()?;
    let selected = main
        .paper_fit()
        .map(|f| f.selected.constants.clone())
        .unwrap_or_default();
    // The readings are independent of each other: the fits of both nets, the side-by-side
    // runs and the default derivation run in parallel (rayon's pool; each result is the same
    // as when run alone, and the lists keep their order).
    let fits = || -> Result<Vec<FitReading>, DeriveError> {
        let per_net = ControlNet::ALL
            .par_iter()
            .map(|&net| fit_readings(&Setup::new(&with_net(base, net)?)?, net))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(per_net.into_iter().flatten().collect())
    };
    let dynamics = || -> Result<Vec<DynamicsReading>, DeriveError> {
        let cases: Vec<(ControlNet, RestShape)> = ControlNet::ALL
            .into_iter()
            .flat_map(|net| [RestShape::Initial, RestShape::Zero].map(|rest| (net, rest)))
            .collect();
        let per_case = cases
            .par_iter()
            .map(|&(net, rest)| dynamics_readings(base, net, rest, (&selected, main.mass.selected)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(per_case.into_iter().flatten().collect())
    };
    let ((fits, dynamics), beyond) =
        rayon::join(|| rayon::join(fits, dynamics), || beyond(base, main));
    let (fits, dynamics, beyond) = (fits?, dynamics?, beyond?);
    cancelled()?;
    let mass_nearest = nearest_eigenvalues(main);
    let lattice = LatticeFacts {
        normal_stiffness_share: normal_stiffness_share(main_setup)?,
        msm_zero_frequencies: main.spectrum.msm.iter().filter(|&&w| w == 0.0).count(),
        msm_frequencies: main.spectrum.msm.len(),
    };
    let verdicts = verdicts(base, main, &fits, &mass_nearest, &dynamics, &lattice);
    Ok(PaperReport {
        fits,
        mass_nearest,
        dynamics,
        lattice,
        verdicts,
        beyond,
    })
}

#[cfg(test)]
mod tests;
