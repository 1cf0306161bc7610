//! What an IMU strapped to a body segment measures: the segment's rotation from the T-pose, as
//! the joint positions of a frame give it, and how the bones no sensor is on share the turn
//! between two that have one.
//!
//! A bone's rotation ([`inverse`]) is the one that carries it, and its twist, from the T-pose;
//! it is what a sensor on that bone measures, with one exception. The root's rotation in the
//! kinematic chain follows its longest bone, the lumbar spine, which bends sideways against
//! the hips' line by up to 40° in a downswing (the bundled swings); a sensor on the sacrum
//! follows the rigid pelvis, which carries the hip joints. So a sensor on the root measures
//! the pelvis: the hips' line, and about it the tilt the root bone has (the lumbar spine's:
//! the captures the skeletons come from show the pelvis's tilt nowhere else).
//!
//! An unsensed bone on a chain of only children between two sensed ones (the spine between
//! sensors on the pelvis and the thorax) takes an even share of the turn from the one above to
//! the one below: the chain bends evenly, as a spine does, rather than rigidly at one joint.

use posecoach_core::config::MAX_JOINTS;
use posecoach_core::joint::Joint;
use posecoach_core::kinematics::{inverse, swing, LengthError, MIN_BONE};
use posecoach_core::math;
use posecoach_core::skeleton::{Segment, Skeleton};
use posecoach_core::{Quat, Vec3};

/// No joint.
const NONE: u8 = u8::MAX;

/// The joints of `skeleton` that define its segments' rotations: its hips, and for every
/// unsensed joint the sensed joint below it that it bridges toward.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segments {
    /// The hips' indices, when both are children of the root.
    hips: [u8; 2],
    /// For a joint the [module](self) docs say is bridged, the sensed joint below it; [`NONE`]
    /// for every other.
    bridged: [u8; MAX_JOINTS],
}

impl Segments {
    /// The segments of `skeleton` with sensors on the joints `sensed` marks.
    pub fn new(skeleton: &Skeleton, sensed: impl Fn(usize) -> bool) -> Segments {
        let n = skeleton.len().min(MAX_JOINTS);
        let hip = |j: Joint| {
            skeleton
                .index_of(j)
                .filter(|&k| skeleton.parent(k) == Some(0))
                .map_or(NONE, |k| k as u8)
        };
        let only_child = |k: usize| {
            let mut children = (k + 1..n).filter(|&c| skeleton.parent(c) == Some(k));
            match (children.next(), children.next()) {
                (Some(c), None) => Some(c),
                _ => None,
            }
        };
        let mut bridged = [NONE; MAX_JOINTS];
        for (k, bridge) in bridged.iter_mut().enumerate().take(n).skip(1) {
            let mut up = skeleton.parent(k);
            while let Some(p) = up.filter(|&p| !sensed(p)) {
                up = skeleton.parent(p);
            }
            if sensed(k) || up.is_none() || !skeleton.segment_contains(Segment::Spine, k) {
                continue;
            }
            let mut down = only_child(k);
            while let Some(c) = down.filter(|&c| !sensed(c)) {
                down = only_child(c);
            }
            if let Some(lower) = down {
                *bridge = lower as u8;
            }
        }
        Segments {
            hips: [hip(Joint::LeftHip), hip(Joint::RightHip)],
            bridged,
        }
    }

    /// Each joint's segment rotation in `frame` (positions on `skeleton`) into `out`: what a
    /// sensor on it would measure (see the [module](self) docs).
    ///
    /// # Errors
    /// [`LengthError`] if `frame` is not as long as the skeleton, or `out` is shorter.
    pub fn rotations(
        &self,
        skeleton: &Skeleton,
        frame: &[Vec3],
        out: &mut [Quat],
    ) -> Result<(), LengthError> {
        let n = skeleton.len();
        let short = LengthError {
            expected: n,
            actual: out.len(),
        };
        let mut local = [Quat::identity(); MAX_JOINTS];
        inverse(skeleton, frame, &mut local[..n])?;
        let out = out.get_mut(..n).ok_or(short)?;
        for k in 0..n {
            let parent = skeleton.parent(k).map_or(Quat::identity(), |p| out[p]);
            out[k] = parent * local[k];
        }
        if let Some(pelvis) = self.pelvis(skeleton, frame, out[0]) {
            out[0] = pelvis;
        }
        Ok(())
    }

    /// Whether unsensed joint `k` shares the turn between the sensed joints around it (see
    /// the [module](self) docs).
    pub fn is_bridged(&self, k: usize) -> bool {
        self.bridged.get(k).is_some_and(|&j| j != NONE)
    }

    /// The rotation of unsensed joint `k` whose parent turned by `parent`, given the sensed
    /// joints' rotations `sensed(j)`: its share toward the sensed joint it bridges to, else its
    /// parent's.
    pub fn unsensed(
        &self,
        skeleton: &Skeleton,
        k: usize,
        parent: Quat,
        sensed: &dyn Fn(usize) -> Option<Quat>,
    ) -> Quat {
        let lower = self.bridged.get(k).map_or(NONE, |&j| j);
        let Some(target) = (lower != NONE)
            .then(|| sensed(usize::from(lower)))
            .flatten()
        else {
            return parent;
        };
        // Of the `d` bones from here down to the sensed joint, this one takes its share of the
        // turn still to go.
        let mut d = 1u8;
        let mut j = usize::from(lower);
        while let Some(p) = skeleton.parent(j).filter(|&p| p != k) {
            j = p;
            d = d.saturating_add(1);
        }
        math::interpolate(parent, target, 1.0 / f32::from(d + 1))
    }

