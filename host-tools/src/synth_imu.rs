//! Synthetic IMU recordings of a motion, for testing the IMU adapter on real swings.
//!
//! Each frame's segment rotations are what a sensor on each would measure
//! ([`posecoach_adapters::segment`]: the bones' from `kinematics::inverse`, the pelvis's from
//! the hips' line), as the device reads them. At the
//! IMU rate a sensor's orientation is its segment's global rotation, interpolated by slerp
//! between frames, times its mounting. A layout's mountings are on the segments of a body in
//! the format's standard T-pose; the motion's own T-pose (its skeleton's rest) may face any
//! way ([`rest_heading`]), and its straps turn with it; its position is the middle of its bone (the pelvis
//! sensor sits on the pelvis joint), interpolated by a Catmull-Rom spline whose second
//! derivative is the linear acceleration. From these, in the sensor frame:
//!
//! - gyro: the body rate that turns the previous sample's orientation into this one's (what
//!   a filter integrating over the step needs), plus a constant bias and white noise;
//! - accelerometer: `Rᵀ(a − g)` plus white noise;
//! - magnetometer (optional): `Rᵀ B` plus white noise, `B` e.g. [`EARTH_FIELD_UT`], and on
//!   the wrist and hand sensors a steel club's field once it is taken ([`SteelClub`]).
//!
//! Values are rounded to wire units and clamped to the `i16` range, as a saturating sensor
//! would. Sample `k` of every sensor is stamped `k / rate` seconds, in layout order.

use posecoach_adapters::fusion::G;
use posecoach_adapters::segment::Segments;
use posecoach_core::joint::Joint;
use posecoach_core::kinematics::{forward, inverse, swing};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::wire::{ImuSample, SensorLayout, SensorPlacement, MAX_SENSORS};
use posecoach_core::{Quat, Vec3};
use posecoach_io::Motion;
use rand::Rng;
use rand_distr::{Distribution, Normal, UnitSphere};
use std::f32::consts::{PI, TAU};

/// Fastest twist of a bone about itself, rad/s. A forearm pronates at up to about 15 rad/s;
/// the inverse kinematics of a nearly straight arm can flip a twist by half a turn between two
/// frames, which no arm does and which would saturate a gyro.
const MAX_TWIST_RAD_S: f32 = 15.0;

/// An earth field of 48 µT dipping 60° below the horizon, its horizontal part 40° from +Z
/// toward +X (the student need not face magnetic north).
pub const EARTH_FIELD_UT: Vec3 = Vec3::new(15.43, -41.57, 18.38);

/// Imperfections of a synthetic IMU.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuNoise {
    /// Largest constant gyro bias, °/s, drawn per sensor and axis uniformly in ±.
    pub gyro_bias_dps: f32,
    /// Gyro white noise density, °/s/√Hz.
    pub gyro_density_dps: f32,
    /// Accelerometer white noise density, mg/√Hz.
    pub accel_density_mg: f32,
    /// Magnetometer white noise, µT rms per sample.
    pub mag_rms_ut: f32,
    /// Largest angle by which a strap is off its nominal mounting, degrees, about a random axis.
    pub mounting_error_deg: f32,
    /// The gyro's range, °/s: an axis past it is sent saturated (the `i16` extreme), as the
    /// LSM6DS3 driver sends an axis at full scale.
    pub gyro_range_dps: f32,
    /// A steel club near the wrist and hand sensors' magnetometers, where there is one.
    pub steel_club: Option<SteelClub>,
}

/// A steel club in the golfer's hands, as the magnetometers of the sensors on the wrists and
/// hands feel it: its magnetized shaft moves with the hands, so to each of those sensors it
/// is a constant field in the sensor's own frame (a hard-iron offset), in a direction drawn
/// per sensor. The earth's field as the steel bends it (soft iron) is not modelled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteelClub {
    /// The club's field at a sensor, µT.
    pub field_ut: f32,
    /// When the golfer takes the club, seconds from the recording's start (the T-pose is
    /// held without it).
    pub from_s: f32,
}

