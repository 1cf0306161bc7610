//! A scoring session: the device's pipeline from wire messages to swing reports.
//!
//! [`Session::handle`] takes each decoded message. A `StudentProfile` gives the student's body
//! (bone lengths measured from the T-pose, directions from the format's standard T-pose) and
//! retargets the selected coach reference onto it once: with the int8 network
//! ([`Session::with_network`]) when the model rate is the network's, else with the analytic
//! retargeter; the network's scratch is the detector's ring, free while the session is set
//! up. Until a `CoachSelect` arrives no coach is selected: the first [`MAX_COACHES`] coaches'
//! set-ups ([`Setup`]: stance, hands and club head out toward the ball) are measured on the
//! student's skeleton, and each swing is scored against the coach whose set-up its own is
//! nearest, so against the coach of its club; when that is not the coach in the virtual coach,
//! it is made anew by the analytic retargeter (the ring then holds the swing). `Config` and
//! `CoachSelect` change the settings. Pose frames then go through the [`PoseStream`] onto the
//! model rate's grid, are put onto the student's skeleton as rigid bones (the analytic
//! retargeter, which also maps a stream format other than the profile's), and feed the
//! [`SwingDetector`]. Each swing it closes is scored where it lies in the detector's ring (its
//! last [`MAX_SWING_FRAMES`] frames, [`SwingDetector::with_window`]), cut to the swing itself
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
//!
//! The session's rooms, one file each under `session/`: `coach.rs` (the coach reference at the
//! model rate and the virtual coach made from it), `buffers.rs` (the caller's buffers and
//! their sizing), `refusal.rs` (refusals and their `Nack`s), `outcome.rs` (what a message led
//! to, and the device's reply); the state machine is here.

mod buffers;
mod coach;
mod outcome;
mod refusal;

#[cfg(feature = "std")]
pub use buffers::OwnedBuffers;
pub use buffers::{BufferLens, Buffers};
pub use coach::Coach;
pub use outcome::{Compared, Outcome, Swing};
pub use refusal::Refusal;

use crate::fusion::FusionError;
use crate::imu::{ImuAdapter, ImuError};
use crate::pose_stream::{PoseStream, StreamConfig, StreamCounters, StreamError, StreamEvent};
use core::ops::Range;
use posecoach_core::band::Band;
use posecoach_core::body::Stance;
use posecoach_core::config::MAX_SWING_FRAMES;
use posecoach_core::contacts::Swing as Contact;
use posecoach_core::detector::{DetectorConfig, SwingDetector, SwingWindow};
use posecoach_core::events::{self, Event, EventError, Side, SwingEvents, STILL_S};
use posecoach_core::format::Format;
use posecoach_core::frames::{Frames, Mm};
use posecoach_core::joint::Joint;
use posecoach_core::math::norm;
use posecoach_core::plausible;
use posecoach_core::retarget::Fit;
use posecoach_core::score::{self, Detected, Report, ScoreError, Unsure};
use posecoach_core::session::Tendencies;
use posecoach_core::setup::{self, Setup};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::weights::Weights;
use posecoach_core::wire::{Config, ImuSample, Message, PoseFrame, SensorLayout, StudentProfile};
use posecoach_core::{config::MAX_JOINTS, Vec3};

/// Settings until a `Config` message arrives.
pub const DEFAULT_CONFIG: Config = Config {
    model_rate_hz: 60,
    band: Band::DEFAULT,
};
/// Seconds of frames the detector keeps.
pub const RING_S: f32 = 6.0;
/// Swings are scored from this long before the set-up to this long after the finish (the
/// still set-up that the event detector looks for), seconds.
pub const SWING_MARGIN_S: f32 = STILL_S;
/// Most coaches a session chooses among by the swing's set-up (further ones only by
/// `CoachSelect`).
pub const MAX_COACHES: usize = 4;
/// A swing's set-up is measured over this long before its takeaway (or as much of it as was
/// kept), seconds: the golfer standing still over the ball.
pub const SETUP_S: f32 = 0.5;
/// Lowest and highest model rates, Hz.
pub const RATES_HZ: (u16, u16) = (20, 120);
/// Most frames one message gives swing detection: a pose frame fills the model-rate grid up to
/// its time, and a longer gap than [`MAX_GAP_S`](crate::pose_stream::MAX_GAP_S) starts the
/// stream afresh; an IMU sample completes a frame or two. Each frame's work is bounded by the
/// joints and the ring, each swing's by [`MAX_SWING_FRAMES`], so every message's work is
/// bounded whatever its times, sequence numbers and values.
pub const MAX_FRAMES_PER_MESSAGE: u64 =
    (crate::pose_stream::MAX_GAP_S * RATES_HZ.1 as f32) as u64 + 1;

