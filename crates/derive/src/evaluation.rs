//! The judgement every derivation shares (docs/math.md §8.6–8.7): the horizon, the D-NURBS
//! reference, the 3-D validation of the probes, the second excitation, the frequency table,
//! the masses against the D-NURBS's, and the warnings.

use nurbspring_dnurbs::{DnurbsModel, Geometry};
use nurbspring_geom::GeomError;
use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::State;

use crate::error::Input;
use crate::method::Method;
use crate::modal_solution::{DENSE_MODES, ModalBasis};
use crate::outcome::{FrequencyRow, MassReport, ProbeError, Regime, Validation};
use crate::reference::{ReferenceKind, Watch, run_scalar, scalar_rows};
use crate::scalar::{EnergyOrigin, ScalarSystem};
use crate::setup::Setup;
use crate::validation::{compare, compare_points, energy_drift, match_modes};
use crate::{DeriveError, Trajectory};

/// The validation horizon covers at least this many periods of the lowest mode.
pub const PERIODS: f64 = 5.0;
/// A relative RMS of the central node above this is a bad model.
pub const WARN_RELATIVE_RMS: f64 = 0.10;
/// A lowest frequency off by more than this (relative) is a bad model.
pub const WARN_FREQUENCY: f64 = 0.01;
/// A free mass off by more than this factor is a bad model.
pub const WARN_MASS_FACTOR: f64 = 2.0;
/// A truncated modal run whose left-out modes carry more than this share of the motion is
/// reported.
pub const WARN_TRUNCATION: f64 = 0.01;
/// Distinct frequencies listed in the frequency table.
pub const TABLE_MODES: usize = 8;
/// The MSM modes searched for the match of a D-NURBS mode: the lowest this many times
/// [`TABLE_MODES`].
pub const MATCH_WINDOW: usize = 3;
/// A matched low mode whose frequency is off by more than this (relative) is reported.
pub const WARN_MODE_FREQUENCY: f64 = 0.05;
/// The modes compared for the regime's frequency bound.
pub const REGIME_MODES: usize = 100;
/// The regime's frequency bound: matched modes within this relative error.
pub const REGIME_FREQUENCY: f64 = 0.01;
/// The linear range: displacements up to this share of the surface's size. Both models are
/// linear in the displacement; a displacement w over a size L strains a sheet by about
/// `(w/L)²/2` beyond what they count (0.5% at this bound), and turns it so far that loads
/// and stiffness no longer act along the rest shape's directions.
pub const LINEAR_RANGE: f64 = 0.1;

/// `max(t_end, PERIODS · 2π/ω₁)`.
pub fn horizon(t_end: f64, omega1: f64) -> f64 {
    if omega1 > 0.0 {
        t_end.max(PERIODS * 2.0 * std::f64::consts::PI / omega1)
    } else {
        t_end
    }
}

/// The scalar system of the D-NURBS (free control points) and all its modes.
pub struct DnurbsModes {
    /// The system.
    pub system: ScalarSystem,
    /// Its modes.
    pub basis: ModalBasis,
}

impl DnurbsModes {
    /// The scalar system and modes of the setup's D-NURBS from its initial state.
    pub fn new(setup: &Setup, what: &'static str) -> Result<Self, DeriveError> {
        let system = ScalarSystem::of_dnurbs(setup.model(), setup.dnurbs_initial(), what)?;
        let basis = ModalBasis::new(&system.stiffness, &system.mass)?;
        Ok(Self { system, basis })
    }

    /// The lowest non-zero angular frequency.
    pub fn omega1(&self) -> f64 {
        self.basis
            .omega
            .iter()
            .copied()
            .find(|&w| w > 0.0)
            .unwrap_or(0.0)
    }
}

/// The probes as points of the D-NURBS scalar system: rest position `Ω_probe p(0)` and the
/// probe rows of Ω on the free control points.
pub fn dnurbs_watch(setup: &Setup, system: &ScalarSystem) -> Vec<Watch> {
    let omega = setup.probe_omega();
    let base = omega.apply(setup.model().p0());
    let scalar = scalar_rows(omega.matrix());
    let mut position = vec![usize::MAX; setup.model().geometry().n_control_points()];
    for (i, &k) in system.free.iter().enumerate() {
        position[k] = i;
    }
    (0..scalar.nrows())
        .map(|p| Watch {
            base: base[p],
            weights: row(&scalar, p)
                .into_iter()
                .filter(|&(k, _)| position[k] != usize::MAX)
                .map(|(k, w)| (position[k], w))
                .collect(),
        })
        .collect()
}

