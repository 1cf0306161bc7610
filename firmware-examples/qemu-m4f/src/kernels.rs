//! Instructions per multiply-accumulate of the int8 kernels, on the committed network's own
//! layers (its widest convolution and a joint layer).

use crate::count;
use posecoach_core::int8::{self, Activation, Conv, Layer, Requant, Vectors};
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

/// Most vectors, inputs and outputs of [`check_shapes`]' layers.
const MAX_COUNT: usize = 9;
const MAX_N: usize = 24;
const MAX_M: usize = 8;

/// Runs `int8::linear` (with and without the leaky slope) and `int8::accumulate` on a grid of
/// shapes, every output against a scalar loop's: fewer vectors than the four lanes, as many and
/// more (a last group overlapping the one before); rows of whole four-byte groups and not;
/// biases shared, one row per vector, and gathered in reverse (lanes a negative stride apart);
/// requantizations below ¼ (the DSP path's one `asm!` loop) and above. Returns the layer calls
/// checked.
#[inline(never)]
pub fn check_shapes() -> Result<u32, &'static str> {
    let pool = bytes::<{ (MAX_COUNT + MAX_M) * MAX_N }>(11);
    let (vectors, weights) = pool.split_at(MAX_COUNT * MAX_N);
    let mut biases = [0i32; MAX_COUNT * MAX_M];
    for (b, &x) in biases.iter_mut().zip(&bytes::<{ MAX_COUNT * MAX_M }>(13)) {
        *b = i32::from(x) * 97;
    }
    let mut work = int8::Workspace::new();
    let mut checked = 0;
    // The grid is read through `black_box`, so that its loops stay loops (flash).
    for &count in core::hint::black_box(&[1, 3, 4, 5, 9]) {
        for &n in core::hint::black_box(&[4, 7, 8, 12, 24]) {
            for &m in core::hint::black_box(&[1, 3, 4, 8]) {
                // Factors below ¼ (all the network's), and from ¼ to ½.
                for &shift in core::hint::black_box(&[-8, -1]) {
                    let requant = requants(shift).ok_or("requantization")?;
                    let requant = &requant[..m];
                    let w = &weights[..m * n];
                    let reversed = |i: usize| &biases[(count - 1 - i) * m..][..m];
                    let gathered = |i: usize| &vectors[(count - 1 - i) * n..][..n];
                    for kind in 0..3 {
                        let (input, bias): (Vectors<'_, i8>, Vectors<'_, i32>) = match kind {
                            0 => (Vectors::Strided(vectors, n), Vectors::Strided(&biases[..m], 0)),
                            1 => (Vectors::Strided(vectors, n), Vectors::Strided(&biases, m)),
                            _ => (Vectors::Each(&gathered), Vectors::Each(&reversed)),
                        };
                        let at = |i: usize| match kind {
                            0 => (&vectors[i * n..][..n], &biases[..m]),
                            1 => (&vectors[i * n..][..n], &biases[i * m..][..m]),
                            _ => (gathered(i), reversed(i)),
                        };
                        let mut raw = [0i32; MAX_COUNT * MAX_M];
                        int8::accumulate(&mut work, count, input, bias, w, &mut raw[..count * m])
                            .map_err(|_| "shape")?;
                        for activation in [Activation::Identity, Activation::Leaky] {
                            let layer = Layer { weights: w, requant, activation };
                            let mut out = [0i8; MAX_COUNT * MAX_M];
                            int8::linear(&mut work, count, input, bias, &layer, &mut out[..count * m])
                                .map_err(|_| "shape")?;
                            for (k, (&o, &r)) in out.iter().zip(&raw).take(count * m).enumerate() {
                                let (i, c) = (k / m, k % m);
                                let (x, b) = at(i);
                                let row = &w[c * n..(c + 1) * n];
                                if !agrees(row, x, b[c], (requant[c], activation), (r, o)) {
                                    return Err("the int8 kernels disagree with a scalar loop");
                                }
                            }
                            checked += 1;
                        }
                        checked += 1;
                    }
                }
            }
        }
    }
    Ok(checked)
}

/// Requantizations of exponent `shift`, one per output, their multipliers spread over
/// `[2^30, 2^31)`: factors from `2^(shift−1)` to nearly `2^shift`. Made from their stored form
/// (two `i32`s), as a weights blob holds them.
fn requants(shift: i32) -> Option<[Requant; MAX_M]> {
    let requant: [Requant; MAX_M] =
        core::array::from_fn(|c| bytemuck::cast([(1 << 30) + (c as i32) * (1 << 27), shift]));
    requant.iter().all(|r| r.is_valid()).then_some(requant)
}

/// Whether a layer's raw sum and output for `row` against `x` with `bias` are a scalar loop's.
#[inline(never)]
fn agrees(
    row: &[i8],
    x: &[i8],
    bias: i32,
    (requant, activation): (Requant, Activation),
    (raw, out): (i32, i8),
) -> bool {
    let dot: i32 = row.iter().zip(x).map(|(&a, &b)| i32::from(a) * i32::from(b)).sum();
    let sum = dot.wrapping_add(bias);
    raw == sum && out == activation.apply(requant, sum)
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
