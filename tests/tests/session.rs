//! The session's refusals: each bad message is refused with its reason and leaves the session
//! as it was.

use posecoach_adapters::session::{
    BufferLens, Buffers, Coach, Outcome, OwnedBuffers, Refusal, Session, MAX_FRAMES_PER_MESSAGE,
};
use posecoach_core::band::Band;
use posecoach_core::format::Format;
use posecoach_core::frames::Frames;
use posecoach_core::plausible::Implausible;
use posecoach_core::score::Phase;
use posecoach_core::session::{JointTallies, Quantity};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::wire::{Config, ImuSample, Message, NackReason, PoseFrame, StudentProfile};
use posecoach_core::Vec3;
use posecoach_io as io;
use posecoach_tests::fixture;
use proptest::prelude::*;

fn outcomes(session: &mut Session<'_>, message: &Message) -> Vec<Refusal> {
    let mut refused = Vec::new();
    session.handle(message, |o| {
        if let Outcome::Refused(r) = o {
            refused.push(r);
        }
    });
    refused
}

fn profile(height: f32) -> Message {
    let skeleton = Skeleton::standard(Format::H36m17).unwrap();
    let mut rest = vec![Vec3::zeros(); skeleton.len()];
    skeleton.rest_positions(&mut rest);
    let scale = height / skeleton.height();
    Message::StudentProfile {
        seq: 0,
        profile: StudentProfile {
            format: Format::H36m17,
            joints_mm: rest
                .iter()
                .map(|p| [p.x, p.y, p.z].map(|v| (v * scale * 1000.0).round() as i16))
                .collect(),
        },
    }
}

#[test]
fn bad_messages_are_refused_and_change_nothing() {
    let coach = io::load(&fixture("golf_driver_60hz.csv")).unwrap();
    let coaches = [Coach {
        skeleton: &coach.skeleton,
        positions: Frames::metres(&coach.positions, coach.skeleton.len()),
        rate_hz: coach.rate_hz,
    }];
    let mut buffers = OwnedBuffers::new(BufferLens::new(17, coach.frames(), 60));
    let mut session = Session::new(&coaches, buffers.buffers());
    let pose = Message::PoseFrame(PoseFrame {
        seq: 0,
        t_us: 0,
        format: Format::H36m17,
        joints_mm: std::iter::repeat_n([0, 900, 0], 17).collect(),
        confidence: heapless::Vec::new(),
    });
    assert_eq!(outcomes(&mut session, &pose), [Refusal::NoProfile]);
    assert_eq!(outcomes(&mut session, &profile(1.75)), []);
    let height = session.student().unwrap().height();
    assert!((height - 1.75).abs() < 0.01, "{height}");

    // A rate the buffers (sized for 60 Hz) cannot hold, a zero band, a rate out of range.
    for (rate, band) in [(120, 10), (60, 0), (5, 10)] {
        let config = Message::Config {
            seq: 0,
            config: Config {
                model_rate_hz: rate,
                band: Band {
                    radius: band,
                    anchored: true,
                },
            },
        };
        let expected = if rate == 120 {
            Refusal::Buffers
        } else {
            Refusal::Config
        };
        assert_eq!(outcomes(&mut session, &config), [expected]);
        assert_eq!(session.config().model_rate_hz, 60);
    }
    assert_eq!(
        outcomes(&mut session, &Message::CoachSelect { seq: 0, coach: 1 }),
        [Refusal::UnknownCoach(1)]
    );
    let Message::StudentProfile {
        profile: mut short, ..
    } = profile(1.75)
    else {
        unreachable!()
    };
    short.joints_mm.truncate(10);
    assert_eq!(
        outcomes(
            &mut session,
            &Message::StudentProfile {
                seq: 0,
                profile: short
            }
        ),
        [Refusal::ProfileFormat(Format::H36m17)]
    );
    assert!((session.student().unwrap().height() - height).abs() < 1e-6);
    // Bodies no person has: a child of 30 cm, a giant of 3 m, one wrist 32 m from its elbow.
    for tiny_or_huge in [0.3, 3.0] {
        assert!(matches!(
            outcomes(&mut session, &profile(tiny_or_huge))[..],
            [Refusal::Implausible(Implausible::Stature(_))]
        ));
    }
    let Message::StudentProfile {
        profile: mut stretched,
        ..
    } = profile(1.75)
    else {
        unreachable!()
    };
    stretched.joints_mm[13] = [32_000, -32_000, 32_000];
    assert!(matches!(
        outcomes(
            &mut session,
            &Message::StudentProfile {
                seq: 0,
                profile: stretched
            }
        )[..],
        [Refusal::Implausible(Implausible::Bone { joint: 13, .. })]
    ));
    assert!((session.student().unwrap().height() - height).abs() < 1e-6);
    // A T-pose sent y-down (a pose estimator's image axis), or lying along the ground.
    let turned = |turn: fn([i16; 3]) -> [i16; 3]| {
        let Message::StudentProfile { mut profile, .. } = profile(1.75) else {
            unreachable!()
        };
        profile.joints_mm.iter_mut().for_each(|p| *p = turn(*p));
        Message::StudentProfile { seq: 0, profile }
    };
    for body in [
        turned(|[x, y, z]| [x, -y, -z]),
        turned(|[x, y, z]| [x, z, -y]),
    ] {
        assert_eq!(outcomes(&mut session, &body), [Refusal::NotUpright]);
    }
    assert!((session.student().unwrap().height() - height).abs() < 1e-6);
    // Still working: a well-formed pose frame is taken.
    assert_eq!(outcomes(&mut session, &pose), []);
    let mut coco = pose.clone();
    if let Message::PoseFrame(f) = &mut coco {
        f.seq = 1;
        f.t_us = 1000;
        f.format = Format::Coco17;
    }
    assert!(matches!(
        outcomes(&mut session, &coco)[..],
        [Refusal::Stream(_)]
    ));
}

