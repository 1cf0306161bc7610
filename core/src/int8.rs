//! Integer arithmetic of the quantized retargeter: symmetric int8 values with `f32` scales
//! (`real = scale · q`, `q` in −127..=127), int32 accumulation and fixed-point
//! requantization.
//!
//! A layer `y = W x + b` with input scale `s_x`, per-output-channel weight scales `s_w[c]`
//! and output scale `s_y` accumulates `Σ W_q x_q + b_q` in int32 (`b_q = b / (s_x s_w[c])`)
//! and takes the accumulator to int8 with [`Requant`] of `s_x s_w[c] / s_y`.

/// A positive real factor as `multiplier · 2^(shift − 31)`, `multiplier` in `[2^30, 2^31)`:
/// the exact integer form of a rescaling, the same on every machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Requant {
    multiplier: i32,
    shift: i8,
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
            shift: shift as i8,
        })
    }

    /// The factor it stands for.
    pub fn factor(self) -> f32 {
        (f64::from(self.multiplier) * libm::exp2(f64::from(self.shift) - 31.0)) as f32
    }

    /// `round(acc · factor)`, ties toward +∞, saturated to `i32`.
    #[inline]
    pub fn scale(self, acc: i32) -> i32 {
        self.rounded(acc)
            .clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32
    }

    /// `acc · factor` rounded as [`Requant::scale`] rounds, as a saturated int8 value.
    #[inline]
    pub fn apply(self, acc: i32) -> i8 {
        self.rounded(acc).clamp(-i64::from(MAX), i64::from(MAX)) as i8
    }

    #[inline(always)]
    fn rounded(self, acc: i32) -> i64 {
        let right = 31 - i32::from(self.shift);
        (i64::from(acc) * i64::from(self.multiplier) + (1i64 << (right - 1))) >> right
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

/// The int8 value nearest `real / scale`, saturated.
pub fn quantize(real: f32, scale: f32) -> i8 {
    libm::roundf(real / scale).clamp(-MAX as f32, MAX as f32) as i8
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

/// [`dot`] of two rows with one `x`: `(Σ r0[k] x[k], Σ r1[k] x[k])` over the shortest. On
/// the DSP path each four bytes of `x` are widened once for both rows.
#[inline]
pub fn dot2(r0: &[i8], r1: &[i8], x: &[i8]) -> (i32, i32) {
    let n = r0.len().min(r1.len()).min(x.len());
    let (x4, x_rest) = x[..n].as_chunks::<4>();
    let (a4, a_rest) = r0[..n].as_chunks::<4>();
    let (b4, b_rest) = r1[..n].as_chunks::<4>();
    let tail = |r: &[i8]| -> i32 {
        r.iter()
            .zip(x_rest)
            .map(|(&w, &v)| i32::from(w) * i32::from(v))
            .sum()
    };
    let (s0, s1) = dot4s2(a4, b4, x4);
    (s0 + tail(a_rest), s1 + tail(b_rest))
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

/// `Σ` over four-byte groups, four lanes at a time.
#[cfg(not(all(feature = "dsp", target_arch = "arm")))]
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

/// `Σ` over four-byte groups with the DSP extension: each group one 32-bit load per side,
/// two `SXTB16` per side (bytes 0, 2 and 1, 3 as 16-bit lanes) and two `SMLAD` (two
/// 16-bit products added per instruction), as CMSIS-NN's kernels do. Integer arithmetic
/// throughout, so the sum is the portable version's exactly.
#[cfg(all(feature = "dsp", target_arch = "arm"))]
#[inline(always)]
fn dot4s(a: &[[i8; 4]], b: &[[i8; 4]]) -> i32 {
    let word = |x: &[i8; 4]| u32::from_le_bytes(x.map(|v| v as u8));
    let mut acc = 0i32;
    for (x, y) in a.iter().zip(b) {
        acc = dsp::dot4(acc, word(x), word(y));
    }
    acc
}

#[cfg(all(feature = "dsp", target_arch = "arm"))]
#[allow(unsafe_code)]
mod dsp {
    /// `acc` plus the four products of the int8 lanes of `a` and `b`.
    #[inline(always)]
    pub(super) fn dot4(mut acc: i32, a: u32, b: u32) -> i32 {
        // SAFETY: register-only instructions (SXTB16, SMLAD) of the ARMv7E-M DSP extension,
        // which the `dsp` feature declares the target has: no memory, no stack; SMLAD may set
        // the Q flag on overflow, which nothing reads (`preserves_flags` is not claimed).
        unsafe {
            core::arch::asm!(
                "sxtb16 {ae}, {a}",
                "sxtb16 {ao}, {a}, ror #8",
                "sxtb16 {be}, {b}",
                "sxtb16 {bo}, {b}, ror #8",
                "smlad {acc}, {ae}, {be}, {acc}",
                "smlad {acc}, {ao}, {bo}, {acc}",
                a = in(reg) a,
                b = in(reg) b,
                acc = inout(reg) acc,
                ae = out(reg) _,
                ao = out(reg) _,
                be = out(reg) _,
                bo = out(reg) _,
                options(pure, nomem, nostack)
            );
        }
        acc
    }

    /// [`dot4`] of two weight words `w0`, `w1` with one input word `x`, widened once.
    #[inline(always)]
    pub(super) fn dot4x2(mut s0: i32, mut s1: i32, x: u32, w0: u32, w1: u32) -> (i32, i32) {
        // SAFETY: as in `dot4`: register-only DSP instructions, no memory, no stack.
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

/// Why a layer could not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ShapeError {
    /// The slices do not have the lengths the layer's sizes give.
    Mismatch,
}

/// A fully connected layer: `out[c] = requant[c](Σ_k weights[c·n + k] · input[k] + bias[c])`
/// for `n = input.len()` and `c` over `out`.
///
/// # Errors
/// [`ShapeError::Mismatch`] unless `weights` is `out.len() × input.len()` and `bias` and
/// `requant` have one entry per output.
pub fn linear(
    input: &[i8],
    weights: &[i8],
    bias: &[i32],
    requant: &[Requant],
    out: &mut [i8],
) -> Result<(), ShapeError> {
    let n = input.len();
    if weights.len() != out.len() * n || bias.len() != out.len() || requant.len() != out.len() {
        return Err(ShapeError::Mismatch);
    }
    let rows = weights.chunks_exact(n.max(1));
    let mut outputs = out.iter_mut().zip(rows).zip(bias.iter().zip(requant));
    while let Some(((o0, r0), (&b0, &q0))) = outputs.next() {
        match outputs.next() {
            Some(((o1, r1), (&b1, &q1))) => {
                let (s0, s1) = dot2(r0, r1, input);
                *o0 = q0.apply(s0 + b0);
                *o1 = q1.apply(s1 + b1);
            }
            None => *o0 = q0.apply(dot(r0, input) + b0),
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
    fn requantization_rounds_ties_up_and_saturates() {
        let half = Requant::new(0.5).unwrap();
        assert_eq!([3, -3, 5, -5].map(|a| half.scale(a)), [2, -1, 3, -2]);
        assert_eq!(half.apply(1000), 127);
        assert_eq!(half.apply(-1000), -127);
    }

    proptest! {
        #[test]
        fn requantization_is_the_rounded_product(acc in -1_000_000i32..1_000_000, factor in 1e-4f32..4.0) {
            let r = Requant::new(factor).unwrap();
            let exact = f64::from(acc) * f64::from(r.factor());
            prop_assert!((f64::from(r.scale(acc)) - exact).abs() <= 0.5 + 1e-6);
        }

        #[test]
        fn dot_is_the_sum_of_products(pairs in proptest::collection::vec((any::<i8>(), any::<i8>()), 0..70)) {
            let (a, b): (Vec<i8>, Vec<i8>) = pairs.into_iter().unzip();
            let naive: i32 = a.iter().zip(&b).map(|(&x, &y)| i32::from(x) * i32::from(y)).sum();
            prop_assert_eq!(dot(&a, &b), naive);
            prop_assert_eq!(dot(&a, &b[..b.len() / 2]), dot(&a[..b.len() / 2], &b[..b.len() / 2]));
            let reversed: Vec<i8> = b.iter().rev().copied().collect();
            prop_assert_eq!(dot2(&a, &reversed, &b), (dot(&a, &b), dot(&reversed, &b)));
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
        linear(&xq, &wq, &bq, &rq, &mut out).unwrap();
        for c in 0..2 {
            let real: f32 = w[c].iter().zip(&x).map(|(a, b)| a * b).sum::<f32>() + b[c];
            assert!(
                (f32::from(out[c]) * sy - real).abs() <= 1.5 * sy,
                "{c}: {} vs {real}",
                f32::from(out[c]) * sy
            );
        }
        assert_eq!(
            linear(&xq, &wq[1..], &bq, &rq, &mut out),
            Err(ShapeError::Mismatch)
        );
    }
}
