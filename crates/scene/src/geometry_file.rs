//! Geometry files ↔ scenes: reading the surfaces and curves of geomdl JSON, IGES and OBJ
//! free-form files (`nurbspring import`, a scene's `[surface] file = "…"`), writing a scene's
//! geometry back to them (`nurbspring export`), a commented scene for an imported shape, and
//! exact refinement of a scene's geometry (`nurbspring refine`).
//!
//! The format is chosen by the file's extension ([`GeometryFormat::from_path`]). Every error
//! names the file and, where the format has lines, the line ([`nurbspring_exchange::Location`]).

use std::path::{Component, Path, PathBuf};

use nurbspring_exchange::{ExchangeError, Shape, geomdl, iges, obj};
use nurbspring_geom::{NurbsCurve, NurbsSurface};
use nurbspring_io::atomic::write_atomic_bytes;
use nurbspring_io::output::{ObjMesh, write_obj};

use crate::spec::{CurveSpec, GeometrySpec, SurfaceSpec};
use crate::{Error, Problem, Scene, SceneError};

/// A geometry exchange format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryFormat {
    /// geomdl's JSON (`.json`).
    GeomdlJson,
    /// IGES 5.3 entities 126 and 128 (`.igs`, `.iges`).
    Iges,
    /// OBJ free-form `cstype bspline` records (`.obj`).
    ObjFreeForm,
}

impl GeometryFormat {
    /// The extensions read, for messages.
    pub const EXTENSIONS: &'static str =
        ".json (geomdl), .igs or .iges (IGES 126/128), .obj (OBJ free-form)";

    /// The format of a file by its extension (case-insensitive).
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "json" => Some(GeometryFormat::GeomdlJson),
            "igs" | "iges" => Some(GeometryFormat::Iges),
            "obj" => Some(GeometryFormat::ObjFreeForm),
            _ => None,
        }
    }

    /// Its name in messages.
    pub fn name(self) -> &'static str {
        match self {
            GeometryFormat::GeomdlJson => "geomdl JSON",
            GeometryFormat::Iges => "IGES",
            GeometryFormat::ObjFreeForm => "OBJ free-form",
        }
    }
}

/// What a geometry file holds.
#[derive(Clone, Debug)]
pub struct GeometryFile {
    /// The file.
    pub path: PathBuf,
    /// Its format.
    pub format: GeometryFormat,
    /// Every curve and surface, in file order.
    pub shapes: Vec<Shape>,
    /// Remarks for people (IGES: entities skipped, surfaces imported untrimmed, …).
    pub notes: Vec<String>,
}

/// The error of a geometry file that cannot be read or written.
fn exchange_error(path: &Path, source: ExchangeError) -> Error {
    Error::Exchange {
        path: path.to_path_buf(),
        source: Box::new(source),
    }
}

/// Reads every curve and surface of a geometry file (format by extension).
pub fn read_geometry_file(path: &Path) -> Result<GeometryFile, Error> {
    let format = GeometryFormat::from_path(path).ok_or_else(|| Error::Option {
        name: "FILE".to_string(),
        value: path.display().to_string(),
        message: format!(
            "unknown geometry format (by extension); expected {}",
            GeometryFormat::EXTENSIONS
        ),
    })?;
    let (shapes, notes) = match format {
        GeometryFormat::GeomdlJson => (geomdl::read_file(path), Vec::new()),
        GeometryFormat::ObjFreeForm => (obj::read_file(path), Vec::new()),
        GeometryFormat::Iges => match iges::read_file(path) {
            Ok(report) => {
                let mut notes = report.notes.clone();
                notes.extend(report.skipped.iter().map(|s| {
                    format!(
                        "skipped entity {} ({}) at line {}: {}",
                        s.entity_type,
                        iges::entity_name(s.entity_type),
                        s.de_line,
                        s.reason
                    )
                }));
                (Ok(report.shapes), notes)
            }
            Err(e) => (Err(e), Vec::new()),
        },
    };
    let shapes = shapes.map_err(|e| exchange_error(path, e))?;
    Ok(GeometryFile {
        path: path.to_path_buf(),
        format,
        shapes,
        notes,
    })
}

