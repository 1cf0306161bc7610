//! Every real file in `../shared/data` and every committed fixture imports with a plausible
//! height.

use posecoach_io as io;
use posecoach_io::c3d::C3d;
use posecoach_tests::{files, fixture, shared_data};
use std::path::Path;

const PLAUSIBLE_HEIGHT_M: std::ops::Range<f32> = 1.4..2.1;

fn check(path: &Path) -> usize {
    let motion = io::load(path).unwrap_or_else(|e| panic!("{e}"));
    let h = motion.skeleton.height();
    assert!(
        PLAUSIBLE_HEIGHT_M.contains(&h),
        "{}: height {h} m",
        path.display()
    );
    assert!(
        motion.frames() > 0 && motion.rate_hz > 0.0,
        "{}",
        path.display()
    );
    assert!(motion
        .positions
        .iter()
        .all(|p| p.iter().all(|v| v.is_finite())));
    motion.frames()
}

#[test]
fn every_shared_motion_file_imports() {
    let Some(data) = shared_data("every_shared_motion_file_imports") else {
        return;
    };
    let bvh = files(&data, "bvh");
    let c3d = files(&data, "c3d");
    assert_eq!(
        (bvh.len(), c3d.len()),
        (24, 2),
        "the shared data set changed"
    );
    for path in bvh.iter().chain(&c3d) {
        check(path);
    }
}

#[test]
fn committed_fixtures_import() {
    for name in ["cmu_131_01_excerpt.bvh", "bandai_walk_excerpt.bvh"] {
        check(&fixture(name));
    }
    let markers = fixture("golf_driver_markers_60hz.c3d");
    assert_eq!(check(&markers), 109);
    let raw = C3d::parse(&std::fs::read(&markers).unwrap()).unwrap();
    assert!(
        raw.valid.contains(&false),
        "the fixture keeps the capture's gaps"
    );
    let golf = io::load(&markers).unwrap();
    assert_eq!(golf.skeleton.format().name(), "golf");
    assert_eq!((golf.skeleton.len(), golf.rate_hz), (22, 60.0));
    let tpose = io::load(&fixture("h36m17_tpose.csv")).unwrap();
    assert_eq!((tpose.frames(), tpose.skeleton.len()), (1, 17));
    assert!((tpose.skeleton.height() - 1.62).abs() < 1e-4);
}

#[test]
fn bvh_formats_and_units_are_recognized() {
    let cmu = io::load(&fixture("cmu_131_01_excerpt.bvh")).unwrap();
    assert_eq!(cmu.skeleton.format().name(), "cmu31");
    assert_eq!(cmu.skeleton.len(), 31);
    assert!((cmu.rate_hz - 30.0).abs() < 0.01);
    let bandai = io::load(&fixture("bandai_walk_excerpt.bvh")).unwrap();
    assert_eq!(bandai.skeleton.format().name(), "bandai22");
    assert_eq!(bandai.names[0], "Hips", "joint_Root is dropped");
    // Feet on the floor: the lowest toe of the walk is within a few centimetres of y = 0.
    let lowest = bandai
        .positions
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    assert!((0.0..0.06).contains(&lowest), "{lowest}");
}
