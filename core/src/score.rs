//! Scoring a student's swing against the coach's virtual swing on the student's skeleton.
//!
//! [`score`] finds both swings' events, aligns them with the event-anchored banded DTW, and
//! builds a fixed-capacity [`Report`]: the score, the frame correspondence, the tempo of each
//! phase, the joints that deviate most at each key event (in the golfer's stance frame), and
//! advice items ordered by importance.
//!
//! - **Score**: `100 · exp(−(Σ_events p / SPATIAL_POINTS_M + Σ_phases q / TEMPO_POINTS))`:
//!   `p` is the event's worst joint's [`excess`] over the larger of [`SPATIAL_THRESHOLD_M`] and
//!   [`NOISE_FACTOR`] times its uncertainty, `q` a phase's excess of `|ln ratio|` over
//!   `ln(1 + TEMPO_TOLERANCE)` (the score is a measure, not a verdict: a tempo change counts
//!   whatever its uncertainty). Identical swings score 100 (to rounding); the score falls
//!   strictly as a deviation or a tempo change grows, by nearly nothing while it is within its
//!   noise; on a clean input a 10 cm offset at one event costs 10 points, a phase 30 % slower
//!   11.
//! - **Event timing**: each of the student's events may be found early or late by about as
//!   long as the hands' velocity takes to change by its noise there (the velocity the still
//!   set-up shows), at least [`EVENT_TIMING_S`].
//! - **Tempo**: each phase's duration, student over coach, with its uncertainty from the event
//!   timing; where the ratio is past ±[`TEMPO_TOLERANCE`] by more than [`TEMPO_CONFIDENCE`]
//!   times its uncertainty the verdict is `slow` or `fast`.
//! - **Spatial**: at each event the student's pose at its time against the coach's at its own
//!   (see [`compare`]), each joint with its uncertainty along its offset: the wander of its
//!   offset over the swing per axis (a camera's depth axis is noisier), and along its path its
//!   speed times the event's timing uncertainty.
//! - **Body checks** ([`crate::checks`]): a few body metrics' change since address at the top
//!   and at impact, against the coach's.
//! - **Sequence** ([`crate::sequence`]): the gaps between the links' peaks in the downswing,
//!   against the coach's, advice only when their interval is past the tolerance, as tempo.
//! - **Stance frame** ([`Stance`]): each swing in its own, so a pelvis that moves toward the
//!   ball is reported as the pelvis moving.

use crate::body::{Body, Measure, Stance};
use crate::checks::{BodyDeviation, CHECKS};
use crate::config::{DEVIATIONS_PER_EVENT, MAX_DEVIATIONS, MAX_JOINTS, MAX_SWING_FRAMES};
use crate::dtw::{self, Band, DtwError, Sequence, Window};
use crate::events::{self, Event, EventError, Position, Side, SwingEvents};
use crate::frames::Frames;
use crate::joint::Joint;
use crate::math::{median, norm, select, MAD_SIGMA};
use crate::sequence::{self, Downswing, Gap, GAPS, GAP_TOLERANCE_S};
use crate::skeleton::Skeleton;
use crate::wire::{SwingReport, WireCheck, WireDeviation, WireGap};
use crate::Vec3;
use heapless::Vec as HVec;

/// Relative phase-duration difference beyond which the tempo verdict is slow or fast.
pub const TEMPO_TOLERANCE: f32 = 0.15;
/// Joint deviations at or below this (metres) are not reported.
pub const SPATIAL_THRESHOLD_M: f32 = 0.05;
/// Nor are those within this many times their uncertainty (how much the joint's offset from the
/// coach wanders over the swing): four standard deviations, the wander over one swing
/// understating an error that drifts over most of a second by about a fifth (its variance
/// around the swing's own median is 0.37 to 0.78 of the error's for correlation times of 1 to
/// 0.2 s over a 1.6 s swing).
pub const NOISE_FACTOR: f32 = 5.0;
/// The least an event's timing uncertainty is taken to be, seconds (one standard deviation;
/// a joint's deviation along its own path is uncertain by its speed times it).
pub const EVENT_TIMING_S: f32 = 0.005;
/// The most an event's timing uncertainty is taken to be, seconds.
pub const MAX_EVENT_TIMING_S: f32 = 0.2;
/// A tempo verdict needs the ratio past its tolerance by this many times its uncertainty
/// (about 95 % one-sided confidence).
pub const TEMPO_CONFIDENCE: f32 = 1.65;
/// The least noise per axis a body check's uncertainty is measured with, metres.
pub const LEAST_NOISE_M: f32 = 0.001;
/// A joint's wander is measured at this many moments spread evenly over the cut swing.
pub const WANDER_SAMPLES: usize = 32;
/// Poses are compared averaged over ± this long, seconds (zero phase).
pub const SPATIAL_SMOOTHING_S: f32 = 0.02;
/// The score's spatial scale: an event's worst excess of this many metres costs a factor `e`.
pub const SPATIAL_POINTS_M: f32 = 0.5;
/// The score's tempo scale: a phase's excess of this much `|ln ratio|` costs a factor `e`.
pub const TEMPO_POINTS: f32 = 1.0;
/// Softness of the excess over a spatial threshold, metres: well below the threshold a
/// deviation costs next to nothing, past it the excess grows as the deviation does.
pub const SPATIAL_SOFTNESS_M: f32 = 0.01;
/// Softness of the excess of a tempo change over its tolerance, in `|ln ratio|`.
pub const TEMPO_SOFTNESS: f32 = 0.03;
/// A student's root (the skeleton's first joint, the pelvis) that stays within this many
/// metres of where it was in the swing's first frame all through it is held by the input, not
/// the golfer: landmarks centred on the hips (MediaPipe's world landmarks) or a root the IMU
/// adapter fixes. No golfer's pelvis stays within 5 mm through a swing (a tour pelvis sways,
/// thrusts and lifts 5 to 15 cm), and a keypoint noise of a millimetre moves it farther.
pub const HELD_ROOT_M: f32 = 0.005;

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
/// Most advice items a report holds.
pub const MAX_ADVICE: usize = 8;
/// Longest warping path a report holds.
pub const MAX_PATH: usize = 2 * MAX_SWING_FRAMES - 1;

/// A swing phase between two events.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Address to top.
    Backswing,
    /// Top to impact.
    Downswing,
    /// Impact to finish.
    FollowThrough,
}

impl Phase {
    /// All phases in swing order.
    pub const ALL: [Phase; 3] = [Phase::Backswing, Phase::Downswing, Phase::FollowThrough];

