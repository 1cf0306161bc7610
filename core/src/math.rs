//! Float functions that `core` lacks: square roots, a turn from its scaled axis, a dot product
//! and scaled sums, and the median and selection the scoring's robust spreads read.
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

/// `√(a² + b²)` through [`sqrt`]: `libm`'s `hypotf` guards against overflow in double
/// precision, software on a Cortex-M4F, where every length here is far from `f32`'s range.
#[inline(always)]
pub fn hypot(a: f32, b: f32) -> f32 {
    sqrt(a * a + b * b)
}

/// Euclidean length, bit-identical to nalgebra's `norm()` (the same sum of squares) but
/// through [`sqrt`], so the FPU's instruction on the device rather than libm's.
#[inline(always)]
pub fn norm(v: &crate::Vec3) -> f32 {
    sqrt(v.norm_squared())
}

/// `v` over its length when that exceeds `min`: nalgebra's `Unit::try_new`, to the bit (the
/// same sum of squares, compared with `min²`, and each coordinate divided by the root), with
/// the root through [`sqrt`].
#[inline]
pub fn unit(v: crate::Vec3, min: f32) -> Option<crate::Vec3> {
    let squared = v.norm_squared();
    (squared > min * min).then(|| v / sqrt(squared))
}

/// `q` over its norm as a rotation: nalgebra's `UnitQuaternion::new_normalize`, to the bit,
/// with the root through [`sqrt`].
#[inline]
pub fn rotation(q: nalgebra::Quaternion<f32>) -> crate::Quat {
    let norm = sqrt(q.coords.norm_squared());
    crate::Quat::new_unchecked(nalgebra::Quaternion::from(q.coords / norm))
}

/// The sine and cosine of `x` (radians), in single precision: `x` less the nearest multiple of
/// π/2 (in two parts, the first of eight significant bits so that its multiples are exact up
/// to 2¹⁶ of them), then the Taylor series of both on ±π/4 to the term under half an ulp:
/// within 2 ulp of the true values, and 2·10⁻¹¹ more per radian of |x| (the second part's
/// rounding), as the property test checks up to 10⁴. `libm`'s `sincosf` works in double
/// precision, software on a Cortex-M4F (about 2 000 instructions a call), and with its
/// reduction of any argument it is 6.8 KiB of the device's flash; this is some 40
/// instructions.
pub fn sin_cos(x: f32) -> (f32, f32) {
    const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
    // π/2 = HI + LO: HI = 201/128 exactly.
    const PIO2_HI: f32 = 1.570_312_5;
    const PIO2_LO: f32 = 4.838_268e-4;
    let k = libm::floorf(x * FRAC_2_PI + 0.5);
    let r = (x - k * PIO2_HI) - k * PIO2_LO;
    let r2 = r * r;
    // sin r = r − r³/3! + … − r¹¹/11!, cos r = 1 − r²/2! + … − r¹²/12! (Horner).
    let sin = r
        * (1.0
            - r2 / 6.0
                * (1.0 - r2 / 20.0 * (1.0 - r2 / 42.0 * (1.0 - r2 / 72.0 * (1.0 - r2 / 110.0)))));
    let cos = 1.0
        - r2 / 2.0
            * (1.0
                - r2 / 12.0
                    * (1.0
                        - r2 / 30.0 * (1.0 - r2 / 56.0 * (1.0 - r2 / 90.0 * (1.0 - r2 / 132.0)))));
    match (k as i64).rem_euclid(4) {
        0 => (sin, cos),
        1 => (cos, -sin),
        2 => (-sin, -cos),
        _ => (-cos, sin),
    }
}

/// The cube root of `x` (0 for `x` ≤ 0 or NaN), in single precision: a first guess from the
/// exponent's bits over three, then two steps of Halley's method (the error cubed each step),
/// within 2 ulp of the true root for normal `x`. `libm`'s `cbrtf` works in double precision,
/// software on a Cortex-M4F.
pub fn cbrt(x: f32) -> f32 {
    if x.is_nan() || x <= 0.0 {
        return 0.0;
    }
    if x == f32::INFINITY {
        return x;
    }
    let mut y = f32::from_bits(x.to_bits() / 3 + 709_921_077);
    for _ in 0..2 {
        let cube = y * y * y;
        y *= (cube + 2.0 * x) / (2.0 * cube + x);
    }
    y
}

