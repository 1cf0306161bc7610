//! Shared helpers for the integration tests: where the committed fixtures and the real data
//! in `../shared/data` live.

use std::path::PathBuf;

/// A committed fixture in `tests/fixtures`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// The real motion-capture folder: `$POSECOACH_DATA`, else `../shared/data` beside the
/// repository. `None`, with a message on stderr, when it is absent (a user's machine).
pub fn shared_data(test: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("POSECOACH_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"));
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "{test}: skipped: no real data at {} (set POSECOACH_DATA)",
            dir.display()
        );
        None
    }
}

/// Every file under `dir` with extension `ext`, sorted.
pub fn files(dir: &std::path::Path, ext: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == ext) {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

/// A piecewise-linear time warp: each piece `(from, to, factor)` stretches the original frames
/// `from..to` by `factor`; pieces are sorted and do not overlap, time elsewhere runs as before.
pub struct Warp(pub Vec<(f32, f32, f32)>);

impl Warp {
    /// Original time (frames) to warped time.
    pub fn forward(&self, t: f32) -> f32 {
        let mut shift = 0.0;
        for &(from, to, factor) in &self.0 {
            if t <= from {
                break;
            }
            shift += (t.min(to) - from) * (factor - 1.0);
        }
        t + shift
    }

    /// Warped time to original time.
    pub fn backward(&self, u: f32) -> f32 {
        // Original time runs at most 1 / (the smallest factor) times faster than warped time.
        let fastest = self.0.iter().map(|p| p.2).fold(1.0f32, f32::min);
        let (mut lo, mut hi) = (0.0f32, u / fastest + 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.forward(mid) < u {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// `motion` played on the warped timeline, linearly interpolated between frames.
    pub fn apply(&self, motion: &posecoach_adapters::io::Motion) -> posecoach_adapters::io::Motion {
        let last = motion.frames() - 1;
        let frames = self.forward(last as f32).floor() as usize + 1;
        let positions = (0..frames)
            .flat_map(|u| {
                let t = self.backward(u as f32).min(last as f32);
                let (f, w) = (t.floor() as usize, t - t.floor());
                let (a, b) = (motion.frame(f.min(last)), motion.frame((f + 1).min(last)));
                a.iter()
                    .zip(b)
                    .map(move |(p, q)| p + (q - p) * w)
                    .collect::<Vec<_>>()
            })
            .collect();
        posecoach_adapters::io::Motion {
            positions,
            missing: vec![false; frames * motion.skeleton.len()],
            ..motion.clone()
        }
    }
}
