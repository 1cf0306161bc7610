//! Shared helpers for the integration tests: where the committed fixtures and the real data
//! in `../shared/data` live.

use std::path::PathBuf;

/// Adds uniform noise of `width` metres peak to peak (standard deviation `width / √12`) to
/// every coordinate of `positions`: a fixed xorshift sequence from `seed`, so a test sees the
/// same noise on every run.
pub fn jitter(positions: &mut [posecoach_core::Vec3], width: f32, seed: u64) {
    let mut state = seed;
    for p in positions {
        for v in p.iter_mut() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            *v += ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * width;
        }
    }
}

/// The mirror image of `swing` across the plane through the ball perpendicular to the target
/// line (z -> -z), left and right joints swapped: a left-handed golfer.
pub fn left_handed(swing: &posecoach_io::Motion) -> posecoach_io::Motion {
    let s = &swing.skeleton;
    let n = s.len();
    let partner: Vec<usize> = (0..n)
        .map(|k| s.joint(k).and_then(|j| s.index_of(j.mirror())).unwrap_or(k))
        .collect();
    let positions = swing
        .positions
        .chunks_exact(n)
        .flat_map(|f| {
            partner
                .iter()
                .map(move |&k| posecoach_core::Vec3::new(f[k].x, f[k].y, -f[k].z))
        })
        .collect();
    posecoach_io::Motion {
        positions,
        ..swing.clone()
    }
}

/// `swing` held still at frame `frame` for `frames` more frames: a pause there.
pub fn paused(swing: &posecoach_io::Motion, frame: usize, frames: usize) -> posecoach_io::Motion {
    let n = swing.skeleton.len();
    let held = &swing.positions[frame * n..(frame + 1) * n];
    let positions: Vec<_> = swing.positions[..frame * n]
        .iter()
        .chain((0..frames).flat_map(|_| held))
        .chain(&swing.positions[frame * n..])
        .copied()
        .collect();
    posecoach_io::Motion {
        missing: vec![false; positions.len()],
        positions,
        ..swing.clone()
    }
}

/// The time of each swing's top in the recorded session `log` (`tests/logs`, without its
/// extension), microseconds on the sender's clock, from its sidecar.
pub fn swing_tops_us(log: &str) -> Vec<u64> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("logs")
        .join(format!("{log}.swings.json"));
    let text = std::fs::read_to_string(&path).unwrap_or_default();
    let sidecar: serde_json::Value = serde_json::from_str(&text).unwrap_or_default();
    let swings = sidecar["swings"].as_array().map_or(&[][..], Vec::as_slice);
    let top = |s: &serde_json::Value| s["events_s"]["top"].as_f64().map(|t| (t * 1e6) as u64);
    swings.iter().filter_map(top).collect()
}

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
    pub fn apply(&self, motion: &posecoach_io::Motion) -> posecoach_io::Motion {
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
        posecoach_io::Motion {
            positions,
            missing: vec![false; frames * motion.skeleton.len()],
            ..motion.clone()
        }
    }
}

