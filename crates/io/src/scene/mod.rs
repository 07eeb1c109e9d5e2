//! Scene files: TOML describing the geometry, material, loads, constraints, initial state,
//! simulation, lattice and fit (every key is listed in `crates/io/SCENE_KEYS.md`).
//!
//! Reading a scene checks everything up front: TOML syntax and unknown keys (with the file, line
//! and column, and the nearest valid key), then every value (finite numbers, signs, shapes of
//! `control_points` and `weights`, knot vectors through `nurbspring-geom`, parameters inside the
//! domain, sizes below [`MAX_ITEMS`]), naming the file, the key path and the value. All problems
//! found are reported together.
//!
//! ```
//! use nurbspring_io::scene::{GeometrySpec, Scene, SceneErrorKind};
//! let text = r#"
//! [curve]
//! degree = 2
//! knots = [0, 0, 0, 1, 1, 1]
//! control_points = [[0, 0, 0], [1, 1, 0], [2, 0, 0]]
//!
//! [material]
//! mu = 2.0
//! "#;
//! let scene = Scene::from_str(text, "string.toml").unwrap();
//! assert!(matches!(scene.geometry, GeometrySpec::Curve(_)));
//! assert_eq!(scene.material.mu, 2.0);
//! assert_eq!(scene.simulation.dt, 0.08); // default
//!
//! let err = Scene::from_str(&text.replace("mu = 2.0", "mu = -2.0"), "x.toml").unwrap_err();
//! assert_eq!(err.kind(), SceneErrorKind::Invalid);
//! assert_eq!(err.to_string(), "x.toml: material.mu = -2: the mass density must be positive");
//! ```

mod error;
mod parse;
mod spec;
mod validate;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use error::{Problem, SceneError, SceneErrorKind};
pub use spec::{
    Component, ConstraintsSpec, CurveSpec, DnurbsIntegrator, DnurbsSpec, FitDofs, FitMethod,
    FitSpec, GeometrySpec, InitialSpec, IntegrationDomain, LatticeGrid, LinearConstraintSpec,
    LinearTermSpec, LoadsSpec, MassMethod, MaterialSpec, MsmFixed, MsmIntegrator, MsmSpec,
    OutputSpec, PointLoadSpec, RestShape, SimulationSpec, SurfaceSpec,
};

/// Largest number of control points, lattice nodes or array entries a scene may ask for
/// (10⁷); larger requests are refused before anything is allocated.
pub const MAX_ITEMS: usize = 10_000_000;

/// Largest scene file read (64 MiB).
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The file it came from (used in messages).
    pub path: PathBuf,
    /// `[surface]` or `[curve]`.
    pub geometry: GeometrySpec,
    /// `[material]`.
    pub material: MaterialSpec,
    /// `[loads]`.
    pub loads: LoadsSpec,
    /// `[constraints]`.
    pub constraints: ConstraintsSpec,
    /// `[dnurbs]`.
    pub dnurbs: DnurbsSpec,
    /// `[initial]`.
    pub initial: InitialSpec,
    /// `[simulation]`.
    pub simulation: SimulationSpec,
    /// `[msm]`.
    pub msm: MsmSpec,
    /// `[fit]`.
    pub fit: FitSpec,
    /// `[output]`.
    pub output: OutputSpec,
}

/// The file as deserialized, before validation.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    surface: Option<RawSurface>,
    curve: Option<RawCurve>,
    #[serde(default)]
    material: MaterialSpec,
    #[serde(default)]
    loads: LoadsSpec,
    #[serde(default)]
    constraints: ConstraintsSpec,
    #[serde(default)]
    dnurbs: DnurbsSpec,
    #[serde(default)]
    initial: RawInitial,
    #[serde(default)]
    simulation: SimulationSpec,
    #[serde(default)]
    msm: MsmSpec,
    #[serde(default)]
    fit: FitSpec,
    #[serde(default)]
    output: OutputSpec,
}

/// `[surface]` with points as plain lists, so that their shapes are checked with key paths.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSurface {
    degree_u: usize,
    degree_v: usize,
    knots_u: Vec<f64>,
    knots_v: Vec<f64>,
    control_points: Vec<Vec<Vec<f64>>>,
    #[serde(default)]
    weights: Option<Vec<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCurve {
    degree: usize,
    knots: Vec<f64>,
    control_points: Vec<Vec<f64>>,
    #[serde(default)]
    weights: Option<Vec<f64>>,
}

#[derive(Deserialize, Serialize, Default)]
#[serde(default, deny_unknown_fields)]
struct RawInitial {
    velocity: [f64; 3],
    weight_velocity: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    velocities: Option<toml::Value>,
    displacement: [f64; 3],
}

