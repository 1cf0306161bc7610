//! Keypoint CSV as spreadsheets, pandas and pose-estimator scripts write it.
//!
//! A header row, then one row per frame. The time is the column whose name says so (`time`,
//! `t`, `timestamp`, `time_ms`, ...: [`keypoints::clock_of`]), else one that counts frames
//! (`frame`, or the unnamed index pandas writes first); every other column is `<landmark><sep><axis>`, the separator one
//! of `_ . : -` or a space and the axis `x`, `y`, `z` or a confidence (`visibility`,
//! `presence`, `score`, `confidence`, `conf`, `c`, `likelihood`), in any case and order.
//! Landmark names are those of any vocabulary [`crate::landmarks`] knows; columns of other
//! names are kept aside and reported, not refused. The separator is whichever of `,` `;` and
//! tab the header holds most of; with `;`, numbers may use a decimal comma. Quotes, a UTF-8
//! byte-order mark, CRLF line ends, blank lines and `#` comment lines are read as the
//! [`csv`](https://docs.rs/csv) crate reads them.
//!
//! An empty cell or `nan` marks a missing sample (all three coordinates of a landmark
//! together), as does a confidence under [`keypoints::MIN_CONFIDENCE`]. Units, up axis and
//! clock are decided for the whole file by [`keypoints::motion`]. A file with one data row is
//! a T-pose: the skeleton is that pose. With more rows the skeleton takes its bone directions
//! from the standard T-pose and its bone lengths from the mean over the frames.

use crate::keypoints::{self, Hints, KeypointError, Reading, Samples, MIN_CONFIDENCE};
use crate::landmarks;
use crate::motion::Motion;
use crate::places::Places;
use posecoach_core::joint::Joint;
use posecoach_core::Vec3;
use std::cell::Cell;
use std::fmt;
use std::num::NonZeroUsize;

/// A CSV problem, with the 1-based line and column where it was found.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvError {
    /// 1-based line; 0 when the whole file is concerned.
    pub line: usize,
    /// 1-based column, 0 when the whole line is concerned.
    pub column: usize,
    /// What is wrong.
    pub kind: CsvErrorKind,
}

/// What is wrong with a CSV file.
#[derive(Clone, Debug, PartialEq)]
pub enum CsvErrorKind {
    /// The file has no header line, or no data row.
    Empty,
    /// Text the CSV parser refuses.
    Syntax(String),
    /// A column appears twice.
    DuplicateColumn(String),
    /// A landmark lacks a coordinate column (the one expected is named).
    MissingColumn(String),
    /// A data row has the wrong number of cells.
    CellCount {
        /// Cells in the header.
        expected: usize,
        /// Cells in this row.
        actual: usize,
    },
    /// A cell is not a finite number.
    BadNumber(String),
    /// Only some of a landmark's three coordinates are empty.
    PartialJoint(String),
    /// Time does not increase.
    TimeNotIncreasing,
    /// The samples are not a motion (the whole file).
    Keypoints(KeypointError),
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "line {}", self.line)?;
            if self.column > 0 {
                write!(f, ", column {}", self.column)?;
            }
            f.write_str(": ")?;
        }
        match &self.kind {
            CsvErrorKind::Empty => f.write_str(
                "expected a header (`time,pelvis_x,pelvis_y,pelvis_z,...`) and at least one row",
            ),
            CsvErrorKind::Syntax(e) => write!(f, "not CSV: {e}"),
            CsvErrorKind::DuplicateColumn(c) => write!(f, "column `{c}` appears twice"),
            CsvErrorKind::MissingColumn(c) => write!(
                f,
                "no column `{c}`: every landmark needs x, y and z (2D keypoints are not enough)"
            ),
            CsvErrorKind::CellCount { expected, actual } => {
                write!(
                    f,
                    "expected {expected} cells as in the header, found {actual}"
                )
            }
            CsvErrorKind::BadNumber(c) => write!(f, "expected a finite number, found `{c}`"),
            CsvErrorKind::PartialJoint(j) => {
                write!(
                    f,
                    "landmark `{j}` has some coordinates empty: leave all three empty or none"
                )
            }
            CsvErrorKind::TimeNotIncreasing => f.write_str("time must increase from row to row"),
            CsvErrorKind::Keypoints(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for CsvError {}

fn err(line: usize, column: usize, kind: CsvErrorKind) -> CsvError {
    CsvError { line, column, kind }
}

/// Parses a keypoint CSV file with nothing given: units, up and clock detected.
///
/// # Errors
/// As [`read_with`].
pub fn read(text: &str) -> Result<Motion, CsvError> {
    read_with(text.as_bytes(), &Hints::default()).map(|(motion, _)| motion)
}

/// Parses a keypoint CSV file, with what [`Hints`] say about it, and says how it was read.
///
/// # Errors
/// A [`CsvError`] naming the line, the column and what was expected, or (line 0) why the
/// samples are not a motion.
pub fn read_with(bytes: &[u8], hints: &Hints) -> Result<(Motion, Reading), CsvError> {
    let samples = samples(bytes)?;
    keypoints::motion(&samples, hints).map_err(|e| err(0, 0, CsvErrorKind::Keypoints(e)))
}

/// What a header cell is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Axis {
    Coordinate(usize),
    Confidence,
}

/// A 1-based column (a wide header's landmarks are many: a column and its absence fit in a
/// word).
type Column = NonZeroUsize;

/// A landmark's columns: x, y, z and a confidence.
#[derive(Clone, Debug)]
struct Columns<'a> {
    /// The name as the first column spells it.
    name: &'a str,
    /// How the first column spelt the separator and axis case, for naming a missing one.
    pattern: (char, bool),
    first: Column,
    xyz: [Option<Column>; 3],
    confidence: Option<Column>,
}

