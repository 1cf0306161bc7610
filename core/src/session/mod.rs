//! A range session: what a golfer's swings against one coach say together.
//!
//! One noisy swing says little; a session's swings each carry fresh noise, so `n` of them say
//! about `√n` times as much. [`Tendencies`] hears every swing as it is scored (it is a
//! [`Sink`]) and keeps, for every quantity a report carries, a [`Tally`] of running robust
//! statistics: each phase's tempo (`ln` of the ratio to the coach's) and the pause at the top,
//! each body check and each sequence gap (the student's less the coach's), and each joint's
//! offset at each event along each stance axis. Memory is fixed: eight bytes a quantity however
//! many swings come (the joints' in the caller's buffer, [`JointTallies`]: 3.2 KiB for a
//! 17-joint skeleton), rather than the last few swings'
//! summaries, because a session's estimate should use every swing of it, and a window long
//! enough for the 20 swings a noisy phone needs would not fit the device.
//!
//! **A swing set aside.** From the fourth swing on, a swing is compared with the session before
//! it is counted: a body-level quantity lying farther from the session's mean than its tally
//! would let it (more than [`CLAMP`](crate::tally::CLAMP) predictive standard deviations and
//! past the quantity's tolerance) is unlike the session. One such quantity is only pulled in;
//! a swing unlike the session in [`UNLIKE`] or more (a practice half swing, a mishit, a track
//! lost or swapped for part of the swing) is set aside whole, and the session keeps why. The
//! first three swings cannot be judged so; their tallies are robust to one of them being
//! unlike the other two ([`crate::tally`]).
//!
//! **Advice** ([`Tendencies::advice`]) follows a swing's rules with the session's estimates: an
//! item only where the estimate's one-sided 95 % interval lies wholly past the tolerance a
//! swing's advice uses (15 % of tempo, each check's, 30 ms of a gap, 5 cm of a joint), a cause
//! before the joint offsets it may explain (folded under it), a check at impact under the gap
//! that accounts for it (the residual of the coach's rate times the gap's estimate not a
//! tendency itself, as [`crate::score`]'s cause stage folds it), each with its evidence: in how
//! many of the session's swings the quantity was past its tolerance that way. Where nothing is
//! clear, [`Tendencies::open`] names the quantity nearest to being advice and about how many
//! swings would settle it.

use crate::checks::{BodyDeviation, CHECKS};
use crate::config::{BODY_LEVEL, MAX_ADVICE, MAX_CHECKS, MAX_GAPS, MAX_SET_ASIDE};
use crate::events::{Event, Side};
use crate::joint::Joint;
use crate::score::{
    insert_sorted, may_explain, predicted_by, ranked, Advice, BodyLevel, Deviation, Direction,
    Explains, Item, Phase, PhaseTempo, Sink, Verdict, SPATIAL_THRESHOLD_M, TEMPO_TOLERANCE,
};
use crate::sequence::{Gap, GAPS, GAP_TOLERANCE_S};
use crate::tally::{t95, Estimate, Tally};
use crate::Vec3;
use heapless::Vec as HVec;

/// A swing unlike the session in this many body-level quantities is set aside.
pub const UNLIKE: usize = 2;

/// How consistently tour players repeat their backswing's duration: within about this many
/// seconds (one standard deviation).
pub const TOUR_BACKSWING_SPREAD_S: f32 = 0.02;

/// A quantity a session keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Quantity {
    /// A phase's duration: `ln` of the student's over the coach's.
    Tempo(Phase),
    /// How much longer the hands paused at the top than the coach's, seconds.
    Pause,
    /// A body check ([`CHECKS`]' index): the student's change less the coach's, degrees or
    /// metres.
    Check(usize),
    /// A gap of the sequence ([`GAPS`]' index): the student's less the coach's, seconds.
    Gap(usize),
    /// A joint's offset from the coach beyond its usual one at an event, along one stance axis
    /// (0 toward the target, 1 toward the ball, 2 up), metres: the skeleton's joint index.
    Offset(Event, usize, usize),
}

impl Quantity {
    /// The body-level quantities, in their order.
    pub const BODY_LEVEL: [Quantity; BODY_LEVEL] = {
        let mut out = [Quantity::Pause; BODY_LEVEL];
        let mut i = 0;
        while i < BODY_LEVEL {
            out[i] = match i {
                0 => Quantity::Tempo(Phase::Backswing),
                1 => Quantity::Tempo(Phase::Downswing),
                2 => Quantity::Tempo(Phase::FollowThrough),
                3 => Quantity::Pause,
                i if i < 4 + MAX_CHECKS => Quantity::Check(i - 4),
                i => Quantity::Gap(i - 4 - MAX_CHECKS),
            };
            i += 1;
        }
        out
    };

