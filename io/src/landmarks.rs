//! Landmark names as pose estimators and depth cameras spell them, and how each canonical joint
//! is made from them.
//!
//! A keypoint file names its landmarks in one of several vocabularies. Names are compared after
//! [`key`] (lower case, letters and digits only), so `left_hip`, `LeftHip` and `LEFT HIP` are
//! one name. The vocabulary is the one that knows the most of the file's names
//! ([`Landmarks::detect`]); each canonical joint is then the first of its sources whose
//! landmarks the file has: one landmark, or the midpoint of two (the pelvis from the hips where
//! a vocabulary has no pelvis).
//!
//! ```
//! use posecoach_io::landmarks::{key, Landmarks};
//! let names = ["nose", "left_eye_inner", "left_hip", "right_hip"].map(key);
//! assert_eq!(Landmarks::detect(&names), Landmarks::BlazePose33);
//! ```

use posecoach_core::format::{Format, Source};
use posecoach_core::joint::Joint;
use std::collections::HashSet;
use std::fmt;

/// A vocabulary of landmark names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Landmarks {
    /// posecoach's own joint names ([`Joint::name`]).
    Canonical,
    /// COCO's 17 keypoints (also MMPose's and YOLO's 2D-to-3D lifters).
    Coco17,
    /// MediaPipe BlazePose's 33 landmarks.
    BlazePose33,
    /// OpenPose's BODY_25 (and its 18-keypoint COCO model, the same names without `MidHip` and
    /// the feet).
    OpenPose25,
    /// Azure Kinect Body Tracking's 32 joints, and Kinect v2's names for the same places.
    Kinect32,
}

/// OpenPose BODY_25, in its output order.
const OPENPOSE: [&str; 25] = [
    "Nose",
    "Neck",
    "RShoulder",
    "RElbow",
    "RWrist",
    "LShoulder",
    "LElbow",
    "LWrist",
    "MidHip",
    "RHip",
    "RKnee",
    "RAnkle",
    "LHip",
    "LKnee",
    "LAnkle",
    "REye",
    "LEye",
    "REar",
    "LEar",
    "LBigToe",
    "LSmallToe",
    "LHeel",
    "RBigToe",
    "RSmallToe",
    "RHeel",
];

/// Azure Kinect's 32 joints in its output order, then Kinect v2's names that differ once
/// compared as [`key`]s (`HipLeft` and `HIP_LEFT` are one name).
const KINECT: [&str; 35] = [
    "PELVIS",
    "SPINE_NAVAL",
    "SPINE_CHEST",
    "NECK",
    "CLAVICLE_LEFT",
    "SHOULDER_LEFT",
    "ELBOW_LEFT",
    "WRIST_LEFT",
    "HAND_LEFT",
    "HANDTIP_LEFT",
    "THUMB_LEFT",
    "CLAVICLE_RIGHT",
    "SHOULDER_RIGHT",
    "ELBOW_RIGHT",
    "WRIST_RIGHT",
    "HAND_RIGHT",
    "HANDTIP_RIGHT",
    "THUMB_RIGHT",
    "HIP_LEFT",
    "KNEE_LEFT",
    "ANKLE_LEFT",
    "FOOT_LEFT",
    "HIP_RIGHT",
    "KNEE_RIGHT",
    "ANKLE_RIGHT",
    "FOOT_RIGHT",
    "HEAD",
    "NOSE",
    "EYE_LEFT",
    "EAR_LEFT",
    "EYE_RIGHT",
    "EAR_RIGHT",
    // Kinect v2.
    "SpineBase",
    "SpineMid",
    "SpineShoulder",
];

/// Where a canonical joint comes from: one landmark, or the midpoint of two.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// The landmark of this name.
    One(&'static str),
    /// The midpoint of two landmarks.
    Mid(&'static str, &'static str),
}

use Origin::{Mid, One};

