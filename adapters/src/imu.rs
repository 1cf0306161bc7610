//! Body poses from IMUs strapped to the student's segments.
//!
//! ```text
//!  ImuSample ──fusion::Reading──▶ still T-pose?  ── CALIBRATION_S ──▶ bias, attitude, offsets
//!                                     │ (after calibration)
//!                                     ▼
//!             Mahony filter per sensor ──▶ segment rotations on the output grid
//!                                     ──kinematics::forward──▶ joint positions, activity
//! ```
//!
//! **Calibration.** A session starts with the student holding a still T-pose for
//! [`CALIBRATION_S`]; any sample that is not still ([`StillPeriod::is_still`]) starts the period
//! over. At its end each sensor's gyro bias is its mean rate, its filter starts from its mean
//! acceleration (and field), and its sensor-to-segment offset follows from the T-pose, where
//! every bone's global rotation is the identity. A filter's heading is arbitrary without a
//! magnetometer: the heading correction is the yaw that brings the calibrated mounting closest
//! to the layout's nominal one. Sensors with magnetometers share magnetic north, so one yaw,
//! fitted over all of them, serves them all and their relative headings stay exact.
//!
//! **Tracking.** Every sample updates its sensor's filter; one with an axis at its sensor's
//! full scale (sent as the `i16` extreme) reads a saturated accelerometer as not there and a
//! saturated gyro axis at the sensor's last rate under the range, and is counted
//! ([`ImuAdapter::saturated_samples`]): a wrist past 2 000 °/s turns on at its range rather than
//! stopping, and turns less than it did while it lasts. A magnetometer reading that is not the
//! earth's field the T-pose saw (a steel club by the wrist) corrects no heading, and is counted
//! ([`ImuAdapter::disturbed_samples`]). Outputs lie on a fixed grid at the
//! adapter's rate, starting one period after calibration; each sensor's orientation is
//! interpolated to a grid time when a sample passes it, and once every sensor has passed it
//! one frame of positions goes out. A sensed bone's global rotation comes from its sensor
//! (what a sensor measures, and how unsensed trunk bones share the turn between two sensed
//! ones: [`crate::segment`]); other unsensed bones follow their parent (the hip bones move
//! with the pelvis, the shoulders with the chest). Unsensed legs stand planted: each foot flat
//! where the T-pose turned to the stance has it, the thigh and shin leaning as one to reach it
//! from the moving hip. The stance is where the trunk last faced while still: halfway between
//! the headings of its sensors' segments (pelvis, spine, thorax), where a golfer set up square
//! faces with the hips and shoulders turned about as far either way, taken once the lowest
//! has turned under [`QUIET_RAD_S`] for [`QUIET_S`] with the sensed arms hanging (the golfer's
//! set-up, wherever the T-pose faced; a pelvis reversing at the top passes under that rate for
//! a few hundredths of a second, and at a pause there, at a held finish or in the T-pose the
//! forearms do not hang: [`HANGING`]). The root stays at
//! the skeleton's rest position. With each frame goes the activity for swing detection: the
//! largest bias-free gyro rate (rad/s) of the wrist, hand and club sensors (of all sensors if
//! there are none of those) since the previous frame. A layout that carries one arm puts the
//! other's hand on the grip by the first's (two-bone inverse kinematics, `contacts::Limb`). What
//! the layout leaves unmeasured
//! (planted legs, a head on the chest, a limb below an unsensed bone:
//! [`ImuAdapter::unmeasured`]) a session judges nothing from.
//!
//! ```
//! use posecoach_adapters::imu::ImuAdapter;
//! use posecoach_core::format::Format;
//! use posecoach_core::joint::Joint;
//! use posecoach_core::skeleton::Skeleton;
//! use posecoach_core::wire::{ImuSample, SensorLayout, SensorPlacement};
//!
//! let skeleton = Skeleton::standard(Format::H36m17).unwrap();
//! let mut layout = SensorLayout { sensors: Default::default() };
//! let placement = SensorPlacement { sensor: 0, joint: Joint::Pelvis, mounting_q14: [16384, 0, 0, 0] };
//! layout.sensors.push(placement).unwrap();
//! let mut adapter = ImuAdapter::new(&layout, &skeleton, 60.0).unwrap();
//! let mut frames = 0;
//! for k in 0..400u64 {
//!     let sample = ImuSample {
//!         sensor: 0,
//!         t_us: k * 5_000,
//!         accel_mg: [0, 1000, 0],
//!         gyro_ddps: [0, 0, 0],
//!         mag_dut: None,
//!     };
//!     adapter.push(&skeleton, &sample, |positions, _activity| {
//!         assert_eq!(positions.len(), 17);
//!         frames += 1;
//!     }).unwrap();
//! }
//! assert_eq!(frames, 59); // 2 s at 200 Hz: 1 s of calibration, then 60 Hz
//! ```

use crate::fusion::{self, FusionError, Gains, Mahony, Reading, StillPeriod};
use crate::segment::Segments;
use posecoach_core::config::MAX_JOINTS;
use posecoach_core::contacts::Limb;
use posecoach_core::joint::Joint;
use posecoach_core::kinematics::{forward, swing};
use posecoach_core::math;
use posecoach_core::skeleton::{Segment, Skeleton};
use posecoach_core::wire::{SensorLayout, MAX_SENSORS};
use posecoach_core::{Quat, Vec3};

/// Length of the still T-pose that starts a session, seconds.
pub const CALIBRATION_S: f32 = 1.0;
const CALIBRATION_US: u64 = 1_000_000;
/// Output rates the adapter accepts, Hz.
pub const RATE_RANGE_HZ: core::ops::RangeInclusive<f32> = 1.0..=1000.0;
/// A nominal mounting's `q14` norm must be within this fraction of 1.
const MOUNTING_TOLERANCE: f32 = 0.1;
/// Units of a `mounting_q14` component.
const Q14: f32 = 16384.0;
/// The trunk sensor's rate under which the legs take the trunk's heading, rad/s (20 °/s): a
/// golfer at address is under it, and a takeaway passes it within a few degrees of turn.
pub const QUIET_RAD_S: f32 = 0.35;
/// How long the trunk sensor must stay under [`QUIET_RAD_S`] before the legs take its heading,
/// seconds: a golfer holds the set-up longer; a turning pelvis reverses (at the top) in far less.
pub const QUIET_S: f32 = 0.2;
const QUIET_US: u64 = 200_000;
/// How far below the horizontal a sensed arm bone (upper arm, forearm, hand) points at least
/// while the legs take the trunk's heading: the sine of 30°. At address the arms hang; at the
/// top of a swing, at its finish and in the T-pose the forearms point up or sideways, and
/// there a quiet trunk says nothing of where the feet stand.
pub const HANGING: f32 = 0.5;
/// Joints whose bones [`HANGING`] is about.
const ARM_JOINTS: [Joint; 6] = [
    Joint::LeftElbow,
    Joint::RightElbow,
    Joint::LeftWrist,
    Joint::RightWrist,
    Joint::LeftHand,
    Joint::RightHand,
];
/// Joints whose sensor, the first the layout places, sets the legs' heading.
const TRUNK_JOINTS: [Joint; 3] = [Joint::Pelvis, Joint::Spine, Joint::Thorax];
/// Joints whose sensors give the activity.
const ACTIVITY_JOINTS: [Joint; 6] = [
    Joint::LeftWrist,
    Joint::RightWrist,
    Joint::LeftHand,
    Joint::RightHand,
    Joint::ClubGrip,
    Joint::ClubHead,
];
const NO_SENSOR: u8 = u8::MAX;
/// Millihertz times microseconds per cycle.
const MHZ_US: u64 = 1_000_000_000;

