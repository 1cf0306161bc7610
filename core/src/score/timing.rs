//! The timing stage: how early or late each of the student's events may be found (seconds,
//! one standard deviation).
//!
//! Every event is a moment of the hands' motion (a turn, a crossing, a start), so it moves by
//! about as long as their velocity takes to change by its noise (its vertical part at the
//! finish, which their height defines), the shorter way; the noise is the velocity the still
//! set-up shows, before the takeaway. A turn may lie anywhere the motion stays within its noise
//! of it: the top, the longer way (a slow backswing turning into a quick downswing); a start, a
//! stop or a crossing, the shorter, and so either end of a pause at the top. The takeaway,
//! timed from the hands' arrival at the top and the crossings of the arms' progress
//! ([`events::takeaway_against`]), moves with the arrival's error, scaled, and with the
//! crossings' scatter.

use super::align::smoothed;
use crate::events::{self, Event, SwingEvents, Takeaway};
use crate::frames::Frames;
use crate::joint::Joint;
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::Vec3;

/// The least an event's timing uncertainty is taken to be, seconds (one standard deviation;
/// a joint's deviation along its own path is uncertain by its speed times it).
pub const EVENT_TIMING_S: f32 = 0.005;
/// The most an event's timing uncertainty is taken to be, seconds.
pub const MAX_EVENT_TIMING_S: f32 = 0.2;

/// What the timing stage finds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Timing {
    /// Each event's uncertainty, seconds, [`Event::ALL`] order.
    pub event: [f32; Event::COUNT],
    /// How far the takeaway moves for each second the top (or the arrival) moves.
    pub top_gain: f32,
    /// The hands paused at the top.
    pub paused: bool,
}

/// The timing of `student`'s `events` (at `hz`), whose takeaway was timed as `takeaway`.
pub(super) fn timing(
    skeleton: &Skeleton,
    (student, hz): (Frames<'_>, f32),
    events: &SwingEvents,
    takeaway: Option<Takeaway>,
) -> Timing {
    let mut event = [MAX_EVENT_TIMING_S; Event::COUNT];
    // Where the hands paused at the top, the takeaway is fitted up to their arrival there
    // ([`SwingEvents::arrival`]): how early or late that may be found.
    let paused = events.pause() > 0.0;
    let mut arrival = MAX_EVENT_TIMING_S;
    let hands = skeleton
        .find(&[Joint::LeftWrist, Joint::LeftHand])
        .zip(skeleton.find(&[Joint::RightWrist, Joint::RightHand]));
    if let (Some(hands), Some(takeaway)) = (hands, events.time(Event::Address)) {
        let change = Change::new((student, hz), hands, takeaway);
        for (e, spread) in Event::ALL.into_iter().zip(event.iter_mut()) {
            let Some(x) = events.time(e) else {
                continue;
            };
            let ways = change.ways(x, e == Event::Finish);
            *spread = match e == Event::Top && !paused {
                true => ways[0].max(ways[1]),
                false => ways[0].min(ways[1]),
            }
            .max(EVENT_TIMING_S);
        }
        if paused {
            let ways = change.ways(events.arrival(), false);
            arrival = ways[0].min(ways[1]).max(EVENT_TIMING_S);
        }
    }
    let top_gain = takeaway.map_or(0.0, |t| t.top_gain);
    if let Some(t) = takeaway {
        let a = Event::Address as usize;
        let arrival = match paused {
            true => arrival,
            false => event[Event::Top as usize],
        };
        event[a] = crate::math::hypot(
            crate::math::hypot(event[a], t.top_gain * arrival),
            t.spread / hz,
        )
        .clamp(EVENT_TIMING_S, MAX_EVENT_TIMING_S);
    }
    Timing {
        event,
        top_gain,
        paused,
    }
}

/// The hands' velocity, and the noise the still set-up shows in it.
struct Change<'a> {
    swing: Frames<'a>,
    hz: f32,
    /// The lead and trail hands' joints.
    hands: (usize, usize),
    /// Their smoothing half-width, frames.
    half: usize,
    /// The velocity's noise, m/s.
    noise: f32,
}

