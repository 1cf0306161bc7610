//! The geometric solution the teacher's decoder corrects, in one of two kinds ([`PriorKind`]).
//!
//! **Chords**: the analytic retargeter ([`posecoach_core::retarget::Analytic`]) as
//! differentiable tensors. Each target bone turns by the smallest rotation that takes a rest
//! chord of the target onto the corresponding chord of the source ([`Analytic::chord`]). A
//! chord is a linear function of the source positions (a row with +1 at its end and −1 at its
//! start), so the whole solution is a few products and differentiates through the cycle's
//! second pass like any other input.
//!
//! **Rotations**: the source's rotations estimated from its positions and its own rest pose
//! ([`Rotations`]: bone directions exact, twists as the format's standard T-pose gives them),
//! applied to the target's rest offsets through canonical names ([`counterparts`]; a target
//! joint without one keeps its parent's global rotation). Bone directions copy the source's
//! turned by the difference of the rest poses, which the chords cannot see: where the rest
//! poses differ, this is what separates the analytic retargeter from the ground truth.
//! Inverse kinematics is not a tensor operation, so this solution is a constant of the
//! positions it is given: no gradient flows through it (the decoder's correction still
//! differentiates through its inputs).
//!
//! Both move the root as the source's, scaled by the ratio of leg lengths: the analytic
//! retargeter's (to the toes where both skeletons have them) for the chords, from the root to
//! the ankles for the rotations ([`leg_length`]: a body's is the same in every format, so
//! its trajectory does not depend on the keypoints a capture has).

use crate::clip::{counterparts, leg_length, transfer, Rotations};
use crate::error::Error;
use crate::fk;
use crate::skeletons::Skeletons;
use burn::prelude::{Device, Tensor, TensorData};
use posecoach_core::retarget::{Analytic, RetargetError};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::{Quat, Vec3};

/// Added to a chord's squared length before its square root, so that a chord of zero (a bone
/// without one) stays finite, gradient included.
const LENGTH_EPSILON: f32 = 1e-12;

/// Which geometric solution the decoder corrects.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PriorKind {
    /// The analytic retargeter: bone directions copied.
    #[default]
    Chords,
    /// The source's rotations, estimated from its positions and its own rest pose, applied to
    /// the target's rest offsets.
    Rotations,
}

impl PriorKind {
    /// The factor this prior moves the root by, from `source`'s metres to `target`'s.
    ///
    /// # Errors
    /// [`Error::Retarget`] for a source without legs.
    pub fn trajectory_scale(self, source: &Skeleton, target: &Skeleton) -> Result<f32, Error> {
        Ok(match self {
            PriorKind::Chords => Analytic::new(source, target)?.scale(),
            PriorKind::Rotations => {
                let legs = leg_length(source);
                if legs <= f32::EPSILON {
                    return Err(Error::Retarget(RetargetError::DegenerateSource));
                }
                leg_length(target) / legs
            }
        })
    }
}

/// The geometric solutions of one side of a batch onto the other.
#[derive(Clone, Debug)]
pub struct Prior {
    /// `[B, J, J']` per target joint its source chord: +1 at the end, −1 at the start (a zero
    /// row for a bone that keeps its rest direction).
    chords: Tensor<3>,
    /// `[B, J, 1, 4]` the target's unit rest chords as pure quaternions, negated (zero where
    /// there is no chord).
    rest: Tensor<4>,
    /// `[B, 1, J']` the source root, times the analytic retargeter's scale of the trajectory
    /// from source heights to target heights.
    root: Tensor<3>,
    /// `[B, 1, J']` the same with the scale of the ratio of ankle leg lengths ([`leg_length`]).
    root_by_legs: Tensor<3>,
    /// Per pair, each target joint's source counterpart ([`counterparts`]).
    counterparts: Vec<Vec<Option<usize>>>,
    /// Per pair, the source's rotation estimator.
    rotations: Vec<Rotations>,
}

