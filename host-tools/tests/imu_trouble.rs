//! Real IMU trouble, recorded through `posecoach synth-log` and replayed: each kind is survived
//! or said.
#![allow(clippy::unwrap_used)] // test helpers fail the test by unwrapping

mod common;

use common::{fixture, posecoach};
use posecoach_adapters::log::{header, LogReader};
use posecoach_cli::device_sim::frame;
use posecoach_core::wire::Message;
use serde_json::Value;
use std::path::Path;

/// The bundled iron swing as the iron coach made it, recorded by synth-log's six IMUs with
/// magnetometers into `log`, with `extra` options: what synth-log says it made.
fn iron_log(log: &Path, extra: &[&str]) -> Value {
    let (iron, tpose) = (fixture("golf_iron_60hz.csv"), fixture("h36m17_tpose.csv"));
    let mut args = vec![
        "synth-log",
        "--swing",
        iron.to_str().unwrap(),
        "--student-tpose",
        tpose.to_str().unwrap(),
        "--imu-rate",
        "200",
        "--coach",
        "1",
        "--seed",
        "3",
        "--out",
        log.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    serde_json::from_str(&posecoach(&args)).unwrap()
}

/// `log` replayed (`--json`), which must find one swing and score it; and its text.
fn replayed(log: &Path) -> (Value, String) {
    let replay: Value =
        serde_json::from_str(&posecoach(&["replay", "--json", log.to_str().unwrap()])).unwrap();
    let swings = replay["swings"].as_array().unwrap();
    assert_eq!(swings.len(), 1, "{replay}");
    assert!(swings[0]["report"].is_object(), "not scored: {}", swings[0]);
    (replay, posecoach(&["replay", log.to_str().unwrap()]))
}

/// The bundled iron swing, made as the iron coach made it, recorded by six IMUs with
/// magnetometers whose wrist sensors feel a steel club of 60 µT from the set-up on (a field
/// fixed in each sensor's frame). Followed, it twisted the forearms' headings into a lead
/// elbow 59° bent at the top against the coach's 24° (measured 2026-12-07 before the filter
/// set such fields aside). Now the swing is scored without a word of advice, and the replay
/// counts the set-aside samples and says what they limit.
#[test]
fn a_steel_club_by_the_wrists_is_set_aside_not_followed() {
    let dir = std::env::temp_dir().join(format!("posecoach-steel-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("steel_club.pclog");
    iron_log(&log, &["--steel-club", "60"]);
    let (replay, text) = replayed(&log);
    let report = &replay["swings"][0]["report"];
    assert_eq!(
        report["advice"],
        serde_json::json!([]),
        "{}",
        report["advice"]
    );
    // Both wrists' magnetometers, some 8 s at 200 Hz each after the T-pose, nearly all set
    // aside.
    let disturbed = replay["counters"]["imu_disturbed"].as_u64().unwrap();
    assert!(disturbed > 2_000, "{disturbed} samples set aside");
    assert!(
        text.contains(&format!(
            "{disturbed} IMU samples read a magnetic field unlike"
        )),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A gyro past its range: synth-log's iron swing with the lead wrist's gyro (sensor 4) sent
/// at full scale on one axis, as the LSM6DS3 sends it, for 50 ms from the top. The swing is
/// still found and scored, and the replay counts those samples and says what they limit.
#[test]
fn a_saturated_gyro_is_counted_and_said() {
    let dir = std::env::temp_dir().join(format!("posecoach-saturated-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (clean, log) = (dir.join("clean.pclog"), dir.join("saturated.pclog"));
    let made = iron_log(&clean, &[]);
    let top_us = (made["expected"]["swings"][0]["events_s"]["top"]
        .as_f64()
        .unwrap()
        * 1e6) as u64;
    let bytes = std::fs::read(&clean).unwrap();
    let mut out = header().to_vec();
    let mut saturated = 0;
    for mut message in LogReader::new(&bytes).unwrap() {
        if let Message::ImuSample(sample) = &mut message {
            if sample.sensor == 4 && (top_us..top_us + 50_000).contains(&sample.t_us) {
                sample.gyro_ddps[0] = i16::MAX;
                saturated += 1;
            }
        }
        out.extend(frame(&message).unwrap());
    }
    assert!(saturated >= 8, "{saturated} samples saturated");
    std::fs::write(&log, out).unwrap();
    let (replay, text) = replayed(&log);
    assert_eq!(replay["counters"]["imu_saturated"], saturated);
    assert!(
        text.contains(&format!(
            "{saturated} IMU samples had a gyro past its range"
        )),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
