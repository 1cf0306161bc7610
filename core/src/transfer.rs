//! The rotation transfer: the coach's joint rotations, measured from its format's standard
//! T-pose, applied to the student's bones in theirs.
//!
//! Both skeletons are first re-rested ([`Skeleton::standard_rest`]): every bone turned to its
//! format's standard T-pose direction, its length kept. A T-pose a student was measured in
//! gives the bones' lengths and nothing else (a phone's 3-8° of posture error in it moves
//! nothing), and a coach file's own zero pose (a BVH's hanging arms) does not turn the motion.
//! Each frame, inverse kinematics on the coach's re-rested skeleton gives every bone's global
//! rotation (its direction exact, its twist the one that best aligns its children,
//! [`kinematics::inverse`]); each student bone takes its counterpart's rotation (joints
//! correspond as for the analytic retargeter; a joint without a counterpart keeps its
//! parent's), so the student's bones keep their lengths and turn as the coach's turn. The root
//! moves along the coach's root trajectory scaled by the ratio of the root-to-ankle chains
//! ([`leg_length`], the same body's in every format).
//!
//! Where the two formats' rest directions agree bone for bone (the same format), the bones'
//! directions are the coach's, as the analytic retargeter's; across formats a bone follows
//! its counterpart's rotation rather than a chord, so a chain the formats cut differently (a
//! thorax joint on one side only) is turned as the coach's bone is, twist included.
//!
//! ```
//! use posecoach_core::format::Format;
//! use posecoach_core::skeleton::Skeleton;
//! use posecoach_core::transfer::Transfer;
//! use posecoach_core::Vec3;
//!
//! let coach = Skeleton::standard(Format::Cmu31).unwrap();
//! let student = Skeleton::standard(Format::H36m17).unwrap();
//! let transfer = Transfer::new(&coach, &student).unwrap();
//! let mut frame = [Vec3::zeros(); 31];
//! coach.rest_positions(&mut frame);
//! let mut out = [Vec3::zeros(); 17];
//! transfer.frame(&frame, &mut out).unwrap();
//! ```

use crate::config::MAX_JOINTS;
use crate::joint::Joint;
use crate::kinematics::{self, LengthError};
use crate::retarget::{counterparts, RetargetError, NONE};
use crate::skeleton::Skeleton;
use crate::{Quat, Vec3};

/// The rotation transfer from one skeleton onto another (see the module).
#[derive(Clone, Debug)]
pub struct Transfer {
    /// The source re-rested: the skeleton its rotations are measured on.
    source: Skeleton,
    /// The target re-rested: the skeleton the output poses.
    target: Skeleton,
    /// Per target joint: its source counterpart, or `NONE`.
    counterpart: [u8; MAX_JOINTS],
    /// Ratio of target to source root-to-ankle chains.
    scale: f32,
}

impl Transfer {
    /// The transfer from `source` onto `target`, both re-rested on their formats' standard
    /// T-poses.
    ///
    /// # Errors
    /// [`RetargetError::DegenerateSource`] if the source's legs have no length;
    /// [`RetargetError::Skeleton`] if a re-rested skeleton cannot be built (not expected: its
    /// tree and joints are the given one's).
    pub fn new(source: &Skeleton, target: &Skeleton) -> Result<Transfer, RetargetError> {
        let source_legs = leg_length(source);
        if source_legs.is_nan() || source_legs <= f32::EPSILON {
            return Err(RetargetError::DegenerateSource);
        }
        Ok(Transfer {
            counterpart: counterparts(source, target),
            scale: leg_length(target) / source_legs,
            source: source.standard_rest().map_err(RetargetError::Skeleton)?,
            target: target.standard_rest().map_err(RetargetError::Skeleton)?,
        })
    }

    /// The target skeleton the output poses: the given one re-rested (same bone lengths).
    pub fn target(&self) -> &Skeleton {
        &self.target
    }

