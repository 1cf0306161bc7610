//! The align stage: the two swings put side by side in time and space.
//!
//! - **Warp**: the event-anchored banded DTW of the swings where they lie (each joint from its
//!   frame's root), its path written where the report keeps it.
//! - **Pair**: each swing's stance frame, the coach's frame matching each of the student's
//!   ([`TimeMap`]: linear between the events, so a pose at an event is read at the coach's own
//!   event), zero-phase smoothing over ±[`SPATIAL_SMOOTHING_S`], the coach's root held where
//!   the input holds the student's ([`HELD_ROOT_M`]), and the joints the stream was unsure of.
//!   Every later stage reads the swings through it.

use super::{Detected, ScoreError, Unsure, MAX_PATH};
use crate::band::Band;
use crate::body::Stance;
use crate::dtw::{self, Sequence, Window};
use crate::events::{Event, Side, SwingEvents};
use crate::frames::Frames;
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::Vec3;
use heapless::Vec as HVec;

/// Poses are compared averaged over ± this long, seconds (zero phase).
pub const SPATIAL_SMOOTHING_S: f32 = 0.02;
/// Farthest a joint the stream was unsure of is bridged from where it was sure, each way,
/// seconds (by its offset from the coach, for the body checks): an occlusion run lasts a few
/// tenths of a second.
pub const BRIDGE_S: f32 = 0.5;
/// A student's root (the skeleton's first joint, the pelvis) that stays within this many
/// metres of where it was in the swing's first frame all through it is held by the input, not
/// the golfer: landmarks centred on the hips (MediaPipe's world landmarks) or a root the IMU
/// adapter fixes. No golfer's pelvis stays within 5 mm through a swing (a tour pelvis sways,
/// thrusts and lifts 5 to 15 cm), and a keypoint noise of a millimetre moves it farther.
pub const HELD_ROOT_M: f32 = 0.005;

/// The DTW's result, its path aside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Warp {
    /// Sum of mean joint distances along the path, metres.
    pub distance: f32,
    /// `distance` over the path length.
    pub normalized: f32,
    /// Cells of the band.
    pub cells: u32,
}

/// The cells the band is anchored at: each event both swings have, strictly after the last
/// anchor and inside both swings (the first and last frames are the band's own corners).
pub(super) fn anchors(
    student: &SwingEvents,
    coach: &SwingEvents,
    (n, m): (usize, usize),
) -> HVec<(u16, u16), { Event::COUNT }> {
    let mut anchors: HVec<(u16, u16), { Event::COUNT }> = HVec::new();
    for event in Event::ALL {
        let (Some(i), Some(j)) = (student.frame(event), coach.frame(event)) else {
            continue;
        };
        let after_last = anchors
            .last()
            .is_none_or(|&(pi, pj)| i > pi as usize && j > pj as usize);
        if i > 0 && j > 0 && i + 1 < n && j + 1 < m && after_last {
            // One anchor an event fits the slots.
            let _ = anchors.push((i as u16, j as u16));
        }
    }
    anchors
}

/// Aligns `student` with `coach` (events `events`, student's first) within `band`, on the
/// caller's scratch, writing the path into `path`.
pub(super) fn warp(
    (student, coach): (Frames<'_>, Frames<'_>),
    events: (&SwingEvents, &SwingEvents),
    band: Band,
    (floats, bytes): (&mut [f32], &mut [u8]),
    path: &mut HVec<(u16, u16), MAX_PATH>,
) -> Result<Warp, ScoreError> {
    let (n, m) = (student.len(), coach.len());
    let window = Window::new(band, &anchors(events.0, events.1, (n, m)))?;
    let len = dtw::scratch_len(n, m, &window)?;
    let (Some(cost), Some(steps)) = (floats.get_mut(..len.cost), bytes.get_mut(..len.path_bytes))
    else {
        return Err(ScoreError::Scratch { needed: len.cost });
    };
    path.clear();
    let _ = path.resize((n + m - 1).min(MAX_PATH), (0, 0));
    let alignment = dtw::align(
        &Sequence::rooted(student)?,
        &Sequence::rooted(coach)?,
        &[],
        &window,
        cost,
        steps,
        path,
    )?;
    path.truncate(alignment.path_len);
    Ok(Warp {
        distance: alignment.distance,
        normalized: alignment.normalized,
        cells: len.cells as u32,
    })
}

/// The stance of `swing` at frame `f`.
pub(super) fn stance_at(skeleton: &Skeleton, swing: Frames<'_>, f: usize, lead: Side) -> Stance {
    let mut pose = [Vec3::zeros(); crate::config::MAX_JOINTS];
    Stance::new(skeleton, swing.frame(f, &mut pose), lead)
}

