//! A recorded motion on the host: a skeleton, joint names and frames of positions, and its
//! conversion from and to BVH.

use crate::bvh::{Bvh, Channel};
use crate::golf::{JointCentres, GOLF_JOINTS};
use crate::limits::{check_limits, LimitError, MAX_RATE_HZ, MIN_RATE_HZ};
use crate::units::Units;
use posecoach_core::contacts::{self, ContactError, Contacts, Swing};
use posecoach_core::events;
use posecoach_core::format::Format;
use posecoach_core::frames::Frames;
use posecoach_core::joint::Joint;
use posecoach_core::reference::{self, Reference, ReferenceError};
use posecoach_core::resample;
use posecoach_core::retarget::{Analytic, RetargetError};
use posecoach_core::skeleton::{Skeleton, SkeletonError};
use posecoach_core::Vec3;
use std::fmt;

/// Two joints this close are one place (a pelvis made as the hips' midpoint), m.
pub const SAME_PLACE_M: f32 = 0.01;

/// A motion in metres, +Y up: `frames × joints` positions on `skeleton`.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// The skeleton: the file's rest pose, a T-pose, or bone lengths measured from the frames.
    pub skeleton: Skeleton,
    /// Joint names as the file spells them, one per skeleton joint.
    pub names: Vec<String>,
    /// Frames per second; 0 for a single T-pose row.
    pub rate_hz: f32,
    /// Joint positions, frame-major.
    pub positions: Vec<Vec3>,
    /// Samples the file lacked (frame-major, like `positions`); each holds the nearest valid
    /// sample of its joint in time.
    pub missing: Vec<bool>,
}

