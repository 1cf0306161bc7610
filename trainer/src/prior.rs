//! The analytic retargeter ([`posecoach_core::retarget::Analytic`]) as differentiable tensors:
//! the solution the teacher's decoder corrects.
//!
//! Each target bone turns by the smallest rotation that takes a rest chord of the target onto
//! the corresponding chord of the source ([`Analytic::chord`]); the root follows the source's,
//! scaled by the ratio of leg lengths. A chord is a linear function of the source positions
//! (a row with +1 at its end and −1 at its start), so the whole solution is a few products
//! and differentiates through the cycle's second pass like any other input.

use crate::error::Error;
use crate::features::Skeletons;
use crate::fk;
use burn::prelude::{Device, Tensor, TensorData};
use posecoach_core::retarget::Analytic;

/// Added to a chord's squared length before its square root, so that a chord of zero (a bone
/// without one) stays finite, gradient included.
const LENGTH_EPSILON: f32 = 1e-12;

/// The analytic solution of one side of a batch onto the other.
#[derive(Clone, Debug)]
pub struct Prior {
    /// `[B, J, J']` per target joint its source chord: +1 at the end, −1 at the start (a zero
    /// row for a bone that keeps its rest direction).
    chords: Tensor<3>,
    /// `[B, J, 1, 4]` the target's unit rest chords as pure quaternions, negated (zero where
    /// there is no chord).
    rest: Tensor<4>,
    /// `[B, 1, J']` the source root, times the scale of the trajectory from source heights to
    /// target heights.
    root: Tensor<3>,
}

impl Prior {
    /// The analytic retargeter from each of `source`'s skeletons onto `target`'s at the same
    /// place.
    ///
    /// # Errors
    /// [`Error::Mismatch`] if the sides differ in length; [`Error::Retarget`] for a source
    /// without legs.
    pub fn new(source: &Skeletons, target: &Skeletons, device: &Device) -> Result<Prior, Error> {
        if source.len() != target.len() {
            return Err(Error::Mismatch {
                expected: source.len(),
                actual: target.len(),
            });
        }
        let (b, from, onto) = (source.len(), source.joints(), target.joints());
        let mut chords = vec![0.0; b * onto * from];
        let mut rest = vec![0.0; b * onto * 4];
        let mut root = vec![0.0; b * from];
        let pairs = source.skeletons.iter().zip(&target.skeletons);
        for (i, (s, t)) in pairs.enumerate() {
            let analytic = Analytic::new(s, t)?;
            root[i * from + analytic.root()] =
                analytic.scale() * source.heights[i] / target.heights[i];
            for k in 0..t.len() {
                let Some(chord) = analytic.chord(k) else {
                    continue;
                };
                let row = (i * onto + k) * from;
                chords[row + chord.to] += 1.0;
                chords[row + chord.from] -= 1.0;
                let unit = chord.rest / (chord.rest.norm_squared() + LENGTH_EPSILON).sqrt();
                rest[(i * onto + k) * 4 + 1..][..3].copy_from_slice(&(-unit).as_slice()[..3]);
            }
        }
        Ok(Prior {
            chords: Tensor::from_data(TensorData::new(chords, [b, onto, from]), device),
            rest: Tensor::from_data(TensorData::new(rest, [b, onto, 1, 4]), device),
            root: Tensor::from_data(TensorData::new(root, [b, 1, from]), device),
        })
    }

    /// The analytic retargeting of source `positions` (`[B, T, J', 3]`, source heights):
    /// each target bone's rotation relative to its parent (`[B, J, T, 4]`, as [`fk`] takes
    /// them) and the root trajectory (`[B, T, 3]`, target heights).
    pub fn solve(&self, positions: Tensor<4>, target: &Skeletons) -> (Tensor<4>, Tensor<3>) {
        let [b, t, _, _] = positions.dims();
        let [_, j, _] = self.chords.dims();
        let root = Skeletons::select(&self.root, positions.clone()).reshape([b, t, 3]);
        let chords = Skeletons::select(&self.chords, positions).swap_dims(1, 2);
        let length = chords
            .clone()
            .square()
            .sum_dim(3)
            .add_scalar(LENGTH_EPSILON)
            .sqrt();
        let direction = chords / length;
        let pure = Tensor::cat(
            vec![Tensor::zeros([b, j, t, 1], &direction.device()), direction],
            3,
        );
        // (0, d)·(0, −r) = (d·r, r × d): plus the identity, twice the half-way quaternion.
        let identity = Tensor::<1>::from_floats(fk::IDENTITY, &pure.device()).reshape([1, 1, 1, 4]);
        let rest = self.rest.clone().expand([b, j, t, 4]);
        let global = fk::normalize(fk::multiply(pure, rest) + identity);
        (fk::local(global, target), root)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::testing::{character, window};
    use crate::features::Batch;
    use posecoach_core::format::Format;
    use posecoach_core::Vec3;

    const TOLERANCE: f32 = 1e-5;

    #[test]
    fn forward_kinematics_of_the_prior_is_the_analytic_retargeter() {
        let device = Device::flex();
        let formats = [Format::Coco17, Format::GolfMarkers, Format::Cmu31];
        let targets = [Format::Cmu31, Format::H36m17, Format::Bandai22];
        let windows: Vec<_> = formats
            .iter()
            .enumerate()
            .map(|(i, &f)| window(&character(f, i as u64).skeleton))
            .collect();
        let bodies: Vec<_> = targets
            .iter()
            .enumerate()
            .map(|(i, &f)| character(f, 10 + i as u64).skeleton)
            .collect();
        let onto: Vec<_> = bodies.iter().collect();
        let batch = Batch::new(&windows, &onto, &device).unwrap();
        let (rotations, root) = batch.prior.solve(batch.positions.clone(), &batch.target);
        let positions = fk::forward(rotations, root, &batch.target);
        let [_, frames, joints, _] = positions.dims();
        let got = positions.to_data().try_to_vec::<f32>().unwrap();
        for (i, (window, target)) in windows.iter().zip(&bodies).enumerate() {
            let analytic = Analytic::new(window.skeleton(), target).unwrap();
            let h = target.height();
            let mut out = vec![Vec3::zeros(); target.len()];
            let origin = window.frame(0)[0];
            for f in 0..frames {
                analytic.frame(window.frame(f), &mut out).unwrap();
                let start = Vec3::new(origin.x, 0.0, origin.z) * analytic.scale();
                for (k, expected) in out.iter().enumerate() {
                    let p = &got[((i * frames + f) * joints + k) * 3..][..3];
                    let p = Vec3::new(p[0], p[1], p[2]) * h;
                    let gap = (p - (expected - start)).norm() / h;
                    assert!(gap < TOLERANCE, "window {i} frame {f} joint {k}: {gap}");
                }
            }
        }
    }
}
