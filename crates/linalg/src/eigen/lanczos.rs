//! Sparse eigenproblems by Lanczos: the largest eigenvalue of a pencil, and the lowest eigenpairs by shift-invert with full reorthogonalization.

use super::*;

/// Deterministic pseudo-random numbers (SplitMix64) for Lanczos start vectors.
pub(super) struct SplitMix64(pub(super) u64);

impl SplitMix64 {
    pub(super) fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// The inner-product operator B of a Lanczos run (`⟨x, y⟩_B = xᵀ B y`).
pub(super) enum InnerProduct<'a> {
    Diagonal(Vec<f64>),
    Sparse(&'a SparseMatrix),
}

impl InnerProduct<'_> {
    pub(super) fn apply(&self, x: &[f64], y: &mut [f64]) {
        match self {
            InnerProduct::Diagonal(d) => y
                .iter_mut()
                .zip(d)
                .zip(x)
                .for_each(|((y, d), x)| *y = d * x),
            InnerProduct::Sparse(b) => b.mul_vec(x, y),
        }
    }
}

pub(super) fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

pub(super) fn axpy(alpha: f64, x: &[f64], y: &mut [f64]) {
    y.iter_mut().zip(x).for_each(|(y, x)| *y += alpha * x);
}

/// Lanczos vectors stored column-major in one buffer, so that the reorthogonalization runs as
/// two matrix-vector products in faer.
pub(super) struct Basis {
    n: usize,
    len: usize,
    data: Vec<f64>,
}

impl Basis {
    pub(super) fn new(n: usize, capacity: usize) -> Self {
        Self {
            n,
            len: 0,
            data: Vec::with_capacity(n * capacity),
        }
    }
    pub(super) fn push(&mut self, v: &[f64]) {
        self.data.extend_from_slice(v);
        self.len += 1;
    }
    pub(super) fn col(&self, j: usize) -> &[f64] {
        &self.data[j * self.n..(j + 1) * self.n]
    }
    pub(super) fn as_mat(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.data[..self.n * self.len], self.n, self.len)
    }
}

/// B-orthogonalizes `w` against `locked` and `basis` by classical Gram–Schmidt (the basis
/// part as the faer products `c = Vᵀ(Bw)`, `w −= V c`), repeated once when the first pass
/// removed most of `w` (the Daniel–Gragg–Kaufman–Stewart criterion: a second pass when
/// `‖w‖_B` fell below `1/√2` of what it was; twice is enough, Giraud et al. 2005). In a Lanczos
/// step the recurrence has already removed nearly everything, so one pass is the rule: each
/// pass reads every Lanczos vector twice, and on large problems that traffic is most of the
/// eigensolver's time. `z` is scratch.
pub(super) fn reorthogonalize(
    w: &mut [f64],
    z: &mut [f64],
    locked: &[Vec<f64>],
    basis: &Basis,
    b: &InnerProduct<'_>,
) {
    let n = w.len();
    let mut coeffs = vec![0.0; basis.len];
    b.apply(w, z);
    let mut before = dot(w, z);
    for _ in 0..2 {
        let locked_coeffs: Vec<f64> = locked.iter().map(|u| dot(u, z)).collect();
        for (u, c) in locked.iter().zip(locked_coeffs) {
            axpy(-c, u, w);
        }
        if basis.len > 0 {
            let v = basis.as_mat();
            let zc = MatRef::from_column_major_slice(z, n, 1);
            let mut cm = MatMut::from_column_major_slice_mut(&mut coeffs, basis.len, 1);
            matmul(
                cm.as_mut(),
                Accum::Replace,
                v.transpose(),
                zc,
                1.0,
                Par::Seq,
            );
            let wm = MatMut::from_column_major_slice_mut(w, n, 1);
            matmul(wm, Accum::Add, v, cm.as_ref(), -1.0, Par::Seq);
        }
        b.apply(w, z);
        let after = dot(w, z);
        if after > 0.5 * before {
            break;
        }
        before = after;
    }
}

