//! The stack's high-water mark: cortex-m-rt's `paint-stack` fills the stack with
//! `0xCCCC_CCCC` before `main`; the deepest word no longer painted is as deep as it got.

use core::ptr::{addr_of, read_volatile};

const PAINT: u32 = 0xCCCC_CCCC;

extern "C" {
    /// Lowest address of the stack (cortex-m-rt's linker script).
    static _stack_end: u32;
    /// One past its highest address.
    static _stack_start: u32;
}

/// Bytes of stack used so far at most.
pub fn high_water() -> usize {
    let bottom = addr_of!(_stack_end) as usize;
    let top = addr_of!(_stack_start) as usize;
    let mut at = bottom;
    while at < top {
        // SAFETY: `at` lies in the stack region the linker script reserves (between
        // `_stack_end` and `_stack_start`), is 4-aligned (cortex-m-rt asserts both ends are),
        // and is plain RAM, so the read cannot fault. The scan stops at the first word ever
        // written, which lies at or below the stack pointer: every word it reads is free
        // stack that no live frame or reference covers.
        if unsafe { read_volatile(at as *const u32) } != PAINT {
            break;
        }
        at += 4;
    }
    top - at
}