/// Joint `k` of `swing` at fractional frame `x` (linear between frames, clamped to the swing),
/// averaged over `x ± half` frames: zero-phase smoothing of the cut swing, computed where it
/// is needed. Out of line: inlined where it is called it takes 3 KiB more of a device's flash.
#[inline(never)]
pub(super) fn smoothed(swing: Frames<'_>, x: f32, k: usize, half: usize) -> Vec3 {
    let last = swing.len().saturating_sub(1);
    let at = |x: f32| {
        let x = x.clamp(0.0, last as f32);
        // x ≥ 0, so truncation is its floor (exact: frames are far below 2^24).
        let f = x as usize;
        let w = x - f as f32;
        let g = (f + 1).min(last);
        swing.at(f, k) * (1.0 - w) + swing.at(g, k) * w
    };
    let sum = (0..=2 * half).fold(Vec3::zeros(), |s, i| s + at(x + i as f32 - half as f32));
    sum / (2 * half + 1) as f32
}

/// The coach's frame matching each of the student's: linear between the events both swings
/// have (their times, and the hands' arrivals at the top where either pauses there), the
/// coach's rate beyond them.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct TimeMap {
    /// (student, coach) times, in order.
    knots: HVec<(f32, f32), { Event::COUNT + 1 }>,
    /// Coach frames per student frame beyond the knots.
    ratio: f32,
}

impl TimeMap {
    pub(super) fn new(student: &SwingEvents, coach: &SwingEvents, ratio: f32) -> TimeMap {
        let mut knots = HVec::new();
        for e in Event::ALL {
            if e == Event::Top && (student.pause() > 0.0 || coach.pause() > 0.0) {
                // The events and one arrival fit the slots.
                let _ = knots.push((student.arrival(), coach.arrival()));
            }
            if let Some(pair) = student.time(e).zip(coach.time(e)) {
                let _ = knots.push(pair);
            }
        }
        TimeMap { knots, ratio }
    }

    /// The coach's frame matching the student's frame `x`.
    pub(super) fn at(&self, x: f32) -> f32 {
        let Some((&first, rest)) = self.knots.split_first() else {
            return x * self.ratio;
        };
        if x <= first.0 {
            return first.1 + (x - first.0) * self.ratio;
        }
        let mut before = first;
        for &after in rest {
            if x <= after.0 {
                let span = after.0 - before.0;
                let w = if span > 0.0 {
                    (x - before.0) / span
                } else {
                    0.0
                };
                return before.1 + (after.1 - before.1) * w;
            }
            before = after;
        }
        before.1 + (x - before.0) * self.ratio
    }
}

/// The two swings as the later stages read them: poses in each swing's stance frame, the
/// coach's at the student's time, both smoothed.
pub(super) struct Pair<'a> {
    /// The student's frames.
    pub student: Frames<'a>,
    /// The coach's frames.
    pub coach: Frames<'a>,
    /// The student's stance at address.
    pub stance_s: Stance,
    /// The coach's stance at address.
    pub stance_c: Stance,
    /// The coach's frame matching each of the student's.
    pub time_map: TimeMap,
    /// Smoothing half-widths in frames, student's and coach's.
    pub half: (usize, usize),
    /// The input held the student's root still: the coach is read with its root held too.
    pub root_held: bool,
    /// The coach's root stays where it is at address in every frame (the IMUs' view of it),
    /// so that holding it changes nothing and is skipped.
    coach_still: bool,
    /// The coach's root at address, single frames and smoothed.
    anchors: [Vec3; 2],
    /// The joints the stream was unsure of.
    unsure: Unsure<'a>,
}

impl<'a> Pair<'a> {
    /// The pair of `student` (with the events it is judged by) and `coach`.
    pub(super) fn new(
        skeleton: &Skeleton,
        (student, events_s): (&Detected<'a>, &SwingEvents),
        coach: &Detected<'a>,
    ) -> Pair<'a> {
        let (swing_s, swing_c, events_c) = (student.positions, coach.positions, &coach.events);
        let stance_s = stance_at(skeleton, swing_s, events_s.address(), events_s.lead);
        let stance_c = stance_at(skeleton, swing_c, events_c.address(), events_c.lead);
        let half = (
            libm::roundf(SPATIAL_SMOOTHING_S * student.hz) as usize,
            libm::roundf(SPATIAL_SMOOTHING_S * coach.hz) as usize,
        );
        // An input that holds the root still shows the body about its pelvis: the coach is
        // then compared the same way, its root held at address.
        let root_held =
            (0..swing_s.len()).all(|f| norm(&(swing_s.at(f, 0) - swing_s.at(0, 0))) < HELD_ROOT_M);
        let coach_still = (0..swing_c.len()).all(|f| swing_c.at(f, 0) == swing_c.at(0, 0));
        let address = events_c.time(Event::Address).unwrap_or(0.0);
        Pair {
            student: swing_s,
            coach: swing_c,
            stance_s,
            stance_c,
            time_map: TimeMap::new(events_s, events_c, coach.hz / student.hz),
            half,
            root_held,
            coach_still,
            anchors: [0, half.1].map(|h| smoothed(swing_c, address, 0, h)),
            unsure: student.unsure,
        }
    }

