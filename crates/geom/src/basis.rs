//! B-spline basis functions and their derivatives (The NURBS Book, A2.2 and A2.3).

use crate::{GeomError, KnotVector};

/// A B-spline basis: a knot vector and its degree. It evaluates into caller buffers.
///
/// The cubic basis on a single span is the Bernstein basis:
/// ```
/// use nurbspring_geom::{BSplineBasis, KnotVector};
/// let basis = BSplineBasis::new(KnotVector::try_new(vec![0., 0., 0., 0., 1., 1., 1., 1.], 3).unwrap());
/// let (span, values) = basis.values(0.25).unwrap();
/// assert_eq!(span, 3);
/// let t: f64 = 0.25;
/// let bernstein = [(1. - t).powi(3), 3. * t * (1. - t).powi(2), 3. * t * t * (1. - t), t.powi(3)];
/// for (a, b) in values.iter().zip(bernstein) { assert!((a - b).abs() < 1e-15); }
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct BSplineBasis {
    knots: KnotVector,
}

/// Scratch space for [`BSplineBasis::derivatives_into`]; reuse it to avoid allocation.
#[derive(Clone, Debug, Default)]
pub struct BasisScratch {
    left: Vec<f64>,
    right: Vec<f64>,
    ndu: Vec<f64>,
    a: Vec<f64>,
}

impl BasisScratch {
    fn ensure(&mut self, p: usize) {
        let n = p + 1;
        if self.left.len() < n {
            self.left.resize(n, 0.0);
            self.right.resize(n, 0.0);
            self.ndu.resize(n * n, 0.0);
            self.a.resize(2 * n, 0.0);
        }
    }
}

impl BSplineBasis {
    /// The basis of a validated knot vector.
    pub fn new(knots: KnotVector) -> Self {
        Self { knots }
    }

    /// The knot vector.
    pub fn knots(&self) -> &KnotVector {
        &self.knots
    }

    /// The degree p.
    pub fn degree(&self) -> usize {
        self.knots.degree()
    }

    /// Number of basis functions.
    pub fn len(&self) -> usize {
        self.knots.n_basis()
    }

    /// Always false (validated knot vectors have at least p + 1 functions).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Span of `u` (see [`KnotVector::find_span`]).
    pub fn find_span(&self, u: f64) -> usize {
        self.knots.find_span(u)
    }

