//! Built-in keypoint formats and their mapping onto the canonical vocabulary.
//!
//! A format lists the keypoints a file or stream carries, and the skeleton joints built from
//! them: each joint has a name, a parent, an optional canonical [`Joint`], a [`Source`] (one
//! keypoint, or the midpoint of two for formats without a pelvis or thorax keypoint) and a
//! [`Place`] in the default T-pose.
//!
//! ```
//! use posecoach_core::format::Format;
//! use posecoach_core::joint::Joint;
//!
//! let coco = Format::Coco17;
//! assert_eq!(coco.keypoints().len(), 17);
//! let pelvis = &coco.joints()[0];
//! assert_eq!(pelvis.joint, Some(Joint::Pelvis));
//! assert_eq!(Format::detect(&["Hips", "LHipJoint", "LeftUpLeg"]), None);
//! ```

use crate::joint::Joint;
use crate::Vec3;

/// A keypoint format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub enum Format {
    /// Canonical joints by name, any subset that includes the pelvis (CSV files).
    Canonical,
    /// CMU Graphics Lab mocap as BVH, 31 joints; both common naming schemes are recognized.
    Cmu31,
    /// Bandai Namco Research Motion Dataset BVH; its `joint_Root`, fixed at the origin, is
    /// dropped, leaving 21 joints below `Hips`.
    Bandai22,
    /// Human3.6M's 17 joints.
    H36m17,
    /// COCO's 17 keypoints lifted to 3D; pelvis, thorax and head are midpoints.
    Coco17,
    /// MediaPipe BlazePose's 33 world landmarks.
    BlazePose33,
    /// SMPL's 24 joints.
    Smpl24,
    /// Joint centres computed from the GearsSports golf marker set.
    GolfMarkers,
    /// A skeleton read from a file whose joints match no built-in format.
    Custom,
}

/// Where a joint's position comes from, in a frame of the format's keypoints.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Keypoint `i`.
    Keypoint(u8),
    /// The midpoint of keypoints `a` and `b`.
    Mid(u8, u8),
}

/// Where a joint sits in the default T-pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Place {
    /// At a canonical joint's T-pose position.
    At(Joint),
    /// At `a + t (b - a)` between two canonical joints' T-pose positions.
    Between(Joint, Joint, f32),
}

/// One joint of a format's skeleton.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormatJoint {
    /// Name in this format's files.
    pub name: &'static str,
    /// Name in the format's alternative naming scheme (CMU), else the same as `name`.
    pub alt_name: &'static str,
    /// Parent index in [`Format::joints`].
    pub parent: Option<u8>,
    /// Canonical joint, where one applies.
    pub joint: Option<Joint>,
    /// How the joint is read from keypoints.
    pub source: Source,
    /// Where the joint sits in the default T-pose.
    pub place: Place,
}

/// Errors mapping keypoints onto a format's joints.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FormatError {
    /// The keypoint frame has the wrong length.
    #[allow(missing_docs)]
    KeypointCount { expected: usize, actual: usize },
    /// The output buffer is shorter than the format's joint count.
    #[allow(missing_docs)]
    OutputTooShort { needed: usize },
}

impl core::fmt::Display for FormatError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FormatError::KeypointCount { expected, actual } => {
                write!(f, "expected {expected} keypoints, got {actual}")
            }
            FormatError::OutputTooShort { needed } => {
                write!(f, "output holds fewer than {needed} joints")
            }
        }
    }
}

impl core::error::Error for FormatError {}

/// T-pose of a 1.75 m adult, metres, +Y up, facing +Z, left side at +X.
pub fn t_pose(joint: Joint) -> Vec3 {
    let mirrored = joint.mirror() != joint && joint.mirror().index() < joint.index();
    let (x, y, z) = match if mirrored { joint.mirror() } else { joint } {
        Joint::Pelvis => (0.0, 0.95, 0.0),
        Joint::LeftHip => (0.09, 0.90, 0.0),
        Joint::LeftKnee => (0.09, 0.50, 0.01),
        Joint::LeftAnkle => (0.09, 0.08, 0.0),
        Joint::LeftToe => (0.09, 0.02, 0.14),
        Joint::Spine => (0.0, 1.15, -0.01),
        Joint::Thorax => (0.0, 1.40, 0.0),
        Joint::Neck => (0.0, 1.52, 0.0),
        Joint::Head => (0.0, 1.62, 0.02),
        Joint::HeadTop => (0.0, 1.75, 0.0),
        Joint::LeftShoulder => (0.18, 1.42, 0.0),
        Joint::LeftElbow => (0.46, 1.42, -0.01),
        Joint::LeftWrist => (0.72, 1.42, 0.0),
        Joint::LeftHand => (0.80, 1.42, 0.0),
        Joint::ClubGrip => (0.84, 1.42, 0.02),
        Joint::ClubHead => (0.84, 1.42, 1.02),
        // Right-side joints were mirrored above.
        _ => (0.0, 0.0, 0.0),
    };
    Vec3::new(if mirrored { -x } else { x }, y, z)
}

