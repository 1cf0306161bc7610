//! The analytic retargeter: bone-direction copy plus a leg-scaled root trajectory.
//!
//! It is the fallback when no network weights are loaded and the baseline every learned model
//! is measured against.
//!
//! Joints correspond by index when both skeletons come from the same built-in format with the
//! same tree, and otherwise by canonical name. A target joint with a counterpart is *anchored*.
//! For each anchored joint `k` with nearest anchored ancestor `a`, the target's rest chain
//! `a → … → k` is turned by the smallest rotation that takes its rest chord `T_k − T_a` onto the
//! source's `S_k − S_a`; for a single bone that is exactly a bone-direction copy. Target joints
//! without a counterpart are interpolated along their chain this way (a CMU clavicle between
//! thorax and shoulder), or, past the last anchored joint, carried rigidly by their parent's
//! rotation (fingers). Source joints without a counterpart are left out (a chord skips them).
//! The root moves along the source's root trajectory scaled by the ratio of leg lengths (to the
//! toes where both skeletons have them, else to the ankles). Every
//! output bone has exactly the target's length.
//!
//! ```
//! use posecoach_core::format::Format;
//! use posecoach_core::skeleton::Skeleton;
//! use posecoach_core::retarget::Analytic;
//! use posecoach_core::Vec3;
//!
//! let coach = Skeleton::standard(Format::Cmu31).unwrap();
//! let student = Skeleton::standard(Format::H36m17).unwrap();
//! let retarget = Analytic::new(&coach, &student).unwrap();
//! let mut frame = [Vec3::zeros(); 31];
//! coach.rest_positions(&mut frame);
//! let mut out = [Vec3::zeros(); 17];
//! retarget.frame(&frame, &mut out).unwrap();
//! ```

use crate::config::MAX_JOINTS;
use crate::joint::Joint;
use crate::kinematics::{swing, LengthError};
use crate::skeleton::Skeleton;
use crate::{Quat, Vec3};

const NONE: u8 = u8::MAX;

/// Why a retarget could not be set up or run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RetargetError {
    /// A frame or output buffer has the wrong length.
    Length(LengthError),
    /// The source skeleton's legs have zero length, so the trajectory cannot be scaled.
    DegenerateSource,
    /// A source joint position is NaN or infinite.
    #[allow(missing_docs)]
    NonFinite { joint: usize },
}

impl From<LengthError> for RetargetError {
    fn from(e: LengthError) -> Self {
        RetargetError::Length(e)
    }
}

impl core::fmt::Display for RetargetError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RetargetError::Length(e) => e.fmt(f),
            RetargetError::DegenerateSource => {
                f.write_str("the source skeleton's legs have no length")
            }
            RetargetError::NonFinite { joint } => write!(f, "source joint {joint} is not finite"),
        }
    }
}

impl core::error::Error for RetargetError {}

/// The source chord whose swing turns a target bone: the bone's rotation is the smallest
/// that takes `rest` (a chord of the target's rest pose) onto `source[to] - source[from]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chord {
    /// Source joint the chord starts at.
    pub from: usize,
    /// Source joint the chord ends at.
    pub to: usize,
    /// The corresponding chord of the target's rest pose.
    pub rest: Vec3,
}

/// The analytic retargeter: a [`Fit`] and the target skeleton it poses.
#[derive(Clone, Debug)]
pub struct Analytic<'a> {
    target: &'a Skeleton,
    fit: Fit,
}

impl<'a> Analytic<'a> {
    /// Prepares the correspondence from `source` onto `target`.
    ///
    /// # Errors
    /// [`RetargetError::DegenerateSource`] if the source's legs have zero length.
    pub fn new(source: &Skeleton, target: &'a Skeleton) -> Result<Self, RetargetError> {
        Ok(Analytic {
            target,
            fit: Fit::new(source, target)?,
        })
    }

    /// Ratio of target to source leg length applied to the root trajectory.
    pub fn scale(&self) -> f32 {
        self.fit.scale
    }

    /// The source joint whose trajectory, times [`Analytic::scale`], is the target root's.
    pub fn root(&self) -> usize {
        self.fit.counterpart[0] as usize
    }

