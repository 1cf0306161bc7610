//! Instructions per unit of work of the core's kernels: a multiply-accumulate of the int8
//! kernels, on the committed network's own layers (its widest convolution and a joint layer),
//! and a cell of the banded DTW, on a real swing.

use crate::count;
use crate::network::GOLDEN_OUT;
use posecoach_core::dtw::{self, Band, Sequence, Window};
use posecoach_core::int8::{self, Activation, Conv, Layer};
use posecoach_core::reference::Reference;
use posecoach_core::weights::{Dense, Weights};

/// Band radius of the DTW benchmark, frames: scoring's at 30 Hz.
const DTW_RADIUS: u16 = 10;

/// Instructions per banded cell of `dtw::align` with the path, times 100: the golden output
/// (the driver coach retargeted onto a 17-joint student, 55 frames at 30 Hz) aligned with
/// itself as scoring aligns swings (rooted frames, every joint weighing the same), in a
/// global band of [`DTW_RADIUS`]. Also returns the cells.
#[inline(never)]
pub fn dtw_per_cell_centi() -> Result<(u64, usize), &'static str> {
    let swing = Reference::from_bytes(&GOLDEN_OUT.0).map_err(|_| "golden output damaged")?;
    let (frames, joints) = (swing.frames(), swing.skeleton().len());
    let a = Sequence::rooted(swing.positions(), joints).map_err(|_| "golden output's shape")?;
    let window = Window::new(Band::global(DTW_RADIUS), &[]).map_err(|_| "band")?;
    let len = dtw::scratch_len(frames, frames, &window).map_err(|_| "band")?;
    let mut cost = [0.0f32; 128];
    let mut steps = [0u8; 512];
    let mut path = [(0u16, 0u16); 2 * 64];
    let (Some(cost), Some(steps), Some(path)) = (
        cost.get_mut(..len.cost),
        steps.get_mut(..len.path_bytes),
        path.get_mut(..2 * frames - 1),
    ) else {
        return Err("the DTW benchmark's scratch is too short for the golden output");
    };
    let b = core::hint::black_box(a);
    let start = count::now();
    let aligned = dtw::align(&a, &b, &[], &window, cost, steps, path).map_err(|_| "DTW")?;
    let spent = count::now() - start;
    if aligned.path_len != frames || aligned.distance != 0.0 {
        return Err("a swing aligned with itself is not the diagonal");
    }
    Ok((spent * 100 / len.cells as u64, len.cells))
}

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
    int8::linear(&mut work, BONES, input, bias, &layer, &mut out).map_err(|_| "shape")?;
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
