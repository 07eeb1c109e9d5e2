//! Hinges (docs/math.md §5.2), spring weights and axial damping (§5.1), and the triangulated
//! lattice (§5.3): energy, force and tangent against finite differences at random deformed
//! states, invariance under rigid motion, stress-free rest states, the unit matrices, the file.

mod support;

use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_linalg::SparseMatrix;
use nurbspring_msm::{
    Class, Constants, Hinge, HingeKind, LatticeOptions, MsmFile, MsmModel, ParameterGrid, Spring,
    SpringKind, SpringLattice,
};
use nurbspring_sim::{DynamicModel, IntegratorKind, RunOptions, Sample, simulate};
use support::tolerances::*;
use support::{Lcg, curved_surface, relative_error};

/// Central differences of a hinge's energy and force with step `FD_STEP`: truncation
/// `h² |∇³E| / 6` grows as the wings' heights shrink (`∂θ/∂x ~ 1/h`), round-off `ε |E| / h`;
/// measured up to 1.2e-9 (gradient) and 5e-10 (Hessian, relative over the 12 × 12 block) on
/// the 39 random hinges below and 2e-10 on a lattice, so 4e-9 fails a wrong term of relative
/// size 1e-8.
const FD_HINGE: f64 = 4e-9;
/// Invariance under a rigid motion: the rotated coordinates carry a round-off of a few ε of
/// their size into atan2 and the cross products (measured ≤ 2e-15 relative).
const RIGID: f64 = 1e-13;

fn rotation(seed: u64) -> [[f64; 3]; 3] {
    let mut r = Lcg(seed);
    let axis = [r.next(), r.next(), r.next()];
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let k = axis.map(|a| a / n);
    let t = 3.0 * r.next();
    let (s, c) = t.sin_cos();
    // Rodrigues.
    let mut m = [[0.0; 3]; 3];
    let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    for i in 0..3 {
        for j in 0..3 {
            let kk: f64 = (0..3).map(|l| kx[i][l] * kx[l][j]).sum();
            m[i][j] = if i == j { 1.0 } else { 0.0 } + s * kx[i][j] + (1.0 - c) * kk;
        }
    }
    m
}

fn rotate(r: &[[f64; 3]; 3], x: &[f64], shift: [f64; 3]) -> Vec<f64> {
    x.chunks(3)
        .flat_map(|p| {
            (0..3).map(move |i| r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2] + shift[i])
        })
        .collect()
}

/// A hinge on random points: an edge near (0,0,0)–(1,0,0), wings on either side, folded and
/// twisted; a rest angle away from the current one.
fn random_hinge(seed: u64) -> (Hinge, Vec<f64>) {
    let mut r = Lcg(seed);
    let x = vec![
        0.1 * r.next(),
        0.1 * r.next(),
        0.1 * r.next(),
        1.0 + 0.2 * r.next(),
        0.1 * r.next(),
        0.1 * r.next(),
        0.5 + 0.4 * r.next(),
        0.8 + 0.3 * r.next(),
        0.6 * r.next(),
        0.5 + 0.4 * r.next(),
        -0.7 + 0.3 * r.next(),
        0.6 * r.next(),
    ];
    let hinge = Hinge {
        nodes: [0, 1, 2, 3],
        kind: HingeKind::Grid,
        k: 1.0 + r.next().abs(),
        weight: 0.5 + r.next().abs(),
        rest_angle: 0.8 * r.next(),
    };
    (hinge, x)
}

fn flat(blocks: &[[[[f64; 3]; 3]; 4]; 4]) -> Vec<Vec<f64>> {
    let mut k = vec![vec![0.0; 12]; 12];
    for i in 0..4 {
        for j in 0..4 {
            for r in 0..3 {
                for c in 0..3 {
                    k[3 * i + r][3 * j + c] = blocks[i][j][r][c];
                }
            }
        }
    }
    k
}

fn forces_flat(h: &Hinge, x: &[f64]) -> Vec<f64> {
    h.forces(x).iter().flatten().copied().collect()
}

