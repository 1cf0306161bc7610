//! Integer arithmetic of the quantized retargeter: int8 values with symmetric `f32` scales
//! (`real = scale · q`, a scale mapping the largest magnitude to 127; values beyond it
//! saturate to −128..=127), int32 accumulation and fixed-point requantization.
//!
//! A layer `y = W x + b` with input scale `s_x`, per-output-channel weight scales `s_w[c]`
//! and output scale `s_y` accumulates `Σ W_q x_q + b_q` in int32 (`b_q = b / (s_x s_w[c])`)
//! and takes the accumulator to int8 with [`Requant`] of `s_x s_w[c] / s_y`.

/// A positive real factor as `multiplier · 2^(shift − 31)`, `multiplier` in `[2^30, 2^31)`:
/// the exact integer form of a rescaling, the same on every machine.
///
/// Its bytes are two little-endian `i32`s (multiplier, shift), so a weights blob stores
/// requantizations as they are used; [`Requant::is_valid`] checks stored ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(C)]
pub struct Requant {
    multiplier: i32,
    shift: i32,
}

/// The largest int8 value, which a symmetric scale maps the largest magnitude to (−128 is
/// reached only by saturation).
pub const MAX: i32 = 127;
/// The smallest int8 value.
const MIN: i32 = -128;
/// Exponents a [`Requant`] covers: factors from about `2^-30` to `2^30`.
const SHIFTS: core::ops::RangeInclusive<i32> = -30..=30;

impl Requant {
    /// The requantization by `factor`, or `None` unless it is finite and within `2^±30`.
    pub fn new(factor: f32) -> Option<Requant> {
        if !(factor.is_finite() && factor > 0.0) {
            return None;
        }
        let (mantissa, exponent) = frexp(factor);
        // mantissa in [0.5, 1): multiplier in [2^30, 2^31], the top case carried into the
        // exponent.
        let mut multiplier = libm::round(f64::from(mantissa) * f64::from(1u32 << 31)) as i64;
        let mut shift = exponent;
        if multiplier == 1 << 31 {
            multiplier /= 2;
            shift += 1;
        }
        SHIFTS.contains(&shift).then_some(Requant {
            multiplier: multiplier as i32,
            shift,
        })
    }

    /// Whether it is one [`Requant::new`] makes: multiplier in `[2^30, 2^31)`, shift within
    /// `±30`. Only such values are safe to [`Requant::scale`] with.
    pub fn is_valid(self) -> bool {
        self.multiplier >= 1 << 30 && SHIFTS.contains(&self.shift)
    }

    /// The factor it stands for.
    pub fn factor(self) -> f32 {
        (f64::from(self.multiplier) * libm::exp2(f64::from(self.shift) - 31.0)) as f32
    }

    /// `acc · factor` rounded to the nearest integer (ties up), saturated to `i32`: one
    /// 32 × 32 → 64-bit multiply (`SMULL`), then, for factors below ½ (every requantization
    /// of the network), the product's top word shifted right with rounding: five
    /// instructions. Integer arithmetic, the same on every machine.
    #[inline]
    pub fn scale(self, acc: i32) -> i32 {
        // `factor = multiplier · 2^-total`, total in 1..=61.
        let total = 31 - self.shift;
        let product = i64::from(acc) * i64::from(self.multiplier);
        if total > 32 {
            // Rounding at bit `total - 1` ≥ 32 touches only the top word, and the bits below
            // it cannot carry into the result: |top| < 2^30, so the sum cannot overflow.
            let top = (product >> 32) as i32;
            (top + (1 << (total - 33))) >> (total - 32)
        } else {
            let rounded = (product + (1i64 << (total - 1))) >> total;
            rounded.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
        }
    }

    /// `acc · factor` rounded as [`Requant::scale`] rounds, as a saturated int8 value.
    #[inline]
    pub fn apply(self, acc: i32) -> i8 {
        self.scale(acc).clamp(MIN, MAX) as i8
    }
    /// The same requantization, when its factor is below ¼ (`shift ≤ −2`), in the form the
    /// kernels apply per output.
    #[inline(always)]
    fn small(self) -> Option<Small> {
        (self.shift <= -2).then_some(Small {
            multiplier: self.multiplier,
            shift: (-2 - self.shift) as u32,
        })
    }
}

/// A [`Requant`] by less than ¼: [`Requant::scale`]'s product's top word is shifted right by
/// `shift + 1` with rounding, as `((top >> shift) + 1) >> 1` (the same integer: flooring
/// first cannot change where the rounded quotient falls): `SMMUL`, three shifts and adds.
#[derive(Clone, Copy)]
struct Small {
    multiplier: i32,
    /// `total − 33` for [`Requant::scale`]'s `total`, at least 0.
    shift: u32,
}

impl Small {
    #[inline(always)]
    fn scale(self, acc: i32) -> i32 {
        let top = ((i64::from(acc) * i64::from(self.multiplier)) >> 32) as i32;
        ((top >> self.shift) + 1) >> 1
    }
}

/// `x = mantissa · 2^exponent` with `mantissa` in `[0.5, 1)`, for a positive normal `x`.
fn frexp(x: f32) -> (f32, i32) {
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xFF) as i32;
    if exponent == 0 {
        // Subnormal: scale into the normal range first.
        let (m, e) = frexp(x * (1u64 << 32) as f32);
        return (m, e - 32);
    }
    let mantissa = f32::from_bits((bits & 0x807F_FFFF) | (126 << 23));
    (mantissa, exponent - 126)
}

/// The int8 value nearest `real / scale` (halves away from zero), saturated; NaN gives 0.
///
/// Rounds by adding a signed half and truncating (`VCVT` on the M4F; a handful of
/// instructions where `roundf` takes a software routine), the same on every machine.
#[inline]
pub fn quantize(real: f32, scale: f32) -> i8 {
    let v = real / scale;
    let half = if v < 0.0 { -0.5 } else { 0.5 };
    ((v + half) as i32).clamp(MIN, MAX) as i8
}

/// `Σ a[k] · b[k]` over the shorter of the two.
#[inline]
pub fn dot(a: &[i8], b: &[i8]) -> i32 {
    let n = a.len().min(b.len());
    let (a4, a_rest) = a[..n].as_chunks::<4>();
    let (b4, b_rest) = b[..n].as_chunks::<4>();
    let mut s = [0i32; 4];
    for (x, y) in a4.iter().zip(b4) {
        for k in 0..4 {
            s[k] += i32::from(x[k]) * i32::from(y[k]);
        }
    }
    let tail: i32 = a_rest
        .iter()
        .zip(b_rest)
        .map(|(&x, &y)| i32::from(x) * i32::from(y))
        .sum();
    tail + s.iter().sum::<i32>()
}

/// Vectors a layer's rows run against together: [`linear`] and [`accumulate`] take their
/// inputs four at a time, so that each weight is loaded and widened once for four products.
pub const LANES: usize = 4;

/// Most inputs of one output (a linear layer's inputs, a convolution's kernel × inputs per
/// group).
pub const MAX_FIELD: usize = 128;
/// Longest convolution kernel (a weights blob with a longer one is refused).
pub const MAX_KERNEL: usize = 7;

