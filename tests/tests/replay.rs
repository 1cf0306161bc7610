//! Every committed recording in `tests/logs` replayed as the device would: the swings its
//! sidecar lists are found, at the right moments, and their reports equal the golden ones. A
//! seeded fault injector then damages the bytes the way a bad serial link does.

use posecoach_cli::replay::{replay, Replay};
use posecoach_core::weights::Weights;
use posecoach_core::wire::{Decoder, Message};
use posecoach_tests::{files, json_difference};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Events other than address must be found within this many seconds: three frames at the 60 Hz
/// model rate, a frame and a half of a 30 Hz capture (an amateur's slow transition makes the
/// top a flat speed minimum; on the clean logs every event is within two frames).
const EVENT_TOLERANCE_S: f64 = 0.05;
/// How close a reported backswing must come to the one the log was made with.
#[derive(Clone, Copy)]
enum Backswing {
    /// Within this share of it.
    Within(f64),
    /// Within this many of the report's own standard deviations of it (a link that lost a
    /// quarter of its frames leaves less to time the swing by, and the report must say so).
    Stated(f64),
}

/// A clean replay's backswing: within 5 %.
const BACKSWING: Backswing = Backswing::Within(0.05);

fn logs() -> Vec<PathBuf> {
    let found = files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("logs"), "pclog");
    assert!(!found.is_empty(), "no committed logs");
    found
}

