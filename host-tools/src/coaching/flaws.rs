//! Flaws planted in a clean swing, and the truth each leaves: the tempo it changes, or the
//! joints it moves at each event and which way.
//!
//! A swing is given on the student's body at a timeline rate, starting at the takeaway (the
//! golfer is still before its first frame), with its events in seconds from there, found in
//! the source swing with its club at the source's own rate.

use posecoach_core::body::Link;
use posecoach_core::body::{self, Metrics, Stance};
use posecoach_core::checks::{Check, CHECKS};
use posecoach_core::events::{Event, Side, SwingEvents};
use posecoach_core::joint::Joint;
use posecoach_core::score::{Direction, Phase, Verdict};
use posecoach_core::sequence::{self, GAPS, GAP_TOLERANCE_S};
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
use posecoach_io::Motion;
use serde::Serialize;

/// A change of body position, in the stance frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Body {
    /// The hips move toward the ball from the top through impact.
    EarlyExtension,
    /// The hips slide away from the target in the backswing.
    Sway,
    /// The head drops in the backswing and stays down.
    HeadDown,
    /// The shoulders turn less in the backswing.
    ReducedTurn,
    /// The lead elbow bends at the top.
    BentLeadArm,
    /// The chest (and everything it carries) moves ahead of time in the downswing, so it peaks
    /// `size` ms early.
    UpperBodyFirst,
}

impl Body {
    /// Every kind.
    pub const ALL: [Body; 6] = [
        Body::EarlyExtension,
        Body::Sway,
        Body::HeadDown,
        Body::ReducedTurn,
        Body::BentLeadArm,
        Body::UpperBodyFirst,
    ];
}

/// One planted flaw.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Flaw {
    /// A phase takes `factor` times as long.
    Tempo {
        /// The phase.
        phase: Phase,
        /// Its duration over the clean swing's.
        factor: f32,
    },
    /// The hands wait at the top for `seconds` (part of the backswing).
    Pause {
        /// How long.
        seconds: f32,
    },
    /// A joint (with the joints it carries) off by `metres` in `direction` around an event.
    Offset {
        /// When.
        event: Event,
        /// Which joint.
        joint: Joint,
        /// Which way.
        direction: Direction,
        /// How far.
        metres: f32,
    },
    /// A body-level fault of `size` (metres; degrees for the turn and the lead arm; ms for the
    /// upper body first).
    Body {
        /// Which.
        body: Body,
        /// How much.
        size: f32,
    },
}

impl Flaw {
    /// Its size in the unit the benchmark bins it by: cm, % of a phase, or the body's own.
    pub fn size(&self) -> f32 {
        match *self {
            Flaw::Tempo { factor, .. } => (factor - 1.0).abs() * 100.0,
            Flaw::Pause { seconds } => seconds * 1000.0,
            Flaw::Offset { metres, .. } => metres * 100.0,
            Flaw::Body { size, .. } => size,
        }
    }
}

/// What a flawed swing should be told: a tempo verdict, a joint off at an event, or a body
/// check off the coach's.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Truth {
    /// This phase is slow or fast.
    Tempo {
        /// The phase.
        phase: Phase,
        /// Its verdict.
        verdict: Verdict,
    },
    /// This joint is off this way at this event.
    Spatial {
        /// When.
        event: Event,
        /// Which joint.
        joint: Joint,
        /// Which way.
        direction: Direction,
    },
    /// This check's change since address is past its tolerance from the clean swing's.
    Body {
        /// Which.
        check: Check,
        /// More than the clean swing's (else less).
        more: bool,
    },
    /// This gap of the kinematic sequence is past its tolerance from the clean swing's.
    Sequence {
        /// The link that should peak first.
        first: Link,
        /// The link that should peak after it.
        then: Link,
        /// Longer than the clean swing's (else shorter).
        more: bool,
    },
}

/// The events in seconds from the takeaway, [`Event::ALL`] order (the takeaway is 0).
pub type Times = [f32; 8];

/// A swing's events in seconds from its first frame, found at `rate_hz`.
pub fn times(events: &SwingEvents, rate_hz: f32) -> Times {
    Event::ALL.map(|e| events.time(e).map_or(f32::NAN, |t| t / rate_hz))
}

/// An offset flaw lasts at least this long either side of its event, seconds.
pub const OFFSET_HALF_S: f32 = 0.1;

/// A displacement counts toward the truth when it is at least this share of the flaw's largest.
pub const TRUTH_SHARE: f32 = 0.7;
/// A displacement shorter than this (metres) shows nothing.
pub const SHOWN_M: f32 = 0.01;

