//! Writes one lattice frame, as `simulate` and `derive` write it (`lattice_grid`), in each VTK
//! encoding: `cargo run -p nurbspring-scene --example lattice_vtk -- OUT_DIR` writes
//! `binary64.vtu` (the default: base64, UInt64 headers), `binary32.vtu` (UInt32 headers) and
//! `ascii.vtu`. The lattice is a flat 4 × 4 grid with structural, shear and bend springs, so
//! every `kind` and `kind_name` occurs; scripts/vtk-check/check_lattice_vtk.py reads the files
//! with VTK itself.

use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_io::vtk::{HeaderType, VtkEncoding, VtkFormat};
use nurbspring_msm::{Class, Constants, LatticeOptions, ParameterGrid, SpringLattice};
use nurbspring_scene::export::lattice_grid;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .ok_or("usage: lattice_vtk OUT_DIR")?,
    );
    std::fs::create_dir_all(&out)?;
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1)?;
    let pts = vec![[0., 0., 0.], [0., 1., 0.], [1., 0., 0.], [1., 1., 0.]];
    let surface = NurbsSurface::try_new(k.clone(), k, pts, vec![1.; 4])?;
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 4,
            nodes_v: 4,
        },
        constants: Constants::from_pairs(Class::SPRINGS.map(|c| (c, 1.0))),
        ..Default::default()
    };
    let lattice = SpringLattice::from_surface(&surface, &options, &[])?;
    let grid = lattice_grid(&lattice, &lattice.flat_positions());
    for (name, encoding, header) in [
        ("binary64.vtu", VtkEncoding::Binary, HeaderType::UInt64),
        ("binary32.vtu", VtkEncoding::Binary, HeaderType::UInt32),
        ("ascii.vtu", VtkEncoding::Ascii, HeaderType::UInt64),
    ] {
        grid.write_with(out.join(name), VtkFormat { encoding, header })?;
    }
    println!(
        "{} springs written to {}",
        lattice.springs.len(),
        out.display()
    );
    Ok(())
}
