//! The solution of an undamped linear scalar system `M ü + K u = f` (constant `f`) by its modes
//! (docs/math.md §8): the reference every linear model is judged against. Each of the three
//! coordinates evolves by the same modes; only the points watched are evaluated. Up to
//! [`DENSE_MODES`] unknowns every mode is computed (dense) and the solution is exact; above, the
//! lowest [`TRUNCATED_MODES`] (sparse shift-invert Lanczos) with the static correction of the
//! modes left out, and the share of the motion they carry is estimated
//! ([`ModalBasis::left_out`]).

use std::sync::OnceLock;

use nurbspring_linalg::{
    DenseMatrix, SparseMatrix, SpdSolver, generalized_eigen_sparse_lowest,
    generalized_symmetric_eigen, largest_generalized_eigenvalue,
};

use crate::DeriveError;
use crate::scalar::{EnergyOrigin, apply3, dot};

/// Largest system whose modes are all computed (dense generalized eigenproblem, `O(n³)`).
pub const DENSE_MODES: usize = 2000;

/// Modes kept for a larger system.
pub const TRUNCATED_MODES: usize = 200;

/// Relative size below which an eigenvalue counts as a rigid (zero-frequency) mode.
const RIGID: f64 = 1e-12;

/// Lowest modes of `K φ = ω² M φ`, M-orthonormal, ascending: all of them, or the lowest
/// [`TRUNCATED_MODES`] of a large system.
#[derive(Clone, Debug)]
pub struct ModalBasis {
    /// Angular frequencies (0 for rigid modes).
    pub omega: Vec<f64>,
    /// `λ = ω²` as computed (rigid modes clamped to 0).
    pub lambda: Vec<f64>,
    /// Mode shapes, one column per mode.
    pub vectors: DenseMatrix,
    /// The highest angular frequency, once asked for ([`ModalBasis::omega_max`]).
    omega_max: OnceLock<f64>,
    /// The mass matrix (for projections).
    mass: SparseMatrix,
    /// The stiffness matrix (for the static correction and the share left out).
    stiffness: SparseMatrix,
    /// Its factor, once a static solve asks for it (`None`: K is not positive definite).
    stiffness_factor: OnceLock<Option<SpdSolver>>,
}

/// `a − b`, per unknown and coordinate.
fn minus(a: &[[f64; 3]], b: &[[f64; 3]]) -> Vec<[f64; 3]> {
    a.iter()
        .zip(b)
        .map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]])
        .collect()
}

impl ModalBasis {
    /// The modes of `(K, M)`: every mode up to [`DENSE_MODES`] unknowns, the lowest
    /// [`TRUNCATED_MODES`] above.
    pub fn new(k: &SparseMatrix, m: &SparseMatrix) -> Result<Self, DeriveError> {
        if k.nrows() <= DENSE_MODES {
            Self::all(k, m)
        } else {
            Self::lowest(k, m, TRUNCATED_MODES)
        }
    }

    /// Every mode of `(K, M)` (dense: `O(n³)` time, `O(n²)` memory).
    pub fn all(k: &SparseMatrix, m: &SparseMatrix) -> Result<Self, DeriveError> {
        let eig = generalized_symmetric_eigen(&k.to_dense(), &m.to_dense())?;
        let scale = eig.values.iter().fold(0.0_f64, |a, &l| a.max(l.abs()));
        Ok(Self::from_pairs(eig.values, eig.vectors, scale, k, m))
    }

    /// The lowest `count` modes of `(K, M)` by shift-invert Lanczos (every mode, dense, when
    /// `count` reaches the size). The shift lies just below zero so that rigid modes are found.
    pub fn lowest(k: &SparseMatrix, m: &SparseMatrix, count: usize) -> Result<Self, DeriveError> {
        if count >= k.nrows() {
            return Self::all(k, m);
        }
        let (kd, md) = (k.diagonal(), m.diagonal());
        let (tk, tm) = (kd.iter().sum::<f64>(), md.iter().sum::<f64>());
        let shift = if tk > 0.0 && tm > 0.0 {
            -1e-6 * tk / tm
        } else {
            -1.0
        };
        let eig = generalized_eigen_sparse_lowest(k, m, count, shift)?;
        // The scale of the rigid-mode test: the largest of the diagonal Rayleigh quotients
        // `K_ii / M_ii` and the modes found, within a small factor of λ_max (which would cost a
        // Lanczos run of its own; `omega_max` computes it when asked).
        let diagonal = kd
            .iter()
            .zip(&md)
            .filter(|&(_, &mi)| mi > 0.0)
            .fold(0.0_f64, |a, (ki, mi)| a.max(ki.abs() / mi));
        let scale = eig.values.iter().fold(diagonal, |a, &l| a.max(l.abs()));
        Ok(Self::from_pairs(eig.values, eig.vectors, scale, k, m))
    }

