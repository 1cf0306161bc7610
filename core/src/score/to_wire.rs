//! The to_wire stage: a report in the wire's compact form ([`SwingReport`]).

use super::{Deviation, Report};
use crate::events::{Position, SwingEvents};
use crate::wire::{SwingReport, WireCheck, WireDeviation, WireGap};

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
        SwingReport {
            swing,
            coach,
            score_centi: libm::roundf(self.score * 100.0).clamp(0.0, 10000.0) as u16,
            student_positions: frames(&self.student_events),
            coach_positions: frames(&self.coach_events),
            phases_ms: self.tempo.map(|t| [ms(t.student_s), ms(t.coach_s)]),
            verdicts: self.tempo.map(|t| t.verdict as u8),
            deviations: self.spatial.iter().map(Deviation::to_wire).collect(),
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
                        check: b.check.index()? as u8,
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
                        gap: g.index()? as u8,
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

impl Deviation {
    /// The wire form of a joint's offset: millimetres, saturating at ±32.767 m (its
    /// uncertainty at 65.535 m).
    pub fn to_wire(&self) -> WireDeviation {
        WireDeviation {
            position: Position::from(self.event) as u8,
            joint: self.joint.index() as u8,
            direction: self.direction as u8,
            offset_mm: self
                .offset_m
                .map(|m| libm::roundf(m * 1000.0).clamp(-32767.0, 32767.0) as i16),
            uncertainty_mm: libm::roundf(self.uncertainty_m * 1000.0)
                .clamp(0.0, f32::from(u16::MAX)) as u16,
        }
    }
}
