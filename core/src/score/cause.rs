//! Causes: the body-level items of a swing (a body check or a sequence gap past its
//! threshold) and the joint offsets each explains.
//!
//! A coach names the turn or the hips, not the hands that moved because of them. Where a
//! cause is given, each event it reaches is explained hierarchically:
//!
//! 1. The body-level difference at the event: the rigid motion taking the coach's pelvis onto
//!    the student's, and the coach's thorax onto the student's (each segment's origin and axes,
//!    [`Body::segments`]: turn, bend, side bend and shift at once), the student's joints taken
//!    without their usual offsets.
//! 2. That difference applied to the coach's pose: the hips and the legs move with the pelvis;
//!    the spine, the head and the arms with the thorax; the club is not judged.
//! 3. A joint whose offset is past its threshold but whose **residual** (the student's joint
//!    less the moved coach's) is within it is explained: it is folded under the cause, not
//!    given as an item of its own. A joint whose residual is past its threshold stays an item.
//!
//! A gap of the sequence moves the impact against the segments that peak before its later
//! link: that link carries the club to the ball, so where the chest peaks 40 ms early the
//! club meets the ball 40 ms early and the hips at impact are where the coach's were 40 ms
//! before its impact. A check at impact of such a segment (the hips' turn, sway or thrust for
//! the hips to the chest; the chest's too for the chest to the lead arm) is **explained by
//! the gap** where it differs from the coach's by about what the coach's own motion makes of
//! the gap's change (the coach's rate of change at impact times it): what is left, the
//! residual, within the check's threshold. The gap then takes the check's place: it reaches
//! the check's events and carries its segment, so the joint offsets the check would explain
//! fold under the gap, which names the check and is ranked by it.
//!
//! A cause reaches the events of the swing it shapes: a check at the top (P4) the toe-up,
//! halfway back and the top; a check at impact (P7) halfway down, impact and what follows it
//! (a body out of place at impact stays so through the finish); the sequence's gaps, halfway
//! down and impact. A pelvis-level cause (the pelvis's turn, sway or thrust) explains the joints both
//! segments carry, the thorax riding on the pelvis; a thorax-level one (the shoulders' turn,
//! the upper body starting the downswing) the thorax's. The head's lift and the lead elbow
//! are not segments: they fold the joint items that state what they state
//! ([`super::advice`]).
//!
//! **Ranking** (the convention): a cause is ranked by the severity of the largest offset it
//! explains where that is above its own, so it comes before every symptom it explains.

use super::advice::Advice;
use super::align::Pair;
use super::noise::Noise;
use super::spatial::{severity, Deviation, Direction};
use crate::body::{Body, Link, Measure};
use crate::checks::{BodyDeviation, Check};
use crate::config::{MAX_CHECKS, MAX_GAPS, MAX_JOINTS};
use crate::events::{Event, Position};
use crate::joint::Joint;
use crate::sequence::Gap;
use crate::Vec3;
use heapless::Vec as HVec;

/// Most causes one swing can have: every check and every gap.
pub const MAX_CAUSES: usize = MAX_CHECKS + MAX_GAPS;

/// A segment whose difference a cause is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Segment {
    /// The pelvis, which carries the thorax.
    Pelvis,
    /// The thorax: the spine, the head and the arms.
    Thorax,
}

impl Segment {
    /// The segment whose motion a joint follows: the legs are taken with the pelvis (a knee
    /// the hips pull along is explained by them; a planted foot is no offset to explain);
    /// `None` for the club.
    fn of(joint: Joint) -> Option<Segment> {
        use Joint::*;
        match joint {
            Pelvis | LeftHip | RightHip | LeftKnee | LeftAnkle | LeftToe | RightKnee
            | RightAnkle | RightToe => Some(Segment::Pelvis),
            ClubGrip | ClubHead => None,
            _ => Some(Segment::Thorax),
        }
    }