/// The landmark name and axis of a header cell, if it is one.
fn column(cell: &str) -> Option<(&str, char, Axis)> {
    const AXES: [(&str, Axis); 10] = [
        ("x", Axis::Coordinate(0)),
        ("y", Axis::Coordinate(1)),
        ("z", Axis::Coordinate(2)),
        ("visibility", Axis::Confidence),
        ("presence", Axis::Confidence),
        ("score", Axis::Confidence),
        ("confidence", Axis::Confidence),
        ("conf", Axis::Confidence),
        ("c", Axis::Confidence),
        ("likelihood", Axis::Confidence),
    ];
    let lower = cell.to_ascii_lowercase();
    AXES.iter().find_map(|&(word, axis)| {
        let rest = lower.strip_suffix(word)?;
        let sep = rest.chars().last().filter(|c| "_.:- ".contains(*c))?;
        let name = &cell[..rest.len() - sep.len_utf8()];
        (!name.is_empty()).then_some((name, sep, axis))
    })
}

/// The separator the header line uses most of: `,`, `;` or tab.
fn separator(bytes: &[u8]) -> u8 {
    let line = bytes.split(|&b| b == b'\n').next().unwrap_or_default();
    [b',', b';', b'\t']
        .into_iter()
        .max_by_key(|&s| (line.iter().filter(|&&b| b == s).count(), s == b','))
        .unwrap_or(b',')
}