    /// The size of its tally's unit in its own unit: a ten-thousandth (of `ln` ratio, second
    /// or metre), a hundredth of a degree.
    pub fn unit(self) -> f32 {
        match self {
            Quantity::Check(i) if CHECKS.get(i).is_some_and(|c| c.measure.in_degrees()) => 0.01,
            _ => 1e-4,
        }
    }

    /// The difference advice acts on, in its own unit (none for the pause: a swing's advice
    /// does not judge it).
    pub fn tolerance(self) -> f32 {
        match self {
            Quantity::Tempo(_) => libm::log1pf(TEMPO_TOLERANCE),
            Quantity::Pause => f32::INFINITY,
            Quantity::Check(i) => CHECKS
                .get(i)
                .map_or(f32::INFINITY, |c| c.measure.tolerance()),
            Quantity::Gap(_) => GAP_TOLERANCE_S,
            Quantity::Offset(..) => SPATIAL_THRESHOLD_M,
        }
    }

    /// Its index among the body-level quantities.
    pub(crate) fn body_level(self) -> Option<usize> {
        match self {
            Quantity::Tempo(p) => Some(p as usize),
            Quantity::Pause => Some(3),
            Quantity::Check(i) if i < MAX_CHECKS => Some(4 + i),
            Quantity::Gap(i) if i < MAX_GAPS => Some(4 + MAX_CHECKS + i),
            _ => None,
        }
    }
}

/// Why a swing was set aside.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SetAside {
    /// The swing's number in the session, from 1.
    pub swing: u16,
    /// In how many body-level quantities it was unlike the session.
    pub unlike: u8,
    /// The one it was most unlike the session in.
    pub worst: Quantity,
    /// How far that one lay from the session's mean, in predictive standard deviations.
    pub z: f32,
}

/// A session's tendency: an item of advice with the session's estimates, and its evidence.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tendency {
    /// The item, its values the session's (the student's its estimate, `±` its uncertainty).
    pub advice: Advice,
    /// Swings it was measured in.
    pub swings: u8,
    /// Of those, how many were past the tolerance the way the item says.
    pub past: u8,
}

impl core::fmt::Display for Tendency {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.advice.sentence(f)?;
        write!(f, " (in {} of {} swings).", self.past, self.swings)
    }
}

/// The quantity nearest to being advice that the session cannot settle yet.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Open {
    /// The quantity (a joint's offset: its largest axis).
    pub quantity: Quantity,
    /// Its estimate (for a joint, along the offset: the distance).
    pub estimate: Estimate,
    /// About how many more swings would settle it, if its mean and scatter stay.
    pub more_swings: u32,
}

/// One joint's tallies: its offset at each event along each stance axis. A session keeps one
/// for each joint of the student's skeleton, in a buffer of its caller's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JointTallies {
    /// The joint, as the swings named it.
    joint: Option<Joint>,
    /// [`Event::ALL`] order; toward the target, toward the ball, up.
    at: [[Tally; 3]; Event::COUNT],
}

impl JointTallies {
    /// No swings.
    pub const EMPTY: JointTallies = JointTallies {
        joint: None,
        at: [[Tally::EMPTY; 3]; Event::COUNT],
    };
}

/// What a range session's swings say together: see the [module documentation](self).
#[derive(Debug)]
pub struct Tendencies<'a> {
    /// The body-level quantities' tallies, [`Quantity::BODY_LEVEL`] order.
    body: [Tally; BODY_LEVEL],
    /// The coach's value of each body-level quantity (a phase's duration and the pause in
    /// seconds, a check's change, a gap) and, for a check, how fast it moves at its position
    /// (its unit per second; 0 for the others), as the last swing counted had them.
    coach: [(f32, f32); BODY_LEVEL],
    /// Each joint's tallies, the skeleton's order (joints past its length are not kept).
    joints: &'a mut [JointTallies],
    /// The golfer's lead side, as the last swing counted had it.
    lead: Side,
    /// Swings heard.
    swings: u16,
    /// Swings counted.
    used: u16,
    /// The latest swings set aside.
    set_aside: HVec<SetAside, MAX_SET_ASIDE>,
    /// Whether the swing being heard is counted (its offsets too).
    counting: bool,
}

/// A body-level quantity's value in a swing (as the session counts it: a phase's `ln` ratio,
/// the student's less the coach's otherwise), its stated uncertainty, and the coach's value and
/// rate (a check's; 0 for the others), each in its own unit.
pub type Values = (f32, f32, (f32, f32));

