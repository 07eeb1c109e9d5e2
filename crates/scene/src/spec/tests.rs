//! Unit tests of `spec`.

use super::*;

/// Without `vtk_every` the frame count ⌈samples / n⌉ is at most 200, with the smallest n.
#[test]
fn default_frame_every_keeps_at_most_200_frames() {
    for (samples, every, frames) in [
        (0, 1, 0),
        (1, 1, 1),
        (200, 1, 200),
        (201, 2, 101),
        (2001, 11, 182),
        (40_001, 201, 200),
    ] {
        let n = default_frame_every(samples);
        assert_eq!(n, every, "{samples}");
        assert_eq!(samples.div_ceil(n), frames, "{samples}");
        assert!(
            n == 1 || samples.div_ceil(n - 1) > DEFAULT_MAX_FRAMES,
            "{samples}"
        );
    }
    let set = OutputSpec { vtk_every: Some(3) };
    assert_eq!(set.frame_every(2001), 3);
    assert_eq!(OutputSpec::default().frame_every(2001), 11);
}