impl ImuNoise {
    /// A consumer MEMS IMU (BMI270-class gyro and accelerometer, BMM150-class magnetometer)
    /// with a strap up to 10° off its nominal mounting. White noise per sample is the density
    /// times the square root of half the sample rate.
    pub const MEMS: ImuNoise = ImuNoise {
        gyro_bias_dps: 2.0,
        gyro_density_dps: 0.008,
        accel_density_mg: 0.16,
        mag_rms_ut: 0.4,
        mounting_error_deg: 10.0,
        gyro_range_dps: 2000.0,
        steel_club: None,
    };
}

/// Interleaved samples of every sensor in `layout` at `rate_hz` over `motion`, with a
/// magnetometer reading `field` (µT, world frame) where given.
pub fn imu_samples(
    motion: &Motion,
    layout: &SensorLayout,
    rate_hz: f32,
    noise: &ImuNoise,
    field: Option<Vec3>,
    rng: &mut impl Rng,
) -> Vec<ImuSample> {
    let track = Track::new(motion);
    let heading = rest_heading(&motion.skeleton);
    let sensors: Vec<Sensor> = layout
        .sensors
        .iter()
        .filter_map(|p| Sensor::new(p, motion, heading, noise, rng))
        .collect();
    let count = (motion.duration_s() * rate_hz).floor() as usize + 1;
    let white = |density: f32| {
        let sigma = density * (0.5 * rate_hz).sqrt();
        Normal::new(0.0, sigma).unwrap_or_else(|_| unreachable!("{sigma} is a valid deviation"))
    };
    let (gyro_noise, accel_noise) = (white(noise.gyro_density_dps), white(noise.accel_density_mg));
    let mag_noise = Normal::new(0.0, noise.mag_rms_ut)
        .unwrap_or_else(|_| unreachable!("{} is a valid deviation", noise.mag_rms_ut));
    let mut previous: Vec<Option<Quat>> = vec![None; sensors.len()];
    let mut samples = Vec::with_capacity(count * sensors.len());
    for k in 0..count {
        let t = k as f32 / rate_hz;
        for (sensor, previous) in sensors.iter().zip(&mut previous) {
            let orientation = track.rotation(sensor.joint, t) * sensor.mounting;
            let rate = previous.map_or(Vec3::zeros(), |p| {
                (p.inverse() * orientation).scaled_axis() * rate_hz
            });
            *previous = Some(orientation);
            let inverse = orientation.inverse();
            let specific = inverse * (track.acceleration(&sensor.site, t) + Vec3::new(0.0, G, 0.0));
            let mut draw = |d: &Normal<f32>| Vec3::from_fn(|_, _| d.sample(rng));
            let gyro_dps = rate.map(f32::to_degrees) + sensor.bias_dps + draw(&gyro_noise);
            let accel_mg = specific * (1000.0 / G) + draw(&accel_noise);
            let club = noise
                .steel_club
                .filter(|club| t >= club.from_s)
                .map_or(Vec3::zeros(), |_| sensor.club_ut);
            let mag_ut = field.map(|b| inverse * b + club + draw(&mag_noise));
            samples.push(ImuSample {
                sensor: sensor.number,
                t_us: (f64::from(t) * 1e6).round() as u64,
                accel_mg: quantize(accel_mg, 1.0),
                gyro_ddps: clipped(gyro_dps, noise.gyro_range_dps),
                mag_dut: mag_ut.map(|m| quantize(m, 10.0)),
            });
        }
    }
    samples
}

