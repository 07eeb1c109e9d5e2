//! Spring forces, energy and stiffness against finite differences and identities
//! (paper eqs. (5), (9)–(10); docs/math.md §5).

mod support;

use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::{Class, MsmModel, SpringKind, SpringLattice};
use nurbspring_sim::DynamicModel;
use proptest::prelude::*;
use support::tolerances::*;
use support::{Lcg, curved_lattice, relative_error};

/// A deformed state of a pre-strained curved lattice with all three spring kinds.
fn deformed(pre_strain: f64, seed: u64) -> (SpringLattice, Vec<f64>) {
    let lattice = curved_lattice(5, 4, pre_strain);
    let mut x = lattice.flat_positions();
    Lcg(seed).perturb(&mut x, 0.05);
    (lattice, x)
}

fn forces(lattice: &SpringLattice, x: &[f64]) -> Vec<f64> {
    let mut f = vec![0.0; x.len()];
    lattice.elastic_forces(x, &mut f);
    f
}

#[test]
fn force_is_minus_energy_gradient() {
    for (pre_strain, seed) in [(0.0, 1), (0.1, 2), (-0.05, 3)] {
        let (lattice, x) = deformed(pre_strain, seed);
        let f = forces(&lattice, &x);
        let h = FD_STEP;
        let grad: Vec<f64> = (0..x.len())
            .map(|j| {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[j] += h;
                xm[j] -= h;
                (lattice.elastic_energy(&xp) - lattice.elastic_energy(&xm)) / (2.0 * h)
            })
            .collect();
        let minus_grad: Vec<f64> = grad.iter().map(|g| -g).collect();
        let err = relative_error(&f, &minus_grad);
        eprintln!("pre-strain {pre_strain}: ‖f + ∇E‖/‖∇E‖ = {err:e}");
        assert!(
            err < FD_RELATIVE,
            "pre-strain {pre_strain}: ‖f + ∇E‖/‖∇E‖ = {err:e}"
        );
    }
}

#[test]
fn tangent_is_minus_force_jacobian() {
    for (pre_strain, seed) in [(0.0, 4), (0.1, 5)] {
        let (lattice, x) = deformed(pre_strain, seed);
        let k = lattice.tangent_stiffness(&x).to_dense();
        let h = FD_STEP;
        let n = x.len();
        let (mut num, mut den) = (0.0, 0.0);
        for j in 0..n {
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[j] += h;
            xm[j] -= h;
            let (fp, fm) = (forces(&lattice, &xp), forces(&lattice, &xm));
            for i in 0..n {
                let fd = -(fp[i] - fm[i]) / (2.0 * h);
                num += (fd - k[(i, j)]).powi(2);
                den += k[(i, j)].powi(2);
            }
        }
        let err = (num / den).sqrt();
        eprintln!("pre-strain {pre_strain}: ‖K_fd − K_T‖/‖K_T‖ = {err:e}");
        assert!(
            err < FD_RELATIVE,
            "pre-strain {pre_strain}: ‖K_fd − K_T‖/‖K_T‖ = {err:e}"
        );
    }
}

#[test]
fn tangent_is_symmetric() {
    let (lattice, x) = deformed(0.1, 6);
    let k = lattice.tangent_stiffness(&x);
    let err = k.symmetry_error();
    eprintln!("symmetry error {err:e}");
    assert!(err < SYMMETRY, "symmetry error {err:e}");
}

fn class_sum(lattice: &SpringLattice, x: &[f64]) -> SparseMatrix {
    let mut sum = SparseMatrix::zeros(x.len(), x.len());
    for kind in lattice.classes() {
        let k_c = lattice.constants().value(kind);
        let g = lattice.unit_stiffness(kind, x);
        sum = SparseMatrix::linear_combination(1.0, &sum, k_c, &g).unwrap();
    }
    sum
}

fn matrix_relative_error(a: &SparseMatrix, b: &SparseMatrix) -> f64 {
    let d = SparseMatrix::linear_combination(1.0, a, -1.0, b).unwrap();
    d.frobenius_norm() / b.frobenius_norm()
}

