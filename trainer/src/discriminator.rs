//! The adversarial loss's discriminator: plain 1-D convolutions over time, per joint.
//!
//! Skeletons differ in joints, so the discriminator judges each bone's motion on its own:
//! a joint's motion features beside its rest features, `[B·J, 12, T]`, through three
//! convolutions (two with stride 2) to a score per joint and quarter window, averaged over
//! the real bones. Least-squares GAN: real motions score 1, retargeted ones 0.

use crate::features::MOTION_CHANNELS;
use crate::skeletons::{Skeletons, REST_CHANNELS};
use burn::nn::conv::{Conv1d, Conv1dConfig};
use burn::nn::PaddingConfig1d;
use burn::prelude::{Device, Module, Tensor};
use burn::tensor::activation::leaky_relu;

/// Channels of the hidden convolutions.
const CHANNELS: usize = 32;
/// Kernel size of every convolution.
const KERNEL: usize = 3;
/// Negative slope of the activations.
const LEAKY_SLOPE: f64 = 0.2;

/// The discriminator.
#[derive(Module, Debug)]
pub struct Discriminator {
    convs: Vec<Conv1d>,
}

impl Discriminator {
    /// A randomly initialized discriminator on `device`.
    pub fn new(device: &Device) -> Discriminator {
        let conv = |input: usize, output: usize, stride: usize| {
            Conv1dConfig::new(input, output, KERNEL)
                .with_stride(stride)
                .with_padding(PaddingConfig1d::Explicit(KERNEL / 2, KERNEL / 2))
                .init(device)
        };
        Discriminator {
            convs: vec![
                conv(MOTION_CHANNELS + REST_CHANNELS, CHANNELS, 2),
                conv(CHANNELS, CHANNELS, 2),
                conv(CHANNELS, 1, 1),
            ],
        }
    }

    /// Scores `[B, J, T/4]` of motion features `[B, T, J, 6]` on `skeletons`.
    fn scores(&self, motion: Tensor<4>, skeletons: &Skeletons) -> Tensor<3> {
        let [b, t, j, _] = motion.dims();
        let rest = skeletons
            .rest_features()
            .reshape([b, 1, j, REST_CHANNELS])
            .expand([b, t, j, REST_CHANNELS]);
        let mut x = Tensor::cat(vec![motion, rest], 3)
            .permute([0, 2, 3, 1])
            .reshape([b * j, MOTION_CHANNELS + REST_CHANNELS, t]);
        let last = self.convs.len() - 1;
        for (i, conv) in self.convs.iter().enumerate() {
            x = conv.forward(x);
            if i < last {
                x = leaky_relu(x, LEAKY_SLOPE);
            }
        }
        let [_, _, steps] = x.dims();
        x.reshape([b, j, steps])
    }

    /// The least-squares distance of the scores from `label` (1 real, 0 retargeted), averaged
    /// over the real bones and time.
    pub fn loss(&self, motion: Tensor<4>, skeletons: &Skeletons, label: f32) -> Tensor<1> {
        let scores = self.scores(motion, skeletons);
        let [b, j, steps] = scores.dims();
        let bones = skeletons.bones.clone().reshape([b, j, 1]);
        let count = bones.clone().sum().mul_scalar(steps as f32);
        (scores.sub_scalar(label).square() * bones).sum() / count
    }
}