impl Place {
    /// Position in the default T-pose.
    pub fn position(self) -> Vec3 {
        match self {
            Place::At(j) => t_pose(j),
            Place::Between(a, b, t) => t_pose(a) + (t_pose(b) - t_pose(a)) * t,
        }
    }
}

const fn kp(
    name: &'static str,
    alt_name: &'static str,
    parent: i8,
    index: u8,
    joint: Option<Joint>,
    place: Place,
) -> FormatJoint {
    FormatJoint {
        name,
        alt_name,
        parent: if parent < 0 { None } else { Some(parent as u8) },
        joint,
        source: Source::Keypoint(index),
        place,
    }
}

/// A joint read straight from keypoint `index` and placed at its canonical T-pose position.
const fn canon(name: &'static str, parent: i8, index: u8, joint: Joint) -> FormatJoint {
    kp(name, name, parent, index, Some(joint), Place::At(joint))
}

const fn mid(name: &'static str, parent: i8, a: u8, b: u8, joint: Joint) -> FormatJoint {
    FormatJoint {
        source: Source::Mid(a, b),
        ..canon(name, parent, a, joint)
    }
}

use Joint::*;

const H36M: [FormatJoint; 17] = [
    canon("Hip", -1, 0, Pelvis),
    canon("RHip", 0, 1, RightHip),
    canon("RKnee", 1, 2, RightKnee),
    canon("RFoot", 2, 3, RightAnkle),
    canon("LHip", 0, 4, LeftHip),
    canon("LKnee", 4, 5, LeftKnee),
    canon("LFoot", 5, 6, LeftAnkle),
    canon("Spine", 0, 7, Spine),
    canon("Thorax", 7, 8, Thorax),
    canon("Neck/Nose", 8, 9, Neck),
    canon("Head", 9, 10, HeadTop),
    canon("LShoulder", 8, 11, LeftShoulder),
    canon("LElbow", 11, 12, LeftElbow),
    canon("LWrist", 12, 13, LeftWrist),
    canon("RShoulder", 8, 14, RightShoulder),
    canon("RElbow", 14, 15, RightElbow),
    canon("RWrist", 15, 16, RightWrist),
];

const COCO_KEYPOINTS: [&str; 17] = [
    "nose",
    "left_eye",
    "right_eye",
    "left_ear",
    "right_ear",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
];

const COCO: [FormatJoint; 15] = [
    mid("pelvis", -1, 11, 12, Pelvis),
    canon("left_hip", 0, 11, LeftHip),
    canon("left_knee", 1, 13, LeftKnee),
    canon("left_ankle", 2, 15, LeftAnkle),
    canon("right_hip", 0, 12, RightHip),
    canon("right_knee", 4, 14, RightKnee),
    canon("right_ankle", 5, 16, RightAnkle),
    mid("thorax", 0, 5, 6, Thorax),
    mid("head", 7, 3, 4, Head),
    canon("left_shoulder", 7, 5, LeftShoulder),
    canon("left_elbow", 9, 7, LeftElbow),
    canon("left_wrist", 10, 9, LeftWrist),
    canon("right_shoulder", 7, 6, RightShoulder),
    canon("right_elbow", 12, 8, RightElbow),
    canon("right_wrist", 13, 10, RightWrist),
];

const BLAZEPOSE_KEYPOINTS: [&str; 33] = [
    "nose",
    "left_eye_inner",
    "left_eye",
    "left_eye_outer",
    "right_eye_inner",
    "right_eye",
    "right_eye_outer",
    "left_ear",
    "right_ear",
    "mouth_left",
    "mouth_right",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_pinky",
    "right_pinky",
    "left_index",
    "right_index",
    "left_thumb",
    "right_thumb",
    "left_hip",
    "right_hip",
    "left_knee",
    "right_knee",
    "left_ankle",
    "right_ankle",
    "left_heel",
    "right_heel",
    "left_foot_index",
    "right_foot_index",
];

