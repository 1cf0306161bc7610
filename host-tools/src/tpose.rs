//! `posecoach tpose`: a format's standard T-pose scaled to a height, as a student file.

use anyhow::{bail, Context, Result};
use posecoach_core::format::{Format, Source};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
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
    let mut positions = vec![Vec3::zeros(); standard.len()];
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

/// Each keypoint of `format` placed on `motion` (its standard T-pose, one frame): a joint's
/// own keypoint where it is one; both keypoints of a joint made as their midpoint (BlazePose's
/// ears for the head) at that joint; a keypoint no joint reads (a nose, an eye, a heel, a
/// thumb) at the joint it belongs to by its name (the head, that side's hand, that side's
/// ankle). A profile of `format` is these keypoints, so the device rebuilds the same joints.
pub fn keypoints(format: Format, motion: &Motion) -> Vec<(&'static str, Vec3)> {
    let names = format.keypoints();
    let joints = format.joints();
    let frame = motion.frame(0);
    let mut placed: Vec<Option<Vec3>> = vec![None; names.len()];
    // Direct keypoints first, so that a midpoint's ends that are joints keep their places.
    for (k, j) in joints.iter().enumerate() {
        if let Source::Keypoint(i) = j.source {
            placed[usize::from(i)] = Some(frame[k]);
        }
    }
    for (k, j) in joints.iter().enumerate() {
        if let Source::Mid(a, b) = j.source {
            for i in [a, b] {
                placed[usize::from(i)].get_or_insert(frame[k]);
            }
        }
    }
    let joint_at = |name: &str| joints.iter().position(|j| j.name == name).map(|k| frame[k]);
    names
        .iter()
        .zip(placed)
        .map(|(&name, at)| {
            let side = if name.starts_with("left") {
                "left"
            } else {
                "right"
            };
            let belongs = if name.contains("heel") {
                format!("{side}_ankle")
            } else if ["pinky", "index", "thumb"].iter().any(|f| name.contains(f)) {
                format!("{side}_hand")
            } else {
                "head".to_string()
            };
            let at = at
                .or_else(|| joint_at(&belongs))
                .or_else(|| joint_at("head"))
                .unwrap_or_else(Vec3::zeros);
            (name, at)
        })
        .collect()
}

/// `points` as a one-row keypoint CSV (time 0, metres).
fn keypoint_csv(points: &[(&str, Vec3)]) -> String {
    let mut header = String::from("time");
    let mut row = String::from("0");
    for (name, p) in points {
        header.push_str(&format!(",{name}_x,{name}_y,{name}_z"));
        row.push_str(&format!(",{},{},{}", p.x, p.y, p.z));
    }
    format!("{header}\n{row}\n")
}

pub fn run(args: &Args) -> Result<String> {
    let Some(format) = Format::from_name(&args.format).filter(|&f| f != Format::Custom) else {
        bail!("unknown format `{}`: expected one of cmu31, bandai22, h36m17, coco17, blazepose33, smpl24, golf, canonical", args.format);
    };
    if !(0.5..=2.5).contains(&args.height) {
        bail!("height {} m is outside 0.5..2.5 m", args.height);
    }
    let motion = standard(format, args.height)?;
    // A keypoint format whose keypoints are not its joints (BlazePose's 33 landmarks make 19
    // joints) is written as its keypoints: what a profile of that format carries.
    let as_keypoints = format != Format::Canonical
        && format.joints().len() != format.keypoints().len()
        && args
            .out
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let points = keypoints(format, &motion);
    if as_keypoints {
        std::fs::write(&args.out, keypoint_csv(&points))
            .with_context(|| format!("writing {}", args.out.display()))?;
    } else {
        io::save(&motion, &args.out)?;
    }
    let written = if as_keypoints {
        points.len()
    } else {
        motion.skeleton.len()
    };
    if args.json {
        let doc = serde_json::json!({
            "out": args.out.display().to_string(), "format": format.to_string(),
            "height_m": motion.skeleton.height(), "joints": motion.skeleton.len(),
            "columns": if as_keypoints { "keypoints" } else { "joints" }, "written": written,
        });
        return Ok(format!("{doc}\n"));
    }
    Ok(format!(
        "wrote a {} T-pose, {:.3} m tall, to {} ({written} {})\n",
        format,
        motion.skeleton.height(),
        args.out.display(),
        if as_keypoints { "keypoints" } else { "joints" }
    ))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A profile written as a format's keypoints gives back, through the format's own joint
    /// table (as the device reads a profile), the T-pose's joints: all but a midpoint of two
    /// other joints' keypoints (COCO's pelvis between its hips), which the keypoints place
    /// where the format defines it.
    #[test]
    fn every_format_writes_the_keypoints_its_profile_needs() {
        for format in Format::BUILT_IN {
            let motion = standard(format, 1.7).unwrap();
            let points = keypoints(format, &motion);
            assert_eq!(points.len(), format.keypoints().len(), "{format}");
            let at: Vec<Vec3> = points.iter().map(|p| p.1).collect();
            let mut joints = vec![Vec3::zeros(); format.joints().len()];
            format.map_keypoints(&at, &mut joints).unwrap();
            let direct = |i: u8| {
                format
                    .joints()
                    .iter()
                    .any(|j| j.source == Source::Keypoint(i))
            };
            for (k, (j, made)) in format.joints().iter().zip(&joints).enumerate() {
                let between_joints =
                    matches!(j.source, Source::Mid(a, b) if direct(a) && direct(b));
                let d = (made - motion.frame(0)[k]).norm();
                assert!(
                    between_joints || d < 1e-5,
                    "{format}: {} off by {d} m",
                    j.name
                );
            }
        }
    }
}