/// Room for the vectors a layer call runs on together, made once and lent to every call
/// ([`linear`], [`accumulate`], [`conv1d`]) so that none clears its own: on the DSP path the
/// inputs' four-byte groups sign-extended to 16-bit lanes and interleaved (group `g` of lane
/// `l` as words `[g][2l]`, bytes 0 and 2, and `[g][2l + 1]`, bytes 1 and 3: the operands of
/// `SMLAD`); nothing elsewhere.
pub struct Workspace {
    #[cfg(all(feature = "dsp", target_arch = "arm"))]
    widened: [[u32; 2 * LANES]; MAX_FIELD / 4],
}

impl Workspace {
    /// An empty workspace (1 KiB on the DSP path).
    pub const fn new() -> Self {
        Workspace {
            #[cfg(all(feature = "dsp", target_arch = "arm"))]
            widened: [[0; 2 * LANES]; MAX_FIELD / 4],
        }
    }

    /// Takes `inputs`, each at most [`MAX_FIELD`] long, for [`Workspace::rows`].
    #[inline(always)]
    fn load(&mut self, inputs: &[&[i8]; LANES]) {
        #[cfg(all(feature = "dsp", target_arch = "arm"))]
        dsp::widen(&mut self.widened, inputs);
        #[cfg(not(all(feature = "dsp", target_arch = "arm")))]
        let _ = inputs;
    }

    /// The loaded vectors' kernel for rows of `n` values: on the DSP path, when the rows are
    /// whole four-byte groups, `SMLAD` on the widened groups; otherwise [`dots`].
    #[inline(always)]
    fn rows<'a>(&'a self, inputs: &'a [&[i8]; LANES], n: usize) -> Kernel<'a> {
        #[cfg(all(feature = "dsp", target_arch = "arm"))]
        if n.is_multiple_of(4) {
            return Kernel::Widened(&self.widened[..(n / 4).min(MAX_FIELD / 4)]);
        }
        let _ = n;
        Kernel::Bytes(inputs)
    }
}

/// How a group of vectors meets each row: see [`Workspace::rows`].
#[derive(Clone, Copy)]
enum Kernel<'a> {
    /// The vectors as they are, through [`dots`].
    Bytes(&'a [&'a [i8]; LANES]),
    /// The vectors widened for `SMLAD`, through `dsp::row`.
    #[cfg(all(feature = "dsp", target_arch = "arm"))]
    Widened(&'a [[u32; 2 * LANES]]),
}

/// `start[l] + Σ_k row[k] · inputs[l][k]` for each lane (wrapping), by [`dot`]: the portable
/// path, and on the DSP path the one for rows of no whole four-byte groups (kept out of line).
#[inline(never)]
fn dots(inputs: &[&[i8]; LANES], row: &[i8], start: [i32; LANES]) -> [i32; LANES] {
    let mut sums = start;
    for (sum, x) in sums.iter_mut().zip(inputs) {
        *sum = sum.wrapping_add(dot(row, x));
    }
    sums
}

impl Default for Workspace {
    fn default() -> Self {
        Workspace::new()
    }
}

#[cfg(all(feature = "dsp", target_arch = "arm"))]
#[allow(unsafe_code)]
mod dsp {
    use super::LANES;

    /// Each lane's whole four-byte groups (as many as the shortest lane has, at most
    /// `widened.len()`), sign-extended to 16 bits: group `g` of lane `l` as `widened[g][2l]`
    /// (bytes 0 and 2) and `widened[g][2l + 1]` (bytes 1 and 3). Per group, a load and two
    /// `SXTB16` a lane and an `STM` for each two lanes: 16 instructions, loop included.
    #[inline(always)]
    pub(super) fn widen(widened: &mut [[u32; 2 * LANES]], inputs: &[&[i8]; LANES]) {
        let groups = inputs.iter().fold(widened.len(), |g, x| g.min(x.len() / 4));
        if groups == 0 {
            return;
        }
        let [x0, x1, x2, x3] = inputs.map(<[i8]>::as_ptr);
        // SAFETY: reads `groups` words from each lane (4 bytes each: `ldr` allows any alignment
        // on the Cortex-M4), which each holds at least that many, and writes `groups` × 32
        // bytes to `widened` (word-aligned `u32`s, as `STM` needs), which holds that many
        // (`groups` is at most either), at least 1 (the loop runs before it tests). `STM`
        // stores `r2`–`r5` in that order, as the layout needs. The flags are clobbered (no
        // `preserves_flags`).
        unsafe {
            core::arch::asm!(
                "2:",
                "ldr r3, [{x0}], #4",
                "ldr r5, [{x1}], #4",
                "sxtb16 r2, r3",
                "sxtb16 r3, r3, ror #8",
                "sxtb16 r4, r5",
                "sxtb16 r5, r5, ror #8",
                "stmia {to}!, {{r2-r5}}",
                "ldr r3, [{x2}], #4",
                "ldr r5, [{x3}], #4",
                "sxtb16 r2, r3",
                "sxtb16 r3, r3, ror #8",
                "sxtb16 r4, r5",
                "sxtb16 r5, r5, ror #8",
                "stmia {to}!, {{r2-r5}}",
                "subs {n}, {n}, #1",
                "bne 2b",
                x0 = inout(reg) x0 => _,
                x1 = inout(reg) x1 => _,
                x2 = inout(reg) x2 => _,
                x3 = inout(reg) x3 => _,
                to = inout(reg) widened.as_mut_ptr() => _,
                n = inout(reg) groups => _,
                out("r2") _,
                out("r3") _,
                out("r4") _,
                out("r5") _,
                options(nostack)
            );
        }
    }

    /// A row's sums: per four-byte group of its weights (`{pw}`), one load and two `SXTB16`
    /// widen them, then per lane `l` one `LDRD` (the lane's widened group, `{px}`) and two
    /// `SMLAD` add four products to `{sl}`; `{n}` groups, at least one.
    macro_rules! sums {
        () => {
            concat!(
                "2:\n",
                "ldr {w}, [{pw}], #4\n",
                "sxtb16 {t}, {w}, ror #8\n",
                "sxtb16 {w}, {w}\n",
                "ldrd {xe}, {xo}, [{px}], #8\n",
                "smlad {s0}, {xe}, {w}, {s0}\n",
                "smlad {s0}, {xo}, {t}, {s0}\n",
                "ldrd {xe}, {xo}, [{px}], #8\n",
                "smlad {s1}, {xe}, {w}, {s1}\n",
                "smlad {s1}, {xo}, {t}, {s1}\n",
                "ldrd {xe}, {xo}, [{px}], #8\n",
                "smlad {s2}, {xe}, {w}, {s2}\n",
                "smlad {s2}, {xo}, {t}, {s2}\n",
                "ldrd {xe}, {xo}, [{px}], #8\n",
                "smlad {s3}, {xe}, {w}, {s3}\n",
                "smlad {s3}, {xo}, {t}, {s3}\n",
                "subs {n}, {n}, #1\n",
                "bne 2b\n",
            )
        };
    }

