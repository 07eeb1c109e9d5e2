//! Unit tests of `model`.

use super::anderson;

/// On a linear map `G(q) = A q + b` the Anderson update is exact once the differences of
/// the history span the space: with `F = G − q` affine, the combination with `F = 0` is the
/// fixed point `q* = (I − A)⁻¹ b`. Here n = 2, three iterates, by hand:
/// `A = [[0.5, 0.2], [−0.1, 0.3]]`, `b = (1, 2)`.
#[test]
fn anderson_finds_the_fixed_point_of_a_linear_map_from_three_iterates() {
    let g = |q: &[f64]| {
        vec![
            0.5 * q[0] + 0.2 * q[1] + 1.0,
            -0.1 * q[0] + 0.3 * q[1] + 2.0,
        ]
    };
    // (I − A) q* = b: [[0.5, −0.2], [0.1, 0.7]] q* = (1, 2), det = 0.37.
    let fixed = [
        (0.7 * 1.0 + 0.2 * 2.0) / 0.37,
        (0.5 * 2.0 - 0.1 * 1.0) / 0.37,
    ];
    let history: Vec<(Vec<f64>, Vec<f64>)> = [[0.0, 0.0], [1.0, -1.0], [3.0, 0.5]]
        .iter()
        .map(|q| {
            let gq = g(q);
            let f = vec![gq[0] - q[0], gq[1] - q[1]];
            (gq, f)
        })
        .collect();
    let next = anderson(&history).unwrap();
    for i in 0..2 {
        assert!((next[i] - fixed[i]).abs() <= 1e-13, "{next:?} vs {fixed:?}");
    }
    // One entry has no differences: no update.
    assert!(anderson(&history[..1]).is_none());
}
