//! Non-negative least squares on the normal equations of a problem whose unknowns are a few
//! constants and many node masses: the active-set method of Lawson–Hanson in the
//! normal-equation form of Bro & De Jong (1997), with every passive-set system solved through
//! its structure,
//!
//! `H = [[H_kk, H_km], [H_mk, diag(d) + SᵀS]]`, `S` a few rows,
//!
//! by the Woodbury identity on the mass block and a Schur complement on the constants, so a
//! solve costs `O(n (c + r)²)` for `n` masses, `c` constants and `r` rows of `S`. The modal
//! fit (docs/math.md §8.3), whose masses are bounded only from below and rarely reach the
//! bound, eliminates them once itself and solves its reduced problem here with no mass block
//! (`n = 0`), a dense NNLS in its group factors.

use nurbspring_linalg::{DenseMatrix, cholesky_solve_dense, solve_dense};

use crate::DeriveError;

/// The quadratic `½ zᵀ H z − gᵀ z` with `H` as above (all blocks already scaled).
pub(crate) struct BlockQp {
    /// `H_kk`, `c × c`.
    pub hkk: DenseMatrix,
    /// `H_km`, `c × n`.
    pub hkm: DenseMatrix,
    /// The diagonal `d > 0` of the mass block.
    pub d: Vec<f64>,
    /// `S`, `r × n`.
    pub s: DenseMatrix,
    /// `g`, `c + n`.
    pub g: Vec<f64>,
}

impl BlockQp {
    fn c(&self) -> usize {
        self.hkk.nrows()
    }

    fn n(&self) -> usize {
        self.d.len()
    }

    /// `H z`.
    pub fn apply(&self, z: &[f64]) -> Vec<f64> {
        let (c, n) = (self.c(), self.n());
        let (zk, zm) = z.split_at(c);
        let mut out = vec![0.0; c + n];
        for i in 0..c {
            out[i] = (0..c).map(|j| self.hkk[(i, j)] * zk[j]).sum::<f64>()
                + self
                    .hkm
                    .row(i)
                    .iter()
                    .zip(zm)
                    .map(|(a, b)| a * b)
                    .sum::<f64>();
        }
        let sz: Vec<f64> = (0..self.s.nrows())
            .map(|r| self.s.row(r).iter().zip(zm).map(|(a, b)| a * b).sum())
            .collect();
        for a in 0..n {
            let mut v = self.d[a] * zm[a];
            for (i, &zi) in zk.iter().enumerate() {
                v += self.hkm[(i, a)] * zi;
            }
            for (r, &s) in sz.iter().enumerate() {
                v += self.s[(r, a)] * s;
            }
            out[c + a] = v;
        }
        out
    }

