//! Writes nurbspring's scalar D-NURBS matrices of the "Assembly" benchmark (docs/benchmarks.md)
//! so that `bench-peers/gismo_assembly.py` can compare them entry by entry with G+Smo and with a
//! numpy Kronecker reference before timing anything.
//!
//! The patch is the one of `crates/dnurbs/benches/assembly.rs`: bicubic, 128 × 128 uniform
//! elements, control points at the Greville abscissae `(u, v, 0.1 sin 3u cos 2v)`, μ = 1,
//! β11 = β22 = 1, 4 × 4 Gauss points per element. Written (CSC, little endian):
//! - `tensor_{mass,stiffness}.*`: `Assembler::assemble_scalar` with the default options
//!   (parameter-domain integration, the exact Kronecker form), on that patch;
//! - `gauss_{mass,stiffness}.*`: the same with `Integration::Area` (the Gauss-point kernel)
//!   on the flat patch `z = 0`, where the area element is 1 and the matrices must be the same.
//!
//! Run: `cargo run --release --manifest-path bench-peers/Cargo.toml --example dump_dnurbs -- DIR`.

use std::io::Write;

use nurbspring_dnurbs::{Assembler, DnurbsOptions, Geometry, Integration, Material};
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_linalg::SparseMatrix;

const ELEMENTS: usize = 128;

fn patch(curved: bool) -> NurbsSurface {
    let k = KnotVector::clamped_uniform(3, ELEMENTS).unwrap();
    let g = k.greville();
    let pts: Vec<[f64; 3]> = g
        .iter()
        .flat_map(|&u| {
            g.iter().map(move |&v| {
                let z = if curved {
                    0.1 * (3.0 * u).sin() * (2.0 * v).cos()
                } else {
                    0.0
                };
                [u, v, z]
            })
        })
        .collect();
    let n = pts.len();
    NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; n]).unwrap()
}

fn write(dir: &std::path::Path, name: &str, m: &SparseMatrix) {
    let put = |ext: &str, bytes: Vec<u8>| {
        let mut f = std::fs::File::create(dir.join(format!("{name}.{ext}"))).unwrap();
        f.write_all(&bytes).unwrap();
    };
    let u64s = |v: &[usize]| v.iter().flat_map(|&x| (x as u64).to_le_bytes()).collect();
    put("colptr.u64", u64s(m.col_ptr()));
    put("rowidx.u64", u64s(m.row_idx()));
    put(
        "values.f64",
        m.values().iter().flat_map(|x| x.to_le_bytes()).collect(),
    );
    println!(
        "{name}: {} x {}, nnz {}, sum {:e}",
        m.nrows(),
        m.ncols(),
        m.nnz(),
        m.sum()
    );
}

fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "/tmp/nurbspring-agree".into());
    let dir = std::path::PathBuf::from(dir);
    std::fs::create_dir_all(&dir).unwrap();
    let material = Material {
        mu: 1.0,
        beta11: 1.0,
        beta22: 1.0,
        ..Material::default()
    };
    let curved = Geometry::Surface(patch(true));
    let options = DnurbsOptions::default();
    let s = Assembler::new(&curved, &options)
        .unwrap()
        .assemble_scalar(&curved, &material)
        .unwrap();
    write(&dir, "tensor_mass", &s.mass);
    write(&dir, "tensor_stiffness", &s.stiffness);
    let flat = Geometry::Surface(patch(false));
    let area = DnurbsOptions {
        integration: Integration::Area,
        ..options
    };
    let s = Assembler::new(&flat, &area)
        .unwrap()
        .assemble_scalar(&flat, &material)
        .unwrap();
    write(&dir, "gauss_mass", &s.mass);
    write(&dir, "gauss_stiffness", &s.stiffness);
}
