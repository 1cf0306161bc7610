//! The advice stage: the report's items, most important first.
//!
//! Tempo verdicts, the sequence's gaps whose interval is wholly past their tolerance, body
//! checks past theirs and joint deviations, each ranked by its severity (how far past its
//! threshold it is, as a multiple of it); a joint item that states what a body item given at
//! its event states is left out (a check at impact that a gap explains is already under the
//! gap: the `cause` stage).

use super::cause::{Cause, Explains, Item, Symptom};
use super::spatial::{severity, Deviation, Direction, NOISE_FACTOR};
use super::tempo::{Phase, PhaseTempo, Verdict, TEMPO_CONFIDENCE, TEMPO_TOLERANCE};
use crate::body::Measure;
use crate::checks::BodyDeviation;
use crate::config::{MAX_ADVICE, MAX_DEVIATIONS};
use crate::events::Side;
use crate::joint::Joint;
use crate::sequence::{Gap, GAP_TOLERANCE_S};
use heapless::Vec as HVec;

/// One piece of advice; [`core::fmt::Display`] renders it as a sentence.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub enum Advice {
    /// A phase too slow or fast.
    Tempo(PhaseTempo),
    /// A joint off at an event that no body-level item explains.
    Spatial(Deviation),
    /// A body metric's change since address off the coach's at a position, and the joint
    /// offsets it explains.
    Body(BodyDeviation, Explains),
    /// A gap between two links' peaks in the downswing off the coach's, and the joint offsets
    /// it explains.
    Sequence(Gap, Explains),
}

impl Advice {
    /// Its rank, most important first: how far past its threshold it is, a cause ranked by
    /// the largest offset it explains where that is higher (see the `cause` stage).
    pub fn severity(&self) -> f32 {
        match self {
            Advice::Tempo(t) => {
                libm::fabsf(libm::logf(t.ratio)) / libm::logf(1.0 + TEMPO_TOLERANCE)
            }
            Advice::Spatial(d) => Advice::severity_of(d),
            Advice::Body(b, explains) => ranked(Advice::severity_of_check(b), explains),
            Advice::Sequence(g, explains) => ranked(Advice::severity_of_gap(g), explains),
        }
    }

    /// Whether a gap is advice: its interval, ± [`TEMPO_CONFIDENCE`] uncertainties, wholly
    /// past [`GAP_TOLERANCE_S`] from the coach's (a NaN gives none).
    pub fn is_clear(g: &Gap) -> bool {
        libm::fabsf(g.student_s - g.coach_s) - TEMPO_CONFIDENCE * g.uncertainty_s > GAP_TOLERANCE_S
    }

    /// A deviation's severity: how far past the larger of [`super::SPATIAL_THRESHOLD_M`] and
    /// [`NOISE_FACTOR`] times its uncertainty it is, as a multiple of that.
    pub fn severity_of(d: &Deviation) -> f32 {
        severity(d.distance_m, d.uncertainty_m)
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

    /// A gap's severity: its difference from the coach's over [`GAP_TOLERANCE_S`].
    pub fn severity_of_gap(g: &Gap) -> f32 {
        libm::fabsf(g.student_s - g.coach_s) / GAP_TOLERANCE_S
    }
}

/// A cause's own severity `own`, or that of the most severe offset or check it `explains`
/// where higher.
pub(crate) fn ranked(own: f32, explains: &Explains) -> f32 {
    own.max(explains.severity())
}

/// Writes "{at event} your {joint} is {cm} ± {u} cm {which way} than the coach's", the
/// event's words capitalized where `capital`.
fn joint_clause(f: &mut core::fmt::Formatter<'_>, d: &Symptom, capital: bool) -> core::fmt::Result {
    let event = d.event.words();
    let mut chars = event.chars();
    match (capital, chars.next()) {
        (true, Some(first)) => write!(f, "{}{}", first.to_ascii_uppercase(), chars.as_str())?,
        _ => f.write_str(event)?,
    }
    let cm = libm::roundf(d.distance_m * 100.0) as u32;
    let within = (libm::ceilf(d.uncertainty_m * 100.0) as u32).max(1);
    f.write_str(" your ")?;
    for (i, word) in d.joint.name().split('_').enumerate() {
        write!(f, "{}{word}", if i > 0 { " " } else { "" })?;
    }
    write!(
        f,
        " is {cm} ± {within} cm {} than the coach's",
        d.direction.comparative()
    )
}

/// Writes what a cause explains, if anything: ", which is why ...".
fn explained(f: &mut core::fmt::Formatter<'_>, explains: &Explains) -> core::fmt::Result {
    let mut then = ", which is why ";
    if let Some(check) = explains.check {
        f.write_str(then)?;
        check.difference(f, explains.by)?;
        then = ", and ";
    }
    let Some(worst) = &explains.worst else {
        return Ok(());
    };
    f.write_str(then)?;
    joint_clause(f, worst, false)?;
    match explains.joints.saturating_sub(1) {
        0 => Ok(()),
        1 => f.write_str(" (and one more joint with it)"),
        n => write!(f, " (and {n} more joints with it)"),
    }
}

impl Advice {
    /// Its sentence without the full stop, for a session's evidence to go on from.
    pub fn sentence(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
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
                write!(f, "Your {phase} is {percent} ± {within}% {adjective} than the coach's ({:.2} s against {:.2} s): {hint}", t.student_s, t.coach_s)
            }
            Advice::Spatial(d) => joint_clause(f, &Symptom::from(d), true),
            Advice::Body(b, explains) => {
                b.sentence(f)?;
                explained(f, explains)
            }
            Advice::Sequence(g, explains) => {
                g.sentence(f)?;
                explained(f, explains)
            }
        }
    }
}