/// Why a layout was refused or a sample not used.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ImuError {
    /// The layout places no sensor.
    EmptyLayout,
    /// A sensor's joint is not in the skeleton.
    #[allow(missing_docs)]
    MissingJoint { sensor: u8, joint: Joint },
    /// Two placements use the same sensor number, or the same joint.
    #[allow(missing_docs)]
    DuplicateSensor { sensor: u8 },
    /// A nominal mounting is not a unit quaternion.
    #[allow(missing_docs)]
    Mounting { sensor: u8 },
    /// The output rate is outside [`RATE_RANGE_HZ`].
    #[allow(missing_docs)]
    Rate { rate_hz: f32 },
    /// The skeleton passed to `push` is not the one given to `new`.
    SkeletonMismatch,
    /// A sample from a sensor the layout does not place.
    #[allow(missing_docs)]
    UnknownSensor { sensor: u8 },
    /// A sample that could not be used; the adapter carries on without it.
    #[allow(missing_docs)]
    Sample { sensor: u8, error: FusionError },
}

impl core::fmt::Display for ImuError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ImuError::EmptyLayout => f.write_str("the sensor layout is empty"),
            ImuError::MissingJoint { sensor, joint } => {
                write!(
                    f,
                    "sensor {sensor} is on `{joint}`, which the skeleton lacks"
                )
            }
            ImuError::DuplicateSensor { sensor } => {
                write!(f, "sensor {sensor} is placed twice, or shares its joint")
            }
            ImuError::Mounting { sensor } => {
                write!(f, "sensor {sensor}: the mounting is not a unit quaternion")
            }
            ImuError::Rate { rate_hz } => write!(
                f,
                "output rate {rate_hz} Hz is outside {}..={} Hz",
                RATE_RANGE_HZ.start(),
                RATE_RANGE_HZ.end()
            ),
            ImuError::SkeletonMismatch => {
                f.write_str("the skeleton differs from the one the adapter was built for")
            }
            ImuError::UnknownSensor { sensor } => {
                write!(f, "sensor {sensor} is not in the layout")
            }
            ImuError::Sample { sensor, error } => write!(f, "sensor {sensor}: {error}"),
        }
    }
}

impl core::error::Error for ImuError {}

/// One sensor: its placement, calibration and filter.
#[derive(Clone, Copy, Debug)]
struct Track {
    sensor: u8,
    joint: Joint,
    /// Skeleton index of `joint`.
    index: u8,
    /// Whether its rate counts toward the activity.
    activity: bool,
    nominal: Quat,
    still: StillPeriod,
    bias: Vec3,
    filter: Mahony,
    last_us: Option<u64>,
    /// The segment's global rotation is `left · q · right` for filter orientation `q`.
    left: Quat,
    right: Quat,
    /// Filter orientation at the pending output time, once a sample has passed it.
    snapshot: Option<Quat>,
    /// The last gyro reading with no axis saturated, in wire units.
    held: [i16; 3],
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// Waiting for a still T-pose; the still period began at the given time.
    Calibrating(Option<u64>),
    /// Output `next` of the grid starting at `origin_us` is pending.
    Tracking { origin_us: u64, next: u64 },
}

/// Turns IMU samples into joint positions on a skeleton (see the [module](self) docs).
#[derive(Clone, Debug)]
pub struct ImuAdapter {
    tracks: [Track; MAX_SENSORS],
    len: u8,
    /// Track of each joint's sensor, [`NO_SENSOR`] where none.
    sensed: [u8; MAX_JOINTS],
    /// The legs, planted where the T-pose turned to `stance` stands.
    legs: [Option<Leg>; 2],
    /// What the sensors measure and how the unsensed bones between them turn.
    segments: Segments,
    /// The unsensed arm's wrist and the sensed one's ([`NO_SENSOR`] for none): a layout that
    /// carries one arm puts the other's hand on the grip, by the first's.
    grip: [u8; 2],
    /// Track of the trunk sensor that sets `stance`, [`NO_SENSOR`] where none.
    trunk: u8,
    /// The planted bones' global rotation: the trunk's heading when it was last quiet.
    stance: Quat,
    /// Since when the trunk sensor has turned under [`QUIET_RAD_S`], microseconds.
    quiet_since: Option<u64>,
    joints: u8,
    root: Vec3,
    rate_mhz: u64,
    phase: Phase,
    /// The pending output time, [`ImuAdapter::output_time`] of `phase`: kept, as its 128-bit
    /// division would cost every sample some thousand instructions.
    due: Option<u64>,
    activity: f32,
    /// Samples taken while tracking with a gyro axis saturated.
    saturated: u32,
    /// Samples taken while tracking whose field was not the earth's.
    disturbed: u32,
}

impl ImuAdapter {
    /// An adapter for `layout`'s sensors on `skeleton`, emitting frames at `rate_hz`, with the
    /// filter gains [`Gains::DEFAULT`].
    ///
    /// # Errors
    /// [`ImuError::EmptyLayout`], [`ImuError::MissingJoint`], [`ImuError::DuplicateSensor`],
    /// [`ImuError::Mounting`] or [`ImuError::Rate`].
    pub fn new(
        layout: &SensorLayout,
        skeleton: &Skeleton,
        rate_hz: f32,
    ) -> Result<ImuAdapter, ImuError> {
        if !RATE_RANGE_HZ.contains(&rate_hz) {
            return Err(ImuError::Rate { rate_hz });
        }
        if layout.sensors.is_empty() {
            return Err(ImuError::EmptyLayout);
        }
        let unplaced = Track {
            sensor: 0,
            joint: Joint::Pelvis,
            index: 0,
            activity: false,
            nominal: Quat::identity(),
            still: StillPeriod::new(),
            bias: Vec3::zeros(),
            filter: Mahony::starting_at(Quat::identity()),
            last_us: None,
            left: Quat::identity(),
            right: Quat::identity(),
            snapshot: None,
            held: [0; 3],
        };
        let mut tracks = [unplaced; MAX_SENSORS];
        let mut sensed = [NO_SENSOR; MAX_JOINTS];
        for (t, (placement, track)) in layout.sensors.iter().zip(&mut tracks).enumerate() {
            let sensor = placement.sensor;
            let index = skeleton
                .index_of(placement.joint)
                .ok_or(ImuError::MissingJoint {
                    sensor,
                    joint: placement.joint,
                })?;
            let duplicate = layout.sensors[..t].iter().any(|p| p.sensor == sensor);
            if duplicate || sensed[index] != NO_SENSOR {
                return Err(ImuError::DuplicateSensor { sensor });
            }
            sensed[index] = t as u8;
            let [w, x, y, z] = placement.mounting_q14.map(|c| f32::from(c) / Q14);
            let raw = nalgebra::Quaternion::new(w, x, y, z);
            if (raw.norm() - 1.0).abs() > MOUNTING_TOLERANCE {
                return Err(ImuError::Mounting { sensor });
            }
            *track = Track {
                sensor,
                joint: placement.joint,
                index: index as u8,
                nominal: Quat::new_normalize(raw),
                ..unplaced
            };
        }
        let len = layout.sensors.len();
        let any_activity = tracks[..len]
            .iter()
            .any(|t| ACTIVITY_JOINTS.contains(&t.joint));
        for track in &mut tracks[..len] {
            track.activity = !any_activity || ACTIVITY_JOINTS.contains(&track.joint);
        }
        let legs = [
            Leg::new(skeleton, Segment::LeftLeg, Joint::LeftAnkle),
            Leg::new(skeleton, Segment::RightLeg, Joint::RightAnkle),
        ];
        let segments = Segments::new(skeleton, |k| sensed[k] != NO_SENSOR);
        let grip = grip(skeleton, |k| sensed[k] != NO_SENSOR);
        let trunk = TRUNK_JOINTS
            .iter()
            .find_map(|&j| tracks[..len].iter().position(|t| t.joint == j))
            .map_or(NO_SENSOR, |t| t as u8);
        Ok(ImuAdapter {
            tracks,
            len: len as u8,
            sensed,
            legs,
            segments,
            grip,
            trunk,
            stance: Quat::identity(),
            quiet_since: None,
            joints: skeleton.len() as u8,
            root: skeleton.offset(0),
            rate_mhz: (rate_hz * 1000.0) as u64,
            phase: Phase::Calibrating(None),
            due: None,
            activity: 0.0,
            saturated: 0,
            disturbed: 0,
        })
    }