/// Eigenvalues of the symmetric tridiagonal matrix with diagonal `d` and off-diagonal `e`
/// (`e[i]` couples `i` and `i + 1`) by the implicit QL algorithm with Wilkinson shifts
/// (EISPACK tql2 / Numerical Recipes `tqli`). Only the rows `rows` of the eigenvector matrix are
/// accumulated: returns the unsorted eigenvalues and `z[r][i]` = row `rows[r]` of eigenvector i.
pub(super) fn tridiagonal_eigen(
    d: &[f64],
    e: &[f64],
    rows: &[usize],
) -> Result<(Vec<f64>, Vec<Vec<f64>>), LinalgError> {
    let n = d.len();
    let mut d = d.to_vec();
    let mut e: Vec<f64> = e
        .iter()
        .copied()
        .chain(std::iter::repeat(0.0))
        .take(n)
        .collect();
    let mut z: Vec<Vec<f64>> = rows
        .iter()
        .map(|&r| {
            let mut row = vec![0.0; n];
            row[r] = 1.0;
            row
        })
        .collect();
    for l in 0..n {
        let mut iter = 0;
        loop {
            let mut m = l;
            while m + 1 < n {
                let dd = d[m].abs() + d[m + 1].abs();
                if e[m].abs() <= f64::EPSILON * dd {
                    break;
                }
                m += 1;
            }
            if m == l {
                break;
            }
            iter += 1;
            if iter > 60 {
                return Err(LinalgError::NoConvergence {
                    what: "tridiagonal QL eigenvalue iteration",
                    iterations: iter,
                });
            }
            let mut g = (d[l + 1] - d[l]) / (2.0 * e[l]);
            let mut r = g.hypot(1.0);
            g = d[m] - d[l] + e[l] / (g + r.copysign(g));
            let (mut s, mut c, mut p) = (1.0, 1.0, 0.0);
            let mut i = m;
            let mut deflated = false;
            while i > l {
                i -= 1;
                let f = s * e[i];
                let b = c * e[i];
                r = f.hypot(g);
                e[i + 1] = r;
                if r == 0.0 {
                    d[i + 1] -= p;
                    e[m] = 0.0;
                    deflated = true;
                    break;
                }
                s = f / r;
                c = g / r;
                g = d[i + 1] - p;
                r = (d[i] - g) * s + 2.0 * c * b;
                p = s * r;
                d[i + 1] = g + p;
                g = c * r - b;
                for row in z.iter_mut() {
                    let f = row[i + 1];
                    row[i + 1] = s * row[i] + c * f;
                    row[i] = c * row[i] - s * f;
                }
            }
            if deflated {
                continue;
            }
            d[l] -= p;
            e[l] = g;
            e[m] = 0.0;
        }
    }
    Ok((d, z))
}

/// Result of one Lanczos run: the largest Ritz values (descending), their residual norms
/// `‖Op x − θx‖_B`, B-normalized Ritz vectors, and whether the wanted ones met the tolerance.
pub(super) struct RitzPairs {
    values: Vec<f64>,
    residuals: Vec<f64>,
    vectors: Vec<Vec<f64>>,
    converged: bool,
}

/// Lanczos steps between two convergence tests of [`lanczos_largest`].
pub(super) const CHECK_EVERY: usize = 5;