/// Each body-level quantity's [`Values`] in `swing`, [`Quantity::BODY_LEVEL`] order; `None`
/// where the swing has none.
pub fn body_level_values(swing: &BodyLevel<'_>) -> [Option<Values>; BODY_LEVEL] {
    let mut out = [None; BODY_LEVEL];
    for t in swing.tempo {
        let relative = t.ratio_uncertainty / t.ratio;
        out[t.phase as usize] = Some((libm::logf(t.ratio), relative, (t.coach_s, 0.0)));
    }
    let (student, coach) = swing.pause_s;
    // A pause is timed to a frame or so: the top's own uncertainty is in the tempo's.
    out[3] = Some((student - coach, 0.0, (coach, 0.0)));
    for (k, b) in swing.body.iter().enumerate() {
        // No rate where the teller knows none (a report keeps none): no gap explains it then.
        let rate = swing.coach_rate.get(k).copied().unwrap_or(0.0);
        if let Some(i) = b.check.index() {
            out[4 + i] = Some((b.student - b.coach, b.uncertainty, (b.coach, rate)));
        }
    }
    for g in swing.gaps {
        if let Some(i) = g.index() {
            out[4 + MAX_CHECKS + i] =
                Some((g.student_s - g.coach_s, g.uncertainty_s, (g.coach_s, 0.0)));
        }
    }
    out
}

impl<'a> Tendencies<'a> {
    /// An empty session keeping its joints' tallies in `joints` (one for each joint of the
    /// largest skeleton it will hear of; emptied).
    pub fn new(joints: &'a mut [JointTallies]) -> Self {
        joints.fill(JointTallies::EMPTY);
        Tendencies {
            body: [Tally::EMPTY; BODY_LEVEL],
            coach: [(0.0, 0.0); BODY_LEVEL],
            joints,
            lead: Side::Left,
            swings: 0,
            used: 0,
            set_aside: HVec::new(),
            counting: false,
        }
    }

    /// Swings heard, counted or set aside.
    pub fn swings(&self) -> u16 {
        self.swings
    }

    /// Swings counted.
    pub fn used(&self) -> u16 {
        self.used
    }

    /// The latest swings set aside, and why.
    pub fn set_aside(&self) -> &[SetAside] {
        &self.set_aside
    }

    /// The session's estimate of `quantity`, in its own unit (`None` for a joint the session
    /// keeps no tallies for).
    pub fn estimate(&self, quantity: Quantity) -> Option<Estimate> {
        let tally = match quantity {
            Quantity::Offset(event, k, axis) => self.joints.get(k)?.at[event as usize].get(axis)?,
            q => &self.body[q.body_level()?],
        };
        Some(tally.estimate(quantity.unit()))
    }

    /// The coach's value of a body-level `quantity`, in its own unit (a phase's duration in
    /// seconds), as the last swing counted had it.
    pub fn coach(&self, quantity: Quantity) -> Option<f32> {
        quantity.body_level().map(|i| self.coach[i].0)
    }

    /// The joint at skeleton index `k`, as the swings named it.
    pub fn joint(&self, k: usize) -> Option<Joint> {
        self.joints.get(k)?.joint
    }

    /// The length of joint `k`'s mean offset at `event`, metres, where it was measured in at
    /// least two swings (else 0, as where none is kept: nothing can be said of it yet): the
    /// distance [`Self::joint_offset`] gives, without the rest of its work.
    fn offset_length(&self, event: Event, k: usize) -> f32 {
        let Some(at) = self.joints.get(k).and_then(|j| j.at.get(event as usize)) else {
            return 0.0;
        };
        if at.iter().any(|t| t.n() < 2) {
            return 0.0;
        }
        let [x, y, z] = at
            .each_ref()
            .map(|t| t.mean(Quantity::Offset(event, k, 0).unit()));
        crate::math::sqrt(x * x + y * y + z * z)
    }

    /// Joint `k`'s offset at `event` as a joint item would give it: its length, its
    /// uncertainty along it, the swings it was measured in and how many of them were past the
    /// threshold along its largest axis, that way; `None` where it was measured in none.
    fn joint_offset(&self, event: Event, k: usize) -> Option<(Deviation, Estimate, u8)> {
        let joint = self.joint(k)?;
        let axes = [0, 1, 2].map(|a| self.estimate(Quantity::Offset(event, k, a)));
        let [Some(x), Some(y), Some(z)] = axes else {
            return None;
        };
        let n = x.n.min(y.n).min(z.n);
        if n == 0 {
            return None;
        }
        let o = Vec3::new(x.value, y.value, z.value);
        let u = Vec3::new(x.uncertainty, y.uncertainty, z.uncertainty);
        let distance_m = crate::math::norm(&o);
        let along = o
            .try_normalize(f32::MIN_POSITIVE)
            .map_or(crate::math::norm(&u) / crate::math::sqrt(3.0), |d| {
                crate::math::norm(&u.component_mul(&d))
            });
        let direction = Direction::of(o);
        let largest = [x, y, z][o.iamax()];
        let past = match o[o.iamax()] > 0.0 {
            true => largest.above,
            false => largest.below,
        };
        let deviation = Deviation {
            event,
            joint,
            distance_m,
            uncertainty_m: along,
            offset_m: [o.x, o.y, o.z],
            direction,
        };
        let estimate = Estimate {
            n,
            value: distance_m,
            uncertainty: along,
            ..largest
        };
        Some((deviation, estimate, past))
    }

