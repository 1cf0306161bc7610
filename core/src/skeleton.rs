//! Skeletons: joints, parents, rest offsets, body segments, end effectors and height.
//!
//! A skeleton is rooted at the pelvis and stored in topological order (a parent's index is
//! always lower than its children's). Joints carry a canonical [`Joint`] name where one
//! applies; joints without one (clavicles, fingers, extra spine joints) are kept and follow
//! their chain.
//!
//! ```
//! use posecoach_core::format::Format;
//! use posecoach_core::skeleton::{Segment, Skeleton};
//!
//! let skeleton = Skeleton::standard(Format::H36m17).unwrap();
//! assert_eq!(skeleton.len(), 17);
//! assert!(skeleton.height() > 1.6 && skeleton.height() < 1.9);
//! let pelvis = 0;
//! assert!(skeleton.segment_contains(Segment::LeftLeg, pelvis));
//! ```

use crate::config::MAX_JOINTS;
use crate::format::{t_pose, Format};
use crate::joint::{Joint, JOINT_COUNT};
use crate::math::norm;
use crate::Vec3;

const NO_JOINT: u8 = u8::MAX;

const _: () = assert!(MAX_JOINTS <= 64, "segment masks are u64 bitsets");
const _: () = assert!(MAX_JOINTS < NO_JOINT as usize);

/// A body segment: the skeleton cut at its branching joints.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Segment {
    Spine,
    Head,
    LeftArm,
    RightArm,
    LeftLeg,
    RightLeg,
}

impl Segment {
    /// All segments in mask order.
    pub const ALL: [Segment; 6] = [
        Segment::Spine,
        Segment::Head,
        Segment::LeftArm,
        Segment::RightArm,
        Segment::LeftLeg,
        Segment::RightLeg,
    ];

    /// The snake_case name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Segment::Spine => "spine",
            Segment::Head => "head",
            Segment::LeftArm => "left_arm",
            Segment::RightArm => "right_arm",
            Segment::LeftLeg => "left_leg",
            Segment::RightLeg => "right_leg",
        }
    }
}

/// The five end effectors, each resolved to the outermost canonical joint a skeleton has.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EndEffector {
    Head,
    LeftHand,
    RightHand,
    LeftFoot,
    RightFoot,
}

impl EndEffector {
    /// All end effectors, limbs in [`Segment`] order after the head.
    pub const ALL: [EndEffector; 5] = [
        EndEffector::Head,
        EndEffector::LeftHand,
        EndEffector::RightHand,
        EndEffector::LeftFoot,
        EndEffector::RightFoot,
    ];

    /// Canonical joints that may serve, preferred first.
    pub const fn candidates(self) -> [Joint; 2] {
        match self {
            EndEffector::Head => [Joint::HeadTop, Joint::Head],
            EndEffector::LeftHand => [Joint::LeftHand, Joint::LeftWrist],
            EndEffector::RightHand => [Joint::RightHand, Joint::RightWrist],
            EndEffector::LeftFoot => [Joint::LeftToe, Joint::LeftAnkle],
            EndEffector::RightFoot => [Joint::RightToe, Joint::RightAnkle],
        }
    }

    const fn segment(self) -> Segment {
        match self {
            EndEffector::Head => Segment::Head,
            EndEffector::LeftHand => Segment::LeftArm,
            EndEffector::RightHand => Segment::RightArm,
            EndEffector::LeftFoot => Segment::LeftLeg,
            EndEffector::RightFoot => Segment::RightLeg,
        }
    }
}

/// Why a skeleton could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SkeletonError {
    /// No joints, or more than [`MAX_JOINTS`].
    #[allow(missing_docs)]
    JointCount { max: usize, actual: usize },
    /// The parent, offset and name slices differ in length.
    LengthMismatch,
    /// Joint 0 must be the root (no parent) and every other joint needs a parent with a lower index.
    #[allow(missing_docs)]
    BadParent { joint: usize },
    /// The root must be the canonical pelvis.
    RootNotPelvis,
    /// A canonical name is used twice.
    DuplicateJoint(Joint),
    /// A required canonical joint is absent (the end effector's last candidate is named).
    MissingJoint(Joint),
    /// An offset is NaN or infinite.
    #[allow(missing_docs)]
    NonFinite { joint: usize },
}

