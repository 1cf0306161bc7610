//! `posecoach bench coaching`: whether the advice is true, on swings whose truth is known.
//!
//! Cases are made from real swings (the source files, with their club) on bodies of other
//! statures and proportions ([`bodies`]): a clean swing, with flaws planted in it
//! ([`flaws`]), laid out as a session (T-pose, set-up, waggle, swing, return), filmed by a
//! phone ([`crate::phone`]) facing the golfer or down the line at 30 or 60 frames per
//! second, and sent through the device's own session with the bundled coach of the swing's club
//! (and once more without it, to see whether the device chooses that coach from the set-up).
//! Every figure compares the report with the planted truth:
//!
//! - **timing**: the takeaway (the first frame of the swing: the golfer is still before it),
//!   the top and impact (found in the source swing with its club at its own rate), against the
//!   report's address, top and impact, in ms;
//! - **tempo**: the backswing:downswing ratio's relative error; **covered**: the share of
//!   swings whose true backswing lies within the report's own interval for it (±
//!   [`TEMPO_CONFIDENCE`] standard deviations, 90 % when the stated uncertainty is honest);
//! - **recall at 1**: the report's first advice item states a planted flaw (see
//!   [`flaws::Truth`]);
//! - **false advice**: an unflawed swing given any advice; **false tempo**: given a tempo verdict;
//!   **false body**: given a body item;
//! - **body named**: of the swings whose flaw moves a body check past its tolerance (see
//!   [`flaws::Truth::Body`]), the share whose advice, at any rank, has a body item stating one;
//! - **cause named first**: of the body-flaw swings whose flaw moves a body check or a gap of
//!   the sequence past its tolerance, per kind of flaw, the share whose first item is a body or
//!   sequence item stating one ([`flaws::Planted::causes`]); a consequence first is a miss: a
//!   joint item (the hands a short turn moved), or a check the flaw moves only by moving the
//!   events it is read at (the hips at impact, which the upper body first brings early);
//! - **score** of unflawed swings, and its fall for a flaw of a given size;
//! - **body metrics**: each of [`KEY_METRICS`] and [`MORE_METRICS`] at every P-position of the swing the device scored,
//!   against the same metric of the planted swing before filming (on the same body, at its own
//!   P-positions): the error a golfer reading the report's body table sees, pose noise, event
//!   timing and the device's skeleton together.

pub mod bodies;
pub mod flaws;
mod sessions;

use crate::coaches;
use crate::phone::{self, Camera, Failure, PhoneNoise};
use crate::progress::Progress;
use crate::synth::{self, lay_out, Placed, Timeline};
use crate::synth_imu::{self, ImuNoise, SteelClub, Worn};
use crate::table::{self, KeyMetric, CM, DEG, KEY_METRICS};
use anyhow::{bail, Context, Result};
use flaws::{Body, Flaw, Times, Truth};
use posecoach_adapters::session::Outcome;
use posecoach_core::band::Band;
use posecoach_core::body::{self, Metrics, Stance};
use posecoach_core::checks::BodyDeviation;
use posecoach_core::events::{self, Event, Position, Side};
use posecoach_core::format::Format;
use posecoach_core::joint::Joint;
use posecoach_core::score::{Advice, Direction, Phase, Report, TEMPO_CONFIDENCE};
use posecoach_core::sequence::{Gap, GAPS};
use posecoach_core::wire::{self, Config, Message, PoseFrame, StudentProfile, MAX_FRAME};
use posecoach_core::Vec3;
use posecoach_io::{self as io, Motion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{json, Value};
use std::borrow::Cow;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc;

/// Rate the cases are laid out at: fine enough that a camera frame's time is exact to 4 ms.
pub const LAYOUT_HZ: f32 = 240.0;
/// The device's model rate in every case.
pub const MODEL_HZ: u16 = 60;
/// The IMUs' sample rate.
pub const IMU_HZ: f32 = 200.0;
/// The range sessions draw from a stream of their own (the seed with these bits flipped), so
/// that they change no single swing's case.
pub const SESSION_STREAM: u64 = 0x005e_5510;
/// The longest range session of the quick configuration, swings (on the first body only).
pub const QUICK_SESSION: usize = 3;

#[derive(clap::Args)]
pub struct Args {
    /// Real swings to plant flaws in (.c3d with a club, or any swing file); the bundled coach
    /// whose name the file name holds scores them. Default: the two tour swings in
    /// `$POSECOACH_DATA/golf`, else `../shared/data/golf`.
    #[arg(long = "swing")]
    swings: Vec<PathBuf>,
    /// Bodies (statures spread over 1.50 to 1.95 m, limb proportions varied).
    #[arg(long, default_value_t = 8)]
    bodies: usize,
    /// Noise levels, mm of drift (3D RMS; white jitter and bias a third of it each).
    #[arg(long, value_delimiter = ',', default_value = "0,10,20,30,50")]
    levels: Vec<f32>,
    /// The small configuration CI runs: 3 bodies, one case per flaw family, range sessions of
    /// at most three swings on the first body.
    #[arg(long)]
    quick: bool,
    /// Leave out the IMU rows (every layout, with and without magnetometers, the steel club).
    #[arg(long)]
    no_imu: bool,
    /// Film with a phone whose estimator makes no left/right swaps, front/back flips or lean
    /// (as the benchmark did until 2026-12-07): noise, occlusion and losses only.
    #[arg(long)]
    no_failures: bool,
    /// Seed of the flaws, cameras and noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also write every case and its outcome here (JSON lines).
    #[arg(long)]
    cases_out: Option<PathBuf>,
    /// Also write every case's session into this folder as `case_SEED.pclog` (the seed is in
    /// `--cases-out`), for `posecoach replay`.
    #[arg(long)]
    logs_out: Option<PathBuf>,
    /// Range sessions: after how many swings their tendencies are judged (each session as
    /// long as the largest number).
    #[arg(long = "session", value_delimiter = ',', default_value = "1,3,5,10,20")]
    sessions: Vec<usize>,
    /// Leave the range sessions out.
    #[arg(long)]
    no_sessions: bool,
    /// Unflawed range sessions per golfer and input.
    #[arg(long, default_value_t = 2)]
    unflawed_sessions: usize,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
}

/// A source swing on one body, ready to flaw.
struct Clean {
    source: PathBuf,
    coach: u16,
    body: Motion,
    swing: Motion,
    times: Times,
    lead: Side,
}

impl Clean {
    /// The swing in `motion` (read from `source`, the coach numbered `coach`) on `body`.
    fn new(source: &Path, coach: u16, motion: &Motion, body: &Motion) -> Result<Clean> {
        let found = events::detect(&motion.skeleton, motion.swing(), motion.rate_hz)
            .with_context(|| format!("events of {}", source.display()))?;
        // The golfer swings as the coach on their own body, keeping their grip and planted
        // feet: the virtual coach the device makes, before any flaw.
        let mut swing = motion
            .retarget_analytic(body)
            .map_err(|(f, e)| anyhow::anyhow!("{} frame {f}: {e}", source.display()))?;
        swing.keep_contacts(motion)?;
        Ok(Clean {
            source: source.to_path_buf(),
            coach,
            body: body.clone(),
            swing: swing.resampled(LAYOUT_HZ)?,
            times: flaws::times(&found, motion.rate_hz),
            lead: found.lead,
        })
    }
}

/// How a case reaches the device.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Input {
    /// A phone's pose frames with errors of a level (mm), at a frame rate, facing the golfer
    /// or down the line, with or without the estimator's failures.
    Phone {
        level_mm: f32,
        rate_hz: f32,
        face_on: bool,
        failures: bool,
    },
    /// IMUs at [`IMU_HZ`], the layout `worn`, with or without magnetometers, a steel club
    /// near the wrists' ([`STEEL_CLUB_UT`]) or not; the profile's T-pose turned to any heading.
    Imu {
        magnetometers: bool,
        worn: Worn,
        steel_club: bool,
    },
}

