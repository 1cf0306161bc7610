//! `bench coaching`'s range sessions: one golfer (a body) with one persistent flaw swinging
//! again and again, filmed by one phone or worn sensors, through one device session; what its
//! tendencies ([`posecoach_core::session`]) say after 1, 3, 5, 10 and 20 swings.
//!
//! - **The golfer**: each swing's flaw is the session's times a size factor drawn from 0.7 to
//!   1.3; each phase lasts `exp(N(0, 0.04))` times its own, and at each event one joint (with
//!   those it carries) is off by a normal 1 cm in a random direction: a golfer's swing-to-swing
//!   variation.
//! - **The input**: one recording of the whole session, so one camera placement, one frame rate
//!   and one per-keypoint bias hold for all its swings, while drift, jitter, occlusion and the
//!   estimator's failures are fresh in each.
//! - **The truth** is the flaw at its nominal size on the clean swing ([`flaws::plant`]): the
//!   tendency a coach should name. A tempo, body or sequence quantity's true value is the
//!   nominal flaw's change of it (0 where it changes nothing), which the session's interval
//!   should cover.
//!
//! Figures, per input and number of swings (a session of one swing says what that swing's
//! report says): **recall at 1** per flaw family (the session's first tendency states the truth; for a body flaw moving a check or gap, the cause named
//! first), **false tendencies** (an unflawed session with any), **coverage** of the session's
//! intervals (one-sided 95 % each way: 90 % when honest) and the **swings needed** for 90 %
//! recall per family.

use super::flaws::{self, Body, Flaw, Planted};
use super::{
    body_of, imu_messages, pct, phone_messages, share, states, Clean, Input, PhoneView, MODEL_HZ,
};
use crate::coaches;
use crate::synth::lay_out;
use anyhow::Result;
use posecoach_adapters::session::Outcome;
use posecoach_core::band::Band;
use posecoach_core::config::BODY_LEVEL;
use posecoach_core::events::Event;
use posecoach_core::joint::Joint;
use posecoach_core::score::BodyLevel;
use posecoach_core::score::{Advice, Direction, Phase};
use posecoach_core::session::{body_level_values, Quantity, Values};
use posecoach_core::tally::t95;
use posecoach_core::wire::{Config, Message};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde_json::{json, Value};

/// A golfer's swing-to-swing variation of each phase's duration, `ln` standard deviation.
pub(super) const PHASE_SPREAD: f32 = 0.04;
/// A golfer's swing-to-swing variation of a joint's place at an event, metres.
pub(super) const PLACE_SPREAD_M: f32 = 0.01;
/// The range of a flaw's size from swing to swing, as a factor of the session's.
pub(super) const SIZE_RANGE: (f32, f32) = (0.7, 1.3);

/// One range session: a clean swing's golfer, the flaw every swing carries, the input.
pub(super) struct SessionCase {
    pub(super) clean: usize,
    pub(super) flaw: Option<Flaw>,
    pub(super) input: Input,
    pub(super) seed: u64,
}

/// What a session's tendencies said after some swings.
#[derive(Clone, Debug, Default)]
pub(super) struct Snapshot {
    /// Swings heard.
    pub(super) swings: usize,
    /// Swings counted.
    pub(super) used: u16,
    /// Its first tendency.
    pub(super) first: Option<String>,
    /// The first tendency states the truth.
    pub(super) right_first: bool,
    /// Any tendency at all.
    pub(super) any: bool,
    /// For each body-level quantity with a known truth: its interval covers it.
    pub(super) covered: Vec<bool>,
    /// Whether an estimator without bias, with the scatter these swings' own measurements of
    /// the truth's quantities showed, would clear one of them past its tolerance (`None`
    /// where the nominal flaw moves none past it): the most that recall could be.
    pub(super) clearable: Option<bool>,
    /// For each truth past its tolerance, the session's estimate over the truth (1 where it
    /// reads the planted change in full).
    pub(super) read: Vec<f32>,
}

/// What a session made of its swings.
#[derive(Default)]
pub(super) struct SessionOutcome {
    /// At each number of swings asked for, what the session said (`None` where it heard fewer).
    pub(super) snapshots: Vec<Option<Snapshot>>,
    /// The largest displacement the nominal flaw shows at an event, metres.
    pub(super) shown_m: f32,
    /// The nominal flaw moves a body check or a gap past its tolerance.
    pub(super) body_truth: bool,
    pub(super) error: Option<String>,
}

