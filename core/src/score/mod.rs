//! Scoring a student's swing against the coach's virtual swing on the student's skeleton.
//!
//! [`score`] finds both swings' events, turns the coach to [`face`] the way the student does
//! and calls [`compare`], which runs the scoring's stages in order, each a module with a typed
//! result:
//!
//! | stage | finds |
//! | --- | --- |
//! | `align` | the event-anchored banded DTW and its path; each swing's stance frame; the coach's frame matching each of the student's |
//! | `noise` | each joint's usual offset from the coach and its wander; the input's noise per stance axis |
//! | `timing` | how early or late each of the student's events may be found |
//! | `tempo` | each phase's duration against the coach's, with its uncertainty and verdict |
//! | `spatial` | the joints off the coach's position at each event, with their uncertainty; every judged joint's offset to a [`Sink`] that asks |
//! | `body` | the body checks ([`crate::checks`]) and the kinematic sequence's gaps ([`crate::sequence`]) |
//! | `cause` | the checks and gaps past their thresholds, and the joint offsets each explains: the body-level difference at each event applied to the coach's pose, a joint within its threshold of it folded under the cause; a check at impact that a gap's change accounts for (the coach's rate of change there times it) folded under the gap |
//! | `advice` | the items a golfer reads, most important first |
//! | `to_wire` | the report's compact wire form ([`Report::to_wire`]) |
//!
//! - **Score**: `100 · exp(−(Σ_events p / SPATIAL_POINTS_M + Σ_phases q / TEMPO_POINTS))`:
//!   `p` is the event's worst joint's [`excess`] over the larger of [`SPATIAL_THRESHOLD_M`] and
//!   [`NOISE_FACTOR`] times its uncertainty, `q` a phase's excess of `|ln ratio|` over
//!   `ln(1 + TEMPO_TOLERANCE)` (the score is a measure, not a verdict: a tempo change counts
//!   whatever its uncertainty). Identical swings score 100 (to rounding); the score falls
//!   strictly as a deviation or a tempo change grows, by nearly nothing while it is within its
//!   noise; on a clean input a 10 cm offset at one event costs 10 points, a phase 30 % slower
//!   11.
//! - **Stance frame** ([`Stance`]): each swing in its own, so a pelvis
//!   that moves toward the ball is reported as the pelvis moving.

mod advice;
mod align;
mod body;
mod cause;
mod noise;
mod sink;
mod spatial;
mod tempo;
mod timing;
mod to_wire;
mod unsure;

pub use advice::Advice;
pub(crate) use advice::{insert_sorted, ranked};
pub use align::{BRIDGE_S, HELD_ROOT_M, SPATIAL_SMOOTHING_S};
pub use body::LEAST_NOISE_M;
pub(crate) use cause::{may_explain, predicted_by, Item};
pub use cause::{Explains, MAX_CAUSES};
pub use noise::WANDER_SAMPLES;
pub use sink::{BodyLevel, Sink};
pub use spatial::{
    Deviation, Direction, NOISE_FACTOR, SPATIAL_POINTS_M, SPATIAL_SOFTNESS_M, SPATIAL_THRESHOLD_M,
};
pub use tempo::{
    Phase, PhaseTempo, Verdict, TEMPO_CONFIDENCE, TEMPO_POINTS, TEMPO_SOFTNESS, TEMPO_TOLERANCE,
};
pub use timing::{EVENT_TIMING_S, MAX_EVENT_TIMING_S};
pub use unsure::Unsure;

use crate::band::Band;
use crate::body::Stance;
use crate::checks::BodyDeviation;
use crate::config::{
    MAX_ADVICE, MAX_CHECKS, MAX_DEVIATIONS, MAX_GAPS, MAX_JOINTS, MAX_SWING_FRAMES,
};
use crate::dtw::{self, DtwError};
use crate::events::{self, Event, EventError, SwingEvents};
use crate::frames::{Frames, Turn};
use crate::sequence::Gap;
use crate::skeleton::Skeleton;
use crate::Vec3;
use heapless::Vec as HVec;

