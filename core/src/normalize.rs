//! Normalization as in the VPC paper: `X = p ⊕ v`.
//!
//! `p` holds every joint relative to its parent (the root's slot is zero: the root sits at the
//! origin), `v` is the root trajectory divided by the skeleton's height. [`denormalize`] is its
//! exact inverse.
//!
//! ```
//! use posecoach_core::format::Format;
//! use posecoach_core::normalize::{denormalize, normalize};
//! use posecoach_core::Vec3;
//!
//! let skeleton = Format::Coco17.default_skeleton().unwrap();
//! let mut frame = [Vec3::zeros(); 15];
//! skeleton.rest_positions(&mut frame);
//! let mut relative = [Vec3::zeros(); 15];
//! let v = normalize(&skeleton, &frame, &mut relative).unwrap();
//! let mut back = [Vec3::zeros(); 15];
//! denormalize(&skeleton, &relative, v, &mut back).unwrap();
//! assert!((back[3] - frame[3]).norm() < 1e-6);
//! ```

use crate::kinematics::{check_len, LengthError};
use crate::skeleton::Skeleton;
use crate::Vec3;

/// Writes parent-relative positions into `relative` and returns the root position divided by
/// the skeleton's height.
///
/// # Errors
/// [`LengthError`] if `frame` or `relative` is shorter than the skeleton.
pub fn normalize(
    skeleton: &Skeleton,
    frame: &[Vec3],
    relative: &mut [Vec3],
) -> Result<Vec3, LengthError> {
    check_len(skeleton, frame.len())?;
    check_len(skeleton, relative.len())?;
    relative[0] = Vec3::zeros();
    for k in 1..skeleton.len() {
        relative[k] = frame[k] - frame[skeleton.parent(k).unwrap_or(0)];
    }
    Ok(frame[0] / skeleton.height())
}

/// Rebuilds absolute positions from parent-relative ones and the normalized root trajectory.
///
/// # Errors
/// [`LengthError`] if `relative` or `out` is shorter than the skeleton.
pub fn denormalize(
    skeleton: &Skeleton,
    relative: &[Vec3],
    root: Vec3,
    out: &mut [Vec3],
) -> Result<(), LengthError> {
    check_len(skeleton, relative.len())?;
    check_len(skeleton, out.len())?;
    out[0] = root * skeleton.height();
    for k in 1..skeleton.len() {
        out[k] = out[skeleton.parent(k).unwrap_or(0)] + relative[k];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::MAX_JOINTS;
    use crate::format::Format;
    use proptest::prelude::*;

    const RELATIVE_TOLERANCE: f32 = 1e-6;

    proptest! {
        #[test]
        fn round_trip_is_exact_to_rounding(
            format in prop::sample::select(Format::BUILT_IN.to_vec()),
            points in prop::collection::vec(prop::array::uniform3(-5.0f32..5.0), MAX_JOINTS),
        ) {
            let skeleton = format.default_skeleton().unwrap();
            let frame: std::vec::Vec<Vec3> = points.iter().take(skeleton.len()).map(|&p| Vec3::from(p)).collect();
            let mut relative = [Vec3::zeros(); MAX_JOINTS];
            let v = normalize(&skeleton, &frame, &mut relative).unwrap();
            let mut back = [Vec3::zeros(); MAX_JOINTS];
            denormalize(&skeleton, &relative, v, &mut back).unwrap();
            let scale = frame.iter().map(|p| p.norm()).fold(1.0f32, f32::max);
            for (a, b) in frame.iter().zip(&back) {
                prop_assert!((a - b).norm() <= RELATIVE_TOLERANCE * scale);
            }
        }
    }
}
