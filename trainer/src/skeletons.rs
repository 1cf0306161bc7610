//! Skeletons as padded, batched tensors: the source or the target side of a batch
//! ([`crate::features`]).
//!
//! Every length is divided by its skeleton's height, as the motions are. A side pads its
//! joints to its largest skeleton (`J`, at most [`MAX_JOINTS`]); padded joints are zero in
//! every tensor, belong to no segment, have no bone and no canonical name. With `B`
//! skeletons, `S` = [`SEGMENTS`], `C` = [`JOINT_COUNT`] canonical joints and `E` =
//! [`EFFECTORS`]:
//!
//! | tensor | shape | holds |
//! | --- | --- | --- |
//! | [`Skeletons::attention`] | `[B, S, S + J]` bool | `true` where a segment token (row) must not see a key (column): segment tokens first, then joints |
//! | [`Skeletons::offsets`] | `[B, J, 3]` | rest offsets from the parent (the root's: zero) |
//! | [`Skeletons::rest`] | `[B, J, 3]` | rest positions relative to the root |
//! | [`Skeletons::pool`] | `[B, S, J]` | `1 / n_s` for the `n_s` joints of segment `s`: masked mean pooling as a product |
//! | [`Skeletons::segment`] | `[B, J, S]` | one-hot: the segment whose feature decodes the bone into each joint |
//! | [`Skeletons::ancestors`] | `[B, J, J]` each | one-hot: pass `i` selects each joint's `2^i`-th ancestor (the root's, padding's and any beyond the root: the root) |
//! | [`Skeletons::chains`] | `[B, J, J]` | 1 where the column is the row's joint or one of its non-root ancestors |
//! | [`Skeletons::bones`] | `[B, J]` | 1 for every real joint but the root |
//! | [`Skeletons::canonical`] | `[B, C, J]` | one-hot: the joint with each canonical name (a zero row where there is none) |
//! | [`Skeletons::present`] | `[B, C]` | 1 where the skeleton has the canonical joint |
//! | [`Skeletons::effectors`] | `[B, E, J]` | one-hot: the end effectors, in [`EndEffector::ALL`] order |

use crate::error::Error;
use burn::prelude::{Bool, Device, Tensor, TensorData};
use posecoach_core::joint::{Joint, JOINT_COUNT};
use posecoach_core::skeleton::{EndEffector, Segment, Skeleton, SkeletonError};
use posecoach_core::Vec3;

/// The most joints a batch pads to (the core's limit).
pub const MAX_JOINTS: usize = posecoach_core::config::MAX_JOINTS;
/// Body segments: the tokens of the motion encoder and the skeleton encoder's outputs.
pub const SEGMENTS: usize = Segment::ALL.len();
/// Rest features per joint: offset from the parent and position from the root.
pub const REST_CHANNELS: usize = 6;
/// End effectors per skeleton.
pub const EFFECTORS: usize = EndEffector::ALL.len();

/// The skeletons of one side of a batch (see the module for the layouts).
#[derive(Clone, Debug)]
pub struct Skeletons {
    /// `[B, J, 3]` rest offsets from the parent.
    pub offsets: Tensor<3>,
    /// `[B, J, 3]` rest positions relative to the root.
    pub rest: Tensor<3>,
    /// `[B, S, J]` masked mean pooling over each segment's joints.
    pub pool: Tensor<3>,
    /// `[B, J, S]` the segment decoding each joint's bone, one-hot.
    pub segment: Tensor<3>,
    /// `[B, J, J]` per doubling pass `i`, one-hot rows selecting the `2^i`-th ancestor; as
    /// many passes as it takes `2^i` to reach the deepest joint's bone count. The first
    /// selects the parents (even without bones deeper than one).
    pub ancestors: Vec<Tensor<3>>,
    /// `[B, J, J]` each joint's chain from the root (the root excluded).
    pub chains: Tensor<3>,
    /// `[B, J]` 1 for real non-root joints.
    pub bones: Tensor<2>,
    /// `[B, C, J]` the joint with each canonical name.
    pub canonical: Tensor<3>,
    /// `[B, C]` 1 where the canonical joint exists.
    pub present: Tensor<2>,
    /// `[B, E, J]` the end effectors.
    pub effectors: Tensor<3>,
    /// `[B, S, S + J]` the motion encoder's attention mask.
    pub attention: Tensor<3, Bool>,
    /// Each skeleton's height, metres: multiply positions by it to get metres.
    pub heights: Vec<f32>,
    /// The skeletons themselves.
    pub skeletons: Vec<Skeleton>,
}

impl Skeletons {
    /// The tensors of `skeletons`, padded to the largest.
    ///
    /// # Errors
    /// [`Error::EmptyBatch`] without skeletons, [`SkeletonError::JointCount`] if one has more
    /// than [`MAX_JOINTS`] joints.
    pub fn new(skeletons: &[&Skeleton], device: &Device) -> Result<Skeletons, Error> {
        let joints = skeletons.iter().map(|s| s.len()).max();
        Skeletons::padded(skeletons, joints.ok_or(Error::EmptyBatch)?, device)
    }

