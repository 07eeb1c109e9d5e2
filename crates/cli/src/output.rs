//! Output helpers shared by the commands: plots, ParaView frames and series, tessellations.

use std::path::Path;

use anyhow::anyhow;
use nurbspring_dnurbs::Geometry;
use nurbspring_geom::linspace;
use nurbspring_io::OutputError;
use nurbspring_io::output::{ObjMesh, write_csv, write_obj};
use nurbspring_io::plot::{PlotOptions, Series, plot_series_with};
use nurbspring_io::vtk::{Cell, DataArray, PvdSeries, VtkStructured, VtkUnstructured};
use nurbspring_msm::SpringLattice;

use crate::Failure;

fn io(e: OutputError) -> Failure {
    Failure::run(e)
}

/// Writes a plot (SVG or PNG by extension), optionally with a logarithmic y axis.
pub fn plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_y: bool,
) -> Result<(), OutputError> {
    let mut options = PlotOptions::new(title, x_label, y_label);
    options.log_y = log_y;
    plot_series_with(path, &options, series).map(|_| ())
}

/// Writes a `.pvd` collection of `(time, file)` frames.
pub fn write_pvd(path: &Path, frames: &[(f64, String)]) -> Result<(), OutputError> {
    let mut series = PvdSeries::default();
    for (t, f) in frames {
        series.push(*t, f.as_str());
    }
    series.write(path)
}