    /// Whether calibration is over and frames are being emitted.
    pub fn is_tracking(&self) -> bool {
        matches!(self.phase, Phase::Tracking { .. })
    }

    /// The joints of `skeleton` whose places these sensors do not measure (bit `k` for joint
    /// `k`). A joint is measured where its parent is (the root where it is sensed) and its
    /// bone is sensed, shares the turn between two sensed ones, or is a hip or a shoulder: the
    /// rigid pelvis and chest carry those. Planted legs, a head following the chest and a limb
    /// following an unsensed bone are not measured, and scoring says nothing of them.
    pub fn unmeasured(&self, skeleton: &Skeleton) -> u64 {
        const GIRDLES: [Joint; 4] = [
            Joint::LeftHip,
            Joint::RightHip,
            Joint::LeftShoulder,
            Joint::RightShoulder,
        ];
        let n = skeleton.len().min(usize::from(self.joints));
        let mut measured = 0u64;
        for k in 0..n {
            let sensed = self.sensed[k] != NO_SENSOR;
            let carried = match skeleton.parent(k) {
                None => sensed,
                Some(p) => {
                    measured & (1 << p) != 0
                        && (sensed
                            || self.segments.is_bridged(k)
                            || skeleton.joint(k).is_some_and(|j| GIRDLES.contains(&j)))
                }
            };
            if carried {
                measured |= 1 << k;
            }
        }
        let all = if n >= 64 { u64::MAX } else { (1u64 << n) - 1 };
        all & !measured
    }

    /// Samples taken while tracking with a gyro axis saturated, each axis at the range held at
    /// its sensor's last unsaturated reading ([`Reading::clipped`]): the swing goes on, its
    /// segments turned less than they did while it lasts.
    pub fn saturated_samples(&self) -> u32 {
        self.saturated
    }

    /// Samples taken while tracking whose magnetic field was set aside as not the earth's
    /// ([`fusion::Field::matches`]: steel near the sensor, a club in the hand): their
    /// sensors' headings followed the gyro alone meanwhile.
    pub fn disturbed_samples(&self) -> u32 {
        self.disturbed
    }

    /// Global rotation of the segment of the sensor numbered `sensor` at its latest sample,
    /// once tracking.
    pub fn segment_rotation(&self, sensor: u8) -> Option<Quat> {
        let track = self.tracks().iter().find(|t| t.sensor == sensor)?;
        self.is_tracking()
            .then(|| track.left * track.filter.orientation() * track.right)
    }

    /// Feeds one sample; calls `emit(positions, activity)` for every output frame it
    /// completes (positions on `skeleton`, activity in rad/s).
    ///
    /// # Errors
    /// [`ImuError::SkeletonMismatch`] if `skeleton` is not the one given to
    /// [`ImuAdapter::new`], [`ImuError::UnknownSensor`], or [`ImuError::Sample`] for a sample
    /// that is saturated before tracking (dropped; once tracking, a saturated sample is read
    /// as [`Reading::clipped`] says and counted, [`ImuAdapter::saturated_samples`]), out of
    /// time order (dropped), or that follows a gap longer than
    /// [`fusion::MAX_STEP_US`] (its time is kept so the next sample is used, and its sensor's
    /// orientation is held over the gap).
    pub fn push(
        &mut self,
        skeleton: &Skeleton,
        sample: &posecoach_core::wire::ImuSample,
        mut emit: impl FnMut(&[Vec3], f32),
    ) -> Result<(), ImuError> {
        let matches = skeleton.len() == usize::from(self.joints)
            && self
                .tracks()
                .iter()
                .all(|t| skeleton.joint(usize::from(t.index)) == Some(t.joint));
        if !matches {
            return Err(ImuError::SkeletonMismatch);
        }
        let sensor = sample.sensor;
        let t = self
            .tracks()
            .iter()
            .position(|t| t.sensor == sensor)
            .ok_or(ImuError::UnknownSensor { sensor })?;
        let fail = |error| ImuError::Sample { sensor, error };
        let reading = if self.is_tracking() {
            let (reading, saturated) = Reading::clipped(sample, self.tracks[t].held);
            if saturated {
                self.saturated = self.saturated.saturating_add(1);
            } else {
                self.tracks[t].held = sample.gyro_ddps;
            }
            reading
        } else {
            Reading::from_wire(sample).map_err(fail)?
        };
        let t_us = sample.t_us;
        if self.tracks[t]
            .last_us
            .is_some_and(|previous| t_us.saturating_add(fusion::MAX_STEP_US) < previous)
        {
            self.restart_clock(t_us);
        }
        let step = match self.tracks[t].last_us {
            Some(previous) => match fusion::time_step(previous, t_us) {
                Err(e @ FusionError::TimeNotIncreasing { .. }) => return Err(fail(e)),
                step => Some(step),
            },
            None => None,
        };
        self.tracks[t].last_us = Some(t_us);
        let result = match self.phase {
            Phase::Calibrating(start) => self.calibrate(t, &reading, start, t_us),
            Phase::Tracking { .. } => {
                let dt = step.and_then(Result::ok);
                self.track(t, &reading, dt, t_us);
                self.emit_ready(skeleton, &mut emit);
                Ok(())
            }
        };
        match step {
            Some(Err(e)) => Err(fail(e)),
            _ => result.map_err(fail),
        }
    }

    /// A sample far behind its sensor's previous one is from a clock that restarted (or
    /// wrapped): every sensor's time is forgotten, calibration starts its still period over,
    /// and tracking moves its grid to the new clock, so that the stream goes on instead of
    /// waiting for the old clock's time to come round again.
    fn restart_clock(&mut self, t_us: u64) {
        for track in &mut self.tracks {
            track.last_us = None;
            track.snapshot = None;
        }
        self.quiet_since = None;
        let phase = match self.phase {
            Phase::Calibrating(_) => {
                for track in &mut self.tracks {
                    track.still = StillPeriod::new();
                }
                Phase::Calibrating(None)
            }
            Phase::Tracking { .. } => Phase::Tracking {
                origin_us: t_us,
                next: 1,
            },
        };
        self.enter(phase);
    }

    fn tracks(&self) -> &[Track] {
        &self.tracks[..usize::from(self.len)]
    }

    /// Adds a reading to the still period, starting it over if the reading is not still, and
    /// calibrates every sensor once the period is long enough and each sensor is in it.
    fn calibrate(
        &mut self,
        t: usize,
        reading: &Reading,
        start: Option<u64>,
        t_us: u64,
    ) -> Result<(), FusionError> {
        let start = match start {
            Some(start) if StillPeriod::is_still(reading) => start,
            _ => {
                for track in &mut self.tracks {
                    track.still = StillPeriod::new();
                }
                t_us
            }
        };
        self.enter(Phase::Calibrating(Some(start)));
        if !StillPeriod::is_still(reading) {
            return Ok(());
        }
        self.tracks[t].still.push(reading);
        let origin_us = start.saturating_add(CALIBRATION_US);
        if t_us < origin_us || self.tracks().iter().any(|t| t.still.samples() == 0) {
            return Ok(());
        }
        self.finish_calibration()?;
        self.enter(Phase::Tracking { origin_us, next: 1 });
        Ok(())
    }

