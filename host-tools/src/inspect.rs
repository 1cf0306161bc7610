//! `posecoach inspect`: what a motion file or a weights file holds: int8 weights (the
//! device's, `core::weights`) or float weights (a teacher, a distilled network or a training
//! checkpoint, `posecoach_teachfile`; read without the `learn` feature).

use crate::input;
use crate::table::decimal;
use anyhow::{Context, Result};
use posecoach_core::skeleton::Segment;
use posecoach_core::weights::{self, Dense, Table, Weights};
use posecoach_io::{Motion, Reading};
use posecoach_teachfile::{self as teachfile, Header};
use serde_json::{json, Value};
use std::io::Read;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A motion file (.bvh, .c3d, .csv, .json, .pcr), int8 weights (.pcw from `posecoach export`) or
    /// float weights (.pcw from `train --teacher` or `distill --distilled`, or a .pcckpt
    /// checkpoint).
    file: PathBuf,
    #[command(flatten)]
    input: input::Args,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// Bytes enough to tell a weights file by its magic.
const MAGIC_BYTES: u64 = 16;

pub fn run(args: &Args) -> Result<String> {
    let context = || format!("reading {}", args.file.display());
    // A motion file is read once, by its reader: only a weights file is read here whole.
    let mut head = Vec::new();
    std::fs::File::open(&args.file)
        .and_then(|f| f.take(MAGIC_BYTES).read_to_end(&mut head))
        .with_context(context)?;
    let weights = head.starts_with(&weights::MAGIC) || teachfile::is_float_weights(&head);
    if !weights {
        let (motion, reading) = args.input.load_read(&args.file)?;
        let mut report = describe(&args.file, &motion);
        if let Some(r) = &reading {
            report["reading"] = reading_json(r);
        }
        return Ok(if args.json {
            format!("{report}\n")
        } else {
            text(&report)
        });
    }
    let bytes = std::fs::read(&args.file).with_context(context)?;
    if bytes.starts_with(&weights::MAGIC) {
        let header = weights_header(&bytes).with_context(context)?;
        return Ok(match args.json {
            true => format!("{header}\n"),
            false => weights_text(&header),
        });
    }
    let report = float_weights(&bytes).with_context(context)?;
    Ok(match args.json {
        true => format!("{report}\n"),
        false => float_text(&report),
    })
}

fn describe(path: &std::path::Path, motion: &Motion) -> Value {
    let skeleton = &motion.skeleton;
    let name = |k: usize| motion.names[k].as_str();
    let joints: Vec<Value> = (0..skeleton.len())
        .map(|k| {
            json!({
                "name": name(k),
                "canonical": skeleton.joint(k).map(|j| j.name()),
                "parent": skeleton.parent(k).map(name),
                "bone_m": skeleton.parent(k).map(|_| decimal(skeleton.offset(k).norm(), 4)),
            })
        })
        .collect();
    let segments: serde_json::Map<String, Value> = Segment::ALL
        .iter()
        .map(|&s| {
            let members: Vec<&str> = (0..skeleton.len())
                .filter(|&k| skeleton.segment_contains(s, k))
                .map(name)
                .collect();
            (s.name().to_string(), json!(members))
        })
        .collect();
    let missing: serde_json::Map<String, Value> = motion
        .missing_per_joint()
        .iter()
        .enumerate()
        .filter(|(_, &c)| c > 0)
        .map(|(k, &c)| (name(k).to_string(), json!(c)))
        .collect();
    json!({
        "file": path.display().to_string(),
        "format": skeleton.format().name(),
        "frames": motion.frames(),
        "rate_hz": decimal(motion.rate_hz, 3),
        "duration_s": decimal(motion.duration_s(), 3),
        "height_m": decimal(skeleton.height(), 3),
        "joints": joints,
        "segments": segments,
        "missing": {"total": motion.missing.iter().filter(|&&m| m).count(), "per_joint": missing},
        "swings": crate::swings::found(motion).iter().map(|&(start, duration)| {
            json!({"start_s": decimal(start, 3), "duration_s": decimal(duration, 3)})
        }).collect::<Vec<_>>(),
    })
}

