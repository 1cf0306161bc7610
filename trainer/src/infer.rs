//! A trained teacher retargeting whole motions: cut into windows, retargeted in one batch,
//! put back together at the motion's own rate.
//!
//! The network runs at [`RATE_HZ`]. A motion at `k` times that rate (60 Hz: `k` = 2) is
//! resampled to exactly `k · RATE_HZ` and split into `k` interleaved streams at [`RATE_HZ`]
//! (frames 0, 2, 4, … and 1, 3, 5, …), each retargeted and interleaved back, so no frame of a
//! fast downswing is lost to interpolation; the result is resampled to the source's rate
//! (an identity for a multiple of [`RATE_HZ`]). Each stream is cut into consecutive
//! [`WINDOW`]-frame windows, the last one ending at the last frame (so it may overlap its
//! neighbour, whose frames it replaces); a motion shorter than a window holds its last frame.
//! Each window's root trajectory starts at its first frame ([`crate::features`]), so the
//! source's root there, scaled as the network's prior scales the trajectory, is added back.
//!
//! A weights blob ([`posecoach_core::weights`]) runs the same way through the core's int8
//! network ([`posecoach_core::network`]), which cuts and holds windows as this module does.

use crate::clip::{motion, standard_rest};
use crate::error::Error;
use crate::features::{Batch, Window, RATE_HZ, WINDOW};
use crate::model::{Teacher, TeacherConfig};
use crate::prior::PriorKind;
use crate::train::{read_weights, teacher_from_bytes, TrainConfig};
use burn::prelude::Device;
use posecoach_core::network;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::weights::{self, Weights};
use posecoach_core::Vec3;
use posecoach_io::Motion;
use std::path::Path;

/// Most interleaved streams a motion is split into (a 240 Hz capture: 8).
const MAX_PHASES: usize = 8;

/// A trained network: a float teacher (or the distilled network) or its int8 export.
#[derive(Clone, Debug)]
enum Model {
    Float {
        teacher: Box<Teacher>,
        device: Device,
    },
    /// A weights blob, in words so that it is aligned for the core's in-place view.
    Int8 { words: Vec<u32>, len: usize },
}

/// A trained network ready to retarget.
#[derive(Clone, Debug)]
pub struct Retargeter {
    model: Model,
    /// What tables call it: its file's stem.
    pub name: String,
    /// How it was trained.
    pub config: TrainConfig,
    /// Steps it was trained for.
    pub steps: usize,
}

impl Retargeter {
    /// The network in a checkpoint or teacher file ([`crate::train`]) or a weights blob.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] if the file cannot be read or its network not loaded,
    /// [`Error::TeachFile`] if a float file is not sound.
    pub fn load(path: &Path) -> Result<Retargeter, Error> {
        let name = path
            .file_stem()
            .map_or("teacher".into(), |s| s.to_string_lossy().into_owned());
        let bytes = read_weights(path)?;
        if bytes.starts_with(&weights::MAGIC) {
            return Retargeter::int8(name, &bytes);
        }
        let device = Device::flex();
        let (teacher, config, steps) = teacher_from_bytes(&bytes, &device)?;
        Ok(Retargeter {
            name,
            model: Model::Float {
                teacher: Box::new(teacher),
                device,
            },
            config,
            steps,
        })
    }

    /// The int8 network of a weights blob, called `name`.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] if the blob is not sound.
    pub fn int8(name: String, bytes: &[u8]) -> Result<Retargeter, Error> {
        let mut words = vec![0u32; bytes.len().div_ceil(4)];
        bytes_mut(&mut words)[..bytes.len()].copy_from_slice(bytes);
        let header = Weights::from_bytes(bytes_of(&words, bytes.len()))
            .map_err(|e| Error::Checkpoint(e.to_string()))?
            .header()
            .clone();
        let a = header.architecture;
        let config = TrainConfig {
            teacher: TeacherConfig {
                features: a.d(),
                heads: usize::from(a.heads),
                kernel: usize::from(a.kernel),
                prior: PriorKind::Chords,
            },
            seed: header.training.seed,
            ..TrainConfig::default()
        };
        Ok(Retargeter {
            name,
            model: Model::Int8 {
                words,
                len: bytes.len(),
            },
            config,
            steps: header.training.steps as usize,
        })
    }

