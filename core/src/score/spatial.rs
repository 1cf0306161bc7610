//! The spatial stage: at each event the student's pose at its time against the coach's at its
//! own, in each swing's stance frame, both smoothed; each joint's offset beyond its usual one
//! ([`super::noise`]), with its uncertainty along the offset: its wander per axis (a camera's
//! depth axis is noisier) and, along its path, how far it moves within the event's timing
//! uncertainty. A joint is reported past the larger of [`SPATIAL_THRESHOLD_M`] and
//! [`NOISE_FACTOR`] times that uncertainty, at most [`DEVIATIONS_PER_EVENT`] an event, and a
//! joint next to one already listed, off the same way, is left out (one fact once). An offset
//! a body-level item explains is folded under it instead ([`super::cause`]).

use super::advice::{insert_sorted, Advice};
use super::align::Pair;
use super::cause::{Cause, Model};
use super::excess;
use super::noise::{judged, Noise};
use super::sink::Sink;
use super::timing::Timing;
use crate::body::Body;
use crate::config::{DEVIATIONS_PER_EVENT, MAX_DEVIATIONS};
use crate::events::{Event, SwingEvents};
use crate::joint::Joint;
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::Vec3;
use heapless::Vec as HVec;

/// Joint deviations at or below this (metres) are not reported.
pub const SPATIAL_THRESHOLD_M: f32 = 0.05;
/// Nor are those within this many times their uncertainty (how much the joint's offset from the
/// coach wanders over the swing): four standard deviations, the wander over one swing
/// understating an error that drifts over most of a second by about a fifth (its variance
/// around the swing's own median is 0.37 to 0.78 of the error's for correlation times of 1 to
/// 0.2 s over a 1.6 s swing).
pub const NOISE_FACTOR: f32 = 5.0;
/// The score's spatial scale: an event's worst excess of this many metres costs a factor `e`.
pub const SPATIAL_POINTS_M: f32 = 0.5;
/// Softness of the excess over a spatial threshold, metres: well below the threshold a
/// deviation costs next to nothing, past it the excess grows as the deviation does.
pub const SPATIAL_SOFTNESS_M: f32 = 0.01;

/// Axes of the golfer's stance frame, and the six directions along them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum Direction {
    TowardTarget,
    AwayFromTarget,
    TowardBall,
    AwayFromBall,
    Up,
    Down,
}

impl Direction {
    /// The snake_case name used in reports.
    pub const fn name(self) -> &'static str {
        match self {
            Direction::TowardTarget => "toward_target",
            Direction::AwayFromTarget => "away_from_target",
            Direction::TowardBall => "toward_ball",
            Direction::AwayFromBall => "away_from_ball",
            Direction::Up => "up",
            Direction::Down => "down",
        }
    }

    /// The words used in advice: "at the top your left wrist is 12 cm {lower}".
    pub const fn comparative(self) -> &'static str {
        match self {
            Direction::TowardTarget => "closer to the target",
            Direction::AwayFromTarget => "farther from the target",
            Direction::TowardBall => "closer to the ball",
            Direction::AwayFromBall => "farther from the ball",
            Direction::Up => "higher",
            Direction::Down => "lower",
        }
    }

    /// The stance direction of `offset`'s largest component.
    pub fn of(offset: Vec3) -> Direction {
        let axis = offset.iamax();
        match (axis, offset[axis] > 0.0) {
            (0, true) => Direction::TowardTarget,
            (0, false) => Direction::AwayFromTarget,
            (1, true) => Direction::TowardBall,
            (1, false) => Direction::AwayFromBall,
            (_, true) => Direction::Up,
            (_, false) => Direction::Down,
        }
    }
}

/// A joint off the coach's position at an event.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Deviation {
    /// The event.
    pub event: Event,
    /// The joint.
    pub joint: Joint,
    /// Length of the offset, metres.
    pub distance_m: f32,
    /// Its uncertainty along it, metres: how much this joint's offset from the coach wanders
    /// over the whole swing (pose noise, and what the retargeting cannot match), and how far
    /// the joint moves within the event's timing uncertainty.
    pub uncertainty_m: f32,
    /// Student minus coach in the stance frame: toward target, toward ball, up (metres).
    pub offset_m: [f32; 3],
    /// The offset's largest component.
    pub direction: Direction,
}

