//! The Kirchhoff–Love shell: the tangent assembly of a bicubic 64 × 64-span net (67² control
//! points) beside the tension plate's assembly of the same net, and the nonlinear static solves
//! compared with Kratos' Shell3pElement in docs/benchmarks.md (the Scordelis–Lo roof at degree
//! 4 on 16² spans in 10 load steps, Sze's cantilever at degree 3 on 16 × 1 spans in 20). Run:
//! `cargo bench -p nurbspring-dnurbs --bench shell`.

// `criterion_group!` generates an undocumented public function.
#![allow(missing_docs)]

use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use nurbspring_dnurbs::{
    Assembler, DnurbsOptions, Geometry, Integration, Material, PathSettings, ShellEnergy,
    ShellMaterial, obstacle,
};
use nurbspring_geom::{KnotVector, NurbsSurface};

const SPANS: usize = 64;

fn patch() -> Geometry {
    let k = KnotVector::clamped_uniform(3, SPANS).unwrap();
    let g = k.greville();
    let pts: Vec<[f64; 3]> = g
        .iter()
        .flat_map(|&u| {
            g.iter()
                .map(move |&v| [u, v, 0.1 * (3.0 * u).sin() * (2.0 * v).cos()])
        })
        .collect();
    let n = pts.len();
    Geometry::Surface(NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; n]).unwrap())
}

fn benches(c: &mut Criterion) {
    let geometry = patch();
    let mut group = c.benchmark_group("shell_64x64_bicubic");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    let shell = ShellEnergy::new(
        &geometry,
        &ShellMaterial {
            young: 1e7,
            poisson: 0.3,
            thickness: 0.01,
            density: 1.0,
            gamma: 0.0,
        },
        4,
    )
    .unwrap();
    // A deformed state: the rest shape bent and stretched.
    let p: Vec<f64> = geometry
        .coordinates(false)
        .chunks(3)
        .flat_map(|x| [x[0] * 1.01, x[1], x[2] + 0.05 * x[0] * x[1]])
        .collect();
    group.bench_function("shell internal force and tangent", |b| {
        b.iter(|| shell.force_and_tangent(&p))
    });
    group.bench_function("shell internal force", |b| {
        let mut f = vec![0.0; p.len()];
        b.iter(|| shell.internal_force(&p, &mut f))
    });
    group.bench_function("shell energy", |b| b.iter(|| shell.energy(&p)));
    let plate = Material {
        mu: 1.0,
        alpha11: 1.0,
        alpha22: 1.0,
        beta11: 1.0,
        beta12: 1.0,
        beta22: 1.0,
        ..Material::default()
    };
    let kronecker = Assembler::new(&geometry, &DnurbsOptions::default()).unwrap();
    group.bench_function("tension plate M, K (Kronecker form)", |b| {
        b.iter(|| kronecker.assemble_scalar(&geometry, &plate).unwrap())
    });
    let area = DnurbsOptions {
        integration: Integration::Area,
        quadrature_points: Some(4),
        ..DnurbsOptions::default()
    };
    let gauss = Assembler::new(&geometry, &area).unwrap();
    group.bench_function(
        "tension plate M, K over the area (Gauss-point kernel)",
        |b| b.iter(|| gauss.assemble_scalar(&geometry, &plate).unwrap()),
    );
    group.finish();

    let mut group = c.benchmark_group("shell_nonlinear_static");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    let roof = obstacle::scordelis_lo(4, 16).unwrap();
    group.bench_function("Scordelis-Lo roof, p = 4, 16^2 spans, 10 load steps", |b| {
        let settings = PathSettings {
            levels: 10,
            ..PathSettings::default()
        };
        b.iter(|| {
            roof.model
                .equilibrium_path(&settings, &|| false, &mut |_| {})
                .unwrap()
        })
    });
    let strip = obstacle::sze_cantilever(3, 16).unwrap();
    group.bench_function("Sze cantilever, p = 3, 16 x 1 spans, 20 load steps", |b| {
        let settings = PathSettings {
            levels: 20,
            ..PathSettings::default()
        };
        b.iter(|| {
            strip
                .model
                .equilibrium_path(&settings, &|| false, &mut |_| {})
                .unwrap()
        })
    });
    group.finish();
}

criterion_group!(shell, benches);
criterion_main!(shell);
