//! The quantized retargeter: the distilled network of ARCHITECTURE.md ("The retargeter") on
//! int8 [`weights`](crate::weights), on caller-owned scratch, without allocation.
//!
//! ```text
//! student T-pose ─SE (f32, int8 weights)─▶ [S][d] ───────────────────────┐
//! coach window ─p⊕v─▶ joint MLP ─▶ attention (f32 softmax) ─▶ [S][T][d] ─▶ down_1 ─▶ down_2 (+ pooled)
//!      │                                                                              │ (+)
//!      │                           [S][T][d] ◀─ up_2 ◀─ ×2 ◀─ up_1 ◀─ ×2 ◀─ [S][T/4][d] ◀┘
//!      │                               └─▶ per joint: Δq; all segments: Δroot
//!      └─analytic prior─▶ q₀, root₀ ──(q₀·Δq, root₀ + Δroot)── FK on the student's skeleton
//! ```
//!
//! Activations are int8, segment-major (`[segment][frame][feature]`), so each convolution
//! within segments reads one contiguous run per output frame ([`int8::conv1d`]). The segment
//! tokens' queries, keys and values are constants of the weights; the joints' keys and values,
//! the softmax, the residual sums, the analytic prior and forward kinematics are `f32` (the
//! Cortex-M4F has an FPU). Every `f32` operation is IEEE single precision in a fixed order
//! (square roots correctly rounded, `libm`'s exponential), so the host and the device compute
//! the same bits.
//!
//! A motion longer than a window is cut into consecutive [`WINDOW`]-frame windows, the last
//! ending at the last frame (its frames replace its overlapping neighbour's); a shorter one
//! holds its last frame. Each window's root trajectory starts from its first frame, as in
//! training.

use crate::config::MAX_JOINTS;
use crate::int8::{self, Activation, Layer, ShapeError, Vectors};
use crate::math;
use crate::retarget::{Analytic, RetargetError};
use crate::skeleton::{Segment, Skeleton};
use crate::weights::{
    Architecture, Dense, Table, Tensors, Weights, MAX_BIAS, MAX_FEATURES, MAX_HEADS, MOTION_INPUTS,
    QUATERNION, REST_CHANNELS, SEGMENTS, WINDOW,
};
use crate::{Quat, Vec3};
use core::ops::Range;
use nalgebra::Quaternion;

/// Added to a quaternion's squared norm before its square root, as in training.
const NORM_EPSILON: f32 = 1e-12;

/// Why a motion could not be retargeted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NetworkError {
    /// The scratch is shorter than [`scratch_len`] or not 4-byte aligned.
    Scratch,
    /// The frames are not whole frames of the source, there are none, or the output is not
    /// as many frames of the target.
    Length,
    /// The analytic prior could not be set up or a position is not finite.
    Retarget(RetargetError),
}

impl core::fmt::Display for NetworkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            NetworkError::Scratch => f.write_str("retargeter scratch too small or misaligned"),
            NetworkError::Length => f.write_str(
                "frames are not whole frames of the source, or the output does not match them",
            ),
            NetworkError::Retarget(e) => e.fmt(f),
        }
    }
}

impl core::error::Error for NetworkError {}

impl From<RetargetError> for NetworkError {
    fn from(e: RetargetError) -> Self {
        NetworkError::Retarget(e)
    }
}

impl From<ShapeError> for NetworkError {
    // Shapes are checked once by `Weights::from_bytes`; a mismatch is a scratch carved wrong.
    fn from(_: ShapeError) -> Self {
        NetworkError::Scratch
    }
}

/// Bytes of scratch [`retarget`] needs for `a`'s network between skeletons of `source` and
/// `target` joints.
pub const fn scratch_len(a: &Architecture, source: usize, target: usize) -> usize {
    let d = a.features as usize;
    let words = SEGMENTS * d + (source + target) * d;
    let bytes = source * d + SEGMENTS * d * (2 * WINDOW + WINDOW / 2 + WINDOW / 4);
    (4 * words + bytes).next_multiple_of(4)
}

/// Scratch for any supported network and skeletons: [`MAX_FEATURES`] and [`MAX_JOINTS`].
pub const MAX_SCRATCH: usize = scratch_len(
    &Architecture {
        features: MAX_FEATURES as u16,
        heads: 1,
        kernel: 1,
        window: WINDOW as u16,
        segments: SEGMENTS as u16,
        rate_hz: 1.0,
    },
    MAX_JOINTS,
    MAX_JOINTS,
);

/// The scratch, carved.
struct Buffers<'s> {
    /// `[S][d]` the student's skeleton feature.
    skeleton: &'s mut [f32],
    /// `[source joint][d]` the motion encoder's first bias, rest features folded in.
    motion_bias: &'s mut [i32],
    /// `[target joint][d]` the joint decoder's first bias, rest features folded in.
    decoder_bias: &'s mut [i32],
    /// `[source joint][d]` one frame's joint embeddings.
    joints: &'s mut [i8],
    /// `[S][T][d]`: the segment tokens after attention, then the last convolution's input.
    a: &'s mut [i8],
    /// `[S][T][d]`: the segment tokens' contexts, then the first decoder convolution's output
    /// (its first half), then the last's.
    b: &'s mut [i8],
    /// `[S][T/2][d]`: the first downsampling's output, then the first decoder input.
    c: &'s mut [i8],
    /// `[S][T/4][d]`: the encoder's output, fused.
    f: &'s mut [i8],
    /// The int8 layers' workspace.
    work: int8::Workspace,
}