    /// Whether a cause of this segment explains a joint that follows `carried`.
    fn explains(self, carried: Segment) -> bool {
        self == Segment::Pelvis || carried == Segment::Thorax
    }
}

/// A joint offset a cause explains, as its sentence needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Symptom {
    /// The event.
    pub event: Event,
    /// The joint.
    pub joint: Joint,
    /// The offset's largest component.
    pub direction: Direction,
    /// Length of the offset, metres.
    pub distance_m: f32,
    /// Its uncertainty along it, metres.
    pub uncertainty_m: f32,
}

impl Symptom {
    /// How far past its threshold it is ([`Advice::severity_of`]).
    pub fn severity(&self) -> f32 {
        severity(self.distance_m, self.uncertainty_m)
    }
}

impl From<&Deviation> for Symptom {
    fn from(d: &Deviation) -> Symptom {
        Symptom {
            event: d.event,
            joint: d.joint,
            direction: d.direction,
            distance_m: d.distance_m,
            uncertainty_m: d.uncertainty_m,
        }
    }
}

/// What a cause explains: the joint offsets folded under it, and for a gap the check at impact
/// it explains.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Explains {
    /// The most severe offset it explains.
    pub worst: Option<Symptom>,
    /// How many offsets it explains.
    pub joints: u8,
    /// The most severe check it explains.
    pub check: Option<Check>,
    /// That check's student less coach, whole degrees or centimetres (saturating).
    pub by: i8,
    /// That check's severity ([`Advice::severity_of_check`]; 0 without one).
    pub check_severity: f32,
}

impl Explains {
    /// Adds `d`.
    pub(crate) fn add(&mut self, d: &Deviation) {
        self.joints = self.joints.saturating_add(1);
        let d = Symptom::from(d);
        if self.worst.is_none_or(|w| d.severity() > w.severity()) {
            self.worst = Some(d);
        }
    }

    /// Adds check `b` of severity `severity`: the most severe check is named.
    pub(crate) fn add_check(&mut self, b: &BodyDeviation, severity: f32) {
        if severity > self.check_severity {
            let scale = if b.check.measure.in_degrees() {
                1.0
            } else {
                100.0
            };
            self.check = Some(b.check);
            self.by = libm::roundf((b.student - b.coach) * scale) as i8;
            self.check_severity = severity;
        }
    }

    /// The severity of the most severe thing it explains (0 for nothing).
    pub fn severity(&self) -> f32 {
        self.worst
            .map_or(0.0, |w| w.severity())
            .max(self.check_severity)
    }
}

/// What `gap` makes of check `check` at the student's impact, where the coach's value moves
/// at `coach_rate` (its unit per second) there: the change it predicts (student less coach,
/// the coach's rate times the gap's change), `None` where the gap does not reach the check's
/// position or the check is not of a segment peaking before the gap's later link (see the
/// module documentation).
pub(crate) fn predicted_by(gap: &Gap, check: Check, coach_rate: f32) -> Option<f32> {
    let link = match check.measure {
        Measure::PelvisTurn | Measure::PelvisSway | Measure::PelvisThrust => Link::Pelvis,
        Measure::ThoraxTurn => Link::Thorax,
        Measure::HeadLift | Measure::LeadElbow => return None,
    };
    let reaches = check
        .position
        .event()
        .is_some_and(|e| GAP_REACH & (1 << e as u8) != 0);
    (reaches && (link as u8) < (gap.then as u8))
        .then_some(coach_rate * (gap.student_s - gap.coach_s))
}

/// The events a gap reaches (bit `e` for event `e`): halfway down and impact.
const GAP_REACH: u8 = (1 << Event::MidDownswing as u8) | (1 << Event::Impact as u8);

/// A body-level item past its threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Item {
    /// A body check.
    Check(BodyDeviation),
    /// A gap of the sequence.
    Gap(Gap),
}