/// The file's samples, as written.
fn samples(bytes: &[u8]) -> Result<Samples, CsvError> {
    let sep = separator(bytes);
    let mut reader = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(sep)
        .comment(Some(b'#'))
        .trim(::csv::Trim::All)
        .from_reader(bytes);
    let mut records = reader.byte_records();
    let lines = Lines::new(bytes);
    let line_of = |p: Option<&::csv::Position>| p.map_or(0, |p| lines.line_at(p.byte()));
    let syntax = |e: ::csv::Error| {
        let line = line_of(e.position());
        err(line, 0, CsvErrorKind::Syntax(e.to_string()))
    };
    let header = records
        .next()
        .ok_or(err(1, 0, CsvErrorKind::Empty))?
        .map_err(syntax)?;
    let header_line = line_of(header.position()).max(1);
    // Text as the parser holds it, in place: a wide header's cells are many.
    let cells = ::csv::StringRecord::from_byte_record_lossy(header);
    // The time column ([`keypoints::time_among`]), of the cells that are no landmark's.
    let clock = keypoints::time_among(cells.iter().map(|c| column(c).is_none().then_some(c)));
    let mut landmarks: Vec<Columns> = Vec::new();
    // Each landmark's place in `landmarks`, by its key.
    let mut by_key = Places::default();
    let mut ignored = Vec::new();
    for (i, cell) in cells.iter().enumerate() {
        if Some(i) == clock {
            continue;
        }
        let Some((name, sep, axis)) = column(cell) else {
            ignored.push(match cell {
                "" => format!("column {} (no name)", i + 1),
                named => named.to_string(),
            });
            continue;
        };
        let key = landmarks::key(name);
        let at = by_key.first_or(&key, landmarks.len(), |j| landmarks::key(landmarks[j].name));
        if at == landmarks.len() {
            let upper = cell.ends_with(|c: char| c.is_ascii_uppercase());
            landmarks.push(Columns {
                name,
                pattern: (sep, upper),
                first: Column::MIN.saturating_add(i),
                xyz: [None; 3],
                confidence: None,
            });
        }
        let slot = match axis {
            Axis::Coordinate(a) => &mut landmarks[at].xyz[a],
            Axis::Confidence => &mut landmarks[at].confidence,
        };
        if slot.is_some() {
            return Err(err(
                header_line,
                i + 1,
                CsvErrorKind::DuplicateColumn(cell.to_string()),
            ));
        }
        *slot = Some(Column::MIN.saturating_add(i));
    }
    // A landmark some vocabulary knows must have all three coordinates; others are set aside.
    let known = landmarks::known();
    for c in &landmarks {
        if let Some(a) = c.xyz.iter().position(Option::is_none) {
            if known.contains(&landmarks::key(c.name)) {
                let axis = ["x", "y", "z"][a];
                let axis = if c.pattern.1 {
                    axis.to_ascii_uppercase()
                } else {
                    axis.to_string()
                };
                let expected = format!("{}{}{axis}", c.name, c.pattern.0);
                return Err(err(
                    header_line,
                    c.first.get(),
                    CsvErrorKind::MissingColumn(expected),
                ));
            }
            ignored.extend(
                c.xyz
                    .iter()
                    .chain([&c.confidence])
                    .flatten()
                    .map(|c| cells[c.get() - 1].to_string()),
            );
        }
    }
    // In place: a wide header's landmarks are many.
    landmarks.retain(|c| c.xyz.iter().all(Option::is_some));
    drop(by_key);
    let read = landmarks;

    let mut out = Samples {
        names: read.iter().map(|c| c.name.to_string()).collect(),
        clock: clock.map(|i| cells[i].to_string()),
        ignored,
        ..Samples::default()
    };
    for record in records {
        let record = record.map_err(syntax)?;
        let line = line_of(record.position());
        if record.len() != cells.len() {
            let kind = CsvErrorKind::CellCount {
                expected: cells.len(),
                actual: record.len(),
            };
            return Err(err(line, 0, kind));
        }
        let cell = |i: usize| String::from_utf8_lossy(&record[i]);
        let bad = |i: usize| err(line, i + 1, CsvErrorKind::BadNumber(cell(i).into_owned()));
        let coordinate = |i: usize| number::<f32>(&cell(i), sep).map_err(|()| bad(i));
        if let Some(i) = clock {
            let t = number::<f64>(&cell(i), sep)
                .map_err(|()| bad(i))?
                .ok_or_else(|| bad(i))?;
            if out.times.last().is_some_and(|&last| t <= last) {
                return Err(err(line, i + 1, CsvErrorKind::TimeNotIncreasing));
            }
            out.times.push(t);
        }
        for c in &read {
            let [x, y, z] = c.xyz.map(|c| c.map_or(0, |c| c.get() - 1));
            let unsure = match c.confidence {
                Some(c) => coordinate(c.get() - 1)?.is_some_and(|v| v < MIN_CONFIDENCE),
                None => false,
            };
            match (coordinate(x)?, coordinate(y)?, coordinate(z)?) {
                (Some(x), Some(y), Some(z)) => {
                    out.positions.push(Vec3::new(x, y, z));
                    out.missing.push(unsure);
                }
                (None, None, None) => {
                    out.positions.push(Vec3::zeros());
                    out.missing.push(true);
                }
                _ => {
                    return Err(err(
                        line,
                        x + 1,
                        CsvErrorKind::PartialJoint(c.name.to_string()),
                    ))
                }
            }
        }
    }
    if out.positions.is_empty() && out.times.is_empty() {
        return Err(err(header_line + 1, 0, CsvErrorKind::Empty));
    }
    Ok(out)
}

