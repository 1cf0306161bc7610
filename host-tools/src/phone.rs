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
//!
//! Beyond noise, the estimator fails as real ones do (swaps as users of MediaPipe and Sports2D
//! report them, flips as in MediaPipe issue #3500, the lean as in #2918):
//!
//! - **left/right swaps** of whole frames, in runs ([`SWAP_RUN_S`] long on average): every left
//!   keypoint is sent as its right counterpart ([`Format::mirror_keypoint`]) and back, with its
//!   confidence. The positions are where the image shows them; only the names are exchanged,
//!   so the pose sent is the body's mirror image.
//! - **front/back flips** of the whole body, in runs ([`FLIP_RUN_S`]): the estimator takes the
//!   golfer's back for their front. A monocular estimator reads each keypoint's two image
//!   coordinates from the picture, which a flip does not change; it infers depth from what it
//!   believes the body is doing, so the depth order reverses (the nearer shoulder becomes the
//!   farther, a hand reaching toward the camera reaches away), and as it believes it sees the
//!   golfer from the other side, the keypoint on the image's one side is named the other
//!   side's. It sends the pose mirrored through the vertical plane across the camera's depth
//!   axis through the body's centre (each keypoint's depth reversed about the keypoints' mean
//!   depth), with left and right exchanged: a body again (a mirror image renamed), turned to
//!   face away, that projects onto the same image. A swap alone gives the mirror image.
//! - a **depth bias that grows with height**: every keypoint moved along the depth axis by
//!   `lean_mm_per_m` for each metre it lies above the lowest keypoint (the feet), toward or
//!   away from the camera (drawn per recording): the body seen leaning.
//!
//! The failures are drawn after the noise, so a recording with them has the same noise as one
//! without.

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
/// Mean length of a run of left/right swapped frames, seconds: 3 frames at 30 Hz.
pub const SWAP_RUN_S: f32 = 0.1;
/// Mean length of a run of front/back flipped frames, seconds.
pub const FLIP_RUN_S: f32 = 0.2;

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
    /// Runs of left/right swapped frames starting per second ([`SWAP_RUN_S`] long on average).
    pub swaps_per_s: f32,
    /// Runs of front/back flipped frames starting per second ([`FLIP_RUN_S`] on average).
    pub flips_per_s: f32,
    /// Depth bias per metre of height above the feet, mm.
    pub lean_mm_per_m: f32,
}

impl PhoneNoise {
    /// The errors of a level of `mm`: drift of `mm`, white jitter and bias of a third of it,
    /// 2 % of the time occluded (a fifth of it lost), 4 ms capture jitter, 3 % of frames lost;
    /// and at every level the failures: a run of left/right swaps a second (10 % of the
    /// frames; about two in a swing from address to finish), a flip every five seconds (4 % of
    /// the frames), and a lean of 30 mm per metre of height (5 cm at the head: 1.7°).
    pub fn level(mm: f32) -> PhoneNoise {
        PhoneNoise {
            white_mm: mm / 3.0,
            drift_mm: mm,
            bias_mm: mm / 3.0,
            occluded: 0.02,
            lost: 0.2,
            jitter_ms: 4.0,
            drop: 0.03,
            swaps_per_s: 1.0,
            flips_per_s: 0.2,
            lean_mm_per_m: 30.0,
        }
    }

    /// These errors without the estimator's failures (swaps, flips, lean): noise, occlusion,
    /// jitter and losses only.
    pub fn without_failures(self) -> PhoneNoise {
        PhoneNoise {
            swaps_per_s: 0.0,
            flips_per_s: 0.0,
            lean_mm_per_m: 0.0,
            ..self
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
    let frames = record_failing(at, duration_s, format, keypoint_joints, camera, noise, rng);
    frames.into_iter().map(|(frame, _)| frame).collect()
}

/// [`record`], each frame with the failure it was sent with.
pub fn record_failing(
    at: impl Fn(f64, usize) -> Vec3,
    duration_s: f64,
    format: Format,
    keypoint_joints: &[usize],
    camera: &Camera,
    noise: &PhoneNoise,
    rng: &mut impl Rng,
) -> Vec<(PoseFrame, Failure)> {
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
        let mut frame = Sent {
            seq,
            t,
            positions: Vec::with_capacity(keypoints.len()),
            confidence: Vec::with_capacity(keypoints.len()),
        };
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
            frame.positions.push(at(t, k) + error_mm * 1e-3);
            frame.confidence.push(match (kp.occluded, kp.lost) {
                (false, _) => rng.random_range(180..=255),
                (true, false) => rng.random_range(20..60),
                (true, true) => 0,
            });
        }
        if rng.random_bool(noise.drop) {
            continue;
        }
        sent.push(frame);
    }
    let failures = fail(&mut sent, &at, format, keypoint_joints, camera, noise, rng);
    sent.into_iter()
        .zip(failures)
        .map(|(f, failure)| {
            let (mut joints_mm, mut confidence) = (heapless::Vec::new(), heapless::Vec::new());
            for (&p, &c) in f.positions.iter().zip(&f.confidence) {
                let _ = joints_mm.push(to_mm(p));
                let _ = confidence.push(c);
            }
            let frame = PoseFrame {
                seq: f.seq,
                t_us: (f.t * 1e6).round() as u64,
                format,
                joints_mm,
                confidence,
            };
            (frame, failure)
        })
        .collect()
}