/// One cause.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Cause {
    /// What it is.
    pub item: Item,
    /// Its own severity.
    pub severity: f32,
    /// The segment whose difference it is, where it is one.
    segment: Option<Segment>,
    /// Bit `e` set where it reaches event `e`.
    events: u8,
    /// What it explains.
    pub explains: Explains,
}

/// The events a check at `position` reaches (see the module documentation).
fn reach(position: Position) -> u8 {
    let bit = |e: Event| 1u8 << e as u8;
    match position {
        Position::P4 => bit(Event::ToeUp) | bit(Event::MidBackswing) | bit(Event::Top),
        Position::P7 => {
            bit(Event::MidDownswing)
                | bit(Event::Impact)
                | bit(Event::MidFollowThrough)
                | bit(Event::Finish)
        }
        _ => 0,
    }
}

impl Cause {
    /// `check` as a cause of severity `severity`.
    pub(super) fn check(check: BodyDeviation, severity: f32) -> Cause {
        let segment = match check.check.measure {
            Measure::ThoraxTurn => Some(Segment::Thorax),
            Measure::PelvisTurn | Measure::PelvisSway | Measure::PelvisThrust => {
                Some(Segment::Pelvis)
            }
            Measure::HeadLift | Measure::LeadElbow => None,
        };
        Cause {
            item: Item::Check(check),
            severity,
            segment,
            events: reach(check.check.position),
            explains: Explains::default(),
        }
    }

    /// `gap` as a cause of severity `severity`: the chest peaking before its time is the
    /// upper body's difference; the arm's is not a segment's.
    pub(super) fn gap(gap: Gap, severity: f32) -> Cause {
        Cause {
            item: Item::Gap(gap),
            severity,
            segment: (gap.first == Link::Pelvis).then_some(Segment::Thorax),
            events: GAP_REACH,
            explains: Explains::default(),
        }
    }
}

/// Whether body-level `item` may explain joint offset `d` (of a golfer whose lead side is
/// `lead`): it reaches `d`'s event and its segment carries the joint, or it states what the
/// offset states ([`super::advice`]). The residual test needs the swing's poses; a session,
/// which keeps no poses, folds by this alone.
pub(crate) fn may_explain(item: &Item, d: &Deviation, lead: crate::events::Side) -> bool {
    let cause = match item {
        Item::Check(b) => Cause::check(*b, 0.0),
        Item::Gap(g) => Cause::gap(*g, 0.0),
    };
    let reaches = cause.events & (1 << d.event as u8) != 0;
    let carries = match (cause.segment, Segment::of(d.joint)) {
        (Some(segment), Some(carried)) => segment.explains(carried),
        _ => false,
    };
    let states = match item {
        Item::Check(b) => {
            b.check.position.event() == Some(d.event)
                && super::advice::states(b.check.measure, d, lead)
        }
        Item::Gap(_) => false,
    };
    (reaches && carries) || states
}

/// The causes of a swing: its sequence's gaps wholly past their tolerance and its body checks
/// past their thresholds (`coach_rate` the rate of change of the coach's value of each, in
/// `body`'s order), but a check a gap explains (its residual within the check's threshold):
/// that gap takes its place.
pub(super) fn causes(
    body: &[BodyDeviation],
    coach_rate: &[f32],
    gaps: &[Gap],
) -> HVec<Cause, MAX_CAUSES> {
    let mut out: HVec<Cause, MAX_CAUSES> = gaps
        .iter()
        .filter(|g| Advice::is_clear(g))
        .map(|g| Cause::gap(*g, Advice::severity_of_gap(g)))
        .collect();
    let clear = out.len();
    for (b, &rate) in body.iter().zip(coach_rate) {
        let severity = Advice::severity_of_check(b);
        if severity <= 1.0 {
            continue;
        }
        // What the gap leaves of the difference, within the difference the check is advice
        // past (the difference over its severity).
        let difference = b.student - b.coach;
        let explaining = out[..clear].iter_mut().find(|c| match c.item {
            Item::Gap(g) => predicted_by(&g, b.check, rate)
                .is_some_and(|p| libm::fabsf(difference - p) * severity <= libm::fabsf(difference)),
            Item::Check(_) => false,
        });
        let check = Cause::check(*b, severity);
        match explaining {
            Some(gap) => gap.take(&check),
            None => {
                let _ = out.push(check);
            }
        }
    }
    out
}

