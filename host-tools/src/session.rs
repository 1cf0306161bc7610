//! A range session's tendencies ([`posecoach_core::session`]) as text and as JSON: the same
//! shape as a swing's report, its values the session's estimates, with how many swings were
//! used, which were set aside and why, and each metric's swing-to-swing spread.

use crate::table::decimal;
use posecoach_core::checks::CHECKS;
use posecoach_core::score::{Advice, Phase, Verdict};
use posecoach_core::sequence::GAPS;
use posecoach_core::session::{Quantity, SetAside, Tendencies, Tendency, TOUR_BACKSWING_SPREAD_S};
use posecoach_core::tally::Estimate;
use serde_json::{json, Value};
use std::fmt::Write;

/// `quantity`'s name in reports: `backswing`, `pause`, `thorax_turn_p4`, `pelvis_thorax_gap`,
/// `left_wrist_toward_ball_top`.
pub fn name(session: &Tendencies<'_>, quantity: Quantity) -> String {
    match quantity {
        Quantity::Tempo(phase) => phase.name().to_string(),
        Quantity::Pause => "pause".to_string(),
        Quantity::Check(i) => {
            let c = CHECKS[i];
            format!("{}_{}", c.measure.name(), c.position.name().to_lowercase())
        }
        Quantity::Gap(i) => format!("{}_{}_gap", GAPS[i].0.name(), GAPS[i].1.name()),
        Quantity::Offset(event, k, axis) => {
            let joint = session.joint(k).map_or("joint", |j| j.name());
            let axis = ["toward_target", "toward_ball", "up"][axis.min(2)];
            format!("{joint}_{axis}_{}", event.name())
        }
    }
}

/// `quantity` in words: "your backswing", "your left wrist's place toward the target".
fn words(session: &Tendencies<'_>, quantity: Quantity) -> String {
    match quantity {
        Quantity::Offset(_, k, axis) => format!(
            "your {}'s place {}",
            session
                .joint(k)
                .map_or("joint", |j| j.name())
                .replace('_', " "),
            ["along the target line", "toward the ball", "up and down"][axis.min(2)]
        ),
        Quantity::Pause => "your pause at the top".to_string(),
        q => format!("your {}", name(session, q).replace('_', " ")),
    }
}

/// Why a swing was set aside, in words.
pub fn reason(session: &Tendencies<'_>, s: &SetAside) -> String {
    format!(
        "unlike the session's other swings in {} body-level measures, most in {} ({:.1} standard deviations off)",
        s.unlike,
        name(session, s.worst),
        s.z.abs()
    )
}

/// An estimate's statistics, scaled to the report's unit by `scale`, to `places` decimals.
fn stats(e: &Estimate, scale: f32, places: i32) -> Value {
    json!({
        "value": decimal(e.value * scale, places),
        "uncertainty": finite(e.uncertainty * scale, places),
        "spread": decimal(e.spread * scale, places),
        "noise": decimal(e.noise * scale, places),
        "swings": e.n, "above": e.above, "below": e.below,
    })
}

/// `v` rounded, or null where no interval exists yet.
fn finite(v: f32, places: i32) -> Value {
    match v.is_finite() {
        true => json!(decimal(v, places)),
        false => Value::Null,
    }
}

