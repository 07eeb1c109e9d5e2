//! Models → pictures: ParaView frames (VTK XML) and OBJ meshes of the lattice and of the
//! surface or curve, and tessellations.

use std::path::Path;

use nurbspring_dnurbs::Geometry;
use nurbspring_geom::linspace;
use nurbspring_io::OutputError;
use nurbspring_io::output::{ObjMesh, write_csv, write_obj};
use nurbspring_io::vtk::{Cell, DataArray, StringArray, VtkStructured, VtkUnstructured};
use nurbspring_msm::{Class, SpringLattice};

use crate::Error;

/// Samples per knot span used for pictures of a surface or curve.
pub const SAMPLES_PER_SPAN: usize = 8;

/// The lattice at positions `x` as an unstructured grid: springs as lines carrying their
/// stiffness, rest length, elongation and kind (an integer code `kind` and its name
/// `kind_name`); nodes carrying mass, fixed flag and displacement.
pub fn lattice_grid(lattice: &SpringLattice, x: &[f64]) -> VtkUnstructured {
    let points: Vec<[f64; 3]> = x.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    let mut grid = VtkUnstructured::new(points.clone());
    grid.cells = lattice
        .springs
        .iter()
        .map(|s| Cell::Line([s.a, s.b]))
        .collect();
    let lengths = lattice.spring_lengths(x);
    grid.cell_data.push(DataArray::scalars(
        "stiffness",
        lattice.springs.iter().map(|s| s.stiffness()).collect(),
    ));
    grid.cell_data.push(DataArray::scalars(
        "rest_length",
        lattice.springs.iter().map(|s| s.rest_length).collect(),
    ));
    // The elongation l − L, not the strain (l − L)/L: zero-rest-length springs have no strain.
    grid.cell_data.push(DataArray::scalars(
        "elongation",
        lattice
            .springs
            .iter()
            .zip(&lengths)
            .map(|(s, l)| l - s.rest_length)
            .collect(),
    ));
    // The spring kind twice: its code (the position in `Class::SPRINGS`, for colouring) and
    // its name (a VTK string array, for ParaView's spreadsheet and categories).
    let code = |s: &nurbspring_msm::Spring| {
        Class::SPRINGS
            .iter()
            .position(|c| *c == Class::Spring(s.kind))
            .unwrap_or(0)
    };
    grid.cell_data.push(DataArray::scalars(
        "kind",
        lattice.springs.iter().map(|s| code(s) as f64).collect(),
    ));
    grid.cell_strings.push(StringArray::new(
        "kind_name",
        lattice
            .springs
            .iter()
            .map(|s| Class::SPRINGS[code(s)].name().to_string())
            .collect(),
    ));
    grid.point_data
        .push(DataArray::scalars("mass", lattice.masses.clone()));
    grid.point_data.push(DataArray::scalars(
        "fixed",
        lattice
            .fixed
            .iter()
            .map(|&f| if f { 1.0 } else { 0.0 })
            .collect(),
    ));
    let displacement: Vec<[f64; 3]> = points
        .iter()
        .zip(&lattice.positions)
        .map(|(p, q)| [p[0] - q[0], p[1] - q[1], p[2] - q[2]])
        .collect();
    grid.point_data
        .push(DataArray::vectors("displacement", &displacement));
    grid
}

/// One lattice frame (`.vtu`) at positions `x`.
pub fn write_lattice_frame(path: &Path, lattice: &SpringLattice, x: &[f64]) -> Result<(), Error> {
    Ok(lattice_grid(lattice, x).write(path)?)
}

/// The lattice at rest (`.vtu`).
pub fn write_lattice_vtu(path: &Path, lattice: &SpringLattice) -> Result<(), Error> {
    write_lattice_frame(path, lattice, &lattice.flat_positions())
}

/// The lattice at rest as an OBJ of points and spring lines.
pub fn write_lattice_obj(path: &Path, lattice: &SpringLattice) -> Result<(), Error> {
    let obj = ObjMesh::lattice(
        lattice.positions.clone(),
        lattice.springs.iter().map(|s| [s.a, s.b]).collect(),
    );
    Ok(write_obj(path, &obj, "nurbspring derived lattice")?)
}

