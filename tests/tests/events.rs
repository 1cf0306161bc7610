//! Swing events and P-positions on the two real tour swings against frames labelled by hand.
//!
//! The labels in `fixtures/golf_positions_60hz.csv` were read off per-frame values of the 60 Hz
//! joint centres, P1 to P10 (GolfDB's eight events and P6, P9), the address as the takeaway:
//! the first motion of the club and hands (both recordings begin as it starts: the club head
//! has moved 0.8 mm after 25 ms); P2 (toe-up) = shaft horizontal in the backswing; P3
//! (mid-backswing) and P5 (mid-downswing) = lead arm horizontal; P4 (top) = club and hands
//! reverse; P6 = shaft horizontal in the downswing; P7 (impact) = club head back at the ball;
//! P8 (mid-follow-through) = shaft horizontal after impact; P9 = trail arm horizontal after
//! impact; P10 (finish) = hands highest after impact. Each label is the frame nearest the
//! crossing or turning point.

use posecoach_core::events::{detect, Event, Position, Side};
use posecoach_io as io;
use posecoach_tests::{fixture, jitter, paused, Warp};

/// Allowed distance from a hand label, in frames at 60 Hz.
const TOLERANCE_FRAMES: i32 = 2;

fn labels() -> Vec<(String, Vec<i32>)> {
    let text = std::fs::read_to_string(fixture("golf_positions_60hz.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|line| {
            let mut cells = line.split(',');
            let name = cells.next().unwrap().to_string();
            (name, cells.map(|c| c.parse().unwrap()).collect())
        })
        .collect()
}

#[test]
fn positions_on_both_tour_swings_are_within_two_frames_of_the_hand_labels() {
    for (name, expected) in labels() {
        let swing = io::load(&fixture(&name)).unwrap();
        let events = detect(&swing.skeleton, swing.swing(), swing.rate_hz).unwrap();
        assert_eq!(events.lead, Side::Left, "{name}: a right-handed golfer");
        assert!(events.club);
        for (position, &label) in Position::ALL.iter().zip(&expected) {
            let found = events.frame(*position).unwrap() as i32;
            assert!(
                (found - label).abs() <= TOLERANCE_FRAMES,
                "{name}: {} at frame {found}, labelled {label}",
                position.name()
            );
        }
    }
}

/// The driver swing and its hand labels.
fn driver() -> (io::Motion, Vec<i32>) {
    let swing = io::load(&fixture("golf_driver_60hz.csv")).unwrap();
    let (_, labels) = labels()
        .into_iter()
        .find(|(n, _)| n == "golf_driver_60hz.csv")
        .unwrap();
    (swing, labels)
}

fn detected(swing: &io::Motion) -> posecoach_core::events::SwingEvents {
    detect(&swing.skeleton, swing.swing(), swing.rate_hz).unwrap()
}

fn assert_near(events: &posecoach_core::events::SwingEvents, expected: &[f32], what: &str) {
    for (position, &label) in Position::ALL.iter().zip(expected) {
        let found = events.frame(*position).unwrap() as f32;
        assert!(
            (found - label).abs() <= TOLERANCE_FRAMES as f32 + 0.5,
            "{what}: {} at frame {found}, expected {label:.1}",
            position.name()
        );
    }
}

#[test]
fn events_survive_pose_noise() {
    let (mut swing, labels) = driver();
    // Uniform noise of ±12 mm per coordinate: 7 mm standard deviation, 12 mm per joint.
    jitter(&mut swing.positions, 0.024, 0x2545_F491_4F6C_DD1D);
    let expected: Vec<f32> = labels.iter().map(|&l| l as f32).collect();
    assert_near(&detected(&swing), &expected, "noisy driver");
}

#[test]
fn events_follow_an_amateur_tempo() {
    let (swing, labels) = driver();
    // Backswing (address to top) 2.5x slower and downswing 1.5x slower: takeaway to impact
    // goes from 1.2 s to 2.9 s.
    let (address, top, impact) = (labels[0] as f32, labels[3] as f32, labels[6] as f32);
    let warp = Warp(vec![(address, top, 2.5), (top, impact, 1.5)]);
    let slow = warp.apply(&swing);
    // Compared in the original timeline, where two frames are the same share of the swing.
    let events = detected(&slow);
    for (position, &label) in Position::ALL.iter().zip(&labels) {
        let found = warp.backward(events.frame(*position).unwrap() as f32);
        assert!(
            (found - label as f32).abs() <= TOLERANCE_FRAMES as f32 + 0.5,
            "slow driver: {} at original frame {found:.1}, labelled {label}",
            position.name()
        );
    }
}

