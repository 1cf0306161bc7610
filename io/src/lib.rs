//! Host-side file import and export (the `std` feature).
//!
//! [`load`] and [`save`] pick the format from the file extension: `.bvh` and `.csv` in and
//! out, `.c3d`, `.json` (keypoints, [`json`]) and `.pcr` (a coach reference,
//! [`posecoach_core::reference`]) in. [`load_with`] takes what a person says about the files
//! that do not say it themselves ([`Hints`]: units, up axis, rate) and says how a keypoint
//! file was read ([`Reading`]). A folder is read as one keypoint JSON file per frame, in
//! the order of their names (OpenPose's `--write_json`: [`folder`]).
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
    /// A folder without `.json` files.
    EmptyFolder,
    /// A folder of more `.json` files than [`limits::MAX_FOLDER_FILES`] (how many).
    FolderTooLarge(usize),
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
            FileErrorKind::EmptyFolder => f.write_str(
                "a folder is read as one keypoint JSON file per frame, and this one holds no .json file",
            ),
            FileErrorKind::FolderTooLarge(n) => write!(
                f,
                "{n} .json files, over the limit of {} frames a folder is read as; move the \
                 swings' frames into folders of their own",
                limits::MAX_FOLDER_FILES
            ),
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
    if path.is_dir() {
        return folder(path, hints).map(|(motion, reading)| (motion, Some(reading)));
    }
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

