//! The motion smoothed, and the hands' path along it with their speeds kept.

use super::SMOOTHING_S;
use crate::frames::Frames;
use crate::math::norm;
use crate::Vec3;
use core::cell::Cell;

/// Frames of a speed [`Memo`] keeps (1 KiB of stack); later frames are computed each time.
const MEMO_FRAMES: usize = crate::config::MAX_SWING_FRAMES;

/// Values of one function of the frame, each of the first [`MEMO_FRAMES`] computed once: the
/// searches ask for the same speeds many times (a still stretch is a maximum over a window at
/// every frame), and each speed is four smoothed positions.
pub(super) struct Memo {
    /// NaN until computed (speeds of finite positions are finite).
    values: [Cell<f32>; MEMO_FRAMES],
}

impl Memo {
    /// A memo with nothing computed yet.
    pub(super) fn new() -> Memo {
        Memo {
            values: core::array::from_fn(|_| Cell::new(f32::NAN)),
        }
    }

    /// `f(t)`, kept from an earlier call where there was one: every call on one memo must pass
    /// the same function.
    pub(super) fn get(&self, t: usize, f: impl Fn(usize) -> f32) -> f32 {
        let Some(cell) = self.values.get(t) else {
            return f(t);
        };
        if cell.get().is_nan() {
            cell.set(f(t));
        }
        cell.get()
    }
}

/// Smoothed trajectories of one motion.
pub(super) struct Track<'a> {
    positions: Frames<'a>,
    /// How many frames the motion has.
    pub(super) frames: usize,
    /// Half-width of the smoothing window, frames.
    pub(super) half: usize,
    /// Frames per second.
    pub(super) rate: f32,
}

impl<'a> Track<'a> {
    /// `positions` at `rate` frames per second, smoothed over ±[`SMOOTHING_S`].
    pub(super) fn new(positions: Frames<'a>, rate: f32) -> Track<'a> {
        Track {
            positions,
            frames: positions.len(),
            half: libm::roundf(SMOOTHING_S * rate) as usize,
            rate,
        }
    }

    /// Joint `j` at frame `t`, averaged over `t ± half` (clamped to the motion).
    pub(super) fn at(&self, j: usize, t: usize) -> Vec3 {
        let (lo, hi) = (
            t.saturating_sub(self.half),
            (t + self.half).min(self.frames - 1),
        );
        let sum = (lo..=hi).fold(Vec3::zeros(), |s, f| s + self.positions.at(f, j));
        sum / (hi - lo + 1) as f32
    }

    /// Speed of `point` at `t` in metres per second, by a central difference over ±half.
    pub(super) fn speed(&self, point: impl Fn(usize) -> Vec3, t: usize) -> f32 {
        let (lo, hi) = (
            t.saturating_sub(self.half.max(1)),
            (t + self.half.max(1)).min(self.frames - 1),
        );
        norm(&(point(hi) - point(lo))) * self.rate / (hi - lo).max(1) as f32
    }
}

/// The hands, the midpoint of the wrists, on a smoothed track; each speed computed once.
pub(super) struct Hands<'a> {
    /// The track they are read from.
    pub(super) track: &'a Track<'a>,
    /// Left and right wrist (or hand).
    wrists: [usize; 2],
    speeds: Memo,
}

impl<'a> Hands<'a> {
    /// The hands between `wrists` (left and right) on `track`.
    pub(super) fn new(track: &'a Track<'a>, wrists: [usize; 2]) -> Hands<'a> {
        Hands {
            track,
            wrists,
            speeds: Memo::new(),
        }
    }

    /// Where the hands are at frame `t`.
    pub(super) fn at(&self, t: usize) -> Vec3 {
        (self.track.at(self.wrists[0], t) + self.track.at(self.wrists[1], t)) * 0.5
    }

    /// How fast the hands go at frame `t`, metres per second.
    pub(super) fn speed(&self, t: usize) -> f32 {
        self.speeds.get(t, |t| self.track.speed(|t| self.at(t), t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// Two joints, 0.1 m apart in z, moving at `v` m/s along x for `frames` frames at 60 Hz.
    fn gliding(v: f32, frames: usize) -> Vec<Vec3> {
        (0..frames)
            .flat_map(|f| {
                let x = v * f as f32 / 60.0;
                [Vec3::new(x, 1.0, 0.0), Vec3::new(x, 1.0, 0.1)]
            })
            .collect()
    }

    #[test]
    fn a_memo_computes_each_kept_frame_once_and_later_frames_each_time() {
        let memo = Memo::new();
        let calls = Cell::new(0);
        let f = |t: usize| {
            calls.set(calls.get() + 1);
            t as f32 * 0.5
        };
        assert_eq!(memo.get(3, f), 1.5);
        assert_eq!(memo.get(3, f), 1.5);
        assert_eq!(calls.get(), 1);
        assert_eq!(memo.get(MEMO_FRAMES, f), MEMO_FRAMES as f32 * 0.5);
        assert_eq!(memo.get(MEMO_FRAMES, f), MEMO_FRAMES as f32 * 0.5);
        assert_eq!(calls.get(), 3);
    }

    #[test]
    fn a_track_averages_over_its_window_clamped_to_the_motion() {
        // One joint whose x is its frame number, at 60 Hz: ±2 frames of smoothing.
        let positions: Vec<Vec3> = (0..10).map(|f| Vec3::new(f as f32, 0.0, 0.0)).collect();
        let track = Track::new(Frames::metres(&positions, 1), 60.0);
        assert_eq!(track.half, 2);
        assert_eq!(track.at(0, 5).x, 5.0);
        // Frames 0, 1 and 2 at the start, 7, 8 and 9 at the end.
        assert_eq!(track.at(0, 0).x, 1.0);
        assert_eq!(track.at(0, 9).x, 8.0);
    }

    #[test]
    fn the_hands_are_between_the_wrists_and_their_speed_is_the_track_s() {
        let positions = gliding(3.0, 30);
        let track = Track::new(Frames::metres(&positions, 2), 60.0);
        let hands = Hands::new(&track, [0, 1]);
        assert!((hands.at(10).z - 0.05).abs() < 1e-6);
        assert!((hands.speed(10) - 3.0).abs() < 1e-4, "{}", hands.speed(10));
        // At the ends the difference is one-sided and the smoothing clamped: slower.
        assert!(hands.speed(0) < hands.speed(10));
        assert_eq!(hands.speed(10), track.speed(|t| hands.at(t), 10));
    }
}