#[test]
fn hinge_force_and_tangent_match_finite_differences() {
    let (mut worst_f, mut worst_k, mut worst_gn) = (0.0f64, 0.0f64, 0.0f64);
    for seed in 1..40 {
        let (h, x) = random_hinge(seed);
        let step = FD_STEP;
        let f = forces_flat(&h, &x);
        let grad: Vec<f64> = (0..12)
            .map(|j| {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[j] += step;
                xm[j] -= step;
                -(h.energy(&xp) - h.energy(&xm)) / (2.0 * step)
            })
            .collect();
        worst_f = worst_f.max(relative_error(&f, &grad));
        let k = flat(&h.stiffness_blocks(&x, false));
        let (mut num, mut den) = (0.0, 0.0);
        for j in 0..12 {
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[j] += step;
            xm[j] -= step;
            let (fp, fm) = (forces_flat(&h, &xp), forces_flat(&h, &xm));
            for i in 0..12 {
                let fd = -(fp[i] - fm[i]) / (2.0 * step);
                num += (fd - k[i][j]).powi(2);
                den += k[i][j].powi(2);
            }
        }
        worst_k = worst_k.max((num / den).sqrt());
        // The Gauss–Newton part is k w ∇θ∇θᵀ exactly: K − K_GN = k w (θ − θ0) ∇²θ.
        let gn = flat(&h.stiffness_blocks(&x, true));
        let d = h.angle(&x) - h.rest_angle;
        let exact_gn = flat(
            &Hinge {
                rest_angle: h.angle(&x),
                ..h
            }
            .stiffness_blocks(&x, false),
        );
        let (mut e, mut s) = (0.0, 0.0);
        for i in 0..12 {
            for j in 0..12 {
                e += (gn[i][j] - exact_gn[i][j]).powi(2);
                s += gn[i][j].powi(2);
            }
        }
        worst_gn = worst_gn.max((e / s).sqrt());
        assert!(d.abs() > 1e-3, "seed {seed}: the state must be loaded");
    }
    eprintln!(
        "hinge: ‖f + ∇E‖/‖∇E‖ ≤ {worst_f:e}, ‖K_fd − K‖/‖K‖ ≤ {worst_k:e}, Gauss–Newton at θ = θ0: {worst_gn:e}"
    );
    assert!(worst_f < FD_HINGE, "{worst_f:e}");
    assert!(worst_k < FD_HINGE, "{worst_k:e}");
    assert!(worst_gn < 1e-15, "{worst_gn:e}");
}

