//! The top: where the hands turn from the backswing to the downswing, and a pause there.

use super::signal::turning;
use super::track::Hands;
use super::{EventError, Moment, NOISE_MARGIN, PUTT_RISE_M, STILL_FRACTION, STILL_SWAY_M_S};

/// Where the hands turn at the top, before a pause there is looked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Turn {
    /// Its frame.
    pub(super) frame: usize,
    /// Whether the stroke is a putt: the hands rise less than [`PUTT_RISE_M`].
    pub(super) putt: bool,
}

/// The top of the backswing (or backstroke), and when the hands arrived there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Top {
    /// The top: the turn, or where the hands pause there, the pause's end.
    pub(super) at: Moment,
    /// When the hands arrived, frames: the top's time, or the pause's start.
    pub(super) arrival: f32,
}

/// The fastest hands of the swing, then back to the first minimum of hand speed where the
/// hands are high (in the upper half of their range): the top. A low minimum (the dip at
/// impact, when the fastest hands come in the follow-through) is passed over; a putt's top is
/// the first minimum.
///
/// # Errors
/// [`EventError::NoSwing`] where that walk reaches the first frame.
pub(super) fn turn(hands: &Hands<'_>) -> Result<Turn, EventError> {
    let frames = hands.track.frames;
    let (low, high) = (0..frames).fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), t| {
        let y = hands.at(t).y;
        (lo.min(y), hi.max(y))
    });
    let putt = high - low < PUTT_RISE_M;
    let fastest = (0..frames)
        .max_by(|&a, &b| hands.speed(a).total_cmp(&hands.speed(b)))
        .ok_or(EventError::NoSwing)?;
    let mut top = fastest;
    loop {
        while top > 0 && hands.speed(top - 1) <= hands.speed(top) {
            top -= 1;
        }
        if top == 0 || putt || hands.at(top).y > 0.5 * (low + high) {
            break;
        }
        // Step off the low minimum (every pass moves back at least one frame), then climb.
        top -= 1;
        while top > 0 && hands.speed(top - 1) >= hands.speed(top) {
            top -= 1;
        }
    }
    if top == 0 {
        return Err(EventError::NoSwing);
    }
    Ok(Turn { frame: top, putt })
}

impl Turn {
    /// The top this turn makes in a backswing from `address`, given the fastest the set-up's
    /// quietest stretch moved (`quietest`, m/s).
    ///
    /// A pause at the top: the hands as still as the set-up's quietest stretch (the club
    /// head's where it is tracked, else the hands'; at least a standing body's sway) for longer
    /// than a speed's smoothing reaches, where that stillness can be told from the hands'
    /// turn (under [`STILL_FRACTION`] of their fastest in the backswing, as the set-up's is).
    /// The backswing lasts until the downswing starts, so the top is the pause's end; the
    /// hands arrived at its start. A speed reads positions smoothed over ±half frames,
    /// `half.max(1)` frames either side, so still speeds run that far inside either end of the
    /// still frames. Without a pause, the top is the slowest hands, between frames.
    pub(super) fn top(self, hands: &Hands<'_>, address: usize, quietest: f32) -> Top {
        let (frames, half) = (hands.track.frames, hands.track.half);
        let quiet = (NOISE_MARGIN * quietest).max(STILL_SWAY_M_S);
        let backswing = (address..self.frame)
            .map(|t| hands.speed(t))
            .fold(0.0, f32::max);
        let inset = half + half.max(1);
        let (mut begin, mut end) = (self.frame, self.frame);
        if quiet < STILL_FRACTION * backswing && hands.speed(self.frame) <= quiet {
            while begin > address + 1 && hands.speed(begin - 1) <= quiet {
                begin -= 1;
            }
            while end + 2 < frames && hands.speed(end + 1) <= quiet {
                end += 1;
            }
        }
        if end - begin >= inset {
            let (begin, end) = (
                (begin.saturating_sub(inset)).max(address + 1),
                (end + inset).min(frames - 2),
            );
            return Top {
                at: Moment::new(end, end as f32),
                arrival: begin as f32,
            };
        }
        let time = turning(&|t| hands.speed(t), self.frame, frames);
        Top {
            at: Moment::new(self.frame, time),
            arrival: time,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::synthetic::{eased, hands_only, FRAMES, HOME, RATE_HZ, SWING};
    use super::super::track::Track;
    use super::*;
    use crate::frames::Frames;

    /// The turn and the top of the hands eased through `keys`.
    fn top_of(keys: &[(usize, [f32; 3])]) -> Result<(Turn, Top), EventError> {
        let positions = hands_only(&eased(keys, FRAMES));
        let track = Track::new(Frames::metres(&positions, 2), RATE_HZ);
        let hands = Hands::new(&track, [0, 1]);
        let turn = turn(&hands)?;
        // The set-up is still: its quietest stretch does not move.
        Ok((turn, turn.top(&hands, 15, 0.0)))
    }

    #[test]
    fn the_top_is_where_the_hands_turn_back_high() {
        let (turn, top) = top_of(&SWING).unwrap();
        assert!(!turn.putt);
        // The downswing is faster than the backswing: the smoothed speed is slowest a little
        // before the hands stop.
        assert!(turn.frame.abs_diff(35) <= 1, "{turn:?}");
        // Without a pause the top is the turn, placed between frames, and the hands arrive
        // there.
        assert_eq!(top.at.frame, turn.frame);
        assert!((top.at.time - turn.frame as f32).abs() <= 0.5, "{top:?}");
        assert_eq!(top.arrival, top.at.time);
    }

    #[test]
    fn the_dip_at_impact_is_passed_over_when_the_fastest_hands_come_after_it() {
        // A follow-through far faster than the downswing.
        let mut keys = SWING;
        keys[3].0 = 46;
        let (turn, _) = top_of(&keys).unwrap();
        assert!(turn.frame.abs_diff(35) <= 1, "{turn:?}");
    }

    #[test]
    fn hands_that_rise_a_little_make_a_putt_whose_top_is_the_first_turn() {
        let keys = [(15, HOME), (30, [0.0, 1.05, -0.15]), (45, [0.0, 1.05, 0.2])];
        let (turn, _) = top_of(&keys).unwrap();
        assert!(turn.putt);
        assert!(turn.frame.abs_diff(30) <= 1, "{turn:?}");
    }

    #[test]
    fn still_hands_have_no_top() {
        assert_eq!(top_of(&[(15, HOME)]), Err(EventError::NoSwing));
    }

    #[test]
    fn a_pause_at_the_top_ends_it_and_the_hands_arrived_at_its_start() {
        // The swing held at the top from frame 35 to 45.
        let keys = [
            SWING[0],
            SWING[1],
            (45, SWING[1].1),
            (53, HOME),
            (65, SWING[3].1),
        ];
        let (turn, top) = top_of(&keys).unwrap();
        assert!((35..=45).contains(&turn.frame), "{turn:?}");
        assert_eq!(top.at.time, top.at.frame as f32);
        assert!((top.at.time - 45.0).abs() <= 1.0, "{top:?}");
        assert!((top.arrival - 35.0).abs() <= 1.0, "{top:?}");
    }
}