    /// The chord that turns the bone into target joint `k`, as [`Analytic::frame`] does; `None`
    /// for a bone that keeps its rest direction (out of the root without an anchored joint
    /// below it), for the root and for `k` out of range.
    pub fn chord(&self, k: usize) -> Option<Chord> {
        let fit = &self.fit;
        let mut k = k;
        while (1..self.target.len()).contains(&k) {
            match fit.driver[k] {
                NONE => k = self.target.parent(k)?,
                d => {
                    let d = d as usize;
                    return Some(Chord {
                        from: fit.counterpart[fit.anchor[d] as usize] as usize,
                        to: fit.counterpart[d] as usize,
                        rest: fit.rest_chord[d],
                    });
                }
            }
        }
        None
    }

    /// Retargets one source frame into `out` (target joint order).
    ///
    /// # Errors
    /// [`RetargetError::Length`] for a frame shorter than the source skeleton or an output
    /// shorter than the target; [`RetargetError::NonFinite`] for a NaN or infinite input.
    pub fn frame(&self, source: &[Vec3], out: &mut [Vec3]) -> Result<(), RetargetError> {
        self.fit.frame(self.target, source, out)
    }
}

/// The analytic retargeter's correspondence from one skeleton onto another, owning neither:
/// what a session keeps, made once per student profile, for every pose frame that follows.
#[derive(Clone, Debug)]
pub struct Fit {
    /// Joints of the source skeleton.
    source_len: usize,
    /// Joints of the target skeleton.
    target_len: usize,
    /// Per target joint: its source counterpart, or `NONE`.
    counterpart: [u8; MAX_JOINTS],
    /// Per anchored target joint: its nearest anchored proper ancestor.
    anchor: [u8; MAX_JOINTS],
    /// Per target joint: the anchored joint whose chord rotation it follows, or `NONE` to
    /// follow its parent.
    driver: [u8; MAX_JOINTS],
    /// Per anchored target joint: the rest chord from its anchor.
    rest_chord: [Vec3; MAX_JOINTS],
    scale: f32,
}

impl Fit {
    /// The correspondence from `source` onto `target`.
    ///
    /// # Errors
    /// [`RetargetError::DegenerateSource`] if the source's legs have zero length.
    pub fn new(source: &Skeleton, target: &Skeleton) -> Result<Fit, RetargetError> {
        let (source_legs, target_legs) = leg_lengths(source, target);
        if source_legs <= f32::EPSILON {
            return Err(RetargetError::DegenerateSource);
        }
        let same_tree = source.format() == target.format()
            && source.format().joints().len() == source.len()
            && source.len() == target.len()
            && (0..source.len()).all(|i| source.parent(i) == target.parent(i));
        let mut counterpart = [NONE; MAX_JOINTS];
        for (k, slot) in counterpart.iter_mut().enumerate().take(target.len()) {
            let found = if same_tree {
                Some(k)
            } else {
                target.joint(k).and_then(|j| source.index_of(j))
            };
            *slot = found.map_or(NONE, |i| i as u8);
        }
        let mut rest = [Vec3::zeros(); MAX_JOINTS];
        target.rest_positions(&mut rest);
        let mut anchor = [NONE; MAX_JOINTS];
        let mut driver = [NONE; MAX_JOINTS];
        let mut rest_chord = [Vec3::zeros(); MAX_JOINTS];
        for k in 1..target.len() {
            if counterpart[k] == NONE {
                continue;
            }
            driver[k] = k as u8;
            let mut a = target.parent(k).unwrap_or(0);
            while counterpart[a] == NONE {
                if driver[a] == NONE {
                    driver[a] = k as u8;
                }
                a = target.parent(a).unwrap_or(0);
            }
            anchor[k] = a as u8;
            rest_chord[k] = rest[k] - rest[a];
        }
        Ok(Fit {
            source_len: source.len(),
            target_len: target.len(),
            counterpart,
            anchor,
            driver,
            rest_chord,
            scale: target_legs / source_legs,
        })
    }

