//! Regenerates the derived fixtures in `tests/fixtures` from `../shared/data`:
//! `cargo test -p posecoach-tests --test fixtures -- --ignored`. Their provenance is this code.

use posecoach_io::bvh::Bvh;
use posecoach_io::c3d::{C3d, Storage};
use posecoach_io::{csv, golf, Motion};
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

/// Every `step`-th frame of a C3D trial, with its labels and missing samples as they are.
fn decimate(c3d: &C3d, step: usize) -> C3d {
    fn every<T: Copy>(samples: &[T], labels: usize, step: usize) -> Vec<T> {
        let frames = samples.chunks_exact(labels).step_by(step);
        frames.flatten().copied().collect()
    }
    let n = c3d.labels.len();
    let points = every(&c3d.points, n, step);
    C3d {
        labels: c3d.labels.clone(),
        rate_hz: c3d.rate_hz / step as f32,
        frames: points.len() / n,
        first_frame: c3d.first_frame,
        units_to_metres: c3d.units_to_metres,
        points,
        valid: every(&c3d.valid, n, step),
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
    for club in ["iron", "driver"] {
        let c3d =
            C3d::parse(&std::fs::read(data.join(format!("golf/gears_tour_{club}.c3d"))).unwrap())
                .unwrap();
        let swing = Motion::from_golf(&golf::joint_centres(&c3d).unwrap())
            .unwrap()
            .resampled(GOLF_RATE_HZ)
            .unwrap();
        std::fs::write(
            fixture(&format!("golf_{club}_60hz.csv")),
            csv::write(&swing),
        )
        .unwrap();
    }
    let c3d = C3d::parse(&std::fs::read(data.join("golf/gears_tour_driver.c3d")).unwrap()).unwrap();

    let markers = decimate(&c3d, (c3d.rate_hz / GOLF_RATE_HZ) as usize);
    assert_eq!(markers.rate_hz, GOLF_RATE_HZ);
    let bytes = markers.to_bytes(MARKER_STORAGE);
    let back = C3d::parse(&bytes).unwrap();
    assert_eq!(
        back.valid, markers.valid,
        "a marker is out of the integer range"
    );
    std::fs::write(fixture("golf_driver_markers_60hz.c3d"), bytes).unwrap();
}

/// The rate the scoring tests use for the golf swings.
const GOLF_RATE_HZ: f32 = 60.0;
/// 0.5 mm steps (±16.38 m): half the size of float storage.
const MARKER_STORAGE: Storage = Storage::Integer { scale: 0.0005 };
