//! Network inputs: motion windows and target T-poses as padded, batched tensors.
//!
//! Every length is divided by its character's height (no per-character mean or variance), so
//! the features of one motion are the same whoever performs it, and a loss on them carries
//! the papers' `/h²` implicitly. Joints are padded to a fixed count `J` (at most
//! [`MAX_JOINTS`]); padded joints are zero in every tensor, belong to no segment and have no
//! bone. With `B` windows, `T` = [`WINDOW`] frames and `S` = [`SEGMENTS`]:
//!
//! | tensor | shape | holds |
//! | --- | --- | --- |
//! | [`Batch::motion`] | `[B, T, J, 6]` | per joint `p ⊕ v`: its position relative to its parent and that position's velocity (heights per second); the root's slot holds the root trajectory |
//! | [`Batch::attention`] | `[B, S, S + J]` bool | `true` where a segment token (row) must not see a key (column): segment tokens first, then joints |
//! | [`Target::offsets`] | `[B, J, 3]` | rest offsets from the parent (the root's: zero) |
//! | [`Target::rest`] | `[B, J, 3]` | rest positions relative to the root |
//! | [`Target::pool`] | `[B, S, J]` | `1 / n_s` for the `n_s` joints of segment `s`: masked mean pooling as a product |
//! | [`Target::segment`] | `[B, J, S]` | one-hot: the segment whose feature decodes the bone into each joint |
//! | [`Target::ancestors`] | `[B, J, J]` each | one-hot: pass `i` selects each joint's `2^i`-th ancestor (the root's, padding's and any beyond the root: the root) |
//! | [`Target::chains`] | `[B, J, J]` | 1 where the column is the row's joint or one of its non-root ancestors |
//! | [`Target::bones`] | `[B, J]` | 1 for every real joint but the root |
//! | [`Batch::truth`] | `[B, T, J, 3]` | the positions to reproduce, as the root trajectory |
//!
//! The **root trajectory** is the root's position relative to where it stands at the window's
//! first frame, horizontally (X and Z); its height (Y) is kept, so a crouch is not a drift.

use crate::error::Error;
use burn::prelude::{Bool, Device, Tensor, TensorData};
use posecoach_adapters::io::Motion;
use posecoach_core::skeleton::{Segment, Skeleton, SkeletonError};
use posecoach_core::Vec3;

/// Frames in a window.
pub const WINDOW: usize = 64;
/// The window's frame rate.
pub const RATE_HZ: f32 = 30.0;
/// The most joints a batch pads to (the core's limit).
pub const MAX_JOINTS: usize = posecoach_core::config::MAX_JOINTS;
/// Body segments: the tokens of the motion encoder and the skeleton encoder's outputs.
pub const SEGMENTS: usize = Segment::ALL.len();
/// Motion features per joint and frame: position and velocity.
pub const MOTION_CHANNELS: usize = 6;

/// [`WINDOW`] frames of a motion at [`RATE_HZ`], on its skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct Window {
    skeleton: Skeleton,
    positions: Vec<Vec3>,
}

impl Window {
    /// The window of `motion` (resampled to [`RATE_HZ`]) starting at frame `start`.
    ///
    /// # Errors
    /// [`Error::TooShort`] if fewer than [`WINDOW`] frames follow `start`.
    pub fn new(motion: &Motion, start: usize) -> Result<Window, Error> {
        let motion = motion.resampled(RATE_HZ);
        let available = motion.frames().saturating_sub(start);
        if available < WINDOW {
            return Err(Error::TooShort {
                expected: WINDOW,
                actual: available,
            });
        }
        let n = motion.skeleton.len();
        Ok(Window {
            positions: motion.positions[start * n..(start + WINDOW) * n].to_vec(),
            skeleton: motion.skeleton,
        })
    }

    /// The skeleton the motion is on.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// Joint positions of frame `t`, metres.
    ///
    /// # Panics
    /// If `t >= WINDOW`.
    pub fn frame(&self, t: usize) -> &[Vec3] {
        let n = self.skeleton.len();
        &self.positions[t * n..(t + 1) * n]
    }

    /// Positions divided by the height, relative to the window's first root position
    /// horizontally: the [`Batch::truth`] of one window, frame-major.
    fn normalized(&self) -> Vec<Vec3> {
        let start = self.frame(0)[0];
        let origin = Vec3::new(start.x, 0.0, start.z);
        let h = self.skeleton.height();
        self.positions.iter().map(|p| (p - origin) / h).collect()
    }
}

/// The target skeletons of a batch (see the module for the layouts).
#[derive(Clone, Debug)]
pub struct Target {
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
    /// Each target's height, metres: multiply positions by it to get metres.
    pub heights: Vec<f32>,
}