/// The non-zeros of row `r` of a CSC matrix, `(column, value)`.
pub(crate) fn row(a: &SparseMatrix, r: usize) -> Vec<(usize, f64)> {
    let (cp, ri, v) = (a.col_ptr(), a.row_idx(), a.values());
    (0..a.ncols())
        .filter_map(|j| {
            (cp[j]..cp[j + 1])
                .find(|&k| ri[k] == r)
                .map(|k| (j, v[k]))
                .filter(|&(_, x)| x != 0.0)
        })
        .collect()
}

/// The probes as points of a node-space system on the free nodes `free` of the lattice
/// nodes at `positions` (a fixed probe node does not move).
pub fn node_watch(probe_nodes: &[usize], free: &[usize], positions: &[[f64; 3]]) -> Vec<Watch> {
    probe_nodes
        .iter()
        .map(|&a| Watch {
            base: positions[a],
            weights: free
                .binary_search(&a)
                .map(|i| vec![(i, 1.0)])
                .unwrap_or_default(),
        })
        .collect()
}

/// Compares the probes of `msm` with those of `reference` in 3-D (the central probe first).
pub fn validation(
    setup: &Setup,
    reference: &Trajectory,
    kind: ReferenceKind,
    msm: &Trajectory,
    integrator: String,
    substeps: usize,
    horizon: f64,
    dt: f64,
) -> Validation {
    let t = &reference.t;
    let probes: Vec<ProbeError> = setup
        .probes()
        .iter()
        .zip(setup.probe_nodes())
        .enumerate()
        .map(|(p, (&(u, v), &node))| {
            let c = compare_points(t, &reference.probes[p], &msm.probes[p]);
            ProbeError {
                u,
                v,
                node,
                relative_rms: c.relative_rms,
                rms: c.rms,
            }
        })
        .collect();
    let stopped = msm.stopped.is_some();
    let central = compare_points(t, &reference.probes[0], &msm.probes[0]);
    let z = compare(t, &reference.component(0, 2), &msm.component(0, 2));
    let complete = !stopped && central.samples == t.len();
    let or_inf = |x: f64| if complete { x } else { f64::INFINITY };
    Validation {
        integrator,
        substeps,
        reference: kind,
        horizon,
        dt,
        rms: or_inf(central.rms),
        max_abs: or_inf(central.max_abs),
        relative_rms: or_inf(central.relative_rms),
        relative_rms_z: or_inf(z.relative_rms),
        dnurbs_amplitude: central.reference_amplitude,
        dnurbs_period: central.reference_period,
        msm_period: if complete { central.other_period } else { None },
        samples: central.samples,
        dnurbs_energy_drift: energy_drift(reference),
        msm_energy_drift: energy_drift(msm),
        msm_stopped: msm.stopped.clone(),
        msm_halved_steps: msm.halved_steps,
        dnurbs_truncation: reference.truncation.clone(),
        msm_truncation: msm.truncation.clone(),
        probes,
    }
}

