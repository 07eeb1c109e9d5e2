//! Side-by-side validation of two trajectories (the paper's Figure 3): errors, amplitude and
//! dominant periods.

use serde::Serialize;

/// A modal run on the lowest modes of a large system (docs/math.md §8.6).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModalTruncation {
    /// Modes followed.
    pub modes: usize,
    /// Modes of the system (its unknowns).
    pub unknowns: usize,
    /// The share of the motion in the modes left out: the time-RMS M-norm of their
    /// oscillation over that of every mode's ([`crate::ModalBasis::left_out`]); absent when
    /// it cannot be computed (rigid modes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub left_out: Option<f64>,
}

/// Sampled positions of the probe points over time.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Trajectory {
    /// Sample times.
    pub t: Vec<f64>,
    /// `probes[p][s]`: position of probe `p` at sample `s`.
    pub probes: Vec<Vec<[f64; 3]>>,
    /// `[kinetic, elastic, external]` energy at each sample: the elastic energy excludes the
    /// load, `external` is the load's potential; their sum is the total energy.
    pub energy: Vec<[f64; 3]>,
    /// Set when the run stopped early (diverged, unstable or cancelled), with the reason.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// Steps of an implicit integrator taken in halves after Newton failed on them.
    pub halved_steps: usize,
    /// Set when the run followed a truncated modal basis: how many modes, and the share of
    /// the motion left out.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truncation: Option<ModalTruncation>,
}

impl Trajectory {
    /// An empty trajectory for `n_probes` probes.
    pub fn new(n_probes: usize) -> Self {
        Self {
            t: Vec::new(),
            probes: vec![Vec::new(); n_probes],
            energy: Vec::new(),
            stopped: None,
            halved_steps: 0,
            truncation: None,
        }
    }

    /// Component `axis` (0 = x, 1 = y, 2 = z) of probe `p` over time.
    pub fn component(&self, p: usize, axis: usize) -> Vec<f64> {
        self.probes[p].iter().map(|x| x[axis]).collect()
    }
}

/// `max_t |E(t) − E(0)| / max_t (kinetic + elastic)` of the total energy `E = kinetic +
/// elastic + external` of `traj` (`None` when it recorded no energies; 0 for a model that
/// never moves).
pub fn energy_drift(traj: &Trajectory) -> Option<f64> {
    let total = |e: &[f64; 3]| e[0] + e[1] + e[2];
    let e0 = total(traj.energy.first()?);
    let scale = traj
        .energy
        .iter()
        .map(|e| e[0] + e[1])
        .fold(0.0_f64, f64::max);
    let change = traj
        .energy
        .iter()
        .map(|e| (total(e) - e0).abs())
        .fold(0.0_f64, f64::max);
    Some(if scale > 0.0 { change / scale } else { change })
}

/// Errors between a reference series and another, sampled at the same times.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// Samples compared (the shorter series sets it).
    pub samples: usize,
    /// `√(mean (a − b)²)`.
    pub rms: f64,
    /// `max |a − b|`.
    pub max_abs: f64,
    /// Peak-to-peak amplitude of the reference about its initial value, `max |a − a₀|`.
    pub reference_amplitude: f64,
    /// `rms / reference_amplitude`.
    pub relative_rms: f64,
    /// Dominant period of the reference (mean spacing of its upward mean crossings).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_period: Option<f64>,
    /// Dominant period of the other series.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub other_period: Option<f64>,
}

/// Compares `other` against `reference` (same sample times `t`; the shorter length is used).
/// Non-finite samples of `other` make every error infinite.
pub fn compare(t: &[f64], reference: &[f64], other: &[f64]) -> Comparison {
    let n = t.len().min(reference.len()).min(other.len());
    let mut sum = 0.0;
    let mut max_abs: f64 = 0.0;
    for s in 0..n {
        let d = reference[s] - other[s];
        if !d.is_finite() {
            sum = f64::INFINITY;
            max_abs = f64::INFINITY;
            break;
        }
        sum += d * d;
        max_abs = max_abs.max(d.abs());
    }
    let rms = if n == 0 {
        f64::NAN
    } else {
        (sum / n as f64).sqrt()
    };
    let a0 = reference.first().copied().unwrap_or(0.0);
    let amplitude = reference[..n]
        .iter()
        .map(|a| (a - a0).abs())
        .fold(0.0, f64::max);
    Comparison {
        samples: n,
        rms,
        max_abs,
        reference_amplitude: amplitude,
        relative_rms: if amplitude > 0.0 {
            rms / amplitude
        } else if rms == 0.0 {
            // Both still: they agree exactly.
            0.0
        } else {
            f64::NAN
        },
        reference_period: dominant_period(&t[..n], &reference[..n]),
        other_period: dominant_period(&t[..n], &other[..n]),
    }
}