    /// The pelvis's rotation in `frame`, or `None` for a skeleton without both hips on the
    /// root or a frame whose hips coincide; `root` is the root bone's rotation.
    fn pelvis(&self, skeleton: &Skeleton, frame: &[Vec3], root: Quat) -> Option<Quat> {
        if self.hips.contains(&NONE) {
            return None;
        }
        let [l, r] = self.hips.map(usize::from);
        let line = *frame.get(l)? - *frame.get(r)?;
        let width = math::norm(&line);
        if width < MIN_BONE {
            return None;
        }
        let axis = line / width;
        let swung = swing(skeleton.offset(l) - skeleton.offset(r), line);
        // The T-pose's up, as the swing and as the root bone carry it, seen along the hips:
        // the swing between them turns about the hips' line.
        let across = |v: Vec3| v - axis * axis.dot(&v);
        Some(swing(across(swung * Vec3::y()), across(root * Vec3::y())) * swung)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_core::format::Format;
    use std::vec::Vec;

    const EPS: f32 = 1e-5;

    fn h36m() -> Skeleton {
        Skeleton::standard(Format::H36m17).unwrap()
    }

    fn at(s: &Skeleton, joint: Joint) -> usize {
        s.index_of(joint).unwrap()
    }

    /// The T-pose turned by `whole`, its trunk above the pelvis then bent sideways by `bend`
    /// about the pelvis (the lumbar spine bending against the hips).
    fn bent(s: &Skeleton, whole: Quat, bend: Quat) -> Vec<Vec3> {
        let mut rest = std::vec![Vec3::zeros(); s.len()];
        s.rest_positions(&mut rest);
        let above = |k: usize| {
            let mut j = Some(k);
            while let Some(i) = j {
                if i == at(s, Joint::Spine) {
                    return true;
                }
                j = s.parent(i);
            }
            false
        };
        (0..s.len())
            .map(|k| {
                let p = rest[k] - rest[0];
                whole * if above(k) { bend * p } else { p }
            })
            .collect()
    }

    fn angle(a: Vec3, b: Vec3) -> f32 {
        a.angle(&b).to_degrees()
    }

    #[test]
    fn a_sensor_on_the_root_follows_the_hips_not_the_bending_lumbar_spine() {
        let s = h36m();
        let whole = Quat::from_euler_angles(0.6, 0.5, 0.1);
        let bend = Quat::from_axis_angle(&Vec3::z_axis(), 0.35);
        let frame = bent(&s, whole, bend);
        let (l, r) = (at(&s, Joint::LeftHip), at(&s, Joint::RightHip));
        let rest_line = s.offset(l) - s.offset(r);
        let mut out = std::vec![Quat::identity(); s.len()];
        Segments::new(&s, |_| true)
            .rotations(&s, &frame, &mut out)
            .unwrap();
        assert!(angle(out[0] * rest_line, frame[l] - frame[r]) < 0.01);
        // The root bone itself, which the sensor does not follow, leaves the hips' line some
        // 20° off, the lumbar spine's bend.
        let mut local = std::vec![Quat::identity(); s.len()];
        inverse(&s, &frame, &mut local).unwrap();
        assert!(angle(local[0] * rest_line, frame[l] - frame[r]) > 15.0);
        // About the hips' line it tilts as the root bone does.
        let axis = (frame[l] - frame[r]).normalize();
        let across = |q: Quat| {
            let up = q * Vec3::y();
            up - axis * axis.dot(&up)
        };
        assert!(angle(across(out[0]), across(local[0])) < 0.01);
        // Every other bone is the chain's.
        let mut global = local.clone();
        for k in 1..s.len() {
            global[k] = global[s.parent(k).unwrap()] * local[k];
            assert!(global[k].angle_to(&out[k]) < EPS, "joint {k}");
        }
    }

    #[test]
    fn an_unsensed_spine_bends_evenly_between_the_pelvis_and_thorax_sensors() {
        let s = h36m();
        let (pelvis, spine, thorax) = (0, at(&s, Joint::Spine), at(&s, Joint::Thorax));
        let (shoulder, elbow) = (at(&s, Joint::LeftShoulder), at(&s, Joint::LeftElbow));
        let on = [pelvis, thorax, elbow];
        let segments = Segments::new(&s, |k| on.contains(&k));
        let turn = |deg: f32| Quat::from_axis_angle(&Vec3::z_axis(), deg.to_radians());
        let sensed = |k: usize| match k {
            0 => Some(turn(10.0)),
            k if k == thorax => Some(turn(50.0)),
            k if k == elbow => Some(turn(-80.0)),
            _ => None,
        };
        let half = segments.unsensed(&s, spine, turn(10.0), &sensed);
        assert!(half.angle_to(&turn(30.0)) < EPS);
        // A shoulder, on a limb, follows the chest: the shoulder girdle's motion is its own.
        let chest = turn(50.0);
        assert_eq!(segments.unsensed(&s, shoulder, chest, &sensed), chest);
        // With no sensor below, the spine follows the pelvis.
        let pelvis_only = Segments::new(&s, |k| k == pelvis);
        assert_eq!(
            pelvis_only.unsensed(&s, spine, turn(10.0), &sensed),
            turn(10.0)
        );
    }
}
