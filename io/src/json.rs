//! Keypoint JSON as pose-estimator scripts write it: one object per frame.
//!
//! The frames are a JSON array, an object's `frames` array, or one object per line (JSON
//! Lines). In a frame, the time is the key that says time, before one that counts frames
//! ([`keypoints::time_among`]: `time`, `t`, `timestamp`, `time_ms`, then `frame`, ...), and
//! the landmarks are the value of `keypoints`, `landmarks`, `joints`, `pose_world_landmarks`,
//! `pose_landmarks`, `landmark` or `keypoints_3d` (inside the first of `people` or
//! `instances` where those hold them; the first pose of a list of poses), else the frame's
//! other keys. A frame where nobody was found is missing; one with only 2D keypoints is
//! refused. They may be:
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
//!
//! The document is never held as `serde_json` values (36 times its size): its syntax is
//! checked as a whole first, allocating nothing, so that a fault anywhere is reported before
//! any frame is read; then each frame is read from its own text, its points straight into the
//! samples (`json/value.rs`). Reading takes the file, the samples and one frame's keys.

mod value;

use crate::keypoints::{self, Hints, KeypointError, Reading, Samples, MIN_CONFIDENCE};
use crate::landmarks::Landmarks;
use crate::motion::Motion;
use crate::places::Places;
use posecoach_core::Vec3;
use serde_json::value::RawValue;
use std::collections::HashSet;
use std::fmt;
use value::{Item, Kind, Object, Point};

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
    /// Only 2D keypoints (OpenPose's `pose_keypoints_2d`, a `keypoints_2d`), no 3D ones.
    TwoD,
    /// No frame holds a pose (every landmark list empty, nobody in `people`).
    NoPose,
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
            JsonErrorKind::TwoD => f.write_str(
                "2D keypoints: posecoach needs 3D (x, y, z): a 3D pose estimator's output \
                 (MediaPipe's world landmarks, OpenPose with --3d, a lifter such as MotionBERT)",
            ),
            JsonErrorKind::NoPose => f.write_str("no frame holds a pose: every landmark list is empty"),
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

fn syntax(message: String) -> JsonError {
    err(0, JsonErrorKind::Syntax(message))
}

/// The file's frames: the texts of an array's items, or a single frame already read.
enum Frames<'a> {
    Texts(Vec<&'a RawValue>),
    One(Object<'a>),
}

/// The file's frames, after its syntax is checked as a whole: a fault anywhere is reported
/// before any frame is read, as when the file was read into one value.
fn frames(bytes: &[u8]) -> Result<Frames<'_>, JsonError> {
    value::check(bytes).map_err(|e| syntax(e.to_string()))?;
    let values: Vec<&RawValue> = serde_json::Deserializer::from_slice(bytes)
        .into_iter()
        .collect::<Result<_, _>>()
        .map_err(|e| syntax(e.to_string()))?;
    let frames = match <[&RawValue; 1]>::try_from(values) {
        Ok([one]) => match (value::items(one), value::object(one)) {
            (Some(frames), _) => Frames::Texts(frames),
            (None, Some(mut top)) => match top.swap_remove("frames").and_then(value::items) {
                Some(frames) => Frames::Texts(frames),
                None => Frames::One(top),
            },
            (None, None) => Frames::Texts(vec![one]),
        },
        Err(values) => Frames::Texts(values),
    };
    match frames {
        Frames::Texts(texts) if texts.is_empty() => Err(err(0, JsonErrorKind::NoFrames)),
        frames => Ok(frames),
    }
}

