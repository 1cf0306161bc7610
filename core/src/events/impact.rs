//! Impact: after the top, the club head (else the hands) back where it was at address.

use super::address::Address;
use super::limbs::Limbs;
use super::signal::turning;
use super::track::Track;
use super::{EventError, Moment, IMPACT_LAG_S, IMPACT_WITHIN_S, PLANTED_M};
use crate::math::norm;
use crate::Vec3;

/// Impact after the `top`: within [`IMPACT_WITHIN_S`], where the `probe` (the club head, else
/// the hands) comes closest to where it was at `address` (with a club, where the head was at
/// its frame; else where the hands rested), its time between frames. Without a club, a full
/// swing's impact comes [`IMPACT_LAG_S`] later: the hands lead the club head through impact
/// (shaft lean).
///
/// # Errors
/// [`EventError::NoSwing`] without a frame after it, or where the feet do not stay planted
/// from address to impact (someone walking).
pub(super) fn find(
    track: &Track<'_>,
    limbs: &Limbs,
    probe: &dyn Fn(usize) -> Vec3,
    address: &Address,
    top: usize,
    putt: bool,
) -> Result<Moment, EventError> {
    let frames = track.frames;
    let home = match limbs.club {
        Some(_) => probe(address.at.frame),
        None => address.rested,
    };
    let away = |t: usize| norm(&(probe(t) - home));
    let reach = top + 1 + (libm::roundf(IMPACT_WITHIN_S * track.rate) as usize).min(frames);
    let impact = (top + 1..reach.min(frames))
        .min_by(|&a, &b| away(a).total_cmp(&away(b)))
        .filter(|&t| t + 1 < frames)
        .ok_or(EventError::NoSwing)?;
    if !planted(track, limbs.feet, address.at.frame, impact) {
        return Err(EventError::NoSwing);
    }
    let time = match limbs.club {
        None if !putt => turning(&away, impact, frames) + IMPACT_LAG_S * track.rate,
        _ => turning(&away, impact, frames),
    }
    .min((frames - 1) as f32);
    Ok(Moment::new(impact, time))
}

/// Whether the `feet` (their midpoint) stay within [`PLANTED_M`] of where they stand at
/// `address` until `impact`: a golfer strikes the ball from where they stand.
fn planted(track: &Track<'_>, feet: [usize; 2], address: usize, impact: usize) -> bool {
    let stance = |t: usize| (track.at(feet[0], t) + track.at(feet[1], t)) * 0.5;
    !(address..=impact).any(|t| norm(&(stance(t) - stance(address))) > PLANTED_M)
}

#[cfg(test)]
mod tests {
    use super::super::synthetic::{eased, joints, wrists, FRAMES, HOME, RATE_HZ, SWING};
    use super::super::track::Hands;
    use super::*;
    use crate::frames::Frames;
    use std::vec::Vec;

    /// Joints: wrists 0 and 1 around the hands eased through [`SWING`], feet 2 and 3 eased
    /// through `feet` (their midpoint), a club head 4 eased through `head`.
    fn swing(feet: &[(usize, [f32; 3])], head: &[(usize, [f32; 3])]) -> Vec<Vec3> {
        let [left, right] = wrists(&eased(&SWING, FRAMES));
        let stance = eased(feet, FRAMES);
        let apart = Vec3::new(0.0, 0.0, 0.2);
        let left_foot: Vec<Vec3> = stance.iter().map(|s| s + apart).collect();
        let right_foot: Vec<Vec3> = stance.iter().map(|s| s - apart).collect();
        joints(&[&left, &right, &left_foot, &right_foot, &eased(head, FRAMES)])
    }

    const STANCE: [(usize, [f32; 3]); 1] = [(0, [0.0, 0.0, 0.0])];

    /// Impact in `positions` (of [`swing`]), with the club head where `club`, the address at
    /// frame 15 and the top at 35.
    fn impact_of(positions: &[Vec3], club: bool, putt: bool) -> Result<Moment, EventError> {
        let track = Track::new(Frames::metres(positions, 5), RATE_HZ);
        let hands = Hands::new(&track, [0, 1]);
        let limbs = Limbs {
            wrists: [0, 1],
            shoulders: [0, 1],
            feet: [2, 3],
            club: club.then_some((0, 4)),
        };
        let address = Address {
            at: Moment::new(15, 15.0),
            rested: hands.at(10),
            quietest: 0.0,
        };
        let head = |t: usize| track.at(4, t);
        let probe: &dyn Fn(usize) -> Vec3 = match club {
            true => &head,
            false => &|t| hands.at(t),
        };
        find(&track, &limbs, probe, &address, 35, putt)
    }

    #[test]
    fn impact_is_where_the_hands_are_back_home_the_club_head_a_little_later() {
        let positions = swing(&STANCE, &SWING);
        let putt = impact_of(&positions, false, true).unwrap();
        assert!(putt.frame.abs_diff(43) <= 1, "{putt:?}");
        assert!((putt.time - 43.0).abs() <= 1.0, "{putt:?}");
        // A full swing's hands lead its club head.
        let full = impact_of(&positions, false, false).unwrap();
        assert_eq!(full.frame, putt.frame);
        assert!(
            (full.time - putt.time - IMPACT_LAG_S * RATE_HZ).abs() < 1e-4,
            "{full:?}"
        );
    }

    #[test]
    fn with_a_club_impact_is_where_its_head_is_back_at_address() {
        // The head comes back to its address two frames after the hands.
        let head = [
            (15, HOME),
            (35, [0.5, 2.5, -0.9]),
            (45, HOME),
            (55, [0.5, 2.5, 1.0]),
        ];
        let impact = impact_of(&swing(&STANCE, &head), true, false).unwrap();
        assert!(impact.frame.abs_diff(45) <= 1, "{impact:?}");
        assert!((impact.time - 45.0).abs() <= 1.0, "{impact:?}");
    }

    #[test]
    fn feet_that_walk_between_address_and_impact_make_no_stroke() {
        let walk = [(15, [0.0, 0.0, 0.0]), (40, [0.6, 0.0, 0.0])];
        let positions = swing(&walk, &SWING);
        assert_eq!(
            impact_of(&positions, false, false),
            Err(EventError::NoSwing)
        );
        // A shuffle of a few centimetres is planted.
        let shuffle = [(15, [0.0, 0.0, 0.0]), (40, [0.05, 0.0, 0.0])];
        assert!(impact_of(&swing(&shuffle, &SWING), false, false).is_ok());
    }
}
