//! The tempo stage: each phase's duration, student over coach, with its uncertainty from the
//! events' timing; where the ratio is past ±[`TEMPO_TOLERANCE`] by more than
//! [`TEMPO_CONFIDENCE`] times its uncertainty the verdict is `slow` or `fast`.

use super::excess;
use super::timing::Timing;
use crate::events::{Event, SwingEvents};

/// Relative phase-duration difference beyond which the tempo verdict is slow or fast.
pub const TEMPO_TOLERANCE: f32 = 0.15;
/// A tempo verdict needs the ratio past its tolerance by this many times its uncertainty
/// (about 95 % one-sided confidence).
pub const TEMPO_CONFIDENCE: f32 = 1.65;
/// The score's tempo scale: a phase's excess of this much `|ln ratio|` costs a factor `e`.
pub const TEMPO_POINTS: f32 = 1.0;
/// Softness of the excess of a tempo change over its tolerance, in `|ln ratio|`.
pub const TEMPO_SOFTNESS: f32 = 0.03;

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

/// `phase`'s duration in `events` at `hz`, seconds: between the events' times (the backswing
/// from the takeaway), not their frames.
fn duration(events: &SwingEvents, hz: f32, phase: Phase) -> f32 {
    let (from, to) = phase.events();
    let at = |event| events.time(event).unwrap_or(0.0);
    (at(to) - at(from)) / hz
}

/// Backswing over downswing duration.
pub(super) fn ratio(events: &SwingEvents, hz: f32) -> f32 {
    duration(events, hz, Phase::Backswing) / duration(events, hz, Phase::Downswing)
}

/// Each phase's tempo, the student's (`events` at `hz`, timed as `timing`) against the
/// coach's (whose events are taken as exact).
pub(super) fn tempo(
    (student, student_hz): (&SwingEvents, f32),
    (coach, coach_hz): (&SwingEvents, f32),
    timing: &Timing,
) -> [PhaseTempo; 3] {
    Phase::ALL.map(|phase| {
        let (student_s, coach_s) = (
            duration(student, student_hz, phase),
            duration(coach, coach_hz, phase),
        );
        let ratio = student_s / coach_s;
        let (from, to) = phase.events();
        // The ratio's relative uncertainty, and a verdict only when the whole interval is past
        // the tolerance. The backswing's ends move together where the hands did not pause at
        // the top: a top found late by δ moves the takeaway earlier by top_gain × δ.
        let (a, b) = (timing.event[from as usize], timing.event[to as usize]);
        let together = match phase {
            Phase::Backswing if !timing.paused => 2.0 * timing.top_gain * b * b,
            _ => 0.0,
        };
        let relative =
            crate::math::sqrt(a * a + b * b + together) / student_s.max(f32::MIN_POSITIVE);
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
    })
}

/// What the phases' changes cost the score: each one's excess of `|ln ratio|` over
/// `ln(1 + TEMPO_TOLERANCE)`, whatever its uncertainty (the score is a measure, not a
/// verdict).
pub(super) fn excess_of(tempo: &[PhaseTempo; 3]) -> f32 {
    tempo
        .iter()
        .map(|t| {
            excess(
                libm::fabsf(libm::logf(t.ratio)),
                libm::logf(1.0 + TEMPO_TOLERANCE),
                TEMPO_SOFTNESS,
            )
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::{excess_of, ratio, tempo, Phase, Verdict};
    use crate::events::Event;
    use crate::score::align::tests::events;
    use crate::score::timing::Timing;

    fn timing(seconds: f32) -> Timing {
        Timing {
            event: [seconds; Event::COUNT],
            top_gain: 0.0,
            paused: false,
        }
    }

    #[test]
    fn a_phase_past_its_tolerance_by_its_uncertainty_is_slow_or_fast() {
        // At 100 Hz: the coach's backswing 0.8 s, downswing 0.3 s, follow-through 0.6 s; the
        // student's backswing 1.2 s (50 % slower), downswing 0.23 s, follow-through 0.64 s.
        let coach = events([0, 20, 50, 80, 95, 110, 140, 170]);
        let student = events([0, 30, 70, 120, 132, 143, 180, 207]);
        let [back, down, through] = tempo((&student, 100.0), (&coach, 100.0), &timing(0.005));
        assert_eq!(back.phase, Phase::Backswing);
        assert!((back.ratio - 1.5).abs() < 1e-5 && back.verdict == Verdict::Slow);
        assert!((down.ratio - 23.0 / 30.0).abs() < 1e-5 && down.verdict == Verdict::Fast);
        assert_eq!(through.verdict, Verdict::Ok);
        // With 100 ms of timing uncertainty the downswing's 23 % is within it.
        let [back, down, _] = tempo((&student, 100.0), (&coach, 100.0), &timing(0.1));
        assert_eq!((back.verdict, down.verdict), (Verdict::Slow, Verdict::Ok));
        assert!((ratio(&coach, 100.0) - 0.8 / 0.3).abs() < 1e-5);
        // The same swing costs the score nothing; a slower one costs.
        let same = tempo((&coach, 100.0), (&coach, 100.0), &timing(0.005));
        assert_eq!(excess_of(&same), 0.0);
        assert!(excess_of(&[back, down, through]) > 0.2);
    }
}
