//! Swing events: GolfDB's eight, from the hands, the lead arm and the club where it is tracked,
//! and the putting variant (address, top of the backstroke, impact, finish).
//!
//! Trajectories are smoothed with a centred moving average of ±[`SMOOTHING_S`] before any
//! speed or angle is taken, which absorbs 5–10 mm of pose noise. The search runs outwards from
//! the one unmistakable moment of a swing, the fastest hands of the downswing:
//!
//! - **top**: walking back from the fastest hands, the first minimum of hand speed (the club
//!   and hands reverse); where the hands pause there, as still as in the set-up, the pause's
//!   end: the backswing lasts until the downswing starts ([`SwingEvents::arrival`] is the
//!   pause's start);
//! - **lead side**: the backswing takes the hands toward the trail foot;
//! - **address**: walking back from the top, the last frame of the still set-up (the club head,
//!   else the hands, slower than [`STILL_FRACTION`] of their backswing peak for [`STILL_S`]),
//!   so a waggle before it is skipped;
//! - **toe_up** / **mid_follow_through**: the shaft (grip → head) horizontal before the top /
//!   after impact; without a club, the lead arm at [`TOE_UP_ARM_DEG`] / [`FOLLOW_ARM_DEG`];
//! - **mid_backswing** / **mid_downswing**: the lead arm (shoulder → wrist) horizontal;
//! - **impact**: after the top, the club head (else the hands) closest to where it was at
//!   address;
//! - **finish**: the hands' highest point after impact;
//! - the P-system's **P6**, the shaft falling through horizontal between mid-downswing and
//!   impact (without a club, [`SHAFT_DOWN_SHARE`] of the way), and **P9**, the trail arm rising
//!   through horizontal after impact; the other eight positions are the events above
//!   ([`Position`]).
//!
//! Feet that travel more than [`PLANTED_M`] from address to impact make no stroke (someone
//! walking). A stroke whose hands rise less than [`PUTT_RISE_M`] is a putt: top, address and impact as
//! above, and the finish where the forward stroke stops.
//!
//! On the two tour swings at 60 Hz every position lands within two frames of a hand label, with
//! or without the club. Frames are indices into the motion given; nothing is allocated.
//!
//! ```
//! use posecoach_core::events::{Event, SwingEvents};
//! assert_eq!(Event::ALL.len(), 8);
//! assert_eq!(Event::Impact.name(), "impact");
//! ```

use crate::frames::Frames;
use crate::joint::Joint;
use crate::skeleton::Skeleton;
use crate::Vec3;
use limbs::Limbs;
use track::{Hands, Track};

// The stages of `detect`: a typed result each.
mod address;
mod finish;
mod impact;
mod parallels;
mod top;
// What the stages read the motion with.
mod limbs;
mod signal;
#[cfg(test)]
mod synthetic;
mod takeaway;
mod track;

pub use takeaway::{takeaway_against, Takeaway, ONSET_SHARES};