impl Input {
    /// The row of the table it is counted in.
    fn row(&self) -> String {
        match *self {
            Input::Phone { level_mm, .. } => format!("{level_mm} mm"),
            Input::Imu {
                magnetometers,
                worn,
                steel_club,
            } => {
                let count = match worn {
                    Worn::Six => "",
                    Worn::Four => "4 ",
                    Worn::One => "1 ",
                };
                let mag = if magnetometers { ", mag" } else { "" };
                let club = if steel_club { ", steel club" } else { "" };
                format!("{count}IMU{mag}{club}")
            }
        }
    }
}

/// One case: a clean swing, its flaws, and how it reaches the device.
struct Case {
    clean: usize,
    flaws: Vec<Flaw>,
    input: Input,
    seed: u64,
}

/// What the device made of a case.
#[derive(Default)]
struct Outcome1 {
    found: bool,
    false_swings: usize,
    /// Measured minus true, ms: takeaway, top, impact.
    timing_ms: Option<[f32; 3]>,
    tempo_error: Option<f32>,
    /// The backswing's error in standard deviations of its stated uncertainty.
    backswing_z: Option<f32>,
    /// The largest displacement the flaws show at an event, metres.
    shown_m: f32,
    first: Option<String>,
    right_first: bool,
    /// The first item is a body or sequence item stating a planted body-level truth (a
    /// consequence named first is a miss).
    cause_first: bool,
    /// Without a `CoachSelect`, the device chose the coach of the swing's own club.
    right_coach: bool,
    any_advice: bool,
    tempo_verdict: bool,
    /// The planted flaws move a body check or a gap of the sequence past its tolerance.
    body_truth: bool,
    /// The advice has a body or sequence item stating one.
    body_named: bool,
    /// The advice has a body or sequence item.
    body_advice: bool,
    /// The advice has a sequence item.
    sequence_advice: bool,
    /// The report's body checks.
    body: Vec<BodyDeviation>,
    /// The report's gaps of the sequence.
    gaps: Vec<Gap>,
    /// The planted truths.
    truths: Vec<Truth>,
    score: Option<f32>,
    /// Pose frames by the failure they were sent with (none, swapped, flipped: rows) and how
    /// the device's pose stream read them (as sent, swapped, flipped: columns).
    relabels: Relabels,
    /// Per P-position both tables have, each of [`measured_metrics`] measured less true and
    /// that error over the report's uncertainty of it (NaN where a skeleton has no head).
    body_errors: Vec<Vec<(f32, f32)>>,
    error: Option<String>,
}

/// Pose frames by failure sent (rows: none, swapped, flipped) and read (columns: as sent,
/// swapped, flipped).
type Relabels = [[u32; 3]; 3];

/// A swing's body metrics at each P-position, [`Position::ALL`] order.
type Table = [Option<Metrics>; Position::ALL.len()];

pub fn run(args: &Args) -> Result<String> {
    let sources = if args.swings.is_empty() {
        let data = std::env::var_os("POSECOACH_DATA")
            .map_or_else(|| PathBuf::from("../shared/data"), PathBuf::from);
        ["gears_tour_driver.c3d", "gears_tour_iron.c3d"]
            .map(|f| data.join("golf").join(f))
            .to_vec()
    } else {
        args.swings.clone()
    };
    let coach_names: Vec<String> = coaches::all()?
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    let bodies = bodies::bodies(if args.quick { 3 } else { args.bodies })?;

    let mut cleans = Vec::new();
    for path in &sources {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        let Some(coach) = coach_names.iter().position(|n| stem.contains(n.as_str())) else {
            bail!(
                "{}: no bundled coach ({}) is named in the file name",
                path.display(),
                coach_names.join(", ")
            );
        };
        let motion = io::load(path).with_context(|| format!("reading {}", path.display()))?;
        for body in &bodies {
            cleans.push(Clean::new(path, coach as u16, &motion, body)?);
        }
    }
    let cases = cases(&cleans, args);
    if let Some(dir) = &args.logs_out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let outcomes: Vec<Outcome1> = parallel(&cases, "cases", |case| {
        run_case(&cleans[case.clean], case, args.logs_out.as_deref()).unwrap_or_else(|e| Outcome1 {
            error: Some(format!("{e:#}")),
            ..Outcome1::default()
        })
    });
    // The quick configuration's sessions stop at three swings, on the first body.
    let ns: Vec<usize> = match args.no_sessions {
        true => Vec::new(),
        false => args
            .sessions
            .iter()
            .copied()
            .filter(|&n| n > 0 && (!args.quick || n <= QUICK_SESSION))
            .collect(),
    };
    let session_cases = match ns.is_empty() {
        true => Vec::new(),
        false => {
            let mut rng = ChaCha8Rng::seed_from_u64(args.seed ^ SESSION_STREAM);
            let unflawed = if args.quick {
                1
            } else {
                args.unflawed_sessions
            };
            let golfers: Vec<usize> = (0..cleans.len())
                .filter(|c| !args.quick || c % bodies.len() == 0)
                .collect();
            sessions::cases(&golfers, &inputs(args), unflawed, &mut rng)
        }
    };
    let session_outcomes: Vec<sessions::SessionOutcome> =
        parallel(&session_cases, "range sessions", |case| {
            sessions::run_case(&cleans[case.clean], case, &ns).unwrap_or_else(|e| {
                sessions::SessionOutcome {
                    error: Some(format!("{e:#}")),
                    ..sessions::SessionOutcome::default()
                }
            })
        });
    if let Some(path) = &args.cases_out {
        let lines: String = cases
            .iter()
            .zip(&outcomes)
            .map(|(c, o)| format!("{}\n", case_json(&cleans[c.clean], c, o)))
            .chain(
                session_cases
                    .iter()
                    .zip(&session_outcomes)
                    .map(|(c, o)| format!("{}\n", sessions::case_json(&cleans[c.clean], c, o))),
            )
            .collect();
        std::fs::write(path, lines).with_context(|| format!("writing {}", path.display()))?;
    }
    let mut rows: Vec<String> = Vec::new();
    for c in &cases {
        let row = c.input.row();
        if !rows.contains(&row) {
            rows.push(row);
        }
    }
    let levels: Vec<Value> = rows
        .iter()
        .map(|row| {
            let pairs: Vec<(&Case, &Outcome1)> = cases
                .iter()
                .zip(&outcomes)
                .filter(|(c, _)| c.input.row() == *row)
                .collect();
            summary(row, &pairs)
        })
        .collect();
    let mut session_rows: Vec<String> = Vec::new();
    for c in &session_cases {
        let row = c.input.row();
        if !session_rows.contains(&row) {
            session_rows.push(row);
        }
    }
    let session_levels: Vec<Value> = session_rows
        .iter()
        .map(|row| {
            let pairs: Vec<_> = session_cases
                .iter()
                .zip(&session_outcomes)
                .filter(|(c, _)| c.input.row() == *row)
                .collect();
            sessions::summary(row, &ns, &pairs)
        })
        .collect();
    let doc = json!({
        "sources": sources.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "bodies": bodies.len(), "cases": cases.len(), "layout_hz": LAYOUT_HZ, "model_hz": MODEL_HZ,
        "levels": levels,
        "sessions": session_levels,
    });
    if args.json {
        return Ok(format!("{doc}\n"));
    }
    Ok(table(&doc) + &sessions::table(&session_levels))
}

