//! Approximate joint centres from the GearsSports golf marker set (see the golf section of the
//! shared data README).
//!
//! The markers sit on the skin and the club, not on the joints, so every centre below is an
//! approximation: knee, ankle, elbow and wrist take the lateral (or dorsal) marker itself, about
//! 3–5 cm from the true joint centre, and the hips follow a regression from the pelvis markers.
//! Axes are those of the file (+Y up; the golfer faces −X at address, lead/left side toward +Z),
//! units are metres.
//!
//! Labels are matched exactly, or as the part after a `Subject:` prefix (e.g.
//! `Golfer:WaistLeft`), so exports that prefix the subject name also work.
use posecoach_core::Vec3;
use std::fmt;

use crate::c3d::{max_gap_frames, C3d, Frame};

/// Canonical joint names produced, in output order, and how each is estimated:
/// - pelvis: mean of the four waist markers; hips: Bell/Davis-style regression from the waist
///   markers (the front pair taken as ASIS-like, the back pair as PSIS-like; see
///   [`joint_centres`] for the accuracy);
/// - knee = KneeOut, ankle = AnkleOut (lateral markers), toe = mean of ToeIn and ToeOut;
/// - shoulder: mean of ShoulderTop and ShoulderBack. Not lowered: a sphere fit of ElbowOut in
///   the shoulder cluster puts the glenohumeral centre 5–7 cm lower, but a fixed drop along the
///   trunk axis made the shoulder–elbow distance less constant (sd 6 → 10–14 mm);
/// - thorax: midpoint of the shoulders; spine: midpoint of pelvis and thorax;
/// - head: mean of HeadTop, HeadFront and HeadSide (HeadSide is on the left, pulling the mean
///   a few cm left); head_top = HeadTop; neck: 35 % of the way from thorax to head;
/// - elbow = ElbowOut, wrist = WristTop;
/// - club_grip: mean of the `Marker_3:3:*` shaft cluster, which sits about 30 cm below the
///   hands; club_head: mean of the `Marker_2:2:*` cluster on the club head.
#[rustfmt::skip]
pub const GOLF_JOINTS: [&str; 22] = [
    "pelvis",
    "left_hip", "left_knee", "left_ankle", "left_toe",
    "right_hip", "right_knee", "right_ankle", "right_toe",
    "spine", "thorax", "neck", "head", "head_top",
    "left_shoulder", "left_elbow", "left_wrist",
    "right_shoulder", "right_elbow", "right_wrist",
    "club_grip", "club_head",
];

/// The marker labels read; all must be present in the file.
#[rustfmt::skip]
pub const GOLF_MARKERS: [&str; 33] = [
    "WaistLeft", "WaistRight", "WaistLBack", "WaistRBack", "BackLeft", "BackRight",
    "HeadTop", "HeadFront", "HeadSide",
    "LShoulderTop", "LShoulderBack", "LUArmHigh", "LElbowOut", "LWristTop",
    "RShoulderTop", "RShoulderBack", "RUArmHigh", "RElbowOut", "RWristTop",
    "LKneeOut", "LAnkleOut", "LToeIn", "LToeOut",
    "RKneeOut", "RAnkleOut", "RToeIn", "RToeOut",
    "Marker_2:2:1", "Marker_2:2:2", "Marker_2:2:3",
    "Marker_3:3:1", "Marker_3:3:2", "Marker_3:3:3",
];

/// Clusters that fill the shoulder-top markers: target, then the three markers of its
/// [`Frame`]. Of the clusters tried, deleting LShoulderTop where it was seen and refilling it
/// from the rest of the trial gave the smallest error with this one (mean 17–27 mm, max
/// 33–45 mm; BackTop/BackLeft/BackRight: mean 49–68 mm; ShoulderBack/UArmHigh/ElbowOut: mean
/// 92–170 mm).
const SHOULDER_CLUSTERS: [(&str, [&str; 3]); 2] = [
    ("LShoulderTop", ["LShoulderBack", "BackLeft", "LUArmHigh"]),
    ("RShoulderTop", ["RShoulderBack", "BackRight", "RUArmHigh"]),
];

/// Pelvis markers: front left, front right, back left, back right.
const WAIST: [&str; 4] = ["WaistLeft", "WaistRight", "WaistLBack", "WaistRBack"];
/// Hip-centre offsets as fractions of the pelvis width (Bell et al. 1990, as used by Davis).
const HIP_LATERAL: f32 = 0.36;
const HIP_POSTERIOR: f32 = 0.19;
const HIP_INFERIOR: f32 = 0.30;
/// Neck position along thorax → head.
const NECK_FRACTION: f32 = 0.35;

