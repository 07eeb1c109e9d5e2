//! The spring derivation of a Kirchhoff–Love shell (docs/math.md §11): a triangulated lattice
//! of rest-length springs and dihedral hinges on the surface, stress-free at rest, its
//! constants from E, ν, t by energy equivalence, then calibrated on the shell's lowest modes
//! about the rest state.
//!
//! - Nodes `x_a = c(u_a, v_b)` on the lattice grid, triangulated with alternating diagonals
//!   ([`SpringLattice::triangulated`]); a node is fixed when the shell's constraints hold its
//!   control points ([`nurbspring_msm::FixedNodes::Auto`]).
//! - Masses: `m_a = ρ t · A_a`, `A_a` the area on the surface of the node's dual cell (the
//!   parameter cell between the midpoints to its neighbours), so the total is the shell's mass;
//!   node damping `γ A_a` (the shell's `D = (γ / ρt) M`).
//! - Membrane springs: an edge `e` of rest length `l_e` bounding triangles of rest area `A_e`
//!   in all has the weight `w_e = A_e / l_e²`; the constants are `k = (2/3) Ē` on grid-line
//!   edges and `(4/3) Ē` on diagonals, `Ē = E t / (1 − ν²)`. On a square grid this lattice is
//!   the plane-stress sheet of modulus `Ē` with ν = 1/3, the least-squares projection of the
//!   plane-stress tensor on the tensors a central-force lattice can have (Cauchy symmetry).
//!   Springs lock the Poisson ratio to 1/3: the shear modulus is `Ē/3` instead of
//!   `Ē (1 − ν)/2` (−4.8 % at ν = 0.3).
//! - Hinges (docs/math.md §5.2): weight `w_e = l_e² / A_e` (the discrete-shell scaling of
//!   Grinspun et al. 2003, `|ē| / h̄_e` up to a constant), constants `k = D` on grid-line edges
//!   and `D (1 − ν) / 2` on diagonals, `D = E t³ / (12 (1 − ν²))`: on a square grid the
//!   hinges store `½ D (κ₁₁² + κ₂₂² + 2 (1 − ν) κ₁₂²)` per unit area, the plate's energy
//!   `½ D (κ₁₁² + κ₂₂² + 2ν κ₁₁κ₂₂ + 2 (1 − ν) κ₁₂²)` without its coupling term `ν D κ₁₁κ₂₂`
//!   (no hinge sees the product of two curvatures): exact under cylindrical bending along a
//!   grid line and under twist, `ν/(1 + ν)` soft under a spherical cap.
//! - Calibration: the class constants `k_c = k⁰_c e^σ_c` by Gauss–Newton on
//!   `ln(ω_i / ω_j)` of the shell's lowest [`SPRING_MODES`] elastic modes `j` and the spring
//!   modes `i` matched to them by MAC (the derivative `∂ ln ω_i / ∂σ_c = k_c ψ_iᵀ G_c ψ_i /
//!   (2 ω_i² ψ_iᵀ M ψ_i)`), with a weak pull [`SPRING_PULL`] of each σ towards 0 so that a
//!   class the modes do not load keeps its rule value; then every constant times one factor
//!   so that the lowest elastic frequency is the shell's.
//!   The masses stay the lumped ones (the total mass and the gravity loads stay exact).

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use nurbspring_dnurbs::{Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, ShellMaterial};
use nurbspring_geom::norm;
use nurbspring_geom::{GaussLegendre, NurbsSurface, area_element, cross};
use nurbspring_msm::{Class, Constants, HingeKind, LatticeOptions, SpringKind, SpringLattice};
use serde::Serialize;

use crate::springs_check::{self, LargeMotion, SmallMotion, sub};
use crate::{DeriveError, InitialConditions, Method, TimeSettings};

mod calibration;
pub(crate) use calibration::ShellModes;
use calibration::calibrate;

