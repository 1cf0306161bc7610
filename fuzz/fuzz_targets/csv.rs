//! Keypoint CSV text must never make the reader panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_io::csv;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = csv::read(text);
    }
});