    /// The minimizer over the unknowns marked `passive` (the others held at 0).
    fn solve_passive(&self, passive: &[bool]) -> Result<Vec<f64>, DeriveError> {
        let (c, n) = (self.c(), self.n());
        let ks: Vec<usize> = (0..c).filter(|&i| passive[i]).collect();
        let ms: Vec<usize> = (0..n).filter(|&a| passive[c + a]).collect();
        let r = self.s.nrows();
        // Woodbury on diag(d) + SᵀS restricted to ms.
        let cap = DenseMatrix::from_fn(r, r, |i, j| {
            let mut v: f64 = ms
                .iter()
                .map(|&a| self.s[(i, a)] * self.s[(j, a)] / self.d[a])
                .sum();
            if i == j {
                v += 1.0;
            }
            v
        });
        let inv_mass = |x: &[f64]| -> Result<Vec<f64>, DeriveError> {
            // x is over ms.
            let dx: Vec<f64> = ms.iter().zip(x).map(|(&a, v)| v / self.d[a]).collect();
            if r == 0 {
                return Ok(dx);
            }
            let sdx: Vec<f64> = (0..r)
                .map(|i| ms.iter().zip(&dx).map(|(&a, v)| self.s[(i, a)] * v).sum())
                .collect();
            let w = cholesky_solve_dense(&cap, &sdx)?;
            Ok(ms
                .iter()
                .zip(&dx)
                .map(|(&a, v)| v - (0..r).map(|i| self.s[(i, a)] * w[i]).sum::<f64>() / self.d[a])
                .collect())
        };
        let g_m: Vec<f64> = ms.iter().map(|&a| self.g[c + a]).collect();
        let inv_gm = inv_mass(&g_m)?;
        let mut inv_hmk = Vec::with_capacity(ks.len());
        for &i in &ks {
            let col: Vec<f64> = ms.iter().map(|&a| self.hkm[(i, a)]).collect();
            inv_hmk.push(inv_mass(&col)?);
        }
        let dot_km = |i: usize, v: &[f64]| -> f64 {
            ms.iter().zip(v).map(|(&a, x)| self.hkm[(i, a)] * x).sum()
        };
        let schur = DenseMatrix::from_fn(ks.len(), ks.len(), |p, q| {
            self.hkk[(ks[p], ks[q])] - dot_km(ks[p], &inv_hmk[q])
        });
        let rhs: Vec<f64> = ks.iter().map(|&i| self.g[i] - dot_km(i, &inv_gm)).collect();
        let yk = if ks.is_empty() {
            Vec::new()
        } else {
            match cholesky_solve_dense(&schur, &rhs) {
                Ok(y) => y,
                Err(_) => solve_dense(&schur, &rhs)?,
            }
        };
        let mut out = vec![0.0; c + n];
        for (p, &i) in ks.iter().enumerate() {
            out[i] = yk[p];
        }
        for (q, &a) in ms.iter().enumerate() {
            out[c + a] = inv_gm[q]
                - inv_hmk
                    .iter()
                    .zip(&yk)
                    .map(|(col, y)| col[q] * y)
                    .sum::<f64>();
        }
        Ok(out)
    }

