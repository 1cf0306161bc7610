//! Any bytes must never make the float weights reader panic or allocate beyond its bounds, and a
//! file it accepts must write back to the same bytes. Each input is also tried with its CRC made
//! right, so that mutations reach the header words and the parts.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_teachfile::{checksum, decode, encode};

fn check(bytes: &[u8]) {
    if let Ok(file) = decode(bytes) {
        let again = encode(&file.header, &file.parts).expect("what reads, writes");
        assert_eq!(again, bytes, "read then written differs");
    }
}

fuzz_target!(|data: &[u8]| {
    check(data);
    if data.len() >= 4 {
        let mut fixed = data.to_vec();
        let body = fixed.len() - 4;
        let crc = checksum(&fixed[..body]);
        fixed[body..].copy_from_slice(&crc.to_le_bytes());
        check(&fixed);
    }
});
