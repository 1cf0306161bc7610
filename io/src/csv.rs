//! Keypoint CSV: `time,<joint>_x,<joint>_y,<joint>_z,...` with canonical joint names.
//!
//! Any subset of the canonical joints that includes `pelvis`, in any column order; metres,
//! +Y up; `time` in seconds, strictly increasing. An empty cell marks a missing sample (all
//! three coordinates of a joint must be empty together). A file with one data row is a
//! T-pose: the skeleton is that pose. With more rows the skeleton takes its bone directions
//! from the standard T-pose and its bone lengths from the mean over the frames.

use crate::limits::{check_limits, LimitError};
use crate::motion::{hold_missing, measured_skeleton, Motion};
use posecoach_core::format::t_pose;
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::{Skeleton, SkeletonError};
use posecoach_core::Vec3;
use std::fmt;

/// A CSV problem, with the 1-based line and column where it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvError {
    /// 1-based line.
    pub line: usize,
    /// 1-based column, 0 when the whole line is concerned.
    pub column: usize,
    /// What is wrong.
    pub kind: CsvErrorKind,
}

/// What is wrong with a CSV file.
#[derive(Clone, Debug, PartialEq)]
pub enum CsvErrorKind {
    /// The file has no header line.
    Empty,
    /// The first column is not `time`.
    NoTimeColumn(String),
    /// A header cell is not `<canonical joint>_x|_y|_z` in x, y, z order.
    BadHeader(String),
    /// A joint appears twice.
    DuplicateJoint(Joint),
    /// The header has no `pelvis` columns.
    NoPelvis,
    /// A data row has the wrong number of cells.
    CellCount {
        /// Cells in the header.
        expected: usize,
        /// Cells in this row.
        actual: usize,
    },
    /// A cell is not a finite number.
    BadNumber(String),
    /// Only some of a joint's three coordinates are empty.
    PartialJoint(Joint),
    /// `time` does not increase.
    TimeNotIncreasing,
    /// A T-pose (single row) has a missing joint.
    MissingInTPose(Joint),
    /// The joints do not make a valid skeleton.
    Skeleton(SkeletonError),
    /// The motion is beyond the limits (the rate comes from the median time step).
    Limit(LimitError),
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}", self.line)?;
        if self.column > 0 {
            write!(f, ", column {}", self.column)?;
        }
        f.write_str(": ")?;
        match &self.kind {
            CsvErrorKind::Empty => f.write_str("empty file, expected a header `time,pelvis_x,...`"),
            CsvErrorKind::NoTimeColumn(c) => write!(f, "expected `time` as the first column, found `{c}`"),
            CsvErrorKind::BadHeader(c) => write!(
                f,
                "expected `<joint>_x`, `<joint>_y`, `<joint>_z` with a canonical joint name (pelvis, left_hip, ...), found `{c}`"
            ),
            CsvErrorKind::DuplicateJoint(j) => write!(f, "joint `{j}` appears twice"),
            CsvErrorKind::NoPelvis => f.write_str("the header needs pelvis_x, pelvis_y, pelvis_z"),
            CsvErrorKind::CellCount { expected, actual } => {
                write!(f, "expected {expected} cells as in the header, found {actual}")
            }
            CsvErrorKind::BadNumber(c) => write!(f, "expected a finite number, found `{c}`"),
            CsvErrorKind::PartialJoint(j) => {
                write!(f, "joint `{j}` has some coordinates empty: leave all three empty or none")
            }
            CsvErrorKind::TimeNotIncreasing => f.write_str("time must increase from row to row"),
            CsvErrorKind::MissingInTPose(j) => write!(f, "a one-row T-pose needs every joint; `{j}` is empty"),
            CsvErrorKind::Skeleton(e) => write!(f, "the joints do not form a skeleton: {e}"),
            CsvErrorKind::Limit(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for CsvError {}

fn err(line: usize, column: usize, kind: CsvErrorKind) -> CsvError {
    CsvError { line, column, kind }
}

/// Parses a keypoint CSV file.
///
/// # Errors
/// A [`CsvError`] naming the line, the column and what was expected; a motion beyond the limits
/// ([`check_limits`]) at the last row's time.
pub fn read(text: &str) -> Result<Motion, CsvError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().ok_or(err(1, 0, CsvErrorKind::Empty))?;
    let columns = parse_header(header)?;
    let n = columns.len();

    let mut times = Vec::new();
    let mut values: Vec<Vec3> = Vec::new();
    let mut missing = Vec::new();
    let mut last = 0;
    for (line, row) in lines {
        last = line;
        let cells: Vec<&str> = row.split(',').map(str::trim).collect();
        if cells.len() != 1 + 3 * n {
            let kind = CsvErrorKind::CellCount {
                expected: 1 + 3 * n,
                actual: cells.len(),
            };
            return Err(err(line, 0, kind));
        }
        let number = |c: usize| -> Result<Option<f32>, CsvError> {
            match cells[c] {
                "" => Ok(None),
                s => s
                    .parse::<f32>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .map(Some)
                    .ok_or_else(|| err(line, c + 1, CsvErrorKind::BadNumber(s.to_string()))),
            }
        };
        let t = number(0)?.ok_or_else(|| err(line, 1, CsvErrorKind::BadNumber(String::new())))?;
        if times.last().is_some_and(|&last| t <= last) {
            return Err(err(line, 1, CsvErrorKind::TimeNotIncreasing));
        }
        times.push(t);
        for (j, joint) in columns.iter().enumerate() {
            let c = 1 + 3 * j;
            match (number(c)?, number(c + 1)?, number(c + 2)?) {
                (Some(x), Some(y), Some(z)) => {
                    values.push(Vec3::new(x, y, z));
                    missing.push(false);
                }
                (None, None, None) => {
                    values.push(Vec3::zeros());
                    missing.push(true);
                }
                _ => return Err(err(line, c + 1, CsvErrorKind::PartialJoint(*joint))),
            }
        }
    }
    if times.is_empty() {
        return Err(err(2, 0, CsvErrorKind::Empty));
    }
    let rate_hz = if times.len() > 1 {
        rate_from_times(&times)
    } else {
        0.0
    };
    check_limits(times.len(), n, rate_hz).map_err(|e| err(last, 1, CsvErrorKind::Limit(e)))?;

    // Reorder the columns into canonical order so parents precede children.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&j| columns[j]);
    let joints: Vec<Joint> = order.iter().map(|&j| columns[j]).collect();
    let reorder = |v: &[Vec3]| -> Vec<Vec3> {
        v.chunks_exact(n)
            .flat_map(|f| order.iter().map(|&j| f[j]))
            .collect()
    };
    let mut positions = reorder(&values);
    let missing: Vec<bool> = missing
        .chunks_exact(n)
        .flat_map(|f| order.iter().map(|&j| f[j]))
        .collect();

    let skeleton_error = |e| err(1, 0, CsvErrorKind::Skeleton(e));
    let skeleton = if times.len() == 1 {
        if let Some(j) = missing.iter().position(|&m| m) {
            return Err(err(2, 0, CsvErrorKind::MissingInTPose(joints[j])));
        }
        Skeleton::canonical(&joints, &positions).map_err(skeleton_error)?
    } else {
        let rest: Vec<Vec3> = joints.iter().map(|&j| t_pose(j)).collect();
        let template = Skeleton::canonical(&joints, &rest).map_err(skeleton_error)?;
        measured_skeleton(&template, &positions, &missing).map_err(skeleton_error)?
    };
    hold_missing(n, &mut positions, &missing);
    Ok(Motion {
        skeleton,
        names: joints.iter().map(|j| j.name().to_string()).collect(),
        rate_hz,
        positions,
        missing,
    })
}

fn parse_header(header: &str) -> Result<Vec<Joint>, CsvError> {
    let cells: Vec<&str> = header.split(',').map(str::trim).collect();
    if cells[0] != "time" {
        return Err(err(1, 1, CsvErrorKind::NoTimeColumn(cells[0].to_string())));
    }
    let mut joints: Vec<Joint> = Vec::new();
    for (k, triple) in cells[1..].chunks(3).enumerate() {
        let column = 2 + 3 * k;
        let name = triple[0].strip_suffix("_x").unwrap_or("");
        let joint = Joint::from_name(name)
            .ok_or_else(|| err(1, column, CsvErrorKind::BadHeader(triple[0].to_string())))?;
        for (axis, (cell, suffix)) in triple.iter().zip(["_x", "_y", "_z"]).enumerate() {
            if cell.strip_suffix(suffix) != Some(name) {
                return Err(err(
                    1,
                    column + axis,
                    CsvErrorKind::BadHeader(cell.to_string()),
                ));
            }
        }
        if triple.len() != 3 {
            return Err(err(
                1,
                column + triple.len(),
                CsvErrorKind::BadHeader(String::new()),
            ));
        }
        if joints.contains(&joint) {
            return Err(err(1, column, CsvErrorKind::DuplicateJoint(joint)));
        }
        joints.push(joint);
    }
    if !joints.contains(&Joint::Pelvis) {
        return Err(err(1, 0, CsvErrorKind::NoPelvis));
    }
    Ok(joints)
}

/// Frame rate from the median time step.
fn rate_from_times(times: &[f32]) -> f32 {
    let mut steps: Vec<f32> = times.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f32::total_cmp);
    1.0 / steps[steps.len() / 2]
}

