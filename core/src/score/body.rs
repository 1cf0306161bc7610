//! The body stage: the body checks ([`CHECKS`], see [`crate::checks`]) and the kinematic
//! sequence's gaps ([`crate::sequence`]) of the student against the coach.
//!
//! A check reads both swings' poses as the joint comparison does ([`Pair`]): the student's at
//! the position, the coach's at its matching frame. Its uncertainty: each joint the check is
//! measured from moved by the input's noise along each stance axis, at the position and at
//! address (`√2`), and the coach's change within the event's timing uncertainty. A joint the
//! stream was unsure of at the position or at address is bridged from where it was sure
//! ([`Pair::bridged`]: the coach's joint moved by the offset from the coach interpolated
//! across), and moves by half the offset's change across too (its wander, where it was held
//! from one side); a check is not made where such a joint
//! cannot be bridged, nor, where the input held the root still, the pelvis's sway and thrust.

use super::align::Pair;
use super::noise::Noise;
use super::timing::Timing;
use crate::body::{Body, Measure};
use crate::checks::{BodyDeviation, CHECKS};
use crate::config::{MAX_CHECKS, MAX_GAPS, MAX_JOINTS};
use crate::events::{Event, Position, SwingEvents};
use crate::sequence::{self, Downswing, Gap};
use crate::skeleton::Skeleton;
use crate::Vec3;
use heapless::Vec as HVec;

/// The least noise per axis a body check's uncertainty is measured with, metres.
pub const LEAST_NOISE_M: f32 = 0.001;

/// Every joint of the student (`student` true) or the coach at its frame `x`, as the joint
/// comparison reads them.
fn pose(pair: &Pair<'_>, student: bool, joints: usize, x: f32, out: &mut [Vec3; MAX_JOINTS]) {
    let (half_s, half_c) = pair.half;
    for (k, p) in out.iter_mut().enumerate().take(joints) {
        *p = match student {
            true => pair.student_at(k, x, half_s),
            false => pair.coach_at(k, x, half_c),
        };
    }
}

/// The body checks a swing could be measured at, and how fast the coach's value of each moves
/// there.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Checks {
    /// The checks, in [`CHECKS`] order.
    pub found: HVec<BodyDeviation, MAX_CHECKS>,
    /// For each check found, in its order: the rate of change of the coach's value at its
    /// position, its unit per second, across the event's timing uncertainty (at least half a
    /// frame each way).
    pub coach_rate: HVec<f32, MAX_CHECKS>,
}