impl GeometryFile {
    /// The `index`-th surface (`surface = true`) or curve of the file (0-based).
    pub fn select(&self, surface: bool, index: usize) -> Result<&Shape, String> {
        let what = if surface { "surface" } else { "curve" };
        let of_kind: Vec<&Shape> = self
            .shapes
            .iter()
            .filter(|s| matches!(s, Shape::Surface(_)) == surface)
            .collect();
        if of_kind.is_empty() {
            let other = self.shapes.len();
            return Err(format!(
                "missing entity: the file holds no {what}{}",
                if other > 0 {
                    format!(
                        " (it holds {other} {}; use a [{}] table)",
                        if surface { "curves" } else { "surfaces" },
                        if surface { "curve" } else { "surface" }
                    )
                } else {
                    String::new()
                }
            ));
        }
        of_kind.get(index).copied().ok_or_else(|| {
            format!(
                "missing entity: index {index}, but the file holds {} {what}{} (indices from 0)",
                of_kind.len(),
                if of_kind.len() == 1 { "" } else { "s" }
            )
        })
    }
}

/// The `[surface]` or `[curve]` of a scene whose table says `file = "…"`, `index = …`; `file` is
/// relative to the scene file's folder. Problems name the key `section.file` and the file and
/// line of the geometry.
pub(crate) fn load_geometry(
    scene_path: &Path,
    section: &str,
    file: &str,
    index: usize,
) -> Result<GeometrySpec, Problem> {
    let key = format!("{section}.file");
    let value = format!("\"{file}\"");
    let resolved = resolve(scene_path, file);
    let problem = |message: String| Problem::new(&key, &value, message);
    let geometry = read_geometry_file(&resolved).map_err(|e| match e {
        Error::Option { message, .. } => problem(message),
        e => problem(e.to_string()),
    })?;
    let shape = geometry
        .select(section == "surface", index)
        .map_err(|m| problem(format!("{}: {m}", resolved.display())))?;
    Ok(GeometrySpec::from_shape(shape))
}

/// `file` relative to the folder of `scene_path` (absolute paths as given).
pub fn resolve(scene_path: &Path, file: &str) -> PathBuf {
    let file = Path::new(file);
    if file.is_absolute() {
        return file.to_path_buf();
    }
    match scene_path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.join(file),
        _ => file.to_path_buf(),
    }
}

impl SurfaceSpec {
    /// The `[surface]` table of a surface (weights left out when all are 1).
    pub fn from_surface(s: &NurbsSurface) -> Self {
        let (n_u, n_v) = (s.n_u(), s.n_v());
        let rows = |flat: &[[f64; 3]]| flat.chunks(n_v).map(<[_]>::to_vec).collect::<Vec<_>>();
        let weights = s.weights();
        SurfaceSpec {
            degree_u: s.basis_u().degree(),
            degree_v: s.basis_v().degree(),
            knots_u: s.basis_u().knots().knots().to_vec(),
            knots_v: s.basis_v().knots().knots().to_vec(),
            control_points: rows(s.control_points()),
            weights: weights.iter().any(|&w| w != 1.0).then(|| {
                (0..n_u)
                    .map(|i| weights[i * n_v..(i + 1) * n_v].to_vec())
                    .collect()
            }),
        }
    }
}

impl CurveSpec {
    /// The `[curve]` table of a curve (weights left out when all are 1).
    pub fn from_curve(c: &NurbsCurve) -> Self {
        CurveSpec {
            degree: c.basis().degree(),
            knots: c.basis().knots().knots().to_vec(),
            control_points: c.control_points().to_vec(),
            weights: c
                .weights()
                .iter()
                .any(|&w| w != 1.0)
                .then(|| c.weights().to_vec()),
        }
    }
}

impl GeometrySpec {
    /// The table of a shape.
    pub fn from_shape(shape: &Shape) -> Self {
        match shape {
            Shape::Surface(s) => GeometrySpec::Surface(SurfaceSpec::from_surface(s)),
            Shape::Curve(c) => GeometrySpec::Curve(CurveSpec::from_curve(c)),
        }
    }
}