    /// `source` retargeted onto `target`, at the source's rate and length.
    ///
    /// Rest poses are not motion. The source's motion is its positions: its skeleton's rest
    /// pose is the file's zero pose (CMU's BVH hangs the arms, Bandai's has its own), so the
    /// source is re-rested on its format's standard T-pose first ([`standard_rest`]: the same
    /// positions and bone lengths); without it, the rotation transfer read a hanging arm at
    /// rest as a T-pose arm turned 90°. The target's T-pose gives its bone lengths; its bones'
    /// directions are a measurement with error (a phone's estimate of a student's T-pose is
    /// several degrees off per bone), so the network works on the target re-rested too
    /// ([`Skeleton::standard_rest`]) and the output, on `target`'s joints, has its bone
    /// lengths and none of its posture.
    ///
    /// # Errors
    /// [`Error::TooShort`] for a motion without frames, [`Error::Retarget`] for a source
    /// without legs, else as [`Batch::new`].
    pub fn retarget(&self, source: &Motion, target: &Skeleton) -> Result<Motion, Error> {
        let source = &standard_rest(source)?;
        let frames = source.frames();
        if frames == 0 || !source.rate_hz.is_finite() || source.rate_hz <= 0.0 {
            return Err(Error::TooShort {
                expected: 1,
                actual: 0,
            });
        }
        let prior = match &self.model {
            Model::Float { teacher, .. } => teacher.prior(),
            Model::Int8 { .. } => PriorKind::Chords,
        };
        let output = target;
        let target = &target.standard_rest()?;
        let scale = prior.trajectory_scale(&source.skeleton, target)?;
        let phases = ((source.rate_hz / RATE_HZ).round() as usize).clamp(1, MAX_PHASES);
        let fine = held(&source.resampled(RATE_HZ * phases as f32)?, WINDOW * phases);
        let (length, m) = (fine.frames(), target.len());
        let mut positions = vec![Vec3::zeros(); length * m];
        for phase in 0..phases {
            let slow: Vec<Vec3> = (phase..length)
                .step_by(phases)
                .flat_map(|f| fine.frame(f).iter().copied())
                .collect();
            let slow = motion(&source.skeleton, RATE_HZ, slow);
            let out = self.retarget_slow(&slow, target, scale)?;
            for (i, pose) in out.chunks_exact(m).enumerate() {
                positions[(phase + i * phases) * m..][..m].copy_from_slice(pose);
            }
        }
        let out = motion(output, RATE_HZ * phases as f32, positions).resampled(source.rate_hz)?;
        Ok(fitted(out, frames))
    }

    /// Positions on `target` of `slow` (at [`RATE_HZ`], at least [`WINDOW`] frames), whose
    /// root trajectory the network scales by `scale`.
    fn retarget_slow(
        &self,
        slow: &Motion,
        target: &Skeleton,
        scale: f32,
    ) -> Result<Vec<Vec3>, Error> {
        let (teacher, device) = match &self.model {
            Model::Float { teacher, device } => (teacher, device),
            Model::Int8 { words, len } => {
                let weights = Weights::from_bytes(bytes_of(words, *len))
                    .map_err(|e| Error::Checkpoint(e.to_string()))?;
                let mut scratch = vec![0u32; network::MAX_SCRATCH.div_ceil(4)];
                let mut out = vec![Vec3::zeros(); slow.frames() * target.len()];
                network::retarget(
                    &weights,
                    &slow.skeleton,
                    target,
                    &slow.positions,
                    bytes_mut(&mut scratch),
                    &mut out,
                )
                .map_err(|e| Error::Checkpoint(e.to_string()))?;
                return Ok(out);
            }
        };
        let length = slow.frames();
        let mut starts: Vec<usize> = (0..=length - WINDOW).step_by(WINDOW).collect();
        if starts.last() != Some(&(length - WINDOW)) {
            starts.push(length - WINDOW);
        }
        let windows = starts
            .iter()
            .map(|&s| Window::new(slow, s))
            .collect::<Result<Vec<_>, _>>()?;
        let targets = vec![target; windows.len()];
        let batch = Batch::new(&windows, &targets, device)?;
        let values: Vec<f32> = teacher
            .forward(&batch)
            .positions
            .into_data()
            .try_to_vec()
            .map_err(|e| Error::Checkpoint(format!("{e:?}")))?;
        let m = target.len();
        let mut positions = vec![Vec3::zeros(); length * m];
        for (w, &start) in starts.iter().enumerate() {
            let root = slow.frame(start)[0];
            let origin = Vec3::new(root.x, 0.0, root.z) * scale;
            let window = &values[w * WINDOW * m * 3..(w + 1) * WINDOW * m * 3];
            for (i, p) in window.chunks_exact(3).enumerate() {
                positions[start * m + i] = Vec3::new(p[0], p[1], p[2]) * target.height() + origin;
            }
        }
        Ok(positions)
    }
}

/// The first `len` bytes of `words`.
fn bytes_of(words: &[u32], len: usize) -> &[u8] {
    &bytemuck::cast_slice(words)[..len]
}