/// The session in the documented JSON shape (docs/SESSION.md).
pub fn to_json(session: &Tendencies<'_>) -> Value {
    let advice = session.advice();
    let phases: Vec<Value> = Phase::ALL
        .iter()
        .filter_map(|&phase| {
            let q = Quantity::Tempo(phase);
            let e = session.estimate(q).filter(|e| e.n > 0)?;
            let coach = session.coach(q).unwrap_or(0.0);
            let ratio = e.value.exp();
            let verdict = match (e.clears(q.tolerance()), e.value > 0.0) {
                (false, _) => Verdict::Ok,
                (true, true) => Verdict::Slow,
                (true, false) => Verdict::Fast,
            };
            Some(json!({
                "phase": phase.name(), "student_s": decimal(coach * ratio, 3),
                "coach_s": decimal(coach, 3), "ratio": decimal(ratio, 3),
                "ratio_uncertainty": finite(ratio * e.uncertainty, 3),
                "verdict": verdict.name(),
                "spread_s": decimal(coach * ratio * e.spread, 3),
                "swings": e.n, "slow": e.above, "fast": e.below,
            }))
        })
        .collect();
    let pause = session
        .estimate(Quantity::Pause)
        .filter(|e| e.n > 0)
        .map(|e| stats(&e, 1.0, 3));
    let body_checks: Vec<Value> = (0..CHECKS.len())
        .filter_map(|i| {
            let q = Quantity::Check(i);
            let e = session.estimate(q).filter(|e| e.n > 0)?;
            let c = CHECKS[i];
            let (unit, scale) = match c.measure.in_degrees() {
                true => ("deg", 1.0),
                false => ("cm", 100.0),
            };
            let coach = session.coach(q).unwrap_or(0.0);
            let tenth = |v: f32| decimal(v * scale, 1);
            Some(json!({
                "position": c.position.name(), "measure": c.measure.name(), "unit": unit,
                "student": tenth(coach + e.value), "coach": tenth(coach),
                "uncertainty": finite(e.uncertainty * scale, 1), "tolerance": tenth(q.tolerance()),
                "spread": tenth(e.spread), "swings": e.n, "above": e.above, "below": e.below,
                "advice": e.clears(q.tolerance()),
            }))
        })
        .collect();
    let gaps: Vec<Value> = (0..GAPS.len())
        .filter_map(|i| {
            let q = Quantity::Gap(i);
            let e = session.estimate(q).filter(|e| e.n > 0)?;
            let coach = session.coach(q).unwrap_or(0.0);
            let ms = |v: f32| decimal(v * 1000.0, 0);
            Some(json!({
                "first": GAPS[i].0.name(), "then": GAPS[i].1.name(),
                "student_ms": ms(coach + e.value), "coach_ms": ms(coach),
                "uncertainty_ms": finite(e.uncertainty * 1000.0, 0), "tolerance_ms": ms(q.tolerance()),
                "spread_ms": ms(e.spread), "swings": e.n,
                "advice": e.clears(q.tolerance()),
            }))
        })
        .collect();
    let cm = |m: f32| decimal(m * 100.0, 1);
    let spatial: Vec<Value> = advice
        .iter()
        .filter_map(|t| match t.advice {
            Advice::Spatial(d) => Some(json!({
                "event": d.event.name(), "joint": d.joint.name(), "distance_cm": cm(d.distance_m),
                "uncertainty_cm": cm(d.uncertainty_m), "direction": d.direction.name(),
                "offset_cm": {"toward_target": cm(d.offset_m[0]), "toward_ball": cm(d.offset_m[1]), "up": cm(d.offset_m[2])},
                "swings": t.swings, "past": t.past,
            })),
            _ => None,
        })
        .collect();
    let open = session.open().map(|o| {
        json!({
            "quantity": name(session, o.quantity),
            "value": decimal(o.estimate.value, 4), "uncertainty": finite(o.estimate.uncertainty, 4),
            "tolerance": decimal(o.quantity.tolerance(), 4), "more_swings": o.more_swings,
        })
    });
    json!({
        "swings": session.swings(),
        "used": session.used(),
        "set_aside": session.set_aside().iter().map(|s| json!({
            "swing": s.swing, "unlike": s.unlike, "worst": name(session, s.worst),
            "z": decimal(s.z, 1), "reason": reason(session, s),
        })).collect::<Vec<_>>(),
        "tempo": {"phases": phases, "pause_s": pause},
        "body_checks": body_checks,
        "spatial": spatial,
        "kinematic_sequence": {"gaps": gaps},
        "advice": advice.iter().map(Tendency::to_string).collect::<Vec<_>>(),
        "open": open,
        "consistency": {
            "backswing_spread_s": backswing_spread(session).map(|s| decimal(s, 3)),
            "tour_backswing_spread_s": TOUR_BACKSWING_SPREAD_S,
        },
    })
}

/// The golfer's swing-to-swing spread of the backswing's duration net of the noise, seconds.
fn backswing_spread(session: &Tendencies<'_>) -> Option<f32> {
    let q = Quantity::Tempo(Phase::Backswing);
    let e = session.estimate(q).filter(|e| e.n >= 2)?;
    Reading::of(session, q)?.seconds(e.value, e.spread)
}

/// The session as readable lines: its swings, its tendencies (or its open question) and each
/// body-level metric with its spread.
pub fn to_text(session: &Tendencies<'_>) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "session: {} swings, {} used",
        session.swings(),
        session.used()
    );
    for s in session.set_aside() {
        let _ = writeln!(out, "  swing {} set aside: {}", s.swing, reason(session, s));
    }
    let advice = session.advice();
    if advice.is_empty() {
        let _ = write!(out, "  nothing is clear yet");
        match open_question(session) {
            Some(open) => {
                let _ = writeln!(out, ": {open}");
            }
            None => out.push('\n'),
        }
    }
    for (i, t) in advice.iter().enumerate() {
        let _ = writeln!(out, "  {}. {t}", i + 1);
    }
    let _ = writeln!(
        out,
        "  each metric: the session's estimate ± its uncertainty; spread: how much you vary from swing to swing, net of the noise"
    );
    for phase in Phase::ALL {
        let q = Quantity::Tempo(phase);
        if let (Some(e), Some(read)) = (
            session.estimate(q).filter(|e| e.n > 0),
            Reading::of(session, q),
        ) {
            let _ = write!(
                out,
                "    {:<22} x{} ± {} of the coach's {:.2} s, spread {}",
                phase.name(),
                read.number(e.value),
                read.amount(e.value, e.uncertainty),
                read.coach,
                read.spread(e.value, e.spread)
            );
            if phase == Phase::Backswing {
                let _ = write!(out, " (tour players: {TOUR_BACKSWING_SPREAD_S} s)");
            }
            out.push('\n');
        }
    }
    for q in Quantity::BODY_LEVEL
        .into_iter()
        .filter(|q| matches!(q, Quantity::Check(_) | Quantity::Gap(_)))
    {
        if let (Some(e), Some(read)) = (
            session.estimate(q).filter(|e| e.n > 0),
            Reading::of(session, q),
        ) {
            let _ = writeln!(
                out,
                "    {:<22} {} ± {} (coach {}), spread {}",
                name(session, q),
                read.number(e.value),
                read.amount(e.value, e.uncertainty),
                read.text(0.0),
                read.amount(e.value, e.spread)
            );
        }
    }
    out
}