/// The arrays a frame of the encoder works in: made once for a window rather than cleared
/// for every frame, as each frame writes the parts it reads first.
struct Encoding {
    /// Each source joint's quantized motion (its padding stays zero).
    x: [[i8; MOTION_INPUTS]; MAX_JOINTS],
    /// Each source joint's hidden features.
    hidden: [i8; MAX_JOINTS * MAX_FEATURES],
    /// Per segment and head: the weighted mean joint embedding.
    means: [[[i8; MAX_FEATURES]; MAX_HEADS]; SEGMENTS],
    /// Per segment and head: the token's and the joints' shares of the softmax.
    shares: [[(f32, f32); MAX_HEADS]; SEGMENTS],
    /// One token's attention.
    attention: Attention,
    /// The attended joint's embedding as `f32`.
    joint: [f32; MAX_FEATURES],
    /// Per head: the value layer's accumulators of every segment.
    values: [i32; SEGMENTS * MAX_FEATURES],
}

impl Encoding {
    fn new() -> Self {
        Encoding {
            x: [[0; MOTION_INPUTS]; MAX_JOINTS],
            hidden: [0; MAX_JOINTS * MAX_FEATURES],
            means: [[[0; MAX_FEATURES]; MAX_HEADS]; SEGMENTS],
            shares: [[(0.0, 0.0); MAX_HEADS]; SEGMENTS],
            attention: Attention::new(),
            joint: [0.0; MAX_FEATURES],
            values: [0; SEGMENTS * MAX_FEATURES],
        }
    }
}

/// The arrays a frame of the decoder works in, as [`Encoding`] is the encoder's.
struct Decoding {
    /// Every segment's feature of the frame.
    features: [i8; SEGMENTS * MAX_FEATURES],
    /// Each target bone's hidden features.
    hidden: [i8; MAX_JOINTS * MAX_FEATURES],
    /// Each bone's raw correction.
    raw: [i32; MAX_JOINTS * QUATERNION],
    /// Each target joint's analytic rotation (the identity where none is fitted).
    prior: [Quat; MAX_JOINTS],
    /// Each target joint's global rotation.
    global: [Quat; MAX_JOINTS],
}

impl Decoding {
    fn new() -> Self {
        Decoding {
            features: [0; SEGMENTS * MAX_FEATURES],
            hidden: [0; MAX_JOINTS * MAX_FEATURES],
            raw: [0; MAX_JOINTS * QUATERNION],
            prior: [Quat::identity(); MAX_JOINTS],
            global: [Quat::identity(); MAX_JOINTS],
        }
    }
}

impl<'s> Buffers<'s> {
    fn carve(scratch: &'s mut [u8], d: usize, source: usize, target: usize) -> Option<Self> {
        fn words<'s, T: bytemuck::Pod>(rest: &mut &'s mut [u8], n: usize) -> Option<&'s mut [T]> {
            let (head, tail) = core::mem::take(rest).split_at_mut_checked(4 * n)?;
            *rest = tail;
            bytemuck::try_cast_slice_mut(head).ok()
        }
        fn bytes<'s>(rest: &mut &'s mut [u8], n: usize) -> Option<&'s mut [i8]> {
            let (head, tail) = core::mem::take(rest).split_at_mut_checked(n)?;
            *rest = tail;
            Some(bytemuck::cast_slice_mut(head))
        }
        let mut rest = scratch;
        Some(Buffers {
            skeleton: words(&mut rest, SEGMENTS * d)?,
            motion_bias: words(&mut rest, source * d)?,
            decoder_bias: words(&mut rest, target * d)?,
            joints: bytes(&mut rest, source * d)?,
            a: bytes(&mut rest, SEGMENTS * WINDOW * d)?,
            b: bytes(&mut rest, SEGMENTS * WINDOW * d)?,
            c: bytes(&mut rest, SEGMENTS * WINDOW / 2 * d)?,
            f: bytes(&mut rest, SEGMENTS * WINDOW / 4 * d)?,
            work: int8::Workspace::new(),
        })
    }
}

/// Retargets `frames` (frame-major positions of `source`'s joints, metres, at the network's
/// rate) onto `target`, writing as many frames of `target`'s joints into `out`.
///
/// # Errors
/// [`NetworkError::Scratch`] if `scratch` is shorter than [`scratch_len`] or not 4-byte
/// aligned; [`NetworkError::Length`]; [`NetworkError::Retarget`] for a source without legs or
/// a position that is not finite.
pub fn retarget(
    weights: &Weights<'_>,
    source: &Skeleton,
    target: &Skeleton,
    frames: &[Vec3],
    scratch: &mut [u8],
    out: &mut [Vec3],
) -> Result<(), NetworkError> {
    let n = target.len();
    if out.len() != frames.len() / source.len().max(1) * n {
        return Err(NetworkError::Length);
    }
    retarget_each(weights, source, target, frames, scratch, &mut |f, pose| {
        if let Some(out) = out.get_mut(f * n..(f + 1) * n) {
            out.copy_from_slice(pose);
        }
    })
}

