//! Cross-format analytic retargeting, written as BVH and CSV and read back.

use posecoach_io::{self as io, Motion};
use posecoach_tests::{fixture, shared_data};
use std::path::Path;

const TOLERANCE_M: f32 = 1e-5;

fn retarget(coach: &Path, student: &Path) -> Motion {
    let coach = io::load(coach).unwrap();
    let student = io::load(student).unwrap();
    let out = coach.retarget_analytic(&student).unwrap();
    assert_eq!(out.frames(), coach.frames());
    assert_eq!(out.skeleton, student.skeleton);
    for f in 0..out.frames() {
        let frame = out.frame(f);
        for k in 1..out.skeleton.len() {
            let bone = (frame[k] - frame[out.skeleton.parent(k).unwrap()]).norm();
            assert!((bone - out.skeleton.offset(k).norm()).abs() < TOLERANCE_M);
        }
    }
    out
}

/// Writes `motion` as BVH and as CSV, reads both back and compares joint positions (the CSV
/// holds the canonical joints only).
fn round_trip(motion: &Motion, stem: &str) {
    let dir = std::env::temp_dir().join(format!("posecoach-{stem}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bvh = dir.join(format!("{stem}.bvh"));
    io::save(motion, &bvh).unwrap();
    let back = io::load(&bvh).unwrap();
    assert_eq!(back.names, motion.names);
    assert_eq!(back.frames(), motion.frames());
    let worst = back
        .positions
        .iter()
        .zip(&motion.positions)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f32::max);
    assert!(worst < TOLERANCE_M, "{stem}.bvh: {worst} m");

    let csv = dir.join(format!("{stem}.csv"));
    io::save(motion, &csv).unwrap();
    let back = io::load(&csv).unwrap();
    assert_eq!(back.frames(), motion.frames());
    let n = motion.skeleton.len();
    let canonical = (0..n)
        .filter(|&k| motion.skeleton.joint(k).is_some())
        .count();
    assert_eq!(back.skeleton.len(), canonical);
    for k in 0..back.skeleton.len() {
        let joint = back.skeleton.joint(k).unwrap();
        let original = motion.skeleton.index_of(joint).unwrap();
        for f in 0..motion.frames() {
            assert_eq!(
                back.frame(f)[k],
                motion.frame(f)[original],
                "{stem}.csv {joint} frame {f}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bandai_onto_cmu_round_trips_through_bvh_and_csv() {
    let out = retarget(
        &fixture("bandai_walk_excerpt.bvh"),
        &fixture("cmu_131_01_excerpt.bvh"),
    );
    assert_eq!(out.skeleton.format().name(), "cmu31");
    round_trip(&out, "bandai-on-cmu");
}

#[test]
fn cmu_onto_an_h36m_t_pose_round_trips() {
    let out = retarget(
        &fixture("cmu_131_01_excerpt.bvh"),
        &fixture("h36m17_tpose.csv"),
    );
    assert_eq!(out.skeleton.len(), 17);
    round_trip(&out, "cmu-on-h36m");
}

#[test]
fn golf_swing_onto_an_h36m_t_pose_round_trips() {
    let out = retarget(
        &fixture("golf_driver_60hz.csv"),
        &fixture("h36m17_tpose.csv"),
    );
    assert!((out.rate_hz - 60.0).abs() < 0.01);
    round_trip(&out, "golf-csv-on-h36m");
}

#[test]
fn c3d_golf_markers_onto_an_h36m_t_pose_round_trip() {
    let out = retarget(
        &fixture("golf_driver_markers_60hz.c3d"),
        &fixture("h36m17_tpose.csv"),
    );
    assert_eq!((out.frames(), out.skeleton.len()), (109, 17));
    assert!((out.rate_hz - 60.0).abs() < 0.01);
    round_trip(&out, "golf-c3d-on-h36m");
}

#[test]
fn real_c3d_golf_swing_onto_an_h36m_t_pose_round_trips() {
    let Some(data) = shared_data("real_c3d_golf_swing_onto_an_h36m_t_pose_round_trips") else {
        return;
    };
    for name in ["gears_tour_driver.c3d", "gears_tour_iron.c3d"] {
        let out = retarget(&data.join("golf").join(name), &fixture("h36m17_tpose.csv"));
        round_trip(&out, name);
    }
}
