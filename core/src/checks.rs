//! Body checks: the few body metrics advice speaks of, each at one P-position, the student's
//! against the coach's.
//!
//! A check compares how a metric has **changed since address** (P1), the student's against
//! the virtual coach's: a bias of the input that holds for the whole swing (where a keypoint
//! model puts the elbow, the heading of a camera or of the sensors) is no fault, as the joint
//! comparison leaves out each joint's usual offset. A check is advice when the difference is
//! past the larger of its [`Measure::tolerance`] and [`crate::score::NOISE_FACTOR`] times its
//! uncertainty ([`crate::score::Advice::severity_of_check`]), ranked with the tempo and joint
//! items by that ratio.
//!
//! The tolerances are how far a golfer may differ from the coach before a coach would say
//! so, round numbers chosen once, not fitted to any benchmark: 5 cm of shift, as for a joint
//! ([`crate::score::SPATIAL_THRESHOLD_M`]), 10° of turn, 15° of lead-elbow bend.
//!
//! The uncertainty is how much the change could read differently with no fault: each joint the
//! metrics are measured from moved by the input's noise along each stance axis (the lower
//! quartile of the joints' wander on that axis, so a camera's depth axis counts as it is, while
//! a fault that lasts most of the swing, widening its own joints' wander, does not), at the
//! position and at address (`√2`), and how much the coach's change moves within the event's
//! timing uncertainty.

use crate::body::{Measure, Metrics};
use crate::config::MAX_CHECKS;
use crate::events::Position;

/// Most a turn may differ from the coach's before it is advice, degrees.
pub const TURN_TOLERANCE_DEG: f32 = 10.0;
/// Most the lead elbow's bend may differ from the coach's before it is advice, degrees.
pub const ELBOW_TOLERANCE_DEG: f32 = 15.0;
/// Most a shift may differ from the coach's before it is advice, metres.
pub const SHIFT_TOLERANCE_M: f32 = 0.05;

impl Measure {
    /// How far the student's change may differ from the coach's before it is advice, in its
    /// unit.
    pub const fn tolerance(self) -> f32 {
        match self {
            Measure::ThoraxTurn | Measure::PelvisTurn => TURN_TOLERANCE_DEG,
            Measure::LeadElbow => ELBOW_TOLERANCE_DEG,
            Measure::PelvisSway | Measure::PelvisThrust | Measure::HeadLift => SHIFT_TOLERANCE_M,
        }
    }

    /// The words of advice: whose, the verb, the word for a positive and for a negative
    /// change, and what the change is counted from.
    const fn words(self) -> (&'static str, &'static str, [&'static str; 2], &'static str) {
        const SINCE: &str = "since address";
        match self {
            Measure::ThoraxTurn => ("shoulders", "have turned", ["back", "open"], SINCE),
            Measure::PelvisTurn => ("hips", "have turned", ["back", "open"], SINCE),
            Measure::PelvisSway => (
                "hips",
                "have moved",
                ["toward the target", "away from the target"],
                SINCE,
            ),
            Measure::PelvisThrust => (
                "hips",
                "have moved",
                ["toward the ball", "away from the ball"],
                SINCE,
            ),
            Measure::HeadLift => ("head", "has moved", ["up", "down"], SINCE),
            Measure::LeadElbow => (
                "lead elbow",
                "is",
                ["more bent", "straighter"],
                "than at address",
            ),
        }
    }
}

impl Measure {
    /// The words for a student's value past the coach's, more and less: what a difference of
    /// this measure is called.
    const fn compared(self) -> [&'static str; 2] {
        match self {
            Measure::ThoraxTurn | Measure::PelvisTurn => ["more closed", "more open"],
            Measure::PelvisSway => ["farther toward the target", "farther from the target"],
            Measure::PelvisThrust => ["closer to the ball", "farther from the ball"],
            Measure::HeadLift => ["higher", "lower"],
            Measure::LeadElbow => ["more bent", "straighter"],
        }
    }
}

/// One measure at one position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Check {
    /// Where.
    pub position: Position,
    /// What.
    pub measure: Measure,
}

/// Every check, in the order reports list them: at the top (P4) the turns, the hips' sway, the
/// head and the lead arm; at impact (P7) the hips' thrust, sway and turn and the head.
pub const CHECKS: [Check; MAX_CHECKS] = {
    use Measure::*;
    use Position::*;
    const fn at(position: Position, measure: Measure) -> Check {
        Check { position, measure }
    }
    [
        at(P4, ThoraxTurn),
        at(P4, PelvisTurn),
        at(P4, PelvisSway),
        at(P4, HeadLift),
        at(P4, LeadElbow),
        at(P7, PelvisThrust),
        at(P7, PelvisSway),
        at(P7, PelvisTurn),
        at(P7, HeadLift),
    ]
};

impl Check {
    /// Its index in [`CHECKS`] (`None` for a check no report makes).
    pub fn index(self) -> Option<usize> {
        CHECKS.iter().position(|c| *c == self)
    }

    /// How its measure changed from `address`'s metrics to `at`'s (shifts are counted from
    /// address already, and read 0 there).
    pub fn change(self, address: &Metrics, at: &Metrics) -> Option<f32> {
        Some(self.measure.of(at)? - self.measure.of(address)?)
    }

    /// What coaches call the student's change when it is past the coach's by `more` (the
    /// student's less the coach's), where they have a name for it.
    pub fn fault(self, more: f32) -> Option<&'static str> {
        use Measure::*;
        match (self.position, self.measure, more > 0.0) {
            (Position::P4, ThoraxTurn, false) => Some("a short turn"),
            (Position::P4, PelvisSway, false) => Some("a sway"),
            (Position::P4, HeadLift, false) => Some("a dipping head"),
            (Position::P4, LeadElbow, true) => Some("a bent lead arm"),
            (Position::P7, PelvisThrust, true) => Some("early extension"),
            (Position::P7, PelvisSway, true) => Some("a slide"),
            (Position::P7, HeadLift, true) => Some("standing up"),
            _ => None,
        }
    }
}