/// Where a frame's landmarks are.
enum Found<'a> {
    /// Name → point: an object, or the frame's other keys.
    Named(Object<'a>),
    /// An array of points, named or not, or of numbers.
    List(&'a RawValue),
    /// Nobody in the frame: an empty list of landmarks or of poses, or an empty `people`.
    Empty,
    /// Only 2D keypoints.
    TwoD,
    /// Neither.
    None,
}

/// A frame's landmarks: the value under a [`LANDMARK_KEYS`] key (inside the first of `people`
/// or `instances`; the first pose of a list of poses, as MediaPipe's results hold them), else
/// the frame's other keys.
fn landmarks_of<'a>(frame: Object<'a>, clock: Option<&str>) -> Found<'a> {
    for holder in ["people", "instances"] {
        let Some(held) = frame.get(holder) else {
            continue;
        };
        return match value::first(held).and_then(value::object) {
            Some(first) => landmarks_of(first, None),
            None if value::kind(held) == Kind::Array => Found::Empty,
            None => Found::None,
        };
    }
    // A 2D tool's output: 2D keypoints, and no 3D ones (OpenPose writes `pose_keypoints_3d`
    // empty beside them).
    let two_d = || {
        frame
            .iter()
            .any(|(k, v)| crate::landmarks::key(k).ends_with("2d") && value::first(v).is_some())
    };
    if let Some(mut v) = LANDMARK_KEYS.iter().find_map(|k| frame.get(*k).copied()) {
        // A list of poses (its first item a list of points, each an array or an object): the
        // first pose's. One level only, so a deeply nested frame costs one more pass at most.
        if let Some(pose) = value::first(v).filter(|p| value::kind(p) == Kind::Array) {
            if matches!(
                value::first(pose).map(value::kind),
                Some(Kind::Array | Kind::Object)
            ) {
                v = pose;
            }
        }
        if value::kind(v) == Kind::Array && value::first(v).is_none() {
            return if two_d() { Found::TwoD } else { Found::Empty };
        }
        return match (value::kind(v), value::object(v)) {
            (Kind::Array, _) => Found::List(v),
            (_, Some(inner)) => match (inner.len(), inner.get("landmark")) {
                // `{"landmark": [...]}`, as a landmark list converted to JSON nests it.
                (1, Some(list)) if value::kind(list) == Kind::Array => Found::List(list),
                _ => Found::Named(inner),
            },
            _ => Found::None,
        };
    }
    if two_d() {
        return Found::TwoD;
    }
    // Only values that may be points: a frame's other numbers and strings (a rate, a source)
    // are not landmarks.
    let mut rest = frame;
    rest.retain(|k, v| Some(&**k) != clock && value::kind(v) != Kind::Scalar);
    Found::Named(rest)
}

/// The first frame's landmark names (a name may repeat), each found at its first place.
struct Names {
    names: Vec<String>,
    places: Places,
}

impl Names {
    fn new(names: Vec<String>) -> Names {
        let mut places = Places::default();
        for (k, name) in names.iter().enumerate() {
            places.first_or(name, k, |j| names[j].as_str());
        }
        Names { names, places }
    }

    /// The first place of `name`.
    fn place(&self, name: &str) -> Option<usize> {
        self.places.find(name, |k| self.names[k].as_str())
    }
}

/// How a landmark list is made: its items' count, whether they are all numbers, and whether
/// they all name themselves (with their names, gathered for the first frame only).
struct Shape {
    count: usize,
    numbers: bool,
    names: Option<Vec<String>>,
}

/// The samples read so far, and what reading the next frame needs.
#[derive(Default)]
struct Reader {
    out: Samples,
    /// The first frame's landmarks.
    names: Option<Names>,
    /// Names already reported as not read.
    ignored: HashSet<String>,
    /// The first frame with only 2D keypoints, if any.
    two_d: Option<usize>,
}