/// `v` (°/s) in tenths as a gyro of `range` sends it: every axis past the range (either way)
/// at the `i16` extreme of its sign.
fn clipped(v: Vec3, range: f32) -> [i16; 3] {
    let mut tenths = quantize(v, 10.0);
    for (t, x) in tenths.iter_mut().zip([v.x, v.y, v.z]) {
        if x.abs() >= range {
            *t = if x > 0.0 { i16::MAX } else { i16::MIN };
        }
    }
    tenths
}

/// `v · scale` rounded and clamped to `i16`.
fn quantize(v: Vec3, scale: f32) -> [i16; 3] {
    [v.x, v.y, v.z].map(|x| {
        (x * scale)
            .round()
            .clamp(f32::from(i16::MIN), f32::from(i16::MAX)) as i16
    })
}

/// One sensor as simulated: where it sits and its own imperfections.
struct Sensor {
    number: u8,
    joint: usize,
    /// Sensor frame to segment frame, the strap's error included.
    mounting: Quat,
    bias_dps: Vec3,
    /// A steel club's field in the sensor's frame once it is taken, µT (zero but on the wrists
    /// and hands).
    club_ut: Vec3,
    /// Positions of the sensor per frame.
    site: Vec<Vec3>,
}

impl Sensor {
    /// `None` where the skeleton lacks the placement's joint. `heading` turns the standard
    /// T-pose to the motion's.
    fn new(
        placement: &SensorPlacement,
        motion: &Motion,
        heading: Quat,
        noise: &ImuNoise,
        rng: &mut impl Rng,
    ) -> Option<Sensor> {
        let skeleton = &motion.skeleton;
        let joint = skeleton.index_of(placement.joint)?;
        let [w, x, y, z] = placement.mounting_q14.map(|c| f32::from(c) / 16384.0);
        let nominal = Quat::new_normalize(nalgebra::Quaternion::new(w, x, y, z));
        let axis = Vec3::from(UnitSphere.sample(rng));
        let angle = rng
            .random_range(0.0..=noise.mounting_error_deg)
            .to_radians();
        let bias = noise.gyro_bias_dps;
        let near_club = matches!(
            placement.joint,
            Joint::LeftWrist | Joint::RightWrist | Joint::LeftHand | Joint::RightHand
        );
        let club_ut = match noise.steel_club {
            Some(club) if near_club => Vec3::from(UnitSphere.sample(rng)) * club.field_ut,
            _ => Vec3::zeros(),
        };
        let site = (0..motion.frames())
            .map(|f| {
                let frame = motion.frame(f);
                match skeleton.parent(joint) {
                    Some(p) => 0.5 * (frame[p] + frame[joint]),
                    None => frame[joint],
                }
            })
            .collect();
        Some(Sensor {
            number: placement.sensor,
            joint,
            mounting: heading * Quat::from_scaled_axis(axis * angle) * nominal,
            bias_dps: Vec3::from_fn(|_, _| rng.random_range(-bias..=bias)),
            club_ut,
            site,
        })
    }
}

/// The turn about the vertical that takes the format's standard T-pose, which faces +Z with
/// the left side at +X, to the facing of `skeleton`'s rest pose: its hips' line, or its
/// shoulders' without hips (the identity with neither).
pub fn rest_heading(skeleton: &Skeleton) -> Quat {
    let mut rest = vec![Vec3::zeros(); skeleton.len()];
    skeleton.rest_positions(&mut rest);
    let line = [
        (Joint::LeftHip, Joint::RightHip),
        (Joint::LeftShoulder, Joint::RightShoulder),
    ]
    .into_iter()
    .find_map(|(l, r)| Some(rest[skeleton.index_of(l)?] - rest[skeleton.index_of(r)?]));
    line.map_or(Quat::identity(), |l| {
        Quat::from_axis_angle(&Vec3::y_axis(), (-l.z).atan2(l.x))
    })
}

/// A motion's frames as segment rotations, sampled at any time.
struct Track {
    rate_hz: f32,
    joints: usize,
    /// Global rotations, frame-major.
    global: Vec<Quat>,
}

