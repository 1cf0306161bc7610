//! The teacher retargeter of ARCHITECTURE.md ("The retargeter"), in burn.
//!
//! ```text
//! target T-pose [B,J,6] ──SE──▶ [B,S,d] ─────────────────┐ (added at every time step)
//! source motion [B,T,J,6] ⊕ T-pose ──ME──▶ [B,S·d,T/4] ──(+)──▶ MD ──▶ Δq [B,J,T,4], Δroot [B,T,3]
//! source positions ──prior──▶ q₀, root₀ ──(q₀·Δq, root₀ + Δroot)──FK(target)─▶ [B,T,J,3]
//! ```
//!
//! The decoder corrects a geometric solution, the rotation transfer or the analytic
//! retargeter's chords, rather than replacing it
//! ([`crate::prior`]): trained from scratch for 22 000 steps, the same network stayed 3–10×
//! further from the ground truth than the analytic retargeter.
//!
//! The motion encoder sees the source's rest features beside each joint's motion: a rotation
//! copy is relative to the source's rest pose, which its positions alone do not tell.
//!
//! Temporal features are `[B, S·d, time]` with channels segment-major (`s·d + c`), so a
//! *masked* convolution, one that mixes only a segment's own channels, is a grouped
//! convolution with one group per segment. Layouts of the inputs: [`crate::features`].

use crate::calibration::{Calibration, Point};
use crate::features::{Batch, MOTION_CHANNELS, WINDOW};
use crate::fk;
use crate::prior::PriorKind;
use crate::skeletons::{Skeletons, REST_CHANNELS, SEGMENTS};
use burn::module::Param;
use burn::nn::attention::{MhaInput, MultiHeadAttention, MultiHeadAttentionConfig};
use burn::nn::conv::{Conv1d, Conv1dConfig};
use burn::nn::interpolate::{Interpolate1d, Interpolate1dConfig, InterpolateMode};
use burn::nn::{
    Initializer, Linear, LinearConfig, PaddingConfig1d, PositionalEncoding,
    PositionalEncodingConfig,
};
use burn::prelude::{Device, Module, Tensor};
use burn::tensor::activation::leaky_relu;
use burn::tensor::Distribution;

/// Negative slope of every activation.
const LEAKY_SLOPE: f64 = 0.2;
/// Standard deviation of the segment tokens' initial values (N(0, 1) · 0.1).
const TOKEN_INIT_STD: f64 = 0.1;
/// Time steps per motion feature: two stride-2 convolutions.
pub const DOWNSAMPLING: usize = 4;
/// Upsampling factor of each decoder stage.
const UPSAMPLING: f32 = 2.0;
/// Quaternion components.
const QUATERNION: usize = 4;
/// Attention logit of a masked key: its weight is below `e^-60` of a visible key's, and
/// unlike a larger negative number its exponential stays out of the slow underflow path.
const MASKED_LOGIT: f64 = -60.0;

const _: () = assert!(
    WINDOW.is_multiple_of(DOWNSAMPLING),
    "a window must downsample evenly"
);

/// The teacher's sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TeacherConfig {
    /// Features per segment (`d`); a multiple of `heads` and even (sinusoidal encoding).
    pub features: usize,
    /// Attention heads.
    pub heads: usize,
    /// Kernel size of the temporal convolutions (odd, so that padding keeps lengths).
    pub kernel: usize,
    /// The geometric solution the decoder corrects.
    pub prior: PriorKind,
}

impl TeacherConfig {
    /// The teacher as trained: `d` = 32 per segment, 2 heads, kernel 3.
    pub const DEFAULT: TeacherConfig = TeacherConfig {
        features: 32,
        heads: 2,
        kernel: 3,
        prior: PriorKind::Rotations,
    };
    /// A tiny teacher for tests.
    pub const TINY: TeacherConfig = TeacherConfig {
        features: 8,
        heads: 2,
        kernel: 3,
        prior: PriorKind::Chords,
    };

    /// A randomly initialized teacher on `device` (seed it with `device.seed`).
    pub fn init(&self, device: &Device) -> Teacher {
        Teacher {
            prior: self.prior,
            skeleton: SkeletonEncoder::new(self, device),
            motion: MotionEncoder::new(self, device),
            decoder: Decoder::new(self, device),
        }
    }