impl Target {
    /// The tensors of `skeletons`, padded to `joints` joints.
    ///
    /// # Errors
    /// [`Error::EmptyBatch`] without skeletons, [`SkeletonError::JointCount`] if one has more
    /// than `joints` joints.
    pub fn new(skeletons: &[&Skeleton], joints: usize, device: &Device) -> Result<Target, Error> {
        if skeletons.is_empty() {
            return Err(Error::EmptyBatch);
        }
        let mut rows = SkeletonRows::default();
        for skeleton in skeletons {
            if skeleton.len() > joints {
                return Err(SkeletonError::JointCount {
                    max: joints,
                    actual: skeleton.len(),
                }
                .into());
            }
            rows.push(skeleton, joints);
        }
        Ok(rows.into_target(skeletons.len(), joints, device))
    }
}

/// A batch of windows to retarget, each onto its target.
#[derive(Clone, Debug)]
pub struct Batch {
    /// `[B, T, J, 6]` source motion features.
    pub motion: Tensor<4>,
    /// `[B, S, S + J]` the motion encoder's attention mask on the source skeleton.
    pub attention: Tensor<3, Bool>,
    /// The target skeletons.
    pub target: Target,
    /// `[B, T, J, 3]` the target positions to reproduce.
    pub truth: Tensor<4>,
}

impl Batch {
    /// Each window retargeted onto its own skeleton, padded to `joints` joints: the
    /// reconstruction task.
    ///
    /// # Errors
    /// As [`Target::new`].
    pub fn reconstruction(
        windows: &[Window],
        joints: usize,
        device: &Device,
    ) -> Result<Batch, Error> {
        let skeletons: Vec<&Skeleton> = windows.iter().map(Window::skeleton).collect();
        let target = Target::new(&skeletons, joints, device)?;
        let b = windows.len();
        let mut motion = Vec::with_capacity(b * WINDOW * joints * MOTION_CHANNELS);
        let mut truth = Vec::with_capacity(b * WINDOW * joints * 3);
        let mut attention = Vec::with_capacity(b * SEGMENTS * (SEGMENTS + joints));
        for window in windows {
            push_motion(window, joints, &mut motion, &mut truth);
            push_attention(window.skeleton(), joints, &mut attention);
        }
        let tokens = SEGMENTS + joints;
        Ok(Batch {
            motion: Tensor::from_data(
                TensorData::new(motion, [b, WINDOW, joints, MOTION_CHANNELS]),
                device,
            ),
            attention: Tensor::from_data(TensorData::new(attention, [b, SEGMENTS, tokens]), device),
            target,
            truth: Tensor::from_data(TensorData::new(truth, [b, WINDOW, joints, 3]), device),
        })
    }

    /// Windows in the batch.
    pub fn len(&self) -> usize {
        self.target.heights.len()
    }