/// Joint-centre trajectories.
#[derive(Debug, Clone, PartialEq)]
pub struct JointCentres {
    /// Frames per second.
    pub rate_hz: f32,
    /// Number of frames.
    pub frames: usize,
    /// `frames × GOLF_JOINTS` positions in metres (+Y up, axes as in the file); zero where
    /// invalid.
    pub positions: Vec<Vec3>,
    /// `frames × GOLF_JOINTS`: whether every marker the joint needs was present or filled.
    pub valid: Vec<bool>,
    /// Marker samples filled by gap and rigid-cluster filling.
    pub filled: usize,
}

/// Why joint centres could not be computed.
#[derive(Debug, Clone, PartialEq)]
pub enum GolfError {
    /// A required marker label is absent from the file.
    MissingMarker(String),
}

impl fmt::Display for GolfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GolfError::MissingMarker(m) => write!(f, "golf marker {m:?} is not in the file"),
        }
    }
}

impl std::error::Error for GolfError {}

/// Column of marker `name`: exact label, else a label `<prefix>:<name>`.
fn find_label(c3d: &C3d, name: &str) -> Option<usize> {
    c3d.label_index(name).or_else(|| {
        let prefixed = |l: &String| l.strip_suffix(name).is_some_and(|p| p.ends_with(':'));
        c3d.labels.iter().position(prefixed)
    })
}

/// Column of `name` in [`GOLF_MARKERS`] (`usize::MAX`, which reads as missing, if absent).
fn marker(name: &str) -> usize {
    GOLF_MARKERS
        .iter()
        .position(|&m| m == name)
        .unwrap_or(usize::MAX)
}

/// Joint centres ([`GOLF_JOINTS`]) from the markers.
///
/// The [`GOLF_MARKERS`] are gap-filled first ([`C3d::fill_gaps`] over at most
/// [`MAX_GAP_S`](crate::c3d::MAX_GAP_S));
/// the shoulder-top markers are then rigid-filled ([`C3d::fill_rigid`]) from ShoulderBack,
/// BackLeft/BackRight and UArmHigh of the same side (RShoulderTop is missing in 80–86 % of the
/// frames, LShoulderTop in frames 0–109 of the iron trial). A joint is invalid in a frame when
/// a marker it needs is still missing.
///
/// On the two GearsSports trials, deleting LShoulderTop where it was seen and refilling it
/// this way is off by 17–27 mm on average (at most 45 mm). The hip centres keep the
/// hip–KneeOut distance constant to 4–12 mm (sd), but a functional sphere fit of KneeOut in
/// the pelvis frame puts them 1–2 cm further out, 3–4 cm further forward and 3–10 cm lower:
/// treat hip height as uncertain by several centimetres.
///
/// # Errors
/// [`GolfError::MissingMarker`] when one of the [`GOLF_MARKERS`] is not in the file.
pub fn joint_centres(c3d: &C3d) -> Result<JointCentres, GolfError> {
    let columns = GOLF_MARKERS.iter().map(|&name| {
        find_label(c3d, name).ok_or_else(|| GolfError::MissingMarker(name.to_owned()))
    });
    let columns = columns.collect::<Result<Vec<usize>, _>>()?;
    let mut markers = C3d {
        labels: GOLF_MARKERS.map(str::to_owned).to_vec(),
        points: Vec::with_capacity(c3d.frames * columns.len()),
        valid: Vec::with_capacity(c3d.frames * columns.len()),
        ..*c3d
    };
    for f in 0..c3d.frames {
        for &column in &columns {
            let p = c3d.point(f, column);
            markers.points.push(p.unwrap_or_default());
            markers.valid.push(p.is_some());
        }
    }
    let mut filled = markers.fill_gaps(max_gap_frames(markers.rate_hz));
    for (target, cluster) in SHOULDER_CLUSTERS {
        filled += markers.fill_rigid(marker(target), cluster.map(marker));
    }

    let mut out = JointCentres {
        rate_hz: c3d.rate_hz,
        frames: c3d.frames,
        positions: Vec::with_capacity(c3d.frames * GOLF_JOINTS.len()),
        valid: Vec::with_capacity(c3d.frames * GOLF_JOINTS.len()),
        filled,
    };
    for f in 0..c3d.frames {
        for p in frame_joints(|name| markers.point(f, marker(name))) {
            out.positions.push(p.unwrap_or_default());
            out.valid.push(p.is_some());
        }
    }
    Ok(out)
}