/// The shell modes the calibration by class fits (fewer when the lattice or the shell has
/// fewer).
pub const SPRING_MODES: usize = 12;
/// The shell modes the calibration by class and band fits (as many as by class: on a 9²
/// lattice the 13th to 24th plate modes are resolved too coarsely to fit).
pub const BAND_SPRING_MODES: usize = SPRING_MODES;
/// The modes the frequency table reports.
pub const TABLE_SPRING_MODES: usize = 6;
/// Weight of the pull of each log class scale towards its rule value, beside one row of
/// weight 1 per fitted mode.
pub const SPRING_PULL: f64 = 0.05;
/// The same under the calibration by class and band, for a whole class (each group's pull
/// is its share of the class's elements times this). Weak: the bands near free edges must
/// move far from the rule to carry what hinges miss there (docs/derivations.md: with
/// [`SPRING_PULL`] the 9² free-edge plate keeps 3/6 modes within 3 %, with 0.005 6/6 at
/// +2.3 %, with this 6/6 at +1.8 %).
pub const BAND_PULL: f64 = 5e-4;
/// The shell's elastic modes the excitation derivation chooses its [`EXCITED_MODES`] from.
pub const EXCITATION_CANDIDATES: usize = 2 * SPRING_MODES;
/// Gauss–Newton iterations of the calibration at most.
pub const CALIBRATION_ITERATIONS: usize = 12;
/// Halvings of a Gauss–Newton step that does not lower the calibration's objective, at most.
pub const STEP_HALVINGS: usize = 4;

/// Rigid-body modes the mode count allows for besides the fitted ones.
pub const RIGID_MODES: usize = 6;
/// A mode is rigid (a mechanism of the constraints) below this fraction of the highest
/// frequency computed.
pub const RIGID_FREQUENCY: f64 = 1e-4;

/// The element classes of a spring model.
pub const SPRING_CLASSES: [Class; 4] = [
    Class::Spring(SpringKind::Structural),
    Class::Spring(SpringKind::Shear),
    Class::Hinge(HingeKind::Grid),
    Class::Hinge(HingeKind::Diagonal),
];

/// Everything the spring derivation needs (a Kirchhoff–Love scene, translated).
#[derive(Clone, Debug)]
pub struct SpringsConfig {
    /// The surface at rest.
    pub surface: NurbsSurface,
    /// The shell's material.
    pub shell: ShellMaterial,
    /// Loads (dead loads: the large-motion runs scale them).
    pub loads: Loads,
    /// Constraints.
    pub constraints: Constraints,
    /// Shell options (quadrature).
    pub dnurbs: DnurbsOptions,
    /// Lattice grid and fixed-node rule (constants, masses, damping and gravity are derived).
    pub lattice: LatticeOptions,
    /// The scene's initial state (the small-motion run's excitation, with the loads).
    pub initial: InitialConditions,
    /// The scene's time step and end (the validation runs choose their own horizon).
    pub time: TimeSettings,
    /// Probe parameters, the centre first.
    pub probes: Vec<(f64, f64)>,
    /// The derivation: [`Method::Springs`] (one scale per class) or [`Method::Modal`] (one
    /// per class and band), [`Method::spring_groups`].
    pub method: Method,
}

/// A shell mode the excitation derivation fits.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExcitedMode {
    /// Shell mode (1-based, rigid modes counted).
    pub mode: usize,
    /// Its angular frequency [rad/s].
    pub omega: f64,
    /// Its share `a_j² / Σ a²` of the motion the scene's initial state and loads excite
    /// (docs/math.md §8.4), over the modes fitted.
    pub share: f64,
}

/// The scale of one calibration group of a modal spring model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GroupScale {
    /// `"hinge[u0,vin]"`: the class, then its bands along u and v ([`crate::FitGroup::name`]).
    pub group: String,
    /// Its springs or hinges.
    pub elements: usize,
    /// The factor on the rule's weights of its elements.
    pub scale: f64,
}