#[test]
fn tangent_is_sum_of_unit_matrices_at_rest_and_deformed() {
    // At rest (no pre-strain): only the k n nᵀ term.
    let lattice = curved_lattice(5, 4, 0.0);
    assert_eq!(lattice.classes(), Class::SPRINGS.to_vec());
    let x0 = lattice.flat_positions();
    let err = matrix_relative_error(&class_sum(&lattice, &x0), &lattice.tangent_stiffness(&x0));
    eprintln!("K_T vs Σ k_c G_c at rest: {err:e}");
    assert!(err < UNIT_SUM, "at rest: {err:e}");
    // Pre-strained and deformed: the geometric term (1 − l/|d|) I enters too, still linear in k.
    let (lattice, x) = deformed(0.1, 7);
    let err = matrix_relative_error(&class_sum(&lattice, &x), &lattice.tangent_stiffness(&x));
    eprintln!("K_T vs Σ k_c G_c deformed: {err:e}");
    assert!(err < UNIT_SUM, "deformed: {err:e}");
    // And the unit matrices share the tangent's pattern.
    let k = lattice.tangent_stiffness(&x);
    let g = lattice.unit_stiffness(Class::Spring(SpringKind::Shear), &x);
    assert_eq!((k.col_ptr(), k.row_idx()), (g.col_ptr(), g.row_idx()));
}

#[test]
fn geometric_term_appears_only_under_tension() {
    // A single spring along x: at rest length only k n nᵀ (no y, z stiffness); stretched,
    // k (1 − l/|d|) on y and z.
    let s = nurbspring_msm::Spring {
        a: 0,
        b: 1,
        kind: SpringKind::Structural,
        k: 2.0,
        rest_length: 1.0,
        weight: 1.0,
        damping: 0.0,
    };
    let lattice = SpringLattice::from_parts(
        vec![[0.0; 3], [1.0, 0.0, 0.0]],
        vec![1.0; 2],
        vec![0.0; 2],
        vec![false; 2],
        vec![s],
        [0.0; 3],
    )
    .unwrap();
    let k = lattice.tangent_stiffness(&[0., 0., 0., 1., 0., 0.]);
    assert_eq!(
        (k.get(0, 0), k.get(1, 1), k.get(2, 2), k.get(0, 3)),
        (2.0, 0.0, 0.0, -2.0)
    );
    let k = lattice.tangent_stiffness(&[0., 0., 0., 2., 0., 0.]);
    assert_eq!(
        (k.get(0, 0), k.get(1, 1), k.get(2, 2), k.get(1, 4)),
        (2.0, 1.0, 1.0, -1.0)
    );
}

#[test]
fn model_forces_match_lattice_forces_on_free_nodes() {
    let mut lattice = curved_lattice(6, 5, 0.05);
    // Fix one row and a few scattered nodes; add gravity.
    for a in [0, 1, 2, 3, 4, 17, 23] {
        lattice.fixed[a] = true;
    }
    lattice.gravity = [0.0, 0.0, -9.81];
    let model = MsmModel::new(lattice.clone()).unwrap();
    let mut q = model.initial_positions().to_vec();
    Lcg(8).perturb(&mut q, 0.05);
    let x = model.full_positions(&q);
    let f_full = forces(&lattice, &x);
    let mut f_int = vec![0.0; q.len()];
    model.internal_force(&q, &mut f_int);
    let expected: Vec<f64> = model
        .dof_map()
        .restrict(&f_full)
        .iter()
        .map(|f| -f)
        .collect();
    assert!(relative_error(&f_int, &expected) < 1e-14);
    // Energy of every spring, those between fixed nodes and to fixed nodes included.
    let e = model.potential_energy(&q);
    assert!((e - lattice.elastic_energy(&x)).abs() < 1e-13 * e);
    // Tangent on the free coordinates = restriction of the full tangent.
    let k_free = model.tangent_stiffness(&q);
    let k_restricted = model
        .dof_map()
        .restrict_matrix(&lattice.tangent_stiffness(&x));
    assert!(matrix_relative_error(&k_free, &k_restricted) < 1e-15);
    // Gravity: m g on every free node.
    let mut f_ext = vec![0.0; q.len()];
    model.external_force(0.0, &mut f_ext);
    assert!(f_ext.chunks(3).all(|c| c == [0.0, 0.0, -9.81]));
}