/// Geometry with generalized coordinates `p` (3 or 4 per control point) substituted.
fn geometry_at(geometry: &Geometry, p: &[f64], dofs_per_point: usize) -> Result<Geometry, Error> {
    geometry
        .with_coordinates(p, dofs_per_point == 4)
        .map_err(|e| {
            Error::Output(OutputError::InvalidData {
                path: Default::default(),
                message: format!("the deformed geometry is invalid: {e}"),
            })
        })
}

/// A ParaView frame of the geometry at coordinates `p`: `.vts` structured grid for a surface
/// (with the displacement from `geometry`), `.vtu` polyline for a curve.
pub fn write_geometry_frame(
    path: &Path,
    geometry: &Geometry,
    p: &[f64],
    dofs_per_point: usize,
) -> Result<(), Error> {
    write_geometry_frame_with(path, geometry, p, None, dofs_per_point)
}

/// The velocity `d c(p(t)) / dt = Σ_k (∂c/∂p_k) ṗ_k` of the surface points of
/// [`Geometry::uniform_samples`]-style grids: with constant weights `c` is linear in the control
/// points, so it is the geometry with control points `ṗ` (same weights) evaluated there; with
/// weights as unknowns a central difference of `c(p ± h ṗ)` (`h ‖ṗ‖∞ = 10⁻⁶ max(1, ‖p‖∞)`).
fn point_velocities(
    geometry: &Geometry,
    p: &[f64],
    velocity: &[f64],
    dofs_per_point: usize,
    sample: &dyn Fn(&Geometry) -> Result<Vec<[f64; 3]>, Error>,
) -> Result<Vec<[f64; 3]>, Error> {
    if dofs_per_point == 3 {
        return sample(&geometry_at(geometry, velocity, 3)?);
    }
    let vmax = velocity.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if vmax == 0.0 {
        return Ok(vec![[0.0; 3]; sample(&geometry_at(geometry, p, 4)?)?.len()]);
    }
    let pmax = p.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
    let h = 1e-6 * pmax / vmax;
    let shifted = |sign: f64| -> Vec<f64> {
        p.iter()
            .zip(velocity)
            .map(|(a, b)| a + sign * h * b)
            .collect()
    };
    let plus = sample(&geometry_at(geometry, &shifted(1.0), 4)?)?;
    let minus = sample(&geometry_at(geometry, &shifted(-1.0), 4)?)?;
    Ok(plus
        .iter()
        .zip(&minus)
        .map(|(a, b)| {
            [
                (a[0] - b[0]) / (2.0 * h),
                (a[1] - b[1]) / (2.0 * h),
                (a[2] - b[2]) / (2.0 * h),
            ]
        })
        .collect())
}

