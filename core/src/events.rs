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
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::Vec3;
use core::cell::Cell;

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

/// Frames of a speed [`Memo`] keeps (1 KiB of stack); later frames are computed each time.
const MEMO_FRAMES: usize = crate::config::MAX_SWING_FRAMES;

/// A function of the frame, each of the first [`MEMO_FRAMES`] values computed once: the
/// searches ask for the same speeds many times (a still stretch is a maximum over a window at
/// every frame), and each speed is four smoothed positions.
struct Memo<F> {
    f: F,
    /// NaN until computed (speeds of finite positions are finite).
    values: [Cell<f32>; MEMO_FRAMES],
}

impl<F: Fn(usize) -> f32> Memo<F> {
    fn new(f: F) -> Memo<F> {
        Memo {
            f,
            values: core::array::from_fn(|_| Cell::new(f32::NAN)),
        }
    }

    fn get(&self, t: usize) -> f32 {
        let Some(cell) = self.values.get(t) else {
            return (self.f)(t);
        };
        if cell.get().is_nan() {
            cell.set((self.f)(t));
        }
        cell.get()
    }
}

/// Smoothed trajectories of one motion.
struct Track<'a> {
    positions: Frames<'a>,
    frames: usize,
    half: usize,
    rate: f32,
}

impl<'a> Track<'a> {
    /// `positions` at `rate` frames per second, smoothed over ±[`SMOOTHING_S`].
    fn new(positions: Frames<'a>, rate: f32) -> Track<'a> {
        Track {
            positions,
            frames: positions.len(),
            half: libm::roundf(SMOOTHING_S * rate) as usize,
            rate,
        }
    }

    /// Joint `j` at frame `t`, averaged over `t ± half` (clamped to the motion).
    fn at(&self, j: usize, t: usize) -> Vec3 {
        let (lo, hi) = (
            t.saturating_sub(self.half),
            (t + self.half).min(self.frames - 1),
        );
        let sum = (lo..=hi).fold(Vec3::zeros(), |s, f| s + self.positions.at(f, j));
        sum / (hi - lo + 1) as f32
    }

    /// Speed of `point` at `t` in metres per second, by a central difference over ±half.
    fn speed(&self, point: impl Fn(usize) -> Vec3, t: usize) -> f32 {
        let (lo, hi) = (
            t.saturating_sub(self.half.max(1)),
            (t + self.half.max(1)).min(self.frames - 1),
        );
        norm(&(point(hi) - point(lo))) * self.rate / (hi - lo).max(1) as f32
    }
}

/// Elevation of `v` above the horizontal plane, degrees.
fn elevation(v: Vec3) -> f32 {
    libm::atan2f(v.y, libm::hypotf(v.x, v.z)).to_degrees()
}

/// The first frame in `range` (walking in its direction) where `f` crosses `level` upwards
/// (`rising`) or downwards, whichever of the two frames around the crossing is nearer the level.
fn crossing(
    range: impl Iterator<Item = usize>,
    f: impl Fn(usize) -> f32,
    level: f32,
    rising: bool,
) -> Option<usize> {
    let mut previous: Option<(usize, f32)> = None;
    for t in range {
        let v = f(t) - level;
        if let Some((p, pv)) = previous {
            let (before, after) = if p < t { (pv, v) } else { (v, pv) };
            let crossed = if rising {
                before < 0.0 && after >= 0.0
            } else {
                before > 0.0 && after <= 0.0
            };
            if crossed {
                return Some(if v.abs() < pv.abs() { t } else { p });
            }
        }
        previous = Some((t, v));
    }
    None
}

/// Where a parabola through `(−1, a)`, `(0, b)`, `(1, c)` turns, in −0.5..=0.5 (0 where the
/// three are on a line): a turning point found at a frame, placed between frames.
fn vertex(a: f32, b: f32, c: f32) -> f32 {
    let curve = a - 2.0 * b + c;
    if curve.abs() > f32::EPSILON {
        (0.5 * (a - c) / curve).clamp(-0.5, 0.5)
    } else {
        0.0
    }
}

/// Where `f` crosses `level` between frames `a` and `b` (linear), as a fractional frame.
fn between(f: impl Fn(usize) -> f32, level: f32, a: usize, b: usize) -> f32 {
    let (fa, fb) = (f(a), f(b));
    let w = if fb != fa {
        ((level - fa) / (fb - fa)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a as f32 + (b as f32 - a as f32) * w
}

/// The hands' progress toward the top is fitted between these shares of it (well above pose
/// noise, early enough to be a start from rest).
pub const ONSET_SHARES: (f32, f32) = (0.08, 0.3);

/// The takeaway, in frames: when the `hands` start back from `home` (their set-up position)
/// toward where they are at `top`, searching from frame `from`. Starting from rest with a
/// smooth push, the hands' progress along their first direction grows as the cube of the time
/// since the takeaway (the start of a minimum-jerk reach; 3.1 to 3.2 on the tour swings), so
/// its cube root is fitted with a line between [`ONSET_SHARES`] of the way to the top and
/// extrapolated back to zero. `None` without enough frames in that stretch.
fn takeaway(hands: impl Fn(usize) -> Vec3, home: Vec3, from: usize, top: usize) -> Option<f32> {
    let reach = norm(&(hands(top) - home));
    if reach <= 0.0 {
        return None;
    }
    let (lo, hi) = (ONSET_SHARES.0 * reach, ONSET_SHARES.1 * reach);
    let last = (from..=top).find(|&t| norm(&(hands(t) - home)) >= hi)?;
    let way = (hands(last) - home) / norm(&(hands(last) - home));
    let progress = |t: usize| (hands(t) - home).dot(&way);
    let mut first = last;
    while first > from && progress(first - 1) >= lo {
        first -= 1;
    }
    if last - first < 1 {
        return None;
    }
    // Pose noise of σ in the progress p is σ / (3 p^(2/3)) in its cube root: each frame is
    // weighted by p^(4/3), the inverse of that variance.
    let (mut sw, mut st, mut sy, mut stt, mut sty) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for t in first..=last {
        let (x, y) = ((t - first) as f32, libm::cbrtf(progress(t).max(0.0)));
        let w = y * y * y * y;
        sw += w;
        st += w * x;
        sy += w * y;
        stt += w * x * x;
        sty += w * x * y;
    }
    let slope = (sw * sty - st * sy) / (sw * stt - st * st);
    if !(slope.is_finite() && slope > 0.0) {
        return None;
    }
    let intercept = (sy - slope * st) / sw;
    Some(first as f32 - intercept / slope)
}

/// The shares of the way from the set-up to the top at which [`takeaway_against`] compares
/// the hands' progress: the 13 from 0.1 to 0.7 in steps of 0.05.
const PROGRESS_SHARES: (f32, f32, usize) = (0.1, 0.05, 13);

/// A student's takeaway timed against a coach's backswing ([`takeaway_against`]), with what
/// moves it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Takeaway {
    /// The takeaway, frames (between frames).
    pub time: f32,
    /// How much earlier it comes for each frame later the hands' arrival at the top is found
    /// (the top, where they do not pause there): without a pause the backswing's length moves
    /// by `1 + top_gain` times the top's error.
    pub top_gain: f32,
    /// Its standard deviation from the crossings' scatter about the fit alone, frames.
    pub spread: f32,
}

/// The student's takeaway (frames, between frames) timed against the coach's: the arms'
/// (wrists and elbows) progress along the line from their set-up to their top pose passes 10 %
/// to 70 % of the way at moments that, were the student's backswing the coach's run at its own
/// pace, would lie at the same shares of the time from the takeaway to the hands' arrival at
/// the top ([`SwingEvents::arrival`]: a pause there is no part of the pace); the takeaway that fits
/// them best (least squares, each crossing weighted by how sharply the progress passes it) is
/// the student's. It uses half a second of the backswing where
/// [`detect`] uses a fifth, so pose noise moves it less. `None` when a swing lacks the joints
/// (or is not read in the skeleton's), the events or a crossing.
pub fn takeaway_against(
    skeleton: &Skeleton,
    student: Frames<'_>,
    student_events: &SwingEvents,
    student_hz: f32,
    coach: Frames<'_>,
    coach_events: &SwingEvents,
    coach_hz: f32,
) -> Option<Takeaway> {
    // The arms: wrists (or hands) and elbows, whose pose errors are independent.
    let arms = [
        skeleton.find(&[Joint::LeftWrist, Joint::LeftHand])?,
        skeleton.find(&[Joint::RightWrist, Joint::RightHand])?,
        skeleton.index_of(Joint::LeftElbow)?,
        skeleton.index_of(Joint::RightElbow)?,
    ];
    if student.joints() != skeleton.len() || coach.joints() != skeleton.len() {
        return None;
    }
    let (s, c) = (Track::new(student, student_hz), Track::new(coach, coach_hz));
    if s.frames == 0 || c.frames == 0 {
        return None;
    }
    type Arms = [Vec3; 4];
    let pose = |t: &Track<'_>, x: f32| -> Arms {
        let f = (x.max(0.0) as usize).min(t.frames - 1);
        let g = (f + 1).min(t.frames - 1);
        let w = (x - f as f32).clamp(0.0, 1.0);
        if w == 0.0 {
            // At a frame: the next one's smoothed read would be weighed by zero.
            return arms.map(|k| t.at(k, f));
        }
        arms.map(|k| t.at(k, f) * (1.0 - w) + t.at(k, g) * w)
    };
    // Each backswing runs from the takeaway to the hands' arrival at the top (a pause there
    // is no part of the coach's pace).
    let (c0, c_top) = (
        coach_events.time(Event::Address)?,
        coach_events
            .time(Event::Top)
            .map(|_| coach_events.arrival())?,
    );
    let (s0, s_top) = (
        student_events.time(Event::Address)?,
        student_events
            .time(Event::Top)
            .map(|_| student_events.arrival())?,
    );
    if c_top <= c0 || s_top <= s0 {
        return None;
    }
    // Progress along the set-up → top line of the arms' pose, 0 at the set-up and 1 at the
    // top.
    let progress = |t: &Track<'_>, home: &Arms, top: &Arms, f: usize| {
        let now = pose(t, f as f32);
        let (mut along, mut length) = (0.0f32, 0.0f32);
        for i in 0..4 {
            let line = top[i] - home[i];
            along += (now[i] - home[i]).dot(&line);
            length += line.norm_squared();
        }
        along / length
    };
    // Each swing's set-up: the arms' mean over the still stretch before its own takeaway.
    let home = |t: &Track<'_>, taken: f32| {
        let still = (libm::roundf(STILL_S * t.rate) as usize).max(1);
        let end = (taken as usize).saturating_sub(1);
        let start = end.saturating_sub(still);
        let mut mean = [Vec3::zeros(); 4];
        for f in start..=end {
            for (m, p) in mean.iter_mut().zip(pose(t, f as f32)) {
                *m += p / (end - start + 1) as f32;
            }
        }
        (start, mean)
    };
    let ((c_start, c_home), (start, s_home)) = (home(&c, c0), home(&s, s0));
    let c_line = (c_home, pose(&c, c_top));
    let s_line = (s_home, pose(&s, s_top));
    // The first moment (frames, between frames) the progress passes `share` in `from..=to`.
    // The moments (frames, between frames) the progress first passes each share, in one walk
    // from `from` to `to`; `None` for a share it never reaches.
    const SHARES: usize = PROGRESS_SHARES.2;
    let passes = |t: &Track<'_>, line: &(Arms, Arms), from: usize, to: usize| {
        let mut at = [None; SHARES];
        let mut next = 0;
        let mut before = progress(t, &line.0, &line.1, from);
        for f in from..to {
            let after = progress(t, &line.0, &line.1, f + 1);
            while next < SHARES {
                let share = PROGRESS_SHARES.0 + PROGRESS_SHARES.1 * next as f32;
                if after < share {
                    break;
                }
                let w = if before >= share || after <= before {
                    0.0
                } else {
                    (share - before) / (after - before)
                };
                at[next] = Some(f as f32 + w);
                next += 1;
            }
            before = after;
        }
        at
    };
    let (c_at, s_at) = (
        passes(&c, &c_line, c_start, c_top as usize),
        passes(&s, &s_line, start, s_top as usize),
    );
    let c_span = c_top - c0;
    // Per crossing: the coach's share f of its backswing's time there, the weight, and the
    // student's moment.
    let mut points = [(0.0f32, 0.0f32, 0.0f32); SHARES];
    let mut count = 0;
    for (c_at, s_at) in c_at.into_iter().zip(s_at) {
        let (c_at, s_at) = (c_at?, s_at?);
        // s_at = t0 + f (s_top − t0), f the coach's share of its backswing's time there. Pose
        // noise moves a crossing in time inversely to how fast the progress goes through it
        // (the coach's pace there, per share of the backswing): each is weighted so.
        let f = ((c_at - c0) / c_span).clamp(0.0, 0.95);
        let k = c_at as usize;
        let pace = (progress(&c, &c_line.0, &c_line.1, (k + 1).min(c.frames - 1))
            - progress(&c, &c_line.0, &c_line.1, k.saturating_sub(1)))
            * 0.5
            * c_span;
        points[count] = (f, pace * pace, s_at);
        count += 1;
    }
    let points = &points[..count];
    let (num, den, gain) =
        points
            .iter()
            .fold((0.0f32, 0.0f32, 0.0f32), |(n, d, g), &(f, w, s_at)| {
                (
                    n + w * (1.0 - f) * (s_at - f * s_top),
                    d + w * (1.0 - f) * (1.0 - f),
                    g + w * (1.0 - f) * f,
                )
            });
    // (A NaN sum gives no takeaway.)
    let time = Some(num / den).filter(|_| den > 0.0)?;
    // The crossings' own scatter about the fit, carried into the takeaway (a sandwich
    // estimate, with n / (n − 1) for the fitted parameter).
    let scatter = points
        .iter()
        .map(|&(f, w, s_at)| {
            let r = s_at - (time * (1.0 - f) + f * s_top);
            let lever = w * (1.0 - f);
            lever * lever * r * r
        })
        .sum::<f32>()
        / (den * den)
        * count as f32
        / count.saturating_sub(1).max(1) as f32;
    Some(Takeaway {
        time,
        top_gain: gain / den,
        spread: libm::sqrtf(scatter),
    })
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
    let need = |j: Joint| skeleton.index_of(j).ok_or(EventError::MissingJoint(j));
    let either = |a: Joint, b: Joint| skeleton.find(&[a, b]).ok_or(EventError::MissingJoint(b));
    let wrists = [
        either(Joint::LeftWrist, Joint::LeftHand)?,
        either(Joint::RightWrist, Joint::RightHand)?,
    ];
    let shoulders = [need(Joint::LeftShoulder)?, need(Joint::RightShoulder)?];
    let feet = [
        either(Joint::LeftAnkle, Joint::LeftToe)?,
        either(Joint::RightAnkle, Joint::RightToe)?,
    ];
    let club = skeleton
        .index_of(Joint::ClubGrip)
        .zip(skeleton.index_of(Joint::ClubHead));
    let track = &Track::new(positions, rate_hz);
    let hands = |t: usize| (track.at(wrists[0], t) + track.at(wrists[1], t)) * 0.5;
    let hand_speeds = Memo::new(|t| track.speed(hands, t));
    let hand_speed = |t: usize| hand_speeds.get(t);

    // The fastest hands of the swing, then back to the first minimum of hand speed where the
    // hands are high (in the upper half of their range): the top. A low minimum (the dip at
    // impact, when the fastest hands come in the follow-through) is passed over.
    let (low, high) = (0..frames).fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), t| {
        let y = hands(t).y;
        (lo.min(y), hi.max(y))
    });
    let fastest = (0..frames)
        .max_by(|&a, &b| hand_speed(a).total_cmp(&hand_speed(b)))
        .ok_or(EventError::NoSwing)?;
    let mut top = fastest;
    loop {
        while top > 0 && hand_speed(top - 1) <= hand_speed(top) {
            top -= 1;
        }
        let putt = high - low < PUTT_RISE_M;
        if top == 0 || putt || hands(top).y > 0.5 * (low + high) {
            break;
        }
        // Step off the low minimum (every pass moves back at least one frame), then climb.
        top -= 1;
        while top > 0 && hand_speed(top - 1) >= hand_speed(top) {
            top -= 1;
        }
    }
    if top == 0 {
        return Err(EventError::NoSwing);
    }

    // Address: the last frame of a still set-up before the top.
    let probe: &dyn Fn(usize) -> Vec3 = match club {
        Some((_, head)) => &move |t| track.at(head, t),
        None => &hands,
    };
    let probe_speeds = Memo::new(|t| track.speed(probe, t));
    let peak = (0..top).map(|t| probe_speeds.get(t)).fold(0.0, f32::max);
    let window = (libm::roundf(STILL_S * rate_hz) as usize).max(1);
    // The fastest the hands go in a stretch of `window` frames ending at `t`.
    let stir = |t: usize| {
        (t.saturating_sub(window)..=t)
            .map(|s| probe_speeds.get(s))
            .fold(0.0, f32::max)
    };
    // Pose noise makes still hands seem to move: the threshold is at least NOISE_MARGIN times
    // the quietest stretch before the top.
    let quietest = (0..top).map(stir).fold(f32::INFINITY, f32::min);
    let still = (STILL_FRACTION * peak).max(NOISE_MARGIN * quietest);
    // A still stretch that runs into the start of the recording counts as long enough.
    let settled = (0..top)
        .rev()
        .find(|&t| stir(t) < still)
        .ok_or(EventError::NoSwing)?;
    // The takeaway: from where the hands rested in that stretch, the start of their way back.
    let rest = settled.saturating_sub(window);
    let rested =
        (rest..=settled).fold(Vec3::zeros(), |s, t| s + hands(t)) / (settled - rest + 1) as f32;
    let putt = high - low < PUTT_RISE_M;
    // A putt's stroke moves the hands a few centimetres: too little to fit its start, so its
    // address is the end of the still set-up.
    let taken = match putt {
        true => settled as f32,
        false => takeaway(hands, rested, rest, top)
            .map_or(settled as f32, |t| t.clamp(0.0, (top - 1) as f32)),
    };
    let address = taken as usize;

    // The backswing takes the hands toward the trail foot.
    let across = track.at(feet[1], address) - track.at(feet[0], address);
    let lead = if (hands(top) - hands(address)).dot(&across) > 0.0 {
        Side::Left
    } else {
        Side::Right
    };
    let (lead_shoulder, lead_wrist) = match lead {
        Side::Left => (shoulders[0], wrists[0]),
        Side::Right => (shoulders[1], wrists[1]),
    };
    let arm = |t: usize| elevation(track.at(lead_wrist, t) - track.at(lead_shoulder, t));
    let (trail_shoulder, trail_wrist) = match lead {
        Side::Left => (shoulders[1], wrists[1]),
        Side::Right => (shoulders[0], wrists[0]),
    };
    let trail_arm = |t: usize| elevation(track.at(trail_wrist, t) - track.at(trail_shoulder, t));

    // A pause at the top: the hands as still as the set-up's quietest stretch (the club
    // head's where it is tracked, else the hands'; at least a standing body's sway) for longer
    // than a speed's smoothing reaches, where that stillness can be told from the hands'
    // turn (under STILL_FRACTION of their fastest in the backswing, as the set-up's is). The
    // backswing lasts until the downswing starts, so the top is the pause's end; the hands
    // arrived at its start. A speed reads positions smoothed over ±half frames, `half.max(1)`
    // frames either side, so still speeds run that far inside either end of the still frames.
    let quiet = (NOISE_MARGIN * quietest).max(STILL_SWAY_M_S);
    let backswing = (address..top).map(hand_speed).fold(0.0, f32::max);
    let inset = track.half + track.half.max(1);
    let (mut begin, mut end) = (top, top);
    if quiet < STILL_FRACTION * backswing && hand_speed(top) <= quiet {
        while begin > address + 1 && hand_speed(begin - 1) <= quiet {
            begin -= 1;
        }
        while end + 2 < frames && hand_speed(end + 1) <= quiet {
            end += 1;
        }
    }
    let pause = (end - begin >= inset).then(|| {
        (
            (begin.saturating_sub(inset)).max(address + 1),
            (end + inset).min(frames - 2),
        )
    });
    let top = pause.map_or(top, |(_, end)| end);

    // Impact: after the top, where the club head (or the hands) comes closest to where it was
    // at address.
    let home = match club {
        Some(_) => probe(address),
        None => rested,
    };
    let away = |t: usize| norm(&(probe(t) - home));
    let reach = top + 1 + (libm::roundf(IMPACT_WITHIN_S * rate_hz) as usize).min(frames);
    let impact = (top + 1..reach.min(frames))
        .min_by(|&a, &b| away(a).total_cmp(&away(b)))
        .filter(|&t| t + 1 < frames)
        .ok_or(EventError::NoSwing)?;
    let stance = |t: usize| (track.at(feet[0], t) + track.at(feet[1], t)) * 0.5;
    if (address..=impact).any(|t| norm(&(stance(t) - stance(address))) > PLANTED_M) {
        return Err(EventError::NoSwing);
    }
    // Turning points between frames: the slowest hands at the top, the nearest at impact.
    let turning = |f: &dyn Fn(usize) -> f32, t: usize| {
        if t == 0 || t + 1 >= frames {
            t as f32
        } else {
            t as f32 + vertex(f(t - 1), f(t), f(t + 1))
        }
    };
    let (top_time, arrival) = match pause {
        Some((begin, end)) => (end as f32, begin as f32),
        None => {
            let time = turning(&hand_speed, top);
            (time, time)
        }
    };
    let impact_time = match club {
        // The hands lead the club head through impact (shaft lean).
        None if !putt => turning(&away, impact) + IMPACT_LAG_S * rate_hz,
        _ => turning(&away, impact),
    }
    .min((frames - 1) as f32);

    if putt {
        // A putt: the finish is where the forward stroke stops, the hands slower than
        // STILL_FRACTION of their fastest after impact (a speed minimum would come late,
        // once the smoothing window has passed the stop).
        let mut peak = impact;
        while peak + 1 < frames && hand_speed(peak + 1) >= hand_speed(peak) {
            peak += 1;
        }
        let stopped = STILL_FRACTION * hand_speed(peak);
        let finish = (peak..frames)
            .find(|&t| hand_speed(t) < stopped)
            .unwrap_or(frames - 1);
        if finish <= impact {
            return Err(EventError::NoSwing);
        }
        let mut frames = [ABSENT; 10];
        let mut times = [0.0; 10];
        for (event, frame, time) in [
            (Event::Address, address, taken),
            (Event::Top, top, top_time),
            (Event::Impact, impact, impact_time),
            (
                Event::Finish,
                finish,
                between(hand_speed, stopped, finish.saturating_sub(1), finish),
            ),
        ] {
            frames[event.position() as usize] = frame as u16;
            times[event.position() as usize] = time;
        }
        return Ok(SwingEvents {
            kind: SwingKind::Putt,
            lead,
            club: club.is_some(),
            frames,
            times,
            arrival,
        });
    }

    let shaft = |t: usize| match club {
        Some((grip, head)) => elevation(track.at(head, t) - track.at(grip, t)),
        None => 0.0,
    };
    let (toe_up, follow) = match club {
        Some(_) => (
            crossing(address..top, shaft, 0.0, true),
            crossing(impact..frames, shaft, 0.0, true),
        ),
        None => (
            crossing(address..top, arm, TOE_UP_ARM_DEG, true),
            crossing(impact..frames, arm, FOLLOW_ARM_DEG, true),
        ),
    };
    let toe_up = toe_up.ok_or(EventError::NoSwing)?;
    let follow = follow.ok_or(EventError::NoSwing)?;
    let mid_backswing = crossing(toe_up..top, arm, 0.0, true).ok_or(EventError::NoSwing)?;
    let mid_downswing = crossing(top..impact, arm, 0.0, false).ok_or(EventError::NoSwing)?;
    // A crossing found at frame `t` of `f` past `level`, placed between the two frames around it.
    let crossed = |f: &dyn Fn(usize) -> f32, level: f32, t: usize| {
        let next = (t + 1).min(frames - 1);
        if (f(t) - level) * (f(next) - level) <= 0.0 {
            between(f, level, t, next)
        } else {
            between(f, level, t.saturating_sub(1), t)
        }
    };
    let (lift, lift_level) = match club {
        Some(_) => (&shaft as &dyn Fn(usize) -> f32, (0.0, 0.0)),
        None => (
            &arm as &dyn Fn(usize) -> f32,
            (TOE_UP_ARM_DEG, FOLLOW_ARM_DEG),
        ),
    };

    // Finish: the hands' highest point after the follow-through.
    let mut finish = follow;
    while finish + 1 < frames && hands(finish + 1).y >= hands(finish).y {
        finish += 1;
    }
    let height = |t: usize| hands(t).y;

    // P6, where the shaft falls through horizontal (without a club, SHAFT_DOWN_SHARE of the way
    // from P5 to impact); P9, where the trail arm rises through horizontal after impact.
    let p5 = crossed(&arm, 0.0, mid_downswing);
    let shaft_down = match club {
        Some(_) => {
            crossing(mid_downswing..impact, shaft, 0.0, false).map(|t| (t, crossed(&shaft, 0.0, t)))
        }
        None => {
            let time = p5 + SHAFT_DOWN_SHARE * (impact_time - p5);
            Some((libm::roundf(time) as usize, time))
        }
    };
    let trail_up =
        crossing(impact..finish, trail_arm, 0.0, true).map(|t| (t, crossed(&trail_arm, 0.0, t)));

    let times = [
        taken,
        crossed(lift, lift_level.0, toe_up),
        crossed(&arm, 0.0, mid_backswing),
        top_time,
        p5,
        impact_time,
        crossed(lift, lift_level.1, follow),
        turning(&height, finish),
    ];
    let mut frames = [
        address,
        toe_up,
        mid_backswing,
        top,
        mid_downswing,
        impact,
        follow,
        finish,
    ]
    .map(|f| f as u16);
    if frames.windows(2).any(|w| w[1] <= w[0]) {
        return Err(EventError::NoSwing);
    }
    // Impact's frame is the one nearest its time (later than the hands' return by the lag),
    // between its neighbours.
    let i = Event::Impact as usize;
    frames[i] = (libm::roundf(times[i]) as u16)
        .clamp(frames[i - 1] + 1, frames[i + 1] - 1)
        .max(frames[i]);
    let mut events = SwingEvents {
        kind: SwingKind::Full,
        lead,
        club: club.is_some(),
        frames: [ABSENT; 10],
        times: [0.0; 10],
        arrival,
    };
    for (k, event) in Event::ALL.into_iter().enumerate() {
        events.frames[event.position() as usize] = frames[k];
        events.times[event.position() as usize] = times[k];
    }
    // P6 and P9 where they fall strictly between their neighbours.
    for (position, found) in [(Position::P6, shaft_down), (Position::P9, trail_up)] {
        let i = position as usize;
        if let Some((frame, time)) = found {
            let frame = frame as u16;
            if events.frames[i - 1] < frame && frame < events.frames[i + 1] {
                events.frames[i] = frame;
                events.times[i] = time;
            }
        }
    }
    Ok(events)
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
