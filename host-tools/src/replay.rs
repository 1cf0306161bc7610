//! `posecoach replay`: a recorded session through the device's pipeline, swing by swing.

use crate::failure::NothingFound;
use crate::{coaches, device_sim, html, report};
use anyhow::{Context, Result};
use posecoach_adapters::log::LogReader;
use posecoach_adapters::session::{Outcome, Session};
use posecoach_core::weights::Weights;
use serde_json::{json, Value};
use std::fmt::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The recorded session (.pclog).
    log: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Also write the report to this file: the HTML page for a name ending in `.html` or
    /// `.htm`, the JSON for `.json`.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Also write the frames the device sends back (a `SwingReport` and a `SessionReport` per
    /// scored swing, an `Ack` per set-up taken, a `Nack` per refused message), COBS-framed
    /// exactly as on the serial link.
    #[arg(long)]
    wire: Option<PathBuf>,
    /// Retarget coaches with these int8 weights (.pcw from `posecoach export`) as a device
    /// carrying them does (when the session's model rate is the network's); the analytic
    /// retargeter otherwise.
    #[arg(long)]
    weights: Option<PathBuf>,
}

/// What a replay found.
pub struct Replay {
    /// One entry per swing: where it is, and its report's JSON or why it was not scored.
    pub swings: Vec<Value>,
    /// Readable lines, one block per swing.
    pub text: String,
    /// Messages refused, in order.
    pub refused: Vec<String>,
    /// Decoder and stream counters.
    pub counters: Value,
    /// Every swing as the HTML report draws it.
    pub pages: Vec<html::Swing>,
    /// The frames the device sends back, in order, as on the serial link.
    pub wire: Vec<u8>,
    /// The range session after the last swing.
    pub session: RangeSession,
}

/// A replay's range session after its last swing, as each output tells it.
pub struct RangeSession {
    /// Its JSON.
    pub json: Value,
    /// Its lines.
    pub text: String,
    /// Its part of the page (none for one swing alone).
    pub page: Option<html::session::SessionSection>,
}

impl Replay {
    /// The JSON `--json` prints.
    pub fn to_json(&self) -> Value {
        json!({"swings": self.swings, "session": self.session.json, "refused": self.refused, "counters": self.counters})
    }
}