/// Half-width of the smoothing window, in seconds.
pub const SMOOTHING_S: f32 = 0.034;
/// The set-up must be still for this long before the takeaway.
pub const STILL_S: f32 = 0.2;
/// The set-up counts as still while the club head (else the hands) moves slower than this
/// fraction of its fastest speed in the backswing, so a slow amateur takeaway is judged like a
/// tour player's.
pub const STILL_FRACTION: f32 = 0.1;
/// Still hands may seem to move up to this many times as fast as in the quietest stretch of
/// the set-up (pose noise).
pub const NOISE_MARGIN: f32 = 1.2;
/// The least speed a golfer's hands are taken to sway at when still, m/s (a standing body
/// sways at about 1 cm/s): the floor of the noise still hands are judged against.
pub const STILL_SWAY_M_S: f32 = 0.01;
/// Lead-arm elevation at toe-up when no club is tracked (the shaft is horizontal there in the
/// two tour swings of the test data: -54° and -50°).
pub const TOE_UP_ARM_DEG: f32 = -52.0;
/// Without a club, P6 (the shaft horizontal in the downswing) comes this share of the way from
/// P5 to impact: 0.69 on both tour swings of the test data. (A lead-arm level, as for toe-up,
/// would be fragile here: the lead arm is within 3° of its lowest, -71° and -69°.)
pub const SHAFT_DOWN_SHARE: f32 = 0.69;
/// Lead-arm elevation at mid-follow-through when no club is tracked (tour swings: -43°, -52°).
pub const FOLLOW_ARM_DEG: f32 = -45.0;
/// Impact comes within this long after the top (a slow amateur downswing takes half of it):
/// a club set back down at the ball later, to address the next shot, is not an impact.
pub const IMPACT_WITHIN_S: f32 = 1.0;
/// Without a club, a full swing's impact comes this long after the hands are back where they
/// were at address: the hands lead the club head through impact (20.4 and 20.5 ms on the two
/// tour swings, timed against their club heads).
pub const IMPACT_LAG_S: f32 = 0.02;
/// A stroke whose hands rise less than this (metres, over the whole motion) is a putt; a full
/// swing raises them 0.8 m or more.
pub const PUTT_RISE_M: f32 = 0.25;
/// A golfer strikes the ball from where they stand: feet (their midpoint) that move farther
/// than this (metres) from address to impact are someone walking, not a stroke. Planted feet
/// move a few centimetres; one walking step is 0.6 m or more.
pub const PLANTED_M: f32 = 0.4;

/// One of GolfDB's eight swing events, in swing order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[allow(missing_docs)]
pub enum Event {
    Address,
    ToeUp,
    MidBackswing,
    Top,
    MidDownswing,
    Impact,
    MidFollowThrough,
    Finish,
}

impl Event {
    /// How many events a swing has.
    pub const COUNT: usize = 8;

    /// All events in swing order.
    pub const ALL: [Event; Event::COUNT] = [
        Event::Address,
        Event::ToeUp,
        Event::MidBackswing,
        Event::Top,
        Event::MidDownswing,
        Event::Impact,
        Event::MidFollowThrough,
        Event::Finish,
    ];

    /// The snake_case name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Event::Address => "address",
            Event::ToeUp => "toe_up",
            Event::MidBackswing => "mid_backswing",
            Event::Top => "top",
            Event::MidDownswing => "mid_downswing",
            Event::Impact => "impact",
            Event::MidFollowThrough => "mid_follow_through",
            Event::Finish => "finish",
        }
    }

    /// When it is, in a golfer's words: "at the top", "halfway back".
    pub const fn words(self) -> &'static str {
        match self {
            Event::Address => "at address",
            Event::ToeUp => "at toe-up",
            Event::MidBackswing => "halfway back",
            Event::Top => "at the top",
            Event::MidDownswing => "halfway down",
            Event::Impact => "at impact",
            Event::MidFollowThrough => "halfway through",
            Event::Finish => "at the finish",
        }
    }

    /// The P-system position this event is.
    pub const fn position(self) -> Position {
        match self {
            Event::Address => Position::P1,
            Event::ToeUp => Position::P2,
            Event::MidBackswing => Position::P3,
            Event::Top => Position::P4,
            Event::MidDownswing => Position::P5,
            Event::Impact => Position::P7,
            Event::MidFollowThrough => Position::P8,
            Event::Finish => Position::P10,
        }
    }
}

/// One of the P-system's ten positions of a full swing, as coaches name them; eight are
/// GolfDB's events ([`Position::event`]), P6 and P9 are not.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[allow(missing_docs)]
pub enum Position {
    P1,
    P2,
    P3,
    P4,
    P5,
    P6,
    P7,
    P8,
    P9,
    P10,
}