/// Pose frames at 30 Hz of `motion` (on a skeleton of `format`, whose keypoints are its joints).
fn pose_frames(motion: &io::Motion, format: Format) -> Vec<Message> {
    let swing = motion.resampled(30.0).unwrap();
    (0..swing.frames())
        .map(|f| {
            Message::PoseFrame(PoseFrame {
                seq: f as u32,
                t_us: f as u64 * 33_333,
                format,
                joints_mm: swing
                    .frame(f)
                    .iter()
                    .map(|p| [p.x, p.y, p.z].map(|v| (v * 1000.0).round() as i16))
                    .collect(),
                confidence: heapless::Vec::new(),
            })
        })
        .collect()
}

/// Replays `messages`; returns each swing's score and its events' frames, and the refusals.
fn scores(coach: &io::Motion, messages: &[Message]) -> (Vec<(f32, Vec<usize>)>, Vec<Refusal>) {
    let coaches = [Coach {
        skeleton: &coach.skeleton,
        positions: Frames::metres(&coach.positions, coach.skeleton.len()),
        rate_hz: coach.rate_hz,
    }];
    let mut buffers = OwnedBuffers::new(BufferLens::new(31, coach.frames(), 60));
    let mut session = Session::new(&coaches, buffers.buffers());
    let (mut found, mut refused) = (Vec::new(), Vec::new());
    for m in messages {
        session.handle(m, |o| match o {
            Outcome::Scored { report, .. } => found.push((
                report.score,
                report.student_events.iter().map(|(_, f)| f).collect(),
            )),
            Outcome::Refused(r) => refused.push(r),
            Outcome::Accepted | Outcome::Session { .. } => {}
            other => panic!("{other:?}"),
        });
    }
    (found, refused)
}

