//! Instructions executed, from SysTick under QEMU's `-icount shift=0`.
//!
//! With `-icount shift=0` QEMU advances virtual time 1 ns per instruction, and the mps2-an386's
//! SysTick, clocked from the 25 MHz CPU clock, counts down once per 40 ns: one tick per
//! [`INSTRUCTIONS_PER_TICK`] instructions. The 24-bit counter wraps every 671 M instructions;
//! its exception counts the wraps. (The DWT cycle counter reads 0 under QEMU.)

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use cortex_m_rt::exception;

/// Instructions per SysTick tick under `-icount shift=0` (40 ns per tick at 1 ns each).
pub const INSTRUCTIONS_PER_TICK: u64 = 40;
/// SysTick's reload value: the largest, so that wraps are rare.
const RELOAD: u32 = 0x00FF_FFFF;

static WRAPS: AtomicU32 = AtomicU32::new(0);

/// Starts SysTick counting down from [`RELOAD`] on the CPU clock, its wrap exception enabled.
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
    // The counter reads 0 until its first tick loads RELOAD, a load that is not a wrap.
    while SYST::get_current() == 0 {}
}

/// Instructions executed since [`start`], to [`INSTRUCTIONS_PER_TICK`].
pub fn now() -> u64 {
    loop {
        let wraps = WRAPS.load(Ordering::Acquire);
        let current = SYST::get_current();
        // A wrap between the two reads shows as a changed count: read again.
        if WRAPS.load(Ordering::Acquire) == wraps {
            let ticks = u64::from(wraps) * u64::from(RELOAD + 1) + u64::from(RELOAD - current);
            return ticks * INSTRUCTIONS_PER_TICK;
        }
    }
}

/// Checks the counter against a loop of known length (`delay(n)` runs `2n + 2`
/// instructions), as QEMU's timing model could change.
///
/// # Errors
/// When the count is off by more than a tick either side.
pub fn check() -> Result<(), &'static str> {
    const N: u32 = 100_000;
    let start = now();
    cortex_m::asm::delay(N);
    let counted = now() - start;
    let expected = 2 * u64::from(N) + 2;
    defmt::println!(
        "COUNTER delay({=u32}) counted {=u64} instructions, expected {=u64}",
        N,
        counted,
        expected
    );
    if counted.abs_diff(expected) > 2 * INSTRUCTIONS_PER_TICK {
        return Err("the instruction counter is off: is QEMU running with -icount shift=0?");
    }
    Ok(())
}

#[exception]
fn SysTick() {
    WRAPS.fetch_add(1, Ordering::AcqRel);
}

/// Instruction totals of one kind of work.
#[derive(Clone, Copy, Default)]
pub struct Tally {
    /// Times it ran.
    pub calls: u32,
    /// Instructions, all calls together.
    pub total: u64,
    /// Instructions of the longest call.
    pub max: u64,
    /// Bytes of stack the deepest call reached, the harness's frames included (0 where not
    /// measured).
    pub stack: usize,
}

impl Tally {
    /// Adds one call of `instructions`.
    pub fn add(&mut self, instructions: u64) {
        self.calls += 1;
        self.total += instructions;
        self.max = self.max.max(instructions);
    }

    /// Notes a call that reached `stack` bytes of stack.
    pub fn reached(&mut self, stack: usize) {
        self.stack = self.stack.max(stack);
    }

    /// Mean instructions per call.
    pub fn mean(&self) -> u64 {
        self.total / u64::from(self.calls.max(1))
    }
}
