//! Scene → models: the geometry, material, loads and constraints of the D-NURBS, the lattice
//! options of the MSM, the derivation's configuration. Model errors come back as
//! [`Error::Model`] naming the file and, where one caused it, the key.

use nurbspring_derive::{
    Config, ElementClasses, FitOptions, InitialConditions, MassChoice, Method, SpringsConfig,
    TimeSettings,
};
use nurbspring_dnurbs::{
    Constraints, DnurbsModel, EdgeCondition, EdgeConstraint, EdgeLoad, Geometry, LinearConstraint,
    Loads, Material, PointLoad,
};
use nurbspring_msm::{
    Class, Constants, FixedNodes, LatticeOptions, LinearKind, MsmError, ParameterGrid, SpringKind,
};

use crate::spec::*;
use crate::{Error, Scene};

/// Spring constants given on top of a scene's or a file's (`--k-edge`, `--mass`, …).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MsmOverrides {
    /// Constants by class.
    pub constants: Constants,
    /// Node mass.
    pub mass: Option<f64>,
}

impl MsmOverrides {
    /// The rules of `LatticeOptions::problems` on the overrides, each problem naming the
    /// option as `flag(symbol)` (for example `--k-edge`, `--mass`).
    pub fn validate(&self, flag: &dyn Fn(&str) -> String) -> Result<(), Error> {
        let options = LatticeOptions {
            constants: self.constants.clone(),
            mass: self.mass.unwrap_or(1.0),
            ..LatticeOptions::default()
        };
        for e in options.problems() {
            if let MsmError::InvalidOption { name, value, rule } = e {
                return Err(Error::option(&flag(&name), value, rule));
            }
        }
        Ok(())
    }
}

/// The spring classes of `[msm]` with their constants (the keys are the constants' symbols);
/// a constant the scene leaves out is [`PLACEHOLDER_K`] (a lattice whose constants a
/// derivation fits; [`MsmSpec::missing`] says which).
pub fn spring_constants(m: &MsmSpec) -> Constants {
    Constants::from_pairs(
        [
            (SpringKind::Structural, m.structural, m.k_edge),
            (SpringKind::Shear, m.shear, m.k_diag),
            (SpringKind::Bend, m.bending, m.k_bend),
        ]
        .into_iter()
        .filter(|&(_, on, _)| on)
        .map(|(kind, _, k)| (Class::Spring(kind), k.unwrap_or(PLACEHOLDER_K))),
    )
}

/// The element classes of `[msm]` for a derivation: the springs of `structural`, `shear`,
/// `bending` for the paper's (and for simulating the scene's own lattice), the linear
/// elements of `elements` (both regions, unit constants) for the others; on a curve only the
/// kinds along u.
pub fn element_classes(m: &MsmSpec, method: Method, curve: bool) -> Constants {
    if method.element_classes() == ElementClasses::Springs {
        return spring_constants(m);
    }
    let kinds: Vec<LinearKind> = match &m.elements {
        Some(k) => k.clone(),
        None if curve => LinearKind::CHAIN.to_vec(),
        None => LinearKind::ALL.to_vec(),
    };
    Constants::from_pairs(Class::linear(&kinds).into_iter().map(|c| (c, 1.0)))
}

/// `[msm]` as lattice options for `method` (fixed nodes by the automatic rule; a node mass
/// left out is [`PLACEHOLDER_MASS`], the damping [`MsmSpec::node_damping`] of the mass).
pub(crate) fn lattice_options(
    m: &MsmSpec,
    material: &nurbspring_dnurbs::MaterialModel,
    gravity: [f64; 3],
    method: Method,
    curve: bool,
) -> LatticeOptions {
    let mass = m.mass_or_placeholder();
    LatticeOptions {
        grid: parameter_grid(m, method),
        constants: element_classes(m, method, curve),
        mass,
        damping: m.node_damping(material, mass),
        pre_strain: m.pre_strain,
        fixed: FixedNodes::Auto,
        gravity,
    }
}

/// `msm.grid` (with `nodes_u`, `nodes_v`) for `method`.
pub(crate) fn parameter_grid(m: &MsmSpec, method: Method) -> ParameterGrid {
    match m.grid_for(method) {
        LatticeGrid::Knots => ParameterGrid::Knots,
        LatticeGrid::Uniform => ParameterGrid::Uniform {
            nodes_u: m.nodes_u,
            nodes_v: m.nodes_v,
        },
        LatticeGrid::Greville => ParameterGrid::Greville,
    }
}

/// Nodes along u and v of the lattice `grid` gives on `geometry` (`n_v = 1` on a curve).
pub(crate) fn lattice_shape(
    grid: &ParameterGrid,
    geometry: &Geometry,
) -> Result<(usize, usize), MsmError> {
    match geometry {
        Geometry::Surface(s) => {
            let (us, vs) = grid.parameters(s)?;
            Ok((us.len(), vs.len()))
        }
        Geometry::Curve(c) => Ok((grid.parameters_along(c.basis().knots())?.len(), 1)),
    }
}