    /// Each lane's `s[l] + Σ_g` of `row[g]`'s four int8 weights times the lane's widened group `g`
    /// (`widened[g][2l]`, `widened[g][2l + 1]`): per group one load and two `SXTB16` widen
    /// the weights, then per lane one `LDRD` and two `SMLAD` add four products (17
    /// instructions for 16 multiply-accumulates, loop included), as CMSIS-NN's kernels do.
    #[inline(always)]
    pub(super) fn row(
        mut s: [i32; LANES],
        widened: &[[u32; 2 * LANES]],
        row: &[[i8; 4]],
    ) -> [i32; LANES] {
        let groups = widened.len().min(row.len());
        if groups == 0 {
            return s;
        }
        // SAFETY: reads `groups` words from `row` (4 bytes each: `ldr` allows any alignment on
        // the Cortex-M4) and `groups` × 32 bytes from `widened` (word-aligned `u32`s, as `ldrd`
        // needs), both within their slices since `groups` is at most either length and at
        // least 1 (the loop runs before it tests). Writes only registers; SMLAD may set the Q
        // flag, which nothing reads; the flags are clobbered (no `preserves_flags`).
        unsafe {
            core::arch::asm!(
                sums!(),
                pw = inout(reg) row.as_ptr() => _,
                px = inout(reg) widened.as_ptr() => _,
                n = inout(reg) groups => _,
                s0 = inout(reg) s[0],
                s1 = inout(reg) s[1],
                s2 = inout(reg) s[2],
                s3 = inout(reg) s[3],
                w = out(reg) _,
                t = out(reg) _,
                xe = out(reg) _,
                xo = out(reg) _,
                options(readonly, nostack)
            );
        }
        s
    }

    /// One lane's output from its sum `$s`: [`super::Small::scale`] by `{n}` and `{w}`
    /// (`SMMUL`, the shift and the rounding), saturated to int8 (`SSAT`, which takes the last
    /// halving) and stored at `$at`; `{xo}` is free to work in (the next row's weights stay in
    /// `{pw}`).
    macro_rules! identity {
        ($s:literal, $at:literal) => {
            concat!(
                "smmul {xo}, ",
                $s,
                ", {n}\n",
                "asr {xo}, {xo}, {w}\n",
                "adds {xo}, {xo}, #1\n",
                "ssat {xo}, #8, {xo}, asr #1\n",
                "strb {xo}, ",
                $at,
                "\n",
            )
        };
    }

    /// [`identity!`]'s steps with the leaky slope, in `{pw}` (`{xo}` holds the slope's
    /// multiplier), for a positive value; a negative one (known by the sign of the value before
    /// its last halving) branches to `$negative`, which comes back to `$back`.
    macro_rules! leaky {
        ($s:literal, $at:literal, $negative:literal, $back:literal) => {
            concat!(
                "smmul {pw}, ",
                $s,
                ", {n}\n",
                "asr {pw}, {pw}, {w}\n",
                "adds {pw}, {pw}, #1\n",
                "bmi ",
                $negative,
                "f\n",
                "ssat {pw}, #8, {pw}, asr #1\n",
                "strb {pw}, ",
                $at,
                "\n",
                $back,
                ":\n",
            )
        };
    }

    /// [`leaky!`]'s negative value, out of the line: halved, scaled by `LEAKY_SMALL` (`{xo}`
    /// holds its multiplier; its shift is 0), saturated and stored at `$at`.
    macro_rules! negative {
        ($at:literal, $negative:literal, $back:literal) => {
            concat!(
                $negative,
                ":\n",
                "asr {pw}, {pw}, #1\n",
                "smmul {pw}, {pw}, {xo}\n",
                "adds {pw}, {pw}, #1\n",
                "ssat {pw}, #8, {pw}, asr #1\n",
                "strb {pw}, ",
                $at,
                "\n",
                "b ",
                $back,
                "b\n",
            )
        };
    }

    /// The whole of [`requantize`] for one activation (`$lanes`: each lane's output by
    /// [`identity!`] or [`leaky!`], after `$setup`; `$aside`: code out of the line, such as
    /// [`negative!`]; `$keep` and `$restore` save the next row's weights pointer while the lanes
    /// need its register and take it back, or are empty): the row loop's state kept below the
    /// stack pointer, each row's biases loaded, its sums by [`row`]'s loop, its four outputs
    /// requantized and stored; `$operands` is the tuple of the loop's pointers and counts.
    macro_rules! requantize {
        ($setup:literal, [$l0:expr, $l1:expr, $l2:expr, $l3:expr], $aside:expr,
         $keep:literal, $restore:literal, $operands:expr) => {{
            let (weights, widened, groups, bias, stride, requant, out, m) = $operands;
            core::arch::asm!(
                // State: 0 the row's weights, 4 widened, 8 groups, 12 the row's lane-0 bias,
                // 16 the lanes' bias stride, 20 the row's requantization, 24 its lane-0
                // output, 28 the lanes' output stride (m), 32 the end of lane 0's outputs.
                "sub sp, sp, #40",
                "str {pw}, [sp]",
                "strd {px}, {n}, [sp, #4]",
                "strd {s0}, {s1}, [sp, #12]",
                "strd {s2}, {s3}, [sp, #20]",
                "str {w}, [sp, #28]",
                "add {t}, {s3}, {w}",
                "str {t}, [sp, #32]",
                "1:",
                $restore,
                "ldrd {px}, {n}, [sp, #4]",
                "ldrd {w}, {t}, [sp, #12]",
                "ldr {s0}, [{w}]",
                "ldr {s1}, [{w}, {t}]",
                "ldr {s2}, [{w}, {t}, lsl #1]",
                "adds {xe}, {w}, #4",
                "str {xe}, [sp, #12]",
                "add {w}, {w}, {t}",
                "ldr {s3}, [{w}, {t}, lsl #1]",
                sums!(),
                // The next row's weights follow this one's.
                $keep,
                "ldr {px}, [sp, #20]",
                "ldrd {n}, {w}, [{px}], #8",
                "str {px}, [sp, #20]",
                // Small's shift: -2 - shift.
                "mvn {w}, {w}",
                "subs {w}, {w}, #1",
                "ldrd {t}, {xe}, [sp, #24]",
                $setup,
                $l0,
                $l1,
                "add {px}, {t}, {xe}, lsl #1",
                $l2,
                $l3,
                "adds {t}, {t}, #1",
                "str {t}, [sp, #24]",
                "ldr {xe}, [sp, #32]",
                "cmp {t}, {xe}",
                "bne 1b",
                "b 9f",
                $aside,
                "9:",
                "add sp, sp, #40",
                pw = inout(reg) weights => _,
                px = inout(reg) widened => _,
                n = inout(reg) groups => _,
                s0 = inout(reg) bias => _,
                s1 = inout(reg) stride => _,
                s2 = inout(reg) requant => _,
                s3 = inout(reg) out => _,
                w = inout(reg) m => _,
                t = out(reg) _,
                xe = out(reg) _,
                xo = out(reg) _,
            )
        }};
    }

