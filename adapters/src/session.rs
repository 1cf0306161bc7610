//! A scoring session: the device's pipeline from wire messages to swing reports.
//!
//! [`Session::handle`] takes each decoded message. A `StudentProfile` gives the student's body
//! (bone lengths measured from the T-pose, directions from the format's standard T-pose) and
//! retargets the selected coach reference onto it once: with the int8 network
//! ([`Session::with_network`]) when the model rate is the network's, else with the analytic
//! retargeter; the network's scratch is the detector's ring, free while the session is set
//! up. `Config` and `CoachSelect` change the settings. Pose frames then go through the [`PoseStream`] onto the model rate's grid, are
//! put onto the student's skeleton as rigid bones (the analytic retargeter, which also maps a
//! stream format other than the profile's), and feed the [`SwingDetector`]. Each swing it
//! closes is scored where it lies in the detector's ring (its last [`MAX_SWING_FRAMES`]
//! frames, [`SwingDetector::with_window`]), cut to the swing itself
//! (set-up to finish with [`SWING_MARGIN_S`] either side, as is the coach's reference) and
//! scored against the virtual coach; the caller hears of it as an [`Outcome`]. A break in the stream drops a
//! swing in progress. Every buffer belongs to the caller ([`Buffers`], sized by
//! [`BufferLens::new`]); nothing allocates and nothing panics.
//!
//! With a `SensorLayout` the session takes IMU samples instead: the [`ImuAdapter`] fuses them
//! into frames on the student's skeleton (after a still T-pose for calibration), and the
//! detector is driven by the wrist sensors' angular speed.
//!
//! Only full swings are detected (the detector wants the hands fast and high); putts are scored
//! from files on the host.

use crate::fusion::FusionError;
use crate::imu::{ImuAdapter, ImuError};
use crate::pose_stream::{PoseStream, StreamConfig, StreamCounters, StreamError, StreamEvent};
use core::ops::Range;
use posecoach_core::config::MAX_SWING_FRAMES;
use posecoach_core::detector::{DetectorConfig, DetectorError, SwingDetector, SwingWindow};
use posecoach_core::events::{self, EventError, SwingEvents, STILL_S};
use posecoach_core::format::Format;
use posecoach_core::math::norm;
use posecoach_core::network::{self, NetworkError};
use posecoach_core::reference::Reference;
use posecoach_core::retarget::Analytic;
use posecoach_core::score::{self, Detected, Report, ScoreError};
use posecoach_core::skeleton::{Skeleton, SkeletonError};
use posecoach_core::weights::{Architecture, Weights};
use posecoach_core::wire::{
    Config, ImuSample, Message, NackReason, PoseFrame, SensorLayout, StudentProfile,
};
use posecoach_core::{config::MAX_JOINTS, Vec3};

/// Settings until a `Config` message arrives.
pub const DEFAULT_CONFIG: Config = Config {
    model_rate_hz: 60,
    band_radius: 10,
    anchored: true,
};
/// Seconds of frames the detector keeps.
pub const RING_S: f32 = 6.0;
/// Swings are scored from this long before the set-up to this long after the finish (the
/// still set-up that the event detector looks for), seconds.
pub const SWING_MARGIN_S: f32 = STILL_S;
/// Lowest and highest model rates, Hz.
pub const RATES_HZ: (u16, u16) = (20, 120);

/// A stored coach reference swing.
#[derive(Clone, Copy, Debug)]
pub struct Coach<'c> {
    /// The coach's skeleton.
    pub skeleton: &'c Skeleton,
    /// Frames × joints of `skeleton`.
    pub positions: &'c [Vec3],
    /// Frame rate, Hz.
    pub rate_hz: f32,
}

impl<'c> From<&'c Reference<'c>> for Coach<'c> {
    /// A stored reference ([`posecoach_core::reference`]) as the session takes it.
    fn from(reference: &'c Reference<'c>) -> Coach<'c> {
        Coach {
            skeleton: reference.skeleton(),
            positions: reference.positions(),
            rate_hz: reference.rate_hz(),
        }
    }
}

