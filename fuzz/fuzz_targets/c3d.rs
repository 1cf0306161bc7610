//! C3D bytes: parsing and, when it parses, golf joint centres must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_io::{c3d::C3d, golf, Motion};

fuzz_target!(|data: &[u8]| {
    if let Ok(c3d) = C3d::parse(data) {
        if let Ok(centres) = golf::joint_centres(&c3d) {
            let _ = Motion::from_golf(&centres);
        }
    }
});