impl core::fmt::Display for SkeletonError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SkeletonError::JointCount { max, actual } => {
                write!(f, "a skeleton needs 1 to {max} joints, got {actual}")
            }
            SkeletonError::LengthMismatch => {
                f.write_str("parents, offsets and joint names differ in length")
            }
            SkeletonError::BadParent { joint } => write!(
                f,
                "joint {joint}: joint 0 must be the only root and parents must precede children"
            ),
            SkeletonError::RootNotPelvis => f.write_str("the root joint must be the pelvis"),
            SkeletonError::DuplicateJoint(j) => write!(f, "canonical joint `{j}` appears twice"),
            SkeletonError::MissingJoint(j) => write!(f, "required joint `{j}` is missing"),
            SkeletonError::NonFinite { joint } => write!(f, "joint {joint}: offset is not finite"),
        }
    }
}

impl core::error::Error for SkeletonError {}

/// A skeleton: at most [`MAX_JOINTS`] joints in topological order, rooted at the pelvis.
#[derive(Clone, Debug, PartialEq)]
pub struct Skeleton {
    format: Format,
    len: u8,
    parents: [u8; MAX_JOINTS],
    joints: [Option<Joint>; MAX_JOINTS],
    offsets: [Vec3; MAX_JOINTS],
    by_joint: [u8; JOINT_COUNT],
    end_effectors: [u8; 5],
    segments: [u64; 6],
    height: f32,
}

impl Skeleton {
    /// Builds a skeleton from parent indices, rest offsets (metres, from the parent; the
    /// root's is its rest position) and canonical names.
    ///
    /// # Errors
    /// Any [`SkeletonError`]: a bad count, a malformed tree, a root that is not the pelvis,
    /// a duplicate name, a missing end effector or a non-finite offset.
    pub fn new(
        format: Format,
        parents: &[Option<usize>],
        offsets: &[Vec3],
        joints: &[Option<Joint>],
    ) -> Result<Skeleton, SkeletonError> {
        let len = parents.len();
        if len == 0 || len > MAX_JOINTS {
            return Err(SkeletonError::JointCount {
                max: MAX_JOINTS,
                actual: len,
            });
        }
        if offsets.len() != len || joints.len() != len {
            return Err(SkeletonError::LengthMismatch);
        }
        let mut skeleton = Skeleton {
            format,
            len: len as u8,
            parents: [NO_JOINT; MAX_JOINTS],
            joints: [None; MAX_JOINTS],
            offsets: [Vec3::zeros(); MAX_JOINTS],
            by_joint: [NO_JOINT; JOINT_COUNT],
            end_effectors: [NO_JOINT; 5],
            segments: [0; 6],
            height: 0.0,
        };
        for (i, (&parent, (&offset, &joint))) in parents
            .iter()
            .zip(offsets.iter().zip(joints.iter()))
            .enumerate()
        {
            match (i, parent) {
                (0, None) => {}
                (i, Some(p)) if i > 0 && p < i => skeleton.parents[i] = p as u8,
                _ => return Err(SkeletonError::BadParent { joint: i }),
            }
            if !offset.iter().all(|v| v.is_finite()) {
                return Err(SkeletonError::NonFinite { joint: i });
            }
            skeleton.offsets[i] = offset;
            skeleton.joints[i] = joint;
            if let Some(j) = joint {
                if skeleton.by_joint[j.index()] != NO_JOINT {
                    return Err(SkeletonError::DuplicateJoint(j));
                }
                skeleton.by_joint[j.index()] = i as u8;
            }
        }
        if joints[0] != Some(Joint::Pelvis) {
            return Err(SkeletonError::RootNotPelvis);
        }
        for (k, effector) in EndEffector::ALL.into_iter().enumerate() {
            let candidates = effector.candidates();
            skeleton.end_effectors[k] = skeleton
                .find(&candidates)
                .ok_or(SkeletonError::MissingJoint(candidates[1]))?
                as u8;
        }
        skeleton.segments = skeleton.cut_segments();
        skeleton.height = skeleton.measure_height();
        Ok(skeleton)
    }

