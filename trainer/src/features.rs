//! Network inputs: motion windows as padded, batched tensors, with the skeletons they are
//! retargeted between ([`crate::skeletons`]) and the geometric solution the teacher corrects
//! ([`crate::prior`]).
//!
//! Every length is divided by its character's height (no per-character mean or variance), so
//! the features of one motion are the same whoever performs it, and a loss on them carries
//! the papers' `/h²` implicitly. Each side of a batch pads its joints to its largest skeleton
//! (`J`, at most [`MAX_JOINTS`](crate::skeletons::MAX_JOINTS)); padded joints are zero in
//! every tensor. With `B` windows and `T` = [`WINDOW`] frames:
//!
//! | tensor | shape | holds |
//! | --- | --- | --- |
//! | [`Batch::positions`] | `[B, T, J, 3]` | the source motion, the root as the root trajectory |
//! | [`Batch::motion`] | `[B, T, J, 6]` | per joint `p ⊕ v` ([`motion_features`]): its position relative to its parent and that position's change since the previous frame (heights per frame: golf's fastest joints stay near 1); the root's slot holds the root trajectory |
//! | [`Batch::source`], [`Batch::target`] | [`Skeletons`] | the two sides' skeletons as tensors |
//! | [`Batch::prior`] | [`Prior`] | the geometric solutions from source onto target |
//!
//! The **root trajectory** is the root's position relative to where it stands at the window's
//! first frame, horizontally (X and Z); its height (Y) is kept, so a crouch is not a drift.

use crate::error::Error;
use crate::prior::Prior;
use crate::skeletons::Skeletons;
use burn::prelude::{Device, Tensor, TensorData};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
use posecoach_io::Motion;

/// Frames in a window.
pub const WINDOW: usize = 64;
/// The window's frame rate.
pub const RATE_HZ: f32 = 30.0;
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
        let motion = motion.resampled(RATE_HZ)?;
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

/// `[B, T, J, 6]` motion features of positions `[B, T, J, 3]` on `skeletons`: each joint
/// relative to its parent (the root: itself; padding: zero) and its change since the previous
/// frame (the first frame takes the second's). Differentiable, so that
/// a retargeted motion can be fed back (the cycle).
pub fn motion_features(positions: Tensor<4>, skeletons: &Skeletons) -> Tensor<4> {
    let [b, t, j, _] = positions.dims();
    let bones = skeletons.bones.clone().reshape([b, 1, j, 1]);
    let relative = skeletons.from_parent(positions.clone()) * bones;
    let root = positions.narrow(2, 0, 1);
    let relative = Tensor::cat(vec![root, relative.narrow(2, 1, j - 1)], 2);
    let steps = relative.clone().narrow(1, 1, t - 1) - relative.clone().narrow(1, 0, t - 1);
    let velocity = Tensor::cat(vec![steps.clone().narrow(1, 0, 1), steps], 1);
    Tensor::cat(vec![relative, velocity], 3).reshape([b, t, j, MOTION_CHANNELS])
}

/// A batch of windows to retarget, each onto its target.
#[derive(Clone, Debug)]
pub struct Batch {
    /// The source skeletons.
    pub source: Skeletons,
    /// `[B, T, J, 3]` the source motions.
    pub positions: Tensor<4>,
    /// `[B, T, J, 6]` their features.
    pub motion: Tensor<4>,
    /// The target skeletons.
    pub target: Skeletons,
    /// The geometric solutions from source onto target that the teacher corrects.
    pub prior: Prior,
}

impl Batch {
    /// Each window to be retargeted onto the skeleton at the same place in `targets`.
    ///
    /// # Errors
    /// [`Error::Mismatch`] if the counts differ, else as [`Skeletons::new`].
    pub fn new(windows: &[Window], targets: &[&Skeleton], device: &Device) -> Result<Batch, Error> {
        if windows.len() != targets.len() {
            return Err(Error::Mismatch {
                expected: windows.len(),
                actual: targets.len(),
            });
        }
        let target = Skeletons::new(targets, device)?;
        let sources: Vec<&Skeleton> = windows.iter().map(Window::skeleton).collect();
        let source = Skeletons::new(&sources, device)?;
        let joints = source.joints();
        let mut positions = Vec::with_capacity(windows.len() * WINDOW * joints * 3);
        for window in windows {
            push_positions(window, joints, &mut positions);
        }
        let positions = Tensor::from_data(
            TensorData::new(positions, [windows.len(), WINDOW, joints, 3]),
            device,
        );
        Batch::on(source, positions, target)
    }

