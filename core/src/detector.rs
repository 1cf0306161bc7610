//! Streaming swing detection: which stretch of a live pose stream is a swing.
//!
//! [`SwingDetector`] keeps the latest frames in a ring buffer the caller owns, in 16-bit
//! millimetres ([`Mm`]: half the RAM of `f32` metres, within 0.5 mm an axis). The hands'
//! speed (over [`SPEED_WINDOW_S`]) opens a candidate when it passes `open_speed`, with `pre_s`
//! of history kept before it for the set-up; the candidate closes once the hands have stayed
//! under `close_speed` for `settle_s` (a frame above it takes back [`SETTLE_SETBACK`]
//! frames), their speed then measured over [`SETTLE_WINDOW_S`]. It is a swing only if the hands
//! peaked above `min_peak_speed` and rose at least `min_rise`: walking, waggles and practice
//! half swings open candidates that fail those tests. A swing hands back a [`SwingWindow`],
//! scored where it lies with [`SwingDetector::with_window`].
//!
//! ```
//! use posecoach_core::detector::{DetectorConfig, SwingDetector};
//! use posecoach_core::format::Format;
//! use posecoach_core::skeleton::Skeleton;
//! use posecoach_core::Vec3;
//!
//! let skeleton = Skeleton::standard(Format::H36m17).unwrap();
//! let mut storage = [[0i16; 3]; 17 * 240];
//! let mut detector = SwingDetector::new(&skeleton, DetectorConfig::full_swing(60.0), &mut storage).unwrap();
//! let mut rest = [Vec3::zeros(); 17];
//! skeleton.rest_positions(&mut rest);
//! assert_eq!(detector.push(&rest), Ok(None));
//! ```

use crate::config::MAX_JOINTS;
use crate::frames::{to_mm, Frames, Mm};
use crate::joint::Joint;
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::Vec3;

/// Hand speed is measured over this long a stretch of frames.
pub const SPEED_WINDOW_S: f32 = 0.1;
/// Settling is judged on the hands' speed between their means over two successive stretches
/// this long (so that 50 mm of pose noise does not keep still hands above it).
pub const SETTLE_WINDOW_S: f32 = 0.2;
/// Skeleton height (feet to head, by bone lengths) of the golfer the hand thresholds are
/// given for: the 1.75 m standard T-pose. Hand speeds and rises scale with the body.
pub const REFERENCE_HEIGHT_M: f32 = 1.62;
/// Settled frames one frame above the settling speed takes back.
pub const SETTLE_SETBACK: usize = 2;

/// Thresholds of the detector. The speeds are of its activity signal: the hands' speed in m/s
/// for [`SwingDetector::push`], the caller's measure (rad/s for gyros) for
/// [`SwingDetector::push_with_activity`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DetectorConfig {
    /// Frame rate of the stream.
    pub rate_hz: f32,
    /// Activity that opens a candidate.
    pub open_speed: f32,
    /// Activity under which the hands count as settled.
    pub close_speed: f32,
    /// How long the hands must stay settled to close a candidate, seconds.
    pub settle_s: f32,
    /// History kept before the opening (the set-up and the start of the takeaway), seconds.
    pub pre_s: f32,
    /// A swing's activity must peak above this.
    pub min_peak_speed: f32,
    /// A swing's hands must rise at least this much, metres.
    pub min_rise: f32,
}

impl DetectorConfig {
    /// Full swings at `rate_hz`: a tour downswing moves the hands at 8-9 m/s and lifts them
    /// 0.8 m; a short golfer's iron on a 30 Hz stream with lost frames still shows 4.7 m/s;
    /// walking, waggles and practice half swings stay under 2 m/s.
    pub const fn full_swing(rate_hz: f32) -> DetectorConfig {
        DetectorConfig {
            rate_hz,
            open_speed: 1.0,
            close_speed: 0.4,
            settle_s: 0.4,
            pre_s: 1.0,
            min_peak_speed: 3.5,
            min_rise: 0.6,
        }
    }