const BLAZEPOSE: [FormatJoint; 19] = [
    mid("pelvis", -1, 23, 24, Pelvis),
    canon("left_hip", 0, 23, LeftHip),
    canon("left_knee", 1, 25, LeftKnee),
    canon("left_ankle", 2, 27, LeftAnkle),
    canon("left_foot_index", 3, 31, LeftToe),
    canon("right_hip", 0, 24, RightHip),
    canon("right_knee", 5, 26, RightKnee),
    canon("right_ankle", 6, 28, RightAnkle),
    canon("right_foot_index", 7, 32, RightToe),
    mid("thorax", 0, 11, 12, Thorax),
    mid("head", 9, 7, 8, Head),
    canon("left_shoulder", 9, 11, LeftShoulder),
    canon("left_elbow", 11, 13, LeftElbow),
    canon("left_wrist", 12, 15, LeftWrist),
    mid("left_hand", 13, 17, 19, LeftHand),
    canon("right_shoulder", 9, 12, RightShoulder),
    canon("right_elbow", 15, 14, RightElbow),
    canon("right_wrist", 16, 16, RightWrist),
    mid("right_hand", 17, 18, 20, RightHand),
];

const SMPL: [FormatJoint; 24] = [
    canon("pelvis", -1, 0, Pelvis),
    canon("left_hip", 0, 1, LeftHip),
    canon("right_hip", 0, 2, RightHip),
    canon("spine1", 0, 3, Spine),
    canon("left_knee", 1, 4, LeftKnee),
    canon("right_knee", 2, 5, RightKnee),
    kp(
        "spine2",
        "spine2",
        3,
        6,
        None,
        Place::Between(Spine, Thorax, 0.5),
    ),
    canon("left_ankle", 4, 7, LeftAnkle),
    canon("right_ankle", 5, 8, RightAnkle),
    canon("spine3", 6, 9, Thorax),
    canon("left_foot", 7, 10, LeftToe),
    canon("right_foot", 8, 11, RightToe),
    canon("neck", 9, 12, Neck),
    kp(
        "left_collar",
        "left_collar",
        9,
        13,
        None,
        Place::Between(Thorax, LeftShoulder, 0.4),
    ),
    kp(
        "right_collar",
        "right_collar",
        9,
        14,
        None,
        Place::Between(Thorax, RightShoulder, 0.4),
    ),
    canon("head", 12, 15, Head),
    canon("left_shoulder", 13, 16, LeftShoulder),
    canon("right_shoulder", 14, 17, RightShoulder),
    canon("left_elbow", 16, 18, LeftElbow),
    canon("right_elbow", 17, 19, RightElbow),
    canon("left_wrist", 18, 20, LeftWrist),
    canon("right_wrist", 19, 21, RightWrist),
    canon("left_hand", 20, 22, LeftHand),
    canon("right_hand", 21, 23, RightHand),
];

const fn cmu(alt: &'static str, j: FormatJoint) -> FormatJoint {
    FormatJoint { alt_name: alt, ..j }
}

const fn extra(name: &'static str, parent: i8, index: u8, place: Place) -> FormatJoint {
    kp(name, name, parent, index, None, place)
}