/// A check's outcome: the student's and the coach's change since address (degrees or metres,
/// as [`Measure::in_degrees`] says) and the uncertainty of the student's.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct BodyDeviation {
    /// The check.
    pub check: Check,
    /// The student's change.
    pub student: f32,
    /// The coach's change.
    pub coach: f32,
    /// The uncertainty of the difference (one standard deviation; see the [module
    /// documentation](self)).
    pub uncertainty: f32,
}

impl Check {
    /// The words at its position: "the top (P4)", "impact (P7)".
    fn moment(self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let moment = match self.position {
            Position::P1 => "address",
            Position::P4 => "the top",
            Position::P7 => "impact",
            Position::P10 => "the finish",
            other => other.moment(),
        };
        write!(f, "{moment} ({})", self.position.name())
    }

    /// "at impact (P7) your hips are 20° more closed than the coach's": the student's value
    /// `by` past the coach's (whole degrees or centimetres, as [`Measure::in_degrees`] says),
    /// as a clause of another sentence.
    pub fn difference(self, f: &mut core::fmt::Formatter<'_>, by: i8) -> core::fmt::Result {
        let (whose, verb, _, _) = self.measure.words();
        let [more, less] = self.measure.compared();
        let unit = if self.measure.in_degrees() {
            "°"
        } else {
            " cm"
        };
        let is = if verb.starts_with("have") {
            "are"
        } else {
            "is"
        };
        f.write_str("at ")?;
        self.moment(f)?;
        let way = if by > 0 { more } else { less };
        write!(
            f,
            " your {whose} {is} {}{unit} {way} than the coach's",
            by.unsigned_abs()
        )
    }
}

impl BodyDeviation {
    /// Its sentence without the full stop, for advice to go on from.
    pub fn sentence(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let measure = self.check.measure;
        let (whose, verb, [more, less], from) = measure.words();
        let (unit, scale) = match measure.in_degrees() {
            true => ("°", 1.0),
            false => (" cm", 100.0),
        };
        let amount = |f: &mut core::fmt::Formatter<'_>, value: f32, within: Option<f32>| {
            let whole = libm::roundf(libm::fabsf(value) * scale) as u32;
            write!(f, "{whole}")?;
            if let Some(u) = within {
                write!(f, " ± {}", (libm::ceilf(u * scale) as u32).max(1))?;
            }
            f.write_str(unit)?;
            match (whole, value > 0.0) {
                (0, _) => Ok(()),
                (_, true) => write!(f, " {more}"),
                (_, false) => write!(f, " {less}"),
            }
        };
        f.write_str("At ")?;
        self.check.moment(f)?;
        write!(f, " your {whose} {verb} ")?;
        amount(f, self.student, Some(self.uncertainty))?;
        write!(f, " {from}, against the coach's ")?;
        amount(f, self.coach, None)?;
        if let Some(fault) = self.check.fault(self.student - self.coach) {
            write!(f, ": {fault}")?;
        }
        Ok(())
    }
}

impl core::fmt::Display for BodyDeviation {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.sentence(f)?;
        f.write_str(".")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deviation(check: usize, student: f32, coach: f32, uncertainty: f32) -> BodyDeviation {
        BodyDeviation {
            check: CHECKS[check],
            student,
            coach,
            uncertainty,
        }
    }

    #[test]
    fn advice_reads_as_a_coach_says_it() {
        let short = deviation(0, 78.2, 95.0, 3.4);
        assert_eq!(
            short.to_string(),
            "At the top (P4) your shoulders have turned 78 ± 4° back since address, against the \
             coach's 95° back: a short turn."
        );
        let early = deviation(5, 0.091, -0.02, 0.012);
        assert_eq!(
            early.to_string(),
            "At impact (P7) your hips have moved 9 ± 2 cm toward the ball since address, \
             against the coach's 2 cm away from the ball: early extension."
        );
        let elbow = deviation(4, 31.0, 4.0, 0.2);
        assert_eq!(
            elbow.to_string(),
            "At the top (P4) your lead elbow is 31 ± 1° more bent than at address, against the \
             coach's 4° more bent: a bent lead arm."
        );
        // No fault named the other way, and no direction for nothing.
        let wide = deviation(2, 0.004, -0.08, 0.01);
        assert_eq!(
            wide.to_string(),
            "At the top (P4) your hips have moved 0 ± 1 cm since address, against the coach's \
             8 cm away from the target."
        );
    }

    #[test]
    fn a_change_is_counted_from_address() {
        let address = Metrics {
            lead_elbow: 38.0,
            thorax: crate::body::Angles {
                turn: 3.0,
                ..Default::default()
            },
            ..Default::default()
        };
        let mut top = address;
        top.lead_elbow = 50.0;
        top.thorax.turn = 93.0;
        top.pelvis_shift.sway = -0.04;
        let change = |i: usize| CHECKS[i].change(&address, &top);
        assert_eq!(change(0), Some(90.0));
        assert_eq!(change(4), Some(12.0));
        assert_eq!(change(2), Some(-0.04));
        // No head, no head check.
        assert_eq!(change(3), None);
    }

    #[test]
    fn every_check_is_at_a_position_that_is_an_event() {
        for check in CHECKS {
            assert!(check.position.event().is_some(), "{check:?}");
        }
    }
}