    /// Always false: a batch has at least one window.
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// Appends a window's `[T, J, 6]` motion features and `[T, J, 3]` truth, padded.
fn push_motion(window: &Window, joints: usize, motion: &mut Vec<f32>, truth: &mut Vec<f32>) {
    let skeleton = window.skeleton();
    let n = skeleton.len();
    let positions = window.normalized();
    let relative: Vec<Vec3> = positions
        .chunks_exact(n)
        .flat_map(|frame| {
            (0..n).map(move |k| match skeleton.parent(k) {
                Some(p) => frame[k] - frame[p],
                None => frame[k],
            })
        })
        .collect();
    for t in 0..WINDOW {
        // Backward differences; the first frame takes the second's.
        let before = t.max(1) - 1;
        let now = before + 1;
        for k in 0..joints {
            if k >= n {
                motion.extend([0.0; MOTION_CHANNELS]);
                truth.extend([0.0; 3]);
                continue;
            }
            let p = relative[t * n + k];
            let v = (relative[now * n + k] - relative[before * n + k]) * RATE_HZ;
            motion.extend([p.x, p.y, p.z, v.x, v.y, v.z]);
            let q = positions[t * n + k];
            truth.extend([q.x, q.y, q.z]);
        }
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

/// The segment whose feature decodes the bone into joint `k`: the first that holds both the
/// joint and its parent (a limb's first bone starts at the branching joint the limb holds).
pub fn bone_segment(skeleton: &Skeleton, k: usize) -> usize {
    let parent = skeleton.parent(k).unwrap_or(0);
    let holds = |s: Segment, i: usize| skeleton.segment_contains(s, i);
    Segment::ALL
        .iter()
        .position(|&s| holds(s, k) && holds(s, parent))
        .or_else(|| Segment::ALL.iter().position(|&s| holds(s, k)))
        .unwrap_or(Segment::Spine as usize)
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
    depth: usize,
    heights: Vec<f32>,
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
                true => bone_segment(skeleton, k),
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
                    .flat_map(|up| {
                        up.iter()
                            .flat_map(|&a| (0..joints).map(move |c| f32::from(u8::from(c == a))))
                    })
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

    fn into_target(self, b: usize, joints: usize, device: &Device) -> Target {
        let floats = |data: Vec<f32>, shape: Vec<usize>| TensorData::new(data, shape);
        let ancestors = self
            .ancestors(joints)
            .into_iter()
            .map(|a| Tensor::from_data(floats(a, vec![b, joints, joints]), device))
            .collect();
        Target {
            offsets: Tensor::from_data(floats(self.offsets, vec![b, joints, 3]), device),
            rest: Tensor::from_data(floats(self.rest, vec![b, joints, 3]), device),
            pool: Tensor::from_data(floats(self.pool, vec![b, SEGMENTS, joints]), device),
            segment: Tensor::from_data(floats(self.segment, vec![b, joints, SEGMENTS]), device),
            ancestors,
            chains: Tensor::from_data(floats(self.chains, vec![b, joints, joints]), device),
            bones: Tensor::from_data(floats(self.bones, vec![b, joints]), device),
            heights: self.heights,
        }
    }
}

#[cfg(test)]
pub(crate) mod testing {
    //! Synthetic windows for tests that must run without the real data.
    use super::*;
    use crate::bodies::{sample_character, Character};
    use crate::clip::testing::{wave_frames, RATE_HZ as WAVE_RATE_HZ};
    use posecoach_core::format::Format;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A random character of `format`, seeded.
    pub fn character(format: Format, seed: u64) -> Character {
        sample_character(format, &mut ChaCha8Rng::seed_from_u64(seed)).unwrap()
    }

    /// The synthetic wave on `skeleton`, long enough for one window.
    pub fn window(skeleton: &Skeleton) -> Window {
        let frames = (WINDOW as f32 * WAVE_RATE_HZ / RATE_HZ) as usize;
        Window::new(&wave_frames(skeleton, frames), 0).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::testing::{character, window};
    use super::*;
    use crate::dataset::FORMATS;

    const TOLERANCE: f32 = 1e-6;

    fn values<const D: usize>(t: &Tensor<D>) -> Vec<f32> {
        t.to_data().try_to_vec::<f32>().unwrap()
    }

    #[test]
    fn features_rebuild_the_truth_and_padding_is_zero() {
        let skeleton = character(posecoach_core::format::Format::H36m17, 1).skeleton;
        let n = skeleton.len();
        let batch = Batch::reconstruction(&[window(&skeleton)], MAX_JOINTS, &Device::flex());
        let batch = batch.unwrap();
        let (motion, truth) = (values(&batch.motion), values(&batch.truth));
        for t in [0, WINDOW - 1] {
            let at = |k: usize, c: usize| motion[(t * MAX_JOINTS + k) * MOTION_CHANNELS + c];
            let truth = |k: usize, c: usize| truth[(t * MAX_JOINTS + k) * 3 + c];
            for k in 1..n {
                let p = skeleton.parent(k).unwrap();
                for c in 0..3 {
                    let rebuilt = truth(p, c) + at(k, c);
                    assert!((rebuilt - truth(k, c)).abs() < TOLERANCE, "{t} {k} {c}");
                }
            }
            assert_eq!(at(0, 1), truth(0, 1));
            assert!((n..MAX_JOINTS).all(|k| (0..6).all(|c| at(k, c) == 0.0)));
        }
        assert_eq!(
            (truth[0], truth[2]),
            (0.0, 0.0),
            "root starts at the origin"
        );
    }

    #[test]
    fn every_bone_has_a_segment_holding_both_ends() {
        for (seed, format) in FORMATS.into_iter().enumerate() {
            let skeleton = character(format, seed as u64).skeleton;
            for k in 1..skeleton.len() {
                let s = Segment::ALL[bone_segment(&skeleton, k)];
                let p = skeleton.parent(k).unwrap();
                assert!(
                    skeleton.segment_contains(s, k) && skeleton.segment_contains(s, p),
                    "{format} joint {k}"
                );
            }
        }
    }

    #[test]
    fn segment_tokens_see_their_joints_and_the_root() {
        let skeleton = character(posecoach_core::format::Format::Coco17, 2).skeleton;
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

    #[test]
    fn short_motions_and_small_paddings_are_errors() {
        let skeleton = character(posecoach_core::format::Format::Cmu31, 3).skeleton;
        let w = window(&skeleton);
        assert!(matches!(
            Batch::reconstruction(&[w], 17, &Device::flex()),
            Err(Error::Skeleton(SkeletonError::JointCount { max: 17, .. }))
        ));
        let short = crate::clip::testing::wave_frames(&skeleton, WINDOW);
        assert!(matches!(
            Window::new(&short, 0),
            Err(Error::TooShort {
                expected: WINDOW,
                ..
            })
        ));
        assert!(matches!(
            Batch::reconstruction(&[], MAX_JOINTS, &Device::flex()),
            Err(Error::EmptyBatch)
        ));
    }
}