/// The body checks of `pair`'s student (events `events.0`) against its coach (events
/// `events.1`, at `coach_hz`), with the noise and timing the earlier stages found: those both
/// swings could be measured at, in [`CHECKS`] order. None for a skeleton that lacks a joint the
/// metrics need.
#[inline(never)]
pub(super) fn checks(
    skeleton: &Skeleton,
    pair: &Pair<'_>,
    (events, hz): ((&SwingEvents, &SwingEvents), (f32, f32)),
    noise: &Noise,
    timing: &Timing,
) -> Checks {
    let coach_hz = hz.1;
    let mut out = Checks::default();
    let joints = skeleton.len();
    let (events_s, events_c) = events;
    let (Ok(body_s), Ok(body_c)) = (
        Body::new(skeleton, events_s.lead),
        Body::new(skeleton, events_c.lead),
    ) else {
        return out;
    };
    let (Some(from_s), Some(from_c)) =
        (events_s.time(Event::Address), events_c.time(Event::Address))
    else {
        return out;
    };
    let [mut address_s, mut address_c, mut at_s, mut coach] = [[Vec3::zeros(); MAX_JOINTS]; 4];
    pose(pair, true, joints, from_s, &mut address_s);
    let at_address = bridge(pair, joints, from_s, hz.0, &mut address_s);
    pose(pair, false, joints, from_c, &mut address_c);
    let (address_s, address_c) = (&address_s[..joints], &address_c[..joints]);
    let (stance_s, stance_c) = (&pair.stance_s, &pair.stance_c);
    let axes = [stance_s.toward_target(), stance_s.toward_ball(), Vec3::y()];
    let mut at: Option<Position> = None;
    let mut at_position = Bridged::default();
    for check in CHECKS {
        let shift = matches!(check.measure, Measure::PelvisSway | Measure::PelvisThrust);
        let Some(event) = check
            .position
            .event()
            .filter(|_| !(pair.root_held && shift))
        else {
            continue;
        };
        let Some(x) = events_s.time(event) else {
            continue;
        };
        let c = pair.time_map.at(x);
        // Each position's student pose once; the coach's made again for each check, in one
        // buffer (the stack is the device's scarcest memory).
        let h = (timing.event[event as usize] * coach_hz).max(0.5);
        if at != Some(check.position) {
            at = Some(check.position);
            pose(pair, true, joints, x, &mut at_s);
            at_position = bridge(pair, joints, x, hz.0, &mut at_s);
        }
        let measure = check.measure;
        let value_s = |pose: &[Vec3]| body_s.value(measure, stance_s, address_s, pose);
        let value_c = |pose: &[Vec3]| body_c.value(measure, stance_c, address_c, pose);
        let mut coach_at = |x: f32| {
            pose(pair, false, joints, x, &mut coach);
            value_c(&coach[..joints])
        };
        let (Some(zero_s), Some(here_s), Some(zero_c), Some(here_c)) = (
            value_s(address_s),
            value_s(&at_s[..joints]),
            value_c(address_c),
            coach_at(c),
        ) else {
            continue;
        };
        let moved_by = body_s.joints_of(measure);
        let lost = at_position.lost | at_address.lost;
        if moved_by.iter().any(|&k| lost & (1 << k) != 0) {
            continue;
        }
        // Each joint it is measured from moved by the noise along each axis, at the position
        // and at address; a bridged joint by its interpolation's error too.
        let mut variance = 0.0f32;
        for &k in &moved_by {
            // A bridged joint's interpolation error per axis, found once: half its offset's
            // change across, or its wander where it was held from one side.
            let error = |b: &Bridged, x: f32| {
                (b.joints & (1 << k) != 0)
                    .then(|| pair.bridged(k, x, hz.0))
                    .flatten()
                    .map_or(Vec3::zeros(), |(_, across)| {
                        across.unwrap_or_else(|| noise.wander.get(k).copied().unwrap_or_default())
                    })
            };
            let errors = [error(&at_position, x), error(&at_address, from_s)];
            for (axis, direction) in axes.iter().enumerate() {
                let n = noise.input[axis].max(LEAST_NOISE_M);
                let spread = |e: &Vec3| n * n + e[axis] * e[axis];
                let kept = at_s[k];
                at_s[k] = kept + direction * n;
                let moved = value_s(&at_s[..joints]);
                at_s[k] = kept;
                let d = moved.map_or(0.0, |m| m - here_s) / n;
                variance += d * d * (spread(&errors[0]) + spread(&errors[1]));
            }
        }
        // The coach's change within the event's timing uncertainty, and so its rate.
        let along = match (coach_at(c + h), coach_at(c - h)) {
            (Some(l), Some(e)) => 0.5 * (l - e),
            _ => 0.0,
        };
        let _ = out.found.push(BodyDeviation {
            check,
            student: here_s - zero_s,
            coach: here_c - zero_c,
            uncertainty: crate::math::sqrt(variance + along * along),
        });
        let _ = out.coach_rate.push(along / h * coach_hz);
    }
    out
}

/// The joints of a student's pose the stream was unsure of (bits by joint index): those
/// [`bridge`]d, and those it could not bridge.
#[derive(Clone, Copy, Debug, Default)]
struct Bridged {
    joints: u64,
    lost: u64,
}

/// Bridges each of the first `joints` joints of `out`, the student's pose at its frame `x` (at
/// `hz`), that the stream was unsure of there ([`Pair::bridged`]).
#[inline(never)]
fn bridge(
    pair: &Pair<'_>,
    joints: usize,
    x: f32,
    hz: f32,
    out: &mut [Vec3; MAX_JOINTS],
) -> Bridged {
    let mut found = Bridged::default();
    for (k, p) in out.iter_mut().enumerate().take(joints.min(64)) {
        if !pair.unsure_near(k, x, pair.half.0) {
            continue;
        }
        match pair.bridged(k, x, hz) {
            Some((bridged, _)) => {
                *p = bridged;
                found.joints |= 1 << k;
            }
            None => found.lost |= 1 << k,
        }
    }
    found
}

/// The gaps of the kinematic sequence of `pair`'s student (events `events.0` at `hz.0`)
/// against its coach's (events `events.1` at `hz.1`), on the swings as they lie.
pub(super) fn gaps(
    skeleton: &Skeleton,
    pair: &Pair<'_>,
    events: (&SwingEvents, &SwingEvents),
    hz: (f32, f32),
) -> HVec<Gap, MAX_GAPS> {
    let (Ok(body_s), Ok(body_c)) = (
        Body::new(skeleton, events.0.lead),
        Body::new(skeleton, events.1.lead),
    ) else {
        return HVec::new();
    };
    sequence::gaps(
        &Downswing {
            body: &body_s,
            positions: pair.student,
            hz: hz.0,
            events: events.0,
        },
        &Downswing {
            body: &body_c,
            positions: pair.coach,
            hz: hz.1,
            events: events.1,
        },
        &|k, from, to| pair.unsure_between(k, from, to),
    )
}