/// Reads a folder of keypoint JSON files, one frame each (OpenPose's `--write_json` writes
/// `<name>_<frame>_keypoints.json`), as one motion: the files in the order of their names,
/// numbers in them compared as numbers, so `frame2` comes before `frame10`. An error inside a
/// frame names its file.
///
/// # Errors
/// A [`FileError`] for a folder without `.json` files or with more than
/// [`limits::MAX_FOLDER_FILES`], a file that cannot be read, or a frame that is not keypoints.
pub fn folder(path: &Path, hints: &Hints) -> Result<(Motion, Reading), FileError> {
    let fail = |path: &Path, kind| FileError {
        path: path.to_path_buf(),
        kind,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(path).map_err(|e| fail(path, FileErrorKind::Io(e)))? {
        let file = entry.map_err(|e| fail(path, FileErrorKind::Io(e)))?.path();
        let hidden = file
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'));
        if extension(&file) == "json" && !file.is_dir() && !hidden {
            files.push(file);
            if files.len() > limits::MAX_FOLDER_FILES {
                return Err(fail(path, FileErrorKind::FolderTooLarge(files.len())));
            }
        }
    }
    if files.is_empty() {
        return Err(fail(path, FileErrorKind::EmptyFolder));
    }
    files.sort_by(|a, b| natural(&a.to_string_lossy(), &b.to_string_lossy()));
    let mut bytes = Vec::new();
    for file in &files {
        let frame = std::fs::read(file).map_err(|e| fail(file, FileErrorKind::Io(e)))?;
        if frame.iter().all(u8::is_ascii_whitespace) {
            // An empty file (a run stopped while writing it): a frame with nobody in it.
            bytes.extend(b"{\"people\": []}");
        } else {
            // Each file's syntax on its own, so that a broken one is named.
            serde_json::from_slice::<&serde_json::value::RawValue>(&frame).map_err(|e| {
                let kind = json::JsonErrorKind::Syntax(e.to_string());
                fail(
                    file,
                    FileErrorKind::Json(json::JsonError { frame: 0, kind }),
                )
            })?;
            bytes.extend(frame);
        }
        bytes.push(b'\n');
    }
    json::read_with(&bytes, hints).map_err(|e| {
        // Frame `n` is the `n`th file; a whole-file fault (frame 0) is the folder's.
        let at = e.frame.checked_sub(1).and_then(|k| files.get(k));
        fail(at.map_or(path, |f| f.as_path()), FileErrorKind::Json(e))
    })
}

/// `a` and `b` in the order a person reads numbered names: runs of digits compared as
/// numbers (without their leading zeros, then by length), the rest as text.
fn natural(a: &str, b: &str) -> std::cmp::Ordering {
    fn runs(s: &str) -> impl Iterator<Item = (bool, &str)> {
        let mut rest = s;
        std::iter::from_fn(move || {
            let digits = rest.chars().next()?.is_ascii_digit();
            let end = rest
                .find(|c: char| c.is_ascii_digit() != digits)
                .unwrap_or(rest.len());
            let (run, tail) = rest.split_at(end);
            rest = tail;
            Some((digits, run))
        })
    }
    let key = |(digits, run): (bool, &str)| {
        let number = if digits {
            run.trim_start_matches('0')
        } else {
            ""
        };
        (!digits, number.len(), number.to_owned(), run.to_owned())
    };
    runs(a).map(key).cmp(runs(b).map(key))
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

    #[test]
    fn numbered_names_sort_as_numbers() {
        let mut names = ["f10.json", "f2.json", "g0.json", "f1.json", "f0.json"];
        names.sort_by(|a, b| natural(a, b));
        assert_eq!(
            names,
            ["f0.json", "f1.json", "f2.json", "f10.json", "g0.json"]
        );
        // OpenPose's zero-padded counters keep their order.
        let padded = [
            "c_000000000010_keypoints.json",
            "c_000000000009_keypoints.json",
        ];
        assert!(natural(padded[1], padded[0]).is_lt());
    }

    #[test]
    fn a_folder_of_frame_files_reads_as_one_motion_in_frame_order() {
        use posecoach_core::format::t_pose;
        use posecoach_core::joint::Joint;
        let dir = std::env::temp_dir().join(format!("posecoach-io-folder-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Frame f: the T-pose moved f cm along x; written unpadded, so name order is not
        // frame order.
        let frame = |f: usize| {
            let points: Vec<String> = Joint::ALL
                .iter()
                .filter(|j| !j.is_club())
                .map(|&j| {
                    let p = t_pose(j);
                    format!("\"{j}\": [{}, {}, {}]", p.x + 0.01 * f as f32, p.y, p.z)
                })
                .collect();
            format!("{{{}}}", points.join(", "))
        };
        for f in 0..12 {
            std::fs::write(dir.join(format!("swing_{f}_keypoints.json")), frame(f)).unwrap();
        }
        std::fs::write(dir.join("notes.txt"), "not a frame").unwrap();
        let hints = Hints {
            rate_hz: Some(30.0),
            ..Hints::default()
        };
        let (m, _) = folder(&dir, &hints).unwrap();
        assert_eq!(m.frames(), 12);
        let pelvis = |f: usize| m.frame(f)[0].x;
        assert!((1..12).all(|f| (pelvis(f) - pelvis(f - 1) - 0.01).abs() < 1e-5));
        // Without a rate the folder says so; a broken frame is named by its file.
        let e = folder(&dir, &Hints::default()).unwrap_err();
        assert!(e.to_string().contains("--rate"), "{e}");
        std::fs::write(
            dir.join("swing_7_keypoints.json"),
            "{\"pelvis\": [0, \"a\", 0]}",
        )
        .unwrap();
        let e = folder(&dir, &hints).unwrap_err();
        assert!(e.path.ends_with("swing_7_keypoints.json"), "{e}");
        // A file cut short is named; an empty one is a frame with nobody in it; a hidden
        // one (macOS's `._` files) is passed over.
        let seventh = dir.join("swing_7_keypoints.json");
        std::fs::write(&seventh, "{\"pelvis\": [0, 1").unwrap();
        let e = folder(&dir, &hints).unwrap_err();
        assert!(e.path.ends_with("swing_7_keypoints.json"), "{e}");
        std::fs::write(&seventh, "").unwrap();
        std::fs::write(dir.join("._swing_7_keypoints.json"), [0u8, 5]).unwrap();
        let (m, _) = folder(&dir, &hints).unwrap();
        let n = m.skeleton.len();
        assert_eq!(m.frames(), 12);
        assert!(m.missing[7 * n..8 * n].iter().all(|&gone| gone));
        std::fs::remove_dir_all(&dir).unwrap();
        let empty = std::env::temp_dir().join(format!("posecoach-io-empty-{}", std::process::id()));
        std::fs::create_dir_all(&empty).unwrap();
        let e = load(&empty).unwrap_err();
        assert!(matches!(e.kind, FileErrorKind::EmptyFolder), "{e}");
        std::fs::remove_dir_all(&empty).unwrap();
    }

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
