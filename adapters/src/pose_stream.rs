//! Pose streams: a camera pose estimator's keypoint frames turned into joint frames on a fixed
//! time grid.
//!
//! A [`PoseStream`] takes [`PoseFrame`]s as they arrive and emits frames of the stream format's
//! joints (see [`Format::joints`]) every `1 / rate_hz` seconds of the sender's clock, each
//! linearly interpolated between the two received frames around it, so capture jitter does not
//! reach the swing's timing. It drops repeated and late frames (by sequence number and time), masks
//! keypoints under `min_confidence` or moving faster than a body part can (the joint is carried by its parent at the offset it last
//! had from it, turned as the parent's bone turned, unless the unsure keypoint lies at about its
//! bone's length from the parent ([`UNSURE_BONE_SHARE`]); a masked root holds its last
//! confident position), and breaks
//! the stream at a gap longer than `max_gap_s`: it emits [`StreamEvent::Gap`] and starts a
//! new grid at the next frame, so a swing is never stitched across missing time. Nothing
//! allocates and nothing panics.
//!
//! ```
//! use posecoach_adapters::pose_stream::{PoseStream, StreamConfig, StreamEvent};
//! use posecoach_core::format::Format;
//! use posecoach_core::wire::PoseFrame;
//!
//! let mut stream = PoseStream::new(StreamConfig::new(60)).unwrap();
//! let pose = |seq: u32, t_us: u64| PoseFrame {
//!     seq,
//!     t_us,
//!     format: Format::H36m17,
//!     joints_mm: core::iter::repeat_n([0, 900, 0], 17).collect(),
//!     confidence: heapless::Vec::new(),
//! };
//! let mut frames = 0;
//! for (seq, t_us) in [(0, 0), (1, 33_333), (2, 66_667)] {
//!     stream
//!         .push(&pose(seq, t_us), |event| {
//!             if let StreamEvent::Frame { joints, .. } = event {
//!                 assert_eq!(joints.len(), 17);
//!                 frames += 1;
//!             }
//!         })
//!         .unwrap();
//! }
//! assert_eq!(frames, 5); // 0, 16.7, 33.3, 50 and 66.7 ms
//! ```

use posecoach_core::config::MAX_JOINTS;
use posecoach_core::format::{Format, Source};
use posecoach_core::math::norm;
use posecoach_core::plausible;
use posecoach_core::resample;
use posecoach_core::wire::{PoseFrame, MAX_WIRE_JOINTS};
use posecoach_core::Vec3;

/// A gap between frames longer than this breaks the stream, seconds.
pub const MAX_GAP_S: f32 = 0.25;
/// Keypoints under this confidence (of 255) are unsure: see [`UNSURE_BONE_SHARE`].
pub const MIN_CONFIDENCE: u8 = 77;
/// An unsure keypoint (under the minimum confidence, but above 0) is taken as sent when its
/// distance from its parent is within this share of the bone's last length; else, and for a
/// keypoint of confidence 0, the joint is carried by its parent.
pub const UNSURE_BONE_SHARE: f32 = 0.3;

/// Settings of a [`PoseStream`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StreamConfig {
    /// Rate of the emitted frames, Hz.
    pub rate_hz: u16,
    /// Longest gap bridged by interpolation, seconds.
    pub max_gap_s: f32,
    /// Keypoints under this confidence hold their joint's last confident position.
    pub min_confidence: u8,
}

impl StreamConfig {
    /// Frames at `rate_hz`, with [`MAX_GAP_S`] and [`MIN_CONFIDENCE`].
    pub const fn new(rate_hz: u16) -> StreamConfig {
        StreamConfig {
            rate_hz,
            max_gap_s: MAX_GAP_S,
            min_confidence: MIN_CONFIDENCE,
        }
    }
}

