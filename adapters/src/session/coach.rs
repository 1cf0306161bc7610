//! The coach reference as the session keeps it: its frames at the model rate, and the virtual
//! coach made from them on the student's skeleton, in millimetres (by the analytic retargeter
//! or the int8 network, then moved onto the coach's golf contacts a frame at a time).

use super::Refusal;
use crate::imu::{ImuAdapter, ImuError};
use core::cell::Cell;
use posecoach_core::config::MAX_JOINTS;
use posecoach_core::contacts::{Contacts, Swing};
use posecoach_core::events::{self, SwingEvents};
use posecoach_core::frames::{from_mm, to_mm, Frames, Mm};
#[cfg(feature = "network")]
use posecoach_core::network::{self, NetworkError};
use posecoach_core::reference::Reference;
use posecoach_core::resample;
use posecoach_core::retarget::Analytic;
use posecoach_core::skeleton::Skeleton;
#[cfg(feature = "network")]
use posecoach_core::weights::Weights;
use posecoach_core::{Quat, Vec3};

/// A stored coach reference swing.
#[derive(Clone, Copy, Debug)]
pub struct Coach<'c> {
    /// The coach's skeleton.
    pub skeleton: &'c Skeleton,
    /// Its frames, `skeleton`'s joints to a frame, in metres or millimetres (a reference's
    /// are read in place; frames of another joint count are no frames).
    pub positions: Frames<'c>,
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
        match self.positions.joints() == self.skeleton.len() {
            true => self.positions.len(),
            false => 0,
        }
    }

    /// Its frames at the model rate `rate_hz`, as the session keeps the virtual coach: the
    /// session retargets the coach at the model rate so that the student's and the coach's
    /// swings are compared frame for frame ([`resample::frames`]; a firmware sizes its buffers
    /// with that `const fn`).
    pub fn frames_at(&self, rate_hz: u16) -> usize {
        resample::frames(self.frames(), self.rate_hz, f32::from(rate_hz))
    }

    /// The rate of the virtual coach: the model rate, or the coach's own where they are the
    /// same rate ([`resample::SAME_RATE`]) and its frames are used as they are.
    pub(super) fn rate_at(&self, rate_hz: u16) -> f32 {
        if resample::same_rate(self.rate_hz, f32::from(rate_hz)) {
            self.rate_hz
        } else {
            f32::from(rate_hz)
        }
    }

    /// Where frame `k` at `rate_hz` falls among the coach's own frames ([`resample::source`]);
    /// `None` without frames.
    fn source(&self, k: usize, rate_hz: u16) -> Option<(usize, f32)> {
        let frames = self.frames();
        let (i, fraction) = resample::source(k, self.rate_hz, f32::from(rate_hz), frames);
        (i < frames).then_some((i, fraction))
    }

    /// Frame `k` at `rate_hz` in metres, in `out` (interpolated when it falls between two of
    /// the coach's own frames); `None` without frames.
    fn frame_at<'a>(
        &self,
        k: usize,
        rate_hz: u16,
        out: &'a mut [Vec3; MAX_JOINTS],
    ) -> Option<&'a [Vec3]> {
        let (i, fraction) = self.source(k, rate_hz)?;
        let out = out.get_mut(..self.skeleton.len())?;
        resample::frame_at(&self.positions, i, fraction, out)?;
        Some(out)
    }

    /// Joint `j` of frame `k` at `rate_hz`, metres, interpolated as [`Coach::frame_at`]
    /// interpolates frames (zero outside them).
    fn joint_at(&self, k: usize, j: usize, rate_hz: u16) -> Vec3 {
        self.source(k, rate_hz)
            .and_then(|(i, fraction)| resample::joint_at(&self.positions, i, fraction, j))
            .unwrap_or_else(Vec3::zeros)
    }

    /// The retargeted coach in `out` (whole frames of `student`, millimetres) moved onto the
    /// coach's golf contacts ([`Contacts`]: planted feet, both hands on one grip, the club at
    /// the ball) a frame at a time, each frame read from `out` and stored back in its place,
    /// and in a session with IMUs as the student's IMUs would see it (the coach seen the way
    /// the student is). The coach's address, impact and lead side are the retargeted swing's,
    /// [`Coach::events_of`] (without a swing found, only the feet are kept). (Out of line: its
    /// frame is not on the stack while a coach is retargeted or its swing found.)
    #[inline(never)]
    pub(super) fn keep_contacts(
        &self,
        student: &Skeleton,
        rate_hz: u16,
        swing: Option<Swing>,
        imu: Option<&ImuAdapter>,
        out: &mut [Mm],
    ) -> Result<(), Refusal> {
        let n = student.len();
        let rate = self.rate_at(rate_hz);
        let count = out.len() / n.max(1);
        // Each frame is read before it is written, and not after.
        let stored = Cell::from_mut(out).as_slice_of_cells();
        let read = |f: usize, pose: &mut [Vec3]| {
            stored.get(f * n..(f + 1) * n).is_some_and(|frame| {
                for (p, s) in pose.iter_mut().zip(frame) {
                    *p = from_mm(s.get());
                }
                true
            })
        };
        // The IMUs see the coach's legs planted facing where its trunk faced at address.
        let mut pose = [Vec3::zeros(); MAX_JOINTS];
        let address = swing.map_or(0, |s| s.address);
        let stance = match imu {
            Some(imu) if read(address, &mut pose[..n]) => {
                imu.stance_of(student, &pose[..n]).map_err(Refusal::Imu)?
            }
            _ => Quat::identity(),
        };
        let mut refusal = Refusal::Retarget;
        let write = |f: usize, pose: &[Vec3]| {
            let mut seen = [Vec3::zeros(); MAX_JOINTS];
            let pose = match imu.map(|imu| seen_by(imu, student, pose, stance, &mut seen)) {
                None => pose,
                Some(Ok(())) => &seen[..n],
                Some(Err(e)) => {
                    refusal = Refusal::Imu(e);
                    return false;
                }
            };
            stored.get(f * n..(f + 1) * n).is_some_and(|to| {
                to.iter()
                    .zip(pose)
                    .all(|(to, p)| to_mm(p).map(|p| to.set(p)).is_some())
            })
        };
        Contacts::new(self.skeleton, student)
            .apply_by_frame(
                |f, k| self.joint_at(f, k, rate_hz),
                rate,
                swing,
                count,
                read,
                write,
            )
            .map_err(|_| refusal)
    }

    /// The events of the retargeted coach in `out` (whole frames of `student` at `rate_hz`,
    /// millimetres), if a swing is found: what the contacts need (its address, impact and lead
    /// side), and its timing as it was made.
    pub(super) fn events_of(
        &self,
        student: &Skeleton,
        rate_hz: u16,
        out: &[Mm],
    ) -> Option<SwingEvents> {
        let frames = Frames::millimetres(out, student.len());
        events::detect(student, frames, self.rate_at(rate_hz)).ok()
    }

    /// The coach at `rate_hz` retargeted onto `student` frame by frame with the analytic
    /// retargeter, into `out` (whole frames of the student, millimetres). (Out of line: its
    /// retargeter is not on the stack while the network runs.)
    #[inline(never)]
    pub(super) fn retarget_analytic(
        &self,
        student: &Skeleton,
        rate_hz: u16,
        out: &mut [Mm],
    ) -> Result<(), Refusal> {
        let retarget = Analytic::new(self.skeleton, student).map_err(|_| Refusal::Retarget)?;
        let (mut resampled, mut pose) = ([Vec3::zeros(); MAX_JOINTS], [Vec3::zeros(); MAX_JOINTS]);
        let pose = pose.get_mut(..student.len()).ok_or(Refusal::Retarget)?;
        for (k, stored) in out.chunks_exact_mut(student.len()).enumerate() {
            let source = self
                .frame_at(k, rate_hz, &mut resampled)
                .ok_or(Refusal::Retarget)?;
            retarget
                .frame(source, pose)
                .map_err(|_| Refusal::Retarget)?;
            store(pose, stored).ok_or(Refusal::Retarget)?;
        }
        Ok(())
    }

    /// The coach at `rate_hz` retargeted onto `student` by the int8 network of `weights`, into
    /// `out` (whole frames of the student, millimetres); its input and scratch are carved from
    /// `ring`.
    #[cfg(feature = "network")]
    pub(super) fn retarget_network(
        &self,
        weights: &Weights<'_>,
        student: &Skeleton,
        rate_hz: u16,
        ring: &mut [Mm],
        out: &mut [Mm],
    ) -> Result<(), Refusal> {
        let (n, m) = (self.skeleton.len(), student.len());
        let frames = out.len() / m.max(1);
        // The ring's room as positions in metres (from its first word boundary).
        let (_, room, _) = bytemuck::pod_align_to_mut::<u8, Vec3>(bytemuck::cast_slice_mut(ring));
        let (source, rest) = room
            .split_at_mut_checked(frames * n)
            .ok_or(Refusal::Buffers)?;
        let mut resampled = [Vec3::zeros(); MAX_JOINTS];
        for (k, pose) in source.chunks_exact_mut(n).enumerate() {
            let frame = self
                .frame_at(k, rate_hz, &mut resampled)
                .ok_or(Refusal::Retarget)?;
            pose.copy_from_slice(frame);
        }
        let scratch: &mut [u8] = bytemuck::cast_slice_mut(rest);
        let mut stored = true;
        network::retarget_each(
            weights,
            self.skeleton,
            student,
            source,
            scratch,
            &mut |f, pose| {
                let to = out.get_mut(f * m..(f + 1) * m);
                stored &= to.is_some_and(|to| store(pose, to).is_some());
            },
        )
        .map_err(|e| match e {
            NetworkError::Scratch => Refusal::Buffers,
            _ => Refusal::Retarget,
        })?;
        stored.then_some(()).ok_or(Refusal::Retarget)
    }
}

/// `frame` (whole frames of `skeleton`) as the student's IMUs would see it, into `out`. (Out
/// of line, so that its frame is on the stack only while a frame is seen.)
#[inline(never)]
fn seen_by(
    imu: &ImuAdapter,
    skeleton: &Skeleton,
    frame: &[Vec3],
    stance: Quat,
    out: &mut [Vec3],
) -> Result<(), ImuError> {
    imu.view(skeleton, frame, stance, out)
}

/// `pose` (metres) stored in `out` in millimetres; `None` if a position has none
/// ([`to_mm`]).
fn store(pose: &[Vec3], out: &mut [Mm]) -> Option<()> {
    for (o, p) in out.iter_mut().zip(pose) {
        *o = to_mm(p)?;
    }
    Some(())
}