/// How far a non-negative `value` is past `threshold`, softly: `s · ln(1 + e^((value −
/// threshold) / s))` less its value at 0 (`s` the softness), which is 0 at 0, grows strictly
/// with `value`, is about `value − threshold` well past it and next to nothing well below.
pub fn excess(value: f32, threshold: f32, softness: f32) -> f32 {
    let soft = |x: f32| {
        let x = x / softness;
        softness
            * if x > 20.0 {
                x
            } else {
                libm::log1pf(libm::expf(x))
            }
    };
    soft(value - threshold) - soft(-threshold)
}
/// Longest warping path a report holds.
pub const MAX_PATH: usize = 2 * MAX_SWING_FRAMES - 1;

/// The result of scoring one swing.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Report {
    /// 0 to 100.
    pub score: f32,
    /// DTW distance (sum of mean joint distances along the path, metres).
    pub distance: f32,
    /// `distance` over the path length.
    pub normalized: f32,
    /// Frame correspondence `(student, coach)`.
    pub path: HVec<(u16, u16), MAX_PATH>,
    /// Cells of the DTW's band: the alignment's work.
    pub cells: u32,
    /// The student's events.
    pub student_events: SwingEvents,
    /// The coach's events.
    pub coach_events: SwingEvents,
    /// Backswing, downswing and follow-through.
    pub tempo: [PhaseTempo; 3],
    /// Backswing over downswing duration, student.
    pub student_tempo_ratio: f32,
    /// Backswing over downswing duration, coach.
    pub coach_tempo_ratio: f32,
    /// At each event, up to [`DEVIATIONS_PER_EVENT`](crate::config::DEVIATIONS_PER_EVENT) joints beyond their threshold that no
    /// body check or gap explains (those are folded under it in the advice: [`Explains`]),
    /// the most severe first.
    pub spatial: HVec<Deviation, MAX_DEVIATIONS>,
    /// The body checks ([`CHECKS`](crate::checks::CHECKS)) both swings could be measured at,
    /// in that order.
    pub body: HVec<BodyDeviation, MAX_CHECKS>,
    /// The sequence's gaps ([`GAPS`](crate::sequence::GAPS)) both swings could be measured
    /// at, in that order.
    pub gaps: HVec<Gap, MAX_GAPS>,
    /// The most important advice first.
    pub advice: HVec<Advice, MAX_ADVICE>,
    /// The input held the student's root still ([`HELD_ROOT_M`]): the coach was compared with
    /// its root held where it was at address too, and the pelvis's sway and thrust were not
    /// judged.
    pub root_held: bool,
    /// How the student's input may err, as the noise and timing stages found.
    pub input: InputSpread,
}

/// How a student's input may err (one standard deviation), kept compact: every byte of a
/// [`Report`] costs the device's stack more than once.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InputSpread {
    /// The input's noise per stance axis (toward the target, toward the ball, up), tenths of a
    /// millimetre.
    noise: [u16; 3],
    /// How early or late each of the student's events may have been found, milliseconds
    /// (rounded up), [`Event::ALL`] order.
    timing: [u8; Event::COUNT],
}

impl InputSpread {
    /// The spread of input whose noise per stance axis is `noise` (metres) and whose events
    /// may be early or late by `timing` (seconds), each saturating at what its unit holds.
    pub fn new(noise: crate::Vec3, timing: &[f32; Event::COUNT]) -> InputSpread {
        InputSpread {
            noise: <[f32; 3]>::from(noise).map(|m| libm::roundf(m * 1e4) as u16),
            timing: timing.map(|s| libm::ceilf(s * 1e3) as u8),
        }
    }

    /// The input's noise per stance axis, metres.
    pub fn noise_m(&self) -> [f32; 3] {
        self.noise.map(|t| f32::from(t) * 1e-4)
    }

    /// How early or late each event may have been found, seconds, [`Event::ALL`] order.
    pub fn timing_s(&self) -> [f32; Event::COUNT] {
        self.timing.map(|ms| f32::from(ms) * 1e-3)
    }
}