/// The lines of a file's byte offsets, counted on from the offset asked for before: reading a
/// file front to back counts each byte once.
struct Lines<'a> {
    bytes: &'a [u8],
    /// The offset last asked for, and its line: one more than the newlines before it.
    at: Cell<(usize, usize)>,
}

impl<'a> Lines<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Lines {
            bytes,
            at: Cell::new((0, 1)),
        }
    }

    /// The 1-based line of the record starting at `byte`. The parser's own line count leaves
    /// out the blank and comment lines it skips, and a record's position precedes them: they
    /// are passed over.
    fn line_at(&self, byte: u64) -> usize {
        let bytes = self.bytes;
        let mut end = usize::try_from(byte).unwrap_or(usize::MAX).min(bytes.len());
        loop {
            let rest = &bytes[end..];
            let skipped = match rest.first() {
                Some(b'\r' | b'\n') => 1,
                // A comment runs to the end of its line.
                Some(b'#') => rest.iter().take_while(|b| !b"\r\n".contains(b)).count(),
                _ => break,
            };
            end += skipped;
        }
        let newlines = |range: &[u8]| range.iter().filter(|&&b| b == b'\n').count();
        let (at, line) = self.at.get();
        let line = if end >= at {
            line + newlines(&bytes[at..end])
        } else {
            line - newlines(&bytes[end..at])
        };
        self.at.set((end, line));
        line
    }
}

