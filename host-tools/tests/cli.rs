//! The `posecoach` binary end to end on the committed fixtures.
#![allow(clippy::unwrap_used)] // test helpers fail the test by unwrapping

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/fixtures")
        .join(name)
}

fn posecoach(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_posecoach"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

fn score_json(coach: &str, student: &str, extra: &[&str]) -> Value {
    let (coach, student) = (fixture(coach), fixture(student));
    let mut args = vec![
        "score",
        "--coach",
        coach.to_str().unwrap(),
        "--student",
        student.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    let (ok, out, err) = posecoach(&args);
    assert!(ok, "{err}");
    serde_json::from_str(&out).unwrap()
}

/// `posecoach score` of `student` against the bundled iron, with `extra` flags.
fn against_iron(student: &std::path::Path, extra: &[&str]) -> (bool, String, String) {
    let mut args = vec![
        "score",
        "--coach",
        "iron",
        "--student",
        student.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    posecoach(&args)
}

#[test]
fn score_json_has_the_documented_shape() {
    let tpose = fixture("h36m17_tpose.csv");
    let r = score_json(
        "golf_driver_60hz.csv",
        "golf_iron_60hz.csv",
        &["--student-tpose", tpose.to_str().unwrap()],
    );
    assert!((0.0..=100.0).contains(&r["score"].as_f64().unwrap()));
    for key in ["distance", "normalized"] {
        assert!(r["dtw"][key].is_number(), "dtw.{key}");
    }
    let path = r["dtw"]["path"].as_array().unwrap();
    assert_eq!(path[0], serde_json::json!([0, 0]));
    for side in ["student", "coach"] {
        for event in [
            "address",
            "toe_up",
            "mid_backswing",
            "top",
            "mid_downswing",
            "impact",
            "mid_follow_through",
            "finish",
        ] {
            assert!(r["events"][side][event].is_u64(), "events.{side}.{event}");
        }
    }
    assert!(r["tempo"]["student_ratio"].is_number() && r["tempo"]["coach_ratio"].is_number());
    let phases: Vec<&str> = r["tempo"]["phases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["phase"].as_str().unwrap())
        .collect();
    assert_eq!(phases, ["backswing", "downswing", "follow_through"]);
    for p in r["tempo"]["phases"].as_array().unwrap() {
        assert!(["ok", "slow", "fast"].contains(&p["verdict"].as_str().unwrap()));
        for key in ["student_s", "coach_s", "ratio"] {
            assert!(p[key].is_number());
        }
    }
    for d in r["spatial"].as_array().unwrap() {
        assert!(d["event"].is_string() && d["joint"].is_string() && d["distance_cm"].is_number());
        let directions = [
            "toward_target",
            "away_from_target",
            "toward_ball",
            "away_from_ball",
            "up",
            "down",
        ];
        assert!(directions.contains(&d["direction"].as_str().unwrap()));
        for axis in ["toward_target", "toward_ball", "up"] {
            assert!(d["offset_cm"][axis].is_number());
        }
    }
    assert!(r["advice"].as_array().unwrap().iter().all(Value::is_string));
}

#[test]
fn a_swing_against_itself_scores_100() {
    let r = score_json("golf_driver_60hz.csv", "golf_driver_60hz.csv", &[]);
    assert_eq!(r["score"].as_f64(), Some(100.0));
    assert!(r["spatial"].as_array().unwrap().is_empty());
    assert!(r["advice"].as_array().unwrap().is_empty());
}

#[test]
fn a_bundled_coach_is_named_without_a_file() {
    // The binary carries the device's coaches: `--coach iron` is `coaches/iron.pcr`.
    let student = fixture("golf_iron_60hz.csv");
    let student = student.to_str().unwrap();
    let bundled = fixture("../../coaches/iron.pcr");
    let scored = |coach: &str| {
        let (ok, out, err) =
            posecoach(&["score", "--coach", coach, "--student", student, "--json"]);
        assert!(ok, "{err}");
        let mut r: Value = serde_json::from_str(&out).unwrap();
        r.as_object_mut().unwrap().remove("files");
        r
    };
    assert_eq!(scored("iron"), scored(bundled.to_str().unwrap()));
    let (ok, _, err) = posecoach(&["score", "--coach", "putter", "--student", student]);
    assert!(!ok && err.contains("bundled: driver, iron"), "{err}");
}

#[test]
fn driver_against_iron_matches_its_golden_report() {
    let mut r = score_json("golf_driver_60hz.csv", "golf_iron_60hz.csv", &[]);
    // The files as given (this checkout's paths), then the rest against the golden report.
    let files = r.as_object_mut().unwrap().remove("files").unwrap();
    for (key, name) in [
        ("coach", "golf_driver_60hz.csv"),
        ("student", "golf_iron_60hz.csv"),
    ] {
        assert!(files[key].as_str().unwrap().ends_with(name), "{files}");
    }
    assert_eq!(files["student_tpose"], Value::Null);
    let golden = fixture("score_iron_vs_driver.json");
    if std::env::var_os("POSECOACH_BLESS").is_some() {
        std::fs::write(&golden, format!("{r:#}\n")).unwrap();
    }
    let expected: Value = serde_json::from_str(&std::fs::read_to_string(&golden).unwrap()).unwrap();
    assert_eq!(
        r, expected,
        "rerun with POSECOACH_BLESS=1 after an intended change"
    );
}

#[test]
fn errors_name_the_file_and_what_to_fix() {
    let (ok, _, err) = posecoach(&[
        "score",
        "--coach",
        "missing.csv",
        "--student",
        "missing.csv",
    ]);
    assert!(!ok);
    assert!(err.contains("missing.csv"), "{err}");
    let tpose = fixture("h36m17_tpose.csv");
    let (ok, _, err) = posecoach(&[
        "score",
        "--coach",
        tpose.to_str().unwrap(),
        "--student",
        tpose.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(err.contains("swing"), "{err}");
}

/// The exit status, standard output and standard error of `posecoach args`.
fn posecoach_status(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_posecoach"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

#[test]
fn failures_have_a_kind_and_an_exit_status() {
    let iron = fixture("golf_iron_60hz.csv");
    let iron = iron.to_str().unwrap();
    let error = |out: &str| -> (String, String) {
        let v: Value = serde_json::from_str(out).unwrap();
        let e = &v["error"];
        (
            e["kind"].as_str().unwrap().into(),
            e["message"].as_str().unwrap().into(),
        )
    };
    // Bad input: 1, the file named.
    let (status, out, err) = posecoach_status(&[
        "score",
        "--coach",
        "missing.csv",
        "--student",
        iron,
        "--json",
    ]);
    assert_eq!(status, 1, "{err}");
    let (kind, message) = error(&out);
    assert_eq!(kind, "bad_input");
    assert!(message.contains("missing.csv"), "{message}");
    assert!(err.starts_with("error: "), "{err}");
    // Usage: 2, from clap and from a command, under --json too; a report's name is checked
    // before any work, and nothing is written.
    let (status, out, _) = posecoach_status(&["score", "--student", iron, "--json"]);
    assert_eq!(status, 2);
    assert_eq!(error(&out).0, "usage");
    let (status, _, err) = posecoach_status(&["score", "--student", iron]);
    assert_eq!(status, 2, "{err}");
    let dir = std::env::temp_dir().join(format!("posecoach-failures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The iron against itself, its report written to `name` (with `--json`).
    let with_report = |name: &str| {
        let path = dir.join(name);
        let run = posecoach_status(&[
            "score",
            "--coach",
            iron,
            "--student",
            iron,
            "--report",
            path.to_str().unwrap(),
            "--json",
        ]);
        (path, run)
    };
    let (pdf, (status, out, _)) = with_report("report.pdf");
    assert_eq!(status, 2);
    let (kind, message) = error(&out);
    assert_eq!(kind, "usage");
    assert!(
        message.contains(".html") && message.contains(".json"),
        "{message}"
    );
    assert!(!pdf.exists());
    // Reports by extension.
    let (htm, (status, _, err)) = with_report("report.HTM");
    assert_eq!(status, 0, "{err}");
    assert!(std::fs::read_to_string(&htm)
        .unwrap()
        .starts_with("<!DOCTYPE html>"));
    // Nothing found: 3. A student standing still at address for two seconds has no swing.
    let text = std::fs::read_to_string(fixture("golf_iron_60hz.csv")).unwrap();
    let mut lines = text.lines();
    let (header, address) = (lines.next().unwrap(), lines.next().unwrap());
    let pose = address.split_once(',').unwrap().1;
    let still = dir.join("still.csv");
    let rows: Vec<String> = (0..120)
        .map(|f| format!("{},{pose}", f as f32 / 60.0))
        .collect();
    std::fs::write(&still, format!("{header}\n{}\n", rows.join("\n"))).unwrap();
    let (status, out, err) = posecoach_status(&[
        "score",
        "--coach",
        iron,
        "--student",
        still.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(status, 3, "{err}");
    assert_eq!(status, 3);
    let (kind, message) = error(&out);
    assert_eq!(kind, "nothing_found");
    assert!(message.contains("still.csv"), "{message}");
    // A recording cut short: its usual output all the same, and 3.
    let log = std::fs::read(fixture("../logs/short_cmu_30hz.pclog")).unwrap();
    let cut = dir.join("cut.pclog");
    let end = (2000..3000).rev().find(|&k| log[k - 1] != 0).unwrap();
    std::fs::write(&cut, &log[..end]).unwrap();
    let (status, out, err) = posecoach_status(&["replay", cut.to_str().unwrap(), "--json"]);
    assert_eq!(status, 3, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["swings"].as_array().unwrap().len(), 0);
    assert!(v["counters"]["frames_ok"].as_u64().unwrap() > 0);
    assert_eq!(v["counters"]["cut_short"], true);
    assert!(
        err.contains("no swing found") && err.contains("cut short"),
        "{err}"
    );
    // One flag per thing across commands: the coach is --coach for `reference` too; an
    // output a command cannot write is refused before any work; float weights where a device's
    // int8 ones belong are named as such, with the command that makes the right ones.
    let pcr = dir.join("iron.pcr");
    let (status, _, err) = posecoach_status(&["reference", iron, "--out", pcr.to_str().unwrap()]);
    assert_eq!(status, 2, "{err}");
    let (status, _, err) =
        posecoach_status(&["reference", "--coach", iron, "--out", pcr.to_str().unwrap()]);
    assert_eq!(status, 0, "{err}");
    let c3d = dir.join("virtual.c3d");
    let (status, out, _) = posecoach_status(&[
        "retarget",
        "--coach",
        iron,
        "--student-tpose",
        fixture("h36m17_tpose.csv").to_str().unwrap(),
        "--out",
        c3d.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(status, 2);
    let (kind, message) = error(&out);
    assert_eq!(kind, "usage");
    assert!(message.contains(".bvh or .csv"), "{message}");
    assert!(!c3d.exists());
    let float = weights("teacher.pcw");
    let log = fixture("../logs/short_cmu_30hz.pclog");
    let (status, _, err) = posecoach_status(&[
        "replay",
        log.to_str().unwrap(),
        "--weights",
        float.to_str().unwrap(),
    ]);
    assert_eq!(status, 1, "{err}");
    assert!(
        err.contains("float weights") && err.contains("posecoach export"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

fn weights(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../weights")
        .join(name)
}

/// `inspect` reads the float weights without the `learn` feature (this build has none): kind,
/// version, header, parts, checksum.
#[test]
fn inspect_describes_float_weights_and_refuses_damaged_ones() {
    let teacher = weights("teacher.pcw");
    let (ok, out, err) = posecoach(&["inspect", teacher.to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    let r: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(r["kind"], "float weights");
    assert_eq!(r["holds"], "network");
    assert_eq!(r["version"], 3);
    assert_eq!(r["bytes"], 343_408);
    let h = &r["header"];
    assert_eq!(
        (&h["features"], &h["heads"], &h["kernel"]),
        (&32.into(), &2.into(), &3.into())
    );
    assert_eq!(
        (&h["step"], &h["prior"]),
        (&10_000.into(), &"rotations".into())
    );
    assert_eq!(r["parts"][0]["name"], "network");
    assert_eq!(r["parts"][0]["bytes"], 343_308);
    assert_eq!(r["checksum"]["ok"], true);
    let (ok, text, err) = posecoach(&["inspect", weights("distilled.pcw").to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(text.contains("d = 16 per segment"), "{text}");
    assert!(text.contains("checksum: CRC-32/ISO-HDLC 0x"), "{text}");

    let dir = std::env::temp_dir().join(format!("posecoach-inspect-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut bytes = std::fs::read(&teacher).unwrap();
    bytes[1000] ^= 4;
    let damaged = dir.join("damaged.pcw");
    std::fs::write(&damaged, &bytes).unwrap();
    let (ok, _, err) = posecoach(&["inspect", damaged.to_str().unwrap()]);
    assert!(
        !ok && err.contains("damaged") && err.contains("damaged.pcw"),
        "{err}"
    );
    bytes[1000] ^= 4;
    bytes[7] = b'2';
    let old = dir.join("old.pcw");
    std::fs::write(&old, &bytes).unwrap();
    let (ok, _, err) = posecoach(&["inspect", old.to_str().unwrap()]);
    assert!(
        !ok && err.contains("PCTEACH2") && err.contains("re-save"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The iron fixture as a spreadsheet writes it from a Z-up capture in millimetres with frame
/// numbers: `;` separators, decimal commas, quoted header cells, a byte-order mark, CRLF.
fn iron_as_a_spreadsheet() -> String {
    let text = std::fs::read_to_string(fixture("golf_iron_60hz.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|c| format!("\"{}\"", if c == "time" { "frame" } else { c }))
        .collect();
    let mut out = vec![header.join(";")];
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        let mut row = vec![format!(
            "{}",
            (cells[0].parse::<f64>().unwrap() * 60.0).round()
        )];
        for xyz in cells[1..].chunks(3) {
            let mm = |c: &str| match c {
                "" => String::new(),
                c => format!("{:.2}", c.parse::<f64>().unwrap() * 1000.0).replace('.', ","),
            };
            // Z up: y ← -z, z ← y.
            let minus_z = match mm(xyz[2]) {
                z if z.is_empty() => z,
                z => z.strip_prefix('-').map_or(format!("-{z}"), str::to_string),
            };
            row.extend([mm(xyz[0]), minus_z, mm(xyz[1])]);
        }
        out.push(row.join(";"));
    }
    format!("\u{feff}{}\r\n", out.join("\r\n"))
}

#[test]
fn input_files_say_how_they_were_read() {
    let dir = std::env::temp_dir().join(format!("posecoach-byod-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("iron_mm_zup.csv");
    std::fs::write(&file, iron_as_a_spreadsheet()).unwrap();
    let file = file.to_str().unwrap();
    // Frame numbers without a rate: bad input, saying what to give.
    let (ok, out, err) = posecoach(&["inspect", file, "--json"]);
    assert!(!ok && err.contains("--rate"), "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["error"]["kind"], "bad_input");
    // With the rate: millimetres and Z up found, and said.
    let (ok, out, err) = posecoach(&["inspect", file, "--rate", "60", "--json"]);
    assert!(ok, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    let reading = &v["reading"];
    assert_eq!(reading["units"], "mm");
    assert_eq!(reading["up"], "+z");
    assert_eq!(reading["time"], "frame numbers");
    let iron: Value = serde_json::from_str(
        &posecoach(&[
            "inspect",
            fixture("golf_iron_60hz.csv").to_str().unwrap(),
            "--json",
        ])
        .1,
    )
    .unwrap();
    assert_eq!(v["height_m"], iron["height_m"]);
    // Scored as the original file is, with a note of what was converted.
    let coach = fixture("golf_driver_60hz.csv");
    let coach = coach.to_str().unwrap();
    let (ok, out, err) = posecoach(&[
        "score",
        "--coach",
        coach,
        "--student",
        file,
        "--rate",
        "60",
        "--json",
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("units mm (detected)") && err.contains("up +z (detected)"),
        "{err}"
    );
    let converted: Value = serde_json::from_str(&out).unwrap();
    let original = score_json("golf_driver_60hz.csv", "golf_iron_60hz.csv", &[]);
    assert_eq!(converted["score"], original["score"]);
    // A unit given that makes no golfer is refused, saying the stature.
    let (ok, _, err) = posecoach(&["inspect", file, "--rate", "60", "--units", "m"]);
    assert!(!ok && err.contains("m tall in m"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_bring_your_own_data_example_reads_as_its_tool_writes_it() {
    // (file, vocabulary, units, up, time) as the README's table says.
    let cases = [
        (
            "mediapipe_iron.jsonl",
            "MediaPipe BlazePose-33 landmarks",
            "m",
            "-y",
            "milliseconds",
        ),
        (
            "openpose_iron.csv",
            "OpenPose BODY_25 keypoints",
            "mm",
            "-y",
            "frame numbers",
        ),
        ("kinect_iron.json", "Kinect joints", "mm", "-y", "seconds"),
        (
            "spreadsheet_iron.csv",
            "posecoach joint names",
            "cm",
            "+z",
            "seconds",
        ),
    ];
    let iron = score_json("golf_iron_60hz.csv", "golf_iron_60hz.csv", &[]);
    for (name, landmarks, units, up, time) in cases {
        let file = fixture(&format!("byod/{name}"));
        let file = file.to_str().unwrap();
        let (ok, out, err) = posecoach(&["inspect", file, "--rate", "60", "--json"]);
        assert!(ok, "{name}: {err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        let r = &v["reading"];
        let found = (
            r["landmarks"].as_str(),
            r["units"].as_str(),
            r["up"].as_str(),
            r["time"].as_str(),
        );
        assert_eq!(
            found,
            (Some(landmarks), Some(units), Some(up), Some(time)),
            "{name}"
        );
        assert!(
            (v["rate_hz"].as_f64().unwrap() - 60.0).abs() < 0.05,
            "{name}: {}",
            v["rate_hz"]
        );
        let scored = score_json(
            "golf_iron_60hz.csv",
            &format!("byod/{name}"),
            &["--rate", "60"],
        );
        // Where the tool gives every joint the iron has, the score is the iron's own.
        if name.starts_with("kinect") || name.starts_with("spreadsheet") {
            assert_eq!(scored["score"], iron["score"], "{name}");
        }
        // MediaPipe's world landmarks hold the hips at the origin: the body is put back on
        // its planted feet, so its hips move again.
        let mediapipe = name.starts_with("mediapipe");
        assert_eq!(r["on_its_feet"], mediapipe, "{name}");
        assert_eq!(scored["root_held"], false, "{name}");
        assert!(
            scored["score"].as_f64().unwrap() > 95.0,
            "{name}: {}",
            scored["score"]
        );
    }
}

/// The real iron as a range recording: each swing from `swings` times over, its first frame
/// held `before` s and its last `after` s, as a CSV in seconds.
fn iron_recording(name: &str, swings: usize, before: f64, after: f64) -> PathBuf {
    let text = std::fs::read_to_string(fixture("golf_iron_60hz.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.map(|l| l.split_once(',').unwrap().1).collect();
    let hold = |s: f64| (s * 60.0).round() as usize;
    let mut frames: Vec<&str> = Vec::new();
    for _ in 0..swings {
        frames.extend(std::iter::repeat_n(rows[0], hold(before)));
        frames.extend(&rows);
        frames.extend(std::iter::repeat_n(rows[rows.len() - 1], hold(after)));
    }
    let mut csv = format!("{header}\n");
    for (i, row) in frames.iter().enumerate() {
        csv.push_str(&format!("{},{row}\n", i as f64 / 60.0));
    }
    let path = std::env::temp_dir().join(format!("posecoach-{name}-{}.csv", std::process::id()));
    std::fs::write(&path, csv).unwrap();
    path
}

#[test]
fn a_whole_recording_is_scored_swing_by_swing() {
    let score = |student: &PathBuf| against_iron(student, &["--json"]);
    // One swing with a second of set-up and a held finish: longer than the scorer takes
    // whole, cut to its swing.
    let one = iron_recording("one-swing", 1, 1.0, 1.5);
    let (ok, out, err) = score(&one);
    assert!(ok, "{err}");
    let r: Value = serde_json::from_str(&out).unwrap();
    assert!(r["score"].as_f64().unwrap() > 99.0, "{}", r["score"]);
    // Three swings in one file: each scored, then the session they make.
    let three = iron_recording("three-swings", 3, 1.0, 1.5);
    let (ok, out, err) = score(&three);
    assert!(ok, "{err}");
    let r: Value = serde_json::from_str(&out).unwrap();
    let swings = r["swings"].as_array().unwrap();
    assert_eq!(swings.len(), 3, "{err}");
    let starts: Vec<f64> = swings
        .iter()
        .map(|s| s["start_s"].as_f64().unwrap())
        .collect();
    let period = 1.0 + 1.5 + 109.0 / 60.0;
    assert!((starts[2] - starts[1] - period).abs() < 0.05, "{starts:?}");
    assert!(swings
        .iter()
        .all(|s| s["report"]["score"].as_f64().unwrap() > 99.0));
    assert_eq!(r["session"]["swings"], 3);
    // The text names each swing by its file and start.
    let (ok, text, _) = against_iron(&three, &[]);
    assert!(ok && text.contains(", the swing at "), "{text}");
    // inspect lists them.
    let (ok, out, err) = posecoach(&["inspect", three.to_str().unwrap(), "--json"]);
    assert!(ok, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["swings"].as_array().unwrap().len(), 3, "{out}");
    for file in [one, three] {
        std::fs::remove_file(file).unwrap();
    }
}

/// The real driver as MediaPipe's world landmarks hand it over: named BlazePose landmarks,
/// metres, +Y down, centred on the hips, time in ms, no club; the ears at the head and the
/// fingers 8 cm past the wrists (the capture has no such joints).
fn driver_as_mediapipe() -> PathBuf {
    let text = std::fs::read_to_string(fixture("golf_driver_60hz.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut out = String::new();
    for row in lines {
        // An empty cell (a club marker lost) is not read below.
        let cells: Vec<f64> = row
            .split(',')
            .map(|c| c.parse().unwrap_or(f64::NAN))
            .collect();
        let at = |joint: &str| -> [f64; 3] {
            let k = header
                .iter()
                .position(|h| *h == format!("{joint}_x"))
                .unwrap();
            [cells[k], cells[k + 1], cells[k + 2]]
        };
        let [l, r] = [at("left_hip"), at("right_hip")];
        let hips: [f64; 3] = std::array::from_fn(|i| (l[i] + r[i]) / 2.0);
        let point = |p: [f64; 3]| {
            format!(
                "[{}, {}, {}]",
                p[0] - hips[0],
                hips[1] - p[1],
                hips[2] - p[2]
            )
        };
        let mut landmarks = Vec::new();
        for side in ["left", "right"] {
            for (joint, name) in [
                ("hip", "hip"),
                ("knee", "knee"),
                ("ankle", "ankle"),
                ("toe", "foot_index"),
                ("shoulder", "shoulder"),
                ("elbow", "elbow"),
                ("wrist", "wrist"),
            ] {
                landmarks.push(format!(
                    "\"{side}_{name}\": {}",
                    point(at(&format!("{side}_{joint}")))
                ));
            }
            landmarks.push(format!("\"{side}_ear\": {}", point(at("head"))));
            let (e, w) = (at(&format!("{side}_elbow")), at(&format!("{side}_wrist")));
            let d: [f64; 3] = std::array::from_fn(|i| w[i] - e[i]);
            let n = d.iter().map(|v| v * v).sum::<f64>().sqrt();
            let hand = point(std::array::from_fn(|i| w[i] + d[i] / n * 0.08));
            for finger in ["pinky", "index"] {
                landmarks.push(format!("\"{side}_{finger}\": {hand}"));
            }
        }
        out.push_str(&format!(
            "{{\"timestamp_ms\": {}, \"pose_world_landmarks\": {{{}}}}}\n",
            (cells[0] * 1000.0).round(),
            landmarks.join(", ")
        ));
    }
    let path =
        std::env::temp_dir().join(format!("posecoach-mp-driver-{}.jsonl", std::process::id()));
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn mediapipe_world_landmarks_stand_on_their_feet_as_student_and_as_coach() {
    let mediapipe = driver_as_mediapipe();
    let mediapipe = mediapipe.to_str().unwrap();
    let driver = fixture("golf_driver_60hz.csv");
    let driver = driver.to_str().unwrap();
    for (coach, student) in [("driver", mediapipe), (mediapipe, driver)] {
        let (ok, out, err) =
            posecoach(&["score", "--coach", coach, "--student", student, "--json"]);
        assert!(ok, "{err}");
        let r: Value = serde_json::from_str(&out).unwrap();
        assert!(
            r["score"].as_f64().unwrap() >= 98.0,
            "{coach} / {student}: {}",
            r["score"]
        );
        assert_eq!(r["advice"], serde_json::json!([]), "{coach} / {student}");
        assert_eq!(r["root_held"], false);
        // The club only the capture tracks is left out, and said to be.
        let left_out = r["not_compared"].to_string();
        assert!(left_out.contains("club_head"), "{left_out}");
        assert!(err.contains("not compared: "), "{err}");
    }
    std::fs::remove_file(mediapipe).unwrap();
}

/// The README's bring-your-own-data table states each example's score against the bundled
/// iron; `score` must print it, or the README is stale.
#[test]
fn the_readmes_bring_your_own_data_scores_are_what_score_prints() {
    let readme = std::fs::read_to_string(fixture("../../README.md")).unwrap();
    let section = readme.split("## Bring your own data").nth(1).unwrap();
    let mut rows = 0;
    for row in section.lines().take_while(|l| !l.starts_with("## ")) {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let Some(file) = cells.get(1).and_then(|c| c.strip_prefix('`')) else {
            continue;
        };
        let file = file.trim_end_matches('`');
        let stated: f64 = cells[3].split([' ', ':']).next().unwrap().parse().unwrap();
        let path = fixture(&format!("byod/{file}"));
        let (ok, out, err) = against_iron(&path, &["--rate", "60", "--json"]);
        assert!(ok, "{file}: {err}");
        let r: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(
            r["score"].as_f64(),
            Some(stated),
            "{file}: the README says {stated}"
        );
        rows += 1;
    }
    assert_eq!(rows, 4, "the README's table has one row per example");
}

/// The OpenPose example written as OpenPose's `--write_json` writes a clip: a folder of
/// per-frame files, BODY_25 flat inside `people` (2D always, 3D with a score where `three_d`).
fn openpose_folder(name: &str, three_d: bool) -> PathBuf {
    let text = std::fs::read_to_string(fixture("byod/openpose_iron.csv")).unwrap();
    let dir = std::env::temp_dir().join(format!("posecoach-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (f, row) in text.lines().skip(1).enumerate() {
        let xyz: Vec<&str> = row.split(',').skip(1).collect();
        let (mut two, mut three) = (Vec::new(), Vec::new());
        for p in xyz.chunks(3) {
            two.extend([p[0], p[1], "0.9"]);
            three.extend([p[0], p[1], p[2], "0.9"]);
        }
        let three = if three_d {
            three.join(",")
        } else {
            String::new()
        };
        let frame = format!(
            "{{\"version\":1.3,\"people\":[{{\"person_id\":[-1],\"pose_keypoints_2d\":[{}],\
             \"face_keypoints_2d\":[],\"pose_keypoints_3d\":[{three}],\"face_keypoints_3d\":[]}}]}}",
            two.join(",")
        );
        std::fs::write(dir.join(format!("iron_{f:012}_keypoints.json")), frame).unwrap();
    }
    dir
}

#[test]
fn an_openpose_folder_is_scored_as_its_frames_and_2d_is_refused() {
    let score = |student: &PathBuf| against_iron(student, &["--rate", "60", "--json"]);
    let (ok, csv, err) = score(&fixture("byod/openpose_iron.csv"));
    assert!(ok, "{err}");
    let folder = openpose_folder("openpose3d", true);
    let (ok, out, err) = score(&folder);
    assert!(ok, "{err}");
    let [a, b]: [Value; 2] = [csv, out].map(|o| serde_json::from_str(&o).unwrap());
    assert_eq!(a["score"], b["score"]);
    let flat = openpose_folder("openpose2d", false);
    let (ok, _, err) = score(&flat);
    assert!(
        !ok && err.contains("2D keypoints: posecoach needs 3D (x, y, z)"),
        "{err}"
    );
    assert!(err.contains("iron_000000000000_keypoints.json"), "{err}");
    for dir in [folder, flat] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

#[test]
fn a_pause_at_the_top_is_reported_with_the_backswing() {
    // The driver held still at its top for 0.3 s (18 frames at 60 Hz).
    let plain = score_json("golf_driver_60hz.csv", "golf_driver_60hz.csv", &[]);
    assert_eq!(plain["tempo"]["student_pause_s"], 0.0);
    let top = plain["events"]["student"]["top"].as_u64().unwrap() as usize;
    let text = std::fs::read_to_string(fixture("golf_driver_60hz.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.collect();
    let mut frames: Vec<&str> = rows[..top].to_vec();
    frames.extend(std::iter::repeat_n(rows[top], 18));
    frames.extend(&rows[top..]);
    let mut csv = format!("{header}\n");
    for (i, row) in frames.iter().enumerate() {
        let rest = row.split_once(',').unwrap().1;
        csv.push_str(&format!("{},{rest}\n", i as f64 / 60.0));
    }
    let dir = std::env::temp_dir().join(format!("posecoach-pause-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let paused = dir.join("paused.csv");
    std::fs::write(&paused, csv).unwrap();
    let coach = fixture("golf_driver_60hz.csv");
    let args = [
        "score",
        "--coach",
        coach.to_str().unwrap(),
        "--student",
        paused.to_str().unwrap(),
    ];
    let (ok, out, err) = posecoach(&[&args[..], &["--json"]].concat());
    assert!(ok, "{err}");
    let json: Value = serde_json::from_str(&out).unwrap();
    let pause = json["tempo"]["student_pause_s"].as_f64().unwrap();
    assert!((pause - 0.3).abs() < 0.05, "pause {pause} s");
    assert_eq!(json["tempo"]["coach_pause_s"], 0.0);
    assert_eq!(json["tempo"]["phases"][0]["verdict"], "slow");
    let (ok, out, err) = posecoach(&args);
    assert!(ok, "{err}");
    assert!(out.contains("pause at the top: you 0.3"), "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Cells of a global band of radius `r` over `n × n` frames: the full rows less the two
/// corners' triangles.
fn band_cells(n: u64, r: u64) -> u64 {
    n * (2 * r + 1) - r * (r + 1)
}

#[test]
fn the_dtw_sweep_moves_one_axis_at_a_time_and_costs_what_one_point_costs() {
    let (ok, out, err) = posecoach(&["bench", "dtw", "--sweep", "--seconds", "0", "--json"]);
    assert!(ok, "{err}");
    assert!(err.contains("point 14 of 14"), "progress on stderr: {err}");
    let sweep: Value = serde_json::from_str(&out).unwrap();
    let points = sweep["points"].as_array().unwrap();
    assert_eq!(points.len(), 14);
    let at = |p: &Value, key: &str| p[key].as_u64().unwrap();
    let ns: Vec<u64> = points.iter().map(|p| at(p, "n")).collect();
    assert_eq!(ns.iter().min(), Some(&100));
    assert_eq!(ns.iter().max(), Some(&5000));
    for p in points {
        // Each point moves one of n, dims and band away from (200, 51, 20).
        let moved = [at(p, "n") != 200, at(p, "dims") != 51, at(p, "band") != 20];
        assert!(moved.iter().filter(|&&m| m).count() <= 1, "{p}");
        let (cells, exact) = (at(p, "cells"), band_cells(at(p, "n"), at(p, "band")));
        if at(p, "n") <= 4096 {
            assert_eq!(cells, exact, "{p}");
        } else {
            // The guide's columns are f32: past 2^24 / n rows a row's end may round up one.
            assert!((exact..exact + exact / 200).contains(&cells), "{p}");
        }
        assert!(p["ns_per_cell"].as_f64().unwrap() > 0.0);
    }
    // The benchmark's own point gives the same alignment as a single run of it.
    let (ok, one, err) = posecoach(&["bench", "dtw", "--seconds", "0", "--json"]);
    assert!(ok, "{err}");
    let one: Value = serde_json::from_str(&one).unwrap();
    let same = points
        .iter()
        .find(|p| (at(p, "n"), at(p, "dims"), at(p, "band")) == (200, 51, 20))
        .unwrap();
    assert_eq!(same["distance"], one["distance"]);
    assert_eq!(same["path_len"], one["path_len"]);
}

#[test]
fn the_score_bench_scores_the_bundled_swings_at_every_point() {
    let args = [
        "bench",
        "score",
        "--formats",
        "h36m17,cmu31",
        "--rates",
        "30,60",
        "--bands",
        "5,20",
        "--seconds",
        "0",
        "--json",
    ];
    let (ok, out, err) = posecoach(&args);
    assert!(ok, "{err}");
    let bench: Value = serde_json::from_str(&out).unwrap();
    let points = bench["points"].as_array().unwrap();
    assert_eq!(points.len(), 8);
    for pair in points.chunks(2) {
        let cells: Vec<u64> = pair.iter().map(|p| p["cells"].as_u64().unwrap()).collect();
        assert!(
            cells[0] < cells[1],
            "a wider band costs more cells: {pair:?}"
        );
    }
    for p in points {
        let frames = p["student_frames"].as_u64().unwrap();
        let expected = if p["rate_hz"].as_f64().unwrap() == 30.0 {
            55
        } else {
            110
        };
        assert!(frames.abs_diff(expected) <= 2, "{p}");
        assert!(p["swings_per_second"].as_f64().unwrap() > 0.0);
        assert!((0.0..=100.0).contains(&p["score"].as_f64().unwrap()));
    }
    assert_eq!(points[0]["dims"], 51);
    assert_eq!(points[4]["dims"], 93);
}
