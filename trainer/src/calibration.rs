//! The activations the int8 network keeps ([`Point`]) and their largest magnitudes on golf
//! windows ([`Calibration`]): what the float network records while it runs
//! ([`crate::model::Teacher::forward_observed`]) and the int8 scales come from
//! ([`crate::quantize`]).

use crate::features::MOTION_CHANNELS;
use burn::prelude::Tensor;
use posecoach_core::int8;
use posecoach_core::weights::Scales;

/// The activations the quantized network keeps in int8, where the float network makes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Point {
    /// The motion features (one scale per channel).
    Motion,
    /// The motion encoder's hidden layer.
    Hidden,
    /// Joint embeddings plus the time encoding.
    Joints,
    /// The attention's context before its output layer.
    Context,
    /// Segment tokens after attention.
    Segments,
    /// After the first downsampling convolution (activated).
    Down1,
    /// After the second, before the residual.
    Down2,
    /// The decoder's input: motion feature plus skeleton feature.
    Fused,
    /// After the first decoder convolution (activated).
    Up1,
    /// After the second (activated).
    Up2,
    /// The joint decoder's hidden layer.
    Decoder,
}

/// Points after [`Point::Motion`], in [`Scales`] order.
const POINTS: [Point; 10] = [
    Point::Hidden,
    Point::Joints,
    Point::Context,
    Point::Segments,
    Point::Down1,
    Point::Down2,
    Point::Fused,
    Point::Up1,
    Point::Up2,
    Point::Decoder,
];

/// Smallest magnitude a scale is computed from: an activation or weight row that is zero
/// everywhere still gets a valid scale.
pub(crate) const TINY: f32 = 1e-8;

/// The largest magnitudes seen at each [`Point`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Calibration {
    motion: [f32; MOTION_CHANNELS],
    max: [f32; POINTS.len()],
    /// Windows seen.
    pub windows: usize,
    /// An activation could not be read back as `f32`s: the scales would miss it.
    pub(crate) unreadable: bool,
}

impl Calibration {
    /// Records the magnitudes of `x` at `point`.
    pub fn see<const D: usize>(&mut self, point: Point, x: &Tensor<D>) {
        let Ok(values) = x.clone().abs().into_data().try_to_vec::<f32>() else {
            self.unreadable = true;
            return;
        };
        match POINTS.iter().position(|&p| p == point) {
            Some(i) => self.max[i] = values.iter().copied().fold(self.max[i], f32::max),
            None => {
                for row in values.chunks_exact(MOTION_CHANNELS) {
                    for (m, v) in self.motion.iter_mut().zip(row) {
                        *m = m.max(*v);
                    }
                }
            }
        }
    }

    /// The int8 scales: each point's largest magnitude over 127.
    pub fn scales(&self) -> Scales {
        let s = |m: f32| m.max(TINY) / int8::MAX as f32;
        let [hidden, joints, context, segments, down_1, down_2, fused, up_1, up_2, decoder] =
            self.max.map(s);
        Scales {
            motion: self.motion.map(s),
            hidden,
            joints,
            context,
            segments,
            down_1,
            down_2,
            fused,
            up_1,
            up_2,
            decoder,
        }
    }
}