/// Below this half angle (radians) [`turn`] takes its sine and cosine from their series.
pub const SERIES_HALF_ANGLE: f32 = 0.25;

/// The rotation about `axis_angle`'s direction by its length (radians): nalgebra's
/// `UnitQuaternion::from_scaled_axis` to an ulp or two (the quaternion exponential of half of
/// it, the identity below `f32::EPSILON`). Under [`SERIES_HALF_ANGLE`] (a gyro's step at
/// 200 Hz, up to 5 700 °/s) the cosine and `sin(x)/x` of the half angle `x` are their Taylor
/// series to `x⁶`, whose next terms are under 4·10⁻¹⁰, in single precision with no root.
/// Larger turns take the root through [`sqrt`] and [`sin_cos`].
#[inline]
pub fn turn(axis_angle: crate::Vec3) -> crate::Quat {
    let half = axis_angle / 2.0;
    let squared = half.norm_squared();
    if squared <= f32::EPSILON * f32::EPSILON {
        return crate::Quat::identity();
    }
    let (cos, sinc) = if squared < SERIES_HALF_ANGLE * SERIES_HALF_ANGLE {
        let s = squared;
        (
            1.0 - s / 2.0 * (1.0 - s / 12.0 * (1.0 - s / 30.0)),
            1.0 - s / 6.0 * (1.0 - s / 20.0 * (1.0 - s / 42.0)),
        )
    } else {
        let n = sqrt(squared);
        let (sin, cos) = sin_cos(n);
        (cos, sin / n)
    };
    crate::Quat::new_unchecked(nalgebra::Quaternion::from_parts(cos, half * sinc))
}

/// The rotation a fraction `f` of the way from `a` to `b` (the shortest arc; `f` clamped to
/// 0..=1).
pub fn interpolate(a: crate::Quat, b: crate::Quat, f: f32) -> crate::Quat {
    a * turn((a.inverse() * b).scaled_axis() * f.clamp(0.0, 1.0))
}

/// The costs of `here` against consecutive frames of `here.len()` joints: for each whole frame
/// `f` of `frames`, as many as `out` holds, `out[f] = scale · Σ |here[k] − (f[k] − f[0])|`, the
/// sum over the joints added in order from 0.0, each length the square root of
/// `dx·dx + dy·dy + dz·dz`: the summed joint distances between a root-relative pose and each
/// frame taken relative to its first joint (a row of DTW cells). Nothing for an empty `here`.
/// On an ARM FPU one `asm!` loop for the whole row, 14 instructions a joint and 11 a frame
/// (23.5 a joint when compiled: the loads one by one and each root through [`sqrt`]'s register
/// moves); the same bits everywhere.
#[inline]
pub fn rooted_distances(here: &[crate::Vec3], frames: &[crate::Vec3], scale: f32, out: &mut [f32]) {
    imp::rooted_distances(here, frames, scale, out);
}

/// A normal spread's standard deviation over its median absolute deviation: `1 / Φ⁻¹(3/4)`.
pub const MAD_SIGMA: f32 = 1.4826;

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

/// `start + Σ a[i] · b[i]` over the length of the shorter, each product added in order from
/// `start`: the bits of a plain fold. Compiled four products to a step; on an ARM FPU one `asm!`
/// loop, four values of each loaded at once (`VLDM`) and each product added with `VMLA` (which
/// rounds the product before adding, as the compiled code does): 8 instructions for four
/// products against about 17.
#[inline]
pub fn dot_from(start: f32, a: &[f32], b: &[f32]) -> f32 {
    imp::dot_from(start, a, b)
}

/// `sums[i] += k · x[i]` over the length of the shorter (each product rounded, then added). On
/// an ARM FPU one `asm!` loop, four of each loaded and stored at once, one `VMLA` a value: the
/// same bits.
#[inline]
pub fn add_scaled(sums: &mut [f32], k: f32, x: &[f32]) {
    imp::add_scaled(sums, k, x);
}