#[test]
fn hinge_tangent_is_symmetric_and_annihilates_rigid_motions() {
    for seed in 1..20 {
        let (h, x) = random_hinge(seed);
        let k = flat(&h.stiffness_blocks(&x, false));
        let scale: f64 = k.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
        for i in 0..12 {
            for j in 0..12 {
                assert_eq!(k[i][j], k[j][i], "seed {seed}: ({i}, {j})");
            }
        }
        // Translations and infinitesimal rotations ω × x are in the kernel of a tangent at
        // rest (θ = θ0), and the force is orthogonal to them at any state.
        let f = forces_flat(&h, &x);
        let at_rest = flat(
            &Hinge {
                rest_angle: h.angle(&x),
                ..h
            }
            .stiffness_blocks(&x, false),
        );
        for m in 0..6 {
            let u: Vec<f64> = (0..4)
                .flat_map(|a| {
                    let p = [x[3 * a], x[3 * a + 1], x[3 * a + 2]];
                    let mut v = [0.0; 3];
                    if m < 3 {
                        v[m] = 1.0;
                    } else {
                        let mut w = [0.0; 3];
                        w[m - 3] = 1.0;
                        v = [
                            w[1] * p[2] - w[2] * p[1],
                            w[2] * p[0] - w[0] * p[2],
                            w[0] * p[1] - w[1] * p[0],
                        ];
                    }
                    v
                })
                .collect();
            let fu: f64 = f.iter().zip(&u).map(|(a, b)| a * b).sum();
            let fnorm: f64 = f.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!(
                fu.abs() < 1e-14 * fnorm,
                "seed {seed}, motion {m}: f·u = {fu:e}"
            );
            let ku: f64 = (0..12)
                .map(|i| (0..12).map(|j| at_rest[i][j] * u[j]).sum::<f64>().powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(
                ku < 1e-13 * scale,
                "seed {seed}, motion {m}: |K u| = {ku:e}"
            );
        }
    }
}

/// `E(Rx + c) = E(x)`, `f(Rx + c) = R f(x)`, `K(Rx + c) = R K(x) Rᵀ` for hinges and springs.
#[test]
fn hinges_and_springs_are_invariant_under_rigid_motion() {
    let mut worst = 0.0f64;
    for seed in 1..30 {
        let (h, x) = random_hinge(seed);
        let s = Spring {
            damping: 0.0,
            weight: 1.7,
            ..Spring::new(2, 3, SpringKind::Shear, 2.0, 1.1)
        };
        let r = rotation(seed + 100);
        let shift = [3.0, -1.0, 0.5];
        let y = rotate(&r, &x, shift);
        let e = (h.energy(&y) - h.energy(&x)).abs() / h.energy(&x);
        let es = (s.energy(&y) - s.energy(&x)).abs() / s.energy(&x);
        let fx = forces_flat(&h, &x);
        let fy = forces_flat(&h, &y);
        let rf = rotate(&r, &fx, [0.0; 3]);
        let ef = relative_error(&fy, &rf);
        let sx = s.force_on_a(&x);
        let sy = s.force_on_a(&y);
        let rs = rotate(&r, &sx, [0.0; 3]);
        let esf = relative_error(&sy, &rs);
        // K(y) = R K(x) Rᵀ, block by block.
        let (kx, ky) = (h.stiffness_blocks(&x, false), h.stiffness_blocks(&y, false));
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..4 {
            for j in 0..4 {
                for a in 0..3 {
                    for b in 0..3 {
                        let mut rkr = 0.0;
                        for p in 0..3 {
                            for q in 0..3 {
                                rkr += r[a][p] * kx[i][j][p][q] * r[b][q];
                            }
                        }
                        num += (ky[i][j][a][b] - rkr).powi(2);
                        den += rkr * rkr;
                    }
                }
            }
        }
        let ek = (num / den).sqrt();
        worst = worst.max(e).max(es).max(ef).max(esf).max(ek);
    }
    eprintln!("rigid motion: largest relative change {worst:e}");
    assert!(worst < RIGID, "{worst:e}");
}

/// Axial damping `−c ((v_a − v_b)·n) n`: its matrix is the force's derivative in v, it pushes
/// nothing under a rigid motion, and it rotates with the body.
#[test]
fn axial_damping_is_along_the_current_direction() {
    let lattice = damped_sheet(0.3);
    let model = MsmModel::new(lattice).unwrap();
    let c = model.configuration_damping().expect("damped springs");
    let n = model.n_dofs();
    let mut r = Lcg(7);
    let mut q = model.initial_positions().to_vec();
    r.perturb(&mut q, 0.05);
    let v: Vec<f64> = (0..n).map(|_| r.next()).collect();
    let mut f = vec![0.0; n];
    c.add_damping_force(&q, &v, &mut f);
    let mut cv = vec![0.0; n];
    c.damping_matrix(&q).mul_vec(&v, &mut cv);
    let e = relative_error(&cv, &f);
    eprintln!("axial damping: ‖C(q) v − f_d‖/‖f_d‖ = {e:e}");
    assert!(e < 1e-14, "{e:e}");
    // A free lattice (no fixed node) in rigid rotation ω × x: no damping force.
    let free = MsmModel::new(damped_sheet_free()).unwrap();
    let q = free.initial_positions().to_vec();
    let w = [0.3, -0.2, 0.9];
    let v: Vec<f64> = q
        .chunks(3)
        .flat_map(|p| {
            [
                w[1] * p[2] - w[2] * p[1] + 0.1,
                w[2] * p[0] - w[0] * p[2],
                w[0] * p[1] - w[1] * p[0],
            ]
        })
        .collect();
    let mut f = vec![0.0; q.len()];
    free.configuration_damping()
        .unwrap()
        .add_damping_force(&q, &v, &mut f);
    let fmax = f.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    eprintln!("axial damping under rigid motion: |f| ≤ {fmax:e}");
    assert!(fmax < 1e-14, "{fmax:e}");
}

/// A sheet on the curved patch: triangulated, every class, axial damping `c`, two fixed
/// corners.
fn damped_sheet(c: f64) -> SpringLattice {
    let mut l = sheet(7, 6, &[0, 5]);
    l.set_axial_damping(None, c);
    l
}

fn damped_sheet_free() -> SpringLattice {
    let mut l = sheet(5, 4, &[]);
    l.set_axial_damping(Some(SpringKind::Structural), 0.4);
    l
}

fn all_classes() -> Constants {
    Constants::from_pairs([
        (Class::Spring(SpringKind::Structural), 30.0),
        (Class::Spring(SpringKind::Shear), 10.0),
        (Class::Hinge(HingeKind::Grid), 0.5),
        (Class::Hinge(HingeKind::Diagonal), 0.3),
    ])
}

/// A triangulated lattice on the curved patch with fixed nodes.
fn sheet(n_u: usize, n_v: usize, fixed: &[usize]) -> SpringLattice {
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: n_u,
            nodes_v: n_v,
        },
        constants: all_classes(),
        fixed: nurbspring_msm::FixedNodes::List(fixed.to_vec()),
        ..Default::default()
    };
    SpringLattice::triangulated(&curved_surface(), &options, &[]).unwrap()
}

