//! The judgement every derivation shares (docs/math.md §8.6–8.7): the horizon, the D-NURBS
//! reference, the 3-D validation of the probes, the second excitation, the frequency table,
//! the masses against the D-NURBS's, and the warnings.

use nurbspring_dnurbs::{DnurbsModel, Geometry};
use nurbspring_geom::GeomError;
use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::State;

use crate::modal_solution::{DENSE_MODES, ModalBasis};
use crate::outcome::{FrequencyRow, MassReport, ProbeError, Regime, Validation};
use crate::reference::{ReferenceKind, Watch, run_scalar, scalar_rows};
use crate::scalar::{EnergyOrigin, ScalarSystem};
use crate::setup::{Method, Setup};
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
        .ok_or_else(|| DeriveError::InvalidOption {
            name: "constraints",
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
mod tests {
    use nurbspring_geom::{KnotVector, NurbsCurve, NurbsSurface};

    use super::*;
    use crate::scalar::EnergyOrigin;
    use crate::test_scenes::setup;

    fn unit(a: [f64; 3]) -> [f64; 3] {
        let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        a.map(|x| x / n)
    }

    /// The velocity of every control point of an impulse state, one triple per point.
    fn point_velocities(setup: &Setup, state: &State) -> Vec<[f64; 3]> {
        let v = setup.model().full_velocity(&state.v);
        v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
    }

    /// On a doubly curved bicubic patch the impulse moves the one free control point whose
    /// Greville point is nearest the point at fractions (0.3, 0.35) of the domain, along the unit normal of the
    /// surface there (checked against the cross product of central-difference tangents), at
    /// the given speed (1 without one).
    #[test]
    fn the_surface_impulse_pushes_the_nearest_free_point_along_the_normal() {
        // The domain [1, 3] × [−1, 1], so that the target (1.6, −0.3) is not at fractions of 1.
        let ku =
            KnotVector::try_new(vec![1., 1., 1., 1., 5. / 3., 7. / 3., 3., 3., 3., 3.], 3).unwrap();
        let kv = KnotVector::try_new(vec![-1., -1., -1., -1., 0., 1., 1., 1., 1.], 3).unwrap();
        let (gu, gv) = (ku.greville(), kv.greville());
        let pts = gu
            .iter()
            .flat_map(|&u| {
                gv.iter().map(move |&v| {
                    let (u, v) = ((u - 1.0) / 2.0, (v + 1.0) / 2.0);
                    [2.0 * u + 0.2 * v, 1.5 * v, 0.3 * u * u - 0.4 * v * u]
                })
            })
            .collect();
        let s = NurbsSurface::try_new(ku, kv, pts, vec![1.0; 30]).unwrap();
        let setup = setup(Geometry::Surface(s.clone()));
        // The free points are the interior 4 × 3; by hand the nearest Greville point to
        // (1 + 0.3·2, −1 + 0.35·2) among them.
        let mut best = (usize::MAX, f64::INFINITY, (0.0, 0.0));
        for i in 1..5 {
            for j in 1..4 {
                let d = (gu[i] - 1.6).powi(2) + (gv[j] + 0.3).powi(2);
                if d < best.1 {
                    best = (i * 5 + j, d, (gu[i], gv[j]));
                }
            }
        }
        let (k, _, (u, v)) = best;
        let h = 1e-5;
        let diff = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|x| (a[x] - b[x]) / (2.0 * h));
        let su = diff(s.point(u + h, v).unwrap(), s.point(u - h, v).unwrap());
        let sv = diff(s.point(u, v + h).unwrap(), s.point(u, v - h).unwrap());
        let normal = unit([
            su[1] * sv[2] - su[2] * sv[1],
            su[2] * sv[0] - su[0] * sv[2],
            su[0] * sv[1] - su[1] * sv[0],
        ]);
        // Every component non-zero, so that none can be dropped unseen.
        assert!(normal.iter().all(|c| c.abs() > 1e-3), "{normal:?}");
        for (speed, expected_speed) in [(0.3, 0.3), (0.0, 1.0)] {
            let state = impulse(&setup, speed).unwrap();
            let velocities = point_velocities(&setup, &state);
            for (a, vel) in velocities.iter().enumerate() {
                if a == k {
                    for x in 0..3 {
                        assert!(
                            (vel[x] - expected_speed * normal[x]).abs() < 1e-8,
                            "{vel:?} vs {normal:?}"
                        );
                    }
                } else {
                    assert_eq!(*vel, [0.0; 3], "point {a}");
                }
            }
        }
    }

    /// On a curve the impulse is across it: the z axis made orthogonal to the tangent (the y
    /// axis where the tangent is nearly along z), at the free point nearest 0.3 of the domain.
    #[test]
    fn the_curve_impulse_pushes_across_the_tangent() {
        let k = KnotVector::clamped_uniform(2, 4).unwrap();
        let g = k.greville();
        let pts: Vec<[f64; 3]> = g.iter().map(|&u| [3.0 * u, u * u, 0.8 * u]).collect();
        let n = pts.len();
        let c = NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap();
        let curve_setup = setup(Geometry::Curve(c.clone()));
        let (point, &u) = g[1..n - 1]
            .iter()
            .enumerate()
            .min_by(|a, b| (a.1 - 0.3).abs().total_cmp(&(b.1 - 0.3).abs()))
            .map(|(i, u)| (i + 1, u))
            .unwrap();
        let h = 1e-5;
        let (a, b) = (c.point(u + h).unwrap(), c.point(u - h).unwrap());
        let t = unit([0, 1, 2].map(|x| a[x] - b[x]));
        let expected = unit([-t[2] * t[0], -t[2] * t[1], 1.0 - t[2] * t[2]]);
        let velocities = point_velocities(&curve_setup, &impulse(&curve_setup, 2.0).unwrap());
        for x in 0..3 {
            assert!((velocities[point][x] - 2.0 * expected[x]).abs() < 1e-8);
        }
        assert_eq!(velocities.iter().filter(|v| **v != [0.0; 3]).count(), 1);

        // A curve in the y–z plane (tangent without x component): across it is still z made
        // orthogonal to the tangent, in that plane.
        let k = KnotVector::clamped_uniform(2, 4).unwrap();
        let pts: Vec<[f64; 3]> = g.iter().map(|&u| [0.0, 3.0 * u, 0.5 * u * u]).collect();
        let c = NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap();
        let plane_setup = setup(Geometry::Curve(c.clone()));
        let (a, b) = (c.point(u + h).unwrap(), c.point(u - h).unwrap());
        let t = unit([0, 1, 2].map(|x| a[x] - b[x]));
        let expected = unit([0.0, -t[2] * t[1], 1.0 - t[2] * t[2]]);
        let velocities = point_velocities(&plane_setup, &impulse(&plane_setup, 1.0).unwrap());
        for x in 0..3 {
            assert!(
                (velocities[point][x] - expected[x]).abs() < 1e-8,
                "{:?}",
                velocities[point]
            );
        }

        // A curve nearly along z (|t_z| > 0.9): across it is the y axis made orthogonal to
        // the tangent, `y − (y·t) t`.
        let k = KnotVector::clamped_uniform(2, 4).unwrap();
        let pts: Vec<[f64; 3]> = g
            .iter()
            .map(|&u| [0.1 * u, 0.3 * u + 0.2 * u * u, 3.0 * u])
            .collect();
        let c = NurbsCurve::try_new(k, pts, vec![1.0; n]).unwrap();
        let steep_setup = setup(Geometry::Curve(c.clone()));
        let (a, b) = (c.point(u + h).unwrap(), c.point(u - h).unwrap());
        let t = unit([0, 1, 2].map(|x| a[x] - b[x]));
        assert!(t[2] > 0.9 && t[0] != 0.0 && t[1] != 0.0, "{t:?}");
        let expected = unit([-t[1] * t[0], 1.0 - t[1] * t[1], -t[1] * t[2]]);
        let velocities = point_velocities(&steep_setup, &impulse(&steep_setup, 1.0).unwrap());
        for x in 0..3 {
            assert!(
                (velocities[point][x] - expected[x]).abs() < 1e-8,
                "{:?} vs {expected:?}",
                velocities[point]
            );
        }
    }

    /// The impulse's target is at 0.3 (and 0.35) of the domain, whatever the domain: on
    /// [2, 10] (× [−3, 1]) with 12 spans the free point moved is the one whose Greville point is
    /// nearest (4.4, −1.6), for a surface and for a curve.
    #[test]
    fn the_impulse_target_is_a_fraction_of_any_domain() {
        let knots = |a: f64, b: f64| {
            let mut k = vec![a; 3];
            k.extend((1..12).map(|i| a + (b - a) * i as f64 / 12.0));
            k.extend([b; 3]);
            KnotVector::try_new(k, 2).unwrap()
        };
        let (ku, kv) = (knots(2.0, 10.0), knots(-3.0, 1.0));
        let (gu, gv) = (ku.greville(), kv.greville());
        let n = gu.len();
        let nearest = |g: &[f64], x: f64| {
            (1..n - 1)
                .min_by(|&a, &b| (g[a] - x).abs().total_cmp(&(g[b] - x).abs()))
                .unwrap()
        };
        let (i, j) = (nearest(&gu, 4.4), nearest(&gv, -1.6));
        let pts = gu
            .iter()
            .flat_map(|&u| gv.iter().map(move |&v| [u, v, 0.05 * u * v]))
            .collect();
        let s = NurbsSurface::try_new(ku.clone(), kv, pts, vec![1.0; n * n]).unwrap();
        let surface = setup(Geometry::Surface(s.clone()));
        let moved: Vec<usize> = point_velocities(&surface, &impulse(&surface, 1.0).unwrap())
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != [0.0; 3])
            .map(|(a, _)| a)
            .collect();
        assert_eq!(moved, vec![s.index(i, j)]);
        let pts: Vec<[f64; 3]> = gu.iter().map(|&u| [u, 0.1 * u * u, 0.0]).collect();
        let c = NurbsCurve::try_new(ku, pts, vec![1.0; n]).unwrap();
        let curve = setup(Geometry::Curve(c));
        let moved: Vec<usize> = point_velocities(&curve, &impulse(&curve, 1.0).unwrap())
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != [0.0; 3])
            .map(|(a, _)| a)
            .collect();
        assert_eq!(moved, vec![i]);
    }

    /// The non-zeros of a row of a CSC matrix, by hand; stored zeros are left out.
    #[test]
    fn rows_of_a_sparse_matrix_by_hand() {
        let a = SparseMatrix::from_triplets(
            3,
            4,
            &[
                (0, 1, 2.0),
                (1, 0, -1.0),
                (1, 3, 4.0),
                (2, 2, 0.0),
                (1, 2, 0.5),
            ],
        )
        .unwrap();
        assert_eq!(row(&a, 0), vec![(1, 2.0)]);
        assert_eq!(row(&a, 1), vec![(0, -1.0), (2, 0.5), (3, 4.0)]);
        assert!(row(&a, 2).is_empty());
    }

    /// With no point fixed the D-NURBS has rigid modes (ω = 0); the lowest non-zero frequency
    /// is the first positive one, not a zero.
    #[test]
    fn omega1_skips_the_rigid_modes() {
        let ku = KnotVector::clamped_uniform(2, 2).unwrap();
        let g = ku.greville();
        let pts = g
            .iter()
            .flat_map(|&u| g.iter().map(move |&v| [u, v, 0.1 * u * v]))
            .collect();
        let s = NurbsSurface::try_new(ku.clone(), ku, pts, vec![1.0; 16]).unwrap();
        let mut config = crate::test_scenes::config(Geometry::Surface(s));
        config.constraints.fixed_rings = 0;
        let setup = Setup::new(&config).unwrap();
        let modes = DnurbsModes::new(&setup, "test").unwrap();
        let zeros = modes.basis.omega.iter().filter(|&&w| w == 0.0).count();
        assert!(zeros >= 1, "{:?}", modes.basis.omega);
        let first = modes
            .basis
            .omega
            .iter()
            .copied()
            .find(|&w| w > 0.0)
            .unwrap();
        assert_eq!(modes.omega1(), first);
        assert!(first > 0.0);
    }

    /// The second excitation's system keeps M and K and replaces the state: no load, the
    /// given displacement and velocity, and the energy origin of no load.
    #[test]
    fn the_unloaded_system_keeps_the_matrices_and_replaces_the_state() {
        use crate::scalar::ScalarSystem;
        let sys = ScalarSystem {
            free: vec![1, 2],
            mass: SparseMatrix::from_diagonal(&[2.0, 3.0]),
            stiffness: SparseMatrix::from_diagonal(&[5.0, 7.0]),
            damping_ratio: 0.1,
            load: vec![[0.0, 0.0, -1.0]; 2],
            displacement: vec![[0.5; 3]; 2],
            velocity: vec![[1.0; 3]; 2],
            energy: EnergyOrigin::of_load(&[[0.0, 0.0, -1.0]; 2], &[[0.5; 3]; 2]),
        };
        let (u0, v0) = (
            vec![[0.0, 0.1, 0.0], [0.2, 0.0, 0.0]],
            vec![[0.0, 0.0, 3.0], [0.0; 3]],
        );
        let out = unloaded(&sys, u0.clone(), v0.clone());
        assert_eq!(
            (out.free.clone(), out.damping_ratio),
            (sys.free.clone(), 0.1)
        );
        assert_eq!(out.mass.to_dense().data(), sys.mass.to_dense().data());
        assert_eq!(
            out.stiffness.to_dense().data(),
            sys.stiffness.to_dense().data()
        );
        assert_eq!(out.load, vec![[0.0; 3]; 2]);
        assert_eq!((out.displacement, out.velocity), (u0, v0));
        assert_eq!((out.energy.elastic, out.energy.external), (0.0, 0.0));
        assert_eq!(out.energy.force, vec![[0.0; 3]; 2]);
    }

    /// With weights as unknowns (4 dofs a point) the totals count the x, y, z rows only:
    /// `Σ_ij M_ij / 3` over them is `μ` times the parameter measure (1) by the partition of
    /// unity; the lattice's totals are its masses, all and free.
    #[test]
    fn mass_totals_skip_the_weight_rows() {
        use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Loads, Material};
        let (ku, kv) = (
            KnotVector::clamped_uniform(2, 2).unwrap(),
            KnotVector::clamped_uniform(2, 2).unwrap(),
        );
        let (gu, gv) = (ku.greville(), kv.greville());
        let pts = gu
            .iter()
            .flat_map(|&u| gv.iter().map(move |&v| [u, v, 0.1 * u * v]))
            .collect();
        let w = (0..16).map(|k| 1.0 + 0.1 * (k % 3) as f64).collect();
        let s = NurbsSurface::try_new(ku, kv, pts, w).unwrap();
        let model = DnurbsModel::new(
            Geometry::Surface(s),
            Material {
                mu: 2.5,
                alpha11: 1.0,
                alpha22: 1.0,
                ..Material::default()
            },
            Loads::default(),
            &Constraints {
                fixed_rings: 1,
                ..Constraints::default()
            },
            DnurbsOptions {
                weights_as_dofs: true,
                ..DnurbsOptions::default()
            },
        )
        .unwrap();
        assert_eq!(model.matrices().dofs_per_point, 4);
        let report = with_totals(
            MassReport::default(),
            &model,
            &[1.0, 2.0, 3.0],
            &[true, false, false],
        );
        assert!(
            (report.total_dnurbs - 2.5).abs() < 1e-12,
            "{}",
            report.total_dnurbs
        );
        assert!(report.free_dnurbs > 0.0 && report.free_dnurbs < report.total_dnurbs);
        assert_eq!((report.total_msm, report.free_msm), (6.0, 5.0));
    }

    #[test]
    fn horizon_and_initial_speed_by_hand() {
        let two_pi = 2.0 * std::f64::consts::PI;
        assert_eq!(horizon(1.0, two_pi), PERIODS);
        assert_eq!(horizon(10.0, two_pi), 10.0);
        assert_eq!(horizon(3.0, 0.0), 3.0);
        let state = State::new(vec![0.0; 6], vec![3.0, -4.0, 0.0, 0.0, 0.0, 1.0]);
        assert_eq!(initial_speed(&state), 5.0);
    }

    #[test]
    fn triplicate_repeats_each_value_for_x_y_z() {
        assert_eq!(triplicate(&[1.0, 2.5]), vec![1.0, 1.0, 1.0, 2.5, 2.5, 2.5]);
        assert!(triplicate(&[]).is_empty());
    }

    fn validation_with(relative_rms: f64) -> Validation {
        Validation {
            integrator: "newmark".into(),
            substeps: 1,
            reference: ReferenceKind::Modal,
            horizon: 1.0,
            dt: 0.01,
            rms: relative_rms,
            max_abs: relative_rms,
            relative_rms,
            relative_rms_z: relative_rms,
            dnurbs_amplitude: 1.0,
            dnurbs_period: None,
            msm_period: None,
            samples: 101,
            dnurbs_energy_drift: None,
            msm_energy_drift: None,
            msm_stopped: None,
            msm_halved_steps: 0,
            dnurbs_truncation: None,
            msm_truncation: None,
            probes: Vec::new(),
        }
    }

    /// A truncated modal run is reported when its left-out modes carry more than
    /// [`WARN_TRUNCATION`] of the motion (1.5% does, 0.5% does not) or an unknown share, naming
    /// the run, the model and the counts.
    #[test]
    fn a_truncated_run_is_reported_above_its_threshold() {
        let rows: [crate::outcome::FrequencyRow; 0] = [];
        let mass = MassReport {
            free_msm: 1.0,
            free_dnurbs: 1.0,
            ..MassReport::default()
        };
        let truncated = |left_out| {
            Some(crate::outcome::ModalTruncation {
                modes: 200,
                unknowns: 3721,
                left_out,
            })
        };
        let quiet = validation_with(0.0);
        let with = |dnurbs, msm| Validation {
            dnurbs_truncation: dnurbs,
            msm_truncation: msm,
            ..validation_with(0.0)
        };
        let w = warnings(
            Method::Modal,
            &with(
                truncated(Some(0.005)),
                truncated(Some(0.5 * WARN_TRUNCATION)),
            ),
            &quiet,
            &rows,
            &mass,
            &[],
            &Regime::default(),
        );
        assert!(w.is_empty(), "{w:?}");
        let w = warnings(
            Method::Modal,
            &quiet,
            &with(truncated(Some(1.5 * WARN_TRUNCATION)), truncated(None)),
            &rows,
            &mass,
            &[],
            &Regime::default(),
        );
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].starts_with(
                "the second excitation followed the lowest 200 of the D-NURBS's 3721 modes"
            ) && w[0].contains("carry 1.5% of its motion (above 1%)"),
            "{w:?}"
        );
        assert!(
            w[1].contains("of the MSM's 3721 modes") && w[1].contains("an unknown share"),
            "{w:?}"
        );
    }

    fn candidate(m: f64) -> crate::outcome::MassCandidate {
        crate::outcome::MassCandidate {
            m,
            rms: 0.0,
            max_abs: 0.0,
            integrator: nurbspring_sim::IntegratorKind::Newmark,
            substeps: 1,
            stopped: None,
        }
    }

    /// Each warning exactly when its number crosses its threshold: the free mass ratio
    /// `free_msm / free_dnurbs` outside [1/2, 2] (2.5 and 0.45 warn, 1.5 and 0.75 do not), a selected mass at
    /// either edge of the paper's scan (not inside it), a class clamped to zero (paper only).
    #[test]
    fn warnings_against_their_thresholds() {
        let quiet = validation_with(0.5 * WARN_RELATIVE_RMS);
        let rows = [crate::outcome::FrequencyRow {
            mode: 1,
            dnurbs: 1.0,
            msm_mode: 1,
            msm: 1.0,
            relative_difference: 0.0,
            mac: None,
        }];
        let masses = |free_msm: f64, free_dnurbs: f64, selected: f64| MassReport {
            candidates: vec![candidate(1.0), candidate(2.0), candidate(3.0)],
            selected,
            free_msm,
            free_dnurbs,
            ..MassReport::default()
        };
        let warn = |method, mass: &MassReport, clamped: &[String]| {
            warnings(
                method,
                &quiet,
                &quiet,
                &rows,
                mass,
                clamped,
                &Regime::default(),
            )
        };
        assert!(warn(Method::Modal, &masses(3.0, 2.0, 2.0), &[]).is_empty());
        assert!(warn(Method::Modal, &masses(1.5, 2.0, 2.0), &[]).is_empty());
        let w = warn(Method::Modal, &masses(5.0, 2.0, 2.0), &[]);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("(2.500×)"), "{w:?}");
        assert!(warn(Method::Modal, &masses(0.9, 2.0, 2.0), &[])[0].contains("(0.450×)"));
        // The scan's edges, for the paper's derivation only.
        for (selected, edge) in [(1.0, true), (2.0, false), (3.0, true)] {
            let w = warn(Method::Paper, &masses(2.0, 2.0, selected), &[]);
            assert_eq!(w.len(), usize::from(edge), "{selected}: {w:?}");
            assert!(
                !edge || w[0].contains("at the edge of the scan [1, 3]"),
                "{w:?}"
            );
            assert!(warn(Method::Modal, &masses(2.0, 2.0, selected), &[]).is_empty());
        }
        let clamped = ["k_bend".to_string()];
        let w = warn(Method::Paper, &masses(2.0, 2.0, 2.0), &clamped);
        assert_eq!(w, vec!["k_bend was clamped to 0 by k >= 0".to_string()]);
    }

    /// A validation run that stopped says so, with its reason, instead of an infinite RMS
    /// ("inf%"), for the scene's excitation and for the second one.
    #[test]
    fn a_stopped_run_is_named_with_its_reason() {
        let rows: [crate::outcome::FrequencyRow; 0] = [];
        let mass = MassReport {
            free_msm: 1.0,
            free_dnurbs: 1.0,
            ..MassReport::default()
        };
        let stopped = Validation {
            msm_stopped: Some("Newton iteration failed at step 7".into()),
            ..validation_with(f64::INFINITY)
        };
        let quiet = validation_with(0.0);
        let w = warnings(
            Method::Modal,
            &stopped,
            &quiet,
            &rows,
            &mass,
            &[],
            &Regime::default(),
        );
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("the MSM's validation run stopped before 1.000 s (Newton iteration failed at step 7)"),
            "{w:?}"
        );
        assert!(!w[0].contains("inf%"), "{w:?}");
        let w = warnings(
            Method::Modal,
            &quiet,
            &stopped,
            &rows,
            &mass,
            &[],
            &Regime::default(),
        );
        assert_eq!(
            w,
            vec![
                "under the second excitation the MSM's run stopped before 1.000 s (Newton iteration failed at step 7)"
                    .to_string()
            ]
        );
    }

    /// A matched mode above the lowest is reported beyond 5% (not at 4.9%), and a motion
    /// beyond 10% of the surface's size (not at 9%), each with its numbers.
    #[test]
    fn mode_and_linear_range_warnings_at_their_thresholds() {
        let quiet = validation_with(0.0);
        let mass = MassReport {
            free_msm: 1.0,
            free_dnurbs: 1.0,
            ..MassReport::default()
        };
        let row = |mode: usize, off: f64| crate::outcome::FrequencyRow {
            mode,
            dnurbs: 2.0,
            msm_mode: mode + 1,
            msm: 2.0 * (1.0 + off),
            relative_difference: off,
            mac: Some(0.98),
        };
        let regime = |motion: f64| Regime {
            frequency: 1.0,
            modes: 1,
            size: 2.0,
            amplitude: LINEAR_RANGE * 2.0,
            motion,
        };
        let warn = |rows: &[crate::outcome::FrequencyRow], r: &Regime| {
            warnings(Method::Modal, &quiet, &quiet, rows, &mass, &[], r)
        };
        let fine = [row(1, 0.0), row(2, 0.049), row(3, -0.049)];
        assert!(warn(&fine, &regime(0.18)).is_empty());
        let off = [row(1, 0.0), row(2, 0.051), row(3, -0.06)];
        let w = warn(&off, &regime(0.0));
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(
            w[0].starts_with(
                "D-NURBS mode 2 (2.000000 rad/s) is matched by MAC (0.980) to MSM mode 3"
            ) && w[0].contains("+5.1% off"),
            "{w:?}"
        );
        assert!(w[1].contains("-6.0% off"), "{w:?}");
        let w = warn(&fine, &regime(0.8));
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("the scene's own motion reaches 0.8000 at the probes, 40% of the surface's size 2.0000"),
            "{w:?}"
        );
    }

    /// The regime by hand: the rows up to the first beyond 1% set the frequency bound, the
    /// size is the lattice's bounding-box diagonal, the motion the largest displacement of
    /// any probe.
    #[test]
    fn regime_by_hand() {
        let k = KnotVector::clamped_uniform(2, 2).unwrap();
        let pts: Vec<[f64; 3]> = (0..16)
            .map(|i| {
                [
                    0.5 * (i / 4) as f64,
                    0.3 * (i % 4) as f64,
                    0.1 * (i % 3) as f64,
                ]
            })
            .collect();
        let s = setup(Geometry::Surface(
            NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 16]).unwrap(),
        ));
        let row = |mode: usize, dnurbs: f64, off: f64| crate::outcome::FrequencyRow {
            mode,
            dnurbs,
            msm_mode: mode,
            msm: dnurbs * (1.0 + off),
            relative_difference: off,
            mac: Some(1.0),
        };
        let rows = [
            row(1, 1.0, 0.0),
            row(2, 2.0, 0.009),
            row(3, 3.0, -0.011),
            row(4, 4.0, 0.0),
        ];
        let mut trajectory = Trajectory::new(2);
        trajectory.t = vec![0.0, 1.0, 2.0];
        trajectory.probes = vec![
            vec![[0.0, 0.0, 1.0], [0.0, 0.3, 1.4], [0.0, 0.0, 1.0]],
            vec![[1.0, 1.0, 0.0], [1.0, 1.0, 0.2], [1.0, 1.0, -0.1]],
        ];
        let r = regime(&s, &trajectory, &rows);
        assert_eq!((r.frequency, r.modes), (2.0, 2));
        let positions = &s.lattice().positions;
        let extent = |x: usize| {
            let v = positions.iter().map(|p| p[x]);
            v.clone().fold(f64::NEG_INFINITY, f64::max) - v.fold(f64::INFINITY, f64::min)
        };
        let size = (extent(0).powi(2) + extent(1).powi(2) + extent(2).powi(2)).sqrt();
        assert!((r.size - size).abs() < 1e-15 * size);
        assert!((r.amplitude - LINEAR_RANGE * size).abs() < 1e-15 * size);
        assert!((r.motion - 0.5).abs() < 1e-15, "{}", r.motion);
        assert_eq!(regime(&s, &trajectory, &[row(1, 1.0, 0.02)]).modes, 0);
    }
}