    /// `format`'s skeleton in its standard 1.75 m T-pose (for canonical, the 22 body joints).
    ///
    /// # Errors
    /// Only for [`Format::Custom`], which has no joint table.
    pub fn standard(format: Format) -> Result<Skeleton, SkeletonError> {
        let mut parents = [None; MAX_JOINTS];
        let mut positions = [Vec3::zeros(); MAX_JOINTS];
        let mut joints = [None; MAX_JOINTS];
        let n = match format {
            Format::Canonical => {
                let body = Joint::ALL.iter().filter(|j| !j.is_club());
                for (i, &j) in body.enumerate() {
                    parents[i] = j.parent().map(Joint::index);
                    positions[i] = t_pose(j);
                    joints[i] = Some(j);
                }
                Joint::ALL.len() - 2
            }
            _ => {
                for (i, j) in format.joints().iter().enumerate() {
                    parents[i] = j.parent.map(usize::from);
                    positions[i] = j.place.position();
                    joints[i] = j.joint;
                }
                format.joints().len()
            }
        };
        Skeleton::from_rest_positions(format, &parents[..n], &positions[..n], &joints[..n])
    }

    /// This skeleton with each bone turned to its format's standard T-pose direction, keeping
    /// its length: the rest pose a motion's rotations are measured from wherever they must mean
    /// the same on every skeleton. A file's own rest pose is its zero pose (CMU's BVH hangs the
    /// arms), which says nothing of the motion; a bone the standard pose gives no direction
    /// (zero length there, or a joint without a standard place) keeps its own offset.
    ///
    /// # Errors
    /// As [`Skeleton::new`] (not expected: the tree and joints are this skeleton's).
    pub fn standard_rest(&self) -> Result<Skeleton, SkeletonError> {
        let n = self.len();
        let mut offsets = [Vec3::zeros(); MAX_JOINTS];
        let mut parents = [None; MAX_JOINTS];
        offsets[..n].copy_from_slice(self.offsets());
        for (k, (parent, offset)) in parents.iter_mut().zip(&mut offsets).enumerate().take(n) {
            *parent = self.parent(k);
            let bone =
                parent.and_then(|p| Some(self.standard_position(k)? - self.standard_position(p)?));
            if let Some(bone) = bone.filter(|b| norm(b) > 0.0) {
                *offset = bone / norm(&bone) * norm(offset);
            }
        }
        Skeleton::new(self.format, &parents[..n], &offsets[..n], self.joints())
    }

    /// The standard T-pose position of joint `k`: its format table's place, or the canonical
    /// T-pose for canonical joints; `None` where neither applies.
    fn standard_position(&self, k: usize) -> Option<Vec3> {
        let table = self.format.joints();
        match table.get(k) {
            Some(j) if table.len() == self.len() => Some(j.place.position()),
            _ if self.format == Format::Canonical || table.is_empty() => self.joint(k).map(t_pose),
            _ => None,
        }
    }

    /// Builds a skeleton from rest (T-pose) joint positions instead of offsets.
    ///
    /// # Errors
    /// As [`Skeleton::new`].
    pub fn from_rest_positions(
        format: Format,
        parents: &[Option<usize>],
        positions: &[Vec3],
        joints: &[Option<Joint>],
    ) -> Result<Skeleton, SkeletonError> {
        let mut offsets = [Vec3::zeros(); MAX_JOINTS];
        let offsets = offsets
            .get_mut(..positions.len())
            .ok_or(SkeletonError::JointCount {
                max: MAX_JOINTS,
                actual: positions.len(),
            })?;
        for (i, offset) in offsets.iter_mut().enumerate() {
            let parent = parents.get(i).copied().flatten();
            let base = parent
                .and_then(|p| positions.get(p))
                .copied()
                .unwrap_or_else(Vec3::zeros);
            *offset = positions[i] - base;
        }
        Skeleton::new(format, parents, offsets, joints)
    }