    /// A temporal convolution within segments, `stride` 1 or 2, keeping `length / stride`.
    fn conv(&self, stride: usize, device: &Device) -> Conv1d {
        let channels = SEGMENTS * self.features;
        let pad = self.kernel / 2;
        Conv1dConfig::new(channels, channels, self.kernel)
            .with_stride(stride)
            .with_groups(SEGMENTS)
            .with_padding(PaddingConfig1d::Explicit(pad, pad))
            .init(device)
    }
}

impl Default for TeacherConfig {
    fn default() -> Self {
        TeacherConfig::DEFAULT
    }
}

/// What the teacher outputs for a batch.
#[derive(Clone, Debug)]
pub struct Retargeted {
    /// `[B, J, T, 4]` (joint-major, as [`fk`] takes them) unit quaternions: each bone's
    /// rotation relative to its parent bone (the root's and padded joints' are not used).
    pub rotations: Tensor<4>,
    /// `[B, T, 3]` the root trajectory, in target heights.
    pub root: Tensor<3>,
    /// `[B, T, J, 3]` joint positions on the target skeletons, in target heights.
    pub positions: Tensor<4>,
    /// `[B, S·d, T/4]` the motion encoder's features of the source (the cycle compares them).
    pub features: Tensor<3>,
}

/// The teacher network.
#[derive(Module, Debug)]
pub struct Teacher {
    #[module(skip)]
    prior: PriorKind,
    skeleton: SkeletonEncoder,
    motion: MotionEncoder,
    decoder: Decoder,
}

impl Teacher {
    /// The geometric solution it corrects.
    pub fn prior(&self) -> PriorKind {
        self.prior
    }

    /// The batch's motions retargeted onto its targets.
    pub fn forward(&self, batch: &Batch) -> Retargeted {
        self.forward_observed(batch, None)
    }

    /// [`Teacher::forward`], recording into `calibration` the magnitudes of the activations
    /// the quantized network keeps in int8.
    pub fn forward_observed(
        &self,
        batch: &Batch,
        mut calibration: Option<&mut Calibration>,
    ) -> Retargeted {
        let cal = &mut calibration;
        observe(cal, Point::Motion, &batch.motion);
        let features = self
            .motion
            .forward(batch.motion.clone(), &batch.source, cal);
        let skeleton = self.skeleton.forward(&batch.target);
        let [b, channels, _] = features.dims();
        let fused = features.clone() + skeleton.reshape([b, channels, 1]);
        observe(cal, Point::Fused, &fused);
        let (raw, correction) = self.decoder.forward(fused, &batch.target, cal);
        let (prior, root) = batch.prior.solve(
            self.prior,
            batch.positions.clone(),
            &batch.source,
            &batch.target,
        );
        let root = root + correction;
        let rotations = fk::multiply(prior, fk::normalize(raw));
        let positions = fk::forward(rotations.clone(), root.clone(), &batch.target);
        Retargeted {
            rotations,
            root,
            positions,
            features,
        }
    }
}

/// A layer's parameters as plain arrays, for export.
#[derive(Clone, Debug, PartialEq)]
pub struct Dense {
    /// `[outputs][inputs]` row-major; a convolution's row is `[tap][input of its group]`.
    pub weight: Vec<f32>,
    /// One per output.
    pub bias: Vec<f32>,
    /// Inputs per output (a convolution's: kernel × inputs per group).
    pub inputs: usize,
}

impl Dense {
    /// Outputs.
    pub fn outputs(&self) -> usize {
        self.bias.len()
    }

    /// Columns `range` of every row: the layer seen by those inputs only.
    pub fn columns(&self, range: std::ops::Range<usize>) -> Dense {
        Dense {
            weight: self
                .weight
                .chunks_exact(self.inputs)
                .flat_map(|row| row[range.clone()].iter().copied())
                .collect(),
            bias: self.bias.clone(),
            inputs: range.len(),
        }
    }

    fn linear(layer: &Linear) -> Dense {
        let [inputs, outputs] = layer.weight.dims();
        let weight = floats(layer.weight.val().transpose());
        let bias = layer
            .bias
            .as_ref()
            .map_or(vec![0.0; outputs], |b| floats(b.val()));
        Dense {
            weight,
            bias,
            inputs,
        }
    }

    fn conv(layer: &Conv1d) -> Dense {
        let [outputs, width, kernel] = layer.weight.dims();
        Dense {
            weight: floats(layer.weight.val().swap_dims(1, 2)),
            bias: layer
                .bias
                .as_ref()
                .map_or(vec![0.0; outputs], |b| floats(b.val())),
            inputs: kernel * width,
        }
    }
}

