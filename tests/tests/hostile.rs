//! The hostile recording `tests/logs/hostile_h36m_30hz.pclog`: the QEMU firmware's clean session
//! (`device_h36m_30hz.pclog`) with bursts of what a broken or hostile phone sends, while the
//! golfer walks (before the first set-up and between the swings), and a tail of IMU samples
//! whose clocks jump, wrap and restart. This test makes it and its sidecar (`POSECOACH_BLESS=1`
//! writes them) and checks that the committed files are what it makes. The replay test then
//! replays it like every log: every swing of the clean session found where it was, and exactly
//! the messages this test expects refused refused; the firmware replays it on QEMU with every
//! message within its instruction budget (docs/DEVICE.md).

use posecoach_adapters::log::{header, HEADER_LEN};
use posecoach_core::band::Band;
use posecoach_core::format::Format;
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::wire::{
    encode, Config, Counters, Decoder, ImuSample, Message, PoseFrame, SensorLayout,
    SensorPlacement, SessionReport, StudentProfile, MAX_FRAME,
};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// The clean session the bursts go into, and the hostile log's name.
const CLEAN: &str = "device_h36m_30hz";
const HOSTILE: &str = "hostile_h36m_30hz";
/// Where the bursts go, seconds into the clean session: walking, well away from a swing.
const BURSTS_S: [f64; 2] = [3.0, 13.0];
/// A clock jump the IMU adapter once walked through for ever (over `u64::MAX / 60 000` µs).
const FAR_JUMP_US: u64 = 300_000_000_000_000;
/// The IMU tail's sample period, µs (200 Hz).
const IMU_PERIOD_US: u64 = 5_000;

fn logs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("logs")
}

/// A message of the hostile log, and whether the device must refuse it (a `Nack`).
struct Sent {
    message: Message,
    refused: bool,
}

fn taken(message: Message) -> Sent {
    Sent {
        message,
        refused: false,
    }
}

fn refused(message: Message) -> Sent {
    Sent {
        message,
        refused: true,
    }
}

/// Sensor layouts no device can take: none at all, and one whose strap turns by a zero
/// quaternion.
fn broken_layouts() -> [Message; 2] {
    let zero = SensorPlacement {
        sensor: 0,
        joint: Joint::Pelvis,
        mounting_q14: [0; 4],
    };
    [
        SensorLayout {
            sensors: heapless::Vec::new(),
        },
        SensorLayout {
            sensors: [zero].into_iter().collect(),
        },
    ]
    .map(|layout| Message::SensorLayout { seq: 90, layout })
}

/// `profile` with each bone's keypoints moved as `reshape` (keypoint, position in mm) says.
fn reshaped(profile: &StudentProfile, reshape: impl Fn(usize, [i16; 3]) -> [i16; 3]) -> Message {
    let joints_mm = profile
        .joints_mm
        .iter()
        .enumerate()
        .map(|(k, &p)| reshape(k, p));
    Message::StudentProfile {
        seq: 91,
        profile: StudentProfile {
            format: profile.format,
            joints_mm: joints_mm.collect(),
        },
    }
}