/// [`write_geometry_frame`] with, when `velocity` (ṗ, the layout of `p`) is given, the points'
/// `velocity` as a second point array.
pub fn write_geometry_frame_with(
    path: &Path,
    geometry: &Geometry,
    p: &[f64],
    velocity: Option<&[f64]>,
    dofs_per_point: usize,
) -> Result<(), Error> {
    let g = geometry_at(geometry, p, dofs_per_point)?;
    let run = |e: nurbspring_geom::GeomError| {
        Error::Output(OutputError::InvalidData {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
    };
    match (&g, geometry) {
        (Geometry::Surface(s), Geometry::Surface(rest)) => {
            let nu = SAMPLES_PER_SPAN * s.basis_u().knots().nonempty_spans().len() + 1;
            let nv = SAMPLES_PER_SPAN * s.basis_v().knots().nonempty_spans().len() + 1;
            let (_, _, pts) = s.uniform_grid(nu, nv).map_err(run)?;
            let (_, _, before) = rest.uniform_grid(nu, nv).map_err(run)?;
            let disp: Vec<[f64; 3]> = before
                .iter()
                .zip(&pts)
                .map(|(x, y)| [y[0] - x[0], y[1] - x[1], y[2] - x[2]])
                .collect();
            let mut grid = VtkStructured::new(nu, nv, pts);
            grid.point_data
                .push(DataArray::vectors("displacement", &disp));
            if let Some(v) = velocity {
                let sample = |g: &Geometry| match g {
                    Geometry::Surface(s) => Ok(s.uniform_grid(nu, nv).map_err(run)?.2),
                    Geometry::Curve(_) => Err(shape_mismatch(path)),
                };
                let vel = point_velocities(geometry, p, v, dofs_per_point, &sample)?;
                grid.point_data.push(DataArray::vectors("velocity", &vel));
            }
            Ok(grid.write(path)?)
        }
        (Geometry::Curve(c), Geometry::Curve(rest)) => {
            let n = SAMPLES_PER_SPAN * c.basis().knots().nonempty_spans().len() + 1;
            let pts = curve_points(c, n).map_err(run)?;
            let before = curve_points(rest, n).map_err(run)?;
            let disp: Vec<[f64; 3]> = before
                .iter()
                .zip(&pts)
                .map(|(x, y)| [y[0] - x[0], y[1] - x[1], y[2] - x[2]])
                .collect();
            let mut grid = VtkUnstructured::new(pts);
            grid.cells.push(Cell::PolyLine((0..n).collect()));
            grid.point_data
                .push(DataArray::vectors("displacement", &disp));
            if let Some(v) = velocity {
                let sample = |g: &Geometry| match g {
                    Geometry::Curve(c) => curve_points(c, n).map_err(run),
                    Geometry::Surface(_) => Err(shape_mismatch(path)),
                };
                let vel = point_velocities(geometry, p, v, dofs_per_point, &sample)?;
                grid.point_data.push(DataArray::vectors("velocity", &vel));
            }
            Ok(grid.write(path)?)
        }
        _ => unreachable_shape(path),
    }
}

/// The control net at coordinates `p` (velocities `velocity`, same layout) as an unstructured
/// grid: one point per control point (`k = i n_v + j`), lines between neighbours along u and v
/// (a polyline for a curve), with point arrays `displacement` (from `p0`), `velocity` and
/// `weight`.
pub fn control_net_grid(
    geometry: &Geometry,
    p: &[f64],
    velocity: &[f64],
    p0: &[f64],
    dofs_per_point: usize,
) -> VtkUnstructured {
    let d = dofs_per_point;
    let n = geometry.n_control_points();
    let xyz = |v: &[f64], k: usize| [v[d * k], v[d * k + 1], v[d * k + 2]];
    let points: Vec<[f64; 3]> = (0..n).map(|k| xyz(p, k)).collect();
    let mut grid = VtkUnstructured::new(points.clone());
    match geometry {
        Geometry::Surface(s) => {
            let (nu, nv) = (s.n_u(), s.n_v());
            for i in 0..nu {
                for j in 0..nv {
                    let k = i * nv + j;
                    if i + 1 < nu {
                        grid.cells.push(Cell::Line([k, k + nv]));
                    }
                    if j + 1 < nv {
                        grid.cells.push(Cell::Line([k, k + 1]));
                    }
                }
            }
        }
        Geometry::Curve(_) => grid.cells.push(Cell::PolyLine((0..n).collect())),
    }
    let disp: Vec<[f64; 3]> = (0..n)
        .map(|k| {
            let (a, b) = (xyz(p, k), xyz(p0, k));
            [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
        })
        .collect();
    grid.point_data
        .push(DataArray::vectors("displacement", &disp));
    let vel: Vec<[f64; 3]> = (0..n).map(|k| xyz(velocity, k)).collect();
    grid.point_data.push(DataArray::vectors("velocity", &vel));
    let weights: Vec<f64> = if d == 4 {
        (0..n).map(|k| p[4 * k + 3]).collect()
    } else {
        geometry.weights().to_vec()
    };
    grid.point_data.push(DataArray::scalars("weight", weights));
    grid
}

fn unreachable_shape(path: &Path) -> Result<(), Error> {
    Err(shape_mismatch(path))
}

fn shape_mismatch(path: &Path) -> Error {
    Error::Output(OutputError::InvalidData {
        path: path.to_path_buf(),
        message: "a surface and a curve cannot be compared".to_string(),
    })
}

fn curve_points(
    c: &nurbspring_geom::NurbsCurve,
    n: usize,
) -> Result<Vec<[f64; 3]>, nurbspring_geom::GeomError> {
    let (a, b) = c.domain();
    Ok(c.derivatives_batch(&linspace(a, b, n), 0)?
        .into_iter()
        .map(|d| d.point)
        .collect())
}

/// Formats a tessellation can be written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TessellationFormat {
    /// `u, v, x, y, z` rows.
    Csv,
    /// VTK structured grid.
    Vts,
    /// VTK unstructured grid of quads (a polyline for a curve).
    Vtu,
    /// Wavefront OBJ.
    Obj,
}

impl TessellationFormat {
    /// From a file extension (case-insensitive).
    pub fn from_extension(ext: &str) -> Option<Self> {
        match ext.to_ascii_lowercase().as_str() {
            "csv" => Some(Self::Csv),
            "vts" => Some(Self::Vts),
            "vtu" => Some(Self::Vtu),
            "obj" => Some(Self::Obj),
            _ => None,
        }
    }
}

/// The point of `geometry` at `params` (`[u, v]`, a curve `[u]`) and its derivatives up to
/// `order` (at most 2), as `eval` prints it: `{"u", "v", "point", "d": {"u", "v", "uu", "uv",
/// "vv"}}`.
pub fn point_json(
    geometry: &Geometry,
    params: &[f64],
    order: usize,
) -> Result<serde_json::Value, nurbspring_geom::GeomError> {
    use serde_json::json;
    Ok(match geometry {
        Geometry::Surface(s) => {
            let d = s.derivatives(params[0], params[1], order)?;
            let mut entry = json!({"u": params[0], "v": params[1], "point": d.point});
            if order >= 1 {
                let mut dd = json!({"u": d.u, "v": d.v});
                if order >= 2 {
                    dd["uu"] = json!(d.uu);
                    dd["uv"] = json!(d.uv);
                    dd["vv"] = json!(d.vv);
                }
                entry["d"] = dd;
            }
            entry
        }
        Geometry::Curve(c) => {
            let d = c.derivatives(params[0], order)?;
            let mut entry = json!({"u": params[0], "point": d.point});
            if order >= 1 {
                let mut dd = json!({"u": d.u});
                if order >= 2 {
                    dd["uu"] = json!(d.uu);
                }
                entry["d"] = dd;
            }
            entry
        }
    })
}

/// The surface on an `nu × nv` uniform parameter grid (a curve: `nu` points) written to
/// `out` in `format` (a curve has no `.vts`: it is written as `.vtu`).
pub fn write_tessellation(
    out: &Path,
    geometry: &Geometry,
    format: TessellationFormat,
    nu: usize,
    nv: usize,
) -> Result<(), Error> {
    let run = |e: nurbspring_geom::GeomError| {
        Error::Output(OutputError::InvalidData {
            path: out.to_path_buf(),
            message: e.to_string(),
        })
    };
    match geometry {
        Geometry::Surface(s) => {
            let (us, vs, pts) = s.uniform_grid(nu, nv).map_err(run)?;
            match format {
                TessellationFormat::Csv => {
                    let rows = pts
                        .iter()
                        .enumerate()
                        .map(|(k, p)| vec![us[k / vs.len()], vs[k % vs.len()], p[0], p[1], p[2]]);
                    Ok(write_csv(out, &["u", "v", "x", "y", "z"], rows)?)
                }
                TessellationFormat::Vts => Ok(VtkStructured::new(nu, nv, pts).write(out)?),
                TessellationFormat::Vtu => {
                    let mut grid = VtkUnstructured::new(pts);
                    for i in 0..nu - 1 {
                        for j in 0..nv - 1 {
                            let a = i * nv + j;
                            grid.cells.push(Cell::Quad([a, a + nv, a + nv + 1, a + 1]));
                        }
                    }
                    Ok(grid.write(out)?)
                }
                TessellationFormat::Obj => crate::geometry_file::write_tessellated_obj(
                    out,
                    s,
                    nu,
                    nv,
                    "nurbspring tessellated surface (vt: parameters mapped to [0, 1]^2, vn: unit normals)",
                ),
            }
        }
        Geometry::Curve(c) => {
            let (a, b) = c.domain();
            let us = linspace(a, b, nu);
            let pts = curve_points(c, nu).map_err(run)?;
            match format {
                TessellationFormat::Csv => Ok(write_csv(
                    out,
                    &["u", "x", "y", "z"],
                    us.iter().zip(&pts).map(|(u, p)| vec![*u, p[0], p[1], p[2]]),
                )?),
                TessellationFormat::Obj => {
                    let lines: Vec<[usize; 2]> = (1..pts.len()).map(|i| [i - 1, i]).collect();
                    Ok(write_obj(
                        out,
                        &ObjMesh::lattice(pts, lines),
                        "nurbspring tessellated curve",
                    )?)
                }
                TessellationFormat::Vts | TessellationFormat::Vtu => {
                    let mut grid = VtkUnstructured::new(pts);
                    grid.cells.push(Cell::PolyLine((0..nu).collect()));
                    Ok(grid.write(out)?)
                }
            }
        }
    }
}

/// The dof ordering of the D-NURBS matrices, in words.
pub fn dof_ordering(dofs_per_point: usize) -> &'static str {
    if dofs_per_point == 4 {
        "interleaved per control point: x, y, z, w; control point k = i * n_v + j (i along u)"
    } else {
        "interleaved per control point: x, y, z; control point k = i * n_v + j (i along u)"
    }
}

/// `dofs.json`: the ordering and the fixed and free dofs of the matrices.
#[derive(serde::Serialize)]
pub struct DofsFile<'a> {
    /// The ordering, in words.
    pub ordering: &'static str,
    /// 3 or 4.
    pub dofs_per_point: usize,
    /// Control points.
    pub n_control_points: usize,
    /// All dofs.
    pub n_dofs: usize,
    /// Fixed dofs, ascending.
    pub fixed_dofs: &'a [usize],
    /// Free dofs, ascending.
    pub free_dofs: &'a [usize],
    /// Fixed control points.
    pub fixed_control_points: &'a [usize],
    /// The matrix files.
    pub files: serde_json::Value,
    /// What the matrices cover.
    pub matrices_cover: &'static str,
}