/// Lanczos with full reorthogonalization for an operator `op` self-adjoint in the B-inner
/// product, restricted to the B-orthogonal complement of `locked` (B-orthonormal vectors).
/// Iterates until the `k` largest Ritz values have residual `≤ tol·|θ|`, the Krylov space is
/// exhausted (then the Ritz pairs are exact) or `m_max` vectors are stored. On an invariant
/// subspace (β = 0) it restarts with a fresh random vector, so multiple eigenvalues are found.
/// Returns up to `k + extra` pairs.
#[allow(clippy::too_many_arguments)]
pub(super) fn lanczos_largest(
    n: usize,
    op: &mut dyn FnMut(&[f64], &mut [f64]),
    b: &InnerProduct<'_>,
    locked: &[Vec<f64>],
    k: usize,
    extra: usize,
    tol: f64,
    m_max: usize,
    seed: u64,
    start: Option<Vec<f64>>,
) -> Result<RitzPairs, LinalgError> {
    let avail = n.saturating_sub(locked.len());
    let k = k.min(avail);
    if k == 0 {
        return Ok(RitzPairs {
            values: Vec::new(),
            residuals: Vec::new(),
            vectors: Vec::new(),
            converged: true,
        });
    }
    let m_max = m_max.min(avail).max(k);
    let mut rng = SplitMix64(seed);
    let mut z = vec![0.0; n];
    let mut w = vec![0.0; n];

    // A fresh start vector B-orthonormal to `locked` and `basis`; None when none is left.
    let mut start = start;
    let mut fresh = |rng: &mut SplitMix64, basis: &Basis, z: &mut [f64]| -> Option<Vec<f64>> {
        for _attempt in 0..4 {
            let mut v: Vec<f64> = match start.take() {
                Some(v) if v.len() == n => v,
                _ => (0..n).map(|_| rng.next_f64()).collect(),
            };
            b.apply(&v, z);
            let before = dot(&v, z).max(0.0).sqrt();
            reorthogonalize(&mut v, z, locked, basis, b);
            b.apply(&v, z);
            let after = dot(&v, z).max(0.0).sqrt();
            if after > 1e-8 * before && after > 0.0 {
                v.iter_mut().for_each(|x| *x /= after);
                return Some(v);
            }
        }
        None
    };

    let mut basis = Basis::new(n, m_max);
    let Some(v0) = fresh(&mut rng, &basis, &mut z) else {
        return Ok(RitzPairs {
            values: Vec::new(),
            residuals: Vec::new(),
            vectors: Vec::new(),
            converged: true,
        });
    };
    basis.push(&v0);
    let mut alphas: Vec<f64> = Vec::with_capacity(m_max);
    let mut betas: Vec<f64> = Vec::with_capacity(m_max);
    let mut tnorm = 0.0_f64;
    let (beta_last, exhausted, converged) = loop {
        let j = basis.len - 1;
        op(basis.col(j), &mut w);
        b.apply(&w, &mut z);
        let alpha = dot(basis.col(j), &z);
        axpy(-alpha, basis.col(j), &mut w);
        if j > 0 {
            axpy(-betas[j - 1], basis.col(j - 1), &mut w);
        }
        // Leaves z = B w.
        reorthogonalize(&mut w, &mut z, locked, &basis, b);
        let beta = dot(&w, &z).max(0.0).sqrt();
        if !alpha.is_finite() || !beta.is_finite() {
            return Err(LinalgError::NonFinite {
                what: "Lanczos recurrence",
            });
        }
        alphas.push(alpha);
        tnorm = tnorm.max(alpha.abs() + beta + if j > 0 { betas[j - 1] } else { 0.0 });
        let size = j + 1;
        let exhausted = size + locked.len() >= n;
        let breakdown = beta <= 1e-12 * tnorm || tnorm == 0.0;
        let beta_eff = if exhausted || breakdown { 0.0 } else { beta };
        // Convergence is tested every CHECK_EVERY steps (and at the end): the tridiagonal
        // eigenproblem costs O(size²), which over hundreds of steps outweighs the few steps
        // a late test adds.
        let due = (size - k.min(size)).is_multiple_of(CHECK_EVERY)
            || size >= m_max
            || exhausted
            || breakdown;
        if size >= k && due {
            let (theta, zl) = tridiagonal_eigen(&alphas, &betas, &[size - 1])?;
            let mut order: Vec<usize> = (0..size).collect();
            order.sort_by(|&a, &c| theta[c].total_cmp(&theta[a]));
            let floor = tnorm * 1e-14;
            let conv = order[..k]
                .iter()
                .all(|&i| beta_eff * zl[0][i].abs() <= tol * theta[i].abs().max(floor));
            if conv || exhausted || size >= m_max {
                break (beta_eff, exhausted, conv || exhausted);
            }
        } else if size < k && exhausted {
            break (0.0, true, true);
        }
        if breakdown {
            match fresh(&mut rng, &basis, &mut z) {
                Some(v) => {
                    betas.push(0.0);
                    basis.push(&v);
                }
                None => break (0.0, true, true),
            }
        } else {
            betas.push(beta);
            w.iter_mut().for_each(|x| *x /= beta);
            basis.push(&w);
        }
    };
    let _ = exhausted;
    // Ritz pairs from the dense EVD of T (small).
    let size = alphas.len();
    let t = Mat::from_fn(size, size, |i, j| {
        if i == j {
            alphas[i]
        } else if i == j + 1 {
            betas[j]
        } else if j == i + 1 {
            betas[i]
        } else {
            0.0
        }
    });
    let (theta, y) = faer_evd(&t, "Lanczos tridiagonal matrix")?;
    let take = (k + extra).min(size);
    let mut values = Vec::with_capacity(take);
    let mut residuals = Vec::with_capacity(take);
    let mut vectors = Vec::with_capacity(take);
    debug_assert_eq!(basis.len, size);
    let ritz = basis.as_mat() * y.as_ref().subcols(size - take, take);
    for c in (0..take).rev() {
        let idx = size - take + c;
        values.push(theta[idx]);
        residuals.push(beta_last * y[(size - 1, idx)].abs());
        vectors.push((0..n).map(|i| ritz[(i, c)]).collect());
    }
    Ok(RitzPairs {
        values,
        residuals,
        vectors,
        converged,
    })
}