const CMU: [FormatJoint; 31] = [
    canon("Hips", -1, 0, Pelvis),
    extra("LHipJoint", 0, 1, Place::At(Pelvis)),
    cmu("LeftUpLeg", canon("LeftHip", 1, 2, LeftHip)),
    cmu("LeftLeg", canon("LeftKnee", 2, 3, LeftKnee)),
    cmu("LeftFoot", canon("LeftAnkle", 3, 4, LeftAnkle)),
    cmu("LeftToeBase", canon("LeftToe", 4, 5, LeftToe)),
    extra("RHipJoint", 0, 6, Place::At(Pelvis)),
    cmu("RightUpLeg", canon("RightHip", 6, 7, RightHip)),
    cmu("RightLeg", canon("RightKnee", 7, 8, RightKnee)),
    cmu("RightFoot", canon("RightAnkle", 8, 9, RightAnkle)),
    cmu("RightToeBase", canon("RightToe", 9, 10, RightToe)),
    cmu("LowerBack", extra("lowerback", 0, 11, Place::At(Pelvis))),
    cmu("Spine", canon("Chest", 11, 12, Spine)),
    cmu("Spine1", canon("Chest2", 12, 13, Thorax)),
    cmu("Neck", extra("lowerneck", 13, 14, Place::At(Thorax))),
    cmu("Neck1", canon("Neck", 14, 15, Neck)),
    canon("Head", 15, 16, Head),
    cmu(
        "LeftShoulder",
        extra("LeftCollar", 13, 17, Place::At(Thorax)),
    ),
    cmu("LeftArm", canon("LeftShoulder", 17, 18, LeftShoulder)),
    cmu("LeftForeArm", canon("LeftElbow", 18, 19, LeftElbow)),
    cmu("LeftHand", canon("LeftWrist", 19, 20, LeftWrist)),
    cmu("LeftFingerBase", canon("lhand", 20, 21, LeftHand)),
    cmu(
        "LeftHandIndex1",
        extra("LFingers", 21, 22, Place::Between(LeftWrist, LeftHand, 1.6)),
    ),
    extra("LThumb", 20, 23, Place::Between(LeftWrist, LeftHand, 0.7)),
    cmu(
        "RightShoulder",
        extra("RightCollar", 13, 24, Place::At(Thorax)),
    ),
    cmu("RightArm", canon("RightShoulder", 24, 25, RightShoulder)),
    cmu("RightForeArm", canon("RightElbow", 25, 26, RightElbow)),
    cmu("RightHand", canon("RightWrist", 26, 27, RightWrist)),
    cmu("RightFingerBase", canon("rhand", 27, 28, RightHand)),
    cmu(
        "RightHandIndex1",
        extra(
            "RFingers",
            28,
            29,
            Place::Between(RightWrist, RightHand, 1.6),
        ),
    ),
    extra("RThumb", 27, 30, Place::Between(RightWrist, RightHand, 0.7)),
];

const BANDAI_KEYPOINTS: [&str; 22] = [
    "joint_Root",
    "Hips",
    "Spine",
    "Chest",
    "Neck",
    "Head",
    "Shoulder_L",
    "UpperArm_L",
    "LowerArm_L",
    "Hand_L",
    "Shoulder_R",
    "UpperArm_R",
    "LowerArm_R",
    "Hand_R",
    "UpperLeg_L",
    "LowerLeg_L",
    "Foot_L",
    "Toes_L",
    "UpperLeg_R",
    "LowerLeg_R",
    "Foot_R",
    "Toes_R",
];

const BANDAI: [FormatJoint; 21] = [
    canon("Hips", -1, 1, Pelvis),
    canon("Spine", 0, 2, Spine),
    canon("Chest", 1, 3, Thorax),
    canon("Neck", 2, 4, Neck),
    canon("Head", 3, 5, Head),
    extra(
        "Shoulder_L",
        2,
        6,
        Place::Between(Thorax, LeftShoulder, 0.3),
    ),
    canon("UpperArm_L", 5, 7, LeftShoulder),
    canon("LowerArm_L", 6, 8, LeftElbow),
    canon("Hand_L", 7, 9, LeftWrist),
    extra(
        "Shoulder_R",
        2,
        10,
        Place::Between(Thorax, RightShoulder, 0.3),
    ),
    canon("UpperArm_R", 9, 11, RightShoulder),
    canon("LowerArm_R", 10, 12, RightElbow),
    canon("Hand_R", 11, 13, RightWrist),
    canon("UpperLeg_L", 0, 14, LeftHip),
    canon("LowerLeg_L", 13, 15, LeftKnee),
    canon("Foot_L", 14, 16, LeftAnkle),
    canon("Toes_L", 15, 17, LeftToe),
    canon("UpperLeg_R", 0, 18, RightHip),
    canon("LowerLeg_R", 17, 19, RightKnee),
    canon("Foot_R", 18, 20, RightAnkle),
    canon("Toes_R", 19, 21, RightToe),
];

const GOLF: [FormatJoint; 22] = [
    canon("pelvis", -1, 0, Pelvis),
    canon("left_hip", 0, 1, LeftHip),
    canon("left_knee", 1, 2, LeftKnee),
    canon("left_ankle", 2, 3, LeftAnkle),
    canon("left_toe", 3, 4, LeftToe),
    canon("right_hip", 0, 5, RightHip),
    canon("right_knee", 5, 6, RightKnee),
    canon("right_ankle", 6, 7, RightAnkle),
    canon("right_toe", 7, 8, RightToe),
    canon("spine", 0, 9, Spine),
    canon("thorax", 9, 10, Thorax),
    canon("neck", 10, 11, Neck),
    canon("head", 11, 12, Head),
    canon("head_top", 12, 13, HeadTop),
    canon("left_shoulder", 10, 14, LeftShoulder),
    canon("left_elbow", 14, 15, LeftElbow),
    canon("left_wrist", 15, 16, LeftWrist),
    canon("right_shoulder", 10, 17, RightShoulder),
    canon("right_elbow", 17, 18, RightElbow),
    canon("right_wrist", 18, 19, RightWrist),
    canon("club_grip", 16, 20, ClubGrip),
    canon("club_head", 20, 21, ClubHead),
];

