//! Regenerates the derived fixtures in `tests/fixtures` from `../shared/data`:
//! `cargo test -p posecoach-tests --test fixtures -- --ignored`. Their provenance is this code.

use posecoach_adapters::io::bvh::Bvh;
use posecoach_adapters::io::c3d::C3d;
use posecoach_adapters::io::{csv, golf, Motion};
use posecoach_tests::{fixture, shared_data};

/// The first `frames` frames of a BVH clip, every `step`-th frame, with the same hierarchy.
fn excerpt(bvh: &Bvh, step: usize, frames: usize) -> Bvh {
    let channels = bvh.channel_count();
    let motion = bvh
        .motion
        .chunks_exact(channels)
        .step_by(step)
        .take(frames)
        .flatten()
        .copied()
        .collect::<Vec<f64>>();
    Bvh {
        joints: bvh.joints.clone(),
        frame_time: bvh.frame_time * step as f64,
        frames: motion.len() / channels,
        motion,
    }
}

#[test]
#[ignore = "writes tests/fixtures from ../shared/data; run by hand"]
fn regenerate() {
    let Some(data) = shared_data("regenerate") else {
        panic!("the fixtures are derived from ../shared/data, which is absent");
    };
    let clips = [
        ("bvh/cmu/131_01.bvh", 4, 60, "cmu_131_01_excerpt.bvh"),
        (
            "bvh/bandai/dataset-1_walk_normal_001.bvh",
            1,
            40,
            "bandai_walk_excerpt.bvh",
        ),
    ];
    for (source, step, frames, out) in clips {
        let bvh = Bvh::parse(&std::fs::read_to_string(data.join(source)).unwrap()).unwrap();
        std::fs::write(fixture(out), excerpt(&bvh, step, frames).to_text()).unwrap();
    }
    let c3d = C3d::parse(&std::fs::read(data.join("golf/gears_tour_driver.c3d")).unwrap()).unwrap();
    let centres = golf::resample(&golf::joint_centres(&c3d).unwrap(), GOLF_RATE_HZ);
    let swing = Motion::from_golf(&centres).unwrap();
    std::fs::write(fixture("golf_driver_60hz.csv"), csv::write(&swing)).unwrap();
}

/// The rate the scoring tests use for the golf swings.
const GOLF_RATE_HZ: f32 = 60.0;