    /// The coach's joint `k` at its frame `x`, smoothed over `± half` frames (its root held at
    /// address where the student's is).
    pub(super) fn coach_at(&self, k: usize, x: f32, half: usize) -> Vec3 {
        let p = smoothed(self.coach, x, k, half);
        if self.root_held && !self.coach_still {
            let anchor = self.anchors[usize::from(half == self.half.1)];
            p - (smoothed(self.coach, x, 0, half) - anchor)
        } else {
            p
        }
    }

    /// The student's joint `k` at its frame `x`, smoothed over `± half` frames.
    pub(super) fn student_at(&self, k: usize, x: f32, half: usize) -> Vec3 {
        smoothed(self.student, x, k, half)
    }

    /// Joint `k`'s offset from the coach at the student's frame `x` (the coach's at its
    /// matching frame), in the stance frames, smoothed over `(student, coach)` half-widths.
    pub(super) fn offset(&self, k: usize, x: f32, (hs, hc): (usize, usize)) -> Vec3 {
        let c = self.time_map.at(x);
        self.stance_s.local(self.student_at(k, x, hs))
            - self.stance_c.local(self.coach_at(k, c, hc))
    }

    /// The student's joint `k` at its frame `x` where the stream was unsure of it there, bridged
    /// from where it was sure: the coach's joint at the matching frame, moved by the joint's
    /// offset from the coach interpolated between the nearest frames either side, within
    /// [`BRIDGE_S`], whose neighbourhood the stream was sure of (smoothed as [`Pair::offset`]
    /// reads it), or held from the one side that has such a frame. With it, how far the
    /// interpolation may be off per stance axis: half the offset's change across (`None` where
    /// it was held: one side cannot tell). `None` where it was sure near `x` (read it as it
    /// is), or where no such frame lies that near.
    pub(super) fn bridged(&self, k: usize, x: f32, hz: f32) -> Option<(Vec3, Option<Vec3>)> {
        let half = self.half.0;
        if !self.unsure_near(k, x, half) {
            return None;
        }
        let reach = libm::roundf(BRIDGE_S * hz) as usize;
        let sure = |f: usize| !self.unsure_near(k, f as f32, half);
        let at = x as usize;
        let last = self.student.len().checked_sub(1)?;
        let before = (at.saturating_sub(reach)..=at).rev().find(|&f| sure(f));
        let after = (at + 1..=(at + reach).min(last)).find(|&f| sure(f));
        let offset = |f: usize| self.offset(k, f as f32, self.half);
        let (offset, spread) = match (before, after) {
            (Some(a), Some(b)) => {
                let w = ((x - a as f32) / (b - a) as f32).clamp(0.0, 1.0);
                let (a, b) = (offset(a), offset(b));
                (a * (1.0 - w) + b * w, Some((b - a).abs() * 0.5))
            }
            // Near either end of the swing (the address starts it), the one side's.
            (Some(f), None) | (None, Some(f)) => (offset(f), None),
            (None, None) => return None,
        };
        let coach = self.coach_at(k, self.time_map.at(x), self.half.1);
        Some((
            self.stance_s.world(self.stance_c.local(coach) + offset),
            spread,
        ))
    }

    /// Whether joint `k` was unsure anywhere within `half` frames (and one more) of the
    /// student's frame `x`.
    pub(super) fn unsure_near(&self, k: usize, x: f32, half: usize) -> bool {
        // The frames either side of x, 0 for a negative x: a cast truncates toward zero and
        // takes a negative to 0.
        let lo = x as usize;
        let hi = lo.saturating_add(usize::from((lo as f32) < x));
        self.unsure_between(k, lo.saturating_sub(half + 1), hi + half + 1)
    }