/// [`retarget`], giving each frame of `target`'s joints to `pose(f, positions)` as it is made
/// rather than writing it into a slice of `f32` metres (a device stores its virtual coach in
/// millimetres). Frames come in windows of [`WINDOW`]; the last window may overlap the one
/// before, so a frame may come twice, the second time as [`retarget`] leaves it. (The callback
/// through `dyn`: one copy of the network in flash, whoever takes its frames.)
///
/// # Errors
/// As [`retarget`].
pub fn retarget_each(
    weights: &Weights<'_>,
    source: &Skeleton,
    target: &Skeleton,
    frames: &[Vec3],
    scratch: &mut [u8],
    pose: &mut dyn FnMut(usize, &[Vec3]),
) -> Result<(), NetworkError> {
    let (m, n) = (source.len(), target.len());
    let count = frames.len() / m.max(1);
    if m == 0 || n == 0 || count == 0 || count * m != frames.len() || n > MAX_JOINTS {
        return Err(NetworkError::Length);
    }
    if let Some(joint) = frames.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(RetargetError::NonFinite { joint: joint % m }.into());
    }
    let d = weights.architecture().d();
    let mut buffers = Buffers::carve(scratch, d, m, n).ok_or(NetworkError::Scratch)?;
    let prior = Analytic::new(source, target)?;
    let mut net = Net {
        weights,
        source,
        target,
        prior,
        d,
        seen: Segment::ALL.map(|segment| Joints::of(source, segment)),
        bone_segments: [0; MAX_JOINTS],
    };
    for (k, segment) in net.bone_segments.iter_mut().enumerate().take(n) {
        *segment = target.bone_segment(k) as u8;
    }
    net.skeleton(&mut buffers);
    net.rest_biases(&mut buffers);
    let mut start = 0;
    loop {
        let last = count.saturating_sub(WINDOW);
        let window = start.min(last);
        net.window(frames, count, window, &mut buffers, pose)?;
        if window == last {
            return Ok(());
        }
        start += WINDOW;
    }
}

/// One retargeting's fixed parts.
struct Net<'n, 'w> {
    weights: &'n Weights<'w>,
    source: &'n Skeleton,
    target: &'n Skeleton,
    prior: Analytic<'n>,
    d: usize,
    /// Per segment: the source joints its token attends to.
    seen: [Joints; SEGMENTS],
    /// Per target joint: the segment whose feature decodes its bone.
    bone_segments: [u8; MAX_JOINTS],
}

/// A segment's attended joints: the root, then the segment's own in order.
struct Joints {
    list: [u8; MAX_JOINTS],
    len: usize,
}

impl Joints {
    fn of(skeleton: &Skeleton, segment: Segment) -> Joints {
        let mut joints = Joints {
            list: [0; MAX_JOINTS],
            len: 0,
        };
        let seen = (0..skeleton.len()).filter(|&k| k == 0 || skeleton.segment_contains(segment, k));
        for (slot, k) in joints.list.iter_mut().zip(seen) {
            *slot = k as u8;
            joints.len += 1;
        }
        joints
    }

    fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        self.list[..self.len].iter().map(|&k| usize::from(k))
    }
}

/// A skeleton's rest features of joint `k`: offset from the parent and position from the
/// root, in heights (the root's: zero).
fn rest_features(skeleton: &Skeleton, rest: &[Vec3], k: usize) -> [f32; REST_CHANNELS] {
    if k == 0 {
        return [0.0; REST_CHANNELS];
    }
    let h = skeleton.height();
    let (o, r) = (skeleton.offset(k) / h, (rest[k] - rest[0]) / h);
    [o.x, o.y, o.z, r.x, r.y, r.z]
}

/// `out[o] = (Σ_i w[o][i] · x[i] + bias[o]) · scale[o]`: a layer with int8 weights on `f32`
/// inputs.
fn dense_f32(t: &Tensors<'_>, x: &[f32], out: &mut [f32]) {
    let rows = t.weights.chunks_exact(x.len().max(1));
    for (((y, row), &b), &s) in out.iter_mut().zip(rows).zip(t.bias).zip(t.scale) {
        let sum = row
            .iter()
            .zip(x)
            .fold(0.0, |s, (&w, x)| s + f32::from(w) * x);
        *y = (sum + b as f32) * s;
    }
}

/// `sums[i] = f(sums[i], x[i])` over the length of the shorter, four to a step.
#[inline(never)]
fn update(sums: &mut [f32], x: &[f32], f: impl Fn(f32, f32) -> f32) {
    let n = sums.len().min(x.len());
    let ((s4, s1), (x4, x1)) = (sums[..n].as_chunks_mut::<4>(), x[..n].as_chunks::<4>());
    for (s, x) in s4.iter_mut().zip(x4) {
        *s = [f(s[0], x[0]), f(s[1], x[1]), f(s[2], x[2]), f(s[3], x[3])];
    }
    for (s, &x) in s1.iter_mut().zip(x1) {
        *s = f(*s, x);
    }
}

fn leaky(v: f32) -> f32 {
    if v < 0.0 {
        int8::LEAKY_SLOPE * v
    } else {
        v
    }
}

/// The `f32` accumulator units of a real value, as an `i32` (saturating).
fn units(real: f32, scale: f32) -> i32 {
    libm::roundf(real / scale) as i32
}