pub fn run(args: &Args) -> Result<String> {
    if let Some(path) = &args.report {
        report::ReportFormat::of(path)?;
    }
    let bytes =
        std::fs::read(&args.log).with_context(|| format!("reading {}", args.log.display()))?;
    let replay = coaches::with_network(args.weights.as_deref(), |weights| {
        replay(&bytes, weights).with_context(|| format!("replaying {}", args.log.display()))
    })?;
    let json = replay.to_json();
    if let Some(path) = &args.wire {
        std::fs::write(path, &replay.wire)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &args.report {
        let notes = [format!("Recorded session: {}", args.log.display())];
        report::write_report(path, &json, || {
            html::page(
                "posecoach session report",
                &notes,
                replay.session.page.as_ref(),
                &replay.pages,
            )
        })?;
    }
    let out = if args.json {
        format!("{json}\n")
    } else {
        let mut out = replay.text;
        out.push_str(&replay.session.text);
        for r in &replay.refused {
            let _ = writeln!(out, "refused: {r}");
        }
        let _ = writeln!(out, "counters: {}", replay.counters);
        out
    };
    // No swing scored: the output all the same, and the status says so.
    if replay.swings.is_empty() {
        return Err(NothingFound {
            message: format!(
                "{}: no swing found in {} frames read ({} messages refused){}",
                args.log.display(),
                replay.counters["frames_ok"],
                replay.refused.len(),
                match replay.counters["cut_short"].as_bool() {
                    Some(true) => "; the log ends inside a frame: it was cut short",
                    _ => "",
                }
            ),
            output: out,
        }
        .into());
    }
    Ok(out)
}

/// Replays `log` (a whole .pclog file) as a device would, with the int8 `network` if given.
///
/// # Errors
/// If the bytes are not a log.
pub fn replay(log: &[u8], network: Option<&Weights<'_>>) -> Result<Replay> {
    coaches::session(network, |session| replay_on(session, log))?
}

fn replay_on(session: &mut Session<'_>, log: &[u8]) -> Result<Replay> {
    // The bundled coaches' names, as CoachSelect numbers them.
    let names: Vec<String> = coaches::all()?
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    let mut reader = LogReader::new(log)?;
    let cut = reader.cut();
    let (mut swings, mut text, mut refused) = (Vec::new(), String::new(), Vec::new());
    let (mut pages, mut sent) = (Vec::new(), Vec::new());
    for message in reader.by_ref() {
        let rate_hz = session.config().model_rate_hz;
        session.handle(&message, |outcome| {
            if let Some(frame) = outcome.reply(&message).as_ref().and_then(device_sim::frame) {
                sent.extend(frame);
            }
            let (swing, result) = match outcome {
                Outcome::Scored {
                    swing,
                    report,
                    compared,
                } => (swing, Ok((report, compared))),
                Outcome::Unscored { swing, error } => (swing, Err(error)),
                Outcome::Refused(r) => return refused.push(r.to_string()),
                Outcome::Accepted | Outcome::Session { .. } => return,
            };
            let start_s = swing.start_us as f64 * 1e-6;
            let coach = names
                .get(usize::from(swing.coach))
                .map_or("?", String::as_str);
            let heading = format!(
                "swing {} at {start_s:.2} s ({} frames) against the {coach}",
                swing.number, swing.frames
            );
            let _ = write!(text, "{heading}:");
            let outcome = result
                .map(|(report, compared)| html::Scored::new(report, &compared))
                .map_err(|error| error.to_string());
            let mut entry = json!({
                "swing": swing.number, "start_s": (start_s * 1000.0).round() / 1000.0, "frames": swing.frames, "rate_hz": rate_hz,
                "coach": coach,
            });
            match &outcome {
                Ok(scored) => {
                    text.push('\n');
                    text.push_str(&report::to_text(scored));
                    entry["report"] = report::to_json(scored);
                }
                Err(error) => {
                    let _ = writeln!(text, " not scored: {error}");
                    entry["error"] = json!(error);
                }
            }
            pages.push(html::Swing { heading, outcome });
            swings.push(entry);
        });
    }
    let wire = reader.counters();
    let stream = session.stream_counters();
    let counters = json!({
        "frames_ok": wire.frames_ok, "crc_errors": wire.crc_errors, "malformed": wire.malformed, "versions": wire.versions,
        "overflows": wire.overflows,
        "pose_accepted": stream.accepted, "pose_duplicates": stream.duplicates,
        "pose_out_of_order": stream.out_of_order, "pose_gaps": stream.gaps,
        "pose_masked": stream.masked, "pose_swapped": stream.swapped, "pose_flipped": stream.flipped,
        "frames_at_model_rate": stream.emitted,
        "imu_stale": session.stale_samples(),
        "imu_saturated": session.saturated_samples(),
        "imu_disturbed": session.disturbed_samples(),
        "cut_short": cut,
    });
    if swings.is_empty() {
        text.push_str("no swing found\n");
    }
    let (saturated, disturbed) = (session.saturated_samples(), session.disturbed_samples());
    if saturated > 0 {
        let _ = writeln!(
            text,
            "{saturated} IMU samples had a gyro past its range: their segments turned faster \
             than measured, and angles after them read short"
        );
    }
    if disturbed > 0 {
        let _ = writeln!(
            text,
            "{disturbed} IMU samples read a magnetic field unlike the earth's the T-pose saw \
             (steel near the sensor, such as the club, or a fast turn's tilt): their sensors' \
             headings followed the gyros alone then, as without magnetometers"
        );
    }
    if cut {
        text.push_str(
            "the log ends inside a frame: it was cut short, and its last frame is lost\n",
        );
    }
    let tendencies = session.tendencies();
    let session = RangeSession {
        json: crate::session::to_json(tendencies),
        text: crate::session::to_text(tendencies),
        page: html::session::section(tendencies, &pages),
    };
    Ok(Replay {
        swings,
        text,
        refused,
        counters,
        pages,
        wire: sent,
        session,
    })
}
