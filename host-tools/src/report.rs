//! A scored swing as the host tools report it: the documented JSON, the text, and the file
//! `--report` writes. `score`, `replay` and `demo` all report through it.

use crate::failure::Usage;
use crate::html;
use crate::table::{decimal, peak_text, whole, with_spread, KEY_METRICS, PLUS_MINUS};
use anyhow::{Context, Result};
use posecoach_core::body::{Angles, Link, Metrics, Shift};
use posecoach_core::checks::BodyDeviation;
use posecoach_core::events::{Event, SwingEvents};
use posecoach_core::score::Advice;
use posecoach_core::sequence::GAP_TOLERANCE_S;
use serde_json::{json, Map, Value};
use std::fmt::Write;
use std::path::Path;

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