impl Net<'_, '_> {
    fn layer(&self, layer: Dense) -> &Tensors<'_> {
        self.weights.layer(layer)
    }

    /// A stored layer's weights and requantizations, with `activation`.
    fn int8_layer(&self, layer: Dense, activation: Activation) -> Layer<'_> {
        let t = self.layer(layer);
        Layer {
            weights: t.weights,
            requant: t.requant,
            activation,
        }
    }

    /// The skeleton encoder on the target: per joint a two-layer MLP over its rest features,
    /// averaged over each segment's joints, then a linear layer.
    fn skeleton(&self, buffers: &mut Buffers<'_>) {
        let d = self.d;
        let mut rest = [Vec3::zeros(); MAX_JOINTS];
        self.target.rest_positions(&mut rest);
        let mut sums = [[0.0f32; MAX_FEATURES]; SEGMENTS];
        let mut counts = [0u8; SEGMENTS];
        for k in 0..self.target.len() {
            let x = rest_features(self.target, &rest, k);
            let (mut hidden, mut joint) = ([0.0; MAX_FEATURES], [0.0; MAX_FEATURES]);
            dense_f32(self.layer(Dense::SkeletonHidden), &x, &mut hidden[..d]);
            hidden.iter_mut().for_each(|v| *v = leaky(*v));
            dense_f32(
                self.layer(Dense::SkeletonOutput),
                &hidden[..d],
                &mut joint[..d],
            );
            for (s, segment) in Segment::ALL.iter().enumerate() {
                if self.target.segment_contains(*segment, k) {
                    counts[s] += 1;
                    for (sum, v) in sums[s].iter_mut().zip(&joint[..d]) {
                        *sum += leaky(*v);
                    }
                }
            }
        }
        let out = buffers.skeleton.chunks_exact_mut(d);
        for ((sum, &count), out) in sums.iter_mut().zip(&counts).zip(out) {
            if count > 0 {
                sum.iter_mut().for_each(|v| *v /= f32::from(count));
            }
            dense_f32(self.layer(Dense::SkeletonSegment), &sum[..d], out);
        }
    }

    /// The first layers' biases per joint: the stored bias plus the constant rest-feature
    /// columns' contribution, in the layer's accumulator units (held within
    /// [`MAX_BIAS`], as stored biases are, so that no accumulator wraps).
    fn rest_biases(&self, buffers: &mut Buffers<'_>) {
        let sides = [
            (self.source, Dense::MotionFeatures, Dense::MotionRest),
            (self.target, Dense::DecoderFeatures, Dense::DecoderRest),
        ];
        let outs = [&mut *buffers.motion_bias, &mut *buffers.decoder_bias];
        for ((skeleton, layer, columns), out) in sides.into_iter().zip(outs) {
            let mut rest = [Vec3::zeros(); MAX_JOINTS];
            skeleton.rest_positions(&mut rest);
            let (layer, columns) = (self.layer(layer), self.layer(columns));
            for (k, bias) in out.chunks_exact_mut(self.d).enumerate() {
                let mut real = [0.0; MAX_FEATURES];
                let x = rest_features(skeleton, &rest, k);
                dense_f32(columns, &x, &mut real[..self.d]);
                let stored = layer.bias.iter().zip(layer.scale);
                for ((b, (&stored, &scale)), real) in bias.iter_mut().zip(stored).zip(real) {
                    let limit = MAX_BIAS as i32;
                    *b = stored
                        .saturating_add(units(real, scale))
                        .clamp(-limit, limit);
                }
            }
        }
    }

    /// Retargets the window of frames `start..start + WINDOW` (held past `count`), giving
    /// each of its frames up to `count` to `pose`.
    fn window(
        &self,
        frames: &[Vec3],
        count: usize,
        start: usize,
        buffers: &mut Buffers<'_>,
        pose: &mut dyn FnMut(usize, &[Vec3]),
    ) -> Result<(), NetworkError> {
        let m = self.source.len();
        let frame = |t: usize| {
            let f = (start + t).min(count - 1);
            &frames[f * m..(f + 1) * m]
        };
        self.encode(frame, buffers)?;
        self.tokens(buffers)?;
        self.convolve(buffers)?;
        let poses = count.saturating_sub(start).min(WINDOW);
        self.decode(frame, start..start + poses, pose, buffers)
    }

    /// The motion encoder over the window's frames (`frame(t)`, source positions), leaving
    /// each segment token's context in `buffers.b`. Out of line, as is [`Net::decode`], so
    /// that the two phases' arrays share the stack.
    #[inline(never)]
    fn encode<'f>(
        &self,
        frame: impl Fn(usize) -> &'f [Vec3],
        buffers: &mut Buffers<'_>,
    ) -> Result<(), NetworkError> {
        let m = self.source.len();
        let root = frame(0)[0];
        let origin = Vec3::new(root.x, 0.0, root.z);
        // Each joint's position relative to its parent (the root's to the window's origin),
        // in heights, of two consecutive frames: the features and their differences.
        let h = self.source.height();
        let relative = |t: usize, out: &mut [Vec3; MAX_JOINTS]| {
            let p = frame(t);
            let at = |k: usize| (p[k] - origin) / h;
            for (k, out) in out.iter_mut().enumerate().take(m) {
                *out = match self.source.parent(k) {
                    Some(parent) if k > 0 => at(k) - at(parent),
                    _ => at(k),
                };
            }
        };
        let mut pair = [[Vec3::zeros(); MAX_JOINTS]; 2];
        let [mut before, mut after] = pair.each_mut();
        relative(0, before);
        let mut encoding = Encoding::new();
        for t in 0..WINDOW {
            // Frame 0 moves as frame 1 does.
            if t > 1 {
                core::mem::swap(&mut before, &mut after);
            }
            if t != 1 {
                relative(t.max(1), after);
            }
            let here = if t == 0 { &*before } else { &*after };
            self.encode_frame(
                &here[..m],
                &before[..m],
                &after[..m],
                t,
                buffers,
                &mut encoding,
            )?;
        }
        Ok(())
    }

    /// The decoder's per-frame part over the window's frames `poses` (`frame(t)`, source
    /// positions, `t` counted from the window's first), each target pose given to `pose`.
    /// (The output through `dyn`: one copy of the decoder in flash, whoever takes it.)
    #[inline(never)]
    fn decode<'f>(
        &self,
        frame: impl Fn(usize) -> &'f [Vec3],
        poses: Range<usize>,
        pose: &mut dyn FnMut(usize, &[Vec3]),
        buffers: &mut Buffers<'_>,
    ) -> Result<(), NetworkError> {
        let mut decoding = Decoding::new();
        let mut out = [Vec3::zeros(); MAX_JOINTS];
        let out = &mut out[..self.target.len()];
        for (t, f) in poses.enumerate() {
            self.decode_frame(frame(t), t, buffers, &mut decoding, out)?;
            pose(f, out);
        }
        Ok(())
    }

    /// The motion encoder up to the segment tokens' output layer, frame `t` (its joints'
    /// relative positions `here`, their velocity `after − before`): joint embeddings, then
    /// attention of each segment token over itself, the root and its segment's joints,
    /// leaving each token's context in `buffers.b` (`[S][T][d]`).
    fn encode_frame(
        &self,
        here: &[Vec3],
        before: &[Vec3],
        after: &[Vec3],
        t: usize,
        buffers: &mut Buffers<'_>,
        arrays: &mut Encoding,
    ) -> Result<(), NetworkError> {
        let (d, m) = (self.d, self.source.len());
        let scales = self.weights.scales();
        let Encoding {
            x,
            hidden,
            means,
            shares,
            attention,
            joint,
            values,
        } = arrays;
        for (k, x) in x.iter_mut().enumerate().take(m) {
            let (p, v) = (here[k], after[k] - before[k]);
            for ((x, real), &scale) in x
                .iter_mut()
                .zip(p.iter().chain(v.iter()))
                .zip(&scales.motion)
            {
                *x = int8::quantize(*real, scale);
            }
        }
        let first = self.int8_layer(Dense::MotionFeatures, Activation::Leaky);
        let motion_bias = &*buffers.motion_bias;
        int8::linear(
            &mut buffers.work,
            m,
            Vectors::Strided(x.as_flattened(), MOTION_INPUTS),
            Vectors::Strided(motion_bias, d),
            &first,
            &mut hidden[..m * d],
        )?;
        let output = self.layer(Dense::MotionOutput);
        let embed = self.int8_layer(Dense::MotionOutput, Activation::Identity);
        let (rows, bias) = (
            Vectors::Strided(hidden, d),
            Vectors::Strided(output.bias_row(t), 0),
        );
        int8::linear(&mut buffers.work, m, rows, bias, &embed, buffers.joints)?;

        let heads = usize::from(self.weights.architecture().heads);
        let width = d / heads;
        let [logits, offsets, token_logits, token_values] =
            Table::ALL.map(|t| self.weights.table(t));
        // Per segment and head: the weighted mean joint embedding and the softmax's parts.
        for (s, seen) in self.seen.iter().enumerate() {
            let row = s * heads..(s + 1) * heads;
            // The root comes first: it starts the sums.
            for (first, k) in seen.iter().enumerate().map(|(i, k)| (i == 0, k)) {
                let embedding = &buffers.joints[k * d..(k + 1) * d];
                let (e4, e1) = embedding.as_chunks::<4>();
                let (j4, j1) = joint[..d].as_chunks_mut::<4>();
                for (x, q) in j4.iter_mut().zip(e4) {
                    *x = q.map(f32::from);
                }
                for (x, &q) in j1.iter_mut().zip(e1) {
                    *x = f32::from(q);
                }
                let joint = &joint[..d];
                let mut logit = [0.0; MAX_HEADS];
                for ((l, u), &offset) in logit
                    .iter_mut()
                    .zip(logits[s * heads * d..].chunks_exact(d))
                    .zip(&offsets[row.clone()])
                {
                    *l = math::dot_from(offset, u, joint);
                }
                if first {
                    attention.start(&token_logits[row.clone()], &logit[..heads], joint);
                } else {
                    attention.add(&logit[..heads], joint);
                }
            }
            for h in 0..heads {
                let joints = attention.joints[h];
                for (q, &x) in means[s][h].iter_mut().zip(&attention.sums[h][..d]) {
                    *q = int8::quantize(x, joints.max(f32::MIN_POSITIVE));
                }
                shares[s][h] = (attention.token[h], joints);
            }
        }
        // Per head, for all segments at once: the value layer of the mean embedding, mixed
        // with the token's own value.
        let value = self.layer(Dense::Value);
        let means = means.as_flattened().as_flattened();
        let context_scale = scales.context;
        for (h, scale) in value.scale.chunks_exact(width).take(heads).enumerate() {
            let span = h * width..(h + 1) * width;
            let acc = &mut values[..SEGMENTS * width];
            int8::accumulate(
                &mut buffers.work,
                SEGMENTS,
                Vectors::Strided(&means[h * MAX_FEATURES..], MAX_HEADS * MAX_FEATURES),
                Vectors::Strided(&value.bias[span.clone()], 0),
                &value.weights[span.start * d..span.end * d],
                acc,
            )?;
            for (s, acc) in acc.chunks_exact(width).enumerate() {
                let (token, joints) = shares[s][h];
                let context = &mut buffers.b[(s * WINDOW + t) * d..][..d][span.clone()];
                let own = &token_values[s * d..][span.clone()];
                for (((q, &a), &scale), &own) in context.iter_mut().zip(acc).zip(scale).zip(own) {
                    let joint = a as f32 * scale;
                    let real = (token * own + joints * joint) / (token + joints);
                    *q = int8::quantize(real, context_scale);
                }
            }
        }
        Ok(())
    }

    /// The segment tokens' output layer over the window's frames, from `buffers.b` into
    /// `buffers.a`.
    fn tokens(&self, buffers: &mut Buffers<'_>) -> Result<(), NetworkError> {
        let d = self.d;
        let output = self.layer(Dense::Output);
        let layer = self.int8_layer(Dense::Output, Activation::Identity);
        let contexts = buffers.b.chunks_exact(WINDOW * d);
        for (s, (context, out)) in contexts
            .zip(buffers.a.chunks_exact_mut(WINDOW * d))
            .enumerate()
        {
            let (frames, bias) = (
                Vectors::Strided(context, d),
                Vectors::Strided(output.bias_row(s), 0),
            );
            int8::linear(&mut buffers.work, WINDOW, frames, bias, &layer, out)?;
        }
        Ok(())
    }

    /// The convolutions: two downsampling ones with the average-pooled residual, fusion with
    /// the skeleton feature, and the decoder's two upsampling stages, leaving `[S][T][d]` in
    /// `buffers.b`.
    fn convolve(&self, buffers: &mut Buffers<'_>) -> Result<(), NetworkError> {
        let d = self.d;
        let kernel = usize::from(self.weights.architecture().kernel);
        let conv = |work: &mut int8::Workspace,
                    layer: Dense,
                    activation,
                    stride,
                    input: &[i8],
                    out: &mut [i8]| {
            let shape = int8::Conv {
                channels: SEGMENTS * d,
                groups: SEGMENTS,
                kernel,
                stride,
            };
            let bias = self.layer(layer).bias;
            int8::conv1d(
                work,
                input,
                &shape,
                &self.int8_layer(layer, activation),
                bias,
                out,
            )
        };
        conv(
            &mut buffers.work,
            Dense::Down1,
            Activation::Leaky,
            2,
            buffers.a,
            buffers.c,
        )?;
        conv(
            &mut buffers.work,
            Dense::Down2,
            Activation::Identity,
            2,
            buffers.c,
            buffers.f,
        )?;
        let scales = self.weights.scales();
        let quarter = WINDOW / 4;
        for s in 0..SEGMENTS {
            for t in 0..quarter {
                for c in 0..d {
                    let pooled: i32 = (0..4)
                        .map(|i| i32::from(buffers.a[(s * WINDOW + 4 * t + i) * d + c]))
                        .sum();
                    let at = (s * quarter + t) * d + c;
                    let y = f32::from(buffers.f[at]) * scales.down_2
                        + pooled as f32 * scales.segments / 4.0;
                    let fused = leaky(y) + buffers.skeleton[s * d + c];
                    buffers.f[at] = int8::quantize(fused, scales.fused);
                }
            }
        }
        let upsample = |input: &[i8], out: &mut [i8], frames: usize| {
            let mut pairs = input
                .chunks_exact(frames * d)
                .zip(out.chunks_exact_mut(2 * frames * d));
            pairs.try_for_each(|(x, y)| int8::upsample2(x, d, y))
        };
        upsample(buffers.f, buffers.c, quarter)?;
        let half = SEGMENTS * WINDOW / 2 * d;
        conv(
            &mut buffers.work,
            Dense::Up1,
            Activation::Leaky,
            1,
            buffers.c,
            &mut buffers.b[..half],
        )?;
        upsample(&buffers.b[..half], buffers.a, WINDOW / 2)?;
        conv(
            &mut buffers.work,
            Dense::Up2,
            Activation::Leaky,
            1,
            buffers.a,
            buffers.b,
        )?;
        Ok(())
    }

    /// The decoder's per-frame part, frame `t` of `source` (positions): the root's and each
    /// bone's correction of the analytic solution, then forward kinematics into `pose`.
    fn decode_frame(
        &self,
        source: &[Vec3],
        t: usize,
        buffers: &mut Buffers<'_>,
        arrays: &mut Decoding,
        pose: &mut [Vec3],
    ) -> Result<(), NetworkError> {
        let (d, n) = (self.d, self.target.len());
        let Decoding {
            features,
            hidden,
            raw,
            prior,
            global,
        } = arrays;
        let feature = |s: usize| &buffers.b[(s * WINDOW + t) * d..][..d];
        for (s, row) in features.chunks_exact_mut(d).enumerate().take(SEGMENTS) {
            row.copy_from_slice(feature(s));
        }
        // The root layer's three rows run as the vectors and the frame's features as the one
        // row (one row of sums instead of three, for the same integers).
        let root = self.layer(Dense::Root);
        let mut acc = [0i32; 3];
        let all = &features[..SEGMENTS * d];
        int8::accumulate(
            &mut buffers.work,
            acc.len(),
            Vectors::Strided(root.weights, SEGMENTS * d),
            Vectors::Strided(root.bias, 1),
            all,
            &mut acc,
        )?;
        let h = self.target.height();
        let correction = Vec3::new(
            acc[0] as f32 * root.scale[0],
            acc[1] as f32 * root.scale[1],
            acc[2] as f32 * root.scale[2],
        );
        let start = source[self.prior.root()];
        pose[0] = start * self.prior.scale() + correction * h;
        // Every bone's correction at once: bone `k` (row `k - 1`) reads its segment's feature.
        let bones = n - 1;
        let layer = self.int8_layer(Dense::DecoderFeatures, Activation::Leaky);
        let input = |i: usize| feature(usize::from(self.bone_segments[i + 1]));
        int8::linear(
            &mut buffers.work,
            bones,
            Vectors::Each(&input),
            Vectors::Strided(&buffers.decoder_bias[d..], d),
            &layer,
            &mut hidden[..bones * d],
        )?;
        // The output layer's four rows run as the vectors and the bones' features as the rows
        // (one group of four instead of one per four bones): `raw[i · bones + k - 1]` is bone
        // `k`'s product with row `i`, its bias added after (the same integer sum).
        let output = self.layer(Dense::DecoderOutput);
        let raw = &mut raw[..bones * QUATERNION];
        int8::accumulate(
            &mut buffers.work,
            QUATERNION,
            Vectors::Strided(output.weights, d),
            Vectors::Strided(&[0; MAX_JOINTS][..bones], 0),
            &hidden[..bones * d],
            raw,
        )?;
        for k in 1..n {
            if let Some(chord) = self.prior.chord(k) {
                let to = source[chord.to] - source[chord.from];
                prior[k] = crate::kinematics::swing(chord.rest, to);
            }
            let parent = self.target.parent(k).unwrap_or(0);
            let q = |i: usize| {
                raw[i * bones + k - 1].wrapping_add(output.bias[i]) as f32 * output.scale[i]
            };
            let raw = Quaternion::new(1.0 + q(0), q(1), q(2), q(3));
            let norm = math::sqrt(raw.norm_squared() + NORM_EPSILON);
            let correction = Quat::new_unchecked(raw / norm);
            let local = prior[parent].inverse() * prior[k] * correction;
            global[k] = global[parent] * local;
            pose[k] = pose[parent] + global[k] * self.target.offset(k);
        }
        Ok(())
    }
}