impl Scene {
    /// The scene's surface or curve as an exchange shape.
    pub fn shape(&self) -> Result<Shape, SceneError> {
        Ok(match &self.geometry {
            GeometrySpec::Surface(_) => Shape::Surface(self.to_surface()?),
            GeometrySpec::Curve(_) => Shape::Curve(self.to_curve()?),
        })
    }
}

/// Writes shapes to `path` in `format` (atomically). geomdl JSON holds shapes of one kind.
pub fn write_geometry_file(
    path: &Path,
    format: GeometryFormat,
    shapes: &[Shape],
) -> Result<(), Error> {
    let text = match format {
        GeometryFormat::GeomdlJson => geomdl::write(shapes).map_err(|e| exchange_error(path, e))?,
        GeometryFormat::Iges => iges::write(shapes),
        GeometryFormat::ObjFreeForm => obj::write(shapes),
    };
    Ok(write_atomic_bytes(path, text.as_bytes())?)
}

/// Writes a tessellation of a surface as an OBJ quad mesh with texture coordinates (the
/// parameters, mapped to `[0, 1]²`) and unit normals: `n_u × n_v` uniformly spaced samples.
/// Where a normal cannot be computed (a degenerate point of the surface) the mesh is written
/// without normals, and its header comment says so.
pub fn write_tessellated_obj(
    path: &Path,
    surface: &NurbsSurface,
    n_u: usize,
    n_v: usize,
    comment: &str,
) -> Result<(), Error> {
    let invalid = |message: String| {
        Error::Output(nurbspring_io::OutputError::InvalidData {
            path: path.to_path_buf(),
            message,
        })
    };
    let (us, vs, points) = surface
        .uniform_grid(n_u, n_v)
        .map_err(|e| invalid(e.to_string()))?;
    let ((u0, u1), (v0, v1)) = surface.domain();
    let mut mesh = ObjMesh::quad_grid(points, us.len(), vs.len())
        .ok_or_else(|| invalid("cannot build the quad mesh".to_string()))?;
    let mut normals = Vec::with_capacity(us.len() * vs.len());
    for &u in &us {
        for &v in &vs {
            mesh.uvs.push([(u - u0) / (u1 - u0), (v - v0) / (v1 - v0)]);
            if let Ok(n) = surface.normal(u, v)
                && n.iter().all(|x| x.is_finite())
            {
                normals.push(n);
            }
        }
    }
    let mut comment = comment.to_string();
    if normals.len() == mesh.vertices.len() {
        mesh.normals = normals;
    } else {
        comment.push_str("\nno normals: the surface is degenerate at some samples");
    }
    Ok(write_obj(path, &mesh, &comment)?)
}

/// Shortest round-trip text of a double, valid TOML (`1.0`, `0.1`, `1e-7`).
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn point(p: &[f64; 3]) -> String {
    format!("[{}, {}, {}]", num(p[0]), num(p[1]), num(p[2]))
}

fn list(v: &[f64]) -> String {
    format!(
        "[{}]",
        v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", ")
    )
}