/// One row of the frequency table: a shell mode and the spring mode of largest MAC.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpringFrequency {
    /// Shell mode (1-based).
    pub mode: usize,
    /// Its angular frequency [rad/s].
    pub shell: f64,
    /// The matched spring-model mode (1-based), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm_mode: Option<usize>,
    /// Its angular frequency [rad/s].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub msm: Option<f64>,
    /// MAC of the match.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mac: Option<f64>,
    /// `(ω_msm − ω_shell) / ω_shell`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relative_error: Option<f64>,
}

/// A class's constant by the rule and after calibration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ClassConstant {
    /// The class name (`structural`, `shear`, `hinge`, `hinge_diagonal`).
    pub class: String,
    /// Elements of the class.
    pub count: usize,
    /// The rule's constant.
    pub rule: f64,
    /// The calibrated constant.
    pub calibrated: f64,
}

/// A derived spring model and its validation against the shell.
#[derive(Clone, Debug, Serialize)]
pub struct SpringsDerivation {
    /// The derivation that made it ([`SpringsConfig::method`]).
    #[serde(skip)]
    pub method: Method,
    /// The model (constants, weights, masses, damping, fixed nodes; no node forces).
    #[serde(skip)]
    pub lattice: SpringLattice,
    /// Initial node velocities (the scene's, mapped by Ω).
    #[serde(skip)]
    pub node_velocities: Vec<[f64; 3]>,
    /// The lattice node of each probe.
    pub probe_nodes: Vec<usize>,
    /// The size the motions are measured against: the diagonal of the rest surface's bounding
    /// box [m].
    pub size: f64,
    /// Total node mass [kg] (= ρ t × area).
    pub total_mass: f64,
    /// Constants by class.
    pub constants: Vec<ClassConstant>,
    /// The scale of each group of the calibration by class and band (the modal derivation);
    /// each element's stiffness is its class constant times its weight, the rule's weight
    /// times its group's scale. Empty for the calibration by class.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub groups: Vec<GroupScale>,
    /// The shell modes the excitation derivation fitted, with their shares of the motion
    /// (empty for the others, which fit the lowest).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub excited_modes: Vec<ExcitedMode>,
    /// The factor that made the lowest frequency the shell's.
    pub frequency_factor: f64,
    /// Shell modes the calibration fitted.
    pub fitted_modes: usize,
    /// RMS of `ln(ω_springs / ω_shell)` over the fitted modes, matched by MAC, before the
    /// lowest frequency was made exact.
    pub fit_residual: f64,
    /// The lowest shell modes and their matched spring modes.
    pub frequencies: Vec<SpringFrequency>,
    /// The small-motion run.
    pub small_motion: SmallMotion,
    /// The large-motion runs (`None` when the scene has no loads to scale).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub large_motion: Option<LargeMotion>,
    /// Why there is no large-motion run, when there is none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub large_motion_skipped: Option<String>,
    /// The one-line verdict.
    pub verdict: String,
}

