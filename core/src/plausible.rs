//! Human limits a body and its motion must keep. A skeleton or a swing outside them is a
//! corrupt file, a wrong unit, a broken sensor or a hostile phone, not a golfer: it is refused,
//! not scored.
//!
//! The limits are wide on purpose: they catch what no person can be (a 44 km stature, an arm as
//! long as the body, a shank half the other's, a joint crossing a room between two frames),
//! never an unusual golfer. They apply to the body's joints: a tracked club is longer than half
//! a child's stature, and its head, at up to 70 m/s and often occluded at impact, jumps between
//! captured samples.
//!
//! The limb bones (upper arms, forearms, thighs, shanks) are judged against their typical share
//! of the stature, from Winter's segment lengths (Biomechanics and Motor Control of Human
//! Movement, 4th ed., 2009, after Drillis and Contini 1966), which every keypoint format names
//! the same way; other bones (spines, clavicles, faces) differ between formats and are only
//! held under [`MAX_BONE_SHARE`].

use crate::joint::Joint;
use crate::math::norm;
use crate::skeleton::Skeleton;
use crate::Vec3;

/// Shortest stature accepted, metres: below the shortest adults recorded (about 0.55 m).
pub const MIN_STATURE_M: f32 = 0.5;
/// Tallest stature accepted, metres: above the tallest person recorded (2.72 m).
pub const MAX_STATURE_M: f32 = 2.75;
/// Longest bone accepted, as a share of the stature: the longest human bone, the femur, is
/// about 27 % of it, and no segment of a body is half of it.
pub const MAX_BONE_SHARE: f32 = 0.5;
/// The limb bones, each as its joint and the parent it hangs from, with its typical length as
/// a share of the stature (Winter 2009: shoulder to elbow 0.186, elbow to wrist 0.146, hip to
/// knee 0.245, knee to ankle 0.246); left and right side by side.
pub const LIMBS: [(Joint, Joint, f32); 8] = [
    (Joint::LeftElbow, Joint::LeftShoulder, 0.186),
    (Joint::RightElbow, Joint::RightShoulder, 0.186),
    (Joint::LeftWrist, Joint::LeftElbow, 0.146),
    (Joint::RightWrist, Joint::RightElbow, 0.146),
    (Joint::LeftKnee, Joint::LeftHip, 0.245),
    (Joint::RightKnee, Joint::RightHip, 0.245),
    (Joint::LeftAnkle, Joint::LeftKnee, 0.246),
    (Joint::RightAnkle, Joint::RightKnee, 0.246),
];
/// A limb bone may be from this many times its typical share of the stature to this many: a
/// segment's share varies between adults by about 5 % (one standard deviation), a keypoint
/// detector places joints a few centimetres apart from the anatomical centres, and a T-pose
/// from a phone carries its noise; half and 1.6 times are far outside all three.
pub const LIMB_RANGE: (f32, f32) = (0.5, 1.6);
/// Most a limb bone may differ from the other side's, as a share of the longer: the limbs'
/// lengths differ by under 2 cm in most adults (under 5 % of a shank), the rest is room for
/// the keypoints' noise in the T-pose. A phone's T-pose at 50 mm of noise puts two 25 cm
/// bones about 20 % apart at one standard deviation: a quarter cost the coaching benchmark 6 %
/// of its swings at 30 mm and 21 % at 50 mm; 40 % is twice that spread and still eight times
/// any adult's difference.
pub const SYMMETRY: f32 = 0.4;
/// The path from one wrist to the other along the bones (both arms and the shoulders between
/// them: arm span less the hands, 0.77 to 0.91 of the stature on the formats' standard
/// skeletons) must be from this share of the
/// stature to this one: the arms count toward the body's size as the legs and trunk do.
pub const SPAN_SHARE: (f32, f32) = (0.6, 1.3);
/// Fastest a body joint may move between two frames, m/s: ten times what the hands reach in
/// a tour swing (under 10 m/s at impact), leaving room for keypoint noise at high rates.
pub const MAX_SPEED_M_S: f32 = 100.0;