    /// Ratio of target to source root-to-ankle chains, applied to the root trajectory.
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// Retargets one source frame into `out` (target joint order).
    ///
    /// # Errors
    /// [`RetargetError::Length`] for a frame shorter than the source skeleton or an output
    /// shorter than the target; [`RetargetError::NonFinite`] for a NaN or infinite input.
    pub fn frame(&self, source: &[Vec3], out: &mut [Vec3]) -> Result<(), RetargetError> {
        let (n, m) = (self.source.len(), self.target.len());
        for (expected, actual) in [(n, source.len()), (m, out.len())] {
            if actual < expected {
                return Err(LengthError { expected, actual }.into());
            }
        }
        if let Some(joint) = source[..n]
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            return Err(RetargetError::NonFinite { joint });
        }
        let mut rotation = [Quat::identity(); MAX_JOINTS];
        let root = kinematics::inverse(&self.source, &source[..n], &mut rotation[..n])?;
        // Local rotations to global, in place: a parent precedes its children.
        for k in 1..n {
            let parent = self.source.parent(k).unwrap_or(0);
            rotation[k] = rotation[parent] * rotation[k];
        }
        let mut global = [Quat::identity(); MAX_JOINTS];
        global[0] = rotation[0];
        out[0] = root * self.scale;
        for k in 1..m {
            let parent = self.target.parent(k).unwrap_or(0);
            global[k] = match self.counterpart[k] {
                NONE => global[parent],
                c => rotation[usize::from(c)],
            };
            out[k] = out[parent] + global[k] * self.target.offset(k);
        }
        Ok(())
    }
}