    /// The session's advice, most important first (see the [module documentation](self)).
    pub fn advice(&self) -> HVec<Tendency, MAX_ADVICE> {
        // Causes: the checks and gaps that clear their tolerance, with what they explain.
        let mut causes: HVec<(Tendency, Explains), { MAX_CHECKS + MAX_GAPS }> = HVec::new();
        let mut out: HVec<Tendency, MAX_ADVICE> = HVec::new();
        for q in Quantity::BODY_LEVEL {
            let Some(e) = self.estimate(q).filter(|e| e.clears(q.tolerance())) else {
                continue;
            };
            let coach = self.coach(q).unwrap_or(0.0);
            let past = if e.value > 0.0 { e.above } else { e.below };
            let advice = match q {
                Quantity::Tempo(phase) => {
                    let ratio = libm::expf(e.value);
                    Advice::Tempo(PhaseTempo {
                        phase,
                        student_s: coach * ratio,
                        coach_s: coach,
                        ratio,
                        ratio_uncertainty: ratio * e.uncertainty,
                        verdict: if e.value > 0.0 {
                            Verdict::Slow
                        } else {
                            Verdict::Fast
                        },
                    })
                }
                Quantity::Check(i) => Advice::Body(
                    BodyDeviation {
                        check: CHECKS[i],
                        student: coach + e.value,
                        coach,
                        uncertainty: e.uncertainty,
                    },
                    Explains::default(),
                ),
                Quantity::Gap(i) => Advice::Sequence(
                    Gap {
                        first: GAPS[i].0,
                        then: GAPS[i].1,
                        student_s: coach + e.value,
                        coach_s: coach,
                        uncertainty_s: e.uncertainty,
                    },
                    Explains::default(),
                ),
                Quantity::Pause | Quantity::Offset(..) => continue,
            };
            let tendency = Tendency {
                advice,
                swings: e.n,
                past,
            };
            match advice {
                Advice::Tempo(_) => insert_sorted(&mut out, tendency, severity),
                _ => {
                    let _ = causes.push((tendency, Explains::default()));
                }
            }
        }
        // A check a gap explains: the residual of what the gap predicts not a tendency itself.
        let mut under = [None::<usize>; MAX_CHECKS + MAX_GAPS];
        for (i, (c, _)) in causes.iter().enumerate() {
            let Advice::Body(b, _) = c.advice else {
                continue;
            };
            let Some(k) = b.check.index() else {
                continue;
            };
            let q = Quantity::Check(k);
            let coach = q.body_level().and_then(|i| self.coach.get(i));
            let (Some(e), Some(&(_, rate))) = (self.estimate(q), coach) else {
                continue;
            };
            under[i] = causes.iter().position(|(g, _)| {
                let Advice::Sequence(gap, _) = g.advice else {
                    return false;
                };
                let Some(i) = gap.index() else {
                    return false;
                };
                let (Some(p), Some(eg)) = (
                    predicted_by(&gap, b.check, rate),
                    self.estimate(Quantity::Gap(i)),
                ) else {
                    return false;
                };
                let residual = Estimate {
                    n: e.n.min(eg.n),
                    value: e.value - p,
                    uncertainty: crate::math::hypot(e.uncertainty, rate * eg.uncertainty),
                    ..e
                };
                !residual.clears(q.tolerance())
            });
        }
        // Joints: those whose interval along the offset clears the threshold, folded under a
        // cause that may explain them (under the gap that explains it, for a check).
        for event in Event::ALL {
            for k in 0..self.joints.len() {
                // An offset no longer than the threshold is no advice, whatever its interval,
                // nor is one measured in fewer than two swings (its interval is unbounded).
                if self.offset_length(event, k) <= SPATIAL_THRESHOLD_M {
                    continue;
                }
                let Some((d, e, past)) = self.joint_offset(event, k) else {
                    continue;
                };
                let margin = t95(usize::from(e.n).saturating_sub(1)) * e.uncertainty;
                if d.distance_m - margin <= SPATIAL_THRESHOLD_M {
                    continue;
                }
                let folding = causes.iter().position(|(c, _)| match c.advice {
                    Advice::Body(b, _) => may_explain(&Item::Check(b), &d, self.lead),
                    Advice::Sequence(g, _) => may_explain(&Item::Gap(g), &d, self.lead),
                    _ => false,
                });
                match folding.and_then(|i| causes.get_mut(under[i].unwrap_or(i))) {
                    Some((_, explains)) => explains.add(&d),
                    None => insert_sorted(
                        &mut out,
                        Tendency {
                            advice: Advice::Spatial(d),
                            swings: e.n,
                            past,
                        },
                        severity,
                    ),
                }
            }
        }
        for i in 0..causes.len() {
            if let (Some(j), Advice::Body(b, _)) = (under[i], causes[i].0.advice) {
                if let Some((_, gap)) = causes.get_mut(j) {
                    gap.add_check(&b, Advice::severity_of_check(&b));
                }
            }
        }
        for (i, (mut c, explains)) in causes.into_iter().enumerate() {
            if under[i].is_some() {
                continue;
            }
            c.advice = match c.advice {
                Advice::Body(b, _) => Advice::Body(b, explains),
                Advice::Sequence(g, _) => Advice::Sequence(g, explains),
                other => other,
            };
            insert_sorted(&mut out, c, severity);
        }
        out
    }

