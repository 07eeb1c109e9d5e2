//! Validation of a deserialized scene: every value is checked and every problem reported with
//! its key path and value.

use nurbspring_sim::representable;
use std::path::Path;

use nurbspring_derive::Method;
use nurbspring_dnurbs::{
    DnurbsError, DnurbsOptions, Geometry, Integration, Material, MaterialModel, RestShape,
    ShellMaterial,
};
use nurbspring_geom::{GeomError, KnotVector, NurbsCurve, NurbsSurface};
use nurbspring_io::output::format_f64;
use nurbspring_msm::{LinearKind, MsmError, MsmModel};
use nurbspring_sim::{SimError, check_time};

use crate::build;
use crate::spec::*;
use crate::{Problem, SceneError};

mod geometry;
use geometry::*;
pub(crate) use geometry::{build_curve, build_surface};

mod msm;
use msm::*;

/// Collected problems.
#[derive(Default)]
struct Problems(Vec<Problem>);

fn fmt_list(v: &[f64]) -> String {
    if v.len() <= 12 {
        format!(
            "[{}]",
            v.iter()
                .map(|&x| format_f64(x))
                .collect::<Vec<_>>()
                .join(", ")
        )
    } else {
        let head: Vec<String> = v[..5].iter().map(|&x| format_f64(x)).collect();
        let tail: Vec<String> = v[v.len() - 2..].iter().map(|&x| format_f64(x)).collect();
        format!(
            "[{}, …, {}] ({} values)",
            head.join(", "),
            tail.join(", "),
            v.len()
        )
    }
}

impl Problems {
    fn push(
        &mut self,
        key: impl Into<String>,
        value: impl Into<String>,
        message: impl Into<String>,
    ) {
        self.0.push(Problem::new(key, value, message));
    }

    fn len(&self) -> usize {
        self.0.len()
    }

    /// Finite number of magnitude at most [`nurbspring_sim::MAX_MAGNITUDE`] (larger values overflow the
    /// assembly); returns whether it is.
    fn finite(&mut self, key: &str, v: f64) -> bool {
        if representable(v) {
            true
        } else {
            self.push(
                key,
                format_f64(v),
                "must be a finite number of magnitude at most 1e30 (larger values overflow)",
            );
            false
        }
    }

    fn positive(&mut self, key: &str, v: f64, what: &str) {
        if self.finite(key, v) && v <= 0.0 {
            self.push(key, format_f64(v), format!("{what} must be positive"));
        }
    }

    fn vec3(&mut self, key: &str, v: &[f64; 3]) {
        for (c, x) in v.iter().enumerate() {
            self.finite(&format!("{key}[{c}]"), *x);
        }
    }
}

/// What later checks need to know about the geometry.
struct GeomInfo {
    /// The geometry, built and valid.
    geometry: Geometry,
    surface: bool,
    n_u: usize,
    n_v: usize,
    domain_u: (f64, f64),
    domain_v: (f64, f64),
}

/// Keys whose presence matters beyond their value: a key left out takes a default that
/// depends on other keys.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct GivenKeys {
    /// `simulation.dnurbs_integrator` (default: Terzopoulos–Qin for the tension plate, Newmark
    /// for the shell).
    pub(crate) dnurbs_integrator: bool,
    /// `dnurbs.integrate_over` (the shell refuses it: it is always integrated over the area).
    pub(crate) integrate_over: bool,
}

impl GivenKeys {
    /// The keys present in the scene text (`None` when it is not a TOML table; the parse
    /// error is reported elsewhere).
    pub(crate) fn of(text: &str) -> Self {
        let Ok(table) = text.parse::<toml::Table>() else {
            return Self::default();
        };
        let has = |section: &str, key: &str| {
            table
                .get(section)
                .and_then(|v| v.as_table())
                .is_some_and(|t| t.contains_key(key))
        };
        Self {
            dnurbs_integrator: has("simulation", "dnurbs_integrator"),
            integrate_over: has("dnurbs", "integrate_over"),
        }
    }
}

