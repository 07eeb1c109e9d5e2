//! `derive` with the default derivation (`modal`) on a 33 × 33 bicubic control net: scene text
//! → fitted, calibrated and validated MSM (everything `nurbspring derive` computes before it
//! writes files). `cargo bench -p nurbspring-scene --bench derive`.

// `criterion_group!` generates an undocumented public function.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use nurbspring_scene::Scene;

#[path = "../tests/support/sheet.rs"]
mod support;

fn bench(c: &mut Criterion) {
    let text = support::sheet_text(33, 0.02);
    let mut group = c.benchmark_group("derive");
    group.sample_size(10);
    group.bench_function("modal_33x33", |b| {
        b.iter(|| {
            let scene = Scene::from_str(&text, "sheet33.toml").unwrap();
            let (method, _) = scene.derivation();
            let config = scene.derivation_config(Some(method)).unwrap();
            nurbspring_derive::derive(&config, None, &mut |_, _| {}).unwrap()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