/// Why a swing could not be scored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ScoreError {
    /// Events could not be found in the student's (`student` true) or coach's swing.
    Events {
        /// Whose swing.
        student: bool,
        /// Why.
        error: EventError,
    },
    /// One swing is a putt and the other a full swing.
    KindMismatch,
    /// A swing is longer than [`MAX_SWING_FRAMES`].
    TooLong {
        /// Its frames.
        frames: usize,
    },
    /// The alignment failed (scratch too small, bad weights).
    Dtw(DtwError),
    /// Scratch shorter than [`scratch_len`] asks.
    Scratch {
        /// Floats needed (bytes are [`ScratchLen::bytes`]).
        needed: usize,
    },
}

impl core::fmt::Display for ScoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ScoreError::Events { student, error } => {
                write!(
                    f,
                    "{} swing: {error}",
                    if *student { "student" } else { "coach" }
                )
            }
            ScoreError::KindMismatch => f.write_str(
                "one swing is a putt and the other a full swing: compare like with like",
            ),
            ScoreError::TooLong { frames } => {
                write!(
                    f,
                    "a swing of {frames} frames is longer than {MAX_SWING_FRAMES}"
                )
            }
            ScoreError::Dtw(e) => write!(f, "alignment: {e}"),
            ScoreError::Scratch { needed } => write!(f, "scoring scratch needs {needed} floats"),
        }
    }
}

impl core::error::Error for ScoreError {}

impl From<DtwError> for ScoreError {
    fn from(e: DtwError) -> Self {
        ScoreError::Dtw(e)
    }
}

/// Scratch [`score`] needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScratchLen {
    /// Floats: the DTW's rows of accumulated cost.
    pub floats: usize,
    /// Bytes: the DTW path bits.
    pub bytes: usize,
}

/// Scratch [`score`] needs for swings of `student` and `coach` frames, whatever band the events
/// give (the swings themselves are read where they lie).
pub const fn scratch_len(student: usize, coach: usize) -> ScratchLen {
    ScratchLen {
        floats: dtw::cost_len_bound(coach),
        bytes: (student * coach).div_ceil(4),
    }
}

/// Turns `coach` (frames × skeleton joints, with its `events`) about the vertical through its
/// stance origin so that its target line runs along `toward_target` (a student's
/// [`Stance::toward_target`]): the alignment compares root-relative poses, which a camera's or
/// a sensor's heading would otherwise turn away from the coach's. Positions along the target
/// line and toward the ball are unchanged in the coach's own stance frame. The turn is
/// [`facing`]'s.
pub fn face(skeleton: &Skeleton, coach: &mut [Vec3], events: &SwingEvents, toward_target: Vec3) {
    let frames = Frames::metres(coach, skeleton.len());
    let Some(turn) = facing(skeleton, frames, events, toward_target) else {
        return;
    };
    for p in coach.iter_mut() {
        *p = turn.apply(p);
    }
}

/// The turn [`face`] gives `coach` (frames of the skeleton's joints, with its `events`), for a
/// coach read turned rather than turned where it is stored
/// ([`Frames::millimetres_turned`]); `None` when it is left as it is: it already faces that
/// way (to a micro-radian), there is no line to turn, or no address frame.
pub fn facing(
    skeleton: &Skeleton,
    coach: Frames<'_>,
    events: &SwingEvents,
    toward_target: Vec3,
) -> Option<Turn> {
    if events.address() >= coach.len() || coach.joints() != skeleton.len() {
        return None;
    }
    let mut pose = [Vec3::zeros(); MAX_JOINTS];
    let pose = coach.frame(events.address(), &mut pose);
    let stance = Stance::new(skeleton, pose, events.lead);
    let (from, to) = (stance.toward_target(), toward_target);
    // The angle about +Y taking `from` to `to` (both horizontal).
    let (sin, cos) = (from.cross(&to).y, from.x * to.x + from.z * to.z);
    let norm = crate::math::hypot(sin, cos);
    // Already facing that way (to a micro-radian), or no line to turn: leave it bit for bit.
    if norm.is_nan() || norm <= 0.0 || (cos > 0.0 && libm::fabsf(sin) <= 1e-6 * norm) {
        return None;
    }
    Some(Turn::new(stance.origin(), sin / norm, cos / norm))
}

