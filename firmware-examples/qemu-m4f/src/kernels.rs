//! Instructions per multiply-accumulate of the int8 kernels, on the committed network's own
//! layers: its widest convolution and a joint layer.

use crate::count;
use posecoach_core::int8::{self, Activation, Layer};
use posecoach_core::weights::{Dense, Weights};

/// Deterministic bytes: a 32-bit LCG's high byte.
fn bytes<const N: usize>(seed: u32) -> [i8; N] {
    let mut out = [0i8; N];
    let mut state = seed;
    for o in &mut out {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        *o = (state >> 24) as i8;
    }
    out
}

/// The decoder's last convolution: six segments of 16 channels, kernel 3, 64 frames.
const CHANNELS: usize = 96;
const GROUPS: usize = 6;
const KERNEL: usize = 3;
const FRAMES: usize = 64;

/// Instructions per MAC of `int8::conv1d` (stride 1) on `up_2`, times 100.
pub fn conv_per_mac_centi(weights: &Weights<'_>) -> Result<u64, &'static str> {
    let t = weights.layer(Dense::Up2);
    if t.weights.len() != CHANNELS * KERNEL * CHANNELS / GROUPS {
        return Err("up_2 is not the benchmark's size");
    }
    let input = core::hint::black_box(bytes::<{ CHANNELS * FRAMES }>(5));
    let mut out = [0i8; CHANNELS * FRAMES];
    let layer = Layer {
        weights: t.weights,
        bias: t.bias,
        requant: t.requant,
        activation: Activation::Leaky,
    };
    let start = count::now();
    int8::conv1d(&input, CHANNELS, GROUPS, KERNEL, 1, &layer, &mut out).map_err(|_| "shape")?;
    let spent = count::now() - start;
    let macs = (FRAMES * CHANNELS * KERNEL * CHANNELS / GROUPS) as u64;
    // Interior frames see every tap; the two end frames one tap fewer.
    let macs = macs - 2 * (CHANNELS * CHANNELS / GROUPS) as u64;
    Ok(spent * 100 / macs)
}

/// Instructions per MAC of `int8::linear` on the joint decoder's hidden layer (16 × 16, as the
/// network runs it once per joint and frame), times 100, after checking its outputs against a
/// plain scalar loop's (the DSP path must add up exactly as the portable one).
pub fn linear_per_mac_centi(weights: &Weights<'_>) -> Result<u64, &'static str> {
    const N: usize = 16;
    let t = weights.layer(Dense::DecoderFeatures);
    if t.weights.len() != N * N {
        return Err("decoder.features is not the benchmark's size");
    }
    let input = core::hint::black_box(bytes::<N>(3));
    let mut out = [0i8; N];
    let layer = Layer {
        weights: t.weights,
        bias: t.bias,
        requant: t.requant,
        activation: Activation::Identity,
    };
    let start = count::now();
    int8::linear(&input, &layer, &mut out).map_err(|_| "shape")?;
    let spent = count::now() - start;
    for (c, &o) in out.iter().enumerate() {
        let row = &t.weights[c * N..(c + 1) * N];
        let sum: i32 = row
            .iter()
            .zip(&input)
            .map(|(&w, &x)| i32::from(w) * i32::from(x))
            .sum();
        if t.requant[c].apply(sum + t.bias[c]) != o {
            return Err("the int8 kernel disagrees with a scalar loop");
        }
    }
    Ok(spent * 100 / (N * N) as u64)
}