    /// A [`Format::Canonical`] skeleton over any subset of canonical joints that includes the
    /// pelvis, listed in canonical order; each joint's parent is its nearest listed canonical
    /// ancestor.
    ///
    /// # Errors
    /// [`SkeletonError::BadParent`] if `joints` is not in ascending canonical order (or lacks
    /// the pelvis first), [`SkeletonError::LengthMismatch`] if the slices differ in length,
    /// and as [`Skeleton::new`].
    pub fn canonical(joints: &[Joint], rest_positions: &[Vec3]) -> Result<Skeleton, SkeletonError> {
        if joints.len() != rest_positions.len() {
            return Err(SkeletonError::LengthMismatch);
        }
        let mut parents = [None; MAX_JOINTS];
        let mut names = [None; MAX_JOINTS];
        let (parents, names) = match (
            parents.get_mut(..joints.len()),
            names.get_mut(..joints.len()),
        ) {
            (Some(p), Some(n)) => (p, n),
            _ => {
                return Err(SkeletonError::JointCount {
                    max: MAX_JOINTS,
                    actual: joints.len(),
                })
            }
        };
        for (i, &joint) in joints.iter().enumerate() {
            if i > 0 && joints[i - 1] >= joint {
                return Err(SkeletonError::BadParent { joint: i });
            }
            names[i] = Some(joint);
            parents[i] = core::iter::successors(joint.parent(), |j| j.parent())
                .find_map(|ancestor| joints[..i].iter().position(|&j| j == ancestor));
            if i > 0 && parents[i].is_none() {
                return Err(SkeletonError::BadParent { joint: i });
            }
        }
        Skeleton::from_rest_positions(Format::Canonical, parents, rest_positions, names)
    }

    /// The same skeleton with bone `k` (from its parent to joint `k`) scaled to `lengths[k]`;
    /// zero-length bones stay zero and the root's entry is ignored.
    ///
    /// # Errors
    /// [`SkeletonError::LengthMismatch`] if `lengths` does not have one entry per joint, and
    /// [`SkeletonError::NonFinite`] for a NaN, infinite or negative length.
    pub fn with_bone_lengths(&self, lengths: &[f32]) -> Result<Skeleton, SkeletonError> {
        if lengths.len() != self.len() {
            return Err(SkeletonError::LengthMismatch);
        }
        let mut offsets = self.offsets;
        for k in 1..self.len() {
            if !(lengths[k].is_finite() && lengths[k] >= 0.0) {
                return Err(SkeletonError::NonFinite { joint: k });
            }
            let norm = offsets[k].norm();
            if norm > 0.0 {
                offsets[k] *= lengths[k] / norm;
            }
        }
        let parents: [Option<usize>; MAX_JOINTS] = core::array::from_fn(|i| self.parent(i));
        Skeleton::new(
            self.format,
            &parents[..self.len()],
            &offsets[..self.len()],
            self.joints(),
        )
    }

    /// The keypoint format this skeleton was built for.
    pub fn format(&self) -> Format {
        self.format
    }

    /// Number of joints.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Always false: a skeleton has at least its root.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Parent of joint `i` (`None` for the root or an index out of range).
    pub fn parent(&self, i: usize) -> Option<usize> {
        match self.parents.get(i) {
            Some(&p) if p != NO_JOINT && i < self.len() => Some(p as usize),
            _ => None,
        }
    }