    /// The tensors of `skeletons`, padded to `joints` joints.
    ///
    /// # Errors
    /// [`Error::EmptyBatch`] without skeletons, [`SkeletonError::JointCount`] if one has more
    /// than `joints` (or [`MAX_JOINTS`]) joints.
    pub fn padded(
        skeletons: &[&Skeleton],
        joints: usize,
        device: &Device,
    ) -> Result<Skeletons, Error> {
        if skeletons.is_empty() {
            return Err(Error::EmptyBatch);
        }
        let mut rows = SkeletonRows::default();
        for skeleton in skeletons {
            if skeleton.len() > joints.min(MAX_JOINTS) {
                return Err(SkeletonError::JointCount {
                    max: joints.min(MAX_JOINTS),
                    actual: skeleton.len(),
                }
                .into());
            }
            rows.push(skeleton, joints);
        }
        Ok(rows.into_skeletons(skeletons, joints, device))
    }

    /// Skeletons in the batch.
    pub fn len(&self) -> usize {
        self.heights.len()
    }

    /// Always false: a batch has at least one skeleton.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Joints per skeleton, padding included.
    pub fn joints(&self) -> usize {
        self.bones.dims()[1]
    }

    /// `[B, J, 6]` rest offsets and positions side by side.
    pub fn rest_features(&self) -> Tensor<3> {
        Tensor::cat(vec![self.offsets.clone(), self.rest.clone()], 2)
    }

    /// `[B, T, J, 3]` the positions of `x` (`[B, T, J, 3]`) relative to their parents.
    pub fn from_parent(&self, x: Tensor<4>) -> Tensor<4> {
        let [b, t, j, c] = x.dims();
        let joint_major = x.clone().swap_dims(1, 2).reshape([b, j, t * c]);
        let above = self.ancestors[0]
            .clone()
            .matmul(joint_major)
            .reshape([b, j, t, c]);
        x - above.swap_dims(1, 2)
    }

    /// `[B, T, K, 3]` the rows of `x` (`[B, T, J, 3]`) that `selection` (`[B, K, J]`) picks.
    pub fn select(selection: &Tensor<3>, x: Tensor<4>) -> Tensor<4> {
        let [b, t, j, c] = x.dims();
        let [_, k, _] = selection.dims();
        let joint_major = x.swap_dims(1, 2).reshape([b, j, t * c]);
        selection
            .clone()
            .matmul(joint_major)
            .reshape([b, k, t, c])
            .swap_dims(1, 2)
    }
}

/// Appends a skeleton's `[S, S + J]` attention mask (`true` = blocked): a segment token sees
/// itself, its joints and the root. Only the segment tokens' outputs are kept, so they are
/// the only queries.
fn push_attention(skeleton: &Skeleton, joints: usize, out: &mut Vec<bool>) {
    let real = |k: usize| k < skeleton.len();
    for query in 0..SEGMENTS {
        for key in 0..SEGMENTS + joints {
            let sees = match key.checked_sub(SEGMENTS) {
                None => query == key,
                Some(k) => real(k) && (k == 0 || skeleton.segment_contains(Segment::ALL[query], k)),
            };
            out.push(!sees);
        }
    }
}

/// Target skeleton rows accumulated on the host.
#[derive(Default)]
struct SkeletonRows {
    offsets: Vec<f32>,
    rest: Vec<f32>,
    pool: Vec<f32>,
    segment: Vec<f32>,
    parents: Vec<Vec<usize>>,
    chains: Vec<f32>,
    bones: Vec<f32>,
    canonical: Vec<f32>,
    present: Vec<f32>,
    effectors: Vec<f32>,
    attention: Vec<bool>,
    depth: usize,
    heights: Vec<f32>,
}

/// A tensor of `shape` on `device` holding `data`.
fn floats<const D: usize>(data: Vec<f32>, shape: [usize; D], device: &Device) -> Tensor<D> {
    Tensor::from_data(TensorData::new(data, shape), device)
}

/// A one-hot row of `len` with a 1 at `at`, if any.
fn one_hot(at: Option<usize>, len: usize) -> impl Iterator<Item = f32> {
    (0..len).map(move |c| f32::from(u8::from(Some(c) == at)))
}