/// How a keypoint file was read, as JSON.
fn reading_json(r: &Reading) -> Value {
    let midpoints: Vec<Value> = r
        .midpoints
        .iter()
        .map(|(joint, a, b)| json!({"joint": joint.name(), "of": [a, b]}))
        .collect();
    json!({
        "landmarks": r.landmarks.title(),
        "midpoints": midpoints,
        "units": r.units.0.symbol(),
        "units_given": r.units.1,
        "up": r.up.0.to_string(),
        "up_given": r.up.1,
        "time": r.clock.0.title(),
        "time_column": r.clock.1,
        "skipped_frames": r.skipped,
        "on_its_feet": r.on_its_feet,
        "not_read": r.ignored,
    })
}

fn text(r: &Value) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    _ = writeln!(out, "file:     {}", r["file"].as_str().unwrap_or(""));
    _ = writeln!(out, "format:   {}", r["format"].as_str().unwrap_or(""));
    if let Some(reading) = r.get("reading") {
        let given = |key: &str| match reading[key].as_bool() {
            Some(true) => "given",
            _ => "detected",
        };
        let field = |key: &str| reading[key].as_str().unwrap_or("").to_string();
        _ = writeln!(out, "read as:  {}", field("landmarks"));
        for m in reading["midpoints"]
            .as_array()
            .map(Vec::as_slice)
            .unwrap_or(&[])
        {
            let of: Vec<&str> = m["of"]
                .as_array()
                .map(|o| o.iter().filter_map(Value::as_str).collect())
                .unwrap_or_default();
            _ = writeln!(
                out,
                "  {} = midpoint of {}",
                m["joint"].as_str().unwrap_or(""),
                of.join(" and ")
            );
        }
        _ = writeln!(
            out,
            "units:    {} ({})",
            field("units"),
            given("units_given")
        );
        _ = writeln!(out, "up:       {} ({})", field("up"), given("up_given"));
        match reading["time_column"].as_str() {
            Some(column) => _ = writeln!(out, "time:     {} (column `{column}`)", field("time")),
            None => _ = writeln!(out, "time:     {}", field("time")),
        }
        if reading["on_its_feet"] == true {
            _ = writeln!(
                out,
                "placed:   on its planted feet (the hips were held at one place in every frame)"
            );
        }
        if let Some(n) = reading["skipped_frames"].as_u64().filter(|&n| n > 0) {
            _ = writeln!(out, "skipped:  {n} frames (kept as missing samples)");
        }
        let not_read: Vec<&str> = reading["not_read"]
            .as_array()
            .map(|a| a.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default();
        if !not_read.is_empty() {
            _ = writeln!(out, "not read: {}", not_read.join(", "));
        }
    }
    let frames = r["frames"].as_u64().unwrap_or(0);
    match r["rate_hz"].as_f64().unwrap_or(0.0) {
        rate if rate > 0.0 => {
            _ = writeln!(
                out,
                "frames:   {frames} at {rate:.1} Hz ({:.2} s)",
                r["duration_s"].as_f64().unwrap_or(0.0)
            )
        }
        _ => _ = writeln!(out, "frames:   {frames} (a T-pose)"),
    }
    if let Some(swings) = r["swings"].as_array().filter(|s| !s.is_empty()) {
        let at: Vec<String> = swings
            .iter()
            .map(|s| format!("{:.1} s", s["start_s"].as_f64().unwrap_or(0.0)))
            .collect();
        _ = writeln!(
            out,
            "swings:   {} found, at {}",
            swings.len(),
            at.join(", ")
        );
    }
    _ = writeln!(
        out,
        "height:   {:.3} m",
        r["height_m"].as_f64().unwrap_or(0.0)
    );
    let joints = r["joints"].as_array().map(Vec::as_slice).unwrap_or(&[]);
    _ = writeln!(out, "joints:   {}", joints.len());
    for (k, j) in joints.iter().enumerate() {
        _ = writeln!(
            out,
            "  {k:>2} {:<16} {:<15} parent {:<16} {}",
            j["name"].as_str().unwrap_or(""),
            j["canonical"].as_str().unwrap_or("-"),
            j["parent"].as_str().unwrap_or("-"),
            j["bone_m"]
                .as_f64()
                .map_or(String::new(), |b| format!("bone {b:.3} m")),
        );
    }
    _ = writeln!(out, "segments:");
    if let Some(segments) = r["segments"].as_object() {
        for (name, members) in segments {
            let members: Vec<&str> = members
                .as_array()
                .map(|m| m.iter().filter_map(Value::as_str).collect())
                .unwrap_or_default();
            _ = writeln!(out, "  {name:<10} {}", members.join(", "));
        }
    }
    let missing = &r["missing"];
    match missing["total"].as_u64().unwrap_or(0) {
        0 => _ = writeln!(out, "missing:  none"),
        total => {
            _ = writeln!(
                out,
                "missing:  {total} samples (held from the nearest valid sample)"
            );
            if let Some(per) = missing["per_joint"].as_object() {
                for (name, count) in per {
                    _ = writeln!(out, "  {name:<16} {count} frames");
                }
            }
        }
    }
    out
}