#[test]
fn a_waggle_before_the_swing_is_not_the_takeaway() {
    let (swing, labels) = driver();
    // 0.5 s still, a 0.5 s waggle moving everything from the hips up 8 cm back and forth
    // along the target line, 0.4 s still, then the swing.
    let rate = swing.rate_hz;
    let (still, waggle, settle) = (
        (0.5 * rate) as usize,
        (0.5 * rate) as usize,
        (0.4 * rate) as usize,
    );
    let first = swing.frame(0).to_vec();
    let pelvis_y = first[0].y;
    let mut positions = Vec::new();
    for f in 0..still + waggle + settle {
        let phase = f.saturating_sub(still) as f32 / waggle as f32;
        let offset = if f >= still && f < still + waggle {
            0.08 * (std::f32::consts::TAU * phase).sin()
        } else {
            0.0
        };
        positions.extend(first.iter().map(|p| {
            let mut q = *p;
            if q.y > pelvis_y {
                q.z -= offset * (q.y - pelvis_y);
            }
            q
        }));
    }
    let lead_in = positions.len() / first.len();
    positions.extend_from_slice(&swing.positions);
    let frames = positions.len() / first.len();
    let waggling = io::Motion {
        positions,
        missing: vec![false; frames * first.len()],
        ..swing.clone()
    };
    let expected: Vec<f32> = labels
        .iter()
        .map(|&l| (l as usize + lead_in) as f32)
        .collect();
    assert_near(&detected(&waggling), &expected, "driver after a waggle");
}

#[test]
fn a_left_handed_golfer_leads_with_the_right_side() {
    let (swing, labels) = driver();
    let lefty = posecoach_tests::left_handed(&swing);
    let events = detected(&lefty);
    assert_eq!(events.lead, Side::Right);
    let expected: Vec<f32> = labels.iter().map(|&l| l as f32).collect();
    assert_near(&events, &expected, "left-handed driver");
}

#[test]
fn without_a_club_the_hands_and_lead_arm_give_the_positions() {
    // The tour swings retargeted onto an H36M-17 student: no club, no hands, no toes.
    let student = io::load(&fixture("h36m17_tpose.csv")).unwrap();
    for (name, expected) in labels() {
        let swing = io::load(&fixture(&name))
            .unwrap()
            .retarget_analytic(&student)
            .unwrap();
        let events = detected(&swing);
        assert!(!events.club);
        assert_eq!(events.lead, Side::Left);
        for (position, &label) in Position::ALL.iter().zip(&expected) {
            let found = events.frame(*position).unwrap() as i32;
            assert!(
                (found - label).abs() <= TOLERANCE_FRAMES,
                "{name} without a club: {} at frame {found}, labelled {label}",
                position.name()
            );
        }
    }
}

#[test]
fn a_putt_has_address_top_impact_and_finish() {
    let (golfer, _) = driver();
    let (putt, expected) = posecoach_tests::synthetic_putt(&golfer, 8.0, 0.6, 12.0, 0.6);
    let events = detected(&putt);
    assert_eq!(events.kind, posecoach_core::events::SwingKind::Putt);
    assert_eq!(events.lead, Side::Left);
    let found = [
        events.address(),
        events.top(),
        events.impact(),
        events.finish(),
    ];
    for ((name, f), e) in ["address", "top", "impact", "finish"]
        .iter()
        .zip(found)
        .zip(expected)
    {
        assert!(
            (f as f32 - e).abs() <= TOLERANCE_FRAMES as f32 + 0.5,
            "putt {name}: frame {f}, built at {e:.1}"
        );
    }
    for event in [
        Position::P2,
        Position::P3,
        Position::P5,
        Position::P6,
        Position::P8,
        Position::P9,
    ] {
        assert_eq!(events.frame(event), None);
    }
}