impl core::fmt::Display for Advice {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.sentence(f)?;
        f.write_str(".")
    }
}

/// The advice of one swing whose lead side is `lead`: its tempo verdicts, its `causes` (a
/// joint item that states what a body item at its event states folded under it) and the joint
/// deviations no cause explains, each ranked by [`Advice::severity`].
pub(super) fn advise(
    tempo: &[PhaseTempo; 3],
    causes: &mut [Cause],
    spatial: &HVec<Deviation, MAX_DEVIATIONS>,
    lead: Side,
) -> HVec<Advice, MAX_ADVICE> {
    let mut advice: HVec<Advice, MAX_ADVICE> = HVec::new();
    for t in tempo.iter().filter(|t| t.verdict != Verdict::Ok) {
        insert_sorted(&mut advice, Advice::Tempo(*t), Advice::severity);
    }
    for d in spatial {
        let stating = causes.iter_mut().find(|c| {
            matches!(c.item, Item::Check(b) if b.check.position.event() == Some(d.event)
                && states(b.check.measure, d, lead))
        });
        match stating {
            Some(cause) => cause.explains.add(d),
            None => insert_sorted(&mut advice, Advice::Spatial(*d), Advice::severity),
        }
    }
    for c in causes.iter() {
        let item = match c.item {
            Item::Check(b) => Advice::Body(b, c.explains),
            Item::Gap(g) => Advice::Sequence(g, c.explains),
        };
        insert_sorted(&mut advice, item, Advice::severity);
    }
    advice
}