impl Reader {
    /// Reads frame `at` (1-based): its time, then its landmarks.
    fn frame(&mut self, at: usize, frame: Option<Object>) -> Result<(), JsonError> {
        let frame = frame.ok_or(err(at, JsonErrorKind::NotAnObject))?;
        let clock = keypoints::time_among(frame.keys().map(|k| Some(&**k)))
            .and_then(|i| frame.keys().nth(i))
            .map(|k| k.to_string());
        if at == 1 {
            self.out.clock.clone_from(&clock);
        }
        if let Some(key) = &self.out.clock {
            let t = frame
                .get(key.as_str())
                .and_then(|v| value::number(v))
                .filter(|t| t.is_finite())
                .ok_or(err(at, JsonErrorKind::BadTime))?;
            if self.out.times.last().is_some_and(|&last| t <= last) {
                return Err(err(at, JsonErrorKind::TimeNotIncreasing));
            }
            self.out.times.push(t);
        }
        let found = landmarks_of(frame, clock.as_deref());
        match found {
            Found::Named(points) => {
                let names = || points.keys().map(|k| k.to_string()).collect();
                let row = self.start(at, points.len(), false, names)?;
                for (name, v) in &points {
                    self.sample(at, row, name, || value::point_of(v))?;
                }
                Ok(())
            }
            Found::List(list) => self.list(at, list),
            // Nobody found (or seen in 2D only): the frame's landmarks are missing, and frames
            // before the first pose are not the recording's (their names are not known yet).
            Found::Empty | Found::TwoD => {
                if matches!(found, Found::TwoD) {
                    self.two_d.get_or_insert(at);
                }
                match &self.names {
                    Some(names) => {
                        let width = names.names.len();
                        self.start(at, width, false, Vec::new).map(|_| ())
                    }
                    None => {
                        if self.out.clock.is_some() {
                            self.out.times.pop();
                        }
                        Ok(())
                    }
                }
            }
            Found::None => Err(err(at, JsonErrorKind::NoLandmarks)),
        }
    }

    /// Reads a landmark list: points that name themselves, or points or their numbers (4 a
    /// landmark where that count fits, else 3) named by the vocabulary with that many
    /// landmarks.
    fn list(&mut self, at: usize, list: &RawValue) -> Result<(), JsonError> {
        let shape = self.shape(list)?;
        let count = |count| err(at, JsonErrorKind::Count(count));
        if shape.numbers {
            let fits = |per: &usize| {
                shape.count % per == 0 && Landmarks::of_count(shape.count / per).is_some()
            };
            let per = [4, 3]
                .into_iter()
                .find(fits)
                .ok_or(count(shape.count / 3))?;
            let numbers = gather(list, |item| item.number)?;
            let points = numbers
                .chunks(per)
                .map(|c| value::point([c[0], c[1], c[2]], c.get(3).copied()));
            return self.by_position(at, points.collect());
        }
        match shape.names {
            Some(names) if shape.count > 0 => {
                let row = self.start(at, shape.count, false, || names)?;
                let each = |item: Item| {
                    let name = item.name.unwrap_or_default();
                    self.sample(at, row, &name, || item.point)
                };
                value::each_item(list, each, syntax)
            }
            _ => {
                // Checked before the points are gathered: a vocabulary's are few.
                Landmarks::of_count(shape.count).ok_or(count(shape.count))?;
                self.by_position(at, gather(list, |item| item.point)?)
            }
        }
    }

    /// Reads unnamed points, named by the vocabulary with as many landmarks.
    fn by_position(&mut self, at: usize, points: Vec<Point>) -> Result<(), JsonError> {
        let n = points.len();
        let names = Landmarks::of_count(n)
            .ok_or(err(at, JsonErrorKind::Count(n)))?
            .names();
        let first = || names.iter().take(n).map(|s| s.to_string()).collect();
        let row = self.start(at, n, true, first)?;
        for (name, point) in names.iter().zip(points) {
            self.sample(at, row, name, || point)?;
        }
        Ok(())
    }

