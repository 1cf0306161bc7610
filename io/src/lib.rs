//! Host-side file import and export (the `std` feature).
//!
//! [`load`] and [`save`] pick the format from the file extension: `.bvh` and `.csv` in and
//! out, `.c3d`, `.json` (keypoints, [`json`]) and `.pcr` (a coach reference,
//! [`posecoach_core::reference`]) in. [`load_with`] takes what a person says about the files
//! that do not say it themselves ([`Hints`]: units, up axis, rate) and says how a keypoint
//! file was read ([`Reading`]).
pub mod bvh;
pub mod c3d;
pub mod csv;
pub mod golf;
pub mod json;
pub mod keypoints;
pub mod landmarks;
pub mod limits;
pub mod motion;
mod places;
pub mod units;

pub use keypoints::{Hints, Reading};
pub use limits::LimitError;
pub use motion::Motion;

use posecoach_core::plausible::{self, Implausible};
use std::fmt;
use std::path::{Path, PathBuf};

/// A file could not be read or written; names the file and what went wrong inside it.
#[derive(Debug)]
pub struct FileError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub kind: FileErrorKind,
}

/// What went wrong with a file.
#[derive(Debug)]
pub enum FileErrorKind {
    /// Reading or writing failed.
    Io(std::io::Error),
    /// The extension names no supported format.
    UnknownExtension,
    /// A keypoint CSV problem.
    Csv(csv::CsvError),
    /// A keypoint JSON problem.
    Json(json::JsonError),
    /// A BVH syntax problem.
    Bvh(bvh::BvhError),
    /// A BVH hierarchy that is not a usable skeleton.
    BvhSkeleton(motion::BvhImportError),
    /// A C3D structure problem.
    C3d(c3d::C3dError),
    /// A C3D file without the golf marker set.
    Golf(golf::GolfError),
    /// Joint centres that do not make a skeleton (a bone never measured).
    Skeleton(posecoach_core::skeleton::SkeletonError),
    /// A coach reference that does not read.
    Reference(posecoach_core::reference::ReferenceError),
    /// A coach reference beyond the limits ([`limits::check_limits`]).
    Limit(limits::LimitError),
    /// A body or motion beyond human limits, with the name of the joint at fault if one is.
    Implausible(Implausible, Option<String>),
    /// A joint (named) that no frame captured.
    NeverCaptured(String),
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: ", self.path.display())?;
        match &self.kind {
            FileErrorKind::Io(e) => e.fmt(f),
            FileErrorKind::UnknownExtension => {
                f.write_str("unknown extension: expected .bvh, .c3d, .csv, .json (.jsonl) or .pcr")
            }
            FileErrorKind::Csv(e) => e.fmt(f),
            FileErrorKind::Json(e) => e.fmt(f),
            FileErrorKind::Bvh(e) => e.fmt(f),
            FileErrorKind::BvhSkeleton(e) => e.fmt(f),
            FileErrorKind::C3d(e) => e.fmt(f),
            FileErrorKind::Golf(e) => write!(
                f,
                "{e}: C3D files are read as the GearsSports golf marker set (see docs/FORMATS.md)"
            ),
            FileErrorKind::Skeleton(e) => write!(f, "the joint centres are not a skeleton: {e}"),
            FileErrorKind::Reference(e) => e.fmt(f),
            FileErrorKind::Limit(e) => e.fmt(f),
            FileErrorKind::Implausible(e, None) => write!(f, "not a human body: {e}"),
            FileErrorKind::Implausible(e, Some(name)) => {
                write!(f, "not a human body: {e} (joint `{name}`)")
            }
            FileErrorKind::NeverCaptured(name) => write!(
                f,
                "joint `{name}` is missing in every frame: a swing cannot be judged without it"
            ),
        }
    }
}

impl std::error::Error for FileError {}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Reads a motion, choosing the reader by extension, and checks it against the human limits
/// ([`posecoach_core::plausible`]: stature, bones, joint speeds) and that every joint was
/// captured at least once.
///
/// # Errors
/// A [`FileError`] naming the file and, inside it, the line, frame, byte or joint at fault.
pub fn load(path: &Path) -> Result<Motion, FileError> {
    load_with(path, &Hints::default()).map(|loaded| loaded.0)
}

