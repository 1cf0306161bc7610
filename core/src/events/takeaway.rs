//! The takeaway: the start of the hands' way back from the set-up, fitted on one swing
//! ([`onset`]) or timed against a coach's backswing ([`takeaway_against`]).

use super::track::Track;
use super::{Event, SwingEvents, STILL_S};
use crate::frames::Frames;
use crate::joint::Joint;
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::Vec3;

/// The hands' progress toward the top is fitted between these shares of it (well above pose
/// noise, early enough to be a start from rest).
pub const ONSET_SHARES: (f32, f32) = (0.08, 0.3);

/// The takeaway, in frames: when the `hands` start back from `home` (their set-up position)
/// toward where they are at `top`, searching from frame `from`. Starting from rest with a
/// smooth push, the hands' progress along their first direction grows as the cube of the time
/// since the takeaway (the start of a minimum-jerk reach; 3.1 to 3.2 on the tour swings), so
/// its cube root is fitted with a line between [`ONSET_SHARES`] of the way to the top and
/// extrapolated back to zero. `None` without enough frames in that stretch.
pub(super) fn onset(
    hands: impl Fn(usize) -> Vec3,
    home: Vec3,
    from: usize,
    top: usize,
) -> Option<f32> {
    let reach = norm(&(hands(top) - home));
    if reach <= 0.0 {
        return None;
    }
    let (lo, hi) = (ONSET_SHARES.0 * reach, ONSET_SHARES.1 * reach);
    let last = (from..=top).find(|&t| norm(&(hands(t) - home)) >= hi)?;
    let way = (hands(last) - home) / norm(&(hands(last) - home));
    let progress = |t: usize| (hands(t) - home).dot(&way);
    let mut first = last;
    while first > from && progress(first - 1) >= lo {
        first -= 1;
    }
    if last - first < 1 {
        return None;
    }
    // Pose noise of σ in the progress p is σ / (3 p^(2/3)) in its cube root: each frame is
    // weighted by p^(4/3), the inverse of that variance.
    let (mut sw, mut st, mut sy, mut stt, mut sty) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for t in first..=last {
        let (x, y) = ((t - first) as f32, crate::math::cbrt(progress(t).max(0.0)));
        let w = y * y * y * y;
        sw += w;
        st += w * x;
        sy += w * y;
        stt += w * x * x;
        sty += w * x * y;
    }
    let slope = (sw * sty - st * sy) / (sw * stt - st * st);
    if !(slope.is_finite() && slope > 0.0) {
        return None;
    }
    let intercept = (sy - slope * st) / sw;
    Some(first as f32 - intercept / slope)
}

/// The shares of the way from the set-up to the top at which [`takeaway_against`] compares
/// the hands' progress: the 13 from 0.1 to 0.7 in steps of 0.05.
const PROGRESS_SHARES: (f32, f32, usize) = (0.1, 0.05, 13);

/// How many shares [`PROGRESS_SHARES`] names.
const SHARES: usize = PROGRESS_SHARES.2;

/// A student's takeaway timed against a coach's backswing ([`takeaway_against`]), with what
/// moves it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Takeaway {
    /// The takeaway, frames (between frames).
    pub time: f32,
    /// How much earlier it comes for each frame later the hands' arrival at the top is found
    /// (the top, where they do not pause there): without a pause the backswing's length moves
    /// by `1 + top_gain` times the top's error.
    pub top_gain: f32,
    /// Its standard deviation from the crossings' scatter about the fit alone, frames.
    pub spread: f32,
}

/// The arms' pose: both wrists (or hands) and both elbows, whose pose errors are independent.
type Pose = [Vec3; 4];

/// A backswing's line in the arms' poses: from the set-up pose to the top pose.
type Line = (Pose, Pose);

/// The arms of one swing on its smoothed track.
struct ArmsTrack<'a> {
    track: Track<'a>,
    /// The joints of a [`Pose`].
    arms: [usize; 4],
}

