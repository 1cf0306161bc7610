//! Attitude of one IMU: wire units to SI, a still period (gyro bias and starting attitude) and
//! a Mahony filter.
//!
//! The filter is written here rather than taken from the `ahrs` crate: it is small, `f32`,
//! allocation-free, and works in the posecoach world (+Y up, gravity along −Y) instead of a
//! NED or Z-up frame. Its orientation `q` maps sensor-frame vectors to the filter's world frame,
//! whose +Y is up and whose heading is either arbitrary (6-axis: the heading the filter started
//! with) or magnetic (9-axis: the horizontal part of the earth's field along +Z).
//!
//! The accelerometer reads `qᵀ(a − g)`, +1 g along the sensor's world-up direction at rest. Each
//! update turns the estimated up direction toward the measured one with the proportional gain
//! `kp` and accumulates the same error with the integral gain `ki` (a slow correction of the
//! gyro bias left after [`StillPeriod::gyro_bias`]). Readings whose norm is not within
//! [`ACCEL_GATE`] of 1 g, or taken while turning faster than [`TURN_GATE`], say little about
//! gravity (a swing's arms feel many g) and only the gyro is integrated. The integral learns
//! only while the sensor lies still ([`STILL_GYRO`], [`STILL_ACCEL`]): a correction taken in
//! motion is partly the motion's, and as a vector in the sensor's frame it would turn with the
//! sensor into the vertical, where it drifts the heading that nothing corrects without a
//! magnetometer (without this gate an IMU session without magnetometers named a wrist 6-17 cm
//! off after 20 swings in 84 % of unflawed sessions; with it 12 %). The magnetometer only
//! corrects heading: its error is projected on the up axis so a disturbed field cannot tilt
//! the estimate. A magnetic filter keeps the field it started from ([`Field`]) and sets aside a
//! reading whose strength or dip is not the earth's ([`FIELD_STRENGTH_GATE`],
//! [`FIELD_DIP_GATE`]), and every reading for [`FIELD_HOLD_S`] after one: steel near the sensor
//! (a club in the hand) adds a field of its own, fixed in the sensor's frame, that matches the
//! earth's at some orientations and not at others, and the step then turns by the gyro alone.
//! Following it where it happened to match, at the same address swing after swing, turned a
//! wrist's heading a little more each time (in range sessions with a 15 µT club, false
//! tendencies after 10 swings: 72 % without the hold).
//!
//! ```
//! use posecoach_adapters::fusion::{Gains, Mahony};
//! use posecoach_core::Vec3;
//!
//! let at_rest = Vec3::new(0.0, 9.81, 0.0);
//! let mut filter = Mahony::from_accel(at_rest).unwrap();
//! let turning = Vec3::new(0.0, 1.0, 0.0); // 1 rad/s about up, for 0.5 s
//! for _ in 0..100 {
//!     filter.update(Gains::DEFAULT, turning, at_rest, None, 0.005);
//! }
//! assert!((filter.orientation().angle() - 0.5).abs() < 1e-3);
//! ```

use posecoach_core::kinematics::swing;
use posecoach_core::math;
use posecoach_core::wire::ImuSample;
use posecoach_core::{Quat, Vec3};

/// Standard gravity, m/s².
pub const G: f32 = 9.80665;
/// Metres per second squared in one milli-g.
const MPS2_PER_MG: f32 = G / 1000.0;
/// Radians per second in one tenth of a degree per second.
const RADPS_PER_DDPS: f32 = 0.1 * core::f32::consts::PI / 180.0;
/// Microtesla in one tenth of a microtesla.
const UT_PER_DUT: f32 = 0.1;

