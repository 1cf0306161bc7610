//! The parallels: the positions where the shaft or an arm passes a level. Toe-up (P2),
//! mid-backswing (P3), mid-downswing (P5), P6, mid-follow-through (P8) and P9.

use super::limbs::{elevation, Arms};
use super::signal::{crossed, crossing};
use super::{EventError, Moment, FOLLOW_ARM_DEG, SHAFT_DOWN_SHARE, TOE_UP_ARM_DEG};

/// The parallels of a full swing up to the follow-through.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Parallels {
    /// P2, toe-up: the shaft (grip → head) rising through horizontal before the top; without
    /// a club, the lead arm rising through [`TOE_UP_ARM_DEG`].
    pub(super) toe_up: Moment,
    /// P3, mid-backswing: the lead arm (shoulder → wrist) rising through horizontal.
    pub(super) mid_backswing: Moment,
    /// P5, mid-downswing: the lead arm falling through horizontal.
    pub(super) mid_downswing: Moment,
    /// P6: the shaft falling through horizontal between mid-downswing and impact, where it
    /// does; without a club, [`SHAFT_DOWN_SHARE`] of the way.
    pub(super) shaft_down: Option<Moment>,
    /// P8, mid-follow-through: the shaft rising through horizontal after impact; without a
    /// club, the lead arm rising through [`FOLLOW_ARM_DEG`].
    pub(super) follow: Moment,
}

/// The parallels of a swing led by `arms` from `address` through the `top` to `impact`, read
/// from the shaft where the `club` (grip, head) is tracked.
///
/// # Errors
/// [`EventError::NoSwing`] where the shaft or the lead arm does not pass a level it must.
pub(super) fn find(
    arms: &Arms<'_>,
    club: Option<(usize, usize)>,
    address: usize,
    top: usize,
    impact: Moment,
) -> Result<Parallels, EventError> {
    let track = arms.track;
    let frames = track.frames;
    let arm = |t: usize| arms.lead(t);
    let shaft = |t: usize| match club {
        Some((grip, head)) => elevation(track.at(head, t) - track.at(grip, t)),
        None => 0.0,
    };
    let (toe_up, follow) = match club {
        Some(_) => (
            crossing(address..top, shaft, 0.0, true),
            crossing(impact.frame..frames, shaft, 0.0, true),
        ),
        None => (
            crossing(address..top, arm, TOE_UP_ARM_DEG, true),
            crossing(impact.frame..frames, arm, FOLLOW_ARM_DEG, true),
        ),
    };
    let toe_up = toe_up.ok_or(EventError::NoSwing)?;
    let follow = follow.ok_or(EventError::NoSwing)?;
    let mid_backswing = crossing(toe_up..top, arm, 0.0, true).ok_or(EventError::NoSwing)?;
    let mid_downswing = crossing(top..impact.frame, arm, 0.0, false).ok_or(EventError::NoSwing)?;
    let (lift, lift_level) = match club {
        Some(_) => (&shaft as &dyn Fn(usize) -> f32, (0.0, 0.0)),
        None => (
            &arm as &dyn Fn(usize) -> f32,
            (TOE_UP_ARM_DEG, FOLLOW_ARM_DEG),
        ),
    };
    let p5 = crossed(&arm, 0.0, mid_downswing, frames);
    let shaft_down = match club {
        Some(_) => crossing(mid_downswing..impact.frame, shaft, 0.0, false)
            .map(|t| Moment::new(t, crossed(&shaft, 0.0, t, frames))),
        None => {
            let time = p5 + SHAFT_DOWN_SHARE * (impact.time - p5);
            Some(Moment::new(libm::roundf(time) as usize, time))
        }
    };
    Ok(Parallels {
        toe_up: Moment::new(toe_up, crossed(lift, lift_level.0, toe_up, frames)),
        mid_backswing: Moment::new(mid_backswing, crossed(&arm, 0.0, mid_backswing, frames)),
        mid_downswing: Moment::new(mid_downswing, p5),
        shaft_down,
        follow: Moment::new(follow, crossed(lift, lift_level.1, follow, frames)),
    })
}

/// P9: the trail arm rising through horizontal after `impact`, before the `finish`.
pub(super) fn trail_up(arms: &Arms<'_>, impact: usize, finish: usize) -> Option<Moment> {
    let trail_arm = |t: usize| arms.trail(t);
    crossing(impact..finish, trail_arm, 0.0, true)
        .map(|t| Moment::new(t, crossed(&trail_arm, 0.0, t, arms.track.frames)))
}

#[cfg(test)]
mod tests {
    use super::super::limbs::Limbs;
    use super::super::synthetic::{joints, RATE_HZ};
    use super::super::track::Track;
    use super::super::Side;
    use super::*;
    use crate::frames::Frames;
    use crate::Vec3;
    use std::vec::Vec;

