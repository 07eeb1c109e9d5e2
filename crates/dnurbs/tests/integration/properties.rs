//! Property tests (proptest) of the assembled matrices on random rational patches, and
//! finite-difference checks of the model's force against its energy.

use nurbspring_dnurbs::{
    Constraints, DnurbsModel, DnurbsOptions, Geometry, Loads, Material, assemble,
};
use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_linalg::SpdSolver;
use nurbspring_sim::DynamicModel;
use proptest::prelude::*;

use crate::support::{self, tol};

fn random_patch(p: usize, spans: usize, z: &[f64], w: &[f64]) -> NurbsSurface {
    let k = KnotVector::clamped_uniform(p, spans).unwrap();
    let g = k.greville();
    let n = g.len();
    let pts: Vec<[f64; 3]> = (0..n * n)
        .map(|i| [2.0 * g[i / n], 3.0 * g[i % n], z[i % z.len()]])
        .collect();
    let weights = (0..n * n).map(|i| w[i % w.len()]).collect();
    NurbsSurface::try_new(k.clone(), k, pts, weights).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn mass_spd_and_stiffness_annihilates_translations(
        p in 2usize..4,
        spans in 1usize..4,
        z in proptest::collection::vec(-1.0f64..1.0, 7),
        w in proptest::collection::vec(0.5f64..2.0, 5),
        coefs in proptest::collection::vec(0.0f64..2.0, 5),
        mu in 0.1f64..10.0,
    ) {
        let geometry = Geometry::Surface(random_patch(p, spans, &z, &w));
        let material = Material {
            mu,
            gamma: 0.0,
            alpha11: coefs[0],
            alpha22: coefs[1],
            beta11: coefs[2],
            beta12: coefs[3],
            beta22: coefs[4],
        };
        let m = assemble(&geometry, &material, &Loads::default(), &DnurbsOptions::default()).unwrap();
        prop_assert!(m.mass.symmetry_error() <= tol::SYMMETRY);
        prop_assert!(SpdSolver::new(&m.mass).is_ok());
        // Partition of unity: Σ M = 3 μ over the unit parameter square, also for rational bases.
        prop_assert!((m.mass.sum() - 3.0 * mu).abs() <= tol::SUM * 3.0 * mu * 10.0);
        prop_assert!(m.stiffness.symmetry_error() <= tol::SYMMETRY);
        let n = m.stiffness.nrows();
        for x in 0..3 {
            let t: Vec<f64> = (0..n).map(|d| if d % 3 == x { 1.0 } else { 0.0 }).collect();
            let mut kt = vec![0.0; n];
            m.stiffness.mul_vec(&t, &mut kt);
            let norm = kt.iter().map(|v| v * v).sum::<f64>().sqrt();
            prop_assert!(norm <= tol::TRANSLATION * m.stiffness.frobenius_norm().max(1e-300) * 10.0);
        }
        // PSD: xᵀ K x ≥ 0 on a few deterministic vectors.
        for s in 0..4 {
            let x: Vec<f64> = (0..n).map(|i| ((i * (7 + s) + 3 * s) % 11) as f64 - 5.0).collect();
            let q = m.stiffness.quadratic_form(&x);
            prop_assert!(q >= -tol::PSD * m.stiffness.frobenius_norm() * x.iter().map(|v| v * v).sum::<f64>());
        }
    }
}

/// `f_int = ∂E/∂q` by central differences (exact for the quadratic energy up to round-off).
#[test]
fn internal_force_is_the_gradient_of_the_energy() {
    let model = DnurbsModel::new(
        Geometry::Surface(support::wavy_rational_patch()),
        Material {
            mu: 1.0,
            alpha11: 0.5,
            alpha22: 0.7,
            beta11: 0.1,
            beta12: 0.05,
            beta22: 0.2,
            ..Material::default()
        },
        Loads::default(),
        &Constraints {
            fixed_rings: 1,
            ..Constraints::default()
        },
        DnurbsOptions {
            rest_shape: nurbspring_dnurbs::RestShape::Zero,
            ..DnurbsOptions::default()
        },
    )
    .unwrap();
    let n = model.n_dofs();
    let q: Vec<f64> = (0..n).map(|i| 0.3 * (i as f64).sin()).collect();
    let mut f = vec![0.0; n];
    model.internal_force(&q, &mut f);
    let h = 1e-4;
    let scale = f.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for i in 0..n {
        let mut qp = q.clone();
        let mut qm = q.clone();
        qp[i] += h;
        qm[i] -= h;
        let fd = (model.potential_energy(&qp) - model.potential_energy(&qm)) / (2.0 * h);
        assert!(
            (fd - f[i]).abs() <= tol::FINITE_DIFFERENCE * scale,
            "dof {i}: {fd} vs {}",
            f[i]
        );
    }
    let k = model.tangent_stiffness(&q);
    assert_eq!(&k, model.linear_stiffness().unwrap());
}