/// Derives the spring model of a shell scene and validates it (module docs); `stage` is told
/// each stage as it begins (for progress lines).
pub fn derive_springs(
    config: &SpringsConfig,
    cancel: Option<Arc<AtomicBool>>,
    stage: &mut dyn FnMut(&str),
) -> Result<SpringsDerivation, DeriveError> {
    let groups = config
        .method
        .spring_groups()
        .ok_or_else(|| DeriveError::InvalidInput {
            input: crate::Input::Derivation,
            value: format!("\"{}\"", config.method.name()),
            reason: format!(
                "the spring models of a Kirchhoff–Love shell are derived by {}",
                Method::names_where(|m| m.spring_groups().is_some())
            ),
        })?;
    stage("the shell's modes and the calibration");
    let geometry = Geometry::Surface(config.surface.clone());
    let model = DnurbsModel::kirchhoff_love(
        geometry.clone(),
        config.shell,
        config.loads.clone(),
        &config.constraints,
        config.dnurbs.clone(),
    )?;
    refuse_unrepresentable(&model, &config.loads)?;
    let (mut lattice, rule) = rule_lattice(
        &config.surface,
        &config.shell,
        &config.lattice,
        model.fixed_points(),
    )?;
    let map = springs_check::NodeMap::new(&geometry, &lattice, &model)?;
    // The excitation derivation fits the modes the scene's own excitation moves.
    let excitation = (config.method == Method::Excitation).then_some(&config.initial);
    let calibration = calibrate(&model, &mut lattice, &map, &rule, groups, excitation)?;
    let size = bounding_diagonal(&lattice.positions);
    let node_velocities = map.node_velocities(&config.initial.state(&model));
    let probe_nodes: Vec<usize> = config
        .probes
        .iter()
        .map(|&(u, v)| lattice.node_nearest(u, v))
        .collect();
    let check = springs_check::Check {
        model: &model,
        lattice: &lattice,
        map: &map,
        size,
        omega1: calibration.omega1,
        mechanism: !calibration.rigid.is_empty(),
        time: &config.time,
        cancel,
    };
    stage("the small-motion check");
    let small_motion = check.small_motion(
        &config.initial,
        probe_nodes[0],
        &calibration.rigid,
        &calibration.first_elastic,
        &|force| check.lattice_at_rest(force),
    )?;
    let (large_motion, large_motion_skipped) = if config.loads.is_zero() {
        (
            None,
            Some("the scene has no loads to scale into large motion".to_string()),
        )
    } else {
        stage("the large-motion check (static load path, then the dynamic run)");
        (
            Some(check.large_motion(
                &config.shell,
                &config.loads,
                &geometry,
                &config.constraints,
                &config.dnurbs,
            )?),
            None,
        )
    };
    let constants = SPRING_CLASSES
        .iter()
        .map(|&c| ClassConstant {
            class: c.name().to_string(),
            count: lattice.count(c),
            rule: rule.get(c).unwrap_or(0.0),
            calibrated: lattice.constants().get(c).unwrap_or(0.0),
        })
        .collect();
    let mut d = SpringsDerivation {
        method: config.method,
        groups: calibration.groups,
        excited_modes: calibration.excited,
        total_mass: lattice.masses.iter().sum(),
        lattice,
        node_velocities,
        probe_nodes,
        size,
        constants,
        frequency_factor: calibration.factor,
        fitted_modes: calibration.fitted,
        fit_residual: calibration.residual,
        frequencies: calibration.table,
        small_motion,
        large_motion,
        large_motion_skipped,
        verdict: String::new(),
    };
    d.verdict = verdict(&d);
    Ok(d)
}

/// What the lattice cannot carry: partial holds and linear constraints (its nodes are fixed
/// whole) and edge moments (it has no rotations).
pub(crate) fn refuse_unrepresentable(
    model: &DnurbsModel,
    loads: &Loads,
) -> Result<(), DeriveError> {
    let held_whole = 3 * model.fixed_points().len();
    let held = model.dof_map().fixed().len();
    if model.has_linear_constraints() || held != held_whole {
        return Err(DeriveError::InvalidInput {
            input: crate::Input::Constraints,
            value: "a partial hold, symmetry or linear constraint".into(),
            reason: "the spring derivation fixes lattice nodes whole; hold whole control points \
                     (fixed rings, clamped or pinned edges)"
                .into(),
        });
    }
    if let Some(e) = loads.edges.iter().find(|e| e.moment != 0.0) {
        return Err(DeriveError::InvalidInput {
            input: crate::Input::EdgeLoads,
            value: format!("moment {} on edge {}", e.moment, e.edge.name()),
            reason: "a spring lattice has no rotations, so an edge moment has no node forces \
                     that follow it through large rotation; give edge forces instead"
                .into(),
        });
    }
    Ok(())
}