/// Why a body or motion is beyond human limits.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Implausible {
    /// A stature (metres, [`Skeleton::height`]) outside [`MIN_STATURE_M`] to [`MAX_STATURE_M`].
    Stature(f32),
    /// Joint `joint`'s bone (from its parent) is `metres` long, outside the `min` to `max`
    /// metres a human's is at this stature: past [`MAX_BONE_SHARE`] of it, or for a limb bone
    /// outside [`LIMB_RANGE`] of its typical share.
    Bone {
        /// The bone's child joint (skeleton index).
        joint: usize,
        /// Its canonical name, where it has one.
        name: Option<Joint>,
        /// Its length.
        metres: f32,
        /// The shortest a human's is at this stature.
        min: f32,
        /// The longest.
        max: f32,
    },
    /// Joint `joint`'s limb bone is `metres` long and the other side's `mirror`: they differ
    /// by more than [`SYMMETRY`] of the longer.
    Asymmetric {
        /// The bone's child joint (skeleton index).
        joint: usize,
        /// Its canonical name.
        name: Joint,
        /// Its length.
        metres: f32,
        /// The other side's.
        mirror: f32,
    },
    /// The path from wrist to wrist along the bones is `metres` long, outside [`SPAN_SHARE`]
    /// of the `stature`.
    Span {
        /// Its length.
        metres: f32,
        /// The stature.
        stature: f32,
    },
    /// Joint `joint` moved at `speed` m/s (past [`MAX_SPEED_M_S`]) into frame `frame`.
    Speed {
        /// Skeleton index.
        joint: usize,
        /// The frame it arrived at.
        frame: usize,
        /// Metres per second.
        speed: f32,
    },
}

impl Implausible {
    /// The skeleton joint the refusal names, if any.
    pub fn joint(&self) -> Option<usize> {
        match *self {
            Implausible::Stature(_) | Implausible::Span { .. } => None,
            Implausible::Bone { joint, .. }
            | Implausible::Asymmetric { joint, .. }
            | Implausible::Speed { joint, .. } => Some(joint),
        }
    }
}

impl core::fmt::Display for Implausible {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Implausible::Stature(m) => write!(
                f,
                "a stature of {m} m is outside the human range of {MIN_STATURE_M} to \
                 {MAX_STATURE_M} m (wrong units or corrupt joints?)"
            ),
            Implausible::Bone {
                joint,
                name,
                metres,
                min,
                max,
            } => {
                write!(f, "the bone into joint {joint}")?;
                if let Some(name) = name {
                    write!(f, " ({name})")?;
                }
                write!(
                    f,
                    " is {metres:.3} m long; at this stature a human's is {min:.3} to {max:.3} m: \
                     a corrupt joint or a body no person has"
                )
            }
            Implausible::Asymmetric {
                joint,
                name,
                metres,
                mirror,
            } => write!(
                f,
                "the bone into joint {joint} ({name}) is {metres:.3} m long and the other \
                 side's {mirror:.3} m: more than {SYMMETRY} of the longer apart, which no \
                 person's limbs are"
            ),
            Implausible::Span { metres, stature } => write!(
                f,
                "the arms, wrist to wrist along the bones, are {metres:.3} m for a stature of \
                 {stature:.3} m; a human's are {} to {} of it",
                SPAN_SHARE.0, SPAN_SHARE.1
            ),
            Implausible::Speed {
                joint,
                frame,
                speed,
            } => write!(
                f,
                "joint {joint} moves at {speed} m/s into frame {frame}, faster than the \
                 {MAX_SPEED_M_S} m/s no body part reaches: a corrupt sample"
            ),
        }
    }
}

/// Whether skeleton joint `k` belongs to the body (not to a tracked club).
fn of_body(skeleton: &Skeleton, k: usize) -> bool {
    !matches!(skeleton.joint(k), Some(Joint::ClubGrip | Joint::ClubHead))
}

/// Checks `skeleton` against the human limits: its stature, every body bone's length, the limb
/// bones' lengths and their symmetry, and the arms' span.
///
/// # Errors
/// The first [`Implausible`] found: the stature, then the bones in joint order, then the limbs
/// in [`LIMBS`]' order, then the span.
pub fn body(skeleton: &Skeleton) -> Result<(), Implausible> {
    let stature = skeleton.height();
    if !(MIN_STATURE_M..=MAX_STATURE_M).contains(&stature) {
        return Err(Implausible::Stature(stature));
    }
    let length = |k: usize| norm(&skeleton.offset(k));
    (1..skeleton.len())
        .filter(|&k| of_body(skeleton, k))
        .try_for_each(|joint| {
            let name = skeleton.joint(joint);
            let share = LIMBS
                .iter()
                .find(|&&(j, parent, _)| {
                    name == Some(j)
                        && skeleton.parent(joint).and_then(|p| skeleton.joint(p)) == Some(parent)
                })
                .map(|&(_, _, share)| share);
            let (min, max) = match share {
                Some(s) => (LIMB_RANGE.0 * s * stature, LIMB_RANGE.1 * s * stature),
                None => (0.0, MAX_BONE_SHARE * stature),
            };
            let metres = length(joint);
            match (min..=max).contains(&metres) {
                true => Ok(()),
                false => Err(Implausible::Bone {
                    joint,
                    name,
                    metres,
                    min,
                    max,
                }),
            }
        })?;
    let limb = |j: Joint, parent: Joint| {
        let k = skeleton.index_of(j)?;
        (skeleton.parent(k) == skeleton.index_of(parent)).then(|| (k, length(k)))
    };
    for pair in LIMBS.chunks_exact(2) {
        let (Some((left, l)), Some((right, r))) =
            (limb(pair[0].0, pair[0].1), limb(pair[1].0, pair[1].1))
        else {
            continue;
        };
        if (l - r).abs() > SYMMETRY * l.max(r) {
            let (joint, name, metres, mirror) = match l < r {
                true => (left, pair[0].0, l, r),
                false => (right, pair[1].0, r, l),
            };
            return Err(Implausible::Asymmetric {
                joint,
                name,
                metres,
                mirror,
            });
        }
    }
    let wrists = (
        skeleton.find(&[Joint::LeftWrist, Joint::LeftHand]),
        skeleton.find(&[Joint::RightWrist, Joint::RightHand]),
    );
    if let (Some(a), Some(b)) = wrists {
        let metres = path_length(skeleton, a, b);
        if !(SPAN_SHARE.0 * stature..=SPAN_SHARE.1 * stature).contains(&metres) {
            return Err(Implausible::Span { metres, stature });
        }
    }
    Ok(())
}