impl Track {
    fn new(motion: &Motion) -> Track {
        let skeleton = &motion.skeleton;
        let n = skeleton.len();
        let mut global = vec![Quat::identity(); motion.frames() * n];
        let segments = Segments::new(skeleton, |_| true);
        let max_twist = MAX_TWIST_RAD_S / motion.rate_hz.max(1.0);
        for f in 0..motion.frames() {
            let (done, rest) = global.split_at_mut(f * n);
            let out = &mut rest[..n];
            segments
                .rotations(skeleton, motion.frame(f), out)
                .unwrap_or_else(|e| unreachable!("a motion's frames fit its skeleton: {e}"));
            // Each bone's twist about itself turns at most `MAX_TWIST_RAD_S` from the last
            // frame; its direction is untouched, so positions stay as they are.
            let Some(previous) = done.get(done.len().saturating_sub(n)..).filter(|_| f > 0) else {
                continue;
            };
            for k in 1..n {
                let Some(axis) = skeleton.offset(k).try_normalize(1e-9) else {
                    continue;
                };
                let moved = swing(previous[k] * axis, out[k] * axis) * previous[k];
                let r = moved.inverse() * out[k];
                let twist = 2.0 * r.imag().dot(&axis).atan2(r.w);
                let twist = (twist + PI).rem_euclid(TAU) - PI;
                let limited = twist.clamp(-max_twist, max_twist);
                out[k] =
                    moved * Quat::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), limited);
            }
        }
        Track {
            rate_hz: motion.rate_hz,
            joints: n,
            global,
        }
    }

    /// Frame index and fraction at time `t`, clamped to the motion.
    fn at(&self, t: f32) -> (usize, f32) {
        let frames = self.global.len() / self.joints;
        let u = (t * self.rate_hz).clamp(0.0, frames.saturating_sub(1) as f32);
        let i = (u.floor() as usize).min(frames.saturating_sub(2));
        (i, u - i as f32)
    }

    /// Global rotation of `joint`'s bone at time `t` (slerp between frames).
    fn rotation(&self, joint: usize, t: f32) -> Quat {
        let (i, f) = self.at(t);
        let a = self.global[i * self.joints + joint];
        let b = self.global.get((i + 1) * self.joints + joint).unwrap_or(&a);
        a * Quat::from_scaled_axis((a.inverse() * b).scaled_axis() * f)
    }

    /// Second derivative at time `t` of the Catmull-Rom spline through `site` (one point per
    /// frame), m/s².
    fn acceleration(&self, site: &[Vec3], t: f32) -> Vec3 {
        let (i, f) = self.at(t);
        let p = |k: isize| site[k.clamp(0, site.len() as isize - 1) as usize];
        let i = i as isize;
        let (p0, p1) = (p(i), p(i + 1));
        let (m0, m1) = (0.5 * (p1 - p(i - 1)), 0.5 * (p(i + 2) - p0));
        let second = p0 * (12.0 * f - 6.0)
            + m0 * (6.0 * f - 4.0)
            + p1 * (6.0 - 12.0 * f)
            + m1 * (6.0 * f - 2.0);
        second * (self.rate_hz * self.rate_hz)
    }
}

