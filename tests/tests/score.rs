//! Scoring on the real driver swing: identical swings, and variants with one planted flaw each.
//!
//! Each variant is derived from `fixtures/golf_driver_60hz.csv` (joint centres of the real
//! tour swing at 60 Hz) by a transformation in this file: a phase time-warped 20-40 %, or one
//! joint moved 8-15 cm around one event along an axis of the golfer's stance frame.

use posecoach_core::band::Band;
use posecoach_core::events::Event;
use posecoach_core::joint::Joint;
use posecoach_core::score::{score, scratch_len, Advice, Direction, Phase, Report, Verdict};
use posecoach_core::Vec3;
use posecoach_io::{self as io, Motion};
use posecoach_tests::{fixture, jitter, paused, Warp};

/// The default band: 10 frames at 60 Hz around the event-anchored guide.
const BAND: Band = Band::DEFAULT;

fn driver() -> Motion {
    io::load(&fixture("golf_driver_60hz.csv")).unwrap()
}

fn run(student: &Motion, coach: &Motion) -> Report {
    let len = scratch_len(student.frames(), coach.frames());
    let (mut floats, mut bytes) = (vec![0.0; len.floats], vec![0u8; len.bytes]);
    score(
        &coach.skeleton,
        &student.positions,
        student.rate_hz,
        &mut coach.positions.clone(),
        coach.rate_hz,
        BAND,
        (&mut floats, &mut bytes),
        &mut (),
    )
    .unwrap()
}

/// `swing` with the phase from event `from` to event `to` (coach frames) stretched by `factor`.
fn warp_phase(swing: &Motion, from: usize, to: usize, factor: f32) -> Motion {
    Warp(vec![(from as f32, to as f32, factor)]).apply(swing)
}

/// Unit axes of the stance frame at address: toward target, toward ball, up.
fn stance_axes(swing: &Motion, address: usize) -> [Vec3; 3] {
    let s = &swing.skeleton;
    let at = |j: Joint| swing.frame(address)[s.index_of(j).unwrap()];
    let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).normalize();
    let target = flat(at(Joint::LeftAnkle) - at(Joint::RightAnkle));
    let mut ball = Vec3::y().cross(&target);
    if ball.dot(&(at(Joint::Thorax) - at(Joint::Pelvis))) < 0.0 {
        ball = -ball;
    }
    [target, ball, Vec3::y()]
}

/// `swing` with `joint` moved by `offset` at frame `at`, fading out over ±0.1 s.
fn plant(swing: &Motion, joint: Joint, at: usize, offset: Vec3) -> Motion {
    let k = swing.skeleton.index_of(joint).unwrap();
    let n = swing.skeleton.len();
    let width = 0.1 * swing.rate_hz;
    let mut out = swing.clone();
    for f in 0..swing.frames() {
        let x = (f as f32 - at as f32) / width;
        if x.abs() < 1.0 {
            let weight = 0.5 * (1.0 + (std::f32::consts::PI * x).cos());
            out.positions[f * n + k] += offset * weight;
        }
    }
    out
}

#[test]
fn identical_swings_score_100_with_nothing_to_fix() {
    let swing = driver();
    let report = run(&swing, &swing);
    assert_eq!(report.score, 100.0);
    assert_eq!(report.distance, 0.0);
    assert!(report
        .tempo
        .iter()
        .all(|t| t.verdict == Verdict::Ok && (t.ratio - 1.0).abs() < 1e-4));
    assert!(report.spatial.is_empty(), "{:?}", report.spatial);
    assert!(report.advice.is_empty());
    assert!(report.path.iter().all(|&(i, j)| i == j));
    assert!((report.student_tempo_ratio - report.coach_tempo_ratio).abs() < 1e-6);
}