/// The inputs of `args`: a phone at each noise level, then the IMU rows.
fn inputs(args: &Args) -> Vec<Input> {
    let mut out: Vec<Input> = args
        .levels
        .iter()
        .map(|&level_mm| Input::Phone {
            level_mm,
            rate_hz: 60.0,
            face_on: true,
            failures: !args.no_failures,
        })
        .collect();
    if !args.no_imu {
        out.extend(IMU_INPUTS);
    }
    out
}

/// The IMU rows: six sensors with magnetometers and without, with magnetometers and a steel
/// club near the wrists', then four and one, with magnetometers.
const IMU_INPUTS: [Input; 5] = [
    Input::Imu {
        magnetometers: true,
        worn: Worn::Six,
        steel_club: false,
    },
    Input::Imu {
        magnetometers: false,
        worn: Worn::Six,
        steel_club: false,
    },
    Input::Imu {
        magnetometers: true,
        worn: Worn::Six,
        steel_club: true,
    },
    Input::Imu {
        magnetometers: true,
        worn: Worn::Four,
        steel_club: false,
    },
    Input::Imu {
        magnetometers: true,
        worn: Worn::One,
        steel_club: false,
    },
];

/// The steel club's field at a wrist sensor, µT: a third of the earth's 48 (a magnetized shaft
/// a few centimetres from the strap; the convention of this benchmark, not a measurement).
const STEEL_CLUB_UT: f32 = 15.0;

/// `run` of every item on every core, in the items' order, with progress shown as `what`.
fn parallel<C: Sync, O: Send + Default>(
    items: &[C],
    what: &'static str,
    run: impl Fn(&C) -> O + Sync,
) -> Vec<O> {
    let progress = Progress::new(items.len() as u64, what);
    let (tx, rx) = mpsc::channel();
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let out = std::thread::scope(|scope| {
        for _ in 0..workers {
            let (tx, next, run) = (tx.clone(), &next, &run);
            scope.spawn(move || loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                if tx.send((i, run(item))).is_err() {
                    break;
                }
            });
        }
        drop(tx);
        let mut out: Vec<Option<O>> = (0..items.len()).map(|_| None).collect();
        for (i, o) in rx {
            out[i] = Some(o);
            progress.inc();
        }
        out.into_iter().map(Option::unwrap_or_default).collect()
    });
    progress.finish_and_clear();
    out
}

/// The cases: for every clean swing and noise level, unflawed swings, tempo flaws, a pause,
/// offsets, the body-level flaws and two combinations, drawn from `args.seed`.
fn cases(cleans: &[Clean], args: &Args) -> Vec<Case> {
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut cases = Vec::new();
    let (unflawed, tempos, offsets) = if args.quick { (1, 1, 2) } else { (12, 4, 10) };
    let joints = [
        Joint::LeftWrist,
        Joint::RightWrist,
        Joint::LeftElbow,
        Joint::RightElbow,
        Joint::Neck,
        Joint::LeftKnee,
        Joint::RightKnee,
        Joint::Pelvis,
    ];
    let directions = [
        Direction::TowardTarget,
        Direction::AwayFromTarget,
        Direction::TowardBall,
        Direction::AwayFromBall,
        Direction::Up,
        Direction::Down,
    ];
    let mut inputs: Vec<Result<f32, Input>> = args.levels.iter().map(|&l| Ok(l)).collect();
    if !args.no_imu {
        inputs.extend(IMU_INPUTS.map(Err));
    }
    for level in inputs {
        for clean in 0..cleans.len() {
            let mut sets: Vec<Vec<Flaw>> = Vec::new();
            for _ in 0..unflawed {
                sets.push(Vec::new());
            }
            let tempo = |rng: &mut ChaCha8Rng| {
                let change = rng.random_range(0.15f32..=0.5);
                Flaw::Tempo {
                    phase: Phase::ALL[rng.random_range(0..3)],
                    factor: if rng.random_bool(0.5) {
                        1.0 + change
                    } else {
                        1.0 / (1.0 + change)
                    },
                }
            };
            let offset = |rng: &mut ChaCha8Rng| Flaw::Offset {
                event: Event::ALL[rng.random_range(0..8)],
                joint: joints[rng.random_range(0..joints.len())],
                direction: directions[rng.random_range(0..6)],
                metres: rng.random_range(0.05f32..=0.2),
            };
            for _ in 0..tempos {
                sets.push(vec![tempo(&mut rng)]);
            }
            sets.push(vec![Flaw::Pause {
                seconds: rng.random_range(0.1f32..=0.3),
            }]);
            for _ in 0..offsets {
                sets.push(vec![offset(&mut rng)]);
            }
            for body in Body::ALL {
                let size = match body {
                    Body::ReducedTurn => rng.random_range(10.0f32..=25.0),
                    Body::BentLeadArm => rng.random_range(20.0f32..=40.0),
                    Body::UpperBodyFirst => rng.random_range(15.0f32..=50.0),
                    _ => rng.random_range(0.05f32..=0.12),
                };
                sets.push(vec![Flaw::Body { body, size }]);
            }
            sets.push(vec![tempo(&mut rng), offset(&mut rng)]);
            sets.push(vec![offset(&mut rng), offset(&mut rng)]);
            for flaws in sets {
                let input = match level {
                    Ok(level_mm) => Input::Phone {
                        level_mm,
                        rate_hz: if rng.random_bool(0.5) { 30.0 } else { 60.0 },
                        face_on: rng.random_bool(0.5),
                        failures: !args.no_failures,
                    },
                    Err(imu) => imu,
                };
                cases.push(Case {
                    clean,
                    flaws,
                    input,
                    seed: rng.random(),
                });
            }
        }
    }
    cases
}

