//! The scalar structure of a constant-weight D-NURBS (docs/math.md §3): `M = S_M ⊗ I₃`,
//! `K = S_K ⊗ I₃`, so its motion is three copies of one scalar system on the free control
//! points, one per coordinate. The linear derivations (modal, excitation, reduction) work on
//! this scalar system.

use nurbspring_dnurbs::DnurbsModel;
use nurbspring_linalg::SparseMatrix;
use nurbspring_sim::{DynamicModel, PointDofs, State};

use crate::error::{DeriveError, ScalarObstacle};

/// A linear scalar system, one copy per coordinate: `M ü + c M u̇ + K u = f` for the
/// displacements `u` of its unknowns (the free control points of a D-NURBS, or the free nodes
/// of a linear node model), with its initial state and constant load.
#[derive(Clone, Debug)]
pub struct ScalarSystem {
    /// The unknowns: free control points or free nodes, ascending.
    pub free: Vec<usize>,
    /// `M` (`S_M` of a D-NURBS).
    pub mass: SparseMatrix,
    /// `K` (`S_K` of a D-NURBS).
    pub stiffness: SparseMatrix,
    /// `c`: the damping is this multiple of the mass (`γ/μ` of a D-NURBS).
    pub damping_ratio: f64,
    /// The constant load per unknown (`f_ext − f_int(q(0))` of a D-NURBS).
    pub load: Vec<[f64; 3]>,
    /// Initial displacement from the rest state per unknown.
    pub displacement: Vec<[f64; 3]>,
    /// Initial velocity per unknown.
    pub velocity: Vec<[f64; 3]>,
    /// What its energies are measured from: those of the model it stands for.
    pub energy: EnergyOrigin,
}

/// The energies of a scalar system as the model it stands for counts them (energy.csv's
/// `kinetic, elastic, external` convention, docs/scenes.md): at displacement `u` the elastic
/// energy is `elastic + Σ internal · u + ½ uᵀ K u` and the load potential `external −
/// Σ force · u`, with `load = force − internal` (so the total is conserved without damping).
#[derive(Clone, Debug, PartialEq)]
pub struct EnergyOrigin {
    /// The elastic energy at `u = 0`.
    pub elastic: f64,
    /// The internal force at `u = 0` per unknown (the gradient of the elastic energy there).
    pub internal: Vec<[f64; 3]>,
    /// The load potential at `u = 0`.
    pub external: f64,
    /// The external force per unknown.
    pub force: Vec<[f64; 3]>,
}

impl EnergyOrigin {
    /// A system at rest at `u = 0` under `load`, its load potential `−(u − u0) · load` zero at
    /// the initial displacement `u0` (an MSM's convention).
    pub fn of_load(load: &[[f64; 3]], u0: &[[f64; 3]]) -> Self {
        Self {
            elastic: 0.0,
            internal: vec![[0.0; 3]; load.len()],
            external: dot(load, u0),
            force: load.to_vec(),
        }
    }
}

/// `Σ_a Σ_x a[a][x] b[a][x]`.
pub(crate) fn dot(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x[0] * y[0] + x[1] * y[1] + x[2] * y[2])
        .sum()
}

