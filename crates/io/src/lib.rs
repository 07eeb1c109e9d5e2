//! # nurbspring-io
//!
//! File formats and pictures for nurbspring, knowing no model: atomic writes ([`atomic`]), CSV,
//! JSON, Matrix Market and OBJ ([`output`]), VTK XML grids and ParaView time series ([`vtk`])
//! and figures ([`plot`]). Scene files and the translation between models and files live in
//! `nurbspring-scene`.
//!
//! Everything written goes through [`atomic::write_atomic`]: a temporary file in the target's
//! folder, synced, then renamed, so an interrupted run never leaves a half-written file; a run's
//! output folder is staged and swapped in whole ([`folder::StagedDir`]).
//!
//! ```
//! use nurbspring_io::output::{read_obj, write_csv, write_obj, ObjMesh};
//! use nurbspring_io::vtk::{DataArray, VtkStructured};
//! # let dir = tempfile::tempdir().unwrap();
//! // A flat 3 × 2 sheet at z = 2, as a structured grid, an OBJ quad mesh and a CSV table.
//! let pts: Vec<[f64; 3]> = (0..3)
//!     .flat_map(|i| (0..2).map(move |j| [1.5 * i as f64, 5.0 * j as f64, 2.0]))
//!     .collect();
//! let mut grid = VtkStructured::new(3, 2, pts.clone());
//! grid.point_data.push(DataArray::scalars("z", pts.iter().map(|p| p[2]).collect()));
//! grid.write(dir.path().join("sheet.vts")).unwrap();
//! let mesh = ObjMesh::quad_grid(pts.clone(), 3, 2).unwrap();
//! write_obj(dir.path().join("sheet.obj"), &mesh, "flat sheet").unwrap();
//! assert_eq!(read_obj(dir.path().join("sheet.obj")).unwrap(), mesh);
//! write_csv(dir.path().join("sheet.csv"), &["x", "y", "z"], pts.iter().map(|p| p.to_vec())).unwrap();
//! ```

pub mod atomic;
mod error;
pub mod folder;
pub mod output;
pub mod plot;
pub mod vtk;

pub use error::OutputError;
