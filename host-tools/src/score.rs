//! `posecoach score`: a student's swing against the coach's, retargeted onto the student.

use crate::failure::NothingFound;
use crate::report::{to_json, to_text, write_report, ReportFormat};
use crate::swings::cut;
use crate::table::decimal;
use crate::{html, input, session, teacher};
use anyhow::{anyhow, bail, Context, Result};
use posecoach_core::band::Band;
use posecoach_core::config::MAX_SWING_FRAMES;
use posecoach_core::detector::DetectorConfig;
use posecoach_core::events::EventError;
use posecoach_core::joint::Joint;
use posecoach_core::score::{self, Report, ScoreError};
use posecoach_core::session::{JointTallies, Tendencies};
use posecoach_io::Motion;
use serde_json::{json, Value};
use std::fmt::Write;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// The coach's swing (.bvh, .c3d, .csv, .json, .pcr), or a bundled coach by name:
    /// `driver` or `iron`.
    #[arg(long)]
    coach: PathBuf,
    /// The student's swing (.bvh, .c3d, .csv or .json); more than once for a session: each
    /// swing is scored, then what they say together.
    #[arg(long, required = true)]
    student: Vec<PathBuf>,
    /// The student's T-pose; without it the skeleton comes from the (first) student's own
    /// frames.
    #[arg(long)]
    student_tpose: Option<PathBuf>,
    /// Retarget the coach with the analytic retargeter (bone-direction copy): the default
    /// without `--weights`.
    #[arg(long, conflicts_with = "weights")]
    analytic: bool,
    /// Retarget the coach with the learned retargeter in this teacher file or checkpoint (needs
    /// the `learn` feature).
    #[arg(long)]
    weights: Option<PathBuf>,
    /// Leave both swings as the retargeter makes them, off golf's contacts (planted feet, both
    /// hands on one grip, the club head at the ball: kept by default, the coach's as on the
    /// device).
    #[arg(long)]
    no_contacts: bool,
    /// DTW band radius in frames at the scoring rate.
    #[arg(long, default_value_t = Band::DEFAULT.radius)]
    band: u16,
    /// One band around the whole diagonal instead of one per phase between the events.
    #[arg(long)]
    global_band: bool,
    /// Both swings are resampled to this rate before scoring.
    #[arg(long, default_value_t = 60.0)]
    score_rate: f32,
    #[command(flatten)]
    input: input::Args,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Also write the report to this file: the HTML page (self-contained, for any browser)
    /// for a name ending in `.html` or `.htm`, the JSON for `.json`.
    #[arg(long)]
    report: Option<PathBuf>,
}