/// What the stream hands on.
#[derive(Debug, PartialEq)]
pub enum StreamEvent<'a> {
    /// The next frame on the grid.
    Frame {
        /// Its time on the sender's clock, microseconds.
        t_us: u64,
        /// The stream format's joints, metres.
        joints: &'a [Vec3],
        /// The joints (bit `k` for joint `k`) that were unsure in either received frame it
        /// lies between: carried by their parents, or taken from an unsure keypoint.
        unsure: u64,
    },
    /// Time is missing before the next frame: whatever was in progress is broken.
    Gap,
}

/// What the stream has taken and dropped; each count stops at `u32::MAX`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StreamCounters {
    /// Frames taken.
    pub accepted: u32,
    /// Frames repeating the last one's sequence number or time.
    pub duplicates: u32,
    /// Frames older than one already taken.
    pub out_of_order: u32,
    /// Breaks longer than the gap limit.
    pub gaps: u32,
    /// Keypoints masked for low confidence, or for moving faster than a body part can
    /// ([`plausible::MAX_SPEED_M_S`]) since the last frame.
    pub masked: u32,
    /// Frames emitted on the grid.
    pub emitted: u32,
}

impl StreamCounters {
    /// Adds `other`'s counts to these.
    pub fn add(&mut self, other: &StreamCounters) {
        self.accepted = self.accepted.saturating_add(other.accepted);
        self.duplicates = self.duplicates.saturating_add(other.duplicates);
        self.out_of_order = self.out_of_order.saturating_add(other.out_of_order);
        self.gaps = self.gaps.saturating_add(other.gaps);
        self.masked = self.masked.saturating_add(other.masked);
        self.emitted = self.emitted.saturating_add(other.emitted);
    }
}

/// Why a frame or a configuration was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StreamError {
    /// A rate of zero, or a gap limit that is not a positive number.
    Config,
    /// The frame's format has no joint table ([`Format::Custom`]) or differs from the
    /// stream's first frame.
    Format(Format),
    /// The keypoint count does not match the format, or confidences are neither absent nor
    /// one per keypoint.
    Keypoints {
        /// Keypoints the format has.
        expected: usize,
        /// Keypoints (or confidences) received.
        actual: usize,
    },
}

impl core::fmt::Display for StreamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StreamError::Config => {
                f.write_str("the stream rate must be above zero and the gap limit positive")
            }
            StreamError::Format(format) => write!(
                f,
                "pose frame in format `{}`, which has no joint table or is not the stream's",
                format.name()
            ),
            StreamError::Keypoints { expected, actual } => write!(
                f,
                "pose frame with {actual} keypoints or confidences where the format has {expected}"
            ),
        }
    }
}

impl core::error::Error for StreamError {}

/// The last frame taken.
#[derive(Clone, Copy, Debug)]
struct Taken {
    seq: u32,
    t_us: u64,
}

/// The resampler; see the [module documentation](self).
#[derive(Clone, Debug)]
pub struct PoseStream {
    config: StreamConfig,
    /// Format of the stream, fixed by its first frame.
    format: Option<Format>,
    /// Joints of that format.
    joints: usize,
    last: Option<Taken>,
    /// Joint positions of the last frame taken (masked joints held).
    previous: [Vec3; MAX_JOINTS],
    /// The joints unsure in the last frame taken.
    previous_unsure: u64,
    /// Joints that have had a confident position.
    seen: u64,
    /// Time of grid frame 0 and the index of the next grid frame, once all joints are seen.
    grid: Option<(u64, u64)>,
    counters: StreamCounters,
}

impl PoseStream {
    /// An empty stream.
    ///
    /// # Errors
    /// [`StreamError::Config`] for a zero rate or a gap limit that is not positive.
    pub fn new(config: StreamConfig) -> Result<PoseStream, StreamError> {
        if config.rate_hz == 0 || !(config.max_gap_s.is_finite() && config.max_gap_s > 0.0) {
            return Err(StreamError::Config);
        }
        Ok(PoseStream {
            config,
            format: None,
            joints: 0,
            last: None,
            previous: [Vec3::zeros(); MAX_JOINTS],
            previous_unsure: 0,
            seen: 0,
            grid: None,
            counters: StreamCounters::default(),
        })
    }

