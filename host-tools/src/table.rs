//! The body table and the kinematic sequence as the reports print them: each of the student's
//! values with its uncertainty, and whether the input's noise swamps it.

use posecoach_core::body::{InputError, Metrics};
use posecoach_core::checks::{ELBOW_TOLERANCE_DEG, SHIFT_TOLERANCE_M, TURN_TOLERANCE_DEG};
use posecoach_core::events::Position;
use posecoach_core::score::{Report, TEMPO_CONFIDENCE};
use posecoach_core::sequence::{Peak, GAP_TOLERANCE_S};

/// One P-position of the body table: both swings' metrics there (`None` where a swing has no
/// such position) and the uncertainty of the student's (one standard deviation each).
#[derive(Clone, Copy, Debug)]
pub struct BodyRow {
    /// Which.
    pub position: Position,
    /// The student's metrics.
    pub student: Option<Metrics>,
    /// Their uncertainties.
    pub spread: Option<Metrics>,
    /// The coach's.
    pub coach: Option<Metrics>,
}

/// How the input of the swing `report` scored (at `hz`) may err, as its noise and timing stages
/// found: its noise per stance axis, and how early or late each P-position may have been
/// found: its event's uncertainty, and for P6 and P9, which are no events, the larger of the
/// two events' around them.
pub fn input_error(report: &Report, hz: f32) -> InputError {
    let timing = report.input.timing_s();
    let of = |p: Position| p.event().map_or(0.0, |e| timing[e as usize]);
    let seconds = |position| match position {
        Position::P6 => of(Position::P5).max(of(Position::P7)),
        Position::P9 => of(Position::P8).max(of(Position::P10)),
        p => of(p),
    };
    InputError {
        noise_m: report.input.noise_m(),
        timing: Position::ALL.map(|p| seconds(p) * hz),
    }
}

/// What a report says of its "±" and of the values the noise swamps (marked "?" in text, grey
/// in HTML): see [`swamped`].
pub const PLUS_MINUS: &str = "± is one standard deviation: how far the input's noise and how \
     early or late each position was found may have moved your value (the coach's is exact). \
     Marked ? (grey on the page): ± 1.65 of them is wider than the least difference the advice \
     acts on (10°, 15° at the elbow, 5 cm; 30 ms for a peak's time), so the input cannot tell it.";

/// A body metric the reports and the coaching benchmark single out: its name, its unit, the
/// least difference advice acts on in that unit (a turn's tolerance for an angle, the
/// elbow's its own, a shift's for a shift) and its value (shifts in cm).
pub type KeyMetric = (&'static str, &'static str, f32, fn(&Metrics) -> f32);

/// An angle's tolerance in a [`KeyMetric`], degrees.
pub const DEG: f32 = TURN_TOLERANCE_DEG;
/// A shift's tolerance in a [`KeyMetric`], cm.
pub const CM: f32 = SHIFT_TOLERANCE_M * 100.0;

/// The body metrics the text report's table shows and the coaching benchmark measures.
pub const KEY_METRICS: [KeyMetric; 10] = [
    ("pelvis_turn", "deg", DEG, |m| m.pelvis.turn),
    ("thorax_turn", "deg", DEG, |m| m.thorax.turn),
    ("x_factor", "deg", DEG, |m| m.x_factor),
    ("thorax_bend", "deg", DEG, |m| m.thorax.bend),
    ("thorax_side_bend", "deg", DEG, |m| m.thorax.side_bend),
    ("spine", "deg", DEG, |m| m.spine),
    ("pelvis_sway", "cm", CM, |m| m.pelvis_shift.sway * 100.0),
    ("pelvis_thrust", "cm", CM, |m| m.pelvis_shift.thrust * 100.0),
    ("pelvis_lift", "cm", CM, |m| m.pelvis_shift.lift * 100.0),
    ("lead_elbow", "deg", ELBOW_TOLERANCE_DEG, |m| m.lead_elbow),
];

/// `value` of a swing's metrics at a position, to the whole degree or centimetre; "-" where
/// the swing has no such position.
pub fn whole(metrics: Option<Metrics>, value: fn(&Metrics) -> f32) -> String {
    metrics.map_or("-".to_string(), |m| {
        format!("{:.0}", value(&m).round() + 0.0)
    })
}

