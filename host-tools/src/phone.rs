//! What a phone's monocular 3D pose estimator makes of a motion: pose frames at the camera's
//! rate, with the errors such estimators really have.
//!
//! Each keypoint's error is the sum of
//!
//! - **white jitter**, fresh every frame;
//! - **drift**: an Ornstein–Uhlenbeck process per keypoint and axis whose correlation time is
//!   drawn per keypoint from [`DRIFT_S`], so the error wanders over a fraction of a second as a
//!   monocular estimator's does;
//! - a constant **bias** per keypoint;
//! - **occlusion**: runs ([`OCCLUSION_RUN_S`] long on average) in which a keypoint is sent with a
//!   low confidence and [`OCCLUDED_MM`] of extra error, or with confidence 0 (lost).
//!
//! White jitter, drift and bias are [`DEPTH_FACTOR`] times as large along the camera's depth
//! axis as across the image; each is given as its 3D RMS. The capture times jitter by up to
//! `jitter_ms` and a share `drop` of the frames never arrive.

use posecoach_core::format::Format;
use posecoach_core::wire::PoseFrame;
use posecoach_core::Vec3;
use rand::Rng;
use rand_distr::{Distribution, Normal};

/// Error along the camera's depth axis over that across the image.
pub const DEPTH_FACTOR: f32 = 2.0;
/// Range of the drift's correlation time, seconds (drawn per keypoint).
pub const DRIFT_S: (f32, f32) = (0.2, 1.0);
/// Mean length of an occlusion run, seconds.
pub const OCCLUSION_RUN_S: f32 = 0.3;
/// Extra error of an occluded keypoint, mm (3D RMS).
pub const OCCLUDED_MM: f32 = 70.0;

/// The estimator's errors, 3D RMS in millimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhoneNoise {
    /// Fresh every frame.
    pub white_mm: f32,
    /// Correlated over [`DRIFT_S`].
    pub drift_mm: f32,
    /// Constant per keypoint.
    pub bias_mm: f32,
    /// Share of the time a keypoint is occluded (in runs).
    pub occluded: f64,
    /// Share of occlusion runs in which the keypoint is lost (confidence 0).
    pub lost: f64,
    /// Capture-time jitter, ms (uniform, plus or minus).
    pub jitter_ms: f32,
    /// Share of frames that never arrive.
    pub drop: f64,
}

impl PhoneNoise {
    /// The errors of a level of `mm`: drift of `mm`, white jitter and bias of a third of it,
    /// 2 % of the time occluded (a fifth of it lost), 4 ms capture jitter, 3 % of frames lost.
    pub fn level(mm: f32) -> PhoneNoise {
        PhoneNoise {
            white_mm: mm / 3.0,
            drift_mm: mm,
            bias_mm: mm / 3.0,
            occluded: 0.02,
            lost: 0.2,
            jitter_ms: 4.0,
            drop: 0.03,
        }
    }
}

/// A phone on a tripod: `depth` is the horizontal direction it looks along.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Pose frames per second.
    pub rate_hz: f32,
    /// Unit vector along the camera's depth axis.
    pub depth: Vec3,
}

/// One keypoint's error state.
struct Keypoint {
    bias: Vec3,
    drift: Vec3,
    tau_s: f32,
    occluded: bool,
    lost: bool,
}

/// An error of 3D RMS `rms` with the depth axis [`DEPTH_FACTOR`] times the others.
fn anisotropic(rms: f32, camera: &Camera, rng: &mut impl Rng) -> Vec3 {
    let sigma = rms / (2.0 + DEPTH_FACTOR * DEPTH_FACTOR).sqrt();
    let Ok(normal) = Normal::new(0.0, sigma.max(f32::MIN_POSITIVE)) else {
        return Vec3::zeros();
    };
    let across = Vec3::y().cross(&camera.depth);
    across * normal.sample(rng)
        + Vec3::y() * normal.sample(rng)
        + camera.depth * (DEPTH_FACTOR * normal.sample(rng))
}

/// The pose frames a phone sends while `at(t, k)` (joint `k` of the motion at `t` seconds,
/// metres) lasts `duration_s`: keypoint `i` of `format` is joint `keypoint_joints[i]`. Frame
/// numbers and capture times start at 0.
pub fn record(
    at: impl Fn(f64, usize) -> Vec3,
    duration_s: f64,
    format: Format,
    keypoint_joints: &[usize],
    camera: &Camera,
    noise: &PhoneNoise,
    rng: &mut impl Rng,
) -> Vec<PoseFrame> {
    let mut keypoints: Vec<Keypoint> = keypoint_joints
        .iter()
        .map(|_| Keypoint {
            bias: anisotropic(noise.bias_mm, camera, rng),
            drift: anisotropic(noise.drift_mm, camera, rng),
            tau_s: rng.random_range(DRIFT_S.0..=DRIFT_S.1),
            occluded: false,
            lost: false,
        })
        .collect();
    let dt = 1.0 / camera.rate_hz;
    // Two-state runs: enter with this chance per frame, leave with `exit`.
    let exit = f64::from((dt / OCCLUSION_RUN_S).min(1.0));
    let enter = if noise.occluded < 1.0 {
        exit * noise.occluded / (1.0 - noise.occluded)
    } else {
        1.0
    };
    let frames = (duration_s * f64::from(camera.rate_hz)) as u32;
    let mut sent = Vec::new();
    for seq in 0..frames {
        let jitter = f64::from(noise.jitter_ms) * 1e-3 * rng.random_range(-1.0..=1.0);
        let t = (f64::from(seq) / f64::from(camera.rate_hz) + jitter).max(0.0);
        let mut joints_mm = heapless::Vec::new();
        let mut confidence = heapless::Vec::new();
        for (kp, &k) in keypoints.iter_mut().zip(keypoint_joints) {
            let keep = (-dt / kp.tau_s).exp();
            kp.drift = kp.drift * keep
                + anisotropic(noise.drift_mm, camera, rng) * (1.0 - keep * keep).sqrt();
            if kp.occluded {
                kp.occluded = !rng.random_bool(exit);
            } else if rng.random_bool(enter.min(1.0)) {
                kp.occluded = true;
                kp.lost = rng.random_bool(noise.lost);
            }
            let mut error_mm = kp.bias + kp.drift + anisotropic(noise.white_mm, camera, rng);
            if kp.occluded {
                error_mm += anisotropic(OCCLUDED_MM, camera, rng);
            }
            let p = at(t, k) + error_mm * 1e-3;
            let _ = joints_mm.push(to_mm(p));
            let _ = confidence.push(match (kp.occluded, kp.lost) {
                (false, _) => rng.random_range(180..=255),
                (true, false) => rng.random_range(20..60),
                (true, true) => 0,
            });
        }
        if rng.random_bool(noise.drop) {
            continue;
        }
        sent.push(PoseFrame {
            seq,
            t_us: (t * 1e6).round() as u64,
            format,
            joints_mm,
            confidence,
        });
    }
    sent
}

