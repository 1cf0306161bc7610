//! The canonical joint vocabulary every keypoint format is mapped onto.
//!
//! ```
//! use posecoach_core::joint::Joint;
//! assert_eq!(Joint::LeftWrist.parent(), Some(Joint::LeftElbow));
//! assert_eq!(Joint::from_name("left_wrist"), Some(Joint::LeftWrist));
//! assert_eq!(Joint::LeftWrist.mirror(), Joint::RightWrist);
//! ```

/// A canonical joint. The order is the canonical order used by CSV files and reports.
#[allow(missing_docs)] // the names say it all
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[repr(u8)]
pub enum Joint {
    Pelvis,
    LeftHip,
    LeftKnee,
    LeftAnkle,
    LeftToe,
    RightHip,
    RightKnee,
    RightAnkle,
    RightToe,
    Spine,
    Thorax,
    Neck,
    Head,
    HeadTop,
    LeftShoulder,
    LeftElbow,
    LeftWrist,
    LeftHand,
    RightShoulder,
    RightElbow,
    RightWrist,
    RightHand,
    /// Top of the club's grip, between the hands (optional: only where a club is tracked).
    ClubGrip,
    /// The club head (optional).
    ClubHead,
}

/// Number of canonical joints.
pub const JOINT_COUNT: usize = 24;

impl Joint {
    /// Every canonical joint in canonical order; a parent always comes before its children.
    pub const ALL: [Joint; JOINT_COUNT] = [
        Joint::Pelvis,
        Joint::LeftHip,
        Joint::LeftKnee,
        Joint::LeftAnkle,
        Joint::LeftToe,
        Joint::RightHip,
        Joint::RightKnee,
        Joint::RightAnkle,
        Joint::RightToe,
        Joint::Spine,
        Joint::Thorax,
        Joint::Neck,
        Joint::Head,
        Joint::HeadTop,
        Joint::LeftShoulder,
        Joint::LeftElbow,
        Joint::LeftWrist,
        Joint::LeftHand,
        Joint::RightShoulder,
        Joint::RightElbow,
        Joint::RightWrist,
        Joint::RightHand,
        Joint::ClubGrip,
        Joint::ClubHead,
    ];

    /// Position of this joint in [`Joint::ALL`].
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The joint at `index` in [`Joint::ALL`], if any.
    pub fn from_index(index: usize) -> Option<Joint> {
        Self::ALL.get(index).copied()
    }

    /// The snake_case name used in files and reports.
    pub const fn name(self) -> &'static str {
        match self {
            Joint::Pelvis => "pelvis",
            Joint::LeftHip => "left_hip",
            Joint::LeftKnee => "left_knee",
            Joint::LeftAnkle => "left_ankle",
            Joint::LeftToe => "left_toe",
            Joint::RightHip => "right_hip",
            Joint::RightKnee => "right_knee",
            Joint::RightAnkle => "right_ankle",
            Joint::RightToe => "right_toe",
            Joint::Spine => "spine",
            Joint::Thorax => "thorax",
            Joint::Neck => "neck",
            Joint::Head => "head",
            Joint::HeadTop => "head_top",
            Joint::LeftShoulder => "left_shoulder",
            Joint::LeftElbow => "left_elbow",
            Joint::LeftWrist => "left_wrist",
            Joint::LeftHand => "left_hand",
            Joint::RightShoulder => "right_shoulder",
            Joint::RightElbow => "right_elbow",
            Joint::RightWrist => "right_wrist",
            Joint::RightHand => "right_hand",
            Joint::ClubGrip => "club_grip",
            Joint::ClubHead => "club_head",
        }
    }

    /// The joint called `name` (exact snake_case name), if any.
    pub fn from_name(name: &str) -> Option<Joint> {
        Self::ALL.iter().copied().find(|j| j.name() == name)
    }

    /// The canonical parent; `None` for the pelvis, the root of every skeleton.
    ///
    /// The club hangs off the left hand: for a left-handed golfer the table is the same, and the
    /// grip's bone simply points the other way.
    pub const fn parent(self) -> Option<Joint> {
        Some(match self {
            Joint::Pelvis => return None,
            Joint::LeftHip | Joint::RightHip | Joint::Spine => Joint::Pelvis,
            Joint::LeftKnee => Joint::LeftHip,
            Joint::LeftAnkle => Joint::LeftKnee,
            Joint::LeftToe => Joint::LeftAnkle,
            Joint::RightKnee => Joint::RightHip,
            Joint::RightAnkle => Joint::RightKnee,
            Joint::RightToe => Joint::RightAnkle,
            Joint::Thorax => Joint::Spine,
            Joint::Neck | Joint::LeftShoulder | Joint::RightShoulder => Joint::Thorax,
            Joint::Head => Joint::Neck,
            Joint::HeadTop => Joint::Head,
            Joint::LeftElbow => Joint::LeftShoulder,
            Joint::LeftWrist => Joint::LeftElbow,
            Joint::LeftHand => Joint::LeftWrist,
            Joint::RightElbow => Joint::RightShoulder,
            Joint::RightWrist => Joint::RightElbow,
            Joint::RightHand => Joint::RightWrist,
            Joint::ClubGrip => Joint::LeftHand,
            Joint::ClubHead => Joint::ClubGrip,
        })
    }

    /// The same joint on the other side of the body (itself for joints on the midline).
    pub const fn mirror(self) -> Joint {
        match self {
            Joint::LeftHip => Joint::RightHip,
            Joint::LeftKnee => Joint::RightKnee,
            Joint::LeftAnkle => Joint::RightAnkle,
            Joint::LeftToe => Joint::RightToe,
            Joint::RightHip => Joint::LeftHip,
            Joint::RightKnee => Joint::LeftKnee,
            Joint::RightAnkle => Joint::LeftAnkle,
            Joint::RightToe => Joint::LeftToe,
            Joint::LeftShoulder => Joint::RightShoulder,
            Joint::LeftElbow => Joint::RightElbow,
            Joint::LeftWrist => Joint::RightWrist,
            Joint::LeftHand => Joint::RightHand,
            Joint::RightShoulder => Joint::LeftShoulder,
            Joint::RightElbow => Joint::LeftElbow,
            Joint::RightWrist => Joint::LeftWrist,
            Joint::RightHand => Joint::LeftHand,
            other => other,
        }
    }

    /// Whether this joint belongs to the club rather than the body.
    pub const fn is_club(self) -> bool {
        matches!(self, Joint::ClubGrip | Joint::ClubHead)
    }
}

impl core::fmt::Display for Joint {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn all_is_in_index_order_and_parents_come_first() {
        for (i, joint) in Joint::ALL.iter().enumerate() {
            assert_eq!(joint.index(), i);
            if let Some(parent) = joint.parent() {
                assert!(
                    parent.index() < i,
                    "{joint} listed before its parent {parent}"
                );
            }
        }
    }

    #[test]
    fn names_round_trip_and_mirror_is_an_involution() {
        for joint in Joint::ALL {
            assert_eq!(Joint::from_name(joint.name()), Some(joint));
            assert_eq!(joint.mirror().mirror(), joint);
            if !joint.is_club() {
                assert_eq!(joint.mirror().parent(), joint.parent().map(Joint::mirror));
            }
        }
        assert_eq!(Joint::from_name("elbow"), None);
    }
}