    /// The quantity nearest to being advice that the session has not settled (its interval
    /// neither wholly past its tolerance nor wholly within it), by its estimate over its
    /// tolerance; `None` where every quantity is settled or none has two swings.
    pub fn open(&self) -> Option<Open> {
        let mut best: Option<(f32, Open)> = None;
        let consider = |best: &mut Option<(f32, Open)>, quantity: Quantity, estimate: Estimate| {
            let tolerance = quantity.tolerance();
            let unsettled = estimate.n >= 2
                && tolerance.is_finite()
                && !estimate.clears(tolerance)
                && !estimate.within(tolerance);
            let nearness = libm::fabsf(estimate.value) / tolerance;
            if !unsettled || best.as_ref().is_some_and(|(b, _)| *b >= nearness) {
                return;
            }
            if let Some(total) = estimate.swings_to_settle(tolerance) {
                let more_swings = total.saturating_sub(u32::from(estimate.n));
                *best = Some((
                    nearness,
                    Open {
                        quantity,
                        estimate,
                        more_swings,
                    },
                ));
            }
        };
        for q in Quantity::BODY_LEVEL {
            if let Some(e) = self.estimate(q) {
                consider(&mut best, q, e);
            }
        }
        for event in Event::ALL {
            for k in 0..self.joints.len() {
                // A joint measured in fewer than two swings is not open, and one no nearer
                // than the nearest so far needs no estimate.
                let nearness = self.offset_length(event, k) / SPATIAL_THRESHOLD_M;
                if nearness == 0.0 || best.as_ref().is_some_and(|(b, _)| *b >= nearness) {
                    continue;
                }
                if let Some((d, e, _)) = self.joint_offset(event, k) {
                    let axis = Vec3::from(d.offset_m).iamax();
                    consider(&mut best, Quantity::Offset(event, k, axis), e);
                }
            }
        }
        best.map(|(_, open)| open)
    }

    /// Starts the session afresh (a new coach or profile, or asked).
    pub fn reset(&mut self) {
        let joints = core::mem::take(&mut self.joints);
        *self = Tendencies::new(joints);
    }
}

/// A tendency's rank: its item's, a cause ranked by the most severe joint it explains where
/// that is higher.
fn severity(t: &Tendency) -> f32 {
    match &t.advice {
        Advice::Body(b, explains) => ranked(Advice::severity_of_check(b), explains),
        Advice::Sequence(g, explains) => ranked(Advice::severity_of_gap(g), explains),
        other => other.severity(),
    }
}

impl Sink for Tendencies<'_> {
    fn body(&mut self, swing: &BodyLevel<'_>) -> bool {
        self.swings = self.swings.saturating_add(1);
        let values = body_level_values(swing);
        // Judged against the session once its tallies can say what is unlike it.
        let mut unlike = 0usize;
        let mut worst: Option<(Quantity, f32)> = None;
        for ((q, tally), value) in Quantity::BODY_LEVEL.iter().zip(&self.body).zip(&values) {
            let Some((value, _, _)) = value else {
                continue;
            };
            let units = value / q.unit();
            if tally.n() >= 3 && tally.unlike(units, q.tolerance() / q.unit()) {
                unlike += 1;
                let z = tally.z(units);
                if worst.is_none_or(|(_, w)| libm::fabsf(z) > libm::fabsf(w)) {
                    worst = Some((*q, z));
                }
            }
        }
        self.counting = unlike < UNLIKE;
        if let (false, Some((worst, z))) = (self.counting, worst) {
            if self.set_aside.is_full() {
                self.set_aside.remove(0);
            }
            let _ = self.set_aside.push(SetAside {
                swing: self.swings,
                unlike: unlike.min(usize::from(u8::MAX)) as u8,
                worst,
                z,
            });
            return false;
        }
        for ((q, tally), (value, coach)) in Quantity::BODY_LEVEL
            .iter()
            .zip(&mut self.body)
            .zip(values.iter().zip(&mut self.coach))
        {
            if let Some((v, u, c)) = value {
                tally.add(v / q.unit(), u / q.unit(), q.tolerance() / q.unit());
                *coach = *c;
            }
        }
        self.lead = swing.lead;
        self.used = self.used.saturating_add(1);
        true
    }

    fn offset(&mut self, (event, k, joint): (Event, usize, Joint), offset: Vec3, u: Vec3) {
        let Some(tallies) = self.joints.get_mut(k).filter(|_| self.counting) else {
            return;
        };
        let q = Quantity::Offset(event, k, 0);
        let (unit, tolerance) = (q.unit(), q.tolerance() / q.unit());
        for (axis, tally) in tallies.at[event as usize].iter_mut().enumerate() {
            tally.add(offset[axis] / unit, u[axis] / unit, tolerance);
        }
        tallies.joint = Some(joint);
    }
}