impl SkeletonRows {
    fn push(&mut self, skeleton: &Skeleton, joints: usize) {
        let n = skeleton.len();
        let h = skeleton.height();
        let mut rest = vec![Vec3::zeros(); n];
        skeleton.rest_positions(&mut rest);
        let mut depth = vec![0usize; joints];
        let mut parents = vec![0; joints];
        for k in 0..joints {
            let parent = (k > 0 && k < n).then(|| skeleton.parent(k)).flatten();
            let (offset, from_root) = match parent {
                Some(_) => (skeleton.offset(k) / h, (rest[k] - rest[0]) / h),
                None => (Vec3::zeros(), Vec3::zeros()),
            };
            self.offsets.extend(offset.iter());
            self.rest.extend(from_root.iter());
            parents[k] = parent.unwrap_or(0);
            let segment = match k < n {
                true => skeleton.bone_segment(k) as usize,
                false => Segment::Spine as usize,
            };
            self.segment
                .extend((0..SEGMENTS).map(|s| if s == segment { 1.0 } else { 0.0 }));
            self.bones.push(if parent.is_some() { 1.0 } else { 0.0 });
            if let Some(p) = parent {
                depth[k] = depth[p] + 1;
            }
            let chain: Vec<usize> = skeleton.ancestry(k).collect();
            self.chains
                .extend((0..joints).map(|a| match chain.contains(&a) {
                    true => 1.0,
                    false => 0.0,
                }));
        }
        for segment in Segment::ALL {
            let count = (0..n)
                .filter(|&k| skeleton.segment_contains(segment, k))
                .count();
            self.pool.extend(
                (0..joints).map(|k| match skeleton.segment_contains(segment, k) {
                    true => 1.0 / count as f32,
                    false => 0.0,
                }),
            );
        }
        for joint in Joint::ALL {
            let at = skeleton.index_of(joint);
            self.canonical.extend(one_hot(at, joints));
            self.present.push(f32::from(u8::from(at.is_some())));
        }
        for effector in EndEffector::ALL {
            self.effectors
                .extend(one_hot(Some(skeleton.end_effector(effector)), joints));
        }
        push_attention(skeleton, joints, &mut self.attention);
        self.depth = self.depth.max(depth.into_iter().max().unwrap_or(0));
        self.parents.push(parents);
        self.heights.push(h);
    }

    /// `[B, J, J]` one-hot selections of each joint's `2^i`-th ancestor, `i` = 0, 1, …
    fn ancestors(&self, joints: usize) -> Vec<Vec<f32>> {
        let mut jumps = self.parents.clone();
        let mut out = Vec::new();
        loop {
            out.push(
                jumps
                    .iter()
                    .flat_map(|up| up.iter().flat_map(|&a| one_hot(Some(a), joints)))
                    .collect(),
            );
            if 1 << out.len() >= self.depth {
                return out;
            }
            for up in &mut jumps {
                *up = up.iter().map(|&a| up[a]).collect();
            }
        }
    }

    fn into_skeletons(self, skeletons: &[&Skeleton], joints: usize, device: &Device) -> Skeletons {
        let b = skeletons.len();
        let ancestors = self
            .ancestors(joints)
            .into_iter()
            .map(|a| floats(a, [b, joints, joints], device))
            .collect();
        Skeletons {
            offsets: floats(self.offsets, [b, joints, 3], device),
            rest: floats(self.rest, [b, joints, 3], device),
            pool: floats(self.pool, [b, SEGMENTS, joints], device),
            segment: floats(self.segment, [b, joints, SEGMENTS], device),
            ancestors,
            chains: floats(self.chains, [b, joints, joints], device),
            bones: floats(self.bones, [b, joints], device),
            canonical: floats(self.canonical, [b, JOINT_COUNT, joints], device),
            present: floats(self.present, [b, JOINT_COUNT], device),
            effectors: floats(self.effectors, [b, EFFECTORS, joints], device),
            attention: Tensor::from_data(
                TensorData::new(self.attention, [b, SEGMENTS, SEGMENTS + joints]),
                device,
            ),
            heights: self.heights,
            skeletons: skeletons.iter().map(|&s| s.clone()).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::testing::character;
    use posecoach_core::format::Format;

    #[test]
    fn segment_tokens_see_their_joints_and_the_root() {
        let skeleton = character(Format::Coco17, 2).skeleton;
        let mut mask = Vec::new();
        push_attention(&skeleton, MAX_JOINTS, &mut mask);
        let tokens = SEGMENTS + MAX_JOINTS;
        let sees = |q: usize, k: usize| !mask[q * tokens + k];
        let left_arm = Segment::LeftArm as usize;
        let wrist = skeleton
            .index_of(posecoach_core::joint::Joint::LeftWrist)
            .unwrap();
        assert!(sees(left_arm, SEGMENTS + wrist));
        assert!(sees(left_arm, SEGMENTS));
        assert!(!sees(Segment::RightLeg as usize, SEGMENTS + wrist));
        assert!(sees(left_arm, left_arm) && !sees(left_arm, Segment::RightArm as usize));
        let padded = SEGMENTS + skeleton.len();
        assert!((0..SEGMENTS).all(|s| !sees(s, padded)));
    }
}
