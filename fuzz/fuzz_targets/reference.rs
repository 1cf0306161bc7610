//! Any bytes, at an aligned address, must never make the coach reference reader panic, and a
//! reference it accepts must write back to bytes that read as the same reference. Each input
//! is also tried with its CRC made right, so that mutations reach the header and payload.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_core::reference::{max_len, write, Reference};

/// `bytes` copied to a 16-byte-aligned buffer, as a blob in flash would be placed.
fn aligned(bytes: &[u8]) -> Vec<u128> {
    let mut store = vec![0u128; bytes.len().div_ceil(16)];
    bytemuck::cast_slice_mut::<u128, u8>(&mut store)[..bytes.len()].copy_from_slice(bytes);
    store
}

fuzz_target!(|data: &[u8]| {
    check(data);
    if let Some(body) = data.len().checked_sub(4) {
        let mut fixed = data.to_vec();
        let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&data[..body]);
        fixed[body..].copy_from_slice(&crc.to_le_bytes());
        check(&fixed);
    }
});

fn check(data: &[u8]) {
    let store = aligned(data);
    let bytes = &bytemuck::cast_slice::<u128, u8>(&store)[..data.len()];
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
        &mut out,
    )
    .expect("an accepted reference can be written again");
    let again = aligned(&out[..n]);
    let back = Reference::from_bytes(&bytemuck::cast_slice::<u128, u8>(&again)[..n])
        .expect("a written reference reads back");
    assert_eq!(back.skeleton(), skeleton);
    assert_eq!(back.positions(), reference.positions());
    assert_eq!(back.name(), reference.name());
}