mod to_wire;

#[cfg(test)]
mod tests {
    use super::{JointTallies, Quantity, Tendencies, UNLIKE};
    use crate::checks::{BodyDeviation, CHECKS};
    use crate::events::{Event, Side};
    use crate::joint::Joint;
    use crate::score::{Advice, BodyLevel, Phase, PhaseTempo, Sink, Verdict};
    use crate::sequence::{Gap, GAPS};
    use crate::Vec3;

    /// A swing's body-level results: the phases' ratios, the checks' differences from the
    /// coach's (degrees or metres), the hips to chest gap's (seconds), each with a small stated
    /// uncertainty; how fast the coach's checks move (their unit per second).
    struct Swing {
        ratios: [f32; 3],
        checks: [f32; 9],
        gap: f32,
        rate: f32,
    }

    impl Swing {
        fn tell(&self, session: &mut Tendencies<'_>) -> bool {
            let tempo = [Phase::Backswing, Phase::Downswing, Phase::FollowThrough].map(|phase| {
                let ratio = self.ratios[phase as usize];
                PhaseTempo {
                    phase,
                    student_s: ratio,
                    coach_s: 1.0,
                    ratio,
                    ratio_uncertainty: 0.02 * ratio,
                    verdict: Verdict::Ok,
                }
            });
            let body: std::vec::Vec<BodyDeviation> = CHECKS
                .iter()
                .zip(self.checks)
                .map(|(check, d)| BodyDeviation {
                    check: *check,
                    student: 40.0 + d,
                    coach: 40.0,
                    uncertainty: if check.measure.in_degrees() {
                        2.0
                    } else {
                        0.01
                    },
                })
                .collect();
            let gaps = GAPS.map(|(first, then)| Gap {
                first,
                then,
                student_s: 0.03 + if first == GAPS[0].0 { self.gap } else { 0.0 },
                coach_s: 0.03,
                uncertainty_s: 0.005,
            });
            session.body(&BodyLevel {
                lead: Side::Left,
                tempo: &tempo,
                pause_s: (0.0, 0.0),
                body: &body,
                coach_rate: &[self.rate; 9],
                gaps: &gaps,
            })
        }
    }

    /// A swing whose backswing is `ratio` times the coach's and whose `check` is `by` off,
    /// every other quantity wobbling by `wobble` (a fraction of its tolerance).
    fn swing(ratio: f32, (check, by): (usize, f32), wobble: f32) -> Swing {
        let mut checks = CHECKS.map(|c| wobble * c.measure.tolerance() * 0.3);
        checks[check] += by;
        Swing {
            ratios: [ratio, 1.0 + 0.02 * wobble, 1.0 - 0.02 * wobble],
            checks,
            gap: 0.0,
            rate: 0.0,
        }
    }

    /// Wobbles of a few swings' worth, about zero.
    const WOBBLES: [f32; 10] = [0.3, -0.5, 0.1, 0.6, -0.2, -0.4, 0.5, -0.1, 0.2, -0.3];

    #[test]
    fn a_slow_backswing_in_every_swing_is_a_tendency_with_its_evidence() {
        let mut joints = [JointTallies::EMPTY; 17];
        let mut session = Tendencies::new(&mut joints);
        for (i, w) in WOBBLES.iter().enumerate() {
            swing(1.3 + 0.02 * w, (0, 0.0), *w).tell(&mut session);
            // One swing says nothing of the scatter: no tendency yet.
            if i == 0 {
                assert!(session.advice().is_empty());
            }
        }
        assert_eq!((session.swings(), session.used()), (10, 10));
        let advice = session.advice();
        assert_eq!(advice.len(), 1, "{advice:?}");
        let Advice::Tempo(t) = advice[0].advice else {
            panic!("{advice:?}");
        };
        assert_eq!((t.phase, t.verdict), (Phase::Backswing, Verdict::Slow));
        assert!((t.ratio - 1.3).abs() < 0.01, "{t:?}");
        let text = std::format!("{}", advice[0]);
        assert!(
            text.starts_with("Your backswing is 30 ± 1% slower")
                && text.ends_with("(in 10 of 10 swings)."),
            "{text}"
        );
    }