/// One segment token's attention over keys given one at a time, per head: a softmax kept as
/// a running maximum and the token's and the joints' exponentials relative to it, with the
/// joints' embeddings summed under their exponentials (no key or value is stored).
struct Attention {
    max: [f32; MAX_HEADS],
    /// The token's own exponential.
    token: [f32; MAX_HEADS],
    /// The joints' exponentials, summed.
    joints: [f32; MAX_HEADS],
    /// The joints' int8 embeddings weighted by their exponentials, summed.
    sums: [[f32; MAX_FEATURES]; MAX_HEADS],
}

impl Attention {
    fn new() -> Self {
        Attention {
            max: [0.0; MAX_HEADS],
            token: [0.0; MAX_HEADS],
            joints: [0.0; MAX_HEADS],
            sums: [[0.0; MAX_FEATURES]; MAX_HEADS],
        }
    }

    /// Starts a token over its first joint: the token's logits for itself and the joint's
    /// (one per head), the joint's embedding `x`. Equal to adding the joint to empty sums,
    /// without clearing them first.
    fn start(&mut self, token_logits: &[f32], logits: &[f32], x: &[f32]) {
        for (h, (&own, &logit)) in token_logits.iter().zip(logits).enumerate() {
            let sums = &mut self.sums[h];
            if logit > own {
                self.max[h] = logit;
                self.token[h] = libm::expf(own - logit);
                self.joints[h] = 1.0;
                update(sums, x, |_, v| v);
            } else {
                let new = libm::expf(logit - own);
                self.max[h] = own;
                self.token[h] = 1.0;
                self.joints[h] = new;
                update(sums, x, |_, v| new * v);
            }
        }
    }