impl ArmsTrack<'_> {
    /// The arms at `x` frames (between frames, linear; clamped to the motion).
    fn pose(&self, x: f32) -> Pose {
        let t = &self.track;
        let f = (x.max(0.0) as usize).min(t.frames - 1);
        let g = (f + 1).min(t.frames - 1);
        let w = (x - f as f32).clamp(0.0, 1.0);
        if w == 0.0 {
            // At a frame: the next one's smoothed read would be weighed by zero.
            return self.arms.map(|k| t.at(k, f));
        }
        self.arms.map(|k| t.at(k, f) * (1.0 - w) + t.at(k, g) * w)
    }

    /// Progress along `line` of the arms' pose at frame `f`: 0 at the set-up and 1 at the top.
    fn progress(&self, line: &Line, f: usize) -> f32 {
        let (home, top) = line;
        let now = self.pose(f as f32);
        let (mut along, mut length) = (0.0f32, 0.0f32);
        for i in 0..4 {
            let line = top[i] - home[i];
            along += (now[i] - home[i]).dot(&line);
            length += line.norm_squared();
        }
        along / length
    }

    /// The set-up: the arms' mean over the still stretch ([`STILL_S`]) before the takeaway at
    /// `taken` (frames), with the stretch's first frame.
    fn home(&self, taken: f32) -> (usize, Pose) {
        let still = (libm::roundf(STILL_S * self.track.rate) as usize).max(1);
        let end = (taken as usize).saturating_sub(1);
        let start = end.saturating_sub(still);
        let mut mean = [Vec3::zeros(); 4];
        for f in start..=end {
            for (m, p) in mean.iter_mut().zip(self.pose(f as f32)) {
                *m += p / (end - start + 1) as f32;
            }
        }
        (start, mean)
    }

    /// The moments (frames, between frames) the progress along `line` first passes each
    /// share, in one walk from `from` to `to`; `None` for a share it never reaches.
    fn passes(&self, line: &Line, from: usize, to: usize) -> [Option<f32>; SHARES] {
        let mut at = [None; SHARES];
        let mut next = 0;
        let mut before = self.progress(line, from);
        for f in from..to {
            let after = self.progress(line, f + 1);
            while next < SHARES {
                let share = PROGRESS_SHARES.0 + PROGRESS_SHARES.1 * next as f32;
                if after < share {
                    break;
                }
                let w = if before >= share || after <= before {
                    0.0
                } else {
                    (share - before) / (after - before)
                };
                at[next] = Some(f as f32 + w);
                next += 1;
            }
            before = after;
        }
        at
    }
}

/// A swing's backswing, frames (between frames): from the takeaway to the hands' arrival at
/// the top (a pause there is no part of its pace).
fn backswing(events: &SwingEvents) -> Option<(f32, f32)> {
    Some((
        events.time(Event::Address)?,
        events.time(Event::Top).map(|_| events.arrival())?,
    ))
}