/// Whether the noise swamps a value of `metric` whose uncertainty is `spread` (one standard
/// deviation, in the metric's unit): its interval, ± [`TEMPO_CONFIDENCE`] uncertainties, is
/// wider than the least difference advice acts on, so the input cannot tell that difference.
pub fn swamped(metric: &KeyMetric, spread: f32) -> bool {
    spread.is_nan() || TEMPO_CONFIDENCE * spread > metric.2
}

/// The student's `metric` at a position of the body table with its uncertainty, to the whole
/// degree or centimetre ("-" where the swing has no such position), and whether the noise
/// swamps it ([`swamped`]).
pub fn with_spread(row: &BodyRow, metric: &KeyMetric) -> (String, bool) {
    let value = metric.3;
    match (row.student, row.spread) {
        (Some(m), Some(s)) => (
            format!("{:.0} ± {:.0}", value(&m).round() + 0.0, value(&s)),
            swamped(metric, value(&s)),
        ),
        (m, _) => (whole(m, value), false),
    }
}

/// A peak of a kinematic sequence as the reports print it: its speed (degrees per second) and
/// its time after the swing's `top` (ms; frames at `hz`), each with its uncertainty unless
/// `exact` (the coach's), and whether the noise swamps it: its time's interval, ±
/// [`TEMPO_CONFIDENCE`] uncertainties, is wider than the gaps' tolerance, or it has none.
pub fn peak_text(p: &Peak, top: f32, hz: f32, exact: bool) -> (String, bool) {
    let ms = |frames: f32| frames / hz * 1000.0;
    match (exact, p.uncertainty) {
        (true, _) => (format!("{:.0} at {:.0}", p.speed, ms(p.time - top)), false),
        (false, Some(u)) => (
            format!(
                "{:.0} ± {:.0} at {:.0} ± {:.0}",
                p.speed,
                u.speed,
                ms(p.time - top),
                ms(u.time)
            ),
            u.time.is_nan() || TEMPO_CONFIDENCE * ms(u.time) > GAP_TOLERANCE_S * 1000.0,
        ),
        (false, None) => (
            format!("{:.0} at {:.0} (±?)", p.speed, ms(p.time - top)),
            true,
        ),
    }
}

/// `value` rounded to `places` decimals, as reports print a measured number: to what it means
/// (a score to 0.1 point, seconds to the ms), not as a widened `f32`'s digits.
pub fn decimal(value: f32, places: i32) -> f64 {
    let scale = 10f64.powi(places);
    (f64::from(value) * scale).round() / scale
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_core::sequence::Spread;

    #[test]
    fn a_value_is_swamped_where_its_interval_is_wider_than_the_tolerance() {
        let turn = &KEY_METRICS[0];
        assert_eq!(turn.2, 10.0);
        // 1.65 × 6 = 9.9 is within 10°, 1.65 × 6.1 is not; no uncertainty is no evidence.
        assert!(!swamped(turn, 6.0));
        assert!(swamped(turn, 6.1));
        assert!(swamped(turn, f32::NAN));
        let mut metrics = Metrics::default();
        metrics.pelvis.turn = -10.4;
        let mut spread = Metrics::default();
        spread.pelvis.turn = 26.0;
        let row = BodyRow {
            position: Position::P1,
            student: Some(metrics),
            spread: Some(spread),
            coach: None,
        };
        assert_eq!(with_spread(&row, turn), ("-10 ± 26".to_string(), true));
        let row = BodyRow {
            spread: None,
            ..row
        };
        assert_eq!(with_spread(&row, turn), ("-10".to_string(), false));
    }

    #[test]
    fn a_peak_is_swamped_where_its_time_cannot_tell_the_gaps_tolerance() {
        // At 60 Hz a frame is 16.7 ms: 1.65 × 1 frame = 27.5 ms is within 30 ms.
        let peak = |time: Option<f32>| Peak {
            speed: 500.0,
            time: 30.0,
            uncertainty: time.map(|time| Spread { speed: 40.0, time }),
        };
        assert_eq!(
            peak_text(&peak(Some(1.0)), 20.0, 60.0, false),
            ("500 ± 40 at 167 ± 17".to_string(), false)
        );
        assert!(peak_text(&peak(Some(1.2)), 20.0, 60.0, false).1);
        assert!(peak_text(&peak(None), 20.0, 60.0, false).1);
        // The coach's is exact.
        assert_eq!(
            peak_text(&peak(None), 20.0, 60.0, true),
            ("500 at 167".to_string(), false)
        );
    }
}