/// Scores `student` (frames × skeleton joints at `student_hz`) against the coach's virtual
/// swing `coach` (on the same skeleton, at `coach_hz`), aligned within `band`: [`compare`]
/// after detecting both swings' events and turning the coach to [`face`] the way the student
/// does.
///
/// # Errors
/// [`ScoreError`] when events cannot be found, a swing is too long or the scratch (see
/// [`scratch_len`]) too short.
#[allow(clippy::too_many_arguments)]
pub fn score(
    skeleton: &Skeleton,
    student: &[Vec3],
    student_hz: f32,
    coach: &mut [Vec3],
    coach_hz: f32,
    band: Band,
    (floats, bytes): (&mut [f32], &mut [u8]),
    sink: &mut dyn Sink,
) -> Result<Report, ScoreError> {
    let detect = |positions, hz, student| {
        Detected::new(skeleton, positions, hz)
            .map_err(|error| ScoreError::Events { student, error })
    };
    let joints = skeleton.len();
    let student = detect(Frames::metres(student, joints), student_hz, true)?;
    let coach_events =
        events::detect(skeleton, Frames::metres(coach, joints), coach_hz).map_err(|error| {
            ScoreError::Events {
                student: false,
                error,
            }
        })?;
    let stance = align::stance_at(
        skeleton,
        student.positions,
        student.events.address(),
        student.events.lead,
    );
    face(skeleton, coach, &coach_events, stance.toward_target());
    let coach = Detected {
        positions: Frames::metres(coach, joints),
        hz: coach_hz,
        events: coach_events,
        unsure: Unsure::default(),
    };
    compare(skeleton, &student, &coach, band, (floats, bytes), sink)
}

/// A swing with its events: frames × skeleton joints at `hz`.
#[derive(Clone, Copy, Debug)]
pub struct Detected<'a> {
    /// The frames.
    pub positions: Frames<'a>,
    /// Their rate.
    pub hz: f32,
    /// Its events, as [`events::detect`] finds them in `positions`.
    pub events: SwingEvents,
    /// The joints the stream was unsure of, frame by frame (none for a swing read whole).
    pub unsure: Unsure<'a>,
}

impl<'a> Detected<'a> {
    /// `positions` with the events [`events::detect`] finds in them.
    ///
    /// # Errors
    /// [`EventError`] when they cannot be found.
    pub fn new(skeleton: &Skeleton, positions: Frames<'a>, hz: f32) -> Result<Self, EventError> {
        let events = events::detect(skeleton, positions, hz)?;
        Ok(Detected {
            positions,
            hz,
            events,
            unsure: Unsure::default(),
        })
    }
}

