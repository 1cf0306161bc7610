//! Instructions per multiply-accumulate of the int8 kernels, on the committed network's own
//! layers (its widest convolution and a joint layer).

use crate::count;
use posecoach_core::int8::{self, Activation, Conv, Layer, Vectors};
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
#[inline(never)]
pub fn conv_per_mac_centi(weights: &Weights<'_>) -> Result<u64, &'static str> {
    let t = weights.layer(Dense::Up2);
    if t.weights.len() != CHANNELS * KERNEL * CHANNELS / GROUPS {
        return Err("up_2 is not the benchmark's size");
    }
    let input = core::hint::black_box(bytes::<{ CHANNELS * FRAMES }>(5));
    let mut out = [0i8; CHANNELS * FRAMES];
    let layer = Layer {
        weights: t.weights,
        requant: t.requant,
        activation: Activation::Leaky,
    };
    let shape = Conv {
        channels: CHANNELS,
        groups: GROUPS,
        kernel: KERNEL,
        stride: 1,
    };
    let mut work = int8::Workspace::new();
    let start = count::now();
    int8::conv1d(&mut work, &input, &shape, &layer, t.bias, &mut out).map_err(|_| "shape")?;
    let spent = count::now() - start;
    let macs = (FRAMES * CHANNELS * KERNEL * CHANNELS / GROUPS) as u64;
    // Interior frames see every tap; the two end frames one tap fewer.
    let macs = macs - 2 * (CHANNELS * CHANNELS / GROUPS) as u64;
    Ok(spent * 100 / macs)
}

/// Instructions per MAC of `int8::linear` on the joint decoder's hidden layer (16 × 16), as
/// the network runs it: on a frame's 16 bones at once, each with its own bias row. Times 100,
/// after checking every output against a plain scalar loop's (the DSP path must add up
/// exactly as the portable one).
#[inline(never)]
pub fn linear_per_mac_centi(weights: &Weights<'_>) -> Result<u64, &'static str> {
    const N: usize = 16;
    const BONES: usize = 16;
    let t = weights.layer(Dense::DecoderFeatures);
    if t.weights.len() != N * N {
        return Err("decoder.features is not the benchmark's size");
    }
    let inputs = core::hint::black_box(bytes::<{ N * BONES }>(3));
    let mut biases = [0i32; N * BONES];
    for (b, &x) in biases.iter_mut().zip(&bytes::<{ N * BONES }>(7)) {
        *b = i32::from(x) * 64;
    }
    let mut out = [0i8; N * BONES];
    let layer = Layer {
        weights: t.weights,
        requant: t.requant,
        activation: Activation::Leaky,
    };
    let input = |i: usize| &inputs[i * N..(i + 1) * N];
    let bias = |i: usize| &biases[i * N..(i + 1) * N];
    let mut work = int8::Workspace::new();
    let start = count::now();
    let vectors = (Vectors::Strided(&inputs, N), Vectors::Strided(&biases, N));
    int8::linear(&mut work, BONES, vectors.0, vectors.1, &layer, &mut out).map_err(|_| "shape")?;
    let spent = count::now() - start;
    for (k, &o) in out.iter().enumerate() {
        let (i, c) = (k / N, k % N);
        let row = &t.weights[c * N..(c + 1) * N];
        let sum: i32 = row
            .iter()
            .zip(input(i))
            .map(|(&w, &x)| i32::from(w) * i32::from(x))
            .sum();
        if Activation::Leaky.apply(t.requant[c], sum + bias(i)[c]) != o {
            return Err("the int8 kernel disagrees with a scalar loop");
        }
    }
    Ok(spent * 100 / (N * N * BONES) as u64)
}
