//! Pointwise formulas of a parametrization used above this crate: the cross product, the
//! area element `|c_u × c_v|` and the line element `|c_u|` of the area measure
//! (docs/math.md §3), and the quotient rule that turns the derivatives of a numerator and of
//! the weight function `W` into those of the rational basis (The NURBS Book eq. (4.8)–(4.10)).

/// `a × b`.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `|a|`.
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The area element `|c_u × c_v|` of a surface with tangents `c_u`, `c_v`.
#[inline]
pub fn area_element(c_u: [f64; 3], c_v: [f64; 3]) -> f64 {
    norm(cross(c_u, c_v))
}

/// The line element `|c_u|` of a curve with tangent `c_u`.
#[inline]
pub fn line_element(c_u: [f64; 3]) -> f64 {
    norm(c_u)
}

/// The quotient `q = n / W` and its derivatives up to `order` (0, 1 or 2) in the six slots
/// `[·, u, v, uu, uv, vv]` (a curve: the u slots, the others 0), from those of the numerator
/// `n` and of the denominator `w`, with `inv_w = 1 / W`; slots above `order` are 0:
///
/// `q_u = (n_u − q W_u) / W`, `q_uu = (n_uu − 2 q_u W_u − q W_uu) / W`,
/// `q_uv = (n_uv − q_u W_v − q_v W_u − q W_uv) / W`.
#[inline]
pub fn quotient_rule(n: &[f64; 6], w: &[f64; 6], inv_w: f64, order: usize) -> [f64; 6] {
    let mut q = [0.0; 6];
    q[0] = n[0] * inv_w;
    if order >= 1 {
        q[1] = (n[1] - q[0] * w[1]) * inv_w;
        q[2] = (n[2] - q[0] * w[2]) * inv_w;
    }
    if order >= 2 {
        q[3] = (n[3] - 2.0 * q[1] * w[1] - q[0] * w[3]) * inv_w;
        q[4] = (n[4] - q[1] * w[2] - q[2] * w[1] - q[0] * w[4]) * inv_w;
        q[5] = (n[5] - 2.0 * q[2] * w[2] - q[0] * w[5]) * inv_w;
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quotient rule against the derivatives of `n / W` for polynomials `n = u² v`,
    /// `W = 1 + u + v²` at (0.3, 0.7), in closed form.
    #[test]
    fn quotient_rule_matches_the_closed_form() {
        let (u, v) = (0.3, 0.7);
        let n = [u * u * v, 2.0 * u * v, u * u, 2.0 * v, 2.0 * u, 0.0];
        let big_w = [1.0 + u + v * v, 1.0, 2.0 * v, 0.0, 0.0, 2.0];
        let q = quotient_rule(&n, &big_w, 1.0 / big_w[0], 2);
        let w = big_w[0];
        let f = u * u * v;
        let expected = [
            f / w,
            2.0 * u * v / w - f / (w * w),
            u * u / w - f * 2.0 * v / (w * w),
            2.0 * v / w - 4.0 * u * v / (w * w) + 2.0 * f / (w * w * w),
            2.0 * u / w - 2.0 * u * v * 2.0 * v / (w * w) - u * u / (w * w)
                + 2.0 * f * 2.0 * v / (w * w * w),
            -2.0 * u * u * 2.0 * v / (w * w) - 2.0 * f / (w * w)
                + 2.0 * f * 4.0 * v * v / (w * w * w),
        ];
        for s in 0..6 {
            assert!(
                (q[s] - expected[s]).abs() < 1e-14,
                "{s}: {} vs {}",
                q[s],
                expected[s]
            );
        }
        assert_eq!(quotient_rule(&n, &big_w, 1.0 / w, 0)[1..], [0.0; 5]);
    }

    /// The area element of the unit square's tangents is 1, of a 2 × 3 parallelogram 6.
    #[test]
    fn area_element_is_the_parallelogram_area() {
        assert_eq!(area_element([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), 1.0);
        assert!((area_element([2.0, 0.0, 0.0], [1.0, 3.0, 0.0]) - 6.0).abs() < 1e-15);
        assert_eq!(line_element([3.0, 4.0, 0.0]), 5.0);
    }
}