impl Scene {
    /// A model error of this scene caused by `key`.
    pub(crate) fn model_error(
        &self,
        key: Option<&str>,
        e: impl Into<nurbspring_derive::DeriveError>,
    ) -> Error {
        Error::model(&self.path, key, e)
    }

    /// The tension plate's coefficients, or the error for a Kirchhoff–Love scene where `what`
    /// needs the tension plate.
    pub(crate) fn tension_plate(&self, what: &str) -> Result<&Material, Error> {
        self.material.tension_plate().ok_or_else(|| {
            Error::refused(
                &self.path,
                Some("material.model"),
                "material",
                "\"kirchhoff-love\"",
                format!(
                    "{what} works on tension-plate scenes (the paper's energy); the \
                     Kirchhoff–Love shell runs with check, steady, modes, matrices, simulate \
                     --model dnurbs, eval, export and refine"
                ),
            )
        })
    }

    /// The surface or curve (validated when the scene was read).
    pub fn build_geometry(&self) -> Result<Geometry, Error> {
        Ok(match &self.geometry {
            GeometrySpec::Surface(_) => Geometry::Surface(self.to_surface()?),
            GeometrySpec::Curve(_) => Geometry::Curve(self.to_curve()?),
        })
    }

    /// `[loads]`.
    pub fn build_loads(&self) -> Loads {
        let l = &self.loads;
        Loads {
            gravity: l.gravity,
            distributed: l.distributed,
            point: l
                .point
                .iter()
                .map(|p| PointLoad {
                    u: p.u,
                    v: p.v.unwrap_or(0.0),
                    force: p.force,
                })
                .collect(),
            edges: l
                .edge
                .iter()
                .map(|e| EdgeLoad {
                    edge: e.edge,
                    force: e.force,
                    moment: e.moment,
                })
                .collect(),
        }
    }

    /// Flat control point index of `[i, j]` (surfaces) or `[i]` (curves), checked when the
    /// scene was read.
    fn point_index(&self, p: &[usize]) -> usize {
        let (_, n_v) = self.geometry.net_dims();
        match p {
            [i, j] => i * n_v + j,
            [i] => *i,
            _ => 0,
        }
    }

    /// `[constraints]`.
    pub fn build_constraints(&self) -> Constraints {
        let c = &self.constraints;
        let dpp = if self.dnurbs.weights_as_dofs { 4 } else { 3 };
        Constraints {
            fixed_points: c.fixed.iter().map(|p| self.point_index(p)).collect(),
            fixed_rings: c.fixed_rings,
            fixed_weights: c.fixed_weights,
            fixed_point_weights: c.fixed_point_weights == crate::spec::FixedPointWeights::Held,
            linear: c
                .linear
                .iter()
                .map(|row| LinearConstraint {
                    terms: row
                        .terms
                        .iter()
                        .map(|t| {
                            (
                                self.point_index(&t.point) * dpp + t.component.offset(),
                                t.coefficient,
                            )
                        })
                        .collect(),
                    rhs: row.rhs,
                })
                .collect(),
            edges: c
                .edge
                .iter()
                .map(|e| EdgeConstraint {
                    edge: e.edge,
                    condition: match e.condition {
                        Some(EdgeConditionName::Clamped) => EdgeCondition::Clamped,
                        Some(EdgeConditionName::Pinned) => EdgeCondition::Pinned,
                        Some(EdgeConditionName::Symmetry) => EdgeCondition::Symmetry,
                        None => EdgeCondition::Hold(std::array::from_fn(|x| {
                            e.hold.iter().any(|c| c.offset() == x)
                        })),
                    },
                })
                .collect(),
        }
    }

    /// The constrained D-NURBS model.
    pub fn build_dnurbs(&self) -> Result<DnurbsModel, Error> {
        DnurbsModel::build(
            self.build_geometry()?,
            &self.material,
            self.build_loads(),
            &self.build_constraints(),
            self.dnurbs.clone(),
        )
        .map_err(|e| self.model_error(None, e))
    }

    /// `[initial]`.
    pub fn initial_conditions(&self) -> InitialConditions {
        let i = &self.initial;
        InitialConditions {
            velocities: i.velocities.clone().unwrap_or_else(|| vec![i.velocity]),
            weight_velocity: i.weight_velocity,
            displacement: i.displacement,
        }
    }

    /// `[simulation]` time stepping.
    pub fn time_settings(&self) -> TimeSettings {
        let s = &self.simulation;
        TimeSettings {
            dt: s.dt,
            t_end: s.t_end,
            dnurbs_integrator: s.dnurbs_integrator,
            msm_integrator: s.msm_integrator,
        }
    }

    /// Probe parameters: the centre of the parameter domain first, then the scene's probes
    /// (duplicates dropped). On a curve `v` is 0.
    pub fn probe_params(&self) -> Result<Vec<(f64, f64)>, Error> {
        let ((u0, u1), (v0, v1)) = match self.build_geometry()? {
            Geometry::Surface(s) => s.domain(),
            Geometry::Curve(c) => (c.domain(), (0.0, 0.0)),
        };
        let mut out = vec![(0.5 * (u0 + u1), 0.5 * (v0 + v1))];
        for p in &self.simulation.probes {
            let q = (p[0], p.get(1).copied().unwrap_or(0.0));
            if !out.contains(&q) {
                out.push(q);
            }
        }
        Ok(out)
    }