#[test]
fn the_triangulated_lattice_has_alternating_diagonals_and_a_hinge_on_every_interior_edge() {
    let l = sheet(5, 4, &[]);
    let (n_u, n_v) = (5, 4);
    let cells = (n_u - 1) * (n_v - 1);
    assert_eq!(l.triangles.len(), 2 * cells);
    let count = |k| l.springs.iter().filter(|s| s.kind == k).count();
    assert_eq!(
        count(SpringKind::Structural),
        n_u * (n_v - 1) + (n_u - 1) * n_v
    );
    assert_eq!(count(SpringKind::Shear), cells);
    // Interior grid-line edges: all grid edges minus the boundary ones; every diagonal.
    let boundary = 2 * (n_u - 1) + 2 * (n_v - 1);
    let grid_edges = n_u * (n_v - 1) + (n_u - 1) * n_v;
    assert_eq!(
        l.count(Class::Hinge(HingeKind::Grid)),
        grid_edges - boundary
    );
    assert_eq!(l.count(Class::Hinge(HingeKind::Diagonal)), cells);
    // Checkerboard: as many diagonals of each direction (± 1).
    let rising = l
        .springs
        .iter()
        .filter(|s| s.kind == SpringKind::Shear && s.b == s.a + n_v + 1)
        .count();
    assert!(
        (2 * rising as i64 - cells as i64).abs() <= 1,
        "{rising} of {cells}"
    );
    // Every hinge's two triangles are triangles of the mesh, oriented alike.
    let has = |t: [usize; 3]| {
        l.triangles
            .iter()
            .any(|u| (0..3).any(|r| [u[r], u[(r + 1) % 3], u[(r + 2) % 3]] == t))
    };
    for h in &l.hinges {
        let [x0, x1, x2, x3] = h.nodes;
        assert!(has([x0, x1, x2]) && has([x1, x0, x3]), "{h:?}");
    }
    // Stress-free at rest on the curved surface: rest angles from the positions.
    let x = l.flat_positions();
    let mut f = vec![0.0; x.len()];
    l.elastic_forces(&x, &mut f);
    assert!(f.iter().all(|v| v.abs() < 1e-13), "{f:?}");
    assert!(l.hinges.iter().any(|h| h.rest_angle.abs() > 0.05));
}