/// Every parameter of a teacher as plain arrays, in the layers' order of use.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameters {
    /// Skeleton encoder: per joint hidden, per joint output, per segment.
    pub skeleton: [Dense; 3],
    /// Motion encoder's joint MLP: hidden (motion then rest features in), output.
    pub motion: [Dense; 2],
    /// `[T][d]` the time encoding added to the joint MLP's output.
    pub time: Vec<f32>,
    /// `[S][d]` the segment tokens.
    pub tokens: Vec<f32>,
    /// Attention: query, key, value, output.
    pub attention: [Dense; 4],
    /// Attention heads.
    pub heads: usize,
    /// The convolutions: down_1, down_2, up_1, up_2.
    pub convolutions: [Dense; 4],
    /// Joint decoder: hidden (segment feature then rest features in), output.
    pub decoder: [Dense; 2],
    /// The root's correction.
    pub root: Dense,
}

fn floats<const D: usize>(t: Tensor<D>) -> Vec<f32> {
    t.into_data().try_to_vec::<f32>().unwrap_or_default()
}

impl Teacher {
    /// Its parameters, for export.
    pub fn parameters(&self) -> Parameters {
        let (m, d) = (&self.motion, &self.decoder);
        let [_, width] = m.tokens.dims();
        Parameters {
            skeleton: [
                Dense::linear(&self.skeleton.joint.hidden),
                Dense::linear(&self.skeleton.joint.output),
                Dense::linear(&self.skeleton.segment),
            ],
            motion: [
                Dense::linear(&m.joint.hidden),
                Dense::linear(&m.joint.output),
            ],
            time: floats(
                m.time
                    .sinusoids
                    .clone()
                    .narrow(1, 0, WINDOW)
                    .reshape([WINDOW * width]),
            ),
            tokens: floats(m.tokens.val()),
            attention: [
                Dense::linear(&m.attention.query),
                Dense::linear(&m.attention.key),
                Dense::linear(&m.attention.value),
                Dense::linear(&m.attention.output),
            ],
            heads: m.attention.n_heads,
            convolutions: [
                Dense::conv(&m.down_1),
                Dense::conv(&m.down_2),
                Dense::conv(&d.up_1),
                Dense::conv(&d.up_2),
            ],
            decoder: [
                Dense::linear(&d.joint.hidden),
                Dense::linear(&d.joint.output),
            ],
            root: Dense::linear(&d.root),
        }
    }
}

fn act<const D: usize>(x: Tensor<D>) -> Tensor<D> {
    leaky_relu(x, LEAKY_SLOPE)
}

/// Records `x` at `point` when calibrating.
fn observe<const D: usize>(cal: &mut Option<&mut Calibration>, point: Point, x: &Tensor<D>) {
    if let Some(cal) = cal {
        cal.see(point, x);
    }
}

/// A linear layer that outputs zeros until trained: an untrained correction changes nothing.
fn zero_linear(input: usize, output: usize, device: &Device) -> Linear {
    LinearConfig::new(input, output)
        .with_initializer(Initializer::Zeros)
        .init(device)
}

/// Two linear layers with an activation between.
#[derive(Module, Debug)]
struct Mlp {
    hidden: Linear,
    output: Linear,
}

impl Mlp {
    fn new(input: usize, hidden: usize, output: usize, device: &Device) -> Mlp {
        Mlp {
            hidden: LinearConfig::new(input, hidden).init(device),
            output: LinearConfig::new(hidden, output).init(device),
        }
    }

    fn forward<const D: usize>(&self, x: Tensor<D>) -> Tensor<D> {
        self.output.forward(act(self.hidden.forward(x)))
    }

    /// [`Mlp::forward`], recording the hidden layer at `point`.
    fn forward_observed<const D: usize>(
        &self,
        x: Tensor<D>,
        cal: &mut Option<&mut Calibration>,
        point: Point,
    ) -> Tensor<D> {
        let hidden = act(self.hidden.forward(x));
        observe(cal, point, &hidden);
        self.output.forward(hidden)
    }
}

/// SE: a per-joint MLP over the target's rest offsets and positions, mean-pooled over each
/// segment's joints, then a linear layer: `[B, S, d]`.
#[derive(Module, Debug)]
struct SkeletonEncoder {
    joint: Mlp,
    segment: Linear,
}

impl SkeletonEncoder {
    fn new(config: &TeacherConfig, device: &Device) -> SkeletonEncoder {
        let d = config.features;
        SkeletonEncoder {
            joint: Mlp::new(REST_CHANNELS, d, d, device),
            segment: LinearConfig::new(d, d).init(device),
        }
    }

