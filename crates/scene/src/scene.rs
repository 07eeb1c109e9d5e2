//! Scene files: TOML describing the geometry, material, loads, constraints, initial state,
//! simulation, lattice and fit (every key is listed in `docs/scenes.md`).
//!
//! Reading a scene checks everything up front: TOML syntax and unknown keys (with the file, line
//! and column, and the nearest valid key), then every value (finite numbers, signs, shapes of
//! `control_points` and `weights`, knot vectors through `nurbspring-geom`, parameters inside the
//! domain, sizes below [`MAX_ITEMS`]), naming the file, the key path and the value. All problems
//! found are reported together.
//!
//! ```
//! use nurbspring_scene::{GeometrySpec, Scene, SceneErrorKind};
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
//! assert_eq!(scene.material.tension_plate().unwrap().mu, 2.0);
//! assert_eq!(scene.simulation.dt, 0.08); // default
//!
//! let err = Scene::from_str(&text.replace("mu = 2.0", "mu = -2.0"), "x.toml").unwrap_err();
//! assert_eq!(err.kind(), SceneErrorKind::Invalid);
//! assert_eq!(err.to_string(), "x.toml: material.mu = -2: the mass density must be positive");
//! ```

use std::path::{Path, PathBuf};

use nurbspring_dnurbs::{DnurbsOptions, MaterialModel};
use serde::Serialize;

use crate::spec::*;
use crate::text_file::read_text;
use crate::{Problem, SceneError, parse, validate};

/// The paper's experiment (Section IV), the same text as `examples/paper.toml`.
pub const PAPER_SCENE: &str = include_str!("../../../examples/paper.toml");

/// Largest scene file read (64 MiB).
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// The file as serialized by [`Scene::to_toml`].
#[derive(Serialize)]
struct OutScene<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    surface: Option<&'a SurfaceSpec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    curve: Option<&'a CurveSpec>,
    material: &'a MaterialModel,
    loads: &'a LoadsSpec,
    constraints: &'a ConstraintsSpec,
    dnurbs: &'a DnurbsOptions,
    initial: RawInitial,
    simulation: &'a SimulationSpec,
    msm: &'a MsmSpec,
    fit: &'a FitSpec,
    output: &'a OutputSpec,
}

/// Why a `.json` file is refused where a scene is expected.
pub const NOT_A_SCENE: &str = "a JSON file, not a scene (scenes are TOML): an msm.json written by \
     `derive` runs with `simulate FILE --model msm`, `stability FILE` and `export FILE --format \
     sofa|npz`; other commands need the scene (.toml) it was derived from, and `import FILE --out \
     SCENE.toml` turns a geomdl JSON file into a scene";

impl Scene {
    /// Reads and validates a scene file: a regular file of at most [`MAX_FILE_BYTES`], read
    /// through its handle (a FIFO, a device or a folder is refused, and nothing is read past
    /// the limit).
    pub fn from_path(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        if crate::msm_file::is_msm_file(path) {
            // msm.json (or another JSON file): say what it is rather than fail in the TOML parser.
            return Err(SceneError::Parse {
                path: path.to_path_buf(),
                message: NOT_A_SCENE.to_string(),
                line: 0,
                column: 0,
                suggestion: None,
            });
        }
        let text = read_text(path, MAX_FILE_BYTES, "scene")?;
        Scene::from_str(&text, path)
    }

    /// The paper's scene ([`PAPER_SCENE`]), named `<built-in paper scene>` in messages.
    pub fn paper() -> Result<Scene, SceneError> {
        Scene::from_str(PAPER_SCENE, "<built-in paper scene>")
    }

    /// Parses and validates scene text; `path` is used in messages and stored in the scene.
    pub fn from_str(text: &str, path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let raw: RawScene = toml::from_str(text).map_err(|e| parse::parse_error(path, text, &e))?;
        validate::build_scene(raw, path, validate::GivenKeys::of(text))
            .map_err(|e| e.with_path(path))
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