    /// Rest offset of joint `i` from its parent (the root's rest position for the root).
    pub fn offset(&self, i: usize) -> Vec3 {
        self.offsets().get(i).copied().unwrap_or_else(Vec3::zeros)
    }

    /// All rest offsets.
    pub fn offsets(&self) -> &[Vec3] {
        &self.offsets[..self.len()]
    }

    /// Canonical name of joint `i`, if it has one.
    pub fn joint(&self, i: usize) -> Option<Joint> {
        self.joints().get(i).copied().flatten()
    }

    /// Canonical names of all joints.
    pub fn joints(&self) -> &[Option<Joint>] {
        &self.joints[..self.len()]
    }

    /// Index of a canonical joint, if this skeleton has it.
    pub fn index_of(&self, joint: Joint) -> Option<usize> {
        match self.by_joint[joint.index()] {
            NO_JOINT => None,
            i => Some(i as usize),
        }
    }

    /// Index of the first of `joints` this skeleton has (a joint, then its fallbacks).
    pub fn find(&self, joints: &[Joint]) -> Option<usize> {
        joints.iter().find_map(|&j| self.index_of(j))
    }

    /// Index of an end effector's joint.
    pub fn end_effector(&self, effector: EndEffector) -> usize {
        let k = EndEffector::ALL
            .iter()
            .position(|&e| e == effector)
            .unwrap_or(0);
        self.end_effectors[k] as usize
    }

    /// Whether joint `i` belongs to `segment` (a branching joint belongs to every segment that
    /// starts at it).
    pub fn segment_contains(&self, segment: Segment, i: usize) -> bool {
        i < self.len() && self.segment_mask(segment) & (1 << i) != 0
    }

    /// The segment whose feature decodes the bone into joint `k` (the retargeter's decoder):
    /// the first that holds both the joint and its parent (a limb's first bone starts at the
    /// branching joint the limb holds), else the first that holds the joint, else the spine.
    pub fn bone_segment(&self, k: usize) -> Segment {
        let parent = self.parent(k).unwrap_or(0);
        let holds = |s: &&Segment, i: usize| self.segment_contains(**s, i);
        Segment::ALL
            .iter()
            .find(|s| holds(s, k) && holds(s, parent))
            .or_else(|| Segment::ALL.iter().find(|s| holds(s, k)))
            .copied()
            .unwrap_or(Segment::Spine)
    }

    /// The joints of `segment` as a bitset (bit `i` = joint `i`).
    pub fn segment_mask(&self, segment: Segment) -> u64 {
        self.segments[segment as usize]
    }

    /// Height: the mean root-to-foot chain length plus the root-to-head chain length (sums of
    /// bone lengths, as the VPC and PAN papers define it).
    pub fn height(&self) -> f32 {
        self.height
    }

    /// Sum of bone lengths from the root to joint `i`.
    pub fn chain_length(&self, i: usize) -> f32 {
        self.ancestry(i).map(|k| norm(&self.offset(k))).sum()
    }

    /// Mean chain length from the root to both feet.
    pub fn leg_length(&self) -> f32 {
        0.5 * (self.chain_length(self.end_effector(EndEffector::LeftFoot))
            + self.chain_length(self.end_effector(EndEffector::RightFoot)))
    }

    /// Rest positions of all joints (the root at its rest position), written to `out`.
    /// Writes `min(out.len(), self.len())` joints.
    pub fn rest_positions(&self, out: &mut [Vec3]) {
        for i in 0..self.len().min(out.len()) {
            let base = self.parent(i).map_or(Vec3::zeros(), |p| out[p]);
            out[i] = base + self.offsets[i];
        }
    }

    /// Joint `i` and its non-root ancestors, outwards-in (the root itself is not yielded).
    pub fn ancestry(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let start = if i < self.len() && i != 0 {
            Some(i)
        } else {
            None
        };
        core::iter::successors(start, move |&k| self.parent(k).filter(|&p| p != 0))
    }