    fn forward(&self, target: &Skeletons) -> Tensor<3> {
        let joints = act(self.joint.forward(target.rest_features()));
        self.segment.forward(target.pool.clone().matmul(joints))
    }
}

/// ME: per-joint embedding plus a sinusoidal encoding of time; masked self-attention per
/// frame over segment tokens and joints, of which only the segment tokens' outputs are kept
/// (with a residual), so only they are computed as queries; two stride-2 convolutions within
/// segments plus an average-pooled residual: `[B, S·d, T/4]`.
#[derive(Module, Debug)]
struct MotionEncoder {
    joint: Mlp,
    time: PositionalEncoding,
    tokens: Param<Tensor<2>>,
    attention: MultiHeadAttention,
    down_1: Conv1d,
    down_2: Conv1d,
}

impl MotionEncoder {
    fn new(config: &TeacherConfig, device: &Device) -> MotionEncoder {
        let d = config.features;
        let tokens = Tensor::random(
            [SEGMENTS, d],
            Distribution::Normal(0.0, TOKEN_INIT_STD),
            device,
        );
        MotionEncoder {
            joint: Mlp::new(MOTION_CHANNELS + REST_CHANNELS, d, d, device),
            time: PositionalEncodingConfig::new(d)
                .with_max_sequence_size(WINDOW)
                .init(device),
            tokens: Param::from_tensor(tokens),
            attention: MultiHeadAttentionConfig::new(d, config.heads)
                .with_dropout(0.0)
                .with_min_float(MASKED_LOGIT)
                .init(device),
            down_1: config.conv(2, device),
            down_2: config.conv(2, device),
        }
    }

    fn forward(
        &self,
        motion: Tensor<4>,
        source: &Skeletons,
        cal: &mut Option<&mut Calibration>,
    ) -> Tensor<3> {
        let [b, t, j, _] = motion.dims();
        let rest = source
            .rest_features()
            .reshape([b, 1, j, REST_CHANNELS])
            .expand([b, t, j, REST_CHANNELS]);
        let motion = Tensor::cat(vec![motion, rest], 3);
        let [_, d] = self.tokens.dims();
        let keys = SEGMENTS + j;
        let time = self
            .time
            .sinusoids
            .clone()
            .narrow(1, 0, t)
            .reshape([1, t, 1, d]);
        let joints =
            (self.joint.forward_observed(motion, cal, Point::Hidden) + time).reshape([b * t, j, d]);
        observe(cal, Point::Joints, &joints);
        let segments = self
            .tokens
            .val()
            .reshape([1, SEGMENTS, d])
            .expand([b * t, SEGMENTS, d]);
        let x = Tensor::cat(vec![segments.clone(), joints], 1);
        let mask = source
            .attention
            .clone()
            .reshape([b, 1, SEGMENTS, keys])
            .expand([b, t, SEGMENTS, keys])
            .reshape([b * t, SEGMENTS, keys]);
        let attended = self
            .attention
            .forward(MhaInput::new(segments.clone(), x.clone(), x.clone()).mask_attn(mask));
        if cal.is_some() {
            // The context before the output layer: the weights times the heads' values.
            let (heads, width) = (self.attention.n_heads, self.attention.d_k);
            let values = self
                .attention
                .value
                .forward(x)
                .reshape([b * t, keys, heads, width])
                .swap_dims(1, 2);
            let context = attended.weights.matmul(values).swap_dims(1, 2);
            observe(cal, Point::Context, &context);
        }
        let segments = segments + attended.context;
        observe(cal, Point::Segments, &segments);
        let x = segments.reshape([b, t, SEGMENTS * d]).swap_dims(1, 2);
        let down = act(self.down_1.forward(x.clone()));
        observe(cal, Point::Down1, &down);
        let y = self.down_2.forward(down);
        observe(cal, Point::Down2, &y);
        let skip = x
            .reshape([b, SEGMENTS * d, t / DOWNSAMPLING, DOWNSAMPLING])
            .mean_dim(3)
            .reshape([b, SEGMENTS * d, t / DOWNSAMPLING]);
        act(y + skip)
    }
}

/// MD: two stages of linear ×2 upsampling and a convolution within segments; then, per
/// target joint, an MLP from its segment's feature and its rest offset and position to a raw
/// quaternion, and a linear layer from all segments to a root offset. Both are corrections
/// of the prior's solution ([`crate::prior`]): each bone's rotation is the prior's times the
/// correction, the root trajectory the prior's plus the offset. Their last layers start at
/// zero (the correction at the identity), so an untrained teacher is its prior.
#[derive(Module, Debug)]
struct Decoder {
    upsample: Interpolate1d,
    up_1: Conv1d,
    up_2: Conv1d,
    joint: Mlp,
    root: Linear,
}

