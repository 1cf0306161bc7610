//! The wire protocol's bytes are pinned: one frame of every message kind, compared with a
//! committed stream (`fixtures/wire_messages.bin`, which also seeds the decoder's fuzz target).

use posecoach_core::band::Band;
use posecoach_core::format::Format;
use posecoach_core::joint::Joint;
use posecoach_core::wire::{
    self, Config, Counters, Decoder, ImuSample, Message, NackReason, PoseFrame, SensorLayout,
    SensorPlacement, SessionReport, StudentProfile, SwingReport, WireCheck, WireDeviation, WireGap,
    WireMetric, WireSetAside, WireTendency, MAX_FRAME,
};
use posecoach_tests::fixture;

fn every_message() -> Vec<Message> {
    let joints = [[12, 950, -3], [-88, 903, 0], [88, 903, 0]]
        .into_iter()
        .collect::<heapless::Vec<_, 33>>();
    vec![
        Message::PoseFrame(PoseFrame {
            seq: 1,
            t_us: 33_333,
            format: Format::H36m17,
            joints_mm: joints.clone(),
            confidence: [200, 180, 255].into_iter().collect(),
        }),
        Message::ImuSample(ImuSample {
            sensor: 2,
            t_us: 5_000,
            accel_mg: [0, -1000, 12],
            gyro_ddps: [150, -20000, 3],
            mag_dut: Some([200, 0, -400]),
        }),
        Message::StudentProfile {
            seq: 11,
            profile: StudentProfile {
                format: Format::Coco17,
                joints_mm: joints,
            },
        },
        Message::CoachSelect { seq: 12, coach: 4 },
        Message::Config {
            seq: 13,
            config: Config {
                model_rate_hz: 60,
                band: Band::DEFAULT,
            },
        },
        Message::SwingReport(SwingReport {
            swing: 3,
            coach: 1,
            score_centi: 7745,
            student_positions: [8, 34, 49, 64, 73, 77, 80, 84, 90, 99],
            coach_positions: [9, 34, 50, 65, 72, 76, 79, 83, 88, 94],
            phases_ms: [[933, 933], [267, 233], [317, 250]],
            verdicts: [0, 1, 1],
            deviations: [WireDeviation {
                position: 6,
                joint: 16,
                direction: 5,
                offset_mm: [4, -20, -159],
                uncertainty_mm: 12,
            }]
            .into_iter()
            .collect(),
            checks: [WireCheck {
                check: 0,
                student: 782,
                coach: 950,
                uncertainty: 34,
            }]
            .into_iter()
            .collect(),
            gaps: [WireGap {
                gap: 0,
                student_ms: -17,
                coach_ms: 33,
                uncertainty_ms: 9,
            }]
            .into_iter()
            .collect(),
        }),
        Message::Status(Counters {
            frames_ok: 10,
            crc_errors: 1,
            malformed: 2,
            versions: 1,
            overflows: 0,
            drops: 3,
        }),
        Message::Ack { seq: 9 },
        Message::Nack {
            seq: 10,
            reason: NackReason::Busy,
        },
        Message::Nack {
            seq: 0,
            reason: NackReason::Version,
        },
        Message::SensorLayout {
            seq: 14,
            layout: SensorLayout {
                sensors: [
                    (0, Joint::Pelvis, [16384, 0, 0, 0]),
                    (1, Joint::LeftWrist, [11585, 0, 11585, 0]),
                ]
                .into_iter()
                .map(|(sensor, joint, mounting_q14)| SensorPlacement {
                    sensor,
                    joint,
                    mounting_q14,
                })
                .collect(),
            },
        },
        Message::SessionReport(SessionReport {
            swings: 10,
            used: 9,
            coach: 1,
            metrics: [
                WireMetric {
                    quantity: 0,
                    swings: 9,
                    above: 8,
                    below: 0,
                    verdict: 1,
                    student: 1194,
                    coach: 933,
                    uncertainty: 37,
                    spread: 52,
                },
                WireMetric {
                    quantity: 4,
                    swings: 9,
                    above: 0,
                    below: 3,
                    verdict: 0,
                    student: 861,
                    coach: 950,
                    uncertainty: 41,
                    spread: 60,
                },
            ]
            .into_iter()
            .collect(),
            tendencies: [
                WireTendency {
                    item: 0,
                    swings: 9,
                    past: 8,
                },
                WireTendency {
                    item: 15,
                    swings: 9,
                    past: 7,
                },
            ]
            .into_iter()
            .collect(),
            spatial: [WireDeviation {
                position: 3,
                joint: 13,
                direction: 4,
                offset_mm: [12, -30, 96],
                uncertainty_mm: 18,
            }]
            .into_iter()
            .collect(),
            set_aside: [WireSetAside {
                swing: 4,
                unlike: 3,
                worst: 1,
                z_tenths: -52,
            }]
            .into_iter()
            .collect(),
            open: None,
        }),
        Message::SessionRequest {
            seq: 15,
            reset: true,
        },
    ]
}

#[test]
fn the_bytes_of_every_message_are_pinned() {
    let mut stream = Vec::new();
    for m in every_message() {
        let mut frame = [0u8; MAX_FRAME];
        let n = wire::encode(&m, &mut frame).unwrap();
        stream.extend_from_slice(&frame[..n]);
    }
    let golden = fixture("wire_messages.bin");
    if std::env::var_os("POSECOACH_BLESS").is_some() {
        std::fs::write(&golden, &stream).unwrap();
    }
    assert_eq!(
        stream,
        std::fs::read(&golden).unwrap(),
        "protocol bytes changed: bump wire::VERSION, then POSECOACH_BLESS=1"
    );
    let mut decoder = Decoder::phone();
    let mut got = Vec::new();
    decoder.push_all(&stream, |m| got.push(m.clone()));
    assert_eq!(got, every_message());
}
