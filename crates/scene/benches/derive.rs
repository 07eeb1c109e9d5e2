//! `derive` with the default derivation (`modal`) on a 33 × 33 bicubic control net: scene text
//! → fitted, calibrated and validated MSM (everything `nurbspring derive` computes before it
//! writes files). `cargo bench -p nurbspring-scene --bench derive`.

// `criterion_group!` generates an undocumented public function.
#![allow(missing_docs)]

use std::fmt::Write;

use criterion::{Criterion, criterion_group, criterion_main};
use nurbspring_scene::Scene;

/// A flat 1 × 1 bicubic sheet with `n × n` control points at the Greville abscissae of uniform
/// clamped knots, clamped by two rings, struck by a uniform initial velocity.
fn sheet(n: usize) -> String {
    let p = 3;
    let inner = n - p - 1;
    let mut knots = vec![0.0; p + 1];
    knots.extend((1..=inner).map(|i| i as f64 / (inner + 1) as f64));
    knots.extend(vec![1.0; p + 1]);
    let greville: Vec<f64> = (0..n)
        .map(|i| knots[i + 1..i + p + 1].iter().sum::<f64>() / p as f64)
        .collect();
    let mut s = String::new();
    writeln!(s, "[surface]\ndegree_u = 3\ndegree_v = 3").unwrap();
    writeln!(s, "knots_u = {knots:?}\nknots_v = {knots:?}").unwrap();
    s.push_str("control_points = [\n");
    for x in &greville {
        let row: Vec<String> = greville
            .iter()
            .map(|y| format!("[{x:?}, {y:?}, 0.0]"))
            .collect();
        writeln!(s, "  [{}],", row.join(", ")).unwrap();
    }
    s.push_str("]\n");
    s.push_str(
        "[material]\nmu = 1.0\nalpha11 = 1.0\nalpha22 = 1.0\nbeta11 = 0.01\nbeta22 = 0.01\n\
         [constraints]\nfixed_rings = 2\n[initial]\nvelocity = [0.0, 0.0, -0.1]\n\
         [simulation]\ndt = 0.02\nt_end = 20.0\n",
    );
    s
}

fn bench(c: &mut Criterion) {
    let text = sheet(33);
    let mut group = c.benchmark_group("derive");
    group.sample_size(10);
    group.bench_function("modal_33x33", |b| {
        b.iter(|| {
            let scene = Scene::from_str(&text, "sheet33.toml").unwrap();
            let (method, _) = scene.derivation();
            let config = scene.derivation_config(Some(method)).unwrap();
            nurbspring_derive::derive_linear(&config, None).unwrap()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