    /// `frames` frames of an elevation, degrees, linear from key to key (frame, degrees).
    fn angles(keys: &[(usize, f32)], frames: usize) -> Vec<f32> {
        (0..frames)
            .map(|f| match keys.iter().position(|&(k, _)| k > f) {
                Some(0) => keys[0].1,
                None => keys[keys.len() - 1].1,
                Some(i) => {
                    let ((a, p), (b, q)) = (keys[i - 1], keys[i]);
                    p + (q - p) * (f - a) as f32 / (b - a) as f32
                }
            })
            .collect()
    }

    /// A segment 0.6 m long from `from` at each of `elevations` (degrees), in the x-y plane.
    fn segment(from: Vec3, elevations: &[f32]) -> [Vec<Vec3>; 2] {
        let to = elevations.iter().map(|e| {
            let (s, c) = libm::sincosf(e.to_radians());
            from + Vec3::new(c, s, 0.0) * 0.6
        });
        [elevations.iter().map(|_| from).collect(), to.collect()]
    }

    /// The lead arm: -80° at address (frame 10), 40° at the top (30), -80° at impact (40),
    /// 60° at frame 60; the trail arm: -80° until impact, 60° at frame 55. With a club, the
    /// shaft 10° above the lead arm.
    fn parallels(club: bool, impact_time: f32) -> (Result<Parallels, EventError>, Option<Moment>) {
        let frames = 70;
        let lead = angles(&[(10, -80.0), (30, 40.0), (40, -80.0), (60, 60.0)], frames);
        let trail = angles(&[(40, -80.0), (55, 60.0)], frames);
        let shaft: Vec<f32> = lead.iter().map(|e| e + 10.0).collect();
        let [lead_shoulder, lead_wrist] = segment(Vec3::new(0.0, 1.4, 0.2), &lead);
        let [trail_shoulder, trail_wrist] = segment(Vec3::new(0.0, 1.4, -0.2), &trail);
        let [grip, head] = segment(Vec3::new(0.0, 0.9, 0.0), &shaft);
        let positions = joints(&[
            &lead_shoulder,
            &lead_wrist,
            &trail_shoulder,
            &trail_wrist,
            &grip,
            &head,
        ]);
        let track = Track::new(Frames::metres(&positions, 6), RATE_HZ);
        let limbs = Limbs {
            wrists: [1, 3],
            shoulders: [0, 2],
            feet: [0, 2],
            club: club.then_some((4, 5)),
        };
        let arms = limbs.arms(&track, Side::Left);
        let found = find(&arms, limbs.club, 10, 30, Moment::new(40, impact_time));
        (found, trail_up(&arms, 40, 65))
    }

    fn near(found: Moment, frame: usize, time: f32) {
        assert_eq!(found.frame, frame, "{found:?}, not {time}");
        assert!((found.time - time).abs() < 0.02, "{found:?}, not {time}");
    }

    #[test]
    fn without_a_club_the_arms_give_the_parallels() {
        let (found, p9) = parallels(false, 40.5);
        let found = found.unwrap();
        // The lead arm rises 6° a frame to the top, falls 12° to impact, rises 7° after it.
        near(found.toe_up, 15, 10.0 + 28.0 / 6.0);
        near(found.mid_backswing, 23, 10.0 + 80.0 / 6.0);
        near(found.mid_downswing, 33, 30.0 + 40.0 / 12.0);
        near(found.follow, 45, 45.0);
        let p5 = found.mid_downswing.time;
        let p6 = p5 + SHAFT_DOWN_SHARE * (40.5 - p5);
        assert_eq!(
            found.shaft_down,
            Some(Moment::new(libm::roundf(p6) as usize, p6))
        );
        // The trail arm rises 140° in 15 frames.
        near(p9.unwrap(), 49, 40.0 + 80.0 * 15.0 / 140.0);
    }

    #[test]
    fn with_a_club_the_shaft_gives_toe_up_p6_and_the_follow_through() {
        let (found, _) = parallels(true, 40.0);
        let found = found.unwrap();
        // The shaft is level where the lead arm is at -10°.
        near(found.toe_up, 22, 10.0 + 70.0 / 6.0);
        near(found.shaft_down.unwrap(), 34, 30.0 + 50.0 / 12.0);
        near(found.follow, 50, 40.0 + 70.0 / 7.0);
        // The lead arm's own parallels are the same.
        near(found.mid_backswing, 23, 10.0 + 80.0 / 6.0);
    }

    #[test]
    fn an_arm_that_never_rises_to_the_level_makes_no_swing() {
        // A top before the lead arm is level: no mid-backswing.
        let frames = 70;
        let lead = angles(&[(10, -80.0), (30, -20.0), (40, -80.0), (60, 60.0)], frames);
        let [shoulder, wrist] = segment(Vec3::new(0.0, 1.4, 0.2), &lead);
        let positions = joints(&[&shoulder, &wrist]);
        let track = Track::new(Frames::metres(&positions, 2), RATE_HZ);
        let limbs = Limbs {
            wrists: [1, 1],
            shoulders: [0, 0],
            feet: [0, 0],
            club: None,
        };
        let arms = limbs.arms(&track, Side::Left);
        assert_eq!(
            find(&arms, None, 10, 30, Moment::new(40, 40.0)),
            Err(EventError::NoSwing)
        );
    }
}