impl Coach<'_> {
    fn frames(&self) -> usize {
        self.positions.len() / self.skeleton.len().max(1)
    }

    /// Its frames at `rate_hz`, as the session keeps the virtual coach
    /// ([`frames_at`]).
    pub fn frames_at(&self, rate_hz: u16) -> usize {
        frames_at(self.frames(), self.rate_hz, rate_hz)
    }

    /// Where frame `k` at `rate_hz` falls among the coach's own frames: the frame before and
    /// the fraction of the way to the next. Rates within [`SAME_RATE`] of each other are the
    /// same rate (a 60.00006 Hz capture is a 60 Hz one): the frames are then used as they are.
    fn source_of(&self, k: usize, rate_hz: u16) -> (usize, f32) {
        if same_rate(self.rate_hz, rate_hz) {
            return (k, 0.0);
        }
        let t = k as f32 * self.rate_hz / f32::from(rate_hz);
        let i = (t as usize).min(self.frames().saturating_sub(1));
        (i, t - i as f32)
    }
}

/// Relative difference under which two frame rates are one.
pub const SAME_RATE: f32 = 1e-3;

const fn same_rate(coach_hz: f32, rate_hz: u16) -> bool {
    let ratio = coach_hz / rate_hz as f32;
    ratio > 1.0 - SAME_RATE && ratio < 1.0 + SAME_RATE
}

/// Frames a coach reference of `frames` frames at `coach_hz` has at the model rate `rate_hz`:
/// the session retargets the coach at the model rate (interpolating its frames), so that the
/// student's and the coach's swings are compared frame for frame; the same frames when the
/// rates are the same ([`SAME_RATE`]).
pub const fn frames_at(frames: usize, coach_hz: f32, rate_hz: u16) -> usize {
    if frames == 0 || same_rate(coach_hz, rate_hz) {
        return frames;
    }
    ((frames - 1) as f32 * rate_hz as f32 / coach_hz) as usize + 1
}

/// Lengths of the buffers a session needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferLens {
    /// Positions of the detector's history.
    pub ring: usize,
    /// Positions of the virtual coach.
    pub coach: usize,
    /// Scoring floats.
    pub floats: usize,
    /// Scoring bytes.
    pub bytes: usize,
}

impl BufferLens {
    /// For students of up to `joints` joints, coaches of up to `coach_frames` frames at the
    /// model rate ([`frames_at`]) and model rates up to `rate_hz`.
    pub const fn new(joints: usize, coach_frames: usize, rate_hz: u16) -> BufferLens {
        let ring_frames = (RING_S * rate_hz as f32) as usize;
        // A swing is scored in the ring, so it is never longer than the ring.
        let swing = if ring_frames < MAX_SWING_FRAMES {
            ring_frames
        } else {
            MAX_SWING_FRAMES
        };
        let scratch = score::scratch_len(swing, coach_frames);
        BufferLens {
            ring: joints * ring_frames,
            coach: joints * coach_frames,
            floats: scratch.floats,
            bytes: scratch.bytes,
        }
    }

    /// These lengths with a ring that also holds, while the session is set up, the int8
    /// network `a`'s input (`coach_frames` frames of a coach of `coach_joints` joints) and
    /// its scratch, for students of up to `joints` joints.
    pub const fn with_network(
        self,
        a: &Architecture,
        joints: usize,
        coach_joints: usize,
        coach_frames: usize,
    ) -> BufferLens {
        let bytes = network::scratch_len(a, coach_joints, joints);
        let ring = coach_frames * coach_joints + bytes.div_ceil(core::mem::size_of::<Vec3>());
        BufferLens {
            ring: if ring > self.ring { ring } else { self.ring },
            ..self
        }
    }
}

/// The caller's buffers, at least [`BufferLens`] long.
#[derive(Debug)]
pub struct Buffers<'b> {
    /// The detector's history.
    pub ring: &'b mut [Vec3],
    /// The virtual coach.
    pub coach: &'b mut [Vec3],
    /// Scoring floats.
    pub floats: &'b mut [f32],
    /// Scoring bytes.
    pub bytes: &'b mut [u8],
}

/// [`Buffers`] of the given lengths on the heap, for host tools and tests.
#[cfg(feature = "std")]
#[derive(Clone, Debug)]
pub struct OwnedBuffers {
    ring: std::vec::Vec<Vec3>,
    coach: std::vec::Vec<Vec3>,
    floats: std::vec::Vec<f32>,
    bytes: std::vec::Vec<u8>,
}

#[cfg(feature = "std")]
impl OwnedBuffers {
    /// Zeroed buffers of `lens`.
    pub fn new(lens: BufferLens) -> OwnedBuffers {
        OwnedBuffers {
            ring: std::vec![Vec3::zeros(); lens.ring],
            coach: std::vec![Vec3::zeros(); lens.coach],
            floats: std::vec![0.0; lens.floats],
            bytes: std::vec![0; lens.bytes],
        }
    }