/// `motion` with a still T-pose of `still_s` seconds and an eased blend of `blend_s` seconds
/// into its first frame put in front, as an IMU session starts.
pub fn with_lead_in(motion: &Motion, still_s: f32, blend_s: f32) -> Motion {
    let skeleton = &motion.skeleton;
    let n = skeleton.len();
    let mut first = vec![Quat::identity(); n];
    let root = inverse(skeleton, motion.frame(0), &mut first)
        .unwrap_or_else(|e| unreachable!("a motion's frames fit its skeleton: {e}"));
    let rest_root = skeleton.offset(0);
    let still = (still_s * motion.rate_hz).round() as usize;
    let blend = (blend_s * motion.rate_hz).round() as usize;
    let mut positions = Vec::with_capacity((still + blend) * n + motion.positions.len());
    let mut local = vec![Quat::identity(); n];
    let mut frame = vec![Vec3::zeros(); n];
    for f in 0..still + blend {
        let x = f.saturating_sub(still) as f32 / blend.max(1) as f32;
        let eased = x * x * (3.0 - 2.0 * x);
        for (l, q) in local.iter_mut().zip(&first) {
            *l = Quat::from_scaled_axis(q.scaled_axis() * eased);
        }
        let at = rest_root + (root - rest_root) * eased;
        forward(skeleton, &local, at, &mut frame)
            .unwrap_or_else(|e| unreachable!("buffers fit the skeleton: {e}"));
        positions.extend_from_slice(&frame);
    }
    positions.extend_from_slice(&motion.positions);
    Motion {
        skeleton: skeleton.clone(),
        names: motion.names.clone(),
        rate_hz: motion.rate_hz,
        missing: vec![false; positions.len()],
        positions,
    }
}

/// Golf sensors: where each goes and how it sits on its segment (roll, pitch, yaw in degrees,
/// nalgebra's Euler convention), as straps usually hold them.
const GOLF_SENSORS: [(Joint, [f32; 3]); 6] = [
    // On the sacrum, facing backward, tilted with the pelvis.
    (Joint::Pelvis, [10.0, 180.0, 0.0]),
    // On the sternum, leaning with the chest.
    (Joint::Thorax, [-15.0, 0.0, 5.0]),
    // On the outside of the upper arms.
    (Joint::LeftElbow, [0.0, 90.0, 20.0]),
    (Joint::RightElbow, [0.0, -90.0, -20.0]),
    // On the back of the wrists.
    (Joint::LeftWrist, [90.0, 0.0, 30.0]),
    (Joint::RightWrist, [90.0, 0.0, -30.0]),
];

// Collecting GOLF_SENSORS into a layout cannot overflow it.
const _: () = assert!(GOLF_SENSORS.len() <= MAX_SENSORS);

/// Which of the golf sensors a right-handed golfer (lead side left) wears.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Worn {
    /// Pelvis, chest, both upper arms and both wrists.
    Six,
    /// Pelvis, chest, the lead upper arm and the lead wrist, as K-Vest's set.
    Four,
    /// The lead wrist alone, as HackMotion's.
    One,
}

impl Worn {
    /// Whether a sensor on `joint` is worn.
    fn wears(self, joint: Joint) -> bool {
        match self {
            Worn::Six => true,
            Worn::Four => !matches!(joint, Joint::RightElbow | Joint::RightWrist),
            Worn::One => joint == Joint::LeftWrist,
        }
    }
}

/// A golf sensor set on the joints `skeleton` has: pelvis, thorax, both upper arms and both
/// forearms, numbered from 0 in that order.
pub fn default_layout(skeleton: &Skeleton) -> SensorLayout {
    layout(skeleton, Worn::Six)
}