    /// Full swings at `rate_hz` from the wrist sensors' angular speed in rad/s (to
    /// [`SwingDetector::push_with_activity`]): on synthetic wrist IMUs a driver and an iron
    /// peak at 25-33 rad/s, walking and practice half swings at 3-5, waggles at about 1.
    pub const fn gyro_swing(rate_hz: f32) -> DetectorConfig {
        DetectorConfig {
            open_speed: 2.5,
            close_speed: 1.0,
            min_peak_speed: 10.0,
            ..DetectorConfig::full_swing(rate_hz)
        }
    }
}

/// A detected swing: `len` frames starting at stream frame `start`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SwingWindow {
    /// Stream index of the first frame.
    pub start: u64,
    /// Frames in the window.
    pub len: usize,
}

/// Why the detector cannot be built or fed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DetectorError {
    /// The skeleton lacks a wrist (or hand).
    MissingJoint(Joint),
    /// The storage holds less than two seconds of frames, or a rate or threshold is not a
    /// positive number.
    Config,
    /// A frame has the wrong number of joints, or a position that is not finite or lies
    /// outside −32.768 m to 32.767 m (no millimetres to keep it in).
    Frame,
    /// The window no longer is in the ring buffer, or `out` is too short.
    Window,
}

impl core::fmt::Display for DetectorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DetectorError::MissingJoint(j) => write!(f, "swing detection needs the joint `{j}`"),
            DetectorError::Config => {
                f.write_str("storage under two seconds of frames, or a non-positive setting")
            }
            DetectorError::Frame => f.write_str(
                "a frame has the wrong joint count, or a position not finite or beyond ±32.7 m",
            ),
            DetectorError::Window => {
                f.write_str("the window has left the buffer, or the output is too short")
            }
        }
    }
}

impl core::error::Error for DetectorError {}

/// A candidate being watched.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    start: u64,
    peak: f32,
    low: f32,
    high: f32,
    settled: usize,
}

/// The streaming detector over caller-owned frame storage.
#[derive(Debug)]
pub struct SwingDetector<'s> {
    storage: &'s mut [Mm],
    joints: usize,
    wrists: [usize; 2],
    config: DetectorConfig,
    /// The body's height over [`REFERENCE_HEIGHT_M`].
    size: f32,
    capacity: usize,
    /// Frames pushed so far.
    seen: u64,
    candidate: Option<Candidate>,
}

impl<'s> SwingDetector<'s> {
    /// A detector for frames of `skeleton`, keeping as many frames as `storage` holds.
    ///
    /// # Errors
    /// [`DetectorError::MissingJoint`] without wrists or hands; [`DetectorError::Config`] for
    /// storage under two seconds or a non-positive setting.
    pub fn new(
        skeleton: &Skeleton,
        config: DetectorConfig,
        storage: &'s mut [Mm],
    ) -> Result<Self, DetectorError> {
        let wrists = Self::check(skeleton, config, storage.len())?;
        let joints = skeleton.len();
        Ok(SwingDetector {
            capacity: storage.len() / joints,
            storage,
            joints,
            wrists,
            config,
            size: skeleton.height() / REFERENCE_HEIGHT_M,
            seen: 0,
            candidate: None,
        })
    }

    /// Checks what [`SwingDetector::new`] checks, for storage of `storage_len` positions,
    /// without giving up the storage; returns the wrist (or hand) joints.
    ///
    /// # Errors
    /// As [`SwingDetector::new`].
    pub fn check(
        skeleton: &Skeleton,
        config: DetectorConfig,
        storage_len: usize,
    ) -> Result<[usize; 2], DetectorError> {
        let side = |wrist: Joint, hand: Joint| {
            skeleton
                .find(&[wrist, hand])
                .ok_or(DetectorError::MissingJoint(wrist))
        };
        let wrists = [
            side(Joint::LeftWrist, Joint::LeftHand)?,
            side(Joint::RightWrist, Joint::RightHand)?,
        ];
        let capacity = storage_len / skeleton.len().max(1);
        let c = config;
        let positive = [
            c.rate_hz,
            c.open_speed,
            c.close_speed,
            c.settle_s,
            c.pre_s,
            c.min_peak_speed,
            c.min_rise,
        ];
        if !positive.iter().all(|v| v.is_finite() && *v > 0.0)
            || (capacity as f32) < 2.0 * c.rate_hz
        {
            return Err(DetectorError::Config);
        }
        Ok(wrists)
    }

