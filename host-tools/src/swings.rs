//! The swings in a recording: a file of any length (up to the readers' limits) cut where the
//! device's streaming detector cuts a pose stream, so that `score` and `inspect` see every
//! swing of a range recording, not only files cut to one swing.

use posecoach_core::detector::{DetectorConfig, SwingDetector, SETTLE_WINDOW_S, SPEED_WINDOW_S};
use posecoach_core::frames::Mm;
use posecoach_io::Motion;

/// One swing of a recording.
#[derive(Clone, Debug)]
pub struct Swing {
    /// Seconds from the recording's first frame to the swing's.
    pub start_s: f32,
    /// Its frames (from its set-up to its settled finish), at the recording's rate.
    pub motion: Motion,
}

/// The swings of `motion`: the whole of it where it lasts at most `longest_s` and the detector
/// closes at most one swing in it (a file cut to one swing, kept as it was cut); else each
/// swing the detector closes, in order, with the set-up and settled finish the device keeps
/// ([`DetectorConfig::full_swing`] at the recording's rate; a swing the recording stops in
/// ends with it). Where it closes none the whole recording is its one swing (the scorer then
/// says what it lacks).
pub fn cut(motion: &Motion, longest_s: f32) -> Vec<Swing> {
    let whole = || {
        vec![Swing {
            start_s: 0.0,
            motion: motion.clone(),
        }]
    };
    let windows = windows(motion);
    if windows.is_empty() || (windows.len() == 1 && motion.duration_s() <= longest_s) {
        return whole();
    }
    let n = motion.skeleton.len();
    let frames = motion.frames();
    windows
        .into_iter()
        .map(|(start, len)| {
            let end = (start + len).min(frames);
            Swing {
                start_s: start as f32 / motion.rate_hz,
                motion: Motion {
                    skeleton: motion.skeleton.clone(),
                    names: motion.names.clone(),
                    rate_hz: motion.rate_hz,
                    positions: motion.positions[start * n..end * n].to_vec(),
                    missing: motion.missing[start * n..end * n].to_vec(),
                },
            }
        })
        .collect()
}

/// Where the detector finds a swing in `motion`: each one's start and duration, seconds.
pub fn found(motion: &Motion) -> Vec<(f32, f32)> {
    windows(motion)
        .into_iter()
        .map(|(start, len)| (start as f32 / motion.rate_hz, len as f32 / motion.rate_hz))
        .collect()
}

/// The (first frame, frames) of every swing the detector closes in `motion`; none for a single
/// frame, or a frame the detector cannot hold (beyond ±32 m).
fn windows(motion: &Motion) -> Vec<(usize, usize)> {
    let n = motion.skeleton.len();
    let frames = motion.frames();
    if frames < 2 || motion.rate_hz <= 0.0 {
        return Vec::new();
    }
    let config = DetectorConfig::full_swing(motion.rate_hz);
    let settle = config.settle_s + SETTLE_WINDOW_S + SPEED_WINDOW_S;
    let held = (settle * motion.rate_hz).ceil() as usize + 1;
    // A ring as long as the recording and its held end (and the two seconds the detector
    // needs at the least): a candidate is never cut short by the ring.
    let capacity = (frames + held).max((2.0 * motion.rate_hz).ceil() as usize + 1);
    let mut storage: Vec<Mm> = vec![[0; 3]; capacity * n];
    let Ok(mut detector) = SwingDetector::new(&motion.skeleton, config, &mut storage) else {
        return Vec::new();
    };
    // The recording, then its last frame held for as long as the detector takes to see hands
    // settle: a recording stopped right after its last swing still closes that swing (its
    // window ends with the recording).
    let mut windows = Vec::new();
    for f in (0..frames).chain(std::iter::repeat_n(frames - 1, held)) {
        match detector.push(motion.frame(f)) {
            Ok(Some(w)) if (w.start as usize) < frames => windows.push((w.start as usize, w.len)),
            Ok(_) => {}
            Err(_) => return Vec::new(),
        }
    }
    windows
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use std::path::Path;

    fn iron() -> Motion {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        posecoach_io::load(&root.join("tests/fixtures/golf_iron_60hz.csv")).unwrap()
    }

    /// `motion` with its first frame held `before` s and its last `after` s.
    fn held(motion: &Motion, before: f32, after: f32) -> Motion {
        let n = motion.skeleton.len();
        let hold = |s: f32| (s * motion.rate_hz) as usize;
        let first = motion.frame(0).to_vec();
        let last = motion.frame(motion.frames() - 1).to_vec();
        let mut out = motion.clone();
        out.positions = std::iter::repeat_n(first, hold(before))
            .flatten()
            .chain(motion.positions.iter().copied())
            .chain(std::iter::repeat_n(last, hold(after)).flatten())
            .collect();
        out.missing = vec![false; out.positions.len()];
        assert_eq!(out.positions.len() % n, 0);
        out
    }

    #[test]
    fn a_recording_of_two_swings_is_cut_into_both() {
        let one = held(&iron(), 1.0, 1.5);
        let mut two = one.clone();
        two.positions.extend(one.positions.iter().copied());
        two.missing.extend(one.missing.iter().copied());
        let swings = cut(&two, 4.0);
        assert_eq!(swings.len(), 2);
        let gap = swings[1].start_s - swings[0].start_s;
        assert!((gap - one.duration_s()).abs() < 0.05, "{gap}");
        // Each is the same stretch of the same swing.
        assert_eq!(swings[0].motion.positions, swings[1].motion.positions);
    }

    #[test]
    fn a_recording_stopped_at_its_last_finish_keeps_that_swing() {
        let one = held(&iron(), 1.0, 1.5);
        let mut two = one.clone();
        two.positions.extend(held(&iron(), 1.0, 0.0).positions);
        two.missing.resize(two.positions.len(), false);
        assert_eq!(cut(&two, 4.0).len(), 2);
    }

    #[test]
    fn one_swing_is_kept_whole_unless_too_long() {
        let iron = iron();
        let swings = cut(&iron, 4.0);
        assert_eq!(swings.len(), 1);
        assert_eq!(swings[0].motion, iron);
        // Held 1 s at address and 1.5 s at the finish: too long whole, cut to its swing.
        let long = held(&iron, 1.0, 1.5);
        let swings = cut(&long, 4.0);
        assert_eq!(swings.len(), 1);
        assert!(swings[0].motion.duration_s() <= 4.0);
        assert!(swings[0].start_s > 0.0);
    }
}