/// What a broken or hostile phone sends after `last`, the clean session's latest pose frame;
/// `setup` is the session's own set-up messages (profile, settings, coach).
fn burst(last: &PoseFrame, setup: &[Message]) -> Vec<Sent> {
    let at = |seq: u32, t_us: u64| PoseFrame {
        seq,
        t_us,
        ..last.clone()
    };
    let mut far_keypoint = at(1, 5_000 + 33_333);
    far_keypoint.joints_mm[3] = [30_000, 30_000, 30_000];
    let mut short = at(2, 5_000 + 66_667);
    short.joints_mm.truncate(5);
    let cmu = Skeleton::standard(Format::Cmu31).unwrap();
    let mut other_format = at(3, 5_000 + 100_000);
    other_format.format = Format::Cmu31;
    other_format.joints_mm = (0..cmu.len()).map(|k| [k as i16, 900, 0]).collect();
    let config = |model_rate_hz, radius| Message::Config {
        seq: 97,
        config: Config {
            model_rate_hz,
            band: Band {
                radius,
                anchored: true,
            },
        },
    };
    let huge = StudentProfile {
        format: last.format,
        joints_mm: (0..last.joints_mm.len())
            .map(|k| {
                let v = if k % 2 == 0 { i16::MAX } else { i16::MIN };
                [v, v, v]
            })
            .collect(),
    };
    let flat = StudentProfile {
        format: last.format,
        joints_mm: (0..last.joints_mm.len()).map(|_| [0; 3]).collect(),
    };
    let Some(Message::StudentProfile { profile, .. }) = setup.first() else {
        panic!("the clean session starts with its profile");
    };
    // H3.6M keypoints: the left shoulder, elbow and wrist, the right knee and ankle.
    let (shoulder, elbow, wrist, knee, ankle) = (11, 12, 13, 2, 3);
    let at_mm = |k: usize| profile.joints_mm[k];
    // The left arm straight out to 1.6 m from the shoulder; both arms folded into the
    // shoulders; the right shank half as long as the left.
    let long_arm = reshaped(profile, |k, p| match k {
        k if k == elbow || k == wrist => {
            let s = at_mm(shoulder);
            let reach = if k == elbow { 800 } else { 1600 };
            [s[0].saturating_add(reach), s[1], s[2]]
        }
        _ => p,
    });
    let no_arms = reshaped(profile, |k, p| match k {
        12 | 13 => at_mm(11),
        15 | 16 => at_mm(14),
        _ => p,
    });
    let half_shank = reshaped(profile, |k, p| match k {
        k if k == ankle => {
            let (kn, an) = (at_mm(knee), p);
            [0, 1, 2].map(|i| kn[i] + (an[i] - kn[i]) / 2)
        }
        _ => p,
    });
    let one_sensor = Message::SensorLayout {
        seq: 92,
        layout: SensorLayout {
            sensors: [SensorPlacement {
                sensor: 0,
                joint: Joint::Pelvis,
                mounting_q14: [16384, 0, 0, 0],
            }]
            .into_iter()
            .collect(),
        },
    };
    let resent: Vec<Sent> = setup.iter().cloned().map(taken).collect();
    let [empty, zero] = broken_layouts();
    let mut out = vec![
        // A gap just under the stream's break: the grid filled up to it in one message.
        taken(Message::PoseFrame(at(last.seq + 1, last.t_us + 240_000))),
        // The clock leaps ahead, leaps to 0.1 s before the end of u64, reaches it, and wraps
        // round to a restart; the sequence number wraps too.
        taken(Message::PoseFrame(at(
            last.seq + 2,
            last.t_us + FAR_JUMP_US,
        ))),
        taken(Message::PoseFrame(at(last.seq + 3, u64::MAX - 100_000))),
        taken(Message::PoseFrame(at(last.seq + 4, u64::MAX))),
        taken(Message::PoseFrame(at(u32::MAX, 1_000))),
        taken(Message::PoseFrame(at(0, 5_000))),
        // The same frame again, then one keypoint 30 m away.
        taken(Message::PoseFrame(at(0, 5_000))),
        taken(Message::PoseFrame(far_keypoint)),
        // Frames the stream cannot take: too few keypoints, another format mid-stream.
        refused(Message::PoseFrame(short)),
        refused(Message::PoseFrame(other_format)),
        // What a device sends, sent to it: dropped as malformed (a device built without the
        // core's `phone` feature cannot decode the report at all), answered with nothing.
        taken(Message::Status(Counters::default())),
        taken(Message::SessionReport(SessionReport {
            swings: 1,
            used: 1,
            coach: 0,
            metrics: Default::default(),
            tendencies: Default::default(),
            spatial: Default::default(),
            set_aside: Default::default(),
            open: None,
        })),
        // The range session asked for: an Ack and its report, nothing changed.
        taken(Message::SessionRequest {
            seq: 98,
            reset: false,
        }),
        // Settings outside the device's range, a coach it does not have.
        refused(config(0, 10)),
        refused(config(u16::MAX, 10)),
        refused(config(30, 0)),
        refused(Message::CoachSelect {
            seq: 93,
            coach: u16::MAX,
        }),
        // Bodies no golfer has: every joint 32 m out, every joint at one point, a left arm of
        // 1.6 m, no arms, one shank half the other.
        refused(Message::StudentProfile {
            seq: 94,
            profile: huge,
        }),
        refused(Message::StudentProfile {
            seq: 95,
            profile: flat,
        }),
        refused(long_arm),
        refused(no_arms),
        refused(half_shank),
        // Layouts no sensor set has.
        refused(empty),
        refused(zero),
        // An IMU sample in a pose session.
        refused(Message::ImuSample(ImuSample {
            sensor: 0,
            t_us: 5_000 + 133_333,
            accel_mg: [0, 1000, 0],
            gyro_ddps: [0; 3],
            mag_dut: None,
        })),
    ];
    // The set-up in force sent again (a phone that missed its acknowledgements): taken, and
    // nothing restarts.
    out.extend(resent);
    // A layout that fits: the session takes IMU samples and refuses pose frames, until the
    // profile sent again returns it to pose frames (sent twice, as a phone that missed the
    // first acknowledgement does: the second changes nothing).
    out.push(taken(one_sensor));
    out.push(refused(Message::PoseFrame(at(7, 5_000 + 166_667))));
    out.push(taken(setup[0].clone()));
    out.push(taken(setup[0].clone()));
    out
}