    /// A group's rows on four widened vectors, each output requantized by a [`super::Small`]
    /// (the leaky slope applied when `LEAKY`) and stored: `out[l·m + c]` for lane `l` and row
    /// `c` (`weights[c·n..]`, `n = 4 · widened.len()`), its sum started from `biases[l][c]`.
    /// One `asm!` loop over the rows, its state below the stack pointer, so that a row's sums
    /// stay in registers from their biases to their outputs: 9 instructions to start a row,
    /// [`row`]'s 17 per four-byte group, then 32 to requantize and store its four outputs;
    /// with the leaky slope 10 and 38, and 4 more for each negative output.
    ///
    /// Every factor of `requant` must be below ¼ (each a [`super::Small`], as the caller
    /// checks once per layer); otherwise the outputs are wrong. Returns `false` (and does
    /// nothing) unless the shapes hold: `widened` not empty, `weights` `m` rows of `n`,
    /// `requant` `m` long, `out` `4m` long, and the lanes' `m` biases each at `stride` after
    /// the one before.
    pub(super) fn requantize<const LEAKY: bool>(
        widened: &[[u32; 2 * LANES]],
        weights: &[i8],
        biases: [&[i32]; LANES],
        requant: &[super::Requant],
        out: &mut [i8],
    ) -> bool {
        let (groups, m) = (widened.len(), requant.len());
        let at = biases.map(|b| b.as_ptr() as usize);
        let stride = at[1].wrapping_sub(at[0]);
        if groups == 0
            || m == 0
            || weights.len() != 4 * groups * m
            || out.len() != LANES * m
            || biases.iter().any(|b| b.len() != m)
            || at[2] != at[1].wrapping_add(stride)
            || at[3] != at[2].wrapping_add(stride)
        {
            return false;
        }
        let operands = (
            weights.as_ptr(),
            widened.as_ptr(),
            groups,
            biases[0].as_ptr(),
            stride,
            requant.as_ptr(),
            out.as_mut_ptr(),
            m,
        );
        // SAFETY: the loop runs `m` rows (at least 1; it ends when lane 0's output pointer, one
        // further each row, is `m` past its start), each reading the row's `n = 4 · groups`
        // weights from `weights` (`m · n` long, rows in order), `groups` × 32 bytes from
        // `widened` (word-aligned `u32`s, as `LDRD` needs) and lane `l`'s bias `c` at
        // `biases[0] + l · stride + 4c` bytes, which is `biases[l][c]` (checked above: every
        // lane's slice starts there and is `m` long); its two words of `requant[c]` (`repr(C)`
        // multiplier and shift, 4-byte aligned); and writing lane `l`'s output at
        // `out[l · m + c]`, inside `out` (`4m` long). The loop's state is kept in 40 bytes
        // below the stack pointer, which it moves down before and back after (no `nostack`).
        // SMLAD may set the Q flag, which nothing reads; the flags are clobbered (no
        // `preserves_flags`).
        unsafe {
            if LEAKY {
                requantize!(
                    "mov {xo}, #0x66666666",
                    [
                        leaky!("{s0}", "[{t}]", "31", "41"),
                        leaky!("{s1}", "[{t}, {xe}]", "32", "42"),
                        leaky!("{s2}", "[{px}]", "33", "43"),
                        leaky!("{s3}", "[{px}, {xe}]", "34", "44")
                    ],
                    concat!(
                        negative!("[{t}]", "31", "41"),
                        negative!("[{t}, {xe}]", "32", "42"),
                        negative!("[{px}]", "33", "43"),
                        negative!("[{px}, {xe}]", "34", "44")
                    ),
                    "str {pw}, [sp]",
                    "ldr {pw}, [sp]",
                    operands
                );
            } else {
                requantize!(
                    "",
                    [
                        identity!("{s0}", "[{t}]"),
                        identity!("{s1}", "[{t}, {xe}]"),
                        identity!("{s2}", "[{px}]"),
                        identity!("{s3}", "[{px}, {xe}]")
                    ],
                    "",
                    "",
                    "",
                    operands
                );
            }
        }
        true
    }
}

#[cfg(all(feature = "dsp", not(target_arch = "arm")))]
compile_error!("the `dsp` feature needs an ARM target with the DSP extension (Cortex-M4, M7, M33)");

/// What a layer applies to its rescaled outputs before they saturate to int8.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Activation {
    /// Nothing.
    Identity,
    /// Leaky ReLU of slope [`LEAKY_SLOPE`] (the network's activation), on the rescaled value.
    Leaky,
}

/// Negative slope of the leaky ReLU.
pub const LEAKY_SLOPE: f32 = 0.2;
/// [`LEAKY_SLOPE`] as a [`Requant`]: round(0.8 · 2^31) · 2^-33, the exact 0.2 to 10 digits.
const LEAKY: Requant = Requant {
    multiplier: 1_717_986_918,
    shift: -2,
};

/// [`LEAKY`] ready to apply.
const LEAKY_SMALL: Small = Small {
    multiplier: LEAKY.multiplier,
    shift: (-2 - LEAKY.shift) as u32,
};

impl Activation {
    /// `acc` rescaled by `requant`, activated and saturated.
    #[inline]
    pub fn apply(self, requant: Requant, acc: i32) -> i8 {
        self.activate(requant.scale(acc))
    }

    /// A rescaled value `v` activated and saturated.
    #[inline(always)]
    fn activate(self, v: i32) -> i8 {
        let v = match self {
            Activation::Leaky if v < 0 => LEAKY_SMALL.scale(v),
            _ => v,
        };
        // One `SSAT` on the M4F.
        v.clamp(MIN, MAX) as i8
    }
}

/// Why a layer could not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ShapeError {
    /// The slices do not have the lengths the layer's sizes give.
    Mismatch,
}

/// A layer's parameters: int8 weights (one row per output channel) and each output
/// channel's requantization; its biases come with its inputs.
#[derive(Clone, Copy, Debug)]
pub struct Layer<'w> {
    /// `outputs × inputs` (for a convolution `outputs × kernel × inputs per group`).
    pub weights: &'w [i8],
    /// One per output channel: accumulator scale over output scale.
    pub requant: &'w [Requant],
    /// Applied after rescaling.
    pub activation: Activation,
}

/// Where a layer call finds vector `i` of its inputs, or of its biases.
#[derive(Clone, Copy)]
pub enum Vectors<'a, T> {
    /// Vector `i` starts at `data[i · stride]` (a stride of 0: every vector is the same one).
    /// Read in place, the common case.
    Strided(&'a [T], usize),
    /// Vector `i` is `f(i)`: a gather or a padded window, one call per vector.
    Each(&'a dyn Fn(usize) -> &'a [T]),
}

impl<'a, T> Vectors<'a, T> {
    /// Whether `count` vectors of `len` can be looked for: strided ones end within `usize`
    /// (so that [`Vectors::lanes`]' offsets cannot overflow).
    fn addressable(&self, count: usize, len: usize) -> bool {
        match *self {
            Vectors::Strided(_, stride) => count
                .saturating_sub(1)
                .checked_mul(stride)
                .and_then(|last| last.checked_add(len))
                .is_some(),
            Vectors::Each(_) => true,
        }
    }