/// The driver coach, an H3.6M profile of a 1.75 m student, and the student's swing of the
/// driver (keeping the grip and planted feet) as two phones send it: one in H3.6M keypoints,
/// the other in CMU-31 keypoints of the same motion, each with still set-up before and after.
fn driver_streams() -> (io::Motion, Message, Vec<Message>, Vec<Message>) {
    let coach = io::load(&fixture("golf_driver_60hz.csv")).unwrap();
    let student = io::load(&fixture("h36m17_tpose.csv")).unwrap();
    let mut on_h36m = coach.retarget_analytic(&student).unwrap();
    on_h36m.keep_contacts(&coach).unwrap();
    let h36m = Skeleton::standard(Format::H36m17).unwrap();
    let h36m = io::Motion {
        skeleton: h36m.clone(),
        names: vec![String::new(); h36m.len()],
        rate_hz: 0.0,
        missing: vec![false; h36m.len()],
        positions: {
            let mut rest = vec![Vec3::zeros(); h36m.len()];
            h36m.rest_positions(&mut rest);
            let scale = student.skeleton.height() / h36m.height();
            rest.iter().map(|p| p * scale).collect()
        },
    };
    let on_h36m = on_h36m.retarget_analytic(&h36m).unwrap();
    let cmu = Skeleton::standard(Format::Cmu31).unwrap();
    let cmu = io::Motion {
        skeleton: cmu.clone(),
        names: vec![String::new(); cmu.len()],
        rate_hz: 0.0,
        missing: vec![false; cmu.len()],
        positions: {
            let mut rest = vec![Vec3::zeros(); cmu.len()];
            cmu.rest_positions(&mut rest);
            let scale = student.skeleton.leg_length() / cmu.leg_length();
            rest.iter().map(|p| p * scale).collect()
        },
    };
    let mut on_cmu = coach.retarget_analytic(&cmu).unwrap();
    on_cmu.keep_contacts(&coach).unwrap();
    let profile = Message::StudentProfile {
        seq: 0,
        profile: StudentProfile {
            format: Format::H36m17,
            joints_mm: h36m
                .positions
                .iter()
                .map(|p| [p.x, p.y, p.z].map(|v| (v * 1000.0).round() as i16))
                .collect(),
        },
    };
    // Still set-up before and after, so the detector sees a whole swing.
    let padded = |m: &io::Motion| {
        let (first, last) = (m.frame(0).to_vec(), m.frame(m.frames() - 1).to_vec());
        let mut positions = first.repeat(60);
        positions.extend_from_slice(&m.positions);
        positions.extend(last.repeat(90));
        io::Motion {
            missing: vec![false; positions.len()],
            positions,
            ..m.clone()
        }
    };
    let h36m = pose_frames(&padded(&on_h36m), Format::H36m17);
    let cmu = pose_frames(&padded(&on_cmu), Format::Cmu31);
    (coach, profile, h36m, cmu)
}

#[test]
fn a_stream_in_another_format_is_mapped_onto_the_profile() {
    let (coach, profile, h36m, cmu) = driver_streams();
    let (same, refused) = scores(
        &coach,
        &[std::slice::from_ref(&profile), &h36m[..]].concat(),
    );
    assert_eq!(refused, []);
    let (mapped, refused) = scores(&coach, &[&[profile], &cmu[..]].concat());
    assert_eq!(refused, []);
    assert_eq!((same.len(), mapped.len()), (1, 1));
    eprintln!("H3.6M stream {:?}\nCMU-31 stream {:?}", same[0], mapped[0]);
    // The events are the same and the score nearly so: CMU-31's head end, mapped onto the
    // H3.6M head top, sits 11 cm higher at the finish, the one deviation the score counts
    // (it was 1 point with the score from the alignment's mean distance, 9 now).
    assert!(mapped[0].0 > 85.0 && (mapped[0].0 - same[0].0).abs() < 10.0);
    for (a, b) in same[0].1.iter().zip(&mapped[0].1) {
        assert!(a.abs_diff(*b) <= 1);
    }
}

