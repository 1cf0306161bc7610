//! `posecoach score`: a student's swing against the coach's, retargeted onto the student.

use crate::failure::{NothingFound, Usage};
use crate::table::{peak_text, whole, with_spread, KEY_METRICS, PLUS_MINUS};
use crate::{html, input, session, teacher};
use anyhow::{anyhow, bail, Context, Result};
use posecoach_core::band::Band;
use posecoach_core::body::{Angles, Link, Metrics, Shift};
use posecoach_core::checks::BodyDeviation;
use posecoach_core::events::{Event, EventError, SwingEvents};
use posecoach_core::score::{self, Advice, Report, ScoreError};
use posecoach_core::sequence::GAP_TOLERANCE_S;
use posecoach_core::session::{JointTallies, Tendencies};
use posecoach_io::Motion;
use serde_json::{json, Map, Value};
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
    let coach = args.input.load_coach(&args.coach)?;
    let first = args.input.load(&args.student[0])?;
    // The student's body: the T-pose if given, else the skeleton measured from the (first)
    // swing. Both swings are compared on it, as rigid bones: the coach's retargeted, the
    // student's own re-expressed (bone-direction copy), so measurement wobble in bone lengths
    // is no fault.
    let body = match &args.student_tpose {
        Some(path) => args.input.load(path)?,
        None => first.clone(),
    };
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
        let on = motion
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
    let mut swings = Vec::new();
    for (i, path) in args.student.iter().enumerate() {
        let motion = match i {
            0 => first.clone(),
            _ => args.input.load(path)?,
        };
        let scored = on_body(&motion, "student")
            .and_then(|student| Ok(student.resampled(args.score_rate)?))
            .and_then(|student| {
                let report = score_swings(&student, &virtual_coach, band, &mut session)?;
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
                    message: format!("{}: {e}", path.display()),
                    output: String::new(),
                }),
                _ => e.context(path.display().to_string()),
            });
        swings.push((path, scored));
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
        .map(|(path, scored)| match scored {
            Ok(scored) => {
                let mut json = to_json(scored);
                // What was scored, and the rate every frame number counts at.
                json["files"] = files(path);
                json["rate_hz"] = json!(decimal(scored.student_hz, 3));
                json
            }
            Err(e) => json!({"files": files(path), "error": format!("{e:#}")}),
        })
        .collect();
    let json = match reports.as_slice() {
        [one] => one.clone(),
        _ => json!({
            "swings": swings.iter().zip(&reports).enumerate().map(|(i, ((path, _), report))| {
                let mut entry = json!({"swing": i + 1, "file": path.display().to_string()});
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
        let pages: Vec<html::Swing> = swings
            .iter()
            .map(|(path, scored)| html::Swing {
                heading: format!("Swing of {}", path.display()),
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
            for (i, (path, scored)) in swings.iter().enumerate() {
                let _ = write!(text, "swing {} ({}):", i + 1, path.display());
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

/// What a report file holds, by its name's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReportFormat {
    /// `.html`, `.htm`: the page.
    Html,
    /// `.json`: the JSON `--json` prints.
    Json,
}

impl ReportFormat {
    /// The format of a report named `path`.
    ///
    /// # Errors
    /// [`Usage`] for any other extension, before any work is done.
    pub fn of(path: &Path) -> Result<ReportFormat> {
        let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        match extension.to_ascii_lowercase().as_str() {
            "html" | "htm" => Ok(ReportFormat::Html),
            "json" => Ok(ReportFormat::Json),
            _ => Err(Usage(format!(
                "--report {}: a report is a page (.html) or JSON (.json); name the file so",
                path.display()
            ))
            .into()),
        }
    }
}

/// Writes `path`: the page `html` makes, or `json`, as its extension says ([`ReportFormat`]).
///
/// # Errors
/// For another extension, or if the file cannot be written.
pub fn write_report(path: &Path, json: &Value, html: impl FnOnce() -> String) -> Result<()> {
    let text = match ReportFormat::of(path)? {
        ReportFormat::Html => html(),
        ReportFormat::Json => format!("{json:#}\n"),
    };
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
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

fn events(e: &SwingEvents) -> Value {
    Value::Object(
        e.iter()
            .map(|(ev, f)| (ev.name().to_string(), json!(f)))
            .collect::<Map<_, _>>(),
    )
}

/// Each event's time in frames, between frames (the address's is the takeaway).
fn times(e: &SwingEvents) -> Value {
    Value::Object(
        Event::ALL
            .iter()
            .filter_map(|&ev| {
                e.time(ev)
                    .map(|t| (ev.name().to_string(), json!(decimal(t, 2))))
            })
            .collect::<Map<_, _>>(),
    )
}

/// `value` rounded to `places` decimals, as reports print a measured number: to what it means
/// (a score to 0.1 point, seconds to the ms), not as a widened `f32`'s digits.
pub fn decimal(value: f32, places: i32) -> f64 {
    let scale = 10f64.powi(places);
    (f64::from(value) * scale).round() / scale
}

/// One swing's kinematic sequence: each link's peak speed (degrees per second) and its time
/// after the top (ms), each with its uncertainty and whether the noise swamps it ([`peak_text`];
/// none for the coach's, taken as exact), and the order they peak in.
fn sequence_json(sequence: &html::Sequenced, exact: bool) -> Value {
    let Some((k, top, hz)) = sequence else {
        return Value::Null;
    };
    let round = |v: f32| f64::from(v).round();
    let ms = |frames: f32| frames / hz * 1000.0;
    json!({
        "peaks": Link::ALL.iter().filter_map(|&l| k.peak(l).map(|p| {
            let mut peak = json!({"link": l.name(), "speed_deg_s": round(p.speed),
                                  "ms_after_top": round(ms(p.time - top))});
            if !exact {
                let u = p.uncertainty;
                peak["speed_uncertainty_deg_s"] = json!(u.map(|u| round(u.speed)));
                peak["ms_uncertainty"] = json!(u.map(|u| round(ms(u.time))));
                peak["swamped"] = json!(peak_text(&p, *top, *hz, false).1);
            }
            peak
        })).collect::<Vec<_>>(),
        "order": k.order().iter().map(|l| l.name()).collect::<Vec<_>>(),
    })
}

/// One swing's metrics at one position: degrees and centimetres to a tenth.
fn metrics_json(m: &Metrics) -> Value {
    let tenth = |v: f32| (f64::from(v) * 10.0).round() / 10.0;
    let angles = |a: &Angles| json!({"turn": tenth(a.turn), "bend": tenth(a.bend), "side_bend": tenth(a.side_bend)});
    let cm = |s: &Shift| json!({"sway": tenth(s.sway * 100.0), "thrust": tenth(s.thrust * 100.0), "lift": tenth(s.lift * 100.0)});
    json!({
        "pelvis": angles(&m.pelvis), "thorax": angles(&m.thorax),
        "x_factor": tenth(m.x_factor), "spine": tenth(m.spine),
        "pelvis_shift_cm": cm(&m.pelvis_shift), "thorax_shift_cm": cm(&m.thorax_shift),
        "head_shift_cm": m.head_shift.as_ref().map(cm),
        "lead_arm": tenth(m.lead_arm), "lead_elbow": tenth(m.lead_elbow),
        "shaft_lean": m.shaft_lean.map(tenth), "wrist_hinge": m.wrist_hinge.map(tenth),
    })
}

/// The report in the documented JSON shape.
pub fn to_json(s: &html::Scored) -> Value {
    let r = &s.report;
    let [student, coach] = s.sequences();
    let cm = |m: f32| (f64::from(m) * 1000.0).round() / 10.0;
    json!({
        "score": decimal(r.score, 1),
        "dtw": {"distance": decimal(r.distance, 4), "normalized": decimal(r.normalized, 4), "path": r.path.iter().map(|&(i, j)| [i, j]).collect::<Vec<_>>()},
        "events": {"student": events(&r.student_events), "coach": events(&r.coach_events),
                   "student_times": times(&r.student_events), "coach_times": times(&r.coach_events),
                   "lead_side": format!("{:?}", r.student_events.lead).to_lowercase(),
                   "kind": format!("{:?}", r.student_events.kind).to_lowercase()},
        "tempo": {
            "student_ratio": decimal(r.student_tempo_ratio, 2),
            "coach_ratio": decimal(r.coach_tempo_ratio, 2),
            "student_pause_s": decimal(r.student_events.pause() / s.student_hz, 3),
            "coach_pause_s": decimal(r.coach_events.pause() / s.coach_hz, 3),
            "phases": r.tempo.iter().map(|t| json!({
                "phase": t.phase.name(), "student_s": decimal(t.student_s, 3), "coach_s": decimal(t.coach_s, 3),
                "ratio": decimal(t.ratio, 3), "ratio_uncertainty": decimal(t.ratio_uncertainty, 3),
                "verdict": t.verdict.name()})).collect::<Vec<_>>(),
        },
        "spatial": r.spatial.iter().map(|d| json!({
            "event": d.event.name(), "joint": d.joint.name(), "distance_cm": cm(d.distance_m),
            "uncertainty_cm": cm(d.uncertainty_m),
            "direction": d.direction.name(),
            "offset_cm": {"toward_target": cm(d.offset_m[0]), "toward_ball": cm(d.offset_m[1]), "up": cm(d.offset_m[2])}})).collect::<Vec<_>>(),
        "body_checks": r.body.iter().map(|b| {
            let (unit, scale) = unit(b);
            let tenth = |v: f32| (f64::from(v * scale) * 10.0).round() / 10.0;
            json!({
                "position": b.check.position.name(), "measure": b.check.measure.name(), "unit": unit,
                "student": tenth(b.student), "coach": tenth(b.coach),
                "uncertainty": tenth(b.uncertainty), "tolerance": tenth(b.check.measure.tolerance()),
                "severity": (f64::from(Advice::severity_of_check(b)) * 100.0).round() / 100.0,
            })
        }).collect::<Vec<_>>(),
        "advice": r.advice.iter().map(Advice::to_string).collect::<Vec<_>>(),
        "root_held": r.root_held,
        "kinematic_sequence": {"student": sequence_json(&student, false), "coach": sequence_json(&coach, true),
            "gaps": r.gaps.iter().map(|g| {
                let ms = |v: f32| (f64::from(v) * 1000.0).round();
                json!({
                    "first": g.first.name(), "then": g.then.name(),
                    "student_ms": ms(g.student_s), "coach_ms": ms(g.coach_s),
                    "uncertainty_ms": ms(g.uncertainty_s), "tolerance_ms": ms(GAP_TOLERANCE_S),
                    "advice": Advice::is_clear(g),
                })
            }).collect::<Vec<_>>()},
        "input_noise_mm": r.input.noise_m().map(|m| decimal(m * 1000.0, 1)),
        "positions": s.body_table().iter().map(|row| {
            let p = row.position;
            json!({
                "position": p.name(), "moment": p.moment(),
                "student_frame": r.student_events.frame(p), "coach_frame": r.coach_events.frame(p),
                "student": row.student.as_ref().map(metrics_json),
                "student_uncertainty": row.spread.as_ref().map(metrics_json),
                "swamped": KEY_METRICS.iter().filter(|m| with_spread(row, m).1).map(|m| m.0).collect::<Vec<_>>(),
                "coach": row.coach.as_ref().map(metrics_json)})
        }).collect::<Vec<_>>(),
    })
}

/// A body check's unit in reports and the factor from its own (degrees or metres) to it.
fn unit(b: &BodyDeviation) -> (&'static str, f32) {
    match b.check.measure.in_degrees() {
        true => ("deg", 1.0),
        false => ("cm", 100.0),
    }
}

/// The report as readable lines.
pub fn to_text(s: &html::Scored) -> String {
    let r = &s.report;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "score: {:.1} / 100 (mean joint distance {:.1} cm along the alignment)",
        r.score,
        r.normalized * 100.0
    );
    let _ = writeln!(
        out,
        "tempo (backswing:downswing): you {:.1}:1, coach {:.1}:1",
        r.student_tempo_ratio, r.coach_tempo_ratio
    );
    for t in &r.tempo {
        let _ = writeln!(
            out,
            "  {:<15} you {:.2} s, coach {:.2} s, x{:.2} ± {:.2}  {}",
            t.phase.name(),
            t.student_s,
            t.coach_s,
            t.ratio,
            t.ratio_uncertainty,
            t.verdict.name()
        );
    }
    let pauses = (
        r.student_events.pause() / s.student_hz,
        r.coach_events.pause() / s.coach_hz,
    );
    if pauses.0 > 0.0 || pauses.1 > 0.0 {
        let _ = writeln!(
            out,
            "  pause at the top: you {:.2} s, coach {:.2} s (part of the backswing)",
            pauses.0, pauses.1
        );
    }
    let _ = writeln!(out, "events (frame: you / coach):");
    for (e, f) in r.student_events.iter() {
        let coach = r
            .coach_events
            .frame(e)
            .map_or(String::from("-"), |c| c.to_string());
        let _ = writeln!(out, "  {:<19} {f:>4} / {coach}", e.name());
    }
    let _ = writeln!(
        out,
        "body at each position, you (coach): degrees; shifts since address in cm"
    );
    let _ = write!(out, "  {:<4}", "");
    for (name, _, _, _) in &KEY_METRICS {
        let _ = write!(out, " {:>18}", name.replace('_', " "));
    }
    out.push('\n');
    for row in s.body_table() {
        let _ = write!(out, "  {:<4}", row.position.name());
        for metric in &KEY_METRICS {
            let (you, swamped) = with_spread(&row, metric);
            let mark = if swamped { "?" } else { "" };
            let coach = whole(row.coach, metric.3);
            let _ = write!(out, " {:>18}", format!("{you}{mark} ({coach})"));
        }
        out.push('\n');
    }
    let _ = writeln!(out, "  {}", PLUS_MINUS);
    let [you, coach] = s.sequences();
    if you.is_some() || coach.is_some() {
        let _ = writeln!(
            out,
            "kinematic sequence (peak speed in degrees/s at ms after the top):"
        );
        for (who, sequence) in [("you", you), ("coach", coach)] {
            let Some((k, top, hz)) = sequence else {
                continue;
            };
            let _ = write!(out, "  {who:<6}");
            for l in Link::ALL {
                if let Some(p) = k.peak(l) {
                    let (text, swamped) = peak_text(&p, top, hz, who == "coach");
                    let mark = if swamped { "?" } else { "" };
                    let _ = write!(out, " {} {text}{mark},", l.name());
                }
            }
            let order: Vec<_> = k.order().iter().map(|l| l.name()).collect();
            let _ = writeln!(out, " peaking {}", order.join(" > "));
        }
        for g in &r.gaps {
            let _ = writeln!(
                out,
                "  {} to {}: you {:.0} ± {:.0} ms (coach {:.0}), tolerance {:.0}{}",
                g.first.name(),
                g.then.name(),
                g.student_s * 1000.0 + 0.0,
                g.uncertainty_s * 1000.0,
                g.coach_s * 1000.0 + 0.0,
                GAP_TOLERANCE_S * 1000.0,
                if Advice::is_clear(g) { "  past it" } else { "" }
            );
        }
    }
    if r.root_held {
        let _ = writeln!(out, "{}", html::ROOT_HELD);
    }
    if !r.body.is_empty() {
        let _ = writeln!(
            out,
            "body checks, change since address: you ± uncertainty (coach), tolerance"
        );
        for b in &r.body {
            let (unit, scale) = unit(b);
            let _ = writeln!(
                out,
                "  {:<4} {:<14} {:>5.0} ± {:<3.0} ({:.0}) {unit}, {:.0}{}",
                b.check.position.name(),
                b.check.measure.name(),
                b.student * scale + 0.0,
                b.uncertainty * scale,
                b.coach * scale + 0.0,
                b.check.measure.tolerance() * scale,
                if Advice::severity_of_check(b) > 1.0 {
                    "  past it"
                } else {
                    ""
                }
            );
        }
    }
    if r.advice.is_empty() {
        let _ = writeln!(out, "advice: nothing to fix: you match the coach.");
    } else {
        let _ = writeln!(out, "advice, most important first:");
        for a in &r.advice {
            let _ = writeln!(out, "  - {a}");
        }
    }
    out
}