const fn names<const N: usize>(joints: &[FormatJoint; N]) -> [&'static str; N] {
    let mut out = [""; N];
    let mut i = 0;
    while i < N {
        out[i] = joints[i].name;
        i += 1;
    }
    out
}

const H36M_KEYPOINTS: [&str; 17] = names(&H36M);
const SMPL_KEYPOINTS: [&str; 24] = names(&SMPL);
const CMU_KEYPOINTS: [&str; 31] = names(&CMU);
const GOLF_KEYPOINTS: [&str; 22] = names(&GOLF);

/// Whether `a` is `b` with `b`'s first `from` bytes replaced by `a`'s first `to` bytes, where
/// those are `left` and `right` (in either order): `a = x + rest`, `b = y + rest`.
const fn same_rest(a: &[u8], b: &[u8], from: usize, to: usize, suffix: bool) -> bool {
    if a.len() < from || b.len() < to || a.len() - from != b.len() - to {
        return false;
    }
    let n = a.len() - from;
    let (a0, b0) = if suffix { (0, 0) } else { (from, to) };
    let mut i = 0;
    while i < n {
        if a[a0 + i] != b[b0 + i] {
            return false;
        }
        i += 1;
    }
    true
}

/// Whether `s` starts (or, with `suffix`, ends) with `part`.
const fn has(s: &[u8], part: &[u8], suffix: bool) -> bool {
    if s.len() < part.len() {
        return false;
    }
    let at = if suffix { s.len() - part.len() } else { 0 };
    let mut i = 0;
    while i < part.len() {
        if s[at + i] != part[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// Whether `a` and `b` name a keypoint and its counterpart on the other side of the body: the
/// same name but for a leading `Left`/`Right`, `left`/`right`, `L`/`R` or `l`/`r`, or a trailing
/// `_L`/`_R` or `_left`/`_right`, in either order.
const fn mirror_names(a: &str, b: &str) -> bool {
    const SIDES: [(&str, &str, bool); 6] = [
        ("Left", "Right", false),
        ("left", "right", false),
        ("L", "R", false),
        ("l", "r", false),
        ("_L", "_R", true),
        ("_left", "_right", true),
    ];
    let (a, b) = (a.as_bytes(), b.as_bytes());
    let mut i = 0;
    while i < SIDES.len() {
        let (l, r, suffix) = SIDES[i];
        let (l, r) = (l.as_bytes(), r.as_bytes());
        if (has(a, l, suffix) && has(b, r, suffix) && same_rest(a, b, l.len(), r.len(), suffix))
            || (has(a, r, suffix) && has(b, l, suffix) && same_rest(a, b, r.len(), l.len(), suffix))
        {
            return true;
        }
        i += 1;
    }
    false
}

/// Each of `names`' counterpart ([`mirror_names`]), else itself.
const fn keypoint_mirrors<const N: usize>(names: &[&str; N]) -> [u8; N] {
    let mut out = [0u8; N];
    let mut i = 0;
    while i < N {
        out[i] = i as u8;
        let mut j = 0;
        while j < N {
            if mirror_names(names[i], names[j]) {
                out[i] = j as u8;
            }
            j += 1;
        }
        i += 1;
    }
    out
}

/// Each of `joints`' counterpart: the joint read from its keypoints' counterparts `mirrors`
/// (a midpoint's in either order), else itself.
const fn joint_mirrors<const J: usize>(joints: &[FormatJoint; J], mirrors: &[u8]) -> [u8; J] {
    let mut out = [0u8; J];
    let mut k = 0;
    while k < J {
        out[k] = k as u8;
        let mut j = 0;
        while j < J {
            let same = match (joints[k].source, joints[j].source) {
                (Source::Keypoint(a), Source::Keypoint(b)) => mirrors[a as usize] == b,
                (Source::Mid(a, b), Source::Mid(c, d)) => {
                    let (ma, mb) = (mirrors[a as usize], mirrors[b as usize]);
                    (ma == c && mb == d) || (ma == d && mb == c)
                }
                _ => false,
            };
            if same {
                out[k] = j as u8;
            }
            j += 1;
        }
        k += 1;
    }
    out
}

const H36M_KEYPOINT_MIRRORS: [u8; 17] = keypoint_mirrors(&H36M_KEYPOINTS);
const SMPL_KEYPOINT_MIRRORS: [u8; 24] = keypoint_mirrors(&SMPL_KEYPOINTS);
const CMU_KEYPOINT_MIRRORS: [u8; 31] = keypoint_mirrors(&CMU_KEYPOINTS);
const GOLF_KEYPOINT_MIRRORS: [u8; 22] = keypoint_mirrors(&GOLF_KEYPOINTS);
const COCO_KEYPOINT_MIRRORS: [u8; 17] = keypoint_mirrors(&COCO_KEYPOINTS);
const BLAZEPOSE_KEYPOINT_MIRRORS: [u8; 33] = keypoint_mirrors(&BLAZEPOSE_KEYPOINTS);
const BANDAI_KEYPOINT_MIRRORS: [u8; 22] = keypoint_mirrors(&BANDAI_KEYPOINTS);
const H36M_JOINT_MIRRORS: [u8; 17] = joint_mirrors(&H36M, &H36M_KEYPOINT_MIRRORS);
const SMPL_JOINT_MIRRORS: [u8; 24] = joint_mirrors(&SMPL, &SMPL_KEYPOINT_MIRRORS);
const CMU_JOINT_MIRRORS: [u8; 31] = joint_mirrors(&CMU, &CMU_KEYPOINT_MIRRORS);
const GOLF_JOINT_MIRRORS: [u8; 22] = joint_mirrors(&GOLF, &GOLF_KEYPOINT_MIRRORS);
const COCO_JOINT_MIRRORS: [u8; 15] = joint_mirrors(&COCO, &COCO_KEYPOINT_MIRRORS);
const BLAZEPOSE_JOINT_MIRRORS: [u8; 19] = joint_mirrors(&BLAZEPOSE, &BLAZEPOSE_KEYPOINT_MIRRORS);
const BANDAI_JOINT_MIRRORS: [u8; 21] = joint_mirrors(&BANDAI, &BANDAI_KEYPOINT_MIRRORS);

impl Format {
    /// Every format with a fixed joint table.
    pub const BUILT_IN: [Format; 7] = [
        Format::Cmu31,
        Format::Bandai22,
        Format::H36m17,
        Format::Coco17,
        Format::BlazePose33,
        Format::Smpl24,
        Format::GolfMarkers,
    ];

    /// Short name used on the command line and in files.
    pub const fn name(self) -> &'static str {
        match self {
            Format::Canonical => "canonical",
            Format::Cmu31 => "cmu31",
            Format::Bandai22 => "bandai22",
            Format::H36m17 => "h36m17",
            Format::Coco17 => "coco17",
            Format::BlazePose33 => "blazepose33",
            Format::Smpl24 => "smpl24",
            Format::GolfMarkers => "golf",
            Format::Custom => "custom",
        }
    }

    /// The format called `name` (as [`Format::name`] writes it).
    pub fn from_name(name: &str) -> Option<Format> {
        Format::BUILT_IN
            .into_iter()
            .chain([Format::Canonical, Format::Custom])
            .find(|f| f.name() == name)
    }

    /// The keypoints a frame of this format carries, in order (empty for canonical and custom).
    pub const fn keypoints(self) -> &'static [&'static str] {
        match self {
            Format::Cmu31 => &CMU_KEYPOINTS,
            Format::Bandai22 => &BANDAI_KEYPOINTS,
            Format::H36m17 => &H36M_KEYPOINTS,
            Format::Coco17 => &COCO_KEYPOINTS,
            Format::BlazePose33 => &BLAZEPOSE_KEYPOINTS,
            Format::Smpl24 => &SMPL_KEYPOINTS,
            Format::GolfMarkers => &GOLF_KEYPOINTS,
            Format::Canonical | Format::Custom => &[],
        }
    }

    /// The skeleton joints built from the keypoints (empty for canonical and custom).
    pub const fn joints(self) -> &'static [FormatJoint] {
        match self {
            Format::Cmu31 => &CMU,
            Format::Bandai22 => &BANDAI,
            Format::H36m17 => &H36M,
            Format::Coco17 => &COCO,
            Format::BlazePose33 => &BLAZEPOSE,
            Format::Smpl24 => &SMPL,
            Format::GolfMarkers => &GOLF,
            Format::Canonical | Format::Custom => &[],
        }
    }

    /// The built-in format whose joint names (either naming scheme) are exactly `names`, in
    /// order. Names of dropped joints above the pelvis (Bandai's `joint_Root`) must already be
    /// removed.
    pub fn detect(names: &[&str]) -> Option<Format> {
        Format::BUILT_IN.into_iter().find(|f| {
            let joints = f.joints();
            joints.len() == names.len()
                && (joints.iter().zip(names).all(|(j, n)| j.name == *n)
                    || joints.iter().zip(names).all(|(j, n)| j.alt_name == *n))
        })
    }

    /// Keypoint `i`'s counterpart on the other side of the body: the keypoint whose name has
    /// left and right exchanged (`LHip` and `RHip`, `left_eye` and `right_eye`, `Hand_L` and
    /// `Hand_R`, `lhand` and `rhand`), else `i` itself (a keypoint on the body's middle, or
    /// past the format's keypoints). A pose estimator that swaps left and right sends each
    /// keypoint in its counterpart's place.
    pub fn mirror_keypoint(self, i: usize) -> usize {
        self.mirrored_keypoints()
            .get(i)
            .map_or(i, |&m| usize::from(m))
    }

    /// Joint `k`'s counterpart on the other side of the body: the joint read from the
    /// counterparts of its keypoints ([`Format::mirror_keypoint`]), else `k` itself (a joint on
    /// the body's middle: a midpoint of two counterparts is its own). Joints, like keypoints,
    /// pair up: the counterpart's counterpart is the joint itself.
    pub fn mirror_joint(self, k: usize) -> usize {
        self.mirrored_joints().get(k).map_or(k, |&m| usize::from(m))
    }

    /// Each keypoint's counterpart ([`Format::mirror_keypoint`]), made at compile time.
    pub const fn mirrored_keypoints(self) -> &'static [u8] {
        match self {
            Format::Cmu31 => &CMU_KEYPOINT_MIRRORS,
            Format::Bandai22 => &BANDAI_KEYPOINT_MIRRORS,
            Format::H36m17 => &H36M_KEYPOINT_MIRRORS,
            Format::Coco17 => &COCO_KEYPOINT_MIRRORS,
            Format::BlazePose33 => &BLAZEPOSE_KEYPOINT_MIRRORS,
            Format::Smpl24 => &SMPL_KEYPOINT_MIRRORS,
            Format::GolfMarkers => &GOLF_KEYPOINT_MIRRORS,
            Format::Canonical | Format::Custom => &[],
        }
    }

    /// Each joint's counterpart ([`Format::mirror_joint`]), made at compile time: a device
    /// reads it every frame without storing or searching it.
    pub const fn mirrored_joints(self) -> &'static [u8] {
        match self {
            Format::Cmu31 => &CMU_JOINT_MIRRORS,
            Format::Bandai22 => &BANDAI_JOINT_MIRRORS,
            Format::H36m17 => &H36M_JOINT_MIRRORS,
            Format::Coco17 => &COCO_JOINT_MIRRORS,
            Format::BlazePose33 => &BLAZEPOSE_JOINT_MIRRORS,
            Format::Smpl24 => &SMPL_JOINT_MIRRORS,
            Format::GolfMarkers => &GOLF_JOINT_MIRRORS,
            Format::Canonical | Format::Custom => &[],
        }
    }

    /// Maps one frame of keypoints onto the format's joints.
    ///
    /// # Errors
    /// [`FormatError::KeypointCount`] if `keypoints` is not [`Format::keypoints`] long,
    /// [`FormatError::OutputTooShort`] if `out` cannot hold [`Format::joints`].
    pub fn map_keypoints(self, keypoints: &[Vec3], out: &mut [Vec3]) -> Result<(), FormatError> {
        let expected = self.keypoints().len();
        if keypoints.len() != expected {
            return Err(FormatError::KeypointCount {
                expected,
                actual: keypoints.len(),
            });
        }
        let joints = self.joints();
        let out = out
            .get_mut(..joints.len())
            .ok_or(FormatError::OutputTooShort {
                needed: joints.len(),
            })?;
        let at = |i: u8| {
            keypoints
                .get(i as usize)
                .copied()
                .unwrap_or_else(Vec3::zeros)
        };
        for (o, j) in out.iter_mut().zip(joints) {
            *o = match j.source {
                Source::Keypoint(i) => at(i),
                Source::Mid(a, b) => (at(a) + at(b)) * 0.5,
            };
        }
        Ok(())
    }
}

