//! The joints the events read (the arms, the feet, the club where it is tracked), which side
//! leads, and the arms' elevation.

use super::track::{Hands, Track};
use super::{EventError, Side};
use crate::joint::Joint;
use crate::skeleton::Skeleton;
use crate::Vec3;

/// The joints the events read, as indices into the skeleton's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Limbs {
    /// Left and right wrist (else hand).
    pub(super) wrists: [usize; 2],
    /// Left and right shoulder.
    pub(super) shoulders: [usize; 2],
    /// Left and right ankle (else toe).
    pub(super) feet: [usize; 2],
    /// The club's grip and head, where the skeleton has both.
    pub(super) club: Option<(usize, usize)>,
}

impl Limbs {
    /// The joints of `skeleton`.
    ///
    /// # Errors
    /// [`EventError::MissingJoint`] for the first it lacks: wrists, shoulders, then feet.
    pub(super) fn find(skeleton: &Skeleton) -> Result<Limbs, EventError> {
        let need = |j: Joint| skeleton.index_of(j).ok_or(EventError::MissingJoint(j));
        let either = |a: Joint, b: Joint| skeleton.find(&[a, b]).ok_or(EventError::MissingJoint(b));
        Ok(Limbs {
            wrists: [
                either(Joint::LeftWrist, Joint::LeftHand)?,
                either(Joint::RightWrist, Joint::RightHand)?,
            ],
            shoulders: [need(Joint::LeftShoulder)?, need(Joint::RightShoulder)?],
            feet: [
                either(Joint::LeftAnkle, Joint::LeftToe)?,
                either(Joint::RightAnkle, Joint::RightToe)?,
            ],
            club: skeleton
                .index_of(Joint::ClubGrip)
                .zip(skeleton.index_of(Joint::ClubHead)),
        })
    }

    /// The lead side: the backswing takes the `hands` from where they are at `address` toward
    /// the trail foot by the `top`.
    pub(super) fn lead(&self, hands: &Hands<'_>, address: usize, top: usize) -> Side {
        let track = hands.track;
        let across = track.at(self.feet[1], address) - track.at(self.feet[0], address);
        if (hands.at(top) - hands.at(address)).dot(&across) > 0.0 {
            Side::Left
        } else {
            Side::Right
        }
    }

    /// The arms on `track` of a golfer led by `lead`.
    pub(super) fn arms<'a>(&self, track: &'a Track<'a>, lead: Side) -> Arms<'a> {
        let (lead, trail) = match lead {
            Side::Left => (0, 1),
            Side::Right => (1, 0),
        };
        Arms {
            track,
            lead: (self.shoulders[lead], self.wrists[lead]),
            trail: (self.shoulders[trail], self.wrists[trail]),
        }
    }
}

/// The lead and the trail arm, each its shoulder and wrist, on a smoothed track.
pub(super) struct Arms<'a> {
    /// The track they are read from.
    pub(super) track: &'a Track<'a>,
    lead: (usize, usize),
    trail: (usize, usize),
}

impl Arms<'_> {
    /// The lead arm's elevation (shoulder → wrist) at frame `t`, degrees.
    pub(super) fn lead(&self, t: usize) -> f32 {
        elevation(self.track.at(self.lead.1, t) - self.track.at(self.lead.0, t))
    }

    /// The trail arm's elevation (shoulder → wrist) at frame `t`, degrees.
    pub(super) fn trail(&self, t: usize) -> f32 {
        elevation(self.track.at(self.trail.1, t) - self.track.at(self.trail.0, t))
    }
}