/// The header of a weights blob and its layers' shapes, as JSON.
///
/// # Errors
/// If the blob is not sound ([`posecoach_core::weights::WeightsError`]).
pub fn weights_header(bytes: &[u8]) -> Result<Value> {
    let mut words = vec![0u32; bytes.len().div_ceil(4)];
    bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
    let w = Weights::from_bytes(&bytemuck::cast_slice::<u32, u8>(&words)[..bytes.len()])?;
    let (h, a) = (w.header(), w.architecture());
    let layers: Vec<Value> = Dense::ALL
        .iter()
        .map(|&l| {
            json!({"name": l.name(), "outputs": l.outputs(a), "inputs": l.inputs(a),
                   "bias_rows": l.bias_rows()})
        })
        .collect();
    let tables: Vec<&str> = Table::ALL.iter().map(|t| t.name()).collect();
    let s = &h.scales;
    Ok(json!({
        "kind": "int8 weights",
        "bytes": bytes.len(),
        "version": h.version,
        "architecture": {"features": a.features, "heads": a.heads, "kernel": a.kernel,
                          "window": a.window, "segments": a.segments, "rate_hz": a.rate_hz},
        "scales": {"motion": s.motion, "hidden": s.hidden, "joints": s.joints,
                   "context": s.context, "segments": s.segments, "down_1": s.down_1,
                   "down_2": s.down_2, "fused": s.fused, "up_1": s.up_1, "up_2": s.up_2,
                   "decoder": s.decoder},
        "training": {"name": h.training.name.as_str(), "steps": h.training.steps,
                     "seed": h.training.seed, "calibration_windows": h.training.calibration_windows,
                     "formats": h.training.formats.iter().map(|f| f.name()).collect::<Vec<_>>()},
        "layers": layers,
        "tables": tables,
        "parameters": Dense::ALL.iter().map(|l| l.outputs(a) * l.inputs(a)).sum::<usize>(),
    }))
}

