//! Any bytes, read as a recorded session (behind a valid header when they lack one), must
//! never make the log reader or the device's session panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_io::{csv, Motion};
use posecoach_adapters::log::{header, LogReader};
use posecoach_adapters::session::{BufferLens, Coach, OwnedBuffers, Session};
use posecoach_core::config::MAX_JOINTS;
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
    let Ok(reader) = LogReader::new(log) else {
        return;
    };
    let coach = coach();
    let coaches = [Coach {
        skeleton: &coach.skeleton,
        positions: &coach.positions,
        rate_hz: coach.rate_hz,
    }];
    let mut buffers = OwnedBuffers::new(BufferLens::new(MAX_JOINTS, coach.frames(), 120));
    let mut session = Session::new(&coaches, buffers.buffers());
    for message in reader {
        session.handle(&message, |_| {});
    }
});
