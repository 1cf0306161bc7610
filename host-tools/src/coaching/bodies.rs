//! Bodies of other statures and proportions than the bundled 1.75 m T-pose.

use anyhow::{Context, Result};
use posecoach_core::skeleton::Segment;
use posecoach_core::Vec3;
use posecoach_io::{csv, Motion};

/// Shortest and tallest stature, metres.
pub const STATURES_M: (f32, f32) = (1.50, 1.95);
/// Stature of the bundled T-pose, metres.
pub const STANDARD_STATURE_M: f32 = 1.75;
/// Largest change of the arms', legs' and spine's lengths against the stature's share, ±.
pub const PROPORTION: f32 = 0.08;

/// `n` T-poses (H3.6M keypoints): statures spread evenly from 1.50 to 1.95 m, each with its
/// arms, legs and spine (with the head) lengthened or shortened by up to 8 % before the whole is
/// scaled back to the stature, in a pattern that gives every body other proportions.
///
/// # Errors
/// Only if the bundled T-pose were damaged.
pub fn bodies(n: usize) -> Result<Vec<Motion>> {
    let standard = csv::read(include_str!("../../../tests/fixtures/h36m17_tpose.csv"))
        .context("bundled T-pose")?;
    let skeleton = &standard.skeleton;
    (0..n)
        .map(|i| {
            let stature = if n > 1 {
                STATURES_M.0 + (STATURES_M.1 - STATURES_M.0) * i as f32 / (n - 1) as f32
            } else {
                1.75
            };
            // Three proportions per body from an additive recurrence (golden ratio steps),
            // each in -1..1.
            let phase = |k: f32| {
                let x = (0.5 + (i as f32 + 1.0) * 0.618_034 * k).fract();
                2.0 * x - 1.0
            };
            let (arms, legs, spine) = (phase(1.0), phase(2.0), phase(3.0));
            let factor = |s: Segment| match s {
                Segment::LeftArm | Segment::RightArm => 1.0 + PROPORTION * arms,
                Segment::LeftLeg | Segment::RightLeg => 1.0 + PROPORTION * legs,
                Segment::Spine | Segment::Head => 1.0 + PROPORTION * spine,
            };
            let lengths: Vec<f32> = (0..skeleton.len())
                .map(|k| skeleton.offset(k).norm() * factor(skeleton.bone_segment(k)))
                .collect();
            let shaped = skeleton.with_bone_lengths(&lengths)?;
            // Skeleton height (feet to the top of the head, by bone lengths) over stature, as
            // in the standard T-pose.
            let scale = stature * skeleton.height() / STANDARD_STATURE_M / shaped.height();
            let scaled: Vec<f32> = lengths.iter().map(|l| l * scale).collect();
            let body = skeleton.with_bone_lengths(&scaled)?;
            let mut rest = vec![Vec3::zeros(); body.len()];
            body.rest_positions(&mut rest);
            // Feet on the ground, as in the standard T-pose.
            let lift = standard
                .positions
                .iter()
                .map(|p| p.y)
                .fold(f32::INFINITY, f32::min)
                - rest.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
            for p in &mut rest {
                p.y += lift;
            }
            Ok(Motion {
                skeleton: body,
                names: standard.names.clone(),
                rate_hz: 0.0,
                missing: vec![false; rest.len()],
                positions: rest,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bodies_standard_height() -> f32 {
        csv::read(include_str!("../../../tests/fixtures/h36m17_tpose.csv"))
            .unwrap()
            .skeleton
            .height()
    }

    #[test]
    fn statures_span_the_range_and_proportions_differ() {
        let bodies = bodies(8).unwrap();
        let standard = bodies_standard_height();
        let statures: Vec<f32> = bodies
            .iter()
            .map(|b| b.skeleton.height() / standard * STANDARD_STATURE_M)
            .collect();
        assert!(
            (statures[0] - 1.50).abs() < 1e-3 && (statures[7] - 1.95).abs() < 1e-3,
            "{statures:?}"
        );
        let feet = |b: &Motion| {
            b.positions
                .iter()
                .map(|p| p.y)
                .fold(f32::INFINITY, f32::min)
        };
        assert!(bodies
            .iter()
            .all(|b| (feet(b) - feet(&bodies[0])).abs() < 1e-5));
        let leg_share: Vec<f32> = bodies
            .iter()
            .map(|b| b.skeleton.leg_length() / b.skeleton.height())
            .collect();
        let spread = leg_share.iter().copied().fold(f32::NEG_INFINITY, f32::max)
            - leg_share.iter().copied().fold(f32::INFINITY, f32::min);
        assert!(spread > 0.03, "{leg_share:?}");
    }
}