    /// The vectors `vectors` (below a count [`Vectors::addressable`] allows), each `len` long,
    /// or `None` where one is not.
    #[inline(always)]
    fn lanes(&self, vectors: &[usize; LANES], len: usize) -> Option<[&'a [T]; LANES]> {
        let mut lanes: [&[T]; LANES] = [&[]; LANES];
        match *self {
            Vectors::Strided(data, stride) => {
                for (lane, &i) in lanes.iter_mut().zip(vectors) {
                    *lane = data.get(i * stride..)?.get(..len)?;
                }
            }
            Vectors::Each(f) => {
                for (lane, &i) in lanes.iter_mut().zip(vectors) {
                    *lane = Some(f(i)).filter(|v| v.len() == len)?;
                }
            }
        }
        Some(lanes)
    }
}

/// A fully connected layer on `count` vectors: for each `i < count`, `out[i·m + c] =
/// act(requant[c](Σ_k weights[c·n + k] · input_i[k] + bias_i[c]))`, with `m` outputs (one per
/// requantization) and `n = weights.len() / m` inputs. Vectors go through the rows
/// [`LANES`] at a time.
///
/// # Errors
/// [`ShapeError::Mismatch`] unless `weights` is `m × n` with `0 < n ≤` [`MAX_FIELD`], every
/// input vector is `n` long (at least), every bias vector `m` and `out` is `count × m`.
#[inline]
pub fn linear(
    work: &mut Workspace,
    count: usize,
    input: Vectors<'_, i8>,
    bias: Vectors<'_, i32>,
    layer: &Layer<'_>,
    out: &mut [i8],
) -> Result<(), ShapeError> {
    if out.len() != count * layer.requant.len() {
        return Err(ShapeError::Mismatch);
    }
    let requant = layer.requant;
    match layer.activation {
        Activation::Identity => {
            let finish = Requantize::<false>::new(requant);
            rows(work, count, input, bias, layer.weights, out, &finish)
        }
        Activation::Leaky => {
            let finish = Requantize::<true>::new(requant);
            rows(work, count, input, bias, layer.weights, out, &finish)
        }
    }
}

/// [`linear`]'s accumulators, not requantized, for a layer whose outputs go on in `f32`:
/// `out[i·m + c] = Σ_k weights[c·n + k] · input_i[k] + bias_i[c]` with `m = out.len() / count`
/// (no vectors: nothing to do).
///
/// # Errors
/// As [`linear`].
#[inline]
pub fn accumulate(
    work: &mut Workspace,
    count: usize,
    input: Vectors<'_, i8>,
    bias: Vectors<'_, i32>,
    weights: &[i8],
    out: &mut [i32],
) -> Result<(), ShapeError> {
    rows(work, count, input, bias, weights, out, &Raw)
}

/// What becomes of a row's sums, one per lane.
trait Finish {
    type Out: Copy + Default;
    /// Output `c` of each lane from its sum, written to the lane's `out`.
    fn finish(&self, c: usize, sums: [i32; LANES], out: [&mut Self::Out; LANES]);

    /// Runs a whole group's rows on widened vectors itself, outputs `block` (four lanes of
    /// `m`), and says so; `false` leaves them to [`group`].
    #[cfg(all(feature = "dsp", target_arch = "arm"))]
    fn widened(
        &self,
        _widened: &[[u32; 2 * LANES]],
        _weights: &[i8],
        _biases: [&[i32]; LANES],
        _block: &mut [Self::Out],
    ) -> bool {
        false
    }
}

/// Requantized to int8, then the leaky slope applied (`LEAKY`) or not.
struct Requantize<'r, const LEAKY: bool> {
    requant: &'r [Requant],
    /// Whether every factor is below ¼, as `dsp::requantize` needs.
    #[cfg(all(feature = "dsp", target_arch = "arm"))]
    small: bool,
}

impl<'r, const LEAKY: bool> Requantize<'r, LEAKY> {
    fn new(requant: &'r [Requant]) -> Self {
        Requantize {
            requant,
            #[cfg(all(feature = "dsp", target_arch = "arm"))]
            small: requant.iter().all(|r| r.small().is_some()),
        }
    }
}

impl<const LEAKY: bool> Finish for Requantize<'_, LEAKY> {
    type Out = i8;

    #[inline(always)]
    fn finish(&self, c: usize, sums: [i32; LANES], out: [&mut i8; LANES]) {
        let activation = if LEAKY {
            Activation::Leaky
        } else {
            Activation::Identity
        };
        let requant = self.requant[c];
        match requant.small() {
            Some(small) => each(out, sums, |acc| activation.activate(small.scale(acc))),
            None => each(out, sums, |acc| activation.apply(requant, acc)),
        }
    }

    /// `dsp::requantize`'s one loop when every factor is below ¼ and the lanes' biases lie
    /// at one stride.
    #[cfg(all(feature = "dsp", target_arch = "arm"))]
    #[inline(always)]
    fn widened(
        &self,
        widened: &[[u32; 2 * LANES]],
        weights: &[i8],
        biases: [&[i32]; LANES],
        block: &mut [i8],
    ) -> bool {
        self.small && dsp::requantize::<LEAKY>(widened, weights, biases, self.requant, block)
    }
}

/// The sums as they are.
struct Raw;

impl Finish for Raw {
    type Out = i32;

    #[inline(always)]
    fn finish(&self, _: usize, sums: [i32; LANES], out: [&mut i32; LANES]) {
        each(out, sums, |sum| sum);
    }
}

/// `*out[l] = f(sums[l])` for each lane, written out so that the lanes stay in registers.
#[inline(always)]
fn each<T>(out: [&mut T; LANES], sums: [i32; LANES], f: impl Fn(i32) -> T) {
    let [a, b, c, d] = out;
    *a = f(sums[0]);
    *b = f(sums[1]);
    *c = f(sums[2]);
    *d = f(sums[3]);
}