impl Position {
    /// All positions in swing order.
    pub const ALL: [Position; 10] = [
        Position::P1,
        Position::P2,
        Position::P3,
        Position::P4,
        Position::P5,
        Position::P6,
        Position::P7,
        Position::P8,
        Position::P9,
        Position::P10,
    ];

    /// Its name: "P1" to "P10".
    pub const fn name(self) -> &'static str {
        match self {
            Position::P1 => "P1",
            Position::P2 => "P2",
            Position::P3 => "P3",
            Position::P4 => "P4",
            Position::P5 => "P5",
            Position::P6 => "P6",
            Position::P7 => "P7",
            Position::P8 => "P8",
            Position::P9 => "P9",
            Position::P10 => "P10",
        }
    }

    /// The moment it names, in a coach's words.
    pub const fn moment(self) -> &'static str {
        match self {
            Position::P1 => "address",
            Position::P2 => "shaft parallel in the backswing",
            Position::P3 => "lead arm parallel in the backswing",
            Position::P4 => "top",
            Position::P5 => "lead arm parallel in the downswing",
            Position::P6 => "shaft parallel in the downswing",
            Position::P7 => "impact",
            Position::P8 => "shaft parallel after impact",
            Position::P9 => "trail arm parallel in the follow-through",
            Position::P10 => "finish",
        }
    }

    /// The GolfDB event at this position, if it is one.
    pub const fn event(self) -> Option<Event> {
        match self {
            Position::P1 => Some(Event::Address),
            Position::P2 => Some(Event::ToeUp),
            Position::P3 => Some(Event::MidBackswing),
            Position::P4 => Some(Event::Top),
            Position::P5 => Some(Event::MidDownswing),
            Position::P6 | Position::P9 => None,
            Position::P7 => Some(Event::Impact),
            Position::P8 => Some(Event::MidFollowThrough),
            Position::P10 => Some(Event::Finish),
        }
    }
}

impl From<Event> for Position {
    fn from(event: Event) -> Position {
        event.position()
    }
}

/// A side of the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[allow(missing_docs)]
pub enum Side {
    Left,
    Right,
}

/// A full swing or a putt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum SwingKind {
    Full,
    Putt,
}

/// The events of one swing: all eight for a full swing, and the P-system's P6 and P9 where
/// the swing shows them; address, top, impact and finish for a putt. Every accessor takes an
/// [`Event`] or a [`Position`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct SwingEvents {
    /// Full swing or putt.
    pub kind: SwingKind,
    /// The lead side: left for a right-handed golfer.
    pub lead: Side,
    /// Whether the club was used (else hands and arms only).
    pub club: bool,
    /// Per position in [`Position::ALL`] order, `u16::MAX` where the swing has none.
    frames: [u16; 10],
    /// Per position, its time in frames (between frames: see [`SwingEvents::time`]); 0 where
    /// the swing has none.
    times: [f32; 10],
    /// When the hands arrived at the top, frames: the top's time, or the start of a pause
    /// there.
    arrival: f32,
}

const ABSENT: u16 = u16::MAX;

#[cfg(test)]
impl SwingEvents {
    /// A full swing's events led by `lead`, at these times (frames; `None` where it has none),
    /// each position's frame the one its time falls in.
    pub(crate) fn at_times(lead: Side, times: [Option<f32>; 10]) -> SwingEvents {
        SwingEvents {
            kind: SwingKind::Full,
            lead,
            club: false,
            frames: times.map(|t| t.map_or(ABSENT, |t| t as u16)),
            times: times.map(|t| t.unwrap_or(0.0)),
            arrival: times[Position::P4 as usize].unwrap_or(0.0),
        }
    }
}

impl SwingEvents {
    /// Frame of `at` (an event or a position), if this swing has it.
    pub fn frame(&self, at: impl Into<Position>) -> Option<usize> {
        match self.frames[at.into() as usize] {
            ABSENT => None,
            f => Some(f as usize),
        }
    }