/// The D-NURBS state of the second excitation: at rest, one off-centre free control point
/// (the one whose Greville point is nearest a third of the way into the domain) pushed along
/// the surface normal (a curve: across it) with the speed of the scene's initial velocity
/// (1 when it has none).
pub fn impulse(setup: &Setup, speed: f64) -> Result<State, DeriveError> {
    let model: &DnurbsModel = setup.model();
    let fixed = model.fixed_points();
    let speed = if speed > 0.0 { speed } else { 1.0 };
    let (target, points): ((f64, f64), Vec<(usize, (f64, f64))>) = match model.geometry() {
        Geometry::Surface(s) => {
            let (gu, gv) = (
                s.basis_u().knots().greville(),
                s.basis_v().knots().greville(),
            );
            let ((u0, u1), (v0, v1)) = s.domain();
            let pts = (0..s.n_u())
                .flat_map(|i| (0..s.n_v()).map(move |j| (i, j)))
                .map(|(i, j)| (s.index(i, j), (gu[i], gv[j])))
                .collect();
            ((u0 + 0.3 * (u1 - u0), v0 + 0.35 * (v1 - v0)), pts)
        }
        Geometry::Curve(c) => {
            let g = c.basis().knots().greville();
            let (u0, u1) = c.domain();
            (
                (u0 + 0.3 * (u1 - u0), 0.0),
                g.iter().enumerate().map(|(k, &u)| (k, (u, 0.0))).collect(),
            )
        }
    };
    let (k, (u, v)) = points
        .into_iter()
        .filter(|(k, _)| !fixed.contains(k))
        .min_by(|a, b| {
            let d = |p: (f64, f64)| (p.0 - target.0).powi(2) + (p.1 - target.1).powi(2);
            d(a.1).total_cmp(&d(b.1))
        })
        .ok_or_else(|| DeriveError::InvalidInput {
            input: Input::Constraints,
            value: "every control point fixed".into(),
            reason: "the second excitation needs a free control point".into(),
        })?;
    let direction = match model.geometry() {
        Geometry::Surface(s) => match s.normal(u, v) {
            Err(GeomError::DegenerateNormal { .. }) => [0.0, 0.0, 1.0],
            n => n?,
        },
        Geometry::Curve(c) => {
            let t = normalize(c.derivatives(u, 1)?.u).unwrap_or([1.0, 0.0, 0.0]);
            let axis = if t[2].abs() < 0.9 {
                [0.0, 0.0, 1.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let along = axis[0] * t[0] + axis[1] * t[1] + axis[2] * t[2];
            normalize([
                axis[0] - along * t[0],
                axis[1] - along * t[1],
                axis[2] - along * t[2],
            ])
            .unwrap_or([0.0, 0.0, 1.0])
        }
    };
    let mut velocities = vec![[0.0; 3]; model.geometry().n_control_points()];
    velocities[k] = direction.map(|x| speed * x);
    Ok(model.initial_state(&velocities, 0.0))
}

fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    (n > 0.0).then(|| a.map(|x| x / n))
}

/// The largest speed among the control points of the scene's initial state.
pub fn initial_speed(state: &State) -> f64 {
    state
        .v
        .chunks(3)
        .map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt())
        .fold(0.0, f64::max)
}

/// The scalar system with a different initial state and no load (the second excitation): at
/// rest at `u = 0`, no load potential.
pub fn unloaded(
    system: &ScalarSystem,
    displacement: Vec<[f64; 3]>,
    velocity: Vec<[f64; 3]>,
) -> ScalarSystem {
    let load = vec![[0.0; 3]; system.n()];
    ScalarSystem {
        energy: EnergyOrigin::of_load(&load, &displacement),
        load,
        displacement,
        velocity,
        ..system.clone()
    }
}

/// The D-NURBS under the second excitation, watched at the probes.
pub fn dnurbs_impulse_run(
    setup: &Setup,
    modes: &DnurbsModes,
    impulse: &State,
    times: &[f64],
    dt: f64,
) -> Result<(Trajectory, ReferenceKind), DeriveError> {
    let sys = unloaded(
        &modes.system,
        vec![[0.0; 3]; modes.system.n()],
        crate::scalar::points(&impulse.v),
    );
    run_scalar(&sys, &modes.basis, &dnurbs_watch(setup, &sys), times, dt)
}

/// The lowest D-NURBS modes, each with the MSM mode matched to it by MAC at the free nodes
/// ([`match_modes`]: a repeated frequency as a subspace) among the MSM's lowest
/// `MATCH_WINDOW × TABLE_MODES` (`omega_ff`: scalar Ω of the free nodes on the free control
/// points; `msm` a basis over the free nodes). A D-NURBS mode left without a match is not
/// listed.
pub fn frequency_table(
    dn: &ModalBasis,
    omega_ff: &SparseMatrix,
    msm: &ModalBasis,
) -> Vec<FrequencyRow> {
    matched_modes(dn, omega_ff, msm, TABLE_MODES)
}

/// The lowest `count` elastic D-NURBS modes (a repeated frequency completed) with the MSM
/// modes matched to them by MAC among the MSM's lowest `MATCH_WINDOW × count`.
pub fn matched_modes(
    dn: &ModalBasis,
    omega_ff: &SparseMatrix,
    msm: &ModalBasis,
    count: usize,
) -> Vec<FrequencyRow> {
    let elastic: Vec<usize> = (0..dn.len()).filter(|&i| dn.omega[i] > 0.0).collect();
    let mut count = count.min(elastic.len());
    // A repeated frequency is listed whole.
    while count < elastic.len()
        && (dn.omega[elastic[count]] - dn.omega[elastic[count - 1]]).abs()
            <= crate::validation::REPEATED_FREQUENCY * dn.omega[elastic[count]]
    {
        count += 1;
    }
    let picked = &elastic[..count];
    let reference: Vec<Vec<f64>> = picked
        .iter()
        .map(|&i| {
            let mut at_nodes = vec![0.0; omega_ff.nrows()];
            omega_ff.mul_vec(&dn.mode(i), &mut at_nodes);
            at_nodes
        })
        .collect();
    let omega: Vec<f64> = picked.iter().map(|&i| dn.omega[i]).collect();
    let window: Vec<usize> = (0..msm.len())
        .filter(|&j| msm.omega[j] > 0.0)
        .take(MATCH_WINDOW * count)
        .collect();
    let candidates: Vec<Vec<f64>> = window.iter().map(|&j| msm.mode(j)).collect();
    match_modes(&reference, &omega, &candidates)
        .into_iter()
        .zip(picked)
        .filter_map(|(m, &i)| {
            let (j, mac) = m?;
            let (a, b) = (dn.omega[i], msm.omega[window[j]]);
            Some(FrequencyRow {
                mode: i + 1,
                dnurbs: a,
                msm_mode: window[j] + 1,
                msm: b,
                relative_difference: if a > 0.0 { b / a - 1.0 } else { f64::NAN },
                mac: Some(mac),
            })
        })
        .collect()
}

