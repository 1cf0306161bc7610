//! `posecoach synth-log`: a realistic recorded session made from swing files.
//!
//! The student's session is laid out at [`TIMELINE_HZ`] on the student's body: a still T-pose
//! (IMU calibration), optional walking up to the ball, then per swing a set-up, a waggle, the
//! swing, a return to the set-up and, between swings, a practice half swing. It is then
//! recorded the way a phone's pose estimator sends it (pose frames at `--rate` with capture
//! jitter, keypoint noise, unsure keypoints and lost frames) or, with `--imu-rate`, as body-worn
//! IMUs send it (a `SensorLayout`, then samples from the segments' motion with bias, noise and
//! misplaced straps), behind the `StudentProfile` and `Config` messages (and a `CoachSelect` with
//! `--coach`; without one the device chooses the coach of each swing from its set-up), as a
//! `.pclog`. A sidecar `NAME.swings.json` lists the
//! swings and their events (from the clean motion) in seconds of the recording; as the golfer
//! stands still at address from `still_from_s`, an address found anywhere after that is right.

use crate::phone::{self, to_mm, Camera, PhoneNoise};
use crate::synth_imu::{self, ImuNoise, SteelClub};
use anyhow::{bail, Context, Result};
use nalgebra::Rotation3;
use posecoach_adapters::log;
use posecoach_core::band::Band;
use posecoach_core::body::Stance;
use posecoach_core::events::{self, SwingEvents, SwingKind};
use posecoach_core::format::{Format, Source};
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::wire::{self, Config, Message, StudentProfile, MAX_FRAME};
use posecoach_core::Vec3;
use posecoach_io::{csv, Motion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{json, Map, Value};
use std::f32::consts::{PI, TAU};
use std::path::{Path, PathBuf};

/// Rate the session is laid out at, Hz.
pub const TIMELINE_HZ: f32 = 60.0;

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
    pose_rate: f32,
    /// Keypoint noise fresh every frame, mm (3D RMS per keypoint; the camera's depth axis
    /// twice the others).
    #[arg(long, default_value_t = 7.0)]
    noise_mm: f32,
    /// Keypoint drift, mm (3D RMS, correlated over 0.2 to 1 s).
    #[arg(long, default_value_t = 0.0)]
    drift_mm: f32,
    /// Constant keypoint bias, mm (3D RMS).
    #[arg(long, default_value_t = 0.0)]
    bias_mm: f32,
    /// Share of the time a keypoint is occluded (runs of low confidence).
    #[arg(long, default_value_t = 0.01)]
    occluded: f64,
    /// Runs of left/right swapped frames (every left keypoint sent as its right counterpart)
    /// starting per second, 0.1 s long on average (`bench coaching`'s phone: 1).
    #[arg(long, default_value_t = 0.0)]
    swaps_per_s: f32,
    /// Runs of front/back flipped frames (the pose's depth reversed about its centre, left and
    /// right exchanged) starting per second, 0.2 s long on average (`bench coaching`: 0.2).
    #[arg(long, default_value_t = 0.0)]
    flips_per_s: f32,
    /// Depth bias per metre of height above the feet, mm, toward or away from the camera
    /// (drawn): the body seen leaning (`bench coaching`: 30).
    #[arg(long, default_value_t = 0.0)]
    lean_mm_per_m: f32,
    /// Where the phone stands: facing the golfer, or behind along the target line.
    #[arg(long, value_enum, default_value_t = View::FaceOn)]
    camera: View,
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
    /// A steel club's field at the wrist sensors' magnetometers, µT, fixed in each sensor's
    /// frame (drawn per sensor), from when the golfer leaves the T-pose to take the club.
    #[arg(long, value_name = "UT")]
    steel_club: Option<f32>,
    /// Share of frames (or IMU samples) lost before they reach the device.
    #[arg(long, default_value_t = 0.03)]
    drop: f64,
    /// Model rate the recording asks the device for (its `Config`).
    #[arg(long, default_value_t = 60)]
    model_rate: u16,
    /// Coach reference the recording selects; without it the device chooses one for each
    /// swing from its set-up.
    #[arg(long)]
    coach: Option<u16>,
    /// Seed of the noise, jitter and losses.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    input: crate::input::Args,
    /// Where to write the log; the sidecar goes beside it.
    #[arg(long)]
    out: PathBuf,
    /// Print one JSON object instead of text: the paths, the size, the pose frames or IMU
    /// samples sent, and the sidecar's content.
    #[arg(long)]
    json: bool,
}