/// Dominant period of a sampled signal: the mean spacing between its upward crossings of its
/// mean value (linear interpolation between samples). None with fewer than two crossings.
///
/// ```
/// let t: Vec<f64> = (0..2000).map(|i| i as f64 * 0.01).collect();
/// let z: Vec<f64> = t.iter().map(|t| (2.0 * std::f64::consts::PI * t / 1.7).sin()).collect();
/// let p = nurbspring_derive::dominant_period(&t, &z).unwrap();
/// assert!((p - 1.7).abs() < 1e-3);
/// ```
pub fn dominant_period(t: &[f64], z: &[f64]) -> Option<f64> {
    let n = t.len().min(z.len());
    if n < 3 || z[..n].iter().any(|x| !x.is_finite()) {
        return None;
    }
    let mean = z[..n].iter().sum::<f64>() / n as f64;
    let spread = z[..n].iter().map(|x| (x - mean).abs()).fold(0.0, f64::max);
    if spread <= 1e-14 * mean.abs().max(1.0) {
        return None;
    }
    let mut crossings = Vec::new();
    for s in 1..n {
        let (a, b) = (z[s - 1] - mean, z[s] - mean);
        if a < 0.0 && b >= 0.0 {
            let f = a / (a - b);
            crossings.push(t[s - 1] + f * (t[s] - t[s - 1]));
        }
    }
    if crossings.len() < 2 {
        return None;
    }
    Some((crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine of period √3 s around a mean of 5 (amplitude 1), sampled every 0.05 s (so each
    /// crossing falls elsewhere between samples) for about 20 periods: the upward crossings, interpolated linearly, are spaced by the period to
    /// within the interpolation error, O((ω Δt)³) of a sample at a crossing; a sine of
    /// amplitude 10⁻³ around the same mean is still a signal.
    #[test]
    fn dominant_period_of_a_small_sine_on_a_large_mean() {
        let period = 3f64.sqrt();
        let t: Vec<f64> = (0..=680).map(|i| i as f64 * 0.05).collect();
        let z: Vec<f64> = t
            .iter()
            .map(|t| 5.0 + (2.0 * std::f64::consts::PI * t / period + 0.3).sin())
            .collect();
        let p = dominant_period(&t, &z).unwrap();
        assert!((p - period).abs() < 1e-5, "{p}");
        let small: Vec<f64> = z.iter().map(|x| 5.0 + 1e-3 * (x - 5.0)).collect();
        let p = dominant_period(&t, &small).unwrap();
        assert!((p - period).abs() < 1e-5, "{p}");
        // A constant has none, nor does a series with a NaN.
        assert_eq!(dominant_period(&t, &vec![5.0; t.len()]), None);
        let mut nan = z.clone();
        nan[3] = f64::NAN;
        assert_eq!(dominant_period(&t, &nan), None);
    }

    /// Totals 1, 1, 0.9 (with a load potential) over a largest kinetic + elastic of 1.25: a
    /// drift of 0.1 / 1.25; no energies, none; a model at rest, 0.
    #[test]
    fn energy_drift_is_relative_to_the_largest_kinetic_and_elastic_energy() {
        let mut traj = Trajectory::new(0);
        assert_eq!(energy_drift(&traj), None);
        traj.energy = vec![[1.0, 0.0, 0.0], [0.75, 0.5, -0.25], [0.0, 1.1, -0.2]];
        let d = energy_drift(&traj).unwrap();
        assert!((d - 0.08).abs() < 1e-15, "{d}");
        traj.energy = vec![[0.0; 3]; 4];
        assert_eq!(energy_drift(&traj), Some(0.0));
    }

    #[test]
    fn identical_series_have_zero_error() {
        let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        let z: Vec<f64> = t.iter().map(|t| t.sin()).collect();
        let c = compare(&t, &z, &z);
        assert_eq!(c.rms, 0.0);
        assert_eq!(c.max_abs, 0.0);
        assert!(c.reference_amplitude > 0.9);
    }

    #[test]
    fn constant_offset_gives_that_rms() {
        let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.1).collect();
        let a: Vec<f64> = t.iter().map(|t| t.sin()).collect();
        let b: Vec<f64> = a.iter().map(|x| x + 0.25).collect();
        let c = compare(&t, &a, &b);
        assert!((c.rms - 0.25).abs() < 1e-15);
        assert!((c.max_abs - 0.25).abs() < 1e-15);
    }

    #[test]
    fn non_finite_is_infinite_error() {
        let t = [0.0, 1.0, 2.0];
        let c = compare(&t, &[0.0, 1.0, 0.0], &[0.0, f64::NAN, 0.0]);
        assert!(c.rms.is_infinite());
    }
}

/// Compares two sampled point trajectories in 3-D (same times; the shorter length is used):
/// `rms = √(mean |a − b|²)`, `max_abs = max |a − b|`, amplitude `max |a − a₀|`, relative RMS
/// their ratio; periods of the coordinate in which the reference moves most. Non-finite
/// samples of `other` make every error infinite.
pub fn compare_points(t: &[f64], reference: &[[f64; 3]], other: &[[f64; 3]]) -> Comparison {
    let n = t.len().min(reference.len()).min(other.len());
    let (mut sum, mut max_abs) = (0.0, 0.0_f64);
    for s in 0..n {
        let d2: f64 = (0..3)
            .map(|x| (reference[s][x] - other[s][x]).powi(2))
            .sum();
        if !d2.is_finite() {
            sum = f64::INFINITY;
            max_abs = f64::INFINITY;
            break;
        }
        sum += d2;
        max_abs = max_abs.max(d2.sqrt());
    }
    let rms = if n == 0 {
        f64::NAN
    } else {
        (sum / n as f64).sqrt()
    };
    let a0 = reference.first().copied().unwrap_or([0.0; 3]);
    let amplitude = reference[..n]
        .iter()
        .map(|a| ((a[0] - a0[0]).powi(2) + (a[1] - a0[1]).powi(2) + (a[2] - a0[2]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    let axis = (0..3)
        .max_by(|&x, &y| {
            let span = |c: usize| {
                reference[..n]
                    .iter()
                    .map(|a| (a[c] - a0[c]).abs())
                    .fold(0.0, f64::max)
            };
            span(x).total_cmp(&span(y))
        })
        .unwrap_or(2);
    let column = |v: &[[f64; 3]]| -> Vec<f64> { v[..n].iter().map(|p| p[axis]).collect() };
    Comparison {
        samples: n,
        rms,
        max_abs,
        reference_amplitude: amplitude,
        relative_rms: if amplitude > 0.0 {
            rms / amplitude
        } else if rms == 0.0 {
            // Both still: they agree exactly.
            0.0
        } else {
            f64::NAN
        },
        reference_period: dominant_period(&t[..n], &column(reference)),
        other_period: dominant_period(&t[..n], &column(other)),
    }
}

/// The modal assurance criterion `(aᵀb)² / ((aᵀa)(bᵀb))` of two mode shapes (1: the same
/// shape up to scale, 0: orthogonal).
pub fn mac(a: &[f64], b: &[f64]) -> f64 {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let (ab, aa, bb) = (dot(a, b), dot(a, a), dot(b, b));
    if aa > 0.0 && bb > 0.0 {
        ab * ab / (aa * bb)
    } else {
        0.0
    }
}

/// Frequencies within this relative distance are one repeated frequency for the matching
/// of modes: its shapes are any rotation of one subspace.
pub const REPEATED_FREQUENCY: f64 = 1e-6;

/// The candidate matched to each reference mode by MAC, and that MAC: `reference` are the
/// shapes of the reference modes with their frequencies `omega` (ascending), `candidates` the
/// shapes of the other model's modes (ascending). A repeated frequency (within
/// [`REPEATED_FREQUENCY`]) is matched as a subspace: a candidate's MAC with it is
/// `|Qᵀψ|²/|ψ|²`, Q an orthonormal basis of the repeated modes' shapes (the plain MAC for a
/// single mode), and the repeated modes take that many candidates, in frequency order.
/// Pairs are taken greedily, the largest MAC first; a reference left without a candidate
/// (fewer candidates than references) gets none.
///
/// ```
/// use nurbspring_derive::match_modes;
/// // A repeated pair spanned by e1, e2 and a single mode e3; the candidates come as
/// // (e3, a rotation of the pair, the other rotation).
/// let s = std::f64::consts::FRAC_1_SQRT_2;
/// let reference = vec![vec![1.0, 0.0, 0.0], vec![0.0, 1.0, 0.0], vec![0.0, 0.0, 1.0]];
/// let candidates = vec![vec![0.0, 0.0, 1.0], vec![s, s, 0.0], vec![s, -s, 0.0]];
/// let m = match_modes(&reference, &[1.0, 1.0, 2.0], &candidates);
/// assert_eq!(m[2], Some((0, 1.0)));
/// let (a, b) = (m[0].unwrap(), m[1].unwrap());
/// assert_eq!((a.0, b.0), (1, 2));
/// assert!((a.1 - 1.0).abs() < 1e-15 && (b.1 - 1.0).abs() < 1e-15);
/// ```
pub fn match_modes(
    reference: &[Vec<f64>],
    omega: &[f64],
    candidates: &[Vec<f64>],
) -> Vec<Option<(usize, f64)>> {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    // Clusters of repeated frequencies, each with an orthonormal basis of its shapes.
    let mut clusters: Vec<(Vec<usize>, Vec<Vec<f64>>)> = Vec::new();
    for (i, shape) in reference.iter().enumerate() {
        let repeated = clusters.last().is_some_and(|(members, _)| {
            let w = omega[members[0]];
            (omega[i] - w).abs() <= REPEATED_FREQUENCY * omega[i].abs().max(w.abs())
        });
        if !repeated {
            clusters.push((Vec::new(), Vec::new()));
        }
        let (members, basis) = clusters.last_mut().expect("a cluster was pushed");
        members.push(i);
        // Gram–Schmidt, twice for round-off.
        let mut v = shape.clone();
        for _ in 0..2 {
            for q in basis.iter() {
                let c = dot(&v, q);
                v.iter_mut().zip(q).for_each(|(a, b)| *a -= c * b);
            }
        }
        let norm = dot(&v, &v).sqrt();
        if norm > 1e-12 * dot(shape, shape).sqrt() {
            basis.push(v.iter().map(|a| a / norm).collect());
        }
    }
    let mut score: Vec<(f64, usize, usize)> = Vec::new();
    for (c, (_, basis)) in clusters.iter().enumerate() {
        for (j, psi) in candidates.iter().enumerate() {
            let nn = dot(psi, psi);
            let m = if nn > 0.0 {
                basis.iter().map(|q| dot(q, psi).powi(2)).sum::<f64>() / nn
            } else {
                0.0
            };
            score.push((m, c, j));
        }
    }
    score.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.2.cmp(&b.2)));
    let mut taken = vec![false; candidates.len()];
    let mut chosen: Vec<Vec<(usize, f64)>> = vec![Vec::new(); clusters.len()];
    for (m, c, j) in score {
        if !taken[j] && chosen[c].len() < clusters[c].0.len() {
            taken[j] = true;
            chosen[c].push((j, m));
        }
    }
    let mut out = vec![None; reference.len()];
    for ((members, _), mut picks) in clusters.into_iter().zip(chosen) {
        picks.sort_by_key(|p| p.0);
        for (i, pick) in members.into_iter().zip(picks) {
            out[i] = Some(pick);
        }
    }
    out
}

#[cfg(test)]
mod point_tests {
    use super::*;

    #[test]
    fn points_compare_in_three_dimensions() {
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.05).collect();
        let a: Vec<[f64; 3]> = t.iter().map(|t| [t.sin(), 0.0, 2.0]).collect();
        // Off by 0.3 along y and 0.4 along z: |d| = 0.5 at every sample.
        let b: Vec<[f64; 3]> = a.iter().map(|p| [p[0], 0.3, p[2] + 0.4]).collect();
        let c = compare_points(&t, &a, &b);
        assert!((c.rms - 0.5).abs() < 1e-15 && (c.max_abs - 0.5).abs() < 1e-15);
        assert!((c.reference_amplitude - 1.0).abs() < 1e-3);
        assert!(
            c.reference_period
                .is_some_and(|p| (p - 2.0 * std::f64::consts::PI).abs() < 0.05)
        );
        assert_eq!(mac(&[1.0, 2.0], &[-2.0, -4.0]), 1.0);
        assert_eq!(mac(&[1.0, 0.0], &[0.0, 3.0]), 0.0);
    }

    /// A constant of 10⁶ with round-off flutter (10⁻¹⁰, below 10⁻¹⁴ of the mean) has no
    /// period; the same flutter on a mean of 0.5 (above 10⁻¹⁴) is a signal.
    #[test]
    fn round_off_on_a_large_constant_is_no_period() {
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
        let flutter = |mean: f64| -> Vec<f64> {
            t.iter()
                .map(|t| mean + 1e-10 * (2.0 * std::f64::consts::PI * t / 0.3).sin())
                .collect()
        };
        assert_eq!(dominant_period(&t, &flutter(1e6)), None);
        let p = dominant_period(&t, &flutter(0.5)).unwrap();
        assert!((p - 0.3).abs() < 0.01, "{p}");
    }

    /// Samples exactly at the mean: `… −1, 0, 1, 0, −1 …` (period 4 samples) crosses upward
    /// once a period, at the 0 between −1 and 1, not again at the 1 after it.
    #[test]
    fn a_sample_on_the_mean_is_one_crossing() {
        // Ten whole periods, so that the mean is exactly 0.
        let t: Vec<f64> = (0..40).map(|i| i as f64).collect();
        let z: Vec<f64> = (0..40).map(|i| [-1.0, 0.0, 1.0, 0.0][i % 4]).collect();
        assert_eq!(dominant_period(&t, &z), Some(4.0));
    }

    /// With a reference that does not move, the relative RMS is undefined (NaN), whatever the
    /// other does.
    #[test]
    fn a_still_reference_has_no_relative_error() {
        let t = [0.0, 1.0, 2.0];
        let still = [[1.0, 2.0, 3.0]; 3];
        let moving = [[1.0, 2.0, 3.0], [1.0, 2.0, 4.0], [1.0, 2.0, 3.0]];
        let c = compare_points(&t, &still, &moving);
        assert!(c.relative_rms.is_nan() && c.rms > 0.0, "{c:?}");
        assert_eq!(c.reference_amplitude, 0.0);
        // A reference moving along y alone: its amplitude is that motion, |Δy| = 0.75.
        let along_y = [[1.0, 2.0, 3.0], [1.0, 2.75, 3.0], [1.0, 2.5, 3.0]];
        let c = compare_points(&t, &along_y, &still);
        assert_eq!(c.reference_amplitude, 0.75);
    }

    /// A period that is no multiple of the sampling step (0.737 s sampled every 0.01 s over
    /// 20 periods): the crossings are interpolated between samples, so the period comes out
    /// to the interpolation error, far below the step.
    #[test]
    fn a_period_between_samples_is_interpolated() {
        let t: Vec<f64> = (0..1500).map(|i| i as f64 * 0.01).collect();
        let z: Vec<f64> = t
            .iter()
            .map(|t| (2.0 * std::f64::consts::PI * t / 0.737 + 0.1).sin())
            .collect();
        let p = dominant_period(&t, &z).unwrap();
        assert!((p - 0.737).abs() < 1e-4, "{p}");
    }

    /// The MAC of a zero shape with any shape is 0 (no shape to compare), not 0/0.
    #[test]
    fn mac_with_a_zero_shape_is_zero() {
        assert_eq!(mac(&[0.0, 0.0], &[1.0, 2.0]), 0.0);
        assert_eq!(mac(&[1.0, 2.0], &[0.0, 0.0]), 0.0);
        assert_eq!(mac(&[3.0, 4.0], &[6.0, 8.0]), 1.0);
    }
}