    /// The events it runs between.
    pub const fn events(self) -> (Event, Event) {
        match self {
            Phase::Backswing => (Event::Address, Event::Top),
            Phase::Downswing => (Event::Top, Event::Impact),
            Phase::FollowThrough => (Event::Impact, Event::Finish),
        }
    }

    /// The snake_case name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Phase::Backswing => "backswing",
            Phase::Downswing => "downswing",
            Phase::FollowThrough => "follow_through",
        }
    }
}

/// How a phase's duration compares with the coach's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum Verdict {
    Ok,
    Slow,
    Fast,
}

impl Verdict {
    /// The name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Verdict::Ok => "ok",
            Verdict::Slow => "slow",
            Verdict::Fast => "fast",
        }
    }
}

/// One phase's tempo.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct PhaseTempo {
    /// The phase.
    pub phase: Phase,
    /// Student's duration, seconds.
    pub student_s: f32,
    /// Coach's duration, seconds.
    pub coach_s: f32,
    /// `student_s / coach_s`.
    pub ratio: f32,
    /// The ratio's uncertainty (one standard deviation, from how early or late the student's
    /// events may be found).
    pub ratio_uncertainty: f32,
    /// Slow or fast where the ratio is beyond [`TEMPO_TOLERANCE`] by more than
    /// [`TEMPO_CONFIDENCE`] times its uncertainty, else ok.
    pub verdict: Verdict,
}

/// Axes of the golfer's stance frame, and the six directions along them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum Direction {
    TowardTarget,
    AwayFromTarget,
    TowardBall,
    AwayFromBall,
    Up,
    Down,
}

impl Direction {
    /// The snake_case name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Direction::TowardTarget => "toward_target",
            Direction::AwayFromTarget => "away_from_target",
            Direction::TowardBall => "toward_ball",
            Direction::AwayFromBall => "away_from_ball",
            Direction::Up => "up",
            Direction::Down => "down",
        }
    }

    /// The words used in advice: "at the top your left wrist is 12 cm {lower}".
    pub const fn comparative(self) -> &'static str {
        match self {
            Direction::TowardTarget => "closer to the target",
            Direction::AwayFromTarget => "farther from the target",
            Direction::TowardBall => "closer to the ball",
            Direction::AwayFromBall => "farther from the ball",
            Direction::Up => "higher",
            Direction::Down => "lower",
        }
    }
}

/// A joint off the coach's position at an event.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Deviation {
    /// The event.
    pub event: Event,
    /// The joint.
    pub joint: Joint,
    /// Length of the offset, metres.
    pub distance_m: f32,
    /// Its uncertainty along it, metres: how much this joint's offset from the coach wanders
    /// over the whole swing (pose noise, and what the retargeting cannot match), and how far
    /// the joint moves within the event's timing uncertainty.
    pub uncertainty_m: f32,
    /// Student minus coach in the stance frame: toward target, toward ball, up (metres).
    pub offset_m: [f32; 3],
    /// The offset's largest component.
    pub direction: Direction,
}

/// One piece of advice; [`core::fmt::Display`] renders it as a sentence.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub enum Advice {
    /// A phase too slow or fast.
    Tempo(PhaseTempo),
    /// A joint off at an event.
    Spatial(Deviation),
    /// A body metric's change since address off the coach's at a position.
    Body(BodyDeviation),
    /// A gap between two links' peaks in the downswing off the coach's.
    Sequence(Gap),
}

impl Advice {
    /// How far past its threshold this is: the sort key, most important first.
    pub fn severity(&self) -> f32 {
        match self {
            Advice::Tempo(t) => {
                libm::fabsf(libm::logf(t.ratio)) / libm::logf(1.0 + TEMPO_TOLERANCE)
            }
            Advice::Spatial(d) => Advice::severity_of(d),
            Advice::Body(b) => Advice::severity_of_check(b),
            Advice::Sequence(g) => libm::fabsf(g.student_s - g.coach_s) / GAP_TOLERANCE_S,
        }
    }

    /// Whether a gap is advice: its interval, ± [`TEMPO_CONFIDENCE`] uncertainties, wholly
    /// past [`GAP_TOLERANCE_S`] from the coach's (a NaN gives none).
    pub fn is_clear(g: &Gap) -> bool {
        libm::fabsf(g.student_s - g.coach_s) - TEMPO_CONFIDENCE * g.uncertainty_s > GAP_TOLERANCE_S
    }

    /// A deviation's severity: how far past the larger of [`SPATIAL_THRESHOLD_M`] and
    /// [`NOISE_FACTOR`] times its uncertainty it is, as a multiple of that.
    pub fn severity_of(d: &Deviation) -> f32 {
        d.distance_m / SPATIAL_THRESHOLD_M.max(NOISE_FACTOR * d.uncertainty_m)
    }

    /// A body check's severity: how far past the larger of its tolerance and [`NOISE_FACTOR`]
    /// times its uncertainty the difference is, as a multiple of that: advice past 1.
    pub fn severity_of_check(b: &BodyDeviation) -> f32 {
        let threshold = b
            .check
            .measure
            .tolerance()
            .max(NOISE_FACTOR * b.uncertainty);
        libm::fabsf(b.student - b.coach) / threshold
    }
}

impl core::fmt::Display for Advice {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Advice::Tempo(t) => {
                let percent = libm::roundf(libm::fabsf(t.ratio - 1.0) * 100.0) as u32;
                let within = (libm::ceilf(t.ratio_uncertainty * 100.0) as u32).max(1);
                let (adjective, hint) = match t.verdict {
                    Verdict::Fast => ("faster", "take it smoother"),
                    _ => ("slower", "keep it moving"),
                };
                let phase = match t.phase {
                    Phase::Backswing => "backswing",
                    Phase::Downswing => "downswing",
                    Phase::FollowThrough => "follow-through",
                };
                write!(f, "Your {phase} is {percent} ± {within}% {adjective} than the coach's ({:.2} s against {:.2} s): {hint}.", t.student_s, t.coach_s)
            }
            Advice::Spatial(d) => {
                let event = match d.event {
                    Event::Address => "At address",
                    Event::ToeUp => "At toe-up",
                    Event::MidBackswing => "Halfway back",
                    Event::Top => "At the top",
                    Event::MidDownswing => "Halfway down",
                    Event::Impact => "At impact",
                    Event::MidFollowThrough => "Halfway through",
                    Event::Finish => "At the finish",
                };
                let cm = libm::roundf(d.distance_m * 100.0) as u32;
                let within = (libm::ceilf(d.uncertainty_m * 100.0) as u32).max(1);
                let joint = d.joint.name();
                write!(f, "{event} your ")?;
                for (i, word) in joint.split('_').enumerate() {
                    write!(f, "{}{word}", if i > 0 { " " } else { "" })?;
                }
                write!(
                    f,
                    " is {cm} ± {within} cm {} than the coach's.",
                    d.direction.comparative()
                )
            }
            Advice::Body(b) => b.fmt(f),
            Advice::Sequence(g) => g.fmt(f),
        }
    }
}

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
    /// At each event, up to [`DEVIATIONS_PER_EVENT`] joints beyond [`SPATIAL_THRESHOLD_M`],
    /// largest first.
    pub spatial: HVec<Deviation, MAX_DEVIATIONS>,
    /// The body checks ([`CHECKS`]) both swings could be measured at, in that order.
    pub body: HVec<BodyDeviation, { CHECKS.len() }>,
    /// The sequence's gaps ([`GAPS`]) both swings could be measured at, in that order.
    pub gaps: HVec<Gap, { GAPS.len() }>,
    /// The most important advice first.
    pub advice: HVec<Advice, MAX_ADVICE>,
    /// The input held the student's root still ([`HELD_ROOT_M`]): the coach was compared with
    /// its root held where it was at address too, and the pelvis's sway and thrust were not
    /// judged.
    pub root_held: bool,
}