/// Where the phone stands.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum View {
    /// Facing the golfer: depth is toward the ball.
    FaceOn,
    /// Behind the golfer on the target line: depth is toward the target.
    DownTheLine,
}

/// A session being laid out on the student's body at `rate` frames per second.
pub struct Timeline {
    /// Joints per frame.
    pub joints: usize,
    /// Frames per second.
    pub rate: f32,
    /// Joint positions, frame-major.
    pub positions: Vec<Vec3>,
}

impl Timeline {
    /// Frames laid out so far.
    pub fn frames(&self) -> usize {
        self.positions.len() / self.joints
    }

    /// Its length in seconds.
    pub fn duration_s(&self) -> f64 {
        self.frames() as f64 / f64::from(self.rate)
    }

    fn last(&self) -> Vec<Vec3> {
        self.positions[self.positions.len() - self.joints..].to_vec()
    }

    fn hold(&mut self, pose: &[Vec3], seconds: f32) {
        for _ in 0..(seconds * self.rate) as usize {
            self.positions.extend_from_slice(pose);
        }
    }

    /// Eases from the last frame to `to` over `seconds`, turning about the vertical through
    /// the shorter way between the two poses' facings (their `hips`' line, left and right
    /// joints), as a golfer turns: blending positions across a turn would squeeze the body
    /// flat, and an IMU on it would see it spin half round in a frame.
    fn blend(&mut self, to: &[Vec3], seconds: f32, hips: (usize, usize)) {
        let from = self.last();
        let facing = |pose: &[Vec3]| {
            let line = pose[hips.0] - pose[hips.1];
            (-line.z).atan2(line.x)
        };
        let turn = (facing(to) - facing(&from) + PI).rem_euclid(TAU) - PI;
        let about_y = |angle: f32| Rotation3::from_axis_angle(&Vec3::y_axis(), angle);
        let back = about_y(-turn);
        let frames = (seconds * self.rate) as usize;
        for f in 1..=frames {
            let w = 0.5 * (1.0 - (PI * f as f32 / frames as f32).cos());
            let (root, spin) = (from[0] + (to[0] - from[0]) * w, about_y(turn * w));
            self.positions.extend(from.iter().zip(to).map(|(a, b)| {
                let shape = (a - from[0]) * (1.0 - w) + back * (b - to[0]) * w;
                root + spin * shape
            }));
        }
    }