    /// Gives the storage back.
    pub fn into_storage(self) -> &'s mut [Mm] {
        self.storage
    }

    /// Forgets every frame (after a break in the stream): frames count from zero again and a
    /// candidate in progress is dropped.
    pub fn clear(&mut self) {
        self.seen = 0;
        self.candidate = None;
    }

    /// Whether a candidate swing is being watched: the hands passed the opening speed and
    /// have not yet settled (or the candidate outgrew the storage).
    pub fn watching(&self) -> bool {
        self.candidate.is_some()
    }

    /// Frames pushed so far.
    pub fn frames_seen(&self) -> u64 {
        self.seen
    }

    fn slot(&self, frame: u64) -> usize {
        (frame % self.capacity as u64) as usize * self.joints
    }

    fn hands(&self, frame: u64) -> Vec3 {
        metres(self.wrists_mm(frame), 2)
    }

    /// Both wrists' millimetres at `frame`, summed.
    fn wrists_mm(&self, frame: u64) -> [i32; 3] {
        let at = self.slot(frame);
        let (a, b) = (
            self.storage[at + self.wrists[0]],
            self.storage[at + self.wrists[1]],
        );
        core::array::from_fn(|i| i32::from(a[i]) + i32::from(b[i]))
    }

    /// The hands averaged over the `span` frames ending at `frame`.
    fn mean_hands(&self, frame: u64, span: u64) -> Vec3 {
        let span = span.min(frame + 1).max(1);
        // Summed exactly in millimetres, turned into metres once.
        let sum = (frame + 1 - span..=frame).fold([0i32; 3], |s, f| {
            let w = self.wrists_mm(f);
            core::array::from_fn(|i| s[i].saturating_add(w[i]))
        });
        metres(sum, 2 * span)
    }

    /// Takes the next frame; returns a window when it closes a swing. Activity is the hands'
    /// speed over [`SPEED_WINDOW_S`].
    ///
    /// # Errors
    /// [`DetectorError::Frame`] for a frame of the wrong length or with a position not finite
    /// or outside −32.768 m to 32.767 m (it is not stored).
    pub fn push(&mut self, frame: &[Vec3]) -> Result<Option<SwingWindow>, DetectorError> {
        self.step(frame, None)
    }

    /// As [`SwingDetector::push`], with the activity measured by the caller: for IMUs, the
    /// angular speed of the wrist or club sensors in rad/s (the thresholds of
    /// [`DetectorConfig::gyro_swing`]).
    ///
    /// # Errors
    /// As [`SwingDetector::push`], and [`DetectorError::Frame`] for a non-finite activity.
    pub fn push_with_activity(
        &mut self,
        frame: &[Vec3],
        activity: f32,
    ) -> Result<Option<SwingWindow>, DetectorError> {
        if !activity.is_finite() {
            return Err(DetectorError::Frame);
        }
        self.step(frame, Some(activity))
    }

    fn step(
        &mut self,
        frame: &[Vec3],
        activity: Option<f32>,
    ) -> Result<Option<SwingWindow>, DetectorError> {
        if frame.len() != self.joints {
            return Err(DetectorError::Frame);
        }
        let mut mm = [[0; 3]; MAX_JOINTS];
        for (m, p) in mm.iter_mut().zip(frame) {
            *m = to_mm(p).ok_or(DetectorError::Frame)?;
        }
        let now = self.seen;
        let at = self.slot(now);
        self.storage[at..at + self.joints].copy_from_slice(&mm[..self.joints]);
        self.seen += 1;

        let rate = self.config.rate_hz;
        let lag = ((SPEED_WINDOW_S * rate) as u64).max(1).min(now);
        let settle = ((SETTLE_WINDOW_S * rate) as u64).max(1);
        // The speed that opens and peaks is over one stretch; the one that settles is between
        // the means of two, which pose noise does not keep above the settling speed.
        let (speed, steady) = match activity {
            Some(a) => (a, a),
            None if lag == 0 => (0.0, 0.0),
            None => {
                let back = settle.min(now);
                let moved = self.mean_hands(now, settle) - self.mean_hands(now - back, settle);
                (
                    norm(&(self.hands(now) - self.hands(now - lag))) * rate / lag as f32,
                    norm(&moved) * rate / back.max(1) as f32,
                )
            }
        };
        let height = self.hands(now).y;
        let c = self.config;
        let Some(mut candidate) = self.candidate else {
            if speed > c.open_speed {
                let pre = (c.pre_s * rate) as u64;
                self.candidate = Some(Candidate {
                    start: now.saturating_sub(pre),
                    peak: speed,
                    low: height,
                    high: height,
                    settled: 0,
                });
            }
            return Ok(None);
        };
        candidate.peak = candidate.peak.max(speed);
        candidate.low = candidate.low.min(height);
        candidate.high = candidate.high.max(height);
        // A frame above the settling speed takes back two settled frames rather than all: a
        // noisy stream still settles, a swing (fast for far longer) does not.
        candidate.settled = if steady < c.close_speed {
            candidate.settled + 1
        } else {
            candidate.settled.saturating_sub(SETTLE_SETBACK)
        };
        let len = (now + 1 - candidate.start) as usize;
        if len >= self.capacity {
            // Longer than the buffer holds: not a swing we can score.
            self.candidate = None;
            return Ok(None);
        }
        if (candidate.settled as f32) < c.settle_s * rate {
            self.candidate = Some(candidate);
            return Ok(None);
        }
        self.candidate = None;
        // Hand speeds and rises scale with the body; an IMU's activity (rad/s) does not.
        let peak = match activity {
            Some(_) => c.min_peak_speed,
            None => c.min_peak_speed * self.size,
        };
        let swing =
            candidate.peak >= peak && candidate.high - candidate.low >= c.min_rise * self.size;
        Ok(swing.then_some(SwingWindow {
            start: candidate.start,
            len,
        }))
    }

    /// Calls `f` with `window`'s frames, oldest first, contiguous in the detector's own
    /// storage: the ring is rotated so that the window starts it, and rotated back after `f`
    /// returns, so a caller scores a swing where it lies instead of copying it out (the
    /// rotations cost two passes over the ring; a copy would cost a second buffer).
    ///
    /// # Errors
    /// [`DetectorError::Window`] when the window's oldest frames have been overwritten or it
    /// has not been seen yet.
    pub fn with_window<R>(
        &mut self,
        window: &SwingWindow,
        f: impl FnOnce(Frames<'_>) -> R,
    ) -> Result<R, DetectorError> {
        let end = window.start + window.len as u64;
        if end > self.seen || self.seen - window.start > self.capacity as u64 {
            return Err(DetectorError::Window);
        }
        let ring = &mut self.storage[..self.capacity * self.joints];
        let turn = (window.start % self.capacity as u64) as usize * self.joints;
        turn_left(ring, turn);
        let result = f(Frames::millimetres(
            &ring[..window.len * self.joints],
            self.joints,
        ));
        turn_left(ring, ring.len() - turn);
        Ok(result)
    }
}