/// Sources, in order of preference, for the joints OpenPose names.
const OPENPOSE_JOINTS: &[(Joint, &[Origin])] = &[
    (Joint::Pelvis, &[One("MidHip"), Mid("LHip", "RHip")]),
    (Joint::LeftHip, &[One("LHip")]),
    (Joint::LeftKnee, &[One("LKnee")]),
    (Joint::LeftAnkle, &[One("LAnkle")]),
    (Joint::LeftToe, &[One("LBigToe")]),
    (Joint::RightHip, &[One("RHip")]),
    (Joint::RightKnee, &[One("RKnee")]),
    (Joint::RightAnkle, &[One("RAnkle")]),
    (Joint::RightToe, &[One("RBigToe")]),
    // OpenPose's neck is the midpoint of the shoulders: posecoach's thorax.
    (Joint::Thorax, &[One("Neck"), Mid("LShoulder", "RShoulder")]),
    (Joint::Head, &[Mid("LEar", "REar")]),
    (Joint::LeftShoulder, &[One("LShoulder")]),
    (Joint::LeftElbow, &[One("LElbow")]),
    (Joint::LeftWrist, &[One("LWrist")]),
    (Joint::RightShoulder, &[One("RShoulder")]),
    (Joint::RightElbow, &[One("RElbow")]),
    (Joint::RightWrist, &[One("RWrist")]),
];

/// Sources for the joints Kinect names (Azure first, then v2).
const KINECT_JOINTS: &[(Joint, &[Origin])] = &[
    (Joint::Pelvis, &[One("PELVIS"), One("SpineBase")]),
    (Joint::LeftHip, &[One("HIP_LEFT")]),
    (Joint::LeftKnee, &[One("KNEE_LEFT")]),
    (Joint::LeftAnkle, &[One("ANKLE_LEFT")]),
    (Joint::LeftToe, &[One("FOOT_LEFT")]),
    (Joint::RightHip, &[One("HIP_RIGHT")]),
    (Joint::RightKnee, &[One("KNEE_RIGHT")]),
    (Joint::RightAnkle, &[One("ANKLE_RIGHT")]),
    (Joint::RightToe, &[One("FOOT_RIGHT")]),
    (Joint::Spine, &[One("SPINE_NAVAL"), One("SpineMid")]),
    (Joint::Thorax, &[One("SPINE_CHEST"), One("SpineShoulder")]),
    (Joint::Neck, &[One("NECK")]),
    (Joint::Head, &[One("HEAD")]),
    (Joint::LeftShoulder, &[One("SHOULDER_LEFT")]),
    (Joint::LeftElbow, &[One("ELBOW_LEFT")]),
    (Joint::LeftWrist, &[One("WRIST_LEFT")]),
    (Joint::LeftHand, &[One("HAND_LEFT")]),
    (Joint::RightShoulder, &[One("SHOULDER_RIGHT")]),
    (Joint::RightElbow, &[One("ELBOW_RIGHT")]),
    (Joint::RightWrist, &[One("WRIST_RIGHT")]),
    (Joint::RightHand, &[One("HAND_RIGHT")]),
];

/// The name compared: lower case, letters and digits only.
pub fn key(name: &str) -> String {
    name.chars()
        .filter(char::is_ascii_alphanumeric)
        .map(|c| c.to_ascii_lowercase())
        .collect()
}

/// The [`key`]s of every name some vocabulary knows.
pub fn known() -> HashSet<String> {
    Landmarks::ALL
        .iter()
        .flat_map(|l| l.names())
        .map(key)
        .collect()
}

impl Landmarks {
    /// Every vocabulary, in the order [`Landmarks::detect`] prefers on a tie.
    pub const ALL: [Landmarks; 5] = [
        Landmarks::Canonical,
        Landmarks::Coco17,
        Landmarks::BlazePose33,
        Landmarks::OpenPose25,
        Landmarks::Kinect32,
    ];