/// Longest step between two samples of one sensor, microseconds (10 Hz).
pub const MAX_STEP_US: u64 = 100_000;
/// Where gravity is needed, the acceleration's norm must be within this fraction of 1 g.
pub const GRAVITY_TOLERANCE: f32 = 0.2;
/// The filter corrects tilt only from readings whose norm is within this fraction of 1 g.
pub const ACCEL_GATE: f32 = 0.1;
/// The filter corrects tilt only while turning slower than this, rad/s (about 17 °/s): a
/// turning segment's accelerometer feels its own motion as well as gravity.
pub const TURN_GATE: f32 = 0.3;
/// Largest bias the integral term may learn, rad/s (about 3 °/s).
pub const MAX_INTEGRAL: f32 = 0.05;
/// A still sensor turns slower than this, rad/s (about 5.7 °/s, above any MEMS gyro's bias).
pub const STILL_GYRO: f32 = 0.1;
/// A still sensor's acceleration norm is within this fraction of 1 g.
pub const STILL_ACCEL: f32 = 0.05;
/// A magnetic field and gravity closer than this sine of their angle give no heading.
const MIN_MAG_SINE: f32 = 0.1;
/// A field is the earth's only while its strength is within this fraction of the one the
/// filter started from: steel a few centimetres away changes it by tens of percent, the
/// earth's changes by a few over a range's bays.
pub const FIELD_STRENGTH_GATE: f32 = 0.1;
/// ...and its direction's vertical component (minus the sine of the dip) within this of the
/// one the filter started from: about 3° of dip at the equator, 6° at a 60° dip.
pub const FIELD_DIP_GATE: f32 = 0.05;
/// After a reading that is not the earth's field, seconds for which the filter follows no
/// field: longer than a swing with its set-up, so that a club held through the swing is not
/// followed at the orientations where its field happens to pass for the earth's.
pub const FIELD_HOLD_S: f32 = 10.0;

/// Why a sample could not be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FusionError {
    /// An accelerometer axis (0 = x) reads `i16::MIN` or `i16::MAX`.
    #[allow(missing_docs)]
    SaturatedAccel { axis: u8 },
    /// A gyro axis (0 = x) reads `i16::MIN` or `i16::MAX`.
    #[allow(missing_docs)]
    SaturatedGyro { axis: u8 },
    /// Gravity is needed but the acceleration's norm (milli-g) is not near 1 g.
    #[allow(missing_docs)]
    AccelNorm { milli_g: u32 },
    /// Heading is needed but the magnetic field is zero or parallel to gravity.
    MagDirection,
    /// The sample is not later than the sensor's previous one.
    #[allow(missing_docs)]
    TimeNotIncreasing { previous_us: u64, t_us: u64 },
    /// The step from the sensor's previous sample is longer than [`MAX_STEP_US`].
    #[allow(missing_docs)]
    TimeStep { step_us: u64, max_us: u64 },
}

impl core::fmt::Display for FusionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FusionError::SaturatedAccel { axis } => {
                write!(f, "accelerometer axis {axis} saturated")
            }
            FusionError::SaturatedGyro { axis } => write!(f, "gyro axis {axis} saturated"),
            FusionError::AccelNorm { milli_g } => {
                write!(f, "acceleration of {milli_g} mg cannot stand for gravity")
            }
            FusionError::MagDirection => {
                f.write_str("magnetic field is zero or parallel to gravity: no heading")
            }
            FusionError::TimeNotIncreasing { previous_us, t_us } => {
                write!(
                    f,
                    "sample at {t_us} us is not after the previous one at {previous_us} us"
                )
            }
            FusionError::TimeStep { step_us, max_us } => {
                write!(
                    f,
                    "step of {step_us} us between samples exceeds {max_us} us"
                )
            }
        }
    }
}

impl core::error::Error for FusionError {}

/// One sample in SI units, in the sensor frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// Specific force, m/s² (`+G` along up at rest).
    pub accel: Vec3,
    /// Angular rate, rad/s.
    pub gyro: Vec3,
    /// Magnetic field, µT, where the sensor has a magnetometer.
    pub mag: Option<Vec3>,
}