/// Validates everything and builds the scene.
pub(crate) fn build_scene(
    raw: RawScene,
    path: &Path,
    given: GivenKeys,
) -> Result<Scene, SceneError> {
    let mut p = Problems::default();
    let section = if raw.surface.is_some() {
        "surface"
    } else {
        "curve"
    };
    let (geometry, info) = match (raw.surface, raw.curve) {
        (Some(_), Some(_)) => {
            p.push(
                "surface, curve",
                "",
                "give exactly one of [surface] or [curve], not both",
            );
            (None, None)
        }
        (None, None) => {
            p.push(
                "surface",
                "",
                "missing geometry: add a [surface] or a [curve] table",
            );
            (None, None)
        }
        (Some(RawGeometry::Inline(s)), None) => match surface_spec(s, &mut p) {
            Some(spec) => {
                let info = surface_info(&spec, &mut p);
                (Some(GeometrySpec::Surface(spec)), info)
            }
            None => (None, None),
        },
        (None, Some(RawGeometry::Inline(c))) => match curve_spec(c, &mut p) {
            Some(spec) => {
                let info = curve_info(&spec, &mut p);
                (Some(GeometrySpec::Curve(spec)), info)
            }
            None => (None, None),
        },
        (Some(RawGeometry::File { file, index }), None)
        | (None, Some(RawGeometry::File { file, index })) => {
            match crate::geometry_file::load_geometry(path, section, &file, index) {
                Ok(spec) => {
                    let info = match &spec {
                        GeometrySpec::Surface(s) => surface_info(s, &mut p),
                        GeometrySpec::Curve(c) => curve_info(c, &mut p),
                    };
                    (Some(spec), info)
                }
                Err(problem) => {
                    p.0.push(problem);
                    (None, None)
                }
            }
        }
    };
    let material = check_material(&raw.material, info.as_ref(), &mut p);
    check_loads(&raw.loads, &material, &raw.dnurbs, info.as_ref(), &mut p);
    check_constraints(&raw.constraints, &raw.dnurbs, info.as_ref(), &mut p);
    check_dnurbs(&raw.dnurbs, &mut p);
    if material.shell().is_some() {
        check_shell_options(&raw.dnurbs, given, &mut p);
    }
    let mut simulation = raw.simulation;
    let mut dnurbs = raw.dnurbs;
    if material.shell().is_some() {
        // The shell's defaults: implicit Newmark, the area measure.
        if !given.dnurbs_integrator {
            simulation.dnurbs_integrator = nurbspring_sim::IntegratorKind::Newmark;
        }
        dnurbs.integration = Integration::Area;
    }
    let initial = initial_spec(raw.initial, &dnurbs, info.as_ref(), &mut p);
    check_simulation(&simulation, &material, &dnurbs, info.as_ref(), &mut p);
    let shell = material.shell().is_some();
    let method = raw.fit.derivation_for(shell, &dnurbs, &raw.constraints).0;
    if !method.takes(shell) {
        p.push(
            "fit.derivation",
            format!("\"{}\"", method.name()),
            if shell {
                format!(
                    "a Kirchhoff–Love scene derives rest-length springs and hinges: fit.derivation = {} (or leave it out)",
                    Method::names_taking(true)
                )
            } else {
                format!(
                    "the spring derivation needs a shell: material.model = \"kirchhoff-love\" (the tension plate derives {})",
                    Method::names_taking(false)
                )
            },
        );
    }
    check_msm(
        &raw.msm,
        &material,
        &raw.loads,
        method,
        info.as_ref(),
        &mut p,
    );
    if raw.fit.mass == MassMethod::Fixed && raw.msm.mass.is_none() {
        p.push(
            "msm.mass",
            "(not given)",
            "fit.mass = \"fixed\" uses msm.mass as the node mass: give it, or let the derivation choose the mass (fit.mass = \"eigenvalue-scan\")",
        );
    }
    if raw.output.vtk_every == Some(0) {
        p.push("output.vtk_every", "0", "must be at least 1");
    }
    match (geometry, p.len()) {
        (Some(geometry), 0) => Ok(Scene {
            path: path.to_path_buf(),
            geometry,
            material,
            loads: raw.loads,
            constraints: raw.constraints,
            dnurbs,
            initial: initial.unwrap_or_default(),
            simulation,
            msm: raw.msm,
            fit: raw.fit,
            output: raw.output,
        }),
        _ => Err(SceneError::Invalid {
            path: path.to_path_buf(),
            problems: p.0,
        }),
    }
}