/// Everything that follows the student's body.
#[derive(Debug)]
struct Student<'b> {
    skeleton: Skeleton,
    /// The fit of the stream format's skeleton (scaled to the student) onto the student's,
    /// made at the first pose frame (the stream keeps to that frame's format) and used for
    /// every one after.
    fit: Option<Fit>,
    /// For each student joint, the stream joint of the same canonical joint (bit source of
    /// the unsure masks), `u8::MAX` for none; made with the fit.
    unsure_source: [u8; MAX_JOINTS],
    stream: PoseStream,
    detector: SwingDetector<'b>,
    /// Stream time of the detector's frame 0.
    t0_us: Option<u64>,
    /// The virtual coach's swing: frames from its set-up to its finish.
    coach_swing: Range<usize>,
    /// The events of the virtual coach's swing, found once.
    coach_events: SwingEvents,
    /// How far the IMUs' view moves events ([`make_virtual`]): a student's are moved back.
    lag: Lag,
    /// The coach reference the virtual coach was made from.
    coach: u16,
    /// Each of the first [`MAX_COACHES`] coaches' set-ups on the student's skeleton, while no
    /// coach is selected (the virtual coach follows each swing's club).
    setups: [Option<Setup>; MAX_COACHES],
}

/// The student as the phone set them up: the profile's skeleton and, in a session with IMUs,
/// where the sensors are (a layout is checked against the body it was sent for, so a new
/// profile clears it).
#[derive(Clone, Debug, PartialEq)]
struct Body {
    skeleton: Skeleton,
    layout: Option<SensorLayout>,
}