/// The triangulated lattice of `options` (grid, fixed-node rule) on `surface` with the rule's
/// weights, constants, masses and damping (module docs), before calibration; node forces and
/// gravity none (loads enter as work-equivalent node forces). Returns the rule's constants.
pub fn rule_lattice(
    surface: &NurbsSurface,
    shell: &ShellMaterial,
    options: &LatticeOptions,
    fixed_control_points: &[usize],
) -> Result<(SpringLattice, Constants), DeriveError> {
    let mut options = options.clone();
    options.constants = Constants::from_pairs(SPRING_CLASSES.map(|c| (c, 1.0)));
    options.gravity = [0.0; 3];
    let mut lattice = SpringLattice::triangulated(surface, &options, fixed_control_points)?;
    let rule = apply_rules(&mut lattice, surface, shell)?;
    Ok((lattice, rule))
}

/// Sets the rule's weights, constants, masses and damping (module docs); returns the rule's
/// constants.
fn apply_rules(
    lattice: &mut SpringLattice,
    surface: &NurbsSurface,
    shell: &ShellMaterial,
) -> Result<Constants, DeriveError> {
    let x = &lattice.positions;
    let area = |t: &[usize; 3]| {
        let (a, b, c) = (x[t[0]], x[t[1]], x[t[2]]);
        0.5 * norm(cross(sub(b, a), sub(c, a)))
    };
    let mut edge_area: HashMap<(usize, usize), f64> = HashMap::new();
    for t in &lattice.triangles {
        let at = area(t);
        for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edge_area.entry((p.min(q), p.max(q))).or_default() += at;
        }
    }
    let area_of = |p: usize, q: usize| edge_area.get(&(p.min(q), p.max(q))).copied();
    let degenerate = |what: &str, p: usize, q: usize| DeriveError::InvalidInput {
        input: crate::Input::Grid,
        value: format!("nodes {p} and {q}"),
        reason: format!(
            "the {what} between them has no area on the rest surface (coincident nodes, e.g. \
             at a degenerate edge of the net); choose a grid whose triangles have area"
        ),
    };
    for s in &mut lattice.springs {
        let l2 = s.rest_length * s.rest_length;
        let a = area_of(s.a, s.b).filter(|&a| a > 0.0 && l2 > 0.0);
        s.weight = a.ok_or_else(|| degenerate("edge", s.a, s.b))? / l2;
    }
    for h in &mut lattice.hinges {
        let [p, q, ..] = h.nodes;
        let l2 = norm2(sub(x[p], x[q]));
        let a = area_of(p, q).filter(|&a| a > 0.0 && l2 > 0.0);
        h.weight = l2 / a.ok_or_else(|| degenerate("hinge", p, q))?;
    }
    let e_bar = shell.membrane_stiffness();
    let d = shell.bending_stiffness();
    let rule = Constants::from_pairs([
        (Class::Spring(SpringKind::Structural), 2.0 / 3.0 * e_bar),
        (Class::Spring(SpringKind::Shear), 4.0 / 3.0 * e_bar),
        (Class::Hinge(HingeKind::Grid), d),
        (
            Class::Hinge(HingeKind::Diagonal),
            0.5 * d * (1.0 - shell.poisson),
        ),
    ]);
    lattice.set_constants(&rule);
    let areas = dual_areas(lattice, surface)?;
    lattice.masses = areas.iter().map(|a| shell.mass_per_area() * a).collect();
    lattice.damping = areas.iter().map(|a| shell.gamma * a).collect();
    Ok(rule)
}