/// Elevation of `v` above the horizontal plane, degrees.
pub(super) fn elevation(v: Vec3) -> f32 {
    libm::atan2f(v.y, crate::math::hypot(v.x, v.z)).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;
    use crate::frames::Frames;
    use std::vec::Vec;

    #[test]
    fn an_elevation_is_the_angle_above_the_horizontal() {
        assert_eq!(elevation(Vec3::new(1.0, 0.0, 0.0)), 0.0);
        assert!((elevation(Vec3::new(0.0, 1.0, 1.0)) - 45.0).abs() < 1e-4);
        assert!((elevation(Vec3::new(-3.0, -4.0, 0.0)) + 53.130_1).abs() < 1e-3);
        assert!((elevation(Vec3::new(0.0, -2.0, 0.0)) + 90.0).abs() < 1e-4);
    }

    #[test]
    fn the_joints_are_found_or_the_first_missing_named() {
        let h36m = Skeleton::standard(Format::H36m17).unwrap();
        let limbs = Limbs::find(&h36m).unwrap();
        assert_eq!(
            limbs.wrists,
            [
                h36m.index_of(Joint::LeftWrist).unwrap(),
                h36m.index_of(Joint::RightWrist).unwrap()
            ]
        );
        // H36M has ankles, no toes, and no club.
        assert_eq!(limbs.feet[1], h36m.index_of(Joint::RightAnkle).unwrap());
        assert_eq!(limbs.club, None);
        // Hands for wrists, toes for ankles, and no shoulders.
        let mut joints = std::vec![
            Joint::Pelvis,
            Joint::LeftToe,
            Joint::RightToe,
            Joint::Head,
            Joint::LeftHand,
            Joint::RightHand,
        ];
        let skeleton = |joints: &[Joint]| {
            let rest: Vec<Vec3> = joints.iter().map(|&j| crate::format::t_pose(j)).collect();
            Skeleton::canonical(joints, &rest).unwrap()
        };
        assert_eq!(
            Limbs::find(&skeleton(&joints)),
            Err(EventError::MissingJoint(Joint::LeftShoulder))
        );
        joints.insert(4, Joint::LeftShoulder);
        joints.insert(6, Joint::RightShoulder);
        let stand_ins = Limbs::find(&skeleton(&joints)).unwrap();
        assert_eq!(stand_ins.wrists, [5, 7]);
        assert_eq!(stand_ins.shoulders, [4, 6]);
        assert_eq!(stand_ins.feet, [1, 2]);
    }

    #[test]
    fn the_lead_side_is_the_one_the_hands_move_away_from() {
        // Wrists at 0 and 1, feet at 2 (left, at +z) and 3 (right, at -z): the hands travel
        // toward -z, the right foot, from frame 10 on.
        let path = |f: usize| {
            let z = -0.05 * f.saturating_sub(10) as f32;
            [
                Vec3::new(0.3, 1.0, z + 0.05),
                Vec3::new(0.3, 1.0, z - 0.05),
                Vec3::new(0.0, 0.0, 0.2),
                Vec3::new(0.0, 0.0, -0.2),
            ]
        };
        let positions: Vec<Vec3> = (0..40).flat_map(path).collect();
        let track = Track::new(Frames::metres(&positions, 4), 60.0);
        let hands = Hands::new(&track, [0, 1]);
        let limbs = Limbs {
            wrists: [0, 1],
            shoulders: [0, 1],
            feet: [2, 3],
            club: None,
        };
        assert_eq!(limbs.lead(&hands, 5, 30), Side::Left);
        // The same hands with the feet swapped: a left-handed golfer.
        let lefty = Limbs {
            feet: [3, 2],
            ..limbs
        };
        assert_eq!(lefty.lead(&hands, 5, 30), Side::Right);
    }

    #[test]
    fn the_lead_arm_is_the_lead_side_s_and_the_trail_arm_the_other() {
        // Left shoulder 0, left wrist 1 level with it; right shoulder 2, right wrist 3 hanging.
        let pose = [
            Vec3::new(0.0, 1.4, 0.2),
            Vec3::new(0.6, 1.4, 0.2),
            Vec3::new(0.0, 1.4, -0.2),
            Vec3::new(0.0, 0.8, -0.2),
        ];
        let positions: Vec<Vec3> = (0..5).flat_map(|_| pose).collect();
        let track = Track::new(Frames::metres(&positions, 4), 60.0);
        let limbs = Limbs {
            wrists: [1, 3],
            shoulders: [0, 2],
            feet: [0, 2],
            club: None,
        };
        let near = |a: f32, b: f32| (a - b).abs() < 1e-4;
        let left = limbs.arms(&track, Side::Left);
        assert!(near(left.lead(2), 0.0) && near(left.trail(2), -90.0));
        let right = limbs.arms(&track, Side::Right);
        assert!(near(right.lead(2), -90.0) && near(right.trail(2), 0.0));
    }
}