/// The regime a derived model may be used in (docs/math.md §8.7): the frequencies up to
/// which the D-NURBS modes, in ascending order, each have a matched MSM mode within
/// [`REGIME_FREQUENCY`] (`rows`: the matched modes, ascending), and the displacements up to
/// [`LINEAR_RANGE`] of the surface's size (the diagonal of its lattice's bounding box at
/// rest), beside the largest displacement the D-NURBS makes at the probes in `reference`.
pub fn regime(setup: &Setup, reference: &Trajectory, rows: &[FrequencyRow]) -> Regime {
    let mut frequency = 0.0;
    let mut modes = 0;
    for r in rows {
        if r.relative_difference.abs() > REGIME_FREQUENCY || r.relative_difference.is_nan() {
            break;
        }
        frequency = r.dnurbs;
        modes += 1;
    }
    let positions = &setup.lattice().positions;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in positions {
        for x in 0..3 {
            lo[x] = lo[x].min(p[x]);
            hi[x] = hi[x].max(p[x]);
        }
    }
    let size = (0..3).map(|x| (hi[x] - lo[x]).powi(2)).sum::<f64>().sqrt();
    let motion = reference
        .probes
        .iter()
        .filter_map(|probe| {
            let start = probe.first()?;
            Some(
                probe
                    .iter()
                    .map(|x| {
                        ((x[0] - start[0]).powi(2)
                            + (x[1] - start[1]).powi(2)
                            + (x[2] - start[2]).powi(2))
                        .sqrt()
                    })
                    .fold(0.0, f64::max),
            )
        })
        .fold(0.0, f64::max);
    Regime {
        frequency,
        modes,
        size,
        amplitude: LINEAR_RANGE * size,
        motion,
    }
}

/// Each value three times (x, y, z), ascending.
pub fn triplicate(omega: &[f64]) -> Vec<f64> {
    omega.iter().flat_map(|&w| [w; 3]).collect()
}

/// The totals of a [`MassReport`]: the model's masses (every node, free nodes) against the
/// D-NURBS's (`Σ_ij M_ij / 3`, the free rows' share).
pub fn with_totals(
    mut report: MassReport,
    model: &DnurbsModel,
    masses: &[f64],
    fixed: &[bool],
) -> MassReport {
    let m = &model.matrices().mass;
    let dpp = model.matrices().dofs_per_point;
    let mut fixed_cp = vec![false; model.geometry().n_control_points()];
    for &k in model.fixed_points() {
        fixed_cp[k] = true;
    }
    let (mut total, mut free) = (0.0, 0.0);
    for (i, j, v) in m.triplets() {
        if dpp == 4 && (i % 4 == 3 || j % 4 == 3) {
            continue;
        }
        total += v;
        if !fixed_cp[i / dpp] {
            free += v;
        }
    }
    report.total_dnurbs = total / 3.0;
    report.free_dnurbs = free / 3.0;
    report.total_msm = masses.iter().sum();
    report.free_msm = masses
        .iter()
        .zip(fixed)
        .filter(|(_, f)| !**f)
        .map(|(m, _)| m)
        .sum();
    report
}