impl core::fmt::Display for Format {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::Skeleton;

    #[test]
    fn every_built_in_table_is_a_valid_skeleton_of_plausible_height() {
        for format in Format::BUILT_IN.into_iter().chain([Format::Canonical]) {
            let skeleton = match Skeleton::standard(format) {
                Ok(s) => s,
                Err(e) => panic!("{format}: {e}"),
            };
            let h = skeleton.height();
            assert!((1.4..2.1).contains(&h), "{format}: height {h}");
            for (i, j) in format.joints().iter().enumerate() {
                if let Some(p) = j.parent {
                    assert!((p as usize) < i, "{format}: {} before its parent", j.name);
                }
                let max = match j.source {
                    Source::Keypoint(a) => a,
                    Source::Mid(a, b) => a.max(b),
                };
                assert!(
                    (max as usize) < format.keypoints().len(),
                    "{format}: {}",
                    j.name
                );
            }
        }
    }

    #[test]
    fn detect_recognizes_both_cmu_schemes_and_rejects_reordering() {
        let primary: [&str; 31] = CMU_KEYPOINTS;
        let alt: [&str; 31] = core::array::from_fn(|i| CMU[i].alt_name);
        assert_eq!(Format::detect(&primary), Some(Format::Cmu31));
        assert_eq!(Format::detect(&alt), Some(Format::Cmu31));
        let mut swapped = primary;
        swapped.swap(1, 2);
        assert_eq!(Format::detect(&swapped), None);
        assert_eq!(
            Format::detect(&BANDAI_KEYPOINTS[1..]),
            Some(Format::Bandai22)
        );
    }

