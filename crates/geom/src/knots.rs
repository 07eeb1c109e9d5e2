//! Knot vectors (The NURBS Book, §2.2).

use crate::GeomError;

/// A validated knot vector `U = (u_0, …, u_{n+p+1})` of degree `p`: finite, non-decreasing, no
/// value repeated more than `p + 1` times, with a non-empty domain `[u_p, u_{n+1}]`.
///
/// ```
/// use nurbspring_geom::KnotVector;
/// let kv = KnotVector::try_new(vec![0., 0., 0., 0.5, 1., 1., 1.], 2).unwrap();
/// assert_eq!(kv.n_basis(), 4);
/// assert_eq!(kv.domain(), (0.0, 1.0));
/// assert_eq!(kv.distinct(), vec![0.0, 0.5, 1.0]);
/// assert_eq!(kv.greville(), vec![0.0, 0.25, 0.75, 1.0]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct KnotVector {
    knots: Vec<f64>,
    degree: usize,
}

impl KnotVector {
    /// Validates `knots` for degree `degree`.
    pub fn try_new(knots: Vec<f64>, degree: usize) -> Result<Self, GeomError> {
        if degree < 1 {
            return Err(GeomError::DegreeTooLow { degree });
        }
        let needed = 2 * (degree + 1);
        if knots.len() < needed {
            return Err(GeomError::TooFewKnots {
                degree,
                needed,
                found: knots.len(),
            });
        }
        for (index, &value) in knots.iter().enumerate() {
            if !value.is_finite() {
                return Err(GeomError::NonFiniteKnot { index, value });
            }
        }
        for i in 1..knots.len() {
            if knots[i] < knots[i - 1] {
                return Err(GeomError::DecreasingKnots {
                    index: i,
                    value: knots[i],
                    prev_index: i - 1,
                    prev: knots[i - 1],
                });
            }
        }
        let mut i = 0;
        while i < knots.len() {
            let mut j = i;
            while j < knots.len() && knots[j] == knots[i] {
                j += 1;
            }
            if j - i > degree + 1 {
                return Err(GeomError::MultiplicityTooHigh {
                    value: knots[i],
                    multiplicity: j - i,
                    max: degree + 1,
                });
            }
            i = j;
        }
        let n = knots.len() - degree - 2;
        let (start, end) = (knots[degree], knots[n + 1]);
        if start >= end {
            return Err(GeomError::EmptyDomain { start, end });
        }
        Ok(Self { knots, degree })
    }

    /// A clamped knot vector with `spans` uniform spans on `[0, 1]`.
    pub fn clamped_uniform(degree: usize, spans: usize) -> Result<Self, GeomError> {
        let spans = spans.max(1);
        let mut knots = vec![0.0; degree + 1];
        knots.extend((1..spans).map(|i| i as f64 / spans as f64));
        knots.extend(std::iter::repeat_n(1.0, degree + 1));
        Self::try_new(knots, degree)
    }

    /// The knots.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The degree p.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Number of basis functions (control points), `n + 1 = m + 1 − (p + 1)`.
    pub fn n_basis(&self) -> usize {
        self.knots.len() - self.degree - 1
    }