    fn from_pairs(
        values: Vec<f64>,
        vectors: DenseMatrix,
        scale: f64,
        k: &SparseMatrix,
        m: &SparseMatrix,
    ) -> Self {
        let lambda: Vec<f64> = values
            .iter()
            .map(|&l| {
                if l.abs() <= RIGID * scale {
                    0.0
                } else {
                    l.max(0.0)
                }
            })
            .collect();
        let omega: Vec<f64> = lambda.iter().map(|l| l.sqrt()).collect();
        let omega_max = OnceLock::new();
        if omega.len() == k.nrows() {
            let _ = omega_max.set(omega.last().copied().unwrap_or(0.0));
        }
        Self {
            omega_max,
            omega,
            lambda,
            vectors,
            mass: m.clone(),
            stiffness: k.clone(),
            stiffness_factor: OnceLock::new(),
        }
    }

    /// Number of modes kept.
    pub fn len(&self) -> usize {
        self.omega.len()
    }

    /// True when there is no mode.
    pub fn is_empty(&self) -> bool {
        self.omega.is_empty()
    }

    /// Unknowns of the system (the number of its modes).
    pub fn unknowns(&self) -> usize {
        self.mass.nrows()
    }

    /// True when every mode is kept (the modal solution is exact).
    pub fn is_complete(&self) -> bool {
        self.len() == self.unknowns()
    }

    /// The highest angular frequency of the system: the last of `omega` when every mode is
    /// kept, else by Lanczos on `M⁻¹K` (computed once, on the first call).
    pub fn omega_max(&self) -> Result<f64, DeriveError> {
        if let Some(&w) = self.omega_max.get() {
            return Ok(w);
        }
        let top = largest_generalized_eigenvalue(&self.stiffness, &self.mass, 1e-10)?;
        Ok(*self.omega_max.get_or_init(|| top.max(0.0).sqrt()))
    }

    /// Mode `i` as a vector.
    pub fn mode(&self, i: usize) -> Vec<f64> {
        self.vectors.column(i)
    }