impl<'a> DofsFile<'a> {
    /// The dof map of `model`'s matrices, as `dofs.json` holds it.
    pub fn of(model: &'a nurbspring_dnurbs::DnurbsModel) -> Self {
        let m = model.matrices();
        let dof_map = model.dof_map();
        DofsFile {
            ordering: dof_ordering(m.dofs_per_point),
            dofs_per_point: m.dofs_per_point,
            n_control_points: model.geometry().n_control_points(),
            n_dofs: dof_map.n_total(),
            fixed_dofs: dof_map.fixed(),
            free_dofs: dof_map.free(),
            fixed_control_points: model.fixed_points(),
            files: serde_json::json!({"M": "M.mtx", "D": "D.mtx", "K": "K.mtx", "f": "f.mtx"}),
            matrices_cover: "all dofs, before constraints are applied",
        }
    }
}

/// What [`write_matrices`] wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MatricesWritten {
    /// Rows (= columns) of M, D and K: every dof.
    pub dofs: usize,
    /// Free dofs.
    pub free_dofs: usize,
    /// Entries stored in each file (`symmetric`: the non-zeros with row ≥ column).
    pub stored_entries: std::collections::BTreeMap<&'static str, usize>,
    /// The files.
    pub files: Vec<&'static str>,
}

/// The entries a `symmetric` Matrix Market file of `a` stores.
fn lower_nonzeros(a: &nurbspring_sim::SparseMatrix) -> usize {
    a.triplets().filter(|&(i, j, v)| i >= j && v != 0.0).count()
}