/// [`weights_header`] as text.
pub fn weights_text(h: &Value) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let a = &h["architecture"];
    _ = writeln!(
        out,
        "kind:     int8 weights, format version {}, {} bytes",
        h["version"], h["bytes"]
    );
    _ = writeln!(
        out,
        "network:  d = {} per segment, {} heads, kernel {}, {}-frame windows at {} Hz, {} segments",
        a["features"], a["heads"], a["kernel"], a["window"], a["rate_hz"], a["segments"]
    );
    let t = &h["training"];
    _ = writeln!(
        out,
        "training: {} ({} steps, seed {}), scales from {} golf windows, formats {}",
        t["name"].as_str().unwrap_or(""),
        t["steps"],
        t["seed"],
        t["calibration_windows"],
        t["formats"].as_array().map_or(String::new(), |f| f
            .iter()
            .filter_map(Value::as_str)
            .collect::<Vec<_>>()
            .join(", "))
    );
    _ = writeln!(out, "scales:");
    if let Some(scales) = h["scales"].as_object() {
        for (name, v) in scales {
            _ = writeln!(out, "  {name:<9} {v}");
        }
    }
    _ = writeln!(out, "layers:   {} int8 weights", h["parameters"]);
    for l in h["layers"].as_array().map(Vec::as_slice).unwrap_or(&[]) {
        _ = writeln!(
            out,
            "  {:<17} {:>3} x {:<3} bias rows {}",
            l["name"].as_str().unwrap_or(""),
            l["outputs"],
            l["inputs"],
            l["bias_rows"]
        );
    }
    out
}

/// A float weights file's kind, version, header, parts and checksum, as JSON; a distilling
/// checkpoint's also the header of the teacher file it carries.
///
/// # Errors
/// If the file is not sound ([`posecoach_teachfile::Error`]: damaged, of an old version, a
/// header word beyond its bound, parts that do not fit).
pub fn float_weights(bytes: &[u8]) -> Result<Value> {
    let file = teachfile::decode(bytes)?;
    let parts: Vec<Value> = file
        .kind
        .parts()
        .iter()
        .zip(&file.parts)
        .map(|(name, p)| json!({"name": name, "bytes": p.len()}))
        .collect();
    let mut report = json!({
        "kind": "float weights",
        "holds": file.kind.name(),
        "version": teachfile::VERSION,
        "bytes": bytes.len(),
        "header": header_json(&file.header),
        "parts": parts,
        "checksum": {"algorithm": "CRC-32/ISO-HDLC", "value": format!("{:#010x}", file.crc),
                     "ok": true},
    });
    if file.kind == teachfile::Kind::Distilling {
        // The teacher file it distills, one level down (a file inside it is not opened).
        report["teacher_file"] = match file.parts.last().map(|p| teachfile::decode(p)) {
            Some(Ok(teacher)) => json!({"holds": teacher.kind.name(),
                                        "header": header_json(&teacher.header)}),
            Some(Err(e)) => json!({"error": e.to_string()}),
            None => Value::Null,
        };
    }
    Ok(report)
}

fn header_json(h: &Header) -> Value {
    json!({
        "step": h.step, "seed": h.seed, "batch": h.batch,
        "features": h.features, "heads": h.heads, "kernel": h.kernel,
        "switches": h.switches_on().collect::<Vec<_>>(),
        "learning_rate": h.learning_rate,
        "prior": teachfile::PRIORS.get(h.prior as usize).copied().unwrap_or("?"),
    })
}