impl Motion {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.positions.len() / self.skeleton.len()
    }

    /// The frames, as the core's readers take them.
    pub fn swing(&self) -> Frames<'_> {
        Frames::metres(&self.positions, self.skeleton.len())
    }

    /// Joint positions of frame `i`.
    ///
    /// # Panics
    /// If `i >= self.frames()`.
    pub fn frame(&self, i: usize) -> &[Vec3] {
        let n = self.skeleton.len();
        &self.positions[i * n..(i + 1) * n]
    }

    /// Duration in seconds (0 for a single frame).
    pub fn duration_s(&self) -> f32 {
        if self.rate_hz > 0.0 {
            self.frames().saturating_sub(1) as f32 / self.rate_hz
        } else {
            0.0
        }
    }

    /// How far the pelvis lies from the hips' midpoint, at most over the frames (`None` without
    /// both hips): 0 where a format makes the pelvis as that midpoint (COCO, BlazePose, H36M),
    /// some centimetres above it where markers on the waist place it (the golf captures).
    fn pelvis_off_hips(&self) -> Option<f32> {
        let (l, r) = self.hips()?;
        let n = self.skeleton.len();
        // Only frames that saw all three: a held sample of one is from another frame.
        (0..self.frames())
            .filter(|f| [0, l, r].iter().all(|&k| !self.missing[f * n + k]))
            .map(|f| {
                let p = self.frame(f);
                (p[0] - (p[l] + p[r]) * 0.5).norm()
            })
            .reduce(f32::max)
    }

    /// The hips' indices, where the root is the pelvis and both hips are joints.
    fn hips(&self) -> Option<(usize, usize)> {
        let s = &self.skeleton;
        (s.joint(0) == Some(Joint::Pelvis)).then_some(())?;
        Some((s.find(&[Joint::LeftHip])?, s.find(&[Joint::RightHip])?))
    }

    /// Whether the pelvis lies at the hips' midpoint (within [`SAME_PLACE_M`]) in every frame,
    /// as COCO, BlazePose and H36M make it; a golf capture's lies 8 cm above, where markers
    /// on the waist place it. `None` without both hips.
    pub fn pelvis_at_hips(&self) -> Option<bool> {
        self.pelvis_off_hips().map(|d| d < SAME_PLACE_M)
    }

    /// This motion with its pelvis moved to its hips' midpoint in every frame and in the rest
    /// pose (the root's children hung from there); unchanged without both hips.
    ///
    /// Two swings are compared on one pelvis: the retargeter copies bone directions, so a golf
    /// capture's pelvis-to-hip bones, pointing 40° down, would tilt a phone student's level
    /// ones and lower everything below them.
    ///
    /// # Errors
    /// If the moved rest pose does not make a skeleton.
    pub fn with_pelvis_at_hips(&self) -> Result<Motion, SkeletonError> {
        let Some((l, r)) = self.hips() else {
            return Ok(self.clone());
        };
        let s = &self.skeleton;
        let n = s.len();
        let mut rest = vec![Vec3::zeros(); n];
        s.rest_positions(&mut rest);
        rest[0] = (rest[l] + rest[r]) * 0.5;
        let parents: Vec<Option<usize>> = (0..n).map(|k| s.parent(k)).collect();
        let skeleton = Skeleton::from_rest_positions(s.format(), &parents, &rest, s.joints())?;
        let mut out = self.clone();
        out.skeleton = skeleton;
        for frame in out.positions.chunks_exact_mut(n) {
            frame[0] = (frame[l] + frame[r]) * 0.5;
        }
        for gone in out.missing.chunks_exact_mut(n) {
            gone[0] = gone[l] || gone[r];
        }
        Ok(out)
    }

    /// The canonical joints the skeleton names.
    pub fn canonical_joints(&self) -> Vec<Joint> {
        self.skeleton.joints().iter().flatten().copied().collect()
    }

    /// This motion on the joints `keep` keeps (joints without a canonical name are kept), each
    /// hung from its nearest kept ancestor with their rest chord as its offset: what it has in
    /// common with a swing that tracks fewer joints.
    ///
    /// # Errors
    /// If the joints kept do not make a skeleton (the pelvis or an end effector left out).
    pub fn only(&self, keep: impl Fn(Joint) -> bool) -> Result<Motion, SkeletonError> {
        let s = &self.skeleton;
        let n = s.len();
        let kept: Vec<usize> = (0..n).filter(|&k| s.joint(k).is_none_or(&keep)).collect();
        let mut rest = vec![Vec3::zeros(); n];
        s.rest_positions(&mut rest);
        let place = |k: usize| kept.iter().position(|&j| j == k);
        let parents: Vec<Option<usize>> = kept
            .iter()
            .map(|&k| {
                let mut up = s.parent(k);
                while let Some(p) = up.filter(|&p| place(p).is_none()) {
                    up = s.parent(p);
                }
                up.and_then(place)
            })
            .collect();
        let at: Vec<Vec3> = kept.iter().map(|&k| rest[k]).collect();
        let joints: Vec<Option<Joint>> = kept.iter().map(|&k| s.joint(k)).collect();
        let skeleton = Skeleton::from_rest_positions(s.format(), &parents, &at, &joints)?;
        let frames = |f: usize| kept.iter().map(move |&k| f * n + k);
        let all = 0..self.frames();
        Ok(Motion {
            skeleton,
            names: kept.iter().map(|&k| self.names[k].clone()).collect(),
            rate_hz: self.rate_hz,
            positions: all
                .clone()
                .flat_map(frames)
                .map(|i| self.positions[i])
                .collect(),
            missing: all.flat_map(frames).map(|i| self.missing[i]).collect(),
        })
    }

    /// This motion retargeted with the analytic retargeter onto `student`'s skeleton, keeping
    /// the student's joint names and this motion's rate.
    ///
    /// # Errors
    /// As [`Analytic::new`] and [`Analytic::frame`], the latter with the frame index.
    pub fn retarget_analytic(&self, student: &Motion) -> Result<Motion, (usize, RetargetError)> {
        let analytic = Analytic::new(&self.skeleton, &student.skeleton).map_err(|e| (0, e))?;
        let n = student.skeleton.len();
        let mut positions = vec![Vec3::zeros(); self.frames() * n];
        for (f, out) in positions.chunks_exact_mut(n).enumerate() {
            analytic.frame(self.frame(f), out).map_err(|e| (f, e))?;
        }
        Ok(Motion {
            skeleton: student.skeleton.clone(),
            names: student.names.clone(),
            rate_hz: self.rate_hz,
            missing: vec![false; positions.len()],
            positions,
        })
    }

    /// This motion (a retargeting of `coach`, frame for frame) moved onto the coach's golf
    /// contacts ([`Contacts`]): planted feet stay planted and, where the detector finds the
    /// coach's swing, both hands stay on one grip and the club head is at the coach's ball at
    /// address and impact.
    ///
    /// # Errors
    /// [`ContactError::Frames`] if the two motions differ in frames (nothing is changed then).
    pub fn keep_contacts(&mut self, coach: &Motion) -> Result<(), ContactError> {
        if coach.frames() != self.frames() {
            return Err(ContactError::Frames {
                coach: coach.frames(),
                student: self.frames(),
            });
        }
        let swing = events::detect(&coach.skeleton, coach.swing(), coach.rate_hz)
            .ok()
            .map(|s| Swing::from(&s));
        Contacts::new(&coach.skeleton, &self.skeleton).apply(
            contacts::frames(&coach.positions, coach.skeleton.len()),
            coach.rate_hz,
            swing,
            &mut self.positions,
        )
    }

    /// The motion resampled to `rate_hz` by linear interpolation in time
    /// ([`posecoach_core::resample`]); a sample is missing if either neighbour was. A T-pose
    /// (rate 0), and a motion already at that rate ([`resample::SAME_RATE`]), are returned
    /// unchanged.
    ///
    /// # Errors
    /// A [`LimitError`], before anything is allocated, for a motion or a result beyond the
    /// limits ([`check_limits`]): `rate_hz` outside [`MIN_RATE_HZ`] to [`MAX_RATE_HZ`], a
    /// motion beyond them (built by hand: the readers refuse one), or more than
    /// [`MAX_SAMPLES`](crate::limits::MAX_SAMPLES) samples out.
    pub fn resampled(&self, rate_hz: f32) -> Result<Motion, LimitError> {
        if self.rate_hz <= 0.0 || self.frames() == 0 || resample::same_rate(self.rate_hz, rate_hz) {
            return Ok(self.clone());
        }
        let n = self.skeleton.len();
        check_limits(self.frames(), n, self.rate_hz)?;
        if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz) {
            return Err(LimitError::Rate(rate_hz));
        }
        let frames = resample::frames(self.frames(), self.rate_hz, rate_hz);
        check_limits(frames, n, rate_hz)?;
        let mut positions = vec![Vec3::zeros(); frames * n];
        let mut missing = Vec::with_capacity(frames * n);
        for (f, out) in positions.chunks_exact_mut(n).enumerate() {
            let (i, w) = resample::source(f, self.rate_hz, rate_hz, self.frames());
            let j = if w > 0.0 { i + 1 } else { i };
            resample::lerp(self.frame(i), self.frame(j), w, out);
            for k in 0..n {
                missing.push(self.missing[i * n + k] || self.missing[j * n + k]);
            }
        }
        Ok(Motion {
            rate_hz,
            positions,
            missing,
            ..self.clone()
        })
    }

    /// How many samples were missing in the file, per joint.
    pub fn missing_per_joint(&self) -> Vec<usize> {
        let n = self.skeleton.len();
        let mut counts = vec![0; n];
        for (i, _) in self.missing.iter().enumerate().filter(|(_, &m)| m) {
            counts[i % n] += 1;
        }
        counts
    }
}