/// Lays the case out, films it and sends it through the device's session.
fn run_case(clean: &Clean, case: &Case, logs_out: Option<&Path>) -> Result<Outcome1> {
    let planted = flaws::plant(&clean.swing, &clean.times, clean.lead, &case.flaws);
    let source = (clean.source.clone(), planted.swing.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(case.seed);
    let body = body_of(clean, case.input, &mut rng)?;
    let (mut timeline, placed) = lay_out(&body, &[source], None, LAYOUT_HZ)?;
    let start_s = placed[0].start as f64 / f64::from(LAYOUT_HZ);
    let swing_end_s = placed[0].end as f64 / f64::from(LAYOUT_HZ);

    let (mut messages, failures) = match case.input {
        Input::Phone {
            level_mm,
            rate_hz,
            face_on,
            failures,
        } => {
            let camera = PhoneView {
                level_mm,
                rate_hz,
                face_on,
                failures,
            };
            phone_messages(clean, &mut timeline, &placed, &camera, &mut rng)?
        }
        Input::Imu {
            magnetometers,
            worn,
            steel_club,
        } => (
            imu_messages(&body, &timeline, magnetometers, worn, steel_club, &mut rng)?,
            Vec::new(),
        ),
    };
    messages.insert(
        1,
        Message::Config {
            seq: 1,
            config: Config {
                model_rate_hz: MODEL_HZ,
                band: Band::DEFAULT,
            },
        },
    );
    // The coach of the swing's club, as a phone that knows the club selects it; the coach the
    // device chooses from the swing's set-up without one is measured on its own.
    let mut selected = messages.clone();
    selected.insert(
        2,
        Message::CoachSelect {
            seq: 2,
            coach: clean.coach,
        },
    );

    if let Some(dir) = logs_out {
        let mut bytes = posecoach_adapters::log::header().to_vec();
        for m in &selected {
            let mut frame = [0u8; MAX_FRAME];
            let n = wire::encode(m, &mut frame)?;
            bytes.extend_from_slice(&frame[..n]);
        }
        let path = dir.join(format!("case_{}.pclog", case.seed));
        std::fs::write(&path, bytes).with_context(|| format!("writing {}", path.display()))?;
    }
    let (scored, refused, relabels) = run_session(&selected, &failures)?;
    let model_s = 1.0 / f64::from(MODEL_HZ);
    let overlaps =
        |at: f64, frames: usize| at < swing_end_s && at + frames as f64 * model_s > start_s;
    let chosen = run_session(&messages, &[])?
        .0
        .into_iter()
        .find(|(at, frames, _, _)| overlaps(*at, *frames))
        .map(|(_, _, coach, _)| coach);

    // The swing that overlaps the planted one; any other is false.
    let (mut ours, mut others): (Vec<_>, Vec<_>) = scored
        .into_iter()
        .partition(|(at, frames, _, _)| overlaps(*at, *frames));
    others.retain(|(_, _, _, r)| r.is_ok());
    let mut outcome = Outcome1 {
        false_swings: others.len() + ours.len().saturating_sub(1),
        shown_m: planted.shown_m,
        relabels,
        ..Outcome1::default()
    };
    outcome.right_coach = chosen == Some(clean.coach);
    let Some((at, _, _, result)) = ours.drain(..).next() else {
        if let Some(r) = refused.first() {
            outcome.error = Some(format!(
                "{} messages refused, the first: {r}",
                refused.len()
            ));
        }
        return Ok(outcome);
    };
    let (report, table, spread) = match result {
        Ok(r) => r,
        Err(e) => {
            outcome.error = Some(e);
            return Ok(outcome);
        }
    };
    // The truth: the planted swing's own metrics (none, and no errors counted, should its
    // events not be found: that says nothing of the device's).
    let swing = &planted.swing;
    let truth_table = events::detect(&swing.skeleton, swing.swing(), swing.rate_hz)
        .ok()
        .and_then(|found| body::at_positions(&swing.skeleton, swing.swing(), &found).ok())
        .unwrap_or([None; Position::ALL.len()]);
    outcome.body_errors = table
        .iter()
        .zip(&spread)
        .zip(&truth_table)
        .filter_map(|((m, s), t)| Some((m.as_ref()?, s.as_ref()?, t.as_ref()?)))
        .map(|(m, s, t)| {
            measured_metrics()
                .map(|(_, _, _, value)| {
                    let error = value(m) - value(t);
                    (error, error / value(s))
                })
                .collect()
        })
        .collect();
    outcome.found = true;
    let measured = |e: Event| {
        report
            .student_events
            .time(e)
            .map_or(f64::NAN, |t| at + f64::from(t) * model_s)
    };
    let truth = |e: Event| start_s + f64::from(planted.times[e as usize]);
    outcome.timing_ms = Some(
        [Event::Address, Event::Top, Event::Impact]
            .map(|e| ((measured(e) - truth(e)) * 1000.0) as f32),
    );
    outcome.tempo_error = Some(report.student_tempo_ratio / planted.tempo_ratio - 1.0);
    let backswing = &report.tempo[0];
    let sigma = f64::from(backswing.ratio_uncertainty / backswing.ratio * backswing.student_s);
    let error = (measured(Event::Top) - measured(Event::Address))
        - (truth(Event::Top) - truth(Event::Address));
    outcome.backswing_z = Some((error / sigma) as f32);
    outcome.score = Some(report.score);
    outcome.any_advice = !report.advice.is_empty();
    outcome.tempo_verdict = report.advice.iter().any(|a| matches!(a, Advice::Tempo(_)));
    outcome.body_truth = !planted.causes.is_empty();
    let body_items = || {
        report
            .advice
            .iter()
            .filter(|a| matches!(a, Advice::Body(..) | Advice::Sequence(..)))
    };
    outcome.sequence_advice = report
        .advice
        .iter()
        .any(|a| matches!(a, Advice::Sequence(..)));
    outcome.gaps = report.gaps.to_vec();
    outcome.body_advice = body_items().next().is_some();
    outcome.body = report.body.to_vec();
    outcome.truths = planted.truths.clone();
    outcome.body_named = body_items().any(|a| states(a, &planted.truths));
    if let Some(first) = report.advice.first() {
        outcome.first = Some(first.to_string());
        outcome.right_first = states(first, &planted.truths);
        outcome.cause_first = matches!(first, Advice::Body(..) | Advice::Sequence(..))
            && states(first, &planted.causes);
    }
    Ok(outcome)
}

/// A phone filming a case.
struct PhoneView {
    level_mm: f32,
    rate_hz: f32,
    face_on: bool,
    failures: bool,
}

/// The profile then the pose frames a phone sends of `timeline` (turned into its frame), and
/// the failure each frame was sent with.
fn phone_messages(
    clean: &Clean,
    timeline: &mut Timeline,
    placed: &[Placed],
    view: &PhoneView,
    rng: &mut ChaCha8Rng,
) -> Result<(Vec<Message>, Vec<Failure>)> {
    // Into the phone's frame: its depth axis is Z, the golfer's stance square to it give or
    // take 15°.
    let joints = timeline.joints;
    let stance = Stance::new(
        &clean.body.skeleton,
        &timeline.positions[placed[0].start * joints..][..joints],
        clean.lead,
    );
    let depth = if view.face_on {
        stance.toward_ball()
    } else {
        stance.toward_target()
    };
    let square = depth.z.atan2(depth.x) - std::f32::consts::FRAC_PI_2;
    let skew = rng.random_range(-15f32..=15.0).to_radians();
    let turn = nalgebra::Rotation3::from_axis_angle(&Vec3::y_axis(), square + skew);
    for p in &mut timeline.positions {
        *p = turn * *p;
    }
    let camera = Camera {
        rate_hz: view.rate_hz,
        depth: Vec3::z(),
    };
    let noise = match view.failures {
        true => PhoneNoise::level(view.level_mm),
        false => PhoneNoise::level(view.level_mm).without_failures(),
    };
    let format = Format::H36m17;
    let keypoint_joints = synth::keypoint_sources(format, &clean.body.skeleton)?;
    let (frames, failures): (Vec<PoseFrame>, Vec<Failure>) = phone::record_failing(
        |t, k| timeline.at(t, k),
        timeline.duration_s(),
        format,
        &keypoint_joints,
        &camera,
        &noise,
        rng,
    )
    .into_iter()
    .unzip();
    // The profile: the T-pose the phone saw in the first second, from the frames whose left and
    // right agree with most of them (an app that asks the golfer to face it in a T-pose tells
    // left from right there, and sets a swapped or flipped frame aside).
    let first: Vec<&PoseFrame> = frames.iter().filter(|f| f.t_us < 1_000_000).collect();
    // Each pair of counterparts' vector from the one to the other (zero where either is
    // unsure), and its sum over the frames.
    let across = |frame: &PoseFrame| -> Vec<Vec3> {
        let at = |i: usize| {
            let p = frame.joints_mm[i];
            Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
        };
        (0..frame.joints_mm.len())
            .map(|i| (i, format.mirror_keypoint(i)))
            .filter(|&(i, m)| m > i)
            .map(
                |(i, m)| match frame.confidence[i].min(frame.confidence[m]) >= 180 {
                    true => at(i) - at(m),
                    false => Vec3::zeros(),
                },
            )
            .collect()
    };
    let mut most: Vec<Vec3> = Vec::new();
    for frame in &first {
        most.resize(frame.joints_mm.len(), Vec3::zeros());
        for (m, v) in most.iter_mut().zip(across(frame)) {
            *m += v;
        }
    }
    let agrees = |frame: &PoseFrame| {
        across(frame)
            .iter()
            .zip(&most)
            .map(|(v, m)| v.dot(m))
            .sum::<f32>()
            > 0.0
    };
    let mut sum = vec![(Vec3::zeros(), 0u32); keypoint_joints.len()];
    for frame in first.iter().filter(|f| agrees(f)) {
        for (k, (p, &c)) in frame.joints_mm.iter().zip(&frame.confidence).enumerate() {
            if c >= 180 {
                sum[k].0 += Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32);
                sum[k].1 += 1;
            }
        }
    }
    if sum.iter().any(|s| s.1 == 0) {
        bail!("a joint was never seen in the T-pose");
    }
    let profile = StudentProfile {
        format,
        joints_mm: sum
            .iter()
            .map(|(p, n)| phone::to_mm(p / (*n as f32) * 1e-3))
            .collect(),
    };
    let mut messages = vec![Message::StudentProfile { seq: 0, profile }];
    messages.extend(frames.into_iter().map(Message::PoseFrame));
    Ok((messages, failures))
}