/// One session; see the [module documentation](self).
#[derive(Debug)]
pub struct Session<'b> {
    coaches: &'b [Coach<'b>],
    #[cfg(feature = "network")]
    network: Option<&'b Weights<'b>>,
    config: Config,
    /// The phone's `CoachSelect`; until one, each swing is scored against the coach whose
    /// set-up its own is nearest ([`setup::nearest`]).
    selected: Option<u16>,
    body: Option<Body>,
    student: Option<Student<'b>>,
    /// The IMUs' fusion, while the student is set up with a sensor layout. Kept beside the
    /// student rather than in it: built where it stays, not copied with the student's other
    /// parts on their way in (each of its 1.9 KiB was some 15 bytes of the set-up's stack).
    imu: Option<ImuAdapter>,
    /// The ring while no detector holds it.
    spare: &'b mut [Mm],
    /// The virtual coach, in millimetres, as it was made: each swing reads it turned toward its
    /// own target line ([`score::facing`]).
    virtual_coach: &'b mut [Mm],
    floats: &'b mut [f32],
    bytes: &'b mut [u8],
    /// Per stream frame, the student's joints the pose stream was unsure of (slot: frame index
    /// modulo its length).
    unsure: &'b mut [u64],
    swings: u32,
    report: Option<Report>,
    /// The range session: what the swings scored against one coach say together.
    tendencies: Tendencies<'b>,
    /// The coach the range session's swings were scored against.
    tendencies_coach: Option<u16>,
    /// Counters of the pose streams before the current one.
    counted: StreamCounters,
    /// IMU samples not newer than their sensor's last one.
    stale: u32,
    /// Frames given to swing detection.
    frames: u64,
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
    /// rate is the network's ([`Architecture::rate_hz`](posecoach_core::weights::Architecture::rate_hz)); its ring must then be as long as
    /// [`BufferLens::with_network`] says. Set it before the profile arrives. (With the
    /// `network` feature.)
    #[cfg(feature = "network")]
    pub fn with_network(mut self, weights: &'b Weights<'b>) -> Session<'b> {
        self.network = Some(weights);
        self
    }

    fn start(coaches: &'b [Coach<'b>], buffers: Buffers<'b>, config: Config) -> Session<'b> {
        Session {
            coaches,
            #[cfg(feature = "network")]
            network: None,
            config,
            selected: None,
            body: None,
            student: None,
            imu: None,
            spare: buffers.ring,
            virtual_coach: buffers.coach,
            floats: buffers.floats,
            bytes: buffers.bytes,
            unsure: buffers.unsure,
            swings: 0,
            report: None,
            tendencies: Tendencies::new(buffers.tallies),
            tendencies_coach: None,
            counted: StreamCounters::default(),
            stale: 0,
            frames: 0,
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

    /// IMU samples with a gyro axis past its range, read at the sensor's last rate under it
    /// ([`crate::imu::ImuAdapter::saturated_samples`]), for the student's current profile.
    pub fn saturated_samples(&self) -> u32 {
        self.imu_adapter().map_or(0, ImuAdapter::saturated_samples)
    }

    /// IMU samples whose magnetic field was set aside as not the earth's
    /// ([`crate::imu::ImuAdapter::disturbed_samples`]), for the student's current profile.
    pub fn disturbed_samples(&self) -> u32 {
        self.imu_adapter().map_or(0, ImuAdapter::disturbed_samples)
    }

    /// The student's IMU adapter, where the layout is set.
    fn imu_adapter(&self) -> Option<&ImuAdapter> {
        self.student.as_ref().and(self.imu.as_ref())
    }

    /// Frames given to swing detection since the session began (at most
    /// [`MAX_FRAMES_PER_MESSAGE`] per message).
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// The range session: what the swings scored against one coach since the profile, the
    /// coach or the settings last changed say together.
    pub fn tendencies(&self) -> &Tendencies<'b> {
        &self.tendencies
    }

    /// The student's skeleton, once a profile has been taken.
    pub fn student(&self) -> Option<&Skeleton> {
        self.body.as_ref().map(|b| &b.skeleton)
    }

    /// Starts a new range session.
    fn new_range_session(&mut self) {
        self.tendencies.reset();
        self.tendencies_coach = None;
    }

    /// The range session as an outcome.
    fn range_session(&self) -> Outcome<'_> {
        Outcome::Session {
            tendencies: &self.tendencies,
            coach: self.tendencies_coach.unwrap_or(u16::MAX),
        }
    }

    /// Whether the detector is watching a swing that may be under way: a set-up message that
    /// would change the session is then refused as busy ([`Refusal::SwingUnderWay`]).
    pub fn swing_under_way(&self) -> bool {
        self.student.as_ref().is_some_and(|s| s.detector.watching())
    }

    /// Takes one message and calls `on` with what it led to: a set-up message taken (applied,
    /// or the same as the one in force) is [`Outcome::Accepted`], a message refused
    /// [`Outcome::Refused`]; a swing scored is followed by the range session
    /// ([`Outcome::Session`]), and a session request is taken (a reset applied) and answered
    /// with it. Messages a device sends rather than receives are ignored.
    pub fn handle(&mut self, message: &Message, mut on: impl FnMut(Outcome<'_>)) {
        let refusal = match message {
            Message::StudentProfile { profile, .. } => self.profile(profile).err(),
            Message::Config { config, .. } => match valid(config) {
                true => self.set(|s| Some(&mut s.config), *config).err(),
                false => Some(Refusal::Config),
            },
            Message::CoachSelect { coach, .. } => match usize::from(*coach) < self.coaches.len() {
                true => self.set(|s| Some(&mut s.selected), Some(*coach)).err(),
                false => Some(Refusal::UnknownCoach(*coach)),
            },
            // A layout is checked against the body it follows: it needs a profile.
            Message::SensorLayout { layout, .. } => self
                .set(
                    |s| s.body.as_mut().map(|b| &mut b.layout),
                    Some(layout.clone()),
                )
                .err(),
            Message::PoseFrame(frame) => self.pose(frame, &mut on).err(),
            Message::ImuSample(sample) => self.imu(sample, &mut on).err(),
            Message::SessionRequest { reset, .. } => {
                if *reset {
                    self.new_range_session();
                }
                on(Outcome::Accepted);
                return on(self.range_session());
            }
            _ => None,
        };
        match refusal {
            Some(r) => on(Outcome::Refused(r)),
            None if message.is_setup() => on(Outcome::Accepted),
            None => {}
        }
    }

    #[inline(never)]
    fn profile(&mut self, profile: &StudentProfile) -> Result<(), Refusal> {
        // A profile sets the body alone: a sensor layout, checked against the body it came
        // after, follows it again if the session is to take IMU samples. So the profile in
        // force sent again changes nothing in a pose session, and in one with IMUs returns it
        // to pose frames (a phone sends its profile, then its layout).
        let body = Some(Body {
            skeleton: body_of(profile)?,
            layout: None,
        });
        self.set(|s| Some(&mut s.body), body)
    }

    /// Sets a field (absent without a profile: [`Refusal::NoProfile`]) to `value` and rebuilds
    /// what follows it. The value in force already changes nothing; another is refused while a
    /// swing may be under way, so that none is lost. If the rebuild fails the field gets its old
    /// value back and the session is rebuilt as it was (no swing was under way).
    fn set<T: PartialEq>(
        &mut self,
        field: fn(&mut Self) -> Option<&mut T>,
        value: T,
    ) -> Result<(), Refusal> {
        let current = field(self).ok_or(Refusal::NoProfile)?;
        if *current == value {
            return Ok(());
        }
        if self.swing_under_way() {
            return Err(Refusal::SwingUnderWay);
        }
        let previous = field(self).map(|f| core::mem::replace(f, value));
        match self.restart() {
            // A change taken starts a new range session; a refused one changes nothing.
            Ok(()) => {
                self.new_range_session();
                Ok(())
            }
            Err(refusal) => {
                if let (Some(f), Some(previous)) = (field(self), previous) {
                    *f = previous;
                }
                // What worked before works again.
                let _ = self.restart();
                Err(refusal)
            }
        }
    }

    /// Rebuilds everything that follows the profile, coach and settings.
    fn restart(&mut self) -> Result<(), Refusal> {
        let Some(skeleton) = self.student().cloned() else {
            return Ok(());
        };
        let layout = self.body.as_ref().and_then(|b| b.layout.as_ref());
        let first = self.selected.unwrap_or(0);
        let coach = self
            .coaches
            .get(usize::from(first))
            .ok_or(Refusal::UnknownCoach(first))?;
        let rate = self.config.model_rate_hz;
        let joints = skeleton.len();
        let detector = match layout {
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
        // Without a selection any of the first MAX_COACHES may be made.
        let candidates = match self.selected {
            Some(_) => &self.coaches[usize::from(first)..=usize::from(first)],
            None => &self.coaches[..self.coaches.len().min(MAX_COACHES)],
        };
        let frames = candidates
            .iter()
            .map(|c| c.frames_at(rate))
            .max()
            .unwrap_or(0);
        let mut setups = [None; MAX_COACHES];
        let checked = SwingDetector::check(&skeleton, detector, ring.len())
            .map_err(Refusal::Detector)
            .and_then(|_| {
                #[cfg(feature = "network")]
                let network = self.network.filter(|w| {
                    posecoach_core::resample::same_rate(w.architecture().rate_hz, f32::from(rate))
                });
                #[cfg(not(feature = "network"))]
                let network: Option<&Weights<'_>> = None;
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
                self.imu = match layout {
                    Some(layout) => Some(
                        ImuAdapter::new(layout, &skeleton, f32::from(rate))
                            .map_err(Refusal::Imu)?,
                    ),
                    None => None,
                };
                if self.selected.is_none() {
                    // A coach that cannot be made for this student is never chosen.
                    for (setup, c) in setups.iter_mut().zip(candidates) {
                        let made = make_virtual(
                            c,
                            &skeleton,
                            rate,
                            None,
                            self.imu.as_ref(),
                            self.virtual_coach,
                        );
                        *setup = made.ok().and_then(|(swing, events, _)| {
                            let address = swing.start + events.address();
                            let out = &self.virtual_coach[..swing.end * joints];
                            let out = Frames::millimetres(out, joints);
                            setup_of(&skeleton, out, address, events.lead, c.rate_at(rate))
                        });
                    }
                }
                let network = network.map(|w| (w, &mut *ring));
                let (swing, events, lag) = make_virtual(
                    coach,
                    &skeleton,
                    rate,
                    network,
                    self.imu.as_ref(),
                    self.virtual_coach,
                )?;
                let stream = PoseStream::new(StreamConfig::new(rate)).map_err(Refusal::Stream)?;
                Ok((stream, swing, events, lag))
            });
        let (stream, coach_swing, coach_events, lag) = match checked {
            Ok(done) => done,
            Err(e) => {
                self.spare = ring;
                self.imu = None;
                return Err(e);
            }
        };
        let detector = SwingDetector::new(&skeleton, detector, ring).map_err(Refusal::Detector)?;
        self.unsure.fill(0);
        self.student = Some(Student {
            skeleton,
            fit: None,
            unsure_source: [u8::MAX; MAX_JOINTS],
            stream,
            detector,
            t0_us: None,
            coach_swing,
            coach_events,
            lag,
            coach: first,
            setups,
        });
        Ok(())
    }

    #[inline(never)]
    fn pose(&mut self, frame: &PoseFrame, on: &mut impl FnMut(Outcome<'_>)) -> Result<(), Refusal> {
        let student = self.student.as_mut().ok_or(Refusal::NoProfile)?;
        if self.imu.is_some() {
            return Err(Refusal::Input);
        }
        // The fit follows the first frame the stream takes: a refused frame before it (a
        // format the stream cannot read, a wrong keypoint count) must not fix its format.
        if student.fit.is_none() || student.stream.format().is_none() {
            let source = stream_skeleton(&student.skeleton, frame.format)?;
            let fit = Fit::new(&source, &student.skeleton).map_err(|_| Refusal::Retarget)?;
            student.fit = Some(fit);
            for (k, slot) in student.unsure_source.iter_mut().enumerate() {
                let same = student.skeleton.joint(k).and_then(|j| source.index_of(j));
                *slot = same.map_or(u8::MAX, |i| i as u8);
            }
        }
        let Student {
            skeleton,
            fit,
            unsure_source,
            stream,
            detector,
            t0_us,
            ..
        } = student;
        let masks = &mut *self.unsure;
        let frames = &mut self.frames;
        let fit = fit.as_ref().ok_or(Refusal::NoProfile)?;
        let rate = f32::from(self.config.model_rate_hz);
        let mut closed: Option<(SwingWindow, u64)> = None;
        stream
            .push(frame, |event| match event {
                StreamEvent::Gap => {
                    detector.clear();
                    masks.fill(0);
                    *t0_us = None;
                }
                StreamEvent::Frame {
                    t_us,
                    joints,
                    unsure,
                } => {
                    let mut out = [Vec3::zeros(); MAX_JOINTS];
                    let out = &mut out[..skeleton.len()];
                    if fit.frame(skeleton, joints, out).is_err() {
                        return;
                    }
                    // The student's joints whose stream joint was unsure, at this frame's slot.
                    let frame = detector.frames_seen();
                    if let Some(slot) = masks.get_mut((frame % masks.len().max(1) as u64) as usize)
                    {
                        let mut mask = unsure_source
                            .iter()
                            .take(skeleton.len())
                            .enumerate()
                            .filter(|&(_, &i)| i < 64 && unsure & (1 << i) != 0)
                            .fold(0u64, |m, (k, _)| m | 1 << k);
                        // The fit places a joint along its bone from its parent: an unsure
                        // parent makes its children unsure (parents come first).
                        for k in 0..skeleton.len() {
                            if skeleton.parent(k).is_some_and(|p| mask & (1 << p) != 0) {
                                mask |= 1 << k;
                            }
                        }
                        *slot = mask;
                    }
                    let t0 = *t0_us.get_or_insert(t_us);
                    *frames += 1;
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

    #[inline(never)]
    fn imu(&mut self, sample: &ImuSample, on: &mut impl FnMut(Outcome<'_>)) -> Result<(), Refusal> {
        let student = self.student.as_mut().ok_or(Refusal::NoProfile)?;
        let Student {
            skeleton,
            detector,
            t0_us,
            ..
        } = student;
        let adapter = self.imu.as_mut().ok_or(Refusal::Input)?;
        let mut closed: Option<(SwingWindow, u64)> = None;
        let frames = &mut self.frames;
        let pushed = adapter
            .push(skeleton, sample, |positions, activity| {
                let t0 = *t0_us.get_or_insert(sample.t_us);
                *frames += 1;
                if let Ok(Some(window)) = detector.push_with_activity(positions, activity) {
                    closed = Some((window, t0));
                }
            })
            .or_else(|e| match e {
                ImuError::Sample {
                    error: FusionError::TimeNotIncreasing { .. },
                    ..
                } => {
                    self.stale = self.stale.saturating_add(1);
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
            lag,
            coach: made,
            setups,
            ..
        } = student;
        let imu = &self.imu;
        let joints = skeleton.len();
        let (swings, config, coaches, selected) =
            (&mut self.swings, self.config, self.coaches, self.selected);
        let (virtual_coach, floats, bytes) = (
            &mut *self.virtual_coach,
            &mut *self.floats,
            &mut *self.bytes,
        );
        let last_report = &mut self.report;
        let (tendencies, tendencies_coach) = (&mut self.tendencies, &mut self.tendencies_coach);
        let (unsure, seen) = (&*self.unsure, detector.frames_seen());
        // The swing is scored where it lies in the detector's ring (a window that has left the
        // ring is skipped, as a copy of it would fail).
        let _ = detector.with_window(&window, |frames| {
            *swings = swings.saturating_add(1);
            // On the sender's clock, which may wrap (the IMU adapter follows it round).
            let at = |frame: u64| t0_us.wrapping_add((frame as f64 * 1e6 / f64::from(rate)) as u64);
            let found = swing_span(skeleton, frames, rate);
            // Without a selection, the coach whose set-up this swing's is nearest, made when it
            // is not the one in the virtual coach (by the analytic retargeter: the network's
            // scratch is the ring, which holds this swing).
            if let (None, Ok((span, events))) = (selected, &found) {
                let address = span.start + events.address();
                let chosen = setup_of(skeleton, frames, address, events.lead, rate)
                    .and_then(|setup| setup::nearest(&setup, setups.iter().copied()))
                    .and_then(|c| u16::try_from(c).ok());
                if let Some((c, coach)) = chosen
                    .filter(|&c| c != *made)
                    .and_then(|c| Some((c, coaches.get(usize::from(c))?)))
                {
                    // It cannot fail: the same coach was made onto the same skeleton, at the same
                    // rate and through the same IMU layout, when its set-up was measured.
                    let rate = config.model_rate_hz;
                    if let Ok((swing, events, l)) =
                        make_virtual(coach, skeleton, rate, None, imu.as_ref(), virtual_coach)
                    {
                        (*coach_swing, *coach_events, *lag, *made) = (swing, events, l, c);
                    }
                }
            }
            let coach = *made;
            let (span, events) = match found {
                Ok((span, events)) => (span, lagged(&events, lag, rate)),
                Err(error) => {
                    let swing = Swing {
                        number: *swings,
                        start_us: at(window.start),
                        frames: window.len,
                        coach,
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
                coach,
            };
            let Some(coach_hz) = coaches
                .get(usize::from(coach))
                .map(|c| c.rate_at(config.model_rate_hz))
            else {
                return;
            };
            let Some(student) = frames.get(span.clone()) else {
                return;
            };
            let Some(coach) =
                virtual_coach.get(coach_swing.start * joints..coach_swing.end * joints)
            else {
                return;
            };
            let mut address = [Vec3::zeros(); MAX_JOINTS];
            let address = student.frame(events.address(), &mut address);
            let stance = Stance::new(skeleton, address, events.lead);
            // The coach faces this swing's target line as it is read: turned where it is
            // stored, it would be rounded again swing after swing.
            let stored = Frames::millimetres(coach, joints);
            let turn = score::facing(skeleton, stored, coach_events, stance.toward_target());
            let compared = Compared {
                skeleton,
                student,
                student_hz: rate,
                coach: match &turn {
                    Some(turn) => Frames::millimetres_turned(coach, joints, turn),
                    None => stored,
                },
                coach_hz,
            };
            let coach = Detected {
                positions: compared.coach,
                hz: coach_hz,
                events: *coach_events,
                unsure: Unsure::default(),
            };
            let student = Detected {
                positions: compared.student,
                hz: rate,
                events,
                unsure: Unsure::new(unsure, window.start + span.start as u64, seen)
                    .with_never(imu.as_ref().map_or(0, |a| a.unmeasured(skeleton))),
            };
            // A swing against another coach than the range session's starts a new one.
            if tendencies_coach.replace(swing.coach) != Some(swing.coach) {
                tendencies.reset();
            }
            let result = score::compare(
                skeleton,
                &student,
                &coach,
                config.band,
                (floats, bytes),
                tendencies,
            );
            match result {
                Ok(report) => {
                    let report = &*last_report.insert(report);
                    on(Outcome::Scored {
                        swing,
                        report,
                        compared,
                    });
                    on(Outcome::Session {
                        tendencies,
                        coach: swing.coach,
                    });
                }
                Err(error) => on(Outcome::Unscored { swing, error }),
            }
        });
    }
}

/// The student's skeleton from `profile`: its bone lengths on the format's standard T-pose,
/// checked against the human limits. (Out of line, so that its arrays are off the stack while
/// the session is rebuilt.)
#[inline(never)]
fn body_of(profile: &StudentProfile) -> Result<Skeleton, Refusal> {
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
    if !upright(&template, &joints) {
        return Err(Refusal::NotUpright);
    }
    let lengths: [f32; MAX_JOINTS] = core::array::from_fn(|k| {
        (k < template.len())
            .then(|| template.parent(k))
            .flatten()
            .map_or(0.0, |p| norm(&(joints[k] - joints[p])))
    });
    let skeleton = template
        .with_bone_lengths(&lengths[..template.len()])
        .map_err(Refusal::Profile)?;
    plausible::body(&skeleton).map_err(Refusal::Implausible)?;
    Ok(skeleton)
}

/// Whether a standing body's `joints` (on `skeleton`'s joints) have the head above the feet
/// along +Y: the feet-to-head vector within 60° of up. The skeleton's own rest pose is the
/// format's, upright whatever the keypoints were, so the keypoints are read.
fn upright(skeleton: &Skeleton, joints: &[Vec3]) -> bool {
    let head = skeleton.find(&[Joint::Head, Joint::Neck, Joint::Thorax]);
    let feet = [
        skeleton.find(&[Joint::LeftAnkle, Joint::LeftToe]),
        skeleton.find(&[Joint::RightAnkle, Joint::RightToe]),
    ];
    let (Some(head), [Some(l), Some(r)]) = (head, feet) else {
        // A format without them is judged by the checks that follow.
        return true;
    };
    let rise = joints[head] - (joints[l] + joints[r]) * 0.5;
    rise.y >= 0.5 * norm(&rise)
}

/// Whether a session can run with `config`.
fn valid(config: &Config) -> bool {
    (RATES_HZ.0..=RATES_HZ.1).contains(&config.model_rate_hz) && config.band.radius > 0
}

/// Makes the virtual coach of `coach` on `skeleton` at the model rate `rate` into the front of
/// `out`, in millimetres: with the int8 network (its scratch the ring) where given, else the
/// analytic retargeter, then moved onto the coach's golf contacts; as the student's IMUs would
/// see it in a session with them. Returns its swing and events, as [`swing_span`], and the
/// [`Lag`] of its IMUs' view (kept out of line: three callers, one copy in flash). The IMUs'
/// view holds the root still and moves unsensed bones with their parents, which moves where
/// the events are found (on the bundled swings the takeaway 11 to 13 ms late, the top 5 ms
/// early, impact 5 to 10 ms late): the coach's takeaway, top and impact are put back where the
/// coach made them, and a student seen the same way is moved by as much.
#[inline(never)]
fn make_virtual(
    coach: &Coach<'_>,
    skeleton: &Skeleton,
    rate: u16,
    network: Option<(&Weights<'_>, &mut [Mm])>,
    imu: Option<&ImuAdapter>,
    out: &mut [Mm],
) -> Result<(Range<usize>, SwingEvents, Lag), Refusal> {
    let joints = skeleton.len();
    let out = out
        .get_mut(..coach.frames_at(rate) * joints)
        .ok_or(Refusal::Buffers)?;
    match network {
        #[cfg(feature = "network")]
        Some((w, ring)) => coach.retarget_network(w, skeleton, rate, ring, out)?,
        _ => coach.retarget_analytic(skeleton, rate, out)?,
    }
    // Found before the contacts are kept, so that their frame is not under the finding's.
    let made = coach.events_of(skeleton, rate, out);
    coach.keep_contacts(skeleton, rate, made.as_ref().map(Contact::from), imu, out)?;
    let hz = coach.rate_at(rate);
    let (span, seen) =
        swing_span(skeleton, Frames::millimetres(out, joints), hz).map_err(Refusal::CoachSwing)?;
    let lag = match (imu, made) {
        (Some(_), Some(made)) => LAGGED.map(|e| {
            let by = made
                .time(e)
                .zip(seen.time(e))
                .map_or(0.0, |(m, s)| m - span.start as f32 - s);
            // More than a tenth of a second is two different findings, not a lag.
            if (by / hz).abs() < MAX_LAG_S {
                by / hz
            } else {
                0.0
            }
        }),
        _ => [0.0; 3],
    };
    Ok((span, lagged(&seen, &lag, hz), lag))
}

/// The events an IMU view moves, and by how much each ([`make_virtual`]), seconds.
type Lag = [f32; 3];
/// The events of [`Lag`], in its order.
const LAGGED: [Event; 3] = [Event::Address, Event::Top, Event::Impact];
/// A view's lag beyond this is not taken, seconds.
const MAX_LAG_S: f32 = 0.1;

/// `events` (of a swing at `hz`) with each of [`LAGGED`] moved by its `lag`.
fn lagged(events: &SwingEvents, lag: &Lag, hz: f32) -> SwingEvents {
    LAGGED
        .iter()
        .zip(lag)
        .fold(*events, |e, (&at, &by)| e.moved(at, by * hz))
}

/// The set-up of the swing in `positions` (at `rate_hz`) whose takeaway is at frame
/// `address`: over the [`SETUP_S`] before it.
fn setup_of(
    skeleton: &Skeleton,
    positions: Frames<'_>,
    address: usize,
    lead: Side,
    rate_hz: f32,
) -> Option<Setup> {
    let from = address.saturating_sub((SETUP_S * rate_hz) as usize);
    Setup::new(skeleton, positions.get(from..address + 1)?, lead)
}

/// The swing in `positions`: its frames from [`SWING_MARGIN_S`] before the set-up to as long
/// after the finish, and its events counted from the first of them (found once, in all of
/// `positions`).
fn swing_span(
    skeleton: &Skeleton,
    positions: Frames<'_>,
    rate_hz: f32,
) -> Result<(Range<usize>, SwingEvents), EventError> {
    let events = events::detect(skeleton, positions, rate_hz)?;
    let margin = (SWING_MARGIN_S * rate_hz) as usize;
    let frames = positions.len();
    let start = events.address().saturating_sub(margin);
    let span = start..(events.finish() + margin + 1).min(frames);
    Ok((span, events.from_frame(start)))
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