    /// How reports name the vocabulary.
    pub const fn title(self) -> &'static str {
        match self {
            Landmarks::Canonical => "posecoach joint names",
            Landmarks::Coco17 => "COCO-17 keypoints",
            Landmarks::BlazePose33 => "MediaPipe BlazePose-33 landmarks",
            Landmarks::OpenPose25 => "OpenPose BODY_25 keypoints",
            Landmarks::Kinect32 => "Kinect joints",
        }
    }

    /// The vocabulary's names; where it has an output order (a pose estimator's landmark
    /// list), in that order.
    pub fn names(self) -> Vec<&'static str> {
        match self {
            Landmarks::Canonical => Joint::ALL.iter().map(|j| j.name()).collect(),
            Landmarks::Coco17 => Format::Coco17.keypoints().to_vec(),
            Landmarks::BlazePose33 => Format::BlazePose33.keypoints().to_vec(),
            Landmarks::OpenPose25 => OPENPOSE.to_vec(),
            Landmarks::Kinect32 => KINECT.to_vec(),
        }
    }

    /// How many landmarks a frame holds where a file lists them by position, without names.
    pub fn count(self) -> usize {
        match self {
            Landmarks::Kinect32 => 32,
            other => other.names().len(),
        }
    }

    /// Each canonical joint the vocabulary can give, with its sources in order of preference.
    pub fn joints(self) -> Vec<(Joint, Vec<Origin>)> {
        match self {
            Landmarks::Canonical => Joint::ALL
                .iter()
                .map(|&j| {
                    let mut from = vec![One(j.name())];
                    if j == Joint::Pelvis {
                        from.push(Mid("left_hip", "right_hip"));
                    }
                    (j, from)
                })
                .collect(),
            Landmarks::Coco17 => from_format(Format::Coco17),
            Landmarks::BlazePose33 => from_format(Format::BlazePose33),
            Landmarks::OpenPose25 => table(OPENPOSE_JOINTS),
            Landmarks::Kinect32 => table(KINECT_JOINTS),
        }
    }

    /// The vocabulary that knows the most of `keys` ([`key`]s of a file's landmark names),
    /// the first in [`Landmarks::ALL`] on a tie.
    pub fn detect(keys: &[String]) -> Landmarks {
        let known = |l: Landmarks| {
            let names: Vec<String> = l.names().into_iter().map(key).collect();
            keys.iter().filter(|k| names.contains(k)).count()
        };
        let mut best = Landmarks::Canonical;
        for l in Landmarks::ALL {
            if known(l) > known(best) {
                best = l;
            }
        }
        best
    }

    /// The vocabulary whose frames hold `count` unnamed landmarks, if one does.
    pub fn of_count(count: usize) -> Option<Landmarks> {
        Landmarks::ALL.into_iter().find(|l| l.count() == count)
    }
}

impl fmt::Display for Landmarks {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.title())
    }
}

fn table(rows: &[(Joint, &[Origin])]) -> Vec<(Joint, Vec<Origin>)> {
    rows.iter().map(|(j, from)| (*j, from.to_vec())).collect()
}

/// The canonical joints of a built-in keypoint format, from its own table: the pelvis, thorax
/// and head are the midpoints the format defines.
fn from_format(format: Format) -> Vec<(Joint, Vec<Origin>)> {
    let names = format.keypoints();
    let name = |i: u8| names.get(usize::from(i)).copied().unwrap_or_default();
    format
        .joints()
        .iter()
        .filter_map(|j| {
            let from = match j.source {
                Source::Keypoint(i) => One(name(i)),
                Source::Mid(a, b) => Mid(name(a), name(b)),
            };
            j.joint.map(|joint| (joint, vec![from]))
        })
        .collect()
}

/// One canonical joint as made from a file's landmarks: indices into the file's landmark list,
/// the two equal for a single landmark.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Made {
    /// The joint.
    pub joint: Joint,
    /// The landmarks averaged (the same one twice for a single landmark).
    pub from: [usize; 2],
}

/// Each canonical joint `landmarks` can make from a file's landmark `keys`, in canonical
/// order, from the first of its sources whose landmarks are all there.
pub fn make(landmarks: Landmarks, keys: &[String]) -> Vec<Made> {
    let mut made: Vec<Made> = made_from(landmarks, keys);
    made.sort_by_key(|m| m.joint);
    made
}