/// The body a case is laid out on: for IMUs the student's T-pose turned to a heading drawn
/// from `rng` (the golfer turns from it to the set-up), as `synth-log` lays out a T-pose file
/// that faces anywhere; for a phone the T-pose as it is.
fn body_of<'c>(clean: &'c Clean, input: Input, rng: &mut ChaCha8Rng) -> Result<Cow<'c, Motion>> {
    Ok(match input {
        Input::Imu { .. } => {
            let heading = rng.random_range(0.0f32..std::f32::consts::TAU);
            Cow::Owned(synth::turned(&clean.body, heading)?)
        }
        Input::Phone { .. } => Cow::Borrowed(&clean.body),
    })
}

/// The profile (the student's T-pose in `body`), the sensor layout and the samples the IMUs
/// `worn` send of `timeline` (3 % lost), a steel club near the wrists' from the T-pose's end
/// where `steel_club`.
fn imu_messages(
    body: &Motion,
    timeline: &Timeline,
    magnetometers: bool,
    worn: Worn,
    steel_club: bool,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<Message>> {
    let format = Format::H36m17;
    let keypoint_joints = synth::keypoint_sources(format, &body.skeleton)?;
    let profile = StudentProfile {
        format,
        joints_mm: keypoint_joints
            .iter()
            .map(|&k| phone::to_mm(body.positions[k]))
            .collect(),
    };
    let motion = Motion {
        skeleton: body.skeleton.clone(),
        names: body.names.clone(),
        rate_hz: timeline.rate,
        missing: vec![false; timeline.positions.len()],
        positions: timeline.positions.clone(),
    };
    let layout = synth_imu::layout(&body.skeleton, worn);
    let field = magnetometers.then_some(synth_imu::EARTH_FIELD_UT);
    let noise = ImuNoise {
        steel_club: steel_club.then_some(SteelClub {
            field_ut: STEEL_CLUB_UT,
            from_s: synth::T_POSE_S,
        }),
        ..ImuNoise::MEMS
    };
    let samples = synth_imu::imu_samples(&motion, &layout, IMU_HZ, &noise, field, rng);
    let mut messages = vec![
        Message::StudentProfile { seq: 0, profile },
        Message::SensorLayout { seq: 3, layout },
    ];
    for sample in samples {
        if !rng.random_bool(0.03) {
            messages.push(Message::ImuSample(sample));
        }
    }
    Ok(messages)
}

/// A swing found in a session, and how it went: start (s), frames, the coach, the report.
type Scored = (
    f64,
    usize,
    u16,
    std::result::Result<(Report, Table, Table), String>,
);

/// What the device's session makes of `messages`: the swings it found, its refusals, and
/// how its pose stream read the pose frames sent with `failures` (one per pose frame, in
/// order; those it took are counted).
fn run_session(
    messages: &[Message],
    failures: &[Failure],
) -> Result<(Vec<Scored>, Vec<String>, Relabels)> {
    let mut scored: Vec<Scored> = Vec::new();
    let mut refused = Vec::new();
    let mut relabels = Relabels::default();
    let mut failures = failures.iter();
    coaches::session(None, |session| {
        for m in messages {
            let before = session.stream_counters();
            let failure = match m {
                Message::PoseFrame(_) => failures.next(),
                _ => None,
            };
            session.handle(m, |outcome| match outcome {
                Outcome::Scored {
                    swing,
                    report,
                    compared,
                } => {
                    let at = swing.start_us as f64 * 1e-6;
                    let (skeleton, student) = (compared.skeleton, compared.student);
                    let events = &report.student_events;
                    let table = body::at_positions(skeleton, student, events)
                        .unwrap_or([None; Position::ALL.len()]);
                    let error = table::input_error(report, compared.student_hz);
                    let spread = body::spread_at_positions(skeleton, student, events, &error)
                        .unwrap_or([None; Position::ALL.len()]);
                    let scored_swing = Ok((report.clone(), table, spread));
                    scored.push((at, swing.frames, swing.coach, scored_swing));
                }
                Outcome::Unscored { swing, error } => {
                    let at = swing.start_us as f64 * 1e-6;
                    scored.push((at, swing.frames, swing.coach, Err(error.to_string())));
                }
                Outcome::Refused(r) => refused.push(r.to_string()),
                Outcome::Accepted | Outcome::Session { .. } => {}
            });
            let after = session.stream_counters();
            // Frames the stream took (none where the profile was refused).
            if let Some(failure) = failure.filter(|_| after.accepted > before.accepted) {
                let read = if after.swapped > before.swapped {
                    1
                } else if after.flipped > before.flipped {
                    2
                } else {
                    0
                };
                let sent = match failure {
                    Failure::None => 0,
                    Failure::Swap => 1,
                    Failure::Flip => 2,
                };
                relabels[sent][read] += 1;
            }
        }
    })?;
    Ok((scored, refused, relabels))
}

/// Whether `advice` states one of `truths`.
fn states(advice: &Advice, truths: &[Truth]) -> bool {
    truths.iter().any(|t| match (t, advice) {
        (Truth::Tempo { phase, verdict }, Advice::Tempo(p)) => {
            p.phase == *phase && p.verdict == *verdict
        }
        (
            Truth::Spatial {
                event,
                joint,
                direction,
            },
            Advice::Spatial(d),
        ) => d.event == *event && d.joint == *joint && d.direction == *direction,
        (Truth::Body { check, more }, Advice::Body(b, _)) => {
            b.check == *check && (b.student > b.coach) == *more
        }
        (Truth::Sequence { first, then, more }, Advice::Sequence(g, _)) => {
            g.first == *first && g.then == *then && (g.student_s > g.coach_s) == *more
        }
        _ => false,
    })
}

/// Median and 95th percentile of `values`' magnitudes.
fn quantiles(values: &[f32]) -> Value {
    if values.is_empty() {
        return json!(null);
    }
    let mut v: Vec<f32> = values.iter().map(|x| x.abs()).collect();
    v.sort_by(f32::total_cmp);
    let q = |p: f32| v[((v.len() - 1) as f32 * p).round() as usize];
    json!({"median": q(0.5), "p95": q(0.95), "n": v.len()})
}

/// A [`share`]'s percentage for the table, `-` where there was none.
fn pct(v: &Value) -> String {
    v["share"]
        .as_f64()
        .map_or("-".into(), |s| format!("{:.0}%", s * 100.0))
}

fn share(hits: usize, of: usize) -> Value {
    if of == 0 {
        json!(null)
    } else {
        json!({"share": hits as f64 / of as f64, "hits": hits, "of": of})
    }
}

fn family(flaws: &[Flaw]) -> &'static str {
    match flaws {
        [] => "unflawed",
        [Flaw::Tempo { .. }] | [Flaw::Pause { .. }] => "tempo",
        [Flaw::Offset { .. }] => "offset",
        [Flaw::Body { .. }] => "body",
        _ => "combined",
    }
}

