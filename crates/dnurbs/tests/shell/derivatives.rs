//! Internal force = ∇E and tangent = ∂f/∂p by central differences at large deformations;
//! invariance under rigid motion (docs/math.md §10.3).

use nurbspring_dnurbs::ShellEnergy;

use crate::support::{self, max_abs, tol};

fn shell() -> (ShellEnergy, Vec<f64>) {
    let g = support::curved_patch();
    let e = ShellEnergy::new(&g, &support::material(), 5).unwrap();
    (e, g.coordinates(false))
}

#[test]
fn the_rest_shape_is_stress_free() {
    let (e, p0) = shell();
    assert!(e.energy(&p0).abs() < 1e-25);
    let mut f = vec![0.0; p0.len()];
    e.internal_force(&p0, &mut f);
    assert!(max_abs(&f) < 1e-12, "{}", max_abs(&f));
}

#[test]
fn the_force_is_the_gradient_of_the_energy_at_large_deformations() {
    let (e, p0) = shell();
    for seed in [1, 2, 3] {
        let p = support::perturbed(&p0, 0.15, seed);
        let mut f = vec![0.0; p.len()];
        e.internal_force(&p, &mut f);
        let h = 1e-5;
        let mut worst = 0.0_f64;
        for k in 0..p.len() {
            let (mut a, mut b) = (p.clone(), p.clone());
            a[k] += h;
            b[k] -= h;
            let fd = (e.energy(&a) - e.energy(&b)) / (2.0 * h);
            worst = worst.max((fd - f[k]).abs());
        }
        let rel = worst / max_abs(&f);
        eprintln!("force vs energy differences, seed {seed}: {rel:.2e}");
        assert!(rel < tol::FORCE_DIFFERENCE, "{rel:e}");
    }
}

#[test]
fn the_tangent_is_the_derivative_of_the_force_at_large_deformations() {
    let (e, p0) = shell();
    for seed in [4, 5] {
        let p = support::perturbed(&p0, 0.15, seed);
        let (f, k) = e.force_and_tangent(&p);
        let dense = k.to_dense();
        let h = 1e-6;
        let mut worst = 0.0_f64;
        let mut largest = 0.0_f64;
        for j in 0..p.len() {
            let (mut a, mut b) = (p.clone(), p.clone());
            a[j] += h;
            b[j] -= h;
            let (mut fa, mut fb) = (vec![0.0; p.len()], vec![0.0; p.len()]);
            e.internal_force(&a, &mut fa);
            e.internal_force(&b, &mut fb);
            for i in 0..p.len() {
                let fd = (fa[i] - fb[i]) / (2.0 * h);
                worst = worst.max((fd - dense[(i, j)]).abs());
                largest = largest.max(dense[(i, j)].abs());
            }
        }
        let rel = worst / largest;
        eprintln!("tangent vs force differences, seed {seed}: {rel:.2e}");
        assert!(rel < tol::TANGENT_DIFFERENCE, "{rel:e}");
        // The force of the one pass equals the force alone.
        let mut f2 = vec![0.0; p.len()];
        e.internal_force(&p, &mut f2);
        let d: Vec<f64> = f.iter().zip(&f2).map(|(a, b)| a - b).collect();
        assert!(max_abs(&d) <= 1e-14 * max_abs(&f));
        // Symmetry.
        let kt = k.transpose();
        let asym = nurbspring_linalg::SparseMatrix::linear_combination(1.0, &k, -1.0, &kt)
            .unwrap()
            .frobenius_norm()
            / k.frobenius_norm();
        assert!(asym < tol::SYMMETRY, "{asym:e}");
    }
}

#[test]
fn energy_and_force_are_invariant_under_rigid_motion() {
    let (e, p0) = shell();
    let p = support::perturbed(&p0, 0.1, 9);
    let energy = e.energy(&p);
    let mut f = vec![0.0; p.len()];
    e.internal_force(&p, &mut f);
    let fmax = max_abs(&f);
    let half_pi = std::f64::consts::FRAC_PI_2;
    let cases = [
        ([0.0, 0.0, 1.0], half_pi),
        ([1.0, 0.0, 0.0], half_pi),
        ([0.0, 1.0, 0.0], std::f64::consts::PI),
        ([0.3, -0.7, 0.5], 1.234),
        ([-0.9, 0.2, 0.4], 4.0),
    ];
    for (axis, angle) in cases {
        let r = support::rotation(axis, angle);
        let q = support::rotate(&r, &p, [3.0, -2.0, 0.5]);
        let eq = e.energy(&q);
        assert!(
            (eq - energy).abs() <= tol::ROTATION * energy,
            "{eq} vs {energy}"
        );
        let mut fq = vec![0.0; q.len()];
        e.internal_force(&q, &mut fq);
        let rf = support::rotate(&r, &f, [0.0; 3]);
        let d: Vec<f64> = fq.iter().zip(&rf).map(|(a, b)| a - b).collect();
        assert!(
            max_abs(&d) <= tol::ROTATION * fmax,
            "{:e}",
            max_abs(&d) / fmax
        );
        // The rest shape moved rigidly is stress-free.
        let q0 = support::rotate(&r, &p0, [1.0, 2.0, 3.0]);
        assert!(e.energy(&q0) <= 1e-24);
    }
}
