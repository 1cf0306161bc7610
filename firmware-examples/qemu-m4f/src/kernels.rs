//! Instructions per multiply-accumulate of the int8 kernels, on a layer the size of the
//! retargeter's widest (96 inputs: six segments of 16 features, 64 outputs).

use crate::count;
use posecoach_core::int8::{self, Activation, Layer, Requant};

const INPUTS: usize = 96;
const OUTPUTS: usize = 64;

/// Deterministic bytes: a 32-bit LCG's high byte.
const fn bytes<const N: usize>(seed: u32) -> [i8; N] {
    let mut out = [0i8; N];
    let mut state = seed;
    let mut k = 0;
    while k < N {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        out[k] = (state >> 24) as i8;
        k += 1;
    }
    out
}

/// Weights in flash, as the blob's will be.
static WEIGHTS: [i8; INPUTS * OUTPUTS] = bytes(7);

/// The decoder's convolutions: six segments of 16 channels, kernel 3, 32 frames.
const CHANNELS: usize = 96;
const GROUPS: usize = 6;
const KERNEL: usize = 3;
const FRAMES: usize = 32;
static CONV_WEIGHTS: [i8; CHANNELS * KERNEL * CHANNELS / GROUPS] = bytes(11);

/// Instructions per MAC of `int8::conv1d` (stride 1), times 100.
pub fn conv_per_mac_centi() -> Result<u64, &'static str> {
    let input = core::hint::black_box(bytes::<{ CHANNELS * FRAMES }>(5));
    let bias = [0i32; CHANNELS];
    let requant = [Requant::new(1.0 / 1024.0).ok_or("requant")?; CHANNELS];
    let mut out = [0i8; CHANNELS * FRAMES];
    let layer = Layer {
        weights: &CONV_WEIGHTS,
        bias: &bias,
        requant: &requant,
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

/// Instructions per MAC of `int8::linear`, times 100, after checking its outputs against a
/// plain scalar loop's (the DSP path must add up exactly as the portable one).
pub fn linear_per_mac_centi() -> Result<u64, &'static str> {
    // Not a constant the compiler could fold into the loop.
    let input = core::hint::black_box(bytes::<INPUTS>(3));
    let bias = [100i32; OUTPUTS];
    let requant = [Requant::new(1.0 / 512.0).ok_or("requant")?; OUTPUTS];
    let mut out = [0i8; OUTPUTS];
    let start = count::now();
    let layer = Layer {
        weights: &WEIGHTS,
        bias: &bias,
        requant: &requant,
        activation: Activation::Identity,
    };
    int8::linear(&input, &layer, &mut out).map_err(|_| "shape")?;
    let spent = count::now() - start;
    for (c, &o) in out.iter().enumerate() {
        let row = &WEIGHTS[c * INPUTS..(c + 1) * INPUTS];
        let sum: i32 = row
            .iter()
            .zip(&input)
            .map(|(&w, &x)| i32::from(w) * i32::from(x))
            .sum();
        if requant[c].apply(sum + bias[c]) != o {
            return Err("the int8 kernel disagrees with a scalar loop");
        }
    }
    defmt::println!(
        "KERNEL linear {=usize}x{=usize}: {=u64} instructions, out[0] {=i8}",
        OUTPUTS,
        INPUTS,
        spent,
        out[0]
    );
    Ok(spent * 100 / (INPUTS * OUTPUTS) as u64)
}