/// The figures of one noise level.
fn summary(row: &str, pairs: &[(&Case, &Outcome1)]) -> Value {
    let found: Vec<&(&Case, &Outcome1)> = pairs.iter().filter(|(_, o)| o.found).collect();
    let timing = |i: usize| {
        quantiles(
            &found
                .iter()
                .filter_map(|(_, o)| o.timing_ms.map(|t| t[i]))
                .collect::<Vec<_>>(),
        )
    };
    let unflawed: Vec<&&(&Case, &Outcome1)> =
        found.iter().filter(|(c, _)| c.flaws.is_empty()).collect();
    let named = |f: &dyn Fn(&Case) -> bool| {
        let of: Vec<_> = found.iter().filter(|(c, o)| o.body_truth && f(c)).collect();
        share(of.iter().filter(|(_, o)| o.body_named).count(), of.len())
    };
    let recall = |f: &dyn Fn(&Case, &Outcome1) -> bool| {
        let of: Vec<_> = found.iter().filter(|(c, o)| f(c, o)).collect();
        share(of.iter().filter(|(_, o)| o.right_first).count(), of.len())
    };
    let offset_at_least = |cm: f32| {
        move |c: &Case, o: &Outcome1| {
            matches!(c.flaws[..], [Flaw::Offset { .. }]) && o.shown_m * 100.0 >= cm
        }
    };
    let mean_score = |f: &dyn Fn(&Case, &Outcome1) -> bool| {
        let s: Vec<f32> = found
            .iter()
            .filter(|(c, o)| f(c, o))
            .filter_map(|(_, o)| o.score)
            .collect();
        if s.is_empty() {
            json!(null)
        } else {
            json!({"mean": s.iter().sum::<f32>() / s.len() as f32, "min": s.iter().copied().fold(f32::INFINITY, f32::min), "n": s.len()})
        }
    };
    let offset_in = |lo: f32, hi: f32| {
        move |c: &Case, o: &Outcome1| {
            matches!(c.flaws[..], [Flaw::Offset { .. }]) && (lo..hi).contains(&(o.shown_m * 100.0))
        }
    };
    let tempo_in = |lo: f32, hi: f32| move |c: &Case, _: &Outcome1| matches!(c.flaws[..], [Flaw::Tempo { factor, .. }] if (lo..hi).contains(&((factor - 1.0).abs() * 100.0)));
    json!({
        "input": row,
        "cases": pairs.len(),
        "found": share(found.len(), pairs.len()),
        "right_coach": share(pairs.iter().filter(|(_, o)| o.right_coach).count(), pairs.len()),
        "false_swings": pairs.iter().map(|(_, o)| o.false_swings).sum::<usize>(),
        "errors": pairs.iter().filter(|(_, o)| o.error.is_some()).count(),
        "takeaway_ms": timing(0), "top_ms": timing(1), "impact_ms": timing(2),
        "tempo_ratio_error": quantiles(&found.iter().filter_map(|(_, o)| o.tempo_error).collect::<Vec<_>>()),
        "backswing_covered": share(
            found
                .iter()
                .filter(|(_, o)| o.backswing_z.is_some_and(|z| z.abs() <= TEMPO_CONFIDENCE))
                .count(),
            found.len(),
        ),
        "false_tempo": share(unflawed.iter().filter(|(_, o)| o.tempo_verdict).count(), unflawed.len()),
        "false_advice": share(unflawed.iter().filter(|(_, o)| o.any_advice).count(), unflawed.len()),
        "false_body": share(unflawed.iter().filter(|(_, o)| o.body_advice).count(), unflawed.len()),
        "false_sequence": share(unflawed.iter().filter(|(_, o)| o.sequence_advice).count(), unflawed.len()),
        "gaps": GAPS.iter().map(|&(first, then)| {
            // On unflawed swings the student's gap is the coach's: its error, and whether it lies
            // within its stated interval (± TEMPO_CONFIDENCE uncertainties).
            let timed: Vec<&Gap> = unflawed.iter().flat_map(|(_, o)| &o.gaps).filter(|g| (g.first, g.then) == (first, then)).collect();
            let errors: Vec<f32> = timed.iter().map(|g| (g.student_s - g.coach_s) * 1000.0).collect();
            (format!("{}_{}", first.name(), then.name()), json!({
                "timed": share(timed.len(), unflawed.len()),
                "error_ms": quantiles(&errors),
                "uncertainty_ms": quantiles(&timed.iter().map(|g| g.uncertainty_s * 1000.0).collect::<Vec<_>>()),
                "covered": share(timed.iter().filter(|g| (g.student_s - g.coach_s).abs() <= TEMPO_CONFIDENCE * g.uncertainty_s).count(), timed.len()),
            }))
        }).collect::<serde_json::Map<_, _>>(),
        "body_named": {
            "all": named(&|_| true),
            "by_flaw": Body::ALL.iter().map(|&b| (
                serde_json::to_value(b).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default(),
                named(&|c: &Case| matches!(c.flaws[..], [Flaw::Body { body, .. }] if body == b)),
            )).collect::<serde_json::Map<_, _>>(),
        },
        // Of the body-flaw cases whose flaw moves a check or a gap past its tolerance, the share
        // whose first item is that body-level item: the cause named before its symptoms.
        "cause_first": Body::ALL.iter().map(|&b| (
            serde_json::to_value(b).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default(),
            {
                let of: Vec<_> = found.iter().filter(|(c, o)| o.body_truth && matches!(c.flaws[..], [Flaw::Body { body, .. }] if body == b)).collect();
                share(of.iter().filter(|(_, o)| o.cause_first).count(), of.len())
            },
        )).collect::<serde_json::Map<_, _>>(),
        "recall_at_1": {
            "tempo": recall(&|c, _| family(&c.flaws) == "tempo"),
            "offset": recall(&|c, _| family(&c.flaws) == "offset"),
            "offset_8cm": recall(&offset_at_least(8.0)),
            "body": recall(&|c, _| family(&c.flaws) == "body"),
            "combined": recall(&|c, _| family(&c.flaws) == "combined"),
        },
        "body_error": measured_metrics().enumerate().map(|(i, (name, unit, _, _))| {
            let both: Vec<(f32, f32)> = found.iter().flat_map(|(_, o)| o.body_errors.iter().map(move |e| e[i])).filter(|(e, _)| e.is_finite()).collect();
            let errors: Vec<f32> = both.iter().map(|&(e, _)| e).collect();
            // The share of errors within the report's interval (± TEMPO_CONFIDENCE of its
            // uncertainties; a normal error falls within it 90 % of the time).
            let covered = both.iter().filter(|&&(_, z)| z.abs() <= TEMPO_CONFIDENCE).count();
            ((*name).to_string(), json!({"unit": unit, "error": quantiles(&errors), "coverage": share(covered, both.len())}))
        }).collect::<serde_json::Map<_, _>>(),
        "score": {
            "unflawed": mean_score(&|c, _| c.flaws.is_empty()),
            "offset_5_10cm": mean_score(&offset_in(5.0, 10.0)),
            "offset_10_15cm": mean_score(&offset_in(10.0, 15.0)),
            "offset_15_20cm": mean_score(&offset_in(15.0, 20.01)),
            "tempo_15_30pc": mean_score(&tempo_in(15.0, 30.0)),
            "tempo_30_50pc": mean_score(&tempo_in(30.0, 50.01)),
        },
        "relabelled": relabelled(pairs),
    })
}