    #[test]
    fn a_half_swing_is_set_aside_with_why_and_moves_nothing() {
        let (mut a, mut b) = ([JointTallies::EMPTY; 17], [JointTallies::EMPTY; 17]);
        let (mut clean, mut with) = (Tendencies::new(&mut a), Tendencies::new(&mut b));
        for (i, w) in WOBBLES.iter().enumerate() {
            let s = swing(1.0 + 0.02 * w, (0, 0.0), *w);
            s.tell(&mut clean);
            s.tell(&mut with);
            if i == 4 {
                // Half the turn and half the backswing.
                let mut half = swing(0.5, (0, -45.0), *w);
                half.checks[1] -= 25.0;
                assert!(!half.tell(&mut with));
            }
        }
        assert_eq!((with.swings(), with.used()), (11, 10));
        let set_aside = with.set_aside();
        assert_eq!(set_aside.len(), 1);
        assert_eq!(set_aside[0].swing, 6);
        assert!(usize::from(set_aside[0].unlike) >= UNLIKE);
        assert!(matches!(
            set_aside[0].worst,
            Quantity::Tempo(Phase::Backswing) | Quantity::Check(0 | 1)
        ));
        for q in Quantity::BODY_LEVEL {
            assert_eq!(with.estimate(q), clean.estimate(q), "{q:?}");
        }
        assert!(with.advice().is_empty());
    }

    #[test]
    fn while_nothing_is_clear_the_nearest_question_is_named_with_the_swings_to_settle_it() {
        let mut joints = [JointTallies::EMPTY; 17];
        let mut session = Tendencies::new(&mut joints);
        // A shoulder turn 12° short with the scatter of a noisy phone: not clear in three.
        for by in [-4.0f32, -20.0, -12.0] {
            swing(1.0, (0, by), 0.0).tell(&mut session);
        }
        assert!(session.advice().is_empty());
        let open = session.open().expect("an open question");
        assert_eq!(open.quantity, Quantity::Check(0));
        assert!((open.estimate.value + 12.0).abs() < 0.1, "{open:?}");
        // (1.645 · 8 / 2)² ≈ 43 swings in all.
        assert!((35..=45).contains(&open.more_swings), "{open:?}");
    }

    #[test]
    fn the_hips_turn_at_impact_is_folded_under_the_gap_that_moves_it() {
        // The hips peak 45 ms less before the chest than the coach's, and at impact are 17°
        // less open (CHECKS[7]) where the coach's open at 400°/s: the gap accounts for 18°.
        let session = |rate: f32, joints: &mut [JointTallies]| {
            let mut session = Tendencies::new(joints);
            for w in WOBBLES {
                let mut s = swing(1.0, (7, 17.0 + 2.0 * w), w);
                (s.gap, s.rate) = (-0.045 + 0.004 * w, rate);
                s.tell(&mut session);
            }
            let advice = session.advice();
            (advice, session.estimate(Quantity::Gap(0)))
        };
        let mut joints = [JointTallies::EMPTY; 17];
        let (advice, gap) = session(-400.0, &mut joints);
        assert!(gap.is_some_and(|g| g.clears(0.03)), "{gap:?}");
        assert_eq!(advice.len(), 1, "{advice:?}");
        let Advice::Sequence(g, explains) = advice[0].advice else {
            panic!("{advice:?}");
        };
        assert_eq!((g.first, explains.check), (GAPS[0].0, Some(CHECKS[7])));
        let text = std::format!("{}", advice[0]);
        assert!(
            text.ends_with(
                "which is why at impact (P7) your hips are 17° more closed than the coach's (in \
                 10 of 10 swings)."
            ),
            "{text}"
        );
        // Where the coach's hips stood still at impact, the gap explains nothing of theirs.
        let (advice, _) = session(0.0, &mut joints);
        assert_eq!(advice.len(), 2, "{advice:?}");
        assert!(
            matches!(advice[0].advice, Advice::Body(b, _) if b.check == CHECKS[7]),
            "{advice:?}"
        );
    }

