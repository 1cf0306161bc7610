//! Wire bytes, in arbitrary chunks, must never make the frame decoder panic, and a frame it
//! accepts must encode back to a frame it accepts again.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_core::wire::{encode, Decoder, MAX_FRAME};

fuzz_target!(|data: &[u8]| {
    let mut decoder = Decoder::new();
    decoder.push_all(data, |message| {
        let mut frame = [0u8; MAX_FRAME];
        let n = encode(message, &mut frame).expect("a decoded message fits a frame");
        let mut again = Decoder::new();
        let mut back = None;
        again.push_all(&frame[..n], |m| back = Some(m.clone()));
        assert_eq!(back.as_ref(), Some(message));
    });
});