/// A flawed swing and what it should be told.
pub struct Planted {
    /// The swing, at the clean swing's rate, from the takeaway.
    pub swing: Motion,
    /// Its own events, seconds from the takeaway: where its club is where the clean swing's
    /// was at its events (the upper body first brings them early).
    pub times: Times,
    /// Backswing over downswing.
    pub tempo_ratio: f32,
    /// Every statement true of the flawed swing as a report measures it (each swing at its own
    /// events) that the flaws make.
    pub truths: Vec<Truth>,
    /// Of its body-level truths, those that are the flaws themselves: a check they move past its
    /// tolerance with the moment held (the same time in both swings), a gap. The others are
    /// consequences: a check that differs only because a flaw moved the events it is read
    /// at, as the upper body first moves impact against the hips.
    pub causes: Vec<Truth>,
    /// The largest displacement the flaws leave at an event, metres (an offset on a body that
    /// keeps its bones' lengths shows less than was planted).
    pub shown_m: f32,
    /// Each body check's change since address less the clean swing's, each at its own events
    /// ([`CHECKS`] order).
    pub checks: [Option<f32>; CHECKS.len()],
    /// Each gap of the sequence less the clean swing's, seconds ([`GAPS`] order).
    pub gaps: [Option<f32>; GAPS.len()],
}

/// Plants `flaws` in `clean` (on its body, at its rate, from the takeaway) whose events are
/// `times` and whose lead side is `lead`.
pub fn plant(clean: &Motion, times: &Times, lead: Side, flaws: &[Flaw]) -> Planted {
    let (warped, warped_times) = warp(clean, times, flaws);
    let own = own_times(&warped_times, flaws);
    let skeleton = &clean.skeleton;
    let joints = skeleton.len();
    let mut moved = warped.clone();
    for flaw in flaws {
        move_joints(&mut moved, &warped_times, lead, flaw);
    }
    // A body keeps its bones' lengths: the moved joints are put back on the skeleton as its
    // bones' directions (the analytic retargeter onto the same skeleton, as the device fits
    // what it receives), so an offset knee turns the thigh and the shin with it. The truth is
    // what this body shows.
    let spatial = flaws
        .iter()
        .any(|f| matches!(f, Flaw::Offset { .. } | Flaw::Body { .. }));
    let swing = match spatial {
        true => moved.retarget_analytic(&moved).unwrap_or(moved),
        false => moved,
    };
    // Each swing in its own stance frame, as the report sees it: a flaw that moves the feet
    // with the rest (a whole body shifted at address) shows nothing.
    let (stance_flawed, stance_clean) = (
        Stance::new(skeleton, swing.frame(0), lead),
        Stance::new(skeleton, warped.frame(0), lead),
    );
    let at = |m: &Motion, t: f32, k: usize| {
        let x = (t * m.rate_hz).clamp(0.0, (m.frames() - 1) as f32);
        let (i, w) = (x.floor() as usize, x.fract());
        let j = (i + 1).min(m.frames() - 1);
        m.positions[i * joints + k] * (1.0 - w) + m.positions[j * joints + k] * w
    };
    // Displacements at each event, in the stance frame, each swing at its own.
    let mut moved = Vec::new();
    for ((e, &t), &u) in Event::ALL.iter().zip(&warped_times).zip(&own) {
        for k in 0..joints {
            let Some(joint) = skeleton.joint(k) else {
                continue;
            };
            let d = stance_flawed.local(at(&swing, u, k)) - stance_clean.local(at(&warped, t, k));
            moved.push((*e, joint, d));
        }
    }
    let largest = moved.iter().map(|m| m.2.norm()).fold(0.0, f32::max);
    let mut truths: Vec<Truth> = moved
        .iter()
        .filter(|m| m.2.norm() >= (TRUTH_SHARE * largest).max(SHOWN_M))
        .map(|&(event, joint, d)| Truth::Spatial {
            event,
            joint,
            direction: Direction::of(d),
        })
        .collect();
    for flaw in flaws {
        let (phase, slow) = match *flaw {
            Flaw::Tempo { phase, factor } => (phase, factor > 1.0),
            Flaw::Pause { .. } => (Phase::Backswing, true),
            _ => continue,
        };
        truths.push(Truth::Tempo {
            phase,
            verdict: if slow { Verdict::Slow } else { Verdict::Fast },
        });
    }
    // The body checks and gaps the flaws move past their tolerances: each swing at its own
    // events, and with the moment held for the flaw itself.
    let checks = check_differences((&swing, &own), (&warped, &warped_times), lead);
    let held = check_differences((&swing, &warped_times), (&warped, &warped_times), lead);
    let gaps = gap_differences((&swing, &own), (&warped, &warped_times), lead);
    let mut causes = Vec::new();
    for ((check, d), d_held) in CHECKS.iter().zip(&checks).zip(&held) {
        let past = |d: &f32| d.abs() > check.measure.tolerance();
        if let Some(d) = d.filter(past) {
            let truth = Truth::Body {
                check: *check,
                more: d > 0.0,
            };
            truths.push(truth);
            if d_held.is_some_and(|h| past(&h) && (h > 0.0) == (d > 0.0)) {
                causes.push(truth);
            }
        }
    }
    for ((first, then), d) in GAPS.iter().zip(&gaps) {
        if let Some(d) = d.filter(|d| d.abs() > GAP_TOLERANCE_S) {
            let truth = Truth::Sequence {
                first: *first,
                then: *then,
                more: d > 0.0,
            };
            truths.push(truth);
            causes.push(truth);
        }
    }
    let (top, impact) = (Event::Top as usize, Event::Impact as usize);
    Planted {
        swing,
        tempo_ratio: own[top] / (own[impact] - own[top]),
        times: own,
        truths,
        causes,
        shown_m: largest,
        checks,
        gaps,
    }
}