    /// The buffers, for [`Session::new`].
    pub fn buffers(&mut self) -> Buffers<'_> {
        Buffers {
            ring: &mut self.ring,
            coach: &mut self.coach,
            floats: &mut self.floats,
            bytes: &mut self.bytes,
        }
    }
}

/// Where a swing sits in the stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Swing {
    /// Swings found so far in this session, this one included.
    pub number: u32,
    /// Time of its first frame on the sender's clock, microseconds.
    pub start_us: u64,
    /// Its frames at the model rate.
    pub frames: usize,
}

/// The two swings a report compares, on the student's skeleton: what a report view draws.
#[derive(Clone, Copy, Debug)]
pub struct Compared<'r> {
    /// The student's skeleton.
    pub skeleton: &'r Skeleton,
    /// The student's swing, frame-major.
    pub student: &'r [Vec3],
    /// Its frame rate.
    pub student_hz: f32,
    /// The virtual coach's swing (the coach retargeted onto the student), frame-major.
    pub coach: &'r [Vec3],
    /// Its frame rate.
    pub coach_hz: f32,
}

/// What a message led to.
#[derive(Debug)]
pub enum Outcome<'r> {
    /// A swing, scored.
    Scored {
        /// Where it is.
        swing: Swing,
        /// Its report.
        report: &'r Report,
        /// The swings the report compares.
        compared: Compared<'r>,
    },
    /// A swing that could not be scored (its events not found, or not like the coach's).
    Unscored {
        /// Where it is.
        swing: Swing,
        /// Why.
        error: ScoreError,
    },
    /// The message was refused (a phone would get a `Nack`).
    Refused(Refusal),
}

impl Outcome<'_> {
    /// What a device answers to `message` when handling it led to this: a `SwingReport` for
    /// a scored swing, a `Nack` for a refusal (of the pose frame's `seq`, else 0), nothing for
    /// a swing that could not be scored.
    pub fn reply(&self, message: &Message) -> Option<Message> {
        match self {
            Outcome::Scored { swing, report, .. } => {
                Some(Message::SwingReport(report.to_wire(swing.number)))
            }
            Outcome::Unscored { .. } => None,
            Outcome::Refused(why) => Some(Message::Nack {
                seq: match message {
                    Message::PoseFrame(f) => f.seq,
                    _ => 0,
                },
                reason: why.nack_reason(),
            }),
        }
    }
}

/// Why a message was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refusal {
    /// Pose frames before any `StudentProfile`.
    NoProfile,
    /// The profile's keypoints do not make a skeleton.
    Profile(SkeletonError),
    /// The profile's format has no joint table, or its keypoint count is wrong.
    ProfileFormat(Format),
    /// No stored coach reference has this number.
    UnknownCoach(u16),
    /// The buffers are too small for this student, coach or rate.
    Buffers,
    /// A model rate outside [`RATES_HZ`] or a zero band.
    Config,
    /// The student's skeleton lacks what swing detection needs.
    Detector(DetectorError),
    /// The pose frame does not fit the stream.
    Stream(StreamError),
    /// The coach cannot be retargeted onto the student (degenerate skeleton).
    Retarget,
    /// No swing found in the coach reference on the student's body.
    CoachSwing(EventError),
    /// IMU samples before a `SensorLayout`, or pose frames after one.
    Input,
    /// The layout does not fit the student, or a sample is degenerate.
    Imu(ImuError),
}

impl Refusal {
    /// The reason a `Nack` gives: the message came at the wrong time, did not fit the session
    /// now, or is wrong in itself.
    pub fn nack_reason(self) -> NackReason {
        match self {
            Refusal::NoProfile | Refusal::Input => NackReason::Unexpected,
            Refusal::Buffers => NackReason::Busy,
            _ => NackReason::Invalid,
        }
    }
}

impl core::fmt::Display for Refusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Refusal::NoProfile => f.write_str("pose frames before a student profile"),
            Refusal::Profile(e) => write!(f, "student profile: {e}"),
            Refusal::ProfileFormat(format) => write!(
                f,
                "student profile in format `{}` with no joint table or the wrong keypoint count",
                format.name()
            ),
            Refusal::UnknownCoach(n) => write!(f, "no coach reference number {n}"),
            Refusal::Buffers => f.write_str("buffers too small for this student, coach or rate"),
            Refusal::Config => write!(
                f,
                "model rate outside {} to {} Hz, or a zero band",
                RATES_HZ.0, RATES_HZ.1
            ),
            Refusal::Detector(e) => write!(f, "swing detection: {e}"),
            Refusal::Stream(e) => write!(f, "pose stream: {e}"),
            Refusal::Retarget => f.write_str("the coach cannot be retargeted onto the student"),
            Refusal::CoachSwing(e) => write!(f, "the coach reference on this student: {e}"),
            Refusal::Input => f.write_str(
                "IMU samples before a sensor layout, or pose frames in a session with IMUs",
            ),
            Refusal::Imu(e) => write!(f, "IMU: {e}"),
        }
    }
}

