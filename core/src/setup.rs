//! The set-up: what a golfer's stance at address says about the club in hand.
//!
//! A longer club is stood farther from and wider over: the stance between the ankles and how
//! far out toward the ball the hands hang (and, where it is tracked, the club head lies) grow
//! from wedge to driver (the two tour swings of the test data: stance 0.58 m with the iron and
//! 0.65 m with the driver, hands 0.27 m and 0.33 m out, the club head 0.68 m and 1.08 m). A
//! [`Setup`] holds those lengths for one swing, averaged over its still set-up; [`nearest`]
//! picks, among the coaches' set-ups on the student's own skeleton (so that stature and
//! proportions cancel), the one a student's is closest to: the coach with the student's club.
//!
//! ```
//! use posecoach_core::setup::{nearest, Setup};
//! let iron = Setup { stance_m: 0.58, hands_out_m: 0.27, head_out_m: None };
//! let driver = Setup { stance_m: 0.65, hands_out_m: 0.33, head_out_m: None };
//! let student = Setup { stance_m: 0.66, hands_out_m: 0.31, head_out_m: None };
//! assert_eq!(nearest(&student, [Some(iron), Some(driver)]), Some(1));
//! ```

use crate::body::Stance;
use crate::config::MAX_JOINTS;
use crate::events::Side;
use crate::frames::Frames;
use crate::joint::Joint;
use crate::skeleton::Skeleton;
use crate::Vec3;

/// A swing's set-up (see the [module documentation](self)), metres.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Setup {
    /// Horizontal distance between the ankles (or toes).
    pub stance_m: f32,
    /// How far the hands (between the wrists) are out toward the ball from between the feet.
    pub hands_out_m: f32,
    /// How far the club head is out toward the ball, where a club is tracked.
    pub head_out_m: Option<f32>,
}

impl Setup {
    /// The set-up of `frames` (of skeleton joints), each measured in the stance of the first (a
    /// golfer whose lead side is `lead`) and averaged: the still frames before a takeaway.
    /// `None` without feet or wrists, or without frames.
    pub fn new(skeleton: &Skeleton, frames: Frames<'_>, lead: Side) -> Option<Setup> {
        if frames.is_empty() || frames.joints() != skeleton.len() {
            return None;
        }
        let mut first = [Vec3::zeros(); MAX_JOINTS];
        let first = frames.frame(0, &mut first);
        let feet = [
            skeleton.find(&[Joint::LeftAnkle, Joint::LeftToe])?,
            skeleton.find(&[Joint::RightAnkle, Joint::RightToe])?,
        ];
        let wrists = [
            skeleton.find(&[Joint::LeftWrist, Joint::LeftHand])?,
            skeleton.find(&[Joint::RightWrist, Joint::RightHand])?,
        ];
        let head = skeleton.index_of(Joint::ClubHead);
        let stance = Stance::new(skeleton, first, lead);
        let (mut sum, mut count) = ([0.0f32; 3], 0.0f32);
        for f in 0..frames.len() {
            let at = |k: usize| frames.at(f, k);
            let apart = at(feet[0]) - at(feet[1]);
            let hands = stance.local((at(wrists[0]) + at(wrists[1])) * 0.5);
            sum[0] += crate::math::hypot(apart.x, apart.z);
            sum[1] += hands.y;
            sum[2] += head.map_or(0.0, |k| stance.local(at(k)).y);
            count += 1.0;
        }
        Some(Setup {
            stance_m: sum[0] / count,
            hands_out_m: sum[1] / count,
            head_out_m: head.map(|_| sum[2] / count),
        })
    }

    /// How far apart two set-ups are, metres: over the lengths both have.
    pub fn distance(&self, other: &Setup) -> f32 {
        let head = match (self.head_out_m, other.head_out_m) {
            (Some(a), Some(b)) => a - b,
            _ => 0.0,
        };
        let (stance, hands) = (
            self.stance_m - other.stance_m,
            self.hands_out_m - other.hands_out_m,
        );
        crate::math::sqrt(stance * stance + hands * hands + head * head)
    }
}

/// Which of `candidates` (`None` for one without a set-up) `setup` is closest to; `None` if
/// none has one. The first of equals wins.
pub fn nearest(
    setup: &Setup,
    candidates: impl IntoIterator<Item = Option<Setup>>,
) -> Option<usize> {
    let mut best: Option<(usize, f32)> = None;
    for (i, candidate) in candidates.into_iter().enumerate() {
        let Some(c) = candidate else {
            continue;
        };
        let d = setup.distance(&c);
        if best.is_none_or(|(_, b)| d < b) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;

    #[test]
    fn stance_and_hands_are_measured_from_the_feet_toward_the_ball() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let mut frame = [Vec3::zeros(); 17];
        skeleton.rest_positions(&mut frame);
        let at = |j: Joint| skeleton.index_of(j).unwrap();
        // Feet 0.6 m apart along X, the chest leaning out toward +Z, the hands 0.3 m out.
        frame[at(Joint::LeftAnkle)] = Vec3::new(0.3, 0.1, 0.0);
        frame[at(Joint::RightAnkle)] = Vec3::new(-0.3, 0.1, 0.0);
        frame[at(Joint::Pelvis)] = Vec3::new(0.0, 1.0, -0.1);
        frame[at(Joint::Thorax)] = Vec3::new(0.0, 1.4, 0.2);
        frame[at(Joint::LeftWrist)] = Vec3::new(0.05, 0.8, 0.3);
        frame[at(Joint::RightWrist)] = Vec3::new(-0.05, 0.8, 0.3);
        let frames: std::vec::Vec<Vec3> = frame.iter().chain(frame.iter()).copied().collect();
        let setup = Setup::new(&skeleton, Frames::metres(&frames, 17), Side::Left).unwrap();
        assert!((setup.stance_m - 0.6).abs() < 1e-5, "{setup:?}");
        assert!((setup.hands_out_m - 0.3).abs() < 1e-5, "{setup:?}");
        assert_eq!(setup.head_out_m, None);
        assert_eq!(
            Setup::new(&skeleton, Frames::metres(&frames[..5], 17), Side::Left),
            None
        );
    }

    #[test]
    fn the_nearest_set_up_wins_and_missing_ones_are_passed_over() {
        let s = |stance_m, hands_out_m| Setup {
            stance_m,
            hands_out_m,
            head_out_m: None,
        };
        let (iron, driver) = (s(0.58, 0.27), s(0.65, 0.33));
        assert_eq!(nearest(&s(0.59, 0.28), [Some(iron), Some(driver)]), Some(0));
        assert_eq!(nearest(&s(0.64, 0.34), [Some(iron), Some(driver)]), Some(1));
        assert_eq!(nearest(&s(0.64, 0.34), [Some(iron), None]), Some(0));
        assert_eq!(nearest(&s(0.64, 0.34), [None, None]), None);
        // A tracked club head decides where the body alone is in between.
        let head = |setup: Setup, m| Setup {
            head_out_m: Some(m),
            ..setup
        };
        let between = head(s(0.615, 0.30), 1.0);
        assert_eq!(
            nearest(&between, [Some(head(iron, 0.68)), Some(head(driver, 1.08))]),
            Some(1)
        );
    }
}