/// The events of a swing with `flaws` planted at events `times` (seconds from the takeaway):
/// where its club is where the clean swing's was at its events. Events are read from the club
/// and the arms, which the upper body carries: the upper body first brings each event as much
/// early as it is ahead of time there ([`ahead`]); no other flaw moves them.
fn own_times(times: &Times, flaws: &[Flaw]) -> Times {
    let Some(size) = flaws.iter().find_map(|f| match *f {
        Flaw::Body {
            body: Body::UpperBodyFirst,
            size,
        } => Some(size),
        _ => None,
    }) else {
        return *times;
    };
    // `u + ahead(u)` grows with `u` (the lead fades over much longer than it lasts): the
    // moment it reaches the clean event, by bisection.
    times.map(|t| {
        let (mut lo, mut hi) = (t - size / 1000.0, t);
        for _ in 0..32 {
            let mid = 0.5 * (lo + hi);
            if mid + ahead(mid, times, size) < t {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    })
}

/// How far ahead of its time the upper body first of `size` ms has the upper body at time `u`
/// of a swing whose events are at `times` (seconds from the takeaway): the lead grows from
/// halfway back to the top and fades from impact to the finish, seconds.
fn ahead(u: f32, times: &Times, size: f32) -> f32 {
    let t = |e: Event| times[e as usize];
    size / 1000.0
        * bump(u, t(Event::MidBackswing), t(Event::Top), t(Event::Top))
        * bump(u, t(Event::Impact), t(Event::Impact), t(Event::Finish))
}

/// Each body check's change since address, `flawed`'s less `clean`'s (each a swing and the
/// events it is read at, in its own stance frame), [`CHECKS`] order; `None` where one cannot
/// be measured.
fn check_differences(
    flawed: (&Motion, &Times),
    clean: (&Motion, &Times),
    lead: Side,
) -> [Option<f32>; CHECKS.len()] {
    let (clean, clean_times) = clean;
    let skeleton = &clean.skeleton;
    let Ok(body) = body::Body::new(skeleton, lead) else {
        return [None; CHECKS.len()];
    };
    let pose = |m: &Motion, t: f32| -> Vec<Vec3> {
        let x = (t * m.rate_hz).clamp(0.0, (m.frames() - 1) as f32);
        let (i, w) = (x.floor() as usize, x.fract());
        let (a, b) = (m.frame(i), m.frame((i + 1).min(m.frames() - 1)));
        a.iter().zip(b).map(|(a, b)| a + (b - a) * w).collect()
    };
    // The metrics at address and at `t`.
    let metrics = |m: &Motion, t: f32| -> Option<(Metrics, Metrics)> {
        let address = pose(m, 0.0);
        let stance = Stance::new(skeleton, &address, lead);
        Some((
            body.measure(&stance, &address, &address)?,
            body.measure(&stance, &address, &pose(m, t))?,
        ))
    };
    CHECKS.map(|check| {
        let e = check.position.event()? as usize;
        let change = |(m, times): (&Motion, &Times)| {
            let (zero, at) = metrics(m, times[e])?;
            check.change(&zero, &at)
        };
        Some(change(flawed)? - change((clean, clean_times))?)
    })
}

/// Each gap of the kinematic sequence ([`GAPS`]), `flawed`'s less `clean`'s (each a swing and
/// its events: between its own top and impact), seconds; `None` where a peak is not found.
fn gap_differences(
    flawed: (&Motion, &Times),
    clean: (&Motion, &Times),
    lead: Side,
) -> [Option<f32>; GAPS.len()] {
    let Ok(body) = body::Body::new(&clean.0.skeleton, lead) else {
        return [None; GAPS.len()];
    };
    let gaps = |(m, times): (&Motion, &Times)| {
        let frame = |e: Event| {
            ((times[e as usize] * m.rate_hz).round().max(0.0) as usize).min(m.frames() - 1)
        };
        let k = sequence::peaks(
            &body,
            m.swing(),
            m.rate_hz,
            frame(Event::Top),
            frame(Event::Impact),
        );
        GAPS.map(|(a, b)| Some((k.peak(b)?.time - k.peak(a)?.time) / m.rate_hz))
    };
    let (f, c) = (gaps(flawed), gaps(clean));
    core::array::from_fn(|i| Some(f[i]? - c[i]?))
}

/// The unit vector of `direction` in the stance frame.
fn unit(direction: Direction) -> Vec3 {
    match direction {
        Direction::TowardTarget => Vec3::x(),
        Direction::AwayFromTarget => -Vec3::x(),
        Direction::TowardBall => Vec3::y(),
        Direction::AwayFromBall => -Vec3::y(),
        Direction::Up => Vec3::z(),
        Direction::Down => -Vec3::z(),
    }
}

/// The swing with its phases stretched and its pause inserted; its events.
fn warp(clean: &Motion, times: &Times, flaws: &[Flaw]) -> (Motion, Times) {
    let mut factor = [1.0f32; 3];
    let mut pause = 0.0;
    for flaw in flaws {
        match *flaw {
            Flaw::Tempo { phase, factor: f } => factor[phase as usize] *= f,
            Flaw::Pause { seconds } => pause += seconds,
            _ => {}
        }
    }
    let (top, impact, finish) = (
        times[Event::Top as usize],
        times[Event::Impact as usize],
        times[Event::Finish as usize],
    );
    let end = clean.frames() as f32 / clean.rate_hz;
    // Knots (warped time, clean time): the pause holds the top.
    let t_top = top * factor[0];
    let t_down = t_top + pause;
    let t_impact = t_down + (impact - top) * factor[1];
    let t_finish = t_impact + (finish - impact) * factor[2];
    let knots = [
        (0.0, 0.0),
        (t_top, top),
        (t_down, top),
        (t_impact, impact),
        (t_finish, finish),
        (t_finish + end - finish, end),
    ];
    let source = |u: f32| {
        let i = knots
            .windows(2)
            .position(|w| u <= w[1].0)
            .unwrap_or(knots.len() - 2);
        let ((u0, s0), (u1, s1)) = (knots[i], knots[i + 1]);
        if u1 > u0 {
            s0 + (s1 - s0) * ((u - u0) / (u1 - u0)).clamp(0.0, 1.0)
        } else {
            s0
        }
    };
    let map = |t: f32| {
        // Clean time to warped time, for the events (the pause belongs to the backswing).
        let i = knots
            .windows(2)
            .position(|w| t <= w[1].1 && w[1].1 > w[0].1)
            .unwrap_or(knots.len() - 2);
        let ((u0, s0), (u1, s1)) = (knots[i], knots[i + 1]);
        if s1 > s0 {
            u0 + (u1 - u0) * (t - s0) / (s1 - s0)
        } else {
            u0
        }
    };
    let mut warped_times = times.map(map);
    warped_times[Event::Top as usize] = t_down.max(t_top);
    if pause > 0.0 {
        warped_times[Event::Top as usize] = t_down;
    }
    let joints = clean.skeleton.len();
    let frames = ((t_finish + end - finish) * clean.rate_hz).round() as usize;
    let mut positions = Vec::with_capacity(frames * joints);
    for f in 0..frames {
        let x = (source(f as f32 / clean.rate_hz) * clean.rate_hz)
            .clamp(0.0, (clean.frames() - 1) as f32);
        let (i, w) = (x.floor() as usize, x.fract());
        let (a, b) = (clean.frame(i), clean.frame((i + 1).min(clean.frames() - 1)));
        positions.extend(a.iter().zip(b).map(|(a, b)| a + (b - a) * w));
    }
    let motion = Motion {
        missing: vec![false; positions.len()],
        positions,
        ..clean.clone()
    };
    (motion, warped_times)
}

/// A smooth bump: 0 outside `from..to`, rising to 1 at `peak` (raised cosines).
fn bump(t: f32, from: f32, peak: f32, to: f32) -> f32 {
    let rise = |x: f32| 0.5 - 0.5 * (std::f32::consts::PI * x.clamp(0.0, 1.0)).cos();
    if t <= peak {
        if peak > from {
            rise((t - from) / (peak - from))
        } else {
            1.0
        }
    } else if to > peak {
        1.0 - rise((t - peak) / (to - peak))
    } else {
        1.0
    }
}

/// Joints `k` of `skeleton` that `joint` carries: itself and, for an arm or the head, the
/// joints beyond it.
fn carried(skeleton: &Skeleton, joint: Joint) -> Vec<usize> {
    let Some(at) = skeleton.index_of(joint) else {
        return Vec::new();
    };
    let limb = matches!(
        joint,
        Joint::LeftElbow
            | Joint::RightElbow
            | Joint::LeftWrist
            | Joint::RightWrist
            | Joint::LeftShoulder
            | Joint::RightShoulder
            | Joint::Head
            | Joint::Neck
    );
    (0..skeleton.len())
        .filter(|&k| k == at || (limb && carries(skeleton, at, k)))
        .collect()
}

/// Whether joint `k` of `skeleton` is `joint` or one it carries.
fn carries(skeleton: &Skeleton, joint: usize, k: usize) -> bool {
    k == joint || skeleton.ancestry(k).any(|a| a == joint)
}

/// The joints of the head beyond the thorax: whichever of neck, head and head top the
/// skeleton has.
fn head(skeleton: &Skeleton) -> Vec<usize> {
    (0..skeleton.len())
        .filter(|&k| {
            matches!(
                skeleton.joint(k),
                Some(Joint::Neck | Joint::Head | Joint::HeadTop)
            )
        })
        .collect()
}

/// Applies a spatial or body flaw to `swing` (events at `times`).
fn move_joints(swing: &mut Motion, times: &Times, lead: Side, flaw: &Flaw) {
    let skeleton = swing.skeleton.clone();
    let joints = skeleton.len();
    let rate = swing.rate_hz;
    let stance = Stance::new(&skeleton, swing.frame(0), lead);
    let world =
        |v: Vec3| stance.toward_target() * v.x + stance.toward_ball() * v.y + Vec3::y() * v.z;
    let t = |e: Event| times[e as usize];
    let find = |j: Joint| skeleton.index_of(j);
    let (lead_arm, trail_arm) = match lead {
        Side::Left => (
            [Joint::LeftShoulder, Joint::LeftElbow, Joint::LeftWrist],
            Joint::RightShoulder,
        ),
        Side::Right => (
            [Joint::RightShoulder, Joint::RightElbow, Joint::RightWrist],
            Joint::LeftShoulder,
        ),
    };
    // Which way the shoulder line turns from address to the top (about +Y): a reduced turn
    // turns back the other way.
    let turn = match (find(lead_arm[0]), find(trail_arm)) {
        (Some(l), Some(r)) => {
            let heading = |f: usize| {
                let v = swing.positions[f * joints + l] - swing.positions[f * joints + r];
                v.z.atan2(v.x)
            };
            let top = ((t(Event::Top) * rate) as usize).min(swing.frames() - 1);
            let turned = heading(top) - heading(0);
            // Rotating by +a about +Y lowers atan2(z, x) by a.
            turned.sin().signum()
        }
        _ => 0.0,
    };
    // The swing as it was, for the upper body first to take its upper body from a later moment.
    let source: Vec<Vec3> = match flaw {
        Flaw::Body {
            body: Body::UpperBodyFirst,
            ..
        } => swing.positions.clone(),
        _ => Vec::new(),
    };
    for f in 0..swing.frames() {
        let u = f as f32 / rate;
        let frame = &mut swing.positions[f * joints..(f + 1) * joints];
        match *flaw {
            Flaw::Offset {
                event,
                joint,
                direction,
                metres,
            } => {
                let i = event as usize;
                // Around the event, reaching halfway to the events either side and at least
                // OFFSET_HALF_S (a golfer holds a fault for a moment, not a frame).
                let before = if i == 0 {
                    -1.0
                } else {
                    (0.5 * (times[i - 1] + times[i])).min(times[i] - OFFSET_HALF_S)
                };
                let after = if i + 1 < 8 {
                    (0.5 * (times[i] + times[i + 1])).max(times[i] + OFFSET_HALF_S)
                } else {
                    times[i] + 0.3
                };
                let w = if event == Event::Address {
                    bump(u, -1.0, 0.0, after)
                } else {
                    bump(u, before, times[i], after)
                };
                for k in carried(&skeleton, joint) {
                    frame[k] += world(unit(direction)) * metres * w;
                }
            }
            Flaw::Body {
                body: Body::EarlyExtension,
                size,
            } => {
                let w = bump(u, t(Event::Top), t(Event::Impact), t(Event::Finish) + 1.0);
                for (j, share) in [
                    (Joint::Pelvis, 1.0),
                    (Joint::LeftHip, 1.0),
                    (Joint::RightHip, 1.0),
                    (Joint::LeftKnee, 0.5),
                    (Joint::RightKnee, 0.5),
                    (Joint::Spine, 0.5),
                ] {
                    if let Some(k) = find(j) {
                        frame[k] += world(Vec3::y()) * size * share * w;
                    }
                }
            }
            Flaw::Body {
                body: Body::Sway,
                size,
            } => {
                let w = bump(u, 0.0, t(Event::Top), t(Event::Impact));
                for (j, share) in [
                    (Joint::Pelvis, 1.0),
                    (Joint::LeftHip, 1.0),
                    (Joint::RightHip, 1.0),
                    (Joint::LeftKnee, 0.5),
                    (Joint::RightKnee, 0.5),
                    (Joint::Spine, 0.5),
                ] {
                    if let Some(k) = find(j) {
                        frame[k] -= world(Vec3::x()) * size * share * w;
                    }
                }
            }
            Flaw::Body {
                body: Body::HeadDown,
                size,
            } => {
                let w = bump(u, 0.0, t(Event::Top), t(Event::Finish));
                for k in head(&skeleton) {
                    frame[k] -= Vec3::y() * size * w;
                }
            }
            Flaw::Body {
                body: Body::ReducedTurn,
                size,
            } => {
                // Everything from the thorax up turns back toward its address heading, about
                // the vertical through the spine.
                let (Some(spine), Some(thorax)) = (find(Joint::Spine), find(Joint::Thorax)) else {
                    return;
                };
                let w = bump(u, 0.0, t(Event::Top), t(Event::Impact));
                let rot = nalgebra::Rotation3::from_axis_angle(
                    &Vec3::y_axis(),
                    size.to_radians() * w * turn,
                );
                let pivot = frame[spine];
                for (k, p) in frame.iter_mut().enumerate() {
                    if carries(&skeleton, thorax, k) {
                        *p = pivot + rot * (*p - pivot);
                    }
                }
            }
            Flaw::Body {
                body: Body::BentLeadArm,
                size,
            } => {
                let (Some(s), Some(e)) = (find(lead_arm[0]), find(lead_arm[1])) else {
                    return;
                };
                let w = bump(
                    u,
                    t(Event::MidBackswing),
                    t(Event::Top),
                    t(Event::MidDownswing),
                );
                let Some(wrist) = find(lead_arm[2]) else {
                    return;
                };
                let (upper, fore) = (frame[s] - frame[e], frame[wrist] - frame[e]);
                let Some(axis) = fore.cross(&upper).try_normalize(1e-9) else {
                    continue;
                };
                let rot = nalgebra::Rotation3::from_axis_angle(
                    &nalgebra::Unit::new_unchecked(axis),
                    size.to_radians() * w,
                );
                let pivot = frame[e];
                for (k, p) in frame.iter_mut().enumerate() {
                    if skeleton.ancestry(k).any(|a| a == e) {
                        *p = pivot + rot * (*p - pivot);
                    }
                }
            }
            Flaw::Body {
                body: Body::UpperBodyFirst,
                size,
            } => {
                // Everything from the thorax up, as it was `size` ms later about the spine, from
                // the top to impact: its downswing comes that much early, its shape kept. The
                // lead grows from halfway back to the top and fades from impact to the finish.
                let (Some(spine), Some(thorax)) = (find(Joint::Spine), find(Joint::Thorax)) else {
                    return;
                };
                let last = source.len() / joints - 1;
                let x = ((u + ahead(u, times, size)) * rate).clamp(0.0, last as f32);
                let (i, fraction) = (x.floor() as usize, x.fract());
                let later = |k: usize| {
                    source[i * joints + k] * (1.0 - fraction)
                        + source[(i + 1).min(last) * joints + k] * fraction
                };
                let (pivot, from) = (frame[spine], later(spine));
                for (k, p) in frame.iter_mut().enumerate() {
                    if carries(&skeleton, thorax, k) {
                        *p = pivot + (later(k) - from);
                    }
                }
            }
            Flaw::Tempo { .. } | Flaw::Pause { .. } => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_core::events;
    use posecoach_io::csv;

    /// The tour driver (committed fixture, with its club) on the bundled T-pose at 240 Hz, and
    /// its events.
    fn clean() -> (Motion, Times, Side) {
        let source =
            csv::read(include_str!("../../../tests/fixtures/golf_driver_60hz.csv")).unwrap();
        let found = events::detect(&source.skeleton, source.swing(), source.rate_hz).unwrap();
        let body = csv::read(include_str!("../../../tests/fixtures/h36m17_tpose.csv")).unwrap();
        let mut swing = source.retarget_analytic(&body).unwrap();
        swing.keep_contacts(&source).unwrap();
        let swing = swing.resampled(240.0).unwrap();
        (swing, times(&found, source.rate_hz), found.lead)
    }

    #[test]
    fn an_unflawed_swing_is_the_clean_one_with_no_truth() {
        let (swing, t, lead) = clean();
        let planted = plant(&swing, &t, lead, &[]);
        assert!(planted.truths.is_empty());
        assert_eq!(planted.swing.frames(), swing.frames());
        let worst = planted
            .swing
            .positions
            .iter()
            .zip(&swing.positions)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f32::max);
        assert!(worst < 1e-5, "{worst}");
    }

    #[test]
    fn a_slow_backswing_stretches_only_the_backswing() {
        let (swing, t, lead) = clean();
        let flaw = Flaw::Tempo {
            phase: Phase::Backswing,
            factor: 1.5,
        };
        let planted = plant(&swing, &t, lead, &[flaw]);
        let (top, impact) = (Event::Top as usize, Event::Impact as usize);
        assert!((planted.times[top] - 1.5 * t[top]).abs() < 1e-4);
        assert!((planted.times[impact] - planted.times[top] - (t[impact] - t[top])).abs() < 1e-4);
        assert!((planted.tempo_ratio - 1.5 * t[top] / (t[impact] - t[top])).abs() < 1e-3);
        assert_eq!(
            planted.truths,
            vec![Truth::Tempo {
                phase: Phase::Backswing,
                verdict: Verdict::Slow
            }]
        );
        let extra = planted.swing.frames() as f32 - swing.frames() as f32;
        assert!((extra - 0.5 * t[top] * 240.0).abs() <= 1.0, "{extra}");
    }

    #[test]
    fn an_offset_is_true_of_its_joint_direction_and_event() {
        let (swing, t, lead) = clean();
        let flaw = Flaw::Offset {
            event: Event::Top,
            joint: Joint::LeftWrist,
            direction: Direction::Down,
            metres: 0.12,
        };
        let planted = plant(&swing, &t, lead, &[flaw]);
        let named = Truth::Spatial {
            event: Event::Top,
            joint: Joint::LeftWrist,
            direction: Direction::Down,
        };
        assert!(planted.truths.contains(&named), "{:?}", planted.truths);
        // Nothing far from the top, and no other joint.
        assert!(
            planted.truths.iter().all(|t| matches!(
                t,
                Truth::Spatial {
                    joint: Joint::LeftWrist,
                    event: Event::Top | Event::MidBackswing | Event::MidDownswing,
                    ..
                }
            )),
            "{:?}",
            planted.truths
        );
        // The forearm keeps its length: the wrist shows part of the 12 cm, and the bones do too.
        let f = (t[Event::Top as usize] * 240.0).round() as usize;
        let k = swing.skeleton.index_of(Joint::LeftWrist).unwrap();
        let j = swing.skeleton.len();
        let drop = swing.positions[f * j + k].y - planted.swing.positions[f * j + k].y;
        assert!(drop > 0.05 && drop <= 0.12 + 1e-3, "{drop}");
        assert!(
            (planted.shown_m - drop).abs() < 0.05,
            "{} {drop}",
            planted.shown_m
        );
        let elbow = swing.skeleton.index_of(Joint::LeftElbow).unwrap();
        let forearm = |m: &Motion| (m.positions[f * j + k] - m.positions[f * j + elbow]).norm();
        assert!((forearm(&planted.swing) - forearm(&swing)).abs() < 1e-3);
    }

    #[test]
    fn body_flaws_move_what_they_name() {
        let (swing, t, lead) = clean();
        let truths = |body, size| plant(&swing, &t, lead, &[Flaw::Body { body, size }]).truths;
        let early = truths(Body::EarlyExtension, 0.1);
        assert!(
            early.iter().any(|t| matches!(
                t,
                Truth::Spatial {
                    event: Event::Impact,
                    joint: Joint::Pelvis,
                    direction: Direction::TowardBall
                }
            )),
            "{early:?}"
        );
        let sway = truths(Body::Sway, 0.1);
        assert!(
            sway.iter().any(|t| matches!(
                t,
                Truth::Spatial {
                    event: Event::Top,
                    joint: Joint::Pelvis,
                    direction: Direction::AwayFromTarget
                }
            )),
            "{sway:?}"
        );
        for body in [Body::ReducedTurn, Body::BentLeadArm, Body::HeadDown] {
            let size = if body == Body::HeadDown { 0.08 } else { 25.0 };
            assert!(!truths(body, size).is_empty(), "{body:?}");
        }
    }

    #[test]
    fn body_flaws_are_true_of_the_checks_that_name_them() {
        use posecoach_core::body::Measure;
        use posecoach_core::events::Position;
        let (swing, t, lead) = clean();
        let body_truths = |body, size| -> Vec<(Position, Measure, bool)> {
            plant(&swing, &t, lead, &[Flaw::Body { body, size }])
                .truths
                .into_iter()
                .filter_map(|t| match t {
                    Truth::Body { check, more } => Some((check.position, check.measure, more)),
                    _ => None,
                })
                .collect()
        };
        for (body, size, named) in [
            (
                Body::EarlyExtension,
                0.1,
                (Position::P7, Measure::PelvisThrust, true),
            ),
            (Body::Sway, 0.1, (Position::P4, Measure::PelvisSway, false)),
            (
                Body::HeadDown,
                0.08,
                (Position::P4, Measure::HeadLift, false),
            ),
            (
                Body::ReducedTurn,
                25.0,
                (Position::P4, Measure::ThoraxTurn, false),
            ),
            (
                Body::BentLeadArm,
                30.0,
                (Position::P4, Measure::LeadElbow, true),
            ),
        ] {
            let truths = body_truths(body, size);
            assert!(truths.contains(&named), "{body:?}: {truths:?}");
        }
        // Within the tolerances, nothing.
        assert_eq!(body_truths(Body::ReducedTurn, 5.0), vec![]);
        assert_eq!(body_truths(Body::Sway, 0.03), vec![]);
    }

    /// Scored against the clean swing with no noise, each body flaw is named first by the body
    /// check its truth names, in a coach's words; the clean swing itself gets no advice.
    #[test]
    fn a_scored_body_flaw_is_named_first_in_a_coachs_words() {
        use posecoach_core::band::Band;
        use posecoach_core::score::Advice;
        let (swing, t, lead) = clean();
        let at_60 = |m: &Motion| m.resampled(60.0).unwrap();
        let coach = at_60(&swing);
        let scored = |flaws: &[Flaw]| {
            let planted = plant(&swing, &t, lead, flaws);
            let report =
                crate::score::score_swings(&at_60(&planted.swing), &coach, Band::DEFAULT, &mut ())
                    .unwrap();
            (planted, report)
        };
        let (_, report) = scored(&[]);
        assert!(report.advice.is_empty(), "{:?}", report.advice);
        // The large sizes, and the two a new user tried: a 16° short turn, whose wrists were
        // named first, and 8 cm of early extension, whose shoulder and neck were.
        for (body, size, fault) in [
            (Body::EarlyExtension, 0.1, "early extension"),
            (Body::EarlyExtension, 0.08, "early extension"),
            (Body::Sway, 0.1, "a sway"),
            (Body::HeadDown, 0.1, "a dipping head"),
            (Body::ReducedTurn, 25.0, "a short turn"),
            (Body::ReducedTurn, 16.0, "a short turn"),
            (Body::BentLeadArm, 35.0, "a bent lead arm"),
        ] {
            let (planted, report) = scored(&[Flaw::Body { body, size }]);
            let first = report.advice.first().expect("advice");
            let Advice::Body(b, _) = first else {
                panic!("{body:?} {size}: {:#?}", report.advice);
            };
            let truth = Truth::Body {
                check: b.check,
                more: b.student > b.coach,
            };
            assert!(planted.truths.contains(&truth), "{body:?}: {first}");
            assert!(first.to_string().contains(&format!(": {fault}")), "{first}");
        }
    }
    /// The upper body turned ahead of time leaves the hips peaking after the chest: planted, it
    /// is true of that gap; scored against the clean swing with no noise, it is advice in a
    /// coach's words, and a smaller one within the tolerance is neither.
    #[test]
    fn the_upper_body_first_is_a_gap_out_of_order() {
        use posecoach_core::band::Band;
        use posecoach_core::score::Advice;
        let (swing, t, lead) = clean();
        let at_60 = |m: &Motion| m.resampled(60.0).unwrap();
        let flaw = |size| Flaw::Body {
            body: Body::UpperBodyFirst,
            size,
        };
        let planted = plant(&swing, &t, lead, &[flaw(50.0)]);
        let hips_late = Truth::Sequence {
            first: Link::Pelvis,
            then: Link::Thorax,
            more: false,
        };
        assert_eq!(planted.causes, vec![hips_late]);
        // Its club meets the ball 50 ms early, the upper body carrying it: at its own impact
        // the hips are where they were 50 ms before, less open than the clean swing's. True,
        // and a consequence, not the flaw.
        let impact = Event::Impact as usize;
        assert!((t[impact] - planted.times[impact] - 0.05).abs() < 1e-3);
        let hips_closed = Truth::Body {
            check: CHECKS[7],
            more: true,
        };
        assert!(
            planted.truths.contains(&hips_closed),
            "{:?}",
            planted.truths
        );
        // The golfer stands still for 0.3 s before the takeaway, as a recorded swing does: the
        // pose noise is read there.
        let still = |m: &Motion| {
            let mut m = at_60(m);
            let first = m.frame(0).to_vec();
            let mut positions: Vec<Vec3> = first
                .iter()
                .cycle()
                .take(18 * first.len())
                .copied()
                .collect();
            positions.extend_from_slice(&m.positions);
            m.missing = vec![false; positions.len()];
            m.positions = positions;
            m
        };
        let report = crate::score::score_swings(
            &still(&planted.swing),
            &still(&swing),
            Band::DEFAULT,
            &mut (),
        )
        .unwrap();
        // The gap comes first, the hips at impact under it.
        let item = report
            .advice
            .first()
            .filter(|a| matches!(a, Advice::Sequence(g, e) if g.first == Link::Pelvis && e.check == Some(CHECKS[7])))
            .unwrap_or_else(|| panic!("{:?} {:?}", report.advice, planted.truths));
        assert!(
            item.to_string().contains(
                ": the upper body starts the downswing, which is why at impact (P7) your hips are"
            ),
            "{item}"
        );
        let small = plant(&swing, &t, lead, &[flaw(10.0)]);
        assert!(
            !small
                .truths
                .iter()
                .any(|t| matches!(t, Truth::Sequence { .. })),
            "{:?}",
            small.truths
        );
    }
}