/// Mean chain length from the root to both ankles (a skeleton without both ankles: its own
/// leg length, [`Skeleton::leg_length`]): a body's is the same in every format, so the root's
/// trajectory does not depend on the keypoints a capture has.
pub fn leg_length(skeleton: &Skeleton) -> f32 {
    let chain = |joint| skeleton.index_of(joint).map(|k| skeleton.chain_length(k));
    match (chain(Joint::LeftAnkle), chain(Joint::RightAnkle)) {
        (Some(left), Some(right)) => 0.5 * (left + right),
        _ => skeleton.leg_length(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;
    use crate::kinematics::testing::{pose, rotations};
    use crate::retarget::Analytic;
    use proptest::prelude::*;
    use std::vec::Vec;

    const TOLERANCE_M: f32 = 1e-5;

    /// `skeleton` with every bone turned by a rotation drawn from `raw` (lengths kept): a rest
    /// pose measured with posture error, or a file's own zero pose.
    fn turned(skeleton: &Skeleton, raw: &[[f32; 4]]) -> Skeleton {
        let n = skeleton.len();
        let turn = rotations(&raw[..n]);
        let offsets: Vec<Vec3> = (0..n).map(|k| turn[k] * skeleton.offset(k)).collect();
        let parents: Vec<_> = (0..n).map(|k| skeleton.parent(k)).collect();
        Skeleton::new(skeleton.format(), &parents, &offsets, skeleton.joints()).unwrap()
    }

    fn run(source: &Skeleton, target: &Skeleton, frame: &[Vec3]) -> Vec<Vec3> {
        let mut out = std::vec![Vec3::zeros(); target.len()];
        Transfer::new(source, target)
            .unwrap()
            .frame(frame, &mut out)
            .unwrap();
        out
    }

    proptest! {
        #[test]
        fn onto_its_own_skeleton_is_the_identity(
            format in prop::sample::select(Format::BUILT_IN.to_vec()),
            raw in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
            root in prop::array::uniform3(-3.0f32..3.0),
        ) {
            let skeleton = Skeleton::standard(format).unwrap();
            let frame = pose(&skeleton, &raw, root);
            let out = run(&skeleton, &skeleton, &frame);
            for k in 0..skeleton.len() {
                prop_assert!((out[k] - frame[k]).norm() <= TOLERANCE_M, "{format} joint {k}");
            }
        }

        #[test]
        fn output_has_the_targets_bone_lengths(
            from in prop::sample::select(Format::BUILT_IN.to_vec()),
            onto in prop::sample::select(Format::BUILT_IN.to_vec()),
            raw in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
            rest in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
        ) {
            let source = Skeleton::standard(from).unwrap();
            let target = turned(&Skeleton::standard(onto).unwrap(), &rest);
            let frame = pose(&source, &raw, [0.0, 1.0, 0.0]);
            let out = run(&source, &target, &frame);
            for k in 1..target.len() {
                let bone = (out[k] - out[target.parent(k).unwrap()]).norm();
                prop_assert!((bone - target.offset(k).norm()).abs() <= TOLERANCE_M, "joint {k}");
            }
        }

        /// Neither the student's T-pose posture nor the coach's own zero pose moves the output:
        /// only their bones' lengths count. (Every bone of the coach is turned from its rest:
        /// a bone whose children all lie on its axis has no measurable twist, and rounding
        /// alone would choose it.)
        #[test]
        fn rest_poses_do_not_move_the_output(
            from in prop::sample::select(Format::BUILT_IN.to_vec()),
            onto in prop::sample::select(Format::BUILT_IN.to_vec()),
            raw in prop::collection::vec(prop::array::uniform4(0.3f32..1.0), MAX_JOINTS),
            coach_rest in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
            student_rest in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
        ) {
            let (source, target) = (Skeleton::standard(from).unwrap(), Skeleton::standard(onto).unwrap());
            let frame = pose(&source, &raw, [0.2, 1.0, -0.3]);
            let standard = run(&source, &target, &frame);
            let turned = run(&turned(&source, &coach_rest), &turned(&target, &student_rest), &frame);
            for k in 0..target.len() {
                prop_assert!((standard[k] - turned[k]).norm() <= TOLERANCE_M, "joint {k}");
            }
        }

        /// Within a format (the same rest directions) every bone points as the coach's does, as
        /// the analytic retargeter's; only the root's scale may differ (ankles, not toes).
        #[test]
        fn within_a_format_bones_point_as_the_analytic_retargeters(
            format in prop::sample::select(Format::BUILT_IN.to_vec()),
            raw in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
            lengths in prop::collection::vec(0.8f32..1.2, MAX_JOINTS),
        ) {
            let source = Skeleton::standard(format).unwrap();
            let target = source.with_bone_lengths(&lengths[..source.len()]).unwrap();
            let frame = pose(&source, &raw, [0.0, 1.0, 0.0]);
            let out = run(&source, &target, &frame);
            let mut analytic = std::vec![Vec3::zeros(); target.len()];
            Analytic::new(&source, &target).unwrap().frame(&frame, &mut analytic).unwrap();
            for k in 1..target.len() {
                let p = target.parent(k).unwrap();
                let bone = |o: &[Vec3]| o[k] - o[p];
                prop_assert!((bone(&out) - bone(&analytic)).norm() <= TOLERANCE_M, "joint {k}");
            }
        }
    }

    #[test]
    fn the_root_moves_by_the_ratio_of_ankle_chains() {
        let coach = Skeleton::standard(Format::GolfMarkers).unwrap();
        let shrunk =
            |s: &Skeleton| -> Vec<f32> { (0..s.len()).map(|k| 0.9 * s.offset(k).norm()).collect() };
        let lengths = shrunk(&coach);
        let h36m = Skeleton::standard(Format::H36m17).unwrap();
        let student = h36m.with_bone_lengths(&shrunk(&h36m)).unwrap();
        let transfer = Transfer::new(&coach, &student).unwrap();
        assert!((transfer.scale() - 0.9).abs() < 1e-6);
        let mut frame = std::vec![Vec3::zeros(); coach.len()];
        coach.rest_positions(&mut frame);
        let moved: Vec<Vec3> = frame.iter().map(|p| p + Vec3::new(0.5, 0.0, 1.0)).collect();
        let out = run(&coach, &student, &moved);
        assert!((out[0] - moved[0] * 0.9).norm() < 1e-6);
        let shorter = leg_length(&coach.with_bone_lengths(&lengths).unwrap());
        assert!((shorter - 0.9 * leg_length(&coach)).abs() < 1e-6);
    }

    #[test]
    fn bad_input_is_an_error() {
        let s = Skeleton::standard(Format::Coco17).unwrap();
        let transfer = Transfer::new(&s, &s).unwrap();
        let mut frame = [Vec3::zeros(); 15];
        s.rest_positions(&mut frame);
        let mut out = [Vec3::zeros(); 15];
        frame[4].y = f32::NAN;
        assert_eq!(
            transfer.frame(&frame, &mut out),
            Err(RetargetError::NonFinite { joint: 4 })
        );
        frame[4].y = f32::INFINITY;
        assert_eq!(
            transfer.frame(&frame, &mut out),
            Err(RetargetError::NonFinite { joint: 4 })
        );
        assert_eq!(
            transfer.frame(&frame[..14], &mut out),
            Err(RetargetError::Length(LengthError {
                expected: 15,
                actual: 14
            }))
        );
        let mut short = [Vec3::zeros(); 14];
        assert_eq!(
            transfer.frame(&frame, &mut short),
            Err(RetargetError::Length(LengthError {
                expected: 15,
                actual: 14
            }))
        );
    }
}