/// Force = −∇E and K_T = −∂f/∂x on a whole triangulated lattice (springs, hinges, weights),
/// through the lattice and through the model on the free nodes.
#[test]
fn the_triangulated_lattice_matches_finite_differences() {
    let mut l = sheet(5, 4, &[0, 3]);
    let mut r = Lcg(11);
    let w: Vec<f64> = (0..l.count(Class::Hinge(HingeKind::Grid)))
        .map(|_| 1.0 + 0.5 * r.next())
        .collect();
    l.set_weights(Class::Hinge(HingeKind::Grid), &w).unwrap();
    let ws: Vec<f64> = (0..l.count(Class::Spring(SpringKind::Shear)))
        .map(|_| 1.0 + 0.5 * r.next())
        .collect();
    l.set_weights(Class::Spring(SpringKind::Shear), &ws)
        .unwrap();
    let model = MsmModel::new(l.clone()).unwrap();
    let mut q = model.initial_positions().to_vec();
    r.perturb(&mut q, 0.08);
    let n = q.len();
    let force = |q: &[f64]| {
        let mut f = vec![0.0; n];
        model.internal_force(q, &mut f);
        f
    };
    let h = FD_STEP;
    let f = force(&q);
    let grad: Vec<f64> = (0..n)
        .map(|j| {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[j] += h;
            qm[j] -= h;
            (model.potential_energy(&qp) - model.potential_energy(&qm)) / (2.0 * h)
        })
        .collect();
    let ef = relative_error(&f, &grad);
    let k = model.tangent_stiffness(&q).to_dense();
    let (mut num, mut den) = (0.0, 0.0);
    for j in 0..n {
        let (mut qp, mut qm) = (q.clone(), q.clone());
        qp[j] += h;
        qm[j] -= h;
        let (fp, fm) = (force(&qp), force(&qm));
        for i in 0..n {
            let fd = (fp[i] - fm[i]) / (2.0 * h);
            num += (fd - k[(i, j)]).powi(2);
            den += k[(i, j)].powi(2);
        }
    }
    let ek = (num / den).sqrt();
    eprintln!("triangulated lattice: ‖f_int − ∇E‖/‖∇E‖ = {ef:e}, ‖K_fd − K_T‖/‖K_T‖ = {ek:e}");
    assert!(ef < FD_HINGE, "{ef:e}");
    assert!(ek < FD_HINGE, "{ek:e}");
    // The model's force and tangent are the lattice's on the free nodes.
    let x = model.full_positions(&q);
    let mut fl = vec![0.0; x.len()];
    l.elastic_forces(&x, &mut fl);
    let fl_free: Vec<f64> = model.dof_map().restrict(&fl).iter().map(|v| -v).collect();
    assert!(relative_error(&f, &fl_free) < 1e-14);
    let kl = l.tangent_stiffness(&x);
    let free: Vec<usize> = model
        .free_nodes()
        .iter()
        .flat_map(|&a| [3 * a, 3 * a + 1, 3 * a + 2])
        .collect();
    let kl_free = kl.submatrix(&free, &free).to_dense();
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            num += (kl_free[(i, j)] - k[(i, j)]).powi(2);
            den += k[(i, j)].powi(2);
        }
    }
    assert!((num / den).sqrt() < 1e-14);
    // The projected tangent is positive semi-definite and equals K_T at rest.
    let q0 = model.initial_positions();
    let kp = model.projected_tangent_stiffness(q0).unwrap();
    let kt = model.tangent_stiffness(q0);
    assert!(matrix_relative_error(&kp, &kt) < 1e-14);
}

fn matrix_relative_error(a: &SparseMatrix, b: &SparseMatrix) -> f64 {
    let d = SparseMatrix::linear_combination(1.0, a, -1.0, b).unwrap();
    let norm = |m: &SparseMatrix| m.values().iter().map(|v| v * v).sum::<f64>().sqrt();
    norm(&d) / norm(b)
}

/// `K_T = Σ_c k_c G_c` with weights inside `G_c`, at rest and deformed, for the lattice and the
/// model; at rest a hinge's `G` is `w ∇θ∇θᵀ`.
#[test]
fn the_tangent_is_the_sum_of_unit_matrices_with_weights() {
    let mut l = sheet(6, 5, &[0, 1, 2]);
    let mut r = Lcg(3);
    for class in l.classes() {
        let w: Vec<f64> = (0..l.count(class)).map(|_| 1.0 + 0.7 * r.next()).collect();
        l.set_weights(class, &w).unwrap();
    }
    let constants = l.constants();
    let model = MsmModel::new(l.clone()).unwrap();
    let mut q = model.initial_positions().to_vec();
    for amplitude in [0.0, 0.05] {
        r.perturb(&mut q, amplitude);
        let kt = model.tangent_stiffness(&q);
        let mut sum: Option<SparseMatrix> = None;
        for (class, k) in constants.iter() {
            let g = model.unit_stiffness(class, &q);
            sum = Some(match sum {
                None => SparseMatrix::linear_combination(k, &g, 0.0, &g).unwrap(),
                Some(s) => SparseMatrix::linear_combination(1.0, &s, k, &g).unwrap(),
            });
        }
        let e = matrix_relative_error(&sum.unwrap(), &kt);
        eprintln!("amplitude {amplitude}: ‖Σ k_c G_c − K_T‖/‖K_T‖ = {e:e}");
        assert!(e < 1e-13, "{e:e}");
        let x = model.full_positions(&q);
        let lt = l.tangent_stiffness(&x);
        let mut lsum = SparseMatrix::linear_combination(0.0, &lt, 0.0, &lt).unwrap();
        for (class, k) in constants.iter() {
            lsum = SparseMatrix::linear_combination(1.0, &lsum, k, &l.unit_stiffness(class, &x))
                .unwrap();
        }
        assert!(matrix_relative_error(&lsum, &lt) < 1e-13);
    }
    assert!(
        l.set_weights(Class::Hinge(HingeKind::Grid), &[1.0])
            .is_err()
    );
}