pub(super) fn check_pencil(
    op: &'static str,
    k: &SparseMatrix,
    m: &SparseMatrix,
) -> Result<usize, LinalgError> {
    let n = k.nrows();
    if k.ncols() != n || m.nrows() != n || m.ncols() != n {
        return Err(mismatch(
            op,
            format!("square K and M of equal size ({n})"),
            format!(
                "K {}×{}, M {}×{}",
                k.nrows(),
                k.ncols(),
                m.nrows(),
                m.ncols()
            ),
        ));
    }
    if !k.all_finite() || !m.all_finite() {
        return Err(LinalgError::NonFinite { what: op });
    }
    Ok(n)
}

pub(super) enum Factor {
    Spd(SpdSolver),
    Lu(Box<LuSolver>),
}

impl Factor {
    pub(super) fn new(a: &SparseMatrix) -> Result<Self, LinalgError> {
        match SpdSolver::new(a) {
            Ok(s) => Ok(Factor::Spd(s)),
            Err(LinalgError::NotPositiveDefinite { .. }) => {
                Ok(Factor::Lu(Box::new(LuSolver::new(a)?)))
            }
            Err(e) => Err(e),
        }
    }
    pub(super) fn solve_in_place(&self, x: &mut [f64]) {
        match self {
            Factor::Spd(s) => s.solve_in_place(x),
            Factor::Lu(s) => s.solve_in_place(x),
        }
    }
}

