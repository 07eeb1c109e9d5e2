//! Shared test support: the one place for tolerances, and small builders.
#![allow(dead_code)]

use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_msm::{Class, Constants, LatticeOptions, ParameterGrid, SpringKind, SpringLattice};

/// Tolerances, each relative to the real error of the method it checks.
pub mod tolerances {
    /// Central differences of the energy or the force with step `FD_STEP` on O(1) positions:
    /// truncation ≈ h² |E'''| / 6 ≈ 1e-11, round-off ≈ ε |E| / h ≈ 1e-11 (relative to the
    /// largest component): 1e-9 leaves a factor 10 over the 1e-10 measured, and a wrong
    /// derivative term of relative size 1e-8 or more fails.
    pub const FD_RELATIVE: f64 = 1e-9;
    /// Finite-difference step.
    pub const FD_STEP: f64 = 1e-5;
    /// Symmetry error ‖K − Kᵀ‖_F / ‖K‖_F of the analytic tangent: every block is symmetric by
    /// construction and placed symmetrically, so round-off only.
    pub const SYMMETRY: f64 = 1e-14;
    /// `K_T = Σ k_c G_c`: the same products summed in another order, round-off only.
    pub const UNIT_SUM: f64 = 1e-14;
    /// Spring-chain frequencies from a dense generalized eigensolver: a few ulps of ω_max
    /// relative to the smallest ω.
    pub const CHAIN_FREQUENCY: f64 = 1e-12;
    /// Sum of forces (momentum balance): per-node sums of exactly antisymmetric pairs.
    pub const FORCE_SUM: f64 = 1e-13;
    /// Momentum drift of a free lattice over a run, relative to Σ m |v|.
    pub const MOMENTUM: f64 = 1e-12;
    /// JSON round trip of f64 (serde_json's default float parser is correct to within one ulp).
    pub const JSON_ROUND_TRIP: f64 = 4.0 * f64::EPSILON;
    /// Positions sampled from a surface that is an exact affine map (Greville net).
    pub const AFFINE_SURFACE: f64 = 1e-14;
}

/// The paper's knot vectors (docs/math.md §7).
pub fn paper_knots() -> (KnotVector, KnotVector) {
    (
        KnotVector::try_new(vec![0., 0., 0., 0., 0.25, 0.5, 0.75, 1., 1., 1., 1.], 3).unwrap(),
        KnotVector::try_new(vec![0., 0., 0., 0., 0.5, 1., 1., 1., 1.], 3).unwrap(),
    )
}

/// The paper's surface: control net as printed, or the Greville reading (docs/math.md §7).
pub fn paper_surface(greville: bool) -> NurbsSurface {
    let (ku, kv) = paper_knots();
    let (px, py): (Vec<f64>, Vec<f64>) = if greville {
        (
            ku.greville().iter().map(|g| 3.0 * g).collect(),
            kv.greville().iter().map(|g| 5.0 * g).collect(),
        )
    } else {
        (
            vec![0., 0.25, 0.75, 1.52, 2.5, 2.75, 3.],
            vec![0., 0.83, 2.5, 4.16, 5.],
        )
    };
    let pts: Vec<[f64; 3]> = px
        .iter()
        .flat_map(|&x| py.iter().map(move |&y| [x, y, 2.0]))
        .collect();
    NurbsSurface::try_new(ku, kv, pts, vec![1.0; 35]).unwrap()
}

/// The paper's fixed control points: the two outer rings of the 7 × 5 net (32 of 35).
pub fn paper_fixed_points() -> Vec<usize> {
    (0..35).filter(|&k| !matches!(k, 12 | 17 | 22)).collect()
}

/// A curved biquadratic rational patch over [0, 2] × [0, 1.5] with a bump.
pub fn curved_surface() -> NurbsSurface {
    let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
    let mut pts = Vec::new();
    let mut w = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            let z = if i == 1 && j == 1 {
                0.6
            } else {
                0.1 * (i + j) as f64
            };
            pts.push([i as f64, 0.75 * j as f64, z]);
            w.push(if i == 1 { 1.3 } else { 1.0 });
        }
    }
    NurbsSurface::try_new(k.clone(), k, pts, w).unwrap()
}

/// A lattice on `curved_surface`, `n_u × n_v` uniform nodes, every kind of spring with
/// different constants, the given pre-strain, no fixed nodes.
pub fn curved_lattice(n_u: usize, n_v: usize, pre_strain: f64) -> SpringLattice {
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: n_u,
            nodes_v: n_v,
        },
        constants: Constants::from_pairs([
            (Class::Spring(SpringKind::Structural), 3.0),
            (Class::Spring(SpringKind::Shear), 1.5),
            (Class::Spring(SpringKind::Bend), 0.7),
        ]),
        pre_strain,
        ..Default::default()
    };
    SpringLattice::from_surface(&curved_surface(), &options, &[]).unwrap()
}

/// A small deterministic generator (64-bit LCG), values in [−1, 1).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    pub fn perturb(&mut self, x: &mut [f64], amplitude: f64) {
        for v in x {
            *v += amplitude * self.next();
        }
    }
}

/// ‖a − b‖₂ / ‖b‖₂.
pub fn relative_error(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt();
    let den: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    num / den
}
