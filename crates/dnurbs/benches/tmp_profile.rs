#![allow(missing_docs)]
use std::time::Instant;
use nurbspring_dnurbs::{DnurbsOptions, Geometry, Material, assemble_scalar};
use nurbspring_geom::{KnotVector, NurbsSurface, surface_rule};
use nurbspring_linalg::AssemblyPattern;
fn main() {
    let k = KnotVector::clamped_uniform(3, 128).unwrap();
    let g = k.greville();
    let pts: Vec<[f64; 3]> = g.iter().flat_map(|&u| g.iter().map(move |&v| [u, v, 0.0])).collect();
    let n = pts.len();
    let s = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; n]).unwrap();
    let t = Instant::now();
    let rule = surface_rule(s.basis_u(), s.basis_v(), 4).unwrap();
    println!("rule {:?}", t.elapsed());
    let t = Instant::now();
    let mut entries = Vec::new();
    let nv = s.n_v();
    for e in &rule {
        let mut idx = Vec::new();
        for a in 0..4 { for b in 0..4 { idx.push((e.span_u - 3 + a) * nv + e.span_v - 3 + b); } }
        for &i in &idx { for &j in &idx { entries.push((i, j)); } }
    }
    println!("entries {} {:?}", entries.len(), t.elapsed());
    let t = Instant::now();
    let p = AssemblyPattern::new(n, n, &entries).unwrap();
    println!("pattern {:?}", t.elapsed());
    let vals = vec![1.0; entries.len()];
    let t = Instant::now();
    let m = p.assemble(&vals);
    println!("assemble {:?}", t.elapsed());
    let t = Instant::now();
    let _m3 = m.kron_identity(3);
    println!("kron {:?}", t.elapsed());
    let geometry = Geometry::Surface(s);
    let material = Material { mu: 1.0, beta11: 1.0, beta22: 1.0, ..Material::default() };
    for _ in 0..2 {
        let t = Instant::now();
        let _ = assemble_scalar(&geometry, &material, &DnurbsOptions::default()).unwrap();
        println!("assemble_scalar {:?}", t.elapsed());
    }
}