#[test]
fn same_results_with_one_and_many_threads() {
    // Large enough for the parallel paths (≥ 32768 incidences).
    let lattice = curved_lattice(80, 80, 0.02);
    let model = MsmModel::new(lattice).unwrap();
    let mut q = model.initial_positions().to_vec();
    Lcg(9).perturb(&mut q, 1e-3);
    let run = || {
        let mut f = vec![0.0; q.len()];
        model.internal_force(&q, &mut f);
        (f, model.potential_energy(&q), model.tangent_stiffness(&q))
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(run);
    let many = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap()
        .install(run);
    assert_eq!(one.0, many.0, "forces differ between 1 and 4 threads");
    assert_eq!(one.1.to_bits(), many.1.to_bits(), "energy differs");
    assert_eq!(one.2, many.2, "tangent differs");
    // And the parallel sums are the sums: against the spring list, one spring at a time (no
    // node is fixed, so q is every coordinate).
    let lattice = curved_lattice(80, 80, 0.02);
    let by_springs = lattice.elastic_energy(&q);
    assert!(
        (one.1 - by_springs).abs() <= 1e-12 * by_springs,
        "{} vs {by_springs}",
        one.1
    );
    let elastic = forces(&lattice, &q);
    let scale = elastic.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (fi, ei) in one.0.iter().zip(&elastic) {
        assert!((fi + ei).abs() <= 1e-12 * scale);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Forces sum to zero, vanish at rest, and K_T annihilates rigid translations.
    #[test]
    fn balance_and_translation_invariance(seed in 0u64..1_000_000, amplitude in 0.0f64..0.2, pre in -0.1f64..0.3) {
        let lattice = curved_lattice(4, 3, pre);
        let mut x = lattice.flat_positions();
        if pre == 0.0 {
            let f = forces(&lattice, &x);
            prop_assert!(f.iter().all(|v| v.abs() < 1e-15));
        }
        Lcg(seed).perturb(&mut x, amplitude);
        let f = forces(&lattice, &x);
        let scale: f64 = f.iter().map(|v| v.abs()).sum::<f64>().max(1.0);
        for c in 0..3 {
            let total: f64 = f.iter().skip(c).step_by(3).sum();
            prop_assert!(total.abs() < FORCE_SUM * scale, "component {} sums to {:e}", c, total);
        }
        let k = lattice.tangent_stiffness(&x);
        let norm = k.frobenius_norm();
        for c in 0..3 {
            let t: Vec<f64> = (0..x.len()).map(|i| if i % 3 == c { 1.0 } else { 0.0 }).collect();
            let mut kt = vec![0.0; x.len()];
            k.mul_vec(&t, &mut kt);
            let r = kt.iter().map(|v| v * v).sum::<f64>().sqrt();
            prop_assert!(r < 1e-14 * norm, "K_T t = {:e} for translation {}", r, c);
        }
    }
}

/// `K̄ = Σ k (I, −I; −I, I)` bounds the tangent at every configuration (docs/math.md §5): the
/// smallest eigenvalue of `K̄ − K_T(q)` is not negative on stretched, compressed and
/// scrambled lattices, and K̄ is the weighted graph Laplacian ⊗ I₃ (diagonal Σk at each node,
/// zero row sums without fixed nodes), computed here from the spring list.
#[test]
fn stiffness_bound_dominates_the_tangent_everywhere() {
    let lattice = curved_lattice(5, 4, 0.1);
    let model = MsmModel::new(lattice.clone()).unwrap();
    let bound = model.stiffness_bound().unwrap().to_dense();
    let n = bound.nrows();
    let mut degree = vec![0.0; lattice.n_nodes()];
    for s in &lattice.springs {
        degree[s.a] += s.k;
        degree[s.b] += s.k;
    }
    for i in 0..n {
        assert!((bound[(i, i)] - degree[i / 3]).abs() <= 1e-14 * degree[i / 3]);
        let row: f64 = (0..n).map(|j| bound[(i, j)]).sum();
        assert!(row.abs() <= 1e-13 * degree[i / 3], "row {i} sums to {row}");
        for j in 0..n {
            if i % 3 != j % 3 {
                assert_eq!(bound[(i, j)], 0.0);
            }
        }
    }
    let x0 = lattice.flat_positions();
    let mut rng = Lcg(11);
    for (scale, noise) in [
        (1.0, 0.0),
        (2.0, 0.0),
        (0.3, 0.0),
        (0.05, 0.0),
        (1.0, 0.5),
        (0.5, 2.0),
    ] {
        let mut x: Vec<f64> = x0.iter().map(|v| scale * v).collect();
        rng.perturb(&mut x, noise);
        let kt = model.tangent_stiffness(&x).to_dense();
        let diff = nurbspring_linalg::DenseMatrix::from_fn(n, n, |i, j| bound[(i, j)] - kt[(i, j)]);
        let eig = nurbspring_linalg::symmetric_eigenvalues(&diff).unwrap();
        let scale_k = degree.iter().cloned().fold(0.0, f64::max);
        assert!(
            eig[0] >= -1e-12 * scale_k,
            "scale {scale}, noise {noise}: λ_min(K̄ − K_T) = {:e}",
            eig[0]
        );
    }
}

/// The per-spring methods on one spring by hand: k = 3, l = 1, nodes at (0.5, 1, −1) and
/// (−0.5, 1, 1), so `d = x_a − x_b = (1, 0, −2)`, `r = √5`. Length r; energy
/// `½·3·(√5 − 1)²`; force on a `k (l − r) d / r`; block `k [(l/r) n nᵀ + (1 − l/r) I]`
/// with `n nᵀ = d dᵀ/5`, and that block is `−∂f_a/∂x_a` by central differences.
#[test]
fn one_spring_by_hand() {
    let spring = nurbspring_msm::Spring {
        a: 1,
        b: 0,
        kind: SpringKind::Shear,
        k: 3.0,
        rest_length: 1.0,
        weight: 1.0,
        damping: 0.0,
    };
    let x = [-0.5, 1.0, 1.0, 0.5, 1.0, -1.0];
    let (d, r) = ([1.0, 0.0, -2.0], 5f64.sqrt());
    assert!((spring.length(&x) - r).abs() <= 2.0 * f64::EPSILON * r);
    let energy = 1.5 * (r - 1.0) * (r - 1.0);
    assert!((spring.energy(&x) - energy).abs() <= 8.0 * f64::EPSILON * energy);
    let f = spring.force_on_a(&x);
    for i in 0..3 {
        let by_hand = 3.0 * (1.0 - r) * d[i] / r;
        assert!((f[i] - by_hand).abs() <= 8.0 * f64::EPSILON, "{i}: {f:?}");
    }
    let block = spring.stiffness_block(&x);
    for i in 0..3 {
        for j in 0..3 {
            let identity = if i == j { 1.0 } else { 0.0 };
            let by_hand = 3.0 * (d[i] * d[j] / 5.0 / r + (1.0 - 1.0 / r) * identity);
            assert!(
                (block[i][j] - by_hand).abs() <= 8.0 * f64::EPSILON,
                "({i}, {j}): {} vs {by_hand}",
                block[i][j]
            );
            let h = FD_STEP;
            let (mut xp, mut xm) = (x, x);
            xp[3 + j] += h;
            xm[3 + j] -= h;
            let fd = -(spring.force_on_a(&xp)[i] - spring.force_on_a(&xm)[i]) / (2.0 * h);
            assert!(
                (fd - block[i][j]).abs() <= FD_RELATIVE * 3.0,
                "({i}, {j}): FD {fd}"
            );
        }
    }
}
