//! Integer arithmetic of the quantized retargeter: symmetric int8 values with `f32` scales
//! (`real = scale · q`, `q` in −127..=127), int32 accumulation and fixed-point
//! requantization.
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

/// Largest magnitude of a quantized value (−128 is never produced, so negation is exact).
pub const MAX: i32 = 127;
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
        self.scale(acc).clamp(-MAX, MAX) as i8
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
    ((v + half) as i32).clamp(-MAX, MAX) as i8
}

/// `Σ a[k] · b[k]` over the shorter of the two.
#[inline]
pub fn dot(a: &[i8], b: &[i8]) -> i32 {
    let n = a.len().min(b.len());
    let (a4, a_rest) = a[..n].as_chunks::<4>();
    let (b4, b_rest) = b[..n].as_chunks::<4>();
    let tail: i32 = a_rest
        .iter()
        .zip(b_rest)
        .map(|(&x, &y)| i32::from(x) * i32::from(y))
        .sum();
    tail + dot4s(a4, b4)
}

/// Both rows' sums over four-byte groups.
#[cfg(not(all(feature = "dsp", target_arch = "arm")))]
#[inline(always)]
fn dot4s2(a: &[[i8; 4]], b: &[[i8; 4]], x: &[[i8; 4]]) -> (i32, i32) {
    (dot4s(a, x), dot4s(b, x))
}

/// Both rows' sums over four-byte groups, `x` widened once per group.
#[cfg(all(feature = "dsp", target_arch = "arm"))]
#[inline(always)]
fn dot4s2(a: &[[i8; 4]], b: &[[i8; 4]], x: &[[i8; 4]]) -> (i32, i32) {
    let word = |v: &[i8; 4]| u32::from_le_bytes(v.map(|b| b as u8));
    let (mut s0, mut s1) = (0i32, 0i32);
    for ((p, q), v) in a.iter().zip(b).zip(x) {
        (s0, s1) = dsp::dot4x2(s0, s1, word(v), word(p), word(q));
    }
    (s0, s1)
}

/// `Σ` over four-byte groups, four lanes at a time (plain code on every target: a single
/// row is the rare odd row of a layer; the DSP path is [`dot4s2`]'s).
#[inline(always)]
fn dot4s(a: &[[i8; 4]], b: &[[i8; 4]]) -> i32 {
    let mut s = [0i32; 4];
    for (x, y) in a.iter().zip(b) {
        for k in 0..4 {
            s[k] += i32::from(x[k]) * i32::from(y[k]);
        }
    }
    s.iter().sum()
}

#[cfg(all(feature = "dsp", target_arch = "arm"))]
#[allow(unsafe_code)]
mod dsp {
    /// `s0` and `s1` plus the four products of the int8 lanes of `x` with those of `w0` and
    /// of `w1`: `x` widened once (two `SXTB16`: bytes 0, 2 and 1, 3 as 16-bit lanes), each
    /// weight word widened and added two products per `SMLAD`, as CMSIS-NN's kernels do.
    #[inline(always)]
    pub(super) fn dot4x2(mut s0: i32, mut s1: i32, x: u32, w0: u32, w1: u32) -> (i32, i32) {
        // SAFETY: register-only instructions (SXTB16, SMLAD) of the ARMv7E-M DSP extension,
        // which the `dsp` feature declares the target has: no memory, no stack; SMLAD may set
        // the Q flag on overflow, which nothing reads (`preserves_flags` is not claimed).
        unsafe {
            core::arch::asm!(
                "sxtb16 {xe}, {x}",
                "sxtb16 {xo}, {x}, ror #8",
                "sxtb16 {te}, {w0}",
                "sxtb16 {to}, {w0}, ror #8",
                "smlad {s0}, {xe}, {te}, {s0}",
                "smlad {s0}, {xo}, {to}, {s0}",
                "sxtb16 {te}, {w1}",
                "sxtb16 {to}, {w1}, ror #8",
                "smlad {s1}, {xe}, {te}, {s1}",
                "smlad {s1}, {xo}, {to}, {s1}",
                x = in(reg) x,
                w0 = in(reg) w0,
                w1 = in(reg) w1,
                s0 = inout(reg) s0,
                s1 = inout(reg) s1,
                xe = out(reg) _,
                xo = out(reg) _,
                te = out(reg) _,
                to = out(reg) _,
                options(pure, nomem, nostack)
            );
        }
        (s0, s1)
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

/// Largest receptive field of one output channel of [`conv1d`] (kernel × inputs per group).
pub const MAX_FIELD: usize = 512;

/// Negative slope of the leaky ReLU.
pub const LEAKY_SLOPE: f32 = 0.2;
/// [`LEAKY_SLOPE`] as a [`Requant`]: round(0.8 · 2^31) · 2^-33, the exact 0.2 to 10 digits.
const LEAKY: Requant = Requant {
    multiplier: 1_717_986_918,
    shift: -2,
};

impl Activation {
    /// `acc` rescaled by `requant`, activated and saturated.
    #[inline]
    pub fn apply(self, requant: Requant, acc: i32) -> i8 {
        let v = requant.scale(acc);
        let v = match self {
            Activation::Leaky if v < 0 => LEAKY.scale(v),
            _ => v,
        };
        v.clamp(-MAX, MAX) as i8
    }
}

/// Why a layer could not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ShapeError {
    /// The slices do not have the lengths the layer's sizes give.
    Mismatch,
}

/// A layer's parameters: int8 weights (one row per output channel), int32 biases in the
/// accumulator's scale, and each output channel's requantization.
#[derive(Clone, Copy, Debug)]
pub struct Layer<'w> {
    /// `outputs × inputs` (for a convolution `outputs × kernel × inputs per group`).
    pub weights: &'w [i8],
    /// One per output channel.
    pub bias: &'w [i32],
    /// One per output channel: accumulator scale over output scale.
    pub requant: &'w [Requant],
    /// Applied after rescaling.
    pub activation: Activation,
}