impl Reading {
    /// Converts a wire sample.
    ///
    /// # Errors
    /// [`FusionError::SaturatedAccel`] or [`FusionError::SaturatedGyro`] if an axis sits at
    /// either end of its `i16` range.
    pub fn from_wire(sample: &ImuSample) -> Result<Reading, FusionError> {
        if let Some(axis) = saturated_axis(sample.accel_mg) {
            return Err(FusionError::SaturatedAccel { axis });
        }
        if let Some(axis) = saturated_axis(sample.gyro_ddps) {
            return Err(FusionError::SaturatedGyro { axis });
        }
        Ok(Reading::clipped(sample, [0; 3]).0)
    }

    /// Converts a wire sample taken while tracking, when arms and clubs pass the sensors'
    /// ranges in the fastest part of a swing: a saturated accelerometer reads zero (never
    /// taken for gravity), and a saturated gyro axis reads `held` on that axis (wire units:
    /// the sensor's last unsaturated reading, a rate just under the range the true one is
    /// past). Also says whether a gyro axis saturated.
    pub fn clipped(sample: &ImuSample, held: [i16; 3]) -> (Reading, bool) {
        let accel = match saturated_axis(sample.accel_mg) {
            Some(_) => Vec3::zeros(),
            None => si(sample.accel_mg, MPS2_PER_MG),
        };
        let mut gyro = sample.gyro_ddps;
        let mut saturated = false;
        for (x, held) in gyro.iter_mut().zip(held) {
            if *x == i16::MIN || *x == i16::MAX {
                *x = held;
                saturated = true;
            }
        }
        let gyro = si(gyro, RADPS_PER_DDPS);
        let reading = Reading {
            accel,
            gyro,
            mag: sample.mag_dut.map(|m| si(m, UT_PER_DUT)),
        };
        (reading, saturated)
    }
}

/// The first axis (0 = x) at either end of the `i16` range.
fn saturated_axis(v: [i16; 3]) -> Option<u8> {
    (0u8..)
        .zip(v)
        .find_map(|(axis, x)| (x == i16::MIN || x == i16::MAX).then_some(axis))
}

fn si(v: [i16; 3], scale: f32) -> Vec3 {
    Vec3::from(v.map(|x| f32::from(x) * scale))
}

/// Seconds from `previous_us` to `t_us`.
///
/// # Errors
/// [`FusionError::TimeNotIncreasing`] if `t_us <= previous_us`, [`FusionError::TimeStep`] if
/// the step exceeds [`MAX_STEP_US`].
pub fn time_step(previous_us: u64, t_us: u64) -> Result<f32, FusionError> {
    match t_us.checked_sub(previous_us) {
        None | Some(0) => Err(FusionError::TimeNotIncreasing { previous_us, t_us }),
        Some(step_us) if step_us > MAX_STEP_US => Err(FusionError::TimeStep {
            step_us,
            max_us: MAX_STEP_US,
        }),
        Some(step_us) => Ok(step_us as f32 * 1e-6),
    }
}

/// The sensor-frame up direction from an acceleration that stands for gravity.
///
/// # Errors
/// [`FusionError::AccelNorm`] if the norm is not within [`GRAVITY_TOLERANCE`] of 1 g.
pub fn gravity_up(accel: Vec3) -> Result<Vec3, FusionError> {
    let norm = accel.norm();
    if (norm / G - 1.0).abs() > GRAVITY_TOLERANCE || !norm.is_finite() {
        let milli_g = if norm.is_finite() {
            norm / MPS2_PER_MG
        } else {
            0.0
        };
        return Err(FusionError::AccelNorm {
            milli_g: milli_g as u32,
        });
    }
    Ok(accel / norm)
}

/// Proportional and integral gains of the [`Mahony`] filter, rad/s per unit of direction error
/// (the sine of the angle between the estimated and measured directions). Given to each step
/// ([`Mahony::update`]) rather than kept by each filter: the filters of one body share them,
/// and a filter's bytes are copied with the adapter that holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gains {
    /// Proportional gain: the correction's time constant is about `1 / kp` seconds.
    pub kp: f32,
    /// Integral gain: how fast a residual gyro bias is learned.
    pub ki: f32,
}

