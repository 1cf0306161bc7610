//! Synthetic motions for the stages' tests: points eased from key to key at 30 Hz (the
//! device's model rate; few frames keep the tests short under Miri).

#![cfg(test)]

use crate::Vec3;

/// The frame rate of every synthetic motion.
pub(super) const RATE_HZ: f32 = 30.0;

/// Where the hands are at address (and back at impact), metres.
pub(super) const HOME: [f32; 3] = [0.0, 1.0, 0.0];

/// A full swing's hands, as keys (frame, where): still at address until frame 15, at the top
/// at frame 35, back at address (impact) at 43, highest at the finish at 55, then lowered.
pub(super) const SWING: [(usize, [f32; 3]); 5] = [
    (15, HOME),
    (35, [0.3, 2.0, -0.5]),
    (43, HOME),
    (55, [0.3, 2.0, 0.6]),
    (70, [0.3, 1.5, 0.4]),
];

/// How many frames [`SWING`] runs: still ones after its last key.
pub(super) const FRAMES: usize = 75;

/// `frames` frames of a point eased with minimum jerk from key to key (frame, where), still
/// before the first key and after the last.
pub(super) fn eased(keys: &[(usize, [f32; 3])], frames: usize) -> Vec<Vec3> {
    (0..frames)
        .map(|f| {
            let next = keys.iter().position(|&(k, _)| k > f);
            // In plain `f32`s: nalgebra's generic arithmetic is slow under Miri.
            let [x, y, z] = match next {
                Some(0) => keys[0].1,
                None => keys[keys.len() - 1].1,
                Some(i) => {
                    let ((a, p), (b, q)) = (keys[i - 1], keys[i]);
                    let s = (f - a) as f32 / (b - a) as f32;
                    let e = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
                    core::array::from_fn(|k| p[k] + (q[k] - p[k]) * e)
                }
            };
            Vec3::new(x, y, z)
        })
        .collect()
}

/// Frames of one joint per path, in the order given.
pub(super) fn joints(paths: &[&[Vec3]]) -> Vec<Vec3> {
    (0..paths[0].len())
        .flat_map(|f| paths.iter().map(move |p| p[f]))
        .collect()
}

/// Left and right wrist, 10 cm apart across `hands` (their midpoint), as two paths.
pub(super) fn wrists(hands: &[Vec3]) -> [Vec<Vec3>; 2] {
    let apart = Vec3::new(0.0, 0.0, 0.05);
    [
        hands.iter().map(|h| h + apart).collect(),
        hands.iter().map(|h| h - apart).collect(),
    ]
}

/// The two wrists' frames around `hands` (joints 0 and 1).
pub(super) fn hands_only(hands: &[Vec3]) -> Vec<Vec3> {
    let [left, right] = wrists(hands);
    joints(&[&left, &right])
}