/// `M.mtx`, `D.mtx`, `K.mtx`, `f.mtx` and `dofs.json` of a D-NURBS model.
pub fn write_matrices(
    out: &Path,
    model: &nurbspring_dnurbs::DnurbsModel,
    scene_label: &str,
) -> Result<MatricesWritten, Error> {
    use nurbspring_io::output::{
        write_json, write_matrix_market_symmetric, write_matrix_market_vector,
    };
    let m = model.matrices();
    let ordering = dof_ordering(m.dofs_per_point);
    let comment = format!("nurbspring D-NURBS matrix of {scene_label}; dof ordering: {ordering}");
    // M, D and K are symmetric: the lower triangle's non-zeros only.
    write_matrix_market_symmetric(out.join("M.mtx"), &m.mass, &comment)?;
    write_matrix_market_symmetric(out.join("D.mtx"), &m.damping, &comment)?;
    write_matrix_market_symmetric(out.join("K.mtx"), &m.stiffness, &comment)?;
    write_matrix_market_vector(out.join("f.mtx"), &m.force, &comment)?;
    write_json(out.join("dofs.json"), &DofsFile::of(model))?;
    let dof_map = model.dof_map();
    Ok(MatricesWritten {
        dofs: dof_map.n_total(),
        free_dofs: dof_map.n_free(),
        stored_entries: [
            ("M", lower_nonzeros(&m.mass)),
            ("D", lower_nonzeros(&m.damping)),
            ("K", lower_nonzeros(&m.stiffness)),
            ("f", m.force.len()),
        ]
        .into_iter()
        .collect(),
        files: vec!["M.mtx", "D.mtx", "K.mtx", "f.mtx", "dofs.json"],
    })
}

