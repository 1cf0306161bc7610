//! Float functions that `core` lacks: square roots, and the median and selection the scoring's
//! robust spreads read.
//!
//! With std (the host build and tests) the square roots are std's, which the compiler can
//! vectorize; on an ARM FPU (the `eabihf` targets: the Cortex-M4F) the square root is the FPU's `VSQRT.F32`;
//! elsewhere libm's (about 90 instructions on a Cortex-M4F, a tenth of all the device's
//! instructions before the FPU path existed). All three are correctly rounded IEEE square
//! roots, so results are bit-identical on the host and on the device.

/// Square root.
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    imp::sqrt(x)
}

/// Euclidean length, bit-identical to nalgebra's `norm()` (the same sum of squares) but
/// through [`sqrt`], so the FPU's instruction on the device rather than libm's.
#[inline(always)]
pub fn norm(v: &crate::Vec3) -> f32 {
    sqrt(v.norm_squared())
}

/// `Σ |here[k] − (frame[k] − frame[0])|` over the joints `k` both hold, added in order from
/// 0.0, each length the square root of `dx·dx + dy·dy + dz·dz`: the summed joint distances
/// between a root-relative pose and a frame taken relative to its first joint (a DTW cell's
/// cost). On an ARM FPU one `asm!` loop of 15 instructions a joint (23.5 when compiled: the
/// loads one by one and each root through [`sqrt`]'s register moves); the same bits everywhere.
#[inline]
pub fn rooted_distance(here: &[crate::Vec3], frame: &[crate::Vec3]) -> f32 {
    imp::rooted_distance(here, frame)
}

/// The median of `values` (reordered; the upper one of an even count), 0 for none.
pub fn median(values: &mut [f32]) -> f32 {
    let mid = values.len() / 2;
    select(values, mid)
}

/// The `mid`-th smallest of `values` (reordered), 0 for none: a quickselect written out, as the
/// core library's selection brings 15 KiB of sorting code to a device's flash.
pub fn select(values: &mut [f32], mid: usize) -> f32 {
    let (mut lo, mut hi) = (0, values.len());
    while hi > lo + 1 {
        // Partition around the middle value of the range (Lomuto).
        values.swap((lo + hi) / 2, hi - 1);
        let pivot = values[hi - 1];
        let mut store = lo;
        for i in lo..hi - 1 {
            if values[i] < pivot {
                values.swap(i, store);
                store += 1;
            }
        }
        values.swap(store, hi - 1);
        match store.cmp(&mid) {
            core::cmp::Ordering::Equal => return values[mid],
            core::cmp::Ordering::Less => lo = store + 1,
            core::cmp::Ordering::Greater => hi = store,
        }
    }
    values.get(mid).copied().unwrap_or(0.0)
}

/// std's or libm's square root.
#[cfg(not(all(
    not(any(test, feature = "std")),
    target_arch = "arm",
    target_abi = "eabihf"
)))]
mod imp {
    #[inline(always)]
    pub(super) fn sqrt(x: f32) -> f32 {
        #[cfg(any(test, feature = "std"))]
        {
            x.sqrt()
        }
        #[cfg(not(any(test, feature = "std")))]
        {
            libm::sqrtf(x)
        }
    }

    #[inline(always)]
    pub(super) fn rooted_distance(here: &[crate::Vec3], frame: &[crate::Vec3]) -> f32 {
        let Some(&root) = frame.first() else {
            return 0.0;
        };
        here.iter().zip(frame).fold(0.0, |sum, (h, p)| {
            let d = h - (p - root);
            sum + sqrt(d.x * d.x + d.y * d.y + d.z * d.z)
        })
    }
}