/// The flaw at `factor` times its size.
fn scaled(flaw: Flaw, factor: f32) -> Flaw {
    match flaw {
        Flaw::Tempo { phase, factor: f } => Flaw::Tempo {
            phase,
            factor: f.powf(factor),
        },
        Flaw::Pause { seconds } => Flaw::Pause {
            seconds: seconds * factor,
        },
        Flaw::Offset {
            event,
            joint,
            direction,
            metres,
        } => Flaw::Offset {
            event,
            joint,
            direction,
            metres: metres * factor,
        },
        Flaw::Body { body, size } => Flaw::Body {
            body,
            size: size * factor,
        },
    }
}

/// The joints a golfer's variation and an offset flaw move.
const JOINTS: [Joint; 8] = [
    Joint::LeftWrist,
    Joint::RightWrist,
    Joint::LeftElbow,
    Joint::RightElbow,
    Joint::Neck,
    Joint::LeftKnee,
    Joint::RightKnee,
    Joint::Pelvis,
];
const DIRECTIONS: [Direction; 6] = [
    Direction::TowardTarget,
    Direction::AwayFromTarget,
    Direction::TowardBall,
    Direction::AwayFromBall,
    Direction::Up,
    Direction::Down,
];

/// The sessions: for every golfer (a clean swing's index) and input, unflawed ones, a tempo
/// flaw, an offset and every body flaw.
pub(super) fn cases(
    golfers: &[usize],
    inputs: &[Input],
    unflawed: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<SessionCase> {
    let mut out = Vec::new();
    for input in inputs {
        for &clean in golfers {
            let mut sets: Vec<Option<Flaw>> = vec![None; unflawed];
            let change = rng.random_range(0.15f32..=0.5);
            sets.push(Some(Flaw::Tempo {
                phase: Phase::ALL[rng.random_range(0..3)],
                factor: if rng.random_bool(0.5) {
                    1.0 + change
                } else {
                    1.0 / (1.0 + change)
                },
            }));
            sets.push(Some(Flaw::Offset {
                event: Event::ALL[rng.random_range(0..8)],
                joint: JOINTS[rng.random_range(0..JOINTS.len())],
                direction: DIRECTIONS[rng.random_range(0..6)],
                metres: rng.random_range(0.05f32..=0.2),
            }));
            for body in Body::ALL {
                let size = match body {
                    Body::ReducedTurn => rng.random_range(10.0f32..=25.0),
                    Body::BentLeadArm => rng.random_range(20.0f32..=40.0),
                    Body::UpperBodyFirst => rng.random_range(15.0f32..=50.0),
                    _ => rng.random_range(0.05f32..=0.12),
                };
                sets.push(Some(Flaw::Body { body, size }));
            }
            for flaw in sets {
                let input = match *input {
                    Input::Phone {
                        level_mm, failures, ..
                    } => Input::Phone {
                        level_mm,
                        rate_hz: if rng.random_bool(0.5) { 30.0 } else { 60.0 },
                        face_on: rng.random_bool(0.5),
                        failures,
                    },
                    imu => imu,
                };
                out.push(SessionCase {
                    clean,
                    flaw,
                    input,
                    seed: rng.random(),
                });
            }
        }
    }
    out
}

/// One swing of the golfer: the session's flaw at a size drawn for it, with the golfer's own
/// variation.
fn swing_flaws(flaw: Option<Flaw>, rng: &mut ChaCha8Rng) -> Vec<Flaw> {
    let mut out = Vec::new();
    if let Some(flaw) = flaw {
        out.push(scaled(flaw, rng.random_range(SIZE_RANGE.0..=SIZE_RANGE.1)));
    }
    for phase in Phase::ALL {
        let z: f32 = rng.sample(StandardNormal);
        let factor = (PHASE_SPREAD * z).exp();
        out.push(Flaw::Tempo { phase, factor });
    }
    for event in Event::ALL {
        let z: f32 = rng.sample(StandardNormal);
        let metres = (PLACE_SPREAD_M * z).abs();
        out.push(Flaw::Offset {
            event,
            joint: JOINTS[rng.random_range(0..JOINTS.len())],
            direction: DIRECTIONS[rng.random_range(0..6)],
            metres,
        });
    }
    out
}

/// Each body-level quantity's true value, where the nominal flaw fixes it: a phase's `ln`
/// ratio, a check's change, a gap's.
fn truths(clean: &Clean, nominal: &Planted) -> Vec<(Quantity, f32)> {
    let mut out = Vec::new();
    let duration = |t: &flaws::Times, phase: Phase| {
        let (from, to) = phase.events();
        t[to as usize] - t[from as usize]
    };
    for phase in Phase::ALL {
        let ratio = duration(&nominal.times, phase) / duration(&clean.times, phase);
        if ratio.is_finite() && ratio > 0.0 {
            out.push((Quantity::Tempo(phase), ratio.ln()));
        }
    }
    for (i, d) in nominal.checks.iter().enumerate() {
        if let Some(d) = d {
            out.push((Quantity::Check(i), *d));
        }
    }
    for (i, d) in nominal.gaps.iter().enumerate() {
        if let Some(d) = d {
            out.push((Quantity::Gap(i), *d));
        }
    }
    out
}

/// Lays out a session of `max(ns)` swings, films it and sends it through one device session,
/// taking what its tendencies say after each of `ns` swings.
pub(super) fn run_case(clean: &Clean, case: &SessionCase, ns: &[usize]) -> Result<SessionOutcome> {
    let mut rng = ChaCha8Rng::seed_from_u64(case.seed);
    let nominal = flaws::plant(&clean.swing, &clean.times, clean.lead, case.flaw.as_slice());
    let truths = truths(clean, &nominal);
    let count = ns.iter().copied().max().unwrap_or(0);
    let sources: Vec<_> = (0..count)
        .map(|_| {
            let flaws = swing_flaws(case.flaw, &mut rng);
            let planted = flaws::plant(&clean.swing, &clean.times, clean.lead, &flaws);
            (clean.source.clone(), planted.swing)
        })
        .collect();
    let body = body_of(clean, case.input, &mut rng)?;
    let (mut timeline, placed) = lay_out(&body, &sources, None, super::LAYOUT_HZ)?;
    let mut messages = match case.input {
        Input::Phone {
            level_mm,
            rate_hz,
            face_on,
            failures,
        } => {
            let view = PhoneView {
                level_mm,
                rate_hz,
                face_on,
                failures,
            };
            phone_messages(clean, &mut timeline, &placed, &view, &mut rng)?.0
        }
        Input::Imu {
            magnetometers,
            worn,
            steel_club,
        } => imu_messages(&body, &timeline, magnetometers, worn, steel_club, &mut rng)?,
    };
    messages.insert(
        1,
        Message::Config {
            seq: 1,
            config: Config {
                model_rate_hz: MODEL_HZ,
                band: Band::DEFAULT,
            },
        },
    );
    messages.insert(
        2,
        Message::CoachSelect {
            seq: 2,
            coach: clean.coach,
        },
    );
    let mut outcome = SessionOutcome {
        snapshots: vec![None; ns.len()],
        shown_m: nominal.shown_m,
        body_truth: !nominal.causes.is_empty(),
        error: None,
    };
    // Each scored swing's measurement of each body-level quantity.
    let mut measured: Vec<Measured> = Vec::new();
    coaches::session(None, |session| {
        for m in &messages {
            // A session of one swing says what that swing's report says.
            let mut swing: Option<Option<Advice>> = None;
            session.handle(m, |o| {
                if let Outcome::Scored { report, .. } = o {
                    swing = Some(report.advice.first().copied());
                    measured.push(body_level_values(&BodyLevel {
                        lead: report.student_events.lead,
                        tempo: &report.tempo,
                        pause_s: (0.0, 0.0),
                        body: &report.body,
                        coach_rate: &[],
                        gaps: &report.gaps,
                    }));
                }
            });
            let Some(swing_first) = swing else {
                continue;
            };
            let tendencies = session.tendencies();
            let heard = usize::from(tendencies.swings());
            let Some(slot) = ns.iter().position(|&n| n == heard) else {
                continue;
            };
            let advice = tendencies.advice();
            let first = match heard {
                1 => swing_first,
                _ => advice.first().map(|t| t.advice),
            };
            let covered = truths
                .iter()
                .filter_map(|&(q, truth)| {
                    let e = tendencies.estimate(q).filter(|e| e.n >= 2)?;
                    let margin = t95(usize::from(e.n) - 1) * e.uncertainty;
                    Some((e.value - truth).abs() <= margin)
                })
                .collect();
            let read = truths
                .iter()
                .filter(|(q, truth)| truth.abs() > q.tolerance())
                .filter_map(|&(q, truth)| {
                    let e = tendencies.estimate(q).filter(|e| e.n > 0)?;
                    Some(e.value / truth)
                })
                .collect();
            outcome.snapshots[slot] = Some(Snapshot {
                swings: heard,
                used: tendencies.used(),
                first: first.map(|a| a.to_string()),
                right_first: first.is_some_and(|a| right(&a, &nominal)),
                any: first.is_some(),
                covered,
                clearable: clearable(&truths, &measured),
                read,
            });
        }
    })?;
    Ok(outcome)
}

/// One swing's value of each body-level quantity ([`body_level_values`]).
type Measured = [Option<Values>; BODY_LEVEL];

/// Whether an estimator without bias, given the scatter of `measured` (each swing's value of
/// each body-level quantity), would clear a truth past its tolerance: `|truth| − t · s / √n`
/// past the tolerance, `s` the values' robust standard deviation, `t` the one-sided 95 %
/// quantile for `n − 1` degrees of freedom, as the session's advice takes it. `None` where no
/// truth is past its tolerance.
fn clearable(truths: &[(Quantity, f32)], measured: &[Measured]) -> Option<bool> {
    let past: Vec<(usize, f32, f32)> = truths
        .iter()
        .filter(|(q, truth)| truth.abs() > q.tolerance())
        .filter_map(|&(q, truth)| {
            let i = Quantity::BODY_LEVEL.iter().position(|b| *b == q)?;
            Some((i, truth, q.tolerance()))
        })
        .collect();
    if past.is_empty() {
        return None;
    }
    Some(past.iter().any(|&(i, truth, tolerance)| {
        let values: Vec<f32> = measured.iter().filter_map(|m| m[i].map(|v| v.0)).collect();
        let n = values.len();
        if n < 2 {
            return false;
        }
        // The scatter, robustly: 1.4826 times the median absolute deviation from the median
        // (a normal's standard deviation), so a mishit or a lost track does not inflate it.
        let median = |v: &mut Vec<f32>| {
            v.sort_by(f32::total_cmp);
            let m = v.len() / 2;
            match v.len() % 2 {
                1 => v[m],
                _ => 0.5 * (v[m - 1] + v[m]),
            }
        };
        let mut sorted = values.clone();
        let centre = median(&mut sorted);
        let mut deviations: Vec<f32> = values.iter().map(|v| (v - centre).abs()).collect();
        let sd = 1.4826 * median(&mut deviations);
        truth.abs() - t95(n - 1) * sd / (n as f32).sqrt() > tolerance
    }))
}

/// Whether `advice` names the planted truth the way the family is judged: a body flaw whose
/// truth is a check or a gap by that body-level item (its cause first), any other by a
/// statement of a truth.
fn right(advice: &Advice, planted: &Planted) -> bool {
    match planted.causes.is_empty() {
        false => {
            matches!(advice, Advice::Body(..) | Advice::Sequence(..))
                && states(advice, &planted.causes)
        }
        true => states(advice, &planted.truths),
    }
}

/// A session's family, as the targets name them: tempo, offsets showing 5 cm or more, body
/// flaws, the sequence (the upper body first).
fn family(case: &SessionCase, o: &SessionOutcome) -> Option<&'static str> {
    match case.flaw {
        None => Some("unflawed"),
        Some(Flaw::Tempo { .. } | Flaw::Pause { .. }) => Some("tempo"),
        Some(Flaw::Offset { .. }) => (o.shown_m >= 0.05).then_some("offset_5cm"),
        Some(Flaw::Body {
            body: Body::UpperBodyFirst,
            ..
        }) => o.body_truth.then_some("sequence"),
        Some(Flaw::Body { .. }) => o.body_truth.then_some("body"),
    }
}