/// `p` (metres) in whole millimetres, clamped to the wire's range.
pub fn to_mm(p: Vec3) -> [i16; 3] {
    [p.x, p.y, p.z].map(|v| (v * 1000.0).round().clamp(-32767.0, 32767.0) as i16)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn errors(noise: &PhoneNoise, camera: &Camera) -> Vec<(Vec3, u8)> {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let keypoints: Vec<usize> = (0..17).collect();
        record(
            |_, _| Vec3::zeros(),
            60.0,
            Format::H36m17,
            &keypoints,
            camera,
            noise,
            &mut rng,
        )
        .iter()
        .flat_map(|f| {
            f.joints_mm
                .iter()
                .zip(&f.confidence)
                .map(|(p, &c)| (Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32), c))
                .collect::<Vec<_>>()
        })
        .collect()
    }

    #[test]
    fn errors_have_the_stated_size_and_the_depth_axis_is_worst() {
        let camera = Camera {
            rate_hz: 30.0,
            depth: Vec3::z(),
        };
        let noise = PhoneNoise {
            occluded: 0.0,
            ..PhoneNoise::level(30.0)
        };
        let e = errors(&noise, &camera);
        let rms = |axis: usize| {
            (e.iter().map(|(p, _)| p[axis] * p[axis]).sum::<f32>() / e.len() as f32).sqrt()
        };
        let total = (rms(0).powi(2) + rms(1).powi(2) + rms(2).powi(2)).sqrt();
        // Drift 30, white 10, bias 10: sqrt(900 + 100 + 100) = 33 mm; 17 biases are few draws.
        assert!((25.0..42.0).contains(&total), "{total}");
        assert!(
            rms(2) > 1.5 * rms(0) && rms(2) > 1.5 * rms(1),
            "{e:?}",
            e = [rms(0), rms(1), rms(2)]
        );
    }

    #[test]
    fn drift_is_correlated_over_a_fraction_of_a_second() {
        let camera = Camera {
            rate_hz: 60.0,
            depth: Vec3::x(),
        };
        let noise = PhoneNoise {
            white_mm: 0.0,
            bias_mm: 0.0,
            occluded: 0.0,
            ..PhoneNoise::level(30.0)
        };
        let e = errors(&noise, &camera);
        // Keypoint 0's error one frame apart is nearly the same; a second apart, far less so.
        let series: Vec<f32> = e.iter().step_by(17).map(|(p, _)| p.x).collect();
        let corr = |lag: usize| {
            let n = series.len() - lag;
            let (a, b) = (&series[..n], &series[lag..]);
            let dot: f32 = a.iter().zip(b).map(|(x, y)| x * y).sum();
            dot / (a.iter().map(|x| x * x).sum::<f32>() * b.iter().map(|x| x * x).sum::<f32>())
                .sqrt()
        };
        assert!(corr(1) > 0.9, "{}", corr(1));
        assert!(corr(120) < 0.5, "{}", corr(120));
    }

    #[test]
    fn occlusion_comes_in_runs_of_low_confidence() {
        let camera = Camera {
            rate_hz: 30.0,
            depth: Vec3::z(),
        };
        let noise = PhoneNoise {
            occluded: 0.1,
            ..PhoneNoise::level(0.0)
        };
        let e = errors(&noise, &camera);
        let low = e.iter().filter(|(_, c)| *c < 77).count() as f64 / e.len() as f64;
        assert!((0.05..0.15).contains(&low), "{low}");
        let lost = e.iter().filter(|(_, c)| *c == 0).count() as f64 / e.len() as f64;
        assert!(lost > 0.0 && lost < low, "{lost}");
        // Runs: a low keypoint is mostly followed by a low one (keypoint 0's series).
        let series: Vec<bool> = e.iter().step_by(17).map(|(_, c)| *c < 77).collect();
        let stays = series.windows(2).filter(|w| w[0] && w[1]).count() as f64
            / series.iter().filter(|&&l| l).count().max(1) as f64;
        assert!(stays > 0.7, "{stays}");
    }
}
