//! Linear resampling of a motion from one frame rate to another: the one place that decides
//! how many frames a stretch has at a new rate, where each new frame falls among the old ones,
//! and how two frames are blended.
//!
//! Frame `k` at `to_hz` lies at time `k / to_hz`, which is input position
//! `t = k · from_hz / to_hz`: between input frames `⌊t⌋` and `⌊t⌋ + 1`, a fraction `t − ⌊t⌋` of
//! the way. Positions are computed in `f64` (exact for any realistic length and rate), snapped
//! down onto an input frame within [`SNAP`], and never past the last frame. Rates within
//! [`SAME_RATE`] of each other are one rate (a 60.00006 Hz capture is a 60 Hz one): the frames
//! are then used as they are. The host's files (`posecoach-io`'s `Motion::resampled`) and the
//! device's coach reference (`adapters::session`) both go through here; the phone's pose
//! stream, whose frames arrive at irregular times, keeps its own time grid and blends with
//! [`lerp`].
//!
//! ```
//! use posecoach_core::resample::{frames, source};
//!
//! // 5 frames at 60 Hz are 3 at 30 Hz: input frames 0, 2 and 4.
//! assert_eq!(frames(5, 60.0, 30.0), 3);
//! assert_eq!(source(1, 60.0, 30.0, 5), (2, 0.0));
//! // At 40 Hz, frame 1 falls halfway between input frames 1 and 2.
//! assert_eq!(source(1, 60.0, 40.0, 5), (1, 0.5));
//! ```

use crate::frames::Frames;
use crate::Vec3;

/// Relative difference under which two frame rates are one.
pub const SAME_RATE: f32 = 1e-3;

/// Input positions within this of a frame are that frame (rounding in `k · from_hz / to_hz`).
pub const SNAP: f64 = 1e-9;

/// Whether `from_hz` and `to_hz` are one rate ([`SAME_RATE`]).
pub const fn same_rate(from_hz: f32, to_hz: f32) -> bool {
    let ratio = from_hz / to_hz;
    ratio > 1.0 - SAME_RATE && ratio < 1.0 + SAME_RATE
}

/// Frames a stretch of `frames` frames at `from_hz` has at `to_hz`: every new frame whose time
/// is within the stretch (its first frame at the same time as the stretch's first); the same
/// frames for the same rate. Rates must be positive.
pub const fn frames(frames: usize, from_hz: f32, to_hz: f32) -> usize {
    if frames == 0 || same_rate(from_hz, to_hz) {
        return frames;
    }
    let last = (frames - 1) as f64 * to_hz as f64 / from_hz as f64;
    // A rate ratio too large for usize saturates rather than wrapping.
    ((last + SNAP) as usize).saturating_add(1)
}

/// Where frame `k` at `to_hz` falls among `frames` input frames at `from_hz`: the input frame
/// at or before it and the fraction of the way to the next (0 on a frame, and past the last
/// frame). Rates must be positive.
pub fn source(k: usize, from_hz: f32, to_hz: f32, frames: usize) -> (usize, f32) {
    let last = frames.saturating_sub(1);
    if same_rate(from_hz, to_hz) {
        return (k.min(last), 0.0);
    }
    let t = k as f64 * f64::from(from_hz) / f64::from(to_hz);
    let i = ((t + SNAP) as usize).min(last);
    let fraction = if i == last {
        0.0
    } else {
        (t - i as f64).max(0.0) as f32
    };
    (i, fraction)
}

/// `a` blended a `fraction` of the way to `b`, joint by joint, into `out` (as many joints as
/// the shortest of the three).
pub fn lerp(a: &[Vec3], b: &[Vec3], fraction: f32, out: &mut [Vec3]) {
    for ((o, p), q) in out.iter_mut().zip(a).zip(b) {
        *o = p + (q - p) * fraction;
    }
}

/// Joint `joint` of `frames` at input frame `i` and `fraction` ([`source`]): blended a
/// `fraction` of the way to frame `i + 1` as [`lerp`] blends, or frame `i`'s own where the
/// fraction is 0 or `i` is the last frame; `None` past the frames or a frame's joints. Reads
/// either storage, so a swing kept in millimetres is resampled without a copy in metres.
pub fn joint_at(frames: &Frames<'_>, i: usize, fraction: f32, joint: usize) -> Option<Vec3> {
    if i >= frames.len() || joint >= frames.joints() {
        return None;
    }
    let p = frames.at(i, joint);
    if fraction > 0.0 && i + 1 < frames.len() {
        let q = frames.at(i + 1, joint);
        Some(p + (q - p) * fraction)
    } else {
        Some(p)
    }
}