/// Why a BVH hierarchy cannot become a motion.
#[derive(Clone, Debug, PartialEq)]
pub enum BvhImportError {
    /// Neither a built-in format nor canonical joint names, with a root that reaches the pelvis
    /// through single-child joints only.
    UnknownSkeleton,
    /// The hierarchy does not make a valid skeleton.
    Skeleton(SkeletonError),
    /// The motion is beyond the limits.
    Limit(LimitError),
}

impl fmt::Display for BvhImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BvhImportError::UnknownSkeleton => f.write_str(
                "joint names match no built-in format (cmu31, bandai22, h36m17, coco17, blazepose33, smpl24, golf) \
                 and the root is not a joint named `pelvis`: rename the joints to canonical names",
            ),
            BvhImportError::Skeleton(e) => write!(f, "the hierarchy is not a usable skeleton: {e}"),
            BvhImportError::Limit(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for BvhImportError {}

impl Motion {
    /// A motion from a BVH file: joints above the pelvis that have a single child (Bandai's
    /// `joint_Root`) are dropped, the format is recognized by joint names (else joints named
    /// like the canonical vocabulary make a custom skeleton), a leading all-zero rest frame is
    /// dropped, and lengths are converted from `units`, or from the units [`Units::nearest`]
    /// picks when `None`.
    ///
    /// # Errors
    /// [`BvhImportError`] when no joint can be identified as the pelvis, the tree is not a
    /// valid skeleton, or the motion is beyond the limits ([`check_limits`]).
    pub fn from_bvh(mut bvh: Bvh, units: Option<Units>) -> Result<Motion, BvhImportError> {
        if bvh.first_frame_is_rest() {
            bvh.drop_first_frame();
        }
        let n = bvh.joints.len();
        let mut start = 0;
        let (format, names) = loop {
            let names: Vec<&str> = bvh.joints[start..]
                .iter()
                .map(|j| j.name.as_str())
                .collect();
            if let Some(format) = Format::detect(&names) {
                let joints = format.joints().iter().map(|j| j.joint).collect::<Vec<_>>();
                break (format, joints);
            }
            if names.first() == Some(&Joint::Pelvis.name()) {
                break (
                    Format::Custom,
                    names.iter().map(|&n| Joint::from_name(n)).collect(),
                );
            }
            let children = bvh
                .joints
                .iter()
                .filter(|j| j.parent == Some(start))
                .count();
            if children != 1 || start + 1 >= n {
                return Err(BvhImportError::UnknownSkeleton);
            }
            start += 1;
        };
        let rate_hz = if bvh.frame_time > 0.0 {
            (1.0 / bvh.frame_time) as f32
        } else {
            0.0
        };
        check_limits(bvh.frames, n - start, rate_hz).map_err(BvhImportError::Limit)?;
        let parents: Vec<Option<usize>> = bvh.joints[start..]
            .iter()
            .map(|j| j.parent.and_then(|p| p.checked_sub(start)))
            .collect();
        let mut rest = vec![[0.0; 3]; n];
        bvh.rest_positions(&mut rest);
        let offset = |k: usize| {
            let v = if k == start {
                rest[k]
            } else {
                bvh.joints[k].offset
            };
            Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
        };
        let offsets: Vec<Vec3> = (start..n).map(offset).collect();
        let build = |scale: f32| {
            let scaled: Vec<Vec3> = offsets.iter().map(|o| o * scale).collect();
            Skeleton::new(format, &parents, &scaled, &names).map_err(BvhImportError::Skeleton)
        };
        let scale = match units {
            Some(units) => units,
            None => Units::nearest(build(1.0)?.height()),
        }
        .metres();
        let skeleton = build(scale)?;
        let mut frame = vec![[0.0; 3]; n];
        let mut positions = Vec::with_capacity(bvh.frames * (n - start));
        for f in 0..bvh.frames {
            bvh.positions(f, &mut frame);
            positions.extend(
                frame[start..]
                    .iter()
                    .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * scale),
            );
        }
        Ok(Motion {
            skeleton,
            names: bvh.joints[start..].iter().map(|j| j.name.clone()).collect(),
            rate_hz,
            missing: vec![false; positions.len()],
            positions,
        })
    }

    /// A motion from golf joint centres on the [`Format::GolfMarkers`] skeleton, with bone
    /// lengths measured as the mean over the frames. Samples still missing after the marker
    /// filling are held from the nearest valid sample and flagged in `missing`.
    ///
    /// # Errors
    /// [`SkeletonError`] if a bone could not be measured in any frame.
    pub fn from_golf(centres: &JointCentres) -> Result<Motion, SkeletonError> {
        let n = GOLF_JOINTS.len();
        let mut positions = centres.positions.clone();
        let missing: Vec<bool> = centres.valid.iter().map(|&v| !v).collect();
        let template = Skeleton::standard(Format::GolfMarkers)?;
        let skeleton = measured_skeleton(&template, &positions, &missing)?;
        hold_missing(n, &mut positions, &missing);
        Ok(Motion {
            skeleton,
            names: GOLF_JOINTS.iter().map(|&j| j.to_string()).collect(),
            rate_hz: centres.rate_hz,
            positions,
            missing,
        })
    }

    /// A coach reference blob (`.pcr`) as a motion: joints named canonically, nothing missing,
    /// positions in metres (millimetres read as [`posecoach_core::frames::from_mm`] reads them).
    ///
    /// # Errors
    /// Any [`ReferenceError`] of [`Reference::from_bytes`].
    pub fn from_reference(bytes: &[u8]) -> Result<Motion, ReferenceError> {
        // Files are read into unaligned memory; the blob is viewed in place only when aligned.
        let mut store = vec![0u128; bytes.len().div_ceil(16)];
        let aligned = &mut bytemuck::cast_slice_mut::<u128, u8>(&mut store)[..bytes.len()];
        aligned.copy_from_slice(bytes);
        let reference = Reference::from_bytes(aligned)?;
        let skeleton = reference.skeleton().clone();
        let names = (0..skeleton.len())
            .map(|k| {
                skeleton
                    .joint(k)
                    .map_or(format!("joint_{k}"), |j| j.name().to_string())
            })
            .collect();
        let positions: Vec<Vec3> = reference.positions().iter().collect();
        Ok(Motion {
            names,
            rate_hz: reference.rate_hz(),
            missing: vec![false; positions.len()],
            positions,
            skeleton,
        })
    }

    /// The motion as a coach reference blob named `name`, its positions stored in `units`
    /// (millimetres as the device's coaches are; metres for the exact floats).
    ///
    /// # Errors
    /// As [`reference::write`]: a T-pose (rate 0), a name over
    /// [`reference::MAX_NAME`] bytes, a non-finite position, or in millimetres one beyond
    /// ±32.767 m.
    pub fn to_reference(
        &self,
        name: &str,
        units: reference::Units,
    ) -> Result<Vec<u8>, ReferenceError> {
        let mut out = vec![0; reference::max_len(self.skeleton.len(), self.frames())];
        let n = reference::write(
            name,
            &self.skeleton,
            self.rate_hz,
            Frames::metres(&self.positions, self.skeleton.len()),
            units,
            &mut out,
        )?;
        out.truncate(n);
        Ok(out)
    }

    /// The motion as BVH in metres: every joint with position and Z-X-Y rotation channels, so
    /// positions re-import exactly (see [`Bvh::from_positions`]). A T-pose gets one frame at
    /// 30 fps.
    pub fn to_bvh(&self) -> Bvh {
        let s = &self.skeleton;
        let f64s = |v: &Vec3| [f64::from(v.x), f64::from(v.y), f64::from(v.z)];
        let parents: Vec<Option<usize>> = (0..s.len()).map(|k| s.parent(k)).collect();
        let offsets: Vec<[f64; 3]> = s.offsets().iter().map(f64s).collect();
        let positions: Vec<[f64; 3]> = self.positions.iter().map(f64s).collect();
        let rate = if self.rate_hz > 0.0 {
            f64::from(self.rate_hz)
        } else {
            30.0
        };
        Bvh::from_positions(
            &self.names,
            &parents,
            &offsets,
            &vec![None; s.len()],
            &positions,
            1.0 / rate,
            [Channel::Zrotation, Channel::Xrotation, Channel::Yrotation],
        )
    }
}

