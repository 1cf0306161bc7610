//! The finish: the hands' highest point after a full swing's follow-through, or where a putt's
//! forward stroke stops.

use super::signal::{between, turning};
use super::track::Hands;
use super::{EventError, Moment, STILL_FRACTION};

/// A full swing's finish: the hands' highest point after the follow-through (`follow`), its
/// time between frames.
pub(super) fn full(hands: &Hands<'_>, follow: usize) -> Moment {
    let frames = hands.track.frames;
    let mut finish = follow;
    while finish + 1 < frames && hands.at(finish + 1).y >= hands.at(finish).y {
        finish += 1;
    }
    Moment::new(finish, turning(&|t| hands.at(t).y, finish, frames))
}

/// A putt's finish: where the forward stroke after `impact` stops, the hands slower than
/// [`STILL_FRACTION`] of their fastest after impact (a speed minimum would come late, once the
/// smoothing window has passed the stop); its time where their speed falls through that.
///
/// # Errors
/// [`EventError::NoSwing`] where that is not after impact.
pub(super) fn putt(hands: &Hands<'_>, impact: usize) -> Result<Moment, EventError> {
    let frames = hands.track.frames;
    let mut peak = impact;
    while peak + 1 < frames && hands.speed(peak + 1) >= hands.speed(peak) {
        peak += 1;
    }
    let stopped = STILL_FRACTION * hands.speed(peak);
    let finish = (peak..frames)
        .find(|&t| hands.speed(t) < stopped)
        .unwrap_or(frames - 1);
    if finish <= impact {
        return Err(EventError::NoSwing);
    }
    let time = between(
        |t| hands.speed(t),
        stopped,
        finish.saturating_sub(1),
        finish,
    );
    Ok(Moment::new(finish, time))
}

#[cfg(test)]
mod tests {
    use super::super::synthetic::{eased, hands_only, FRAMES, HOME, RATE_HZ, SWING};
    use super::super::track::Track;
    use super::*;
    use crate::frames::Frames;

    #[test]
    fn a_full_swing_finishes_with_the_hands_highest() {
        let positions = hands_only(&eased(&SWING, FRAMES));
        let track = Track::new(Frames::metres(&positions, 2), RATE_HZ);
        let hands = Hands::new(&track, [0, 1]);
        // From anywhere on the way up after impact.
        for follow in [45, 50] {
            let finish = full(&hands, follow);
            assert!(finish.frame.abs_diff(55) <= 1, "{finish:?}");
            assert!(
                (finish.time - finish.frame as f32).abs() <= 0.5,
                "{finish:?}"
            );
            assert!(hands.at(finish.frame).y >= hands.at(52).y);
        }
    }

    #[test]
    fn a_putt_finishes_where_the_forward_stroke_stops() {
        // Back to frame 30, through address (at frame 36) to frame 45, still after.
        let keys = [(15, HOME), (30, [0.0, 1.02, -0.1]), (45, [0.0, 1.02, 0.2])];
        let positions = hands_only(&eased(&keys, FRAMES));
        let track = Track::new(Frames::metres(&positions, 2), RATE_HZ);
        let hands = Hands::new(&track, [0, 1]);
        let finish = putt(&hands, 36).unwrap();
        // Near the stop, once the hands' smoothed speed is that slow.
        assert!((42..=46).contains(&finish.frame), "{finish:?}");
        let stopped = STILL_FRACTION * (36..45).map(|t| hands.speed(t)).fold(0.0, f32::max);
        assert!(hands.speed(finish.frame) < stopped);
        assert!(hands.speed(finish.frame - 1) >= stopped);
        assert!(finish.time >= (finish.frame - 1) as f32 && finish.time <= finish.frame as f32);
        // An impact at the last frame leaves no frame to finish in.
        assert_eq!(putt(&hands, FRAMES - 1), Err(EventError::NoSwing));
    }
}
