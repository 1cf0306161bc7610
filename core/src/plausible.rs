//! Human limits a body and its motion must keep. A skeleton or a swing outside them is a
//! corrupt file, a wrong unit or a broken sensor, not a golfer: it is refused, not scored.
//!
//! The limits are wide on purpose: they catch what no person can be (a 44 km stature, a joint
//! crossing a room between two frames), never an unusual golfer. They apply to the body's
//! joints: a tracked club is longer than half a child's stature, and its head, at up to 70 m/s
//! and often occluded at impact, jumps between captured samples.

use crate::joint::Joint;
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::Vec3;

/// Shortest stature accepted, metres: below the shortest adults recorded (about 0.55 m).
pub const MIN_STATURE_M: f32 = 0.5;
/// Tallest stature accepted, metres: above the tallest person recorded (2.72 m).
pub const MAX_STATURE_M: f32 = 2.75;
/// Longest bone accepted, as a share of the stature: the longest human bone, the femur, is
/// about 27 % of it, and no segment of a body is half of it.
pub const MAX_BONE_SHARE: f32 = 0.5;
/// Fastest a body joint may move between two frames, m/s: ten times what the hands reach in
/// a tour swing (under 10 m/s at impact), leaving room for keypoint noise at high rates.
pub const MAX_SPEED_M_S: f32 = 100.0;

/// Why a body or motion is beyond human limits.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Implausible {
    /// A stature (metres, [`Skeleton::height`]) outside [`MIN_STATURE_M`] to [`MAX_STATURE_M`].
    Stature(f32),
    /// Joint `joint`'s bone (from its parent) is `metres` long, more than [`MAX_BONE_SHARE`] of
    /// the stature.
    Bone {
        /// The bone's child joint (skeleton index).
        joint: usize,
        /// Its length.
        metres: f32,
    },
    /// Joint `joint` moved at `speed` m/s (past [`MAX_SPEED_M_S`]) into frame `frame`.
    Speed {
        /// Skeleton index.
        joint: usize,
        /// The frame it arrived at.
        frame: usize,
        /// Metres per second.
        speed: f32,
    },
}

impl core::fmt::Display for Implausible {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Implausible::Stature(m) => write!(
                f,
                "a stature of {m} m is outside the human range of {MIN_STATURE_M} to \
                 {MAX_STATURE_M} m (wrong units or corrupt joints?)"
            ),
            Implausible::Bone { joint, metres } => write!(
                f,
                "joint {joint}'s bone is {metres} m long, more than {MAX_BONE_SHARE} of the \
                 stature: a corrupt joint"
            ),
            Implausible::Speed {
                joint,
                frame,
                speed,
            } => write!(
                f,
                "joint {joint} moves at {speed} m/s into frame {frame}, faster than the \
                 {MAX_SPEED_M_S} m/s no body part reaches: a corrupt sample"
            ),
        }
    }
}

/// Whether skeleton joint `k` belongs to the body (not to a tracked club).
fn of_body(skeleton: &Skeleton, k: usize) -> bool {
    !matches!(skeleton.joint(k), Some(Joint::ClubGrip | Joint::ClubHead))
}

/// Checks `skeleton`'s stature and every body bone against the human limits.
///
/// # Errors
/// The first [`Implausible`] found: the stature, then the bones in joint order.
pub fn body(skeleton: &Skeleton) -> Result<(), Implausible> {
    let stature = skeleton.height();
    if !(MIN_STATURE_M..=MAX_STATURE_M).contains(&stature) {
        return Err(Implausible::Stature(stature));
    }
    (1..skeleton.len())
        .filter(|&k| of_body(skeleton, k))
        .try_for_each(|joint| {
            let metres = norm(&skeleton.offset(joint));
            match metres <= MAX_BONE_SHARE * stature {
                true => Ok(()),
                false => Err(Implausible::Bone { joint, metres }),
            }
        })
}