impl<'a> Change<'a> {
    /// `swing` at `hz` whose hands are `hands` and whose takeaway is at frame `takeaway`.
    fn new((swing, hz): (Frames<'a>, f32), hands: (usize, usize), takeaway: f32) -> Change<'a> {
        let half = libm::roundf(events::SMOOTHING_S * hz) as usize;
        let mut change = Change {
            swing,
            hz,
            hands,
            half,
            noise: 0.0,
        };
        let still = libm::floorf(takeaway) as usize;
        change.noise = crate::math::sqrt(
            (0..=still)
                .map(|f| change.velocity(f as f32).norm_squared())
                .sum::<f32>()
                / (still + 1) as f32,
        )
        .max(events::STILL_SWAY_M_S);
        change
    }

    /// The hands' midpoint's velocity at frame `x`, m/s.
    fn velocity(&self, x: f32) -> Vec3 {
        let (l, r) = self.hands;
        let at = |x: f32| {
            (smoothed(self.swing, x, l, self.half) + smoothed(self.swing, x, r, self.half)) * 0.5
        };
        (at(x + 1.0) - at(x - 1.0)) * (0.5 * self.hz)
    }

    /// How long the velocity at `x` takes to change by its noise (its vertical part only,
    /// counted against a third of the noise, where `vertical`), back and forth, seconds.
    fn ways(&self, x: f32, vertical: bool) -> [f32; 2] {
        let here = self.velocity(x);
        let reach = libm::ceilf(MAX_EVENT_TIMING_S * self.hz) as usize;
        let (noise, changed): (f32, &dyn Fn(Vec3) -> f32) = match vertical {
            true => (self.noise / crate::math::sqrt(3.0), &|v: Vec3| {
                libm::fabsf(v.y - here.y)
            }),
            false => (self.noise, &|v: Vec3| norm(&(v - here))),
        };
        [-1.0f32, 1.0].map(|way| {
            let mut before = 0.0;
            for k in 1..=reach {
                let now = changed(self.velocity(x + way * k as f32));
                if now >= noise {
                    let w = (noise - before) / (now - before).max(f32::MIN_POSITIVE);
                    return (k as f32 - 1.0 + w) / self.hz;
                }
                before = now;
            }
            MAX_EVENT_TIMING_S
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{Change, MAX_EVENT_TIMING_S};
    use crate::events::STILL_SWAY_M_S;
    use crate::frames::Frames;
    use crate::Vec3;

    /// Two hands at 100 Hz, still for 50 frames, then moving along x at 1 m/s, then 3 m/s.
    fn swing() -> std::vec::Vec<Vec3> {
        let mut x = 0.0;
        let mut out = std::vec::Vec::new();
        for f in 0..200 {
            x += match f {
                0..=50 => 0.0,
                51..=120 => 0.01,
                _ => 0.03,
            };
            out.extend([Vec3::new(x, 1.0, 0.0), Vec3::new(x, 1.0, 0.2)]);
        }
        out
    }

    #[test]
    fn a_still_set_up_sets_the_least_noise_and_a_change_of_speed_is_found_within_reach() {
        let positions = swing();
        let change = Change::new((Frames::metres(&positions, 2), 100.0), (0, 1), 40.0);
        assert_eq!(change.noise, STILL_SWAY_M_S);
        assert!((change.velocity(60.0).x - 1.0).abs() < 1e-3);
        // At frame 60 the smoothed speed left 0 about 7 frames earlier; it changes again 57
        // frames later, beyond the 20 frames of reach.
        let [back, ahead] = change.ways(60.0, false);
        assert!(back > 0.05 && back < 0.08, "{back}");
        assert_eq!(ahead, MAX_EVENT_TIMING_S);
        // The vertical part never changes.
        assert_eq!(change.ways(60.0, true), [MAX_EVENT_TIMING_S; 2]);
    }
}