/// The families recall is given for.
pub(super) const FAMILIES: [&str; 4] = ["tempo", "body", "offset_5cm", "sequence"];

/// The families whose truth is a body-level quantity, for which the bound on recall is given.
const BOUNDED: [&str; 3] = ["tempo", "body", "sequence"];

/// The session figures of one input: per number of swings, recall at 1 per family, false
/// tendencies, coverage; per family the swings needed for 90 % recall.
pub(super) fn summary(row: &str, ns: &[usize], pairs: &[(&SessionCase, &SessionOutcome)]) -> Value {
    let at: Vec<Value> = ns
        .iter()
        .enumerate()
        .map(|(slot, &n)| {
            let snap = |o: &SessionOutcome| o.snapshots.get(slot).cloned().flatten();
            let of = |f: &str| -> Vec<&(&SessionCase, &SessionOutcome)> {
                pairs.iter().filter(|(c, o)| family(c, o) == Some(f)).collect()
            };
            let recall = |f: &str| {
                let of = of(f);
                share(
                    of.iter().filter(|(_, o)| snap(o).is_some_and(|s| s.right_first)).count(),
                    of.len(),
                )
            };
            // The most recall could be: sessions whose truth an unbiased estimator with the
            // swings' own scatter would clear (tempo and the body-level families).
            let bound = |f: &str| {
                let of = of(f);
                share(
                    of.iter()
                        .filter(|(_, o)| snap(o).is_some_and(|s| s.clearable == Some(true)))
                        .count(),
                    of.len(),
                )
            };
            // How much of the planted change the session's estimates read, median.
            let read = |f: &str| {
                let mut r: Vec<f32> = of(f)
                    .iter()
                    .filter_map(|(_, o)| snap(o))
                    .flat_map(|s| s.read)
                    .collect();
                r.sort_by(f32::total_cmp);
                r.get(r.len() / 2).map_or(Value::Null, |m| json!((m * 100.0).round() / 100.0))
            };
            let unflawed = of("unflawed");
            let covered: Vec<bool> = pairs
                .iter()
                .filter_map(|(_, o)| snap(o))
                .flat_map(|s| s.covered)
                .collect();
            json!({
                "swings": n,
                "reached": share(pairs.iter().filter(|(_, o)| snap(o).is_some()).count(), pairs.len()),
                "set_aside": pairs.iter().filter_map(|(_, o)| snap(o)).map(|s| s.swings - usize::from(s.used)).sum::<usize>(),
                "recall_at_1": FAMILIES.iter().map(|f| (f.to_string(), recall(f))).collect::<serde_json::Map<_, _>>(),
                "read": BOUNDED.iter().map(|f| (f.to_string(), read(f))).collect::<serde_json::Map<_, _>>(),
                "clearable": match n {
                    // One swing's report is judged on its own uncertainty, not a scatter.
                    0 | 1 => Value::Null,
                    _ => BOUNDED.iter().map(|f| (f.to_string(), bound(f))).collect::<serde_json::Map<_, _>>().into(),
                },
                "false_tendencies": share(unflawed.iter().filter(|(_, o)| snap(o).is_none_or(|s| s.any)).count(), unflawed.len()),
                "coverage": share(covered.iter().filter(|c| **c).count(), covered.len()),
            })
        })
        .collect();
    let needed = FAMILIES
        .iter()
        .map(|f| {
            let first = at.iter().find(|a| {
                a["recall_at_1"][f]["share"]
                    .as_f64()
                    .is_some_and(|s| s >= 0.9)
            });
            (
                f.to_string(),
                first.map_or(json!(null), |a| a["swings"].clone()),
            )
        })
        .collect::<serde_json::Map<_, _>>();
    json!({"input": row, "sessions": pairs.len(), "by_swings": at, "swings_for_90pc": needed,
           "errors": pairs.iter().filter(|(_, o)| o.error.is_some()).count()})
}