    /// Biases, filters and sensor-to-segment offsets from the still T-pose.
    fn finish_calibration(&mut self) -> Result<(), FusionError> {
        let len = usize::from(self.len);
        for track in &mut self.tracks[..len] {
            track.filter = track.still.filter()?;
            track.bias = track.still.gyro_bias();
        }
        // In the T-pose the filter reads `yaw · mounting`: compare it with the nominal one.
        let heading = |t: &Track| t.filter.orientation() * t.nominal.inverse();
        let magnetic = heading_fit(
            self.tracks()
                .iter()
                .filter(|t| t.filter.is_magnetic())
                .map(heading),
        );
        for track in &mut self.tracks[..len] {
            let yaw = if track.filter.is_magnetic() {
                magnetic
            } else {
                heading_fit(core::iter::once(heading(track)))
            };
            track.left = yaw.inverse();
            track.right = track.filter.orientation().inverse() * yaw;
            track.snapshot = None;
        }
        self.stance = Quat::identity();
        self.quiet_since = None;
        self.activity = 0.0;
        Ok(())
    }

    /// Updates a sensor's filter (over `dt` seconds, or holds it after a gap) and records its
    /// orientation at the pending output time if this sample passed it.
    fn track(&mut self, t: usize, reading: &Reading, dt: Option<f32>, t_us: u64) {
        let due = self.due;
        let track = &mut self.tracks[t];
        let before = track.filter.orientation();
        let gyro = reading.gyro - track.bias;
        if let Some(dt) = dt {
            if track
                .filter
                .update(Gains::DEFAULT, gyro, reading.accel, reading.mag, dt)
            {
                self.disturbed = self.disturbed.saturating_add(1);
            }
            let rate = math::norm(&gyro);
            if track.activity {
                self.activity = self.activity.max(rate);
            }
            if usize::from(self.trunk) == t {
                self.quiet_since = (rate < QUIET_RAD_S).then(|| self.quiet_since.unwrap_or(t_us));
            }
        }
        let Some(due) = due.filter(|&due| t_us >= due) else {
            return;
        };
        if track.snapshot.is_none() {
            let after = track.filter.orientation();
            track.snapshot = Some(match dt {
                Some(dt) => {
                    let behind = (t_us - due) as f32 * 1e-6;
                    math::interpolate(before, after, 1.0 - behind / dt)
                }
                None => after,
            });
        }
    }

    /// Emits every output frame all sensors have passed. Grid times that every sensor is
    /// already past (a gap in all their streams) are skipped rather than repeated.
    fn emit_ready(&mut self, skeleton: &Skeleton, emit: &mut impl FnMut(&[Vec3], f32)) {
        while self.tracks().iter().all(|t| t.snapshot.is_some()) {
            self.emit_frame(skeleton, emit);
            let latest = self.tracks().iter().filter_map(|t| t.last_us).min();
            if let (Phase::Tracking { origin_us, next }, Some(latest)) = (&mut self.phase, latest) {
                // Exact (a saturated product would stop the grid short of a far jump in time,
                // and this loop would then walk the rest of it one frame at a time).
                let passed = u128::from(latest.saturating_sub(*origin_us))
                    * u128::from(self.rate_mhz)
                    / u128::from(MHZ_US);
                *next = next
                    .saturating_add(1)
                    .max(u64::try_from(passed).unwrap_or(u64::MAX));
            }
            self.due = self.output_time();
            let due = self.due;
            let len = usize::from(self.len);
            for track in &mut self.tracks[..len] {
                track.snapshot = track
                    .last_us
                    .zip(due)
                    .filter(|&(last, due)| last >= due)
                    .map(|_| track.filter.orientation());
            }
        }
    }

    /// Moves to `phase`, and its pending output time.
    fn enter(&mut self, phase: Phase) {
        self.phase = phase;
        self.due = self.output_time();
    }

    /// Time of the pending output frame, microseconds: none before tracking, nor once the
    /// grid has run past the end of the clock (a saturated time would equal every later one,
    /// and the frames would never stop coming; a clock that wraps restarts the grid).
    fn output_time(&self) -> Option<u64> {
        match self.phase {
            Phase::Calibrating(_) => None,
            Phase::Tracking { origin_us, next } => {
                let after =
                    u128::from(next) * u128::from(MHZ_US) / u128::from(self.rate_mhz.max(1));
                origin_us.checked_add(u64::try_from(after).ok()?)
            }
        }
    }

    fn emit_frame(&mut self, skeleton: &Skeleton, emit: &mut impl FnMut(&[Vec3], f32)) {
        let n = skeleton.len();
        let mut positions = [Vec3::zeros(); MAX_JOINTS];
        let sensed = |k: usize| {
            let track = self.tracks.get(usize::from(self.sensed[k]))?;
            let q = track.snapshot.unwrap_or_else(|| track.filter.orientation());
            Some(track.left * q * track.right)
        };
        let quiet = self
            .quiet_since
            .zip(self.due)
            .is_some_and(|(since, due)| due.saturating_sub(since) >= QUIET_US);
        let hanging = || {
            self.tracks()
                .iter()
                .filter(|t| ARM_JOINTS.contains(&t.joint))
                .all(|t| {
                    let k = usize::from(t.index);
                    let bone = sensed(k).unwrap_or(Quat::identity()) * skeleton.offset(k);
                    bone.y < -HANGING * math::norm(&bone)
                })
        };
        if quiet && hanging() {
            self.stance = self.trunk_heading(|k| sensed(k).unwrap_or(Quat::identity()));
        }
        if self.compose(skeleton, &sensed, self.stance, &mut positions[..n]) {
            emit(&positions[..n], self.activity);
        }
        self.activity = 0.0;
    }

    /// `frame` (positions on `skeleton`) as these sensors would see it, its legs planted
    /// facing `stance` (what [`ImuAdapter::stance_of`] gives of the frame the golfer was
    /// still in, the address): sensed bones keep their rotation, the others follow the
    /// tracking rules and the root goes to its rest position. An IMU session's swings are
    /// scored against a coach seen this way, so that what no sensor measures is not held
    /// against the student.
    ///
    /// # Errors
    /// [`ImuError::SkeletonMismatch`] if `skeleton` is not the one given to
    /// [`ImuAdapter::new`] or `frame` or `out` is shorter than it.
    pub fn view(
        &self,
        skeleton: &Skeleton,
        frame: &[Vec3],
        stance: Quat,
        out: &mut [Vec3],
    ) -> Result<(), ImuError> {
        let mut global = [Quat::identity(); MAX_JOINTS];
        let n = self.global(skeleton, frame, &mut global)?;
        if out.len() < n {
            return Err(ImuError::SkeletonMismatch);
        }
        let sensed = |k: usize| {
            self.tracks
                .get(usize::from(self.sensed[k]))
                .map(|_| global[k])
        };
        self.compose(skeleton, &sensed, stance, &mut out[..n])
            .then_some(())
            .ok_or(ImuError::SkeletonMismatch)
    }

    /// The heading the legs of `frame` (positions on `skeleton`) take when the golfer is still
    /// in it: its trunk sensor's segment's, as tracking takes it (the identity without one).
    ///
    /// # Errors
    /// As [`ImuAdapter::view`].
    pub fn stance_of(&self, skeleton: &Skeleton, frame: &[Vec3]) -> Result<Quat, ImuError> {
        let mut global = [Quat::identity(); MAX_JOINTS];
        self.global(skeleton, frame, &mut global)?;
        Ok(self.trunk_heading(|k| global[k]))
    }