    /// How a landmark list is made, in one pass over it.
    fn shape(&self, list: &RawValue) -> Result<Shape, JsonError> {
        let first = self.names.is_none();
        let mut shape = Shape {
            count: 0,
            numbers: true,
            names: Some(Vec::new()),
        };
        let each = |item: Item| {
            shape.count += 1;
            shape.numbers &= item.number.is_some();
            match (&mut shape.names, item.name) {
                (Some(names), Some(name)) if first => names.push(name),
                (Some(_), Some(_)) => {}
                _ => shape.names = None,
            }
            Ok(())
        };
        value::each_item(list, each, syntax)?;
        Ok(shape)
    }

    /// Starts a frame of `count` landmarks, named by position or not: the first frame's names
    /// (`names`) are the file's; by position the count must hold, by name a landmark may be
    /// absent. Every sample of the row starts missing; returns the row's first.
    fn start(
        &mut self,
        at: usize,
        count: usize,
        positional: bool,
        names: impl FnOnce() -> Vec<String>,
    ) -> Result<usize, JsonError> {
        let width = match &self.names {
            None => self.names.insert(Names::new(names())).names.len(),
            Some(first) if positional && count != first.names.len() => {
                let expected = first.names.len();
                let actual = count;
                return Err(err(at, JsonErrorKind::CountChanged { expected, actual }));
            }
            Some(first) => first.names.len(),
        };
        let row = self.out.positions.len();
        self.out.positions.resize(row + width, Vec3::zeros());
        self.out.missing.resize(row + width, true);
        Ok(row)
    }

    /// Reads landmark `name`'s sample in the row from `row`, or sets the name aside as not
    /// read where the first frame has no such landmark.
    fn sample(
        &mut self,
        at: usize,
        row: usize,
        name: &str,
        point: impl FnOnce() -> Point,
    ) -> Result<(), JsonError> {
        let Some(k) = self.names.as_ref().and_then(|n| n.place(name)) else {
            if self.ignored.insert(name.to_string()) {
                self.out.ignored.push(name.to_string());
            }
            return Ok(());
        };
        let p = point().map_err(|()| err(at, JsonErrorKind::BadPoint(name.to_string())))?;
        if let Some((position, confidence)) = p {
            self.out.positions[row + k] = position;
            self.out.missing[row + k] = confidence < f64::from(MIN_CONFIDENCE);
        }
        Ok(())
    }
}

/// What `take` keeps of each item of `list`.
fn gather<T>(list: &RawValue, take: impl Fn(Item) -> T) -> Result<Vec<T>, JsonError> {
    let mut kept = Vec::new();
    let keep = |item| {
        kept.push(take(item));
        Ok(())
    };
    value::each_item(list, keep, syntax)?;
    Ok(kept)
}