/// Everything that follows the student's body.
#[derive(Debug)]
struct Student<'b> {
    skeleton: Skeleton,
    /// Skeleton of the stream's format scaled to the student, once the format is known.
    source: Option<Skeleton>,
    stream: PoseStream,
    detector: SwingDetector<'b>,
    /// Stream time of the detector's frame 0.
    t0_us: Option<u64>,
    /// The virtual coach's swing: frames from its set-up to its finish.
    coach_swing: Range<usize>,
    /// The events of the virtual coach's swing, found once.
    coach_events: SwingEvents,
    /// The IMUs' fusion, in a session with a sensor layout.
    imu: Option<ImuAdapter>,
}

/// One session; see the [module documentation](self).
#[derive(Debug)]
pub struct Session<'b> {
    coaches: &'b [Coach<'b>],
    network: Option<&'b Weights<'b>>,
    config: Config,
    coach: u16,
    profile: Option<Skeleton>,
    layout: Option<SensorLayout>,
    student: Option<Student<'b>>,
    /// The ring while no detector holds it.
    spare: &'b mut [Vec3],
    virtual_coach: &'b mut [Vec3],
    floats: &'b mut [f32],
    bytes: &'b mut [u8],
    swings: u32,
    report: Option<Report>,
    /// Counters of the pose streams before the current one.
    counted: StreamCounters,
    /// IMU samples not newer than their sensor's last one.
    stale: u32,
}

impl<'b> Session<'b> {
    /// A session choosing among `coaches` (reference 0 until a `CoachSelect`), with
    /// [`DEFAULT_CONFIG`] until a `Config` arrives.
    pub fn new(coaches: &'b [Coach<'b>], buffers: Buffers<'b>) -> Session<'b> {
        Session::start(coaches, buffers, DEFAULT_CONFIG)
    }