/// The `[surface]` or `[curve]` table of a geometry as readable TOML: one row of control
/// points (one u index) per line, numbers in shortest round-trip form.
pub fn geometry_toml(geometry: &GeometrySpec) -> String {
    let mut t = String::new();
    match geometry {
        GeometrySpec::Surface(s) => {
            t.push_str("[surface]\n");
            t.push_str(&format!("degree_u = {}\n", s.degree_u));
            t.push_str(&format!("degree_v = {}\n", s.degree_v));
            t.push_str(&format!(
                "knots_u = {}   # {} basis functions\n",
                list(&s.knots_u),
                s.n_u()
            ));
            t.push_str(&format!(
                "knots_v = {}   # {} basis functions\n",
                list(&s.knots_v),
                s.n_v()
            ));
            t.push_str("# control_points[i][j]: i along u, j along v\ncontrol_points = [\n");
            for row in &s.control_points {
                let pts: Vec<String> = row.iter().map(point).collect();
                t.push_str(&format!("  [{}],\n", pts.join(", ")));
            }
            t.push_str("]\n");
            match &s.weights {
                Some(w) => {
                    t.push_str("weights = [\n");
                    for row in w {
                        t.push_str(&format!("  {},\n", list(row)));
                    }
                    t.push_str("]\n");
                }
                None => t.push_str("# weights: omitted, all 1\n"),
            }
        }
        GeometrySpec::Curve(c) => {
            t.push_str("[curve]\n");
            t.push_str(&format!("degree = {}\n", c.degree));
            t.push_str(&format!(
                "knots = {}   # {} basis functions\n",
                list(&c.knots),
                c.control_points.len()
            ));
            t.push_str("control_points = [\n");
            for p in &c.control_points {
                t.push_str(&format!("  {},\n", point(p)));
            }
            t.push_str("]\n");
            match &c.weights {
                Some(w) => t.push_str(&format!("weights = {}\n", list(w))),
                None => t.push_str("# weights: omitted, all 1\n"),
            }
        }
    }
    t
}

/// How [`imported_scene`] writes the geometry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GeometrySource {
    /// The control net, knots and weights inline.
    Inline,
    /// `file = "…"` (relative to the scene) and `index`.
    Link {
        /// As it will be written in the scene.
        file: String,
        /// Which surface or curve of the file.
        index: usize,
    },
}

/// The path of `file` as a scene at `scene` should write it: relative to the scene's folder
/// when both can be resolved, else absolute.
pub fn relative_to_scene(file: &Path, scene: &Path) -> String {
    let absolute = |p: &Path| std::path::absolute(p).ok();
    let dir = scene
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let (Some(file_abs), Some(dir_abs)) = (absolute(file), absolute(dir)) else {
        return file.display().to_string();
    };
    fn normal(p: &Path) -> Vec<Component<'_>> {
        p.components()
            .filter(|c| !matches!(c, Component::CurDir))
            .collect()
    }
    let (f, d) = (normal(&file_abs), normal(&dir_abs));
    if f.iter()
        .chain(&d)
        .any(|c| matches!(c, Component::ParentDir))
    {
        return file_abs.display().to_string();
    }
    let common = f.iter().zip(&d).take_while(|(a, b)| a == b).count();
    if common == 0 {
        return file_abs.display().to_string();
    }
    let mut rel = PathBuf::new();
    for _ in common..d.len() {
        rel.push("..");
    }
    for c in &f[common..] {
        rel.push(c.as_os_str());
    }
    rel.to_string_lossy().replace('\\', "/")
}