/// The length of the path from joint `a` to joint `b` along `skeleton`'s bones.
fn path_length(skeleton: &Skeleton, a: usize, b: usize) -> f32 {
    let above_a = skeleton.ancestry(a).fold(0u64, |m, k| m | 1 << k);
    // The lowest joint above both (the root when their chains meet only there).
    let common = skeleton
        .ancestry(b)
        .find(|&k| above_a & (1 << k) != 0)
        .unwrap_or(0);
    skeleton.chain_length(a) + skeleton.chain_length(b) - 2.0 * skeleton.chain_length(common)
}

/// Checks the speed of every body joint of `skeleton` in `positions` (frames of
/// `skeleton.len()` joints) at `rate_hz` between successive frames where both samples were
/// captured (`missing`, when given, flags the rest).
///
/// # Errors
/// The first [`Implausible::Speed`] found, in frame order.
pub fn motion(
    skeleton: &Skeleton,
    positions: &[Vec3],
    missing: Option<&[bool]>,
    rate_hz: f32,
) -> Result<(), Implausible> {
    let joints = skeleton.len();
    if joints == 0 || rate_hz.is_nan() || rate_hz <= 0.0 {
        return Ok(());
    }
    let captured = |i: usize| missing.is_none_or(|m| !m.get(i).copied().unwrap_or(true));
    let mut frames = positions.chunks_exact(joints).enumerate();
    let Some((_, mut previous)) = frames.next() else {
        return Ok(());
    };
    for (frame, now) in frames {
        for joint in (0..joints).filter(|&k| of_body(skeleton, k)) {
            let (i, j) = ((frame - 1) * joints + joint, frame * joints + joint);
            if !(captured(i) && captured(j)) {
                continue;
            }
            let speed = norm(&(now[joint] - previous[joint])) * rate_hz;
            // (A NaN sample is refused too.)
            if speed.is_nan() || speed > MAX_SPEED_M_S {
                return Err(Implausible::Speed {
                    joint,
                    frame,
                    speed,
                });
            }
        }
        previous = now;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;

    #[test]
    fn a_standard_body_passes_and_a_scaled_one_does_not() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        assert_eq!(body(&skeleton), Ok(()));
        let n = skeleton.len();
        for (scale, ok) in [
            (0.0, false),
            (0.25, false),
            (0.33, true),
            (1.5, true),
            (1.6, false),
            (1e20, false),
        ] {
            let lengths: [f32; 17] = core::array::from_fn(|k| scale * norm(&skeleton.offset(k)));
            let scaled = skeleton.with_bone_lengths(&lengths[..n]).unwrap();
            assert_eq!(
                body(&scaled).is_ok(),
                ok,
                "scale {scale}: {:?}",
                body(&scaled)
            );
        }
    }

    #[test]
    fn one_long_bone_is_named() {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let n = skeleton.len();
        let wrist = (1..n)
            .find(|&k| skeleton.joint(k) == Some(crate::joint::Joint::LeftWrist))
            .unwrap();
        let lengths: [f32; 17] = core::array::from_fn(|k| match k == wrist {
            true => 32.0,
            false => norm(&skeleton.offset(k)),
        });
        let broken = skeleton.with_bone_lengths(&lengths[..n]).unwrap();
        let e = body(&broken).unwrap_err();
        assert!(
            matches!(e, Implausible::Bone { joint, metres, .. } if joint == wrist && (metres - 32.0).abs() < 1e-3),
            "{e:?}"
        );
    }

    /// The standard H3.6M skeleton with each bone's length from `length` (index, standard
    /// length).
    fn reshaped(length: impl Fn(usize, f32) -> f32) -> Skeleton {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let lengths: [f32; 17] = core::array::from_fn(|k| length(k, norm(&skeleton.offset(k))));
        skeleton.with_bone_lengths(&lengths).unwrap()
    }

    /// Both arms' bones: the upper arms and forearms, by their child joints.
    fn arm_bones() -> [usize; 4] {
        [
            Joint::LeftElbow,
            Joint::LeftWrist,
            Joint::RightElbow,
            Joint::RightWrist,
        ]
        .map(index)
    }

    fn index(j: Joint) -> usize {
        Skeleton::standard(Format::H36m17)
            .unwrap()
            .index_of(j)
            .unwrap()
    }

    #[test]
    fn every_standard_body_passes() {
        for format in [Format::Canonical].into_iter().chain(Format::BUILT_IN) {
            if let Ok(skeleton) = Skeleton::standard(format) {
                assert_eq!(body(&skeleton), Ok(()), "{format:?}");
            }
        }
    }

    #[test]
    fn limbs_no_person_has_are_named() {
        let (elbow, wrist) = (index(Joint::LeftElbow), index(Joint::LeftWrist));
        // A left arm of 1.6 m on a body of about 1.62 m.
        let long = reshaped(|k, l| match k {
            k if k == elbow || k == wrist => 0.8,
            _ => l,
        });
        assert!(
            matches!(body(&long), Err(Implausible::Bone { joint, name: Some(Joint::LeftElbow), .. }) if joint == elbow),
            "{:?}",
            body(&long)
        );
        // Arms of zero length: both upper arms named, the left first.
        let arms = arm_bones();
        let none = reshaped(|k, l| if arms.contains(&k) { 0.0 } else { l });
        assert!(
            matches!(body(&none), Err(Implausible::Bone { joint, metres: 0.0, .. }) if joint == elbow),
            "{:?}",
            body(&none)
        );
        // One shank half the other's: each within its human range, the pair not.
        let ankle = index(Joint::RightAnkle);
        let short = reshaped(|k, l| if k == ankle { 0.55 * l } else { l });
        assert!(
            matches!(body(&short), Err(Implausible::Asymmetric { joint, name: Joint::RightAnkle, .. }) if joint == ankle),
            "{:?}",
            body(&short)
        );
        // Within the tolerance: 15 % shorter passes.
        let near = reshaped(|k, l| if k == ankle { 0.85 * l } else { l });
        assert_eq!(body(&near), Ok(()));
    }

    #[test]
    fn arms_count_toward_the_bodys_size() {
        // Every arm bone 1.45 times its length and the shoulders three times theirs (each bone
        // within its range): the span is not.
        let arms = arm_bones();
        let shoulders = [Joint::LeftShoulder, Joint::RightShoulder].map(index);
        let wide = reshaped(|k, l| match k {
            k if arms.contains(&k) => 1.45 * l,
            k if shoulders.contains(&k) => 3.0 * l,
            _ => l,
        });
        assert!(
            matches!(body(&wide), Err(Implausible::Span { .. })),
            "{:?}",
            body(&wide)
        );
        let e = body(&wide).unwrap_err();
        assert_eq!(e.joint(), None);
    }

    #[test]
    fn a_body_joint_jumping_between_frames_is_refused_unless_a_sample_is_missing() {
        // Three frames at 100 Hz: the left hip jumps 2 m into frame 2 (200 m/s).
        let skeleton = Skeleton::standard(Format::Canonical).unwrap();
        let n = skeleton.len();
        let hip = skeleton.index_of(Joint::LeftHip).unwrap();
        let mut p = [Vec3::zeros(); 3 * 22];
        p[2 * n + hip] = Vec3::new(2.0, 0.0, 0.0);
        let jump = Implausible::Speed {
            joint: hip,
            frame: 2,
            speed: 200.0,
        };
        assert_eq!(motion(&skeleton, &p[..3 * n], None, 100.0), Err(jump));
        let mut missing = [false; 3 * 22];
        missing[2 * n + hip] = true;
        assert_eq!(
            motion(&skeleton, &p[..3 * n], Some(&missing[..3 * n]), 100.0),
            Ok(())
        );
        // 0.9 m in 1/100 s is 90 m/s: within the limit; NaN is not.
        p[2 * n + hip] = Vec3::new(0.9, 0.0, 0.0);
        assert_eq!(motion(&skeleton, &p[..3 * n], None, 100.0), Ok(()));
        p[2 * n + hip] = Vec3::new(f32::NAN, 0.0, 0.0);
        assert!(motion(&skeleton, &p[..3 * n], None, 100.0).is_err());
    }
}
