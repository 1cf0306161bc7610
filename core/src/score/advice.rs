//! The advice stage: the report's items, most important first.
//!
//! Tempo verdicts, the sequence's gaps whose interval is wholly past their tolerance, body
//! checks past theirs and joint deviations, each ranked by its severity (how far past its
//! threshold it is, as a multiple of it); a joint item that states what a body item given at
//! its event states is left out.

use super::spatial::{Deviation, Direction, NOISE_FACTOR, SPATIAL_THRESHOLD_M};
use super::tempo::{Phase, PhaseTempo, Verdict, TEMPO_CONFIDENCE, TEMPO_TOLERANCE};
use crate::body::Measure;
use crate::checks::BodyDeviation;
use crate::config::{MAX_CHECKS, MAX_DEVIATIONS, MAX_GAPS};
use crate::events::{Event, Side};
use crate::joint::Joint;
use crate::sequence::{Gap, GAP_TOLERANCE_S};
use heapless::Vec as HVec;

/// Most advice items a report holds.
pub const MAX_ADVICE: usize = 8;

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

/// The advice of one swing whose lead side is `lead`, from its stages' findings.
pub(super) fn advise(
    tempo: &[PhaseTempo; 3],
    gaps: &HVec<Gap, MAX_GAPS>,
    body: &HVec<BodyDeviation, MAX_CHECKS>,
    spatial: &HVec<Deviation, MAX_DEVIATIONS>,
    lead: Side,
) -> HVec<Advice, MAX_ADVICE> {
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
    for d in spatial {
        let stated = advice.iter().any(|a| {
            matches!(a, Advice::Body(b) if b.check.position.event() == Some(d.event)
                && states(b.check.measure, d, lead))
        });
        if !stated {
            insert_sorted(&mut advice, Advice::Spatial(*d), Advice::severity);
        }
    }
    advice
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

/// Inserts `item` into `list`, kept sorted by `key` descending; when full, the smallest goes.
#[inline(never)]
pub(super) fn insert_sorted<T: Copy, const N: usize>(
    list: &mut HVec<T, N>,
    item: T,
    key: impl Fn(&T) -> f32,
) {
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
    use super::Advice;
    use crate::checks::{BodyDeviation, CHECKS, SHIFT_TOLERANCE_M};
    use crate::score::SPATIAL_THRESHOLD_M;

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
}