/// Rows `3a + x` of an interleaved vector as points.
pub(crate) fn points(v: &[f64]) -> Vec<[f64; 3]> {
    v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

impl ScalarSystem {
    /// The scalar system of the D-NURBS `model` from the state `initial` (reduced
    /// coordinates) on its free control points. Needs constant weights and no linear
    /// constraints (`what` names the derivation in the error).
    pub fn of_dnurbs(
        model: &DnurbsModel,
        initial: &State,
        what: &'static str,
    ) -> Result<Self, DeriveError> {
        let refuse = |obstacle| DeriveError::NotScalar {
            method: what,
            obstacle,
        };
        if model.options().weights_as_dofs {
            return Err(refuse(ScalarObstacle::WeightsAsDofs));
        }
        if model.has_linear_constraints() {
            return Err(refuse(ScalarObstacle::LinearConstraints));
        }
        let n_cp = model.geometry().n_control_points();
        let fixed = model.fixed_points();
        let free: Vec<usize> = (0..n_cp).filter(|k| !fixed.contains(k)).collect();
        if free.is_empty() {
            return Err(refuse(ScalarObstacle::NoFreeControlPoint));
        }
        // With fixed points only, the free dofs are the x, y, z of the free points.
        let x_rows = PointDofs::XYZ.scalar_rows(free.len());
        let mass = model.reduced_mass().submatrix(&x_rows, &x_rows);
        let stiffness = model.reduced_stiffness().submatrix(&x_rows, &x_rows);
        let q0 = model.reduced_coordinates(model.p0());
        let mut f_int = vec![0.0; q0.len()];
        model.internal_force(&q0, &mut f_int);
        // `f_int(q0) = K q0 + f_int0` vanishes at the reference in exact arithmetic; what is
        // left is rounding of size eps·|K|·|q0|, which is not a load and must not excite modes.
        let k = model.reduced_stiffness();
        let k_scale = k
            .col_ptr()
            .windows(2)
            .map(|w| k.values()[w[0]..w[1]].iter().map(|x| x.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let q_scale = q0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let rounding = 1e3 * f64::EPSILON * k_scale * q_scale;
        let f_ext = model.reduced_force();
        // The internal force at the reference with its rounding removed where it leaves no
        // load, so that `load = f_ext − internal` exactly as the energies count it.
        let internal: Vec<f64> = f_ext
            .iter()
            .zip(&f_int)
            .map(|(f, g)| if (f - g).abs() <= rounding { *f } else { *g })
            .collect();
        let load: Vec<f64> = f_ext.iter().zip(&internal).map(|(f, g)| f - g).collect();
        let u0: Vec<f64> = initial.q.iter().zip(&q0).map(|(a, b)| a - b).collect();
        let material = model.material();
        // The D-NURBS's own energies (its `DynamicModel` potentials) at the reference q0.
        let energy = EnergyOrigin {
            elastic: model.potential_energy(&q0),
            internal: points(&internal),
            external: model.external_potential(0.0, &q0),
            force: points(f_ext),
        };
        Ok(Self {
            free,
            mass,
            stiffness,
            damping_ratio: material.gamma / material.mu,
            load: points(&load),
            displacement: points(&u0),
            velocity: points(&initial.v),
            energy,
        })
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.free.len()
    }

    /// `[kinetic, elastic, external]` at displacement `u` and velocity `v`: `½ vᵀ M v`, the
    /// elastic energy and the load potential of [`EnergyOrigin`].
    pub fn energies(&self, u: &[[f64; 3]], v: &[[f64; 3]]) -> [f64; 3] {
        let e = &self.energy;
        let kinetic = 0.5 * dot(v, &apply3(&self.mass, v));
        let elastic = e.elastic + dot(&e.internal, u) + 0.5 * dot(u, &apply3(&self.stiffness, u));
        [kinetic, elastic, e.external - dot(&e.force, u)]
    }
}

/// `A` applied to each of the three coordinate columns of `x`.
pub(crate) fn apply3(a: &SparseMatrix, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut out = vec![[0.0; 3]; a.nrows()];
    let mut col = vec![0.0; x.len()];
    let mut y = vec![0.0; a.nrows()];
    for c in 0..3 {
        for (v, p) in col.iter_mut().zip(x) {
            *v = p[c];
        }
        a.mul_vec(&col, &mut y);
        for (o, v) in out.iter_mut().zip(&y) {
            o[c] = *v;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two points, `M = [[2, 0], [0, 3]]`, `K = [[2, −1], [−1, 2]]`, an energy origin with
    /// elastic 0.5, internal force `r` and load `f`: by hand at `u`, `v`,
    /// kinetic `½ Σ_x vₓᵀ M vₓ`, elastic `0.5 + Σ rᵀu + ½ Σ uₓᵀ K uₓ`, external `e − Σ fᵀu`.
    #[test]
    fn energies_by_hand() {
        let mass = SparseMatrix::from_diagonal(&[2.0, 3.0]);
        let stiffness = SparseMatrix::from_triplets(
            2,
            2,
            &[(0, 0, 2.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 2.0)],
        )
        .unwrap();
        let sys = ScalarSystem {
            free: vec![4, 7],
            mass,
            stiffness,
            damping_ratio: 0.0,
            load: vec![[0.0; 3]; 2],
            displacement: vec![[0.0; 3]; 2],
            velocity: vec![[0.0; 3]; 2],
            energy: EnergyOrigin {
                elastic: 0.5,
                internal: vec![[1.0, 0.0, 1.0], [0.0, 2.0, 0.0]],
                external: 0.25,
                force: vec![[0.0, 0.0, -3.0], [1.0, 0.0, 0.0]],
            },
        };
        let u = [[1.0, 0.0, 2.0], [-1.0, 0.5, 0.0]];
        let v = [[0.0, 1.0, 0.0], [2.0, 0.0, -1.0]];
        // Kinetic: x: 3·4 = 12; y: 2·1 = 2; z: 3·1 = 3 → ½·17.
        // Elastic: rᵀu = 1 + 2 + 1 = 4; uᵀKu per component: x (1, −1): 2 + 2 + 2 = 6,
        // y (0, 0.5): 0.5, z (2, 0): 8 → 0.5 + 4 + ½·14.5.
        // External: 0.25 − (−6 − 1) = 7.25.
        let [kinetic, elastic, external] = sys.energies(&u, &v);
        assert_eq!(kinetic, 8.5);
        assert_eq!(elastic, 0.5 + 4.0 + 7.25);
        assert_eq!(external, 7.25);
        assert_eq!(dot(&u, &v), 0.0 + 0.0 + 0.0 - 2.0 + 0.0 + 0.0);
        // A load's origin: external potential fᵀu₀, no elastic part.
        let origin = EnergyOrigin::of_load(&sys.energy.force, &u);
        assert_eq!((origin.elastic, origin.external), (0.0, -6.0 - 1.0));
    }

    /// A stiff sheet (α = 10⁴) far from the origin (x ≈ 10³), at rest in its own rest shape and
    /// unloaded: `f_int(q₀)` is round-off of size ε |K| |q₀|, which is no load: every load of
    /// the scalar system is exactly zero, at every such scale.
    #[test]
    fn round_off_at_the_rest_shape_is_no_load() {
        use nurbspring_dnurbs::{Geometry, Material};
        use nurbspring_geom::{KnotVector, NurbsSurface};
        let ku = KnotVector::clamped_uniform(3, 3).unwrap();
        let g = ku.greville();
        let n = g.len();
        for (alpha, offset) in [(1e4, 1e3), (1e-4, 1e3), (1e4, 1e-3)] {
            let pts = g
                .iter()
                .flat_map(|&u| {
                    g.iter().map(move |&v| {
                        [
                            offset + 2.0 * u,
                            1.5 * v,
                            0.3 * (3.0 * u).sin() * (2.0 * v).cos(),
                        ]
                    })
                })
                .collect();
            let s = NurbsSurface::try_new(ku.clone(), ku.clone(), pts, vec![1.0; n * n]).unwrap();
            let mut config = crate::test_scenes::config(Geometry::Surface(s));
            config.material = Material {
                mu: 1.0,
                alpha11: alpha,
                alpha22: alpha,
                beta11: 1e-2 * alpha,
                beta22: 1e-2 * alpha,
                ..Material::default()
            };
            let setup = crate::setup::Setup::new(&config).unwrap();
            let model = setup.model();
            let initial = model.initial_state(&[], 0.0);
            let sys = ScalarSystem::of_dnurbs(model, &initial, "test").unwrap();
            assert!(
                sys.load.iter().flatten().all(|&f| f == 0.0),
                "α {alpha}, offset {offset}: {:?}",
                sys.load
            );
        }
    }
}