/// The lattice at positions `x` as an unstructured grid: springs as lines carrying their
/// kind, stiffness, rest length and strain; nodes carrying mass, fixed flag and displacement.
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
    grid.cell_data.push(DataArray::scalars(
        "strain",
        lattice
            .springs
            .iter()
            .zip(&lengths)
            .map(|(s, l)| (l - s.rest_length) / s.rest_length)
            .collect(),
    ));
    grid.cell_data.push(DataArray::scalars(
        "kind",
        lattice
            .springs
            .iter()
            .map(|s| {
                nurbspring_msm::SpringKind::ALL
                    .iter()
                    .position(|k| *k == s.kind)
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

/// One lattice frame (`.vtu`).
pub fn write_lattice_frame(path: &Path, lattice: &SpringLattice, x: &[f64]) -> Result<(), Failure> {
    lattice_grid(lattice, x).write(path).map_err(io)
}

/// The lattice at rest (`.vtu`).
pub fn write_lattice_vtu(path: &Path, lattice: &SpringLattice) -> Result<(), Failure> {
    write_lattice_frame(path, lattice, &lattice.flat_positions())
}

/// Samples per knot span used for pictures of a surface or curve.
const SAMPLES_PER_SPAN: usize = 8;

/// Geometry with generalized coordinates `p` (3 or 4 per control point) substituted.
fn geometry_at(geometry: &Geometry, p: &[f64], dofs_per_point: usize) -> Result<Geometry, Failure> {
    let n = geometry.n_control_points();
    let pts: Vec<[f64; 3]> = (0..n)
        .map(|k| {
            [
                p[dofs_per_point * k],
                p[dofs_per_point * k + 1],
                p[dofs_per_point * k + 2],
            ]
        })
        .collect();
    let fail = |e: nurbspring_geom::GeomError| {
        Failure::run(anyhow!("the deformed geometry is invalid: {e}"))
    };
    Ok(match geometry {
        Geometry::Surface(s) => {
            if dofs_per_point == 4 {
                let w: Vec<f64> = (0..n).map(|k| p[4 * k + 3]).collect();
                Geometry::Surface(s.with_control_points_and_weights(pts, w).map_err(fail)?)
            } else {
                Geometry::Surface(s.with_control_points(pts).map_err(fail)?)
            }
        }
        Geometry::Curve(c) => Geometry::Curve(c.with_control_points(pts).map_err(fail)?),
    })
}

/// A ParaView frame of the geometry at coordinates `p`: `.vts` structured grid for a surface,
/// `.vtu` polyline for a curve.
pub fn write_geometry_frame(
    path: &Path,
    geometry: &Geometry,
    p: &[f64],
    dofs_per_point: usize,
) -> Result<(), Failure> {
    let g = geometry_at(geometry, p, dofs_per_point)?;
    match &g {
        Geometry::Surface(s) => {
            let nu = SAMPLES_PER_SPAN * s.basis_u().knots().nonempty_spans().len() + 1;
            let nv = SAMPLES_PER_SPAN * s.basis_v().knots().nonempty_spans().len() + 1;
            let (_, _, pts) = s.uniform_grid(nu, nv).map_err(Failure::run)?;
            let mut grid = VtkStructured::new(nu, nv, pts);
            let disp = displacement_samples(geometry, &g, nu, nv)?;
            grid.point_data
                .push(DataArray::vectors("displacement", &disp));
            grid.write(path).map_err(io)
        }
        Geometry::Curve(c) => {
            let n = SAMPLES_PER_SPAN * c.basis().knots().nonempty_spans().len() + 1;
            let (a, b) = c.domain();
            let us = linspace(a, b, n);
            let pts: Vec<[f64; 3]> = c
                .derivatives_batch(&us, 0)
                .map_err(Failure::run)?
                .into_iter()
                .map(|d| d.point)
                .collect();
            let mut grid = VtkUnstructured::new(pts);
            grid.cells.push(Cell::PolyLine((0..n).collect()));
            grid.write(path).map_err(io)
        }
    }
}

fn displacement_samples(
    rest: &Geometry,
    now: &Geometry,
    nu: usize,
    nv: usize,
) -> Result<Vec<[f64; 3]>, Failure> {
    match (rest, now) {
        (Geometry::Surface(a), Geometry::Surface(b)) => {
            let (_, _, pa) = a.uniform_grid(nu, nv).map_err(Failure::run)?;
            let (_, _, pb) = b.uniform_grid(nu, nv).map_err(Failure::run)?;
            Ok(pa
                .iter()
                .zip(&pb)
                .map(|(x, y)| [y[0] - x[0], y[1] - x[1], y[2] - x[2]])
                .collect())
        }
        _ => Ok(Vec::new()),
    }
}

fn parse_grid(spec: &str, n: usize) -> Result<Vec<usize>, Failure> {
    let parts: Vec<&str> = spec.split(',').map(str::trim).collect();
    let bad = || {
        Failure::input(anyhow!(
            "--grid {spec}: expected {n} integer{} ≥ 2",
            if n == 1 { "" } else { "s" }
        ))
    };
    if parts.len() != n {
        return Err(bad());
    }
    let v: Vec<usize> = parts
        .iter()
        .map(|p| p.parse::<usize>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    if v.iter().any(|&x| x < 2) {
        return Err(bad());
    }
    if v.iter().product::<usize>() > 50_000_000 {
        return Err(Failure::input(anyhow!(
            "--grid {spec}: more than 5·10^7 points"
        )));
    }
    Ok(v)
}

/// `eval --grid NU,NV --out FILE`: the tessellated surface (or curve) as CSV, VTS, VTU or OBJ.
pub fn write_tessellation(out: &Path, geometry: &Geometry, spec: &str) -> Result<(), Failure> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if !matches!(ext.as_str(), "csv" | "vts" | "vtu" | "obj") {
        return Err(Failure::input(anyhow!(
            "--out {}: unknown format `{ext}` (use .csv, .vts, .vtu or .obj)",
            out.display()
        )));
    }
    match geometry {
        Geometry::Surface(s) => {
            let n = parse_grid(spec, 2)?;
            let (us, vs, pts) = s.uniform_grid(n[0], n[1]).map_err(Failure::run)?;
            match ext.as_str() {
                "csv" => {
                    let rows = pts
                        .iter()
                        .enumerate()
                        .map(|(k, p)| vec![us[k / vs.len()], vs[k % vs.len()], p[0], p[1], p[2]]);
                    write_csv(out, &["u", "v", "x", "y", "z"], rows).map_err(io)
                }
                "vts" => VtkStructured::new(n[0], n[1], pts).write(out).map_err(io),
                "vtu" => {
                    let mut grid = VtkUnstructured::new(pts);
                    for i in 0..n[0] - 1 {
                        for j in 0..n[1] - 1 {
                            let a = i * n[1] + j;
                            grid.cells
                                .push(Cell::Quad([a, a + n[1], a + n[1] + 1, a + 1]));
                        }
                    }
                    grid.write(out).map_err(io)
                }
                _ => {
                    let mesh = ObjMesh::quad_grid(pts, n[0], n[1])
                        .ok_or_else(|| Failure::run(anyhow!("cannot build the quad mesh")))?;
                    write_obj(out, &mesh, "nurbspring tessellated surface").map_err(io)
                }
            }
        }
        Geometry::Curve(c) => {
            let n = parse_grid(spec.split(',').next().unwrap_or(spec), 1)?;
            let (a, b) = c.domain();
            let us = linspace(a, b, n[0]);
            let pts: Vec<[f64; 3]> = c
                .derivatives_batch(&us, 0)
                .map_err(Failure::run)?
                .into_iter()
                .map(|d| d.point)
                .collect();
            match ext.as_str() {
                "csv" => write_csv(
                    out,
                    &["u", "x", "y", "z"],
                    us.iter().zip(&pts).map(|(u, p)| vec![*u, p[0], p[1], p[2]]),
                )
                .map_err(io),
                "obj" => {
                    let springs: Vec<[usize; 2]> = (1..pts.len()).map(|i| [i - 1, i]).collect();
                    write_obj(
                        out,
                        &ObjMesh::lattice(pts, springs),
                        "nurbspring tessellated curve",
                    )
                    .map_err(io)
                }
                _ => {
                    let mut grid = VtkUnstructured::new(pts);
                    grid.cells.push(Cell::PolyLine((0..n[0]).collect()));
                    grid.write(out).map_err(io)
                }
            }
        }
    }
}