/// The (at most) `count` eigenpairs of `K φ = λ M φ` nearest above `shift`, for sparse symmetric
/// K and SPD M: shift-invert Lanczos with full reorthogonalization (Ericsson & Ruhe 1980;
/// Grimes, Lewis & Simon 1994) on `(K − σM)⁻¹ M`, self-adjoint in the M-inner product, whose
/// largest eigenvalues `θ = 1/(λ − σ)` are the wanted λ. `K − σM` is factored once (sparse
/// Cholesky, or sparse LU when σ lies inside the spectrum). Converged pairs are locked and
/// Lanczos is restarted in their M-orthogonal complement until nothing nearer to σ is left, so
/// multiple eigenvalues (e.g. the threefold ones of `S ⊗ I₃`) are all found. Eigenvalues are
/// Rayleigh quotients `φᵀKφ / φᵀMφ`, ascending; vectors M-orthonormal. Fewer than `count` pairs
/// are returned only when fewer eigenvalues lie above σ.
///
/// σ must not be an eigenvalue: for a K with rigid-body modes (singular) use a small negative σ.
///
/// ```
/// use nurbspring_linalg::{generalized_eigen_sparse_lowest, SparseMatrix};
/// let n = 50;
/// let mut t = Vec::new();
/// for i in 0..n {
///     t.push((i, i, 2.0));
///     if i + 1 < n { t.push((i, i + 1, -1.0)); t.push((i + 1, i, -1.0)); }
/// }
/// let k = SparseMatrix::from_triplets(n, n, &t).unwrap();
/// let e = generalized_eigen_sparse_lowest(&k, &SparseMatrix::identity(n), 3, 0.0).unwrap();
/// for (j, lambda) in e.values.iter().enumerate() {
///     let exact = 2.0 - 2.0 * (((j + 1) as f64) * std::f64::consts::PI / (n + 1) as f64).cos();
///     assert!((lambda - exact).abs() < 1e-12);
/// }
/// ```
pub fn generalized_eigen_sparse_lowest(
    k: &SparseMatrix,
    m: &SparseMatrix,
    count: usize,
    shift: f64,
) -> Result<SymmetricEigen, LinalgError> {
    let n = check_pencil("generalized_eigen_sparse_lowest", k, m)?;
    if !shift.is_finite() {
        return Err(LinalgError::NonFinite {
            what: "shift of generalized_eigen_sparse_lowest",
        });
    }
    let count = count.min(n);
    if count == 0 {
        return Ok(SymmetricEigen {
            values: Vec::new(),
            vectors: DenseMatrix::zeros(n, 0),
        });
    }
    let shifted = SparseMatrix::linear_combination(1.0, k, -shift, m)?;
    let factor = Factor::new(&shifted)?;
    let mut scratch = vec![0.0; n];
    let mut op = |x: &[f64], y: &mut [f64]| {
        m.mul_vec(x, &mut scratch);
        y.copy_from_slice(&scratch);
        factor.solve_in_place(y);
    };
    let b = InnerProduct::Sparse(m);
    const TOL: f64 = 1e-12;
    let mut locked: Vec<Vec<f64>> = Vec::new();
    let mut locked_theta: Vec<f64> = Vec::new();
    let max_rounds = 2 * count + 20;
    let mut round = 0;
    let mut start: Option<Vec<f64>> = None;
    loop {
        if round >= max_rounds {
            return Err(LinalgError::NoConvergence {
                what: "shift-invert Lanczos (restarts)",
                iterations: round,
            });
        }
        let need = if locked.len() < count {
            count - locked.len()
        } else {
            1
        };
        if n == locked.len() {
            break;
        }
        let m_max = (3 * need + 60).max(100);
        let res = lanczos_largest(
            n,
            &mut op,
            &b,
            &locked,
            need,
            10,
            TOL,
            m_max,
            0x5EED_0000 + round as u64,
            start.take(),
        )?;
        round += 1;
        let Some(&top) = res.values.first() else {
            break;
        };
        if res.converged {
            if top <= 0.0 {
                break; // nothing (more) above the shift
            }
            if locked.len() >= count {
                let mut sorted = locked_theta.clone();
                sorted.sort_by(|a, c| c.total_cmp(a));
                if top <= sorted[count - 1] * (1.0 + 1e-9) {
                    break;
                }
            }
        }
        // Lock every converged pair (a true eigenpair, whichever round found it); restart
        // from the unconverged wanted Ritz vectors (explicit restart).
        let mut added = 0;
        let mut restart = vec![0.0; n];
        for (i, ((theta, resid), mut x)) in res
            .values
            .iter()
            .zip(&res.residuals)
            .zip(res.vectors)
            .enumerate()
        {
            let ok = (res.converged && i < need) || *resid <= TOL * theta.abs();
            if *theta <= 0.0 {
                continue;
            }
            if !ok {
                if i < need {
                    axpy(1.0, &x, &mut restart);
                }
                continue;
            }
            reorthogonalize(&mut x, &mut scratch_vec(n), &locked, &Basis::new(n, 0), &b);
            let mut bx = vec![0.0; n];
            b.apply(&x, &mut bx);
            let norm = dot(&x, &bx).max(0.0).sqrt();
            if norm < 1e-6 {
                continue;
            }
            x.iter_mut().for_each(|v| *v /= norm);
            locked.push(x);
            locked_theta.push(*theta);
            added += 1;
        }
        if res.converged && added == 0 {
            break;
        }
        if !res.converged {
            start = Some(restart);
        }
    }
    // Rank by θ (nearest above σ first), keep `count`, refine λ by the Rayleigh quotient.
    let mut order: Vec<usize> = (0..locked.len())
        .filter(|&i| locked_theta[i] > 0.0)
        .collect();
    order.sort_by(|&a, &c| locked_theta[c].total_cmp(&locked_theta[a]));
    order.truncate(count);
    let mut kx = vec![0.0; n];
    let mut mx = vec![0.0; n];
    let mut pairs: Vec<(f64, &Vec<f64>)> = order
        .iter()
        .map(|&i| {
            let x = &locked[i];
            k.mul_vec(x, &mut kx);
            m.mul_vec(x, &mut mx);
            (dot(x, &kx) / dot(x, &mx), x)
        })
        .collect();
    pairs.sort_by(|a, c| a.0.total_cmp(&c.0));
    let mut vectors = DenseMatrix::zeros(n, pairs.len());
    for (j, (_, x)) in pairs.iter().enumerate() {
        for i in 0..n {
            vectors[(i, j)] = x[i];
        }
    }
    normalize_signs(&mut vectors);
    Ok(SymmetricEigen {
        values: pairs.iter().map(|p| p.0).collect(),
        vectors,
    })
}

pub(super) fn scratch_vec(n: usize) -> Vec<f64> {
    vec![0.0; n]
}