/// Every sign of a bad model: the central node's relative RMS, the lowest frequency, the free
/// mass; for the paper's derivation a class clamped to zero or a mass at the edge of its scan.
pub fn warnings(
    method: Method,
    validation: &Validation,
    second: &Validation,
    frequencies: &[crate::outcome::FrequencyRow],
    mass: &MassReport,
    clamped: &[String],
    regime: &Regime,
) -> Vec<String> {
    let mut out = Vec::new();
    let pct = |x: f64| 100.0 * x;
    if regime.motion > regime.amplitude {
        out.push(format!(
            "the scene's own motion reaches {:.4} at the probes, {:.0}% of the surface's size \
             {:.4} (linear range: {:.0}%): the D-NURBS and the MSM are linear models, so their \
             agreement here says nothing of so large a motion",
            regime.motion,
            pct(regime.motion / regime.size),
            regime.size,
            pct(LINEAR_RANGE)
        ));
    }
    // NaN (no motion to compare) counts as a bad sign too.
    let above = |x: f64, limit: f64| x.is_nan() || x > limit;
    if validation.dnurbs_amplitude == 0.0 {
        out.push(
            "the scene's initial state and loads do not move the D-NURBS, so its own motion \
             validates nothing; only the second excitation does (give initial.velocity, \
             initial.displacement or loads)"
                .into(),
        );
    } else if let Some(why) = &validation.msm_stopped {
        out.push(format!(
            "the MSM's validation run stopped before {:.3} s ({why}), so nothing after that is \
             compared and its relative RMS counts as infinite",
            validation.horizon
        ));
    } else if above(validation.relative_rms, WARN_RELATIVE_RMS) {
        out.push(format!(
            "the central node's relative RMS against the D-NURBS is {:.1}% over {:.3} s (above {:.0}%)",
            pct(validation.relative_rms),
            validation.horizon,
            pct(WARN_RELATIVE_RMS)
        ));
    }
    if let Some(first) = frequencies.first()
        && above(first.relative_difference.abs(), WARN_FREQUENCY)
    {
        out.push(format!(
            "the lowest frequency is off by {:+.2}% ({:.6} rad/s against the D-NURBS's {:.6})",
            pct(first.relative_difference),
            first.msm,
            first.dnurbs
        ));
    }
    for row in frequencies.iter().skip(1) {
        if above(row.relative_difference.abs(), WARN_MODE_FREQUENCY) {
            out.push(format!(
                "D-NURBS mode {} ({:.6} rad/s) is matched by MAC ({}) to MSM mode {} at \
                 {:.6} rad/s, {:+.1}% off (above {:.0}%)",
                row.mode,
                row.dnurbs,
                row.mac
                    .map_or_else(|| "by rank".to_string(), |m| format!("{m:.3}")),
                row.msm_mode,
                row.msm,
                pct(row.relative_difference),
                pct(WARN_MODE_FREQUENCY)
            ));
        }
    }
    let ratio = mass.free_msm / mass.free_dnurbs;
    if !(1.0 / WARN_MASS_FACTOR..=WARN_MASS_FACTOR).contains(&ratio) {
        out.push(format!(
            "the free nodes carry {:.4} of mass against the D-NURBS's {:.4} ({ratio:.3}×)",
            mass.free_msm, mass.free_dnurbs
        ));
    }
    if let Some(why) = &second.msm_stopped {
        out.push(format!(
            "under the second excitation the MSM's run stopped before {:.3} s ({why})",
            second.horizon
        ));
    } else if above(second.relative_rms, 2.0 * WARN_RELATIVE_RMS) {
        out.push(format!(
            "under the second excitation the central node's relative RMS is {:.1}%",
            pct(second.relative_rms)
        ));
    }
    for (run, v) in [("validation", validation), ("second excitation", second)] {
        for (model, t) in [
            ("D-NURBS", &v.dnurbs_truncation),
            ("MSM", &v.msm_truncation),
        ] {
            let Some(t) = t else { continue };
            let share = match t.left_out {
                Some(x) if x <= WARN_TRUNCATION => continue,
                Some(x) => format!(
                    "carry {:.1}% of its motion (above {:.0}%)",
                    pct(x),
                    pct(WARN_TRUNCATION)
                ),
                None => "carry an unknown share of its motion (it has rigid modes)".into(),
            };
            out.push(format!(
                "the {run} followed the lowest {} of the {model}'s {} modes (a dense \
                 eigenproblem above {DENSE_MODES} unknowns is not attempted); the modes left \
                 out {share}, so its figures describe the low modes",
                t.modes, t.unknowns
            ));
        }
    }
    if method == Method::Paper {
        for c in clamped {
            out.push(format!("{c} was clamped to 0 by k >= 0"));
        }
        if let (Some(first), Some(last)) = (mass.candidates.first(), mass.candidates.last())
            && mass.candidates.len() > 1
            && (mass.selected == first.m || mass.selected == last.m)
        {
            out.push(format!(
                "the selected mass {} is at the edge of the scan [{}, {}]",
                mass.selected, first.m, last.m
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests;