/// Frame `i` of `frames` blended a `fraction` of the way to frame `i + 1` as [`joint_at`]
/// blends each joint, into `out` (its first joints; at most a frame's); `None` past the frames.
pub fn frame_at(frames: &Frames<'_>, i: usize, fraction: f32, out: &mut [Vec3]) -> Option<()> {
    let (len, joints) = (frames.len(), frames.joints());
    if i >= len || out.len() > joints {
        return None;
    }
    let blend = fraction > 0.0 && i + 1 < len;
    for (j, o) in out.iter_mut().enumerate() {
        let p = frames.at(i, j);
        *o = match blend {
            true => p + (frames.at(i + 1, j) - p) * fraction,
            false => p,
        };
    }
    Some(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_same_rate_keeps_the_frames() {
        assert_eq!(frames(110, 60.000_057, 60.0), 110);
        assert_eq!(source(3, 60.000_057, 60.0, 110), (3, 0.0));
        assert_eq!(source(200, 60.000_057, 60.0, 110), (109, 0.0));
    }

    #[test]
    fn known_rates_land_where_they_should() {
        assert_eq!(frames(110, 60.000_057, 30.0), 55);
        assert_eq!(frames(110, 60.0, 120.0), 219);
        assert_eq!(frames(0, 60.0, 30.0), 0);
        assert_eq!(frames(1, 60.0, 30.0), 1);
        assert_eq!(frames(2, 1e-30, 1e30), usize::MAX);
        assert_eq!(source(1, 60.000_057, 30.0, 110).0, 2);
        let (i, fraction) = source(1, 60.0, 40.0, 110);
        assert_eq!(i, 1);
        assert!((fraction - 0.5).abs() < 1e-6);
        // 100 Hz to 30 Hz: frame 3 is input position 10 exactly, though 3 · 100 / 30 rounds.
        assert_eq!(source(3, 100.0, 30.0, 20), (10, 0.0));
    }

    /// Input frames of [`every_new_frame_lies_within_the_input`], fewer than this: fewer under
    /// Miri, where up to 2000 (and about three new frames to each) took 37 s.
    const MOST_FRAMES: usize = if cfg!(miri) { 100 } else { 2000 };

    proptest! {
        #[test]
        fn every_new_frame_lies_within_the_input(
            n in 1..MOST_FRAMES, from in 1.0f32..500.0, to in 1.0f32..500.0,
        ) {
            let m = frames(n, from, to);
            prop_assert!(m >= 1);
            let mut previous = (0, 0.0);
            for k in 0..m {
                let (i, fraction) = source(k, from, to, n);
                prop_assert!(i < n && (0.0..1.0).contains(&fraction), "{k}: {i} {fraction}");
                prop_assert!(i + usize::from(fraction > 0.0) < n, "frame {k} reads past the input");
                prop_assert!((i, fraction) >= previous, "frame {k} goes back in time");
                previous = (i, fraction);
            }
            // The new frames span the input: the last is within one new frame of its end (to
            // f32's precision at that many frames: 90 000 new frames are 0.008 apart).
            let (i, fraction) = source(m - 1, from, to, n);
            let end = (i as f32 + fraction) / from;
            let span = (n - 1) as f32 * to / from;
            prop_assert!(end * to + 1.0 + 1e-3 + span * 1e-6 >= span);
        }
    }

    #[test]
    fn lerp_blends_joint_by_joint() {
        let (a, b) = ([Vec3::zeros(); 2], [Vec3::new(1.0, 2.0, -4.0); 2]);
        let mut out = [Vec3::zeros(); 2];
        lerp(&a, &b, 0.25, &mut out);
        assert_eq!(out, [Vec3::new(0.25, 0.5, -1.0); 2]);
    }

    #[test]
    fn joint_at_and_frame_at_blend_as_lerp_does_in_either_storage() {
        let metres = [
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.5, 1.0, -0.25),
            Vec3::new(1.0, 2.0, -4.0),
            Vec3::new(0.5, 3.0, -0.75),
        ];
        let mm = metres.map(|p| crate::frames::to_mm(&p).unwrap());
        for frames in [Frames::metres(&metres, 2), Frames::millimetres(&mm, 2)] {
            let mut out = [Vec3::zeros(); 2];
            lerp(&metres[..2], &metres[2..], 0.25, &mut out);
            assert_eq!(joint_at(&frames, 0, 0.25, 1), Some(out[1]));
            assert_eq!(joint_at(&frames, 1, 0.0, 0), Some(metres[2]));
            // The last frame has nothing to blend towards.
            assert_eq!(joint_at(&frames, 1, 0.5, 1), Some(metres[3]));
            assert_eq!(joint_at(&frames, 2, 0.0, 0), None);
            assert_eq!(joint_at(&frames, 0, 0.0, 2), None);
            let mut whole = [Vec3::zeros(); 2];
            for (i, fraction) in [(0, 0.25), (0, 0.0), (1, 0.5)] {
                assert_eq!(frame_at(&frames, i, fraction, &mut whole), Some(()));
                for (j, w) in whole.iter().enumerate() {
                    assert_eq!(Some(*w), joint_at(&frames, i, fraction, j));
                }
            }
            assert_eq!(frame_at(&frames, 2, 0.0, &mut whole), None);
            assert_eq!(frame_at(&frames, 0, 0.0, &mut [Vec3::zeros(); 3]), None);
        }
    }
}