#[test]
fn a_slowed_or_hurried_phase_is_named_first() {
    let coach = driver();
    let events = run(&coach, &coach).coach_events;
    let cases = [
        (
            Phase::Backswing,
            Event::Address,
            Event::Top,
            1.3,
            Verdict::Slow,
        ),
        (
            Phase::Backswing,
            Event::Address,
            Event::Top,
            0.75,
            Verdict::Fast,
        ),
        (
            Phase::Downswing,
            Event::Top,
            Event::Impact,
            1.4,
            Verdict::Slow,
        ),
        (
            Phase::Downswing,
            Event::Top,
            Event::Impact,
            0.7,
            Verdict::Fast,
        ),
        (
            Phase::FollowThrough,
            Event::Impact,
            Event::Finish,
            1.35,
            Verdict::Slow,
        ),
        (
            Phase::FollowThrough,
            Event::Impact,
            Event::Finish,
            0.75,
            Verdict::Fast,
        ),
    ];
    for (phase, from, to, factor, verdict) in cases {
        let student = warp_phase(
            &coach,
            events.frame(from).unwrap(),
            events.frame(to).unwrap(),
            factor,
        );
        let report = run(&student, &coach);
        match report.advice.first() {
            Some(Advice::Tempo(t)) => {
                assert_eq!(
                    (t.phase, t.verdict),
                    (phase, verdict),
                    "{phase:?} x{factor}: {report:?}"
                )
            }
            other => panic!("{phase:?} x{factor}: first advice {other:?}"),
        }
        let entry = report.tempo.iter().find(|t| t.phase == phase).unwrap();
        assert!(
            (entry.ratio - factor).abs() < 0.1,
            "{phase:?}: ratio {} for x{factor}",
            entry.ratio
        );
    }
}

#[test]
fn a_moved_joint_is_named_first_with_its_event_and_direction() {
    let coach = driver();
    let events = run(&coach, &coach).coach_events;
    let axes = stance_axes(&coach, events.frame(Event::Address).unwrap());
    let cases = [
        (Joint::LeftWrist, Event::Top, 2, -0.12, Direction::Down),
        (Joint::Head, Event::Address, 1, 0.10, Direction::TowardBall),
        (
            Joint::Pelvis,
            Event::Impact,
            0,
            0.08,
            Direction::TowardTarget,
        ),
        (
            Joint::RightElbow,
            Event::Top,
            1,
            -0.15,
            Direction::AwayFromBall,
        ),
        (
            Joint::LeftKnee,
            Event::Impact,
            0,
            -0.09,
            Direction::AwayFromTarget,
        ),
        (Joint::RightShoulder, Event::Finish, 2, 0.11, Direction::Up),
    ];
    for (joint, event, axis, metres, direction) in cases {
        let student = plant(
            &coach,
            joint,
            events.frame(event).unwrap(),
            axes[axis] * metres,
        );
        let report = run(&student, &coach);
        match report.advice.first() {
            Some(Advice::Spatial(d)) => {
                assert_eq!(
                    (d.joint, d.event, d.direction),
                    (joint, event, direction),
                    "{report:?}"
                );
                assert!(
                    (d.distance_m - metres.abs()).abs() < 0.03,
                    "{joint}: {} m",
                    d.distance_m
                );
            }
            other => panic!("{joint} at {event:?}: first advice {other:?}"),
        }
    }
}

#[test]
fn the_score_falls_strictly_as_a_planted_offset_grows() {
    let coach = driver();
    let events = run(&coach, &coach).coach_events;
    let axes = stance_axes(&coach, events.frame(Event::Address).unwrap());
    let scores: Vec<f32> = [0.0, 0.03, 0.06, 0.09, 0.12, 0.15]
        .iter()
        .map(|&m| {
            run(
                &plant(
                    &coach,
                    Joint::LeftWrist,
                    events.frame(Event::Top).unwrap(),
                    axes[2] * -m,
                ),
                &coach,
            )
            .score
        })
        .collect();
    assert!(scores.windows(2).all(|w| w[1] < w[0]), "{scores:?}");
}

#[test]
fn a_10_cm_fault_or_a_30_percent_phase_costs_at_least_5_points() {
    let coach = driver();
    let events = run(&coach, &coach).coach_events;
    let axes = stance_axes(&coach, events.frame(Event::Address).unwrap());
    let offset = plant(
        &coach,
        Joint::RightElbow,
        events.frame(Event::Top).unwrap(),
        axes[1] * 0.1,
    );
    let score = run(&offset, &coach).score;
    assert!(
        score <= 95.0,
        "a 10 cm elbow offset at the top scores {score}"
    );
    for (from, to) in [(Event::Address, Event::Top), (Event::Top, Event::Impact)] {
        for factor in [1.3, 1.0 / 1.3] {
            let warped = warp_phase(
                &coach,
                events.frame(from).unwrap(),
                events.frame(to).unwrap(),
                factor,
            );
            let score = run(&warped, &coach).score;
            assert!(score <= 95.0, "{from:?} to {to:?} x{factor}: {score}");
        }
    }
}