impl Cause {
    /// This gap explaining `check` (a cause of a check): it reaches the check's events too and
    /// carries its segment where that carries more (the pelvis the thorax), so the joints the
    /// check would explain fold under the gap, and the gap names it and is ranked by it.
    fn take(&mut self, check: &Cause) {
        self.events |= check.events;
        if check.segment == Some(Segment::Pelvis) || self.segment.is_none() {
            self.segment = check.segment;
        }
        if let Item::Check(b) = check.item {
            self.explains.add_check(&b, check.severity);
        }
    }
}

/// A segment's rigid motion from the coach's pose to the student's.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rigid {
    coach: (Vec3, [Vec3; 3]),
    student: (Vec3, [Vec3; 3]),
}

impl Rigid {
    /// Where the coach's point `p` goes.
    fn apply(&self, p: Vec3) -> Vec3 {
        let ((from, a), (to, b)) = (self.coach, self.student);
        let d = p - from;
        to + b[0] * a[0].dot(&d) + b[1] * a[1].dot(&d) + b[2] * a[2].dot(&d)
    }
}

/// The body-level difference at one event, and the causes that reach it: for each segment the
/// index of the most severe cause that may explain its joints.
pub(super) struct Model {
    /// Pelvis, thorax.
    rigid: [Rigid; 2],
    /// Pelvis, thorax.
    cause: [Option<usize>; 2],
}

impl Model {
    /// The model at `event` (the student's frame `x`) where a cause reaches it, the segments
    /// measured as `body` says.
    #[inline(never)]
    pub(super) fn at(
        (pair, body): (&Pair<'_>, &Body),
        noise: &Noise,
        causes: &[Cause],
        (event, x): (Event, f32),
    ) -> Option<Model> {
        let mut cause = [None::<usize>; 2];
        for (carried, best) in [Segment::Pelvis, Segment::Thorax]
            .into_iter()
            .zip(&mut cause)
        {
            let reaching = causes.iter().enumerate().filter(|(_, c)| {
                c.events & (1 << event as u8) != 0 && c.segment.is_some_and(|s| s.explains(carried))
            });
            *best = reaching
                .max_by(|a, b| a.1.severity.total_cmp(&b.1.severity))
                .map(|(i, _)| i);
        }
        if cause == [None; 2] {
            return None;
        }
        let (half_s, half_c) = pair.half;
        let c = pair.time_map.at(x);
        let [mut student, mut coach] = [[Vec3::zeros(); MAX_JOINTS]; 2];
        let joints = noise
            .usual
            .iter()
            .zip(student.iter_mut().zip(coach.iter_mut()));
        for (k, (usual, (s, c_k))) in joints.enumerate().take(pair.student.joints()) {
            *s = pair.stance_s.local(pair.student_at(k, x, half_s)) - usual;
            *c_k = pair.stance_c.local(pair.coach_at(k, c, half_c));
        }
        let (s, c) = (body.segments(&student)?, body.segments(&coach)?);
        Some(Model {
            rigid: [0, 1].map(|i| Rigid {
                coach: c[i],
                student: s[i],
            }),
            cause,
        })
    }

    /// The cause that explains joint `joint` of offset `offset` (student less coach) from the
    /// coach's `coach` (both in the stance frames) within `threshold`, if one does.
    pub(super) fn explains(
        &self,
        joint: Joint,
        (offset, coach): (Vec3, Vec3),
        threshold: f32,
    ) -> Option<usize> {
        let i = match Segment::of(joint)? {
            Segment::Pelvis => 0,
            Segment::Thorax => 1,
        };
        let cause = self.cause[i]?;
        let moved = self.rigid[i].apply(coach) - coach;
        (crate::math::norm(&(offset - moved)) <= threshold).then_some(cause)
    }
}

#[cfg(test)]
mod tests {
    use super::{reach, Rigid, Segment};
    use crate::events::{Event, Position};
    use crate::joint::Joint;
    use crate::Vec3;