/// The FPU's square root. `core` has no stable `f32::sqrt` and LLVM does not turn libm's
/// software square root into the instruction, hence `asm!`. Rust admits FPU registers as
/// `asm!` operands only with its `vfp2` target feature, which also claims double precision the
/// Cortex-M4F lacks, so values pass through core registers and the FPU registers used are
/// saved and restored around the instructions.
#[cfg(all(
    not(any(test, feature = "std")),
    target_arch = "arm",
    target_abi = "eabihf"
))]
#[allow(unsafe_code)]
mod imp {
    /// One root: `s0` saved in a core register and restored, five instructions in all.
    #[inline(always)]
    pub(super) fn sqrt(x: f32) -> f32 {
        let root: u32;
        // SAFETY: the instructions touch only core registers the compiler allocated for them
        // and `s0`, which they restore: no memory, no stack, no flags (VSQRT may set FPSCR's
        // sticky exception bits, which nothing here reads). Every `eabihf` ARM target has a
        // VFP unit with VMOV and VSQRT.F32.
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

    /// [`super::rooted_distance`]: the root in `s0`–`s2`, each joint's position and pose value
    /// loaded three at a time (`VLDM`), the square summed as the compiled code does (`VMUL`, then
    /// `VMLA`, which rounds the product before adding), `s0`–`s11` pushed before and popped after.
    #[inline(always)]
    pub(super) fn rooted_distance(here: &[crate::Vec3], frame: &[crate::Vec3]) -> f32 {
        let joints = here.len().min(frame.len());
        if joints == 0 {
            return 0.0;
        }
        let out: u32;
        // SAFETY: reads `joints` (at least one) whole positions of 3 floats from each of
        // `frame` and `here`, both valid for that many (`joints` is the shorter length) and
        // 4-byte aligned (`f32`s), as `VLDM` needs; the loop counts `joints` down to zero, so it
        // ends. `s0`–`s11` are pushed before use and popped after, so every FPU register the
        // compiler allocated keeps its value; the stack is used only between the push and the
        // pop, below `sp` as the ABI allows. `SUBS` sets the flags (not preserved); VSQRT may
        // set FPSCR's sticky exception bits, which nothing here reads.
        unsafe {
            core::arch::asm!(
                "vpush {{s0-s11}}",
                "vldmia {frame}, {{s0-s2}}",
                "vmov s11, {zero}",
                "2:",
                "vldmia {frame}!, {{s3-s5}}",
                "vldmia {here}!, {{s6-s8}}",
                "vsub.f32 s3, s3, s0",
                "vsub.f32 s4, s4, s1",
                "vsub.f32 s5, s5, s2",
                "vsub.f32 s6, s6, s3",
                "vsub.f32 s7, s7, s4",
                "vsub.f32 s8, s8, s5",
                "vmul.f32 s9, s6, s6",
                "vmla.f32 s9, s7, s7",
                "vmla.f32 s9, s8, s8",
                "vsqrt.f32 s9, s9",
                "vadd.f32 s11, s11, s9",
                "subs {joints}, {joints}, #1",
                "bne 2b",
                "vmov {out}, s11",
                "vpop {{s0-s11}}",
                frame = inout(reg) frame.as_ptr() => _,
                here = inout(reg) here.as_ptr() => _,
                joints = inout(reg) joints => _,
                zero = in(reg) 0u32,
                out = lateout(reg) out,
                options(readonly)
            );
        }
        f32::from_bits(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        #[test]
        fn the_median_is_the_middle_of_the_sorted_values(
            values in proptest::collection::vec(-1e3f32..1e3, 0..64),
        ) {
            let mut sorted = values.clone();
            sorted.sort_by(f32::total_cmp);
            let mut work = values.clone();
            let expected = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
            proptest::prop_assert_eq!(median(&mut work), expected);
        }

        #[test]
        fn the_kth_smallest_is_the_kth_of_the_sorted_values(
            values in proptest::collection::vec(-1e3f32..1e3, 1..64),
            at in 0.0f64..1.0,
        ) {
            let mut sorted = values.clone();
            sorted.sort_by(f32::total_cmp);
            let k = ((values.len() - 1) as f64 * at) as usize;
            let mut work = values.clone();
            proptest::prop_assert_eq!(select(&mut work, k), sorted[k]);
        }
    }
}