#[test]
fn a_joint_the_stream_was_unsure_of_is_not_judged_there() {
    use posecoach_core::events::EventError;
    use posecoach_core::frames::Frames;
    use posecoach_core::score::{compare, Detected, ScoreError, Unsure};
    let coach = driver();
    let events = run(&coach, &coach).coach_events;
    let axes = stance_axes(&coach, events.frame(Event::Address).unwrap());
    let top = events.frame(Event::Top).unwrap();
    let student = plant(&coach, Joint::LeftWrist, top, axes[2] * -0.12);
    let wrist = coach.skeleton.index_of(Joint::LeftWrist).unwrap();
    fn detected(m: &Motion) -> Detected<'_> {
        Detected::new(&m.skeleton, m.swing(), m.rate_hz).unwrap()
    }
    // The wrist unsure for a quarter second around the top.
    let masks: Vec<u64> = (0..student.frames())
        .map(|f| if f.abs_diff(top) <= 8 { 1 << wrist } else { 0 })
        .collect();
    let unsure = Detected {
        unsure: Unsure::new(&masks, 0, masks.len() as u64),
        ..detected(&student)
    };
    let len = scratch_len(student.frames(), coach.frames());
    let (mut floats, mut bytes) = (vec![0.0; len.floats], vec![0u8; len.bytes]);
    let report = compare(
        &coach.skeleton,
        &unsure,
        &detected(&coach),
        BAND,
        (&mut floats, &mut bytes),
        &mut (),
    )
    .unwrap();
    assert!(
        report
            .spatial
            .iter()
            .all(|d| d.joint != Joint::LeftWrist || d.event != Event::Top),
        "{:?}",
        report.spatial
    );
    // A coach read with the wrong joint count is refused, not misread.
    let misread = Detected {
        positions: Frames::metres(&coach.positions, coach.skeleton.len() - 1),
        ..detected(&coach)
    };
    assert_eq!(
        compare(
            &coach.skeleton,
            &unsure,
            &misread,
            BAND,
            (&mut floats, &mut bytes),
            &mut (),
        )
        .err(),
        Some(ScoreError::Events {
            student: false,
            error: EventError::Length
        })
    );
    // Sure of it, the same swing is told.
    let sure = run(&student, &coach);
    assert!(sure
        .spatial
        .iter()
        .any(|d| d.joint == Joint::LeftWrist && d.event == Event::Top));
}

#[test]
fn advice_reads_as_sentences() {
    let coach = driver();
    let events = run(&coach, &coach).coach_events;
    let axes = stance_axes(&coach, events.frame(Event::Address).unwrap());
    let student = plant(
        &coach,
        Joint::LeftWrist,
        events.frame(Event::Top).unwrap(),
        axes[2] * -0.12,
    );
    let report = run(&student, &coach);
    // Compared at the top's time, a pure offset keeps its size and direction; the uncertainty is
    // how much the wrist's offset wanders over the swing (a centimetre at most here).
    let sentence = report.advice[0].to_string();
    assert_eq!(
        sentence,
        "At the top your left wrist is 12 ± 1 cm lower than the coach's."
    );
    let slow = warp_phase(
        &coach,
        events.frame(Event::Top).unwrap(),
        events.frame(Event::Impact).unwrap(),
        1.4,
    );
    let sentence = run(&slow, &coach).advice[0].to_string();
    assert!(sentence.starts_with("Your downswing is "), "{sentence}");
    assert!(sentence.contains("% slower than the coach's"), "{sentence}");
}

/// A camera or a sensor set's heading is not the coach's: a student swing turned about the
/// vertical scores as it did facing the coach's way.
#[test]
fn the_student_may_face_any_way() {
    let coach = driver();
    let slow = warp_phase(&coach, 12, 65, 1.3);
    let facing = run(&slow, &coach);
    for degrees in [90.0f32, -135.0, 180.0] {
        let turn = nalgebra::Rotation3::from_axis_angle(&Vec3::y_axis(), degrees.to_radians());
        let turned = Motion {
            positions: slow.positions.iter().map(|p| turn * p).collect(),
            ..slow.clone()
        };
        let report = run(&turned, &coach);
        assert!(
            (report.score - facing.score).abs() < 0.05,
            "{degrees}: {} against {}",
            report.score,
            facing.score
        );
        assert_eq!(report.advice.len(), facing.advice.len());
        for (a, b) in report.advice.iter().zip(&facing.advice) {
            assert_eq!(a.to_string(), b.to_string(), "{degrees}");
        }
    }
}