/// How the device's pose stream read the frames a phone sent swapped, flipped or neither, over
/// every case of a row (null for IMUs): each failure's frames, the share read relabelled (as
/// either) and as that failure, and the share of the frames sent without one read relabelled.
fn relabelled(pairs: &[(&Case, &Outcome1)]) -> Value {
    let mut all = Relabels::default();
    for (_, o) in pairs {
        for (row, add) in all.iter_mut().zip(&o.relabels) {
            for (n, a) in row.iter_mut().zip(add) {
                *n += a;
            }
        }
    }
    if all.iter().flatten().all(|&n| n == 0) {
        return json!(null);
    }
    let of = |row: &[u32; 3]| row.iter().sum::<u32>() as usize;
    let sent = |i: usize| {
        json!({"frames": of(&all[i]), "read_relabelled": share((all[i][1] + all[i][2]) as usize, of(&all[i])),
               "read_as_sent_failure": share(all[i][i] as usize, of(&all[i]))})
    };
    json!({
        "swapped": sent(1), "flipped": sent(2),
        "sound": {"frames": of(&all[0]), "read_relabelled": share((all[0][1] + all[0][2]) as usize, of(&all[0]))},
        "matrix": all,
    })
}

/// A phone's rate and view, as `--cases-out` gives them (null for IMUs).
fn camera_json(input: &Input) -> Value {
    match *input {
        Input::Phone {
            rate_hz, face_on, ..
        } => {
            json!({"rate_hz": rate_hz, "view": if face_on { "face_on" } else { "down_the_line" }})
        }
        Input::Imu { .. } => json!(null),
    }
}

fn case_json(clean: &Clean, case: &Case, o: &Outcome1) -> Value {
    json!({
        "source": clean.source.file_name().map(|n| n.to_string_lossy().into_owned()),
        "height_m": clean.body.skeleton.height(), "flaws": case.flaws, "input": case.input.row(),
        "seed": case.seed, "camera": camera_json(&case.input),
        "shown_cm": o.shown_m * 100.0, "found": o.found, "false_swings": o.false_swings, "timing_ms": o.timing_ms,
        "tempo_error": o.tempo_error, "backswing_z": o.backswing_z, "score": o.score, "first": o.first, "right_first": o.right_first, "cause_first": o.cause_first, "right_coach": o.right_coach,
        "any_advice": o.any_advice, "body_truth": o.body_truth, "body_named": o.body_named, "truths": o.truths, "body": o.body, "gaps": o.gaps, "error": o.error,
        "relabels": o.relabels,
    })
}

