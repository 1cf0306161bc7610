//! A static library for a Cortex-M4F that uses the core and adapters without a heap.
//!
//! Rust requires a `#[global_allocator]` in any final artifact whose crate graph contains
//! `alloc`; this library defines none, so it only builds while both crates stay free of it.
#![no_std]

use posecoach_adapters::log::LogReader;
use posecoach_adapters::session::{Buffers, Session};
use posecoach_core::format::Format;
use posecoach_core::retarget::Analytic;
use posecoach_core::session::JointTallies;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;

/// Retargets the default CMU rest pose onto the default H36M skeleton; returns the output's
/// head height in millimetres, or -1 on error.
#[no_mangle]
pub extern "C" fn posecoach_no_alloc_check() -> i32 {
    let (Ok(source), Ok(target)) = (
        Skeleton::standard(Format::Cmu31),
        Skeleton::standard(Format::H36m17),
    ) else {
        return -1;
    };
    let Ok(retarget) = Analytic::new(&source, &target) else {
        return -1;
    };
    let mut frame = [Vec3::zeros(); 31];
    source.rest_positions(&mut frame);
    let mut out = [Vec3::zeros(); 17];
    match retarget.frame(&frame, &mut out) {
        Ok(()) => (out[10].y * 1000.0) as i32,
        Err(_) => -1,
    }
}

/// Replays a recorded session from `log` (the start of a `.pclog`) through the device's
/// session with no coach and buffers on the stack; returns the messages read, or -1 if the
/// bytes are not a log.
#[no_mangle]
pub extern "C" fn posecoach_no_alloc_replay(log: &[u8; 64]) -> i32 {
    let Ok(reader) = LogReader::new(log) else {
        return -1;
    };
    let (mut ring, mut coach) = ([[0i16; 3]; 8], [[0i16; 3]; 8]);
    let (mut floats, mut bytes, mut unsure) = ([0.0; 8], [0u8; 8], [0u64; 8]);
    let mut tallies = [JointTallies::EMPTY; 1];
    let mut session = Session::new(
        &[],
        Buffers {
            ring: &mut ring,
            coach: &mut coach,
            floats: &mut floats,
            bytes: &mut bytes,
            unsure: &mut unsure,
            tallies: &mut tallies,
        },
    );
    let mut read = 0;
    for message in reader {
        session.handle(&message, |_| {});
        read += 1;
    }
    read
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}