    /// Time of `event` in frames from the first, between frames where the motion tells: the
    /// takeaway for [`Event::Address`] (whose frame is the last before it), the crossing or
    /// the turning point of the signal that defines the others (see the module documentation).
    pub fn time(&self, at: impl Into<Position>) -> Option<f32> {
        let at = at.into();
        self.frame(at).map(|_| self.times[at as usize])
    }

    /// These events with the takeaway at `time` (frames, within the backswing): a takeaway
    /// timed against a coach's ([`takeaway_against`]).
    pub fn with_takeaway(&self, time: f32) -> SwingEvents {
        let mut events = *self;
        let a = Position::P1 as usize;
        if events.frames[a] != ABSENT && time.is_finite() {
            let top = f32::from(events.frames[Position::P4 as usize]).min(events.arrival);
            let time = time.clamp(0.0, (top - 1.0).max(0.0));
            events.times[a] = time;
            events.frames[a] = time as u16;
        }
        events
    }

    /// These events with `at` moved by `by` frames (a time read through a biased view
    /// corrected), kept within the positions on either side of it; the hands' arrival at the
    /// top moves with the top.
    pub fn moved(&self, at: impl Into<Position>, by: f32) -> SwingEvents {
        let at = at.into() as usize;
        let mut events = *self;
        if events.frames[at] == ABSENT || !by.is_finite() {
            return events;
        }
        let present = |p: &usize| events.frames[*p] != ABSENT;
        let before = (0..at).rev().find(present).map_or(0.0, |p| events.times[p]);
        let after = (at + 1..events.times.len())
            .find(present)
            .map_or(f32::MAX, |p| events.times[p]);
        let time = (events.times[at] + by).clamp(before, after);
        let moved = time - events.times[at];
        if at == Position::P4 as usize {
            events.arrival = (events.arrival + moved).min(time);
        }
        events.times[at] = time;
        // The frame moves as far (rounded): a position's frame is not always its time's floor.
        let frame = libm::roundf(f32::from(events.frames[at]) + moved);
        events.frames[at] = frame.clamp(0.0, f32::from(ABSENT - 1)) as u16;
        events
    }

    /// These events counted from frame `start` instead of 0: the events of the stretch that
    /// begins there (`start` at most the address; a later one clamps events before it to 0).
    pub fn from_frame(&self, start: usize) -> SwingEvents {
        let start = start.min(usize::from(u16::MAX - 1)) as u16;
        SwingEvents {
            frames: self.frames.map(|f| match f {
                ABSENT => ABSENT,
                f => f.saturating_sub(start),
            }),
            times: self.times.map(|t| (t - f32::from(start)).max(0.0)),
            arrival: (self.arrival - f32::from(start)).max(0.0),
            ..*self
        }
    }

    /// When the hands arrived at the top, frames (between frames): the top's time, or where
    /// they paused there, the pause's start (the top is its end).
    pub fn arrival(&self) -> f32 {
        self.arrival
    }

    /// How long the hands paused at the top, frames (0 without a pause, or without a top).
    pub fn pause(&self) -> f32 {
        self.time(Event::Top)
            .map_or(0.0, |top| (top - self.arrival).max(0.0))
    }

    /// Frame of the address (every swing has one).
    pub fn address(&self) -> usize {
        self.frames[Position::P1 as usize] as usize
    }

    /// Frame of the top (of the backswing or backstroke).
    pub fn top(&self) -> usize {
        self.frames[Position::P4 as usize] as usize
    }

    /// Frame of impact.
    pub fn impact(&self) -> usize {
        self.frames[Position::P7 as usize] as usize
    }

    /// Frame of the finish.
    pub fn finish(&self) -> usize {
        self.frames[Position::P10 as usize] as usize
    }

