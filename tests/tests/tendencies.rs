//! A session of several swings scored from files: `score` with `--student` more than once
//! prints each swing and what they say together, and its session agrees with its swings.

use posecoach_cli::score;
use posecoach_tests::parse;

fn fixture(name: &str) -> String {
    posecoach_tests::fixture(name).display().to_string()
}

#[test]
fn score_with_several_students_gives_each_swing_and_the_session() {
    let (coach, iron, driver, tpose) = (
        fixture("golf_driver_60hz.csv"),
        fixture("golf_iron_60hz.csv"),
        fixture("golf_driver_60hz.csv"),
        fixture("h36m17_tpose.csv"),
    );
    let files = [&iron, &driver, &iron];
    let mut argv = vec!["--coach", &coach, "--student-tpose", &tpose];
    for f in files {
        argv.extend(["--student", f.as_str()]);
    }
    let json: serde_json::Value = serde_json::from_str(
        &score::run(&parse(&[argv.as_slice(), &["--json"]].concat())).unwrap(),
    )
    .unwrap();
    let swings = json["swings"].as_array().unwrap();
    assert_eq!(swings.len(), 3);
    let session = &json["session"];
    assert_eq!(
        (session["swings"].as_u64(), session["used"].as_u64()),
        (Some(3), Some(3))
    );
    // The session's backswing is the swings' geometric mean ratio (three values within their
    // tolerance of each other are never pulled in).
    let ratios: Vec<f64> = swings
        .iter()
        .map(|s| s["report"]["tempo"]["phases"][0]["ratio"].as_f64().unwrap())
        .collect();
    let mean = (ratios.iter().map(|r| r.ln()).sum::<f64>() / 3.0).exp();
    let phase = &session["tempo"]["phases"][0];
    assert_eq!(phase["phase"], "backswing");
    assert!(
        (phase["ratio"].as_f64().unwrap() - mean).abs() < 0.002,
        "{phase} {ratios:?}"
    );
    assert_eq!(phase["swings"].as_u64(), Some(3));
    // The driver against itself adds no backswing difference, so neither is slow.
    assert_eq!(phase["verdict"], "ok");
    assert_eq!(session["body_checks"].as_array().unwrap().len(), 9);
    assert!(session["advice"].is_array() && session["set_aside"].as_array().unwrap().is_empty());
    let text = score::run(&parse(&argv)).unwrap();
    for heading in [
        "swing 1 (",
        "swing 2 (",
        "swing 3 (",
        "session: 3 swings, 3 used",
    ] {
        assert!(text.contains(heading), "{heading}");
    }
}
