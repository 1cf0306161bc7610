//! `posecoach synth-log`: a realistic recorded session made from swing files.
//!
//! The student's session is laid out at [`TIMELINE_HZ`] on the student's body: a still T-pose
//! (IMU calibration), optional walking up to the ball, then per swing a set-up, a waggle, the
//! swing, a return to the set-up and, between swings, a practice half swing. It is then
//! recorded the way a phone's pose estimator sends it (pose frames at `--rate` with capture
//! jitter, keypoint noise, unsure keypoints and lost frames) or, with `--imu-rate`, as body-worn
//! IMUs send it (a `SensorLayout`, then samples from the segments' motion with bias, noise and
//! misplaced straps), behind the `StudentProfile`, `Config` and `CoachSelect` messages, as a
//! `.pclog`. A sidecar `NAME.swings.json` lists the
//! swings and their events (from the clean motion) in seconds of the recording; as the golfer
//! stands still at address from `still_from_s`, an address found anywhere after that is right.

use crate::synth_imu::{self, ImuNoise};
use anyhow::{bail, Context, Result};
use posecoach_adapters::log;
use posecoach_core::dtw::Band;
use posecoach_core::events::{self, SwingKind};
use posecoach_core::format::{Format, Source};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::wire::{self, Config, Message, PoseFrame, StudentProfile, MAX_FRAME};
use posecoach_core::Vec3;
use posecoach_io::{self as io, csv, Motion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde_json::{json, Map, Value};
use std::f32::consts::{PI, TAU};
use std::path::{Path, PathBuf};

/// Rate the session is laid out at, Hz.
pub const TIMELINE_HZ: f32 = 60.0;
/// Share of keypoints a pose estimator loses to occlusion in a frame.
const OCCLUDED: f64 = 0.01;
/// Extra error of an occluded keypoint, mm (one sigma per axis).
const OCCLUDED_MM: f32 = 40.0;

#[derive(clap::Args)]
pub struct Args {
    /// A swing the student makes (.bvh, .c3d or .csv); repeat for several, in order.
    #[arg(long = "swing", required = true)]
    swings: Vec<PathBuf>,
    /// The student's T-pose (default: the bundled 1.75 m H3.6M T-pose).
    #[arg(long)]
    student_tpose: Option<PathBuf>,
    /// Keypoint format of the profile and pose frames: one whose keypoints are all joints
    /// (h36m17, cmu31, bandai22, smpl24).
    #[arg(long, default_value = "h36m17")]
    format: String,
    /// Walking to insert before the first set-up and between swings (.bvh, .c3d or .csv).
    #[arg(long)]
    walk: Option<PathBuf>,
    /// Stretch every swing's backswing by this factor (an amateur's takes 1.3 to 3 times as
    /// long as a pro's; under 1 speeds it up).
    #[arg(long, default_value_t = 1.0)]
    backswing_tempo: f32,
    /// Pose frames per second.
    #[arg(long, default_value_t = 30.0)]
    rate: f32,
    /// Keypoint noise, mm (RMS 3D error per keypoint).
    #[arg(long, default_value_t = 7.0)]
    noise_mm: f32,
    /// Capture-time jitter, ms (uniform, plus or minus).
    #[arg(long, default_value_t = 4.0)]
    jitter_ms: f32,
    /// Record IMUs at this rate (200 to 1000 Hz) instead of pose frames: sensors on the
    /// pelvis, chest, upper arms and wrists, with bias, noise and misplaced straps.
    #[arg(long)]
    imu_rate: Option<f32>,
    /// IMUs without magnetometers.
    #[arg(long)]
    no_mag: bool,
    /// Share of frames (or IMU samples) lost before they reach the device.
    #[arg(long, default_value_t = 0.03)]
    drop: f64,
    /// Model rate the recording asks the device for (its `Config`).
    #[arg(long, default_value_t = 60)]
    model_rate: u16,
    /// Coach reference the recording selects.
    #[arg(long, default_value_t = 0)]
    coach: u16,
    /// Seed of the noise, jitter and losses.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Where to write the log; the sidecar goes beside it.
    #[arg(long)]
    out: PathBuf,
    /// Print one JSON object instead of text: the paths, the size, the pose frames or IMU
    /// samples sent, and the sidecar's content.
    #[arg(long)]
    json: bool,
}

/// A session being laid out on the student's body.
struct Timeline {
    joints: usize,
    positions: Vec<Vec3>,
}

impl Timeline {
    fn frames(&self) -> usize {
        self.positions.len() / self.joints
    }

    fn last(&self) -> Vec<Vec3> {
        self.positions[self.positions.len() - self.joints..].to_vec()
    }

    fn hold(&mut self, pose: &[Vec3], seconds: f32) {
        for _ in 0..(seconds * TIMELINE_HZ) as usize {
            self.positions.extend_from_slice(pose);
        }
    }

    /// Eases from the last frame to `to` over `seconds`.
    fn blend(&mut self, to: &[Vec3], seconds: f32) {
        let from = self.last();
        let frames = (seconds * TIMELINE_HZ) as usize;
        for f in 1..=frames {
            let w = 0.5 * (1.0 - (PI * f as f32 / frames as f32).cos());
            self.positions
                .extend(from.iter().zip(to).map(|(a, b)| a + (b - a) * w));
        }
    }

    /// Everything above the hips sways `amplitude` m along X and back, twice.
    fn waggle(&mut self, address: &[Vec3], amplitude: f32) {
        let hips = address[0].y;
        let frames = TIMELINE_HZ as usize;
        for f in 0..frames {
            let offset = amplitude * (2.0 * TAU * f as f32 / frames as f32).sin();
            self.positions.extend(
                address
                    .iter()
                    .map(|p| p - Vec3::x() * offset * (p.y - hips).max(0.0)),
            );
        }
    }

    /// Position of joint `k` at `t` seconds, linear between frames.
    fn at(&self, t: f64, k: usize) -> Vec3 {
        let x = (t * f64::from(TIMELINE_HZ)).max(0.0);
        let last = self.frames() - 1;
        let i = (x.floor() as usize).min(last);
        let j = (i + 1).min(last);
        let w = (x - i as f64).min(1.0) as f32;
        let (a, b) = (
            self.positions[i * self.joints + k],
            self.positions[j * self.joints + k],
        );
        a + (b - a) * w
    }
}

pub fn run(args: &Args) -> Result<String> {
    if args
        .imu_rate
        .is_some_and(|r| !(200.0..=1000.0).contains(&r))
    {
        bail!("--imu-rate must be between 200 and 1000 Hz");
    }
    if !(10.0..=120.0).contains(&args.rate) {
        bail!(
            "--rate {} must be between 10 and 120 frames per second",
            args.rate
        );
    }
    if !(0.5..=3.0).contains(&args.backswing_tempo) {
        bail!(
            "--backswing-tempo {} must be between 0.5 and 3",
            args.backswing_tempo
        );
    }
    if !(0.0..=0.5).contains(&args.drop) {
        bail!("--drop {} must be between 0 and 0.5", args.drop);
    }
    if !(0.0..=50.0).contains(&args.noise_mm)
        || !(0.0..1000.0 / (2.0 * args.rate)).contains(&args.jitter_ms)
    {
        bail!("--noise-mm must be 0 to 50, and --jitter-ms under half a frame");
    }
    let body = match &args.student_tpose {
        Some(path) => io::load(path)?,
        None => csv::read(include_str!("../../tests/fixtures/h36m17_tpose.csv"))
            .context("bundled T-pose")?,
    };
    let Some(format) = Format::from_name(&args.format) else {
        bail!("unknown format `{}`", args.format);
    };
    let keypoint_joints = keypoint_sources(format, &body.skeleton)?;
    let onto_body = |path: &Path| -> Result<Motion> {
        let motion = io::load(path)?.retarget_analytic(&body).map_err(|(f, e)| {
            anyhow::anyhow!("{} frame {f} onto the student: {e}", path.display())
        })?;
        Ok(motion.resampled(TIMELINE_HZ))
    };
    let swings: Vec<(PathBuf, Motion)> = args
        .swings
        .iter()
        .map(|p| {
            let swing = onto_body(p)?;
            let top = events::detect(&swing.skeleton, &swing.positions, TIMELINE_HZ)
                .with_context(|| format!("events of {}", p.display()))?
                .top();
            Ok((p.clone(), stretch(&swing, top, args.backswing_tempo)))
        })
        .collect::<Result<_>>()?;
    let (timeline, expected) = lay_out(
        &body,
        &swings,
        args.walk.as_deref().map(onto_body).transpose()?,
    )?;

    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut bytes = log::header().to_vec();
    let mut rest = vec![Vec3::zeros(); body.skeleton.len()];
    body.skeleton.rest_positions(&mut rest);
    let profile = StudentProfile {
        format,
        joints_mm: keypoint_joints.iter().map(|&k| to_mm(rest[k])).collect(),
    };
    for m in [
        Message::StudentProfile(profile),
        Message::Config(Config {
            model_rate_hz: args.model_rate,
            band: Band::DEFAULT,
        }),
        Message::CoachSelect { coach: args.coach },
    ] {
        push_frame(&mut bytes, &m)?;
    }
    let sent = match args.imu_rate {
        Some(rate) => record_imu(&timeline, &body, rate, args, &mut rng, &mut bytes)?,
        None => record_pose(
            &timeline,
            format,
            &keypoint_joints,
            args,
            &mut rng,
            &mut bytes,
        )?,
    };
    std::fs::write(&args.out, &bytes).with_context(|| format!("writing {}", args.out.display()))?;
    let sidecar = sidecar_path(&args.out);
    let doc = json!({
        "log": args.out.file_name().map(|n| n.to_string_lossy().into_owned()),
        "kind": if args.imu_rate.is_some() { "imu" } else { "pose" },
        "rate_hz": args.imu_rate.unwrap_or(args.rate), "magnetometers": args.imu_rate.map(|_| !args.no_mag), "seed": args.seed, "noise_mm": args.noise_mm,
        "jitter_ms": args.jitter_ms, "drop": args.drop,
        "duration_s": timeline.frames() as f32 / TIMELINE_HZ,
        "swings": expected,
    });
    std::fs::write(&sidecar, format!("{doc:#}\n"))
        .with_context(|| format!("writing {}", sidecar.display()))?;
    if args.json {
        let doc = json!({"log": args.out.display().to_string(), "sidecar": sidecar.display().to_string(),
                         "bytes": bytes.len(), "sent": sent, "expected": doc});
        return Ok(format!("{doc}\n"));
    }
    Ok(format!(
        "wrote {} ({} bytes, {sent} {} over {:.1} s, {} swings) and {}\n",
        args.out.display(),
        bytes.len(),
        if args.imu_rate.is_some() {
            "IMU samples"
        } else {
            "pose frames"
        },
        timeline.frames() as f32 / TIMELINE_HZ,
        swings.len(),
        sidecar.display()
    ))
}

/// `NAME.pclog` → `NAME.swings.json`.
pub fn sidecar_path(log: &Path) -> PathBuf {
    log.with_extension("swings.json")
}

/// For each keypoint of `format`, the joint of `body` at that keypoint (the same joint when
/// `body` is in `format`, else the same canonical joint).
fn keypoint_sources(format: Format, body: &Skeleton) -> Result<Vec<usize>> {
    let keypoints = format.keypoints().len();
    let sources: Vec<Option<usize>> = (0..keypoints)
        .map(|i| {
            let at = format
                .joints()
                .iter()
                .position(|j| j.source == Source::Keypoint(i as u8))?;
            if body.format() == format {
                return Some(at);
            }
            format.joints()[at].joint.and_then(|j| body.index_of(j))
        })
        .collect();
    if keypoints == 0 || keypoints > wire::MAX_WIRE_JOINTS || sources.iter().any(Option::is_none) {
        bail!(
            "pose frames in format `{format}` cannot be made from the student's joints: use a format whose keypoints are all joints the T-pose has (h36m17, cmu31, bandai22, smpl24)"
        );
    }
    Ok(sources.into_iter().flatten().collect())
}

fn to_mm(p: Vec3) -> [i16; 3] {
    [p.x, p.y, p.z].map(|v| (v * 1000.0).round().clamp(-32767.0, 32767.0) as i16)
}

fn push_frame(bytes: &mut Vec<u8>, message: &Message) -> Result<()> {
    let mut frame = [0u8; MAX_FRAME];
    let n = wire::encode(message, &mut frame)?;
    bytes.extend_from_slice(&frame[..n]);
    Ok(())
}

/// Lays the session out; returns it and the sidecar's swing entries.
/// `swing` with frames `0..=top` stretched in time by `factor` (linear interpolation).
fn stretch(swing: &Motion, top: usize, factor: f32) -> Motion {
    let joints = swing.skeleton.len();
    let frames = ((top as f32 * factor).round() as usize).max(1);
    let mut positions = Vec::with_capacity((swing.frames() + frames) * joints);
    for i in 0..frames {
        let x = i as f32 * top as f32 / frames as f32;
        let (a, w) = (x.floor() as usize, x.fract());
        let (p, q) = (swing.frame(a), swing.frame((a + 1).min(top)));
        positions.extend(p.iter().zip(q).map(|(p, q)| p + (q - p) * w));
    }
    positions.extend_from_slice(&swing.positions[top * joints..]);
    Motion {
        missing: vec![false; positions.len()],
        positions,
        ..swing.clone()
    }
}

fn lay_out(
    body: &Motion,
    swings: &[(PathBuf, Motion)],
    walk: Option<Motion>,
) -> Result<(Timeline, Vec<Value>)> {
    let skeleton = &body.skeleton;
    let joints = skeleton.len();
    let mut rest = vec![Vec3::zeros(); joints];
    skeleton.rest_positions(&mut rest);
    let first = swings[0].1.frame(0).to_vec();
    let place = |pose: &[Vec3], at: Vec3| -> Vec<Vec3> {
        let shift = Vec3::new(at.x - pose[0].x, 0.0, at.z - pose[0].z);
        pose.iter().map(|p| p + shift).collect()
    };
    let mut t = Timeline {
        joints,
        positions: Vec::new(),
    };
    t.hold(&place(&rest, first[0]), 1.5);
    // Walking up to where the next swing's set-up stands.
    let walk_to = |t: &mut Timeline, at: Vec3| {
        if let Some(walk) = &walk {
            let end = walk.frame(walk.frames() - 1)[0];
            let shift = Vec3::new(at.x - end.x, 0.0, at.z - end.z);
            let walk: Vec<Vec3> = walk.positions.iter().map(|p| p + shift).collect();
            t.blend(&walk[..joints], 1.0);
            t.positions.extend_from_slice(&walk);
        }
    };
    let mut expected = Vec::new();
    for (n, (path, swing)) in swings.iter().enumerate() {
        let address = swing.frame(0).to_vec();
        walk_to(&mut t, address[0]);
        let truth = events::detect(skeleton, &swing.positions, TIMELINE_HZ)
            .with_context(|| format!("events of {}", path.display()))?;
        if truth.kind != SwingKind::Full {
            bail!(
                "{} is a putt: recorded sessions hold full swings",
                path.display()
            );
        }
        t.blend(&address, 1.0);
        t.hold(&address, 0.8);
        t.waggle(&address, 0.08);
        let still = t.frames();
        t.hold(&address, 0.6);
        let start = t.frames();
        t.positions.extend_from_slice(&swing.positions);
        let events: Map<String, Value> = truth
            .iter()
            .map(|(e, f)| {
                (
                    e.name().to_string(),
                    json!((start + f) as f32 / TIMELINE_HZ),
                )
            })
            .collect();
        expected.push(json!({
            "source": path.file_name().map(|n| n.to_string_lossy().into_owned()),
            "start_s": start as f32 / TIMELINE_HZ,
            "still_from_s": still as f32 / TIMELINE_HZ,
            "end_s": t.frames() as f32 / TIMELINE_HZ,
            "events_s": events,
        }));
        t.blend(&address, 1.0);
        t.hold(&address, 1.0);
        if n + 1 < swings.len() {
            // A practice half swing: the takeaway to hip height and back.
            let half = (truth.frame(events::Event::ToeUp).unwrap_or(truth.top()) + 3)
                .min(swing.frames() - 1);
            for f in (0..=half).chain((0..=half).rev()) {
                t.positions.extend_from_slice(swing.frame(f));
            }
            t.hold(&address, 0.8);
        }
    }
    let end = t.last();
    t.hold(&end, 1.0);
    Ok((t, expected))
}

/// Appends the pose frames a phone would send while `timeline` happens; returns how many
/// were sent (lost ones excluded).
fn record_pose(
    timeline: &Timeline,
    format: Format,
    keypoint_joints: &[usize],
    args: &Args,
    rng: &mut ChaCha8Rng,
    bytes: &mut Vec<u8>,
) -> Result<usize> {
    let sigma = args.noise_mm / 3f32.sqrt();
    let noise = Normal::new(0.0, sigma.max(f32::MIN_POSITIVE))?;
    let occluded = Normal::new(0.0, OCCLUDED_MM)?;
    let duration = timeline.frames() as f64 / f64::from(TIMELINE_HZ);
    let frames = (duration * f64::from(args.rate)) as u32;
    let mut sent = 0;
    for seq in 0..frames {
        let jitter = f64::from(args.jitter_ms) * 1e-3 * rng.random_range(-1.0..=1.0);
        let t = (f64::from(seq) / f64::from(args.rate) + jitter).max(0.0);
        let lost = rng.random_bool(args.drop);
        let mut joints_mm = heapless::Vec::new();
        let mut confidence = heapless::Vec::new();
        for &k in keypoint_joints {
            let unsure = rng.random_bool(OCCLUDED);
            let extra = if unsure { OCCLUDED_MM } else { 0.0 };
            let mut p = timeline.at(t, k) * 1000.0;
            for axis in 0..3 {
                p[axis] += noise.sample(rng)
                    + if extra > 0.0 {
                        occluded.sample(rng)
                    } else {
                        0.0
                    };
            }
            let _ = joints_mm.push(to_mm(p * 1e-3));
            let _ = confidence.push(if unsure {
                rng.random_range(20..60)
            } else {
                rng.random_range(180..=255)
            });
        }
        if lost {
            continue;
        }
        let frame = PoseFrame {
            seq,
            t_us: (t * 1e6).round() as u64,
            format,
            joints_mm,
            confidence,
        };
        push_frame(bytes, &Message::PoseFrame(frame))?;
        sent += 1;
    }
    Ok(sent)
}

/// Appends the sensor layout and the IMU samples of `timeline` at `rate_hz`; returns how many
/// samples were sent.
fn record_imu(
    timeline: &Timeline,
    body: &Motion,
    rate_hz: f32,
    args: &Args,
    rng: &mut ChaCha8Rng,
    bytes: &mut Vec<u8>,
) -> Result<usize> {
    let motion = Motion {
        skeleton: body.skeleton.clone(),
        names: body.names.clone(),
        rate_hz: TIMELINE_HZ,
        missing: vec![false; timeline.positions.len()],
        positions: timeline.positions.clone(),
    };
    let layout = synth_imu::default_layout(&body.skeleton);
    push_frame(bytes, &Message::SensorLayout(layout.clone()))?;
    let field = (!args.no_mag).then_some(synth_imu::EARTH_FIELD_UT);
    let samples = synth_imu::imu_samples(&motion, &layout, rate_hz, &ImuNoise::MEMS, field, rng);
    let mut sent = 0;
    for sample in samples {
        if rng.random_bool(args.drop) {
            continue;
        }
        push_frame(bytes, &Message::ImuSample(sample))?;
        sent += 1;
    }
    Ok(sent)
}