/// The file's samples, as written, read one frame at a time.
fn samples(bytes: &[u8]) -> Result<Samples, JsonError> {
    let mut reader = Reader::default();
    match frames(bytes)? {
        Frames::One(frame) => reader.frame(1, Some(frame))?,
        Frames::Texts(texts) => {
            for (f, text) in texts.into_iter().enumerate() {
                reader.frame(f + 1, value::object(text))?;
            }
        }
    }
    // A file whose frames hold 2D keypoints only (a 3D run's frame seen in 2D alone is
    // missing there).
    let names = match (reader.names, reader.two_d) {
        (Some(names), _) => names,
        (None, Some(at)) => return Err(err(at, JsonErrorKind::TwoD)),
        (None, None) => return Err(err(0, JsonErrorKind::NoPose)),
    };
    reader.out.names = names.names;
    Ok(reader.out)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use posecoach_core::format::t_pose;
    use posecoach_core::joint::Joint;
    use proptest::prelude::*;

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
    fn mediapipe_results_as_dumped_read_as_their_first_pose() {
        // A PoseLandmarkerResult per frame, dumped as it comes: a list of poses under each key,
        // the frame's counter beside its timestamp, nobody found in the first two frames and in
        // frame 20.
        let dumped = |f: usize, points: &[(&str, [f32; 3])], as_lists: bool| {
            let pose: Vec<String> = points
                .iter()
                .map(|(_, [x, y, z])| match as_lists {
                    true => format!("[{x}, {y}, {z}, 0.9]"),
                    false => format!(
                        "{{\"x\": {x}, \"y\": {y}, \"z\": {z}, \"visibility\": 0.9, \"presence\": 0.9}}"
                    ),
                })
                .collect();
            let poses = match f {
                0 | 1 | 20 => String::new(),
                _ => format!("[{}]", pose.join(", ")),
            };
            format!(
                "{{\"frame\": {f}, \"timestamp_ms\": {}, \"pose_landmarks\": [{poses}], \
                 \"pose_world_landmarks\": [{poses}]}}",
                (f as f64 * 1000.0 / 30.0).round()
            )
        };
        let hints = Hints::default();
        let by_name = |f: usize, points: &[(&str, [f32; 3])]| {
            let body: Vec<String> = points
                .iter()
                .map(|(n, [x, y, z])| format!("\"{n}\": [{x}, {y}, {z}]"))
                .collect();
            format!("{{\"t\": {}, {}}}", f as f64 / 30.0, body.join(", "))
        };
        let (plain, _) = read_with(blazepose(38, by_name).as_bytes(), &hints).unwrap();
        let n = plain.skeleton.len();
        for as_lists in [false, true] {
            let text = blazepose(40, |f, p| dumped(f, p, as_lists));
            let (m, reading) = read_with(text.as_bytes(), &hints).unwrap();
            assert_eq!(reading.landmarks, Landmarks::BlazePose33);
            // The timestamp, not the counter; whole milliseconds at their 30 Hz.
            assert_eq!(reading.clock.0, keypoints::Clock::Milliseconds);
            assert!((m.rate_hz - 30.0).abs() < 0.01, "{}", m.rate_hz);
            assert_eq!(m.frames(), 38, "the recording starts at its first pose");
            assert!(m.missing[18 * n..19 * n].iter().all(|&gone| gone));
            assert_eq!(m.positions[..18 * n], plain.positions[..18 * n]);
            assert_eq!(reading.skipped, 0);
        }
        let nobody = "{\"timestamp_ms\": 0, \"pose_world_landmarks\": []}";
        let e = read_with(nobody.as_bytes(), &hints).unwrap_err();
        assert_eq!(e.kind, JsonErrorKind::NoPose);
    }

    #[test]
    fn openpose_frames_are_read_in_3d_and_refused_in_2d() {
        // OpenPose's --write_json: BODY_25 as flat numbers inside `people`, 2D always, 3D with
        // --3d (x, y, z and a score), the other model's lists empty.
        let joint = |name: &str| {
            let side = |l: Joint, r: Joint| if name.starts_with('L') { l } else { r };
            match name {
                "MidHip" => Joint::Pelvis,
                "Neck" => Joint::Thorax,
                n if n.ends_with("Shoulder") => side(Joint::LeftShoulder, Joint::RightShoulder),
                n if n.ends_with("Elbow") => side(Joint::LeftElbow, Joint::RightElbow),
                n if n.ends_with("Wrist") => side(Joint::LeftWrist, Joint::RightWrist),
                n if n.ends_with("Hip") => side(Joint::LeftHip, Joint::RightHip),
                n if n.ends_with("Knee") => side(Joint::LeftKnee, Joint::RightKnee),
                n if n.ends_with("Ankle") || n.ends_with("Heel") => {
                    side(Joint::LeftAnkle, Joint::RightAnkle)
                }
                n if n.ends_with("Toe") => side(Joint::LeftToe, Joint::RightToe),
                _ => Joint::Head,
            }
        };
        let body: Vec<[f32; 3]> = Landmarks::OpenPose25
            .names()
            .iter()
            .map(|n| t_pose(joint(n)).into())
            .collect();
        let flat = |per: usize| {
            let numbers: Vec<String> = body
                .iter()
                .flat_map(|p| {
                    let mut v = vec![p[0] * 1000.0, -p[1] * 1000.0, p[2] * 1000.0];
                    v.truncate(per.min(3));
                    v.resize(per, 0.9);
                    v
                })
                .map(|x| x.to_string())
                .collect();
            numbers.join(", ")
        };
        let frame = |three: bool| {
            format!(
                "{{\"version\": 1.3, \"people\": [{{\"person_id\": [-1], \
                 \"pose_keypoints_2d\": [{}], \"face_keypoints_2d\": [], \
                 \"pose_keypoints_3d\": [{}], \"face_keypoints_3d\": []}}]}}",
                flat(3),
                if three { flat(4) } else { String::new() }
            )
        };
        let hints = Hints {
            rate_hz: Some(30.0),
            ..Hints::default()
        };
        let two_d = [frame(false), frame(false)].join("\n");
        let e = read_with(two_d.as_bytes(), &hints).unwrap_err();
        assert_eq!((e.frame, &e.kind), (1, &JsonErrorKind::TwoD));
        assert!(
            e.to_string()
                .contains("2D keypoints: posecoach needs 3D (x, y, z)"),
            "{e}"
        );
        let three_d = [frame(true), frame(true)].join("\n");
        let (m, reading) = read_with(three_d.as_bytes(), &hints).unwrap();
        assert_eq!(reading.landmarks, Landmarks::OpenPose25);
        assert_eq!(m.frames(), 2);
        // A 3D run with one frame seen in 2D only: missing there, not refused.
        let some_2d = [frame(true), frame(false), frame(true)].join("\n");
        let (m, _) = read_with(some_2d.as_bytes(), &hints).unwrap();
        let n = m.skeleton.len();
        assert!(m.missing[n..2 * n].iter().all(|&gone| gone) && !m.missing[0]);
        // Nobody in a frame: missing there.
        let empty = "{\"version\": 1.3, \"people\": []}";
        let (m, _) = read_with(
            [frame(true), empty.into(), frame(true)]
                .join("\n")
                .as_bytes(),
            &hints,
        )
        .unwrap();
        let n = m.skeleton.len();
        assert!(m.missing[n..2 * n].iter().all(|&gone| gone) && !m.missing[0]);
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

    /// The standard T-pose's body joints as `frames` frames at 30 Hz, each with `extra`
    /// landmarks more, keys as landmarks.
    fn t_poses(frames: usize, extra: impl Fn(usize) -> Vec<String>) -> String {
        let joints = Joint::ALL.iter().filter(|j| !j.is_club());
        let lines: Vec<String> = (0..frames)
            .map(|f| {
                let mut points: Vec<String> = joints
                    .clone()
                    .map(|&j| {
                        let p = t_pose(j);
                        format!("\"{j}\": [{}, {}, {}]", p.x, p.y, p.z)
                    })
                    .collect();
                points.extend(extra(f).iter().map(|n| format!("\"{n}\": [0, 0, 0]")));
                format!("{{\"t\": {}, {}}}", f as f64 / 30.0, points.join(", "))
            })
            .collect();
        lines.join("\n")
    }

    #[test]
    fn a_frame_of_many_names_reads_as_one_of_few() {
        let hints = Hints::default();
        let (few, _) = read_with(t_poses(3, |_| vec![]).as_bytes(), &hints).unwrap();
        let names: Vec<String> = (0..20_000).map(|k| format!("extra{k}")).collect();
        let many = t_poses(3, |_| names.clone());
        let (motion, reading) = read_with(many.as_bytes(), &hints).unwrap();
        assert_eq!(motion.positions, few.positions);
        assert_eq!(reading.ignored, names);
        // Names the first frame lacks are set aside once each, in the order first met.
        let later = t_poses(4, |f| {
            (0..f).map(|k| format!("late{}", (k * 7) % 5)).collect()
        });
        let samples = samples(later.as_bytes()).unwrap();
        assert_eq!(samples.ignored, ["late0", "late2", "late4"]);
    }

    #[test]
    fn the_whole_file_is_checked_before_a_frame_is_read() {
        let cases = [
            (
                "{\"t\": 0, \"pelvis\": [0, \"a\", 0]}\n{",
                "EOF while parsing",
            ),
            ("{\"t\": 0, \"source\": 1e400}", "number out of range"),
            ("[{\"t\": 0, \"a\": \"\\ud800\"}]", "hex escape"),
        ];
        for (text, message) in cases {
            let e = samples(text.as_bytes()).unwrap_err();
            assert!(
                matches!(&e.kind, JsonErrorKind::Syntax(m) if m.contains(message)),
                "{text}: {e}"
            );
        }
    }

    #[test]
    fn a_key_given_twice_keeps_its_first_place_and_last_value() {
        let text =
            "{\"frames\": 5, \"t\": 0, \"neck\": null, \"pelvis\": {\"x\": \"a\", \"x\": 1, \
                    \"y\": 2, \"z\": 3}, \"neck\": [4, 5, 6]}";
        let samples = samples(text.as_bytes()).unwrap();
        // `frames` that holds no frames is set aside, its place taken by the last key.
        assert_eq!(samples.names, ["pelvis", "neck"]);
        assert_eq!(
            samples.positions,
            [Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)]
        );
        assert_eq!(samples.missing, [false, false]);
    }

    /// A frame: its landmarks' names (from a few), each a point as an array, an object with a
    /// visibility, or null.
    fn frame() -> impl Strategy<Value = Vec<(usize, u8, [i8; 3])>> {
        proptest::collection::vec((0usize..6, 0u8..3, any::<[i8; 3]>()), 0..6)
    }

    proptest! {
        #[test]
        fn every_framing_of_the_same_frames_reads_alike(
            frames in proptest::collection::vec(frame(), 1..5),
            named_list in any::<bool>(),
        ) {
            const NAMES: [&str; 6] = ["pelvis", "left_hip", "head", "neck", "extra", "t2"];
            let text: Vec<String> = frames
                .iter()
                .enumerate()
                .map(|(f, points)| {
                    let point = |&(n, shape, [x, y, z]): &(usize, u8, [i8; 3])| {
                        let name = NAMES[n];
                        match (named_list, shape) {
                            (false, 0) => format!("\"{name}\": [{x}, {y}, {z}]"),
                            (false, 1) => format!(
                                "\"{name}\": {{\"x\": {x}, \"y\": {y}, \"z\": {z}, \"visibility\": 0.{n}}}"
                            ),
                            (false, _) => format!("\"{name}\": null"),
                            (true, 0) => format!("{{\"name\": \"{name}\", \"x\": {x}, \"y\": {y}, \"z\": {z}}}"),
                            (true, 1) => format!(
                                "{{\"x\": {x}, \"y\": {y}, \"z\": {z}, \"label\": \"{name}\", \"score\": 0.{n}}}"
                            ),
                            (true, _) => format!("{{\"joint\": \"{name}\"}}"),
                        }
                    };
                    let body: Vec<String> = points.iter().map(point).collect();
                    match named_list {
                        true => format!("{{\"time\": {f}.5, \"landmarks\": [{}]}}", body.join(", ")),
                        false => format!("{{\"time\": {f}.5, \"landmarks\": {{{}}}}}", body.join(", ")),
                    }
                })
                .collect();
            let lines = samples(text.join("\n").as_bytes());
            let array = samples(format!("[{}]", text.join(",")).as_bytes());
            let wrapped = format!("{{\"rate\": 30, \"frames\": [{}]}}", text.join(", "));
            prop_assert_eq!(&array, &samples(wrapped.as_bytes()));
            if frames.len() > 1 {
                prop_assert_eq!(&lines, &array);
            }
        }
    }
}
