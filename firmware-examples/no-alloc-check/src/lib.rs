//! A static library for a Cortex-M4F that uses the core and adapters without a heap.
//!
//! Rust requires a `#[global_allocator]` in any final artifact whose crate graph contains
//! `alloc`; this library defines none, so it only builds while both crates stay free of it.
#![no_std]

use posecoach_core::format::Format;
use posecoach_core::retarget::Analytic;
use posecoach_core::Vec3;

/// Retargets the default CMU rest pose onto the default H36M skeleton; returns the output's
/// head height in millimetres, or -1 on error.
#[no_mangle]
pub extern "C" fn posecoach_no_alloc_check() -> i32 {
    let (Ok(source), Ok(target)) = (
        Format::Cmu31.default_skeleton(),
        Format::H36m17.default_skeleton(),
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

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}
