//! The exact solution of an undamped linear scalar system `M ü + K u = f` (constant `f`), by
//! its modes (docs/math.md §8): the reference every linear model is judged against. Each of
//! the three coordinates evolves by the same modes; only the points watched are evaluated.

use nurbspring_linalg::{DenseMatrix, SparseMatrix, generalized_symmetric_eigen};

use crate::DeriveError;
use crate::scalar::{EnergyOrigin, dot};

/// Largest system solved by dense modes.
pub const MAX_MODAL: usize = 4000;

/// Relative size below which an eigenvalue counts as a rigid (zero-frequency) mode.
const RIGID: f64 = 1e-12;

/// The modes of `K φ = ω² M φ`, M-orthonormal, ascending.
#[derive(Clone, Debug)]
pub struct ModalBasis {
    /// Angular frequencies (0 for rigid modes).
    pub omega: Vec<f64>,
    /// `λ = ω²` as computed (rigid modes clamped to 0).
    pub lambda: Vec<f64>,
    /// Mode shapes, one column per mode.
    pub vectors: DenseMatrix,
    /// The mass matrix (for projections).
    mass: SparseMatrix,
}

impl ModalBasis {
    /// Every mode of `(K, M)` (dense; at most [`MAX_MODAL`] unknowns).
    pub fn new(k: &SparseMatrix, m: &SparseMatrix) -> Result<Self, DeriveError> {
        let n = k.nrows();
        if n > MAX_MODAL {
            return Err(DeriveError::InvalidOption {
                name: "modal solution size",
                value: n.to_string(),
                reason: format!("more than {MAX_MODAL} unknowns for dense modes"),
            });
        }
        let eig = generalized_symmetric_eigen(&k.to_dense(), &m.to_dense())?;
        let scale = eig.values.iter().fold(0.0_f64, |a, &l| a.max(l.abs()));
        let lambda: Vec<f64> = eig
            .values
            .iter()
            .map(|&l| {
                if l.abs() <= RIGID * scale {
                    0.0
                } else {
                    l.max(0.0)
                }
            })
            .collect();
        Ok(Self {
            omega: lambda.iter().map(|l| l.sqrt()).collect(),
            lambda,
            vectors: eig.vectors,
            mass: m.clone(),
        })
    }

    /// Number of modes.
    pub fn len(&self) -> usize {
        self.omega.len()
    }

    /// True when there is no mode.
    pub fn is_empty(&self) -> bool {
        self.omega.is_empty()
    }

    /// Mode `i` as a vector.
    pub fn mode(&self, i: usize) -> Vec<f64> {
        self.vectors.column(i)
    }

    /// `Φᵀ M x` per coordinate (modal coordinates of a displacement or velocity field).
    fn project_mass(&self, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let mx = crate::scalar::apply3(&self.mass, x);
        self.project(&mx)
    }

    /// `Φᵀ f` per coordinate.
    fn project(&self, f: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let (n, r) = (self.vectors.nrows(), self.vectors.ncols());
        let mut out = vec![[0.0; 3]; r];
        for a in 0..n {
            let row = self.vectors.row(a);
            for (i, o) in out.iter_mut().enumerate() {
                for c in 0..3 {
                    o[c] += row[i] * f[a][c];
                }
            }
        }
        out
    }

    /// The displacement at the points `watch` (rows: weights of the unknowns, so a point is
    /// `Σ_a watch[p][a] u_a`) at each time of `times`, from displacement `u0`, velocity `v0`
    /// and constant load `f` (each one `[x, y, z]` per unknown); with `energy`, also the
    /// `[kinetic, elastic, external]` energies at each time, in closed form from the modal
    /// coordinates (M-orthonormal modes, `u = Φ η`): kinetic `½ Σ η̇²`, elastic
    /// `E₀ + hᵀ η + ½ Σ ω² η²` and load potential `V₀ − gᵀ η`, with `h = Φᵀ internal` and
    /// `g = Φᵀ force` of the [`EnergyOrigin`] (the static load offset is part of `η`).
    pub fn response(
        &self,
        watch: &[Vec<(usize, f64)>],
        times: &[f64],
        u0: &[[f64; 3]],
        v0: &[[f64; 3]],
        f: &[[f64; 3]],
        energy: Option<&EnergyOrigin>,
    ) -> (Vec<Vec<[f64; 3]>>, Vec<[f64; 3]>) {
        let r = self.len();
        let (e0, e1, g) = (
            self.project_mass(u0),
            self.project_mass(v0),
            self.project(f),
        );
        let origin = energy.map(|e| (e, self.project(&e.internal), self.project(&e.force)));
        // The watched combinations of each mode.
        let shapes: Vec<Vec<f64>> = watch
            .iter()
            .map(|w| {
                (0..r)
                    .map(|i| w.iter().map(|&(a, c)| c * self.vectors[(a, i)]).sum())
                    .collect()
            })
            .collect();
        let mut out = vec![Vec::with_capacity(times.len()); watch.len()];
        let mut energies = Vec::with_capacity(if energy.is_some() { times.len() } else { 0 });
        let mut eta = vec![[0.0; 3]; r];
        let mut rate = vec![[0.0; 3]; r];
        for &t in times {
            for i in 0..r {
                let (w, l) = (self.omega[i], self.lambda[i]);
                // η = c e0 + s e1 + q g and η̇ = c' e0 + s' e1 + q' g.
                let ((c, s, q), (dc, ds, dq)) = if l > 0.0 {
                    let (cos, sin) = ((w * t).cos(), (w * t).sin());
                    ((cos, sin / w, (1.0 - cos) / l), (-w * sin, cos, sin / w))
                } else {
                    ((1.0, t, 0.5 * t * t), (0.0, 1.0, t))
                };
                for x in 0..3 {
                    eta[i][x] = c * e0[i][x] + s * e1[i][x] + q * g[i][x];
                    rate[i][x] = dc * e0[i][x] + ds * e1[i][x] + dq * g[i][x];
                }
            }
            for (p, shape) in shapes.iter().enumerate() {
                let mut d = [0.0; 3];
                for i in 0..r {
                    for x in 0..3 {
                        d[x] += shape[i] * eta[i][x];
                    }
                }
                out[p].push(d);
            }
            if let Some((e, h, fe)) = &origin {
                let kinetic = 0.5 * dot(&rate, &rate);
                let strain: f64 = (0..r)
                    .map(|i| 0.5 * self.lambda[i] * dot(&eta[i..=i], &eta[i..=i]))
                    .sum();
                energies.push([
                    kinetic,
                    e.elastic + dot(h, &eta) + strain,
                    e.external - dot(fe, &eta),
                ]);
            }
        }
        (out, energies)
    }
}