    /// As [`Session::new`] with the device's own settings until a `Config` arrives: a device
    /// whose buffers fit only its own model rate takes a profile sent before the settings.
    ///
    /// # Errors
    /// [`Refusal::Config`] for a model rate outside [`RATES_HZ`] or a zero band.
    pub fn with_config(
        coaches: &'b [Coach<'b>],
        buffers: Buffers<'b>,
        config: Config,
    ) -> Result<Session<'b>, Refusal> {
        if !valid(&config) {
            return Err(Refusal::Config);
        }
        Ok(Session::start(coaches, buffers, config))
    }

    /// This session retargeting coaches with the int8 network of `weights` whenever the model
    /// rate is the network's ([`Architecture::rate_hz`]); its ring must then be as long as
    /// [`BufferLens::with_network`] says. Set it before the profile arrives.
    pub fn with_network(mut self, weights: &'b Weights<'b>) -> Session<'b> {
        self.network = Some(weights);
        self
    }

    fn start(coaches: &'b [Coach<'b>], buffers: Buffers<'b>, config: Config) -> Session<'b> {
        Session {
            coaches,
            network: None,
            config,
            coach: 0,
            profile: None,
            layout: None,
            student: None,
            spare: buffers.ring,
            virtual_coach: buffers.coach,
            floats: buffers.floats,
            bytes: buffers.bytes,
            swings: 0,
            report: None,
            counted: StreamCounters::default(),
            stale: 0,
        }
    }

    /// The settings in force.
    pub fn config(&self) -> Config {
        self.config
    }

    /// What the pose streams of this session have taken and dropped.
    pub fn stream_counters(&self) -> StreamCounters {
        let mut total = self.counted;
        if let Some(s) = &self.student {
            total.add(&s.stream.counters());
        }
        total
    }

    /// IMU samples dropped for not being newer than their sensor's last one (repeated or late
    /// on the link); they are not refusals.
    pub fn stale_samples(&self) -> u32 {
        self.stale
    }

    /// The student's skeleton, once a profile has been taken.
    pub fn student(&self) -> Option<&Skeleton> {
        self.profile.as_ref()
    }

    /// Takes one message and calls `on` with what it led to. Messages a device sends rather
    /// than receives are ignored.
    pub fn handle(&mut self, message: &Message, mut on: impl FnMut(Outcome<'_>)) {
        let refusal = match message {
            Message::StudentProfile(p) => self.profile(p).err(),
            Message::Config(c) => {
                if valid(c) {
                    self.reconfigure(|s| &mut s.config, *c).err()
                } else {
                    Some(Refusal::Config)
                }
            }
            Message::CoachSelect { coach } => {
                if usize::from(*coach) >= self.coaches.len() {
                    Some(Refusal::UnknownCoach(*coach))
                } else {
                    self.reconfigure(|s| &mut s.coach, *coach).err()
                }
            }
            Message::SensorLayout(layout) => self
                .reconfigure(|s| &mut s.layout, Some(layout.clone()))
                .err(),
            Message::PoseFrame(frame) => self.pose(frame, &mut on).err(),
            Message::ImuSample(sample) => self.imu(sample, &mut on).err(),
            _ => None,
        };
        if let Some(r) = refusal {
            on(Outcome::Refused(r));
        }
    }

    fn profile(&mut self, profile: &StudentProfile) -> Result<(), Refusal> {
        let format = profile.format;
        let table = format.joints();
        if table.is_empty() || profile.joints_mm.len() != format.keypoints().len() {
            return Err(Refusal::ProfileFormat(format));
        }
        let mut keypoints = [Vec3::zeros(); MAX_JOINTS];
        for (k, [x, y, z]) in keypoints.iter_mut().zip(&profile.joints_mm) {
            *k = Vec3::new(f32::from(*x), f32::from(*y), f32::from(*z)) * 1e-3;
        }
        let mut joints = [Vec3::zeros(); MAX_JOINTS];
        format
            .map_keypoints(&keypoints[..profile.joints_mm.len()], &mut joints)
            .map_err(|_| Refusal::ProfileFormat(format))?;
        let template = Skeleton::standard(format).map_err(Refusal::Profile)?;
        let lengths: [f32; MAX_JOINTS] = core::array::from_fn(|k| {
            (k < template.len())
                .then(|| template.parent(k))
                .flatten()
                .map_or(0.0, |p| norm(&(joints[k] - joints[p])))
        });
        let skeleton = template
            .with_bone_lengths(&lengths[..template.len()])
            .map_err(Refusal::Profile)?;
        self.reconfigure(|s| &mut s.profile, Some(skeleton))
    }

    /// Sets a field and rebuilds what follows it; if that fails the field gets its old value
    /// back and the session is rebuilt as it was (a swing in progress is dropped either way).
    fn reconfigure<T>(&mut self, field: fn(&mut Self) -> &mut T, value: T) -> Result<(), Refusal> {
        let previous = core::mem::replace(field(self), value);
        self.restart().inspect_err(|_| {
            *field(self) = previous;
            // What worked before works again.
            let _ = self.restart();
        })
    }

    /// Rebuilds everything that follows the profile, coach and settings.
    fn restart(&mut self) -> Result<(), Refusal> {
        let Some(skeleton) = self.profile.clone() else {
            return Ok(());
        };
        let coach = self
            .coaches
            .get(usize::from(self.coach))
            .ok_or(Refusal::UnknownCoach(self.coach))?;
        let rate = self.config.model_rate_hz;
        let joints = skeleton.len();
        let detector = match self.layout {
            Some(_) => DetectorConfig::gyro_swing(f32::from(rate)),
            None => DetectorConfig::full_swing(f32::from(rate)),
        };
        let ring = match self.student.take() {
            Some(s) => {
                self.counted.add(&s.stream.counters());
                s.detector.into_storage()
            }
            None => core::mem::take(&mut self.spare),
        };
        let checked = SwingDetector::check(&skeleton, detector, ring.len())
            .map_err(Refusal::Detector)
            .and_then(|_| {
                let frames = coach.frames_at(rate);
                let network = self
                    .network
                    .filter(|w| same_rate(w.architecture().rate_hz, rate));
                let mut needed = BufferLens::new(joints, frames, rate);
                if let Some(w) = network {
                    let n = coach.skeleton.len();
                    needed = needed.with_network(w.architecture(), joints, n, frames);
                }
                let fits = ring.len() >= needed.ring
                    && self.virtual_coach.len() >= needed.coach
                    && self.floats.len() >= needed.floats
                    && self.bytes.len() >= needed.bytes;
                fits.then_some(()).ok_or(Refusal::Buffers)?;
                let out = &mut self.virtual_coach[..frames * joints];
                match network {
                    Some(w) => retarget_network(w, coach, &skeleton, rate, ring, out),
                    None => retarget_analytic(coach, &skeleton, rate, out),
                }
            })
            .and_then(|()| {
                let imu = self
                    .layout
                    .as_ref()
                    .map(|layout| ImuAdapter::new(layout, &skeleton, f32::from(rate)))
                    .transpose()
                    .map_err(Refusal::Imu)?;
                if let Some(imu) = &imu {
                    // The coach as the student's IMUs would see them.
                    for frame in self
                        .virtual_coach
                        .chunks_exact_mut(joints)
                        .take(coach.frames_at(rate))
                    {
                        let mut seen = [Vec3::zeros(); MAX_JOINTS];
                        imu.view(&skeleton, frame, &mut seen)
                            .map_err(Refusal::Imu)?;
                        frame.copy_from_slice(&seen[..joints]);
                    }
                }
                let frames = &self.virtual_coach[..coach.frames_at(rate) * joints];
                let coach_hz = coach_rate(coach, rate);
                let swing = swing_span(&skeleton, frames, coach_hz).map_err(Refusal::CoachSwing)?;
                let span = &frames[swing.start * joints..swing.end * joints];
                let events =
                    events::detect(&skeleton, span, coach_hz).map_err(Refusal::CoachSwing)?;
                let stream = PoseStream::new(StreamConfig::new(rate)).map_err(Refusal::Stream)?;
                Ok((stream, swing, events, imu))
            });
        let (stream, coach_swing, coach_events, imu) = match checked {
            Ok(done) => done,
            Err(e) => {
                self.spare = ring;
                return Err(e);
            }
        };
        let detector = SwingDetector::new(&skeleton, detector, ring).map_err(Refusal::Detector)?;
        self.student = Some(Student {
            skeleton,
            source: None,
            stream,
            detector,
            t0_us: None,
            coach_swing,
            coach_events,
            imu,
        });
        Ok(())
    }

    fn pose(&mut self, frame: &PoseFrame, on: &mut impl FnMut(Outcome<'_>)) -> Result<(), Refusal> {
        let student = self.student.as_mut().ok_or(Refusal::NoProfile)?;
        if student.imu.is_some() {
            return Err(Refusal::Input);
        }
        if student.source.is_none() {
            student.source = Some(stream_skeleton(&student.skeleton, frame.format)?);
        }
        let Student {
            skeleton,
            source,
            stream,
            detector,
            t0_us,
            ..
        } = student;
        let source = source.as_ref().ok_or(Refusal::NoProfile)?;
        let retarget = Analytic::new(source, skeleton).map_err(|_| Refusal::Retarget)?;
        let rate = f32::from(self.config.model_rate_hz);
        let mut closed: Option<(SwingWindow, u64)> = None;
        stream
            .push(frame, |event| match event {
                StreamEvent::Gap => {
                    detector.clear();
                    *t0_us = None;
                }
                StreamEvent::Frame { t_us, joints } => {
                    let mut out = [Vec3::zeros(); MAX_JOINTS];
                    let out = &mut out[..skeleton.len()];
                    if retarget.frame(joints, out).is_err() {
                        return;
                    }
                    let t0 = *t0_us.get_or_insert(t_us);
                    if let Ok(Some(window)) = detector.push(out) {
                        closed = Some((window, t0));
                    }
                }
            })
            .map_err(Refusal::Stream)?;
        if let Some((window, t0)) = closed {
            self.score(window, t0, rate, on);
        }
        Ok(())
    }

    fn imu(&mut self, sample: &ImuSample, on: &mut impl FnMut(Outcome<'_>)) -> Result<(), Refusal> {
        let student = self.student.as_mut().ok_or(Refusal::NoProfile)?;
        let Student {
            skeleton,
            detector,
            t0_us,
            imu,
            ..
        } = student;
        let adapter = imu.as_mut().ok_or(Refusal::Input)?;
        let mut closed: Option<(SwingWindow, u64)> = None;
        let pushed = adapter
            .push(skeleton, sample, |positions, activity| {
                let t0 = *t0_us.get_or_insert(sample.t_us);
                if let Ok(Some(window)) = detector.push_with_activity(positions, activity) {
                    closed = Some((window, t0));
                }
            })
            .or_else(|e| match e {
                ImuError::Sample {
                    error: FusionError::TimeNotIncreasing { .. },
                    ..
                } => {
                    self.stale += 1;
                    Ok(())
                }
                e => Err(Refusal::Imu(e)),
            });
        if let Some((window, t0)) = closed {
            self.score(window, t0, f32::from(self.config.model_rate_hz), on);
        }
        pushed
    }

    /// Scores a closed window.
    fn score(
        &mut self,
        window: SwingWindow,
        t0_us: u64,
        rate: f32,
        on: &mut impl FnMut(Outcome<'_>),
    ) {
        let Some(student) = &mut self.student else {
            return;
        };
        let Some(coach_hz) = self
            .coaches
            .get(usize::from(self.coach))
            .map(|c| coach_rate(c, self.config.model_rate_hz))
        else {
            return;
        };
        let cut = window.len.saturating_sub(MAX_SWING_FRAMES);
        let window = SwingWindow {
            start: window.start + cut as u64,
            len: window.len - cut,
        };
        let Student {
            skeleton,
            detector,
            coach_swing,
            coach_events,
            ..
        } = student;
        let joints = skeleton.len();
        let (swings, config) = (&mut self.swings, self.config);
        let (virtual_coach, floats, bytes) =
            (&*self.virtual_coach, &mut *self.floats, &mut *self.bytes);
        let last_report = &mut self.report;
        // The swing is scored where it lies in the detector's ring (a window that has left the
        // ring is skipped, as a copy of it would fail).
        let _ = detector.with_window(&window, |frames| {
            *swings += 1;
            let at = |frame: u64| t0_us + (frame as f64 * 1e6 / f64::from(rate)) as u64;
            let span = match swing_span(skeleton, frames, rate) {
                Ok(span) => span,
                Err(error) => {
                    let swing = Swing {
                        number: *swings,
                        start_us: at(window.start),
                        frames: window.len,
                    };
                    let error = ScoreError::Events {
                        student: true,
                        error,
                    };
                    return on(Outcome::Unscored { swing, error });
                }
            };
            let swing = Swing {
                number: *swings,
                start_us: at(window.start + span.start as u64),
                frames: span.len(),
            };
            let compared = Compared {
                skeleton,
                student: &frames[span.start * joints..span.end * joints],
                student_hz: rate,
                coach: &virtual_coach[coach_swing.start * joints..coach_swing.end * joints],
                coach_hz,
            };
            let coach = Detected {
                positions: compared.coach,
                hz: coach_hz,
                events: *coach_events,
            };
            let result = Detected::new(skeleton, compared.student, rate)
                .map_err(|error| ScoreError::Events {
                    student: true,
                    error,
                })
                .and_then(|student| {
                    let (radius, anchored) = (config.band_radius, config.anchored);
                    score::compare(skeleton, &student, &coach, radius, anchored, floats, bytes)
                });
            match result {
                Ok(report) => {
                    let report = &*last_report.insert(report);
                    on(Outcome::Scored {
                        swing,
                        report,
                        compared,
                    });
                }
                Err(error) => on(Outcome::Unscored { swing, error }),
            }
        });
    }
}

/// Whether a session can run with `config`.
fn valid(config: &Config) -> bool {
    (RATES_HZ.0..=RATES_HZ.1).contains(&config.model_rate_hz) && config.band_radius > 0
}

/// The rate of the virtual coach: the model rate, or the coach's own where they are the same
/// rate ([`SAME_RATE`]) and its frames are used as they are.
/// Frame `k` of `coach` at `rate_hz`, interpolated into `between` when it falls between two
/// of its own frames.
fn coach_frame<'a>(
    coach: &'a Coach<'_>,
    k: usize,
    rate_hz: u16,
    between: &'a mut [Vec3; MAX_JOINTS],
) -> Option<&'a [Vec3]> {
    let n = coach.skeleton.len();
    let (i, fraction) = coach.source_of(k, rate_hz);
    let frame = |i: usize| coach.positions.get(i * n..(i + 1) * n);
    match (frame(i), frame(i + 1)) {
        (Some(a), Some(b)) if fraction > 0.0 => {
            for ((m, p), q) in between.iter_mut().zip(a).zip(b) {
                *m = p + (q - p) * fraction;
            }
            Some(&between[..n])
        }
        (Some(a), _) => Some(a),
        (None, _) => None,
    }
}

/// `coach` at `rate_hz` retargeted onto `student` frame by frame with the analytic
/// retargeter, into `out` (whole frames of the student).
fn retarget_analytic(
    coach: &Coach<'_>,
    student: &Skeleton,
    rate_hz: u16,
    out: &mut [Vec3],
) -> Result<(), Refusal> {
    let retarget = Analytic::new(coach.skeleton, student).map_err(|_| Refusal::Retarget)?;
    let mut between = [Vec3::zeros(); MAX_JOINTS];
    for (k, pose) in out.chunks_exact_mut(student.len()).enumerate() {
        let source = coach_frame(coach, k, rate_hz, &mut between).ok_or(Refusal::Retarget)?;
        retarget
            .frame(source, pose)
            .map_err(|_| Refusal::Retarget)?;
    }
    Ok(())
}

/// `coach` at `rate_hz` retargeted onto `student` by the int8 network of `weights`, into
/// `out` (whole frames of the student); its input and scratch are carved from `ring`.
fn retarget_network(
    weights: &Weights<'_>,
    coach: &Coach<'_>,
    student: &Skeleton,
    rate_hz: u16,
    ring: &mut [Vec3],
    out: &mut [Vec3],
) -> Result<(), Refusal> {
    let n = coach.skeleton.len();
    let frames = out.len() / student.len().max(1);
    let (source, rest) = ring
        .split_at_mut_checked(frames * n)
        .ok_or(Refusal::Buffers)?;
    let mut between = [Vec3::zeros(); MAX_JOINTS];
    for (k, pose) in source.chunks_exact_mut(n).enumerate() {
        let frame = coach_frame(coach, k, rate_hz, &mut between).ok_or(Refusal::Retarget)?;
        pose.copy_from_slice(frame);
    }
    let scratch: &mut [u8] = bytemuck::cast_slice_mut(rest);
    network::retarget(weights, coach.skeleton, student, source, scratch, out).map_err(|e| match e {
        NetworkError::Scratch => Refusal::Buffers,
        _ => Refusal::Retarget,
    })
}

fn coach_rate(coach: &Coach<'_>, rate_hz: u16) -> f32 {
    if same_rate(coach.rate_hz, rate_hz) {
        coach.rate_hz
    } else {
        f32::from(rate_hz)
    }
}

/// Frames of `positions` from [`SWING_MARGIN_S`] before the set-up to as long after the finish.
fn swing_span(
    skeleton: &Skeleton,
    positions: &[Vec3],
    rate_hz: f32,
) -> Result<Range<usize>, EventError> {
    let events = events::detect(skeleton, positions, rate_hz)?;
    let margin = (SWING_MARGIN_S * rate_hz) as usize;
    let frames = positions.len() / skeleton.len().max(1);
    Ok(events.address().saturating_sub(margin)..(events.finish() + margin + 1).min(frames))
}

/// The skeleton pose frames of `format` are read on: the student's own when the formats
/// match, else the format's standard skeleton scaled to the student's leg length.
fn stream_skeleton(student: &Skeleton, format: Format) -> Result<Skeleton, Refusal> {
    if format == student.format() {
        return Ok(student.clone());
    }
    let standard =
        Skeleton::standard(format).map_err(|_| Refusal::Stream(StreamError::Format(format)))?;
    let scale = student.leg_length() / standard.leg_length().max(f32::EPSILON);
    let lengths: [f32; MAX_JOINTS] =
        core::array::from_fn(|k| standard.offsets().get(k).map_or(0.0, |o| o.norm() * scale));
    standard
        .with_bone_lengths(&lengths[..standard.len()])
        .map_err(Refusal::Profile)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_coach_is_kept_at_the_model_rate() {
        assert_eq!(frames_at(110, 60.000_057, 60), 110);
        assert_eq!(frames_at(110, 60.000_057, 30), 55);
        assert_eq!(frames_at(110, 60.0, 120), 219);
        assert_eq!(frames_at(0, 60.0, 30), 0);
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let positions = [Vec3::zeros(); 17 * 4];
        let coach = Coach {
            skeleton: &skeleton,
            positions: &positions,
            rate_hz: 60.000_057,
        };
        assert_eq!(coach.source_of(3, 60), (3, 0.0));
        assert_eq!(coach.source_of(1, 30).0, 2);
        let (i, fraction) = coach.source_of(1, 40);
        assert_eq!(i, 1);
        assert!((fraction - 0.5).abs() < 1e-4);
    }

    #[test]
    fn the_scoring_scratch_is_sized_for_a_swing_as_long_as_the_ring() {
        let at_30 = BufferLens::new(17, 55, 30);
        assert_eq!(at_30.ring, 17 * 180);
        assert_eq!(at_30.floats, score::scratch_len(180, 55).floats);
        let at_60 = BufferLens::new(17, 110, 60);
        assert_eq!(
            at_60.floats,
            score::scratch_len(MAX_SWING_FRAMES, 110).floats
        );
    }
}