    #[test]
    fn a_joint_off_at_the_top_is_folded_under_the_short_turn_that_moves_it() {
        let mut joints = [JointTallies::EMPTY; 17];
        let mut session = Tendencies::new(&mut joints);
        let (wrist, k) = (Joint::LeftWrist, 13);
        for w in WOBBLES {
            swing(1.0, (0, -20.0 + w), w).tell(&mut session);
            for event in Event::ALL {
                let o = match event {
                    Event::Top => Vec3::new(0.12 + 0.01 * w, 0.0, 0.0),
                    _ => Vec3::new(0.005 * w, 0.0, 0.0),
                };
                session.offset((event, k, wrist), o, Vec3::repeat(0.01));
            }
        }
        let advice = session.advice();
        assert_eq!(advice.len(), 1, "{advice:?}");
        let Advice::Body(b, explains) = advice[0].advice else {
            panic!("{advice:?}");
        };
        assert_eq!(b.check, CHECKS[0]);
        let worst = explains.worst.expect("the wrist");
        assert_eq!(
            (worst.joint, worst.event, explains.joints),
            (wrist, Event::Top, 1)
        );
        // Without the turn, the wrist is an item of its own.
        let mut joints = [JointTallies::EMPTY; 17];
        let mut alone = Tendencies::new(&mut joints);
        for w in WOBBLES {
            swing(1.0, (0, 0.0), w).tell(&mut alone);
            let o = Vec3::new(0.12 + 0.01 * w, 0.0, 0.0);
            alone.offset((Event::Top, k, wrist), o, Vec3::repeat(0.01));
        }
        let advice = alone.advice();
        assert!(
            matches!(advice.as_slice(), [t] if matches!(t.advice, Advice::Spatial(d) if d.joint == wrist) && t.past == 10),
            "{advice:?}"
        );
        alone.reset();
        assert_eq!(alone.swings(), 0);
        assert!(alone.advice().is_empty());
    }

    #[test]
    fn the_wire_form_carries_the_estimates_the_tendencies_in_order_and_the_open_question() {
        use crate::config::BODY_LEVEL;
        let mut joints = [JointTallies::EMPTY; 17];
        let mut session = Tendencies::new(&mut joints);
        let (wrist, k) = (Joint::LeftWrist, 13);
        for w in WOBBLES {
            swing(1.3 + 0.02 * w, (0, 0.0), w).tell(&mut session);
            let o = Vec3::new(0.12 + 0.01 * w, 0.0, 0.0);
            session.offset((Event::Top, k, wrist), o, Vec3::repeat(0.01));
        }
        let wire = session.to_wire(3);
        assert_eq!((wire.swings, wire.used, wire.coach), (10, 10, 3));
        // Every body-level quantity was measured, in order; the backswing 1.3 s against the
        // coach's 1 s, slow in all ten.
        let order: std::vec::Vec<u8> = wire.metrics.iter().map(|m| m.quantity).collect();
        assert_eq!(order, (0..BODY_LEVEL as u8).collect::<std::vec::Vec<_>>());
        let back = wire.metrics[0];
        assert_eq!(
            (back.coach, back.verdict, back.above, back.swings),
            (1000, 1, 10, 10)
        );
        assert!((1295..=1305).contains(&back.student), "{back:?}");
        // The shoulder turn: 40° in tenths, within tolerance.
        assert_eq!((wire.metrics[4].coach, wire.metrics[4].verdict), (400, 0));
        // The tendencies as advice ranks them: the wrist (12 cm, its own item) and the slow
        // backswing, each pointing at what it is about.
        let advice = session.advice();
        assert_eq!(wire.tendencies.len(), advice.len());
        for (t, a) in wire.tendencies.iter().zip(&advice) {
            match a.advice {
                Advice::Tempo(_) => assert_eq!(t.item, 0),
                Advice::Spatial(d) => {
                    let spatial = wire.spatial[usize::from(t.item) - BODY_LEVEL];
                    assert_eq!(spatial.joint as usize, wrist.index());
                    assert_eq!(spatial.position, 3, "the top, P4");
                    assert!((115..=125).contains(&spatial.offset_mm[0]), "{spatial:?}");
                    assert_eq!(d.joint, wrist);
                }
                _ => panic!("{advice:?}"),
            }
            assert_eq!((t.swings, t.past), (a.swings, a.past));
        }
        assert_eq!(wire.spatial.len(), 1);
        assert_eq!(wire.open, None, "every quantity near advice is settled");
        // Nothing clear: the open question, in the check's tenths of a degree.
        let mut joints = [JointTallies::EMPTY; 17];
        let mut open = Tendencies::new(&mut joints);
        for by in [-4.0f32, -20.0, -12.0] {
            swing(1.0, (0, by), 0.0).tell(&mut open);
        }
        let wire = open.to_wire(0);
        assert!(wire.tendencies.is_empty());
        let question = wire.open.expect("an open question");
        assert_eq!(question.quantity, 4);
        assert!((-121..=-119).contains(&question.value), "{question:?}");
        assert!((35..=45).contains(&question.more_swings), "{question:?}");
    }
}