    /// Each window retargeted onto its own skeleton: the reconstruction task.
    ///
    /// # Errors
    /// As [`Skeletons::new`].
    pub fn reconstruction(windows: &[Window], device: &Device) -> Result<Batch, Error> {
        let skeletons: Vec<&Skeleton> = windows.iter().map(Window::skeleton).collect();
        Batch::new(windows, &skeletons, device)
    }

    /// Motions `[B, T, J, 3]` on `source` to retarget onto `target`.
    ///
    /// # Errors
    /// As [`Prior::new`].
    pub fn on(source: Skeletons, positions: Tensor<4>, target: Skeletons) -> Result<Batch, Error> {
        Ok(Batch {
            prior: Prior::new(&source, &target, &positions.device())?,
            motion: motion_features(positions.clone(), &source),
            positions,
            source,
            target,
        })
    }

    /// Windows in the batch.
    pub fn len(&self) -> usize {
        self.source.len()
    }

    /// Always false: a batch has at least one window.
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// Appends a window's `[T, J, 3]` positions in heights, padded with zeros.
fn push_positions(window: &Window, joints: usize, out: &mut Vec<f32>) {
    let n = window.skeleton().len();
    for frame in window.normalized().chunks_exact(n) {
        out.extend(frame.iter().flat_map(|p| [p.x, p.y, p.z]));
        out.extend((n..joints).flat_map(|_| [0.0; 3]));
    }
}

#[cfg(test)]
pub(crate) mod testing {
    //! Synthetic windows for tests that must run without the real data.
    use super::*;
    use crate::clip::testing::{wave_frames, RATE_HZ as WAVE_RATE_HZ};