    /// The parameter domain `[u_p, u_{n+1}]`.
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.n_basis()])
    }

    /// True when the first p + 1 knots coincide.
    pub fn is_clamped_start(&self) -> bool {
        self.knots[..=self.degree]
            .iter()
            .all(|&k| k == self.knots[0])
    }

    /// True when the last p + 1 knots coincide.
    pub fn is_clamped_end(&self) -> bool {
        let m = self.knots.len();
        self.knots[m - self.degree - 1..]
            .iter()
            .all(|&k| k == self.knots[m - 1])
    }

    /// Whether `u` lies in the domain (closed interval).
    pub fn contains(&self, u: f64) -> bool {
        let (a, b) = self.domain();
        u.is_finite() && u >= a && u <= b
    }

    /// Checks that `u` is in the domain, naming the parameter in the error.
    pub fn check_parameter(&self, name: &'static str, u: f64) -> Result<(), GeomError> {
        if self.contains(u) {
            Ok(())
        } else {
            let (start, end) = self.domain();
            Err(GeomError::ParameterOutOfDomain {
                name,
                value: u,
                start,
                end,
            })
        }
    }

    /// The knot span index `i` with `u_i ≤ u < u_{i+1}` (The NURBS Book A2.1).
    /// Right-continuous at interior knots; at the end of the domain the last non-empty span.
    /// Parameters outside the domain are clamped to it (callers validate with
    /// [`KnotVector::check_parameter`]).
    ///
    /// With at most [`LINEAR_SPAN_SEARCH`] interior knots the span is counted without branches
    /// (`p` plus the number of knots `u_{p+1} … u_n` at or below `u`: they are a prefix, since the
    /// knots do not decrease), which avoids the mispredicted branches of bisection on scattered
    /// parameters; longer knot vectors are bisected. Both give the same span.
    pub fn find_span(&self, u: f64) -> usize {
        let p = self.degree;
        let n = self.n_basis() - 1;
        let k = &self.knots;
        if u >= k[n + 1] {
            // Last non-empty span: largest i ≤ n with k[i] < k[n+1].
            let mut i = n;
            while k[i] >= k[n + 1] {
                i -= 1;
            }
            return i;
        }
        if u <= k[p] {
            // First non-empty span: largest i with k[i] = k[p], i.e. k[i] ≤ u < k[i+1].
            let mut i = p;
            while k[i + 1] <= k[p] {
                i += 1;
            }
            return i;
        }
        if n - p <= LINEAR_SPAN_SEARCH {
            return p + k[p + 1..=n]
                .iter()
                .map(|&x| usize::from(x <= u))
                .sum::<usize>();
        }
        let (mut low, mut high) = (p, n + 1);
        let mut mid = (low + high) / 2;
        while u < k[mid] || u >= k[mid + 1] {
            if u < k[mid] {
                high = mid;
            } else {
                low = mid;
            }
            mid = (low + high) / 2;
        }
        mid
    }

    /// Multiplicity of the value `u` in the knot vector (0 if absent).
    pub fn multiplicity(&self, u: f64) -> usize {
        self.knots.iter().filter(|&&k| k == u).count()
    }

    /// Distinct knot values inside the domain, ascending.
    pub fn distinct(&self) -> Vec<f64> {
        let (a, b) = self.domain();
        let mut out: Vec<f64> = Vec::new();
        for &k in &self.knots {
            if k >= a && k <= b && out.last() != Some(&k) {
                out.push(k);
            }
        }
        out
    }

    /// Distinct knot values with their multiplicities (whole vector).
    pub fn distinct_with_multiplicity(&self) -> Vec<(f64, usize)> {
        let mut out: Vec<(f64, usize)> = Vec::new();
        for &k in &self.knots {
            match out.last_mut() {
                Some((v, m)) if *v == k => *m += 1,
                _ => out.push((k, 1)),
            }
        }
        out
    }

    /// Greville abscissae `ξ_i = (u_{i+1} + … + u_{i+p}) / p`, one per basis function.
    pub fn greville(&self) -> Vec<f64> {
        let p = self.degree;
        (0..self.n_basis())
            .map(|i| self.knots[i + 1..=i + p].iter().sum::<f64>() / p as f64)
            .collect()
    }

    /// The non-empty spans inside the domain: `(i, u_i, u_{i+1})` with `u_i < u_{i+1}`.
    pub fn nonempty_spans(&self) -> Vec<(usize, f64, f64)> {
        let p = self.degree;
        let n = self.n_basis() - 1;
        (p..=n)
            .filter(|&i| self.knots[i] < self.knots[i + 1])
            .map(|i| (i, self.knots[i], self.knots[i + 1]))
            .collect()
    }
}