/// Mean length of every bone over the frames where both its ends were present (0 where never).
pub fn mean_bone_lengths(skeleton: &Skeleton, positions: &[Vec3], missing: &[bool]) -> Vec<f32> {
    let n = skeleton.len();
    let mut sums = vec![(0.0f64, 0usize); n];
    for (frame, gaps) in positions.chunks_exact(n).zip(missing.chunks_exact(n)) {
        for k in 1..n {
            let p = skeleton.parent(k).unwrap_or(0);
            if !gaps[k] && !gaps[p] {
                sums[k].0 += f64::from((frame[k] - frame[p]).norm());
                sums[k].1 += 1;
            }
        }
    }
    sums.iter()
        .map(|&(s, c)| if c > 0 { (s / c as f64) as f32 } else { 0.0 })
        .collect()
}

/// `template` with its bones rescaled to the mean lengths measured in `positions`.
///
/// # Errors
/// As [`Skeleton::with_bone_lengths`].
pub fn measured_skeleton(
    template: &Skeleton,
    positions: &[Vec3],
    missing: &[bool],
) -> Result<Skeleton, SkeletonError> {
    template.with_bone_lengths(&mean_bone_lengths(template, positions, missing))
}

/// Replaces every missing sample by the nearest valid sample of the same joint in time
/// (earlier one on ties). Joints never present keep their value.
pub fn hold_missing(joints: usize, positions: &mut [Vec3], missing: &[bool]) {
    if joints == 0 {
        return;
    }
    let frames = positions.len() / joints;
    for j in 0..joints {
        let valid: Vec<usize> = (0..frames).filter(|&f| !missing[f * joints + j]).collect();
        if valid.is_empty() {
            continue;
        }
        let mut next = 0;
        for f in 0..frames {
            while next + 1 < valid.len() && valid[next + 1] <= f {
                next += 1;
            }
            let a = valid[next];
            let source = match valid.get(next + 1) {
                Some(&b) if b.abs_diff(f) < a.abs_diff(f) => b,
                _ => a,
            };
            positions[f * joints + j] = positions[source * joints + j];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn golf_joint_order_matches_the_core_format() {
        let core: Vec<&str> = Format::GolfMarkers
            .joints()
            .iter()
            .map(|j| j.name)
            .collect();
        assert_eq!(core, GOLF_JOINTS);
    }

    #[test]
    fn resampling_interpolates_in_time() {
        let skeleton = Skeleton::standard(Format::Canonical).unwrap();
        let n = skeleton.len();
        let positions: Vec<Vec3> = (0..3 * n)
            .map(|i| Vec3::new((i / n) as f32, 0.0, 0.0))
            .collect();
        let motion = Motion {
            names: vec![String::new(); n],
            rate_hz: 10.0,
            missing: vec![false; positions.len()],
            positions,
            skeleton,
        };
        let fine = motion.resampled(40.0).unwrap();
        assert_eq!(fine.frames(), 9);
        assert_eq!(fine.frame(3)[0].x, 0.75);
        assert_eq!(fine.frame(8)[n - 1].x, 2.0);
        // A missing sample spreads to the output samples either side of it; an output that
        // falls exactly on an input sample takes only that one.
        let mut gappy = motion.clone();
        gappy.missing[n] = true;
        let fine = gappy.resampled(40.0).unwrap();
        let flagged: Vec<usize> = (0..9).filter(|&f| fine.missing[f * n]).collect();
        assert_eq!(flagged, [1, 2, 3, 4, 5, 6, 7]);
        let coarse = gappy.resampled(5.0).unwrap();
        assert_eq!(coarse.frames(), 2);
        assert!(!coarse.missing[0] && !coarse.missing[n]);
    }

    /// The CMU fixture's hierarchy with no channels, and a MOTION section of `motion`.
    fn without_channels(motion: &str) -> Bvh {
        let fixture = include_str!("../../tests/fixtures/cmu_131_01_excerpt.bvh");
        let hierarchy = fixture.split("MOTION").next().unwrap().lines();
        let no_channels = |l: &str| match l.trim_start().starts_with("CHANNELS") {
            true => "CHANNELS 0".to_string(),
            false => l.to_string(),
        };
        let text: Vec<String> = hierarchy.map(no_channels).collect();
        Bvh::parse(&format!("{}\nMOTION\n{motion}", text.join("\n"))).unwrap()
    }

    /// A BVH of a `pelvis` and `children` joints under it, with `channels` on the pelvis.
    fn pelvis(children: usize, channels: &str, motion: &str) -> Bvh {
        let child = "JOINT j { OFFSET 0 1 0 End Site { OFFSET 0 1 0 } }\n";
        let text = format!(
            "HIERARCHY\nROOT pelvis\n{{\nOFFSET 0 0 0\nCHANNELS {channels}\n{}}}\nMOTION\n{motion}",
            child.repeat(children)
        );
        Bvh::parse(&text).unwrap()
    }

    #[test]
    fn hostile_bvh_files_are_refused_before_their_frames_are_made() {
        use BvhImportError::Limit;
        // A second of motion stretched over 31 years: resampling it asked for 934 TB.
        let slow = pelvis(
            0,
            "3 Xposition Yposition Zposition",
            "Frames: 2\nFrame Time: 1000000000\n0 0 0 0 0 1",
        );
        let e = Motion::from_bvh(slow, None).unwrap_err();
        assert_eq!(e, Limit(LimitError::Rate(1e-9)));
        // No channels, so the frames cost no text: 16777216 frames at 120 Hz (39 h) took 6 GB.
        let hours = without_channels("Frames: 16777216\nFrame Time: 0.0083333");
        assert_eq!((hours.frames, hours.motion.len()), (16_777_216, 0));
        let e = Motion::from_bvh(hours, None).unwrap_err();
        assert!(
            matches!(e, Limit(LimitError::Duration(s)) if (s - 139_810.0).abs() < 1.0),
            "{e}"
        );
        // Within the duration limit (150 s at 2000 Hz), the samples limit stops it.
        let many = pelvis(30, "0", "Frames: 300000\nFrame Time: 0.0005");
        let e = Motion::from_bvh(many, None).unwrap_err();
        let samples = LimitError::Samples {
            frames: 300_000,
            joints: 31,
        };
        assert_eq!(e, Limit(samples));
    }

    #[test]
    fn frames_without_channels_are_all_kept() {
        // Frame 0 of a file without rotation channels is no rest frame: it was dropped.
        let still = Motion::from_bvh(without_channels("Frames: 3\nFrame Time: 0.01"), None);
        let still = still.unwrap();
        assert_eq!((still.frames(), still.rate_hz), (3, 100.0));
        assert_eq!(still.frame(0), still.frame(2));
    }

    #[test]
    fn resampling_refuses_before_allocating() {
        let skeleton = Skeleton::standard(Format::Canonical).unwrap();
        let n = skeleton.len();
        let motion = |frames: usize, rate_hz: f32| Motion {
            names: vec![String::new(); n],
            rate_hz,
            positions: vec![Vec3::zeros(); frames * n],
            missing: vec![false; frames * n],
            skeleton: skeleton.clone(),
        };
        // Built outside the readers: a source rate or duration beyond the limits.
        let slow = motion(2, 1e-9);
        assert_eq!(slow.resampled(60.0), Err(LimitError::Rate(1e-9)));
        let long = motion(1202, 2.0);
        assert_eq!(long.resampled(60.0), Err(LimitError::Duration(600.5)));
        // Rates out of range, and more samples out than the limit.
        let swing = motion(501, 1.0);
        for rate in [0.0, -60.0, 0.5, 1e9, f32::NAN] {
            let e = swing.resampled(rate).unwrap_err();
            assert!(matches!(e, LimitError::Rate(r) if r.to_bits() == rate.to_bits()));
        }
        let samples = LimitError::Samples {
            frames: 1_000_001,
            joints: n,
        };
        assert_eq!(swing.resampled(2000.0), Err(samples));
        assert_eq!(swing.resampled(60.0).unwrap().frames(), 30_001);
    }

    #[test]
    fn hold_missing_takes_the_nearest_valid_sample() {
        let mut p: Vec<Vec3> = (0..6).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let missing = [true, false, true, true, true, false];
        hold_missing(1, &mut p, &missing);
        let xs: Vec<f32> = p.iter().map(|v| v.x).collect();
        assert_eq!(xs, [1.0, 1.0, 1.0, 1.0, 5.0, 5.0]);
    }
}