    /// The minimizer over `z ≥ 0`, from the feasible start `x0` (its positive entries start
    /// passive). Errors when the active-set loop does not settle.
    pub fn solve_nonnegative(&self, x0: Vec<f64>) -> Result<Vec<f64>, DeriveError> {
        let total = self.c() + self.n();
        let mut x = x0;
        let mut passive: Vec<bool> = x.iter().map(|&v| v > 0.0).collect();
        let g_scale = self
            .g
            .iter()
            .fold(0.0_f64, |a, v| a.max(v.abs()))
            .max(f64::MIN_POSITIVE);
        let tol = 1e-12 * g_scale;
        let max_iterations = 3 * total + 50;
        let mut iterations = 0;
        loop {
            // Inner loop: the passive-set minimizer, stepping back while it is infeasible.
            loop {
                iterations += 1;
                if iterations > max_iterations {
                    return Err(DeriveError::InvalidOption {
                        name: "modal fit",
                        value: format!("{iterations} iterations"),
                        reason: "the non-negative least-squares iteration did not settle".into(),
                    });
                }
                let s = self.solve_passive(&passive)?;
                let infeasible: Vec<usize> =
                    (0..total).filter(|&j| passive[j] && s[j] <= 0.0).collect();
                if infeasible.is_empty() {
                    x = s;
                    break;
                }
                let alpha = infeasible
                    .iter()
                    .map(|&j| x[j] / (x[j] - s[j]))
                    .fold(1.0_f64, f64::min)
                    .max(0.0);
                let hit = infeasible
                    .iter()
                    .copied()
                    .min_by(|&a, &b| (x[a] / (x[a] - s[a])).total_cmp(&(x[b] / (x[b] - s[b]))));
                for j in 0..total {
                    x[j] += alpha * (s[j] - x[j]);
                }
                let scale = x
                    .iter()
                    .fold(0.0_f64, |a, v| a.max(v.abs()))
                    .max(f64::MIN_POSITIVE);
                for j in 0..total {
                    if passive[j] && (x[j] <= 1e-14 * scale || Some(j) == hit) {
                        passive[j] = false;
                        x[j] = 0.0;
                    }
                }
            }
            // Outer loop: free the active unknown with the largest descent.
            let hx = self.apply(&x);
            let best = (0..total)
                .filter(|&j| !passive[j])
                .map(|j| (j, self.g[j] - hx[j]))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            match best {
                Some((j, w)) if w > tol => passive[j] = true,
                _ => return Ok(x),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random problems `H = BᵀB + diag(ε, d)` with B of `r` rows (so the mass block is
    /// `diag(d) + SᵀS` with `S` the mass columns of B), from a fixed generator.
    fn problems(count: usize) -> Vec<BlockQp> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let (c, n, r) = (2, 5, 3);
        (0..count)
            .map(|_| {
                let b = DenseMatrix::from_fn(r, c + n, |_, _| next());
                let eps = 0.1 + 0.5 * next().abs();
                BlockQp {
                    hkk: DenseMatrix::from_fn(c, c, |i, j| {
                        (0..r).map(|q| b[(q, i)] * b[(q, j)]).sum::<f64>()
                            + if i == j { eps } else { 0.0 }
                    }),
                    hkm: DenseMatrix::from_fn(c, n, |i, a| {
                        (0..r).map(|q| b[(q, i)] * b[(q, c + a)]).sum()
                    }),
                    d: (0..n).map(|_| 0.2 + next().abs()).collect(),
                    s: DenseMatrix::from_fn(r, n, |q, a| b[(q, c + a)]),
                    g: (0..c + n).map(|_| 2.0 * next()).collect(),
                }
            })
            .collect()
    }

    /// H as a dense matrix, column by column through `apply`.
    fn dense(qp: &BlockQp) -> DenseMatrix {
        let t = qp.c() + qp.n();
        let cols: Vec<Vec<f64>> = (0..t)
            .map(|j| {
                let mut e = vec![0.0; t];
                e[j] = 1.0;
                qp.apply(&e)
            })
            .collect();
        DenseMatrix::from_fn(t, t, |i, j| cols[j][i])
    }

    /// The minimizer over `z ≥ 0` by enumeration: the passive set whose equality-constrained
    /// minimizer is positive and whose multipliers `g − Hz` are ≤ 0 elsewhere (unique, H
    /// being positive definite).
    fn by_enumeration(h: &DenseMatrix, g: &[f64]) -> Vec<f64> {
        let t = g.len();
        for mask in 0..(1u32 << t) {
            let p: Vec<usize> = (0..t).filter(|&j| mask & (1 << j) != 0).collect();
            let hp = DenseMatrix::from_fn(p.len(), p.len(), |i, j| h[(p[i], p[j])]);
            let gp: Vec<f64> = p.iter().map(|&j| g[j]).collect();
            let zp = if p.is_empty() {
                Vec::new()
            } else {
                solve_dense(&hp, &gp).unwrap()
            };
            if zp.iter().any(|&v| v <= 0.0) {
                continue;
            }
            let mut z = vec![0.0; t];
            for (&j, &v) in p.iter().zip(&zp) {
                z[j] = v;
            }
            let hz = h.mul_vec(&z);
            if (0..t).all(|j| mask & (1 << j) != 0 || g[j] - hz[j] <= 1e-12) {
                return z;
            }
        }
        panic!("no KKT point");
    }

    /// The active-set solution equals the enumerated one, from the origin and from a start
    /// with every unknown positive, and the structured passive solves equal dense ones.
    #[test]
    fn the_active_set_solution_against_enumeration() {
        let mut bounded = 0;
        for (case, qp) in problems(60).iter().enumerate() {
            let h = dense(qp);
            let expected = by_enumeration(&h, &qp.g);
            bounded += expected.iter().filter(|&&v| v == 0.0).count();
            let t = qp.g.len();
            for start in [vec![0.0; t], vec![0.5; t]] {
                let z = qp.solve_nonnegative(start.clone()).unwrap();
                for j in 0..t {
                    assert!(
                        (z[j] - expected[j]).abs() < 1e-10 * (1.0 + expected[j].abs()),
                        "case {case} from {:?}: {z:?} vs {expected:?}",
                        start[0]
                    );
                }
            }
            // Every unknown passive: the plain solve of H z = g.
            let all = qp.solve_passive(&vec![true; t]).unwrap();
            let direct = solve_dense(&h, &qp.g).unwrap();
            for j in 0..t {
                assert!((all[j] - direct[j]).abs() < 1e-10 * (1.0 + direct[j].abs()));
            }
        }
        assert!(bounded >= 60, "{bounded}");
    }
}