    /// `Φᵀ M x` per coordinate (modal coordinates of a displacement or velocity field).
    fn project_mass(&self, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
        let mx = apply3(&self.mass, x);
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

    /// `Φ η` per coordinate.
    fn expand(&self, eta: &[[f64; 3]]) -> Vec<[f64; 3]> {
        (0..self.vectors.nrows())
            .map(|a| {
                let row = self.vectors.row(a);
                let mut x = [0.0; 3];
                for (phi, e) in row.iter().zip(eta) {
                    for c in 0..3 {
                        x[c] += phi * e[c];
                    }
                }
                x
            })
            .collect()
    }

    /// `K⁻¹ x` per coordinate, or `None` when K is singular (a rigid mode among those found;
    /// they are the lowest, so a truncated basis has them all). K is factored once.
    pub(crate) fn static_solve(&self, x: &[[f64; 3]]) -> Option<Vec<[f64; 3]>> {
        if self.lambda.first() == Some(&0.0) {
            return None;
        }
        let solver = self
            .stiffness_factor
            .get_or_init(|| SpdSolver::new(&self.stiffness).ok())
            .as_ref()?;
        let mut out = vec![[0.0; 3]; x.len()];
        for c in 0..3 {
            let mut col: Vec<f64> = x.iter().map(|p| p[c]).collect();
            solver.solve_in_place(&mut col);
            for (o, v) in out.iter_mut().zip(col) {
                o[c] = v;
            }
        }
        Some(out)
    }

    /// `x − Φ Φᵀ M x`: the part of `x` in the modes left out.
    fn left_out_part(&self, x: &[[f64; 3]]) -> Vec<[f64; 3]> {
        minus(x, &self.expand(&self.project_mass(x)))
    }

    /// The static displacement of the modes left out under the load `f`,
    /// `c = (I − ΦΦᵀM) K⁻¹ f` (none when every mode is kept, the load is zero or K is
    /// singular).
    fn static_correction(&self, f: &[[f64; 3]]) -> Option<Vec<[f64; 3]>> {
        if self.is_complete() || f.iter().all(|p| p.iter().all(|&x| x == 0.0)) {
            return None;
        }
        Some(self.left_out_part(&self.static_solve(f)?))
    }

    /// The share of the motion from displacement `u0`, velocity `v0` and constant load `f`
    /// carried by the modes left out: `√(Σ_{i>r} a_i² / Σ_i a_i²)` with `a_i² = Σ_x
    /// (φ_iᵀM(u₀ − K⁻¹f))² + (φ_iᵀMv₀/ω_i)²` the squared amplitude of mode `i` (so the ratio is
    /// that of the time-RMS M-norms of the oscillation about the static state, the sums over
    /// every mode in closed form: `Σ_i a_i² = ‖u₀ − K⁻¹f‖²_M + v₀ᵀMK⁻¹Mv₀`). `Some(0)` when
    /// every mode is kept, `None` when K is singular (rigid modes) or nothing moves.
    pub fn left_out(&self, u0: &[[f64; 3]], v0: &[[f64; 3]], f: &[[f64; 3]]) -> Option<f64> {
        if self.is_complete() {
            return Some(0.0);
        }
        let w = minus(u0, &self.static_solve(f)?);
        let mv = apply3(&self.mass, v0);
        let z = self.static_solve(&mv)?;
        let total = dot(&w, &apply3(&self.mass, &w)) + dot(&mv, &z);
        let (ew, ev) = (self.project_mass(&w), self.project(&mv));
        let kept: f64 = (0..self.len())
            .filter(|&i| self.lambda[i] > 0.0)
            .map(|i| dot(&ew[i..=i], &ew[i..=i]) + dot(&ev[i..=i], &ev[i..=i]) / self.lambda[i])
            .sum();
        (total > 0.0).then(|| ((total - kept).max(0.0) / total).sqrt())
    }

    /// The displacement at the points `watch` (rows: weights of the unknowns, so a point is
    /// `Σ_a watch[p][a] u_a`) at each time of `times`, from displacement `u0`, velocity `v0`
    /// and constant load `f` (each one `[x, y, z]` per unknown); with `energy`, also the
    /// `[kinetic, elastic, external]` energies at each time, in closed form from the modal
    /// coordinates (M-orthonormal modes, `u = Φ η`): kinetic `½ Σ η̇²`, elastic
    /// `E₀ + hᵀ η + ½ Σ ω² η²` and load potential `V₀ − gᵀ η`, with `h = Φᵀ internal` and
    /// `g = Φᵀ force` of the [`EnergyOrigin`] (the static load offset is part of `η`). A
    /// truncated basis adds the static displacement of the modes left out,
    /// `c = (I − ΦΦᵀM) K⁻¹ f`, constant in time (M-orthogonal to the modes kept, so it adds
    /// only constants to the energies): the motion of the modes left out is dropped, their
    /// static response kept.
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
        let correction = self.static_correction(f);
        // The correction at the watched points and its energy constants.
        let offsets: Vec<[f64; 3]> = watch
            .iter()
            .map(|w| {
                let mut d = [0.0; 3];
                if let Some(cs) = &correction {
                    for &(a, c) in w {
                        for x in 0..3 {
                            d[x] += c * cs[a][x];
                        }
                    }
                }
                d
            })
            .collect();
        let (elastic_offset, external_offset) = match (&correction, energy) {
            (Some(c), Some(e)) => (
                dot(&e.internal, c) + 0.5 * dot(c, &apply3(&self.stiffness, c)),
                -dot(&e.force, c),
            ),
            _ => (0.0, 0.0),
        };
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
                let mut d = offsets[p];
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
                    e.elastic + elastic_offset + dot(h, &eta) + strain,
                    e.external + external_offset - dot(fe, &eta),
                ]);
            }
        }
        (out, energies)
    }
}