/// [`score`] of two swings whose events are known (a device detects its coach's once), the
/// coach already turned to [`face`] the way the student does (or read turned by [`facing`]'s
/// turn). `sink` is told the swing's body-level results and, where it asks, every judged
/// joint's offset at every event.
///
/// # Errors
/// [`ScoreError`] when a swing is too long, the swings are of different kinds or the
/// scratch (see [`scratch_len`]) too short.
pub fn compare(
    skeleton: &Skeleton,
    student: &Detected<'_>,
    coach: &Detected<'_>,
    band: Band,
    (floats, bytes): (&mut [f32], &mut [u8]),
    sink: &mut dyn Sink,
) -> Result<Report, ScoreError> {
    let joints = skeleton.len();
    for (frames, student) in [(student.positions, true), (coach.positions, false)] {
        if !frames.is_whole() || frames.joints() != joints {
            let error = EventError::Length;
            return Err(ScoreError::Events { student, error });
        }
    }
    let (events_c, hz) = (&coach.events, (student.hz, coach.hz));
    if student.events.kind != events_c.kind {
        return Err(ScoreError::KindMismatch);
    }
    // The student's takeaway timed against the coach's backswing (steadier under pose noise).
    let takeaway = events::takeaway_against(
        skeleton,
        student.positions,
        &student.events,
        student.hz,
        coach.positions,
        events_c,
        coach.hz,
    );
    let events_s = takeaway.map_or(student.events, |t| student.events.with_takeaway(t.time));
    let (n, m) = (student.positions.len(), coach.positions.len());
    for frames in [n, m] {
        if frames > MAX_SWING_FRAMES {
            return Err(ScoreError::TooLong { frames });
        }
    }
    let needed = scratch_len(n, m);
    if floats.len() < needed.floats || bytes.len() < needed.bytes {
        return Err(ScoreError::Scratch {
            needed: needed.floats,
        });
    }
    // The path is written where the report keeps it (no copy on the stack).
    let mut path = HVec::new();
    let warp = align::warp(
        (student.positions, coach.positions),
        (&events_s, events_c),
        band,
        (floats, bytes),
        &mut path,
    )?;
    let pair = align::Pair::new(skeleton, (student, &events_s), coach);
    let noise = noise::measure(skeleton, &pair, &events_s);
    let timing = timing::timing(
        skeleton,
        (student.positions, student.hz),
        &events_s,
        takeaway,
    );
    let tempo = tempo::tempo((&events_s, hz.0), (events_c, hz.1), &timing);
    let body = body::checks(
        skeleton,
        &pair,
        ((&events_s, events_c), hz),
        &noise,
        &timing,
    );
    let gaps = body::gaps(skeleton, &pair, (&events_s, events_c), hz);
    let mut causes = cause::causes(&body.found, &body.coach_rate, &gaps);
    let offsets = sink.body(&BodyLevel {
        lead: events_s.lead,
        tempo: &tempo,
        pause_s: (events_s.pause() / hz.0, events_c.pause() / hz.1),
        body: &body.found,
        coach_rate: &body.coach_rate,
        gaps: &gaps,
    });
    let spatial = spatial::spatial(
        skeleton,
        &pair,
        (&events_s, hz.1),
        (&noise, &timing),
        (&mut causes, offsets.then_some(sink)),
    );
    let advice = advice::advise(&tempo, &mut causes, &spatial.deviations, events_s.lead);
    let score = 100.0
        * libm::expf(
            -(spatial.excess / SPATIAL_POINTS_M + tempo::excess_of(&tempo) / TEMPO_POINTS),
        );
    Ok(Report {
        score,
        distance: warp.distance,
        normalized: warp.normalized,
        path,
        cells: warp.cells,
        student_events: events_s,
        coach_events: *events_c,
        tempo,
        student_tempo_ratio: tempo::ratio(&events_s, hz.0),
        coach_tempo_ratio: tempo::ratio(events_c, hz.1),
        spatial: spatial.deviations,
        body: body.found,
        gaps,
        advice,
        root_held: pair.root_held,
        input: InputSpread::new(noise.input, &timing.event),
    })
}

#[cfg(test)]
mod tests {
    use super::InputSpread;
    use crate::events::Event;
    use crate::Vec3;

    #[test]
    fn an_input_spread_keeps_a_tenth_of_a_millimetre_and_rounds_timing_up_to_the_ms() {
        let mut timing = [0.0051f32; Event::COUNT];
        timing[1] = 1.0;
        let spread = InputSpread::new(Vec3::new(0.01234, 0.00004, 10.0), &timing);
        let noise = spread.noise_m();
        assert!((noise[0] - 0.0123).abs() < 1e-6, "{noise:?}");
        assert_eq!(noise[1], 0.0);
        // Past what the unit holds, it saturates.
        assert!((noise[2] - 6.5535).abs() < 1e-4, "{noise:?}");
        let back = spread.timing_s();
        assert!(
            (back[0] - 0.006).abs() < 1e-6 && (back[1] - 0.255).abs() < 1e-6,
            "{back:?}"
        );
    }
}