#[test]
fn a_refused_first_frame_does_not_fix_the_streams_format() {
    // Before the stream has taken a frame, a frame it refuses (a format without keypoints, a
    // wrong keypoint count) must leave the next frames in any format to be read as if it had
    // not come: once, such a frame fixed the session's fit, and every later frame was dropped
    // without a word.
    let (coach, profile, h36m, cmu) = driver_streams();
    for frames in [h36m, cmu] {
        let (clean, refused) = scores(
            &coach,
            &[std::slice::from_ref(&profile), &frames[..]].concat(),
        );
        assert_eq!((clean.len(), refused.len()), (1, 0));
        let Message::PoseFrame(first) = &frames[0] else {
            unreachable!()
        };
        let canonical = PoseFrame {
            format: Format::Canonical,
            ..first.clone()
        };
        let mut short = PoseFrame {
            format: Format::Coco17,
            ..first.clone()
        };
        short.joints_mm.truncate(16);
        for bad in [canonical, short] {
            let format = bad.format;
            let messages = [&[profile.clone(), Message::PoseFrame(bad)], &frames[..]].concat();
            let (found, refused) = scores(&coach, &messages);
            assert!(
                matches!(refused[..], [Refusal::Stream(_)]),
                "{format:?}: {refused:?}"
            );
            assert_eq!(found, clean, "after a refused {format:?} frame");
        }
    }
}

/// With int8 weights the session asks for a ring that also holds the network's input (`f32`
/// metres from a 4-byte boundary) and scratch, counted in the ring's 6-byte millimetre
/// positions, and works at the network's rate and, with the analytic retargeter, at others.
#[test]
fn a_network_borrows_the_ring_at_its_rate() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../weights/distilled-int8.pcw");
    let network = posecoach_cli::coaches::Network::load(&path).unwrap();
    let weights = network.weights().unwrap();
    let a = weights.architecture();
    let coach = io::load(&fixture("golf_driver_60hz.csv")).unwrap();
    let coaches = [Coach {
        skeleton: &coach.skeleton,
        positions: Frames::metres(&coach.positions, coach.skeleton.len()),
        rate_hz: coach.rate_hz,
    }];
    let (n, frames) = (coach.skeleton.len(), coaches[0].frames_at(30));
    let plain = BufferLens::new(17, frames, 30);
    let need = |joints, coach_joints, frames: usize| {
        let scratch = posecoach_core::network::scratch_len(a, coach_joints, joints);
        (frames * coach_joints * 12 + scratch.next_multiple_of(12) + 4usize).div_ceil(6)
    };
    let lens = plain.with_network(a, 17, n, frames);
    assert_eq!(lens.ring, plain.ring.max(need(17, n, frames)));
    let big = plain.with_network(a, 40, 40, 256);
    assert_eq!(big.ring, need(40, 40, 256));
    assert!(big.ring > plain.ring);
    for rate in [30, 60] {
        let config = Config {
            model_rate_hz: rate,
            band: Band::DEFAULT,
        };
        let frames = coaches[0].frames_at(rate);
        let lens = BufferLens::new(17, frames, rate).with_network(a, 17, n, frames);
        let mut buffers = OwnedBuffers::new(lens);
        let mut session = Session::with_config(&coaches, buffers.buffers(), config)
            .unwrap()
            .with_network(&weights);
        assert_eq!(outcomes(&mut session, &profile(1.75)), [], "{rate} Hz");
        // A ring starting 2 bytes past a 4-byte boundary: the network's room starts at the
        // next one, within the length asked for.
        let mut ring = vec![[0i16; 3]; lens.ring + 1];
        let (mut coach, mut floats) = (vec![[0i16; 3]; lens.coach], vec![0.0; lens.floats]);
        let (mut bytes, mut unsure) = (vec![0u8; lens.bytes], vec![0u64; lens.unsure]);
        let mut tallies = vec![JointTallies::EMPTY; lens.tallies];
        let ring = &mut ring[1..];
        assert_eq!(ring.as_ptr() as usize % 4, 2);
        let buffers = Buffers {
            ring,
            coach: &mut coach,
            floats: &mut floats,
            bytes: &mut bytes,
            unsure: &mut unsure,
            tallies: &mut tallies,
        };
        let mut session = Session::with_config(&coaches, buffers, config)
            .unwrap()
            .with_network(&weights);
        assert_eq!(
            outcomes(&mut session, &profile(1.75)),
            [],
            "{rate} Hz, off a word"
        );
    }
}