    /// The lattice options of `[msm]` for `method` with `overrides`, fixed nodes as the scene
    /// gives them.
    pub fn lattice_options(
        &self,
        method: Method,
        overrides: &MsmOverrides,
    ) -> Result<LatticeOptions, Error> {
        let curve = !self.geometry.is_surface();
        let mut options =
            lattice_options(&self.msm, &self.material, self.loads.gravity, method, curve);
        for (class, k) in overrides.constants.iter() {
            options.constants.set(class, k);
        }
        if let Some(m) = overrides.mass {
            options.mass = m;
            options.damping = self.msm.node_damping(&self.material, m);
        }
        if let MsmFixed::Nodes(list) = &self.msm.fixed {
            let geometry = self.build_geometry()?;
            let (_, n_v) = lattice_shape(&options.grid, &geometry)
                .map_err(|e| self.model_error(Some("msm.grid"), e))?;
            options.fixed = FixedNodes::List(
                list.iter()
                    .map(|node| match node.as_slice() {
                        [i, j] => i * n_v + j,
                        [a] => *a,
                        _ => 0,
                    })
                    .collect(),
            );
        }
        Ok(options)
    }

    /// The derivation the scene asks for, and why when it is not the one named (see
    /// [`crate::spec::FitSpec::derivation_for`]).
    pub fn derivation(&self) -> (Method, Option<&'static str>) {
        self.fit.derivation_for(
            self.material.shell().is_some(),
            &self.dnurbs,
            &self.constraints,
        )
    }

    /// The spring derivation's configuration (docs/math.md §11), or the error for a
    /// tension-plate scene.
    /// `method` is the derivation `key` chose: one that takes a shell
    /// ([`Method::spring_groups`]).
    pub fn springs_config(&self, method: Method, key: &str) -> Result<SpringsConfig, Error> {
        let Some(shell) = self.material.shell() else {
            return Err(Error::refused(
                &self.path,
                Some("material.model"),
                "material",
                "the tension plate",
                "the spring derivation derives from a Kirchhoff–Love shell: material.model = \
                 \"kirchhoff-love\" with young, poisson, thickness and density"
                    .to_string(),
            ));
        };
        if !method.takes(true) {
            return Err(Error::refused(
                &self.path,
                Some(key),
                key,
                format!("\"{}\"", method.name()),
                format!(
                    "a Kirchhoff–Love scene derives rest-length springs and hinges: {} (the \
                     {} derivation takes the tension plate)",
                    Method::names_taking(true),
                    method.name()
                ),
            ));
        }
        let surface = self.to_surface()?;
        Ok(SpringsConfig {
            surface,
            shell: *shell,
            loads: self.build_loads(),
            constraints: self.build_constraints(),
            dnurbs: self.dnurbs.clone(),
            lattice: self.lattice_options(Method::Springs, &MsmOverrides::default())?,
            initial: self.initial_conditions(),
            time: self.time_settings(),
            probes: self.probe_params()?,
            method,
        })
    }

    /// The derivation's configuration for `method` (`None`: [`Scene::derivation`]); for the
    /// paper's derivation the scene's `[msm]` constants and mass are kept as the "given"
    /// parameters, evaluated beside the derived ones.
    pub fn derivation_config(&self, method: Option<Method>) -> Result<Config, Error> {
        let method = method.unwrap_or(self.derivation().0);
        let material = self.tension_plate("a derivation")?.clone();
        let geometry = self.build_geometry()?;
        let fit = &self.fit;
        Ok(Config {
            method,
            geometry,
            material,
            loads: self.build_loads(),
            constraints: self.build_constraints(),
            dnurbs: self.dnurbs.clone(),
            lattice: self.lattice_options(method, &MsmOverrides::default())?,
            initial: self.initial_conditions(),
            time: self.time_settings(),
            fit: FitOptions {
                dofs: fit.dofs,
                nonnegative: fit.nonnegative,
                method: fit.method,
                mass: match fit.mass {
                    // Validation refuses `fit.mass = "fixed"` without `msm.mass`.
                    MassMethod::EigenvalueScan => MassChoice::EigenvalueScan,
                    MassMethod::Fixed => MassChoice::Fixed(self.msm.mass_or_placeholder()),
                },
                max_candidates: fit.max_candidates,
                scan: fit.mass_scan,
            },
            probes: self.probe_params()?,
            // The scene's own constants are evaluated beside the derived ones only when it
            // gives every one of them (placeholders are no model).
            given: match (method, self.msm.mass) {
                (Method::Paper, Some(m)) if self.msm.missing().is_empty() => {
                    Some((spring_constants(&self.msm), m))
                }
                _ => None,
            },
            node_damping: self.msm.damping,
        })
    }
}
