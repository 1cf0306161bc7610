//! `posecoach reference`: a coach's swing stored as the device stores it (a `.pcr` blob, its
//! positions in 16-bit millimetres).

use crate::input;
use anyhow::{bail, Context, Result};
use posecoach_core::reference::Units;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The coach's swing (.csv, .json, .bvh, .c3d, .pcr), or a bundled coach by name:
    /// `driver` or `iron`.
    #[arg(long)]
    coach: PathBuf,
    /// The name it is stored under (at most 32 bytes); the file's stem by default.
    #[arg(long)]
    name: Option<String>,
    /// Where to write it (.pcr).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    input: input::Args,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<String> {
    let motion = args.input.load_coach(&args.coach)?;
    if motion.rate_hz <= 0.0 {
        bail!(
            "{} is a single pose; a coach reference is a swing",
            args.coach.display()
        );
    }
    let name = match &args.name {
        Some(name) => name.clone(),
        None => args
            .coach
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
    };
    let bytes = motion
        .to_reference(&name, Units::Millimetres)
        .with_context(|| format!("storing {}", args.coach.display()))?;
    std::fs::write(&args.out, &bytes).with_context(|| format!("writing {}", args.out.display()))?;
    let (joints, frames) = (motion.skeleton.len(), motion.frames());
    if args.json {
        let doc = serde_json::json!({
            "out": args.out.display().to_string(), "name": name, "joints": joints,
            "frames": frames, "rate_hz": crate::table::decimal(motion.rate_hz, 3), "bytes": bytes.len(),
        });
        return Ok(format!("{doc}\n"));
    }
    Ok(format!(
        "wrote coach reference `{name}` ({joints} joints, {frames} frames at {} Hz, {} bytes) to {}\n",
        crate::table::decimal(motion.rate_hz, 3),
        bytes.len(),
        args.out.display()
    ))
}
