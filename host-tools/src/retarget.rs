//! `posecoach retarget`: the coach's motion on the student's skeleton.

use crate::failure::Usage;
use crate::{input, teacher};
use anyhow::Result;
use posecoach_io as io;
use serde_json::json;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The coach's motion (.bvh, .c3d, .csv, .json, .pcr), or a bundled coach by name:
    /// `driver` or `iron`.
    #[arg(long)]
    coach: PathBuf,
    /// The student's T-pose: a one-row CSV, or any motion file whose skeleton is used.
    #[arg(long)]
    student_tpose: PathBuf,
    /// Where to write the retargeted motion (.bvh or .csv).
    #[arg(long)]
    out: PathBuf,
    /// Use the analytic retargeter (bone-direction copy): the default without `--weights`.
    #[arg(long, conflicts_with = "weights")]
    analytic: bool,
    /// Use the learned retargeter in this teacher file or checkpoint (`posecoach train`; needs
    /// the `learn` feature).
    #[arg(long)]
    weights: Option<PathBuf>,
    /// Leave the motion as the retargeter makes it, off golf's contacts (planted feet, both
    /// hands on one grip, the club head at the ball: kept by default).
    #[arg(long)]
    no_contacts: bool,
    #[command(flatten)]
    input: input::Args,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<String> {
    let written = args.out.extension().and_then(|e| e.to_str());
    if !written.is_some_and(|e| e.eq_ignore_ascii_case("bvh") || e.eq_ignore_ascii_case("csv")) {
        return Err(Usage(format!(
            "--out {}: a retargeted motion is written as .bvh or .csv",
            args.out.display()
        ))
        .into());
    }
    let coach = args.input.load_coach(&args.coach)?;
    let student = args.input.load(&args.student_tpose)?;
    let (mut virtual_swing, method) = match &args.weights {
        Some(path) => (
            teacher::retarget(path, &coach, &student.skeleton)?,
            "teacher",
        ),
        None => (
            match (coach.pelvis_at_hips(), student.pelvis_at_hips()) {
                // The student's format makes the pelvis as the hips' midpoint: the coach's
                // is put there too (bone directions are copied).
                (Some(false), Some(true)) => coach.with_pelvis_at_hips()?,
                _ => coach.clone(),
            }
            .retarget_analytic(&student)
            .map_err(|(frame, e)| anyhow::anyhow!("coach frame {frame}: {e}"))?,
            "analytic",
        ),
    };
    if !args.no_contacts {
        virtual_swing
            .keep_contacts(&coach)
            .map_err(|e| anyhow::anyhow!("the coach's contacts on the student: {e}"))?;
    }
    io::save(&virtual_swing, &args.out)?;
    let summary = json!({
        "method": method,
        "contacts": !args.no_contacts,
        "weights": args.weights.as_ref().map(|p| p.display().to_string()),
        "coach": {"file": args.coach.display().to_string(), "format": coach.skeleton.format().name(),
                  "joints": coach.skeleton.len(), "frames": coach.frames(), "height_m": coach.skeleton.height()},
        "student": {"file": args.student_tpose.display().to_string(), "format": student.skeleton.format().name(),
                    "joints": student.skeleton.len(), "height_m": student.skeleton.height()},
        "root_scale": student.skeleton.leg_length() / coach.skeleton.leg_length(),
        "out": args.out.display().to_string(),
    });
    Ok(if args.json {
        format!("{summary}\n")
    } else {
        format!(
            "retargeted ({method}{}) {} frames of {} ({} joints, {:.2} m) onto {} ({} joints, {:.2} m), root scale {:.3}\n",
            if args.no_contacts { "" } else { ", golf's contacts kept" },
            coach.frames(),
            args.coach.display(),
            coach.skeleton.len(),
            coach.skeleton.height(),
            args.student_tpose.display(),
            student.skeleton.len(),
            student.skeleton.height(),
            summary["root_scale"].as_f64().unwrap_or(1.0),
        ) + &format!("wrote {}\n", args.out.display())
    })
}
