//! `posecoach tpose`: a format's standard T-pose scaled to a height, as a student file.

use anyhow::{bail, Result};
use posecoach_core::format::Format;
use posecoach_core::skeleton::Skeleton;
use posecoach_io::{self as io, Motion};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Keypoint format: cmu31, bandai22, h36m17, coco17, blazepose33, smpl24, golf, canonical.
    #[arg(long, default_value = "canonical")]
    format: String,
    /// Height in metres (as `inspect` measures it: leg chain plus spine-to-head chain).
    #[arg(long, default_value_t = 1.75)]
    height: f32,
    /// Where to write it (.csv or .bvh).
    #[arg(long)]
    out: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// `format`'s standard T-pose scaled to `height` metres, as a one-row motion (rate 0).
///
/// # Errors
/// If the format's standard skeleton cannot be built at that size.
pub fn standard(format: Format, height: f32) -> Result<Motion> {
    let standard = Skeleton::standard(format)?;
    let scale = height / standard.height();
    let mut positions = vec![posecoach_core::Vec3::zeros(); standard.len()];
    standard.rest_positions(&mut positions);
    positions.iter_mut().for_each(|p| *p *= scale);
    let parents: Vec<Option<usize>> = (0..standard.len()).map(|k| standard.parent(k)).collect();
    let skeleton = Skeleton::from_rest_positions(format, &parents, &positions, standard.joints())?;
    let names = match format {
        Format::Canonical => (0..skeleton.len())
            .map(|k| skeleton.joint(k).map_or("", |j| j.name()).to_string())
            .collect(),
        _ => format.joints().iter().map(|j| j.name.to_string()).collect(),
    };
    Ok(Motion {
        missing: vec![false; positions.len()],
        skeleton,
        names,
        rate_hz: 0.0,
        positions,
    })
}

pub fn run(args: &Args) -> Result<String> {
    let Some(format) = Format::from_name(&args.format).filter(|&f| f != Format::Custom) else {
        bail!("unknown format `{}`: expected one of cmu31, bandai22, h36m17, coco17, blazepose33, smpl24, golf, canonical", args.format);
    };
    if !(0.5..=2.5).contains(&args.height) {
        bail!("height {} m is outside 0.5..2.5 m", args.height);
    }
    let motion = standard(format, args.height)?;
    io::save(&motion, &args.out)?;
    if args.json {
        let doc = serde_json::json!({
            "out": args.out.display().to_string(), "format": format.to_string(),
            "height_m": motion.skeleton.height(), "joints": motion.skeleton.len(),
        });
        return Ok(format!("{doc}\n"));
    }
    Ok(format!(
        "wrote a {} T-pose, {:.3} m tall, to {}\n",
        format,
        motion.skeleton.height(),
        args.out.display()
    ))
}