/// The same forces and energy on one thread and on several (a lattice with more hinges than
/// the serial threshold).
#[test]
fn hinge_forces_do_not_depend_on_the_threads() {
    let l = sheet(80, 70, &[0]);
    let model = MsmModel::new(l).unwrap();
    let mut q = model.initial_positions().to_vec();
    Lcg(5).perturb(&mut q, 0.01);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut f = vec![0.0; q.len()];
            model.internal_force(&q, &mut f);
            (f, model.potential_energy(&q), model.tangent_stiffness(&q))
        })
    };
    let (f1, e1, k1) = run(1);
    let (f4, e4, k4) = run(4);
    assert_eq!(f1, f4);
    assert_eq!(e1, e4);
    assert_eq!(k1.values(), k4.values());
    // The force kernel works in chunks of 2048 nodes, each adding the hinges with a node in it:
    // at the nodes on either side of a chunk boundary the force is still the energy's gradient
    // (central differences).
    let scale = f1.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    for node in [2046, 2047, 2048, 2049, 4095, 4096] {
        for c in 0..3 {
            let i = 3 * node + c;
            let h = 1e-6;
            let mut qp = q.clone();
            qp[i] += h;
            let mut qm = q.clone();
            qm[i] -= h;
            let fd = (model.potential_energy(&qp) - model.potential_energy(&qm)) / (2.0 * h);
            assert!(
                (fd - f1[i]).abs() <= 1e-6 * scale,
                "dof {i}: {fd} vs {}",
                f1[i]
            );
        }
    }
}

