//! Assembly of M and K (β11 = β22 = 1) for a bicubic patch of 128 × 128 elements
//! (131 × 131 = 17,161 control points, 51,483 dofs), and one Terzopoulos–Qin step after the
//! factorization. The B-spline patch over the parameter domain takes the exact Kronecker form;
//! the same patch with unequal weights, or integrated over its area, takes the Gauss-point
//! kernel (4 × 4 points an element, as G+Smo in bench-peers/gismo_assembly.py); weights as
//! unknowns (4N × 4N) are measured on 32 × 32 elements. Run:
//! `cargo bench -p nurbspring-dnurbs --bench assembly`.

// `criterion_group!` generates an undocumented public function.
#![allow(missing_docs)]

use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use nurbspring_dnurbs::{
    Assembler, Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material, assemble,
    assemble_scalar,
};
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_sim::{IntegratorKind, make_stepper};

const ELEMENTS: usize = 128;

fn patch() -> NurbsSurface {
    patch_of(ELEMENTS)
}

fn patch_of(elements: usize) -> NurbsSurface {
    let k = KnotVector::clamped_uniform(3, elements).unwrap();
    let g = k.greville();
    let pts: Vec<[f64; 3]> = g
        .iter()
        .flat_map(|&u| {
            g.iter()
                .map(move |&v| [u, v, 0.1 * (3.0 * u).sin() * (2.0 * v).cos()])
        })
        .collect();
    let n = pts.len();
    NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; n]).unwrap()
}

fn material() -> Material {
    Material {
        mu: 1.0,
        beta11: 1.0,
        beta22: 1.0,
        ..Material::default()
    }
}

fn benches(c: &mut Criterion) {
    let geometry = Geometry::Surface(patch());
    assert_eq!(geometry.n_control_points(), 131 * 131);
    let options = DnurbsOptions::default();
    let mut group = c.benchmark_group("dnurbs_128x128_bicubic");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    group.bench_function(
        "pattern only (Assembler::new, once per knot vectors)",
        |b| b.iter(|| Assembler::new(&geometry, &options).unwrap()),
    );
    let assembler = Assembler::new(&geometry, &options).unwrap();
    group.bench_function("Assembler::assemble_scalar (pattern reused)", |b| {
        b.iter(|| assembler.assemble_scalar(&geometry, &material()).unwrap())
    });
    // Area integration cannot be sum-factorized: the Gauss-point kernel runs instead.
    let area = DnurbsOptions {
        integration: nurbspring_dnurbs::Integration::Area,
        ..options.clone()
    };
    let area_assembler = Assembler::new(&geometry, &area).unwrap();
    group.bench_function(
        "Assembler::assemble_scalar, area integration (Gauss-point kernel)",
        |b| {
            b.iter(|| {
                area_assembler
                    .assemble_scalar(&geometry, &material())
                    .unwrap()
            })
        },
    );
    group.bench_function("Assembler::assemble (pattern reused, 3N dofs)", |b| {
        b.iter(|| {
            assembler
                .assemble(&geometry, &material(), &Loads::default())
                .unwrap()
        })
    });
    group.bench_function("assemble_scalar (S_M, S_K, N x N)", |b| {
        b.iter(|| assemble_scalar(&geometry, &material(), &options).unwrap())
    });
    group.bench_function("assemble (M, D, K, f on 3N dofs)", |b| {
        b.iter(|| assemble(&geometry, &material(), &Loads::default(), &options).unwrap())
    });
    // The general path, pattern included, 4 x 4 Gauss points an element.
    let four = DnurbsOptions {
        quadrature_points: Some(4),
        ..options.clone()
    };
    let rational = {
        let s = patch();
        let w: Vec<f64> = (0..s.n_control_points())
            .map(|k| 1.0 + 0.25 * ((k * 7) % 5) as f64 / 4.0)
            .collect();
        Geometry::Surface(
            s.with_control_points_and_weights(s.control_points().to_vec(), w)
                .unwrap(),
        )
    };
    group.bench_function(
        "assemble_scalar, unequal weights (Gauss-point kernel, incl. pattern)",
        |b| b.iter(|| assemble_scalar(&rational, &material(), &four).unwrap()),
    );
    let four_area = DnurbsOptions {
        integration: nurbspring_dnurbs::Integration::Area,
        ..four.clone()
    };
    group.bench_function(
        "assemble_scalar, area integration (Gauss-point kernel, incl. pattern)",
        |b| b.iter(|| assemble_scalar(&geometry, &material(), &four_area).unwrap()),
    );
    let small = Geometry::Surface(patch_of(32));
    let wad = DnurbsOptions {
        weights_as_dofs: true,
        ..four.clone()
    };
    group.bench_function(
        "assemble, weights as dofs, 32 x 32 elements (4N dofs, incl. pattern)",
        |b| b.iter(|| assemble(&small, &material(), &Loads::default(), &wad).unwrap()),
    );
    let constraints = Constraints {
        fixed_rings: 1,
        ..Constraints::default()
    };
    let model = DnurbsModel::new(
        geometry.clone(),
        material(),
        Loads::default(),
        &constraints,
        options.clone(),
    )
    .unwrap();
    let dt = 0.01;
    let mut state = model.initial_state(&[[0.0, 0.0, -0.2]], 0.0);
    let mut stepper = make_stepper(IntegratorKind::TerzopoulosQin, &model, &state, dt).unwrap();
    group.bench_function("terzopoulos-qin step (factored)", |b| {
        b.iter(|| stepper.step(&model, &mut state, dt).unwrap())
    });
    group.finish();
}

criterion_group!(dnurbs, benches);
criterion_main!(dnurbs);