/// As [`load`], with what [`Hints`] say about the file; a keypoint file also says how it was
/// read. A file that states what a hint says keeps its own: units are used by keypoint files
/// and BVH, the up axis by keypoint files, the rate by keypoint files with frame numbers or no
/// time column.
///
/// # Errors
/// As [`load`].
pub fn load_with(path: &Path, hints: &Hints) -> Result<(Motion, Option<Reading>), FileError> {
    let fail = |kind| FileError {
        path: path.to_path_buf(),
        kind,
    };
    let loaded = read(path, hints)?;
    human(&loaded.0).map_err(fail)?;
    Ok(loaded)
}

/// Whether `motion` is a human body that was seen: every joint captured in some frame, the
/// skeleton and the joints' speeds within [`posecoach_core::plausible`]'s limits.
fn human(motion: &Motion) -> Result<(), FileErrorKind> {
    let n = motion.skeleton.len();
    let seen = |k: usize| motion.missing.iter().skip(k).step_by(n).any(|&m| !m);
    if let Some(k) = (0..n).find(|&k| !seen(k)) {
        return Err(FileErrorKind::NeverCaptured(motion.names[k].clone()));
    }
    let name = |e: Implausible| {
        let joint = e.joint().and_then(|k| motion.names.get(k).cloned());
        FileErrorKind::Implausible(e, joint)
    };
    plausible::body(&motion.skeleton).map_err(name)?;
    plausible::motion(
        &motion.skeleton,
        &motion.positions,
        Some(&motion.missing),
        motion.rate_hz,
    )
    .map_err(name)
}

/// Reads a motion, choosing the reader by extension.
fn read(path: &Path, hints: &Hints) -> Result<(Motion, Option<Reading>), FileError> {
    let fail = |kind| FileError {
        path: path.to_path_buf(),
        kind,
    };
    let bytes = || std::fs::read(path).map_err(|e| fail(FileErrorKind::Io(e)));
    let text = || std::fs::read_to_string(path).map_err(|e| fail(FileErrorKind::Io(e)));
    let read = |(motion, reading)| (motion, Some(reading));
    let motion = match extension(path).as_str() {
        "csv" => {
            return csv::read_with(&bytes()?, hints)
                .map(read)
                .map_err(|e| fail(FileErrorKind::Csv(e)))
        }
        "json" | "jsonl" | "ndjson" => {
            return json::read_with(&bytes()?, hints)
                .map(read)
                .map_err(|e| fail(FileErrorKind::Json(e)))
        }
        "bvh" => {
            let bvh = bvh::Bvh::parse(&text()?).map_err(|e| fail(FileErrorKind::Bvh(e)))?;
            Motion::from_bvh(bvh, hints.units).map_err(|e| fail(FileErrorKind::BvhSkeleton(e)))
        }
        "c3d" => {
            let c3d = c3d::C3d::parse(&bytes()?).map_err(|e| fail(FileErrorKind::C3d(e)))?;
            let centres = golf::joint_centres(&c3d).map_err(|e| fail(FileErrorKind::Golf(e)))?;
            Motion::from_golf(&centres).map_err(|e| fail(FileErrorKind::Skeleton(e)))
        }
        "pcr" => {
            let motion =
                Motion::from_reference(&bytes()?).map_err(|e| fail(FileErrorKind::Reference(e)))?;
            let (frames, joints) = (motion.frames(), motion.skeleton.len());
            limits::check_limits(frames, joints, motion.rate_hz)
                .map_err(|e| fail(FileErrorKind::Limit(e)))?;
            Ok(motion)
        }
        _ => Err(fail(FileErrorKind::UnknownExtension)),
    };
    motion.map(|motion| (motion, None))
}