/// Turns `ring` left by `by` positions (as `rotate_left`) by three reversals: each position
/// is swapped twice, where core's rotation moves it about once, but in a few dozen bytes of
/// code where core's takes 3.7 KiB of the device's flash (its three algorithms for every
/// length).
fn turn_left(ring: &mut [Mm], by: usize) {
    if let Some((front, back)) = ring.split_at_mut_checked(by) {
        front.reverse();
        back.reverse();
        ring.reverse();
    }
}

/// The mean position, metres, of `count` positions whose millimetres sum to `sum`.
fn metres(sum: [i32; 3], count: u64) -> Vec3 {
    let per = 1000.0 * count as f32;
    Vec3::new(
        sum[0] as f32 / per,
        sum[1] as f32 / per,
        sum[2] as f32 / per,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;

    const RATE_HZ: f32 = 60.0;

    #[test]
    fn bad_setup_and_frames_are_errors() {
        let s = Skeleton::standard(Format::H36m17).unwrap();
        let mut small = [[0i16; 3]; 17 * 60];
        assert_eq!(
            SwingDetector::new(&s, DetectorConfig::full_swing(RATE_HZ), &mut small).err(),
            Some(DetectorError::Config)
        );
        let mut storage = [[0i16; 3]; 17 * 200];
        let bad_rate = DetectorConfig {
            rate_hz: f32::NAN,
            ..DetectorConfig::full_swing(RATE_HZ)
        };
        assert_eq!(
            SwingDetector::new(&s, bad_rate, &mut storage).err(),
            Some(DetectorError::Config)
        );
        let mut d =
            SwingDetector::new(&s, DetectorConfig::full_swing(RATE_HZ), &mut storage).unwrap();
        assert_eq!(d.push(&[Vec3::zeros(); 3]), Err(DetectorError::Frame));
        let mut nan = [Vec3::zeros(); 17];
        nan[4].z = f32::INFINITY;
        assert_eq!(d.push(&nan), Err(DetectorError::Frame));
        let mut far = [Vec3::zeros(); 17];
        far[16].x = 40.0;
        assert_eq!(d.push(&far), Err(DetectorError::Frame));
        assert_eq!(d.frames_seen(), 0);
        assert_eq!(
            d.with_window(&SwingWindow { start: 0, len: 1 }, |_| ()),
            Err(DetectorError::Window)
        );
    }

    #[test]
    fn a_window_across_the_ring_s_end_reads_in_order_and_the_ring_is_restored() {
        let s = Skeleton::standard(Format::H36m17).unwrap();
        let capacity = (2.0 * RATE_HZ) as usize;
        let mut storage = vec![[0i16; 3]; capacity * 17];
        let mut d =
            SwingDetector::new(&s, DetectorConfig::full_swing(RATE_HZ), &mut storage).unwrap();
        // Still frames, each marked with its number (centimetres): far more than the ring holds.
        let frame = |n: usize| [Vec3::new(n as f32 / 100.0, 1.0, 0.0); 17];
        for n in 0..capacity + capacity / 2 {
            d.push(&frame(n)).unwrap();
        }
        let window = SwingWindow {
            start: (capacity - 10) as u64,
            len: 30,
        };
        let before = d.storage.to_vec();
        let seen: Vec<usize> = d
            .with_window(&window, |frames| {
                (0..frames.len())
                    .map(|f| (frames.at(f, 0).x * 100.0).round() as usize)
                    .collect()
            })
            .unwrap();
        let expected: Vec<usize> = (capacity - 10..capacity + 20).collect();
        assert_eq!(seen, expected);
        assert_eq!(d.storage, &before[..]);
        let gone = SwingWindow { start: 0, len: 5 };
        assert_eq!(d.with_window(&gone, |_| ()), Err(DetectorError::Window));
    }

    #[test]
    fn it_watches_from_fast_hands_until_they_settle() {
        let s = Skeleton::standard(Format::H36m17).unwrap();
        let mut storage = vec![[0i16; 3]; 17 * 6 * RATE_HZ as usize];
        let mut d =
            SwingDetector::new(&s, DetectorConfig::full_swing(RATE_HZ), &mut storage).unwrap();
        let at = |x: f32| [Vec3::new(x, 1.0, 0.0); 17];
        for _ in 0..30 {
            d.push(&at(0.0)).unwrap();
        }
        assert!(!d.watching());
        // Every joint, the hands among them, moving at 3 m/s for 0.2 s: watched.
        let mut x = 0.0;
        for _ in 0..12 {
            x += 3.0 / RATE_HZ;
            d.push(&at(x)).unwrap();
        }
        assert!(d.watching());
        // Still again: watched until the hands have settled (0.4 s and the means' span),
        // then not (a slow movement is no swing, so no window comes out).
        let mut closed = None;
        for n in 0..90 {
            if d.push(&at(x)).unwrap().is_some() {
                closed = Some(n);
            }
            if !d.watching() {
                break;
            }
        }
        assert_eq!(closed, None);
        assert!(!d.watching());
        d.push(&at(x + 1.0)).unwrap();
        d.clear();
        assert!(!d.watching());
    }
}