/// Interior knot counts up to which [`KnotVector::find_span`] counts instead of bisecting.
pub const LINEAR_SPAN_SEARCH: usize = 16;

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A2.1 by definition: the largest `i ≤ n` with `u_i ≤ u` and `u_i < u_{i+1}`, clamped to
    /// the first and last non-empty spans.
    fn span_by_definition(kv: &KnotVector, u: f64) -> usize {
        let k = kv.knots();
        let (p, n) = (kv.degree(), kv.n_basis() - 1);
        let spans: Vec<usize> = (p..=n).filter(|&i| k[i] < k[i + 1]).collect();
        let u = u.clamp(k[p], k[n + 1]);
        spans
            .iter()
            .copied()
            .rfind(|&i| k[i] <= u)
            .unwrap_or(spans[0])
    }

    proptest! {
        /// Counting (short knot vectors) and bisection (long ones) both follow A2.1, at random
        /// parameters and exactly at (repeated) knots.
        #[test]
        fn find_span_follows_the_definition(
            p in 1usize..4,
            steps in prop::collection::vec(0u8..3, 1..40),
            ts in prop::collection::vec(-0.1f64..1.1, 1..20),
        ) {
            let mut k = vec![0.0; p + 1];
            let mut x = 0.0;
            for &s in &steps {
                x += f64::from(s);
                if k.iter().filter(|&&y| y == x).count() < p {
                    k.push(x);
                }
            }
            let end = x + 1.0;
            k.extend(std::iter::repeat_n(end, p + 1));
            let kv = KnotVector::try_new(k.clone(), p).unwrap();
            let mut us: Vec<f64> = ts.iter().map(|t| t * end).collect();
            us.extend(&k);
            for u in us {
                prop_assert_eq!(kv.find_span(u), span_by_definition(&kv, u), "u = {}", u);
            }
        }
    }

    #[test]
    fn validation_errors() {
        assert!(matches!(
            KnotVector::try_new(vec![0., 0., 1., 1.], 0),
            Err(GeomError::DegreeTooLow { degree: 0 })
        ));
        assert!(matches!(
            KnotVector::try_new(vec![0., 0., 1.], 1),
            Err(GeomError::TooFewKnots { .. })
        ));
        assert!(matches!(
            KnotVector::try_new(vec![0., 0., 0.5, 0.25, 1., 1.], 1),
            Err(GeomError::DecreasingKnots { index: 3, .. })
        ));
        assert!(matches!(
            KnotVector::try_new(vec![0., 0., 0.5, 0.5, 0.5, 1., 1.], 1),
            Err(GeomError::MultiplicityTooHigh {
                multiplicity: 3,
                ..
            })
        ));
        assert!(matches!(
            KnotVector::try_new(vec![0., 0., f64::NAN, 1., 1.], 1),
            Err(GeomError::NonFiniteKnot { index: 2, .. })
        ));
        assert!(matches!(
            KnotVector::try_new(vec![0., 1., 1., 2.], 1),
            Err(GeomError::EmptyDomain { .. })
        ));
    }

    #[test]
    fn spans_follow_a2_1() {
        // The NURBS Book Ex. 2.3: U = {0,0,0,1,2,3,4,4,5,5,5}, p = 2, u = 5/2 → span 4.
        let kv = KnotVector::try_new(vec![0., 0., 0., 1., 2., 3., 4., 4., 5., 5., 5.], 2).unwrap();
        assert_eq!(kv.find_span(2.5), 4);
        assert_eq!(kv.find_span(0.0), 2);
        assert_eq!(kv.find_span(1.0), 3); // right-continuous
        assert_eq!(kv.find_span(4.0), 7); // after the double knot
        assert_eq!(kv.find_span(5.0), 7); // last non-empty span
        assert_eq!(kv.multiplicity(4.0), 2);
        assert!(kv.is_clamped_start() && kv.is_clamped_end());
        assert_eq!(kv.nonempty_spans().len(), 5);
    }

    #[test]
    fn unclamped_domain() {
        let kv = KnotVector::try_new((0..8).map(f64::from).collect(), 3).unwrap();
        assert_eq!(kv.domain(), (3.0, 4.0));
        assert!(!kv.is_clamped_start());
        assert_eq!(kv.find_span(3.0), 3);
        assert_eq!(kv.find_span(4.0), 3);
    }
}