/// Writes a motion, choosing the writer by extension.
///
/// # Errors
/// A [`FileError`] for an unknown extension or a failed write.
pub fn save(motion: &Motion, path: &Path) -> Result<(), FileError> {
    let fail = |kind| FileError {
        path: path.to_path_buf(),
        kind,
    };
    let text = match extension(path).as_str() {
        "csv" => csv::write(motion),
        "bvh" => motion.to_bvh().to_text(),
        _ => return Err(fail(FileErrorKind::UnknownExtension)),
    };
    std::fs::write(path, text).map_err(|e| fail(FileErrorKind::Io(e)))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// `text` loaded as a file named `name`.
    fn load_text(name: &str, text: &str) -> Result<Motion, FileError> {
        let path = std::env::temp_dir().join(format!("posecoach-io-{}-{name}", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let loaded = load(&path);
        std::fs::remove_file(&path).unwrap();
        loaded
    }

    /// The driver fixture with `change` applied to each data row's cells (row number, column
    /// name, cell).
    fn driver_with(change: impl Fn(usize, &str, &mut String)) -> String {
        let text = include_str!("../../tests/fixtures/golf_driver_60hz.csv");
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let rows = lines.enumerate().map(|(row, line)| {
            let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
            for (cell, column) in cells.iter_mut().zip(&header) {
                change(row, column, cell);
            }
            cells.join(",")
        });
        let rows: Vec<String> = rows.collect();
        format!("{}\n{}\n", header.join(","), rows.join("\n"))
    }

    #[test]
    fn one_corrupt_coordinate_is_refused_naming_its_joint() {
        let text = driver_with(|row, column, cell| {
            if row == 50 && column == "left_wrist_x" {
                *cell = (cell.parse::<f32>().unwrap() + 10.0).to_string();
            }
        });
        let e = load_text("corrupt.csv", &text).unwrap_err();
        assert!(
            matches!(&e.kind, FileErrorKind::Implausible(Implausible::Speed { frame: 50, .. }, Some(n)) if n == "left_wrist"),
            "{e}"
        );
        assert!(load_text("clean.csv", &driver_with(|_, _, _| {})).is_ok());
    }

    #[test]
    fn a_joint_never_captured_is_named() {
        let text = driver_with(|_, column, cell| {
            if column.starts_with("left_elbow_") {
                cell.clear();
            }
        });
        let e = load_text("elbowless.csv", &text).unwrap_err();
        assert!(
            matches!(&e.kind, FileErrorKind::NeverCaptured(n) if n == "left_elbow"),
            "{e}"
        );
    }

    #[test]
    fn a_t_pose_of_no_human_size_is_refused() {
        let text = include_str!("../../tests/fixtures/h36m17_tpose.csv");
        let (header, row) = text.split_once('\n').unwrap();
        for scale in [1e-2f32, 20.0, 1e20] {
            let cells: Vec<String> = row
                .trim()
                .split(',')
                .enumerate()
                .map(|(k, c)| match k {
                    0 => c.to_string(),
                    _ => (c.parse::<f32>().unwrap() * scale).to_string(),
                })
                .collect();
            let e =
                load_text("tpose.csv", &format!("{header}\n{}\n", cells.join(","))).unwrap_err();
            assert!(
                matches!(
                    e.kind,
                    FileErrorKind::Csv(csv::CsvError {
                        kind: csv::CsvErrorKind::Keypoints(keypoints::KeypointError::Stature(_)),
                        ..
                    })
                ),
                "scale {scale}: {e}"
            );
        }
        assert!(load_text("tpose.csv", text).is_ok());
    }

    #[test]
    fn a_coach_reference_beyond_the_limits_is_refused() {
        let mut swing =
            csv::read(include_str!("../../tests/fixtures/golf_driver_60hz.csv")).unwrap();
        swing.rate_hz = 0.001;
        let path =
            std::env::temp_dir().join(format!("posecoach-io-slow-{}.pcr", std::process::id()));
        std::fs::write(
            &path,
            swing
                .to_reference("slow", posecoach_core::reference::Units::Millimetres)
                .unwrap(),
        )
        .unwrap();
        let e = load(&path).unwrap_err();
        std::fs::remove_file(&path).unwrap();
        assert!(
            matches!(e.kind, FileErrorKind::Limit(limits::LimitError::Rate(r)) if r == 0.001),
            "{e}"
        );
    }
}
