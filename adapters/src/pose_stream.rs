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
//! A frame whose left and right the estimator swapped, or whose front and back it flipped, is
//! found by comparing it with the last frame taken: see [`RELABEL_MARGIN`]. It is read with its
//! labels put back (and, for a flip, its depth mirrored back), and all its joints are unsure, so
//! scoring treats it as missing.
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
use posecoach_core::joint::Joint;
use posecoach_core::math::norm;
use posecoach_core::plausible;
use posecoach_core::resample;
use posecoach_core::wire::{PoseFrame, MAX_WIRE_JOINTS};
use posecoach_core::{Quat, Vec3};

/// A gap between frames longer than this breaks the stream, seconds.
pub const MAX_GAP_S: f32 = 0.25;
/// Keypoints under this confidence (of 255) are unsure: see [`UNSURE_BONE_SHARE`].
pub const MIN_CONFIDENCE: u8 = 77;
/// An unsure keypoint (under the minimum confidence, but above 0) is taken as sent when its
/// distance from its parent is within this share of the bone's last length; else, and for a
/// keypoint of confidence 0, the joint is carried by its parent.
pub const UNSURE_BONE_SHARE: f32 = 0.3;

/// A frame is taken as swapped (or flipped) when the last frame taken is nearer its swapped
/// (flipped) reading than the reading as sent by at least this share of the squared distance
/// between the two readings: the last frame lies at least three quarters of the way from the
/// one reading to the other, measured along the line between them. The last frame is first
/// turned on about the vertical through its mean at the rate the body turned between the two
/// frames before it (the rigid turn that fits their sure joints best), so a body turning fast is
/// compared where it should be; until that rate is known (a stream's first two frames, and
/// after a break) a frame is not taken as flipped, since a turning pose that is its own mirror
/// image across the camera's axis moves as a flip would move it.
///
/// Why three quarters. Between two left/right counterparts (hips, knees, ankles, shoulders,
/// elbows, wrists: a person's are 0.2 to 0.5 m apart), the sent reading and the swapped one
/// differ only in the direction from the one to the other. A frame as sent is then taken as
/// swapped only if those directions turned, on average weighted by the squared widths, more
/// than 120° from where the last frame's turn would have them (cos 120° = -1/2), and a swapped
/// frame is missed only if they turned more than 60°. The fastest turn in a golf swing, the
/// arms' about 1 000 °/s through impact, is 33° in a frame at 30 Hz, and the feet, knees and
/// hips, which weigh most, turn far less; neither mistake needs a turn a body makes between two
/// frames. The midpoint (a half) would be the likelier reading at even odds; the margin keeps a
/// frame as sent where the turn is unusual. A relabelled reading must also lie within half the
/// distance between the readings of the last frame, in every direction and not only along the
/// line: where no reading comes near it (a downswing across lost frames, the arms a metre on),
/// the last frame cannot judge the frame, which keeps the reading in force. Going back to the
/// frame as sent needs no such nearness.
///
/// For flips the other reading is the frame with its left and right exchanged and its depth
/// (the sender's Z axis: a phone's camera axis) mirrored about its joints' mean depth. Where
/// the pose is its own mirror image across the camera's axis (a T-pose side on to the camera; a
/// golfer at address filmed down the line) the flipped reading barely differs from the sent
/// one, the flip barely matters, and it cannot be told from noise or a small turn:
/// [`MIN_RELABEL`].
pub const RELABEL_MARGIN: f32 = 0.5;
/// A relabelled reading counts only where it lies at least this many times what exchanging the
/// two hips moves a frame (twice their distance squared: 0.06 m² for hips 18 cm apart; their
/// mean distance over the frames taken) from the sent reading, in the sum of the joints'
/// squared distances. Three quarters of the way is then at least 0.19 m along the line between
/// them, nine times a sound frame's change along any one line from the fresh noise of the
/// phone model's 50 mm level (17 mm per keypoint, 3D; its drift, correlated over 0.2-1 s,
/// changes less between frames). A swap always passes (it exchanges the hips and more); a flip
/// that moves the frame less changes the body less than a swap of its hips would.
pub const MIN_RELABEL: f32 = 1.0;
/// Longest run of relabelled frames, seconds: a labelling the estimator holds for longer is its
/// reading of the golfer (a stream that started on a swapped frame, a flip that began where it
/// barely moved the body and was followed), and the frame is taken as sent. Estimators' swaps
/// and flips last a few frames.
pub const MAX_RELABEL_S: f32 = 1.0;

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
    /// Frames taken as left/right swapped ([`RELABEL_MARGIN`]): read with their labels put
    /// back, all their joints unsure.
    pub swapped: u32,
    /// Frames taken as front/back flipped: read with their labels put back and their depth
    /// mirrored back, all their joints unsure.
    pub flipped: u32,
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
        self.swapped = self.swapped.saturating_add(other.swapped);
        self.flipped = self.flipped.saturating_add(other.flipped);
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