/// `sums[i] = sums[i] · k + x[i]` over the length of the shorter (the product rounded, then
/// added), as [`add_scaled`] is run.
#[inline]
pub fn scale_then_add(sums: &mut [f32], k: f32, x: &[f32]) {
    imp::scale_then_add(sums, k, x);
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
    pub(super) fn rooted_distances(
        here: &[crate::Vec3],
        frames: &[crate::Vec3],
        scale: f32,
        out: &mut [f32],
    ) {
        if here.is_empty() {
            return;
        }
        for (o, frame) in out.iter_mut().zip(frames.chunks_exact(here.len())) {
            let root = frame[0];
            let sum = here.iter().zip(frame).fold(0.0, |sum, (h, p)| {
                let d = h - (p - root);
                sum + sqrt(d.x * d.x + d.y * d.y + d.z * d.z)
            });
            *o = sum * scale;
        }
    }

    #[inline(never)]
    pub(super) fn dot_from(start: f32, a: &[f32], b: &[f32]) -> f32 {
        let n = a.len().min(b.len());
        let ((a4, a1), (b4, b1)) = (a[..n].as_chunks::<4>(), b[..n].as_chunks::<4>());
        let sum = a4.iter().zip(b4).fold(start, |s, (a, b)| {
            s + a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
        });
        a1.iter().zip(b1).fold(sum, |s, (a, b)| s + a * b)
    }

    #[inline]
    pub(super) fn add_scaled(sums: &mut [f32], k: f32, x: &[f32]) {
        for (s, x) in sums.iter_mut().zip(x) {
            *s += k * x;
        }
    }

    #[inline]
    pub(super) fn scale_then_add(sums: &mut [f32], k: f32, x: &[f32]) {
        for (s, x) in sums.iter_mut().zip(x) {
            *s = *s * k + x;
        }
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

    /// One joint of [`rooted_distances`]: its position in the frame and its pose value loaded,
    /// the difference of the two root-relative positions squared, rooted and added to `s11`.
    macro_rules! joint {
        () => {
            concat!(
                "vldmia {frame}!, {{s3-s5}}\n",
                "vldmia {here_at}!, {{s6-s8}}\n",
                "vsub.f32 s3, s3, s0\n",
                "vsub.f32 s4, s4, s1\n",
                "vsub.f32 s5, s5, s2\n",
                "vsub.f32 s6, s6, s3\n",
                "vsub.f32 s7, s7, s4\n",
                "vsub.f32 s8, s8, s5\n",
                "vmul.f32 s9, s6, s6\n",
                "vmla.f32 s9, s7, s7\n",
                "vmla.f32 s9, s8, s8\n",
                "vsqrt.f32 s9, s9\n",
                "vadd.f32 s11, s11, s9",
            )
        };
    }

    /// [`super::rooted_distances`]: for each frame its root in `s0`–`s2` and the sum in `s11`;
    /// each joint's position and pose value loaded three at a time (`VLDM`), the square summed as
    /// the compiled code does (`VMUL`, then `VMLA`, which rounds the product before adding);
    /// the scale in `s12`, zero in `s13`; `s0`–`s13` pushed before and popped after.
    #[inline(always)]
    pub(super) fn rooted_distances(
        here: &[crate::Vec3],
        frames: &[crate::Vec3],
        scale: f32,
        out: &mut [f32],
    ) {
        let joints = here.len();
        let cells = frames.len().checked_div(joints).unwrap_or(0).min(out.len());
        if cells == 0 {
            return;
        }
        // SAFETY: `joints` and `cells` are at least one. The loops read `cells` frames of
        // `joints` whole positions (3 floats each) from `frames` and, for each, `joints`
        // positions from `here` (one joint when `joints` is odd, then `joints / 2` pairs, none
        // when it is 1): both hold that many (`cells` is at most `frames.len() / joints`), 4-byte
        // aligned (`f32`s), as `VLDM` needs; they write `cells` floats to `out`, which holds that
        // many. The loops count down to zero, so they end. `s0`–`s13` are pushed before use and
        // popped after, so every FPU register the compiler allocated keeps its value; the stack
        // is used only between the push and the pop, below `sp` as the ABI allows. `SUBS` sets
        // the flags (not preserved); VSQRT may set FPSCR's sticky exception bits, which nothing
        // here reads.
        unsafe {
            core::arch::asm!(
                "vpush {{s0-s13}}",
                "vmov s12, {k}",
                "vmov s13, {here_at}",
                "3:",
                "vldmia {frame}, {{s0-s2}}",
                "vmov.f32 s11, s13",
                "mov {here_at}, {here}",
                // Half the joints in pairs; an odd one (the carry) first, on its own.
                "lsrs {k}, {joints}, #1",
                "bcc 4f",
                joint!(),
                "4:",
                "cmp {k}, #0",
                "beq 5f",
                "2:",
                joint!(),
                joint!(),
                "subs {k}, {k}, #1",
                "bne 2b",
                "5:",
                "vmul.f32 s11, s11, s12",
                "vstmia {out}!, {{s11}}",
                "subs {cells}, {cells}, #1",
                "bne 3b",
                "vpop {{s0-s13}}",
                frame = inout(reg) frames.as_ptr() => _,
                here = in(reg) here.as_ptr(),
                joints = in(reg) joints,
                // The scale's bits going in, then the pairs of joints left of a frame.
                k = inout(reg) scale.to_bits() => _,
                // Zero's bits going in, then the pose value being read.
                here_at = inout(reg) 0u32 => _,
                out = inout(reg) out.as_mut_ptr() => _,
                cells = inout(reg) cells => _,
            );
        }
    }

    /// [`super::dot_from`]: the sum in `s8`, four values of each loaded into `s0`–`s3` and
    /// `s4`–`s7` (then one at a time for the rest); `s0`–`s8` pushed before and popped after.
    #[inline(never)]
    pub(super) fn dot_from(start: f32, a: &[f32], b: &[f32]) -> f32 {
        let n = a.len().min(b.len());
        let sum: u32;
        // SAFETY: the loops read `n` floats from each of `a` and `b` (`n` is at most either
        // length; four at a time for `n / 4` steps, then one at a time for `n % 4`), 4-byte
        // aligned (`f32`s), as `VLDM` needs; both count down to zero, so they end. `s0`–`s8`
        // are pushed before use and popped after, so every FPU register the compiler allocated
        // keeps its value; the stack is used only between the push and the pop, below `sp` as
        // the ABI allows. `LSRS`, `ANDS` and `SUBS` set the flags (not preserved).
        unsafe {
            core::arch::asm!(
                "vpush {{s0-s8}}",
                "vmov s8, {sum}",
                "lsrs {k}, {n}, #2",
                "beq 3f",
                "2:",
                "vldmia {a}!, {{s0-s3}}",
                "vldmia {b}!, {{s4-s7}}",
                "vmla.f32 s8, s0, s4",
                "vmla.f32 s8, s1, s5",
                "vmla.f32 s8, s2, s6",
                "vmla.f32 s8, s3, s7",
                "subs {k}, {k}, #1",
                "bne 2b",
                "3:",
                "ands {n}, {n}, #3",
                "beq 5f",
                "4:",
                "vldmia {a}!, {{s0}}",
                "vldmia {b}!, {{s4}}",
                "vmla.f32 s8, s0, s4",
                "subs {n}, {n}, #1",
                "bne 4b",
                "5:",
                "vmov {sum}, s8",
                "vpop {{s0-s8}}",
                sum = inout(reg) start.to_bits() => sum,
                k = out(reg) _,
                n = inout(reg) n => _,
                a = inout(reg) a.as_ptr() => _,
                b = inout(reg) b.as_ptr() => _,
            );
        }
        f32::from_bits(sum)
    }

    /// One loop for [`add_scaled`] and [`scale_then_add`] over `$sums` and `$x`: `k` in `s8`,
    /// four sums loaded into `s0`–`s3` and four values into `s4`–`s7` (then one of each at a
    /// time), combined by the `VMLA`s `$four` (then `$one`) and stored from `$stored` (then
    /// `$one_stored`); `s0`–`s8` pushed before and popped after.
    macro_rules! scaled {
        ($sums:expr, $k:expr, $x:expr, [$($four:literal),*], $stored:literal,
         $one:literal, $one_stored:literal) => {{
            let n = $sums.len().min($x.len());
            // SAFETY: the loops read and write `n` floats of `$sums` and read `n` of `$x` (`n` is
            // at most either length; four at a time for `n / 4` steps, then one at a time for
            // `n % 4`), 4-byte aligned (`f32`s), as `VLDM` and `VSTM` need; both count down to
            // zero, so they end. `s0`–`s8` are pushed before use and popped after, so every FPU
            // register the compiler allocated keeps its value; the stack is used only between
            // the push and the pop, below `sp` as the ABI allows. `LSRS`, `ANDS` and `SUBS` set
            // the flags (not preserved).
            unsafe {
                core::arch::asm!(
                    "vpush {{s0-s8}}",
                    "vmov s8, {k}",
                    "lsrs {q}, {n}, #2",
                    "beq 3f",
                    "2:",
                    "vldmia {s}, {{s0-s3}}",
                    "vldmia {x}!, {{s4-s7}}",
                    $($four,)*
                    concat!("vstmia {s}!, {{", $stored, "}}"),
                    "subs {q}, {q}, #1",
                    "bne 2b",
                    "3:",
                    "ands {n}, {n}, #3",
                    "beq 5f",
                    "4:",
                    "vldmia {s}, {{s0}}",
                    "vldmia {x}!, {{s4}}",
                    $one,
                    concat!("vstmia {s}!, {{", $one_stored, "}}"),
                    "subs {n}, {n}, #1",
                    "bne 4b",
                    "5:",
                    "vpop {{s0-s8}}",
                    k = in(reg) $k.to_bits(),
                    q = out(reg) _,
                    n = inout(reg) n => _,
                    s = inout(reg) $sums.as_mut_ptr() => _,
                    x = inout(reg) $x.as_ptr() => _,
                );
            }
        }};
    }

    /// [`super::add_scaled`]: each sum plus `k` times its value (`VMLA` into the sum).
    #[inline(never)]
    pub(super) fn add_scaled(sums: &mut [f32], k: f32, x: &[f32]) {
        scaled!(
            sums,
            k,
            x,
            [
                "vmla.f32 s0, s8, s4",
                "vmla.f32 s1, s8, s5",
                "vmla.f32 s2, s8, s6",
                "vmla.f32 s3, s8, s7"
            ],
            "s0-s3",
            "vmla.f32 s0, s8, s4",
            "s0"
        );
    }

    /// [`super::scale_then_add`]: each value plus its sum times `k` (`VMLA` into the value:
    /// the same sum, as addition commutes bit for bit).
    #[inline(never)]
    pub(super) fn scale_then_add(sums: &mut [f32], k: f32, x: &[f32]) {
        scaled!(
            sums,
            k,
            x,
            [
                "vmla.f32 s4, s0, s8",
                "vmla.f32 s5, s1, s8",
                "vmla.f32 s6, s2, s8",
                "vmla.f32 s7, s3, s8"
            ],
            "s4-s7",
            "vmla.f32 s4, s0, s8",
            "s4"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        #[test]
        fn a_turn_is_nalgebras_from_its_scaled_axis(
            v in proptest::array::uniform3(-4.0f32..4.0),
            scale in proptest::sample::select(&[1e-8f32, 1e-3, 0.05, 0.14, 1.0][..]),
        ) {
            // Tiny, in the series' range (to its edge) and past it.
            let v = crate::Vec3::from(v) * scale;
            // nalgebra's sine and cosine are the host's (std), ours libm's: to an ulp or so.
            let (ours, theirs) = (turn(v), crate::Quat::from_scaled_axis(v));
            proptest::prop_assert!((ours.coords - theirs.coords).amax() <= 2.0 * f32::EPSILON);
            proptest::prop_assert!((ours.norm() - 1.0).abs() <= 2.0 * f32::EPSILON);
        }

        #[test]
        fn interpolating_is_nalgebras_slerp(
            a in proptest::array::uniform3(-3.0f32..3.0),
            b in proptest::array::uniform3(-3.0f32..3.0),
            f in 0.0f32..=1.0,
        ) {
            let (a, b) = (turn(crate::Vec3::from(a)), turn(crate::Vec3::from(b)));
            // Not across a half turn, where the shortest arc is either way.
            proptest::prop_assume!((a.inverse() * b).angle() < 3.0);
            let (ours, theirs) = (interpolate(a, b, f), a.slerp(&b, f));
            proptest::prop_assert!(ours.angle_to(&theirs) < 1e-3, "{} rad", ours.angle_to(&theirs));
            proptest::prop_assert!(interpolate(a, b, 0.0).angle_to(&a) < 1e-3);
            proptest::prop_assert!(interpolate(a, b, 2.0).angle_to(&b) < 1e-3);
        }

        #[test]
        fn sin_cos_is_within_two_ulp_of_the_true_values(x in -1.0e4f32..1.0e4, small in -4.0f32..4.0) {
            for x in [x, small] {
                let (s, c) = sin_cos(x);
                let (ts, tc) = (f64::from(x).sin(), f64::from(x).cos());
                // Two ulp of a value of magnitude one, as the reduction's rounding of x allows.
                let ulp = |v: f64| (v.abs().max(1e-3) * f64::from(f32::EPSILON)).max(1e-12);
                let tol = 2.0 * f64::from(f32::EPSILON) + 2.0 * f64::from(x.abs()) * 1e-11;
                proptest::prop_assert!((f64::from(s) - ts).abs() <= tol.max(2.0 * ulp(ts)), "sin {x}: {s} against {ts}");
                proptest::prop_assert!((f64::from(c) - tc).abs() <= tol.max(2.0 * ulp(tc)), "cos {x}: {c} against {tc}");
            }
        }

        #[test]
        fn cbrt_is_within_two_ulp_of_the_true_root(x in 1e-30f32..1e30) {
            let (ours, theirs) = (f64::from(cbrt(x)), f64::from(x).cbrt());
            proptest::prop_assert!((ours - theirs).abs() <= 2.0 * f64::from(f32::EPSILON) * theirs, "{x}: {ours} against {theirs}");
        }

        #[test]
        fn dot_from_is_a_plain_fold_to_the_bit(
            a in proptest::collection::vec(-100.0f32..100.0, 0..23),
            b in proptest::collection::vec(-100.0f32..100.0, 0..23),
            start in -100.0f32..100.0,
        ) {
            let plain = a.iter().zip(&b).fold(start, |s, (a, b)| s + a * b);
            proptest::prop_assert_eq!(dot_from(start, &a, &b).to_bits(), plain.to_bits());
        }

        #[test]
        fn scaled_sums_are_each_values_product_and_sum_to_the_bit(
            a in proptest::collection::vec(-100.0f32..100.0, 0..23),
            b in proptest::collection::vec(-100.0f32..100.0, 0..23),
            k in -10.0f32..10.0,
        ) {
            let n = a.len().min(b.len());
            let (mut added, mut scaled) = (a.clone(), a.clone());
            add_scaled(&mut added, k, &b);
            scale_then_add(&mut scaled, k, &b);
            for (i, (&s, &x)) in a.iter().zip(&b).enumerate() {
                proptest::prop_assert_eq!(added[i].to_bits(), (s + k * x).to_bits());
                proptest::prop_assert_eq!(scaled[i].to_bits(), (s * k + x).to_bits());
            }
            proptest::prop_assert_eq!(&added[n..], &a[n..]);
            proptest::prop_assert_eq!(&scaled[n..], &a[n..]);
        }
    }

    #[test]
    fn rooted_distances_sum_each_frames_joint_distances_from_its_root_scaled() {
        use crate::Vec3;
        let here = [Vec3::zeros(), Vec3::new(3.0, 4.0, 0.0)];
        let frames = [
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0), // at its root: 5 from (3, 4, 0)
            Vec3::new(2.0, 2.0, 2.0),
            Vec3::new(2.0, 6.0, 2.0), // (0, 4, 0) from its root: 3
            Vec3::new(9.0, 9.0, 9.0), // half a frame: not read
        ];
        let mut out = [-1.0; 3];
        rooted_distances(&here, &frames, 0.5, &mut out);
        assert_eq!(out, [2.5, 1.5, -1.0]);
        let mut short = [-1.0; 1];
        rooted_distances(&here, &frames, 1.0, &mut short);
        assert_eq!(short, [5.0]);
        rooted_distances(&[], &frames, 1.0, &mut out);
        assert_eq!(out, [2.5, 1.5, -1.0]);
    }

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

        #[test]
        fn unit_and_rotation_are_nalgebras_to_the_bit(
            v in proptest::array::uniform3(-2.0f32..2.0),
            w in -2.0f32..2.0,
            min in 0.0f32..1.0,
        ) {
            let v = crate::Vec3::from(v);
            let bits = |v: crate::Vec3| v.map(f32::to_bits);
            let theirs = nalgebra::Unit::try_new(v, min).map(nalgebra::Unit::into_inner);
            proptest::prop_assert_eq!(unit(v, min).map(bits), theirs.map(bits));
            let q = nalgebra::Quaternion::new(w, v.x, v.y, v.z);
            proptest::prop_assume!(q.norm_squared() > 0.0);
            let (ours, theirs) = (rotation(q), crate::Quat::new_normalize(q));
            proptest::prop_assert_eq!(ours.coords.map(f32::to_bits), theirs.coords.map(f32::to_bits));
        }
    }
}