    /// Everything above the hips sways `amplitude` m along X and back, twice.
    fn waggle(&mut self, address: &[Vec3], amplitude: f32) {
        let hips = address[0].y;
        let frames = self.rate as usize;
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
    pub fn at(&self, t: f64, k: usize) -> Vec3 {
        let x = (t * f64::from(self.rate)).max(0.0);
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
    if let Some(ut) = args.steel_club {
        if args.imu_rate.is_none() || args.no_mag {
            bail!("--steel-club needs IMUs with magnetometers (--imu-rate, without --no-mag)");
        }
        if !(0.0..=1000.0).contains(&ut) {
            bail!("--steel-club {ut} must be between 0 and 1000 µT");
        }
    }
    if !(10.0..=120.0).contains(&args.pose_rate) {
        bail!(
            "--pose-rate {} must be between 10 and 120 frames per second",
            args.pose_rate
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
    if [args.noise_mm, args.drift_mm, args.bias_mm]
        .iter()
        .any(|mm| !(0.0..=100.0).contains(mm))
        || !(0.0..1000.0 / (2.0 * args.pose_rate)).contains(&args.jitter_ms)
        || !(0.0..=0.5).contains(&args.occluded)
    {
        bail!("--noise-mm, --drift-mm and --bias-mm must be 0 to 100, --occluded 0 to 0.5, and --jitter-ms under half a frame");
    }
    if [args.swaps_per_s, args.flips_per_s]
        .iter()
        .any(|r| !(0.0..=5.0).contains(r))
        || !(0.0..=200.0).contains(&args.lean_mm_per_m)
    {
        bail!("--swaps-per-s and --flips-per-s must be 0 to 5, and --lean-mm-per-m 0 to 200");
    }
    let body = match &args.student_tpose {
        Some(path) => args.input.load(path)?,
        None => csv::read(include_str!("../../tests/fixtures/h36m17_tpose.csv"))
            .context("bundled T-pose")?,
    };
    let Some(format) = Format::from_name(&args.format) else {
        bail!("unknown format `{}`", args.format);
    };
    let keypoint_joints = keypoint_sources(format, &body.skeleton)?;
    // A golfer swings as the coach, on their own body, with their contacts: both hands on one
    // grip, the feet planted.
    let onto_body = |path: &Path| -> Result<Motion> {
        let coach = args.input.load(path)?;
        let mut motion = coach.retarget_analytic(&body).map_err(|(f, e)| {
            anyhow::anyhow!("{} frame {f} onto the student: {e}", path.display())
        })?;
        motion.keep_contacts(&coach)?;
        Ok(motion.resampled(TIMELINE_HZ)?)
    };
    let swings: Vec<(PathBuf, Motion)> = args
        .swings
        .iter()
        .map(|p| {
            let swing = onto_body(p)?;
            let top = events::detect(&swing.skeleton, swing.swing(), TIMELINE_HZ)
                .with_context(|| format!("events of {}", p.display()))?
                .top();
            Ok((p.clone(), stretch(&swing, top, args.backswing_tempo)))
        })
        .collect::<Result<_>>()?;
    let walk = args.walk.as_deref().map(onto_body).transpose()?;
    let (timeline, placed) = lay_out(&body, &swings, walk.as_ref(), TIMELINE_HZ)?;
    let expected: Vec<Value> = placed.iter().map(|p| p.to_json(TIMELINE_HZ)).collect();

    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut bytes = log::header().to_vec();
    let mut rest = vec![Vec3::zeros(); body.skeleton.len()];
    body.skeleton.rest_positions(&mut rest);
    let profile = StudentProfile {
        format,
        joints_mm: keypoint_joints.iter().map(|&k| to_mm(rest[k])).collect(),
    };
    // The set-up messages are numbered 0, 1, 2 (and 3 for the sensor layout), in their own
    // sequence: the device only sends each number back in its `Ack`.
    let select = args
        .coach
        .map(|coach| Message::CoachSelect { seq: 2, coach });
    for m in [
        Message::StudentProfile { seq: 0, profile },
        Message::Config {
            seq: 1,
            config: Config {
                model_rate_hz: args.model_rate,
                band: Band::DEFAULT,
            },
        },
    ]
    .into_iter()
    .chain(select)
    {
        push_frame(&mut bytes, &m)?;
    }
    let sent = match args.imu_rate {
        Some(rate) => record_imu(&timeline, &body, rate, args, &mut rng, &mut bytes)?,
        None => {
            let first = &placed[0];
            let stance = Stance::new(
                &body.skeleton,
                &timeline.positions[first.start * timeline.joints..][..timeline.joints],
                first.events.lead,
            );
            let depth = match args.camera {
                View::FaceOn => stance.toward_ball(),
                View::DownTheLine => stance.toward_target(),
            };
            // Into the phone's frame, as its estimator sends it: the depth axis is +Z.
            let angle = (-depth.x).atan2(depth.z);
            let turn = nalgebra::Rotation3::from_axis_angle(&Vec3::y_axis(), angle);
            let camera = Camera {
                rate_hz: args.pose_rate,
                depth: Vec3::z(),
            };
            let noise = PhoneNoise {
                white_mm: args.noise_mm,
                drift_mm: args.drift_mm,
                bias_mm: args.bias_mm,
                occluded: args.occluded,
                lost: 0.0,
                jitter_ms: args.jitter_ms,
                drop: args.drop,
                swaps_per_s: args.swaps_per_s,
                flips_per_s: args.flips_per_s,
                lean_mm_per_m: args.lean_mm_per_m,
            };
            let joints = &keypoint_joints;
            let seen = Timeline {
                joints: timeline.joints,
                rate: timeline.rate,
                positions: timeline.positions.iter().map(|p| turn * p).collect(),
            };
            record_pose(&seen, format, joints, &camera, &noise, &mut rng, &mut bytes)?
        }
    };
    std::fs::write(&args.out, &bytes).with_context(|| format!("writing {}", args.out.display()))?;
    let sidecar = sidecar_path(&args.out);
    let doc = json!({
        "log": args.out.file_name().map(|n| n.to_string_lossy().into_owned()),
        "kind": if args.imu_rate.is_some() { "imu" } else { "pose" },
        "rate_hz": args.imu_rate.unwrap_or(args.pose_rate), "magnetometers": args.imu_rate.map(|_| !args.no_mag), "steel_club_ut": args.steel_club, "seed": args.seed, "noise_mm": args.noise_mm,
        "drift_mm": args.drift_mm, "bias_mm": args.bias_mm, "occluded": args.occluded,
        "jitter_ms": args.jitter_ms, "drop": args.drop, "swaps_per_s": args.swaps_per_s,
        "flips_per_s": args.flips_per_s, "lean_mm_per_m": args.lean_mm_per_m,
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
pub fn keypoint_sources(format: Format, body: &Skeleton) -> Result<Vec<usize>> {
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

fn push_frame(bytes: &mut Vec<u8>, message: &Message) -> Result<()> {
    let mut frame = [0u8; MAX_FRAME];
    let n = wire::encode(message, &mut frame)?;
    bytes.extend_from_slice(&frame[..n]);
    Ok(())
}

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

/// Where one swing was laid out on a [`Timeline`] (frames of it).
pub struct Placed {
    /// The swing file.
    pub source: PathBuf,
    /// The golfer stands still at address from here.
    pub still: usize,
    /// The swing's first frame: the takeaway starts here.
    pub start: usize,
    /// The frame after the swing.
    pub end: usize,
    /// Its events as found in the clean swing, counted from `start`.
    pub events: SwingEvents,
}

impl Placed {
    /// The sidecar's entry, times in seconds on a timeline at `rate`.
    fn to_json(&self, rate: f32) -> Value {
        let s = |f: usize| f as f32 / rate;
        let events: Map<String, Value> = self
            .events
            .iter()
            .map(|(e, f)| (e.name().to_string(), json!(s(self.start + f))))
            .collect();
        json!({
            "source": self.source.file_name().map(|n| n.to_string_lossy().into_owned()),
            "start_s": s(self.start),
            "takeaway_s": s(self.start),
            "still_from_s": s(self.still),
            "end_s": s(self.end),
            "events_s": events,
        })
    }
}

/// How long a laid-out session's T-pose is held, seconds: the golfer takes the club after it.
pub const T_POSE_S: f32 = 1.5;

/// Lays a session out at `rate` on `body`: a still T-pose ([`T_POSE_S`]), then per swing (at `rate` on the
/// body) the walk up to it if given, a set-up, a waggle, the swing and the return; a practice
/// half swing between swings.
///
/// # Errors
/// If a swing has no events or is a putt.
pub fn lay_out(
    body: &Motion,
    swings: &[(PathBuf, Motion)],
    walk: Option<&Motion>,
    rate: f32,
) -> Result<(Timeline, Vec<Placed>)> {
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
        rate,
        positions: Vec::new(),
    };
    let hips = [Joint::LeftHip, Joint::RightHip].map(|j| skeleton.index_of(j));
    let [Some(left), Some(right)] = hips else {
        bail!("the student's body has no hips to turn about");
    };
    let hips = (left, right);
    t.hold(&place(&rest, first[0]), T_POSE_S);
    // Walking up to where the next swing's set-up stands.
    let walk_to = |t: &mut Timeline, at: Vec3| {
        if let Some(walk) = walk {
            let end = walk.frame(walk.frames() - 1)[0];
            let shift = Vec3::new(at.x - end.x, 0.0, at.z - end.z);
            let walk: Vec<Vec3> = walk.positions.iter().map(|p| p + shift).collect();
            t.blend(&walk[..joints], 1.0, hips);
            t.positions.extend_from_slice(&walk);
        }
    };
    let mut placed = Vec::new();
    for (n, (path, swing)) in swings.iter().enumerate() {
        let address = swing.frame(0).to_vec();
        walk_to(&mut t, address[0]);
        let events = events::detect(skeleton, swing.swing(), rate)
            .with_context(|| format!("events of {}", path.display()))?;
        if events.kind != SwingKind::Full {
            bail!(
                "{} is a putt: recorded sessions hold full swings",
                path.display()
            );
        }
        t.blend(&address, 1.0, hips);
        t.hold(&address, 0.8);
        t.waggle(&address, 0.08);
        let still = t.frames();
        t.hold(&address, 0.6);
        let start = t.frames();
        t.positions.extend_from_slice(&swing.positions);
        placed.push(Placed {
            source: path.clone(),
            still,
            start,
            end: t.frames(),
            events,
        });
        t.blend(&address, 1.0, hips);
        t.hold(&address, 1.0);
        if n + 1 < swings.len() {
            // A practice half swing: the takeaway to hip height and back.
            let half = (events.frame(events::Event::ToeUp).unwrap_or(events.top()) + 3)
                .min(swing.frames() - 1);
            for f in (0..=half).chain((0..=half).rev()) {
                t.positions.extend_from_slice(swing.frame(f));
            }
            t.hold(&address, 0.8);
        }
    }
    let end = t.last();
    t.hold(&end, 1.0);
    Ok((t, placed))
}

/// `body` (a student's T-pose) turned by `angle` radians about the vertical through its root:
/// the same student facing elsewhere.
///
/// # Errors
/// If the turned rest pose does not make a skeleton (it always does for a skeleton's own).
pub fn turned(body: &Motion, angle: f32) -> Result<Motion> {
    let skeleton = &body.skeleton;
    let turn = Rotation3::from_axis_angle(&Vec3::y_axis(), angle);
    let mut rest = vec![Vec3::zeros(); skeleton.len()];
    skeleton.rest_positions(&mut rest);
    let about = |p: &Vec3| rest[0] + turn * (p - rest[0]);
    let rest: Vec<Vec3> = rest.iter().map(about).collect();
    let parents: Vec<Option<usize>> = (0..skeleton.len()).map(|k| skeleton.parent(k)).collect();
    Ok(Motion {
        skeleton: Skeleton::from_rest_positions(
            skeleton.format(),
            &parents,
            &rest,
            skeleton.joints(),
        )?,
        names: body.names.clone(),
        rate_hz: body.rate_hz,
        missing: body.missing.clone(),
        positions: body.positions.iter().map(about).collect(),
    })
}

/// Appends the pose frames a phone (see [`phone`]) would send while `timeline` happens;
/// returns how many were sent.
fn record_pose(
    timeline: &Timeline,
    format: Format,
    keypoint_joints: &[usize],
    camera: &Camera,
    noise: &PhoneNoise,
    rng: &mut ChaCha8Rng,
    bytes: &mut Vec<u8>,
) -> Result<usize> {
    let frames = phone::record(
        |t, k| timeline.at(t, k),
        timeline.duration_s(),
        format,
        keypoint_joints,
        camera,
        noise,
        rng,
    );
    for frame in &frames {
        push_frame(bytes, &Message::PoseFrame(frame.clone()))?;
    }
    Ok(frames.len())
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
    let seq = 2 + u32::from(args.coach.is_some());
    push_frame(
        bytes,
        &Message::SensorLayout {
            seq,
            layout: layout.clone(),
        },
    )?;
    let field = (!args.no_mag).then_some(synth_imu::EARTH_FIELD_UT);
    let noise = ImuNoise {
        steel_club: args.steel_club.map(|field_ut| SteelClub {
            field_ut,
            from_s: T_POSE_S,
        }),
        ..ImuNoise::MEMS
    };
    let samples = synth_imu::imu_samples(&motion, &layout, rate_hz, &noise, field, rng);
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