/// The [`GOLF_JOINTS`] of one frame from its markers (`None` where a marker is missing).
fn frame_joints(at: impl Fn(&str) -> Option<Vec3>) -> [Option<Vec3>; GOLF_JOINTS.len()] {
    let mean = |names: &[&str]| {
        let sum = names
            .iter()
            .try_fold(Vec3::zeros(), |s, n| Some(s + at(n)?));
        Some(sum? * (1.0 / names.len() as f32))
    };
    let lerp = |a: Option<Vec3>, b: Option<Vec3>, t: f32| {
        let (a, b) = (a?, b?);
        Some(a + (b - a) * t)
    };
    let hips = match WAIST.map(&at) {
        [Some(l), Some(r), Some(lb), Some(rb)] => hip_centres([l, r, lb, rb]),
        _ => None,
    };
    let [left_hip, right_hip] = hips.map_or([None; 2], |h| h.map(Some));
    let pelvis = mean(&WAIST);
    let left_shoulder = mean(&["LShoulderTop", "LShoulderBack"]);
    let right_shoulder = mean(&["RShoulderTop", "RShoulderBack"]);
    let thorax = lerp(left_shoulder, right_shoulder, 0.5);
    let head = mean(&["HeadTop", "HeadFront", "HeadSide"]);
    [
        pelvis,
        left_hip,
        at("LKneeOut"),
        at("LAnkleOut"),
        mean(&["LToeIn", "LToeOut"]),
        right_hip,
        at("RKneeOut"),
        at("RAnkleOut"),
        mean(&["RToeIn", "RToeOut"]),
        lerp(pelvis, thorax, 0.5),
        thorax,
        lerp(thorax, head, NECK_FRACTION),
        head,
        at("HeadTop"),
        left_shoulder,
        at("LElbowOut"),
        at("LWristTop"),
        right_shoulder,
        at("RElbowOut"),
        at("RWristTop"),
        mean(&["Marker_3:3:1", "Marker_3:3:2", "Marker_3:3:3"]),
        mean(&["Marker_2:2:1", "Marker_2:2:2", "Marker_2:2:3"]),
    ]
}

