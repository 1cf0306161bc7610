//! Keypoint JSON bytes must never make the reader panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_io::{json, Hints};

fuzz_target!(|data: &[u8]| {
    let _ = json::read_with(data, &Hints::default());
});