impl Gains {
    /// For tracking a body segment after the bias was measured at rest: a 2 s time constant
    /// while the segment is nearly still, and an integral whose slow pole (about 7 s, near
    /// critical damping) takes up the bias left after calibration. On the driver swing with
    /// synthetic MEMS noise, `kp` 1 doubled the arm errors and `kp` 2 (no turn gate) made
    /// them ten times larger.
    pub const DEFAULT: Gains = Gains { kp: 0.5, ki: 0.05 };
}

/// The earth's field as a magnetic filter first saw it: what its later readings must match to
/// correct its heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    /// Strength, µT.
    pub strength: f32,
    /// The unit field's component along up: minus the sine of the dip north of the magnetic
    /// equator.
    pub vertical: f32,
    /// Seconds for which readings are still set aside after one that did not match.
    hold_s: f32,
}

impl Field {
    /// Whether a reading of `strength` (µT) whose unit vector's vertical component is
    /// `vertical` is this field, within [`FIELD_STRENGTH_GATE`] and [`FIELD_DIP_GATE`].
    pub fn matches(&self, strength: f32, vertical: f32) -> bool {
        (strength - self.strength).abs() <= FIELD_STRENGTH_GATE * self.strength
            && (vertical - self.vertical).abs() <= FIELD_DIP_GATE
    }
}

/// A Mahony complementary filter on one IMU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mahony {
    q: Quat,
    integral: Vec3,
    /// The field the heading follows; none for a filter without a magnetic heading.
    field: Option<Field>,
}

impl Mahony {
    /// A filter levelled on one accelerometer reading (or a still period's mean), with an
    /// arbitrary heading: the smallest rotation taking the measured up onto +Y.
    ///
    /// # Errors
    /// As [`gravity_up`].
    pub fn from_accel(accel: Vec3) -> Result<Mahony, FusionError> {
        let up = gravity_up(accel)?;
        Ok(Mahony::starting_at(swing(up, Vec3::y())))
    }

    /// A filter levelled on an accelerometer reading with its heading from a magnetometer
    /// reading: the field's horizontal part along +Z. The reading is the [`Field`] its updates
    /// follow.
    ///
    /// # Errors
    /// As [`gravity_up`], and [`FusionError::MagDirection`] if the field gives no heading.
    pub fn from_accel_mag(accel: Vec3, mag: Vec3) -> Result<Mahony, FusionError> {
        let up = gravity_up(accel)?;
        let north = mag - up * up.dot(&mag);
        let strength = mag.norm();
        if north.norm() <= MIN_MAG_SINE * strength || north.norm() == 0.0 {
            return Err(FusionError::MagDirection);
        }
        let north = north.normalize();
        // Rows: the world axes X, Y, Z seen in the sensor frame.
        let rows = nalgebra::Matrix3::from_rows(&[
            up.cross(&north).transpose(),
            up.transpose(),
            north.transpose(),
        ]);
        let rotation = nalgebra::Rotation3::from_matrix_unchecked(rows);
        Ok(Mahony {
            field: Some(Field {
                strength,
                vertical: up.dot(&mag) / strength,
                hold_s: 0.0,
            }),
            ..Mahony::starting_at(Quat::from_rotation_matrix(&rotation))
        })
    }

    /// A filter starting at orientation `q`, with an arbitrary heading.
    pub fn starting_at(q: Quat) -> Mahony {
        Mahony {
            q,
            integral: Vec3::zeros(),
            field: None,
        }
    }

    /// Whether the heading is magnetic ([`Mahony::from_accel_mag`]): then updates use the field.
    pub fn is_magnetic(&self) -> bool {
        self.field.is_some()
    }

    /// The estimated orientation: sensor frame to the filter's world frame.
    pub fn orientation(&self) -> Quat {
        self.q
    }