/// How a frame is read back from what the estimator sent.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Relabel {
    /// Left and right exchanged.
    Swap,
    /// Left and right exchanged and the depth (Z) mirrored about `centre`.
    Flip { centre: f32 },
}

/// The joints of `format`'s left and right hips, where it has both.
fn hips(format: Format) -> Option<(usize, usize)> {
    let table = format.joints();
    let hip = |j: Joint| table.iter().position(|f| f.joint == Some(j));
    Some((hip(Joint::LeftHip)?, hip(Joint::RightHip)?))
}

/// A frame's readings (0 as sent, 1 swapped, 2 flipped) against the last frame taken.
#[derive(Clone, Copy, Debug)]
struct Readings {
    /// Each reading's sum of squared distances from the last frame, m².
    from_last: [f32; 3],
    /// The sums of squared distances between readings 0 and 1, 0 and 2, 1 and 2, m².
    apart: [f32; 3],
    /// What exchanging the hips moves a frame (twice their mean distance over the frames
    /// taken, squared), m².
    hips: f32,
    /// Whether the flipped reading may be taken: once the body's turn rate is known (a turning
    /// body that is its own mirror image across the camera's axis turns as a flip moves it).
    flip: bool,
    /// The depth the flip is mirrored about: the mean of the compared joints', m.
    centre: f32,
}

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
    /// The joints masked in the last frame taken (low confidence, too fast): those a
    /// relabelled frame is not compared on.
    previous_masked: u64,
    /// Whether the last frame taken is one to compare the next with: none before the first
    /// frame and after a break.
    reference: bool,
    /// How frames are read now: 0 as sent, 1 swapped, 2 flipped.
    reading: u8,
    /// The sum of the hips' distances over the frames taken with both sure, and how many.
    hips: (f32, u32),
    /// The body's turn rate about the vertical between the last two frames taken, rad/s, once
    /// there are two.
    spin: Option<f32>,
    /// The time of the first frame of the current run read relabelled.
    relabelled_since: Option<u64>,
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
            previous_masked: 0,
            reference: false,
            reading: 0,
            hips: (0.0, 0),
            spin: None,
            relabelled_since: None,
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
    #[inline(never)]
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
                self.reference = false;
                emit(StreamEvent::Gap);
            }
        }
        self.format = Some(frame.format);
        self.joints = joints.len();
        self.counters.accepted = self.counters.accepted.saturating_add(1);
        let mut joints = joints;
        let relabel = self.relabelling(&joints, frame.t_us);
        if let Some((relabel, moved)) = relabel {
            self.relabel(&mut joints, relabel, moved);
        }
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
                .map_or_else(Quat::identity, |g| {
                    let (was, is) = (self.previous[p] - self.previous[g], current[p] - current[g]);
                    posecoach_core::kinematics::swing(was, is)
                });
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
        let masked = unsure;
        if let Some((l, r)) = hips(frame.format) {
            if masked & (1 << l | 1 << r) == 0 {
                let (sum, n) = self.hips;
                self.hips = (sum + norm(&(current[l] - current[r])), n.saturating_add(1));
            }
        }
        if relabel.is_some_and(|(_, moved)| moved) {
            unsure |= u64::MAX >> (64 - self.joints.clamp(1, 64));
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
        let dt = self
            .last
            .map_or(0.0, |l| t_us.saturating_sub(l.t_us) as f32 * 1e-6);
        self.spin = self.turn_rate(&current[..self.joints.min(MAX_JOINTS)], masked, dt);
        self.previous = current;
        self.previous_unsure = unsure;
        self.previous_masked = masked;
        self.reference = true;
        self.last = Some(Taken {
            seq: frame.seq,
            t_us,
        });
        Ok(())
    }

    /// How `joints` (the frame at `t_us`) is to be read, and whether the reading moves it (then
    /// it is unsure): compared, on the joints sure in it and in the last frame taken, with that
    /// frame ([`RELABEL_MARGIN`], [`MIN_RELABEL`], [`MAX_RELABEL_S`]). A reading is kept until
    /// another is clearly better, so a run of swapped or flipped frames is followed through
    /// poses that are their own mirror image (where the readings do not differ). Bounded work:
    /// a few passes over the joints.
    #[inline(never)]
    fn relabelling(&mut self, joints: &[(Vec3, u8)], t_us: u64) -> Option<(Relabel, bool)> {
        let Some(c) = self.compare(joints, t_us) else {
            (self.reading, self.relabelled_since) = (0, None);
            return None;
        };
        // Squared distances between the readings (0 as sent, 1 swapped, 2 flipped).
        let apart = |a: usize, b: usize| match a + b {
            1 => c.apart[0],
            2 => c.apart[1],
            _ => c.apart[2],
        };
        // Reading `to` clearly better than `from`: the last frame three quarters of the way
        // from the one to the other (and, for a relabelled one, within half the distance
        // between them of it), and the two at least `MIN_RELABEL` apart.
        let clear = |from: usize, to: usize| {
            let between = apart(from, to);
            (to != 2 || c.flip)
                && c.from_last[from] - c.from_last[to] >= RELABEL_MARGIN * between
                && (to == 0 || c.from_last[to] <= 0.25 * between)
                && between >= MIN_RELABEL * c.hips
        };
        let now = usize::from(self.reading);
        let mut next = if clear(0, 2) && (!clear(0, 1) || clear(1, 2)) {
            2
        } else if clear(0, 1) {
            1
        } else if now != 0 && clear(now, 0) {
            0
        } else {
            now
        };
        match self.relabelled_since {
            _ if next == 0 => self.relabelled_since = None,
            Some(since) if t_us.saturating_sub(since) as f32 * 1e-6 > MAX_RELABEL_S => {
                (next, self.relabelled_since) = (0, None);
            }
            _ => {
                self.relabelled_since.get_or_insert(t_us);
            }
        }
        self.reading = next as u8;
        let moves = next != 0 && apart(0, next) >= MIN_RELABEL * c.hips;
        match next {
            1 => Some((Relabel::Swap, moves)),
            2 => Some((Relabel::Flip { centre: c.centre }, moves)),
            _ => None,
        }
    }

    /// The readings of `joints` (the frame at `t_us`) against the last frame taken, turned on
    /// about the vertical at the body's last turn rate, if there is one and they share a pair
    /// of counterparts sure in both.
    fn compare(&self, joints: &[(Vec3, u8)], t_us: u64) -> Option<Readings> {
        let format = self.format?;
        let last = self.last?;
        let (widths, frames) = self.hips;
        if !self.reference || self.seen.count_ones() as usize != self.joints || frames == 0 {
            return None;
        }
        let hip_width = widths / frames as f32;
        let previous = &self.previous;
        let min = self.config.min_confidence;
        let mirror = |k: usize| format.mirror_joint(k);
        let sure = |k: usize| {
            joints.get(k).is_some_and(|j| j.1 >= min)
                && k < 64
                && self.previous_masked & (1 << k) == 0
        };
        let used = |k: usize| sure(k) && sure(mirror(k));
        let (mut n, mut sum, mut sum_last, mut pairs) = (0usize, Vec3::zeros(), Vec3::zeros(), 0);
        for (k, ((p, _), q)) in joints.iter().zip(previous).enumerate() {
            if used(k) {
                n += 1;
                sum += p;
                sum_last += q;
                pairs += usize::from(mirror(k) != k);
            }
        }
        if pairs == 0 {
            return None;
        }
        let centre = sum.z / n as f32;
        let around = sum_last / n as f32;
        let dt = t_us.saturating_sub(last.t_us) as f32 * 1e-6;
        let angle = self.spin.unwrap_or(0.0) * dt;
        let (sin, cos) = posecoach_core::math::sin_cos(angle);
        let turned = |q: &Vec3| {
            let d = q - around;
            Vec3::new(
                around.x + cos * d.x + sin * d.z,
                q.y,
                around.z - sin * d.x + cos * d.z,
            )
        };
        let mut c = Readings {
            from_last: [0.0; 3],
            apart: [0.0; 3],
            hips: 2.0 * hip_width * hip_width,
            centre,
            flip: self.spin.is_some(),
        };
        for (k, (p, _)) in joints.iter().enumerate() {
            let (Some(last), Some(other)) = (previous.get(k), joints.get(mirror(k))) else {
                continue;
            };
            if !used(k) {
                continue;
            }
            let last = turned(last);
            let swapped = other.0;
            let flipped = Vec3::new(swapped.x, swapped.y, 2.0 * centre - swapped.z);
            let sq = |a: Vec3, b: &Vec3| (a - b).norm_squared();
            c.from_last[0] += sq(*p, &last);
            c.from_last[1] += sq(swapped, &last);
            c.from_last[2] += sq(flipped, &last);
            c.apart[0] += sq(swapped, p);
            c.apart[1] += sq(flipped, p);
            c.apart[2] += sq(flipped, &swapped);
        }
        Some(c)
    }

    /// The body's turn rate about the vertical from the last frame taken to `current` (taken
    /// `dt` seconds later), rad/s: the rigid turn of the joints sure in both that fits them
    /// best, about their means (0 without a last frame).
    #[inline(never)]
    fn turn_rate(&self, current: &[Vec3], masked: u64, dt: f32) -> Option<f32> {
        let both = |k: usize| k < 64 && (masked | self.previous_masked) & (1 << k) == 0;
        let pairs = || {
            current
                .iter()
                .zip(&self.previous)
                .take(self.joints)
                .enumerate()
                .filter(move |&(k, _)| both(k))
                .map(|(_, pair)| pair)
        };
        let n = pairs().count();
        if !self.reference || n < 2 || dt <= 0.0 {
            return None;
        }
        let (now, was) = pairs().fold((Vec3::zeros(), Vec3::zeros()), |(a, b), (p, q)| {
            (a + p, b + q)
        });
        let (now, was) = (now / n as f32, was / n as f32);
        let (mut dot, mut cross) = (0.0f32, 0.0f32);
        for (p, q) in pairs() {
            let (a, b) = (q - was, p - now);
            dot += a.x * b.x + a.z * b.z;
            cross += a.z * b.x - a.x * b.z;
        }
        Some(libm::atan2f(cross, dot) / dt)
    }

    /// Puts `joints` back as `relabel` says: each joint (with its confidence) takes its
    /// counterpart's place, and for a flip its depth is mirrored back about `centre`; counted
    /// where `counted`.
    #[inline(never)]
    fn relabel(&mut self, joints: &mut [(Vec3, u8)], relabel: Relabel, counted: bool) {
        let mut read = [(Vec3::zeros(), 0u8); MAX_JOINTS];
        for (r, j) in read.iter_mut().zip(joints.iter()) {
            *r = *j;
        }
        let format = self.format;
        for (k, j) in joints.iter_mut().enumerate() {
            let m = format.map_or(k, |f| f.mirror_joint(k));
            let (p, c) = read.get(m).copied().unwrap_or(*j);
            *j = match relabel {
                Relabel::Swap => (p, c),
                Relabel::Flip { centre } => (Vec3::new(p.x, p.y, 2.0 * centre - p.z), c),
            };
        }
        let count = match relabel {
            Relabel::Swap => &mut self.counters.swapped,
            Relabel::Flip { .. } => &mut self.counters.flipped,
        };
        *count = count.saturating_add(u32::from(counted));
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

    /// A golfer of 1.75 m at address facing +Z (the camera's depth axis, as a phone filming
    /// face on sends it), H36M-17: bent forward, knees flexed, arms hanging toward the ball;
    /// turned `turn` radians about the vertical and moved `x` metres along X.
    fn address(turn: f32, x: f32) -> [Vec3; 17] {
        let mut pose: [Vec3; 17] =
            core::array::from_fn(|k| Format::H36m17.joints()[k].place.position());
        for p in &mut pose {
            if p.y > 0.95 {
                p.z += 0.5 * (p.y - 0.95);
            }
        }
        for (k, p) in [
            (2, Vec3::new(-0.11, 0.5, 0.1)),
            (5, Vec3::new(0.11, 0.5, 0.1)),
            (12, Vec3::new(0.2, 1.1, 0.35)),
            (13, Vec3::new(0.05, 0.85, 0.45)),
            (15, Vec3::new(-0.2, 1.1, 0.35)),
            (16, Vec3::new(-0.05, 0.87, 0.45)),
        ] {
            pose[k] = p;
        }
        let (sin, cos) = libm::sincosf(turn);
        pose.map(|p| Vec3::new(cos * p.x + sin * p.z + x, p.y, -sin * p.x + cos * p.z))
    }

    /// What an estimator that swaps (or flips) a frame sends of `pose`: every keypoint in its
    /// counterpart's place, and for a flip the depths reversed about their mean.
    fn relabelled(pose: &[Vec3; 17], flip: bool) -> [Vec3; 17] {
        let centre = pose.iter().map(|p| p.z).sum::<f32>() / 17.0;
        core::array::from_fn(|i| {
            let p = pose[Format::H36m17.mirror_keypoint(i)];
            match flip {
                true => Vec3::new(p.x, p.y, 2.0 * centre - p.z),
                false => p,
            }
        })
    }

    /// Frame `seq` at 30 Hz (on the 30 Hz grid's own times) of `pose`.
    fn sent(seq: u32, pose: &[Vec3; 17]) -> PoseFrame {
        let mm = |v: f32| (v * 1000.0).round() as i16;
        PoseFrame {
            seq,
            t_us: (u64::from(seq) * 1_000_000 + 15) / 30,
            format: Format::H36m17,
            joints_mm: pose.iter().map(|p| [mm(p.x), mm(p.y), mm(p.z)]).collect(),
            confidence: core::iter::repeat_n(255, 17).collect(),
        }
    }

    /// Pushes each frame through a 30 Hz stream: per frame whether it was taken as swapped or
    /// flipped, the joints emitted at its time and whether all of them were unsure.
    fn read(frames: &[PoseFrame]) -> Vec<(u8, Vec<Vec3>, bool)> {
        let mut stream = PoseStream::new(StreamConfig::new(30)).unwrap();
        frames
            .iter()
            .map(|f| {
                let before = stream.counters();
                let mut out = (Vec::new(), false);
                stream
                    .push(f, |e| {
                        if let StreamEvent::Frame { joints, unsure, .. } = e {
                            out = (joints.to_vec(), unsure == (1 << 17) - 1);
                        }
                    })
                    .unwrap();
                let after = stream.counters();
                let taken = if after.swapped > before.swapped {
                    1
                } else if after.flipped > before.flipped {
                    2
                } else {
                    0
                };
                (taken, out.0, out.1)
            })
            .collect()
    }

    #[test]
    fn swapped_and_flipped_runs_are_read_back_and_unsure() {
        // A golfer at address turning 20°/s through 2 s at 30 Hz; frames 10-12 and 40-44
        // swapped, 25-30 flipped.
        let truth: Vec<[Vec3; 17]> = (0..60)
            .map(|i| address(i as f32 / 30.0 * 20f32.to_radians(), 0.0))
            .collect();
        let failure = |i: usize| match i {
            10..=12 | 40..=44 => 1,
            25..=30 => 2,
            _ => 0,
        };
        let frames: Vec<PoseFrame> = truth
            .iter()
            .enumerate()
            .map(|(i, pose)| match failure(i) {
                0 => sent(i as u32, pose),
                kind => sent(i as u32, &relabelled(pose, kind == 2)),
            })
            .collect();
        let read = read(&frames);
        for (i, ((taken, joints, all_unsure), pose)) in read.iter().zip(&truth).enumerate() {
            // Each failed frame is found, as its kind, and only those.
            assert_eq!(*taken, failure(i), "frame {i}");
            // Read back, it is the golfer's pose (within the wire's millimetres); and a failed
            // frame's joints are all unsure, as is the grid frame after it (which lies between
            // it and the next).
            for (j, p) in joints.iter().zip(pose) {
                assert!((j - p).norm() < 2e-3, "frame {i}: {j:?} against {p:?}");
            }
            assert_eq!(
                *all_unsure,
                failure(i) != 0 || failure(i.saturating_sub(1)) != 0
            );
        }
    }

    #[test]
    fn a_run_is_not_taken_as_the_truth_until_it_lasts_longer_than_any_estimator_failure() {
        let pose = |i: usize| address(i as f32 * 0.01, 0.0);
        let kind = |taken: &[(u8, Vec<Vec3>, bool)]| taken.iter().map(|t| t.0).collect::<Vec<_>>();
        // Swapped for 2 s at 30 Hz: taken as swapped for MAX_RELABEL_S (the 30 frames after
        // its first, 1 s), then as the estimator's reading of the golfer...
        let frames: Vec<PoseFrame> = (0..140)
            .map(|i| match i {
                10..70 => sent(i as u32, &relabelled(&pose(i), false)),
                _ => sent(i as u32, &pose(i)),
            })
            .collect();
        let taken = kind(&read(&frames));
        assert!(taken[..10].iter().all(|&t| t == 0), "{taken:?}");
        assert!(taken[10..41].iter().all(|&t| t == 1), "{taken:?}");
        assert!(taken[41..70].iter().all(|&t| t == 0), "{taken:?}");
        // ... so that when the estimator turns back, its frames look swapped for as long, and
        // are then read as sent again.
        assert!(taken[70..101].iter().all(|&t| t == 1), "{taken:?}");
        assert!(taken[101..].iter().all(|&t| t == 0), "{taken:?}");
        // A stream whose very first frame came swapped reads the sound ones after it swapped
        // for MAX_RELABEL_S.
        let frames: Vec<PoseFrame> = (0..60)
            .map(|i| match i {
                0 => sent(0, &relabelled(&pose(0), false)),
                _ => sent(i as u32, &pose(i)),
            })
            .collect();
        let taken = kind(&read(&frames));
        assert!(taken[1..32].iter().all(|&t| t == 1), "{taken:?}");
        assert!(taken[32..].iter().all(|&t| t == 0), "{taken:?}");
    }

    #[test]
    fn a_flip_that_moves_the_body_no_more_than_a_turn_is_read_as_sent() {
        // A T-pose side on to the camera (left and right along its depth axis) flipped is the
        // same pose: nothing to read back, and its joints stay sure. Swapped, its arms change
        // places, and that is found. Facing the camera, the flip is a swap (the depths barely
        // change), and is read back as one.
        let tpose: [Vec3; 17] =
            core::array::from_fn(|k| Format::H36m17.joints()[k].place.position());
        let side_on = tpose.map(|p| Vec3::new(p.z, p.y, -p.x));
        for (pose, flip) in [(side_on, 0), (tpose, 1)] {
            let frames: Vec<PoseFrame> = (0..10)
                .map(|i| match i {
                    4 => sent(i, &relabelled(&pose, true)),
                    7 => sent(i, &relabelled(&pose, false)),
                    _ => sent(i, &pose),
                })
                .collect();
            let read = read(&frames);
            assert_eq!((read[4].0, read[4].2), (flip, flip != 0), "{:?}", read[4]);
            assert_eq!((read[7].0, read[7].2), (1, true));
            assert!(read
                .iter()
                .enumerate()
                .all(|(i, r)| [4, 7].contains(&i) || r.0 == 0));
        }
    }

    /// Seeded draws (xorshift).
    struct Noise(u64);

    impl Noise {
        /// Uniform in (0, 1].
        fn uniform(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            ((self.0 >> 40) as f32 + 1.0) / (1u64 << 24) as f32
        }

        /// A keypoint's error of 3D RMS `mm`, the depth axis (Z) twice the others, metres.
        fn keypoint(&mut self, mm: f32) -> Vec3 {
            let sigma = mm * 1e-3 / posecoach_core::math::sqrt(6.0);
            let mut normal = || {
                let (a, b) = (self.uniform(), self.uniform());
                posecoach_core::math::sqrt(-2.0 * libm::logf(a))
                    * libm::cosf(core::f32::consts::TAU * b)
                    * sigma
            };
            Vec3::new(normal(), normal(), 2.0 * normal())
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

        /// A sound stream is not read relabelled: at most one frame in a hundred (the stated
        /// false rate; none is expected) of a golfer at address turning whole at up to 180 °/s
        /// and drifting, filmed at 30 Hz with the phone model's errors up to its 50 mm level
        /// (keypoint drift up to 50 mm correlated over 0.5 s, fresh noise of a third of it, both
        /// 3D RMS with the depth axis twice the others) and 5 % of frames lost.
        #[test]
        fn a_sound_noisy_stream_is_not_read_relabelled(
            turn_deg_s in -360f32..360.0,
            level_mm in 0f32..50.0,
            start in 0f32..6.3,
            seed in any::<u64>(),
        ) {
            let mut noise = Noise(seed | 1);
            let keep = libm::expf(-1.0 / 30.0 / 0.5);
            let mut drift: Vec<Vec3> = (0..17).map(|_| noise.keypoint(level_mm)).collect();
            let frames: Vec<PoseFrame> = (0..90u32)
                .filter_map(|i| {
                    let t = i as f32 / 30.0;
                    let pose = address(start + turn_deg_s.to_radians() * t, 0.2 * t);
                    for d in &mut drift {
                        *d = *d * keep + noise.keypoint(level_mm) * posecoach_core::math::sqrt(1.0 - keep * keep);
                    }
                    let noisy: [Vec3; 17] =
                        core::array::from_fn(|k| pose[k] + drift[k] + noise.keypoint(level_mm / 3.0));
                    (noise.uniform() > 0.05).then(|| sent(i, &noisy))
                })
                .collect();
            let relabelled = read(&frames).iter().filter(|r| r.0 != 0).count();
            prop_assert!(relabelled * 100 <= frames.len(), "{relabelled} of {}", frames.len());
        }
    }
}