/// After the session: the golfer's six IMUs declared, a still moment, then every sensor's
/// clock leaps ahead, restarts, leaps to the end of `u64` and wraps round, and a sensor that
/// was never declared speaks. A sample after a leap is refused (the step is too long to
/// integrate; the next one is used); a restarted or wrapped clock restarts the stream.
fn imu_tail(last_t_us: u64) -> Vec<Sent> {
    let skeleton = Skeleton::standard(Format::H36m17).unwrap();
    let layout = posecoach_cli::synth_imu::default_layout(&skeleton);
    let sensors = layout.sensors.len() as u8;
    let mut out = vec![taken(Message::SensorLayout { seq: 98, layout })];
    let sample = |sensor, t_us| {
        Message::ImuSample(ImuSample {
            sensor,
            t_us,
            accel_mg: [0, 1000, 0],
            gyro_ddps: [0; 3],
            mag_dut: None,
        })
    };
    // `samples` samples of every sensor from `from_us`, the first of each refused if `leap`.
    let run = |from_us: u64, samples: u64, leap: bool, out: &mut Vec<Sent>| {
        for i in 0..samples {
            for sensor in 0..sensors {
                let message = sample(sensor, from_us.wrapping_add(i * IMU_PERIOD_US));
                out.push(if leap && i == 0 {
                    refused(message)
                } else {
                    taken(message)
                });
            }
        }
    };
    let start = last_t_us + 1_000_000;
    run(start, 40, false, &mut out);
    run(start + FAR_JUMP_US, 20, true, &mut out);
    run(1_000, 20, false, &mut out);
    run(u64::MAX - 10 * IMU_PERIOD_US, 20, true, &mut out);
    out.push(refused(sample(sensors + 1, 20 * IMU_PERIOD_US)));
    out
}

/// The hostile log's bytes, and how many of its messages the device must refuse.
fn make() -> (Vec<u8>, usize) {
    let clean = std::fs::read(logs().join(format!("{CLEAN}.pclog"))).unwrap();
    let mut decoder = Decoder::new();
    let mut messages = Vec::new();
    for &b in &clean[HEADER_LEN..] {
        decoder.push(b, |m| messages.push(m.clone()));
    }
    let setup: Vec<Message> = messages
        .iter()
        .take_while(|m| m.is_setup())
        .cloned()
        .collect();
    let Some(Message::CoachSelect { coach, .. }) = setup.last() else {
        panic!("the clean session's set-up ends with its coach");
    };
    let other_coach = Message::CoachSelect {
        seq: 96,
        coach: 1 - coach,
    };
    // Layouts before any profile: refused, and the session still takes its set-up.
    let mut sent: Vec<Sent> = broken_layouts().into_iter().map(refused).collect();
    let mut bursts = BURSTS_S.iter().map(|s| (s * 1e6) as u64).peekable();
    let mut tops = posecoach_tests::swing_tops_us(CLEAN).into_iter().peekable();
    let mut last: Option<PoseFrame> = None;
    for message in messages {
        if let Message::PoseFrame(frame) = &message {
            if let (Some(&at), Some(previous)) = (bursts.peek(), &last) {
                if frame.t_us >= at {
                    sent.extend(burst(previous, &setup));
                    bursts.next();
                }
            }
            // At the top of each swing: the coach in force selected again (taken, the swing
            // goes on) and the other coach (refused as busy: the swing is not lost).
            if tops.next_if(|&top| frame.t_us >= top).is_some() {
                sent.push(taken(setup[setup.len() - 1].clone()));
                sent.push(refused(other_coach.clone()));
            }
            last = Some(frame.clone());
        }
        sent.push(taken(message));
    }
    assert!(bursts.next().is_none(), "every burst placed");
    assert!(tops.next().is_none(), "every swing's top reached");
    sent.extend(imu_tail(last.unwrap().t_us));
    let mut bytes = header().to_vec();
    let mut frame = [0u8; MAX_FRAME];
    for s in &sent {
        let n = encode(&s.message, &mut frame).unwrap();
        bytes.extend_from_slice(&frame[..n]);
    }
    (bytes, sent.iter().filter(|s| s.refused).count())
}

/// The clean session's sidecar with this log's name and the refusals it must get.
fn sidecar(refused: usize) -> String {
    let text = std::fs::read_to_string(logs().join(format!("{CLEAN}.swings.json"))).unwrap();
    let mut sidecar: Value = serde_json::from_str(&text).unwrap();
    sidecar["log"] = Value::from(format!("{HOSTILE}.pclog"));
    sidecar["hostile"] = Value::from(format!(
        "{CLEAN}.pclog behind two broken sensor layouts, with bursts of hostile messages at \
         {BURSTS_S:?} s, the coach selected again and another one at each swing's top, and a \
         tail of IMU samples whose clocks jump, wrap and restart (tests/tests/hostile.rs)"
    ));
    sidecar["refused"] = Value::from(refused);
    format!("{sidecar:#}\n")
}

#[test]
fn the_hostile_log_is_what_this_test_makes() {
    let (bytes, refused) = make();
    let (log, side) = (
        logs().join(format!("{HOSTILE}.pclog")),
        logs().join(format!("{HOSTILE}.swings.json")),
    );
    if std::env::var_os("POSECOACH_BLESS").is_some() {
        std::fs::write(&log, &bytes).unwrap();
        std::fs::write(&side, sidecar(refused)).unwrap();
    }
    let committed = std::fs::read(&log)
        .unwrap_or_else(|_| panic!("{}: missing; POSECOACH_BLESS=1 writes it", log.display()));
    assert!(
        committed == bytes,
        "{} differs from what this test makes (POSECOACH_BLESS=1 rewrites it)",
        log.display()
    );
    assert_eq!(std::fs::read_to_string(&side).unwrap(), sidecar(refused));
}