/// How far past the larger of [`SPATIAL_THRESHOLD_M`] and [`NOISE_FACTOR`] times its
/// uncertainty an offset of `distance` metres is, as a multiple of that.
pub(super) fn severity(distance: f32, uncertainty: f32) -> f32 {
    distance / SPATIAL_THRESHOLD_M.max(NOISE_FACTOR * uncertainty)
}

/// What the spatial stage finds.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Spatial {
    /// At each event, up to [`DEVIATIONS_PER_EVENT`] joints past their threshold, the most
    /// severe first.
    pub deviations: HVec<Deviation, MAX_DEVIATIONS>,
    /// Each event's worst joint's excess over its threshold, summed: what the score is
    /// docked, metres.
    pub excess: f32,
}

/// The deviations of `pair`'s student (its events `events`) from its coach (at `coach_hz`),
/// with the noise and timing the earlier stages found; an offset a cause explains is folded
/// under it ([`super::cause`]). Every judged joint's offset goes to `sink` where there is one.
pub(super) fn spatial(
    skeleton: &Skeleton,
    pair: &Pair<'_>,
    (events, coach_hz): (&SwingEvents, f32),
    (noise, timing): (&Noise, &Timing),
    (causes, mut sink): (&mut [Cause], Option<&mut dyn Sink>),
) -> Spatial {
    let mut out = Spatial {
        deviations: HVec::new(),
        excess: 0.0,
    };
    let body = Body::new(skeleton, events.lead).ok();
    for event in Event::ALL {
        let Some(x) = events.time(event) else {
            continue;
        };
        // The coach frames the event's timing uncertainty spans.
        let h = (timing.event[event as usize] * coach_hz).max(0.5);
        let model = body
            .as_ref()
            .and_then(|b| Model::at((pair, b), noise, causes, (event, x)));
        let (worst, excess) = at_event(
            skeleton,
            pair,
            (event, x, h),
            noise,
            (model, causes, reborrow(&mut sink)),
        );
        for d in one_fact_once(skeleton, worst) {
            let _ = out.deviations.push(d);
        }
        out.excess += excess;
    }
    out
}

/// `sink` lent for one call (the trait object's lifetime shortened to the loan's).
fn reborrow<'a>(sink: &'a mut Option<&mut dyn Sink>) -> Option<&'a mut dyn Sink> {
    match sink {
        Some(s) => Some(&mut **s),
        None => None,
    }
}