    /// Retargets one source frame into `out`, posing `target`: the skeleton this fit was made
    /// for (another of the same length is posed with this fit's rotations, wrongly).
    ///
    /// # Errors
    /// [`RetargetError::Length`] for a `target` other than the fit's length, a frame shorter
    /// than the source skeleton or an output shorter than the target;
    /// [`RetargetError::NonFinite`] for a NaN or infinite input.
    pub fn frame(
        &self,
        target: &Skeleton,
        source: &[Vec3],
        out: &mut [Vec3],
    ) -> Result<(), RetargetError> {
        let n = self.target_len;
        if target.len() != n {
            let actual = target.len();
            return Err(LengthError {
                expected: n,
                actual,
            }
            .into());
        }
        for (expected, actual) in [(self.source_len, source.len()), (n, out.len())] {
            if actual < expected {
                return Err(LengthError { expected, actual }.into());
            }
        }
        if let Some(joint) = source[..self.source_len]
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            return Err(RetargetError::NonFinite { joint });
        }
        let at = |k: u8| source[self.counterpart[k as usize] as usize];
        let mut rotation = [Quat::identity(); MAX_JOINTS];
        // Anchored joints first: a joint between two anchors follows the one below it.
        for k in (1..n).filter(|&k| self.driver[k] as usize == k) {
            rotation[k] = swing(self.rest_chord[k], at(k as u8) - at(self.anchor[k]));
        }
        out[0] = at(0) * self.scale;
        for k in 1..n {
            let parent = target.parent(k).unwrap_or(0);
            rotation[k] = match self.driver[k] {
                NONE => rotation[parent],
                d => rotation[d as usize],
            };
            out[k] = out[parent] + rotation[k] * target.offset(k);
        }
        Ok(())
    }
}

