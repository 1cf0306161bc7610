//! `posecoach retarget`: the coach's motion on the student's skeleton.

use anyhow::Result;
use posecoach_adapters::io;
use serde_json::json;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// The coach's motion (.bvh, .c3d or .csv).
    #[arg(long)]
    coach: PathBuf,
    /// The student's T-pose: a one-row CSV, or any motion file whose skeleton is used.
    #[arg(long)]
    student_tpose: PathBuf,
    /// Where to write the retargeted motion (.bvh or .csv).
    #[arg(long)]
    out: PathBuf,
    /// Use the analytic retargeter (bone-direction copy); the only method until weights exist.
    #[arg(long)]
    analytic: bool,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<String> {
    let coach = io::load(&args.coach)?;
    let student = io::load(&args.student_tpose)?;
    let virtual_swing = coach
        .retarget_analytic(&student)
        .map_err(|(frame, e)| anyhow::anyhow!("coach frame {frame}: {e}"))?;
    io::save(&virtual_swing, &args.out)?;
    let summary = json!({
        "method": "analytic",
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
            "retargeted {} frames of {} ({} joints, {:.2} m) onto {} ({} joints, {:.2} m), root scale {:.3}\n",
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
