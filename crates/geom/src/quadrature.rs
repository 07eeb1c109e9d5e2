//! Gauss–Legendre quadrature: rules of any order (computed by Newton iteration on the Legendre
//! polynomial, not read from a table) and tensor-product rules over the non-empty knot spans.

use crate::{BSplineBasis, GeomError};

/// An n-point Gauss–Legendre rule on `[-1, 1]`, exact for polynomials of degree `2n − 1`.
///
/// Nodes are the roots of the Legendre polynomial `P_n`, found by Newton's method from the
/// Tricomi initial guess `cos(π (i − 1/4) / (n + 1/2))`; weights are `2 / ((1 − x²) P_n'(x)²)`
/// (Abramowitz & Stegun 25.4.29).
///
/// ```
/// use nurbspring_geom::GaussLegendre;
/// let rule = GaussLegendre::new(3).unwrap();
/// // ∫_{-1}^{1} x⁴ dx = 2/5, exact for 3 points (degree ≤ 5).
/// let integral: f64 = rule.nodes().iter().zip(rule.weights()).map(|(x, w)| w * x.powi(4)).sum();
/// assert!((integral - 0.4).abs() < 1e-15);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// The `n`-point rule, nodes ascending.
    pub fn new(n: usize) -> Result<Self, GeomError> {
        if n == 0 {
            return Err(GeomError::InvalidQuadrature { points: 0 });
        }
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for i in 0..n.div_ceil(2) {
            // Root i counted from the right end (x near 1).
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut derivative = 0.0;
            for _ in 0..100 {
                let (p, dp) = legendre_with_derivative(n, x);
                derivative = dp;
                let dx = p / dp;
                x -= dx;
                if dx.abs() <= 1e-16 * x.abs().max(1.0) {
                    let (_, dp) = legendre_with_derivative(n, x);
                    derivative = dp;
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
            nodes[n - 1 - i] = x;
            nodes[i] = -x;
            weights[n - 1 - i] = w;
            weights[i] = w;
        }
        if n % 2 == 1 {
            nodes[n / 2] = 0.0;
        }
        Ok(Self { nodes, weights })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false: a rule has at least one point.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Nodes on `[-1, 1]`, ascending.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Weights on `[-1, 1]` (they sum to 2).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Nodes and weights mapped to `[a, b]`.
    pub fn mapped(&self, a: f64, b: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(move |(x, w)| (mid + half * x, half * w))
    }
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre_with_derivative(n: usize, x: f64) -> (f64, f64) {
    let mut p0 = 1.0;
    let mut p1 = x;
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let nf = n as f64;
    // P_n'(x) = n (x P_n − P_{n−1}) / (x² − 1), valid away from ±1 (roots are interior).
    let dp = nf * (x * p1 - p0) / (x * x - 1.0);
    (p1, dp)
}

/// One quadrature point of a rule over a parameter domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadraturePoint {
    /// Parameter u.
    pub u: f64,
    /// Parameter v (0 for curves).
    pub v: f64,
    /// Weight (includes the Jacobian of the map from `[-1, 1]`).
    pub weight: f64,
}

/// A tensor-product knot span `[u_i, u_{i+1}) × [v_j, v_{j+1})` (an element) with its points.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadratureElement {
    /// Knot span index in u.
    pub span_u: usize,
    /// Knot span index in v (0 for curves).
    pub span_v: usize,
    /// Points and weights inside the element.
    pub points: Vec<QuadraturePoint>,
}

/// Gauss–Legendre rule with `g` points per direction on every non-empty knot span of a
/// surface's bases, grouped by element (the unit of assembly).
pub fn surface_rule(
    basis_u: &BSplineBasis,
    basis_v: &BSplineBasis,
    g: usize,
) -> Result<Vec<QuadratureElement>, GeomError> {
    let rule = GaussLegendre::new(g)?;
    let spans_u = basis_u.knots().nonempty_spans();
    let spans_v = basis_v.knots().nonempty_spans();
    let mut elements = Vec::with_capacity(spans_u.len() * spans_v.len());
    for &(su, ua, ub) in &spans_u {
        for &(sv, va, vb) in &spans_v {
            let mut points = Vec::with_capacity(g * g);
            for (u, wu) in rule.mapped(ua, ub) {
                for (v, wv) in rule.mapped(va, vb) {
                    points.push(QuadraturePoint {
                        u,
                        v,
                        weight: wu * wv,
                    });
                }
            }
            elements.push(QuadratureElement {
                span_u: su,
                span_v: sv,
                points,
            });
        }
    }
    Ok(elements)
}

/// Gauss–Legendre rule with `g` points on every non-empty knot span of a curve's basis.
pub fn curve_rule(basis: &BSplineBasis, g: usize) -> Result<Vec<QuadratureElement>, GeomError> {
    let rule = GaussLegendre::new(g)?;
    Ok(basis
        .knots()
        .nonempty_spans()
        .into_iter()
        .map(|(s, a, b)| QuadratureElement {
            span_u: s,
            span_v: 0,
            points: rule
                .mapped(a, b)
                .map(|(u, weight)| QuadraturePoint { u, v: 0.0, weight })
                .collect(),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_for_degree_2n_minus_1() {
        for n in 1..=40 {
            let rule = GaussLegendre::new(n).unwrap();
            for deg in 0..2 * n {
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                let got: f64 = rule
                    .nodes()
                    .iter()
                    .zip(rule.weights())
                    .map(|(x, w)| w * x.powi(deg as i32))
                    .sum();
                assert!(
                    (got - exact).abs() < 5e-15 * (n as f64),
                    "n={n} deg={deg} got={got} exact={exact}"
                );
            }
        }
    }

    #[test]
    fn not_exact_for_degree_2n() {
        let rule = GaussLegendre::new(3).unwrap();
        let got: f64 = rule
            .nodes()
            .iter()
            .zip(rule.weights())
            .map(|(x, w)| w * x.powi(6))
            .sum();
        assert!((got - 2.0 / 7.0).abs() > 1e-3);
    }

    #[test]
    fn known_two_point_rule() {
        let rule = GaussLegendre::new(2).unwrap();
        let x = 1.0 / 3f64.sqrt();
        assert!(
            (rule.nodes()[0] + x).abs() < 2.0 * f64::EPSILON,
            "{}",
            rule.nodes()[0] + x
        );
        assert!((rule.nodes()[1] - x).abs() < 2.0 * f64::EPSILON);
        assert!((rule.weights()[0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn zero_points_is_an_error() {
        assert_eq!(
            GaussLegendre::new(0),
            Err(GeomError::InvalidQuadrature { points: 0 })
        );
    }
}