/// A frame on its way out: capture time (s), keypoints (metres) and confidences.
struct Sent {
    seq: u32,
    t: f64,
    positions: Vec<Vec3>,
    confidence: Vec<u8>,
}

/// What the estimator got wrong in a frame, beyond noise and the lean.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failure {
    /// Nothing.
    None,
    /// Left and right swapped.
    Swap,
    /// Front and back flipped: left and right swapped, the depth mirrored.
    Flip,
}

/// For each of `frames` captured frames at `rate_hz`, its failure: runs of swaps and flips
/// starting at their rates per second, each frame leaving a run with the chance of one frame
/// in its mean length (a flip wins over a swap where both run). No draw where both rates are 0.
fn failure_runs(frames: u32, rate_hz: f32, noise: &PhoneNoise, rng: &mut impl Rng) -> Vec<Failure> {
    let dt = f64::from(1.0 / rate_hz);
    let run = |per_s: f32, run_s: f32| {
        let enter = (f64::from(per_s) * dt).min(1.0);
        let exit = (dt / f64::from(run_s)).min(1.0);
        (enter, exit)
    };
    let (swap, flip) = (
        run(noise.swaps_per_s, SWAP_RUN_S),
        run(noise.flips_per_s, FLIP_RUN_S),
    );
    let (mut swapping, mut flipping) = (false, false);
    let mut runs = Vec::with_capacity(frames as usize);
    for _ in 0..frames {
        for (on, (enter, exit)) in [(&mut swapping, swap), (&mut flipping, flip)] {
            if enter > 0.0 {
                *on = if *on {
                    !rng.random_bool(exit)
                } else {
                    rng.random_bool(enter)
                };
            }
        }
        runs.push(match (swapping, flipping) {
            (_, true) => Failure::Flip,
            (true, false) => Failure::Swap,
            (false, false) => Failure::None,
        });
    }
    runs
}