impl Decoder {
    fn new(config: &TeacherConfig, device: &Device) -> Decoder {
        let d = config.features;
        Decoder {
            upsample: Interpolate1dConfig::new()
                .with_scale_factor(Some(UPSAMPLING))
                .with_mode(InterpolateMode::Linear)
                .with_align_corners(false)
                .init(),
            up_1: config.conv(1, device),
            up_2: config.conv(1, device),
            joint: Mlp {
                hidden: LinearConfig::new(d + REST_CHANNELS, d).init(device),
                output: zero_linear(d, QUATERNION, device),
            },
            root: zero_linear(SEGMENTS * d, 3, device),
        }
    }

    /// Raw quaternions `[B, J, T, 4]` and the root's correction `[B, T, 3]`.
    fn forward(
        &self,
        x: Tensor<3>,
        target: &Skeletons,
        cal: &mut Option<&mut Calibration>,
    ) -> (Tensor<4>, Tensor<3>) {
        let x = act(self.up_1.forward(self.upsample.forward(x)));
        observe(cal, Point::Up1, &x);
        let x = act(self.up_2.forward(self.upsample.forward(x)));
        observe(cal, Point::Up2, &x);
        let [b, channels, t] = x.dims();
        let d = channels / SEGMENTS;
        let root = self.root.forward(x.clone().swap_dims(1, 2));
        let [_, j, _] = target.segment.dims();
        let joints = target
            .segment
            .clone()
            .matmul(x.reshape([b, SEGMENTS, d * t]))
            .reshape([b, j, d, t])
            .swap_dims(2, 3);
        let rest = target
            .rest_features()
            .reshape([b, j, 1, REST_CHANNELS])
            .expand([b, j, t, REST_CHANNELS]);
        let identity =
            Tensor::<1>::from_floats(fk::IDENTITY, &root.device()).reshape([1, 1, 1, QUATERNION]);
        let raw =
            self.joint
                .forward_observed(Tensor::cat(vec![joints, rest], 3), cal, Point::Decoder)
                + identity;
        (raw, root)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::testing::character;
    use crate::features::testing::window;
    use posecoach_core::format::Format;

    const SEED: u64 = 3;
    const TOLERANCE: f32 = 1e-5;

    fn values<const D: usize>(t: Tensor<D>) -> Vec<f32> {
        t.to_data().try_to_vec::<f32>().unwrap()
    }

    /// Positions `[T, n, 3]` of window `i` of a batch padded to `joints`.
    fn real_positions(out: &Retargeted, i: usize, n: usize) -> Vec<f32> {
        values(out.positions.clone().narrow(0, i, 1).narrow(2, 0, n))
    }

    #[test]
    fn outputs_have_their_shapes_and_unit_rotations() {
        let device = Device::flex();
        device.seed(SEED);
        let model = TeacherConfig::TINY.init(&device);
        let windows = [Format::H36m17, Format::Cmu31].map(|f| window(&character(f, 1).skeleton));
        let batch = Batch::reconstruction(&windows, &device).unwrap();
        let j = batch.target.joints();
        let out = model.forward(&batch);
        assert_eq!(out.rotations.dims(), [2, j, WINDOW, 4]);
        assert_eq!(out.root.dims(), [2, WINDOW, 3]);
        assert_eq!(out.positions.dims(), [2, WINDOW, j, 3]);
        let norms = values(out.rotations.square().sum_dim(3));
        assert!(norms.iter().all(|n| (n - 1.0).abs() < TOLERANCE));
    }

    #[test]
    fn padding_and_batch_mates_do_not_change_outputs() {
        let device = Device::flex();
        device.seed(SEED);
        let model = TeacherConfig::TINY.init(&device);
        let skeleton = character(Format::Coco17, 2).skeleton;
        let n = skeleton.len();
        let alone = Batch::reconstruction(&[window(&skeleton)], &device).unwrap();
        let mate = window(&character(Format::Cmu31, 3).skeleton);
        let padded = Batch::reconstruction(&[mate, window(&skeleton)], &device).unwrap();
        let a = real_positions(&model.forward(&alone), 0, n);
        let b = real_positions(&model.forward(&padded), 1, n);
        let gap = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        assert!(gap < TOLERANCE, "{gap}");
    }
}
