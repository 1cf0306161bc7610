//! The session's refusals: each bad message is refused with its reason and leaves the session
//! as it was.

use posecoach_adapters::io;
use posecoach_adapters::session::{BufferLens, Buffers, Coach, Outcome, Refusal, Session};
use posecoach_core::format::Format;
use posecoach_core::wire::{Config, Message, PoseFrame, StudentProfile};
use posecoach_core::Vec3;
use posecoach_tests::fixture;

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
    let skeleton = Format::H36m17.default_skeleton().unwrap();
    let mut rest = vec![Vec3::zeros(); skeleton.len()];
    skeleton.rest_positions(&mut rest);
    let scale = height / skeleton.height();
    Message::StudentProfile(StudentProfile {
        format: Format::H36m17,
        joints_mm: rest
            .iter()
            .map(|p| [p.x, p.y, p.z].map(|v| (v * scale * 1000.0).round() as i16))
            .collect(),
    })
}

#[test]
fn bad_messages_are_refused_and_change_nothing() {
    let coach = io::load(&fixture("golf_driver_60hz.csv")).unwrap();
    let coaches = [Coach {
        skeleton: &coach.skeleton,
        positions: &coach.positions,
        rate_hz: coach.rate_hz,
    }];
    let lens = BufferLens::new(17, coach.frames(), 60);
    let (mut ring, mut window, mut virtual_coach) = (
        vec![Vec3::zeros(); lens.ring],
        vec![Vec3::zeros(); lens.window],
        vec![Vec3::zeros(); lens.coach],
    );
    let (mut floats, mut bytes) = (vec![0.0; lens.floats], vec![0u8; lens.bytes]);
    let mut session = Session::new(
        &coaches,
        Buffers {
            ring: &mut ring,
            window: &mut window,
            coach: &mut virtual_coach,
            floats: &mut floats,
            bytes: &mut bytes,
        },
    );
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
        let config = Message::Config(Config {
            model_rate_hz: rate,
            band_radius: band,
            anchored: true,
        });
        let expected = if rate == 120 {
            Refusal::Buffers
        } else {
            Refusal::Config
        };
        assert_eq!(outcomes(&mut session, &config), [expected]);
        assert_eq!(session.config().model_rate_hz, 60);
    }
    assert_eq!(
        outcomes(&mut session, &Message::CoachSelect { coach: 1 }),
        [Refusal::UnknownCoach(1)]
    );
    let Message::StudentProfile(mut short) = profile(1.75) else {
        unreachable!()
    };
    short.joints_mm.truncate(10);
    assert_eq!(
        outcomes(&mut session, &Message::StudentProfile(short)),
        [Refusal::ProfileFormat(Format::H36m17)]
    );
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