/// Checks the speed of every body joint of `skeleton` in `positions` (frames of
/// `skeleton.len()` joints) at `rate_hz` between successive frames where both samples were
/// captured (`missing`, when given, flags the rest).
///
/// # Errors
/// The first [`Implausible::Speed`] found, in frame order.
pub fn motion(
    skeleton: &Skeleton,
    positions: &[Vec3],
    missing: Option<&[bool]>,
    rate_hz: f32,
) -> Result<(), Implausible> {
    let joints = skeleton.len();
    if joints == 0 || rate_hz.is_nan() || rate_hz <= 0.0 {
        return Ok(());
    }
    let captured = |i: usize| missing.is_none_or(|m| !m.get(i).copied().unwrap_or(true));
    let mut frames = positions.chunks_exact(joints).enumerate();
    let Some((_, mut previous)) = frames.next() else {
        return Ok(());
    };
    for (frame, now) in frames {
        for joint in (0..joints).filter(|&k| of_body(skeleton, k)) {
            let (i, j) = ((frame - 1) * joints + joint, frame * joints + joint);
            if !(captured(i) && captured(j)) {
                continue;
            }
            let speed = norm(&(now[joint] - previous[joint])) * rate_hz;
            // (A NaN sample is refused too.)
            if speed.is_nan() || speed > MAX_SPEED_M_S {
                return Err(Implausible::Speed {
                    joint,
                    frame,
                    speed,
                });
            }
        }
        previous = now;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;

    #[test]
    fn a_standard_body_passes_and_a_scaled_one_does_not() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        assert_eq!(body(&skeleton), Ok(()));
        let n = skeleton.len();
        for (scale, ok) in [
            (0.0, false),
            (0.25, false),
            (0.33, true),
            (1.5, true),
            (1.6, false),
            (1e20, false),
        ] {
            let lengths: [f32; 17] = core::array::from_fn(|k| scale * norm(&skeleton.offset(k)));
            let scaled = skeleton.with_bone_lengths(&lengths[..n]).unwrap();
            assert_eq!(
                body(&scaled).is_ok(),
                ok,
                "scale {scale}: {:?}",
                body(&scaled)
            );
        }
    }

    #[test]
    fn one_long_bone_is_named() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let n = skeleton.len();
        let wrist = (1..n)
            .find(|&k| skeleton.joint(k) == Some(crate::joint::Joint::LeftWrist))
            .unwrap();
        let lengths: [f32; 17] = core::array::from_fn(|k| match k == wrist {
            true => 32.0,
            false => norm(&skeleton.offset(k)),
        });
        let broken = skeleton.with_bone_lengths(&lengths[..n]).unwrap();
        let e = body(&broken).unwrap_err();
        assert!(
            matches!(e, Implausible::Bone { joint, metres } if joint == wrist && (metres - 32.0).abs() < 1e-3),
            "{e:?}"
        );
    }

    #[test]
    fn a_body_joint_jumping_between_frames_is_refused_unless_a_sample_is_missing() {
        // Three frames at 100 Hz: the left hip jumps 2 m into frame 2 (200 m/s).
        let skeleton = Skeleton::standard(Format::Canonical).unwrap();
        let n = skeleton.len();
        let hip = skeleton.index_of(Joint::LeftHip).unwrap();
        let mut p = [Vec3::zeros(); 3 * 22];
        p[2 * n + hip] = Vec3::new(2.0, 0.0, 0.0);
        let jump = Implausible::Speed {
            joint: hip,
            frame: 2,
            speed: 200.0,
        };
        assert_eq!(motion(&skeleton, &p[..3 * n], None, 100.0), Err(jump));
        let mut missing = [false; 3 * 22];
        missing[2 * n + hip] = true;
        assert_eq!(
            motion(&skeleton, &p[..3 * n], Some(&missing[..3 * n]), 100.0),
            Ok(())
        );
        // 0.9 m in 1/100 s is 90 m/s: within the limit; NaN is not.
        p[2 * n + hip] = Vec3::new(0.9, 0.0, 0.0);
        assert_eq!(motion(&skeleton, &p[..3 * n], None, 100.0), Ok(()));
        p[2 * n + hip] = Vec3::new(f32::NAN, 0.0, 0.0);
        assert!(motion(&skeleton, &p[..3 * n], None, 100.0).is_err());
    }
}