    /// The heading halfway between those of the trunk sensors' segments (`rotation(joint)`
    /// each; the identity without one): where a golfer set up square faces, the hips and the
    /// shoulders turned about as far from the feet either way.
    fn trunk_heading(&self, rotation: impl Fn(usize) -> Quat) -> Quat {
        if self.trunk == NO_SENSOR {
            return Quat::identity();
        }
        heading_fit(
            self.tracks()
                .iter()
                .filter(|t| TRUNK_JOINTS.contains(&t.joint))
                .map(|t| heading(rotation(usize::from(t.index)))),
        )
    }

    /// The global rotations of `frame`'s bones into `out`; the skeleton's joints.
    fn global(
        &self,
        skeleton: &Skeleton,
        frame: &[Vec3],
        out: &mut [Quat; MAX_JOINTS],
    ) -> Result<usize, ImuError> {
        let n = skeleton.len();
        if n != usize::from(self.joints) {
            return Err(ImuError::SkeletonMismatch);
        }
        self.segments
            .rotations(skeleton, frame, out)
            .map_err(|_| ImuError::SkeletonMismatch)?;
        Ok(n)
    }

    /// Positions from the global rotations of the sensed bones (`sensed(k)`, `None` for an
    /// unsensed joint): planted legs stand as in the T-pose turned to `stance`, other bones
    /// follow their parent.
    fn compose(
        &self,
        skeleton: &Skeleton,
        sensed: &dyn Fn(usize) -> Option<Quat>,
        stance: Quat,
        out: &mut [Vec3],
    ) -> bool {
        let n = skeleton.len();
        let mut global = [Quat::identity(); MAX_JOINTS];
        let mut local = [Quat::identity(); MAX_JOINTS];
        for k in 0..n {
            let parent = skeleton.parent(k).map_or(Quat::identity(), |p| global[p]);
            global[k] =
                sensed(k).unwrap_or_else(|| self.segments.unsensed(skeleton, k, parent, sensed));
        }
        for leg in self.legs.iter().flatten() {
            let lean = leg.lean(skeleton, self.root, global[usize::from(leg.hip)], stance);
            for k in (0..n).filter(|&k| leg.joints & (1 << k) != 0 && sensed(k).is_none()) {
                global[k] = if leg.leaning & (1 << k) != 0 {
                    lean
                } else {
                    stance
                };
            }
        }
        for k in 0..n {
            let parent = skeleton.parent(k).map_or(Quat::identity(), |p| global[p]);
            local[k] = parent.inverse() * global[k];
        }
        if forward(skeleton, &local[..n], self.root, out).is_err() {
            return false;
        }
        let [trail, lead] = self.grip.map(usize::from);
        if let (Some(limb), Some(&hand)) = (
            skeleton.joint(trail).and_then(|j| Limb::new(skeleton, j)),
            out.get(lead),
        ) {
            limb.reach(out, hand);
        }
        true
    }
}

/// The wrists of a layout that senses one arm down to its wrist and neither bone of the other
/// (the other's wrist, then the sensed one), `[NO_SENSOR; 2]` for any other: the unsensed
/// arm's hand holds the grip with the sensed one's, as both hands do in a golf swing.
fn grip(skeleton: &Skeleton, sensed: impl Fn(usize) -> bool) -> [u8; 2] {
    let arm = |elbow: Joint, wrist: Joint| {
        let (e, w) = (skeleton.index_of(elbow)?, skeleton.index_of(wrist)?);
        Some((e, w))
    };
    let (Some(left), Some(right)) = (
        arm(Joint::LeftElbow, Joint::LeftWrist),
        arm(Joint::RightElbow, Joint::RightWrist),
    ) else {
        return [NO_SENSOR; 2];
    };
    let carried = |(e, w): (usize, usize)| sensed(e) && sensed(w);
    let bare = |(e, w): (usize, usize)| !sensed(e) && !sensed(w);
    match (carried(left), carried(right)) {
        (true, false) if bare(right) => [right.1 as u8, left.1 as u8],
        (false, true) if bare(left) => [left.1 as u8, right.1 as u8],
        _ => [NO_SENSOR; 2],
    }
}

/// An unsensed leg: the hip it hangs from (a child of the root), the joint it stands on, and
/// its joints below the hip: those down to the foot lean as one to reach the ground, and the
/// foot's own stay flat (bit `i` for joint `i`).
#[derive(Clone, Copy, Debug)]
struct Leg {
    hip: u8,
    joints: u64,
    leaning: u64,
    /// From the hip to the foot in the T-pose.
    reach: Vec3,
}

impl Leg {
    /// `segment`'s leg on `skeleton`, standing on `ankle` (on its lowest joint without one);
    /// `None` for a skeleton without that leg below its hip.
    fn new(skeleton: &Skeleton, segment: Segment, ankle: Joint) -> Option<Leg> {
        let n = skeleton.len();
        let held = (1..n).filter(|&k| skeleton.segment_contains(segment, k));
        let hip = held.clone().find(|&k| skeleton.parent(k) == Some(0))?;
        let joints = held
            .clone()
            .filter(|&k| k != hip)
            .fold(0u64, |mask, k| mask | 1 << k);
        let foot = skeleton
            .index_of(ankle)
            .filter(|&k| joints & (1 << k) != 0)
            .or_else(|| held.clone().rfind(|&k| k != hip))?;
        let (mut leaning, mut reach) = (0u64, Vec3::zeros());
        let mut j = foot;
        while j != hip {
            leaning |= 1 << j;
            reach += skeleton.offset(j);
            j = skeleton.parent(j)?;
        }
        Some(Leg {
            hip: hip as u8,
            joints,
            leaning,
            reach,
        })
    }

    /// The rotation of the leg's leaning bones when its hip bone turns by `hip` about the root
    /// at `root`: as in the T-pose turned to `stance`, then swung so the foot stands where the
    /// T-pose turned to `stance` has it, whatever the pelvis does (the foot reaches it to
    /// within the leg's lengthening on the lean).
    fn lean(&self, skeleton: &Skeleton, root: Vec3, hip: Quat, stance: Quat) -> Quat {
        let offset = skeleton.offset(usize::from(self.hip));
        let planted = root + stance * (offset + self.reach);
        swing(stance * self.reach, planted - (root + hip * offset)) * stance
    }
}

/// The rotation about +Y closest to all of `rotations` (least squares over their quaternions'
/// `w` and `y` parts, sign-free); the identity for none.
fn heading_fit(rotations: impl Iterator<Item = Quat>) -> Quat {
    let (mut ww, mut yy, mut wy) = (0.0f32, 0.0f32, 0.0f32);
    for q in rotations {
        ww += q.w * q.w;
        yy += q.j * q.j;
        wy += q.w * q.j;
    }
    let (sin, cos) = math::sin_cos(0.5 * libm::atan2f(2.0 * wy, ww - yy));
    Quat::new_unchecked(nalgebra::Quaternion::new(cos, 0.0, sin, 0.0))
}