impl Prior {
    /// The analytic retargeter from each of `source`'s skeletons onto `target`'s at the same
    /// place.
    ///
    /// # Errors
    /// [`Error::Mismatch`] if the sides differ in length; [`Error::Retarget`] for a source
    /// without legs; else as [`Rotations::new`].
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
        let mut root_by_legs = vec![0.0; b * from];
        let mut matches = Vec::with_capacity(b);
        let mut rotations = Vec::with_capacity(b);
        let pairs = source.skeletons.iter().zip(&target.skeletons);
        for (i, (s, t)) in pairs.enumerate() {
            let analytic = Analytic::new(s, t)?;
            matches.push(counterparts(s, t));
            rotations.push(Rotations::new(s)?);
            let heights = source.heights[i] / target.heights[i];
            let scale = |kind: PriorKind| kind.trajectory_scale(s, t).map(|k| k * heights);
            root[i * from + analytic.root()] = scale(PriorKind::Chords)?;
            root_by_legs[i * from + analytic.root()] = scale(PriorKind::Rotations)?;
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
            root_by_legs: Tensor::from_data(TensorData::new(root_by_legs, [b, 1, from]), device),
            counterparts: matches,
            rotations,
        })
    }

    /// The `kind` of solution for source `positions` (`[B, T, J', 3]` on `source`, source
    /// heights): each target bone's rotation relative to its parent (`[B, J, T, 4]`, as [`fk`]
    /// takes them) and the root trajectory (`[B, T, 3]`, target heights).
    pub fn solve(
        &self,
        kind: PriorKind,
        positions: Tensor<4>,
        source: &Skeletons,
        target: &Skeletons,
    ) -> (Tensor<4>, Tensor<3>) {
        let [b, t, _, _] = positions.dims();
        let scaled = match kind {
            PriorKind::Chords => &self.root,
            PriorKind::Rotations => &self.root_by_legs,
        };
        let root = Skeletons::select(scaled, positions.clone()).reshape([b, t, 3]);
        let global = match kind {
            PriorKind::Chords => self.chord_globals(positions),
            PriorKind::Rotations => self.transferred_globals(positions, source, target),
        };
        (fk::local(global, target), root)
    }

    /// `[B, J, T, 4]` each target bone's global rotation by the chords.
    fn chord_globals(&self, positions: Tensor<4>) -> Tensor<4> {
        let [b, t, _, _] = positions.dims();
        let [_, j, _] = self.chords.dims();
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
        fk::normalize(fk::multiply(pure, rest) + identity)
    }

    /// `[B, J, T, 4]` each target bone's global rotation by the rotation transfer; the root's
    /// is the identity, as [`fk`] has it.
    fn transferred_globals(
        &self,
        positions: Tensor<4>,
        source: &Skeletons,
        target: &Skeletons,
    ) -> Tensor<4> {
        let device = positions.device();
        let [b, t, from, _] = positions.dims();
        let onto = target.joints();
        let values = positions
            .into_data()
            .try_to_vec::<f32>()
            .unwrap_or_default();
        let mut out = vec![0.0; b * onto * t * 4];
        out.chunks_exact_mut(4).for_each(|q| q[0] = 1.0);
        if values.len() != b * t * from * 3 {
            return Tensor::from_data(TensorData::new(out, [b, onto, t, 4]), &device);
        }
        let mut frame = vec![Vec3::zeros(); from];
        let mut source_global = vec![Quat::identity(); from];
        let mut global = vec![Quat::identity(); onto];
        let pairs = self.counterparts.iter().zip(&self.rotations);
        for (i, (matches, rotations)) in pairs.enumerate() {
            let n = source.skeletons[i].len();
            let m = target.skeletons[i].len();
            for f in 0..t {
                for (k, p) in frame[..n].iter_mut().enumerate() {
                    let at = ((i * t + f) * from + k) * 3;
                    *p = Vec3::new(values[at], values[at + 1], values[at + 2]);
                }
                if rotations.globals(&frame[..n], &mut source_global).is_err() {
                    continue;
                }
                transfer(&target.skeletons[i], matches, &source_global, &mut global);
                for (k, g) in global[..m].iter().enumerate() {
                    let q = if k == 0 { Quat::identity() } else { *g };
                    let at = ((i * onto + k) * t + f) * 4;
                    out[at..at + 4].copy_from_slice(&[q.w, q.i, q.j, q.k]);
                }
            }
        }
        Tensor::from_data(TensorData::new(out, [b, onto, t, 4]), &device)
    }
}
