//! Body metrics on the two real tour swings: they read the way tour swings are described
//! (turned at the top, open at impact, the pelvis shifted toward the target), and a
//! left-handed golfer's mirror image reads the same.

use posecoach_core::body::{at_positions, Metrics};
use posecoach_core::events::{detect, Position, Side};
use posecoach_io as io;
use posecoach_tests::{fixture, left_handed};

fn table(swing: &io::Motion) -> [Option<Metrics>; 10] {
    let events = detect(&swing.skeleton, swing.swing(), swing.rate_hz).unwrap();
    at_positions(&swing.skeleton, swing.swing(), &events).unwrap()
}

fn at(table: &[Option<Metrics>; 10], p: Position) -> Metrics {
    table[p as usize].unwrap_or_else(|| panic!("no {}", p.name()))
}

const SWINGS: [&str; 2] = ["golf_driver_60hz.csv", "golf_iron_60hz.csv"];

#[test]
fn tour_swings_turn_at_the_top_and_open_through_impact() {
    for name in SWINGS {
        let t = table(&io::load(&fixture(name)).unwrap());
        assert!(t.iter().all(Option::is_some), "{name}: every position");
        let (address, top, impact) = (
            at(&t, Position::P1),
            at(&t, Position::P4),
            at(&t, Position::P7),
        );
        // Set up square, bent over the ball, trail shoulder lower.
        assert!(
            address.pelvis.turn.abs() < 10.0 && address.thorax.turn.abs() < 10.0,
            "{name}: {address:?}"
        );
        assert!((20.0..50.0).contains(&address.spine), "{name}: {address:?}");
        assert!(address.thorax.side_bend > 0.0, "{name}: {address:?}");
        // The top: shoulders turned about twice as far as the hips.
        assert!((40.0..70.0).contains(&top.pelvis.turn), "{name}: {top:?}");
        assert!((85.0..120.0).contains(&top.thorax.turn), "{name}: {top:?}");
        assert!((35.0..60.0).contains(&top.x_factor), "{name}: {top:?}");
        // Impact: hips open more than the shoulders, the pelvis moved toward the target,
        // the trail side down.
        assert!(
            impact.pelvis.turn < -30.0 && impact.pelvis.turn < impact.thorax.turn,
            "{name}: {impact:?}"
        );
        assert!(impact.pelvis_shift.sway > 0.03, "{name}: {impact:?}");
        assert!(impact.thorax.side_bend > 15.0, "{name}: {impact:?}");
        // The club: hands ahead of the head at impact.
        assert!(impact.shaft_lean.unwrap() > 0.0, "{name}: {impact:?}");
    }
}

#[test]
fn a_left_handed_golfer_reads_like_the_right_handed_one() {
    for name in SWINGS {
        let swing = io::load(&fixture(name)).unwrap();
        let lefty = left_handed(&swing);
        let events = detect(&lefty.skeleton, lefty.swing(), lefty.rate_hz).unwrap();
        assert_eq!(events.lead, Side::Right);
        let (right, left) = (table(&swing), table(&lefty));
        for p in Position::ALL {
            let (a, b) = (at(&right, p), at(&left, p));
            let pairs = [
                (a.pelvis.turn, b.pelvis.turn),
                (a.thorax.turn, b.thorax.turn),
                (a.thorax.bend, b.thorax.bend),
                (a.thorax.side_bend, b.thorax.side_bend),
                (a.spine, b.spine),
                (a.lead_elbow, b.lead_elbow),
                (a.pelvis_shift.sway * 100.0, b.pelvis_shift.sway * 100.0),
                (a.pelvis_shift.thrust * 100.0, b.pelvis_shift.thrust * 100.0),
            ];
            for (x, y) in pairs {
                assert!((x - y).abs() < 0.01, "{name} {}: {x} against {y}", p.name());
            }
        }
    }
}

#[test]
fn tour_swings_speed_up_from_the_hips_to_the_club() {
    use posecoach_core::body::Link;
    use posecoach_core::sequence::kinematic_sequence;
    for name in SWINGS {
        let swing = io::load(&fixture(name)).unwrap();
        let events = detect(&swing.skeleton, swing.swing(), swing.rate_hz).unwrap();
        let sequence = kinematic_sequence(&swing.skeleton, swing.swing(), swing.rate_hz, &events)
            .unwrap()
            .unwrap();
        let peak = |l| sequence.peak(l).unwrap();
        // Tour players' peaks, degrees per second (about 500, 700, 1000 and 2300 in published
        // K-Vest norms): each link faster than the one before.
        let speeds = Link::ALL.map(|l| peak(l).speed);
        assert!((400.0..800.0).contains(&speeds[0]), "{name}: {speeds:?}");
        assert!(speeds.windows(2).all(|w| w[1] > w[0]), "{name}: {speeds:?}");
        assert!((1800.0..3200.0).contains(&speeds[3]), "{name}: {speeds:?}");
        // The hips peak first and the club last, within the downswing.
        let order = sequence.order();
        assert_eq!((order[0], order[3]), (Link::Pelvis, Link::Club), "{name}");
        let (top, impact) = (
            events.time(Position::P4).unwrap(),
            events.time(Position::P7).unwrap(),
        );
        for l in Link::ALL {
            assert!(peak(l).time > top && peak(l).time <= impact, "{name}");
        }
    }
}