/// The worst joints at `event` (the student's frame `x`; the coach's timing uncertainty `h`
/// frames) that no cause explains (by `model`, where a cause reaches the event), and the worst
/// one's excess over its threshold; each judged joint's offset to `sink`.
fn at_event(
    skeleton: &Skeleton,
    pair: &Pair<'_>,
    (event, x, h): (Event, f32, f32),
    noise: &Noise,
    (model, causes, mut sink): (Option<Model>, &mut [Cause], Option<&mut dyn Sink>),
) -> (HVec<Deviation, DEVIATIONS_PER_EVENT>, f32) {
    let mut worst: HVec<Deviation, DEVIATIONS_PER_EVENT> = HVec::new();
    let mut event_excess = 0.0f32;
    let (half_s, half_c) = pair.half;
    let c = pair.time_map.at(x);
    for (k, sigma) in noise.wander.iter().enumerate().take(skeleton.len()) {
        let Some(joint) = skeleton.joint(k).filter(|_| judged(skeleton, k)) else {
            continue;
        };
        // A joint the stream was unsure of around the event is not judged there.
        if pair.unsure_near(k, x, half_s) {
            continue;
        }
        // This moment's own offset, beyond the joint's usual one.
        let o = pair.offset(k, x, pair.half) - noise.usual[k];
        let distance_m = norm(&o);
        // The uncertainty along the offset: the wander in that direction (a camera's depth
        // axis is noisier than the two across it) and, along the joint's path, how far it
        // moves in the event's timing uncertainty.
        let along = (pair.stance_c.local(pair.coach_at(k, c + h, half_c))
            - pair.stance_c.local(pair.coach_at(k, c - h, half_c)))
            * 0.5;
        if let Some(sink) = sink.as_deref_mut() {
            let per_axis = sigma.zip_map(&along, crate::math::hypot);
            sink.offset((event, k, joint), o, per_axis);
        }
        let uncertainty_m = match o.try_normalize(f32::MIN_POSITIVE) {
            Some(u) => crate::math::hypot(norm(&sigma.component_mul(&u)), along.dot(&u)),
            None => crate::math::hypot(norm(sigma), norm(&along)) / crate::math::sqrt(3.0),
        };
        let threshold = SPATIAL_THRESHOLD_M.max(NOISE_FACTOR * uncertainty_m);
        event_excess = event_excess.max(excess(distance_m, threshold, SPATIAL_SOFTNESS_M));
        if distance_m <= threshold {
            continue;
        }
        let deviation = Deviation {
            event,
            joint,
            distance_m,
            uncertainty_m,
            offset_m: [o.x, o.y, o.z],
            direction: Direction::of(o),
        };
        let coach = || pair.stance_c.local(pair.coach_at(k, c, half_c));
        match model
            .as_ref()
            .and_then(|m| m.explains(joint, (o, coach()), threshold))
        {
            Some(i) => causes[i].explains.add(&deviation),
            None => insert_sorted(&mut worst, deviation, Advice::severity_of),
        }
    }
    (worst, event_excess)
}

/// `worst` without a joint next to one kept before it, off the same way: one fact once.
fn one_fact_once(
    skeleton: &Skeleton,
    worst: HVec<Deviation, DEVIATIONS_PER_EVENT>,
) -> HVec<Deviation, DEVIATIONS_PER_EVENT> {
    let mut kept: HVec<Deviation, DEVIATIONS_PER_EVENT> = HVec::new();
    for d in worst {
        let k = skeleton.index_of(d.joint);
        let adjacent = |e: &Deviation| {
            let j = skeleton.index_of(e.joint);
            e.direction == d.direction
                && (k.and_then(|k| skeleton.parent(k)) == j
                    || j.and_then(|j| skeleton.parent(j)) == k)
        };
        if !kept.iter().any(adjacent) {
            let _ = kept.push(d);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::{one_fact_once, Deviation, Direction};
    use crate::events::Event;
    use crate::format::Format;
    use crate::joint::Joint;
    use crate::skeleton::Skeleton;
    use crate::Vec3;
    use heapless::Vec as HVec;

    #[test]
    fn a_direction_is_its_largest_components() {
        assert_eq!(
            Direction::of(Vec3::new(0.1, -0.2, 0.05)),
            Direction::AwayFromBall
        );
        assert_eq!(
            Direction::of(Vec3::new(-0.3, 0.2, 0.05)),
            Direction::AwayFromTarget
        );
        assert_eq!(Direction::of(Vec3::new(0.0, 0.0, 0.01)), Direction::Up);
    }

    #[test]
    fn a_joint_next_to_one_listed_and_off_the_same_way_is_left_out() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let at = |joint, direction| Deviation {
            event: Event::Top,
            joint,
            distance_m: 0.1,
            uncertainty_m: 0.01,
            offset_m: [0.1, 0.0, 0.0],
            direction,
        };
        let worst: HVec<Deviation, 3> = [
            at(Joint::LeftWrist, Direction::TowardTarget),
            at(Joint::LeftElbow, Direction::TowardTarget),
            at(Joint::LeftShoulder, Direction::Up),
        ]
        .into_iter()
        .collect();
        let kept = one_fact_once(&skeleton, worst);
        let joints: std::vec::Vec<Joint> = kept.iter().map(|d| d.joint).collect();
        // The elbow is the wrist's parent, off the same way; the shoulder, though the elbow's
        // parent, is off another way.
        assert_eq!(joints, [Joint::LeftWrist, Joint::LeftShoulder]);
    }
}
