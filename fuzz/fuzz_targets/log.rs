//! Any bytes, read as a recorded session (behind a valid header when they lack one), must
//! never make the log reader or the device's session panic. Each input is also tried with every
//! frame's CRC made right, so that mutations of a recorded message (positions, times, settings)
//! reach the session and its scoring rather than stopping at the frame's check.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_io::{csv, Motion};
use posecoach_adapters::log::{header, LogReader, HEADER_LEN};
use posecoach_adapters::session::{BufferLens, Coach, OwnedBuffers, Session};
use posecoach_core::config::MAX_JOINTS;
use posecoach_core::frames::Frames;
use std::sync::OnceLock;

fn coach() -> &'static Motion {
    static COACH: OnceLock<Motion> = OnceLock::new();
    COACH.get_or_init(|| {
        csv::read(include_str!("../../tests/fixtures/golf_driver_60hz.csv"))
            .expect("the bundled coach reads")
    })
}

fuzz_target!(|data: &[u8]| {
    let mut framed;
    let log = if LogReader::new(data).is_ok() {
        data
    } else {
        framed = header().to_vec();
        framed.extend_from_slice(data);
        &framed[..]
    };
    replay(log);
    replay(&with_crcs_made_right(log));
});

/// `log` with the CRC of each frame that decodes from COBS made right (other frames as they
/// are).
fn with_crcs_made_right(log: &[u8]) -> Vec<u8> {
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
    let (head, frames) = log.split_at(HEADER_LEN.min(log.len()));
    let mut out = head.to_vec();
    for frame in frames.split_inclusive(|&b| b == 0) {
        let mut payload = frame.strip_suffix(&[0]).unwrap_or(frame).to_vec();
        match cobs::decode_in_place(&mut payload) {
            Ok(n) if n > 4 => {
                let body = &payload[..n - 4];
                let mut fixed = body.to_vec();
                fixed.extend_from_slice(&crc.checksum(body).to_le_bytes());
                out.extend_from_slice(&cobs::encode_vec(&fixed));
                out.push(0);
            }
            _ => out.extend_from_slice(frame),
        }
    }
    out
}

/// Reads `log` and gives each message to a fresh session.
fn replay(log: &[u8]) {
    let Ok(reader) = LogReader::new(log) else {
        return;
    };
    let coach = coach();
    let coaches = [Coach {
        skeleton: &coach.skeleton,
        positions: Frames::metres(&coach.positions, coach.skeleton.len()),
        rate_hz: coach.rate_hz,
    }];
    let mut buffers = OwnedBuffers::new(BufferLens::new(MAX_JOINTS, coach.frames(), 120));
    let mut session = Session::new(&coaches, buffers.buffers());
    for message in reader {
        session.handle(&message, |_| {});
    }
}