/// One message of a hostile phone, its time as a step from the last message's (any `u64`: far
/// jumps, and wrapping round to a restarted clock).
#[derive(Clone, Debug)]
enum Hostile {
    Pose {
        seq: u32,
        step: u64,
        noise: Vec<[i16; 3]>,
        confidence: Vec<u8>,
    },
    Imu {
        sensor: u8,
        step: u64,
        accel: [i16; 3],
        gyro: [i16; 3],
        mag: Option<[i16; 3]>,
    },
    Layout,
    Config {
        rate: u16,
        radius: u16,
        anchored: bool,
    },
    Coach(u16),
    Profile(f32),
}

fn step() -> impl Strategy<Value = u64> {
    prop_oneof![8 => 0u64..100_000, 1 => any::<u64>(), 1 => Just(0)]
}

fn hostile() -> impl Strategy<Value = Hostile> {
    let pose = (
        any::<u32>(),
        step(),
        prop::collection::vec(any::<[i16; 3]>().prop_map(|v| v.map(|c| c % 300)), 17),
        prop::option::of(prop::collection::vec(any::<u8>(), 17))
            .prop_map(Option::unwrap_or_default),
    )
        .prop_map(|(seq, step, noise, confidence)| Hostile::Pose {
            seq,
            step,
            noise,
            confidence,
        });
    let imu = (
        0u8..8,
        step(),
        any::<[i16; 3]>(),
        any::<[i16; 3]>(),
        any::<Option<[i16; 3]>>(),
    )
        .prop_map(|(sensor, step, accel, gyro, mag)| Hostile::Imu {
            sensor,
            step,
            accel,
            gyro,
            mag,
        });
    prop_oneof![
        6 => pose,
        6 => imu,
        1 => Just(Hostile::Layout),
        1 => (any::<u16>(), any::<u16>(), any::<bool>())
            .prop_map(|(rate, radius, anchored)| Hostile::Config { rate, radius, anchored }),
        1 => any::<u16>().prop_map(Hostile::Coach),
        1 => (0.2f32..3.0).prop_map(Hostile::Profile),
    ]
}

/// The recorded session the QEMU firmware replays (an H3.6M phone at 30 Hz, coach 0
/// selected, two swings), its messages.
fn device_log() -> Vec<Message> {
    let logs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("logs");
    let bytes = std::fs::read(logs.join("device_h36m_30hz.pclog")).unwrap();
    posecoach_adapters::log::LogReader::new(&bytes)
        .unwrap()
        .collect()
}

/// What the bundled device answers to each of `messages` (its `Ack`s, `Nack`s and reports, as
/// messages), and each scored swing's number and score.
fn device_replies(messages: &[Message]) -> (Vec<Message>, Vec<(u32, f32)>) {
    let (mut replies, mut swings) = (Vec::new(), Vec::new());
    posecoach_cli::coaches::session(None, |session| {
        for m in messages {
            session.handle(m, |o| {
                if let Outcome::Scored { swing, report, .. } = &o {
                    swings.push((swing.number, report.score));
                }
                replies.extend(o.reply(m));
            });
        }
    })
    .unwrap();
    (replies, swings)
}

