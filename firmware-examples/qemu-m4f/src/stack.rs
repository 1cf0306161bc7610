//! The stack's high-water mark: cortex-m-rt's `paint-stack` fills the stack with
//! `0xCCCC_CCCC` before `main`, and [`repaint`] fills what lies below the stack pointer again;
//! the deepest word no longer painted is as deep as it got.

use core::ptr::{addr_of, read_volatile, write_volatile};

const PAINT: u32 = 0xCCCC_CCCC;
/// Bytes below the stack pointer that [`repaint`] leaves alone: its own frame and the
/// SysTick exception's, which may be stacked while it paints.
const MARGIN: usize = 256;
/// The deepest stack measured, bytes: [`repaint`] paints and [`high_water`] scans only this
/// much below the stack's top (QEMU's stack is the board's 4 MiB), and a depth beyond it reads
/// as `SPAN`.
const SPAN: usize = 128 * 1024;

extern "C" {
    /// Lowest address of the stack (cortex-m-rt's linker script).
    static _stack_end: u32;
    /// One past its highest address.
    static _stack_start: u32;
}

/// Bytes of stack used at most since reset or the last [`repaint`] (at most [`SPAN`]).
pub fn high_water() -> usize {
    let top = addr_of!(_stack_start) as usize;
    let mut at = floor();
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

/// Paints the free stack again, from [`SPAN`] below its top to [`MARGIN`] below the stack
/// pointer, so that the next [`high_water`] measures only what runs after this call.
#[inline(never)]
pub fn repaint() {
    let below = (cortex_m::register::msp::read() as usize - MARGIN) & !3;
    let mut at = floor();
    while at < below {
        // SAFETY: `at` is 4-aligned and lies inside the stack region, below MARGIN bytes
        // under the stack pointer: free stack that no live frame or reference covers (this
        // function's frame and an exception stacked meanwhile lie within the margin, and an
        // exception's frame is dead once it returns). Nothing reads it but `high_water`.
        unsafe { write_volatile(at as *mut u32, PAINT) };
        at += 4;
    }
}

/// Bytes of stack in use where it is called: its caller's frames.
#[inline(always)]
pub fn in_use() -> usize {
    (addr_of!(_stack_start) as usize).saturating_sub(cortex_m::register::msp::read() as usize)
}

/// The lowest address measured: [`SPAN`] below the stack's top, or its bottom.
fn floor() -> usize {
    let bottom = addr_of!(_stack_end) as usize;
    let top = addr_of!(_stack_start) as usize;
    top.saturating_sub(SPAN).max(bottom)
}