/// The keys of the tension plate only (`gamma` is shared).
const PLATE_KEYS: [&str; 6] = ["mu", "alpha11", "alpha22", "beta11", "beta12", "beta22"];
/// The keys of the shell only.
const SHELL_KEYS: [&str; 4] = ["young", "poisson", "thickness", "density"];

impl RawMaterial {
    fn plate_values(&self) -> [(&'static str, Option<f64>); 6] {
        [
            ("mu", self.mu),
            ("alpha11", self.alpha11),
            ("alpha22", self.alpha22),
            ("beta11", self.beta11),
            ("beta12", self.beta12),
            ("beta22", self.beta22),
        ]
    }

    fn shell_values(&self) -> [(&'static str, Option<f64>); 4] {
        [
            ("young", self.young),
            ("poisson", self.poisson),
            ("thickness", self.thickness),
            ("density", self.density),
        ]
    }
}

/// `[material]`: the model named by `model` (the tension plate by default), the keys of the
/// other model refused by name, the rules of `Material::problems` or
/// `ShellMaterial::problems` with their key paths. An invalid table gives the default
/// material beside its problems.
fn check_material(m: &RawMaterial, info: Option<&GeomInfo>, p: &mut Problems) -> MaterialModel {
    let curve = info.is_some_and(|g| !g.surface);
    let push_rules = |errors: Vec<DnurbsError>, p: &mut Problems| {
        for e in errors {
            if let DnurbsError::InvalidMaterial { name, value, rule } = e {
                p.push(format!("material.{name}"), format_f64(value), rule);
            }
        }
    };
    match m.model.as_deref() {
        None | Some("tension-plate") => {
            for (key, value) in m.shell_values() {
                if let Some(v) = value {
                    p.push(
                        format!("material.{key}"),
                        format_f64(v),
                        format!(
                            "a key of model = \"kirchhoff-love\"; the tension plate (model = \
                             \"tension-plate\", the default) is given by mu, gamma and alpha/beta \
                             ({}); add model = \"kirchhoff-love\" for a shell",
                            PLATE_KEYS.join(", ")
                        ),
                    );
                }
            }
            let d = Material::default();
            let material = Material {
                mu: m.mu.unwrap_or(d.mu),
                gamma: m.gamma.unwrap_or(d.gamma),
                alpha11: m.alpha11.unwrap_or(d.alpha11),
                alpha22: m.alpha22.unwrap_or(d.alpha22),
                beta11: m.beta11.unwrap_or(d.beta11),
                beta12: m.beta12.unwrap_or(d.beta12),
                beta22: m.beta22.unwrap_or(d.beta22),
            };
            push_rules(material.problems(curve), p);
            MaterialModel::TensionPlate(material)
        }
        Some("kirchhoff-love") => {
            for (key, value) in m.plate_values() {
                if let Some(v) = value {
                    p.push(
                        format!("material.{key}"),
                        format_f64(v),
                        format!(
                            "the Kirchhoff–Love shell is given by {} (and gamma); mu, alpha and \
                             beta belong to model = \"tension-plate\"",
                            SHELL_KEYS.join(", ")
                        ),
                    );
                }
            }
            for (key, value) in m.shell_values() {
                if value.is_none() {
                    p.push(
                        format!("material.{key}"),
                        "",
                        format!(
                            "missing: model = \"kirchhoff-love\" needs {}",
                            SHELL_KEYS.join(", ")
                        ),
                    );
                }
            }
            if curve {
                p.push(
                    "material.model",
                    "\"kirchhoff-love\"",
                    "the Kirchhoff–Love shell needs a [surface]; a curve is a tension plate \
                     (string) only",
                );
            }
            let shell = ShellMaterial {
                young: m.young.unwrap_or(1.0),
                poisson: m.poisson.unwrap_or(0.0),
                thickness: m.thickness.unwrap_or(1.0),
                density: m.density.unwrap_or(1.0),
                gamma: m.gamma.unwrap_or(0.0),
            };
            let given: Vec<&str> = m
                .shell_values()
                .iter()
                .filter(|(_, v)| v.is_some())
                .map(|(k, _)| *k)
                .chain(m.gamma.map(|_| "gamma"))
                .collect();
            let rules: Vec<DnurbsError> = shell
                .problems()
                .into_iter()
                .filter(|e| match e {
                    DnurbsError::InvalidMaterial { name, .. } => given.contains(name),
                    _ => true,
                })
                .collect();
            push_rules(rules, p);
            MaterialModel::KirchhoffLove(shell)
        }
        Some(other) => {
            p.push(
                "material.model",
                format!("\"{other}\""),
                "expected \"tension-plate\" (the paper's energy, the default) or \
                 \"kirchhoff-love\" (a thin shell of E, ν, thickness, density)",
            );
            MaterialModel::default()
        }
    }
}

/// The `[dnurbs]` options a shell refuses, naming each key: its weights are geometry, its rest
/// shape is the surface and it is integrated over the surface (docs/math.md §10).
fn check_shell_options(d: &DnurbsOptions, given: GivenKeys, p: &mut Problems) {
    if d.weights_as_dofs {
        p.push(
            "dnurbs.weights_as_dofs",
            "true",
            "the Kirchhoff–Love shell's weights are part of its geometry, not unknowns",
        );
    }
    if d.rest_shape != RestShape::Initial {
        p.push(
            "dnurbs.rest_shape",
            format!("\"{}\"", d.rest_shape.name()),
            "the Kirchhoff–Love shell's rest shape is the scene's surface",
        );
    }
    if given.integrate_over && d.integration == Integration::Parameter {
        p.push(
            "dnurbs.integrate_over",
            "\"parameter\"",
            "the Kirchhoff–Love shell is integrated over the surface's area (\"area\", the \
             shell's only measure): leave the key out",
        );
    }
}

/// Checks that parameter `x` lies in `domain`.
fn check_param(p: &mut Problems, key: &str, x: f64, domain: (f64, f64)) {
    if p.finite(key, x) && (x < domain.0 || x > domain.1) {
        p.push(
            key,
            format_f64(x),
            format!(
                "outside the parameter domain [{}, {}]",
                format_f64(domain.0),
                format_f64(domain.1)
            ),
        );
    }
}

fn check_loads(
    l: &LoadsSpec,
    material: &MaterialModel,
    d: &DnurbsOptions,
    info: Option<&GeomInfo>,
    p: &mut Problems,
) {
    p.vec3("loads.gravity", &l.gravity);
    p.vec3("loads.distributed", &l.distributed);
    for (k, e) in l.edge.iter().enumerate() {
        let key = format!("loads.edge[{k}]");
        p.vec3(&format!("{key}.force"), &e.force);
        p.finite(&format!("{key}.moment"), e.moment);
        if info.is_some_and(|g| !g.surface) {
            p.push(
                format!("{key}.edge"),
                format!("\"{}\"", e.edge.name()),
                "a curve has no edges: edge loads need a [surface]",
            );
        }
        if e.moment != 0.0 && material.shell().is_none() {
            p.push(
                format!("{key}.moment"),
                format_f64(e.moment),
                "edge moments need model = \"kirchhoff-love\" (the tension plate has no \
                 rotations)",
            );
        }
        if d.weights_as_dofs {
            p.push(
                format!("{key}.edge"),
                format!("\"{}\"", e.edge.name()),
                "edge loads need constant weights (dnurbs.weights_as_dofs = false)",
            );
        }
    }
    for (k, pl) in l.point.iter().enumerate() {
        let key = format!("loads.point[{k}]");
        p.vec3(&format!("{key}.force"), &pl.force);
        let Some(g) = info else {
            p.finite(&format!("{key}.u"), pl.u);
            continue;
        };
        check_param(p, &format!("{key}.u"), pl.u, g.domain_u);
        match (g.surface, pl.v) {
            (true, Some(v)) => check_param(p, &format!("{key}.v"), v, g.domain_v),
            (true, None) => p.push(
                format!("{key}.v"),
                "",
                "missing: a point load on a surface needs u and v",
            ),
            (false, Some(v)) => p.push(
                format!("{key}.v"),
                format_f64(v),
                "a point load on a curve has u only",
            ),
            (false, None) => {}
        }
    }
}

/// Checks a control-point index `[i, j]` (curves `[i]`).
fn check_point_index(p: &mut Problems, key: &str, idx: &[usize], g: &GeomInfo) {
    let value = format!("{idx:?}");
    let arity = if g.surface { 2 } else { 1 };
    if idx.len() != arity {
        let want = if g.surface { "[i, j]" } else { "[i]" };
        p.push(key, value, format!("a control point is given as {want}"));
        return;
    }
    if idx[0] >= g.n_u || (g.surface && idx[1] >= g.n_v) {
        let size = if g.surface {
            format!("{} x {}", g.n_u, g.n_v)
        } else {
            g.n_u.to_string()
        };
        p.push(key, value, format!("outside the {size} control net"));
    }
}

fn check_constraints(
    c: &ConstraintsSpec,
    d: &DnurbsOptions,
    info: Option<&GeomInfo>,
    p: &mut Problems,
) {
    if c.fixed_point_weights == FixedPointWeights::Held && (!d.weights_as_dofs || c.fixed_weights) {
        p.push(
            "constraints.fixed_point_weights",
            "\"held\"".to_string(),
            "applies only to free weights: dnurbs.weights_as_dofs = true and \
             constraints.fixed_weights = false",
        );
    }
    for (r, row) in c.linear.iter().enumerate() {
        let key = format!("constraints.linear[{r}]");
        p.finite(&format!("{key}.rhs"), row.rhs);
        if row.terms.is_empty() {
            p.push(
                format!("{key}.terms"),
                "[]",
                "a constraint needs at least one term",
            );
        } else if row.terms.iter().all(|t| t.coefficient == 0.0) {
            p.push(format!("{key}.terms"), "", "every coefficient is zero");
        }
        for (t, term) in row.terms.iter().enumerate() {
            let tk = format!("{key}.terms[{t}]");
            p.finite(&format!("{tk}.coefficient"), term.coefficient);
            if term.component == Component::W && !d.weights_as_dofs {
                p.push(
                    format!("{tk}.component"),
                    "\"w\"",
                    "weights are constants unless dnurbs.weights_as_dofs = true",
                );
            }
            if let Some(g) = info {
                check_point_index(p, &format!("{tk}.point"), &term.point, g);
            }
        }
    }
    for (k, e) in c.edge.iter().enumerate() {
        let key = format!("constraints.edge[{k}]");
        if info.is_some_and(|g| !g.surface) {
            p.push(
                format!("{key}.edge"),
                format!("\"{}\"", e.edge.name()),
                "a curve has no edges: edge conditions need a [surface] (a curve's ends are \
                 held with constraints.fixed)",
            );
        }
        match (e.condition, e.hold.is_empty()) {
            (Some(_), false) => p.push(
                format!("{key}.hold"),
                format!("{:?}", e.hold),
                "give either condition or hold, not both",
            ),
            (None, true) => p.push(
                format!("{key}.condition"),
                "",
                "missing: give condition = \"clamped\", \"pinned\" or \"symmetry\", or the \
                 components to hold, e.g. hold = [\"y\", \"z\"]",
            ),
            _ => {}
        }
        if e.hold.contains(&Component::W) {
            p.push(
                format!("{key}.hold"),
                "\"w\"",
                "edge conditions hold x, y and z; weights are held with constraints.fixed_weights",
            );
        }
    }
    let Some(g) = info else { return };
    for (k, idx) in c.fixed.iter().enumerate() {
        check_point_index(p, &format!("constraints.fixed[{k}]"), idx, g);
    }
    // Count the free control points.
    let r = c.fixed_rings;
    let in_ring = |i: usize, j: usize| {
        i < r
            || i.saturating_add(r) >= g.n_u
            || (g.surface && (j < r || j.saturating_add(r) >= g.n_v))
    };
    let listed: std::collections::HashSet<(usize, usize)> = c
        .fixed
        .iter()
        .map(|idx| {
            (
                idx.first().copied().unwrap_or(0),
                idx.get(1).copied().unwrap_or(0),
            )
        })
        .collect();
    let any_free =
        (0..g.n_u).any(|i| (0..g.n_v).any(|j| !in_ring(i, j) && !listed.contains(&(i, j))));
    if !any_free {
        p.push(
            "constraints.fixed_rings",
            r.to_string(),
            format!(
                "with constraints.fixed this fixes every control point of the {} x {} net: nothing can move",
                g.n_u, g.n_v
            ),
        );
    }
}

/// The rules of `DnurbsOptions::validate`, with their key paths.
fn check_dnurbs(d: &DnurbsOptions, p: &mut Problems) {
    if let Err(DnurbsError::InvalidOption {
        name,
        value,
        reason,
    }) = d.validate()
    {
        p.push(format!("dnurbs.{name}"), value, reason);
    }
}

/// Reads a number of a TOML array.
fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// Reads `[x, y, z]` at `key`.
fn read_vec3(p: &mut Problems, key: &str, v: &toml::Value) -> Option<[f64; 3]> {
    let arr = v.as_array().filter(|a| a.len() == 3);
    let nums: Option<Vec<f64>> = arr.and_then(|a| a.iter().map(number).collect());
    match nums {
        Some(n) => {
            let out = [n[0], n[1], n[2]];
            p.vec3(key, &out);
            Some(out)
        }
        None => {
            p.push(
                key,
                v.to_string(),
                "expected a velocity [vx, vy, vz] of 3 numbers",
            );
            None
        }
    }
}

fn initial_spec(
    i: RawInitial,
    d: &DnurbsOptions,
    info: Option<&GeomInfo>,
    p: &mut Problems,
) -> Option<InitialSpec> {
    p.vec3("initial.velocity", &i.velocity);
    p.vec3("initial.displacement", &i.displacement);
    if p.finite("initial.weight_velocity", i.weight_velocity)
        && i.weight_velocity != 0.0
        && !d.weights_as_dofs
    {
        p.push(
            "initial.weight_velocity",
            format_f64(i.weight_velocity),
            "weights are constants unless dnurbs.weights_as_dofs = true",
        );
    }
    let velocities = match (&i.velocities, info) {
        (None, _) => None,
        (Some(_), None) => return None,
        (Some(v), Some(g)) => {
            if i.velocity != [0.0; 3] {
                p.push(
                    "initial.velocity",
                    format!("{:?}", i.velocity),
                    "give either initial.velocity or initial.velocities, not both",
                );
            }
            let start = p.len();
            let mut out = Vec::new();
            let key = "initial.velocities";
            let shape = if g.surface {
                format!(
                    "{} rows of {} [vx, vy, vz], like control_points",
                    g.n_u, g.n_v
                )
            } else {
                format!("{} entries [vx, vy, vz], like control_points", g.n_u)
            };
            match v.as_array() {
                Some(rows) if rows.len() == g.n_u => {
                    for (r, row) in rows.iter().enumerate() {
                        if g.surface {
                            match row.as_array() {
                                Some(cols) if cols.len() == g.n_v => {
                                    for (c, x) in cols.iter().enumerate() {
                                        if let Some(x) =
                                            read_vec3(p, &format!("{key}[{r}][{c}]"), x)
                                        {
                                            out.push(x);
                                        }
                                    }
                                }
                                _ => p.push(
                                    format!("{key}[{r}]"),
                                    row.to_string(),
                                    format!("expected {} velocities [vx, vy, vz]", g.n_v),
                                ),
                            }
                        } else if let Some(x) = read_vec3(p, &format!("{key}[{r}]"), row) {
                            out.push(x);
                        }
                    }
                }
                Some(rows) => p.push(
                    key,
                    format!("{} rows", rows.len()),
                    format!("expected {shape}"),
                ),
                None => p.push(key, v.to_string(), format!("expected {shape}")),
            }
            if p.len() != start {
                return None;
            }
            Some(out)
        }
    };
    Some(InitialSpec {
        velocity: i.velocity,
        weight_velocity: i.weight_velocity,
        velocities,
        displacement: i.displacement,
    })
}

fn check_simulation(
    s: &SimulationSpec,
    m: &MaterialModel,
    d: &DnurbsOptions,
    info: Option<&GeomInfo>,
    p: &mut Problems,
) {
    match check_time(s.dt, s.t_end, 0.0) {
        Ok(()) => {}
        Err(SimError::InvalidTimeStep { dt }) => {
            time_problem(p, "simulation.dt", dt, "the time step")
        }
        Err(SimError::InvalidDuration { t_end }) => {
            time_problem(p, "simulation.t_end", t_end, "the end time")
        }
        Err(SimError::TooManySteps { steps, max, .. }) => p.push(
            "simulation.t_end",
            format_f64(s.t_end),
            format!(
                "t_end / dt = {} steps of dt = {}; at most {} are allowed",
                format_f64(steps),
                format_f64(s.dt),
                format_f64(max)
            ),
        ),
        Err(other) => p.push("simulation.dt", format_f64(s.dt), other.to_string()),
    }
    if s.t_end <= 0.0 && s.dt > 0.0 {
        time_problem(p, "simulation.t_end", s.t_end, "the end time");
    }
    if s.save_every == 0 {
        p.push("simulation.save_every", "0", "must be at least 1");
    }
    if !(0.0..=1.0).contains(&s.rho_infinity) {
        p.push(
            "simulation.rho_infinity",
            format_f64(s.rho_infinity),
            "the spectral radius of generalized-α at infinite frequency must be in [0, 1]",
        );
    }
    if let Some(reason) = nurbspring_dnurbs::integrator_problem(s.dnurbs_integrator, m, d) {
        p.push(
            "simulation.dnurbs_integrator",
            format!("\"{}\"", s.dnurbs_integrator),
            reason,
        );
    }
    if let Some(reason) = MsmModel::integrator_problem(s.msm_integrator) {
        p.push(
            "simulation.msm_integrator",
            format!("\"{}\"", s.msm_integrator),
            reason,
        );
    }
    if s.probes.len() > MAX_PROBES {
        p.push(
            "simulation.probes",
            format!("{} probes", s.probes.len()),
            format!(
                "more than {MAX_PROBES} (each is a column of trajectory.csv and a run of the validation; to follow the whole surface, read its ParaView frames)"
            ),
        );
        return;
    }
    let Some(g) = info else { return };
    for (k, probe) in s.probes.iter().enumerate() {
        let key = format!("simulation.probes[{k}]");
        let arity = if g.surface { 2 } else { 1 };
        if probe.len() != arity {
            let want = if g.surface { "[u, v]" } else { "[u]" };
            p.push(&key, fmt_list(probe), format!("a probe is given as {want}"));
            continue;
        }
        check_param(p, &format!("{key}[0]"), probe[0], g.domain_u);
        if g.surface {
            check_param(p, &format!("{key}[1]"), probe[1], g.domain_v);
        }
    }
}

/// A time value refused by `check_time`: not finite, or not positive.
fn time_problem(p: &mut Problems, key: &str, value: f64, what: &str) {
    if value.is_finite() {
        p.push(key, format_f64(value), format!("{what} must be positive"));
    } else {
        p.push(key, format_f64(value), "must be a finite number");
    }
}
