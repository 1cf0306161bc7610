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
//! source's root there, scaled as the analytic retargeter scales it, is added back.

use crate::clip::motion;
use crate::error::Error;
use crate::features::{Batch, Window, RATE_HZ, WINDOW};
use crate::model::Teacher;
use crate::train::{load_teacher, TrainConfig};
use burn::prelude::Device;
use posecoach_adapters::io::Motion;
use posecoach_core::retarget::Analytic;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
use std::path::Path;

/// Most interleaved streams a motion is split into (a 240 Hz capture: 8).
const MAX_PHASES: usize = 8;

/// A trained teacher on an inference device.
#[derive(Clone, Debug)]
pub struct Retargeter {
    teacher: Teacher,
    device: Device,
    /// What tables call it: its file's stem.
    pub name: String,
    /// How it was trained.
    pub config: TrainConfig,
    /// Steps it was trained for.
    pub steps: usize,
}

impl Retargeter {
    /// The teacher in a checkpoint or teacher file ([`crate::train`]).
    ///
    /// # Errors
    /// [`Error::Checkpoint`] if the file cannot be read.
    pub fn load(path: &Path) -> Result<Retargeter, Error> {
        let device = Device::flex();
        let (teacher, config, steps) = load_teacher(path, &device)?;
        let name = path
            .file_stem()
            .map_or("teacher".into(), |s| s.to_string_lossy().into_owned());
        Ok(Retargeter {
            name,
            teacher,
            device,
            config,
            steps,
        })
    }

    /// `source` retargeted onto `target`, at the source's rate and length.
    ///
    /// # Errors
    /// [`Error::TooShort`] for a motion without frames, [`Error::Retarget`] for a source
    /// without legs, else as [`Batch::new`].
    pub fn retarget(&self, source: &Motion, target: &Skeleton) -> Result<Motion, Error> {
        let frames = source.frames();
        if frames == 0 || !source.rate_hz.is_finite() || source.rate_hz <= 0.0 {
            return Err(Error::TooShort {
                expected: 1,
                actual: 0,
            });
        }
        let scale = Analytic::new(&source.skeleton, target)?.scale();
        let phases = ((source.rate_hz / RATE_HZ).round() as usize).clamp(1, MAX_PHASES);
        let fine = held(&source.resampled(RATE_HZ * phases as f32), WINDOW * phases);
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
        let out = motion(target, RATE_HZ * phases as f32, positions).resampled(source.rate_hz);
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
        let batch = Batch::new(&windows, &targets, &self.device)?;
        let values: Vec<f32> = self
            .teacher
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
    use crate::clip::testing::wave_frames;
    use crate::features::testing::character;
    use crate::model::TeacherConfig;
    use posecoach_core::format::Format;

    #[test]
    fn an_untrained_teacher_retargets_as_the_analytic_retargeter() {
        let device = Device::flex();
        device.seed(4);
        let retargeter = Retargeter {
            teacher: TeacherConfig::TINY.init(&device),
            device,
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
            let analytic = m
                .retarget_analytic(&motion(&target, rate_hz, Vec::new()))
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
    fn whole_motions_keep_their_rate_length_and_target_bones() {
        let device = Device::flex();
        device.seed(1);
        let retargeter = Retargeter {
            teacher: TeacherConfig::TINY.init(&device),
            device,
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