#[test]
fn every_set_up_message_is_acknowledged_with_its_sequence_number() {
    let messages = device_log();
    let setups: Vec<u32> = messages
        .iter()
        .filter(|m| m.is_setup())
        .filter_map(Message::seq)
        .collect();
    assert_eq!(setups.len(), 3, "profile, settings, coach");
    let (replies, swings) = device_replies(&messages);
    let acks: Vec<u32> = replies
        .iter()
        .filter_map(|r| match r {
            Message::Ack { seq } => Some(*seq),
            _ => None,
        })
        .collect();
    assert_eq!(acks, setups);
    assert_eq!(swings.len(), 2);
}

#[test]
fn a_set_up_sent_again_mid_swing_loses_nothing_and_a_change_waits_for_the_swing_to_end() {
    let clean = device_log();
    let (_, expected) = device_replies(&clean);
    let setup: Vec<Message> = clean.iter().take_while(|m| m.is_setup()).cloned().collect();
    let other_coach = Message::CoachSelect { seq: 77, coach: 1 };
    // The whole set-up again every 10 frames (a third of a second), as a phone that missed its
    // acknowledgements sends it, and another coach at each swing's top (its sidecar's time).
    let tops = posecoach_tests::swing_tops_us("device_h36m_30hz");
    assert_eq!(tops.len(), 2);
    let mut tops = tops.into_iter().peekable();
    let mut sent = Vec::new();
    for (n, m) in clean.iter().enumerate() {
        if n > setup.len() && n % 10 == 0 {
            sent.extend(setup.iter().cloned());
        }
        if let Message::PoseFrame(f) = m {
            if tops.next_if(|&top| f.t_us >= top).is_some() {
                sent.push(other_coach.clone());
            }
        }
        sent.push(m.clone());
    }
    assert!(tops.next().is_none());
    let (replies, swings) = device_replies(&sent);
    // The same set-up is taken and changes nothing: the same swings, scored the same; the
    // other coach is refused as busy, each time.
    let resent = sent
        .iter()
        .filter(|m| m.is_setup() && **m != other_coach)
        .count();
    let acks = replies
        .iter()
        .filter(|r| matches!(r, Message::Ack { .. }))
        .count();
    assert_eq!(acks, resent);
    let nacks: Vec<&Message> = replies
        .iter()
        .filter(|r| matches!(r, Message::Nack { .. }))
        .collect();
    let busy = Message::Nack {
        seq: 77,
        reason: NackReason::Busy,
    };
    assert_eq!(nacks, [&busy, &busy]);
    assert_eq!(swings, expected);
}