#[test]
fn a_takeaway_timed_against_the_coach_follows_a_slow_backswing_through_noise() {
    use posecoach_core::events::takeaway_against;
    let (coach, labels) = driver();
    // Twice the coach's backswing from the takeaway (frame 0) to the top, then 2 cm of
    // uniform noise per coordinate on the student.
    let top = labels[3] as f32;
    let warp = Warp(vec![(0.0, top, 2.0)]);
    let slow = warp.apply(&coach);
    // Behind 40 frames of still set-up.
    let lead_in = 40;
    let mut positions: Vec<_> = (0..lead_in).flat_map(|_| slow.frame(0).to_vec()).collect();
    positions.extend_from_slice(&slow.positions);
    let mut student = io::Motion {
        missing: vec![false; positions.len()],
        positions,
        ..slow
    };
    jitter(&mut student.positions, 0.04, 0x9E37_79B9_7F4A_7C15);
    let (s, c) = (detected(&student), detected(&coach));
    let s_hz = student.rate_hz;
    let found = takeaway_against(
        &coach.skeleton,
        student.swing(),
        &s,
        s_hz,
        coach.swing(),
        &c,
        coach.rate_hz,
    )
    .unwrap();
    // The noise shows in the crossings' scatter, and a later top would pull the takeaway
    // earlier (the backswing's ends move together).
    assert!(found.spread > 0.0 && found.top_gain > 0.0, "{found:?}");
    let found = found.time;
    let truth = lead_in as f32 + warp.forward(c.time(Event::Address).unwrap());
    assert!(
        (found - truth).abs() <= 1.5,
        "takeaway at frame {found:.1}, truth {truth:.1}"
    );
    let moved = s.with_takeaway(found);
    assert_eq!(moved.time(Event::Address), Some(found));
    assert_eq!(moved.address(), found as usize);
    assert_eq!(moved.time(Event::Top), s.time(Event::Top));
}

#[test]
fn someone_walking_makes_no_stroke() {
    // The driver carried along at a walking pace (1.2 m/s): the same hands, but the feet
    // travel a metre between address and impact.
    let (swing, _) = driver();
    let n = swing.skeleton.len();
    let mut walking = swing.clone();
    for (f, frame) in walking.positions.chunks_exact_mut(n).enumerate() {
        let along = 1.2 * f as f32 / swing.rate_hz;
        frame.iter_mut().for_each(|p| p.x += along);
    }
    let e = detect(&walking.skeleton, walking.swing(), walking.rate_hz).unwrap_err();
    assert_eq!(e, posecoach_core::events::EventError::NoSwing);
    // Real walking, which the hands' small rise made a putt.
    let Some(data) = posecoach_tests::shared_data("someone_walking_makes_no_stroke") else {
        return;
    };
    for name in ["walk_normal_001", "walk-left_normal_001", "walk_giant_001"] {
        let path = data.join(format!("bvh/bandai/dataset-1_{name}.bvh"));
        let walk = io::load(&path).unwrap().resampled(60.0).unwrap();
        let found = detect(&walk.skeleton, walk.swing(), walk.rate_hz);
        assert!(found.is_err(), "{name}: {found:?}");
    }
}

#[test]
fn a_pause_at_the_top_belongs_to_the_backswing() {
    let (swing, _) = driver();
    let plain = detected(&swing);
    let top = plain.top();
    // The arrival is the top where the hands do not pause.
    assert_eq!(plain.arrival(), plain.time(Event::Top).unwrap());
    // The same swing held still at its top for 0.25 s.
    let held = (0.25 * swing.rate_hz).round() as usize;
    let paused = paused(&swing, top, held);
    let events = detected(&paused);
    // Counted from a later frame, the arrival moves with the other events.
    let later = events.from_frame(3);
    assert_eq!(later.arrival(), events.arrival() - 3.0);
    assert_eq!(
        later.time(Event::Top),
        events.time(Event::Top).map(|t| t - 3.0)
    );
    // The top is the pause's end, where the downswing starts; the hands arrived at its start.
    let (start, end) = (top as f32, (top + held) as f32);
    let found = events.time(Event::Top).unwrap();
    assert!(
        (found - end).abs() <= 1.5,
        "top {found}, pause {start}..{end}"
    );
    assert!(
        (events.arrival() - start).abs() <= 1.5,
        "arrival {}",
        events.arrival()
    );
    // Its takeaway is the unpaused swing's, timed against the unpaused coach, to the arrival's
    // frame times the takeaway's gain on it (1.5 to 3); timed from the pause's end it came 6
    // to 12 frames early.
    let against = |e: &posecoach_core::events::SwingEvents, m: &io::Motion| {
        posecoach_core::events::takeaway_against(
            &m.skeleton,
            m.swing(),
            e,
            m.rate_hz,
            swing.swing(),
            &plain,
            swing.rate_hz,
        )
        .unwrap()
        .time
    };
    let (a, b) = (against(&plain, &swing), against(&events, &paused));
    assert!((a - b).abs() <= 2.0, "takeaway {a} unpaused, {b} paused");
}