/// A session's JSON line for `--cases-out`.
pub(super) fn case_json(clean: &Clean, case: &SessionCase, o: &SessionOutcome) -> Value {
    json!({
        "session": true,
        "source": clean.source.file_name().map(|n| n.to_string_lossy().into_owned()),
        "height_m": clean.body.skeleton.height(), "flaw": case.flaw, "input": case.input.row(),
        "seed": case.seed, "camera": super::camera_json(&case.input),
        "shown_cm": o.shown_m * 100.0, "family": family(case, o),
        "snapshots": o.snapshots.iter().map(|s| s.as_ref().map(|s| json!({
            "swings": s.swings, "used": s.used, "first": s.first, "right_first": s.right_first,
            "any": s.any, "covered": s.covered.iter().filter(|c| **c).count(), "of": s.covered.len(),
            "clearable": s.clearable, "read": s.read,
        }))).collect::<Vec<_>>(),
        "error": o.error,
    })
}

/// The session rows of the table printed without `--json`.
pub(super) fn table(levels: &[Value]) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "range sessions (one golfer, one flaw ×0.7-1.3 each swing): input | swings | reached | set aside | recall@1 {} | false | covered [90 %] | clearable without bias {} | read of the planted change, median, {}",
        FAMILIES.join(" / "),
        BOUNDED.join(" / "),
        BOUNDED.join(" / ")
    );
    for l in levels {
        for a in l["by_swings"].as_array().into_iter().flatten() {
            let recall: Vec<String> = FAMILIES.iter().map(|f| pct(&a["recall_at_1"][f])).collect();
            let bound: Vec<String> = BOUNDED.iter().map(|f| pct(&a["clearable"][f])).collect();
            let read: Vec<String> = BOUNDED
                .iter()
                .map(|f| {
                    a["read"][f]
                        .as_f64()
                        .map_or("-".into(), |r| format!("×{r:.2}"))
                })
                .collect();
            let _ = writeln!(
                out,
                "{:>8} | {:>2} | {} | {} | {} | {} | {} | {} | {}",
                l["input"].as_str().unwrap_or("-"),
                a["swings"],
                pct(&a["reached"]),
                a["set_aside"],
                recall.join(" / "),
                pct(&a["false_tendencies"]),
                pct(&a["coverage"]),
                bound.join(" / "),
                read.join(" / "),
            );
        }
        let needed: Vec<String> = FAMILIES
            .iter()
            .map(|f| {
                l["swings_for_90pc"][f]
                    .as_u64()
                    .map_or("-".into(), |n| n.to_string())
            })
            .collect();
        let _ = writeln!(
            out,
            "{:>8} | swings for 90 % recall: {}",
            l["input"].as_str().unwrap_or("-"),
            needed.join(" / ")
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{clearable, scaled, swing_flaws, Measured, PHASE_SPREAD};
    use posecoach_core::config::BODY_LEVEL;
    use posecoach_core::session::Quantity;

    /// Swings whose backswing (`ln` ratio) measured each of `values`.
    fn backswings(values: &[f32]) -> Vec<Measured> {
        values
            .iter()
            .map(|&v| {
                let mut m = [None; BODY_LEVEL];
                m[0] = Some((v, 0.0, (1.0, 0.0)));
                m
            })
            .collect()
    }

    #[test]
    fn a_truth_is_clearable_when_the_swings_scatter_leaves_it_past_its_tolerance() {
        let backswing = Quantity::Tempo(Phase::Backswing);
        // 30 % slow (ln 0.262) against a tolerance of ln 1.15 (0.140).
        let truth = [(backswing, 1.3f32.ln())];
        let tight = [0.25, 0.27, 0.26, 0.28, 0.24, 0.26];
        assert_eq!(clearable(&truth, &backswings(&tight)), Some(true));
        // A scatter of ±0.3 in six swings leaves it unclear; one wild swing among tight ones
        // does not (the scatter is robust).
        let wide = [0.6, -0.1, 0.5, 0.0, 0.55, -0.05];
        assert_eq!(clearable(&truth, &backswings(&wide)), Some(false));
        let wild = [0.25, 0.27, 0.26, 3.0, 0.24, 0.26];
        assert_eq!(clearable(&truth, &backswings(&wild)), Some(true));
        // A truth within its tolerance is no tendency to clear; one swing says nothing.
        assert_eq!(clearable(&[(backswing, 0.1)], &backswings(&tight)), None);
        assert_eq!(clearable(&truth, &backswings(&[0.26])), Some(false));
    }
    use crate::coaching::flaws::Flaw;
    use posecoach_core::score::Phase;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn a_flaw_scales_in_its_own_unit_and_a_tempo_in_its_log() {
        let slow = Flaw::Tempo {
            phase: Phase::Backswing,
            factor: 1.3,
        };
        let Flaw::Tempo { factor, .. } = scaled(slow, 2.0) else {
            panic!();
        };
        assert!((factor - 1.69).abs() < 1e-5);
        let Flaw::Pause { seconds } = scaled(Flaw::Pause { seconds: 0.2 }, 0.5) else {
            panic!();
        };
        assert!((seconds - 0.1).abs() < 1e-6);
    }

    #[test]
    fn a_golfers_phases_vary_by_their_stated_spread() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let logs: Vec<f32> = (0..2000)
            .flat_map(|_| swing_flaws(None, &mut rng))
            .filter_map(|f| match f {
                Flaw::Tempo { factor, .. } => Some(factor.ln()),
                _ => None,
            })
            .collect();
        let sd = (logs.iter().map(|l| l * l).sum::<f32>() / logs.len() as f32).sqrt();
        assert!((sd - PHASE_SPREAD).abs() < 0.003, "{sd}");
    }
}