impl Report {
    /// The wire form of swing number `swing`'s report, scored against coach reference `coach`:
    /// durations in milliseconds saturate at 65.534 s, offsets at ±32.767 m (uncertainties at
    /// 65.535 m), the score is rounded to hundredths, body checks go in tenths of a degree or
    /// millimetres, gaps in milliseconds (saturating likewise).
    pub fn to_wire(&self, swing: u32, coach: u16) -> SwingReport {
        let frames = |events: &SwingEvents| {
            Position::ALL.map(|p| events.frame(p).map_or(u16::MAX, |f| f as u16))
        };
        let ms = |s: f32| libm::roundf(s * 1000.0).clamp(0.0, f32::from(u16::MAX - 1)) as u16;
        let mm = |m: f32| libm::roundf(m * 1000.0).clamp(-32767.0, 32767.0) as i16;
        SwingReport {
            swing,
            coach,
            score_centi: libm::roundf(self.score * 100.0).clamp(0.0, 10000.0) as u16,
            student_positions: frames(&self.student_events),
            coach_positions: frames(&self.coach_events),
            phases_ms: self.tempo.map(|t| [ms(t.student_s), ms(t.coach_s)]),
            verdicts: self.tempo.map(|t| t.verdict as u8),
            deviations: self
                .spatial
                .iter()
                .map(|d| WireDeviation {
                    position: Position::from(d.event) as u8,
                    joint: d.joint.index() as u8,
                    direction: d.direction as u8,
                    offset_mm: d.offset_m.map(mm),
                    uncertainty_mm: libm::roundf(d.uncertainty_m * 1000.0)
                        .clamp(0.0, f32::from(u16::MAX)) as u16,
                })
                .collect(),
            checks: self
                .body
                .iter()
                .filter_map(|b| {
                    let scale = if b.check.measure.in_degrees() {
                        10.0
                    } else {
                        1000.0
                    };
                    let wide = |v: f32| libm::roundf(v * scale).clamp(-32767.0, 32767.0) as i16;
                    Some(WireCheck {
                        check: CHECKS.iter().position(|c| *c == b.check)? as u8,
                        student: wide(b.student),
                        coach: wide(b.coach),
                        uncertainty: libm::roundf(b.uncertainty * scale)
                            .clamp(0.0, f32::from(u16::MAX))
                            as u16,
                    })
                })
                .collect(),
            gaps: self
                .gaps
                .iter()
                .filter_map(|g| {
                    let ms = |s: f32| libm::roundf(s * 1000.0).clamp(-32767.0, 32767.0) as i16;
                    Some(WireGap {
                        gap: GAPS.iter().position(|&p| p == (g.first, g.then))? as u8,
                        student_ms: ms(g.student_s),
                        coach_ms: ms(g.coach_s),
                        uncertainty_ms: libm::roundf(g.uncertainty_s * 1000.0)
                            .clamp(0.0, f32::from(u16::MAX))
                            as u16,
                    })
                })
                .collect(),
        }
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
/// line and toward the ball are unchanged in the coach's own stance frame.
pub fn face(skeleton: &Skeleton, coach: &mut [Vec3], events: &SwingEvents, toward_target: Vec3) {
    let joints = skeleton.len();
    let address = events.address() * joints;
    let Some(pose) = coach.get(address..address + joints) else {
        return;
    };
    let stance = Stance::new(skeleton, pose, events.lead);
    let (from, to) = (stance.toward_target(), toward_target);
    // The angle about +Y taking `from` to `to` (both horizontal).
    let (sin, cos) = (from.cross(&to).y, from.x * to.x + from.z * to.z);
    let norm = libm::hypotf(sin, cos);
    // Already facing that way (to a micro-radian), or no line to turn: leave it bit for bit.
    if norm.is_nan() || norm <= 0.0 || (cos > 0.0 && libm::fabsf(sin) <= 1e-6 * norm) {
        return;
    }
    let (sin, cos) = (sin / norm, cos / norm);
    let origin = stance.origin();
    for p in coach.iter_mut() {
        let d = *p - origin;
        *p = origin + Vec3::new(cos * d.x + sin * d.z, d.y, -sin * d.x + cos * d.z);
    }
}

/// The stance of `swing` at frame `f`.
fn stance_at(skeleton: &Skeleton, swing: Frames<'_>, f: usize, lead: Side) -> Stance {
    let mut pose = [Vec3::zeros(); MAX_JOINTS];
    Stance::new(skeleton, swing.frame(f, &mut pose), lead)
}

/// Joint `k` of `swing` at fractional frame `x` (linear between frames, clamped to the swing),
/// averaged over `x ± half` frames: zero-phase smoothing of the cut swing, computed where it
/// is needed. Out of line: inlined where it is called it takes 3 KiB more of a device's flash.
#[inline(never)]
fn smoothed(swing: Frames<'_>, x: f32, k: usize, half: usize) -> Vec3 {
    let last = swing.len().saturating_sub(1);
    let at = |x: f32| {
        let x = x.clamp(0.0, last as f32);
        // x ≥ 0, so truncation is its floor (exact: frames are far below 2^24).
        let f = x as usize;
        let w = x - f as f32;
        let g = (f + 1).min(last);
        swing.at(f, k) * (1.0 - w) + swing.at(g, k) * w
    };
    let sum = (0..=2 * half).fold(Vec3::zeros(), |s, i| s + at(x + i as f32 - half as f32));
    sum / (2 * half + 1) as f32
}

/// The coach's frame matching each of the student's: linear between the events both swings
/// have (their times, and the hands' arrivals at the top where either pauses there), the
/// coach's rate beyond them.
struct TimeMap {
    /// (student, coach) times, in order.
    knots: HVec<(f32, f32), 9>,
    /// Coach frames per student frame beyond the knots.
    ratio: f32,
}

impl TimeMap {
    fn new(student: &SwingEvents, coach: &SwingEvents, ratio: f32) -> TimeMap {
        let mut knots = HVec::new();
        for e in Event::ALL {
            if e == Event::Top && (student.pause() > 0.0 || coach.pause() > 0.0) {
                // Eight events and one arrival fit the nine slots.
                let _ = knots.push((student.arrival(), coach.arrival()));
            }
            if let Some(pair) = student.time(e).zip(coach.time(e)) {
                let _ = knots.push(pair);
            }
        }
        TimeMap { knots, ratio }
    }

    /// The coach's frame matching the student's frame `x`.
    fn at(&self, x: f32) -> f32 {
        let Some((&first, rest)) = self.knots.split_first() else {
            return x * self.ratio;
        };
        if x <= first.0 {
            return first.1 + (x - first.0) * self.ratio;
        }
        let mut before = first;
        for &after in rest {
            if x <= after.0 {
                let span = after.0 - before.0;
                let w = if span > 0.0 {
                    (x - before.0) / span
                } else {
                    0.0
                };
                return before.1 + (after.1 - before.1) * w;
            }
            before = after;
        }
        before.1 + (x - before.0) * self.ratio
    }
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
    floats: &mut [f32],
    bytes: &mut [u8],
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
    let stance = stance_at(
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
    compare(skeleton, &student, &coach, band, floats, bytes)
}

/// Which joints a stream was unsure of, frame by frame: a ring of bit masks (bit `k` for
/// skeleton joint `k`) written at stream frame `n` into slot `n % ring.len()`, and where a swing
/// starts in the stream. A frame whose slot has since been written again counts as sure.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unsure<'a> {
    ring: &'a [u64],
    /// The slot of the swing's first frame.
    first: usize,
    /// The swing's frames whose masks the ring still holds, `from..to`.
    kept: (usize, usize),
}

impl<'a> Unsure<'a> {
    /// A swing starting at stream frame `start` of a stream that has pushed `seen` frames, its
    /// masks in `ring`.
    pub fn new(ring: &'a [u64], start: u64, seen: u64) -> Unsure<'a> {
        let len = ring.len() as u64;
        // Stream frame `n` is still held from `seen - len` up to `seen`.
        let frame = |n: u64| usize::try_from(n.saturating_sub(start)).unwrap_or(usize::MAX);
        Unsure {
            ring,
            first: start.checked_rem(len).unwrap_or(0) as usize,
            kept: if len == 0 {
                (0, 0)
            } else {
                (frame(seen.saturating_sub(len)), frame(seen))
            },
        }
    }

    /// The joints unsure at the swing's frame `frame`.
    pub fn at(&self, frame: usize) -> u64 {
        if !(self.kept.0..self.kept.1).contains(&frame) {
            return 0;
        }
        // The slot of stream frame `start + frame`, without a 64-bit division.
        let len = self.ring.len();
        self.ring[(self.first + frame % len) % len]
    }
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
/// coach already turned to [`face`] the way the student does.
///
/// # Errors
/// [`ScoreError`] when a swing is too long, the swings are of different kinds or the
/// scratch (see [`scratch_len`]) too short.
pub fn compare(
    skeleton: &Skeleton,
    student: &Detected<'_>,
    coach: &Detected<'_>,
    band: Band,
    floats: &mut [f32],
    bytes: &mut [u8],
) -> Result<Report, ScoreError> {
    let joints = skeleton.len();
    let Detected {
        positions: student,
        hz: student_hz,
        events: student_events,
        unsure,
    } = *student;
    let Detected {
        positions: coach,
        hz: coach_hz,
        events: coach_events,
        ..
    } = *coach;
    for (frames, student) in [(student, true), (coach, false)] {
        if !frames.is_whole() || frames.joints() != joints {
            let error = EventError::Length;
            return Err(ScoreError::Events { student, error });
        }
    }
    if student_events.kind != coach_events.kind {
        return Err(ScoreError::KindMismatch);
    }
    // The student's takeaway timed against the coach's backswing (steadier under pose noise).
    let takeaway = events::takeaway_against(
        skeleton,
        student,
        &student_events,
        student_hz,
        coach,
        &coach_events,
        coach_hz,
    );
    let student_events = takeaway.map_or(student_events, |t| student_events.with_takeaway(t.time));
    let (n, m) = (student.len(), coach.len());
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

    // Alignment, on the swings where they lie (each joint measured from its frame's root).
    let mut anchors: HVec<(u16, u16), { Event::COUNT }> = HVec::new();
    for event in Event::ALL {
        let (Some(i), Some(j)) = (student_events.frame(event), coach_events.frame(event)) else {
            continue;
        };
        let after_last = anchors
            .last()
            .is_none_or(|&(pi, pj)| i > pi as usize && j > pj as usize);
        if i > 0 && j > 0 && i + 1 < n && j + 1 < m && after_last {
            // Eight events fit the eight slots.
            let _ = anchors.push((i as u16, j as u16));
        }
    }
    let window = Window::new(band, &anchors)?;
    let len = dtw::scratch_len(n, m, &window)?;
    let cost = &mut floats[..len.cost];
    let steps = &mut bytes[..len.path_bytes];
    // The path is written where the report keeps it (no copy on the stack).
    let mut path = HVec::new();
    let _ = path.resize((n + m - 1).min(MAX_PATH), (0, 0));
    let alignment = dtw::align(
        &Sequence::rooted(student)?,
        &Sequence::rooted(coach)?,
        &[],
        &window,
        cost,
        steps,
        &mut path,
    )?;
    path.truncate(alignment.path_len);

    // Spatial deviations at each event, in each swing's stance frame, the student's pose at its
    // event time against the coach's at its own (a pure offset keeps its direction), both
    // smoothed over ±SPATIAL_SMOOTHING_S.
    let stance_s = stance_at(
        skeleton,
        student,
        student_events.address(),
        student_events.lead,
    );
    let stance_c = stance_at(skeleton, coach, coach_events.address(), coach_events.lead);
    let ratio = coach_hz / student_hz;
    let time_map = TimeMap::new(&student_events, &coach_events, ratio);
    let (half_s, half_c) = (
        libm::roundf(SPATIAL_SMOOTHING_S * student_hz) as usize,
        libm::roundf(SPATIAL_SMOOTHING_S * coach_hz) as usize,
    );

    // An input that holds the root still shows the body about its pelvis: the coach is then
    // compared the same way, its root held at address.
    let root_held = (0..n).all(|f| norm(&(student.at(f, 0) - student.at(0, 0))) < HELD_ROOT_M);
    let coach_address = coach_events.time(Event::Address).unwrap_or(0.0);
    // The coach's root at address, once for each smoothing it is read with (single frames,
    // and ±SPATIAL_SMOOTHING_S).
    let anchors = [0, half_c].map(|half| smoothed(coach, coach_address, 0, half));
    let coach_at = |k: usize, x: f32, half: usize| {
        let p = smoothed(coach, x, k, half);
        if root_held {
            let anchor = anchors[usize::from(half == half_c)];
            p - (smoothed(coach, x, 0, half) - anchor)
        } else {
            p
        }
    };
    let offset = |k: usize, x: f32, (hs, hc): (usize, usize)| {
        let c = time_map.at(x);
        stance_s.local(smoothed(student, x, k, hs)) - stance_c.local(coach_at(k, c, hc))
    };
    // Each joint's usual offset from the coach over the swing, takeaway to finish (per axis the
    // median: a keypoint's constant bias, or a joint another format places elsewhere), and how
    // much the offset wanders around it (per axis `MAD_SIGMA` times the median absolute deviation,
    // the standard deviation of a normal spread). Neither moves for a flaw confined to part of
    // the swing.
    let (from, to) = (
        student_events.time(Event::Address).unwrap_or(0.0),
        student_events.time(Event::Finish).unwrap_or((n - 1) as f32),
    );
    let samples = (libm::ceilf(to - from) as usize + 1).clamp(1, WANDER_SAMPLES);
    let step = (to - from) / samples.saturating_sub(1).max(1) as f32;
    let mut usual = [Vec3::zeros(); crate::config::MAX_JOINTS];
    let mut wander = [Vec3::zeros(); crate::config::MAX_JOINTS];
    let mut series = [[0.0f32; WANDER_SAMPLES]; 3];
    // Whether joint `k` was unsure anywhere within `half` frames (and one more) of frame `x`.
    let unsure_near = |k: usize, x: f32, half: usize| {
        // The frames either side of x, 0 for a negative x: a cast truncates toward zero and
        // takes a negative to 0.
        let lo = x as usize;
        let hi = lo.saturating_add(usize::from((lo as f32) < x));
        (lo.saturating_sub(half + 1)..=(hi + half + 1).min(n.saturating_sub(1)))
            .any(|f| unsure.at(f) & (1 << k) != 0)
    };
    let judged = |k: usize| skeleton.joint(k).is_some_and(|j| !j.is_club());
    for (k, (u, w)) in usual
        .iter_mut()
        .zip(wander.iter_mut())
        .enumerate()
        .take(joints)
    {
        // Unsmoothed (the wander of single frames bounds the smoothed one's from above), and
        // only where the stream was sure of the joint.
        let mut count = 0;
        for i in 0..samples {
            let x = from + step * i as f32;
            if unsure_near(k, x, 0) {
                continue;
            }
            let o = offset(k, x, (0, 0));
            for (axis, values) in series.iter_mut().enumerate() {
                values[count] = o[axis];
            }
            count += 1;
        }
        for (axis, values) in series.iter_mut().enumerate() {
            let values = &mut values[..count];
            u[axis] = median(values);
            for v in values.iter_mut() {
                *v = libm::fabsf(*v - u[axis]);
            }
            w[axis] = MAD_SIGMA * median(values);
        }
    }
    // Over one swing a keypoint error that drifts for most of a second is seen at a few
    // independent moments, so one joint's wander can come out far below its noise: no joint's
    // is taken below the median of all judged joints' (per axis; the pose noise is much the
    // same for all keypoints, the retargeting's mismatch is not).
    // Per axis, the median of the joints' wander is the least any joint's is taken to be; its
    // lower quartile is the input's noise the body checks are judged against (noise moves
    // every joint, a fault a few, and one that lasts most of the swing widens their wander).
    let (mut floor, mut noise) = (Vec3::zeros(), Vec3::zeros());
    let mut values = [0.0f32; crate::config::MAX_JOINTS];
    for axis in 0..3 {
        let mut count = 0;
        for (k, w) in wander.iter().enumerate().take(joints) {
            if judged(k) {
                values[count] = w[axis];
                count += 1;
            }
        }
        floor[axis] = median(&mut values[..count]);
        noise[axis] = select(&mut values[..count], count / 4);
    }
    for w in wander.iter_mut().take(joints) {
        *w = w.sup(&floor);
    }

    // How early or late each of the student's events may be found (seconds, one standard
    // deviation). Every event is a moment of the hands' motion (a turn, a crossing, a start), so
    // it moves by about as long as their velocity takes to change by its noise (its vertical
    // part at the finish, which their height defines), the shorter way; the noise is the
    // velocity the still set-up shows, before the takeaway.
    let mut timing = [MAX_EVENT_TIMING_S; Event::COUNT];
    // Where the hands paused at the top, the takeaway is fitted up to their arrival there
    // ([`SwingEvents::arrival`]): how early or late that may be found.
    let paused = student_events.pause() > 0.0;
    let mut arrival = MAX_EVENT_TIMING_S;
    let hands = skeleton
        .find(&[Joint::LeftWrist, Joint::LeftHand])
        .zip(skeleton.find(&[Joint::RightWrist, Joint::RightHand]));
    if let (Some((l, r)), Some(takeaway)) = (hands, student_events.time(Event::Address)) {
        let half = libm::roundf(events::SMOOTHING_S * student_hz) as usize;
        let at = |x: f32| (smoothed(student, x, l, half) + smoothed(student, x, r, half)) * 0.5;
        let velocity = |x: f32| (at(x + 1.0) - at(x - 1.0)) * (0.5 * student_hz);
        let still = libm::floorf(takeaway) as usize;
        let noise = libm::sqrtf(
            (0..=still)
                .map(|f| velocity(f as f32).norm_squared())
                .sum::<f32>()
                / (still + 1) as f32,
        )
        .max(events::STILL_SWAY_M_S);
        let reach = libm::ceilf(MAX_EVENT_TIMING_S * student_hz) as usize;
        // How long the velocity at `x` takes to change by its noise (its vertical part only,
        // counted against a third of the noise, where `vertical`), back and forth, seconds.
        let ways = |x: f32, vertical: bool| {
            let here = velocity(x);
            let (noise, changed): (f32, &dyn Fn(Vec3) -> f32) = match vertical {
                true => (noise / libm::sqrtf(3.0), &|v: Vec3| {
                    libm::fabsf(v.y - here.y)
                }),
                false => (noise, &|v: Vec3| norm(&(v - here))),
            };
            [-1.0f32, 1.0].map(|way| {
                let mut before = 0.0;
                for k in 1..=reach {
                    let now = changed(velocity(x + way * k as f32));
                    if now >= noise {
                        let w = (noise - before) / (now - before).max(f32::MIN_POSITIVE);
                        return (k as f32 - 1.0 + w) / student_hz;
                    }
                    before = now;
                }
                MAX_EVENT_TIMING_S
            })
        };
        for (event, spread) in Event::ALL.into_iter().zip(timing.iter_mut()) {
            let Some(x) = student_events.time(event) else {
                continue;
            };
            let ways = ways(x, event == Event::Finish);
            // A turn may lie anywhere the motion stays within its noise of it: the top, the
            // longer way (a slow backswing turning into a quick downswing); a start, a stop or
            // a crossing, the shorter, and so either end of a pause at the top.
            *spread = match event == Event::Top && !paused {
                true => ways[0].max(ways[1]),
                false => ways[0].min(ways[1]),
            }
            .max(EVENT_TIMING_S);
        }
        if paused {
            let ways = ways(student_events.arrival(), false);
            arrival = ways[0].min(ways[1]).max(EVENT_TIMING_S);
        }
    }
    // The takeaway is timed from the hands' arrival at the top (the top, without a pause) and
    // the crossings of the arms' progress ([`events::takeaway_against`]): it moves with the
    // arrival's error, scaled, and with the crossings' scatter.
    let top_gain = takeaway.map_or(0.0, |t| t.top_gain);
    if let Some(t) = takeaway {
        let a = Event::Address as usize;
        let arrival = match paused {
            true => arrival,
            false => timing[Event::Top as usize],
        };
        timing[a] = libm::hypotf(
            libm::hypotf(timing[a], t.top_gain * arrival),
            t.spread / student_hz,
        )
        .clamp(EVENT_TIMING_S, MAX_EVENT_TIMING_S);
    }

    // Tempo.
    // Between the events' times (the backswing from the takeaway), not their frames.
    let duration = |e: &SwingEvents, hz: f32, phase: Phase| {
        let (from, to) = phase.events();
        let at = |event| e.time(event).unwrap_or(0.0);
        (at(to) - at(from)) / hz
    };
    let tempo = Phase::ALL.map(|phase| {
        let (student_s, coach_s) = (
            duration(&student_events, student_hz, phase),
            duration(&coach_events, coach_hz, phase),
        );
        let ratio = student_s / coach_s;
        let (from, to) = phase.events();
        // The ratio's relative uncertainty (the coach's events are taken as exact), and a
        // verdict only when the whole interval is past the tolerance.
        // The backswing's ends move together where the hands did not pause at the top: a top
        // found late by δ moves the takeaway earlier by top_gain × δ.
        let (a, b) = (timing[from as usize], timing[to as usize]);
        let together = match phase {
            Phase::Backswing if !paused => 2.0 * top_gain * b * b,
            _ => 0.0,
        };
        let relative = libm::sqrtf(a * a + b * b + together) / student_s.max(f32::MIN_POSITIVE);
        let margin = libm::fabsf(libm::logf(ratio)) - TEMPO_CONFIDENCE * relative;
        // (A NaN margin, from a zero duration, gives no verdict.)
        let clear = margin > libm::logf(1.0 + TEMPO_TOLERANCE);
        let verdict = match (clear, ratio > 1.0) {
            (false, _) => Verdict::Ok,
            (true, true) => Verdict::Slow,
            (true, false) => Verdict::Fast,
        };
        PhaseTempo {
            phase,
            student_s,
            coach_s,
            ratio,
            ratio_uncertainty: ratio * relative,
            verdict,
        }
    });
    let tempo_ratio = |e: &SwingEvents, hz: f32| {
        duration(e, hz, Phase::Backswing) / duration(e, hz, Phase::Downswing)
    };

    let mut spatial: HVec<Deviation, MAX_DEVIATIONS> = HVec::new();
    let mut spatial_excess = 0.0f32;
    for event in Event::ALL {
        let Some(x) = student_events.time(event) else {
            continue;
        };
        let mut worst: HVec<Deviation, DEVIATIONS_PER_EVENT> = HVec::new();
        let mut event_excess = 0.0f32;
        // The coach's frame at this event, and the coach frames the event's timing
        // uncertainty spans.
        let c = time_map.at(x);
        let h = (timing[event as usize] * coach_hz).max(0.5);
        for (k, sigma) in wander.iter().enumerate().take(joints) {
            let Some(joint) = skeleton.joint(k).filter(|_| judged(k)) else {
                continue;
            };
            // A joint the stream was unsure of around the event is not judged there.
            if unsure_near(k, x, half_s) {
                continue;
            }
            // This moment's own offset, beyond the joint's usual one.
            let o = offset(k, x, (half_s, half_c)) - usual[k];
            let distance_m = norm(&o);
            // The uncertainty along the offset: the wander in that direction (a camera's depth
            // axis is noisier than the two across it) and, along the joint's path, how far it
            // moves in the event's timing uncertainty.
            let along = (stance_c.local(coach_at(k, c + h, half_c))
                - stance_c.local(coach_at(k, c - h, half_c)))
                * 0.5;
            let uncertainty_m = match o.try_normalize(f32::MIN_POSITIVE) {
                Some(u) => libm::hypotf(norm(&sigma.component_mul(&u)), along.dot(&u)),
                None => libm::hypotf(norm(sigma), norm(&along)) / libm::sqrtf(3.0),
            };
            let threshold = SPATIAL_THRESHOLD_M.max(NOISE_FACTOR * uncertainty_m);
            event_excess = event_excess.max(excess(distance_m, threshold, SPATIAL_SOFTNESS_M));
            if distance_m <= threshold {
                continue;
            }
            let deviation = Deviation {
                event,
                joint,
                distance_m,
                uncertainty_m,
                offset_m: [o.x, o.y, o.z],
                direction: direction(o),
            };
            insert_sorted(&mut worst, deviation, Advice::severity_of);
        }
        // One fact once: a joint next to one already listed, off the same way, is left out.
        let mut kept: HVec<Deviation, DEVIATIONS_PER_EVENT> = HVec::new();
        for d in worst {
            let k = skeleton.index_of(d.joint);
            let adjacent = |e: &Deviation| {
                let j = skeleton.index_of(e.joint);
                e.direction == d.direction
                    && (k.and_then(|k| skeleton.parent(k)) == j
                        || j.and_then(|j| skeleton.parent(j)) == k)
            };
            if !kept.iter().any(adjacent) {
                let _ = kept.push(d);
            }
        }
        for d in kept {
            let _ = spatial.push(d);
        }
        spatial_excess += event_excess;
    }
    let tempo_excess: f32 = tempo
        .iter()
        .map(|t| {
            excess(
                libm::fabsf(libm::logf(t.ratio)),
                libm::logf(1.0 + TEMPO_TOLERANCE),
                TEMPO_SOFTNESS,
            )
        })
        .sum();
    let score =
        100.0 * libm::expf(-(spatial_excess / SPATIAL_POINTS_M + tempo_excess / TEMPO_POINTS));

    let body = body_checks(
        skeleton,
        &Swing {
            at: &|k, x| smoothed(student, x, k, half_s),
            events: &student_events,
            stance: &stance_s,
        },
        &Swing {
            at: &|k, x| coach_at(k, x, half_c),
            events: &coach_events,
            stance: &stance_c,
        },
        &|x| time_map.at(x),
        &|k, x| unsure_near(k, x, half_s),
        &Input {
            noise,
            timing: timing.map(|t| t * coach_hz),
            root_held,
        },
    );

    let gaps = match (
        Body::new(skeleton, student_events.lead),
        Body::new(skeleton, coach_events.lead),
    ) {
        (Ok(body_s), Ok(body_c)) => sequence::gaps(
            &Downswing {
                body: &body_s,
                positions: student,
                hz: student_hz,
                events: &student_events,
            },
            &Downswing {
                body: &body_c,
                positions: coach,
                hz: coach_hz,
                events: &coach_events,
            },
            &|k, from, to| {
                (from..=to.min(n.saturating_sub(1))).any(|f| unsure.at(f) & (1 << k) != 0)
            },
        ),
        _ => HVec::new(),
    };

    // Advice: tempo, sequence, body and joint items by severity; a joint item that states what
    // a body item given at its event states is left out.
    let mut advice: HVec<Advice, MAX_ADVICE> = HVec::new();
    for t in tempo.iter().filter(|t| t.verdict != Verdict::Ok) {
        insert_sorted(&mut advice, Advice::Tempo(*t), Advice::severity);
    }
    for g in gaps.iter().filter(|g| Advice::is_clear(g)) {
        insert_sorted(&mut advice, Advice::Sequence(*g), Advice::severity);
    }
    for b in body.iter().filter(|b| Advice::severity_of_check(b) > 1.0) {
        insert_sorted(&mut advice, Advice::Body(*b), Advice::severity);
    }
    for d in &spatial {
        let stated = advice.iter().any(|a| {
            matches!(a, Advice::Body(b) if b.check.position.event() == Some(d.event)
                && states(b.check.measure, d, student_events.lead))
        });
        if !stated {
            insert_sorted(&mut advice, Advice::Spatial(*d), Advice::severity);
        }
    }

    Ok(Report {
        score,
        distance: alignment.distance,
        normalized: alignment.normalized,
        path,
        cells: len.cells as u32,
        student_events,
        coach_events,
        tempo,
        student_tempo_ratio: tempo_ratio(&student_events, student_hz),
        coach_tempo_ratio: tempo_ratio(&coach_events, coach_hz),
        spatial,
        body,
        gaps,
        advice,
        root_held,
    })
}

/// One swing as the body checks read it: joint `k` at frame `x` as the joint comparison
/// reads it, its events and its stance.
struct Swing<'a> {
    at: &'a dyn Fn(usize, f32) -> Vec3,
    events: &'a SwingEvents,
    stance: &'a Stance,
}

/// What the student's input allows the body checks: its noise per stance axis, each event's
/// timing uncertainty in coach frames, and whether it held the root still (then the pelvis's
/// sway and thrust are not checked).
struct Input {
    noise: Vec3,
    timing: [f32; Event::COUNT],
    root_held: bool,
}

impl Swing<'_> {
    /// Every joint at frame `x`.
    fn pose(&self, joints: usize, x: f32, out: &mut [Vec3; MAX_JOINTS]) {
        for (k, p) in out.iter_mut().enumerate().take(joints) {
            *p = (self.at)(k, x);
        }
    }
}

/// The body checks ([`CHECKS`], see [`crate::checks`]) of `student` against `coach`: the
/// coach's frame matching a student's frame is `coach_frame`'s, a joint the stream was unsure
/// of near a frame is `unsure` there (a check is not made at a position where a joint it is
/// measured from is), what the student's input allows is `input`. None for a skeleton that
/// lacks a joint the metrics need.
fn body_checks(
    skeleton: &Skeleton,
    student: &Swing<'_>,
    coach: &Swing<'_>,
    coach_frame: &dyn Fn(f32) -> f32,
    unsure: &dyn Fn(usize, f32) -> bool,
    input: &Input,
) -> HVec<BodyDeviation, { CHECKS.len() }> {
    let mut out = HVec::new();
    let joints = skeleton.len();
    let (Ok(body_s), Ok(body_c)) = (
        Body::new(skeleton, student.events.lead),
        Body::new(skeleton, coach.events.lead),
    ) else {
        return out;
    };
    let (Some(from_s), Some(from_c)) = (
        student.events.time(Event::Address),
        coach.events.time(Event::Address),
    ) else {
        return out;
    };
    let [mut address_s, mut address_c, mut at_s, mut at_c, mut later, mut earlier] =
        [[Vec3::zeros(); MAX_JOINTS]; 6];
    student.pose(joints, from_s, &mut address_s);
    coach.pose(joints, from_c, &mut address_c);
    let (address_s, address_c) = (&address_s[..joints], &address_c[..joints]);
    let axes = [
        student.stance.toward_target(),
        student.stance.toward_ball(),
        Vec3::y(),
    ];
    let mut at: Option<Position> = None;
    for check in CHECKS {
        let shift = matches!(check.measure, Measure::PelvisSway | Measure::PelvisThrust);
        let Some(event) = check
            .position
            .event()
            .filter(|_| !(input.root_held && shift))
        else {
            continue;
        };
        let Some(x) = student.events.time(event) else {
            continue;
        };
        let c = coach_frame(x);
        // Each position's poses once: the student's, the coach's and the coach's within the
        // event's timing uncertainty.
        let h = input.timing[event as usize].max(0.5);
        if at != Some(check.position) {
            at = Some(check.position);
            student.pose(joints, x, &mut at_s);
            coach.pose(joints, c, &mut at_c);
            coach.pose(joints, c + h, &mut later);
            coach.pose(joints, c - h, &mut earlier);
        }
        let measure = check.measure;
        let value_s = |pose: &[Vec3]| body_s.value(measure, student.stance, address_s, pose);
        let value_c = |pose: &[Vec3]| body_c.value(measure, coach.stance, address_c, pose);
        let (Some(zero_s), Some(here_s), Some(zero_c), Some(here_c)) = (
            value_s(address_s),
            value_s(&at_s[..joints]),
            value_c(address_c),
            value_c(&at_c[..joints]),
        ) else {
            continue;
        };
        let moved_by = body_s.joints_of(measure);
        if moved_by.iter().any(|&k| unsure(k, x) || unsure(k, from_s)) {
            continue;
        }
        // Each joint it is measured from moved by the noise along each axis.
        let mut variance = 0.0f32;
        for &k in &moved_by {
            for (axis, direction) in axes.iter().enumerate() {
                let kept = at_s[k];
                at_s[k] = kept + direction * input.noise[axis].max(LEAST_NOISE_M);
                let moved = value_s(&at_s[..joints]);
                at_s[k] = kept;
                let d = moved.map_or(0.0, |m| m - here_s);
                variance += d * d;
            }
        }
        // The coach's change within the event's timing uncertainty.
        let along = match (value_c(&later[..joints]), value_c(&earlier[..joints])) {
            (Some(l), Some(e)) => 0.5 * (l - e),
            _ => 0.0,
        };
        let _ = out.push(BodyDeviation {
            check,
            student: here_s - zero_s,
            coach: here_c - zero_c,
            uncertainty: libm::sqrtf(2.0 * variance + along * along),
        });
    }
    out
}

/// Whether joint item `d` (of a golfer whose lead side is `lead`) states the fact a body item
/// of `measure` states: then it is left out of the advice where the body item is in it.
fn states(measure: Measure, d: &Deviation, lead: Side) -> bool {
    use Direction::*;
    let hips = matches!(d.joint, Joint::Pelvis | Joint::LeftHip | Joint::RightHip);
    // A turn moves its joints about the vertical: across it, not up or down.
    let across = !matches!(d.direction, Up | Down);
    match measure {
        Measure::ThoraxTurn => {
            across && matches!(d.joint, Joint::LeftShoulder | Joint::RightShoulder)
        }
        Measure::PelvisTurn => across && matches!(d.joint, Joint::LeftHip | Joint::RightHip),
        Measure::PelvisSway => hips && matches!(d.direction, TowardTarget | AwayFromTarget),
        Measure::PelvisThrust => hips && matches!(d.direction, TowardBall | AwayFromBall),
        Measure::HeadLift => {
            matches!(d.joint, Joint::Neck | Joint::Head | Joint::HeadTop)
                && matches!(d.direction, Up | Down)
        }
        Measure::LeadElbow => match lead {
            Side::Left => matches!(d.joint, Joint::LeftElbow | Joint::LeftWrist),
            Side::Right => matches!(d.joint, Joint::RightElbow | Joint::RightWrist),
        },
    }
}

/// The stance direction of `offset`'s largest component.
fn direction(offset: Vec3) -> Direction {
    let axis = offset.iamax();
    match (axis, offset[axis] > 0.0) {
        (0, true) => Direction::TowardTarget,
        (0, false) => Direction::AwayFromTarget,
        (1, true) => Direction::TowardBall,
        (1, false) => Direction::AwayFromBall,
        (_, true) => Direction::Up,
        (_, false) => Direction::Down,
    }
}

/// Inserts `item` into `list`, kept sorted by `key` descending; when full, the smallest goes.
fn insert_sorted<T: Copy, const N: usize>(list: &mut HVec<T, N>, item: T, key: impl Fn(&T) -> f32) {
    let item_key = key(&item);
    let at = list
        .iter()
        .position(|x| key(x) < item_key)
        .unwrap_or(list.len());
    if at >= N {
        return;
    }
    if list.is_full() {
        list.pop();
    }
    let _ = list.insert(at, item);
}

#[cfg(test)]
mod tests {
    use super::{Advice, Unsure, SPATIAL_THRESHOLD_M};
    use crate::checks::{BodyDeviation, CHECKS, SHIFT_TOLERANCE_M};

    #[test]
    fn a_body_check_is_advice_past_its_tolerance_or_its_noise_whichever_is_larger() {
        let severity = |check: usize, student: f32, coach: f32, uncertainty: f32| {
            Advice::severity_of_check(&BodyDeviation {
                check: CHECKS[check],
                student,
                coach,
                uncertainty,
            })
        };
        // 17° short of the coach: past the 10° tolerance while the noise is small.
        assert!((severity(0, 78.0, 95.0, 1.0) - 1.7).abs() < 1e-5);
        // The same with 4° of uncertainty: 17 / 20.
        assert!((severity(0, 78.0, 95.0, 4.0) - 0.85).abs() < 1e-5);
        // A 6 cm thrust against the 5 cm tolerance, the joints' own threshold.
        assert!((severity(5, 0.06, 0.0, 0.001) - 1.2).abs() < 1e-5);
        assert_eq!(SHIFT_TOLERANCE_M, SPATIAL_THRESHOLD_M);
    }

    #[test]
    fn unsure_masks_are_read_where_the_ring_still_holds_them() {
        // A ring of 4 slots after 10 frames: frames 6 to 9 are held, in slots 2, 3, 0, 1.
        let ring = [0b01, 0b10, 0b100, 0b1000];
        let swing = Unsure::new(&ring, 5, 10);
        assert_eq!(swing.at(0), 0); // frame 5: written over
        assert_eq!(swing.at(1), 0b100); // frame 6
        assert_eq!(swing.at(4), 0b10); // frame 9
        assert_eq!(swing.at(5), 0); // frame 10: not yet pushed
        assert_eq!(Unsure::default().at(3), 0);
    }

    proptest::proptest! {
        #[test]
        fn unsure_reads_stream_frame_start_plus_frame_from_its_slot_while_the_ring_holds_it(
            len in 0usize..9,
            start in 0u64..(1 << 40),
            back in 0u64..60,
            frame in 0usize..60,
        ) {
            let ring: std::vec::Vec<u64> = (0..len as u64).map(|i| 1 << i).collect();
            let seen = (start + back).saturating_sub(20);
            // Stream frame n is in slot n % len, written over once n + len < seen.
            let n = start + frame as u64;
            let held = len > 0 && n < seen && n + len as u64 >= seen;
            let expected = if held { ring[(n % len as u64) as usize] } else { 0 };
            proptest::prop_assert_eq!(Unsure::new(&ring, start, seen).at(frame), expected);
        }
    }
}