/// The golf sensors `worn` on the joints `skeleton` has, numbered from 0 in
/// [`default_layout`]'s order.
pub fn layout(skeleton: &Skeleton, worn: Worn) -> SensorLayout {
    let placed = GOLF_SENSORS
        .iter()
        .filter(|(joint, _)| worn.wears(*joint) && skeleton.index_of(*joint).is_some());
    let sensors = (0u8..)
        .zip(placed)
        .map(|(sensor, &(joint, [roll, pitch, yaw]))| {
            let q =
                Quat::from_euler_angles(roll.to_radians(), pitch.to_radians(), yaw.to_radians());
            SensorPlacement {
                sensor,
                joint,
                mounting_q14: [q.w, q.i, q.j, q.k].map(|c| (c * 16384.0).round() as i16),
            }
        })
        .collect();
    SensorLayout { sensors }
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_adapters::imu::{ImuAdapter, CALIBRATION_S};
    use posecoach_io as io;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use std::path::Path;

    const STILL_S: f32 = 1.5;
    const BLEND_S: f32 = 1.0;
    const OUTPUT_HZ: f32 = 60.0;
    const SEED: u64 = 2024;

    /// The driver swing without its club: the capture lost the club near impact, and the
    /// held samples would twist the lead forearm (whose twist the grip sets) by over 7000 °/s.
    fn driver() -> Motion {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures/golf_driver_60hz.csv");
        let motion = io::load(&path).unwrap();
        let skeleton = &motion.skeleton;
        let body: Vec<usize> = (0..skeleton.len())
            .filter(|&k| skeleton.joint(k).is_some_and(|j| !j.is_club()))
            .collect();
        let mut rest = vec![Vec3::zeros(); skeleton.len()];
        skeleton.rest_positions(&mut rest);
        let joints: Vec<Joint> = body.iter().filter_map(|&k| skeleton.joint(k)).collect();
        let rest: Vec<Vec3> = body.iter().map(|&k| rest[k]).collect();
        let positions: Vec<Vec3> = (0..motion.frames())
            .flat_map(|f| body.iter().map(|&k| motion.frame(f)[k]).collect::<Vec<_>>())
            .collect();
        Motion {
            skeleton: Skeleton::canonical(&joints, &rest).unwrap(),
            names: joints.iter().map(|j| j.name().to_string()).collect(),
            rate_hz: motion.rate_hz,
            missing: vec![false; positions.len()],
            positions,
        }
    }

    /// RMS and largest of some errors.
    fn summary(errors: &[f32]) -> (f32, f32) {
        let rms = (errors.iter().map(|e| e * e).sum::<f32>() / errors.len() as f32).sqrt();
        (rms, errors.iter().copied().fold(0.0, f32::max))
    }

    /// Errors over the swing: per sensed joint the bone-direction error in degrees (the
    /// pelvis: its hips' line's, which its sensor carries), per wrist the position error relative to the root in
    /// centimetres, each as (name, RMS, max).
    fn swing_errors(rate_hz: f32, field: Option<Vec3>) -> Vec<(String, f32, f32)> {
        let swing = driver();
        let motion = with_lead_in(&swing, STILL_S, BLEND_S);
        let skeleton = &motion.skeleton;
        let n = skeleton.len();
        let layout = default_layout(skeleton);
        let mut rng = ChaCha8Rng::seed_from_u64(SEED);
        let samples = imu_samples(&motion, &layout, rate_hz, &ImuNoise::MEMS, field, &mut rng);
        let mut adapter = ImuAdapter::new(&layout, skeleton, OUTPUT_HZ).unwrap();
        let mut frames: Vec<Vec<Vec3>> = Vec::new();
        for sample in &samples {
            adapter
                .push(skeleton, sample, |p, _| frames.push(p.to_vec()))
                .unwrap();
        }
        // Output k (from 0) is one period after calibration plus k periods: a motion frame.
        let first = (CALIBRATION_S * motion.rate_hz).round() as usize + 1;
        let lead = motion.frames() - swing.frames();
        let rest_root = skeleton.offset(0);
        let wrists = [Joint::LeftWrist, Joint::RightWrist].map(|j| skeleton.index_of(j).unwrap());
        let sensed: Vec<usize> = layout
            .sensors
            .iter()
            .map(|p| skeleton.index_of(p.joint).unwrap())
            .collect();
        let mut angles = vec![Vec::new(); sensed.len()];
        let mut distances = vec![Vec::new(); wrists.len()];
        let mut truth_local = vec![Quat::identity(); n];
        let hips = [Joint::LeftHip, Joint::RightHip].map(|j| skeleton.index_of(j).unwrap());
        let line = |p: &[Vec3]| p[hips[0]] - p[hips[1]];
        let mut truth = vec![Vec3::zeros(); n];
        for (k, estimate) in frames.iter().enumerate() {
            let f = first + k;
            if f < lead || f >= motion.frames() {
                continue;
            }
            inverse(skeleton, motion.frame(f), &mut truth_local).unwrap();
            forward(skeleton, &truth_local, rest_root, &mut truth).unwrap();
            for (&j, angles) in sensed.iter().zip(&mut angles) {
                angles.push(
                    match skeleton.parent(j) {
                        Some(p) => (estimate[j] - estimate[p]).angle(&(truth[j] - truth[p])),
                        None => line(estimate).angle(&line(&truth)),
                    }
                    .to_degrees(),
                );
            }
            for (&w, distances) in wrists.iter().zip(&mut distances) {
                let error = (estimate[w] - estimate[0]) - (truth[w] - truth[0]);
                distances.push(100.0 * error.norm());
            }
        }
        assert!(
            angles[0].len() + 2 >= swing.frames(),
            "{} swing frames tracked",
            angles[0].len()
        );
        let name = |j: usize| skeleton.joint(j).map_or("?", |j| j.name()).to_string();
        sensed
            .iter()
            .chain(&wrists)
            .zip(angles.iter().chain(&distances))
            .map(|(&j, errors)| {
                let (rms, max) = summary(errors);
                (name(j), rms, max)
            })
            .collect()
    }

    /// Without magnetometers each heading is fitted to a nominal mounting that the strap
    /// misses by up to 10°, which sets the bound on angles; with them, filter error is left.
    const ANGLE_RMS_DEG: f32 = 8.0;
    const MAGNETIC_ANGLE_RMS_DEG: f32 = 2.0;
    /// Unsensed bones cost about 4 cm: the spine bends evenly between the pelvis and the
    /// chest, not as the capture's does, and the clavicles follow the chest.
    const WRIST_RMS_CM: f32 = 7.0;
    const MAGNETIC_WRIST_RMS_CM: f32 = 5.0;

    fn check(rate_hz: f32, field: Option<Vec3>) {
        let (max_angle_rms, max_wrist_rms_cm) = match field {
            Some(_) => (MAGNETIC_ANGLE_RMS_DEG, MAGNETIC_WRIST_RMS_CM),
            None => (ANGLE_RMS_DEG, WRIST_RMS_CM),
        };
        let errors = swing_errors(rate_hz, field);
        let sensed = errors.len() - 2;
        println!("{rate_hz} Hz, magnetometer: {}", field.is_some());
        for (k, (name, rms, max)) in errors.iter().enumerate() {
            let unit = if k < sensed {
                "deg"
            } else {
                "cm (wrist position)"
            };
            println!("  {name:>12}: RMS {rms:5.2}, max {max:5.2} {unit}");
        }
        for (k, (name, rms, _)) in errors.iter().enumerate() {
            let bound = if k < sensed {
                max_angle_rms
            } else {
                max_wrist_rms_cm
            };
            assert!(rms < &bound, "{name}: RMS {rms} over {bound}");
        }
    }

    #[test]
    fn a_gyro_past_its_range_is_sent_saturated() {
        assert_eq!(
            clipped(Vec3::new(2500.0, -1999.04, -2000.0), 2000.0),
            [i16::MAX, -19990, i16::MIN]
        );
        assert_eq!(clipped(Vec3::new(0.04, 1.0, -3.0), 2000.0), [0, 10, -30]);
    }

    #[test]
    fn tracks_the_driver_swing_at_200_hz() {
        check(200.0, None);
    }

    #[test]
    fn tracks_the_driver_swing_at_200_hz_with_magnetometers() {
        check(200.0, Some(EARTH_FIELD_UT));
    }

    #[test]
    fn tracks_the_driver_swing_at_1000_hz() {
        check(1000.0, None);
        check(1000.0, Some(EARTH_FIELD_UT));
    }
}