impl Layer<'_> {
    fn outputs(&self) -> usize {
        self.bias.len()
    }
}

/// A fully connected layer: `out[c] = act(requant[c](Σ_k weights[c·n + k] · input[k] +
/// bias[c]))` for `n = input.len()` and `c` over `out`.
///
/// # Errors
/// [`ShapeError::Mismatch`] unless `weights` is `out.len() × input.len()` and `bias` and
/// `requant` have one entry per output.
#[inline]
pub fn linear(input: &[i8], layer: &Layer<'_>, out: &mut [i8]) -> Result<(), ShapeError> {
    if layer.requant.len() != out.len() {
        return Err(ShapeError::Mismatch);
    }
    let (outputs, activation) = (out.len(), layer.activation);
    let sinks = out.iter_mut().zip(layer.requant);
    sums(
        input,
        layer.weights,
        layer.bias,
        outputs,
        sinks,
        |acc, (o, &q)| {
            *o = activation.apply(q, acc);
        },
    )
}

/// The accumulators of a fully connected layer, not requantized: `out[c] = Σ_k
/// weights[c·n + k] · input[k] + bias[c]`, for a layer whose outputs go on in `f32`.
///
/// # Errors
/// [`ShapeError::Mismatch`] unless `weights` is `out.len() × input.len()` and `bias` has one
/// entry per output.
#[inline]
pub fn accumulate(
    input: &[i8],
    weights: &[i8],
    bias: &[i32],
    out: &mut [i32],
) -> Result<(), ShapeError> {
    let outputs = out.len();
    sums(input, weights, bias, outputs, out.iter_mut(), |acc, o| {
        *o = acc
    })
}

/// Calls `f(Σ_k weights[c·n + k] · input[k] + bias[c], sink)` for each row `c` of `outputs`
/// and its sink. With `n` a multiple of four (every layer of the network) rows go two at a
/// time through whole four-byte groups ([`dot4s2`]); otherwise one at a time through [`dot`].
/// The sum cannot overflow (127² · [`MAX_FIELD`] is far below `i32::MAX`); adding the bias
/// saturates.
#[inline(always)]
fn sums<S>(
    input: &[i8],
    weights: &[i8],
    bias: &[i32],
    outputs: usize,
    mut sinks: impl Iterator<Item = S>,
    mut f: impl FnMut(i32, S),
) -> Result<(), ShapeError> {
    let n = input.len();
    if weights.len() != outputs * n || bias.len() != outputs || n == 0 {
        return Err(ShapeError::Mismatch);
    }
    let (x, x_rest) = input.as_chunks::<4>();
    let (w, _) = weights.as_chunks::<4>();
    if !x_rest.is_empty() {
        for ((row, &b), sink) in weights.chunks_exact(n).zip(bias).zip(sinks) {
            f(dot(row, input).saturating_add(b), sink);
        }
        return Ok(());
    }
    let mut rows = w.chunks_exact(x.len()).zip(bias);
    while let (Some((r0, &b0)), Some(s0)) = (rows.next(), sinks.next()) {
        match (rows.next(), sinks.next()) {
            (Some((r1, &b1)), Some(s1)) => {
                let (a0, a1) = dot4s2(r0, r1, x);
                f(a0.saturating_add(b0), s0);
                f(a1.saturating_add(b1), s1);
            }
            _ => f(dot4s(r0, x).saturating_add(b0), s0),
        }
    }
    Ok(())
}