/// The turn of `q` about +Y: its twist about the vertical, which for a segment bent or leaned
/// about a level axis is where it faces (the identity for a rotation with none, a half turn
/// about a level axis).
fn heading(q: Quat) -> Quat {
    let norm = math::sqrt(q.w * q.w + q.j * q.j);
    if norm < f32::EPSILON {
        return Quat::identity();
    }
    Quat::new_unchecked(nalgebra::Quaternion::new(q.w / norm, 0.0, q.j / norm, 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_core::format::Format;
    use posecoach_core::wire::{ImuSample, SensorPlacement};
    use std::vec::Vec;

    const STEP_US: u64 = 5_000;
    const IDENTITY_Q14: [i16; 4] = [16384, 0, 0, 0];
    const TOLERANCE_M: f32 = 1e-4;

    fn skeleton() -> Skeleton {
        Skeleton::standard(Format::H36m17).unwrap()
    }

    fn layout(joints: &[(u8, Joint)]) -> SensorLayout {
        SensorLayout {
            sensors: joints
                .iter()
                .map(|&(sensor, joint)| SensorPlacement {
                    sensor,
                    joint,
                    mounting_q14: IDENTITY_Q14,
                })
                .collect(),
        }
    }

    fn still(sensor: u8, k: u64) -> ImuSample {
        ImuSample {
            sensor,
            t_us: k * STEP_US,
            accel_mg: [0, 1000, 0],
            gyro_ddps: [0, 0, 0],
            mag_dut: None,
        }
    }

    fn pelvis_and_wrist() -> SensorLayout {
        layout(&[(3, Joint::Pelvis), (7, Joint::LeftWrist)])
    }

    #[test]
    fn bad_layouts_and_rates_are_refused() {
        let s = skeleton();
        let ok = pelvis_and_wrist();
        assert_eq!(
            ImuAdapter::new(&layout(&[]), &s, 60.0).err(),
            Some(ImuError::EmptyLayout)
        );
        assert_eq!(
            ImuAdapter::new(&layout(&[(1, Joint::ClubHead)]), &s, 60.0).err(),
            Some(ImuError::MissingJoint {
                sensor: 1,
                joint: Joint::ClubHead
            })
        );
        let twice = layout(&[(1, Joint::Pelvis), (1, Joint::Thorax)]);
        assert_eq!(
            ImuAdapter::new(&twice, &s, 60.0).err(),
            Some(ImuError::DuplicateSensor { sensor: 1 })
        );
        let mut zero = ok.clone();
        zero.sensors[1].mounting_q14 = [0; 4];
        assert_eq!(
            ImuAdapter::new(&zero, &s, 60.0).err(),
            Some(ImuError::Mounting { sensor: 7 })
        );
        for rate_hz in [0.0, -60.0, 5000.0] {
            assert_eq!(
                ImuAdapter::new(&ok, &s, rate_hz).err(),
                Some(ImuError::Rate { rate_hz })
            );
        }
        assert!(ImuAdapter::new(&ok, &s, f32::NAN).is_err());
    }

    #[test]
    fn a_still_t_pose_gives_the_rest_pose_after_calibration() {
        let s = skeleton();
        let mut adapter = ImuAdapter::new(&pelvis_and_wrist(), &s, 50.0).unwrap();
        let mut rest = [Vec3::zeros(); 17];
        s.rest_positions(&mut rest);
        let mut frames = 0;
        for k in 0..300 {
            for sensor in [3, 7] {
                adapter
                    .push(&s, &still(sensor, k), |p, activity| {
                        frames += 1;
                        assert_eq!(activity, 0.0);
                        for (a, b) in p.iter().zip(&rest) {
                            assert!((a - b).norm() < TOLERANCE_M);
                        }
                    })
                    .unwrap();
            }
            assert_eq!(adapter.is_tracking(), k >= 200);
        }
        // 1.495 s: calibration to 1 s, then a frame every 20 ms.
        assert_eq!(frames, 24);
    }

    /// A golfer set up with the hips 10° open and the shoulders 10° closed stands square: the
    /// legs face halfway between the trunk sensors, or where the only one faces.
    #[test]
    fn the_stance_faces_halfway_between_the_hips_and_the_shoulders() {
        let s = skeleton();
        let mut rest = [Vec3::zeros(); MAX_JOINTS];
        s.rest_positions(&mut rest);
        let turn = |deg: f32| Quat::from_axis_angle(&Vec3::y_axis(), deg.to_radians());
        let spine = s.index_of(Joint::Spine).unwrap();
        let upper =
            |k: usize| core::iter::successors(Some(k), |&j| s.parent(j)).any(|j| j == spine);
        let frame: Vec<Vec3> = (0..s.len())
            .map(|k| rest[0] + turn(if upper(k) { -10.0 } else { 10.0 }) * (rest[k] - rest[0]))
            .collect();
        let degrees = |q: Quat| q.scaled_axis().y.to_degrees();
        let both = layout(&[(0, Joint::Pelvis), (1, Joint::Thorax)]);
        let adapter = ImuAdapter::new(&both, &s, 60.0).unwrap();
        assert!(degrees(adapter.stance_of(&s, &frame).unwrap()).abs() < 0.01);
        let hips = ImuAdapter::new(&layout(&[(0, Joint::Pelvis)]), &s, 60.0).unwrap();
        assert!((degrees(hips.stance_of(&s, &frame).unwrap()) - 10.0).abs() < 0.01);
    }

    /// An adapter for the pelvis and wrist, tracking after a still second of samples 0..250.
    fn tracking() -> ImuAdapter {
        let s = skeleton();
        let mut adapter = ImuAdapter::new(&pelvis_and_wrist(), &s, 60.0).unwrap();
        for k in 0..250 {
            for sensor in [3, 7] {
                adapter.push(&s, &still(sensor, k), |_, _| {}).unwrap();
            }
        }
        assert!(adapter.is_tracking());
        adapter
    }

    /// Sample `k` of the pelvis (sensor 3) turning about the vertical at 90 °/s over `turning`
    /// but for `halted`, and of the left forearm (sensor 7) lowered from the T-pose to hang
    /// straight down at 90 °/s over `lowering`; still otherwise, each accelerometer reading
    /// gravity as its sensor is turned.
    fn turn_and_lower(
        sensor: u8,
        k: u64,
        turning: core::ops::Range<u64>,
        halted: core::ops::Range<u64>,
        lowering: core::ops::Range<u64>,
    ) -> ImuSample {
        let mut sample = still(sensor, k);
        if sensor == 3 && turning.contains(&k) && !halted.contains(&k) {
            sample.gyro_ddps = [0, 900, 0];
        }
        if sensor == 7 {
            let done = k.clamp(lowering.start, lowering.end) - lowering.start;
            let angle = -core::f32::consts::FRAC_PI_2 * done as f32 / 200.0;
            let (sin, cos) = libm::sincosf(angle);
            sample.accel_mg = [(1000.0 * sin) as i16, (1000.0 * cos) as i16, 0];
            if lowering.contains(&k) {
                sample.gyro_ddps = [0, 0, -900];
            }
        }
        sample
    }

    /// The left toe's offset from the ankle in every frame of `samples` (`turn_and_lower`'s
    /// sample `k` of a sensor) fed from sample 0 up to `end`, after a still T-pose, with `k`.
    fn feet(samples: impl Fn(u8, u64) -> ImuSample, end: u64) -> Vec<(u64, Vec3)> {
        let s = Skeleton::standard(Format::Canonical).unwrap();
        let mut adapter = ImuAdapter::new(&pelvis_and_wrist(), &s, 60.0).unwrap();
        let at = |j: Joint| s.index_of(j).unwrap();
        let (ankle, toe) = (at(Joint::LeftAnkle), at(Joint::LeftToe));
        let mut feet = Vec::new();
        for k in 0..end {
            for sensor in [3, 7] {
                adapter
                    .push(&s, &samples(sensor, k), |p, _| {
                        feet.push((k, p[toe] - p[ankle]))
                    })
                    .unwrap();
            }
        }
        feet
    }

    /// The T-pose's left foot, and turned 90° about the vertical.
    fn foot() -> (Vec3, Vec3) {
        let s = Skeleton::standard(Format::Canonical).unwrap();
        let mut rest = [Vec3::zeros(); MAX_JOINTS];
        s.rest_positions(&mut rest);
        let at = |j: Joint| s.index_of(j).unwrap();
        let foot = rest[at(Joint::LeftToe)] - rest[at(Joint::LeftAnkle)];
        let turned = Quat::from_axis_angle(&Vec3::y_axis(), core::f32::consts::FRAC_PI_2) * foot;
        (foot, turned)
    }

    /// The golfer lowers the arms from the T-pose, then turns 90° about the vertical (the
    /// pelvis sensor at 90 °/s for a second, halting for 50 ms halfway as a pelvis reversing at
    /// the top would) and stands still: while the pelvis turns the feet stay flat where they
    /// stood, pointing as they did (the legs lean to reach them from the moving hips), and once
    /// it has been quiet for [`QUIET_S`] they point where it faces.
    #[test]
    fn the_feet_face_where_the_trunk_last_faced_while_still() {
        let s = Skeleton::standard(Format::Canonical).unwrap();
        let mut rest = [Vec3::zeros(); MAX_JOINTS];
        s.rest_positions(&mut rest);
        let at = |j: Joint| s.index_of(j).unwrap();
        let (ankle, hip) = (at(Joint::LeftAnkle), at(Joint::LeftHip));
        let (foot, turned) = foot();
        let samples = |sensor, k| turn_and_lower(sensor, k, 450..660, 550..560, 250..450);
        let all = feet(samples, 810);
        let during: Vec<_> = all.iter().filter(|(k, _)| (450..660).contains(k)).collect();
        assert!(!during.is_empty());
        for (_, f) in &during {
            assert!((f - foot).norm() < 1e-4, "{f:?} against {foot:?}");
        }
        let last = all.last().unwrap().1;
        assert!(
            (last - turned).norm() < 0.01 * foot.norm(),
            "{last:?} against {turned:?}"
        );
        // The ankle stays where it stood: the hip swings at most its distance from the root
        // away, so the leg reaches it to within the leg's lengthening on that lean.
        let mut adapter = ImuAdapter::new(&pelvis_and_wrist(), &s, 60.0).unwrap();
        let mut ankles = Vec::new();
        for k in 0..660u64 {
            for sensor in [3, 7] {
                adapter
                    .push(&s, &samples(sensor, k), |p, _| ankles.push((k, p[ankle])))
                    .unwrap();
            }
        }
        let leg = rest[ankle] - rest[hip];
        let lean = 2.0 * Vec3::new(rest[hip].x - rest[0].x, 0.0, rest[hip].z - rest[0].z).norm();
        let reach = (leg.norm_squared() + lean * lean).sqrt() - leg.norm();
        for (_, a) in ankles.iter().filter(|(k, _)| *k >= 450) {
            assert!(
                (a - rest[ankle]).norm() <= reach,
                "{a:?} against {:?}",
                rest[ankle]
            );
        }
    }

    /// The same turn with the arms still out as in the T-pose, as at the top of a swing or a
    /// held finish: the trunk is quiet for longer than [`QUIET_S`], but the feet keep their
    /// place until the arms hang.
    #[test]
    fn the_feet_stay_put_until_the_arms_hang() {
        let (foot, turned) = foot();
        let samples = |sensor, k| turn_and_lower(sensor, k, 250..450, 0..0, 600..800);
        let all = feet(samples, 950);
        let quiet = all.iter().filter(|(k, _)| (450..600).contains(k));
        assert!(quiet.clone().count() > 10);
        for (_, f) in quiet {
            assert!((f - foot).norm() < 1e-4, "{f:?} against {foot:?}");
        }
        let last = all.last().unwrap().1;
        assert!(
            (last - turned).norm() < 0.01 * foot.norm(),
            "{last:?} against {turned:?}"
        );
    }

    /// The wrist turns at 1000 °/s about its long axis for 50 ms, then for 50 ms past the gyro's
    /// range, sent saturated: the swing goes on, the clipped samples are counted, and the
    /// segment turns on at the held rate (100° in all) rather than stopping (50°).
    #[test]
    fn a_saturated_gyro_holds_its_last_rate_and_is_counted() {
        let s = skeleton();
        let mut adapter = tracking();
        let before = adapter.segment_rotation(7).unwrap();
        let mut frames = 0;
        for k in 250..300u64 {
            for sensor in [3, 7] {
                let mut sample = still(sensor, k);
                if sensor == 7 && k < 270 {
                    sample.gyro_ddps = [0, if k < 260 { 10_000 } else { i16::MAX }, 0];
                }
                adapter.push(&s, &sample, |_, _| frames += 1).unwrap();
            }
        }
        assert!(frames > 10);
        assert_eq!(adapter.saturated_samples(), 10);
        let turned = (before.inverse() * adapter.segment_rotation(7).unwrap())
            .angle()
            .to_degrees();
        assert!((turned - 100.0).abs() < 2.0, "{turned}°");
    }

    /// What each layout measures on the H3.6M skeleton: six sensors leave the planted legs and
    /// the head; four (no trail arm) the trail elbow and wrist too; a wrist alone, whose
    /// forearm hangs from no measured joint, nothing.
    #[test]
    fn each_layout_measures_what_its_sensors_carry() {
        let s = skeleton();
        let bits = |joints: &[Joint]| {
            joints
                .iter()
                .fold(0u64, |m, &j| m | 1 << s.index_of(j).unwrap())
        };
        let unmeasured = |joints: &[(u8, Joint)]| {
            ImuAdapter::new(&layout(joints), &s, 60.0)
                .unwrap()
                .unmeasured(&s)
        };
        use Joint::*;
        let legs_and_head = bits(&[LeftKnee, LeftAnkle, RightKnee, RightAnkle, Neck, HeadTop]);
        let six = [
            (0, Pelvis),
            (1, Thorax),
            (2, LeftElbow),
            (3, RightElbow),
            (4, LeftWrist),
            (5, RightWrist),
        ];
        assert_eq!(unmeasured(&six), legs_and_head);
        assert_eq!(
            unmeasured(&[six[0], six[1], six[2], six[4]]),
            legs_and_head | bits(&[RightElbow, RightWrist])
        );
        assert_eq!(unmeasured(&[six[4]]), (1 << s.len()) - 1);
        // Without a thorax sensor the spine shares nothing and the chest is not measured.
        assert_eq!(
            unmeasured(&[six[0]]) & bits(&[Spine, Thorax, LeftShoulder]),
            bits(&[Spine, Thorax, LeftShoulder])
        );
    }

    /// Four sensors, one arm: the other's hand holds the grip by the sensed one's, as far as
    /// its arm reaches.
    #[test]
    fn an_unsensed_arm_puts_its_hand_on_the_grip() {
        use Joint::*;
        let s = skeleton();
        let four = layout(&[(0, Pelvis), (1, Thorax), (2, LeftElbow), (3, LeftWrist)]);
        let adapter = ImuAdapter::new(&four, &s, 60.0).unwrap();
        let at = |j: Joint| s.index_of(j).unwrap();
        let mut frame = [Vec3::zeros(); MAX_JOINTS];
        s.rest_positions(&mut frame);
        // The lead arm hangs, its forearm across the chest.
        let (shoulder, elbow, wrist) = (at(LeftShoulder), at(LeftElbow), at(LeftWrist));
        let upper = s.offset(elbow).norm();
        frame[elbow] = frame[shoulder] - Vec3::y() * upper;
        frame[wrist] =
            frame[elbow] + Vec3::new(-0.7, 0.0, 0.7).normalize() * s.offset(wrist).norm();
        let mut out = [Vec3::zeros(); MAX_JOINTS];
        let n = s.len();
        adapter
            .view(&s, &frame[..n], Quat::identity(), &mut out[..n])
            .unwrap();
        assert!((out[at(RightWrist)] - out[wrist]).norm() < 1e-3);
        // Out of reach in the T-pose: as far toward it as the arm goes.
        s.rest_positions(&mut frame);
        adapter
            .view(&s, &frame[..n], Quat::identity(), &mut out[..n])
            .unwrap();
        let from = out[at(RightShoulder)];
        let arm = s.offset(at(RightElbow)).norm() + s.offset(at(RightWrist)).norm();
        let toward = from + (out[wrist] - from).normalize() * arm;
        assert!((out[at(RightWrist)] - toward).norm() < 1e-3);
        // With a sensor on each forearm, each arm is its own.
        let both = ImuAdapter::new(&layout(&[(0, LeftWrist), (1, RightWrist)]), &s, 60.0).unwrap();
        both.view(&s, &frame[..n], Quat::identity(), &mut out[..n])
            .unwrap();
        assert!((out[at(RightWrist)] - frame[at(RightWrist)]).norm() < 1e-3);
    }

    /// Frames emitted by `samples` still samples of both sensors from `from_us` on, the clock
    /// wrapping round past `u64::MAX`.
    fn frames_from(adapter: &mut ImuAdapter, from_us: u64, samples: u64) -> usize {
        let s = skeleton();
        let mut frames = 0;
        for k in 0..samples {
            for sensor in [3, 7] {
                let mut sample = still(sensor, k);
                sample.t_us = from_us.wrapping_add(k * STEP_US);
                let _ = adapter.push(&s, &sample, |_, _| frames += 1);
            }
        }
        frames
    }

    #[test]
    fn a_far_jump_in_time_is_skipped_not_walked() {
        // Every sensor jumps ahead by 3e14 to 1.8e19 µs (past where a saturating product of
        // time and rate stalled the grid), the last jump to within ten samples of the end of
        // the clock, which then reaches u64::MAX exactly (where a saturated grid time once
        // equalled every later one) and wraps: each sample ends after a frame or two.
        for jump_us in [300_000_000_000_000u64, 1 << 60, u64::MAX - 10 * STEP_US] {
            let mut adapter = tracking();
            let frames = frames_from(&mut adapter, jump_us, 12);
            assert!(frames <= 12, "{jump_us}: {frames} frames");
        }
    }

    #[test]
    fn a_restarted_clock_restarts_the_stream() {
        // While tracking: the grid moves to the new clock and frames go on at the rate (60 Hz
        // over 0.5 s, less the first period), whether the clock restarted or wrapped round.
        for before_us in [10_000_000u64, u64::MAX - 2 * STEP_US] {
            let mut adapter = tracking();
            frames_from(&mut adapter, before_us, 3);
            let frames = frames_from(&mut adapter, 1_000, 100);
            assert!((28..=30).contains(&frames), "{before_us}: {frames} frames");
        }
        // While calibrating: the still period starts over on the new clock and ends a second
        // into it.
        let s = skeleton();
        let mut adapter = ImuAdapter::new(&pelvis_and_wrist(), &s, 60.0).unwrap();
        frames_from(&mut adapter, 50_000_000, 150);
        assert!(!adapter.is_tracking());
        frames_from(&mut adapter, 0, 150);
        assert!(!adapter.is_tracking());
        frames_from(&mut adapter, 150 * STEP_US, 60);
        assert!(adapter.is_tracking());
    }

    #[test]
    fn motion_restarts_calibration() {
        let s = skeleton();
        let mut adapter = ImuAdapter::new(&pelvis_and_wrist(), &s, 60.0).unwrap();
        for k in 0..400 {
            for sensor in [3, 7] {
                let mut sample = still(sensor, k);
                if k == 150 {
                    sample.gyro_ddps = [0, 300, 0];
                }
                adapter.push(&s, &sample, |_, _| {}).unwrap();
            }
            assert_eq!(adapter.is_tracking(), k >= 350, "{k}");
        }
    }

    #[test]
    fn a_turning_pelvis_turns_the_body_and_the_wrist_gives_activity() {
        let s = skeleton();
        let mut adapter = ImuAdapter::new(&pelvis_and_wrist(), &s, 100.0).unwrap();
        let (rate_ddps, turn_samples) = (900i16, 100u64);
        let mut last = Vec::new();
        let mut activity = 0.0f32;
        // Calibration ends with the samples at 1 s, then both sensors turn.
        for k in 0..=200 + turn_samples {
            for sensor in [3, 7] {
                let mut sample = still(sensor, k);
                if k > 200 {
                    sample.gyro_ddps = [0, rate_ddps, 0];
                }
                adapter
                    .push(&s, &sample, |p, a| {
                        last = p.to_vec();
                        activity = a;
                    })
                    .unwrap();
            }
        }
        // The pelvis turned 90 °/s for 0.5 s about up, and the body with it.
        let turned = (f32::from(rate_ddps) / 10.0 * 0.5).to_radians();
        let mut rest = [Vec3::zeros(); 17];
        s.rest_positions(&mut rest);
        let shoulder = s.index_of(Joint::LeftShoulder).unwrap();
        let expected = Quat::from_axis_angle(&Vec3::y_axis(), turned) * (rest[shoulder] - rest[0]);
        // The last frame is at most one 10 ms period before the last sample.
        let tolerance = (f32::from(rate_ddps) / 10.0 * 0.01).to_radians();
        assert!((last[shoulder] - last[0]).angle(&expected) <= tolerance);
        assert!((activity - f32::from(rate_ddps).to_radians() / 10.0).abs() < 1e-3);
        let rotation = adapter.segment_rotation(3).unwrap();
        assert!((rotation.angle() - turned).abs() < 1e-3);
        assert_eq!(adapter.segment_rotation(9), None);
    }

    #[test]
    fn bad_samples_are_errors_and_the_adapter_carries_on() {
        let s = skeleton();
        let mut adapter = ImuAdapter::new(&pelvis_and_wrist(), &s, 60.0).unwrap();
        let other = Skeleton::standard(Format::Coco17).unwrap();
        assert_eq!(
            adapter.push(&other, &still(3, 0), |_, _| {}),
            Err(ImuError::SkeletonMismatch)
        );
        assert_eq!(
            adapter.push(&s, &still(4, 0), |_, _| {}),
            Err(ImuError::UnknownSensor { sensor: 4 })
        );
        adapter.push(&s, &still(3, 1), |_, _| {}).unwrap();
        let sample_error = |error| Err(ImuError::Sample { sensor: 3, error });
        assert_eq!(
            adapter.push(&s, &still(3, 1), |_, _| {}),
            sample_error(FusionError::TimeNotIncreasing {
                previous_us: STEP_US,
                t_us: STEP_US
            })
        );
        let saturated = ImuSample {
            accel_mg: [0, i16::MAX, 0],
            ..still(3, 2)
        };
        assert_eq!(
            adapter.push(&s, &saturated, |_, _| {}),
            sample_error(FusionError::SaturatedAccel { axis: 1 })
        );
        let late = 2 * STEP_US + fusion::MAX_STEP_US;
        assert_eq!(
            adapter.push(&s, &still(3, late / STEP_US), |_, _| {}),
            sample_error(FusionError::TimeStep {
                step_us: late - STEP_US,
                max_us: fusion::MAX_STEP_US
            })
        );
        let mut frames = 0;
        for k in late / STEP_US + 1..late / STEP_US + 400 {
            for sensor in [3, 7] {
                adapter
                    .push(&s, &still(sensor, k), |_, _| frames += 1)
                    .unwrap();
            }
        }
        assert!(adapter.is_tracking() && frames > 0);
    }
}