/// The student's takeaway (frames, between frames) timed against the coach's: the arms'
/// (wrists and elbows) progress along the line from their set-up to their top pose passes 10 %
/// to 70 % of the way at moments that, were the student's backswing the coach's run at its own
/// pace, would lie at the same shares of the time from the takeaway to the hands' arrival at
/// the top ([`SwingEvents::arrival`]: a pause there is no part of the pace); the takeaway that fits
/// them best (least squares, each crossing weighted by how sharply the progress passes it) is
/// the student's. It uses half a second of the backswing where
/// [`detect`](super::detect) uses a fifth, so pose noise moves it less. `None` when a swing
/// lacks the joints (or is not read in the skeleton's), the events or a crossing.
pub fn takeaway_against(
    skeleton: &Skeleton,
    student: Frames<'_>,
    student_events: &SwingEvents,
    student_hz: f32,
    coach: Frames<'_>,
    coach_events: &SwingEvents,
    coach_hz: f32,
) -> Option<Takeaway> {
    let arms = [
        skeleton.find(&[Joint::LeftWrist, Joint::LeftHand])?,
        skeleton.find(&[Joint::RightWrist, Joint::RightHand])?,
        skeleton.index_of(Joint::LeftElbow)?,
        skeleton.index_of(Joint::RightElbow)?,
    ];
    if student.joints() != skeleton.len() || coach.joints() != skeleton.len() {
        return None;
    }
    let s = ArmsTrack {
        track: Track::new(student, student_hz),
        arms,
    };
    let c = ArmsTrack {
        track: Track::new(coach, coach_hz),
        arms,
    };
    if s.track.frames == 0 || c.track.frames == 0 {
        return None;
    }
    let ((c0, c_top), (s0, s_top)) = (backswing(coach_events)?, backswing(student_events)?);
    if c_top <= c0 || s_top <= s0 {
        return None;
    }
    let ((c_start, c_home), (start, s_home)) = (c.home(c0), s.home(s0));
    let c_line = (c_home, c.pose(c_top));
    let s_line = (s_home, s.pose(s_top));
    let (c_at, s_at) = (
        c.passes(&c_line, c_start, c_top as usize),
        s.passes(&s_line, start, s_top as usize),
    );
    let c_span = c_top - c0;
    // Per crossing: the coach's share f of its backswing's time there, the weight, and the
    // student's moment.
    let mut points = [(0.0f32, 0.0f32, 0.0f32); SHARES];
    let mut count = 0;
    for (c_at, s_at) in c_at.into_iter().zip(s_at) {
        let (c_at, s_at) = (c_at?, s_at?);
        // s_at = t0 + f (s_top − t0), f the coach's share of its backswing's time there. Pose
        // noise moves a crossing in time inversely to how fast the progress goes through it
        // (the coach's pace there, per share of the backswing): each is weighted so.
        let f = ((c_at - c0) / c_span).clamp(0.0, 0.95);
        let k = c_at as usize;
        let pace = (c.progress(&c_line, (k + 1).min(c.track.frames - 1))
            - c.progress(&c_line, k.saturating_sub(1)))
            * 0.5
            * c_span;
        points[count] = (f, pace * pace, s_at);
        count += 1;
    }
    fit(&points[..count], s_top)
}

/// The takeaway that best fits the crossings `points` (the coach's share of its backswing's
/// time, the weight, the student's moment) of a student whose hands arrive at the top at
/// `s_top`: weighted least squares. `None` without a weight (or with a NaN).
// In its one caller: out of line it costs the firmware 0.1 KiB of flash and 16 bytes of the
// stack's high-water mark.
#[inline(always)]
fn fit(points: &[(f32, f32, f32)], s_top: f32) -> Option<Takeaway> {
    let (num, den, gain) =
        points
            .iter()
            .fold((0.0f32, 0.0f32, 0.0f32), |(n, d, g), &(f, w, s_at)| {
                (
                    n + w * (1.0 - f) * (s_at - f * s_top),
                    d + w * (1.0 - f) * (1.0 - f),
                    g + w * (1.0 - f) * f,
                )
            });
    // (A NaN sum gives no takeaway.)
    let time = Some(num / den).filter(|_| den > 0.0)?;
    // The crossings' own scatter about the fit, carried into the takeaway (a sandwich
    // estimate, with n / (n − 1) for the fitted parameter).
    let count = points.len();
    let scatter = points
        .iter()
        .map(|&(f, w, s_at)| {
            let r = s_at - (time * (1.0 - f) + f * s_top);
            let lever = w * (1.0 - f);
            lever * lever * r * r
        })
        .sum::<f32>()
        / (den * den)
        * count as f32
        / count.saturating_sub(1).max(1) as f32;
    Some(Takeaway {
        time,
        top_gain: gain / den,
        spread: crate::math::sqrt(scatter),
    })
}

#[cfg(test)]
mod tests {
    use super::super::synthetic::{eased, FRAMES, HOME, RATE_HZ, SWING};
    use super::super::{Position, Side};
    use super::*;
    use crate::format::Format;
    use std::vec::Vec;