    #[test]
    fn left_and_right_pair_up_in_every_format() {
        for format in Format::BUILT_IN {
            let (keypoints, joints) = (format.keypoints().len(), format.joints().len());
            for i in 0..keypoints {
                let m = format.mirror_keypoint(i);
                assert_eq!(format.mirror_keypoint(m), i, "{format}: keypoint {i}");
            }
            for (k, j) in format.joints().iter().enumerate() {
                let m = format.mirror_joint(k);
                assert_eq!(format.mirror_joint(m), k, "{format}: {}", j.name);
                // A canonical joint's counterpart is its mirror image's.
                if let (Some(a), Some(b)) = (j.joint, format.joints()[m].joint) {
                    assert_eq!(a.mirror(), b, "{format}: {}", j.name);
                }
                // Every body joint placed off the middle has a counterpart (the club has
                // none), and a canonical joint on it has none (CMU's hip joints and collars sit on the middle in the
                // T-pose, and pair up).
                let club = j.joint.is_some_and(Joint::is_club);
                if j.place.position().x.abs() > 1e-6 && !club {
                    assert_ne!(m, k, "{format}: {}", j.name);
                }
                if j.joint.is_some_and(|c| c.mirror() == c) {
                    assert_eq!(m, k, "{format}: {}", j.name);
                }
            }
            assert_eq!(format.mirror_joint(joints), joints);
            assert_eq!(format.mirrored_joints().len(), joints);
            assert_eq!(format.mirrored_keypoints().len(), keypoints);
        }
        assert_eq!(Format::Cmu31.mirror_keypoint(1), 6); // LHipJoint, RHipJoint
        assert_eq!(Format::Cmu31.mirror_keypoint(11), 11); // lowerback
        assert_eq!(Format::Coco17.mirror_keypoint(1), 2); // the eyes
        assert_eq!(Format::BlazePose33.mirror_keypoint(9), 10); // the mouth's corners
    }

    #[test]
    fn midpoints_are_computed_from_keypoints() {
        let kps: [Vec3; 17] = core::array::from_fn(|i| Vec3::new(i as f32, 0.0, 0.0));
        let mut out = [Vec3::zeros(); 15];
        assert_eq!(Format::Coco17.map_keypoints(&kps, &mut out), Ok(()));
        assert_eq!(out[0].x, 11.5);
        assert_eq!(out[1].x, 11.0);
        assert_eq!(
            Format::Coco17.map_keypoints(&kps[..3], &mut out),
            Err(FormatError::KeypointCount {
                expected: 17,
                actual: 3
            })
        );
    }
}