    /// One step of `dt` seconds: integrates `gyro` (rad/s, bias removed) corrected toward the
    /// up direction of `accel` (m/s², ignored outside [`ACCEL_GATE`] or beyond [`TURN_GATE`])
    /// and, where given and the heading is magnetic, the heading of `mag` (µT) if it matches
    /// the filter's [`Field`] and no reading in the last [`FIELD_HOLD_S`] did not. Returns
    /// whether a field was given that did not match.
    pub fn update(
        &mut self,
        gains: Gains,
        gyro: Vec3,
        accel: Vec3,
        mag: Option<Vec3>,
        dt: f32,
    ) -> bool {
        // The rotation's matrix, sensor to world, made once: its rows are the world's axes in
        // the sensor's frame (the middle one is up), and it turns the field both ways.
        let rotation = *self.q.to_rotation_matrix().matrix();
        let up = Vec3::new(rotation.m21, rotation.m22, rotation.m23);
        let mut error = Vec3::zeros();
        let (norm, rate) = (math::norm(&accel), math::norm(&gyro));
        if (norm / G - 1.0).abs() <= ACCEL_GATE && rate <= TURN_GATE {
            error += (accel / norm).cross(&up);
        }
        let mut disturbed = false;
        if let (Some(field), Some(m)) = (&mut self.field, mag.filter(|m| m.norm_squared() > 0.0)) {
            let strength = math::norm(&m);
            let m = m / strength;
            let h = rotation * m;
            if !field.matches(strength, h.y) {
                disturbed = true;
                field.hold_s = FIELD_HOLD_S;
            } else if field.hold_s > 0.0 {
                field.hold_s -= dt;
            } else {
                let horizontal = math::sqrt(h.x * h.x + h.z * h.z);
                let expected = rotation.tr_mul(&Vec3::new(0.0, h.y, horizontal));
                error += up * up.dot(&m.cross(&expected));
            }
        }
        // The bias is learned only while the sensor lies still: a correction taken in motion
        // (an arm swinging through a turn) is in part the motion's, and the integral, a vector
        // in the sensor's frame, carries it into whatever axis the sensor later turns toward,
        // the vertical too, where nothing without a magnetometer corrects it.
        if rate < STILL_GYRO && (norm / G - 1.0).abs() < STILL_ACCEL {
            self.integral += error * (gains.ki * dt);
        }
        let bias_norm = math::norm(&self.integral);
        if bias_norm > MAX_INTEGRAL {
            self.integral *= MAX_INTEGRAL / bias_norm;
        }
        let rate = gyro + error * gains.kp + self.integral;
        // Normalized through the FPU's root (nalgebra's `new_normalize`, to the bit).
        let turned = (self.q * math::turn(rate * dt)).into_inner();
        self.q = Quat::new_unchecked(turned / math::sqrt(turned.norm_squared()));
        disturbed
    }
}

/// Sums over a period in which a sensor lies still: its mean gyro is the bias, its mean
/// acceleration (and field) the starting attitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StillPeriod {
    gyro: Vec3,
    accel: Vec3,
    mag: Vec3,
    samples: u32,
    mag_samples: u32,
}

impl Default for StillPeriod {
    fn default() -> Self {
        StillPeriod::new()
    }
}

impl StillPeriod {
    /// An empty period.
    pub fn new() -> StillPeriod {
        StillPeriod {
            gyro: Vec3::zeros(),
            accel: Vec3::zeros(),
            mag: Vec3::zeros(),
            samples: 0,
            mag_samples: 0,
        }
    }

    /// Whether `reading` looks like a sensor at rest: turning slower than [`STILL_GYRO`] and
    /// feeling 1 g within [`STILL_ACCEL`].
    pub fn is_still(reading: &Reading) -> bool {
        math::norm(&reading.gyro) < STILL_GYRO
            && (math::norm(&reading.accel) / G - 1.0).abs() < STILL_ACCEL
    }