    /// The stream's format, once a frame has been taken.
    pub fn format(&self) -> Option<Format> {
        self.format
    }

    /// What has been taken and dropped so far.
    pub fn counters(&self) -> StreamCounters {
        self.counters
    }

    /// Time of grid frame `k` after a grid starting at `t0_us`; none past the end of the clock
    /// (a saturated time would equal a frame sent at `u64::MAX`, and the grid would never pass
    /// it).
    fn grid_time(&self, t0_us: u64, k: u64) -> Option<u64> {
        let rate = u64::from(self.config.rate_hz);
        t0_us.checked_add(k.checked_mul(1_000_000)?.checked_add(rate / 2)? / rate)
    }

    /// Takes the next received frame and calls `emit` for each grid frame (and break) it
    /// completes. Repeated and late frames are counted and dropped without error.
    ///
    /// # Errors
    /// [`StreamError::Format`] or [`StreamError::Keypoints`] for a frame that does not fit the
    /// stream; the stream is unchanged.
    pub fn push(
        &mut self,
        frame: &PoseFrame,
        mut emit: impl FnMut(StreamEvent<'_>),
    ) -> Result<(), StreamError> {
        let joints = self.check(frame)?;
        if let Some(last) = self.last {
            if frame.seq == last.seq || frame.t_us == last.t_us {
                self.counters.duplicates = self.counters.duplicates.saturating_add(1);
                return Ok(());
            }
            let gap_us = (self.config.max_gap_s * 1e6) as u64;
            let newer = (frame.seq.wrapping_sub(last.seq) as i32) > 0;
            // A clock far behind the last frame's is a sender that restarted: a break.
            let restarted = frame.t_us.saturating_add(gap_us) < last.t_us;
            if !restarted && (!newer || frame.t_us < last.t_us) {
                self.counters.out_of_order = self.counters.out_of_order.saturating_add(1);
                return Ok(());
            }
            if restarted || frame.t_us - last.t_us > gap_us {
                self.counters.gaps = self.counters.gaps.saturating_add(1);
                self.grid = None;
                emit(StreamEvent::Gap);
            }
        }
        self.format = Some(frame.format);
        self.joints = joints.len();
        self.counters.accepted = self.counters.accepted.saturating_add(1);
        let mut current = self.previous;
        let mut unsure = 0u64;
        let table = frame.format.joints();
        // A keypoint that moved faster than any body part can since the last frame is a wild
        // estimate: it is unsure whatever its confidence.
        let reach = match self.last {
            Some(last) if frame.t_us > last.t_us => {
                plausible::MAX_SPEED_M_S * (frame.t_us - last.t_us) as f32 * 1e-6
            }
            _ => f32::INFINITY,
        };
        let seen = self.seen;
        let wild = |k: usize, position: &Vec3| {
            seen & (1 << k) != 0 && norm(&(*position - self.previous[k])) > reach
        };
        let mut wild_mask = 0u64;
        for (k, (position, confidence)) in joints.iter().enumerate() {
            let too_fast = wild(k, position);
            wild_mask |= u64::from(too_fast) << k;
            if *confidence >= self.config.min_confidence && !too_fast {
                current[k] = *position;
                self.seen |= 1 << k;
            } else {
                self.counters.masked = self.counters.masked.saturating_add(1);
                unsure |= 1 << k;
            }
        }
        // A masked joint is carried by its parent: it keeps the offset from it that it had in
        // the last frame (parents come first in a format's table), so an occluded wrist follows
        // its elbow through a downswing instead of staying behind.
        for (k, (position, confidence)) in joints.iter().enumerate() {
            let parent = |k: usize| table.get(k).and_then(|j| j.parent).map(usize::from);
            let unsure = unsure & (1 << k) != 0;
            let Some(p) = parent(k).filter(|&p| unsure && p < k) else {
                continue;
            };
            let offset = self.previous[k] - self.previous[p];
            // Turned as the parent's own bone turned since the last frame.
            let turn = parent(p)
                .filter(|&g| g < p)
                .and_then(|g| {
                    let (was, is) = (self.previous[p] - self.previous[g], current[p] - current[g]);
                    nalgebra::UnitQuaternion::rotation_between(&was, &is)
                })
                .unwrap_or_else(nalgebra::UnitQuaternion::identity);
            current[k] = current[p] + turn * offset;
            // An unsure keypoint the estimator still placed at about its bone's length from the
            // parent is the better guess.
            let (bone, sent) = (norm(&offset), norm(&(*position - current[p])));
            if *confidence > 0
                && wild_mask & (1 << k) == 0
                && libm::fabsf(sent - bone) <= UNSURE_BONE_SHARE * bone
            {
                current[k] = *position;
            }
        }
        let ready = self.seen.count_ones() as usize == self.joints;
        let t_us = frame.t_us;
        match (self.grid, self.last) {
            (Some((t0, mut k)), Some(last)) if t_us > last.t_us => {
                let span = (t_us - last.t_us) as f32;
                let mut out = [Vec3::zeros(); MAX_JOINTS];
                while let Some(t) = self.grid_time(t0, k).filter(|&t| t <= t_us) {
                    let w = (t.saturating_sub(last.t_us)) as f32 / span;
                    resample::lerp(&self.previous, &current, w, &mut out);
                    self.counters.emitted = self.counters.emitted.saturating_add(1);
                    emit(StreamEvent::Frame {
                        t_us: t,
                        joints: &out[..self.joints],
                        unsure: self.previous_unsure | unsure,
                    });
                    k += 1;
                }
                self.grid = Some((t0, k));
            }
            _ if ready => {
                self.grid = Some((t_us, 1));
                self.counters.emitted = self.counters.emitted.saturating_add(1);
                emit(StreamEvent::Frame {
                    t_us,
                    joints: &current[..self.joints],
                    unsure,
                });
            }
            _ => {}
        }
        self.previous = current;
        self.previous_unsure = unsure;
        self.last = Some(Taken {
            seq: frame.seq,
            t_us,
        });
        Ok(())
    }

    /// The frame's joints in metres with their confidence, in the format's joint order.
    fn check(
        &self,
        frame: &PoseFrame,
    ) -> Result<heapless::Vec<(Vec3, u8), MAX_JOINTS>, StreamError> {
        let format = frame.format;
        let table = format.joints();
        if table.is_empty() || self.format.is_some_and(|f| f != format) {
            return Err(StreamError::Format(format));
        }
        let expected = format.keypoints().len();
        let (n, c) = (frame.joints_mm.len(), frame.confidence.len());
        if n != expected || (c != 0 && c != n) {
            return Err(StreamError::Keypoints {
                expected,
                actual: if n != expected { n } else { c },
            });
        }
        let keypoint = |i: u8| {
            let i = usize::from(i);
            let [x, y, z] = frame.joints_mm.get(i).copied().unwrap_or_default();
            let confidence = frame.confidence.get(i).copied().unwrap_or(u8::MAX);
            (
                Vec3::new(f32::from(x), f32::from(y), f32::from(z)) * 1e-3,
                confidence,
            )
        };
        Ok(table
            .iter()
            .take(MAX_JOINTS)
            .map(|j| match j.source {
                Source::Keypoint(i) => keypoint(i),
                Source::Mid(a, b) => {
                    let ((pa, ca), (pb, cb)) = (keypoint(a), keypoint(b));
                    ((pa + pb) * 0.5, ca.min(cb))
                }
            })
            .collect())
    }
}

const _: () = assert!(MAX_WIRE_JOINTS <= MAX_JOINTS && MAX_JOINTS <= 64);

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    /// A pelvis-only-moving H36M frame: every keypoint at `x` mm along X, 1 m up.
    fn frame(seq: u32, t_us: u64, x: i16) -> PoseFrame {
        PoseFrame {
            seq,
            t_us,
            format: Format::H36m17,
            joints_mm: core::iter::repeat_n([x, 1000, 0], 17).collect(),
            confidence: heapless::Vec::new(),
        }
    }