/// Whether joint item `d` (of a golfer whose lead side is `lead`) states the fact a body item
/// of `measure` states: then it is left out of the advice where the body item is in it.
pub(super) fn states(measure: Measure, d: &Deviation, lead: Side) -> bool {
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
pub(crate) fn insert_sorted<T: Copy, const N: usize>(
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
    use crate::score::{Phase, PhaseTempo, Verdict};

    /// Every phase as long as the coach's.
    fn on_tempo() -> [PhaseTempo; 3] {
        Phase::ALL.map(|phase| PhaseTempo {
            phase,
            student_s: 1.0,
            coach_s: 1.0,
            ratio: 1.0,
            ratio_uncertainty: 0.01,
            verdict: Verdict::Ok,
        })
    }
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

    #[test]
    fn a_cause_folds_the_joint_item_it_states_and_ranks_above_it() {
        use super::{advise, Advice};
        use crate::events::{Event, Side};
        use crate::joint::Joint;
        use crate::score::cause::causes;
        use crate::score::{Deviation, Direction};
        // A thorax turn 14° short at the top (severity 1.4) and the left shoulder 20 cm toward
        // the target there (severity 4), which the turn states; the right knee 12 cm lower
        // halfway down, which it does not.
        let body = [BodyDeviation {
            check: CHECKS[0],
            student: 81.0,
            coach: 95.0,
            uncertainty: 1.0,
        }];
        let mut causes = causes(&body, &[0.0], &[]);
        let joint = |event, joint, direction, distance_m| Deviation {
            event,
            joint,
            distance_m,
            uncertainty_m: 0.01,
            offset_m: [distance_m, 0.0, 0.0],
            direction,
        };
        let spatial = [
            joint(
                Event::Top,
                Joint::LeftShoulder,
                Direction::TowardTarget,
                0.2,
            ),
            joint(Event::MidDownswing, Joint::RightKnee, Direction::Down, 0.12),
        ]
        .into_iter()
        .collect();
        let tempo = on_tempo();
        let advice = advise(&tempo, &mut causes, &spatial, Side::Left);
        assert_eq!(advice.len(), 2, "{advice:?}");
        let Advice::Body(b, explains) = advice[0] else {
            panic!("{advice:?}");
        };
        assert_eq!(b.check, CHECKS[0]);
        assert_eq!(explains.joints, 1);
        assert!((advice[0].severity() - 4.0).abs() < 1e-5);
        assert!(matches!(advice[1], Advice::Spatial(d) if d.joint == Joint::RightKnee));
        assert!(
            advice[0].to_string().ends_with(
                ": a short turn, which is why at the top your left shoulder is 20 ± 1 cm closer \
                 to the target than the coach's."
            ),
            "{}",
            advice[0]
        );
    }

    #[test]
    fn a_clear_gap_folds_the_hips_turn_at_impact_it_moves_and_ranks_by_it() {
        use super::{advise, Advice};
        use crate::body::Link;
        use crate::events::Side;
        use crate::score::cause::causes;
        use crate::sequence::Gap;
        // The hips peak 5 ms after the chest against the coach's 40 ms before (45 ms less,
        // severity 1.5), and at impact (CHECKS[7]) are 20° less open than the coach's (severity
        // 2) while the coach's open at 400°/s: the gap accounts for 18°. A lead elbow 20° more
        // bent at the top (CHECKS[4]) is not the gap's.
        let gap = Gap {
            first: Link::Pelvis,
            then: Link::Thorax,
            student_s: -0.005,
            coach_s: 0.04,
            uncertainty_s: 0.004,
        };
        let check = |i: usize, student: f32, coach: f32| BodyDeviation {
            check: CHECKS[i],
            student,
            coach,
            uncertainty: 1.0,
        };
        let tempo = on_tempo();
        let advise_on = |body: &[BodyDeviation], rates: &[f32]| {
            let mut causes = causes(body, rates, &[gap]);
            advise(&tempo, &mut causes, &Default::default(), Side::Left)
        };
        let body = [check(4, 40.0, 20.0), check(7, -33.0, -53.0)];
        let advice = advise_on(&body, &[0.0, -400.0]);
        assert_eq!(advice.len(), 2, "{advice:?}");
        let Advice::Sequence(g, explains) = advice[0] else {
            panic!("{advice:?}");
        };
        assert_eq!((g, explains.check, explains.by), (gap, Some(CHECKS[7]), 20));
        assert!((advice[0].severity() - 2.0).abs() < 1e-5, "{advice:?}");
        assert!(matches!(advice[1], Advice::Body(b, _) if b.check == CHECKS[4]));
        assert_eq!(
            advice[0].to_string(),
            "In the downswing your hips peak 5 ± 4 ms after your chest, against the coach's 40 \
             ms before: the upper body starts the downswing, which is why at impact (P7) your \
             hips are 20° more closed than the coach's."
        );
        // Turned 30° less open, the hips are more than the gap explains: a cause of their own.
        let body = [check(7, -23.0, -53.0)];
        let advice = advise_on(&body, &[-400.0]);
        assert!(
            matches!(advice[0], Advice::Body(b, _) if b.check == CHECKS[7]),
            "{advice:?}"
        );
        assert!(matches!(advice[1], Advice::Sequence(_, e) if e.check.is_none()));
        // Where the coach's hips stood still at impact the gap explains nothing of them.
        let advice = advise_on(&[check(7, -38.0, -53.0)], &[0.0]);
        assert!(
            advice
                .iter()
                .any(|a| matches!(a, Advice::Body(b, _) if b.check == CHECKS[7]))
                && advice
                    .iter()
                    .all(|a| !matches!(a, Advice::Sequence(_, e) if e.check.is_some())),
            "{advice:?}"
        );
    }
}