/// A commented scene for an imported surface or curve: its geometry (inline or linked), and
/// default material, loads, constraints, simulation, lattice and fit tables to edit. `origin`
/// says where the shape came from (a line of the header comment).
pub fn imported_scene(geometry: &GeometrySpec, origin: &str, source: &GeometrySource) -> String {
    let surface = geometry.is_surface();
    let (n_u, n_v) = geometry.net_dims();
    let mut t = String::new();
    let shape = if surface {
        format!("surface ({n_u} x {n_v} control points)")
    } else {
        format!("curve ({n_u} control points)")
    };
    t.push_str(&format!(
        "# Imported by `nurbspring import` from {origin}.\n"
    ));
    t.push_str(&match source {
        GeometrySource::Inline => format!("# The NURBS {shape} is written out below.\n"),
        GeometrySource::Link { .. } => {
            format!("# The NURBS {shape} is read from its file when the scene is loaded.\n")
        }
    });
    t.push_str(&format!(
        "# The tables after the geometry hold defaults to edit: the {} fixed,\n\
         # gravity, material, time stepping, lattice and fit (docs/scenes.md lists every key).\n\
         # Coordinates are as the file wrote them (IGES files are often in mm): choose mu, the\n\
         # stiffnesses and gravity in the same units.\n\n",
        if surface {
            "outer ring of control points"
        } else {
            "end control points"
        }
    ));
    match source {
        GeometrySource::Inline => t.push_str(&geometry_toml(geometry)),
        GeometrySource::Link { file, index } => {
            let section = geometry.section();
            t.push_str(&format!(
                "[{section}]\n# Read when the scene is loaded; the path is relative to this file.\n\
                 file = \"{}\"\nindex = {index}   # which {section} of the file, counted from 0\n",
                file.replace('\\', "\\\\").replace('"', "\\\"")
            ));
        }
    }
    t.push_str(
        "\n[material]\n\
         mu = 1.0                 # mass per unit parameter area (curves: length)\n\
         gamma = 0.1              # damping density\n\
         alpha11 = 1.0            # stretching along u\n",
    );
    if surface {
        t.push_str(
            "alpha22 = 1.0            # stretching along v\n\
             beta11 = 0.01            # bending along u\n\
             beta12 = 0.01            # twist\n\
             beta22 = 0.01            # bending along v\n",
        );
    } else {
        t.push_str("beta11 = 0.01            # bending\n");
    }
    t.push_str(
        "\n[loads]\n\
         gravity = [0.0, 0.0, -9.81]\n\
         \n[constraints]\n",
    );
    t.push_str(if surface {
        "fixed_rings = 1          # the outer ring of control points is held\n"
    } else {
        "fixed_rings = 1          # the first and the last control point are held\n"
    });
    t.push_str(
        "\n[simulation]\n\
         dt = 0.01\n\
         t_end = 2.0\n\
         dnurbs_integrator = \"newmark\"\n\
         msm_integrator = \"backward-euler\"   # unconditionally stable; explicit ones need dt below `nurbspring stability`\n\
         save_every = 10\n\
         \n[msm]\n\
         # The lattice of `simulate --model msm`; `derive` fits its constants (see [fit]).\n\
         structural = true\n\
         shear = true\n\
         bending = true\n\
         \n[fit]\n\
         derivation = \"modal\"\n",
    );
    t
}

/// What `refine` does to a scene's geometry, in this order: raise the degrees to `degrees`
/// (when given), then insert the knots.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Refinement {
    /// Knots to insert along u (a curve's only direction).
    pub insert_u: Vec<f64>,
    /// Knots to insert along v (surfaces only).
    pub insert_v: Vec<f64>,
    /// Target degrees `(p, q)` (curves: `(p, _)`), each at least the current one.
    pub degrees: Option<(usize, Option<usize>)>,
}

impl GeometrySpec {
    /// The net's size and degrees, in words: `4 x 3 control points, degrees 3,2`.
    pub fn describe(&self) -> String {
        match self {
            GeometrySpec::Surface(s) => format!(
                "{} x {} control points, degrees {},{}",
                s.n_u(),
                s.n_v(),
                s.degree_u,
                s.degree_v
            ),
            GeometrySpec::Curve(c) => {
                format!(
                    "{} control points, degree {}",
                    c.control_points.len(),
                    c.degree
                )
            }
        }
    }
}