/// Mean root-to-foot chain lengths of both skeletons, measured to the deepest foot joints both
/// have (toes, else ankles) so that a format without toes is not compared with one that has
/// them; each skeleton's own end-effector chains if they share neither.
fn leg_lengths(source: &Skeleton, target: &Skeleton) -> (f32, f32) {
    let to = |s: &Skeleton, [left, right]: [Joint; 2]| {
        Some(0.5 * (s.chain_length(s.index_of(left)?) + s.chain_length(s.index_of(right)?)))
    };
    [
        [Joint::LeftToe, Joint::RightToe],
        [Joint::LeftAnkle, Joint::RightAnkle],
    ]
    .into_iter()
    .find_map(|feet| Some((to(source, feet)?, to(target, feet)?)))
    .unwrap_or((source.leg_length(), target.leg_length()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;
    use crate::kinematics::testing::pose;
    use proptest::prelude::*;

    const TOLERANCE_M: f32 = 1e-5;

    #[test]
    fn a_fit_poses_only_a_target_of_its_length() {
        let (h36m, coco) = (
            Skeleton::standard(Format::H36m17).unwrap(),
            Skeleton::standard(Format::Coco17).unwrap(),
        );
        let fit = Fit::new(&h36m, &h36m).unwrap();
        let mut frame = [Vec3::zeros(); MAX_JOINTS];
        h36m.rest_positions(&mut frame);
        let mut out = [Vec3::zeros(); MAX_JOINTS];
        assert_eq!(fit.frame(&h36m, &frame[..17], &mut out), Ok(()));
        assert_eq!(
            fit.frame(&coco, &frame[..17], &mut out),
            Err(RetargetError::Length(LengthError {
                expected: 17,
                actual: coco.len()
            }))
        );
        assert_eq!(
            fit.frame(&h36m, &frame[..16], &mut out),
            Err(RetargetError::Length(LengthError {
                expected: 17,
                actual: 16
            }))
        );
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
            let retarget = Analytic::new(&skeleton, &skeleton).unwrap();
            let mut out = [Vec3::zeros(); MAX_JOINTS];
            retarget.frame(&frame, &mut out).unwrap();
            for k in 0..skeleton.len() {
                prop_assert!((out[k] - frame[k]).norm() <= TOLERANCE_M, "{format} joint {k}");
            }
        }

        #[test]
        fn output_has_the_targets_bone_lengths(
            from in prop::sample::select(Format::BUILT_IN.to_vec()),
            onto in prop::sample::select(Format::BUILT_IN.to_vec()),
            raw in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
        ) {
            let source = Skeleton::standard(from).unwrap();
            let target = Skeleton::standard(onto).unwrap();
            let frame = pose(&source, &raw, [0.0, 1.0, 0.0]);
            let retarget = Analytic::new(&source, &target).unwrap();
            let mut out = [Vec3::zeros(); MAX_JOINTS];
            retarget.frame(&frame, &mut out).unwrap();
            for k in 1..target.len() {
                let bone = (out[k] - out[target.parent(k).unwrap()]).norm();
                prop_assert!((bone - target.offset(k).norm()).abs() <= TOLERANCE_M);
            }
        }
    }

    proptest! {
        #[test]
        fn chords_turn_bones_as_frame_does(
            from in prop::sample::select(Format::BUILT_IN.to_vec()),
            onto in prop::sample::select(Format::BUILT_IN.to_vec()),
            raw in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
        ) {
            let source = Skeleton::standard(from).unwrap();
            let target = Skeleton::standard(onto).unwrap();
            let frame = pose(&source, &raw, [0.0, 1.0, 0.0]);
            let retarget = Analytic::new(&source, &target).unwrap();
            let mut out = [Vec3::zeros(); MAX_JOINTS];
            retarget.frame(&frame, &mut out).unwrap();
            prop_assert!((out[0] - frame[retarget.root()] * retarget.scale()).norm() <= TOLERANCE_M);
            for k in 1..target.len() {
                let turn = retarget.chord(k).map_or(Quat::identity(), |c| {
                    swing(c.rest, frame[c.to] - frame[c.from])
                });
                let bone = out[k] - out[target.parent(k).unwrap()];
                prop_assert!((bone - turn * target.offset(k)).norm() <= TOLERANCE_M, "joint {k}");
            }
            prop_assert_eq!(retarget.chord(0), None);
            prop_assert_eq!(retarget.chord(target.len()), None);
        }
    }

    #[test]
    fn root_trajectory_scales_with_leg_length() {
        let coach = Skeleton::standard(Format::H36m17).unwrap();
        let mut offsets = [Vec3::zeros(); 17];
        offsets[..17].copy_from_slice(coach.offsets());
        for o in &mut offsets {
            *o *= 0.8;
        }
        let parents: std::vec::Vec<_> = (0..17).map(|i| coach.parent(i)).collect();
        let student = Skeleton::new(Format::H36m17, &parents, &offsets, coach.joints()).unwrap();
        let retarget = Analytic::new(&coach, &student).unwrap();
        assert!((retarget.scale() - 0.8).abs() < 1e-6);
        let mut frame = [Vec3::zeros(); 17];
        coach.rest_positions(&mut frame);
        let mut out = [Vec3::zeros(); 17];
        retarget.frame(&frame, &mut out).unwrap();
        assert!((out[0] - frame[0] * 0.8).norm() < 1e-6);
        assert!((out[10] - frame[10] * 0.8).norm() < 1e-5);
    }

    #[test]
    fn leg_ratio_compares_the_same_chain() {
        // Golf joint centres reach the toes, H36M only the ankles: compare pelvis-to-ankle.
        let golf = Skeleton::standard(Format::GolfMarkers).unwrap();
        let h36m = Skeleton::standard(Format::H36m17).unwrap();
        let retarget = Analytic::new(&golf, &h36m).unwrap();
        let ankle = |s: &Skeleton| s.chain_length(s.index_of(Joint::LeftAnkle).unwrap());
        assert!((retarget.scale() - ankle(&h36m) / ankle(&golf)).abs() < 1e-6);
        assert!(
            (retarget.scale() - 1.0).abs() < 1e-6,
            "both are the same standard body"
        );
    }

    #[test]
    fn non_finite_input_is_an_error() {
        let s = Skeleton::standard(Format::Coco17).unwrap();
        let retarget = Analytic::new(&s, &s).unwrap();
        let mut frame = [Vec3::zeros(); 15];
        frame[4].y = f32::NAN;
        let mut out = [Vec3::zeros(); 15];
        assert_eq!(
            retarget.frame(&frame, &mut out),
            Err(RetargetError::NonFinite { joint: 4 })
        );
    }
}