/// msm.json carries hinges, weights, axial damping and triangles; a file without them loads
/// as before.
#[test]
fn the_file_carries_hinges_weights_and_damping() {
    let mut l = damped_sheet(0.2);
    let n = l.count(Class::Spring(SpringKind::Structural));
    l.set_weights(
        Class::Spring(SpringKind::Structural),
        &(0..n).map(|i| 1.0 + 0.01 * i as f64).collect::<Vec<_>>(),
    )
    .unwrap();
    let text = l.to_json_string();
    let back = SpringLattice::from_json_str(&text).unwrap();
    assert_eq!(back, l);
    // Hand-written: a hinge without rest angle or weight takes the angle at the positions.
    let text = r#"{"nodes": [{"position": [0, 0, 0], "mass": 1}, {"position": [1, 0, 0], "mass": 1},
        {"position": [0.5, 1, 0], "mass": 1}, {"position": [0.5, -0.5, 0.5], "mass": 1}],
        "springs": [{"a": 0, "b": 1, "k": 2}],
        "hinges": [{"nodes": [0, 1, 2, 3], "k": 3}]}"#;
    let l = SpringLattice::from_json_str(text).unwrap();
    assert_eq!(l.hinges.len(), 1);
    let h = l.hinges[0];
    assert_eq!((h.kind, h.weight, h.k), (HingeKind::Grid, 1.0, 3.0));
    assert!((h.rest_angle - h.angle(&l.flat_positions())).abs() < 1e-15);
    assert_eq!((l.springs[0].weight, l.springs[0].damping), (1.0, 0.0));
    // Bad values name the hinge and the value.
    let bad = text.replace(r#""k": 3}"#, r#""k": 3, "weight": -1}"#);
    let e = SpringLattice::from_json_str(&bad).unwrap_err().to_string();
    assert!(
        e.contains("hinge 0") && e.contains("weight") && e.contains("-1"),
        "{e}"
    );
    let bad = text.replace("[0, 1, 2, 3]", "[0, 1, 2, 9]");
    let e = SpringLattice::from_json_str(&bad).unwrap_err().to_string();
    assert!(e.contains("hinge 0") && e.contains("node 9"), "{e}");
    let bad = text.replace(r#""k": 2}"#, r#""k": 2, "damping": -0.5}"#);
    let e = SpringLattice::from_json_str(&bad).unwrap_err().to_string();
    assert!(
        e.contains("axial damping of spring 0") && e.contains("-0.5"),
        "{e}"
    );
    let file = MsmFile::from_json_str(text).unwrap();
    assert!(file.triangles.is_empty());
}

/// Every integrator runs the damped hinge sheet released under gravity: the damping takes
/// energy out (the total, kinetic + elastic + gravity's, ends below its start of 0), and the
/// explicit and implicit schemes agree at small Δt.
#[test]
fn integrators_run_hinges_and_axial_damping() {
    let mut l = damped_sheet(0.05);
    l.gravity = [0.0, 0.0, -1.0];
    l.set_mass(0.02);
    let model = MsmModel::new(l).unwrap();
    let limit = model.stability().unwrap();
    let dt = 0.2 * limit.dt_critical;
    let mut finals = Vec::new();
    for integrator in [
        IntegratorKind::SymplecticEuler,
        IntegratorKind::VelocityVerlet,
        IntegratorKind::Rk4,
        IntegratorKind::Newmark,
        IntegratorKind::BackwardEuler,
    ] {
        let opts = RunOptions::new(dt, 400.0 * dt, integrator);
        let mut energy = Vec::new();
        let mut last = Vec::new();
        let mut observer = |s: &Sample<'_>| {
            energy.push(s.kinetic + s.potential);
            last = s.q.to_vec();
        };
        simulate(&model, model.initial_state(&[]), &opts, &mut observer).unwrap();
        let scale = energy.iter().fold(0.0f64, |m, e| m.max(e.abs()));
        let end = *energy.last().unwrap();
        eprintln!(
            "{integrator}: total energy {end:.3e} at the end (start 0, largest |E| {scale:.2e})"
        );
        assert!(end < -0.01 * scale, "{integrator}: {end:e}");
        finals.push((integrator, last));
    }
    // The five agree to their accuracy at this Δt (first-order schemes at 0.2 Δt_crit).
    let reference = finals[2].1.clone();
    let q0 = model.initial_positions();
    let motion: Vec<f64> = reference.iter().zip(q0).map(|(a, b)| a - b).collect();
    for (integrator, q) in &finals {
        let d: Vec<f64> = q.iter().zip(&reference).map(|(a, b)| a - b).collect();
        let e = d.iter().map(|v| v * v).sum::<f64>().sqrt()
            / motion.iter().map(|v| v * v).sum::<f64>().sqrt();
        eprintln!("{integrator}: ‖q − q_rk4‖/‖q_rk4 − q0‖ = {e:.2e}");
        assert!(e < 0.05, "{integrator}: {e:e}");
    }
}

/// The paper's surface, flat: a triangulated lattice is flat at rest and has zero hinge
/// stiffness in-plane but out-of-plane stiffness from the hinges (which springs alone lack).
#[test]
fn hinges_give_a_flat_lattice_out_of_plane_stiffness() {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let s = NurbsSurface::try_new(
        k.clone(),
        k,
        vec![[0., 0., 0.], [0., 1., 0.], [1., 0., 0.], [1., 1., 0.]],
        vec![1.; 4],
    )
    .unwrap();
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: 4,
            nodes_v: 4,
        },
        constants: all_classes(),
        ..Default::default()
    };
    let l = SpringLattice::triangulated(&s, &options, &[]).unwrap();
    let x = l.flat_positions();
    let g = l
        .unit_stiffness(Class::Hinge(HingeKind::Grid), &x)
        .to_dense();
    let springs = l
        .unit_stiffness(Class::Spring(SpringKind::Structural), &x)
        .to_dense();
    for a in 0..16 {
        for b in 0..16 {
            // Springs: nothing out of plane; hinges: nothing in plane.
            assert_eq!(springs[(3 * a + 2, 3 * b + 2)], 0.0);
            for c in 0..2 {
                assert!(g[(3 * a + c, 3 * b + c)].abs() < 1e-12);
            }
        }
    }
    assert!(g[(3 * 5 + 2, 3 * 5 + 2)] > 1.0);
}