    /// Adds a joint with `logits` (one per head) and embedding `x` (its int8 values): a new
    /// maximum rescales what came before by `old`, any other logit adds its exponential
    /// `new` (the factor of 1 on the other side skipped: exact).
    fn add(&mut self, logits: &[f32], x: &[f32]) {
        for (h, &logit) in logits.iter().enumerate() {
            let sums = &mut self.sums[h];
            if logit > self.max[h] {
                let old = libm::expf(self.max[h] - logit);
                self.max[h] = logit;
                self.token[h] *= old;
                self.joints[h] = self.joints[h] * old + 1.0;
                math::scale_then_add(sums, old, x);
            } else {
                let new = libm::expf(logit - self.max[h]);
                self.joints[h] += new;
                math::add_scaled(sums, new, x);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;
    use crate::kinematics::testing::pose;
    use crate::weights::testing::{blob, DISTILLED};
    use std::vec::Vec;

    const TOLERANCE_M: f32 = 1e-5;

    /// `frames` poses of `skeleton` swaying a little from frame to frame.
    fn motion(skeleton: &Skeleton, frames: usize) -> Vec<Vec3> {
        (0..frames)
            .flat_map(|f| {
                let phase = f as f32 * 0.1;
                let raw: Vec<[f32; 4]> = (0..skeleton.len())
                    .map(|k| {
                        let a = phase + k as f32;
                        [0.0, 0.3 * libm::sinf(a), 0.2 * libm::cosf(a), 0.1]
                    })
                    .collect();
                pose(skeleton, &raw, [0.01 * f as f32, 0.9, 0.0])
            })
            .collect()
    }

    fn run(
        bytes: &[u8],
        source: &Skeleton,
        target: &Skeleton,
        frames: &[Vec3],
    ) -> Result<Vec<Vec3>, NetworkError> {
        let mut words = std::vec![0u32; bytes.len().div_ceil(4)];
        bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
        let weights =
            Weights::from_bytes(&bytemuck::cast_slice::<u32, u8>(&words)[..bytes.len()]).unwrap();
        let mut scratch = std::vec![0u32; MAX_SCRATCH / 4];
        let mut out = std::vec![Vec3::zeros(); frames.len() / source.len() * target.len()];
        let scratch = bytemuck::cast_slice_mut(&mut scratch);
        retarget(&weights, source, target, frames, scratch, &mut out)?;
        Ok(out)
    }

    #[test]
    #[cfg_attr(miri, ignore = "a whole window of the network: minutes under Miri")]
    fn without_corrections_it_is_the_analytic_retargeter() {
        let bytes = blob(DISTILLED, 5, true);
        for (from, onto, frames) in [
            (Format::Cmu31, Format::H36m17, 70),
            (Format::H36m17, Format::Coco17, 20),
            (Format::GolfMarkers, Format::Cmu31, 130),
        ] {
            let (source, target) = (
                Skeleton::standard(from).unwrap(),
                Skeleton::standard(onto).unwrap(),
            );
            let frames_in = motion(&source, frames);
            let out = run(&bytes, &source, &target, &frames_in).unwrap();
            let analytic = Analytic::new(&source, &target).unwrap();
            let mut expected = std::vec![Vec3::zeros(); target.len()];
            for (f, pose) in out.chunks_exact(target.len()).enumerate() {
                let frame = &frames_in[f * source.len()..(f + 1) * source.len()];
                analytic.frame(frame, &mut expected).unwrap();
                for (k, (p, e)) in pose.iter().zip(&expected).enumerate() {
                    assert!(
                        (p - e).norm() < TOLERANCE_M,
                        "{from}→{onto} frame {f} joint {k}"
                    );
                }
            }
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "a whole window of the network: minutes under Miri")]
    fn corrections_keep_the_targets_bones_and_move_the_pose() {
        let bytes = blob(DISTILLED, 6, false);
        let (source, target) = (
            Skeleton::standard(Format::Cmu31).unwrap(),
            Skeleton::standard(Format::H36m17).unwrap(),
        );
        let frames = motion(&source, 64);
        let out = run(&bytes, &source, &target, &frames).unwrap();
        let same = run(&bytes, &source, &target, &frames).unwrap();
        assert_eq!(out, same);
        let analytic = run(&blob(DISTILLED, 6, true), &source, &target, &frames).unwrap();
        let moved = out
            .iter()
            .zip(&analytic)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f32::max);
        assert!(moved > 0.01, "{moved}");
        // Made-up weights put the root hundreds of metres away: bones are exact to its ulps.
        for pose in out.chunks_exact(target.len()) {
            let tolerance = 1e-6 * (1.0 + pose[0].norm());
            for k in 1..target.len() {
                let bone = (pose[k] - pose[target.parent(k).unwrap()]).norm();
                assert!(
                    (bone - target.offset(k).norm()).abs() < tolerance,
                    "joint {k}"
                );
            }
        }
    }

    proptest::proptest! {
        #[test]
        fn four_step_loops_match_plain_folds_to_the_bit(
            a in proptest::collection::vec(-100.0f32..100.0, 0..23),
            b in proptest::collection::vec(-100.0f32..100.0, 0..23),
            start in -100.0f32..100.0,
        ) {
            let mut sums = a.clone();
            update(&mut sums, &b, |s, x| s * start + x);
            let n = a.len().min(b.len());
            for (k, (s, (a, x))) in sums.iter().zip(a.iter().zip(&b)).enumerate() {
                proptest::prop_assert_eq!(s.to_bits(), (a * start + x).to_bits(), "value {}", k);
            }
            proptest::prop_assert_eq!(&sums[n..], &a[n..]);
        }
    }

    #[test]
    #[cfg_attr(miri, ignore = "a whole window of the network: minutes under Miri")]
    fn bad_buffers_and_inputs_are_typed_errors() {
        let bytes = blob(DISTILLED, 7, false);
        let mut words = std::vec![0u32; bytes.len().div_ceil(4)];
        bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(&bytes);
        let weights =
            Weights::from_bytes(&bytemuck::cast_slice::<u32, u8>(&words)[..bytes.len()]).unwrap();
        let (source, target) = (
            Skeleton::standard(Format::H36m17).unwrap(),
            Skeleton::standard(Format::H36m17).unwrap(),
        );
        let mut frames = motion(&source, 10);
        let need = scratch_len(weights.architecture(), 17, 17);
        let mut scratch = std::vec![0u32; need / 4];
        let scratch = bytemuck::cast_slice_mut::<u32, u8>(&mut scratch);
        let mut out = std::vec![Vec3::zeros(); 10 * 17];
        let call = |frames: &[Vec3], scratch: &mut [u8], out: &mut [Vec3]| {
            retarget(&weights, &source, &target, frames, scratch, out)
        };
        assert_eq!(call(&frames, scratch, &mut out), Ok(()));
        assert_eq!(
            call(&frames, &mut scratch[..need - 4], &mut out),
            Err(NetworkError::Scratch)
        );
        assert_eq!(
            call(&frames, &mut scratch[1..], &mut out),
            Err(NetworkError::Scratch)
        );
        assert_eq!(
            call(&frames[1..], scratch, &mut out),
            Err(NetworkError::Length)
        );
        assert_eq!(
            call(&frames, scratch, &mut out[1..]),
            Err(NetworkError::Length)
        );
        assert_eq!(call(&[], scratch, &mut []), Err(NetworkError::Length));
        frames[20].y = f32::NAN;
        assert_eq!(
            call(&frames, scratch, &mut out),
            Err(NetworkError::Retarget(RetargetError::NonFinite {
                joint: 3
            }))
        );
    }
}