    /// The events this swing has, with their frames, in swing order.
    pub fn iter(&self) -> impl Iterator<Item = (Event, usize)> + '_ {
        Event::ALL
            .into_iter()
            .filter_map(|e| self.frame(e).map(|f| (e, f)))
    }

    /// The positions this swing has, with their frames, in swing order.
    pub fn positions(&self) -> impl Iterator<Item = (Position, usize)> + '_ {
        Position::ALL
            .into_iter()
            .filter_map(|p| self.frame(p).map(|f| (p, f)))
    }
}

// A report keeps its deviations event by event.
const _: () =
    assert!(crate::config::MAX_DEVIATIONS == Event::COUNT * crate::config::DEVIATIONS_PER_EVENT);

/// Why events could not be found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EventError {
    /// The skeleton lacks a joint the detector needs.
    MissingJoint(Joint),
    /// `positions` is not whole frames of the skeleton's joints, or too few frames (under a second) or
    /// more than `u16::MAX`.
    Length,
    /// The rate is not a positive finite number.
    Rate,
    /// A position is NaN or infinite.
    NonFinite,
    /// No complete swing (set-up, backswing, top, downswing, impact, follow-through) was found.
    NoSwing,
}

impl core::fmt::Display for EventError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EventError::MissingJoint(j) => write!(f, "swing events need the joint `{j}`"),
            EventError::Length => f.write_str("the motion is not a whole number of frames, or too short or long for a swing"),
            EventError::Rate => f.write_str("the frame rate must be positive"),
            EventError::NonFinite => f.write_str("a joint position is not a finite number"),
            EventError::NoSwing => f.write_str("no complete swing found: set-up, backswing, top, downswing, impact and follow-through"),
        }
    }
}

impl core::error::Error for EventError {}

/// One event found: its frame, and its time in frames from the first (between frames).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Moment {
    frame: usize,
    time: f32,
}

impl Moment {
    /// The event at `frame`, at `time`.
    const fn new(frame: usize, time: f32) -> Moment {
        Moment { frame, time }
    }
}

impl SwingEvents {
    /// A swing of `kind` led by `lead` with no event yet, its hands arriving at the top at
    /// `arrival`.
    fn new(kind: SwingKind, lead: Side, club: bool, arrival: f32) -> SwingEvents {
        SwingEvents {
            kind,
            lead,
            club,
            frames: [ABSENT; 10],
            times: [0.0; 10],
            arrival,
        }
    }

    /// Puts `position` at `frame`, at `time`.
    fn put(&mut self, position: Position, frame: u16, time: f32) {
        self.frames[position as usize] = frame;
        self.times[position as usize] = time;
    }

    /// A putt's events from its address, top, impact and finish, in that order.
    fn putt(lead: Side, club: bool, four: [Moment; 4], arrival: f32) -> SwingEvents {
        let mut events = SwingEvents::new(SwingKind::Putt, lead, club, arrival);
        let putt = [Event::Address, Event::Top, Event::Impact, Event::Finish];
        for (event, at) in putt.into_iter().zip(four) {
            events.put(event.position(), at.frame as u16, at.time);
        }
        events
    }

    /// A full swing's events from its eight in swing order ([`Event::ALL`]), and P6 and P9
    /// where they were found and fall strictly between their neighbours.
    ///
    /// # Errors
    /// [`EventError::NoSwing`] where the eight are not in swing order.
    fn full(
        lead: Side,
        club: bool,
        eight: [Moment; Event::COUNT],
        arrival: f32,
        p6_p9: [Option<Moment>; 2],
    ) -> Result<SwingEvents, EventError> {
        let mut frames = eight.map(|at| at.frame as u16);
        if frames.windows(2).any(|w| w[1] <= w[0]) {
            return Err(EventError::NoSwing);
        }
        // Impact's frame is the one nearest its time (later than the hands' return by the lag),
        // between its neighbours.
        let i = Event::Impact as usize;
        frames[i] = (libm::roundf(eight[i].time) as u16)
            .clamp(frames[i - 1] + 1, frames[i + 1] - 1)
            .max(frames[i]);
        let mut events = SwingEvents::new(SwingKind::Full, lead, club, arrival);
        for (k, event) in Event::ALL.into_iter().enumerate() {
            events.put(event.position(), frames[k], eight[k].time);
        }
        for (position, found) in [Position::P6, Position::P9].into_iter().zip(p6_p9) {
            let i = position as usize;
            if let Some(at) = found {
                let frame = at.frame as u16;
                if events.frames[i - 1] < frame && frame < events.frames[i + 1] {
                    events.put(position, frame, at.time);
                }
            }
        }
        Ok(events)
    }
}