/// The estimator's failures put into `sent`: the lean, then the swaps and flips; each frame's
/// failure.
fn fail(
    sent: &mut [Sent],
    at: &impl Fn(f64, usize) -> Vec3,
    format: Format,
    keypoint_joints: &[usize],
    camera: &Camera,
    noise: &PhoneNoise,
    rng: &mut impl Rng,
) -> Vec<Failure> {
    if noise.lean_mm_per_m != 0.0 {
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let lean = sign * noise.lean_mm_per_m * 1e-3;
        for frame in sent.iter_mut() {
            let heights: Vec<f32> = keypoint_joints.iter().map(|&k| at(frame.t, k).y).collect();
            let feet = heights.iter().copied().fold(f32::INFINITY, f32::min);
            for (p, h) in frame.positions.iter_mut().zip(&heights) {
                *p += camera.depth * (lean * (h - feet));
            }
        }
    }
    if noise.swaps_per_s <= 0.0 && noise.flips_per_s <= 0.0 {
        return vec![Failure::None; sent.len()];
    }
    let frames = sent.last().map_or(0, |f| f.seq + 1);
    let runs = failure_runs(frames, camera.rate_hz, noise, rng);
    let mirror: Vec<usize> = (0..keypoint_joints.len())
        .map(|i| format.mirror_keypoint(i))
        .collect();
    for frame in sent.iter_mut() {
        let failure = runs[frame.seq as usize];
        if failure == Failure::None {
            continue;
        }
        let (positions, confidence) = (frame.positions.clone(), frame.confidence.clone());
        let centre = positions.iter().map(|p| p.dot(&camera.depth)).sum::<f32>()
            / positions.len().max(1) as f32;
        for (i, &m) in mirror.iter().enumerate() {
            let p = positions[m];
            frame.positions[i] = match failure {
                // Depth reversed about the keypoints' mean depth.
                Failure::Flip => p - camera.depth * (2.0 * (p.dot(&camera.depth) - centre)),
                _ => p,
            };
            frame.confidence[i] = confidence[m];
        }
    }
    sent.iter().map(|f| runs[f.seq as usize]).collect()
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
            ..PhoneNoise::level(30.0).without_failures()
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
            ..PhoneNoise::level(30.0).without_failures()
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
            ..PhoneNoise::level(0.0).without_failures()
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

    /// A still H36M-17 pose of 1.75 m, no two keypoints alike (each moved `k` cm toward the
    /// camera), filmed at 30 Hz along Z for `seconds` with only the failures of `noise`:
    /// each frame's keypoints and failure.
    fn failing(noise: &PhoneNoise, seconds: f64) -> (Vec<Vec3>, Vec<(Vec<Vec3>, Failure)>) {
        let pose: Vec<Vec3> = Format::H36m17
            .joints()
            .iter()
            .enumerate()
            .map(|(k, j)| j.place.position() + Vec3::z() * (0.01 * k as f32))
            .collect();
        let camera = Camera {
            rate_hz: 30.0,
            depth: Vec3::z(),
        };
        let still = PhoneNoise {
            white_mm: 0.0,
            drift_mm: 0.0,
            bias_mm: 0.0,
            occluded: 0.0,
            jitter_ms: 0.0,
            drop: 0.0,
            ..*noise
        };
        let keypoints: Vec<usize> = (0..17).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let frames = record_failing(
            |_, k| pose[k],
            seconds,
            Format::H36m17,
            &keypoints,
            &camera,
            &still,
            &mut rng,
        );
        let read = frames
            .into_iter()
            .map(|(f, failure)| {
                let p = f
                    .joints_mm
                    .iter()
                    .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * 1e-3);
                (p.collect(), failure)
            })
            .collect();
        (pose, read)
    }

    /// The share of `failure`'s frames and its mean run length in frames.
    fn runs(frames: &[(Vec<Vec3>, Failure)], failure: Failure) -> (f64, f64) {
        let on: Vec<bool> = frames.iter().map(|(_, f)| *f == failure).collect();
        let starts = on.windows(2).filter(|w| !w[0] && w[1]).count().max(1);
        let n = on.iter().filter(|&&o| o).count();
        (n as f64 / on.len() as f64, n as f64 / starts as f64)
    }

    #[test]
    fn swaps_come_in_short_runs_at_their_rate_and_exchange_every_left_keypoint_for_its_right() {
        let noise = PhoneNoise {
            flips_per_s: 0.0,
            lean_mm_per_m: 0.0,
            ..PhoneNoise::level(0.0)
        };
        let (pose, frames) = failing(&noise, 600.0);
        // A run a second, 0.1 s (3 frames) long: 0.1 / 1.1 of the frames.
        let (share, run) = runs(&frames, Failure::Swap);
        assert!((0.08..0.10).contains(&share), "{share}");
        assert!((2.7..3.3).contains(&run), "{run}");
        for (keypoints, failure) in &frames {
            for (i, p) in keypoints.iter().enumerate() {
                let truth = match failure {
                    Failure::Swap => pose[Format::H36m17.mirror_keypoint(i)],
                    _ => pose[i],
                };
                assert!((p - truth).norm() < 1e-3, "{failure:?} {i}");
            }
        }
    }

    #[test]
    fn flips_are_rarer_and_mirror_the_depths_about_their_mean_with_left_and_right_exchanged() {
        let noise = PhoneNoise {
            swaps_per_s: 0.0,
            lean_mm_per_m: 0.0,
            ..PhoneNoise::level(0.0)
        };
        let (pose, frames) = failing(&noise, 1800.0);
        // A run every five seconds, 0.2 s (6 frames) long: 0.04 / 1.04 of the frames.
        let (share, run) = runs(&frames, Failure::Flip);
        assert!((0.032..0.045).contains(&share), "{share}");
        assert!((5.2..6.8).contains(&run), "{run}");
        let centre = pose.iter().map(|p| p.z).sum::<f32>() / 17.0;
        for (keypoints, failure) in frames.iter().filter(|(_, f)| *f == Failure::Flip) {
            for (i, p) in keypoints.iter().enumerate() {
                let m = pose[Format::H36m17.mirror_keypoint(i)];
                // Where the image shows the counterpart, its depth reversed about the mean.
                let truth = Vec3::new(m.x, m.y, 2.0 * centre - m.z);
                assert!((p - truth).norm() < 1e-3, "{failure:?} {i}");
            }
        }
    }

    #[test]
    fn the_lean_moves_each_keypoint_along_the_depth_axis_by_its_height_above_the_feet() {
        let noise = PhoneNoise {
            swaps_per_s: 0.0,
            flips_per_s: 0.0,
            ..PhoneNoise::level(0.0)
        };
        let (pose, frames) = failing(&noise, 10.0);
        let feet = pose.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        // 30 mm per metre, toward or away from the camera, the same all recording.
        let lean = (frames[0].0[10].z - pose[10].z) / (pose[10].y - feet);
        assert!((lean.abs() - 0.03).abs() < 1e-3, "{lean}");
        for (keypoints, _) in &frames {
            for (p, q) in keypoints.iter().zip(&pose) {
                let truth = q + Vec3::z() * (lean * (q.y - feet));
                assert!((p - truth).norm() < 1.5e-3, "{p:?} {truth:?}");
            }
        }
    }
}