/// A 1-D convolution over time within channel groups, group-major: `input` is `groups ×
/// frames × width` (each group's frames together, as the network keeps each body segment's
/// features), zero-padded by `kernel / 2` each side, so output frame `t` of a group sees its
/// input frames `t·stride − kernel/2 ..= t·stride + kernel/2`: one contiguous run of the
/// input, against which each output channel's weights (`[k][i]` for tap `k` and in-group
/// input `i`) are one row of a linear layer. `out` is `groups × frames.div_ceil(stride) ×
/// width`; `channels = groups × width`.
///
/// # Errors
/// [`ShapeError::Mismatch`] if the lengths do not fit `channels`, `groups` and `kernel`, or a
/// channel's field exceeds [`MAX_FIELD`].
pub fn conv1d(
    input: &[i8],
    channels: usize,
    groups: usize,
    kernel: usize,
    stride: usize,
    layer: &Layer<'_>,
    out: &mut [i8],
) -> Result<(), ShapeError> {
    let width = channels.checked_div(groups).ok_or(ShapeError::Mismatch)?;
    let frames = input
        .len()
        .checked_div(channels)
        .ok_or(ShapeError::Mismatch)?;
    let outputs = frames.div_ceil(stride.max(1));
    if stride == 0
        || kernel.is_multiple_of(2)
        || width * groups != channels
        || frames * channels != input.len()
        || layer.outputs() != channels
        || layer.requant.len() != channels
        || layer.weights.len() != channels * kernel * width
        || out.len() != outputs * channels
    {
        return Err(ShapeError::Mismatch);
    }
    let half = kernel / 2;
    let field = kernel * width;
    // The field of an output frame near either end, zeros where it overhangs.
    let mut padded = [0i8; MAX_FIELD];
    let padded = padded.get_mut(..field).ok_or(ShapeError::Mismatch)?;
    let segments = input.chunks_exact(frames * width);
    for (g, (x, y)) in segments
        .zip(out.chunks_exact_mut(outputs * width))
        .enumerate()
    {
        let span = g * width..(g + 1) * width;
        let group = Layer {
            weights: &layer.weights[span.start * field..span.end * field],
            bias: &layer.bias[span.clone()],
            requant: &layer.requant[span],
            activation: layer.activation,
        };
        for (t, row) in y.chunks_exact_mut(width).enumerate() {
            let first = (t * stride) as isize - half as isize;
            let inside = first >= 0 && first as usize + kernel <= frames;
            let run = if inside {
                &x[first as usize * width..(first as usize + kernel) * width]
            } else {
                for (k, taps) in padded.chunks_exact_mut(width).enumerate() {
                    let s = first + k as isize;
                    match usize::try_from(s).ok().filter(|&s| s < frames) {
                        Some(s) => taps.copy_from_slice(&x[s * width..(s + 1) * width]),
                        None => taps.fill(0),
                    }
                }
                &*padded
            };
            linear(run, &group, row)?;
        }
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
    let at = |t: usize, c: usize| i32::from(input[t * channels + c]);
    for t in 0..frames {
        let (before, after) = (t.saturating_sub(1), (t + 1).min(frames - 1));
        for c in 0..channels {
            let x = 3 * at(t, c);
            out[2 * t * channels + c] = ((at(before, c) + x + 2) >> 2) as i8;
            out[(2 * t + 1) * channels + c] = ((x + at(after, c) + 2) >> 2) as i8;
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
        assert_eq!(Activation::Identity.apply(one, -500), -127);
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
        for stride in [1, 2] {
            let mut out = vec![0i8; frames.div_ceil(stride) * channels];
            let layer = Layer {
                weights: &wq,
                bias: &bq,
                requant: &rq,
                activation: Activation::Identity,
            };
            conv1d(&xq, channels, groups, kernel, stride, &layer, &mut out).unwrap();
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
        let layer = Layer {
            weights: &wq,
            bias: &bq,
            requant: &rq,
            activation: Activation::Identity,
        };
        assert_eq!(
            conv1d(&xq, channels, 3, kernel, 1, &layer, &mut out),
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
        assert_eq!(half.apply(-1000), -127);
    }

    proptest! {
        #[test]
        fn requantization_is_the_rounded_product(acc in any::<i32>(), factor in 1e-6f32..1e6) {
            let r = Requant::new(factor).unwrap();
            let exact = f64::from(acc) * f64::from(r.factor());
            prop_assert!((f64::from(r.scale(acc)) - exact.clamp(f64::from(i32::MIN), f64::from(i32::MAX))).abs() <= 0.5 + 1e-9 * exact.abs());
        }

        #[test]
        fn dot_is_the_sum_of_products(pairs in proptest::collection::vec((any::<i8>(), any::<i8>()), 0..70)) {
            let (a, b): (Vec<i8>, Vec<i8>) = pairs.into_iter().unzip();
            let naive: i32 = a.iter().zip(&b).map(|(&x, &y)| i32::from(x) * i32::from(y)).sum();
            prop_assert_eq!(dot(&a, &b), naive);
            prop_assert_eq!(dot(&a, &b[..b.len() / 2]), dot(&a[..b.len() / 2], &b[..b.len() / 2]));
            // Two rows at a time (lengths a multiple of four) or one (any other) add up alike.
            let reversed: Vec<i8> = b.iter().rev().copied().collect();
            let rows = [a.clone(), reversed.clone(), a.clone()].concat();
            let mut out = [0i32; 3];
            if !b.is_empty() {
                accumulate(&b, &rows, &[1, -1, i32::MAX], &mut out).unwrap();
                let expected = [dot(&a, &b) + 1, dot(&reversed, &b) - 1, dot(&a, &b).saturating_add(i32::MAX)];
                prop_assert_eq!(out, expected);
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
            bias: &bq,
            requant: &rq,
            activation: Activation::Identity,
        };
        linear(&xq, &layer, &mut out).unwrap();
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
        assert_eq!(linear(&xq, &short, &mut out), Err(ShapeError::Mismatch));
    }
}