pub fn run(args: &Args) -> Result<String> {
    if !(args.score_rate.is_finite() && (10.0..=240.0).contains(&args.score_rate)) {
        bail!(
            "--score-rate {} must be between 10 and 240 Hz",
            args.score_rate
        );
    }
    if let Some(path) = &args.report {
        ReportFormat::of(path)?;
    }
    // The longest swing the scorer takes, at the scoring rate.
    // (A motion lasting `d` s holds `d · rate + 1` frames.)
    let longest_s = (MAX_SWING_FRAMES - 1) as f32 / args.score_rate;
    let coach = {
        let recording = args.input.load_coach(&args.coach)?;
        let mut swings = cut(&recording, longest_s);
        if swings.len() > 1 {
            eprintln!(
                "note: {}: {} swings; the first, at {:.1} s, is the coach's",
                args.coach.display(),
                swings.len(),
                swings[0].start_s
            );
        }
        swings.swap_remove(0).motion
    };
    let first = args.input.load(&args.student[0])?;
    // The student's body: the T-pose if given, else the skeleton measured from the (first)
    // swing. Both swings are compared on it, as rigid bones: the coach's retargeted, the
    // student's own re-expressed (bone-direction copy), so measurement wobble in bone lengths
    // is no fault.
    let body = match &args.student_tpose {
        Some(path) => args.input.load(path)?,
        None => first.clone(),
    };
    // Compared on what both swings have: a joint only one of them tracks is left out (the
    // virtual coach would otherwise carry a head top or a club its file never had).
    let (of_coach, of_student) = (coach.canonical_joints(), body.canonical_joints());
    let untracked = |have: &[Joint], lack: &[Joint], whose: &str| {
        let names: Vec<&str> = have
            .iter()
            .filter(|j| !lack.contains(j))
            .map(|j| j.name())
            .collect();
        (!names.is_empty()).then(|| {
            format!(
                "{} (the {whose}'s file does not track them)",
                names.join(", ")
            )
        })
    };
    let left_out: Vec<String> = [
        untracked(&of_student, &of_coach, "coach"),
        untracked(&of_coach, &of_student, "student"),
    ]
    .into_iter()
    .flatten()
    .collect();
    let body = body
        .only(|j| of_coach.contains(&j))
        .context("the student's skeleton on the coach's joints")?;
    // One pelvis for both: where one file makes it as the hips' midpoint and the other does
    // not, every swing is compared with its pelvis there.
    // (The learned retargeter takes the coach as its training did: not with it.)
    let at_hips = match (coach.pelvis_at_hips(), body.pelvis_at_hips()) {
        (Some(c), Some(s)) => c != s && args.weights.is_none(),
        _ => false,
    };
    let hips = |motion: &Motion| match at_hips {
        true => motion.with_pelvis_at_hips(),
        false => Ok(motion.clone()),
    };
    let body = hips(&body).context("the student's skeleton with its pelvis at its hips")?;
    if !left_out.is_empty() {
        eprintln!("note: not compared: {}", left_out.join("; "));
    }
    // Each keeps its own golf contacts as the device's virtual coach does (planted feet, both
    // hands on one grip, the club at the ball), which rigid bones of other lengths would lose.
    let contacts = |mut on: Motion, of: &Motion, who: &str| -> Result<Motion> {
        if !args.no_contacts {
            on.keep_contacts(of)
                .with_context(|| format!("the {who}'s contacts on the student's skeleton"))?;
        }
        Ok(on)
    };
    let on_body = |motion: &Motion, who: &str| {
        let on = hips(motion)
            .with_context(|| format!("the {who}'s pelvis at its hips"))?
            .retarget_analytic(&body)
            .map_err(|(f, e)| anyhow!("{who} frame {f} onto the student's skeleton: {e}"))?;
        contacts(on, motion, who)
    };
    let virtual_coach = match &args.weights {
        Some(path) => contacts(
            teacher::retarget(path, &coach, &body.skeleton)?,
            &coach,
            "coach",
        )?,
        None => on_body(&coach, "coach")?,
    };
    let virtual_coach = virtual_coach.resampled(args.score_rate)?;
    let band = Band {
        radius: args.band,
        anchored: !args.global_band,
    };
    let mut joints = vec![JointTallies::EMPTY; body.skeleton.len()];
    let mut session = Tendencies::new(&mut joints);
    let scored = |motion: &Motion, taken: &Taken, session: &mut Tendencies| {
        on_body(motion, "student")
            .and_then(|student| Ok(student.resampled(args.score_rate)?))
            .and_then(|student| {
                let report = score_swings(&student, &virtual_coach, band, session)?;
                Ok(html::Scored {
                    report,
                    skeleton: student.skeleton.clone(),
                    student: student.positions.clone(),
                    student_hz: student.rate_hz,
                    coach: virtual_coach.positions.clone(),
                    coach_hz: virtual_coach.rate_hz,
                })
            })
            .map_err(|e| match e.downcast_ref::<ScoreError>() {
                Some(ScoreError::Events {
                    student: true,
                    error: EventError::NoSwing,
                }) => anyhow::Error::new(NothingFound {
                    message: format!("{taken}: {e}"),
                    output: String::new(),
                }),
                Some(ScoreError::TooLong { .. }) => e.context(format!(
                    "{taken}: no swing was found to cut it at (a set-up, a swing and a finish \
                     held {SETTLE} s): cut the file to one swing of at most {longest_s:.1} s, or \
                     score at a lower --score-rate",
                    SETTLE = DetectorConfig::full_swing(1.0).settle_s
                )),
                _ => e.context(taken.to_string()),
            })
    };
    let mut swings = Vec::new();
    for (i, path) in args.student.iter().enumerate() {
        let recording = match i {
            0 => first.clone(),
            _ => args.input.load(path)?,
        };
        // Every swing of a recording (a file cut to one swing is kept whole).
        let parts = cut(&recording, longest_s);
        let several = parts.len() > 1;
        for part in parts {
            let taken = Taken {
                path,
                start_s: several.then_some(part.start_s),
            };
            let scored = scored(&part.motion, &taken, &mut session);
            swings.push((taken, scored));
        }
    }
    // One swing that cannot be scored is the command's error.
    if let [(_, Err(_))] = swings.as_slice() {
        if let Some((_, Err(e))) = swings.pop() {
            return Err(e);
        }
    }
    let files = |student: &Path| {
        json!({
            "coach": args.coach.display().to_string(),
            "student": student.display().to_string(),
            "student_tpose": args.student_tpose.as_ref().map(|p| p.display().to_string()),
            "weights": args.weights.as_ref().map(|p| p.display().to_string()),
        })
    };
    let reports: Vec<Value> = swings
        .iter()
        .map(|(taken, scored)| match scored {
            Ok(scored) => {
                let mut json = to_json(scored);
                // What was scored, and the rate every frame number counts at.
                json["files"] = files(taken.path);
                json["not_compared"] = json!(left_out);
                json["rate_hz"] = json!(decimal(scored.student_hz, 3));
                json
            }
            Err(e) => json!({"files": files(taken.path), "error": format!("{e:#}")}),
        })
        .collect();
    let json = match reports.as_slice() {
        [one] => one.clone(),
        _ => json!({
            "swings": swings.iter().zip(&reports).enumerate().map(|(i, ((taken, _), report))| {
                let mut entry = json!({"swing": i + 1, "file": taken.path.display().to_string()});
                if let Some(start) = taken.start_s {
                    entry["start_s"] = json!(decimal(start, 3));
                }
                match report.get("error") {
                    Some(error) => entry["error"] = error.clone(),
                    None => entry["report"] = report.clone(),
                }
                entry
            }).collect::<Vec<_>>(),
            "session": session::to_json(&session),
        }),
    };
    if let Some(path) = &args.report {
        let retargeter = match &args.weights {
            Some(w) => format!("learned retargeter {}", w.display()),
            None => "analytic retargeter".to_string(),
        };
        let mut notes = vec![format!("Coach: {}", args.coach.display())];
        notes.extend(
            args.student
                .iter()
                .map(|s| format!("Student: {}", s.display())),
        );
        notes.push(format!(
            "Coach retargeted onto the student by the {retargeter}"
        ));
        if !left_out.is_empty() {
            notes.push(format!("Not compared: {}", left_out.join("; ")));
        }
        let pages: Vec<html::Swing> = swings
            .iter()
            .map(|(taken, scored)| html::Swing {
                heading: format!("Swing of {taken}"),
                outcome: match scored {
                    Ok(scored) => Ok(scored.clone()),
                    Err(e) => Err(format!("{e:#}")),
                },
            })
            .collect();
        let range = html::session::section(&session, &pages);
        write_report(path, &json, || {
            html::page("posecoach swing report", &notes, range.as_ref(), &pages)
        })?;
    }
    if args.json {
        return Ok(format!("{json}\n"));
    }
    Ok(match swings.as_slice() {
        [(_, Ok(scored))] => to_text(scored),
        _ => {
            let mut text = String::new();
            for (i, (taken, scored)) in swings.iter().enumerate() {
                let _ = write!(text, "swing {} ({taken}):", i + 1);
                match scored {
                    Ok(scored) => {
                        text.push('\n');
                        text.push_str(&to_text(scored));
                    }
                    Err(e) => {
                        let _ = writeln!(text, " not scored: {e:#}");
                    }
                }
            }
            text.push_str(&session::to_text(&session));
            text
        }
    })
}

/// Which swing of which file: a file holding several names each by its start.
struct Taken<'a> {
    path: &'a Path,
    start_s: Option<f32>,
}

impl std::fmt::Display for Taken<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.path.display())?;
        match self.start_s {
            Some(start) => write!(f, ", the swing at {start:.1} s"),
            None => Ok(()),
        }
    }
}

/// Scores `student` against `coach`, both on the student's skeleton (the coach turned to face
/// the student's way), telling `sink` of it.
pub fn score_swings(
    student: &Motion,
    coach: &Motion,
    band: Band,
    sink: &mut dyn score::Sink,
) -> Result<Report> {
    let mut coach_positions = coach.positions.clone();
    let len = score::scratch_len(student.frames(), coach.frames());
    let (mut floats, mut bytes) = (vec![0.0; len.floats], vec![0u8; len.bytes]);
    Ok(score::score(
        &student.skeleton,
        &student.positions,
        student.rate_hz,
        &mut coach_positions,
        coach.rate_hz,
        band,
        (&mut floats, &mut bytes),
        sink,
    )?)
}