/// `out[i·m + c] = finish(c, sums)[l]` for every vector `i` and output `c`, where `sums[l] =
/// bias_i[c] + Σ_k weights[c·n + k] · input_i[k]` for the vectors `i` of lane `l`: rows
/// outermost within each group of [`LANES`] vectors. With fewer vectors than lanes, the last
/// repeats in the missing lanes; with more, the last group overlaps the one before (its
/// vectors' outputs are stored twice, alike). The products' sum cannot overflow (127² ·
/// [`MAX_FIELD`] is far below `i32::MAX`); the bias is the accumulator's start, so a bias
/// within `2^30` of either end of `i32` wraps it around (the same on every target).
///
/// One copy per kind of output (the vectors and biases found through [`Vectors`], once per
/// group), not one per layer: the kernel's code is flash.
#[inline(never)]
fn rows<F: Finish>(
    work: &mut Workspace,
    count: usize,
    input: Vectors<'_, i8>,
    bias: Vectors<'_, i32>,
    weights: &[i8],
    out: &mut [F::Out],
    finish: &F,
) -> Result<(), ShapeError> {
    let Some(m) = out.len().checked_div(count) else {
        return if out.is_empty() {
            Ok(())
        } else {
            Err(ShapeError::Mismatch)
        };
    };
    let n = weights.len().checked_div(m).ok_or(ShapeError::Mismatch)?;
    if n == 0
        || n > MAX_FIELD
        || n * m != weights.len()
        || m * count != out.len()
        || !input.addressable(count, n)
        || !bias.addressable(count, m)
    {
        return Err(ShapeError::Mismatch);
    }
    let mut first = 0;
    while first < count {
        let start = first.min(count.saturating_sub(LANES));
        // With fewer vectors than lanes (`start` is 0) the last repeats.
        let vectors: [usize; LANES] = if count >= LANES {
            core::array::from_fn(|l| start + l)
        } else {
            core::array::from_fn(|l| l.min(count - 1))
        };
        let (Some(inputs), Some(biases)) = (input.lanes(&vectors, n), bias.lanes(&vectors, m))
        else {
            return Err(ShapeError::Mismatch);
        };
        work.load(&inputs);
        let rows = weights.chunks_exact(n);
        match work.rows(&inputs, n) {
            Kernel::Bytes(inputs) => bytes(inputs, rows, biases, out, start, finish),
            #[cfg(all(feature = "dsp", target_arch = "arm"))]
            Kernel::Widened(widened) => {
                let whole = out.get_mut(start * m..(start + LANES) * m);
                if !whole.is_some_and(|block| finish.widened(widened, weights, biases, block)) {
                    group(rows, biases, out, start, finish, |row, start| {
                        dsp::row(start, widened, row.as_chunks::<4>().0)
                    });
                }
            }
        }
        first = start + LANES;
    }
    Ok(())
}

/// [`group`] through [`dots`]: out of line, as on the DSP path only rows of no whole
/// four-byte groups take it.
#[inline(never)]
fn bytes<'w, F: Finish>(
    inputs: &[&[i8]; LANES],
    rows: impl Iterator<Item = &'w [i8]>,
    biases: [&[i32]; LANES],
    out: &mut [F::Out],
    start: usize,
    finish: &F,
) {
    group(rows, biases, out, start, finish, |row, start| {
        dots(inputs, row, start)
    });
}

/// [`rows`] for the group of vectors from `start` (the last repeated past the end), their
/// rows' sums by `kernel` from the biases `biases[l][c]`.
#[inline(always)]
fn group<'w, F: Finish>(
    rows: impl Iterator<Item = &'w [i8]>,
    biases: [&[i32]; LANES],
    out: &mut [F::Out],
    start: usize,
    finish: &F,
    kernel: impl Fn(&[i8], [i32; LANES]) -> [i32; LANES],
) {
    let m = biases[0].len();
    let [b0, b1, b2, b3] = biases;
    let starts = b0.iter().zip(b1).zip(b2).zip(b3);
    let rows = rows.zip(starts).enumerate();
    if let Some(block) = out.get_mut(start * m..(start + LANES) * m) {
        // Four whole vectors: each lane's outputs in a slice of its own.
        let (o0, rest) = block.split_at_mut(m);
        let (o1, rest) = rest.split_at_mut(m);
        let (o2, o3) = rest.split_at_mut(m);
        let lanes = o0.iter_mut().zip(o1).zip(o2).zip(o3);
        for ((c, (row, (((&s0, &s1), &s2), &s3))), (((a, b), c_), d)) in rows.zip(lanes) {
            finish.finish(c, kernel(row, [s0, s1, s2, s3]), [a, b, c_, d]);
        }
    } else {
        // Fewer vectors than lanes: each output is stored once per lane that holds it.
        for (c, (row, (((&s0, &s1), &s2), &s3))) in rows {
            let mut values = [F::Out::default(); LANES];
            let [a, b, c_, d] = &mut values;
            finish.finish(c, kernel(row, [s0, s1, s2, s3]), [a, b, c_, d]);
            for (o, v) in out[c..].iter_mut().step_by(m).zip(values) {
                *o = v;
            }
        }
    }
}

/// The shape of a [`conv1d`]: 1-D convolution over time within channel groups.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Conv {
    /// Input and output channels.
    pub channels: usize,
    /// Groups of `channels / groups` channels, each convolved on its own.
    pub groups: usize,
    /// Taps (odd).
    pub kernel: usize,
    /// Output frames are input frames `0, stride, 2·stride, …`.
    pub stride: usize,
}

/// A 1-D convolution over time within channel groups, group-major: `input` is `groups ×
/// frames × width` (each group's frames together, as the network keeps each body segment's
/// features), zero-padded by `kernel / 2` each side, so output frame `t` of a group sees its
/// input frames `t·stride − kernel/2 ..= t·stride + kernel/2`: one contiguous run of the
/// input, against which each output channel's weights (`[k][i]` for tap `k` and in-group
/// input `i`) are one row of a [`linear`] layer, biases `bias` (one per channel). `out` is
/// `groups × frames.div_ceil(stride) × width`, `width = channels / groups`.
///
/// # Errors
/// [`ShapeError::Mismatch`] if the lengths do not fit `shape`, the kernel is even or longer
/// than [`MAX_KERNEL`], or a channel's field (kernel × width) exceeds [`MAX_FIELD`].
pub fn conv1d(
    work: &mut Workspace,
    input: &[i8],
    shape: &Conv,
    layer: &Layer<'_>,
    bias: &[i32],
    out: &mut [i8],
) -> Result<(), ShapeError> {
    let Conv {
        channels,
        groups,
        kernel,
        stride,
    } = *shape;
    let width = channels.checked_div(groups).ok_or(ShapeError::Mismatch)?;
    let frames = input
        .len()
        .checked_div(channels)
        .ok_or(ShapeError::Mismatch)?;
    let outputs = frames.div_ceil(stride.max(1));
    let field = kernel * width;
    if stride == 0
        || kernel.is_multiple_of(2)
        || kernel > MAX_KERNEL
        || field > MAX_FIELD
        || width * groups != channels
        || frames * channels != input.len()
        || bias.len() != channels
        || layer.requant.len() != channels
        || layer.weights.len() != channels * field
        || out.len() != outputs * channels
    {
        return Err(ShapeError::Mismatch);
    }
    let half = kernel / 2;
    let first = |t: usize| (t * stride) as isize - half as isize;
    // Output frames whose fields overhang the input: the first `left`, and those from
    // `right` on (at most `half` each side, fewer with a stride); their fields are copied
    // with zeros where they overhang.
    let left = (0..outputs).take_while(|&t| first(t) < 0).count();
    let right = (left..outputs)
        .find(|&t| first(t) + kernel as isize > frames as isize)
        .unwrap_or(outputs);
    let mut padded = [[0i8; MAX_FIELD]; MAX_KERNEL - 1];
    let segments = input.chunks_exact(frames * width);
    for (g, (x, y)) in segments
        .zip(out.chunks_exact_mut(outputs * width))
        .enumerate()
    {
        let edge = (0..left).chain(right..outputs);
        for (taps, t) in padded.iter_mut().zip(edge) {
            for (k, tap) in taps[..field].chunks_exact_mut(width).enumerate() {
                let s = first(t) + k as isize;
                match usize::try_from(s).ok().filter(|&s| s < frames) {
                    Some(s) => tap.copy_from_slice(&x[s * width..(s + 1) * width]),
                    None => tap.fill(0),
                }
            }
        }
        let run = |t: usize| {
            if t < left {
                &padded[t][..field]
            } else if t >= right {
                &padded[left + t - right][..field]
            } else {
                let s = first(t) as usize;
                &x[s * width..(s + kernel) * width]
            }
        };
        let span = g * width..(g + 1) * width;
        let group = Layer {
            weights: &layer.weights[span.start * field..span.end * field],
            requant: &layer.requant[span.clone()],
            activation: layer.activation,
        };
        let bias = Vectors::Strided(&bias[span.clone()], 0);
        linear(work, outputs, Vectors::Each(&run), bias, &group, y)?;
    }
    Ok(())
}