#[test]
fn putts_are_scored_like_putts() {
    let golfer = driver();
    let (coach, _) = posecoach_tests::synthetic_putt(&golfer, 8.0, 0.6, 12.0, 0.6);
    let same = run(&coach, &coach);
    assert_eq!(same.score, 100.0);
    assert!(same.advice.is_empty());
    // A backstroke of 0.9 s instead of 0.6 s: the tempo advice comes first.
    let (student, _) = posecoach_tests::synthetic_putt(&golfer, 8.0, 0.9, 12.0, 0.6);
    let report = run(&student, &coach);
    match report.advice.first() {
        Some(Advice::Tempo(t)) => {
            assert_eq!((t.phase, t.verdict), (Phase::Backswing, Verdict::Slow))
        }
        other => panic!("first advice {other:?}"),
    }
    assert!(report.score < 100.0);
    // A putt is not compared with a full swing.
    let len = scratch_len(student.frames(), golfer.frames());
    let (mut floats, mut bytes) = (vec![0.0; len.floats], vec![0u8; len.bytes]);
    let mismatch = score(
        &coach.skeleton,
        &student.positions,
        60.0,
        &mut golfer.positions.clone(),
        60.0,
        BAND,
        (&mut floats, &mut bytes),
        &mut (),
    );
    assert_eq!(
        mismatch.unwrap_err(),
        posecoach_core::score::ScoreError::KindMismatch
    );
}

#[test]
fn a_tempo_verdict_waits_for_the_ratio_to_be_clear_of_its_noise() {
    let coach = driver();
    let events = run(&coach, &coach).coach_events;
    let (top, impact) = (
        events.frame(Event::Top).unwrap(),
        events.frame(Event::Impact).unwrap(),
    );
    let slower = warp_phase(&coach, top, impact, 1.25);
    // The same swing with the jitter of a poor camera: 2 cm standard deviation per axis on
    // every joint and frame.
    let mut noisy = slower.clone();
    jitter(&mut noisy.positions, 0.07, 0x2545_F491);
    let downswing = |r: &Report| r.tempo[Phase::Downswing as usize];
    let (clean, jittered) = (
        downswing(&run(&slower, &coach)),
        downswing(&run(&noisy, &coach)),
    );
    assert_eq!(clean.verdict, Verdict::Slow, "{clean:?}");
    assert!(
        jittered.ratio_uncertainty > 1.5 * clean.ratio_uncertainty,
        "{clean:?} {jittered:?}"
    );
    assert!(
        (jittered.ratio - 1.0).abs() > 0.15 && jittered.verdict == Verdict::Ok,
        "{jittered:?}"
    );
}

#[test]
fn a_student_whose_input_holds_the_hips_is_compared_about_them() {
    // MediaPipe's world landmarks are centred on the hips: the same swing with its root held
    // where it was in the first frame.
    let coach = driver();
    let n = coach.skeleton.len();
    let mut held = coach.clone();
    let root = coach.positions[0];
    for frame in held.positions.chunks_mut(n) {
        let travel = frame[0] - root;
        frame.iter_mut().for_each(|p| *p -= travel);
    }
    let report = run(&held, &coach);
    assert!(report.root_held);
    assert!(report.score > 99.0, "{}", report.score);
    assert!(report.advice.is_empty(), "{:?}", report.advice);
    let shifts = |r: &Report| {
        r.body
            .iter()
            .filter(|b| {
                b.check.measure.name().starts_with("pelvis_") && !b.check.measure.in_degrees()
            })
            .count()
    };
    assert_eq!(shifts(&report), 0);
    // The swing as captured moves its hips, and they are judged.
    let free = run(&coach, &coach);
    assert!(!free.root_held);
    assert_eq!(shifts(&free), 3);
}

#[test]
fn a_pause_at_the_top_makes_the_backswing_slow_and_nothing_else() {
    // The driver held still at its top for 0.3 s, against itself: the backswing is slow by
    // the pause, the downswing is the coach's, and nothing else is off.
    let coach = driver();
    let top = posecoach_core::events::detect(&coach.skeleton, coach.swing(), coach.rate_hz)
        .unwrap()
        .top();
    let report = run(&paused(&coach, top, (0.3 * coach.rate_hz) as usize), &coach);
    let [backswing, downswing, _] = report.tempo;
    let expected = (backswing.coach_s + 0.3) / backswing.coach_s;
    assert!(
        (backswing.ratio - expected).abs() < 0.05,
        "backswing x{:.3}, paused x{expected:.3}",
        backswing.ratio
    );
    assert_eq!(backswing.verdict, Verdict::Slow);
    assert_eq!(downswing.verdict, Verdict::Ok, "{downswing:?}");
    assert!(
        matches!(report.advice.first(), Some(Advice::Tempo(t)) if t.phase == Phase::Backswing),
        "{:?}",
        report.advice
    );
    assert!(report.spatial.is_empty(), "{:?}", report.spatial);
}
