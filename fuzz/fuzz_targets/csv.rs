//! Keypoint CSV bytes, in any encoding, must never make the reader panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_io::{csv, Hints};

fuzz_target!(|data: &[u8]| {
    let _ = csv::read_with(data, &Hints::default());
});