    fn measure_height(&self) -> f32 {
        self.leg_length() + self.chain_length(self.end_effector(EndEffector::Head))
    }

    /// Cuts the tree into the six segments. The main tree is the union of the root-to-end-
    /// effector paths; each limb runs from the nearest branching ancestor of its end effector
    /// (a joint with two or more main-tree children) out to the end effector, and the spine
    /// holds the rest of the main tree. Joints off the main tree (fingers, club) join the
    /// segment of their nearest main-tree ancestor, or the spine if that is a branching joint.
    fn cut_segments(&self) -> [u64; 6] {
        let mut main = 0u64;
        for &e in &self.end_effectors {
            main |= 1 | self.ancestry(e as usize).fold(0, |m, k| m | 1 << k);
        }
        let mut main_children = [0u8; MAX_JOINTS];
        for i in 1..self.len() {
            if main & (1 << i) != 0 {
                main_children[self.parents[i] as usize] += 1;
            }
        }
        let mut segments = [0u64; 6];
        let mut limbs = 0u64;
        for effector in EndEffector::ALL {
            let mut mask = 0u64;
            let mut k = self.end_effector(effector);
            loop {
                mask |= 1 << k;
                match self.parent(k) {
                    Some(p) if main_children[p] < 2 => k = p,
                    Some(p) => {
                        mask |= 1 << p;
                        limbs |= mask & !(1 << p);
                        break;
                    }
                    None => {
                        limbs |= mask & !1;
                        break;
                    }
                }
            }
            segments[effector.segment() as usize] = mask;
        }
        segments[Segment::Spine as usize] = main & !limbs;
        for i in 1..self.len() {
            if main & (1 << i) == 0 {
                let p = self.parents[i] as usize;
                let owner = Segment::ALL
                    .iter()
                    .rposition(|&s| segments[s as usize] & (1 << p) != 0);
                let owner = match owner {
                    Some(s) if limbs & (1 << p) != 0 || main & (1 << p) == 0 => s,
                    _ => Segment::Spine as usize,
                };
                segments[owner] |= 1 << i;
            }
        }
        segments
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn h36m() -> Skeleton {
        match Skeleton::standard(Format::H36m17) {
            Ok(s) => s,
            Err(e) => unreachable!("{e}"),
        }
    }

    #[test]
    fn a_rest_pose_with_hanging_arms_is_re_rested_on_the_t_pose_with_its_own_bone_lengths() {
        let standard = h36m();
        let n = standard.len();
        // Every bone longer by its index in mm; the arms hang (their bones point down).
        let mut offsets = [Vec3::zeros(); MAX_JOINTS];
        let mut parents = [None; MAX_JOINTS];
        for k in 0..n {
            parents[k] = standard.parent(k);
            let o = standard.offsets()[k];
            let length = norm(&o) + 0.001 * k as f32;
            let arm = matches!(
                standard.joint(k),
                Some(Joint::LeftElbow | Joint::LeftWrist | Joint::RightElbow | Joint::RightWrist)
            );
            offsets[k] = match (k, arm) {
                (0, _) => o,
                (_, true) => Vec3::new(0.0, -length, 0.0),
                _ => o / norm(&o) * length,
            };
        }
        let hanging = Skeleton::new(
            Format::H36m17,
            &parents[..n],
            &offsets[..n],
            standard.joints(),
        )
        .unwrap_or_else(|e| unreachable!("{e}"));
        let rested = hanging
            .standard_rest()
            .unwrap_or_else(|e| unreachable!("{e}"));
        let bones = rested
            .offsets()
            .iter()
            .zip(standard.offsets())
            .zip(&offsets);
        for (k, ((a, b), own)) in bones.enumerate().skip(1) {
            assert!((norm(a) - norm(own)).abs() < 1e-6, "joint {k}: length");
            assert!(
                (a / norm(a) - b / norm(b)).norm() < 1e-6,
                "joint {k}: direction"
            );
        }
        // The standard pose is its own re-resting.
        let again = standard
            .standard_rest()
            .unwrap_or_else(|e| unreachable!("{e}"));
        for (a, b) in again.offsets().iter().zip(standard.offsets()) {
            assert!((a - b).norm() < 1e-6);
        }
    }

    #[test]
    fn h36m_segments_cut_at_pelvis_and_thorax() {
        let s = h36m();
        let names = |seg: Segment| {
            (0..s.len())
                .filter(|&i| s.segment_contains(seg, i))
                .filter_map(|i| s.joint(i))
                .collect::<std::vec::Vec<_>>()
        };
        use Joint::*;
        assert_eq!(names(Segment::Spine), [Pelvis, Spine, Thorax]);
        assert_eq!(names(Segment::Head), [Thorax, Neck, HeadTop]);
        assert_eq!(
            names(Segment::LeftArm),
            [Thorax, LeftShoulder, LeftElbow, LeftWrist]
        );
        assert_eq!(
            names(Segment::RightLeg),
            [Pelvis, RightHip, RightKnee, RightAnkle]
        );
    }

    #[test]
    fn every_joint_is_in_a_segment() {
        let s = h36m();
        let all = Segment::ALL
            .iter()
            .fold(0, |m, &seg| m | s.segment_mask(seg));
        assert_eq!(all, (1u64 << s.len()) - 1);
    }

    #[test]
    fn canonical_subsets_attach_to_the_nearest_present_ancestor() {
        use Joint::*;
        let joints = [
            Pelvis, LeftHip, LeftAnkle, RightHip, RightAnkle, Thorax, HeadTop, LeftWrist,
            RightWrist,
        ];
        let rest: std::vec::Vec<Vec3> = joints.iter().map(|&j| t_pose(j)).collect();
        let s = Skeleton::canonical(&joints, &rest).unwrap();
        assert_eq!(s.parent(2), Some(1));
        assert_eq!(s.parent(5), Some(0));
        assert_eq!(s.parent(7), Some(5));
        assert_eq!(s.end_effector(EndEffector::LeftHand), 7);
        let mut swapped = joints;
        swapped.swap(1, 2);
        assert_eq!(
            Skeleton::canonical(&swapped, &rest),
            Err(SkeletonError::BadParent { joint: 2 })
        );
    }

    #[test]
    fn bone_lengths_can_be_replaced() {
        let s = h36m();
        let lengths: std::vec::Vec<f32> = (0..s.len()).map(|k| 0.1 * k as f32).collect();
        let scaled = s.with_bone_lengths(&lengths).unwrap();
        for (k, &length) in lengths.iter().enumerate().skip(1) {
            assert!((scaled.offset(k).norm() - length).abs() < 1e-6);
            assert!(scaled.offset(k).normalize().dot(&s.offset(k).normalize()) > 0.9999);
        }
        assert_eq!(
            s.with_bone_lengths(&lengths[1..]),
            Err(SkeletonError::LengthMismatch)
        );
    }

    #[test]
    fn rejects_malformed_trees() {
        let off = [Vec3::zeros(); 2];
        let joints = [Some(Joint::Pelvis), Some(Joint::Spine)];
        assert_eq!(
            Skeleton::new(Format::Custom, &[None, None], &off, &joints),
            Err(SkeletonError::BadParent { joint: 1 })
        );
        assert_eq!(
            Skeleton::new(Format::Custom, &[None, Some(0)], &off, &joints),
            Err(SkeletonError::MissingJoint(Joint::Head))
        );
        assert_eq!(
            Skeleton::new(
                Format::Custom,
                &[None, Some(0)],
                &off,
                &[Some(Joint::Spine); 2]
            ),
            Err(SkeletonError::DuplicateJoint(Joint::Spine))
        );
        assert_eq!(
            Skeleton::new(Format::Custom, &[], &[], &[]),
            Err(SkeletonError::JointCount {
                max: MAX_JOINTS,
                actual: 0
            })
        );
    }
}
