//! Reading a signal of the frame (a speed, an angle, a height): where it crosses a level and
//! where it turns, placed between frames.

/// The first frame in `range` (walking in its direction) where `f` crosses `level` upwards
/// (`rising`) or downwards, whichever of the two frames around the crossing is nearer the level.
pub(super) fn crossing(
    range: impl Iterator<Item = usize>,
    f: impl Fn(usize) -> f32,
    level: f32,
    rising: bool,
) -> Option<usize> {
    let mut previous: Option<(usize, f32)> = None;
    for t in range {
        let v = f(t) - level;
        if let Some((p, pv)) = previous {
            let (before, after) = if p < t { (pv, v) } else { (v, pv) };
            let crossed = if rising {
                before < 0.0 && after >= 0.0
            } else {
                before > 0.0 && after <= 0.0
            };
            if crossed {
                return Some(if v.abs() < pv.abs() { t } else { p });
            }
        }
        previous = Some((t, v));
    }
    None
}

/// A crossing of `level` that [`crossing`] found at frame `t` of `f` (over `frames` frames),
/// placed between the two frames around it.
// Out of line: inlined, each caller reads its own `f` four times over in place (2.9 KiB more
// of the firmware's flash).
#[inline(never)]
pub(super) fn crossed(f: &dyn Fn(usize) -> f32, level: f32, t: usize, frames: usize) -> f32 {
    let next = (t + 1).min(frames - 1);
    if (f(t) - level) * (f(next) - level) <= 0.0 {
        between(f, level, t, next)
    } else {
        between(f, level, t.saturating_sub(1), t)
    }
}

/// A turning point of `f` found at frame `t` (of `frames` frames), placed between frames; at
/// the first or last frame, that frame.
// Out of line, as `crossed` (0.6 KiB of the firmware's flash).
#[inline(never)]
pub(super) fn turning(f: &dyn Fn(usize) -> f32, t: usize, frames: usize) -> f32 {
    if t == 0 || t + 1 >= frames {
        t as f32
    } else {
        t as f32 + vertex(f(t - 1), f(t), f(t + 1))
    }
}

/// Where a parabola through `(−1, a)`, `(0, b)`, `(1, c)` turns, in −0.5..=0.5 (0 where the
/// three are on a line): a turning point found at a frame, placed between frames.
fn vertex(a: f32, b: f32, c: f32) -> f32 {
    let curve = a - 2.0 * b + c;
    if curve.abs() > f32::EPSILON {
        (0.5 * (a - c) / curve).clamp(-0.5, 0.5)
    } else {
        0.0
    }
}

/// Where `f` crosses `level` between frames `a` and `b` (linear), as a fractional frame.
pub(super) fn between(f: impl Fn(usize) -> f32, level: f32, a: usize, b: usize) -> f32 {
    let (fa, fb) = (f(a), f(b));
    let w = if fb != fa {
        ((level - fa) / (fb - fa)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a as f32 + (b as f32 - a as f32) * w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A signal rising by one a frame from -3.25 at frame 0: it passes 0 at frame 3.25.
    fn ramp(t: usize) -> f32 {
        t as f32 - 3.25
    }

    #[test]
    fn a_crossing_is_the_frame_nearer_the_level_in_either_walk() {
        assert_eq!(crossing(0..10, ramp, 0.0, true), Some(3));
        assert_eq!(crossing(0..10, ramp, 0.5, true), Some(4));
        assert_eq!(crossing(0..10, ramp, 0.0, false), None);
        // Walking back finds the same rising crossing.
        assert_eq!(crossing((0..10).rev(), ramp, 0.0, true), Some(3));
        let falling = |t: usize| -ramp(t);
        assert_eq!(crossing(0..10, falling, 0.0, false), Some(3));
        assert_eq!(crossing(5..10, ramp, 0.0, true), None);
    }

    #[test]
    fn a_crossing_is_placed_between_frames() {
        assert_eq!(between(ramp, 0.0, 3, 4), 3.25);
        // From either frame around it.
        assert_eq!(crossed(&ramp, 0.0, 3, 10), 3.25);
        assert_eq!(crossed(&ramp, 0.0, 4, 10), 3.25);
        // A flat stretch places it at its first frame.
        assert_eq!(between(|_| 1.0, 0.0, 3, 4), 3.0);
    }

    #[test]
    fn a_turning_point_is_the_parabola_s_vertex() {
        // (t - 4.3)², lowest at 4.3.
        let bowl = |t: usize| (t as f32 - 4.3) * (t as f32 - 4.3);
        assert!((turning(&bowl, 4, 10) - 4.3).abs() < 1e-5);
        // At the ends, the frame itself; on a line, the frame.
        assert_eq!(turning(&bowl, 0, 10), 0.0);
        assert_eq!(turning(&bowl, 9, 10), 9.0);
        assert_eq!(turning(&ramp, 5, 10), 5.0);
        // Never more than half a frame away.
        let skewed = |t: usize| [0.0, 10.0, 10.0, 0.0][t.min(3)];
        assert_eq!(turning(&skewed, 1, 4), 1.5);
    }
}
