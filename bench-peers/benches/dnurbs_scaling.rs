//! D-NURBS assembly (the pattern, then the values with the pattern reused) and the
//! Terzopoulos–Qin step at several patch sizes (docs/benchmarks.md, "Assembly"): is the step
//! after the factorization O(nnz)?
//!
//! The patch is the one of `crates/dnurbs/benches/assembly.rs` at 32 × 32, 64 × 64 and
//! 128 × 128 elements (bicubic, control points `(u, v, 0.1 sin 3u cos 2v)` at the Greville
//! abscissae, μ = 1, β11 = β22 = 1, outer ring of control points fixed, Δt = 0.01). Before
//! timing, each size prints the free dofs, nnz of the matrix `A = 2M + 2Δt²K` that the
//! Terzopoulos–Qin stepper factors, the number of values of its sparse Cholesky factor (faer's
//! symbolic analysis with the default AMD ordering, as `SpdSolver` does) and the same for the
//! scalar `N × N` matrix `2S_M + 2Δt²S_K` (A is that matrix ⊗ I_3).
//!
//! Run: `cargo bench --manifest-path bench-peers/Cargo.toml --bench dnurbs_scaling`.

// `criterion_group!` generates an undocumented public function.
#![allow(missing_docs)]

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use faer::Side;
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::factorize_symbolic_cholesky;
use nurbspring_dnurbs::{
    Assembler, Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material,
};
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::{IntegratorKind, make_stepper};

const SIZES: [usize; 3] = [32, 64, 128];
const DT: f64 = 0.01;

fn patch(elements: usize) -> NurbsSurface {
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

/// Stored values of the sparse Cholesky factor of the symmetric matrix `a` (lower triangle).
fn factor_len(a: &SparseMatrix) -> usize {
    let sym =
        SymbolicSparseColMatRef::new_checked(a.nrows(), a.ncols(), a.col_ptr(), None, a.row_idx());
    // What `SymbolicLlt::try_new` (used by `SpdSolver`) does: default ordering (AMD) and params.
    factorize_symbolic_cholesky(sym, Side::Lower, Default::default(), Default::default())
        .unwrap()
        .len_val()
}

fn lower_nnz(a: &SparseMatrix) -> usize {
    a.triplets().filter(|&(r, c, _)| r >= c).count()
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("dnurbs_scaling");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(2))
        .measurement_time(Duration::from_secs(5));
    for &elements in &SIZES {
        let geometry = Geometry::Surface(patch(elements));
        let options = DnurbsOptions::default();
        let model = DnurbsModel::new(
            geometry.clone(),
            material(),
            Loads::default(),
            &Constraints {
                fixed_rings: 1,
                ..Constraints::default()
            },
            options.clone(),
        )
        .unwrap();
        let a = SparseMatrix::linear_combination(
            2.0,
            model.reduced_mass(),
            2.0 * DT * DT,
            model.reduced_stiffness(),
        )
        .unwrap();
        let s = Assembler::new(&geometry, &options)
            .unwrap()
            .assemble_scalar(&geometry, &material())
            .unwrap();
        let scalar = SparseMatrix::linear_combination(2.0, &s.mass, 2.0 * DT * DT, &s.stiffness)
            .unwrap();
        let (n, nnz_a, len_l) = (a.nrows(), a.nnz(), factor_len(&a));
        eprintln!(
            "{elements} x {elements} elements: {} control points, {n} free dofs, nnz(M_r) {}, \
             nnz(A) {nnz_a} (lower {}), factor values {len_l}; scalar N x N: nnz {}, \
             factor values {}",
            geometry.n_control_points(),
            model.reduced_mass().nnz(),
            lower_nnz(&a),
            scalar.nnz(),
            factor_len(&scalar),
        );
        let assembler = Assembler::new(&geometry, &options).unwrap();
        group.throughput(Throughput::Elements(geometry.n_control_points() as u64));
        group.bench_with_input(
            BenchmarkId::new("pattern (Assembler::new)", elements),
            &elements,
            |b, _| b.iter(|| Assembler::new(&geometry, &options).unwrap()),
        );
        group.bench_with_input(
            BenchmarkId::new("assemble_scalar (pattern reused)", elements),
            &elements,
            |b, _| b.iter(|| assembler.assemble_scalar(&geometry, &material()).unwrap()),
        );
        let mut state = model.initial_state(&[[0.0, 0.0, -0.2]], 0.0);
        let mut stepper =
            make_stepper(IntegratorKind::TerzopoulosQin, &model, &state, DT).unwrap();
        group.throughput(Throughput::Elements(len_l as u64));
        group.bench_with_input(
            BenchmarkId::new("terzopoulos-qin step (factored)", elements),
            &elements,
            |b, _| b.iter(|| stepper.step(&model, &mut state, DT).unwrap()),
        );
    }
    group.finish();
}

criterion_group!(dnurbs, benches);
criterion_main!(dnurbs);
