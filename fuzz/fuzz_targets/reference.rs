//! Any bytes, at an aligned address, must never make the coach reference reader panic, and a
//! reference it accepts must write back to bytes that read as the same reference. Each input
//! is also tried with its CRC made right, so that mutations reach the header and payload.
#![no_main]

mod blob_input;

use blob_input::{aligned, view, with_and_without_crc};
use libfuzzer_sys::fuzz_target;
use posecoach_core::reference::{max_len, write, Reference};

fuzz_target!(|data: &[u8]| with_and_without_crc(data, check));

fn check(data: &[u8]) {
    let store = aligned(data);
    let bytes = view(&store, data.len());
    let Ok(reference) = Reference::from_bytes(bytes) else {
        return;
    };
    let skeleton = reference.skeleton();
    let mut out = vec![0u8; max_len(skeleton.len(), reference.frames())];
    let n = write(
        reference.name(),
        skeleton,
        reference.rate_hz(),
        reference.positions(),
        reference.units(),
        &mut out,
    )
    .expect("an accepted reference can be written again");
    let again = aligned(&out[..n]);
    let back = Reference::from_bytes(view(&again, n)).expect("a written reference reads back");
    assert_eq!(back.skeleton(), skeleton);
    assert_eq!(back.units(), reference.units());
    let bits = |p: posecoach_core::Vec3| p.map(f32::to_bits);
    assert!(back
        .positions()
        .iter()
        .map(bits)
        .eq(reference.positions().iter().map(bits)));
    assert_eq!(back.name(), reference.name());
}