fn sidecar(log: &Path) -> Value {
    let text = std::fs::read_to_string(log.with_extension("swings.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Checks the replay found exactly the sidecar's swings with their events, and their backswings.
fn check_swings(name: &str, replay: &Replay, expected: &Value, backswing: Backswing) {
    let expected = expected["swings"].as_array().unwrap();
    assert_eq!(
        replay.swings.len(),
        expected.len(),
        "{name}: swings found\n{}",
        replay.text
    );
    for (found, truth) in replay.swings.iter().zip(expected) {
        let report = &found["report"];
        assert!(report.is_object(), "{name}: not scored: {found}");
        let start = found["start_s"].as_f64().unwrap();
        let rate = found["rate_hz"].as_f64().unwrap();
        for (event, frame) in report["events"]["student"].as_object().unwrap() {
            let at = start + frame.as_f64().unwrap() / rate;
            let want = truth["events_s"][event].as_f64().unwrap();
            if event == "address" {
                // Anywhere in the still set-up before the takeaway.
                let still = truth["still_from_s"].as_f64().unwrap();
                assert!(
                    at >= still - EVENT_TOLERANCE_S && at <= want + EVENT_TOLERANCE_S,
                    "{name}: address at {at:.3} s, still from {still:.3} s to {want:.3} s"
                );
            } else {
                assert!(
                    (at - want).abs() <= EVENT_TOLERANCE_S,
                    "{name}: {event} at {at:.3} s, expected {want:.3} s"
                );
            }
        }
        // The backswing as it was made: from the takeaway (the swing's first frame, the golfer
        // still before it) to the top.
        let takeaway = truth
            .get("takeaway_s")
            .unwrap_or(&truth["start_s"])
            .as_f64()
            .unwrap();
        let made = truth["events_s"]["top"].as_f64().unwrap() - takeaway;
        let phase = &report["tempo"]["phases"][0];
        let reported = phase["student_s"].as_f64().unwrap();
        let bound = match backswing {
            Backswing::Within(share) => share,
            Backswing::Stated(sds) => {
                sds * phase["ratio_uncertainty"].as_f64().unwrap()
                    / phase["ratio"].as_f64().unwrap()
            }
        };
        assert!(
            (reported / made - 1.0).abs() <= bound,
            "{name}: backswing {reported:.3} s, made {made:.3} s (bound {:.1} %)",
            bound * 100.0
        );
    }
}

/// Logs also replayed with the committed int8 weights: the firmware's clean and hostile
/// sessions (their model rate is the network's, so the coach is retargeted by the network).
const INT8_LOGS: [&str; 2] = ["device_h36m_30hz.pclog", "hostile_h36m_30hz.pclog"];

#[test]
fn every_log_replays_to_its_swings_and_golden_reports() {
    for log in logs() {
        check_log(&log, None, "");
    }
}

#[test]
fn the_firmwares_log_replays_with_the_int8_network_to_its_goldens() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../weights/distilled-int8.pcw");
    let network = posecoach_cli::coaches::Network::load(&path).unwrap();
    let weights = network.weights().unwrap();
    for name in INT8_LOGS {
        let log = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("logs")
            .join(name);
        let analytic = replay(&std::fs::read(&log).unwrap(), None).unwrap();
        let int8 = check_log(&log, Some(&weights), "int8.");
        // The network did retarget the coach: the reports are not the analytic ones.
        assert_ne!(int8.swings, analytic.swings, "{name}");
    }
}

/// Replays `log` with `network`, checks its swings against the sidecar and its reports, its
/// range session and its device frames against the goldens (`<log>.<prefix>replay.json`, `<log>.<prefix>device.bin`).
fn check_log(log: &Path, network: Option<&Weights<'_>>, prefix: &str) -> Replay {
    let name = log.file_name().unwrap().to_string_lossy().into_owned();
    let bytes = std::fs::read(log).unwrap();
    let replay = replay(&bytes, network).unwrap();
    let expected = sidecar(log);
    // Clean logs have nothing refused; a hostile one (tests/tests/hostile.rs) states how much.
    let refusals = expected.get("refused").map_or(0, |n| n.as_u64().unwrap());
    assert_eq!(
        replay.refused.len() as u64,
        refusals,
        "{name}: refused {:?}",
        replay.refused
    );
    check_swings(&name, &replay, &expected, BACKSWING);
    let golden = log.with_extension(format!("{prefix}replay.json"));
    // Every swing's report, and the range session they made.
    let reports = serde_json::json!({"swings": replay.swings, "session": replay.session.json});
    let got = format!("{reports:#}\n");
    if std::env::var_os("POSECOACH_BLESS").is_some() {
        std::fs::write(&golden, &got).unwrap();
    }
    let want = std::fs::read_to_string(&golden)
        .unwrap_or_else(|_| panic!("{}: missing; POSECOACH_BLESS=1 writes it", golden.display()));
    let want: Value = serde_json::from_str(&want).unwrap();
    let difference = json_difference(&reports, &want, 1e-5);
    assert!(
        difference.is_none(),
        "{name}: the reports differ from {} at {} (POSECOACH_BLESS=1 rewrites it after a deliberate change)",
        golden.display(),
        difference.unwrap_or_default()
    );
    // What the device sends back, byte for byte: the QEMU firmware compares its own
    // frames with this file.
    let wire = log.with_extension(format!("{prefix}device.bin"));
    if std::env::var_os("POSECOACH_BLESS").is_some() {
        std::fs::write(&wire, &replay.wire).unwrap();
    }
    let want = std::fs::read(&wire)
        .unwrap_or_else(|_| panic!("{}: missing; POSECOACH_BLESS=1 writes it", wire.display()));
    assert!(
        replay.wire == want,
        "{name}: the device's frames differ from {} (POSECOACH_BLESS=1 rewrites it after a deliberate change)",
        wire.display()
    );
    replay
}

/// The wire frames of a log after its header, each with its delimiter.
fn frames(log: &[u8]) -> Vec<&[u8]> {
    log[posecoach_adapters::log::HEADER_LEN..]
        .split_inclusive(|&b| b == 0)
        .collect()
}

fn decode(frame: &[u8]) -> Option<Message> {
    let mut decoder = Decoder::new();
    let mut got = None;
    for &b in frame {
        decoder.push(b, |m| got = Some(m.clone()));
    }
    got
}

/// What the injector did.
struct Faults {
    bytes: Vec<u8>,
    /// Messages of the frames that reached the device undamaged, in order.
    intact: Vec<Message>,
    damaged: usize,
    dropped: usize,
    duplicated: usize,
}

/// Drops `drop` of the frames, sends `duplicate` of them twice, then flips each byte with
/// probability `flip`. The first `keep` frames (the set-up a phone resends until it is
/// acknowledged: profile, settings, coach and sensor layout) pass untouched.
fn inject(log: &[u8], seed: u64, flip: f64, drop: f64, duplicate: f64, keep: usize) -> Faults {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut sent: Vec<&[u8]> = Vec::new();
    let (mut dropped, mut duplicated) = (0, 0);
    for (i, frame) in frames(log).into_iter().enumerate() {
        if i >= keep && rng.random_bool(drop) {
            dropped += 1;
            continue;
        }
        sent.push(frame);
        if i >= keep && rng.random_bool(duplicate) {
            duplicated += 1;
            sent.push(frame);
        }
    }
    let mut bytes = log[..posecoach_adapters::log::HEADER_LEN].to_vec();
    let mut intact = Vec::new();
    let mut damaged = 0;
    // A frame is lost if any of its bytes flips, or if the delimiter before it flips (the
    // two run together).
    let mut previous_delimiter_hit = false;
    for (i, frame) in sent.iter().enumerate() {
        let mut hit = false;
        let mut delimiter_hit = false;
        for (k, &b) in frame.iter().enumerate() {
            let mut b = b;
            if i >= keep && rng.random_bool(flip) {
                b ^= rng.random_range(1..=255u8);
                hit = true;
                delimiter_hit |= k + 1 == frame.len();
            }
            bytes.push(b);
        }
        if hit || previous_delimiter_hit {
            damaged += 1;
        } else {
            // A frame a device sends (the hostile log sends some) is dropped whole, as the
            // device drops it.
            intact.extend(decode(frame));
        }
        previous_delimiter_hit = delimiter_hit;
    }
    Faults {
        bytes,
        intact,
        damaged,
        dropped,
        duplicated,
    }
}

#[test]
fn a_damaged_link_loses_only_the_damaged_frames() {
    for log in logs() {
        let bytes = std::fs::read(&log).unwrap();
        for (seed, flip) in [(1, 0.01), (2, 0.001)] {
            let faults = inject(&bytes, seed, flip, 0.05, 0.02, 4);
            let got: Vec<Message> = posecoach_adapters::log::LogReader::new(&faults.bytes)
                .unwrap()
                .collect();
            assert!(faults.damaged > 0 && faults.dropped > 0 && faults.duplicated > 0);
            assert!(
                got == faults.intact,
                "{}: {} messages read, {} intact frames sent",
                log.display(),
                got.len(),
                faults.intact.len()
            );
        }
    }
}

#[test]
fn every_swing_survives_a_noisy_link() {
    for log in logs() {
        let name = log.file_name().unwrap().to_string_lossy().into_owned();
        let bytes = std::fs::read(&log).unwrap();
        // 1 % of bytes flipped damages a quarter of the 30-byte IMU frames but nearly every
        // 130 to 220-byte pose frame, too many to follow a swing: pose links get 0.1 %.
        let imu = sidecar(&log)["kind"] == "imu";
        let flip = if imu { 0.01 } else { 0.001 };
        let faults = inject(&bytes, 7, flip, 0.05, 0.02, 4);
        let replay = replay(&faults.bytes, None).unwrap();
        eprintln!(
            "{name}: {} frames damaged, {} dropped, {} duplicated; counters {}",
            faults.damaged, faults.dropped, faults.duplicated, replay.counters
        );
        // A duplicate whose copy was damaged is not seen as one.
        let repeats = if imu { "imu_stale" } else { "pose_duplicates" };
        let duplicates = replay.counters[repeats].as_u64().unwrap();
        assert!(duplicates > 0 && duplicates <= faults.duplicated as u64);
        check_swings(&name, &replay, &sidecar(&log), Backswing::Stated(3.0));
    }
}

#[test]
fn without_a_coach_selected_each_swing_gets_the_coach_of_its_club() {
    use posecoach_adapters::log::LogReader;
    use posecoach_adapters::session::Outcome;
    // The bundled coaches, in CoachSelect's numbering, and the club each sidecar swing was made
    // with (its source file's name).
    let clubs = ["driver", "iron"];
    for log in logs() {
        let name = log.file_name().unwrap().to_string_lossy().into_owned();
        let bytes = std::fs::read(&log).unwrap();
        let messages: Vec<Message> = LogReader::new(&bytes)
            .unwrap()
            .filter(|m| !matches!(m, Message::CoachSelect { .. }))
            .collect();
        let mut chosen = Vec::new();
        posecoach_cli::coaches::session(None, |session| {
            for m in &messages {
                session.handle(m, |outcome| {
                    if let Outcome::Scored { swing, .. } = outcome {
                        chosen.push(clubs[usize::from(swing.coach)]);
                    }
                });
            }
        })
        .unwrap();
        let made: Vec<&str> = sidecar(&log)["swings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| {
                let source = s["source"].as_str().unwrap();
                *clubs.iter().find(|c| source.contains(*c)).unwrap()
            })
            .collect();
        assert_eq!(chosen, made, "{name}");
    }
}

#[test]
fn an_imu_clock_that_wraps_mid_session_keeps_the_swings_and_their_times() {
    use posecoach_adapters::log::LogReader;
    use posecoach_adapters::session::Outcome;
    // The IMU recording moved to the end of the sensors' clock: it wraps 1.5 s in, after the
    // still period, while tracking. The adapter moves its grid to the new clock and the
    // session goes on; each swing's start is reported on the sender's clock, wrapped as it
    // is (once, its time past the end of the clock panicked).
    let log = Path::new(env!("CARGO_MANIFEST_DIR")).join("logs/imu_200hz.pclog");
    let bytes = std::fs::read(&log).unwrap();
    let messages: Vec<Message> = LogReader::new(&bytes).unwrap().collect();
    let first = messages
        .iter()
        .find_map(|m| match m {
            Message::ImuSample(s) => Some(s.t_us),
            _ => None,
        })
        .unwrap();
    let shift = (u64::MAX - 1_500_000).wrapping_sub(first);
    let wrapped: Vec<Message> = messages
        .iter()
        .cloned()
        .map(|m| match m {
            Message::ImuSample(mut s) => {
                s.t_us = s.t_us.wrapping_add(shift);
                Message::ImuSample(s)
            }
            m => m,
        })
        .collect();
    let swings = |messages: &[Message]| {
        let mut found = Vec::new();
        posecoach_cli::coaches::session(None, |session| {
            for m in messages {
                session.handle(m, |outcome| match outcome {
                    Outcome::Scored { swing, report, .. } => {
                        found.push((swing.start_us, swing.frames, report.score))
                    }
                    Outcome::Unscored { swing, error } => panic!("{swing:?}: {error:?}"),
                    _ => {}
                });
            }
        })
        .unwrap();
        found
    };
    let (clean, wrapped) = (swings(&messages), swings(&wrapped));
    assert_eq!(
        clean.len(),
        sidecar(&log)["swings"].as_array().unwrap().len()
    );
    assert_eq!(clean.len(), wrapped.len());
    for ((start, frames, score), (start_w, frames_w, score_w)) in clean.iter().zip(&wrapped) {
        // The grid's move to the new clock may take or give one frame at the 30 Hz model
        // rate, and the session times a swing by its frames since the first.
        let off_us = start_w.wrapping_sub(start.wrapping_add(shift)) as i64;
        assert!(off_us.abs() <= 33_334, "{off_us} µs off");
        assert!(frames.abs_diff(*frames_w) <= 1 && (score - score_w).abs() < 1.0);
    }
}