/// The largest eigenvalue λ_max of `K φ = λ M φ` (K symmetric, M SPD; M may be diagonal, which
/// is detected and inverted entrywise), by Lanczos with full reorthogonalization on `M⁻¹K`,
/// self-adjoint in the M-inner product. Stops when the Ritz residual `‖M⁻¹Kx − θx‖_M ≤ tol·θ`
/// (Parlett, *The Symmetric Eigenvalue Problem*, §13.2). If 400 Lanczos vectors are not
/// enough (large problems with a clustered top spectrum), returns the upper estimate
/// `θ + residual`, capped by the Gershgorin bound of `M^{-1/2} K M^{-1/2}` when M is diagonal:
/// conservative for a stability limit `Δt < 2/√λ_max`. Returns 0 for `K = 0`.
///
/// ```
/// use nurbspring_linalg::{largest_generalized_eigenvalue, SparseMatrix};
/// let k = SparseMatrix::from_triplets(2, 2, &[(0, 0, 2.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 2.0)]).unwrap();
/// let m = SparseMatrix::from_diagonal(&[0.5, 0.5]);
/// let lambda = largest_generalized_eigenvalue(&k, &m, 1e-12).unwrap();
/// assert!((lambda - 6.0).abs() < 1e-10);
/// ```
pub fn largest_generalized_eigenvalue(
    k: &SparseMatrix,
    m: &SparseMatrix,
    tol: f64,
) -> Result<f64, LinalgError> {
    let n = check_pencil("largest_generalized_eigenvalue", k, m)?;
    if n == 0 || k.frobenius_norm() == 0.0 {
        return Ok(0.0);
    }
    let tol = if tol.is_finite() && tol > 0.0 {
        tol.max(10.0 * f64::EPSILON)
    } else {
        1e-10
    };
    let mut kx = vec![0.0; n];
    let (b, solver) = if m.is_diagonal() {
        let d = m.diagonal();
        if let Some(i) = d.iter().position(|&v| v.is_nan() || v <= 0.0) {
            return Err(LinalgError::NotPositiveDefinite {
                detail: format!("diagonal mass entry {i} is {}", d[i]),
            });
        }
        (InnerProduct::Diagonal(d), None)
    } else {
        (InnerProduct::Sparse(m), Some(SpdSolver::new(m)?))
    };
    let mut op = |x: &[f64], y: &mut [f64]| {
        k.mul_vec(x, &mut kx);
        match (&b, &solver) {
            (InnerProduct::Diagonal(d), _) => y
                .iter_mut()
                .zip(&kx)
                .zip(d)
                .for_each(|((y, kx), d)| *y = kx / d),
            (_, Some(s)) => {
                y.copy_from_slice(&kx);
                s.solve_in_place(y);
            }
            _ => unreachable!("a sparse mass matrix always has a solver"),
        }
    };
    // At most 400 Lanczos vectors, and at most LANCZOS_BYTES of them: on large models the
    // basis (and its full reorthogonalization, O(m² n)) would dominate memory and time; an
    // unconverged top Ritz value is bounded below.
    const M_MAX: usize = 400;
    const LANCZOS_BYTES: usize = 64 << 20;
    let m_max = (LANCZOS_BYTES / (8 * n)).clamp(20, M_MAX);
    let res = lanczos_largest(n, &mut op, &b, &[], 1, 0, tol, m_max, 0xB16_B00B5, None)?;
    // No Ritz value at all: the Krylov space collapsed at its first vector, which a non-zero K
    // only allows when M⁻¹K underflows (masses near the top of the f64 range).
    let (Some(&theta), Some(&resid)) = (res.values.first(), res.residuals.first()) else {
        return Err(LinalgError::NoConvergence {
            what: "largest_generalized_eigenvalue (M⁻¹K underflows)",
            iterations: 0,
        });
    };
    if res.converged {
        return Ok(theta);
    }
    // Not converged within the memory budget: θ ≤ λ_max ≤ θ + residual in practice (the top
    // Ritz value approaches λ_max from below); cap by Gershgorin's rigorous bound when M is
    // diagonal.
    let mut estimate = theta + resid;
    if let InnerProduct::Diagonal(d) = &b {
        let mut row_sum = vec![0.0; n];
        for (i, j, v) in k.triplets() {
            row_sum[i] += v.abs() / (d[i] * d[j]).sqrt();
        }
        let gershgorin = row_sum.iter().fold(0.0_f64, |m, &r| m.max(r));
        estimate = estimate.min(gershgorin).max(theta);
    }
    Ok(estimate)
}