/// [`float_weights`] as text.
pub fn float_text(r: &Value) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let network = |h: &Value| {
        format!(
            "d = {} per segment, {} heads, kernel {}, prior {}",
            h["features"],
            h["heads"],
            h["kernel"],
            h["prior"].as_str().unwrap_or("")
        )
    };
    let training = |h: &Value| {
        let losses: Vec<&str> = h["switches"]
            .as_array()
            .map(|s| s.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default();
        format!(
            "{} steps, seed {}, batch {}, learning rate {}, losses beyond reconstruction: {}",
            h["step"],
            h["seed"],
            h["batch"],
            h["learning_rate"],
            match losses.is_empty() {
                true => "none".to_string(),
                false => losses.join(", "),
            }
        )
    };
    let h = &r["header"];
    _ = writeln!(
        out,
        "kind:     float weights ({}), format version {}, {} bytes",
        r["holds"].as_str().unwrap_or(""),
        r["version"],
        r["bytes"]
    );
    _ = writeln!(out, "network:  {}", network(h));
    _ = writeln!(out, "training: {}", training(h));
    let parts = r["parts"].as_array().map(Vec::as_slice).unwrap_or(&[]);
    _ = writeln!(out, "parts:    {}", parts.len());
    for p in parts {
        _ = writeln!(
            out,
            "  {:<24} {:>9} bytes",
            p["name"].as_str().unwrap_or(""),
            p["bytes"]
        );
    }
    let t = &r["teacher_file"];
    if let Some(e) = t["error"].as_str() {
        _ = writeln!(out, "teacher:  not sound: {e}");
    } else if !t.is_null() {
        _ = writeln!(
            out,
            "teacher:  {}; {}",
            network(&t["header"]),
            training(&t["header"])
        );
    }
    let c = &r["checksum"];
    _ = writeln!(
        out,
        "checksum: {} {}, {}",
        c["algorithm"].as_str().unwrap_or(""),
        c["value"].as_str().unwrap_or(""),
        match c["ok"].as_bool() {
            Some(true) => "matches",
            _ => "does not match",
        }
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: Header = Header {
        step: 12,
        seed: 3,
        batch: 8,
        features: 16,
        heads: 2,
        kernel: 3,
        switches: 0b00101,
        learning_rate: 1e-3,
        prior: 0,
    };

    #[test]
    fn a_distilling_checkpoint_shows_its_parts_and_the_teacher_it_carries() {
        let teacher = teachfile::encode(
            &Header {
                features: 32,
                prior: 1,
                ..HEADER
            },
            &[vec![1u8; 10]],
        )
        .unwrap();
        let parts = [vec![2u8; 5], vec![3; 6], vec![4; 7], vec![5; 8], teacher];
        let bytes = teachfile::encode(&HEADER, &parts).unwrap();
        let r = float_weights(&bytes).unwrap();
        assert_eq!(r["holds"], "distilling checkpoint");
        let names: Vec<&str> = r["parts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["name"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            [
                "network",
                "discriminator",
                "network optimizer",
                "discriminator optimizer",
                "teacher file"
            ]
        );
        assert_eq!(r["header"]["switches"], json!(["cycle", "adversarial"]));
        assert_eq!(r["teacher_file"]["header"]["features"], 32);
        assert_eq!(r["teacher_file"]["header"]["prior"], "rotations");
        let text = float_text(&r);
        assert!(
            text.contains("float weights (distilling checkpoint), format version 3"),
            "{text}"
        );
        assert!(text.contains("teacher:  d = 32 per segment"), "{text}");
        assert!(
            text.contains("losses beyond reconstruction: cycle, adversarial"),
            "{text}"
        );

        // A damaged teacher inside a sound checkpoint is named, not opened.
        let mut parts = parts;
        parts[4][20] ^= 1;
        let r = float_weights(&teachfile::encode(&HEADER, &parts).unwrap()).unwrap();
        let error = r["teacher_file"]["error"].as_str().unwrap();
        assert!(error.starts_with("damaged"), "{error}");
        assert!(float_text(&r).contains("teacher:  not sound: damaged"));
    }

    #[test]
    fn a_checkpoint_has_four_named_parts() {
        let parts = [vec![2u8; 5], vec![3; 6], vec![4; 7], vec![5; 8]];
        let r = float_weights(&teachfile::encode(&HEADER, &parts).unwrap()).unwrap();
        assert_eq!(r["holds"], "checkpoint");
        assert_eq!(r["parts"][3]["name"], "discriminator optimizer");
        assert_eq!(r["parts"][3]["bytes"], 8);
        assert!(r["teacher_file"].is_null());
        assert!(!float_text(&r).contains("teacher:"));
    }
}