/// The table printed without `--json`.
fn table(doc: &Value) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "coaching benchmark: {} cases, {} bodies, sources {}",
        doc["cases"], doc["bodies"], doc["sources"]
    );
    let _ = writeln!(out, "input | found | coach | false | takeaway ms | top ms | impact ms | tempo err | covered | false tempo / body / any | recall@1 offset>=8cm / tempo / body | body named | score unflawed / 10-15cm / tempo 30-50%");
    let q = |v: &Value| {
        v["median"].as_f64().map_or("-".into(), |m| {
            format!("{m:.0} / {:.0}", v["p95"].as_f64().unwrap_or(f64::NAN))
        })
    };
    let sc = |v: &Value| v["mean"].as_f64().map_or("-".into(), |m| format!("{m:.1}"));
    for l in doc["levels"].as_array().into_iter().flatten() {
        let r = &l["recall_at_1"];
        let _ = writeln!(
            out,
            "{:>8} | {} | {} | {} | {} | {} | {} | {} | {} | {} / {} / {} | {} / {} / {} | {} | {} / {} / {}",
            l["input"].as_str().unwrap_or("-"),
            pct(&l["found"]),
            pct(&l["right_coach"]),
            l["false_swings"],
            q(&l["takeaway_ms"]),
            q(&l["top_ms"]),
            q(&l["impact_ms"]),
            l["tempo_ratio_error"]["median"]
                .as_f64()
                .map_or("-".into(), |m| format!("{:.1}%", m * 100.0)),
            pct(&l["backswing_covered"]),
            pct(&l["false_tempo"]),
            pct(&l["false_body"]),
            pct(&l["false_advice"]),
            pct(&r["offset_8cm"]),
            pct(&r["tempo"]),
            pct(&r["body"]),
            pct(&l["body_named"]["all"]),
            sc(&l["score"]["unflawed"]),
            sc(&l["score"]["offset_10_15cm"]),
            sc(&l["score"]["tempo_30_50pc"]),
        );
    }
    let _ = writeln!(
        out,
        "cause named first, of the body flaws that move a check or a gap past its tolerance: {}",
        Body::ALL
            .iter()
            .map(|b| serde_json::to_value(b)
                .ok()
                .and_then(|v| v.as_str().map(String::from))
                .unwrap_or_default())
            .collect::<Vec<_>>()
            .join(" / ")
    );
    for l in doc["levels"].as_array().into_iter().flatten() {
        let cells: Vec<String> = l["cause_first"]
            .as_object()
            .into_iter()
            .flatten()
            .map(|(_, v)| match (v["hits"].as_u64(), v["of"].as_u64()) {
                (Some(h), Some(n)) => format!("{h}/{n}"),
                _ => "-".into(),
            })
            .collect();
        let _ = writeln!(
            out,
            "{:>8} | {}",
            l["input"].as_str().unwrap_or("-"),
            cells.join(" / ")
        );
    }
    let _ = writeln!(
        out,
        "sequence gaps on unflawed swings, hips to chest | chest to lead arm: timed, error ms median / p95, uncertainty ms median, covered [90 %]; false sequence items"
    );
    for l in doc["levels"].as_array().into_iter().flatten() {
        let cells: Vec<String> = GAPS
            .iter()
            .map(|(first, then)| {
                let g = &l["gaps"][format!("{}_{}", first.name(), then.name())];
                format!(
                    "{}, {}, {:.0}, {}",
                    pct(&g["timed"]),
                    q(&g["error_ms"]),
                    g["uncertainty_ms"]["median"].as_f64().unwrap_or(f64::NAN),
                    pct(&g["covered"])
                )
            })
            .collect();
        let _ = writeln!(
            out,
            "{:>8} | {} | {}",
            l["input"].as_str().unwrap_or("-"),
            cells.join(" | "),
            pct(&l["false_sequence"])
        );
    }
    for metrics in [&KEY_METRICS[..], &MORE_METRICS[..]] {
        let _ = writeln!(
            out,
            "body metric error at P1-P10, median / p95, and the share within the report's ± 1.65 \
             uncertainties ({}):",
            metrics
                .iter()
                .map(|(name, unit, _, _)| format!("{name} {unit}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        for l in doc["levels"].as_array().into_iter().flatten() {
            let cells: Vec<String> = metrics
                .iter()
                .map(|(name, _, _, _)| {
                    let e = &l["body_error"][name]["error"];
                    let covered = pct(&l["body_error"][name]["coverage"]);
                    e["median"].as_f64().map_or("-".into(), |m| {
                        let p95 = e["p95"].as_f64().unwrap_or(f64::NAN);
                        format!("{m:.1} / {p95:.1} / {covered}")
                    })
                })
                .collect();
            let _ = writeln!(
                out,
                "{:>8} | {}",
                l["input"].as_str().unwrap_or("-"),
                cells.join(" | ")
            );
        }
    }
    out
}

/// The body metrics the benchmark measures besides [`KEY_METRICS`]: every other one the device
/// can measure (it tracks no club, so no shaft lean or wrist hinge). A head's shifts are NaN
/// where the skeleton has no head.
pub const MORE_METRICS: [KeyMetric; 9] = [
    ("pelvis_bend", "deg", DEG, |m| m.pelvis.bend),
    ("pelvis_side_bend", "deg", DEG, |m| m.pelvis.side_bend),
    ("thorax_sway", "cm", CM, |m| m.thorax_shift.sway * 100.0),
    ("thorax_thrust", "cm", CM, |m| m.thorax_shift.thrust * 100.0),
    ("thorax_lift", "cm", CM, |m| m.thorax_shift.lift * 100.0),
    ("head_sway", "cm", CM, |m| {
        m.head_shift.map_or(f32::NAN, |s| s.sway * 100.0)
    }),
    ("head_thrust", "cm", CM, |m| {
        m.head_shift.map_or(f32::NAN, |s| s.thrust * 100.0)
    }),
    ("head_lift", "cm", CM, |m| {
        m.head_shift.map_or(f32::NAN, |s| s.lift * 100.0)
    }),
    ("lead_arm", "deg", DEG, |m| m.lead_arm),
];

/// Every body metric the benchmark measures the error of.
fn measured_metrics() -> impl Iterator<Item = &'static KeyMetric> {
    KEY_METRICS.iter().chain(&MORE_METRICS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_io::csv;
    use std::f32::consts::TAU;

    /// The bench's IMU path at eight headings of the student's T-pose, 45° apart: seeds whose
    /// first draw (the heading, [`body_of`]) falls in each octant, the unflawed iron on the
    /// bundled T-pose, six IMUs with and without magnetometers.
    #[test]
    fn imu_cases_are_found_and_timed_at_every_heading() {
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures");
        let source = fixtures.join("golf_iron_60hz.csv");
        let motion = io::load(&source).unwrap();
        let body = csv::read(include_str!("../../../tests/fixtures/h36m17_tpose.csv")).unwrap();
        let clean = Clean::new(&source, 1, &motion, &body).unwrap();
        let octant = |seed: u64| {
            let heading = ChaCha8Rng::seed_from_u64(seed).random_range(0.0f32..TAU);
            (heading / (TAU / 8.0)) as usize
        };
        let mut seeds = [None; 8];
        for seed in 0.. {
            seeds[octant(seed)].get_or_insert(seed);
            if seeds.iter().all(Option::is_some) {
                break;
            }
        }
        for magnetometers in [true, false] {
            for seed in seeds.into_iter().flatten() {
                let case = Case {
                    clean: 0,
                    flaws: Vec::new(),
                    input: Input::Imu {
                        magnetometers,
                        worn: Worn::Six,
                        steel_club: false,
                    },
                    seed,
                };
                let outcome = run_case(&clean, &case, None).unwrap();
                let at = format!("octant {}, magnetometers {magnetometers}", octant(seed));
                assert!(outcome.found, "{at}: not found");
                let [_, top, impact] = outcome.timing_ms.unwrap();
                assert!(
                    top.abs() < 50.0 && impact.abs() < 50.0,
                    "{at}: {top} / {impact} ms"
                );
            }
        }
    }
}