/// Left and right hip centres, Bell/Davis style, from the [`WAIST`] markers.
///
/// In these captures WaistLeft/WaistRight sit about 15 cm anterior to WaistLBack/WaistRBack
/// and 35 cm apart (wider than a typical inter-ASIS distance), the back pair 17 cm apart: an
/// ASIS/PSIS-like layout. The pelvis frame has its lateral axis from the right (front + back)
/// midpoint to the left one, its forward axis from the back pair toward the front pair made
/// orthogonal, and up = forward × lateral. The width `w` is the distance between the left and
/// right midpoints (≈ 26 cm), and each hip lies at the front midpoint + (±0.36 w lateral,
/// −0.19 w forward, −0.30 w up). Of the variants tried (origin at the front midpoint or the
/// mean of the four, `w` from the front pair or the midpoints) this one kept the hip–KneeOut
/// distance most constant.
fn hip_centres([left, right, lback, rback]: [Vec3; 4]) -> Option<[Vec3; 2]> {
    let mid = |a: Vec3, b: Vec3| (a + b) * 0.5;
    let (left_mid, right_mid, front) = (mid(left, lback), mid(right, rback), mid(left, right));
    let w = (left_mid - right_mid).norm();
    // x: toward the left, y: forward, z: x × forward = down.
    let [lateral, forward, down] = Frame::new(right_mid, left_mid, front)?.axes;
    let hip = |side: f32| {
        let offsets = [
            (lateral, side * HIP_LATERAL),
            (forward, -HIP_POSTERIOR),
            (down, HIP_INFERIOR),
        ];
        offsets
            .iter()
            .fold(front, |p, &(axis, k)| p + axis * (k * w))
    };
    Some([hip(1.0), hip(-1.0)])
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use crate::c3d::tests::data_dir;

    const TOLERANCE: f32 = 1e-6;
    const FRAMES: usize = 3;
    /// Stand-in position of any marker not placed explicitly.
    fn spot(m: usize) -> Vec3 {
        Vec3::new(
            0.01 * m as f32,
            0.5 + 0.02 * m as f32,
            0.1 - 0.03 * m as f32,
        )
    }
    /// Waist markers of a golfer facing −X, left toward +Z: front pair 30 cm apart, back pair
    /// 20 cm apart and 14 cm behind, so the midpoint width is 25 cm.
    const WAIST_AT: [Vec3; 4] = [
        Vec3::new(0.0, 1.0, 0.15),
        Vec3::new(0.0, 1.0, -0.15),
        Vec3::new(0.14, 1.0, 0.1),
        Vec3::new(0.14, 1.0, -0.1),
    ];

    /// Static markers (labels with a subject prefix), all valid.
    fn synthetic() -> C3d {
        let n = GOLF_MARKERS.len();
        let at = |m: usize| WAIST_AT.get(m).copied().unwrap_or(spot(m));
        C3d {
            labels: GOLF_MARKERS.iter().map(|m| format!("Pro:{m}")).collect(),
            rate_hz: 360.0,
            frames: FRAMES,
            first_frame: 1,
            units_to_metres: 1.0,
            points: (0..FRAMES * n).map(|i| at(i % n)).collect(),
            valid: vec![true; FRAMES * n],
        }
    }

    fn joint(jc: &JointCentres, f: usize, name: &str) -> Option<Vec3> {
        let i = f * GOLF_JOINTS.len() + GOLF_JOINTS.iter().position(|&j| j == name).unwrap();
        jc.valid[i].then_some(jc.positions[i])
    }

    fn assert_near(a: Vec3, b: impl Into<Vec3>) {
        let b = b.into();
        assert!((a - b).norm() < TOLERANCE, "{a:?} vs {b:?}");
    }

    #[test]
    fn joint_centres_of_a_synthetic_frame() {
        let mut c = synthetic();
        let n = GOLF_MARKERS.len();
        c.valid[marker("RShoulderTop")] = false; // frame 0: rigid-filled from its cluster
        c.valid[(FRAMES - 1) * n + marker("HeadSide")] = false; // last frame: stays missing
        let jc = joint_centres(&c).unwrap();
        assert_eq!((jc.frames, jc.filled, jc.rate_hz), (FRAMES, 1, 360.0));
        let m = |name: &str| spot(marker(name));
        let mean = |names: &[&str]| {
            let sum: Vec3 = names.iter().map(|&name| m(name)).sum();
            sum / names.len() as f32
        };
        assert_near(joint(&jc, 0, "pelvis").unwrap(), [0.07, 1.0, 0.0]);
        // w = 0.25: 0.09 lateral, 0.0475 posterior (+X), 0.075 down.
        assert_near(joint(&jc, 0, "left_hip").unwrap(), [0.0475, 0.925, 0.09]);
        assert_near(joint(&jc, 1, "right_hip").unwrap(), [0.0475, 0.925, -0.09]);
        assert_near(joint(&jc, 0, "left_knee").unwrap(), m("LKneeOut"));
        assert_near(
            joint(&jc, 0, "right_toe").unwrap(),
            mean(&["RToeIn", "RToeOut"]),
        );
        let right_shoulder = mean(&["RShoulderTop", "RShoulderBack"]);
        assert_near(joint(&jc, 0, "right_shoulder").unwrap(), right_shoulder);
        let left_shoulder = mean(&["LShoulderTop", "LShoulderBack"]);
        let thorax = (left_shoulder + right_shoulder) / 2.0;
        assert_near(joint(&jc, 1, "thorax").unwrap(), thorax);
        let spine = (thorax + Vec3::new(0.07, 1.0, 0.0)) / 2.0;
        assert_near(joint(&jc, 1, "spine").unwrap(), spine);
        let head = mean(&["HeadTop", "HeadFront", "HeadSide"]);
        assert_near(joint(&jc, 1, "head").unwrap(), head);
        let neck = thorax + (head - thorax) * NECK_FRACTION;
        assert_near(joint(&jc, 1, "neck").unwrap(), neck);
        let club = ["Marker_2:2:1", "Marker_2:2:2", "Marker_2:2:3"];
        assert_near(joint(&jc, 1, "club_head").unwrap(), mean(&club));
        let last = FRAMES - 1;
        assert_eq!(
            (joint(&jc, last, "head"), joint(&jc, last, "neck")),
            (None, None)
        );
        assert_near(joint(&jc, last, "head_top").unwrap(), m("HeadTop"));
    }

    #[test]
    fn missing_label_is_an_error() {
        let mut c = synthetic();
        c.labels[marker("HeadSide")] = "Hat".into();
        let e = joint_centres(&c).unwrap_err();
        assert_eq!(e, GolfError::MissingMarker("HeadSide".into()));
        assert_eq!(e.to_string(), "golf marker \"HeadSide\" is not in the file");
    }

    /// Mean and standard deviation.
    fn mean_sd(xs: &[f32]) -> (f32, f32) {
        let m = xs.iter().sum::<f32>() / xs.len() as f32;
        let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f32>() / xs.len() as f32;
        (m, var.sqrt())
    }

    /// Peak speed (m/s) of a joint by central differences over valid neighbours.
    fn peak_speed(jc: &JointCentres, name: &str) -> f32 {
        let speeds = (1..jc.frames.saturating_sub(1)).filter_map(|f| {
            let d = joint(jc, f + 1, name)? - joint(jc, f - 1, name)?;
            Some(d.norm() * jc.rate_hz / 2.0)
        });
        speeds.fold(0.0, f32::max)
    }

    #[test]
    fn golf_files_give_plausible_skeletons() {
        const BONES: [(&str, &str); 10] = [
            ("pelvis", "left_hip"),
            ("left_hip", "left_knee"),
            ("right_hip", "right_knee"),
            ("left_knee", "left_ankle"),
            ("right_knee", "right_ankle"),
            ("left_shoulder", "left_elbow"),
            ("right_shoulder", "right_elbow"),
            ("left_elbow", "left_wrist"),
            ("right_elbow", "right_wrist"),
            ("club_grip", "club_head"),
        ];
        const MAX_BONE_SD: f32 = 0.025;
        const MAX_SPEED: f32 = 100.0;
        let Some(dir) = data_dir() else {
            eprintln!("skipping: golf data folder not found (set POSECOACH_DATA)");
            return;
        };
        for (file, club_speed) in [
            ("gears_tour_driver.c3d", 42.0..58.0),
            ("gears_tour_iron.c3d", 33.0..47.0),
        ] {
            let c = C3d::parse(&std::fs::read(dir.join(file)).unwrap()).unwrap();
            let jc = joint_centres(&c).unwrap();
            eprintln!(
                "{file}: {} frames at {} Hz, {} samples filled",
                jc.frames, jc.rate_hz, jc.filled
            );
            for (j, name) in GOLF_JOINTS.iter().enumerate() {
                let invalid = (0..jc.frames)
                    .filter(|f| !jc.valid[f * GOLF_JOINTS.len() + j])
                    .count();
                if invalid > 0 {
                    eprintln!("  {name}: {invalid} invalid frames");
                }
                assert!(invalid == 0 || name.starts_with("club"), "{file} {name}");
                assert!(invalid < 40, "{file} {name}");
            }
            for (a, b) in BONES {
                let lengths: Vec<f32> = (0..jc.frames)
                    .filter_map(|f| Some((joint(&jc, f, a)? - joint(&jc, f, b)?).norm()))
                    .collect();
                let (m, sd) = mean_sd(&lengths);
                eprintln!("  {a}–{b}: {m:.3} ± {sd:.4} m");
                assert!(sd < MAX_BONE_SD, "{file} {a}–{b}");
            }
            let toe_y = (joint(&jc, 0, "left_toe").unwrap().y
                + joint(&jc, 0, "right_toe").unwrap().y)
                / 2.0;
            let height = joint(&jc, 0, "head_top").unwrap().y - toe_y;
            let tallest = (0..jc.frames)
                .filter_map(|f| joint(&jc, f, "head_top"))
                .map(|p| p.y - toe_y);
            eprintln!(
                "  head top above the toes: {height:.3} m at address, {:.3} m at most",
                tallest.fold(0.0, f32::max)
            );
            let (club, wrist) = (peak_speed(&jc, "club_head"), peak_speed(&jc, "left_wrist"));
            let fastest = GOLF_JOINTS
                .iter()
                .map(|j| peak_speed(&jc, j))
                .fold(0.0, f32::max);
            eprintln!("  peak speeds (m/s): club head {club:.1}, lead wrist {wrist:.1}, any joint {fastest:.1}");
            assert!((1.5..2.0).contains(&height), "{file}");
            assert!(club_speed.contains(&club), "{file}");
            assert!((4.0..15.0).contains(&wrist), "{file}");
            assert!(fastest < MAX_SPEED, "{file}");
        }
    }
}