/// The area on the surface of each node's dual cell: the parameter cell between the midpoints
/// to its grid neighbours (the domain's edge at the boundary), integrated by Gauss–Legendre
/// on each knot span it covers.
fn dual_areas(lattice: &SpringLattice, surface: &NurbsSurface) -> Result<Vec<f64>, DeriveError> {
    let (n_u, n_v) = lattice.grid.ok_or(DeriveError::LatticeWithoutParameters)?;
    let params = lattice
        .params
        .as_ref()
        .ok_or(DeriveError::LatticeWithoutParameters)?;
    let us: Vec<f64> = (0..n_u).map(|i| params[i * n_v].0).collect();
    let vs: Vec<f64> = (0..n_v).map(|j| params[j].1).collect();
    let ((u0, u1), (v0, v1)) = surface.domain();
    let cells = |t: &[f64], lo: f64, hi: f64, knots: &[f64]| -> Vec<Vec<f64>> {
        (0..t.len())
            .map(|i| {
                let a = if i == 0 { lo } else { 0.5 * (t[i - 1] + t[i]) };
                let b = if i + 1 == t.len() {
                    hi
                } else {
                    0.5 * (t[i] + t[i + 1])
                };
                let mut cuts = vec![a];
                cuts.extend(knots.iter().copied().filter(|&k| k > a && k < b));
                cuts.push(b);
                cuts.dedup();
                cuts
            })
            .collect()
    };
    let cu = cells(&us, u0, u1, surface.basis_u().knots().knots());
    let cv = cells(&vs, v0, v1, surface.basis_v().knots().knots());
    let rule = GaussLegendre::new(4)?;
    let mut out = vec![0.0; n_u * n_v];
    for (i, su) in cu.iter().enumerate() {
        for (j, sv) in cv.iter().enumerate() {
            let mut a = 0.0;
            for wu in su.windows(2) {
                for wv in sv.windows(2) {
                    let (hu, hv) = (0.5 * (wu[1] - wu[0]), 0.5 * (wv[1] - wv[0]));
                    for (&xu, &gu) in rule.nodes().iter().zip(rule.weights()) {
                        for (&xv, &gv) in rule.nodes().iter().zip(rule.weights()) {
                            let u = wu[0] + hu * (xu + 1.0);
                            let v = wv[0] + hv * (xv + 1.0);
                            let d = surface.derivatives(u, v, 1)?;
                            a += gu * gv * hu * hv * area_element(d.u, d.v);
                        }
                    }
                }
            }
            out[i * n_v + j] = a;
        }
    }
    Ok(out)
}

/// The one-line verdict (docs/derivations.md, "the spring derivation").
fn verdict(d: &SpringsDerivation) -> String {
    let within = d
        .frequencies
        .iter()
        .take_while(|r| r.relative_error.is_some_and(|e| e.abs() <= 0.03))
        .count();
    let mut parts = vec![format!(
        "the lowest {within} of {} shell modes within 3 %",
        d.frequencies.len()
    )];
    parts.push(format!(
        "small motion: probe error {:.1} % over {:.0} periods",
        100.0 * d.small_motion.relative_rms,
        d.small_motion.periods
    ));
    match &d.large_motion {
        Some(l) => {
            match (l.largest_displacement, l.static_error) {
                (Some(reach), Some(e)) => parts.push(format!(
                    "large static motion up to {:.0} % of the size{}: node error {:.1} %{}",
                    100.0 * reach,
                    if l.shell_limit.is_some() {
                        " (below the shell's limit point)"
                    } else {
                        ""
                    },
                    100.0 * e,
                    if l.static_failure.is_some() {
                        " (the spring model buckles beyond)"
                    } else {
                        ""
                    }
                )),
                _ => parts.push("large static motion not compared (the load path stopped)".into()),
            }
            match &l.dynamic {
                Some(r) => parts.push(format!(
                    "dynamic step load over {:.3} s: node error {:.1} %",
                    r.t_end,
                    100.0 * r.max_error
                )),
                None => parts.push("dynamic large motion not compared (a run stopped)".into()),
            }
        }
        None => parts.push("large motion not checked (no loads)".into()),
    }
    let usable = within >= d.frequencies.len().min(3)
        && d.small_motion.relative_rms <= 0.05
        && d.large_motion
            .as_ref()
            .is_none_or(|l| l.static_error.is_some_and(|e| e <= 0.03));
    format!(
        "{}: {}",
        if usable {
            "Usable in the regimes checked"
        } else {
            "Use with care"
        },
        parts.join("; ")
    )
}

pub(crate) fn bounding_diagonal(x: &[[f64; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in x {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    norm(sub(hi, lo))
}

fn norm2(a: [f64; 3]) -> f64 {
    a[0] * a[0] + a[1] * a[1] + a[2] * a[2]
}
