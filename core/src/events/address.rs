//! The address: the still set-up before the top, and the takeaway from it.

use super::takeaway::onset;
use super::top::Turn;
use super::track::{Hands, Memo, Track};
use super::{EventError, Moment, NOISE_MARGIN, STILL_FRACTION, STILL_S};
use crate::Vec3;

/// The set-up and the takeaway from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Address {
    /// The takeaway's time (frames, between frames) and the frame before it.
    pub(super) at: Moment,
    /// Where the hands rested in the set-up.
    pub(super) rested: Vec3,
    /// The fastest the probe moved in the set-up's quietest stretch, m/s: pose noise.
    pub(super) quietest: f32,
}

/// The end of the still set-up.
struct Still {
    /// Its last frame.
    settled: usize,
    /// The fastest the probe moved in the quietest stretch before the top, m/s.
    quietest: f32,
}

/// Walking back from the `top`, the last frame of a still set-up: the `probe` (the club head,
/// else the hands) slower than [`STILL_FRACTION`] of its backswing peak over `window` frames,
/// so a waggle before it is skipped. Pose noise makes still hands seem to move: the threshold
/// is at least [`NOISE_MARGIN`] times the quietest stretch before the top. A still stretch that
/// runs into the start of the recording counts as long enough.
fn still(
    track: &Track<'_>,
    probe: &dyn Fn(usize) -> Vec3,
    top: usize,
    window: usize,
) -> Result<Still, EventError> {
    let speeds = Memo::new();
    let speed = |t: usize| speeds.get(t, |t| track.speed(probe, t));
    let peak = (0..top).map(speed).fold(0.0, f32::max);
    // The fastest the probe goes in a stretch of `window` frames ending at `t`.
    let stir = |t: usize| {
        (t.saturating_sub(window)..=t)
            .map(speed)
            .fold(0.0, f32::max)
    };
    let quietest = (0..top).map(stir).fold(f32::INFINITY, f32::min);
    let still = (STILL_FRACTION * peak).max(NOISE_MARGIN * quietest);
    let settled = (0..top)
        .rev()
        .find(|&t| stir(t) < still)
        .ok_or(EventError::NoSwing)?;
    Ok(Still { settled, quietest })
}

/// The address before the hands' `turn` at the top, the `probe` (the club head, else the
/// hands) still for [`STILL_S`] there: the takeaway, the start of the hands' way back from
/// where they rested ([`onset`]), its frame the last before it. A putt's stroke moves the
/// hands a few centimetres, too little to fit its start: its address is the end of the still
/// set-up.
///
/// # Errors
/// [`EventError::NoSwing`] without a still set-up before the top.
pub(super) fn find(
    hands: &Hands<'_>,
    probe: &dyn Fn(usize) -> Vec3,
    turn: Turn,
) -> Result<Address, EventError> {
    let top = turn.frame;
    let window = (libm::roundf(STILL_S * hands.track.rate) as usize).max(1);
    let Still { settled, quietest } = still(hands.track, probe, top, window)?;
    let rest = settled.saturating_sub(window);
    let rested =
        (rest..=settled).fold(Vec3::zeros(), |s, t| s + hands.at(t)) / (settled - rest + 1) as f32;
    let taken = match turn.putt {
        true => settled as f32,
        false => onset(|t| hands.at(t), rested, rest, top)
            .map_or(settled as f32, |t| t.clamp(0.0, (top - 1) as f32)),
    };
    Ok(Address {
        at: Moment::new(taken as usize, taken),
        rested,
        quietest,
    })
}

#[cfg(test)]
mod tests {
    use super::super::synthetic::{eased, hands_only, FRAMES, HOME, RATE_HZ, SWING};
    use super::*;
    use crate::frames::Frames;

    /// The address of the hands eased through `keys`, their turn at the top at `top`.
    fn address_of(
        keys: &[(usize, [f32; 3])],
        top: usize,
        putt: bool,
    ) -> Result<Address, EventError> {
        let positions = hands_only(&eased(keys, FRAMES));
        let track = Track::new(Frames::metres(&positions, 2), RATE_HZ);
        let hands = Hands::new(&track, [0, 1]);
        find(&hands, &|t| hands.at(t), Turn { frame: top, putt })
    }

    #[test]
    fn the_address_is_the_takeaway_from_the_still_set_up() {
        // The hands leave at frame 15, easing out of rest: the line fitted to the cube root of
        // their progress meets zero a little before it.
        let address = address_of(&SWING, 35, false).unwrap();
        assert!((12.5..=15.0).contains(&address.at.time), "{address:?}");
        assert_eq!(address.at.frame, address.at.time as usize);
        assert!((address.rested - Vec3::from(HOME)).norm() < 1e-3);
        assert_eq!(address.quietest, 0.0);
    }

    #[test]
    fn a_waggle_before_the_set_up_is_skipped() {
        let waggle = [0.2, 1.1, 0.1];
        let keys = [(0, HOME), (4, waggle), (8, HOME), (15, HOME), SWING[1]];
        let address = address_of(&keys, 35, false).unwrap();
        assert!((12.5..=15.0).contains(&address.at.time), "{address:?}");
    }

    #[test]
    fn a_putt_s_address_is_the_end_of_its_still_set_up() {
        let keys = [(15, HOME), (30, [0.0, 1.0, -0.15])];
        let address = address_of(&keys, 30, true).unwrap();
        assert_eq!(address.at.time, address.at.frame as f32);
        // Its last still frame: the hands move under a tenth of their peak speed for a few
        // frames after they start.
        assert!((15..=19).contains(&address.at.frame), "{address:?}");
    }

    #[test]
    fn without_motion_before_the_top_no_set_up_can_be_told() {
        // A turn found while the hands still rest: nothing is slower than their stillness.
        assert_eq!(address_of(&SWING, 10, false), Err(EventError::NoSwing));
    }
}