    /// The synthetic wave on `skeleton`, long enough for one window.
    pub fn window(skeleton: &Skeleton) -> Window {
        let frames = (WINDOW as f32 * WAVE_RATE_HZ / RATE_HZ) as usize;
        Window::new(&wave_frames(skeleton, frames), 0).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::testing::window;
    use super::*;
    use crate::bodies::testing::character;
    use crate::clip::testing::wave_frames;
    use crate::clip::Clip;
    use crate::dataset::FORMATS;
    use crate::fk;
    use crate::prior::PriorKind;
    use posecoach_core::format::Format;
    use posecoach_core::retarget::Analytic;
    use posecoach_core::skeleton::SkeletonError;

    const TOLERANCE: f32 = 1e-5;

    fn values<const D: usize>(t: &Tensor<D>) -> Vec<f32> {
        t.to_data().try_to_vec::<f32>().unwrap()
    }

    #[test]
    fn features_rebuild_the_positions_and_padding_is_zero() {
        let skeleton = character(Format::H36m17, 1).skeleton;
        let mate = character(Format::Cmu31, 2).skeleton;
        let (n, joints) = (skeleton.len(), mate.len());
        let windows = [window(&skeleton), window(&mate)];
        let batch = Batch::reconstruction(&windows, &Device::flex()).unwrap();
        assert_eq!(batch.source.joints(), joints);
        let (motion, positions) = (values(&batch.motion), values(&batch.positions));
        let at = |t: usize, k: usize, c: usize| motion[(t * joints + k) * MOTION_CHANNELS + c];
        let position = |t: usize, k: usize, c: usize| positions[(t * joints + k) * 3 + c];
        for t in [0, 1, WINDOW - 1] {
            for k in 1..n {
                let p = skeleton.parent(k).unwrap();
                for c in 0..3 {
                    let rebuilt = position(t, p, c) + at(t, k, c);
                    assert!(
                        (rebuilt - position(t, k, c)).abs() < TOLERANCE,
                        "{t} {k} {c}"
                    );
                    let now = t.max(1);
                    let step = at(now, k, c) - at(now - 1, k, c);
                    let velocity = at(t, k, c + 3);
                    assert!((velocity - step).abs() < TOLERANCE, "{t} {k} {c}");
                }
            }
            assert_eq!(at(t, 0, 1), position(t, 0, 1));
            assert!((n..joints).all(|k| (0..6).all(|c| at(t, k, c) == 0.0)));
        }
        assert_eq!(
            (positions[0], positions[2]),
            (0.0, 0.0),
            "root starts at the origin"
        );
    }

    #[test]
    fn every_bone_has_a_segment_holding_both_ends() {
        for (seed, format) in FORMATS.into_iter().enumerate() {
            let skeleton = character(format, seed as u64).skeleton;
            for k in 1..skeleton.len() {
                let s = skeleton.bone_segment(k);
                let p = skeleton.parent(k).unwrap();
                assert!(
                    skeleton.segment_contains(s, k) && skeleton.segment_contains(s, p),
                    "{format} joint {k}"
                );
            }
        }
    }

    #[test]
    fn short_motions_small_paddings_and_mismatches_are_errors() {
        let skeleton = character(Format::Cmu31, 3).skeleton;
        let device = Device::flex();
        assert!(matches!(
            Skeletons::padded(&[&skeleton], 17, &device),
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
            Batch::reconstruction(&[], &device),
            Err(Error::EmptyBatch)
        ));
        assert!(matches!(
            Batch::new(&[window(&skeleton)], &[], &device),
            Err(Error::Mismatch { .. })
        ));
    }

    // The prior of a batch (crate::prior), checked through forward kinematics; here, where
    // batches are made, so that the prior's own module imports nothing above it.

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
        let (rotations, root) = batch.prior.solve(
            PriorKind::Chords,
            batch.positions.clone(),
            &batch.source,
            &batch.target,
        );
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

    #[test]
    fn the_rotation_prior_recovers_the_ground_truth_where_the_chords_miss_the_rest_poses() {
        let device = Device::flex();
        let pairs = [
            (Format::H36m17, Format::H36m17),
            (Format::Cmu31, Format::Coco17),
            (Format::Bandai22, Format::H36m17),
        ];
        let mut windows = Vec::new();
        let mut truths = Vec::new();
        let mut bodies = Vec::new();
        for (i, &(from, onto)) in pairs.iter().enumerate() {
            let standard = character(from, 20 + i as u64)
                .skeleton
                .standard_rest()
                .unwrap();
            let motion = wave_frames(&standard, 3 * WINDOW);
            let clip = Clip::from_motion("wave", &motion).unwrap();
            let source = character(from, i as u64);
            let target = character(onto, 10 + i as u64);
            windows.push(Window::new(&clip.on(&source).unwrap(), 0).unwrap());
            truths.push(clip.on(&target).unwrap().resampled(RATE_HZ).unwrap());
            bodies.push(target.skeleton);
        }
        let onto: Vec<_> = bodies.iter().collect();
        let batch = Batch::new(&windows, &onto, &device).unwrap();
        let error = |kind: PriorKind| {
            let (rotations, root) =
                batch
                    .prior
                    .solve(kind, batch.positions.clone(), &batch.source, &batch.target);
            let positions = fk::forward(rotations, root, &batch.target);
            let [_, frames, joints, _] = positions.dims();
            let got = positions.to_data().try_to_vec::<f32>().unwrap();
            let (mut sum, mut count) = (0.0, 0.0);
            for (i, (truth, target)) in truths.iter().zip(&bodies).enumerate() {
                let h = target.height();
                let at = |f: usize, k: usize| {
                    let p = &got[((i * frames + f) * joints + k) * 3..][..3];
                    Vec3::new(p[0], p[1], p[2]) * h
                };
                for f in 0..frames {
                    let truth = truth.frame(f);
                    for k in 1..target.len() {
                        let gap = (at(f, k) - at(f, 0)) - (truth[k] - truth[0]);
                        sum += gap.norm() / h;
                        count += 1.0;
                    }
                }
            }
            sum / count
        };
        let (rotations, chords) = (error(PriorKind::Rotations), error(PriorKind::Chords));
        assert!(
            rotations < 0.3 * chords && rotations < 0.004,
            "rotations {rotations}, chords {chords} (heights)"
        );
    }
}