/// [`detect`]'s checks of the rate and the motion, before any joint is looked for.
///
/// # Errors
/// [`EventError::Rate`], [`EventError::Length`] or [`EventError::NonFinite`], as [`detect`]
/// documents them.
fn check(skeleton: &Skeleton, positions: Frames<'_>, rate_hz: f32) -> Result<(), EventError> {
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(EventError::Rate);
    }
    let frames = positions.len();
    if !positions.is_whole()
        || positions.joints() != skeleton.len()
        || (frames as f32) < rate_hz
        || frames > u16::MAX as usize
    {
        return Err(EventError::Length);
    }
    if !positions.is_finite() {
        return Err(EventError::NonFinite);
    }
    Ok(())
}

/// Finds the events of the one swing (eight) or putt (four) in `positions` (frames × skeleton joints,
/// metres, +Y up) recorded at `rate_hz`.
///
/// Needs both shoulders and wrists (or hands) and both feet; uses `club_grip` and `club_head`
/// when the skeleton has them.
///
/// # Errors
/// [`EventError`] for a skeleton without the joints above, a malformed, too short or
/// non-finite motion, or a motion without a complete swing.
pub fn detect(
    skeleton: &Skeleton,
    positions: Frames<'_>,
    rate_hz: f32,
) -> Result<SwingEvents, EventError> {
    check(skeleton, positions, rate_hz)?;
    let limbs = Limbs::find(skeleton)?;
    let track = &Track::new(positions, rate_hz);
    let hands = &Hands::new(track, limbs.wrists);
    let turn = top::turn(hands)?;
    // The set-up's stillness and impact are read from the club head where it is tracked, else
    // from the hands.
    let probe: &dyn Fn(usize) -> Vec3 = match limbs.club {
        Some((_, head)) => &move |t| track.at(head, t),
        None => &|t| hands.at(t),
    };
    let address = address::find(hands, probe, turn)?;
    let lead = limbs.lead(hands, address.at.frame, turn.frame);
    let top = turn.top(hands, address.at.frame, address.quietest);
    let impact = impact::find(track, &limbs, probe, &address, top.at.frame, turn.putt)?;
    let club = limbs.club.is_some();
    if turn.putt {
        let finish = finish::putt(hands, impact.frame)?;
        let four = [address.at, top.at, impact, finish];
        return Ok(SwingEvents::putt(lead, club, four, top.arrival));
    }
    let arms = limbs.arms(track, lead);
    let p = parallels::find(&arms, limbs.club, address.at.frame, top.at.frame, impact)?;
    let finish = finish::full(hands, p.follow.frame);
    let trail_up = parallels::trail_up(&arms, impact.frame, finish.frame);
    let eight = [
        address.at,
        p.toe_up,
        p.mid_backswing,
        top.at,
        p.mid_downswing,
        impact,
        p.follow,
        finish,
    ];
    SwingEvents::full(lead, club, eight, top.arrival, [p.shaft_down, trail_up])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;
    use std::vec::Vec;

    const RATE_HZ: f32 = 60.0;

    /// [`super::detect`] of positions in metres.
    fn detect(skeleton: &Skeleton, positions: &[Vec3], hz: f32) -> Result<SwingEvents, EventError> {
        super::detect(skeleton, Frames::metres(positions, skeleton.len()), hz)
    }

    fn standing(skeleton: &Skeleton, frames: usize) -> Vec<Vec3> {
        let mut rest = std::vec![Vec3::zeros(); skeleton.len()];
        skeleton.rest_positions(&mut rest);
        rest.iter()
            .cycle()
            .take(frames * skeleton.len())
            .copied()
            .collect()
    }

    #[test]
    fn the_eight_events_are_eight_of_the_ten_positions() {
        for event in Event::ALL {
            assert_eq!(event.position().event(), Some(event));
        }
        let named: std::vec::Vec<_> = Position::ALL.iter().filter_map(|p| p.event()).collect();
        assert_eq!(named, Event::ALL);
        assert_eq!(Position::P6.event(), None);
        assert_eq!(Position::P9.event(), None);
    }

    /// Events at `frames`, each a quarter frame later.
    fn at(frames: [usize; 8]) -> [Moment; 8] {
        frames.map(|f| Moment::new(f, f as f32 + 0.25))
    }

    #[test]
    fn a_moved_event_keeps_its_frame_in_step_and_stays_between_its_neighbours() {
        let eight = at([10, 20, 30, 40, 50, 60, 70, 80]);
        let events = SwingEvents::full(Side::Left, false, eight, 38.5, [None, None]).unwrap();
        // Impact 0.4 frame earlier: its time moves, its frame rounds with it.
        let moved = events.moved(Event::Impact, -0.4);
        assert_eq!(moved.time(Event::Impact), Some(59.85));
        assert_eq!(moved.frame(Event::Impact), Some(60));
        assert_eq!(
            moved.moved(Event::Impact, -0.6).frame(Event::Impact),
            Some(59)
        );
        // Never past the positions either side; nothing moves by nothing.
        assert_eq!(
            events.moved(Event::Impact, -30.0).time(Event::Impact),
            Some(50.25)
        );
        assert_eq!(events.moved(Event::Impact, 0.0), events);
        // The top carries the hands' arrival with it.
        let top = events.moved(Event::Top, 0.5);
        assert_eq!((top.time(Event::Top), top.arrival()), (Some(40.75), 39.0));
    }

    #[test]
    fn a_full_swing_keeps_its_events_in_swing_order() {
        let eight = at([10, 20, 30, 40, 50, 60, 70, 80]);
        let full = |eight, p6_p9| SwingEvents::full(Side::Left, true, eight, 38.5, p6_p9);
        let both = [Some(Moment::new(55, 55.5)), Some(Moment::new(75, 75.0))];
        let events = full(eight, both).unwrap();
        assert_eq!(events.kind, SwingKind::Full);
        let frames: Vec<_> = events.positions().map(|(_, f)| f).collect();
        assert_eq!(frames, [10, 20, 30, 40, 50, 55, 60, 70, 75, 80]);
        assert_eq!(events.time(Event::Finish), Some(80.25));
        assert_eq!(events.time(Position::P6), Some(55.5));
        assert_eq!((events.arrival(), events.pause()), (38.5, 1.75));
        // Impact's frame is the one nearest its time, short of its neighbours.
        for (time, frame) in [(62.6, 63), (75.0, 69), (58.0, 60)] {
            let mut late = eight;
            late[Event::Impact as usize].time = time;
            assert_eq!(full(late, both).unwrap().impact(), frame);
        }
        // P6 and P9 only strictly between their neighbours.
        let outside = [Some(Moment::new(60, 60.0)), Some(Moment::new(70, 70.0))];
        let events = full(eight, outside).unwrap();
        assert_eq!(
            (events.frame(Position::P6), events.frame(Position::P9)),
            (None, None)
        );
        let mut swapped = eight;
        swapped.swap(1, 2);
        assert_eq!(full(swapped, both), Err(EventError::NoSwing));
    }

    #[test]
    fn a_putt_has_address_top_impact_and_finish() {
        let [address, top, impact, finish, ..] = at([10, 30, 40, 60, 0, 0, 0, 0]);
        let events = SwingEvents::putt(Side::Right, false, [address, top, impact, finish], 29.0);
        assert_eq!(
            (events.kind, events.lead, events.club),
            (SwingKind::Putt, Side::Right, false)
        );
        let found: Vec<_> = events.iter().collect();
        let expected = [
            (Event::Address, 10),
            (Event::Top, 30),
            (Event::Impact, 40),
            (Event::Finish, 60),
        ];
        assert_eq!(found, expected);
        assert_eq!(events.time(Event::Top), Some(30.25));
        assert_eq!(events.positions().count(), 4);
    }

    /// The rate of [`arbitrary_motion_never_panics`]'s motion and its frames: one to two
    /// seconds at 60 Hz, under Miri (which interprets each frame in seconds) one second at
    /// 30 Hz, a phone's rate (the shortest motion [`detect`] reads).
    const ARBITRARY_HZ: f32 = if cfg!(miri) { 30.0 } else { RATE_HZ };
    const ARBITRARY_FRAMES: core::ops::Range<usize> = if cfg!(miri) { 30..31 } else { 60..120 };

    proptest::proptest! {
        // One case under Miri, which interprets each in minutes.
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(if cfg!(miri) { 1 } else { 64 }))]
        #[test]
        fn arbitrary_motion_never_panics(
            values in proptest::collection::vec(-3.0f32..3.0, 17 * 3 * ARBITRARY_FRAMES.start..17 * 3 * ARBITRARY_FRAMES.end),
        ) {
            let h36m = Skeleton::standard(Format::H36m17).unwrap();
            let frames = values.len() / (17 * 3);
            let positions: Vec<Vec3> = values[..frames * 17 * 3].chunks_exact(3).map(Vec3::from_column_slice).collect();
            if let Ok(events) = detect(&h36m, &positions, ARBITRARY_HZ) {
                let f: Vec<usize> = events.iter().map(|(_, f)| f).collect();
                proptest::prop_assert!(f.windows(2).all(|w| w[0] < w[1]) && events.finish() < frames);
            }
        }
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let h36m = Skeleton::standard(Format::H36m17).unwrap();
        // Under Miri, which takes seconds over each frame, the second that detect needs at least.
        let still = standing(&h36m, if cfg!(miri) { 60 } else { 90 });
        assert_eq!(detect(&h36m, &still, 0.0), Err(EventError::Rate));
        assert_eq!(detect(&h36m, &still, f32::NAN), Err(EventError::Rate));
        assert_eq!(
            detect(&h36m, &still[..still.len() - 1], RATE_HZ),
            Err(EventError::Length)
        );
        assert_eq!(
            detect(&h36m, &still[..17 * 30], RATE_HZ),
            Err(EventError::Length)
        );
        assert_eq!(detect(&h36m, &still, RATE_HZ), Err(EventError::NoSwing));
        let coco = Skeleton::standard(Format::Coco17).unwrap();
        let mut nan = standing(&coco, 90);
        nan[40].x = f32::NAN;
        assert_eq!(detect(&coco, &nan, RATE_HZ), Err(EventError::NonFinite));
        let joints = [
            Joint::Pelvis,
            Joint::LeftAnkle,
            Joint::RightAnkle,
            Joint::Head,
            Joint::LeftWrist,
            Joint::RightWrist,
        ];
        let rest: Vec<Vec3> = joints.iter().map(|&j| crate::format::t_pose(j)).collect();
        let armless = Skeleton::canonical(&joints, &rest).unwrap();
        assert_eq!(
            detect(&armless, &standing(&armless, 90), RATE_HZ),
            Err(EventError::MissingJoint(Joint::LeftShoulder))
        );
    }
}