/// The file as serialized by [`Scene::to_toml`].
#[derive(Serialize)]
struct OutScene<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    surface: Option<&'a SurfaceSpec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    curve: Option<&'a CurveSpec>,
    material: &'a MaterialSpec,
    loads: &'a LoadsSpec,
    constraints: &'a ConstraintsSpec,
    dnurbs: &'a DnurbsSpec,
    initial: RawInitial,
    simulation: &'a SimulationSpec,
    msm: &'a MsmSpec,
    fit: &'a FitSpec,
    output: &'a OutputSpec,
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let io = |source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        };
        let len = std::fs::metadata(path).map_err(io)?.len();
        if len > MAX_FILE_BYTES {
            return Err(SceneError::Invalid {
                path: path.to_path_buf(),
                problems: vec![Problem::new(
                    "(file size)",
                    format!("{len} bytes"),
                    format!("scene files are limited to {MAX_FILE_BYTES} bytes"),
                )],
            });
        }
        let text = std::fs::read_to_string(path).map_err(io)?;
        Scene::from_str(&text, path)
    }

    /// Parses and validates scene text; `path` is used in messages and stored in the scene.
    pub fn from_str(text: &str, path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let raw: RawScene = toml::from_str(text).map_err(|e| parse::parse_error(path, text, &e))?;
        validate::build_scene(raw, path).map_err(|e| e.with_path(path))
    }

    /// The scene as TOML text that [`Scene::from_str`] reads back to an equal scene (numbers
    /// are written with full precision).
    pub fn to_toml(&self) -> String {
        let (surface, curve) = match &self.geometry {
            GeometrySpec::Surface(s) => (Some(s), None),
            GeometrySpec::Curve(c) => (None, Some(c)),
        };
        let velocities = self.initial.velocities.as_ref().map(|v| {
            let value = match &self.geometry {
                GeometrySpec::Surface(s) => {
                    let n_v = s.n_v().max(1);
                    toml::Value::try_from(v.chunks(n_v).map(<[_]>::to_vec).collect::<Vec<_>>())
                }
                GeometrySpec::Curve(_) => toml::Value::try_from(v),
            };
            value.expect("arrays of finite numbers are valid TOML")
        });
        let out = OutScene {
            surface,
            curve,
            material: &self.material,
            loads: &self.loads,
            constraints: &self.constraints,
            dnurbs: &self.dnurbs,
            initial: RawInitial {
                velocity: self.initial.velocity,
                weight_velocity: self.initial.weight_velocity,
                velocities,
                displacement: self.initial.displacement,
            },
            simulation: &self.simulation,
            msm: &self.msm,
            fit: &self.fit,
            output: &self.output,
        };
        toml::to_string(&out).expect("a scene is always representable in TOML")
    }

    /// The surface of a `[surface]` scene, built through `nurbspring-geom`.
    pub fn to_surface(&self) -> Result<nurbspring_geom::NurbsSurface, SceneError> {
        match &self.geometry {
            GeometrySpec::Surface(s) => s.to_surface().map_err(|e| e.with_path(&self.path)),
            GeometrySpec::Curve(_) => Err(SceneError::Invalid {
                path: self.path.clone(),
                problems: vec![Problem::new(
                    "surface",
                    "",
                    "this scene has a [curve], not a [surface]",
                )],
            }),
        }
    }

    /// The curve of a `[curve]` scene, built through `nurbspring-geom`.
    pub fn to_curve(&self) -> Result<nurbspring_geom::NurbsCurve, SceneError> {
        match &self.geometry {
            GeometrySpec::Curve(c) => c.to_curve().map_err(|e| e.with_path(&self.path)),
            GeometrySpec::Surface(_) => Err(SceneError::Invalid {
                path: self.path.clone(),
                problems: vec![Problem::new(
                    "curve",
                    "",
                    "this scene has a [surface], not a [curve]",
                )],
            }),
        }
    }
}

impl SurfaceSpec {
    /// Builds and validates the surface through `nurbspring-geom`; errors name the keys
    /// (`surface.knots_u[4]`, `surface.weights[2][1]`, …). The error's path is empty; use
    /// [`Scene::to_surface`] for messages naming the file.
    pub fn to_surface(&self) -> Result<nurbspring_geom::NurbsSurface, SceneError> {
        validate::build_surface(self).map_err(|p| SceneError::Invalid {
            path: PathBuf::new(),
            problems: vec![p],
        })
    }
}

impl CurveSpec {
    /// Builds and validates the curve through `nurbspring-geom`; errors name the keys
    /// (`curve.knots[3]`, `curve.weights[1]`, …).
    pub fn to_curve(&self) -> Result<nurbspring_geom::NurbsCurve, SceneError> {
        validate::build_curve(self).map_err(|p| SceneError::Invalid {
            path: PathBuf::new(),
            problems: vec![p],
        })
    }
}
