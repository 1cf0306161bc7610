//! Keypoint JSON as pose-estimator scripts write it: one object per frame.
//!
//! The frames are a JSON array, an object's `frames` array, or one object per line (JSON
//! Lines). In a frame, the time is the first key that names one ([`keypoints::clock_of`]:
//! `time`, `t`, `timestamp`, `time_ms`, `frame`, ...), and the landmarks are the value of
//! `keypoints`, `landmarks`, `joints`, `pose_world_landmarks`, `pose_landmarks`, `landmark` or
//! `keypoints_3d` (inside the first of `people` or `instances` where those hold them), else
//! the frame's other keys. They may be:
//!
//! - an object of name → point;
//! - an array of points that name themselves (`name`, `label`, `type` or `joint`);
//! - an array of unnamed points, or a flat array of numbers (x, y, z and, where four per
//!   landmark fit, a confidence), named by the vocabulary with that many landmarks
//!   ([`Landmarks::of_count`]: 33 MediaPipe BlazePose, 17 COCO, 25 OpenPose, 32 Azure Kinect).
//!
//! A point is `[x, y, z]`, `[x, y, z, confidence]` or `{"x", "y", "z"}` with an optional
//! `visibility`, `presence`, `score`, `confidence` or `likelihood`; `null` is a missing sample.
//! The first frame's landmarks are the file's; a landmark absent from a later frame is missing
//! there. Units, up axis and clock are decided as for CSV ([`keypoints::motion`]).

use crate::keypoints::{self, Hints, KeypointError, Reading, Samples, MIN_CONFIDENCE};
use crate::landmarks::Landmarks;
use crate::motion::Motion;
use posecoach_core::Vec3;
use serde_json::{Map, Value};
use std::fmt;

/// A JSON problem, with the 1-based frame where it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct JsonError {
    /// 1-based frame; 0 when the whole file is concerned.
    pub frame: usize,
    /// What is wrong.
    pub kind: JsonErrorKind,
}

/// What is wrong with a keypoint JSON file.
#[derive(Clone, Debug, PartialEq)]
pub enum JsonErrorKind {
    /// Not JSON (the parser's message names the line and column).
    Syntax(String),
    /// No frames.
    NoFrames,
    /// A frame is not an object.
    NotAnObject,
    /// A frame whose landmarks are not found.
    NoLandmarks,
    /// Unnamed landmarks in a number no vocabulary has.
    Count(usize),
    /// Unnamed landmarks in a number other than the first frame's.
    CountChanged {
        /// The first frame's.
        expected: usize,
        /// This frame's.
        actual: usize,
    },
    /// A landmark that is not a point (named).
    BadPoint(String),
    /// A time that is not a finite number.
    BadTime,
    /// Time does not increase.
    TimeNotIncreasing,
    /// The samples are not a motion (the whole file).
    Keypoints(KeypointError),
}