/// A synthetic putt at 60 Hz from the address pose (frame 0) of `golfer`: shoulders, arms and
/// club rock about the spine axis through the thorax, eased with minimum jerk: 0.5 s still, a backstroke of
/// `back_deg` over `back_s`, a forward stroke to `through_deg` over `through_s`, 0.5 s still.
/// Returns the motion and its events by construction: address, top, impact (the pose of
/// address again) and finish, in frames.
pub fn synthetic_putt(
    golfer: &posecoach_io::Motion,
    back_deg: f32,
    back_s: f32,
    through_deg: f32,
    through_s: f32,
) -> (posecoach_io::Motion, [f32; 4]) {
    use posecoach_core::joint::Joint;
    use posecoach_core::{Quat, Vec3};
    const RATE_HZ: f32 = 60.0;
    let s = &golfer.skeleton;
    let address = golfer.frame(0).to_vec();
    let at = |j: Joint| address[s.index_of(j).unwrap()];
    let (thorax, pelvis) = (at(Joint::Thorax), at(Joint::Pelvis));
    let axis = nalgebra::Unit::new_normalize(thorax - pelvis);
    let moving: Vec<usize> = (0..s.len())
        .filter(|&k| {
            s.joint(k).is_some_and(|j| {
                j.is_club()
                    || matches!(
                        j,
                        Joint::LeftShoulder | Joint::LeftElbow | Joint::LeftWrist | Joint::LeftHand
                    )
                    || matches!(
                        j,
                        Joint::RightShoulder
                            | Joint::RightElbow
                            | Joint::RightWrist
                            | Joint::RightHand
                    )
            })
        })
        .collect();
    // Back is away from the target: from the lead (left) foot toward the trail foot.
    let trail = at(Joint::RightAnkle) - at(Joint::LeftAnkle);
    let hands = (at(Joint::LeftWrist) + at(Joint::RightWrist)) * 0.5;
    let turned = Quat::from_axis_angle(&axis, 0.1) * (hands - thorax) + thorax;
    let sign = if (turned - hands).dot(&trail) > 0.0 {
        1.0
    } else {
        -1.0
    };
    // Minimum-jerk easing, the smooth start and stop of a human point-to-point movement.
    let ease = |x: f32| {
        let x = x.clamp(0.0, 1.0);
        x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
    };
    let (still, back, through) = (
        (0.5 * RATE_HZ) as usize,
        back_s * RATE_HZ,
        through_s * RATE_HZ,
    );
    let frames = still + back as usize + through as usize + still;
    let (a, b) = (back_deg.to_radians(), through_deg.to_radians());
    let mut positions: Vec<Vec3> = Vec::with_capacity(frames * s.len());
    for f in 0..frames {
        let t = f as f32 - still as f32;
        let angle = if t <= back {
            a * ease(t / back)
        } else {
            a - (a + b) * ease((t - back) / through)
        };
        let rotation = Quat::from_axis_angle(&axis, sign * angle);
        positions.extend(address.iter().enumerate().map(|(k, &p)| {
            if moving.contains(&k) {
                rotation * (p - thorax) + thorax
            } else {
                p
            }
        }));
    }
    // Impact: the forward stroke passes the address angle where ease(x) = a / (a + b).
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if ease(mid) < a / (a + b) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let impact = still as f32 + back + through * lo;
    let events = [
        still as f32,
        still as f32 + back,
        impact,
        still as f32 + back + through,
    ];
    let motion = posecoach_io::Motion {
        rate_hz: RATE_HZ,
        missing: vec![false; positions.len()],
        positions,
        ..golfer.clone()
    };
    (motion, events)
}

/// Where two JSON documents differ, numbers compared to a relative `tolerance` (the last bits
/// of f32 arithmetic differ between builds whose math comes from `std` or from `libm`);
/// `None` if they agree.
pub fn json_difference(
    a: &serde_json::Value,
    b: &serde_json::Value,
    tolerance: f64,
) -> Option<String> {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64()?, y.as_f64()?);
            let close = (x - y).abs() <= tolerance * x.abs().max(y.abs()).max(1.0);
            (!close).then(|| format!("{x} vs {y}"))
        }
        (Value::Array(x), Value::Array(y)) => {
            if x.len() != y.len() {
                return Some(format!("{} vs {} items", x.len(), y.len()));
            }
            x.iter().zip(y).enumerate().find_map(|(i, (x, y))| {
                json_difference(x, y, tolerance).map(|d| format!("[{i}]: {d}"))
            })
        }
        (Value::Object(x), Value::Object(y)) => {
            if x.keys().ne(y.keys()) {
                return Some("different keys".to_string());
            }
            x.iter().zip(y.values()).find_map(|((k, x), y)| {
                json_difference(x, y, tolerance).map(|d| format!(".{k}: {d}"))
            })
        }
        _ => (a != b).then(|| format!("{a} vs {b}")),
    }
}

/// A command's clap arguments.
#[derive(clap::Parser)]
struct Command<T: clap::Args> {
    #[command(flatten)]
    args: T,
}

/// Parses a command's arguments as the `posecoach` binary does.
pub fn parse<T: clap::Args>(args: &[&str]) -> T {
    use clap::Parser;
    Command::<T>::parse_from(std::iter::once("posecoach").chain(args.iter().copied())).args
}
