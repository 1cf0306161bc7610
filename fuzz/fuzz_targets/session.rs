//! Any bytes, read as a phone's messages with hostile times (each a step of any size from the
//! last: jumps, a clock that wraps or restarts, repeats), now and then another keypoint format
//! or a wrong keypoint count, layouts broken or sent before any profile, set-ups sent again and
//! coaches selected again, must never make the device's session panic or give swing detection
//! more than `MAX_FRAMES_PER_MESSAGE` frames for one message, nor leave it unable to take a
//! valid set-up once no swing is under way.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_adapters::session::{
    BufferLens, Coach, Outcome, OwnedBuffers, Session, MAX_FRAMES_PER_MESSAGE,
};
use posecoach_core::band::Band;
use posecoach_core::format::Format;
use posecoach_core::frames::Frames;
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::wire::{
    Config, ImuSample, Message, PoseFrame, SensorLayout, SensorPlacement, StudentProfile,
};
use posecoach_core::Vec3;
use posecoach_io::{csv, Motion};
use std::sync::OnceLock;

fn coach() -> &'static Motion {
    static COACH: OnceLock<Motion> = OnceLock::new();
    COACH.get_or_init(|| {
        csv::read(include_str!("../../tests/fixtures/golf_driver_60hz.csv"))
            .expect("the bundled coach reads")
    })
}

/// The standard H3.6M T-pose, in millimetres.
fn tpose() -> Vec<[i16; 3]> {
    let skeleton = Skeleton::standard(Format::H36m17).expect("a built-in format");
    let mut rest = vec![Vec3::zeros(); skeleton.len()];
    skeleton.rest_positions(&mut rest);
    rest.iter()
        .map(|p| [p.x, p.y, p.z].map(|v| (v * 1000.0).round() as i16))
        .collect()
}

/// Reads fields off the front of the fuzzer's bytes (zeros once they run out).
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        let n = N.min(self.0.len());
        out[..n].copy_from_slice(&self.0[..n]);
        self.0 = &self.0[n..];
        out
    }

    fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }

    fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }

    fn i16x3(&mut self) -> [i16; 3] {
        [0; 3].map(|_| i16::from_le_bytes(self.take()))
    }

    /// A time step: small mostly, any size when the selector's top bit is set.
    fn step(&mut self) -> u64 {
        match self.u8() {
            s if s & 0x80 != 0 => u64::from_le_bytes(self.take()),
            s => u64::from(s) * 4_000,
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let coach = coach();
    let coaches = [Coach {
        skeleton: &coach.skeleton,
        positions: Frames::metres(&coach.positions, coach.skeleton.len()),
        rate_hz: coach.rate_hz,
    }];
    let mut buffers = OwnedBuffers::new(BufferLens::new(17, coach.frames(), 120));
    let mut session = Session::new(&coaches, buffers.buffers());
    let tpose = tpose();
    let profile = Message::StudentProfile {
        seq: 0,
        profile: StudentProfile {
            format: Format::H36m17,
            joints_mm: tpose.iter().copied().collect(),
        },
    };
    let mut bytes = Bytes(data);
    // Mostly a session set up first; otherwise whatever comes first (a layout before any
    // profile among it).
    if bytes.u8() & 3 != 0 {
        session.handle(&profile, |_| {});
    }
    let joints = [
        Joint::Pelvis,
        Joint::Thorax,
        Joint::LeftElbow,
        Joint::RightElbow,
        Joint::LeftWrist,
        Joint::RightWrist,
    ];
    let layout = Message::SensorLayout {
        seq: 1,
        layout: SensorLayout {
            sensors: (0u8..)
                .zip(joints)
                .map(|(sensor, joint)| SensorPlacement {
                    sensor,
                    joint,
                    mounting_q14: [16384, 0, 0, 0],
                })
                .collect(),
        },
    };
    let settings = |model_rate_hz, radius, anchored| Message::Config {
        seq: 2,
        config: Config {
            model_rate_hz,
            band: Band { radius, anchored },
        },
    };
    let mut clock = 0u64;
    while !bytes.0.is_empty() {
        let message = match bytes.u8() % 8 {
            0..=2 => {
                clock = clock.wrapping_add(bytes.step());
                let seq = u32::from(bytes.u16());
                let wobble = bytes.i16x3();
                // Mostly H3.6M; otherwise any format, its keypoints the T-pose's over again,
                // one short when the selector is odd.
                let (format, keypoints) = match bytes.u8() {
                    f if f < 192 => (Format::H36m17, tpose.len()),
                    f => {
                        // Every wire format: the built-in ones, and two without keypoints.
                        let built_in = Format::BUILT_IN;
                        let format = match usize::from(f) % (built_in.len() + 2) {
                            i if i < built_in.len() => built_in[i],
                            i if i == built_in.len() => Format::Canonical,
                            _ => Format::Custom,
                        };
                        let n = format.keypoints().len();
                        (format, n.saturating_sub(usize::from(f & 1)))
                    }
                };
                Message::PoseFrame(PoseFrame {
                    seq,
                    t_us: clock,
                    format,
                    joints_mm: tpose
                        .iter()
                        .cycle()
                        .take(keypoints)
                        .map(|p| [0, 1, 2].map(|i| p[i].saturating_add(wobble[i] % 400)))
                        .collect(),
                    confidence: heapless::Vec::new(),
                })
            }
            3..=5 => {
                clock = clock.wrapping_add(bytes.step());
                let sensor = bytes.u8() % 8;
                let (accel_mg, gyro_ddps) = (bytes.i16x3(), bytes.i16x3());
                let mag_dut = (bytes.u8() & 1 == 1).then(|| bytes.i16x3());
                Message::ImuSample(ImuSample {
                    sensor,
                    t_us: clock,
                    accel_mg,
                    gyro_ddps,
                    mag_dut,
                })
            }
            // The layout that fits, or one cut short, or with a strap's turn zeroed.
            6 => match bytes.u8() % 4 {
                0 => {
                    let mut broken = layout.clone();
                    if let Message::SensorLayout { layout, .. } = &mut broken {
                        let keep = usize::from(bytes.u8()) % (layout.sensors.len() + 1);
                        layout.sensors.truncate(keep);
                        if let Some(s) = layout.sensors.last_mut() {
                            s.mounting_q14 = [0; 4];
                        }
                    }
                    broken
                }
                _ => layout.clone(),
            },
            // Settings (any, or the ones in force again), a coach (any, or the first two
            // again and again), the profile again.
            _ => match bytes.u8() % 5 {
                0 => settings(bytes.u16(), bytes.u16(), bytes.u8() & 1 == 1),
                1 => settings(60, 10, true),
                2 => Message::CoachSelect {
                    seq: 3,
                    coach: bytes.u16(),
                },
                3 => Message::CoachSelect {
                    seq: 3,
                    coach: u16::from(bytes.u8() & 1),
                },
                _ => profile.clone(),
            },
        };
        let before = session.frames();
        session.handle(&message, |_| {});
        let given = session.frames() - before;
        assert!(given <= MAX_FRAMES_PER_MESSAGE, "{given} frames from {message:?}");
    }
    // Whatever came before, no message left the session unable to take a valid set-up: once
    // no swing is under way, the device's settings and the profile are acknowledged, and the
    // session takes pose frames again.
    if !session.swing_under_way() {
        for message in [settings(60, 10, true), profile] {
            let mut acknowledged = false;
            session.handle(&message, |o| acknowledged |= matches!(o, Outcome::Accepted));
            assert!(acknowledged, "{message:?} not taken");
        }
    }
});
