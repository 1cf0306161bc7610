//! `posecoach inspect`: what a motion file holds.

use anyhow::Result;
use posecoach_adapters::io::{self, Motion};
use posecoach_core::skeleton::Segment;
use serde_json::{json, Value};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A .bvh, .c3d or .csv file.
    file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<String> {
    let motion = io::load(&args.file)?;
    let report = describe(&args.file, &motion);
    Ok(if args.json {
        format!("{report}\n")
    } else {
        text(&report)
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
                "bone_m": skeleton.parent(k).map(|_| skeleton.offset(k).norm()),
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
        "rate_hz": motion.rate_hz,
        "duration_s": motion.duration_s(),
        "height_m": skeleton.height(),
        "joints": joints,
        "segments": segments,
        "missing": {"total": motion.missing.iter().filter(|&&m| m).count(), "per_joint": missing},
    })
}

fn text(r: &Value) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    _ = writeln!(out, "file:     {}", r["file"].as_str().unwrap_or(""));
    _ = writeln!(out, "format:   {}", r["format"].as_str().unwrap_or(""));
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