/// Writes the canonical joints of `motion` as keypoint CSV (joints without a canonical name are
/// left out). Values use the shortest representation that reads back to the same `f32`.
pub fn write(motion: &Motion) -> String {
    let skeleton = &motion.skeleton;
    let columns: Vec<(usize, Joint)> = (0..skeleton.len())
        .filter_map(|k| skeleton.joint(k).map(|j| (k, j)))
        .collect();
    let mut out = String::from("time");
    for (_, joint) in &columns {
        out.push_str(&format!(",{joint}_x,{joint}_y,{joint}_z"));
    }
    out.push('\n');
    for f in 0..motion.frames() {
        let t = if motion.rate_hz > 0.0 {
            f as f64 / f64::from(motion.rate_hz)
        } else {
            0.0
        };
        out.push_str(&format!("{t}"));
        let frame = motion.frame(f);
        for &(k, _) in &columns {
            if motion.missing[f * skeleton.len() + k] {
                out.push_str(",,,");
            } else {
                let p = frame[k];
                out.push_str(&format!(",{},{},{}", p.x, p.y, p.z));
            }
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const T_POSE: &str = "time,pelvis_x,pelvis_y,pelvis_z,left_hip_x,left_hip_y,left_hip_z,\
left_ankle_x,left_ankle_y,left_ankle_z,right_hip_x,right_hip_y,right_hip_z,\
right_ankle_x,right_ankle_y,right_ankle_z,head_x,head_y,head_z,left_wrist_x,left_wrist_y,left_wrist_z,\
right_wrist_x,right_wrist_y,right_wrist_z\n\
0,0,1,0,0.1,0.95,0,0.1,0.1,0,-0.1,0.95,0,-0.1,0.1,0,0,1.6,0,0.7,1.4,0,-0.7,1.4,0\n";

    #[test]
    fn one_row_is_a_t_pose() {
        let m = read(T_POSE).unwrap();
        assert_eq!(m.frames(), 1);
        assert_eq!(m.rate_hz, 0.0);
        assert_eq!(m.skeleton.len(), 8);
        assert!((m.skeleton.offset(2).norm() - 0.85).abs() < 1e-6);
    }

    #[test]
    fn write_then_read_is_exact() {
        let mut text = T_POSE.to_string();
        text.push_str(
            "0.1,0.5,1,0,0.6,0.95,0,0.6,0.1,0,0.4,0.95,0,0.4,0.1,0,0.5,1.6,0,1.2,1.4,0,,,\n",
        );
        let m = read(&text).unwrap();
        assert_eq!(m.frames(), 2);
        assert!((m.rate_hz - 10.0).abs() < 1e-3);
        assert!(m.missing[2 * 8 - 1]);
        let again = read(&write(&m)).unwrap();
        assert_eq!(again.positions, m.positions);
        assert_eq!(again.missing, m.missing);
    }

    #[test]
    fn errors_name_line_column_and_expectation() {
        let cases = [
            ("", 1, 0),
            ("t,pelvis_x,pelvis_y,pelvis_z\n0,0,0,0\n", 1, 1),
            ("time,pelvis_x,pelvis_y,pelvis_q\n0,0,0,0\n", 1, 4),
            ("time,elbow_x,elbow_y,elbow_z\n0,0,0,0\n", 1, 2),
            ("time,head_x,head_y,head_z\n0,0,0,0\n", 1, 0),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,0\n", 2, 0),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,abc,0\n", 2, 3),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,,0\n", 2, 2),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,0,0\n0,0,0,0\n", 3, 1),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,NaN,0\n", 2, 3),
        ];
        for (text, line, column) in cases {
            let e = read(text).unwrap_err();
            assert_eq!((e.line, e.column), (line, column), "{text:?}: {e}");
            assert!(!e.to_string().is_empty());
        }
        // One 1e4 s step: resampling it to 240 Hz asked for 17 GB.
        let e = read("time,pelvis_x,pelvis_y,pelvis_z\n0,0,1,0\n\n10000,0,1,0\n").unwrap_err();
        assert_eq!((e.line, e.column), (4, 1));
        assert_eq!(e.kind, CsvErrorKind::Limit(LimitError::Rate(1e-4)));
        assert!(e
            .to_string()
            .contains("0.0001 Hz is outside the limits of 1 to 2000 Hz"));
        let e = read("time,pelvis_x,pelvis_y,pelvis_z\n0,0,0,0\n").unwrap_err();
        assert_eq!(
            e.kind,
            CsvErrorKind::Skeleton(SkeletonError::MissingJoint(Joint::Head))
        );
    }
}
