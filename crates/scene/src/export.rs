//! Models → pictures: ParaView frames (VTK XML) and OBJ meshes of the lattice and of the
//! surface or curve, and tessellations.

use std::path::Path;

use nurbspring_dnurbs::Geometry;
use nurbspring_geom::linspace;
use nurbspring_io::OutputError;
use nurbspring_io::output::{ObjMesh, write_csv, write_obj};
use nurbspring_io::vtk::{Cell, DataArray, VtkStructured, VtkUnstructured};
use nurbspring_msm::{Class, SpringLattice};

use crate::Error;

/// Samples per knot span used for pictures of a surface or curve.
pub const SAMPLES_PER_SPAN: usize = 8;

/// The lattice at positions `x` as an unstructured grid: springs as lines carrying their
/// class, stiffness, rest length and strain; nodes carrying mass, fixed flag and displacement.
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
        lattice.springs.iter().map(|s| s.k).collect(),
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
    grid.cell_data.push(DataArray::scalars(
        "kind",
        lattice
            .springs
            .iter()
            .map(|s| {
                Class::SPRINGS
                    .iter()
                    .position(|c| *c == Class::Spring(s.kind))
                    .unwrap_or(0) as f64
            })
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
            Ok(grid.write(path)?)
        }
        (Geometry::Curve(c), _) => {
            let n = SAMPLES_PER_SPAN * c.basis().knots().nonempty_spans().len() + 1;
            let pts = curve_points(c, n).map_err(run)?;
            let mut grid = VtkUnstructured::new(pts);
            grid.cells.push(Cell::PolyLine((0..n).collect()));
            Ok(grid.write(path)?)
        }
        _ => unreachable_shape(path),
    }
}

fn unreachable_shape(path: &Path) -> Result<(), Error> {
    Err(Error::Output(OutputError::InvalidData {
        path: path.to_path_buf(),
        message: "a surface and a curve cannot be compared".to_string(),
    }))
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
    let dof_map = model.dof_map();
    write_json(
        out.join("dofs.json"),
        &DofsFile {
            ordering,
            dofs_per_point: m.dofs_per_point,
            n_control_points: model.geometry().n_control_points(),
            n_dofs: dof_map.n_total(),
            fixed_dofs: dof_map.fixed(),
            free_dofs: dof_map.free(),
            fixed_control_points: model.fixed_points(),
            files: serde_json::json!({"M": "M.mtx", "D": "D.mtx", "K": "K.mtx", "f": "f.mtx"}),
            matrices_cover: "all dofs, before constraints are applied",
        },
    )?;
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