impl fmt::Display for JsonError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.frame > 0 {
            write!(f, "frame {}: ", self.frame)?;
        }
        match &self.kind {
            JsonErrorKind::Syntax(e) => write!(f, "not JSON: {e}"),
            JsonErrorKind::NoFrames => f.write_str(
                "no frames: expected an array of frame objects, a `frames` array or one object per line",
            ),
            JsonErrorKind::NotAnObject => f.write_str("a frame must be an object"),
            JsonErrorKind::NoLandmarks => f.write_str(
                "no landmarks: expected `keypoints`, `landmarks` or `joints`, or landmark names as keys",
            ),
            JsonErrorKind::Count(n) => write!(
                f,
                "{n} unnamed landmarks match no vocabulary (33 BlazePose, 17 COCO, 25 OpenPose, \
                 32 Kinect): name them"
            ),
            JsonErrorKind::CountChanged { expected, actual } => write!(
                f,
                "{actual} unnamed landmarks where the first frame has {expected}"
            ),
            JsonErrorKind::BadPoint(name) => write!(
                f,
                "landmark `{name}` is not a point: expected [x, y, z], {{\"x\", \"y\", \"z\"}} or null"
            ),
            JsonErrorKind::BadTime => f.write_str("the time is not a finite number"),
            JsonErrorKind::TimeNotIncreasing => f.write_str("time must increase from frame to frame"),
            JsonErrorKind::Keypoints(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for JsonError {}

fn err(frame: usize, kind: JsonErrorKind) -> JsonError {
    JsonError { frame, kind }
}

/// Parses a keypoint JSON file, with what [`Hints`] say about it, and says how it was read.
///
/// # Errors
/// A [`JsonError`] naming the frame and what was expected, or (frame 0) why the samples are
/// not a motion.
pub fn read_with(bytes: &[u8], hints: &Hints) -> Result<(Motion, Reading), JsonError> {
    let samples = samples(bytes)?;
    keypoints::motion(&samples, hints).map_err(|e| err(0, JsonErrorKind::Keypoints(e)))
}

/// Keys a frame's landmarks are found under.
const LANDMARK_KEYS: [&str; 8] = [
    "keypoints",
    "landmarks",
    "joints",
    "pose_world_landmarks",
    "pose_landmarks",
    "landmark",
    "keypoints_3d",
    "pose_keypoints_3d",
];

/// Keys a point's confidence is found under.
const CONFIDENCE_KEYS: [&str; 5] = [
    "visibility",
    "presence",
    "score",
    "confidence",
    "likelihood",
];

/// Keys a point's name is found under.
const NAME_KEYS: [&str; 4] = ["name", "label", "type", "joint"];

/// The file's frames.
fn frames(bytes: &[u8]) -> Result<Vec<Value>, JsonError> {
    let values: Vec<Value> = serde_json::Deserializer::from_slice(bytes)
        .into_iter::<Value>()
        .collect::<Result<_, _>>()
        .map_err(|e| err(0, JsonErrorKind::Syntax(e.to_string())))?;
    let frames = match <[Value; 1]>::try_from(values) {
        Ok([Value::Array(frames)]) => frames,
        Ok([Value::Object(mut top)]) => match top.remove("frames") {
            Some(Value::Array(frames)) => frames,
            _ => vec![Value::Object(top)],
        },
        Ok([other]) => vec![other],
        Err(values) => values,
    };
    if frames.is_empty() {
        return Err(err(0, JsonErrorKind::NoFrames));
    }
    Ok(frames)
}

/// A frame's landmarks: the value under a [`LANDMARK_KEYS`] key (inside the first of `people`
/// or `instances`), else the frame's other keys.
fn landmarks_of(frame: &Map<String, Value>, clock: Option<&str>) -> Value {
    for holder in ["people", "instances"] {
        if let Some(Value::Object(first)) = frame.get(holder).and_then(|v| v.get(0)) {
            return landmarks_of(first, None);
        }
    }
    if let Some(v) = LANDMARK_KEYS.iter().find_map(|k| frame.get(*k)) {
        // `{"landmark": [...]}`, as a landmark list converted to JSON nests it.
        if let Value::Object(inner) = v {
            if let (1, Some(list @ Value::Array(_))) = (inner.len(), inner.get("landmark")) {
                return list.clone();
            }
        }
        return v.clone();
    }
    // Only values that may be points: a frame's other numbers and strings (a rate, a source)
    // are not landmarks.
    let rest: Map<String, Value> = frame
        .iter()
        .filter(|(k, v)| {
            Some(k.as_str()) != clock && (v.is_array() || v.is_object() || v.is_null())
        })
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    Value::Object(rest)
}

/// A point's position and confidence; `None` for `null`.
fn point(v: &Value) -> Result<Option<(Vec3, f64)>, ()> {
    let num = |v: Option<&Value>| v.and_then(Value::as_f64).filter(|x| x.is_finite());
    let (xyz, confidence) = match v {
        Value::Null => return Ok(None),
        Value::Array(a) if a.len() == 3 || a.len() == 4 => {
            ([num(a.first()), num(a.get(1)), num(a.get(2))], a.get(3))
        }
        Value::Object(o) => (
            [num(o.get("x")), num(o.get("y")), num(o.get("z"))],
            CONFIDENCE_KEYS.iter().find_map(|k| o.get(*k)),
        ),
        _ => return Err(()),
    };
    let [Some(x), Some(y), Some(z)] = xyz else {
        return Err(());
    };
    let confidence = match confidence {
        None => 1.0,
        Some(c) => num(Some(c)).ok_or(())?,
    };
    Ok(Some((Vec3::new(x as f32, y as f32, z as f32), confidence)))
}

/// One frame's landmarks as (name, point) pairs, and whether they were named by position
/// (unnamed, named by their vocabulary).
fn named(landmarks: Value, frame: usize) -> Result<(Vec<(String, Value)>, bool), JsonError> {
    let unnamed = |points: Vec<Value>| {
        let vocabulary = Landmarks::of_count(points.len())
            .ok_or(err(frame, JsonErrorKind::Count(points.len())))?;
        let names = vocabulary.names().into_iter().map(str::to_string);
        Ok((names.zip(points).collect(), true))
    };
    match landmarks {
        Value::Object(map) => Ok((map.into_iter().collect(), false)),
        Value::Array(items) if items.iter().all(Value::is_number) => {
            let per = [4, 3]
                .into_iter()
                .find(|&per| {
                    items.len() % per == 0 && Landmarks::of_count(items.len() / per).is_some()
                })
                .ok_or(err(frame, JsonErrorKind::Count(items.len() / 3)))?;
            unnamed(
                items
                    .chunks(per)
                    .map(|c| Value::Array(c.to_vec()))
                    .collect(),
            )
        }
        Value::Array(items) => {
            let name = |v: &Value| {
                NAME_KEYS
                    .iter()
                    .find_map(|k| v.get(*k).and_then(Value::as_str))
                    .map(str::to_string)
            };
            match items.iter().map(name).collect::<Option<Vec<String>>>() {
                Some(names) if !names.is_empty() => {
                    Ok((names.into_iter().zip(items).collect(), false))
                }
                _ => unnamed(items),
            }
        }
        _ => Err(err(frame, JsonErrorKind::NoLandmarks)),
    }
}

/// The file's samples, as written.
fn samples(bytes: &[u8]) -> Result<Samples, JsonError> {
    let frames = frames(bytes)?;
    let mut out = Samples::default();
    let mut count = None;
    for (f, frame) in frames.into_iter().enumerate() {
        let at = f + 1;
        let Value::Object(frame) = frame else {
            return Err(err(at, JsonErrorKind::NotAnObject));
        };
        let clock = frame
            .keys()
            .find(|k| keypoints::clock_of(k).is_some())
            .cloned();
        if f == 0 {
            out.clock.clone_from(&clock);
        }
        if let Some(key) = &out.clock {
            let t = frame
                .get(key)
                .and_then(Value::as_f64)
                .filter(|t| t.is_finite())
                .ok_or(err(at, JsonErrorKind::BadTime))?;
            if out.times.last().is_some_and(|&last| t <= last) {
                return Err(err(at, JsonErrorKind::TimeNotIncreasing));
            }
            out.times.push(t);
        }
        let (points, positional) = named(landmarks_of(&frame, clock.as_deref()), at)?;
        match count {
            None => {
                out.names = points.iter().map(|(n, _)| n.clone()).collect();
                count = Some(points.len());
            }
            // By position the count must hold; by name a landmark may be absent.
            Some(expected) if positional && points.len() != expected => {
                let actual = points.len();
                return Err(err(at, JsonErrorKind::CountChanged { expected, actual }));
            }
            Some(_) => {}
        }
        let row = out.positions.len();
        out.positions.resize(row + out.names.len(), Vec3::zeros());
        out.missing.resize(row + out.names.len(), true);
        for (name, value) in points {
            let Some(k) = out.names.iter().position(|n| *n == name) else {
                if !out.ignored.contains(&name) {
                    out.ignored.push(name);
                }
                continue;
            };
            let p = point(&value).map_err(|()| err(at, JsonErrorKind::BadPoint(name.clone())))?;
            if let Some((position, confidence)) = p {
                out.positions[row + k] = position;
                out.missing[row + k] = confidence < f64::from(MIN_CONFIDENCE);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use posecoach_core::format::t_pose;
    use posecoach_core::joint::Joint;

    /// The standard T-pose as `frames` BlazePose frames in millimetres, as `shape` writes one
    /// frame from its 33 landmarks (name, position).
    fn blazepose(frames: usize, shape: impl Fn(usize, &[(&str, [f32; 3])]) -> String) -> String {
        let names = Landmarks::BlazePose33.names();
        let at = |name: &str| {
            let p = match name {
                "left_hip" => t_pose(Joint::LeftHip),
                "right_hip" => t_pose(Joint::RightHip),
                "left_knee" => t_pose(Joint::LeftKnee),
                "right_knee" => t_pose(Joint::RightKnee),
                "left_ankle" => t_pose(Joint::LeftAnkle),
                "right_ankle" => t_pose(Joint::RightAnkle),
                "left_foot_index" => t_pose(Joint::LeftToe),
                "right_foot_index" => t_pose(Joint::RightToe),
                "left_shoulder" => t_pose(Joint::LeftShoulder),
                "right_shoulder" => t_pose(Joint::RightShoulder),
                "left_elbow" => t_pose(Joint::LeftElbow),
                "right_elbow" => t_pose(Joint::RightElbow),
                "left_wrist" => t_pose(Joint::LeftWrist),
                "right_wrist" => t_pose(Joint::RightWrist),
                n if n.starts_with("left") => t_pose(Joint::LeftHand),
                n if n.starts_with("right") => t_pose(Joint::RightHand),
                _ => t_pose(Joint::Head),
            };
            // MediaPipe's world landmarks: +y down.
            [p.x * 1000.0, -p.y * 1000.0, -p.z * 1000.0]
        };
        let lines: Vec<String> = (0..frames)
            .map(|f| {
                let points: Vec<(&str, [f32; 3])> = names.iter().map(|&n| (n, at(n))).collect();
                shape(f, &points)
            })
            .collect();
        lines.join("\n")
    }

    #[test]
    fn mediapipe_frames_in_every_shape_read_alike() {
        let by_name = |f: usize, points: &[(&str, [f32; 3])]| {
            let body: Vec<String> = points
                .iter()
                .map(|(n, [x, y, z])| {
                    format!("\"{n}\": {{\"x\": {x}, \"y\": {y}, \"z\": {z}, \"visibility\": 0.9}}")
                })
                .collect();
            format!(
                "{{\"time_ms\": {}, \"landmarks\": {{{}}}}}",
                f * 33,
                body.join(", ")
            )
        };
        let by_position = |f: usize, points: &[(&str, [f32; 3])]| {
            let body: Vec<String> = points
                .iter()
                .map(|(_, [x, y, z])| format!("[{x}, {y}, {z}]"))
                .collect();
            format!(
                "{{\"t\": {}, \"keypoints\": [{}]}}",
                f as f64 / 30.0,
                body.join(", ")
            )
        };
        let listed = |f: usize, points: &[(&str, [f32; 3])]| {
            let body: Vec<String> = points
                .iter()
                .map(|(n, [x, y, z])| {
                    format!("{{\"name\": \"{n}\", \"x\": {x}, \"y\": {y}, \"z\": {z}}}")
                })
                .collect();
            format!(
                "{{\"frame\": {f}, \"pose_world_landmarks\": {{\"landmark\": [{}]}}}}",
                body.join(", ")
            )
        };
        let hints = Hints::default();
        let (a, reading) = read_with(blazepose(40, by_name).as_bytes(), &hints).unwrap();
        assert_eq!(reading.landmarks, Landmarks::BlazePose33);
        assert_eq!(reading.units.0, crate::units::Units::Mm);
        assert_eq!(reading.up.0.to_string(), "-y");
        assert!((a.rate_hz - 30.3).abs() < 0.1, "{}", a.rate_hz);
        let array = format!("[{}]", blazepose(40, by_position).replace('\n', ","));
        let (b, _) = read_with(array.as_bytes(), &hints).unwrap();
        assert_eq!(a.positions, b.positions);
        let with_rate = Hints {
            rate_hz: Some(30.0),
            ..hints
        };
        let (c, reading) = read_with(blazepose(40, listed).as_bytes(), &with_rate).unwrap();
        assert_eq!(reading.clock.0, keypoints::Clock::Frames);
        assert_eq!(a.positions, c.positions);
        assert!(
            (1.5..1.7).contains(&a.skeleton.height()),
            "{}",
            a.skeleton.height()
        );
    }

    #[test]
    fn errors_name_the_frame() {
        type Case = (&'static str, usize, fn(&JsonErrorKind) -> bool);
        let cases: [Case; 5] = [
            ("", 0, |k| matches!(k, JsonErrorKind::NoFrames)),
            ("[1, 2", 0, |k| matches!(k, JsonErrorKind::Syntax(_))),
            ("[{\"t\": 0, \"keypoints\": [[0, 0, 0]]}]", 1, |k| {
                matches!(k, JsonErrorKind::Count(1))
            }),
            (
                "{\"t\": 0, \"pelvis\": [0, 1, 0]}\n{\"t\": 0, \"pelvis\": [0, 1, 0]}",
                2,
                |k| matches!(k, JsonErrorKind::TimeNotIncreasing),
            ),
            ("{\"t\": 0, \"pelvis\": [0, \"a\", 0]}", 1, |k| {
                matches!(k, JsonErrorKind::BadPoint(_))
            }),
        ];
        for (text, frame, kind) in cases {
            let e = read_with(text.as_bytes(), &Hints::default()).unwrap_err();
            assert_eq!(e.frame, frame, "{text}: {e}");
            assert!(kind(&e.kind), "{text}: {e}");
        }
    }
}