#[cfg(test)]
mod tests {
    use super::checks;
    use crate::body::Measure;
    use crate::events::{Event, Position};
    use crate::format::Format;
    use crate::score::align::tests::events;
    use crate::score::align::Pair;
    use crate::score::noise::Noise;
    use crate::score::timing::Timing;
    use crate::score::{Detected, Unsure};
    use crate::skeleton::Skeleton;
    use crate::Vec3;

    /// A standing skeleton's 100 frames, everything above the hips turned `degrees` about the
    /// vertical through the pelvis from frame 30 on.
    fn swing(skeleton: &Skeleton, degrees: f32) -> std::vec::Vec<Vec3> {
        let mut rest = [Vec3::zeros(); 17];
        skeleton.rest_positions(&mut rest);
        let pelvis = rest[0];
        let (sin, cos) = degrees.to_radians().sin_cos();
        let mut out = std::vec::Vec::new();
        for f in 0..100 {
            for p in rest {
                let d = p - pelvis;
                let turned = f >= 30 && d.y > 0.1;
                out.push(match turned {
                    true => pelvis + Vec3::new(cos * d.x + sin * d.z, d.y, -sin * d.x + cos * d.z),
                    false => p,
                });
            }
        }
        out
    }

    /// The checks of `student` against `coach` (17 joints at 30 Hz, the same events), with a
    /// centimetre of noise and 10 ms of timing uncertainty.
    fn checks_of(skeleton: &Skeleton, student: &[Vec3], coach: &[Vec3]) -> super::Checks {
        let frames = events([10, 20, 30, 40, 50, 60, 70, 90]);
        let detected = |positions| Detected {
            positions: crate::frames::Frames::metres(positions, 17),
            hz: 30.0,
            events: frames,
            unsure: Unsure::default(),
        };
        let (student, coach) = (detected(student), detected(coach));
        let pair = Pair::new(skeleton, (&student, &frames), &coach);
        let noise = Noise {
            usual: [Vec3::zeros(); 40],
            wander: [Vec3::zeros(); 40],
            input: Vec3::repeat(0.01),
        };
        let timing = Timing {
            event: [0.01; Event::COUNT],
            top_gain: 0.0,
            paused: false,
        };
        checks(
            skeleton,
            &pair,
            ((&frames, &frames), (30.0, 30.0)),
            &noise,
            &timing,
        )
    }

    #[test]
    fn the_coachs_rate_is_how_fast_its_value_moves_at_the_position() {
        // The coach's whole body turning 2° a frame at 30 Hz from frame 30 on (the student
        // still): its hips' turn moves at 60°/s at impact, its head's lift not at all.
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let mut rest = [Vec3::zeros(); 17];
        skeleton.rest_positions(&mut rest);
        let mut coach = std::vec::Vec::new();
        for f in 0..100 {
            let (sin, cos) = (2.0 * f.max(30) as f32 - 60.0).to_radians().sin_cos();
            coach.extend(
                rest.iter()
                    .map(|d| Vec3::new(cos * d.x + sin * d.z, d.y, -sin * d.x + cos * d.z)),
            );
        }
        let student = swing(&skeleton, 0.0);
        let found = checks_of(&skeleton, &student, &coach);
        let rate = |measure| {
            let i = found
                .found
                .iter()
                .position(|b| b.check.position == Position::P7 && b.check.measure == measure)
                .unwrap();
            found.coach_rate[i]
        };
        assert!(
            (rate(Measure::PelvisTurn).abs() - 60.0).abs() < 0.5,
            "{found:?}"
        );
        assert!(rate(Measure::HeadLift).abs() < 1e-3, "{found:?}");
    }

    #[test]
    fn a_turned_chest_reads_as_the_thorax_turn_alone_within_its_uncertainty() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let (student, coach) = (swing(&skeleton, 25.0), swing(&skeleton, 0.0));
        let found = checks_of(&skeleton, &student, &coach);
        let at = |measure| {
            found
                .found
                .iter()
                .find(|b| b.check.position == Position::P4 && b.check.measure == measure)
                .unwrap()
        };
        let (thorax, pelvis) = (at(Measure::ThoraxTurn), at(Measure::PelvisTurn));
        assert!(
            (libm::fabsf(thorax.student - thorax.coach) - 25.0).abs() < 0.5,
            "{thorax:?}"
        );
        assert!(
            thorax.uncertainty > 0.1 && thorax.uncertainty < 5.0,
            "{thorax:?}"
        );
        assert!(
            libm::fabsf(pelvis.student - pelvis.coach) < 0.5,
            "{pelvis:?}"
        );
    }
}