/// A cell's number: `None` for an empty cell or `nan`; with `;` separators a decimal comma is
/// read as a point. Coordinates are parsed as `f32` straight from the text (rounding once),
/// times as `f64` (timestamps since an epoch need its digits).
fn number<T: std::str::FromStr + Into<f64> + Copy>(cell: &str, sep: u8) -> Result<Option<T>, ()> {
    if cell.is_empty() || cell.eq_ignore_ascii_case("nan") {
        return Ok(None);
    }
    let parse = |s: &str| s.parse::<T>().ok().filter(|v| (*v).into().is_finite());
    parse(cell)
        .or_else(|| {
            (sep == b';')
                .then(|| parse(&cell.replace(',', ".")))
                .flatten()
        })
        .map(Some)
        .ok_or(())
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
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::landmarks::Landmarks;
    use posecoach_core::skeleton::SkeletonError;
    use proptest::prelude::*;

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
            ("time,pelvis_x,pelvis_y,pelvis_q\n0,0,0,0\n", 1, 2),
            (
                "time,pelvis_x,pelvis_y,pelvis_z,pelvis_x\n0,0,0,0,0\n",
                1,
                5,
            ),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,0\n", 2, 0),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,abc,0\n", 2, 3),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,,0\n", 2, 2),
            (
                "time,pelvis_x,pelvis_y,pelvis_z\n0,0,0,0\n\n0,0,0,0\n",
                4,
                1,
            ),
            ("time,pelvis_x,pelvis_y,pelvis_z\n0,0,inf,0\n", 2, 3),
            ("time,pelvis_x,pelvis_y,pelvis_z\n", 2, 0),
            (
                "# from a tool\ntime,pelvis_x,pelvis_y,pelvis_q\n0,0,0,0\n",
                2,
                2,
            ),
            (
                "time,pelvis_x,pelvis_y,pelvis_z\n# a\n\n# b\n0,0,x,0\n",
                5,
                3,
            ),
        ];
        for (text, line, column) in cases {
            let e = read(text).unwrap_err();
            assert_eq!((e.line, e.column), (line, column), "{text:?}: {e}");
            assert!(!e.to_string().is_empty());
        }
        let e = read("time,pelvis_x,pelvis_y,pelvis_q\n0,0,0,0\n").unwrap_err();
        assert_eq!(e.kind, CsvErrorKind::MissingColumn("pelvis_z".into()));
        // One 1e4 s step: resampling it to 240 Hz asked for 17 GB.
        let (header, row) = T_POSE.split_once('\n').unwrap();
        let header = header.replacen("time", "time_s", 1);
        let later = row.replacen('0', "10000", 1);
        let e = read(&format!("{header}\n{row}\n{later}")).unwrap_err();
        assert_eq!(
            e.kind,
            CsvErrorKind::Keypoints(KeypointError::Limit(crate::LimitError::Rate(1e-4)))
        );
        assert!(e
            .to_string()
            .contains("0.0001 Hz is outside the limits of 1 to 2000 Hz"));
        let e = read("time,pelvis_x,pelvis_y,pelvis_z\n0,0,0,0\n").unwrap_err();
        assert_eq!(
            e.kind,
            CsvErrorKind::Keypoints(KeypointError::Skeleton(SkeletonError::MissingJoint(
                Joint::Head
            )))
        );
    }

    const DRIVER: &str = include_str!("../../tests/fixtures/golf_driver_60hz.csv");

    /// The driver fixture rewritten: each header cell and each number passed through `cell`
    /// and `value` (cell, position and column name), joined by `sep`, lines ended by `end`.
    fn driver_as(
        header: impl Fn(&str) -> String,
        value: impl Fn(f64, &str) -> String,
        sep: &str,
        end: &str,
    ) -> String {
        let mut lines = DRIVER.lines();
        let names: Vec<&str> = lines.next().unwrap().split(',').collect();
        let mut out: Vec<String> = vec![names
            .iter()
            .map(|n| header(n))
            .collect::<Vec<_>>()
            .join(sep)];
        for line in lines {
            let cells: Vec<String> = line
                .split(',')
                .zip(&names)
                .map(|(c, n)| match c.parse::<f64>() {
                    Ok(v) => value(v, n),
                    Err(_) => c.to_string(),
                })
                .collect();
            out.push(cells.join(sep));
        }
        out.join(end) + end
    }

    fn close(a: &Motion, b: &Motion, tolerance: f32) {
        assert_eq!(a.frames(), b.frames());
        assert!(
            (a.rate_hz - b.rate_hz).abs() < 1e-2,
            "{} {}",
            a.rate_hz,
            b.rate_hz
        );
        for (p, q) in a.positions.iter().zip(&b.positions) {
            assert!((p - q).norm() < tolerance, "{p} {q}");
        }
    }

    #[test]
    fn a_spreadsheet_in_millimetres_z_up_reads_as_the_original() {
        let original = read(DRIVER).unwrap();
        // Z up: (x, y, z) → (x, -z, y); millimetres; milliseconds; `;` with decimal commas;
        // quoted header cells; a byte-order mark; CRLF.
        let text = driver_as(
            |n| match n {
                "time" => "\"time_ms\"".to_string(),
                n => format!("\"{n}\""),
            },
            |v, n| {
                let _ = n;
                format!("{:.3}", v * 1000.0).replace('.', ",")
            },
            ";",
            "\r\n",
        );
        // Swap the axes column by column: y ← -z, z ← y.
        let mut rows: Vec<Vec<String>> = text
            .trim_end()
            .split("\r\n")
            .map(|l| l.split(';').map(str::to_string).collect())
            .collect();
        for row in rows.iter_mut().skip(1) {
            for j in (1..row.len()).step_by(3) {
                let (y, z) = (row[j + 1].clone(), row[j + 2].clone());
                row[j + 1] = match z.strip_prefix('-') {
                    Some(rest) => rest.to_string(),
                    None if z.is_empty() => z,
                    None => format!("-{z}"),
                };
                row[j + 2] = y;
            }
        }
        let text: Vec<String> = rows.iter().map(|r| r.join(";")).collect();
        let text = format!("\u{feff}{}\r\n", text.join("\r\n"));
        let (motion, reading) = read_with(text.as_bytes(), &Hints::default()).unwrap();
        assert_eq!(reading.units, (crate::units::Units::Mm, false));
        assert_eq!(reading.up.0.to_string(), "+z");
        assert_eq!(reading.clock.0, keypoints::Clock::Milliseconds);
        close(&motion, &original, 2e-6);
    }

    #[test]
    fn pose_estimator_names_are_mapped_and_the_pelvis_made_from_the_hips() {
        let original = read(DRIVER).unwrap();
        // OpenPose spelling, pelvis dropped: MidHip is absent, so the pelvis is the hips'
        // midpoint, and a name no vocabulary knows is set aside.
        let openpose = |n: &str| {
            let (name, axis) = n.rsplit_once('_').unwrap_or((n, ""));
            let name = match name {
                "left_hip" => "LHip",
                "right_hip" => "RHip",
                "left_knee" => "LKnee",
                "right_knee" => "RKnee",
                "left_ankle" => "LAnkle",
                "right_ankle" => "RAnkle",
                "left_shoulder" => "LShoulder",
                "right_shoulder" => "RShoulder",
                "left_elbow" => "LElbow",
                "right_elbow" => "RElbow",
                "left_wrist" => "LWrist",
                "right_wrist" => "RWrist",
                "thorax" => "Neck",
                "head" => "LEar",
                "head_top" => "REar",
                "time" => return "frame".to_string(),
                other => return format!("x{other}_{axis}"),
            };
            format!("{name}_{axis}")
        };
        let text = driver_as(
            openpose,
            |v, n| {
                if n == "time" {
                    format!("{}", (v * 60.0).round())
                } else {
                    format!("{v}")
                }
            },
            ",",
            "\n",
        );
        let hints = Hints {
            rate_hz: Some(60.0),
            ..Hints::default()
        };
        let (motion, reading) = read_with(text.as_bytes(), &hints).unwrap();
        assert_eq!(reading.landmarks, Landmarks::OpenPose25);
        assert_eq!(reading.midpoints[0].0, Joint::Pelvis);
        assert!(
            reading.ignored.iter().any(|c| c == "xspine"),
            "{:?}",
            reading.ignored
        );
        let at = |m: &Motion, f: usize, j: Joint| m.frame(f)[m.skeleton.index_of(j).unwrap()];
        for f in [0, 50, 100] {
            let mid = |a, b| (at(&original, f, a) + at(&original, f, b)) * 0.5;
            let pelvis = mid(Joint::LeftHip, Joint::RightHip);
            let head = mid(Joint::Head, Joint::HeadTop);
            assert!((at(&motion, f, Joint::Pelvis) - pelvis).norm() < 1e-5);
            assert!((at(&motion, f, Joint::Head) - head).norm() < 1e-5);
            let thorax = at(&original, f, Joint::Thorax);
            assert!((at(&motion, f, Joint::Thorax) - thorax).norm() < 1e-5);
        }
        // Without the rate, frame numbers are refused, saying so.
        let e = read(&text).unwrap_err();
        assert!(
            e.to_string().contains("give the frame rate with --rate"),
            "{e}"
        );
    }

    #[test]
    fn pandas_index_before_the_time_column_is_set_aside() {
        let original = read(DRIVER).unwrap();
        let mut lines = DRIVER.lines();
        let mut text = format!(",{}\n", lines.next().unwrap());
        for (k, line) in lines.enumerate() {
            text.push_str(&format!("{k},{line}\n"));
        }
        let (motion, reading) = read_with(text.as_bytes(), &Hints::default()).unwrap();
        assert_eq!(
            reading.clock,
            (keypoints::Clock::Seconds, Some("time".into()))
        );
        assert_eq!(reading.ignored, ["column 1 (no name)"]);
        assert_eq!(motion.positions, original.positions);
    }

    #[test]
    fn a_missing_coordinate_column_is_named_as_the_file_spells_it() {
        let text = driver_as(
            |n| n.to_uppercase().replace("RIGHT_WRIST_Z", "RW"),
            |v, _| format!("{v}"),
            ",",
            "\n",
        );
        let e = read(&text).unwrap_err();
        assert_eq!(
            e.kind,
            CsvErrorKind::MissingColumn("RIGHT_WRIST_Z".into()),
            "{e}"
        );
        assert_eq!(e.line, 1);
    }

    /// What may stand between two rows: a blank line (LF or CRLF) or a comment.
    const FILLERS: [&str; 3] = ["", "\r", "# a comment, with a comma"];

    proptest! {
        #[test]
        fn an_error_names_the_line_it_was_written_on(
            fillers in proptest::collection::vec(proptest::option::of(0..FILLERS.len()), 1..300),
            crlf in any::<bool>(),
            bad in any::<prop::sample::Index>(),
        ) {
            let end = if crlf { "\r\n" } else { "\n" };
            let bad = bad.index(fillers.len());
            let mut text = format!("time,pelvis_x,pelvis_y,pelvis_z{end}");
            let mut line = 1;
            let mut written = 0;
            for (row, filler) in fillers.iter().enumerate() {
                if let Some(f) = filler {
                    text.push_str(FILLERS[*f]);
                    text.push_str(end);
                    line += 1;
                }
                line += 1;
                if row == bad {
                    written = line;
                    text.push_str(&format!("{row},0,abc,0{end}"));
                } else {
                    text.push_str(&format!("{row},0,1,0{end}"));
                }
            }
            let e = read(&text).unwrap_err();
            prop_assert_eq!((e.line, e.column), (written, 3), "{}", e);
        }

        #[test]
        fn lines_are_counted_on_from_any_offset(
            bytes in proptest::collection::vec(prop::sample::select(b"\n\ra#".to_vec()), 0..200),
            offsets in proptest::collection::vec(0u64..220, 1..20),
        ) {
            let lines = Lines::new(&bytes);
            for byte in offsets {
                // The first line from `byte` on that is neither blank nor a comment.
                let mut start = (byte as usize).min(bytes.len());
                while start < bytes.len() && b"\r\n#".contains(&bytes[start]) {
                    start += match bytes[start] {
                        b'#' => bytes[start..].iter().take_while(|&&b| b != b'\r' && b != b'\n').count(),
                        _ => 1,
                    };
                }
                let expected = 1 + bytes[..start].iter().filter(|&&b| b == b'\n').count();
                prop_assert_eq!(lines.line_at(byte), expected);
            }
        }
    }

    #[test]
    fn a_late_row_names_its_line() {
        let mut lines = DRIVER.lines();
        let mut text = format!("{}\n", lines.next().unwrap());
        let rows: Vec<&str> = lines.collect();
        for k in 0..20_000 {
            let (_, cells) = rows[k % rows.len()].split_once(',').unwrap();
            text.push_str(&format!("{},{cells}", k as f64 / 60.0));
            text.push_str(if k % 7 == 0 { "\n\n" } else { "\n" });
        }
        text.push_str("1e9,x\n");
        let e = read(&text).unwrap_err();
        assert_eq!(
            (e.line, e.column),
            (1 + 20_000 + 20_000 / 7 + 1 + 1, 0),
            "{e}"
        );
    }

    #[test]
    fn a_wide_header_reads_as_a_narrow_one() {
        let narrow = read_with(T_POSE.as_bytes(), &Hints::default()).unwrap();
        // Each landmark's columns spelt anew, with 999 columns of 333 landmarks no vocabulary
        // knows after each column.
        let (header, row) = T_POSE.split_once('\n').unwrap();
        let (mut names, mut cells, mut extra) = (vec![], vec![], vec![]);
        let spell = ["{}_x", "{}.Y", "{} z"];
        for (k, (name, cell)) in header.split(',').zip(row.trim().split(',')).enumerate() {
            names.push(match name.rsplit_once('_') {
                Some((landmark, axis)) => {
                    let a = "xyz".find(axis).unwrap();
                    spell[a].replace("{}", &landmark.to_uppercase())
                }
                None => name.to_string(),
            });
            cells.push(cell.to_string());
            for j in 0..333 {
                extra.push(format!("extra{k}n{j}"));
                for axis in ["x", "y", "z"] {
                    names.push(format!("extra{k}n{j}_{axis}"));
                    cells.push("0".into());
                }
            }
        }
        let text = format!("{}\n{}\n", names.join(","), cells.join(","));
        let (motion, reading) = read_with(text.as_bytes(), &Hints::default()).unwrap();
        assert_eq!(motion.positions, narrow.0.positions);
        assert_eq!(motion.names, narrow.0.names);
        assert_eq!(reading.landmarks, narrow.1.landmarks);
        assert_eq!(reading.ignored, extra);
    }
}