/// The session's open question ([`Tendencies::open`]) in words: what it is, how far it lies
/// and about how many more swings would settle it.
pub fn open_question(session: &Tendencies<'_>) -> Option<String> {
    let o = session.open()?;
    Some(format!(
        "the nearest question is {} ({}); about {} more swings would settle it",
        words(session, o.quantity),
        open_value(&o.estimate, o.quantity),
        o.more_swings
    ))
}

/// An open question's value in words: a ratio, degrees, centimetres or milliseconds.
fn open_value(e: &Estimate, q: Quantity) -> String {
    match q {
        Quantity::Tempo(_) => format!("x{:.2} of the coach's", e.value.exp()),
        Quantity::Check(i) if CHECKS[i].measure.in_degrees() => {
            format!("{:+.0}° against the coach's", e.value)
        }
        Quantity::Check(_) => format!("{:+.1} cm against the coach's", e.value * 100.0),
        Quantity::Gap(_) | Quantity::Pause => {
            format!("{:+.0} ms against the coach's", e.value * 1000.0)
        }
        Quantity::Offset(event, ..) => {
            format!(
                "{:.1} cm off the coach's {}",
                e.value * 100.0,
                event.words()
            )
        }
    }
}

/// How a body-level quantity reads. The session keeps each against the coach's in its own unit
/// (`ln` of a phase's ratio; seconds, degrees or metres); a reader sees the student's value:
/// a phase's as its ratio to the coach's, the pause in seconds, a check in degrees or
/// centimetres, a gap in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// The coach's value, in the quantity's own unit (a phase's duration, seconds).
    pub coach: f32,
    /// The unit after a number: `°`, ` cm`, ` ms`, ` s`; none for a ratio.
    pub unit: &'static str,
    /// The quantity's own unit in the unit read (1 for a ratio).
    pub scale: f32,
    /// Decimals read.
    pub places: usize,
    /// Read as a ratio to the coach's (a phase's tempo).
    ratio: bool,
}

impl Reading {
    /// How `quantity` reads in `session`; `None` for a joint's offset.
    pub fn of(session: &Tendencies<'_>, quantity: Quantity) -> Option<Reading> {
        let (unit, scale, places) = match quantity {
            Quantity::Tempo(_) => ("", 1.0, 2),
            Quantity::Pause => (" s", 1.0, 2),
            Quantity::Check(i) if CHECKS.get(i)?.measure.in_degrees() => ("°", 1.0, 1),
            Quantity::Check(_) => (" cm", 100.0, 1),
            Quantity::Gap(_) => (" ms", 1000.0, 0),
            Quantity::Offset(..) => return None,
        };
        Some(Reading {
            coach: session.coach(quantity)?,
            unit,
            scale,
            places,
            ratio: matches!(quantity, Quantity::Tempo(_)),
        })
    }

    /// The student's value read, for `v` against the coach's in the quantity's own unit.
    pub fn value(&self, v: f32) -> f32 {
        match self.ratio {
            true => v.exp(),
            false => (self.coach + v) * self.scale,
        }
    }

    /// [`Reading::value`] as a bare number: `1.28`, `-52.7`.
    pub fn number(&self, v: f32) -> String {
        format!("{:.*}", self.places, self.value(v))
    }

    /// [`Reading::value`] with its unit: `×1.28`, `-52.7°`, `36 ms`.
    pub fn text(&self, v: f32) -> String {
        match self.ratio {
            true => format!("×{}", self.number(v)),
            false => format!("{}{}", self.number(v), self.unit),
        }
    }

    /// A width `d` about `v` (an uncertainty, a spread; the quantity's own unit) in the unit
    /// read, with it: a ratio's as a share of the ratio, `0.04`.
    pub fn amount(&self, v: f32, d: f32) -> String {
        match self.ratio {
            true => format!("{:.*}", self.places, v.exp() * d),
            false => format!("{:.*}{}", self.places, d * self.scale, self.unit),
        }
    }

    /// A phase's width `d` about `v` (`ln` of its ratio) in seconds of its duration; `None`
    /// for another quantity.
    pub fn seconds(&self, v: f32, d: f32) -> Option<f32> {
        self.ratio.then(|| self.coach * v.exp() * d)
    }

    /// A spread `d` about `v` (the golfer's, or the noise's), with its unit: a phase's in
    /// seconds of its duration.
    pub fn spread(&self, v: f32, d: f32) -> String {
        match self.seconds(v, d) {
            Some(s) => format!("{s:.3} s"),
            None => self.amount(v, d),
        }
    }
}