    /// Pushes `frames` and returns the emitted events: `Some(x of joint 0)` per frame, `None`
    /// per break.
    fn run(stream: &mut PoseStream, frames: &[PoseFrame]) -> Vec<Option<f32>> {
        let mut out = Vec::new();
        for f in frames {
            stream
                .push(f, |e| {
                    out.push(match e {
                        StreamEvent::Frame { joints, .. } => Some(joints[0].x),
                        StreamEvent::Gap => None,
                    })
                })
                .unwrap();
        }
        out
    }

    #[test]
    fn jittered_frames_land_on_the_grid() {
        // Motion at 1 m/s along X sampled at 30 Hz with up to ±6 ms of jitter, emitted at 60 Hz.
        let jitter = [0i64, 5000, -6000, 2000, -1000, 6000, -4000, 3000, 0];
        let frames: Vec<_> = jitter
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let t = (i as i64 * 33_333 + j) as u64;
                frame(i as u32, t, (t / 1000) as i16)
            })
            .collect();
        let mut stream = PoseStream::new(StreamConfig::new(60)).unwrap();
        let got = run(&mut stream, &frames);
        assert_eq!(got.len(), 16); // 0 to 250 ms
        for (k, x) in got.iter().enumerate() {
            // Millimetre keypoints: within rounding of 1 m/s at k / 60 s.
            assert!((x.unwrap() - k as f32 / 60.0).abs() < 1.5e-3, "{k}: {x:?}");
        }
        assert_eq!(stream.counters().emitted, 16);
    }

    #[test]
    fn repeated_and_late_frames_are_dropped() {
        let clean: Vec<_> = (0..6)
            .map(|i| frame(i, u64::from(i) * 33_333, 10 * i as i16))
            .collect();
        let mut messy = clean.clone();
        messy.insert(3, clean[2].clone()); // repeated
        messy.insert(5, clean[1].clone()); // late
        let mut shifted = clean[4].clone();
        shifted.seq = 2; // an old sequence number with a new time
        messy.insert(6, shifted);
        let mut a = PoseStream::new(StreamConfig::new(60)).unwrap();
        let mut b = PoseStream::new(StreamConfig::new(60)).unwrap();
        assert_eq!(run(&mut a, &clean), run(&mut b, &messy));
        let c = b.counters();
        assert_eq!((c.accepted, c.duplicates, c.out_of_order), (6, 1, 2));
    }

    #[test]
    fn a_long_gap_breaks_the_stream_and_restarts_the_grid() {
        let frames = [
            frame(0, 0, 0),
            frame(1, 33_333, 33),
            frame(2, 433_333, 433),
            frame(3, 466_667, 467),
        ];
        let mut stream = PoseStream::new(StreamConfig::new(60)).unwrap();
        let got = run(&mut stream, &frames);
        let expected = [
            Some(0.0),
            Some(0.0165),
            Some(0.033),
            None,
            Some(0.433),
            Some(0.45),
            Some(0.467),
        ];
        assert_eq!(got.len(), expected.len());
        for (g, e) in got.iter().zip(expected) {
            assert_eq!(g.is_some(), e.is_some());
            assert!(
                (g.unwrap_or(0.0) - e.unwrap_or(0.0)).abs() < 1e-4,
                "{got:?}"
            );
        }
        assert_eq!(stream.counters().gaps, 1);
        // A sender whose clock starts again from zero is a break too, not a late frame.
        let got = run(&mut stream, &[frame(0, 0, 0), frame(1, 16_667, 17)]);
        assert_eq!(got, [None, Some(0.0), Some(0.017)]);
    }

    #[test]
    fn a_clock_that_runs_to_its_end_and_wraps_is_followed() {
        // A leap to 0.1 s before the end of the clock, a frame at u64::MAX itself (where a
        // saturated grid time once equalled the frame's and the grid never passed it), then
        // the clock wraps and the sequence number with it.
        let end = u64::MAX;
        let frames = [
            frame(0, 0, 0),
            frame(1, end - 100_000, 0),
            frame(2, end, 100),
            frame(u32::MAX, 1_000, 0),
            frame(0, 17_667, 17),
        ];
        let mut stream = PoseStream::new(StreamConfig::new(60)).unwrap();
        let got = run(&mut stream, &frames);
        // The first frame; a break, the leap's frame and the grid's six up to the end; a break
        // and the wrapped clock's two.
        assert_eq!(got.len(), 1 + 1 + 1 + 6 + 1 + 2, "{got:?}");
        assert_eq!(stream.counters().gaps, 2);
    }

    #[test]
    fn unconfident_keypoints_hold_their_joint() {
        let mut stream = PoseStream::new(StreamConfig::new(30)).unwrap();
        let mut f1 = frame(1, 33_333, 500);
        f1.confidence = core::iter::repeat_n(255, 17).collect();
        f1.confidence[0] = 10; // the pelvis is a guess: hold it
        let got = run(&mut stream, &[frame(0, 0, 100), f1]);
        assert_eq!(got, [Some(0.1), Some(0.1)]);
        assert_eq!(stream.counters().masked, 1);
        // A joint never seen with confidence holds back the first frame.
        let mut stream = PoseStream::new(StreamConfig::new(30)).unwrap();
        let mut f0 = frame(0, 0, 100);
        f0.confidence = core::iter::repeat_n(255, 17).collect();
        f0.confidence[5] = 0;
        let got = run(
            &mut stream,
            &[f0, frame(1, 33_333, 200), frame(2, 66_667, 300)],
        );
        assert_eq!(got.len(), 2);
        assert!((got[0].unwrap() - 0.2).abs() < 1e-6 && (got[1].unwrap() - 0.3).abs() < 1e-5);
    }

    #[test]
    fn a_keypoint_faster_than_a_body_is_unsure_whatever_its_confidence() {
        // At 30 Hz a body part moves at most 100 m/s x 33 ms = 3.3 m: the pelvis keypoint
        // jumping 5 m is held where it was, one moving 3 m is taken.
        let mut stream = PoseStream::new(StreamConfig::new(30)).unwrap();
        let mut wild = frame(1, 33_333, 5100);
        wild.confidence = core::iter::repeat_n(255, 17).collect();
        let got = run(&mut stream, &[frame(0, 0, 100), wild]);
        assert_eq!(got, [Some(0.1), Some(0.1)]);
        assert_eq!(stream.counters().masked, 17);
        let got = run(&mut stream, &[frame(2, 66_667, 3100)]);
        assert!(
            got.len() == 1 && (got[0].unwrap() - 3.1).abs() < 1e-5,
            "{got:?}"
        );
        assert_eq!(stream.counters().masked, 17);
    }

    #[test]
    fn an_unsure_keypoint_counts_at_about_its_bones_length_from_its_parent() {
        // Keypoint k at (k/10, 1, 0) m; the next frame moves everything 0.1 m along X, with
        // the right ankle (keypoint 3, below the knee) unsure and sent `off` from there.
        let at = |seq: u32, dx: f32, off: [f32; 3], confidence: u8| {
            let mut f = frame(seq, u64::from(seq) * 33_333, 0);
            for (k, p) in f.joints_mm.iter_mut().enumerate() {
                *p = [(k as f32 * 100.0 + dx * 1000.0) as i16, 1000, 0];
            }
            f.joints_mm[3] = [
                300 + (dx * 1000.0 + off[0]) as i16,
                1000 + off[1] as i16,
                off[2] as i16,
            ];
            f.confidence = core::iter::repeat_n(255, 17).collect();
            f.confidence[3] = confidence;
            f
        };
        let ankle = |off: [f32; 3], confidence: u8| {
            let mut stream = PoseStream::new(StreamConfig::new(30)).unwrap();
            let mut last = Vec3::zeros();
            for f in [at(0, 0.0, [0.0; 3], 255), at(1, 0.1, off, confidence)] {
                stream
                    .push(&f, |e| {
                        if let StreamEvent::Frame { joints, .. } = e {
                            last = joints[3];
                        }
                    })
                    .unwrap();
            }
            last
        };
        let carried = Vec3::new(0.4, 1.0, 0.0);
        // Sent 5 cm off (the shin 0.4 m long, 5 % longer): taken as sent.
        assert!((ankle([0.0, 50.0, 0.0], 30) - Vec3::new(0.4, 1.05, 0.0)).norm() < 1e-4);
        // Sent 50 cm off (the shin twice as long), or with no confidence: carried along with
        // the knee.
        assert!((ankle([0.0, 500.0, 0.0], 30) - carried).norm() < 1e-4);
        assert!((ankle([0.0, 50.0, 0.0], 0) - carried).norm() < 1e-4);
    }

    #[test]
    fn frames_that_do_not_fit_are_errors() {
        assert_eq!(
            PoseStream::new(StreamConfig::new(0)).err(),
            Some(StreamError::Config)
        );
        let mut stream = PoseStream::new(StreamConfig::new(60)).unwrap();
        let mut short = frame(0, 0, 0);
        short.joints_mm.truncate(16);
        assert_eq!(
            stream.push(&short, |_| {}),
            Err(StreamError::Keypoints {
                expected: 17,
                actual: 16
            })
        );
        let mut confidences = frame(0, 0, 0);
        confidences.confidence.extend([255; 3]);
        assert_eq!(
            stream.push(&confidences, |_| {}),
            Err(StreamError::Keypoints {
                expected: 17,
                actual: 3
            })
        );
        let mut custom = frame(0, 0, 0);
        custom.format = Format::Custom;
        assert_eq!(
            stream.push(&custom, |_| {}),
            Err(StreamError::Format(Format::Custom))
        );
        stream.push(&frame(0, 0, 0), |_| {}).unwrap();
        let mut coco = frame(1, 1000, 0);
        coco.format = Format::Coco17;
        assert_eq!(
            stream.push(&coco, |_| {}),
            Err(StreamError::Format(Format::Coco17))
        );
        assert_eq!(stream.counters().accepted, 1);
    }

    #[test]
    fn coco_midpoint_joints_need_both_keypoints() {
        let mut stream = PoseStream::new(StreamConfig::new(30)).unwrap();
        let mut f = frame(0, 0, 0);
        f.format = Format::Coco17;
        for (k, p) in f.joints_mm.iter_mut().enumerate() {
            p[0] = 10 * k as i16;
        }
        let mut joints = Vec::new();
        stream
            .push(&f, |e| {
                if let StreamEvent::Frame { joints: j, .. } = e {
                    joints.extend_from_slice(j);
                }
            })
            .unwrap();
        assert_eq!(joints.len(), Format::Coco17.joints().len());
        for (j, p) in Format::Coco17.joints().iter().zip(&joints) {
            let expected = match j.source {
                Source::Keypoint(i) => 0.01 * f32::from(i),
                Source::Mid(a, b) => 0.005 * f32::from(a + b),
            };
            assert!((p.x - expected).abs() < 1e-6, "{}", j.name);
        }
    }

    proptest! {
        #[test]
        fn any_arrival_order_emits_an_increasing_grid(
            arrivals in prop::collection::vec((0u32..40, 0u64..2_000_000, -2000i16..2000), 1..80),
        ) {
            let mut stream = PoseStream::new(StreamConfig::new(60)).unwrap();
            let mut xs = Vec::new();
            for (seq, t, x) in arrivals {
                let _ = stream.push(&frame(seq, t, x), |e| {
                    if let StreamEvent::Frame { joints, .. } = e {
                        xs.push(joints[0].x);
                    }
                });
            }
            let c = stream.counters();
            prop_assert_eq!(c.emitted as usize, xs.len());
            prop_assert!(xs.iter().all(|x| x.abs() <= 2.0));
            // Each frame taken completes at most the grid frames of one gap limit.
            prop_assert!(xs.len() <= c.accepted as usize * 16);
        }
    }
}
