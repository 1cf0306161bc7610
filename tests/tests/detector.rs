//! The streaming swing detector on a recorded-like stream built from real motion: walking, a
//! waggle, the real driver swing, a practice half swing and the real iron swing, joined by
//! eased blends and still holds at 60 Hz. Exactly the two real swings must come out.

use posecoach_core::detector::{DetectorConfig, SwingDetector};
use posecoach_core::events::{detect, SwingKind};
use posecoach_core::frames::Frames;
use posecoach_core::Vec3;
use posecoach_io::{self as io, Motion};
use posecoach_tests::fixture;

const RATE_HZ: f32 = 60.0;

/// Appends `frames` frames easing from `from` to `to`.
fn blend(stream: &mut Vec<Vec3>, from: &[Vec3], to: &[Vec3], frames: usize) {
    for f in 1..=frames {
        let w = 0.5 * (1.0 - (std::f32::consts::PI * f as f32 / frames as f32).cos());
        stream.extend(from.iter().zip(to).map(|(a, b)| a + (b - a) * w));
    }
}

fn hold(stream: &mut Vec<Vec3>, pose: &[Vec3], seconds: f32) {
    for _ in 0..(seconds * RATE_HZ) as usize {
        stream.extend_from_slice(pose);
    }
}

fn last(stream: &[Vec3], joints: usize) -> Vec<Vec3> {
    stream[stream.len() - joints..].to_vec()
}

#[test]
fn only_the_real_swings_come_out_of_a_stream() {
    let driver = io::load(&fixture("golf_driver_60hz.csv")).unwrap();
    let iron = io::load(&fixture("golf_iron_60hz.csv"))
        .unwrap()
        .retarget_analytic(&driver)
        .unwrap();
    let walk: Motion = io::load(&fixture("bandai_walk_excerpt.bvh"))
        .unwrap()
        .retarget_analytic(&driver)
        .unwrap()
        .resampled(RATE_HZ)
        .unwrap();
    let j = driver.skeleton.len();
    let address = driver.frame(0).to_vec();

    // Walking, placed where the golfer will stand.
    let shift = Vec3::new(
        address[0].x - walk.frame(0)[0].x,
        0.0,
        address[0].z - walk.frame(0)[0].z,
    );
    let mut stream: Vec<Vec3> = walk.positions.iter().map(|p| p + shift).collect();
    let walked = last(&stream, j);
    blend(&mut stream, &walked, &address, 30);
    hold(&mut stream, &address, 0.8);
    // A waggle: everything above the hips swings 8 cm back and forth along the target line.
    for f in 0..30 {
        let offset = 0.08 * (std::f32::consts::TAU * f as f32 / 30.0).sin();
        stream.extend(address.iter().map(|p| {
            if p.y > address[0].y {
                p - Vec3::z() * offset * (p.y - address[0].y)
            } else {
                *p
            }
        }));
    }
    hold(&mut stream, &address, 0.5);
    let driver_at = stream.len() / j;
    stream.extend_from_slice(&driver.positions);
    let finished = last(&stream, j);
    blend(&mut stream, &finished, &address, 30);
    hold(&mut stream, &address, 1.0);
    // A practice half swing: the takeaway to hip height and back.
    for f in (0..45).chain((0..45).rev()) {
        stream.extend_from_slice(driver.frame(f));
    }
    hold(&mut stream, &address, 0.8);
    let iron_start = iron.frame(0).to_vec();
    blend(&mut stream, &address, &iron_start, 30);
    let iron_at = stream.len() / j;
    stream.extend_from_slice(&iron.positions);
    let done = last(&stream, j);
    hold(&mut stream, &done, 1.0);

    let mut storage = vec![[0i16; 3]; j * (6.0 * RATE_HZ) as usize];
    let mut detector = SwingDetector::new(
        &driver.skeleton,
        DetectorConfig::full_swing(RATE_HZ),
        &mut storage,
    )
    .unwrap();
    let mut swings = Vec::new();
    for frame in stream.chunks_exact(j) {
        if let Some(window) = detector.push(frame).unwrap() {
            let out: Vec<Vec3> = detector
                .with_window(&window, |f| f.iter().collect())
                .unwrap();
            swings.push((window, out));
        }
    }
    assert_eq!(
        swings.len(),
        2,
        "windows: {:?}",
        swings.iter().map(|s| s.0).collect::<Vec<_>>()
    );
    for ((window, frames), (at, swing)) in
        swings.iter().zip([(driver_at, &driver), (iron_at, &iron)])
    {
        let events = detect(&driver.skeleton, Frames::metres(frames, j), RATE_HZ).unwrap();
        assert_eq!(events.kind, SwingKind::Full);
        // The window holds the whole swing from its set-up to its finish.
        let truth = detect(&driver.skeleton, swing.swing(), RATE_HZ).unwrap();
        let start = window.start as usize;
        assert!(
            start <= at + truth.address(),
            "window starts at {start}, address at {}",
            at + truth.address()
        );
        assert!(
            start + window.len > at + truth.finish(),
            "window ends at {}, finish at {}",
            start + window.len,
            at + truth.finish()
        );
        for (event, frame) in truth.iter() {
            let found = events.frame(event).map(|f| f + start);
            assert!(
                found.is_some_and(|f| f.abs_diff(at + frame) <= 2),
                "{}: {found:?} vs {}",
                event.name(),
                at + frame
            );
        }
    }
}
