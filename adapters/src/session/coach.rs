//! The coach reference as the session keeps it: its frames at the model rate, and the virtual
//! coach made from them on the student's skeleton (by the analytic retargeter or the int8
//! network).

use super::Refusal;
use posecoach_core::config::MAX_JOINTS;
use posecoach_core::network::{self, NetworkError};
use posecoach_core::reference::Reference;
use posecoach_core::retarget::Analytic;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::weights::Weights;
use posecoach_core::Vec3;

/// A stored coach reference swing.
#[derive(Clone, Copy, Debug)]
pub struct Coach<'c> {
    /// The coach's skeleton.
    pub skeleton: &'c Skeleton,
    /// Frames × joints of `skeleton`.
    pub positions: &'c [Vec3],
    /// Frame rate, Hz.
    pub rate_hz: f32,
}

impl<'c> From<&'c Reference<'c>> for Coach<'c> {
    /// A stored reference ([`posecoach_core::reference`]) as the session takes it.
    fn from(reference: &'c Reference<'c>) -> Coach<'c> {
        Coach {
            skeleton: reference.skeleton(),
            positions: reference.positions(),
            rate_hz: reference.rate_hz(),
        }
    }
}

impl Coach<'_> {
    fn frames(&self) -> usize {
        self.positions.len() / self.skeleton.len().max(1)
    }

    /// Its frames at `rate_hz`, as the session keeps the virtual coach
    /// ([`frames_at`]).
    pub fn frames_at(&self, rate_hz: u16) -> usize {
        frames_at(self.frames(), self.rate_hz, rate_hz)
    }

    /// Where frame `k` at `rate_hz` falls among the coach's own frames: the frame before and
    /// the fraction of the way to the next. Rates within [`SAME_RATE`] of each other are the
    /// same rate (a 60.00006 Hz capture is a 60 Hz one): the frames are then used as they are.
    fn source_of(&self, k: usize, rate_hz: u16) -> (usize, f32) {
        if same_rate(self.rate_hz, rate_hz) {
            return (k, 0.0);
        }
        let t = k as f32 * self.rate_hz / f32::from(rate_hz);
        let i = (t as usize).min(self.frames().saturating_sub(1));
        (i, t - i as f32)
    }

    /// The rate of the virtual coach: the model rate, or the coach's own where they are the
    /// same rate ([`SAME_RATE`]) and its frames are used as they are.
    pub(super) fn rate_at(&self, rate_hz: u16) -> f32 {
        if same_rate(self.rate_hz, rate_hz) {
            self.rate_hz
        } else {
            f32::from(rate_hz)
        }
    }

    /// Frame `k` at `rate_hz`, interpolated into `between` when it falls between two of the
    /// coach's own frames.
    fn frame_at<'a>(
        &'a self,
        k: usize,
        rate_hz: u16,
        between: &'a mut [Vec3; MAX_JOINTS],
    ) -> Option<&'a [Vec3]> {
        let n = self.skeleton.len();
        let (i, fraction) = self.source_of(k, rate_hz);
        let frame = |i: usize| self.positions.get(i * n..(i + 1) * n);
        match (frame(i), frame(i + 1)) {
            (Some(a), Some(b)) if fraction > 0.0 => {
                for ((m, p), q) in between.iter_mut().zip(a).zip(b) {
                    *m = p + (q - p) * fraction;
                }
                Some(&between[..n])
            }
            (Some(a), _) => Some(a),
            (None, _) => None,
        }
    }

    /// The coach at `rate_hz` retargeted onto `student` frame by frame with the analytic
    /// retargeter, into `out` (whole frames of the student).
    pub(super) fn retarget_analytic(
        &self,
        student: &Skeleton,
        rate_hz: u16,
        out: &mut [Vec3],
    ) -> Result<(), Refusal> {
        let retarget = Analytic::new(self.skeleton, student).map_err(|_| Refusal::Retarget)?;
        let mut between = [Vec3::zeros(); MAX_JOINTS];
        for (k, pose) in out.chunks_exact_mut(student.len()).enumerate() {
            let source = self
                .frame_at(k, rate_hz, &mut between)
                .ok_or(Refusal::Retarget)?;
            retarget
                .frame(source, pose)
                .map_err(|_| Refusal::Retarget)?;
        }
        Ok(())
    }

    /// The coach at `rate_hz` retargeted onto `student` by the int8 network of `weights`, into
    /// `out` (whole frames of the student); its input and scratch are carved from `ring`.
    pub(super) fn retarget_network(
        &self,
        weights: &Weights<'_>,
        student: &Skeleton,
        rate_hz: u16,
        ring: &mut [Vec3],
        out: &mut [Vec3],
    ) -> Result<(), Refusal> {
        let n = self.skeleton.len();
        let frames = out.len() / student.len().max(1);
        let (source, rest) = ring
            .split_at_mut_checked(frames * n)
            .ok_or(Refusal::Buffers)?;
        let mut between = [Vec3::zeros(); MAX_JOINTS];
        for (k, pose) in source.chunks_exact_mut(n).enumerate() {
            let frame = self
                .frame_at(k, rate_hz, &mut between)
                .ok_or(Refusal::Retarget)?;
            pose.copy_from_slice(frame);
        }
        let scratch: &mut [u8] = bytemuck::cast_slice_mut(rest);
        network::retarget(weights, self.skeleton, student, source, scratch, out).map_err(
            |e| match e {
                NetworkError::Scratch => Refusal::Buffers,
                _ => Refusal::Retarget,
            },
        )
    }
}

/// Relative difference under which two frame rates are one.
pub const SAME_RATE: f32 = 1e-3;

pub(super) const fn same_rate(coach_hz: f32, rate_hz: u16) -> bool {
    let ratio = coach_hz / rate_hz as f32;
    ratio > 1.0 - SAME_RATE && ratio < 1.0 + SAME_RATE
}

/// Frames a coach reference of `frames` frames at `coach_hz` has at the model rate `rate_hz`:
/// the session retargets the coach at the model rate (interpolating its frames), so that the
/// student's and the coach's swings are compared frame for frame; the same frames when the
/// rates are the same ([`SAME_RATE`]).
pub const fn frames_at(frames: usize, coach_hz: f32, rate_hz: u16) -> usize {
    if frames == 0 || same_rate(coach_hz, rate_hz) {
        return frames;
    }
    ((frames - 1) as f32 * rate_hz as f32 / coach_hz) as usize + 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_core::format::Format;

    #[test]
    fn a_coach_is_kept_at_the_model_rate() {
        assert_eq!(frames_at(110, 60.000_057, 60), 110);
        assert_eq!(frames_at(110, 60.000_057, 30), 55);
        assert_eq!(frames_at(110, 60.0, 120), 219);
        assert_eq!(frames_at(0, 60.0, 30), 0);
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let positions = [Vec3::zeros(); 17 * 4];
        let coach = Coach {
            skeleton: &skeleton,
            positions: &positions,
            rate_hz: 60.000_057,
        };
        assert_eq!(coach.source_of(3, 60), (3, 0.0));
        assert_eq!(coach.source_of(1, 30).0, 2);
        let (i, fraction) = coach.source_of(1, 40);
        assert_eq!(i, 1);
        assert!((fraction - 0.5).abs() < 1e-4);
    }
}
