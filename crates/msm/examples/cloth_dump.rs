//! Writes the cloth of `benches/cloth.rs` for its peers (`bench-peers/cloth_step_newton.py`):
//! `DIR/cloth.json` (the lattice as an msm.json) and, as little-endian f64 arrays of every
//! node's xyz (fixed nodes at rest, velocity 0), the benchmark's initial state
//! (`x0.f64`, `v0.f64`) and nurbspring's state after 1 and 10 symplectic-Euler steps of the
//! benchmark's Δt (`x1.f64`, `v1.f64`, `x10.f64`, `v10.f64`), for the agreement check.
//!
//! Run: `cargo run --release -p nurbspring-msm --example cloth_dump -- DIR [N]` (N = 256).

use std::io::Write;

use nurbspring_sim::{IntegratorKind, State, make_stepper};

#[path = "../benches/support/lattices.rs"]
mod support;

fn write_f64(path: &std::path::Path, values: &[f64]) {
    let mut bytes = Vec::with_capacity(8 * values.len());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::File::create(path)
        .and_then(|mut f| f.write_all(&bytes))
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
}

fn main() {
    let mut args = std::env::args().skip(1);
    let dir = std::path::PathBuf::from(args.next().expect("usage: cloth_dump DIR [N]"));
    let n: usize = args
        .next()
        .map_or(256, |s| s.parse().expect("N: an integer"));
    std::fs::create_dir_all(&dir).expect("the output folder");
    let model = support::cloth(n);
    let lattice = model.lattice();
    std::fs::write(dir.join("cloth.json"), lattice.to_file().to_json_string()).expect("cloth.json");
    let full_v = |s: &State| {
        let mut v = vec![0.0; 3 * lattice.n_nodes()];
        for (i, &a) in model.free_nodes().iter().enumerate() {
            v[3 * a..3 * a + 3].copy_from_slice(&s.v[3 * i..3 * i + 3]);
        }
        v
    };
    let mut s = support::perturbed_state(&model);
    write_f64(&dir.join("x0.f64"), &model.full_positions(&s.q));
    write_f64(&dir.join("v0.f64"), &full_v(&s));
    let dt = support::DT;
    let mut stepper = make_stepper(IntegratorKind::SymplecticEuler, &model, &s, dt).unwrap();
    for step in 1..=10 {
        stepper.step(&model, &mut s, dt).unwrap();
        if step == 1 || step == 10 {
            write_f64(
                &dir.join(format!("x{step}.f64")),
                &model.full_positions(&s.q),
            );
            write_f64(&dir.join(format!("v{step}.f64")), &full_v(&s));
        }
    }
    println!(
        "{}: {} nodes, {} springs, {} hinges, dt = {dt}",
        dir.display(),
        lattice.n_nodes(),
        lattice.springs.len(),
        lattice.hinges.len()
    );
}
