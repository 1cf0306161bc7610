//! Float functions that `core` lacks.
//!
//! With std (the host build and tests) these are std's, which the compiler can vectorize; on
//! an ARM FPU (the `eabihf` targets: the Cortex-M4F) the square root is the FPU's `VSQRT.F32`
//! (see `vsqrt`); elsewhere libm's (about 90 instructions on a Cortex-M4F, a tenth of all the
//! device's instructions before this path existed). All three are correctly rounded IEEE
//! square roots, so results are bit-identical on the host and on the device.

/// Square root.
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(any(test, feature = "std"))]
    {
        x.sqrt()
    }
    #[cfg(all(
        not(any(test, feature = "std")),
        target_arch = "arm",
        target_abi = "eabihf"
    ))]
    {
        vsqrt(x)
    }
    #[cfg(all(
        not(any(test, feature = "std")),
        not(all(target_arch = "arm", target_abi = "eabihf"))
    ))]
    {
        libm::sqrtf(x)
    }
}

/// Euclidean length, bit-identical to nalgebra's `norm()` (the same sum of squares) but
/// through [`sqrt`], so the FPU's instruction on the device rather than libm's.
#[inline(always)]
pub fn norm(v: &crate::Vec3) -> f32 {
    sqrt(v.norm_squared())
}

/// The FPU's square root. `core` has no stable `f32::sqrt` and LLVM does not turn libm's
/// software square root into the instruction, hence the one `asm!` in the crate. Rust admits
/// FPU registers as `asm!` operands only with its `vfp2` target feature, which also claims
/// double precision the Cortex-M4F lacks, so the value passes through a core register and
/// `s0` is saved and restored around the instruction: five instructions in all.
#[cfg(all(
    not(any(test, feature = "std")),
    target_arch = "arm",
    target_abi = "eabihf"
))]
#[inline(always)]
#[allow(unsafe_code)]
fn vsqrt(x: f32) -> f32 {
    let root: u32;
    // SAFETY: the instructions touch only core registers the compiler allocated for them and
    // `s0`, which they restore: no memory, no stack, no flags (VSQRT may set FPSCR's sticky
    // exception bits, which nothing here reads). Every `eabihf` ARM target has a VFP unit
    // with VMOV and VSQRT.F32.
    unsafe {
        core::arch::asm!(
            "vmov {save}, s0",
            "vmov s0, {x}",
            "vsqrt.f32 s0, s0",
            "vmov {root}, s0",
            "vmov s0, {save}",
            x = in(reg) x.to_bits(),
            root = lateout(reg) root,
            save = out(reg) _,
            options(pure, nomem, nostack, preserves_flags)
        );
    }
    f32::from_bits(root)
}