/// Linear upsampling ×2 over time (frames-major, `channels` per frame), as burn's
/// `Interpolate1d` with `align_corners = false`: output `2i` is `¼ x[i−1] + ¾ x[i]`, output
/// `2i + 1` is `¾ x[i] + ¼ x[i+1]` (ends held), rounded half up. The scale is unchanged.
///
/// # Errors
/// [`ShapeError::Mismatch`] unless `out` is twice `input` and `input` whole frames.
pub fn upsample2(input: &[i8], channels: usize, out: &mut [i8]) -> Result<(), ShapeError> {
    let frames = input
        .len()
        .checked_div(channels)
        .ok_or(ShapeError::Mismatch)?;
    if frames * channels != input.len() || out.len() != 2 * input.len() || frames == 0 {
        return Err(ShapeError::Mismatch);
    }
    let frame = |t: usize| &input[t * channels..(t + 1) * channels];
    for (t, pair) in out.chunks_exact_mut(2 * channels).enumerate() {
        let (even, odd) = pair.split_at_mut(channels);
        let (before, after) = (frame(t.saturating_sub(1)), frame((t + 1).min(frames - 1)));
        let outs = even.iter_mut().zip(odd);
        for (((e, o), &b), (&x, &a)) in outs.zip(before).zip(frame(t).iter().zip(after)) {
            let x = 3 * i32::from(x);
            *e = ((i32::from(b) + x + 2) >> 2) as i8;
            *o = ((x + i32::from(a) + 2) >> 2) as i8;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_requant_is_its_factor_to_float_precision() {
        for factor in [1.0f32, 0.5, 0.75, 1e-3, 3.3e-5, 17.0, 0.999_999_9] {
            let r = Requant::new(factor).unwrap();
            assert!((r.factor() - factor).abs() <= factor * 1e-7, "{factor}");
        }
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e-12, 1e12] {
            assert_eq!(Requant::new(bad), None, "{bad}");
        }
    }

    #[test]
    fn the_leaky_constant_is_its_slope_and_negatives_shrink() {
        // The exact 0.2 (the f32 0.2 is 0.2000000030).
        assert!((f64::from(LEAKY.multiplier) * libm::exp2(-33.0) - 0.2).abs() < 1e-10);
        let one = Requant::new(1.0).unwrap();
        assert_eq!(Activation::Leaky.apply(one, -50), -10);
        assert_eq!(Activation::Leaky.apply(one, 50), 50);
        assert_eq!(Activation::Identity.apply(one, -500), -128);
    }

    /// A float convolution with the same (group-major) layout, for comparison.
    fn conv_reference(
        x: &[f32],
        channels: usize,
        groups: usize,
        kernel: usize,
        stride: usize,
        w: &[f32],
        b: &[f32],
    ) -> Vec<f32> {
        let (width, frames) = (channels / groups, x.len() / channels);
        let outputs = frames.div_ceil(stride);
        let mut out = vec![0.0; outputs * channels];
        for t in 0..outputs {
            for c in 0..channels {
                let mut sum = b[c];
                for k in 0..kernel {
                    let s = (t * stride + k) as isize - (kernel / 2) as isize;
                    if s < 0 || s >= frames as isize {
                        continue;
                    }
                    let g = c / width;
                    for i in 0..width {
                        sum += w[(c * kernel + k) * width + i]
                            * x[(g * frames + s as usize) * width + i];
                    }
                }
                out[(c / width * outputs + t) * width + c % width] = sum;
            }
        }
        out
    }

    #[test]
    fn a_grouped_strided_convolution_matches_the_float_one_within_a_step() {
        let (channels, groups, kernel, frames) = (8, 2, 3, 9);
        let width = channels / groups;
        let wave = |k: usize, f: f32| libm::sinf(k as f32 * f);
        let x: Vec<f32> = (0..frames * channels).map(|k| wave(k, 0.7)).collect();
        let w: Vec<f32> = (0..channels * kernel * width)
            .map(|k| 0.3 * wave(k, 1.3))
            .collect();
        let b: Vec<f32> = (0..channels).map(|c| 0.05 * c as f32).collect();
        let (sx, sy) = (1.0 / 127.0, 2.0 / 127.0);
        let sw: Vec<f32> = (0..channels)
            .map(|c| {
                w[c * kernel * width..(c + 1) * kernel * width]
                    .iter()
                    .fold(0.0f32, |m, v| m.max(v.abs()))
                    / 127.0
            })
            .collect();
        let wq: Vec<i8> = w
            .iter()
            .enumerate()
            .map(|(k, &v)| quantize(v, sw[k / (kernel * width)]))
            .collect();
        let bq: Vec<i32> = (0..channels)
            .map(|c| libm::roundf(b[c] / (sx * sw[c])) as i32)
            .collect();
        let rq: Vec<Requant> = sw
            .iter()
            .map(|&s| Requant::new(sx * s / sy).unwrap())
            .collect();
        let xq: Vec<i8> = x.iter().map(|&v| quantize(v, sx)).collect();
        let layer = Layer {
            weights: &wq,
            requant: &rq,
            activation: Activation::Identity,
        };
        for stride in [1, 2] {
            let mut out = vec![0i8; frames.div_ceil(stride) * channels];
            let shape = Conv {
                channels,
                groups,
                kernel,
                stride,
            };
            conv1d(&mut Workspace::new(), &xq, &shape, &layer, &bq, &mut out).unwrap();
            let real = conv_reference(&x, channels, groups, kernel, stride, &w, &b);
            for (k, (&q, &r)) in out.iter().zip(&real).enumerate() {
                assert!(
                    (f32::from(q) * sy - r).abs() <= 2.0 * sy,
                    "stride {stride} output {k}: {} vs {r}",
                    f32::from(q) * sy
                );
            }
        }
        let mut out = vec![0i8; frames * channels];
        let shape = Conv {
            channels,
            groups: 3,
            kernel,
            stride: 1,
        };
        assert_eq!(
            conv1d(&mut Workspace::new(), &xq, &shape, &layer, &bq, &mut out),
            Err(ShapeError::Mismatch)
        );
    }

    #[test]
    fn upsampling_interpolates_between_neighbours_and_holds_the_ends() {
        let x = [0i8, 40, -40];
        let mut out = [0i8; 6];
        upsample2(&x, 1, &mut out).unwrap();
        assert_eq!(out, [0, 10, 30, 20, -20, -40]);
        assert_eq!(upsample2(&x, 2, &mut out), Err(ShapeError::Mismatch));
    }

    #[test]
    fn requantization_rounds_ties_up_and_saturates() {
        let half = Requant::new(0.5).unwrap();
        assert_eq!([3, -3, 5, -5].map(|a| half.scale(a)), [2, -1, 3, -2]);
        let eighth = Requant::new(0.125).unwrap();
        assert_eq!(
            [4, -4, 12, -12, 3].map(|a| eighth.scale(a)),
            [1, 0, 2, -1, 0]
        );
        assert_eq!(half.apply(1000), 127);
        assert_eq!(half.apply(-1000), -128);
        assert_eq!([quantize(-200.0, 1.0), quantize(200.0, 1.0)], [-128, 127]);
    }

    proptest! {
        #[test]
        fn requantization_is_the_rounded_product(acc in any::<i32>(), factor in 1e-6f32..1e6) {
            let r = Requant::new(factor).unwrap();
            let exact = f64::from(acc) * f64::from(r.factor());
            prop_assert!((f64::from(r.scale(acc)) - exact.clamp(f64::from(i32::MIN), f64::from(i32::MAX))).abs() <= 0.5 + 1e-9 * exact.abs());
        }

        #[test]
        fn a_small_requantization_rounds_as_the_general_one(acc in any::<i32>(), factor in 1e-7f32..0.3) {
            let r = Requant::new(factor).unwrap();
            match r.small() {
                Some(small) => prop_assert_eq!(small.scale(acc), r.scale(acc)),
                None => prop_assert!(factor >= 0.25),
            }
            prop_assert_eq!(LEAKY_SMALL.scale(acc), LEAKY.scale(acc));
        }

        #[test]
        fn dot_is_the_sum_of_products(pairs in proptest::collection::vec((any::<i8>(), any::<i8>()), 0..70)) {
            let (a, b): (Vec<i8>, Vec<i8>) = pairs.into_iter().unzip();
            let naive: i32 = a.iter().zip(&b).map(|(&x, &y)| i32::from(x) * i32::from(y)).sum();
            prop_assert_eq!(dot(&a, &b), naive);
            prop_assert_eq!(dot(&a, &b[..b.len() / 2]), dot(&a[..b.len() / 2], &b[..b.len() / 2]));
        }

        /// Vectors go through the rows four at a time (a short last group, widths that are no
        /// multiple of four, biases at the ends of `i32`): each sum is still its own dot
        /// product plus its bias (wrapping at the ends of `i32`).
        #[test]
        fn batched_rows_are_each_vectors_dot_products(
            (n, m, count) in (1..40usize, 1..6usize, 1..10usize),
            seed in any::<u64>(),
        ) {
            let mut state = seed;
            let mut next = move || {
                state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                (state >> 56) as i8
            };
            let weights: Vec<i8> = (0..m * n).map(|_| next()).collect();
            let inputs: Vec<i8> = (0..count * n).map(|_| next()).collect();
            let ends = [i32::MAX, i32::MIN, 0];
            let biases: Vec<i32> = (0..count * m)
                .map(|k| if k % 5 == 0 { ends[k % 3] } else { i32::from(next()) * 1000 })
                .collect();
            let mut out = vec![0i32; count * m];
            let input = |i: usize| &inputs[i * n..(i + 1) * n];
            let bias = |i: usize| &biases[i * m..(i + 1) * m];
            let (inputs, biases) = (Vectors::Strided(&inputs, n), Vectors::Strided(&biases, m));
            accumulate(&mut Workspace::new(), count, inputs, biases, &weights, &mut out).unwrap();
            for i in 0..count {
                for c in 0..m {
                    let expected = dot(&weights[c * n..(c + 1) * n], input(i)).wrapping_add(bias(i)[c]);
                    prop_assert_eq!(out[i * m + c], expected, "vector {} output {}", i, c);
                }
            }
            let requant = vec![Requant::new(0.01).unwrap(); m];
            let layer = Layer { weights: &weights, requant: &requant, activation: Activation::Leaky };
            let mut q = vec![0i8; count * m];
            linear(&mut Workspace::new(), count, Vectors::Each(&input), Vectors::Each(&bias), &layer, &mut q).unwrap();
            for (k, (&q, &acc)) in q.iter().zip(&out).enumerate() {
                prop_assert_eq!(q, Activation::Leaky.apply(requant[k % m], acc));
            }
        }
    }

    #[test]
    fn linear_matches_the_float_layer_within_a_step() {
        // y = W x + b in reals, quantized in and out.
        let (sx, sy) = (0.02f32, 0.05f32);
        let w = [[0.5f32, -0.25, 0.125], [-1.0, 0.75, 0.3]];
        let b = [0.1f32, -0.2];
        let x = [0.4f32, -1.2, 2.0];
        let sw: Vec<f32> = w
            .iter()
            .map(|row| row.iter().fold(0.0f32, |m, v| m.max(v.abs())) / 127.0)
            .collect();
        let wq: Vec<i8> = w
            .iter()
            .zip(&sw)
            .flat_map(|(row, &s)| row.iter().map(move |&v| quantize(v, s)))
            .collect();
        let bq: Vec<i32> = b
            .iter()
            .zip(&sw)
            .map(|(&v, &s)| libm::roundf(v / (sx * s)) as i32)
            .collect();
        let rq: Vec<Requant> = sw
            .iter()
            .map(|&s| Requant::new(sx * s / sy).unwrap())
            .collect();
        let xq = x.map(|v| quantize(v, sx));
        let mut out = [0i8; 2];
        let layer = Layer {
            weights: &wq,
            requant: &rq,
            activation: Activation::Identity,
        };
        let (xs, bs) = (Vectors::Strided(&xq, 0), Vectors::Strided(&bq, 0));
        linear(&mut Workspace::new(), 1, xs, bs, &layer, &mut out).unwrap();
        for c in 0..2 {
            let real: f32 = w[c].iter().zip(&x).map(|(a, b)| a * b).sum::<f32>() + b[c];
            assert!(
                (f32::from(out[c]) * sy - real).abs() <= 1.5 * sy,
                "{c}: {} vs {real}",
                f32::from(out[c]) * sy
            );
        }
        let short = Layer {
            weights: &wq[1..],
            ..layer
        };
        assert_eq!(
            linear(&mut Workspace::new(), 1, xs, bs, &short, &mut out),
            Err(ShapeError::Mismatch)
        );
        assert_eq!(
            linear(
                &mut Workspace::new(),
                1,
                Vectors::Strided(&xq[1..], 0),
                bs,
                &layer,
                &mut out
            ),
            Err(ShapeError::Mismatch)
        );
        assert_eq!(
            linear(&mut Workspace::new(), 2, xs, bs, &layer, &mut out),
            Err(ShapeError::Mismatch)
        );
    }
}