/// The scene with its geometry refined exactly (The NURBS Book A5.9/A5.10 degree elevation, then
/// A5.4/A5.5 knot insertion, on the homogeneous control points): the surface or curve is the same
/// point set with the same parametrization. Keys that name control points of the coarse net
/// (`constraints.fixed`, `[[constraints.linear]]`, `initial.velocities`) are refused rather than
/// guessed; `fixed_rings` keeps its meaning on the fine net. Errors name the option.
pub fn refine_scene(scene: &Scene, r: &Refinement) -> Result<Scene, Error> {
    let bad = |name: &str, value: String, message: String| Error::Option {
        name: name.to_string(),
        value,
        message,
    };
    for (key, used) in [
        ("constraints.fixed", !scene.constraints.fixed.is_empty()),
        ("constraints.linear", !scene.constraints.linear.is_empty()),
        ("initial.velocities", scene.initial.velocities.is_some()),
    ] {
        if used {
            return Err(Error::Scene(SceneError::Invalid {
                path: scene.path.clone(),
                problems: vec![Problem::new(
                    key,
                    "",
                    "names control points of the coarse net, which refine cannot carry over to the refined net; \
                     refine a copy without it (fixed_rings and uniform velocities carry over) and add it back",
                )],
            }));
        }
    }
    let fmt_knots = |v: &[f64]| v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(",");
    let geometry = match &scene.geometry {
        GeometrySpec::Surface(_) => {
            let mut s = scene.to_surface()?;
            if let Some((p, q)) = r.degrees {
                let q = q.ok_or_else(|| {
                    bad(
                        "--elevate",
                        p.to_string(),
                        "a surface needs two degrees, P,Q (u, v)".to_string(),
                    )
                })?;
                let (pu, pv) = (s.basis_u().degree(), s.basis_v().degree());
                if p < pu || q < pv {
                    return Err(bad(
                        "--elevate",
                        format!("{p},{q}"),
                        format!("the target degrees must be at least the current ones ({pu},{pv})"),
                    ));
                }
                s = s
                    .elevate_degree(p - pu, q - pv)
                    .map_err(|e| bad("--elevate", format!("{p},{q}"), e.to_string()))?
                    .0;
            }
            for (name, knots) in [("--insert-u", &r.insert_u), ("--insert-v", &r.insert_v)] {
                if knots.is_empty() {
                    continue;
                }
                let (u, v): (&[f64], &[f64]) = if name == "--insert-u" {
                    (knots, &[])
                } else {
                    (&[], knots)
                };
                s = s
                    .refine_knots(u, v)
                    .map_err(|e| bad(name, fmt_knots(knots), e.to_string()))?
                    .0;
            }
            GeometrySpec::Surface(SurfaceSpec::from_surface(&s))
        }
        GeometrySpec::Curve(_) => {
            if !r.insert_v.is_empty() {
                return Err(bad(
                    "--insert-v",
                    fmt_knots(&r.insert_v),
                    "a curve has one parameter: use --insert-u".to_string(),
                ));
            }
            let mut c = scene.to_curve()?;
            if let Some((p, q)) = r.degrees {
                if let Some(q) = q {
                    return Err(bad(
                        "--elevate",
                        format!("{p},{q}"),
                        "a curve has one degree: --elevate P".to_string(),
                    ));
                }
                let pc = c.basis().degree();
                if p < pc {
                    return Err(bad(
                        "--elevate",
                        p.to_string(),
                        format!("the target degree must be at least the current one ({pc})"),
                    ));
                }
                c = c
                    .elevate_degree(p - pc)
                    .map_err(|e| bad("--elevate", p.to_string(), e.to_string()))?
                    .0;
            }
            if !r.insert_u.is_empty() {
                c = c
                    .refine_knots(&r.insert_u)
                    .map_err(|e| bad("--insert-u", fmt_knots(&r.insert_u), e.to_string()))?
                    .0;
            }
            GeometrySpec::Curve(CurveSpec::from_curve(&c))
        }
    };
    let mut refined = scene.clone();
    refined.geometry = geometry;
    // Validate the whole scene again: lattice and probe keys may not fit the new net.
    Ok(Scene::from_str(&refined.to_toml(), &scene.path)?)
}

/// Writes a polyline of `n` points uniformly spaced in the parameter of a curve as OBJ `l`
/// records.
pub fn write_tessellated_curve_obj(
    path: &Path,
    curve: &NurbsCurve,
    n: usize,
    comment: &str,
) -> Result<(), Error> {
    let (a, b) = curve.domain();
    let points = nurbspring_geom::linspace(a, b, n)
        .into_iter()
        .map(|u| curve.point(u))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| {
            Error::Output(nurbspring_io::OutputError::InvalidData {
                path: path.to_path_buf(),
                message: e.to_string(),
            })
        })?;
    let lines = (1..points.len()).map(|i| [i - 1, i]).collect();
    Ok(write_obj(path, &ObjMesh::lattice(points, lines), comment)?)
}

/// Writes a scene (or any text file) atomically.
pub fn write_text_file(path: &Path, text: &str) -> Result<(), Error> {
    Ok(write_atomic_bytes(path, text.as_bytes())?)
}