fn made_from(landmarks: Landmarks, keys: &[String]) -> Vec<Made> {
    let find = |name: &str| {
        let k = key(name);
        keys.iter().position(|x| *x == k)
    };
    landmarks
        .joints()
        .into_iter()
        .filter_map(|(joint, sources)| {
            sources.iter().find_map(|s| {
                let from = match *s {
                    One(a) => find(a).map(|a| [a, a]),
                    Mid(a, b) => find(a).zip(find(b)).map(|(a, b)| [a, b]),
                };
                from.map(|from| Made { joint, from })
            })
        })
        .collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn keys(names: &[&str]) -> Vec<String> {
        names.iter().map(|n| key(n)).collect()
    }

    #[test]
    fn each_vocabulary_is_detected_from_its_own_names() {
        for l in Landmarks::ALL {
            assert_eq!(Landmarks::detect(&keys(&l.names())), l, "{l}");
            assert_eq!(Landmarks::of_count(l.count()), Some(l), "{l}");
        }
        assert_eq!(Landmarks::of_count(31), None);
        // COCO's names are all BlazePose's too: a tie goes to COCO.
        assert_eq!(
            Landmarks::detect(&keys(Format::Coco17.keypoints())),
            Landmarks::Coco17
        );
    }

    #[test]
    fn every_vocabulary_gives_a_pelvis_and_the_arms() {
        for l in Landmarks::ALL {
            let made = make(l, &keys(&l.names()));
            let joints: Vec<Joint> = made.iter().map(|m| m.joint).collect();
            for j in [
                Joint::Pelvis,
                Joint::LeftHip,
                Joint::RightAnkle,
                Joint::LeftWrist,
                Joint::RightShoulder,
            ] {
                assert!(joints.contains(&j), "{l}: no {j}");
            }
            let mut sorted = joints.clone();
            sorted.sort();
            assert_eq!(sorted, joints, "{l}: canonical order");
        }
    }

    #[test]
    fn a_missing_pelvis_is_the_hips_midpoint() {
        let names = keys(&["Left Hip", "right-hip", "LEFT_KNEE"]);
        let made = make(Landmarks::detect(&names), &names);
        assert_eq!(
            made[0],
            Made {
                joint: Joint::Pelvis,
                from: [0, 1]
            }
        );
        let openpose = keys(&["MidHip", "LHip", "RHip"]);
        assert_eq!(make(Landmarks::OpenPose25, &openpose)[0].from, [0, 0]);
        assert_eq!(Landmarks::detect(&openpose), Landmarks::OpenPose25);
    }

    #[test]
    fn kinect_v2_names_read_as_azure_ones() {
        let v2 = keys(&[
            "SpineBase",
            "SpineMid",
            "SpineShoulder",
            "HipLeft",
            "HipRight",
            "KneeLeft",
            "AnkleLeft",
            "FootLeft",
            "ShoulderLeft",
            "WristRight",
        ]);
        assert_eq!(Landmarks::detect(&v2), Landmarks::Kinect32);
        let joints: Vec<Joint> = make(Landmarks::Kinect32, &v2)
            .iter()
            .map(|m| m.joint)
            .collect();
        for j in [
            Joint::Pelvis,
            Joint::Spine,
            Joint::Thorax,
            Joint::LeftHip,
            Joint::LeftToe,
            Joint::RightWrist,
        ] {
            assert!(joints.contains(&j), "{j}");
        }
    }

    #[test]
    fn openpose_neck_is_the_thorax() {
        let names = keys(&OPENPOSE);
        let made = make(Landmarks::OpenPose25, &names);
        let thorax = made.iter().find(|m| m.joint == Joint::Thorax).unwrap();
        assert_eq!(thorax.from, [1, 1]);
        assert!(made.iter().all(|m| m.joint != Joint::Neck));
    }
}