/// `steady.vts` (the deformed surface) and `steady.csv` (its control points) of a steady
/// state `p`.
pub fn write_steady(
    out: &Path,
    model: &nurbspring_dnurbs::DnurbsModel,
    p: &[f64],
) -> Result<(), Error> {
    let dpp = model.matrices().dofs_per_point;
    // The control points are finite by construction of the solve; a non-finite value would
    // be an internal failure, not a file to write.
    if p.iter().any(|x| !x.is_finite()) {
        return Err(Error::model(
            Path::new("steady"),
            None,
            nurbspring_dnurbs::DnurbsError::NonFinite {
                what: "steady state",
                step: 0,
                time: 0.0,
            },
        ));
    }
    write_geometry_frame(&out.join("steady.vts"), model.geometry(), p, dpp)?;
    let rows = (0..model.geometry().n_control_points()).map(|k| p[dpp * k..dpp * k + dpp].to_vec());
    let header: &[&str] = if dpp == 4 {
        &["x", "y", "z", "w"]
    } else {
        &["x", "y", "z"]
    };
    write_csv(out.join("steady.csv"), header, rows)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/scenes.md names the integer `kind` of lattice frames: its mapping is
    /// `Class::SPRINGS`' order.
    #[test]
    fn lattice_kind_codes_are_documented() {
        let docs = include_str!("../../../docs/scenes.md");
        let names: Vec<String> = Class::SPRINGS
            .iter()
            .enumerate()
            .map(|(k, c)| format!("`{k}` {}", c.name()))
            .collect();
        for n in &names {
            assert!(docs.contains(n.as_str()), "docs/scenes.md lacks {n}");
        }
    }

    /// Each spring's `kind_name` is the name of its `kind` code, on a 4 × 4 lattice with all
    /// three kinds (12 + 12 structural, 2 · 9 shear, 8 + 8 bend springs).
    #[test]
    fn lattice_kind_names_match_codes() {
        use nurbspring_geom::{KnotVector, NurbsSurface};
        use nurbspring_msm::{Constants, LatticeOptions, ParameterGrid, SpringKind};
        let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
        let pts = vec![[0., 0., 0.], [0., 1., 0.], [1., 0., 0.], [1., 1., 0.]];
        let surface = NurbsSurface::try_new(k.clone(), k, pts, vec![1.; 4]).unwrap();
        let options = LatticeOptions {
            grid: ParameterGrid::Uniform {
                nodes_u: 4,
                nodes_v: 4,
            },
            constants: Constants::from_pairs(Class::SPRINGS.map(|c| (c, 1.0))),
            ..Default::default()
        };
        let lattice = SpringLattice::from_surface(&surface, &options, &[]).unwrap();
        let grid = lattice_grid(&lattice, &lattice.flat_positions());
        grid.validate().unwrap();
        let codes = &grid
            .cell_data
            .iter()
            .find(|a| a.name == "kind")
            .unwrap()
            .values;
        let names = &grid.cell_strings[0];
        assert_eq!(names.name, "kind_name");
        assert_eq!(names.values.len(), lattice.springs.len());
        let mut count = [0; 3];
        for ((s, &c), n) in lattice.springs.iter().zip(codes).zip(&names.values) {
            let expected = match s.kind {
                SpringKind::Structural => ("structural", 0.0),
                SpringKind::Shear => ("shear", 1.0),
                SpringKind::Bend => ("bend", 2.0),
            };
            assert_eq!((n.as_str(), c), expected);
            count[c as usize] += 1;
        }
        assert_eq!(count, [24, 18, 16]);
    }

    fn paper_model() -> nurbspring_dnurbs::DnurbsModel {
        crate::Scene::paper().unwrap().build_dnurbs().unwrap()
    }

    fn surface_samples(g: &Geometry) -> Result<Vec<[f64; 3]>, Error> {
        match g {
            Geometry::Surface(s) => Ok(s.uniform_grid(5, 4).unwrap().2),
            Geometry::Curve(_) => Err(shape_mismatch(Path::new(""))),
        }
    }

    /// A uniform control-point velocity moves every surface point with it (partition of
    /// unity); with weights as unknowns the central difference agrees with the exact linear
    /// velocity of constant weights.
    #[test]
    fn surface_point_velocities() {
        let model = paper_model();
        let g = model.geometry();
        let p = model.p0().to_vec();
        let n = g.n_control_points();
        let v: Vec<f64> = (0..n).flat_map(|_| [0.0, 0.0, -0.2]).collect();
        let exact = point_velocities(g, &p, &v, 3, &surface_samples).unwrap();
        assert_eq!(exact.len(), 20);
        for x in &exact {
            assert!(x[0].abs() < 1e-15 && x[1].abs() < 1e-15, "{x:?}");
            assert!((x[2] + 0.2).abs() < 1e-14, "{x:?}");
        }
        // A non-uniform velocity: the exact and the central-difference paths agree.
        let v: Vec<f64> = (0..3 * n)
            .map(|i| ((i * 7) % 5) as f64 * 0.1 - 0.2)
            .collect();
        let exact = point_velocities(g, &p, &v, 3, &surface_samples).unwrap();
        let p4: Vec<f64> = p
            .chunks(3)
            .zip(g.weights())
            .flat_map(|(c, w)| [c[0], c[1], c[2], *w])
            .collect();
        let v4: Vec<f64> = v.chunks(3).flat_map(|c| [c[0], c[1], c[2], 0.0]).collect();
        let diff = point_velocities(g, &p4, &v4, 4, &surface_samples).unwrap();
        for (a, b) in exact.iter().zip(&diff) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-8, "{a:?} vs {b:?}");
            }
        }
    }

    /// The control net of the paper's 7 × 5 patch: 6·5 + 7·4 lines, the displacement from p0
    /// and the velocity per control point, unit weights.
    #[test]
    fn control_net_carries_displacement_velocity_and_weight() {
        let model = paper_model();
        let g = model.geometry();
        let p0 = model.p0().to_vec();
        let mut p = p0.clone();
        p[3 * 17 + 2] -= 0.05;
        let v: Vec<f64> = (0..p.len()).map(|i| i as f64).collect();
        let grid = control_net_grid(g, &p, &v, &p0, 3);
        assert_eq!(grid.points.len(), 35);
        assert_eq!(grid.cells.len(), 6 * 5 + 7 * 4);
        assert!(grid.cells.contains(&Cell::Line([17, 22])));
        assert!(grid.cells.contains(&Cell::Line([17, 18])));
        assert!(
            !grid.cells.contains(&Cell::Line([4, 5])),
            "no line across rows"
        );
        let array = |name: &str| {
            grid.point_data
                .iter()
                .find(|a| a.name == name)
                .unwrap_or_else(|| panic!("{name}"))
                .values
                .clone()
        };
        let disp = array("displacement");
        assert_eq!(&disp[3 * 17..3 * 17 + 2], &[0.0, 0.0]);
        assert!((disp[53] + 0.05).abs() < 1e-15, "{}", disp[53]);
        assert!(disp.iter().enumerate().all(|(i, d)| i == 53 || *d == 0.0));
        assert_eq!(array("velocity"), v);
        assert_eq!(array("weight"), vec![1.0; 35]);
    }
}