    #[test]
    fn a_rigid_motion_takes_the_coachs_segment_onto_the_students() {
        // The student's segment 20 cm toward the ball and turned 90° about the vertical.
        let coach = (Vec3::new(0.0, 0.0, 1.0), [Vec3::x(), Vec3::z(), Vec3::y()]);
        let student = (Vec3::new(0.0, 0.2, 1.0), [Vec3::y(), Vec3::z(), -Vec3::x()]);
        let rigid = Rigid { coach, student };
        let moved = rigid.apply(Vec3::new(0.3, 0.0, 1.5));
        assert!((moved - Vec3::new(0.0, 0.5, 1.5)).norm() < 1e-6, "{moved}");
        assert_eq!(rigid.apply(coach.0), student.0);
    }

    #[test]
    fn the_hips_and_legs_ride_the_pelvis_the_arms_the_thorax_and_the_club_neither() {
        assert_eq!(Segment::of(Joint::LeftHip), Some(Segment::Pelvis));
        assert_eq!(Segment::of(Joint::RightWrist), Some(Segment::Thorax));
        assert_eq!(Segment::of(Joint::LeftKnee), Some(Segment::Pelvis));
        assert_eq!(Segment::of(Joint::ClubHead), None);
        // A pelvis cause explains the thorax's joints too; a thorax cause not the hips.
        assert!(Segment::Pelvis.explains(Segment::Thorax));
        assert!(!Segment::Thorax.explains(Segment::Pelvis));
    }

    #[test]
    fn a_gap_predicts_the_checks_at_impact_of_the_segments_peaking_before_its_later_link() {
        use super::predicted_by;
        use crate::body::{Link, Measure};
        use crate::checks::Check;
        use crate::sequence::Gap;
        let gap = |first, then| Gap {
            first,
            then,
            student_s: 0.0,
            coach_s: 0.04,
            uncertainty_s: 0.001,
        };
        let at = |position, measure| Check { position, measure };
        let hips_turn = at(Position::P7, Measure::PelvisTurn);
        let hips_chest = gap(Link::Pelvis, Link::Thorax);
        // 40 ms less between the hips' and the chest's peaks: the club arrives 40 ms early, and
        // the hips at impact are where the coach's were 40 ms before: 16° less open at 400°/s.
        assert_eq!(predicted_by(&hips_chest, hips_turn, -400.0), Some(16.0));
        // Not the head, which rides the chest, nor the top, which the gap does not reach.
        assert_eq!(
            predicted_by(&hips_chest, at(Position::P7, Measure::HeadLift), 1.0),
            None
        );
        assert_eq!(
            predicted_by(&hips_chest, at(Position::P4, Measure::PelvisTurn), 1.0),
            None
        );
        // The chest to the lead arm moves the club against the hips too.
        let chest_arm = gap(Link::Thorax, Link::LeadArm);
        assert_eq!(predicted_by(&chest_arm, hips_turn, 100.0), Some(-4.0));
    }

    #[test]
    fn a_cause_reaches_the_events_of_the_swing_it_shapes() {
        let top = reach(Position::P4);
        assert!(top & (1 << Event::MidBackswing as u8) != 0);
        assert!(top & (1 << Event::Impact as u8) == 0);
        assert_eq!(reach(Position::P7).count_ones(), 4);
        assert_eq!(reach(Position::P10), 0);
    }
}