    /// Adds one reading.
    pub fn push(&mut self, reading: &Reading) {
        self.gyro += reading.gyro;
        self.accel += reading.accel;
        self.samples = self.samples.saturating_add(1);
        if let Some(m) = reading.mag {
            self.mag += m;
            self.mag_samples = self.mag_samples.saturating_add(1);
        }
    }

    /// Readings added.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Mean gyro: the bias to subtract from later readings (zero for an empty period).
    pub fn gyro_bias(&self) -> Vec3 {
        self.mean(self.gyro, self.samples)
    }

    /// Mean acceleration.
    pub fn accel(&self) -> Vec3 {
        self.mean(self.accel, self.samples)
    }

    /// Mean field, if every reading had one.
    pub fn mag(&self) -> Option<Vec3> {
        (self.samples > 0 && self.mag_samples == self.samples)
            .then(|| self.mean(self.mag, self.mag_samples))
    }

    fn mean(&self, sum: Vec3, n: u32) -> Vec3 {
        if n == 0 {
            Vec3::zeros()
        } else {
            sum / n as f32
        }
    }

    /// A filter started from this period's mean readings: with a heading from the field where
    /// every reading had a usable one, else levelled only.
    ///
    /// # Errors
    /// As [`gravity_up`] (an empty period has no gravity).
    pub fn filter(&self) -> Result<Mahony, FusionError> {
        let accel = self.accel();
        match self.mag() {
            Some(mag) => Mahony::from_accel_mag(accel, mag).or_else(|_| Mahony::from_accel(accel)),
            None => Mahony::from_accel(accel),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f32 = 0.005;
    const GAINS: Gains = Gains::DEFAULT;
    /// The gyro alone.
    const UNCORRECTED: Gains = Gains { kp: 0.0, ki: 0.0 };

    #[test]
    fn a_clipped_sample_holds_its_saturated_gyro_axes_and_drops_a_saturated_accelerometer() {
        let sample = ImuSample {
            sensor: 0,
            t_us: 0,
            accel_mg: [0, i16::MIN, 500],
            gyro_ddps: [i16::MAX, 100, i16::MIN],
            mag_dut: Some([10, 20, 30]),
        };
        let held = [300, -1, -310];
        let (reading, saturated) = Reading::clipped(&sample, held);
        assert!(saturated);
        assert_eq!(reading.accel, Vec3::zeros());
        assert_eq!(reading.gyro, si([300, 100, -310], RADPS_PER_DDPS));
        assert_eq!(reading.mag, Some(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(
            Reading::from_wire(&sample),
            Err(FusionError::SaturatedAccel { axis: 1 })
        );
        let unsaturated = ImuSample {
            accel_mg: [0, 1000, 0],
            gyro_ddps: [1, 2, 3],
            ..sample
        };
        let (reading, saturated) = Reading::clipped(&unsaturated, held);
        assert!(!saturated);
        assert_eq!(Ok(reading), Reading::from_wire(&unsaturated));
    }
    const RATE: f32 = 1.2;
    const TOLERANCE_RAD: f32 = 1e-3;
    /// Long enough for the default gains' slow (integral) pole, about 7 s, to settle.
    const CONVERGED_S: f32 = 60.0;

    fn at_rest(orientation: Quat) -> Vec3 {
        orientation.inverse() * Vec3::new(0.0, G, 0.0)
    }

    fn tilted() -> Quat {
        Quat::from_euler_angles(0.5, 0.3, -0.7)
    }

    fn sample(accel_mg: [i16; 3], gyro_ddps: [i16; 3]) -> ImuSample {
        ImuSample {
            sensor: 0,
            t_us: 0,
            accel_mg,
            gyro_ddps,
            mag_dut: None,
        }
    }

    #[test]
    fn a_still_sensor_converges_to_gravity() {
        let truth = tilted();
        let mut filter = Mahony::starting_at(Quat::identity());
        for _ in 0..(CONVERGED_S / DT) as usize {
            filter.update(GAINS, Vec3::zeros(), at_rest(truth), None, DT);
        }
        let up = filter.orientation().inverse() * Vec3::y();
        let expected = truth.inverse() * Vec3::y();
        assert!(
            up.angle(&expected) < TOLERANCE_RAD,
            "{}",
            up.angle(&expected)
        );
    }

    #[test]
    fn a_constant_rate_integrates_to_its_angle() {
        let axis = Vec3::new(1.0, 0.5, -0.3).normalize();
        let mut filter = Mahony::starting_at(tilted());
        let steps = 400;
        for _ in 0..steps {
            filter.update(UNCORRECTED, axis * RATE, Vec3::zeros(), None, DT);
        }
        let turned = tilted().inverse() * filter.orientation();
        let expected = RATE * DT * steps as f32;
        assert!((turned.angle() - expected).abs() < TOLERANCE_RAD);
        let turned_axis = turned.axis().map_or(Vec3::zeros(), |a| a.into_inner());
        assert!(turned_axis.angle(&axis) < TOLERANCE_RAD);
    }

    #[test]
    fn a_turn_about_up_with_gravity_correction_keeps_its_angle() {
        let mut filter = Mahony::from_accel(at_rest(Quat::identity())).unwrap();
        for _ in 0..200 {
            filter.update(
                GAINS,
                Vec3::y() * RATE,
                at_rest(filter.orientation()),
                None,
                DT,
            );
        }
        assert!((filter.orientation().angle() - RATE * DT * 200.0).abs() < TOLERANCE_RAD);
    }

    #[test]
    fn the_still_bias_is_removed() {
        let bias = Vec3::new(0.02, -0.03, 0.01);
        let mut still = StillPeriod::new();
        for k in 0..200 {
            let wobble = if k % 2 == 0 { 0.004 } else { -0.004 };
            let reading = Reading {
                accel: at_rest(tilted()),
                gyro: bias + Vec3::repeat(wobble),
                mag: None,
            };
            assert!(StillPeriod::is_still(&reading));
            still.push(&reading);
        }
        assert!((still.gyro_bias() - bias).norm() < 1e-6);
        let mut filter = still.filter().unwrap();
        let start = filter.orientation();
        for _ in 0..(10.0 / DT) as usize {
            filter.update(
                UNCORRECTED,
                bias - still.gyro_bias(),
                at_rest(tilted()),
                None,
                DT,
            );
        }
        assert!(start.angle_to(&filter.orientation()) < TOLERANCE_RAD);
    }

    #[test]
    fn accel_and_mag_give_the_whole_orientation() {
        let field = Vec3::new(0.0, -41.6, 24.0);
        let truth = tilted();
        let filter = Mahony::from_accel_mag(at_rest(truth), truth.inverse() * field).unwrap();
        assert!(filter.is_magnetic());
        assert!(filter.orientation().angle_to(&truth) < TOLERANCE_RAD);
        let level = Mahony::from_accel(at_rest(truth)).unwrap();
        assert!(!level.is_magnetic());
        let up = level.orientation().inverse() * Vec3::y();
        assert!(up.angle(&(truth.inverse() * Vec3::y())) < TOLERANCE_RAD);
    }

    /// A field of the earth's strength and dip is followed to the filter's heading; one with a
    /// steel club's own field added in the sensor's frame is set aside, and the gyro alone
    /// keeps the heading; after such a field the earth's is followed again only once
    /// [`FIELD_HOLD_S`] have passed.
    #[test]
    fn a_field_that_is_not_the_earths_is_set_aside() {
        let earth = Vec3::new(0.0, -41.6, 24.0);
        let truth = tilted();
        let (accel, field) = (at_rest(truth), truth.inverse() * earth);
        let club = Vec3::new(15.0, 0.0, 0.0);
        // Started 20° off in heading, the earth's field turns the filter to the truth, once
        // the hold after a club's reading has passed.
        let off = Quat::from_axis_angle(&Vec3::y_axis(), 20f32.to_radians());
        let mut filter = Mahony::from_accel_mag(accel, truth.inverse() * (off * earth)).unwrap();
        let start = filter.orientation();
        assert!(filter.update(GAINS, Vec3::zeros(), accel, Some(field + club), DT));
        for _ in 0..((FIELD_HOLD_S - 0.1) / DT) as usize {
            assert!(!filter.update(GAINS, Vec3::zeros(), accel, Some(field * 1.05), DT));
        }
        assert!(filter.orientation().angle_to(&start) < TOLERANCE_RAD);
        for _ in 0..(CONVERGED_S / DT) as usize {
            assert!(!filter.update(GAINS, Vec3::zeros(), accel, Some(field * 1.05), DT));
        }
        assert!(filter.orientation().angle_to(&truth) < 0.01);
        // A club's 15 µT, fixed in the sensor's frame: its heading would be some 20° off.
        let mut filter = Mahony::from_accel_mag(accel, field).unwrap();
        for _ in 0..(CONVERGED_S / DT) as usize {
            assert!(filter.update(GAINS, Vec3::zeros(), accel, Some(field + club), DT));
        }
        assert!(filter.orientation().angle_to(&truth) < TOLERANCE_RAD);
    }

    #[test]
    fn wire_units_convert_to_si() {
        let reading = Reading::from_wire(&ImuSample {
            mag_dut: Some([480, 0, -10]),
            ..sample([0, 1000, -500], [10, 0, -3600])
        })
        .unwrap();
        assert!((reading.accel - Vec3::new(0.0, G, -0.5 * G)).norm() < 1e-5);
        let expected = Vec3::new(1.0, 0.0, -360.0) * core::f32::consts::PI / 180.0;
        assert!((reading.gyro - expected).norm() < 1e-5);
        assert_eq!(reading.mag, Some(Vec3::new(48.0, 0.0, -1.0)));
    }

    #[test]
    fn every_degenerate_input_is_its_error() {
        for axis in 0..3u8 {
            for extreme in [i16::MIN, i16::MAX] {
                let mut v = [0, 1000, 0];
                v[usize::from(axis)] = extreme;
                let accel = Reading::from_wire(&sample(v, [0; 3]));
                assert_eq!(accel, Err(FusionError::SaturatedAccel { axis }));
                let gyro = Reading::from_wire(&sample([0, 1000, 0], v));
                assert_eq!(gyro, Err(FusionError::SaturatedGyro { axis }));
            }
        }
        assert_eq!(
            gravity_up(Vec3::zeros()),
            Err(FusionError::AccelNorm { milli_g: 0 })
        );
        assert_eq!(
            Mahony::from_accel(Vec3::new(0.0, 3.0 * G, 0.0)).map(|_| ()),
            Err(FusionError::AccelNorm { milli_g: 3000 })
        );
        let up = Vec3::new(0.0, G, 0.0);
        for mag in [Vec3::zeros(), Vec3::new(0.0, -50.0, 0.0)] {
            let filter = Mahony::from_accel_mag(up, mag);
            assert_eq!(filter.map(|_| ()), Err(FusionError::MagDirection));
        }
        for (previous_us, t_us) in [(10, 10), (10, 9)] {
            assert_eq!(
                time_step(previous_us, t_us),
                Err(FusionError::TimeNotIncreasing { previous_us, t_us })
            );
        }
        assert_eq!(
            time_step(0, MAX_STEP_US + 1),
            Err(FusionError::TimeStep {
                step_us: MAX_STEP_US + 1,
                max_us: MAX_STEP_US
            })
        );
        assert_eq!(time_step(0, 5_000), Ok(0.005));
        assert_eq!(
            StillPeriod::new().filter().map(|_| ()),
            Err(FusionError::AccelNorm { milli_g: 0 })
        );
    }
}
