//! The noise stage: what the student's input lets the joint comparison see.
//!
//! Each joint's **usual offset** from the coach over the swing, takeaway to finish (per axis
//! the median: a keypoint's constant bias, or a joint another format places elsewhere), and
//! how much the offset **wanders** around it (per axis [`MAD_SIGMA`] times the median absolute
//! deviation, the standard deviation of a normal spread). Neither moves for a flaw confined to
//! part of the swing.
//!
//! Over one swing a keypoint error that drifts for most of a second is seen at a few
//! independent moments, so one joint's wander can come out far below its noise: no joint's is
//! taken below the median of all judged joints' (per axis; the pose noise is much the same for
//! all keypoints, the retargeting's mismatch is not). The lower quartile of the joints' wander
//! is the **input's noise** the body checks are judged against (noise moves every joint, a
//! fault a few, and one that lasts most of the swing widens their wander).

use super::align::Pair;
use crate::config::MAX_JOINTS;
use crate::events::{Event, SwingEvents};
use crate::math::{median, select, MAD_SIGMA};
use crate::skeleton::Skeleton;
use crate::Vec3;

/// A joint's wander is measured at this many moments spread evenly over the cut swing.
pub const WANDER_SAMPLES: usize = 32;

/// What the noise stage finds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Noise {
    /// Each joint's usual offset from the coach, stance axes, metres.
    pub usual: [Vec3; MAX_JOINTS],
    /// How much each joint's offset wanders around it (one standard deviation per axis, at
    /// least the joints' median), metres.
    pub wander: [Vec3; MAX_JOINTS],
    /// The input's noise per stance axis, metres.
    pub input: Vec3,
}

/// Whether joint `k` is judged (the club's joints are not: the coach's club is the coach's).
pub(super) fn judged(skeleton: &Skeleton, k: usize) -> bool {
    skeleton.joint(k).is_some_and(|j| !j.is_club())
}

/// The noise of `pair`, whose student's events are `events`.
pub(super) fn measure(skeleton: &Skeleton, pair: &Pair<'_>, events: &SwingEvents) -> Noise {
    let joints = skeleton.len();
    let (from, to) = (
        events.time(Event::Address).unwrap_or(0.0),
        events
            .time(Event::Finish)
            .unwrap_or((pair.student.len() - 1) as f32),
    );
    let samples = (libm::ceilf(to - from) as usize + 1).clamp(1, WANDER_SAMPLES);
    let step = (to - from) / samples.saturating_sub(1).max(1) as f32;
    let mut usual = [Vec3::zeros(); MAX_JOINTS];
    let mut wander = [Vec3::zeros(); MAX_JOINTS];
    let mut series = [[0.0f32; WANDER_SAMPLES]; 3];
    // The joints seen sure at least once: a joint the input never measures has no wander.
    let mut seen = 0u64;
    for (k, (u, w)) in usual
        .iter_mut()
        .zip(wander.iter_mut())
        .enumerate()
        .take(joints)
    {
        // Unsmoothed (the wander of single frames bounds the smoothed one's from above), and
        // only where the stream was sure of the joint.
        let mut count = 0;
        for i in 0..samples {
            let x = from + step * i as f32;
            if pair.unsure_near(k, x, 0) {
                continue;
            }
            let o = pair.offset(k, x, (0, 0));
            for (axis, values) in series.iter_mut().enumerate() {
                values[count] = o[axis];
            }
            count += 1;
        }
        if count > 0 {
            seen |= 1 << k;
        }
        for (axis, values) in series.iter_mut().enumerate() {
            let values = &mut values[..count];
            u[axis] = median(values);
            for v in values.iter_mut() {
                *v = libm::fabsf(*v - u[axis]);
            }
            w[axis] = MAD_SIGMA * median(values);
        }
    }
    let (floor, input) = spread(skeleton, &wander, seen);
    for w in wander.iter_mut().take(joints) {
        *w = w.sup(&floor);
    }
    Noise {
        usual,
        wander,
        input,
    }
}

/// Per axis, the median and the lower quartile of the `wander` of the judged joints among
/// those `seen` (bit `k` for joint `k`).
fn spread(skeleton: &Skeleton, wander: &[Vec3; MAX_JOINTS], seen: u64) -> (Vec3, Vec3) {
    let (mut floor, mut noise) = (Vec3::zeros(), Vec3::zeros());
    let mut values = [0.0f32; MAX_JOINTS];
    for axis in 0..3 {
        let mut count = 0;
        for (k, w) in wander.iter().enumerate().take(skeleton.len()) {
            if judged(skeleton, k) && seen & (1 << k) != 0 {
                values[count] = w[axis];
                count += 1;
            }
        }
        floor[axis] = median(&mut values[..count]);
        noise[axis] = select(&mut values[..count], count / 4);
    }
    (floor, noise)
}

#[cfg(test)]
mod tests {
    use super::{judged, spread};
    use crate::config::MAX_JOINTS;
    use crate::format::Format;
    use crate::joint::Joint;
    use crate::skeleton::Skeleton;
    use crate::Vec3;

    #[test]
    fn the_floor_is_the_judged_joints_median_and_the_noise_their_lower_quartile() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let mut wander = [Vec3::zeros(); MAX_JOINTS];
        for (k, w) in wander.iter_mut().enumerate().take(skeleton.len()) {
            *w = Vec3::new(k as f32, 2.0 * k as f32, 1.0);
        }
        let (floor, noise) = spread(&skeleton, &wander, u64::MAX);
        // 17 joints, none a club's: the median is the 9th smallest, the quartile the 5th.
        assert_eq!(floor, Vec3::new(8.0, 16.0, 1.0));
        assert_eq!(noise, Vec3::new(4.0, 8.0, 1.0));
        // Joints never seen (0 to 8) are left out: of 9 to 16, the 5th and the 3rd smallest.
        let (floor, noise) = spread(&skeleton, &wander, !0x1ff);
        assert_eq!(floor, Vec3::new(13.0, 26.0, 1.0));
        assert_eq!(noise, Vec3::new(11.0, 22.0, 1.0));
    }

    #[test]
    fn the_clubs_joints_are_not_judged() {
        let skeleton = Skeleton::standard(Format::GolfMarkers).unwrap();
        let club = skeleton.index_of(Joint::ClubHead).unwrap();
        let wrist = skeleton.index_of(Joint::LeftWrist).unwrap();
        assert!(!judged(&skeleton, club) && judged(&skeleton, wrist));
    }
}
