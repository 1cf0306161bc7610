//! A range session in the wire's compact form ([`SessionReport`]).

use super::{Quantity, Tendencies};
use crate::checks::CHECKS;
use crate::config::BODY_LEVEL;
use crate::events::Position;
use crate::score::Advice;
use crate::tally::Estimate;
use crate::wire::{SessionReport, WireMetric, WireOpen, WireSetAside, WireTendency};

/// `v` rounded, saturating at ±32 767.
fn signed(v: f32) -> i16 {
    libm::roundf(v).clamp(-32767.0, 32767.0) as i16
}

/// `v` rounded, saturating at 65 535 (an infinite uncertainty: none yet).
fn unsigned(v: f32) -> u16 {
    libm::roundf(v).clamp(0.0, f32::from(u16::MAX)) as u16
}

/// The wire's unit per the quantity's own: a millisecond per second, a tenth of a degree per
/// degree, a millimetre per metre.
fn scale(q: Quantity) -> f32 {
    match q {
        Quantity::Check(i) if CHECKS.get(i).is_some_and(|c| c.measure.in_degrees()) => 10.0,
        _ => 1000.0,
    }
}

/// The index of body-level quantity `q` on the wire.
fn index(q: Quantity) -> u8 {
    q.body_level().map_or(BODY_LEVEL as u8, |i| i as u8)
}

impl Tendencies<'_> {
    /// The wire form of the session, its swings scored against coach reference `coach`
    /// (`u16::MAX` before its first swing): each body-level quantity's estimate with the
    /// student's value in [`crate::wire::SwingReport`]'s units, its tendencies in order with
    /// the joint offsets they name, the swings set aside and the open question.
    pub fn to_wire(&self, coach: u16) -> SessionReport {
        let mut report = SessionReport {
            swings: self.swings,
            used: self.used,
            coach,
            metrics: Default::default(),
            tendencies: Default::default(),
            spatial: Default::default(),
            set_aside: self
                .set_aside
                .iter()
                .map(|s| WireSetAside {
                    swing: s.swing,
                    unlike: s.unlike,
                    worst: index(s.worst),
                    z_tenths: signed(s.z * 10.0),
                })
                .collect(),
            open: None,
        };
        for q in Quantity::BODY_LEVEL {
            let (Some(e), Some(c)) = (self.estimate(q).filter(|e| e.n > 0), self.coach(q)) else {
                continue;
            };
            let _ = report.metrics.push(metric(q, &e, c));
        }
        for t in self.advice() {
            let item = match t.advice {
                Advice::Tempo(p) => Quantity::Tempo(p.phase).body_level(),
                Advice::Body(b, _) => b
                    .check
                    .index()
                    .and_then(|i| Quantity::Check(i).body_level()),
                Advice::Sequence(g, _) => g.index().and_then(|i| Quantity::Gap(i).body_level()),
                Advice::Spatial(d) => {
                    let _ = report.spatial.push(d.to_wire());
                    Some(BODY_LEVEL + report.spatial.len() - 1)
                }
            };
            let Some(item) = item else {
                continue;
            };
            let _ = report.tendencies.push(WireTendency {
                item: item as u8,
                swings: t.swings,
                past: t.past,
            });
        }
        report.open = self.open().map(|o| {
            let (mut position, mut joint, mut direction) = (0, 0, 0);
            let unit = match o.quantity {
                Quantity::Offset(event, k, _) => {
                    if let Some((d, ..)) = self.joint_offset(event, k) {
                        position = Position::from(event) as u8;
                        joint = d.joint.index() as u8;
                        direction = d.direction as u8;
                    }
                    1000.0
                }
                q => scale(q),
            };
            WireOpen {
                quantity: index(o.quantity),
                position,
                joint,
                direction,
                value: signed(o.estimate.value * unit),
                uncertainty: unsigned(o.estimate.uncertainty * unit),
                more_swings: o.more_swings.min(u32::from(u16::MAX)) as u16,
            }
        });
        report
    }
}

/// Body-level quantity `q`'s wire form from its estimate `e` and the coach's value `coach`.
fn metric(q: Quantity, e: &Estimate, coach: f32) -> WireMetric {
    let verdict = match (e.clears(q.tolerance()), e.value > 0.0) {
        (false, _) => 0,
        (true, true) => 1,
        (true, false) => 2,
    };
    // A phase's estimate is `ln` of the student's over the coach's: its uncertainty and spread
    // are relative.
    let (student, uncertainty, spread) = match q {
        Quantity::Tempo(_) => {
            let student = coach * libm::expf(e.value);
            (student, student * e.uncertainty, student * e.spread)
        }
        _ => (coach + e.value, e.uncertainty, e.spread),
    };
    let s = scale(q);
    WireMetric {
        quantity: index(q),
        swings: e.n,
        above: e.above,
        below: e.below,
        verdict,
        student: signed(student * s),
        coach: signed(coach * s),
        uncertainty: unsigned(uncertainty * s),
        spread: unsigned(spread * s),
    }
}
