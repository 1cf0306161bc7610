//! BVH text: parsing and, when it parses, import as a motion must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_io::{bvh::Bvh, Motion};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(bvh) = Bvh::parse(text) {
        let _ = Motion::from_bvh(bvh, None);
    }
});
