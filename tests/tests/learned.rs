//! The learned retargeter through the command line: `retarget`, `score` and `eval` with
//! `--weights`, on the committed teacher or a tiny untrained one written the way
//! `posecoach train --teacher` does. Runs with the `learn` feature.
#![cfg(feature = "learn")]

use burn::prelude::Device;
use posecoach_cli::{learn, retarget, score};
use posecoach_io as io;
use posecoach_tests::parse;
use posecoach_train::model::TeacherConfig;
use posecoach_train::train::{TrainConfig, Trainer};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> String {
    posecoach_tests::fixture(name).display().to_string()
}

/// A folder of its own for a test, and a tiny teacher file in it.
fn teacher(test: &str) -> (PathBuf, String) {
    let dir = std::env::temp_dir().join(format!("posecoach-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config = TrainConfig {
        teacher: TeacherConfig::TINY,
        ..TrainConfig::default()
    };
    let path = dir.join("tiny.pcw");
    Trainer::new(config, &Device::flex().autodiff())
        .save_teacher(&path)
        .unwrap();
    let path = path.display().to_string();
    (dir, path)
}

#[test]
fn retarget_with_weights_keeps_the_students_bones_and_the_coachs_frames() {
    let (dir, weights) = teacher("retarget");
    let out = dir.join("virtual.csv").display().to_string();
    let coach = fixture("golf_driver_60hz.csv");
    let tpose = fixture("h36m17_tpose.csv");
    let args: retarget::Args = parse(&[
        "--coach",
        &coach,
        "--student-tpose",
        &tpose,
        "--out",
        &out,
        "--weights",
        &weights,
        "--json",
    ]);
    let summary: serde_json::Value = serde_json::from_str(&retarget::run(&args).unwrap()).unwrap();
    assert_eq!(summary["method"], "teacher");
    let (virtual_swing, coach) = (
        io::load(Path::new(&out)).unwrap(),
        io::load(Path::new(&coach)).unwrap(),
    );
    let student = io::load(Path::new(&tpose)).unwrap().skeleton;
    assert_eq!(virtual_swing.frames(), coach.frames());
    let first = virtual_swing.frame(0);
    for k in 1..student.len() {
        let bone = (first[k] - first[student.parent(k).unwrap()]).norm();
        assert!((bone - student.offset(k).norm()).abs() < 1e-3, "joint {k}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// The committed teacher (`posecoach train`'s `--teacher`).
fn committed_weights() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../weights/teacher.pcw")
        .display()
        .to_string()
}

/// The iron swing scored against the driver through `weights`, else the analytic retargeter.
fn score_with(weights: Option<&str>) -> anyhow::Result<String> {
    let (coach, student) = (
        fixture("golf_driver_60hz.csv"),
        fixture("golf_iron_60hz.csv"),
    );
    let mut args = vec!["--coach", &coach, "--student", &student, "--json"];
    if let Some(weights) = weights {
        args.extend(["--weights", weights]);
    }
    score::run(&parse::<score::Args>(&args))
}

/// How far apart the scores through the committed teacher and the analytic retargeter may
/// be: the teacher corrects the analytic solution by a few millimetres.
const TEACHER_SCORE_GAP: f64 = 5.0;
/// Frames at 60 Hz by which an event of the virtual coach may move between the two.
const TEACHER_EVENT_GAP: i64 = 2;

#[test]
fn score_with_the_committed_teacher_agrees_with_the_analytic_retargeter() {
    let json = |text: String| -> serde_json::Value { serde_json::from_str(&text).unwrap() };
    let teacher = json(score_with(Some(&committed_weights())).unwrap());
    let analytic = json(score_with(None).unwrap());
    let (a, b) = (
        teacher["score"].as_f64().unwrap(),
        analytic["score"].as_f64().unwrap(),
    );
    assert!(
        (a - b).abs() < TEACHER_SCORE_GAP,
        "teacher {a}, analytic {b}"
    );
    for (event, frame) in analytic["events"]["coach"].as_object().unwrap() {
        let (f, g) = (
            frame.as_i64().unwrap(),
            teacher["events"]["coach"][event].as_i64().unwrap(),
        );
        assert!(
            (f - g).abs() <= TEACHER_EVENT_GAP,
            "{event}: teacher {g}, analytic {f}"
        );
    }
}

#[test]
fn score_with_a_missing_teacher_says_which_file() {
    let error = format!("{:#}", score_with(Some("no/such/teacher.pcw")).unwrap_err());
    assert!(error.contains("no/such/teacher.pcw"), "{error}");
}

#[test]
fn eval_compares_a_teacher_with_the_analytic_baseline() {
    let Some(data) =
        posecoach_tests::shared_data("eval_compares_a_teacher_with_the_analytic_baseline")
    else {
        return;
    };
    let (dir, weights) = teacher("eval");
    let data = data.display().to_string();
    let args: learn::EvalArgs = parse(&[
        "--weights",
        &weights,
        "--analytic",
        "--data",
        &data,
        "--synthetic",
        "1",
        "--contacts",
        "--json",
    ]);
    let table: serde_json::Value = serde_json::from_str(&learn::eval(&args).unwrap()).unwrap();
    let rows = table["rows"].as_array().unwrap();
    for method in ["tiny", "analytic"] {
        assert!(rows.iter().any(|r| r["method"] == method), "{method}");
    }
    let cross = |m: &str| {
        rows.iter()
            .find(|r| r["method"] == m && r["structure"] == "cross")
            .unwrap()["global_pct_height"]
            .as_f64()
            .unwrap()
    };
    // An untrained teacher's corrections are zero: it is the analytic retargeter, run through
    // the network's windows and interleaved 30 Hz streams.
    let (tiny, analytic) = (cross("tiny"), cross("analytic"));
    assert!(
        analytic > 0.1,
        "cross-format pairs differ from their ground truth: {analytic}"
    );
    assert!((tiny - analytic).abs() < 1e-3, "{tiny} against {analytic}");
    // Golf's convention-free measures: planted feet everywhere, the club head where the target
    // carries a club, and how far a noisy T-pose moves each method's swing (the chords, which
    // take only bone lengths from the T-pose, hardly at all).
    assert!(rows.iter().all(|r| r["foot_height_error_cm"].is_number()));
    assert!(rows
        .iter()
        .any(|r| r["club_pairs"].as_u64().unwrap() > 0 && r["club_head_error_cm"].is_array()));
    // With the contacts kept, both hands are on the coach's grip on every golf cell.
    let kept: Vec<&serde_json::Value> = rows
        .iter()
        .filter(|r| r["method"] == "analytic + contacts" && r["golf_pairs"].as_u64() > Some(0))
        .collect();
    assert!(!kept.is_empty());
    for row in kept {
        let gap = &row["hand_gap_error_cm"];
        assert!(
            gap[0].as_f64().unwrap() < 0.2 && gap[1].as_f64().unwrap() < 0.2,
            "{row}"
        );
    }
    let posture = table["posture_error"]["rows"].as_array().unwrap();
    assert_eq!(
        table["posture_error"]["turn_deg"],
        serde_json::json!([3.0, 8.0])
    );
    for method in ["tiny", "analytic"] {
        for structure in ["intra", "cross"] {
            let row = posture
                .iter()
                .find(|r| r["method"] == method && r["structure"] == structure)
                .unwrap();
            assert!(row["pairs"].as_u64().unwrap() > 0, "{row}");
            assert!(row["mean_cm"].as_f64().unwrap() < 1.0, "{row}");
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn train_with_no_epochs_writes_the_checkpoint_it_names() {
    // Nothing to train: the untrained prior, still written where `--out` says.
    let dir = std::env::temp_dir().join(format!("posecoach-epochs0-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("data")).unwrap();
    let (checkpoint, teacher) = (dir.join("run.pcckpt"), dir.join("teacher.pcw"));
    let args: learn::TrainArgs = parse(&[
        "--data",
        dir.join("data").to_str().unwrap(),
        "--synthetic",
        "1",
        "--epochs",
        "0",
        "--out",
        checkpoint.to_str().unwrap(),
        "--teacher",
        teacher.to_str().unwrap(),
    ]);
    let said = learn::train(&args).unwrap();
    assert!(said.starts_with("0 steps"), "{said}");
    assert!(checkpoint.is_file() && teacher.is_file(), "{said}");
    std::fs::remove_dir_all(dir).unwrap();
}