/// `words` as bytes, to write.
fn bytes_mut(words: &mut [u32]) -> &mut [u8] {
    bytemuck::cast_slice_mut(words)
}

/// `m` with its last frame repeated up to `frames` frames.
fn held(m: &Motion, frames: usize) -> Motion {
    fitted(m.clone(), m.frames().max(frames))
}

/// `m` cut or extended (its last frame held) to exactly `frames` frames.
fn fitted(mut m: Motion, frames: usize) -> Motion {
    let n = m.skeleton.len();
    let last = m.positions[m.positions.len() - n..].to_vec();
    m.positions.truncate(frames * n);
    m.missing.truncate(frames * n);
    while m.positions.len() < frames * n {
        m.positions.extend_from_slice(&last);
        m.missing.extend(std::iter::repeat_n(false, n));
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::testing::character;
    use crate::clip::leg_length;
    use crate::clip::testing::wave_frames;
    use posecoach_core::format::Format;

    #[test]
    fn an_untrained_teacher_retargets_as_the_analytic_retargeter_on_the_standard_rest_poses() {
        let device = Device::flex();
        device.seed(4);
        let retargeter = Retargeter {
            model: Model::Float {
                teacher: Box::new(TeacherConfig::TINY.init(&device)),
                device,
            },
            name: "untrained".into(),
            config: TrainConfig::default(),
            steps: 0,
        };
        let source = character(Format::GolfMarkers, 3).skeleton;
        let target = character(Format::Cmu31, 4).skeleton;
        for (frames, rate_hz) in [(150, 60.0), (90, 30.0), (40, 120.0)] {
            let mut m = wave_frames(&source, frames);
            m.rate_hz = rate_hz;
            let out = retargeter.retarget(&m, &target).unwrap();
            // Both skeletons re-rested, as the network sees them (the characters' rest poses
            // are turned up to 5 degrees a bone).
            let rested = motion(&target.standard_rest().unwrap(), rate_hz, Vec::new());
            let analytic = standard_rest(&m)
                .unwrap()
                .retarget_analytic(&rested)
                .unwrap();
            let gap = out
                .positions
                .iter()
                .zip(&analytic.positions)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f32::max);
            assert!(gap < 1e-4 * target.height(), "{rate_hz} Hz: {gap} m");
        }
    }

    #[test]
    fn an_untrained_rotation_teacher_moves_the_root_by_the_ratio_of_leg_lengths() {
        let device = Device::flex();
        device.seed(4);
        let config = TeacherConfig {
            prior: PriorKind::Rotations,
            ..TeacherConfig::TINY
        };
        let retargeter = Retargeter {
            model: Model::Float {
                teacher: Box::new(config.init(&device)),
                device,
            },
            name: "untrained".into(),
            config: TrainConfig {
                teacher: config,
                ..TrainConfig::default()
            },
            steps: 0,
        };
        let source = character(Format::GolfMarkers, 3).skeleton;
        let target = character(Format::Cmu31, 4).skeleton;
        let scale = leg_length(&target) / leg_length(&source);
        for (frames, rate_hz) in [(150, 60.0), (90, 30.0)] {
            let mut m = wave_frames(&source, frames);
            m.rate_hz = rate_hz;
            let out = retargeter.retarget(&m, &target).unwrap();
            for f in 0..frames {
                let gap = (out.frame(f)[0] - m.frame(f)[0] * scale).norm();
                assert!(
                    gap < 1e-4 * target.height(),
                    "{rate_hz} Hz frame {f}: {gap} m"
                );
            }
        }
    }

    #[test]
    fn whole_motions_keep_their_rate_length_and_target_bones() {
        let device = Device::flex();
        device.seed(1);
        let retargeter = Retargeter {
            model: Model::Float {
                teacher: Box::new(TeacherConfig::TINY.init(&device)),
                device,
            },
            name: "tiny".into(),
            config: TrainConfig::default(),
            steps: 0,
        };
        let source = character(Format::Cmu31, 1).skeleton;
        let target = character(Format::H36m17, 2).skeleton;
        for frames in [10, 200] {
            let m = wave_frames(&source, frames);
            let out = retargeter.retarget(&m, &target).unwrap();
            assert_eq!((out.frames(), out.rate_hz), (frames, m.rate_hz));
            assert_eq!(out.skeleton, target);
            let bone = |f: usize, k: usize| {
                (out.frame(f)[k] - out.frame(f)[target.parent(k).unwrap()]).norm()
            };
            for k in 1..target.len() {
                let rest = target.offset(k).norm();
                assert!((bone(0, k) - rest).abs() < 1e-4 * target.height(), "{k}");
            }
        }
    }
}