    /// Whether joint `k` was unsure at any of the student's frames `from..=to` (clamped to
    /// the swing).
    pub(super) fn unsure_between(&self, k: usize, from: usize, to: usize) -> bool {
        (from..=to.min(self.student.len().saturating_sub(1)))
            .any(|f| self.unsure.at(f) & (1 << k) != 0)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::{anchors, smoothed, TimeMap};
    use crate::events::{Event, Position, Side, SwingEvents};
    use crate::frames::Frames;
    use crate::Vec3;

    /// A full swing's events at these frames, in [`Event::ALL`] order.
    pub(crate) fn events(frames: [u16; 8]) -> SwingEvents {
        let mut times = [None; 10];
        for (e, f) in Event::ALL.into_iter().zip(frames) {
            times[Position::from(e) as usize] = Some(f32::from(f));
        }
        SwingEvents::at_times(Side::Left, times)
    }

    #[test]
    fn the_time_map_is_linear_between_events_and_at_the_coachs_rate_beyond() {
        let student = events([10, 20, 30, 40, 50, 60, 70, 80]);
        let coach = events([20, 30, 50, 60, 64, 68, 90, 100]);
        let map = TimeMap::new(&student, &coach, 2.0);
        assert_eq!(map.at(10.0), 20.0);
        assert_eq!(map.at(25.0), 40.0); // halfway from toe-up to mid-backswing
        assert_eq!(map.at(55.0), 66.0);
        assert_eq!(map.at(5.0), 10.0); // before address, twice the student's rate
        assert_eq!(map.at(90.0), 120.0);
    }

    #[test]
    fn anchors_keep_events_inside_both_swings_in_strict_order() {
        // The coach's impact not after its mid-downswing, its finish at its last frame.
        let student = events([10, 20, 30, 40, 50, 60, 70, 80]);
        let coach = events([0, 30, 50, 60, 64, 64, 90, 99]);
        let got = anchors(&student, &coach, (100, 100));
        assert_eq!(
            &got[..],
            &[(20, 30), (30, 50), (40, 60), (50, 64), (70, 90)]
        );
    }

    #[test]
    fn smoothing_averages_either_side_and_holds_the_ends() {
        let positions: std::vec::Vec<Vec3> =
            (0..5).map(|f| Vec3::new(f as f32, 0.0, 0.0)).collect();
        let swing = Frames::metres(&positions, 1);
        assert_eq!(smoothed(swing, 2.0, 0, 1).x, 2.0);
        assert_eq!(smoothed(swing, 2.5, 0, 0).x, 2.5);
        // At the first frame the frame before reads as the first.
        assert!((smoothed(swing, 0.0, 0, 1).x - 1.0 / 3.0).abs() < 1e-6);
    }

    #[test]
    fn a_joint_the_stream_was_unsure_of_is_bridged_by_its_offset_from_the_coach() {
        use super::Pair;
        use crate::format::Format;
        use crate::score::{Detected, Unsure};
        use crate::skeleton::Skeleton;
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let mut rest = [Vec3::zeros(); 17];
        skeleton.rest_positions(&mut rest);
        // The coach's wrist (joint 16) rises 1 cm a frame; the student's runs 5 cm ahead of
        // it toward the target, but the stream was unsure of it at frames 45 to 55, where it
        // sent nonsense.
        let wrist = 16;
        let swing = |student: bool| -> std::vec::Vec<Vec3> {
            let mut out = std::vec::Vec::new();
            for f in 0..100 {
                for (k, &p) in rest.iter().enumerate() {
                    let mut p = p;
                    if k == wrist {
                        p.y += 0.01 * f as f32;
                        if student {
                            p.x += 0.05;
                            if (45..=55).contains(&f) {
                                p.z += 0.7;
                            }
                        }
                    }
                    out.push(p);
                }
            }
            out
        };
        let (student, coach) = (swing(true), swing(false));
        let mut ring = [0u64; 128];
        for mask in &mut ring[45..=55] {
            *mask = 1 << wrist;
        }
        let frames = events([10, 20, 30, 40, 50, 60, 70, 90]);
        let detected = |positions, unsure| Detected {
            positions: Frames::metres(positions, 17),
            hz: 60.0,
            events: frames,
            unsure,
        };
        let student = detected(&student, Unsure::new(&ring, 0, 100));
        let coach = detected(&coach, Unsure::default());
        let pair = Pair::new(&skeleton, (&student, &frames), &coach);
        // Sure there: read as it is.
        assert_eq!(pair.bridged(wrist, 20.0, 60.0), None);
        let (at, across) = pair.bridged(wrist, 50.0, 60.0).unwrap();
        let truth = rest[wrist] + Vec3::new(0.05, 0.5, 0.0);
        let local = |p: Vec3| pair.stance_s.local(p);
        assert!(
            (local(at) - local(truth)).norm() < 1e-3,
            "{at:?} against {truth:?}"
        );
        // The offset did not change across: the interpolation is exact.
        assert!(across.unwrap().norm() < 1e-4, "{across:?}");
        // Farther than half a second from any frame it was sure of: not bridged.
        let mut lost = [1u64 << wrist; 128];
        lost[99] = 0;
        let again = swing(true);
        let student = detected(&again, Unsure::new(&lost, 0, 100));
        let pair = Pair::new(&skeleton, (&student, &frames), &coach);
        assert!(pair.bridged(wrist, 20.0, 60.0).is_none());
    }
}