    #[test]
    fn a_start_from_rest_as_the_cube_of_time_is_extrapolated_to_its_start() {
        // Hands 0.5 (t − 31.4)³ mm from home along a slant after frame 31.4, still before.
        let way = Vec3::new(0.6, 0.8, 0.0);
        let home = Vec3::from(HOME);
        let hands = |t: usize| {
            let since = (t as f32 - 31.4).max(0.0);
            home + way * (0.0005 * since * since * since)
        };
        let found = onset(hands, home, 10, 60).unwrap();
        assert!((found - 31.4).abs() < 0.05, "{found}");
        // Without a way to go, or without the frames to fit, none.
        assert_eq!(onset(|_| home, home, 10, 60), None);
        assert_eq!(onset(hands, home, 40, 41), None);
    }

    #[test]
    fn a_fit_weighs_its_crossings() {
        // Crossings on a takeaway at frame 10 with the top at 50: s = 10 (1 − f) + 50 f.
        let on = |f: f32, w: f32| (f, w, 10.0 * (1.0 - f) + 50.0 * f);
        let exact = fit(&[on(0.1, 1.0), on(0.4, 2.0), on(0.7, 1.0)], 50.0).unwrap();
        assert!(
            (exact.time - 10.0).abs() < 1e-4 && exact.spread < 1e-3,
            "{exact:?}"
        );
        assert!(exact.top_gain > 0.0);
        // A crossing off the line moves the takeaway by its weight's share, and spreads it.
        let off = |f: f32, w: f32, by: f32| (f, w, on(f, w).2 + by);
        let light = fit(&[on(0.1, 1.0), off(0.4, 0.1, 3.0), on(0.7, 1.0)], 50.0).unwrap();
        let heavy = fit(&[on(0.1, 1.0), off(0.4, 10.0, 3.0), on(0.7, 1.0)], 50.0).unwrap();
        assert!(
            light.time > 10.0 && heavy.time > light.time,
            "{light:?} {heavy:?}"
        );
        assert!(light.spread > 0.0 && heavy.spread > 0.0);
        assert_eq!(fit(&[], 50.0), None);
        assert_eq!(fit(&[(0.5, 0.0, 30.0)], 50.0), None);
    }

    #[test]
    fn a_swing_timed_against_itself_keeps_its_takeaway() {
        // The arms of an H36M skeleton eased through the swing's hands (both wrists and both
        // elbows alike), every other joint at rest.
        let h36m = Skeleton::standard(Format::H36m17).unwrap();
        let mut rest = std::vec![Vec3::zeros(); h36m.len()];
        h36m.rest_positions(&mut rest);
        let path = eased(&SWING, FRAMES);
        let arms = [
            Joint::LeftWrist,
            Joint::RightWrist,
            Joint::LeftElbow,
            Joint::RightElbow,
        ]
        .map(|j| h36m.index_of(j).unwrap());
        let positions: Vec<Vec3> = path
            .iter()
            .flat_map(|&hands| {
                let mut pose = rest.clone();
                for (k, &a) in arms.iter().enumerate() {
                    pose[a] = hands * (1.0 - 0.1 * k as f32);
                }
                pose
            })
            .collect();
        let frames = Frames::metres(&positions, h36m.len());
        let mut times = [None; 10];
        times[Position::P1 as usize] = Some(15.2);
        let no_top = SwingEvents::at_times(Side::Left, times);
        times[Position::P4 as usize] = Some(35.0);
        let events = SwingEvents::at_times(Side::Left, times);
        let against =
            |events| takeaway_against(&h36m, frames, events, RATE_HZ, frames, events, RATE_HZ);
        let found = against(&events).unwrap();
        assert!((found.time - 15.2).abs() < 1e-3, "{found:?}");
        assert!(found.spread < 1e-3, "{found:?}");
        // A swing without a top has no backswing to time.
        assert_eq!(against(&no_top), None);
    }
}