    /// Values of the p + 1 non-zero functions `N_{span−p..=span}(u)` (The NURBS Book A2.2).
    /// `left`, `right` and `out` must hold at least p + 1 entries.
    pub fn values_into(&self, span: usize, u: f64, out: &mut [f64], scratch: &mut BasisScratch) {
        let p = self.degree();
        scratch.ensure(p);
        let k = self.knots.knots();
        let (left, right) = (&mut scratch.left, &mut scratch.right);
        out[0] = 1.0;
        for j in 1..=p {
            left[j] = u - k[span + 1 - j];
            right[j] = k[span + j] - u;
            let mut saved = 0.0;
            for r in 0..j {
                let temp = out[r] / (right[r + 1] + left[j - r]);
                out[r] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            out[j] = saved;
        }
    }

    /// Values and derivatives up to order `n` of the p + 1 non-zero functions at `u`
    /// (The NURBS Book A2.3). `out` is row-major `(n + 1) × (p + 1)`: row k holds the k-th
    /// derivatives of `N_{span−p}, …, N_{span}`. Orders above p are zero.
    pub fn derivatives_into(
        &self,
        span: usize,
        u: f64,
        n: usize,
        out: &mut [f64],
        scratch: &mut BasisScratch,
    ) {
        let p = self.degree();
        let w = p + 1;
        scratch.ensure(p);
        let k = self.knots.knots();
        let BasisScratch {
            left,
            right,
            ndu,
            a,
        } = scratch;
        // ndu[j][r] stored at j * w + r.
        ndu[0] = 1.0;
        for j in 1..=p {
            left[j] = u - k[span + 1 - j];
            right[j] = k[span + j] - u;
            let mut saved = 0.0;
            for r in 0..j {
                // Lower triangle: knot differences.
                ndu[j * w + r] = right[r + 1] + left[j - r];
                let temp = ndu[r * w + j - 1] / ndu[j * w + r];
                // Upper triangle: basis functions.
                ndu[r * w + j] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            ndu[j * w + j] = saved;
        }
        for j in 0..=p {
            out[j] = ndu[j * w + p];
        }
        let top = n.min(p);
        for r in 0..=p {
            let (mut s1, mut s2) = (0usize, 1usize);
            a[0] = 1.0;
            for kk in 1..=top {
                let mut d = 0.0;
                let rk = r as isize - kk as isize;
                let pk = p - kk;
                if rk >= 0 {
                    let rk = rk as usize;
                    a[s2 * w] = a[s1 * w] / ndu[(pk + 1) * w + rk];
                    d = a[s2 * w] * ndu[rk * w + pk];
                }
                let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
                let j2 = if r as isize - 1 <= pk as isize {
                    kk - 1
                } else {
                    p - r
                };
                for j in j1..=j2 {
                    let idx = (rk + j as isize) as usize;
                    a[s2 * w + j] = (a[s1 * w + j] - a[s1 * w + j - 1]) / ndu[(pk + 1) * w + idx];
                    d += a[s2 * w + j] * ndu[idx * w + pk];
                }
                if r <= pk {
                    a[s2 * w + kk] = -a[s1 * w + kk - 1] / ndu[(pk + 1) * w + r];
                    d += a[s2 * w + kk] * ndu[r * w + pk];
                }
                out[kk * w + r] = d;
                std::mem::swap(&mut s1, &mut s2);
            }
        }
        let mut factor = p as f64;
        for kk in 1..=top {
            for j in 0..=p {
                out[kk * w + j] *= factor;
            }
            factor *= (p - kk) as f64;
        }
        for kk in top + 1..=n {
            out[kk * w..(kk + 1) * w].fill(0.0);
        }
    }

    /// [`BSplineBasis::values_into`] with stack buffers of capacity `CAP` (needs `p < CAP`):
    /// the same operations in the same order, so bit-identical results, without scratch space.
    /// With `CAP = p + 1` known at compile time the loops unroll completely.
    #[inline(always)]
    pub(crate) fn values_stack<const CAP: usize>(&self, span: usize, u: f64) -> [f64; CAP] {
        let p = self.degree();
        debug_assert!(p < CAP);
        // The 2p knots u_{span+1−p} … u_{span+p} that A2.2 reads.
        let k = &self.knots.knots()[span + 1 - p..span + 1 + p];
        let mut out = [0.0; CAP];
        let mut left = [0.0; CAP];
        let mut right = [0.0; CAP];
        out[0] = 1.0;
        for j in 1..=p {
            left[j] = u - k[p - j];
            right[j] = k[p - 1 + j] - u;
            let mut saved = 0.0;
            for r in 0..j {
                let temp = out[r] / (right[r + 1] + left[j - r]);
                out[r] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            out[j] = saved;
        }
        out
    }

    /// Convenience: span and values at `u`, with the parameter checked against the domain.
    pub fn values(&self, u: f64) -> Result<(usize, Vec<f64>), GeomError> {
        self.knots.check_parameter("u", u)?;
        let span = self.find_span(u);
        let mut out = vec![0.0; self.degree() + 1];
        self.values_into(span, u, &mut out, &mut BasisScratch::default());
        Ok((span, out))
    }

    /// Convenience: span and derivatives up to order `n` at `u` (row-major, see
    /// [`BSplineBasis::derivatives_into`]), with the parameter checked.
    pub fn derivatives(&self, u: f64, n: usize) -> Result<(usize, Vec<f64>), GeomError> {
        self.knots.check_parameter("u", u)?;
        let span = self.find_span(u);
        let mut out = vec![0.0; (n + 1) * (self.degree() + 1)];
        self.derivatives_into(span, u, n, &mut out, &mut BasisScratch::default());
        Ok((span, out))
    }

    /// All `len()` function values at `u` (zeros outside the support), for tests and
    /// small problems.
    pub fn all_values(&self, u: f64) -> Result<Vec<f64>, GeomError> {
        let (span, local) = self.values(u)?;
        let mut out = vec![0.0; self.len()];
        let p = self.degree();
        out[span - p..=span].copy_from_slice(&local);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ex23() -> BSplineBasis {
        BSplineBasis::new(
            KnotVector::try_new(vec![0., 0., 0., 1., 2., 3., 4., 4., 5., 5., 5.], 2).unwrap(),
        )
    }

    /// The NURBS Book, Ex. 2.3: at u = 5/2, N_{2,2} = 1/8, N_{3,2} = 6/8, N_{4,2} = 1/8.
    #[test]
    fn nurbs_book_example_2_3() {
        let (span, n) = ex23().values(2.5).unwrap();
        assert_eq!(span, 4);
        let expected = [1. / 8., 6. / 8., 1. / 8.];
        for (a, b) in n.iter().zip(expected) {
            assert!((a - b).abs() < 1e-15);
        }
    }

    /// The NURBS Book, Ex. 2.4: derivatives at u = 5/2: N'_{2,2} = −1/2, N'_{3,2} = 0,
    /// N'_{4,2} = 1/2; second derivatives 1, −2, 1.
    #[test]
    fn nurbs_book_example_2_4() {
        let (span, d) = ex23().derivatives(2.5, 3).unwrap();
        assert_eq!(span, 4);
        let first = [-0.5, 0.0, 0.5];
        let second = [1.0, -2.0, 1.0];
        for j in 0..3 {
            assert!((d[3 + j] - first[j]).abs() < 1e-14, "{:?}", &d[3..6]);
            assert!((d[6 + j] - second[j]).abs() < 1e-14, "{:?}", &d[6..9]);
            assert_eq!(d[9 + j], 0.0);
        }
    }

    #[test]
    fn derivative_row_zero_equals_values() {
        let b = ex23();
        let mut scratch = BasisScratch::default();
        for i in 0..=50 {
            let u = 5.0 * i as f64 / 50.0;
            let span = b.find_span(u);
            let mut v = [0.0; 3];
            let mut d = [0.0; 9];
            b.values_into(span, u, &mut v, &mut scratch);
            b.derivatives_into(span, u, 2, &mut d, &mut scratch);
            for j in 0..3 {
                assert!((v[j] - d[j]).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn end_of_domain_uses_last_span() {
        let all = ex23().all_values(5.0).unwrap();
        assert_eq!(all.last(), Some(&1.0));
        assert!(all[..all.len() - 1].iter().all(|&x| x == 0.0));
    }

    #[test]
    fn outside_domain_is_an_error() {
        assert!(matches!(
            ex23().values(5.5),
            Err(GeomError::ParameterOutOfDomain { .. })
        ));
        assert!(ex23().values(f64::NAN).is_err());
    }
}