#[test]
fn no_sensor_layout_wedges_the_session() {
    let clean = device_log();
    let (_, expected) = device_replies(&clean);
    let layout = |mounting_q14: [i16; 4], sensors: usize| Message::SensorLayout {
        seq: 50,
        layout: posecoach_core::wire::SensorLayout {
            sensors: (0..sensors as u8)
                .map(|sensor| posecoach_core::wire::SensorPlacement {
                    sensor,
                    joint: posecoach_core::joint::Joint::Pelvis,
                    mounting_q14,
                })
                .collect(),
        },
    };
    // Before any profile: an empty layout and a zero turn are refused as unexpected, and the
    // session then scores exactly what it scores without them.
    let mut before = vec![
        layout([0; 4], 0),
        layout([0; 4], 1),
        layout([16384, 0, 0, 0], 1),
    ];
    before.extend(clean.iter().cloned());
    let (replies, swings) = device_replies(&before);
    assert!(replies[..3].iter().all(|r| matches!(
        r,
        Message::Nack {
            seq: 50,
            reason: NackReason::Unexpected
        }
    )));
    assert_eq!(swings, expected);
    // A layout that fits, taken before the swings: pose frames are refused as unexpected until
    // the profile comes again, and the swings after it are scored.
    let setup = clean.iter().take_while(|m| m.is_setup()).count();
    let mut switched = clean[..setup].to_vec();
    switched.push(layout([16384, 0, 0, 0], 1));
    switched.extend(clean[setup..setup + 20].iter().cloned());
    switched.push(clean[0].clone());
    switched.extend(clean[setup + 20..].iter().cloned());
    let (replies, swings) = device_replies(&switched);
    let unexpected = replies
        .iter()
        .filter(|r| {
            matches!(
                r,
                Message::Nack {
                    reason: NackReason::Unexpected,
                    ..
                }
            )
        })
        .count();
    assert_eq!(unexpected, 20);
    assert_eq!(swings.len(), expected.len());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Whatever a phone sends (times that jump, wrap or stand still, sequence numbers anywhere,
    /// settings and layouts at any moment), no message gives swing detection more than
    /// `MAX_FRAMES_PER_MESSAGE` frames: each message's work stays bounded.
    #[test]
    fn no_message_makes_unbounded_work(messages in prop::collection::vec(hostile(), 1..300)) {
        let coach = io::load(&fixture("golf_driver_60hz.csv")).unwrap();
        let coaches = [Coach {
            skeleton: &coach.skeleton,
            positions: Frames::metres(&coach.positions, coach.skeleton.len()),
            rate_hz: coach.rate_hz,
        }];
        let mut buffers = OwnedBuffers::new(BufferLens::new(17, coach.frames(), 60));
        let mut session = Session::new(&coaches, buffers.buffers());
        let Message::StudentProfile { profile: tpose, .. } = profile(1.75) else { unreachable!() };
        session.handle(&profile(1.75), |_| {});
        let layout = posecoach_cli::synth_imu::default_layout(
            &Skeleton::standard(Format::H36m17).unwrap(),
        );
        let mut clock = 0u64;
        for m in messages {
            let message = match m {
                Hostile::Pose { seq, step, noise, confidence } => {
                    clock = clock.wrapping_add(step);
                    Message::PoseFrame(PoseFrame {
                        seq,
                        t_us: clock,
                        format: Format::H36m17,
                        joints_mm: tpose
                            .joints_mm
                            .iter()
                            .zip(&noise)
                            .map(|(p, n)| [0, 1, 2].map(|i| p[i].saturating_add(n[i])))
                            .collect(),
                        confidence: confidence.into_iter().collect(),
                    })
                }
                Hostile::Imu { sensor, step, accel, gyro, mag } => {
                    clock = clock.wrapping_add(step);
                    Message::ImuSample(ImuSample {
                        sensor,
                        t_us: clock,
                        accel_mg: accel,
                        gyro_ddps: gyro,
                        mag_dut: mag,
                    })
                }
                Hostile::Layout => Message::SensorLayout { seq: 0, layout: layout.clone() },
                Hostile::Config { rate, radius, anchored } => Message::Config {
                    seq: 0,
                    config: Config { model_rate_hz: rate, band: Band { radius, anchored } },
                },
                Hostile::Coach(coach) => Message::CoachSelect { seq: 0, coach },
                Hostile::Profile(height) => profile(height),
            };
            let before = session.frames();
            session.handle(&message, |_| {});
            let given = session.frames() - before;
            prop_assert!(given <= MAX_FRAMES_PER_MESSAGE, "{given} frames from {message:?}");
        }
    }
}

#[test]
fn the_range_session_counts_every_swing_and_starts_afresh_with_a_new_coach_or_profile() {
    let messages = device_log();
    let profile = messages
        .iter()
        .find(|m| matches!(m, Message::StudentProfile { .. }))
        .cloned()
        .unwrap();
    posecoach_cli::coaches::session(None, |session| {
        let mut scored = Vec::new();
        for m in &messages {
            session.handle(m, |o| {
                if let Outcome::Scored { report, .. } = o {
                    scored.push(report.tempo[0].ratio);
                }
            });
        }
        let tendencies = session.tendencies();
        assert_eq!(scored.len(), 2);
        assert_eq!((tendencies.swings(), tendencies.used()), (2, 2));
        // Its backswing is the swings' geometric mean (two values are never pulled in).
        let backswing = tendencies
            .estimate(Quantity::Tempo(Phase::Backswing))
            .unwrap();
        let mean = (scored.iter().map(|r| r.ln()).sum::<f32>() / 2.0).exp();
        assert!((backswing.value.exp() - mean).abs() < 1e-3, "{backswing:?}");
        // Another coach starts a new range session; so does another profile.
        let select = Message::CoachSelect { seq: 90, coach: 1 };
        session.handle(&select, |_| {});
        assert_eq!(session.tendencies().swings(), 0);
        for m in &messages {
            session.handle(m, |_| {});
        }
        assert!(session.tendencies().swings() > 0);
        let Message::StudentProfile { profile: p, .. } = profile else {
            unreachable!()
        };
        let mut taller = p.clone();
        for j in taller.joints_mm.iter_mut() {
            j[1] = (f32::from(j[1]) * 1.05) as i16;
        }
        let message = Message::StudentProfile {
            seq: 91,
            profile: taller,
        };
        session.handle(&message, |_| {});
        assert_eq!(session.tendencies().swings(), 0);
    })
    .unwrap();
}

#[test]
fn a_session_report_follows_every_swing_report_and_answers_a_request() {
    let messages = device_log();
    let (replies, swings) = device_replies(&messages);
    // Each swing report is followed at once by the range session's, its swings counted.
    let mut told = 0;
    for pair in replies.windows(2) {
        if let [Message::SwingReport(swing), next] = pair {
            told += 1;
            let Message::SessionReport(session) = next else {
                panic!("{next:?} after swing {}", swing.swing);
            };
            assert_eq!((session.swings, session.coach), (told, swing.coach));
        }
    }
    assert_eq!(usize::from(told), swings.len());
    posecoach_cli::coaches::session(None, |session| {
        for m in &messages {
            session.handle(m, |_| {});
        }
        let ask = |reset| Message::SessionRequest { seq: 7, reset };
        let answer = |session: &mut Session<'_>, m: &Message| {
            let mut got = Vec::new();
            session.handle(m, |o| got.extend(o.reply(m)));
            got
        };
        // Asked: the last report again, and nothing changes.
        let last = replies
            .iter()
            .rev()
            .find(|m| matches!(m, Message::SessionReport(_)))
            .cloned()
            .unwrap();
        assert_eq!(
            answer(session, &ask(false)),
            [Message::Ack { seq: 7 }, last.clone()]
        );
        assert_eq!(answer(session, &ask(false))[1], last);
        // Reset: a new session, empty.
        let got = answer(session, &ask(true));
        let Message::SessionReport(empty) = &got[1] else {
            panic!("{got:?}");
        };
        assert_eq!(got[0], Message::Ack { seq: 7 });
        assert_eq!((empty.swings, empty.used, empty.coach), (0, 0, u16::MAX));
        assert!(empty.metrics.is_empty() && empty.tendencies.is_empty() && empty.open.is_none());
        assert_eq!(session.tendencies().swings(), 0);
    })
    .unwrap();
}

#[test]
fn a_refused_set_up_keeps_the_range_session() {
    let coach = io::load(&fixture("golf_driver_60hz.csv")).unwrap();
    let coaches = [Coach {
        skeleton: &coach.skeleton,
        positions: Frames::metres(&coach.positions, coach.skeleton.len()),
        rate_hz: coach.rate_hz,
    }];
    // Buffers for 60 Hz: the device log's 30 Hz fits, 120 Hz does not.
    let mut buffers = OwnedBuffers::new(BufferLens::new(17, coach.frames(), 60));
    let mut session = Session::new(&coaches, buffers.buffers());
    for m in &device_log() {
        session.handle(m, |_| {});
    }
    let swings = session.tendencies().swings();
    assert!(swings > 0);
    let config = Message::Config {
        seq: 90,
        config: Config {
            model_rate_hz: 120,
            band: Band::DEFAULT,
        },
    };
    assert_eq!(outcomes(&mut session, &config), [Refusal::Buffers]);
    assert_eq!(session.tendencies().swings(), swings);
}
