//! Random characters: anthropometric bodies dressed in a keypoint format.
//!
//! A [`Body`] is a set of canonical bones: each bone's length is a fraction of the sampled
//! stature ([`PROPORTIONS`]) times a per-segment factor, and its rest direction is the
//! standard T-pose's ([`t_pose`]) turned by a small random angle, so rest poses differ
//! between characters. A [`Character`] is a body built into one format's skeleton: every
//! format joint sits where its [`Place`] says, measured on the body instead of the standard
//! T-pose, so the same body gives consistent skeletons in every format.
//!
//! ```
//! use posecoach_core::format::Format;
//! use posecoach_train::bodies::sample_character;
//! use rand::SeedableRng;
//!
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
//! let character = sample_character(Format::H36m17, &mut rng).unwrap();
//! assert_eq!(character.skeleton.len(), 17);
//! assert!((1.45..=2.05).contains(&character.body.stature));
//! ```

use posecoach_core::format::{t_pose, Format, Place};
use posecoach_core::joint::{Joint, JOINT_COUNT};
use posecoach_core::skeleton::{Skeleton, SkeletonError};
use posecoach_core::{Quat, Vec3};
use rand::Rng;
use rand_distr::StandardNormal;

/// Shortest stature sampled (metres, floor to the top of the head).
pub const MIN_STATURE_M: f32 = 1.45;
/// Tallest stature sampled.
pub const MAX_STATURE_M: f32 = 2.05;
/// Stature of the standard T-pose ([`t_pose`]).
pub const TEMPLATE_STATURE_M: f32 = 1.75;
/// Ankle joint height as a fraction of stature (Drillis and Contini).
pub const ANKLE_HEIGHT: f32 = 0.039;
/// Normal draws are clamped to this many standard deviations, so every body is plausible.
pub const TRUNCATE_SD: f32 = 2.5;
/// Standard deviation of the left/right difference of a paired segment (fraction of length).
pub const ASYMMETRY_SD: f32 = 0.01;
/// Largest angle (degrees) by which a bone's rest direction is turned.
pub const REST_JITTER_DEG: f32 = 5.0;
/// Club lengths sampled (metres, grip to head): a wedge to a driver.
pub const CLUB_LENGTH_M: (f32, f32) = (0.89, 1.15);

/// Length of the bone into `joint`, as a fraction of stature, and its spread between people.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proportion {
    /// The bone's far joint (left side; the right side mirrors it).
    pub joint: Joint,
    /// Mean length over stature.
    pub fraction: f32,
    /// Coefficient of variation of that fraction between people.
    pub spread: f32,
}

const fn prop(joint: Joint, fraction: f32, spread: f32) -> Proportion {
    Proportion {
        joint,
        fraction,
        spread,
    }
}

/// Bone lengths over stature. Thigh, shank, upper arm and forearm, and the landmark heights
/// that fix the trunk (hip joint 0.530, shoulder 0.818, chin 0.870, ankle 0.039 of stature),
/// are Drillis and Contini's (1966) segment proportions as tabulated in Winter, *Biomechanics
/// and Motor Control of Human Movement*; the pelvis, shoulder girdle, foot, hand and head
/// bones keep the standard T-pose's proportions, with the trunk and head bones rescaled to
/// meet those landmarks. Spreads are a few percent, wider for the short, hard-to-locate bones.
pub const PROPORTIONS: [Proportion; 13] = [
    prop(Joint::LeftHip, 0.059, 0.06),
    prop(Joint::LeftKnee, 0.245, 0.04),
    prop(Joint::LeftAnkle, 0.246, 0.04),
    prop(Joint::LeftToe, 0.087, 0.05),
    prop(Joint::Spine, 0.110, 0.05),
    prop(Joint::Thorax, 0.138, 0.05),
    prop(Joint::Neck, 0.069, 0.06),
    prop(Joint::Head, 0.055, 0.05),
    prop(Joint::HeadTop, 0.071, 0.05),
    prop(Joint::LeftShoulder, 0.103, 0.05),
    prop(Joint::LeftElbow, 0.186, 0.04),
    prop(Joint::LeftWrist, 0.146, 0.04),
    prop(Joint::LeftHand, 0.046, 0.06),
];

/// The proportion of the bone into `joint` (either side), if it is a body bone.
pub fn proportion(joint: Joint) -> Option<&'static Proportion> {
    PROPORTIONS
        .iter()
        .find(|p| p.joint == joint || p.joint == joint.mirror())
}

/// The range of lengths over stature a sampled bone into `joint` can take.
pub fn proportion_bounds(joint: Joint) -> Option<(f32, f32)> {
    proportion(joint).map(|p| {
        let side = 1.0 + TRUNCATE_SD * ASYMMETRY_SD;
        let shared = 1.0 + TRUNCATE_SD * p.spread;
        (
            p.fraction * (2.0 - shared) * (2.0 - side),
            p.fraction * shared * side,
        )
    })
}

/// How much bodies vary besides stature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variation {
    /// Whether segment lengths vary around [`PROPORTIONS`] (else exactly the mean).
    pub proportions: bool,
    /// Largest rest-direction turn per bone, degrees (0: every rest pose is the standard one).
    pub rest_jitter_deg: f32,
}

impl Variation {
    /// Varied proportions and rest poses.
    pub const FULL: Variation = Variation {
        proportions: true,
        rest_jitter_deg: REST_JITTER_DEG,
    };
    /// Varied proportions on the standard rest pose.
    pub const STANDARD_REST: Variation = Variation {
        proportions: true,
        rest_jitter_deg: 0.0,
    };
}

/// A body: the canonical joints' rest offsets, built from a stature.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Floor to the top of the head, standing, metres (the sampled value; the bones' own
    /// spread makes the built body differ from it by a few percent).
    pub stature: f32,
    /// Per canonical joint, its rest offset from its canonical parent (the pelvis: its rest
    /// position). Club joints hang from the left hand.
    offsets: [Vec3; JOINT_COUNT],
}

impl Body {
    /// A random body of stature in [`MIN_STATURE_M`]..=[`MAX_STATURE_M`] (uniform, to cover
    /// the range evenly), with a club of random length.
    pub fn sample(variation: &Variation, rng: &mut impl Rng) -> Body {
        let stature = rng.random_range(MIN_STATURE_M..=MAX_STATURE_M);
        let mut factors = [1.0f32; JOINT_COUNT];
        if variation.proportions {
            for p in &PROPORTIONS {
                let shared = 1.0 + p.spread * normal(rng);
                for joint in sides(p.joint) {
                    factors[joint.index()] = shared * (1.0 + ASYMMETRY_SD * normal(rng));
                }
            }
        }
        let club = rng.random_range(CLUB_LENGTH_M.0..=CLUB_LENGTH_M.1);
        let mut offsets = [Vec3::zeros(); JOINT_COUNT];
        for joint in Joint::ALL.into_iter().skip(1) {
            let length = match (joint, proportion(joint)) {
                (Joint::ClubHead, _) => club,
                (_, Some(p)) => p.fraction * stature * factors[joint.index()],
                (_, None) => template_bone(joint).norm() * stature / TEMPLATE_STATURE_M,
            };
            let direction = jitter(template_bone(joint), variation.rest_jitter_deg, rng);
            offsets[joint.index()] = direction * length;
        }
        let mut body = Body { stature, offsets };
        body.stand_on_floor();
        body
    }

    /// Length of the bone from `joint`'s canonical parent to it (0 for the pelvis).
    pub fn bone_length(&self, joint: Joint) -> f32 {
        match joint {
            Joint::Pelvis => 0.0,
            _ => self.offsets[joint.index()].norm(),
        }
    }

    /// Rest positions of every canonical joint, in [`Joint::ALL`] order.
    pub fn rest_positions(&self) -> [Vec3; JOINT_COUNT] {
        let mut out = [Vec3::zeros(); JOINT_COUNT];
        for joint in Joint::ALL {
            let base = joint.parent().map_or(Vec3::zeros(), |p| out[p.index()]);
            out[joint.index()] = base + self.offsets[joint.index()];
        }
        out
    }

    /// The same body with every bone and the stature scaled by `factor` (same rest
    /// directions).
    pub fn scaled(&self, factor: f32) -> Body {
        Body {
            stature: self.stature * factor,
            offsets: self.offsets.map(|o| o * factor),
        }
    }

    /// The same body, bones and stature, with every body bone's rest direction turned by a
    /// uniform angle in `min_deg..=max_deg` about a random axis across it: a T-pose measured
    /// with error in its posture (what a phone's pose estimate gives), not in its proportions.
    /// The club, which a T-pose does not show, keeps its direction.
    pub fn with_posture_error(&self, min_deg: f32, max_deg: f32, rng: &mut impl Rng) -> Body {
        let mut offsets = self.offsets;
        for joint in Joint::ALL.into_iter().skip(1).filter(|j| !j.is_club()) {
            let bone = offsets[joint.index()];
            offsets[joint.index()] = turn(bone, min_deg, max_deg, rng) * bone.norm();
        }
        let mut body = Body {
            stature: self.stature,
            offsets,
        };
        body.stand_on_floor();
        body
    }

    /// Puts the pelvis at the height that sets the lower ankle at [`ANKLE_HEIGHT`].
    fn stand_on_floor(&mut self) {
        self.offsets[0] = Vec3::zeros();
        let rest = self.rest_positions();
        let ankles = [Joint::LeftAnkle, Joint::RightAnkle].map(|j| rest[j.index()].y);
        self.offsets[0].y = ANKLE_HEIGHT * self.stature - ankles[0].min(ankles[1]);
    }
}

/// `joint` and its mirror image (once for midline joints).
fn sides(joint: Joint) -> impl Iterator<Item = Joint> {
    let mirror = joint.mirror();
    core::iter::once(joint).chain((mirror != joint).then_some(mirror))
}

/// A standard normal draw clamped to ±[`TRUNCATE_SD`].
fn normal(rng: &mut impl Rng) -> f32 {
    let z: f32 = rng.sample(StandardNormal);
    z.clamp(-TRUNCATE_SD, TRUNCATE_SD)
}

/// The standard T-pose's bone from `joint`'s canonical parent.
fn template_bone(joint: Joint) -> Vec3 {
    joint
        .parent()
        .map_or(Vec3::zeros(), |p| t_pose(joint) - t_pose(p))
}

/// `bone`'s unit direction turned by a uniform angle of up to `max_deg` about a random axis
/// perpendicular to it.
fn jitter(bone: Vec3, max_deg: f32, rng: &mut impl Rng) -> Vec3 {
    turn(bone, 0.0, max_deg, rng)
}

/// `bone`'s unit direction turned by a uniform angle in `min_deg..=max_deg` about a random
/// axis perpendicular to it (not turned for `max_deg` ≤ 0).
fn turn(bone: Vec3, min_deg: f32, max_deg: f32, rng: &mut impl Rng) -> Vec3 {
    let direction = bone.normalize();
    if max_deg <= 0.0 {
        return direction;
    }
    let random = Vec3::from_fn(|_, _| rng.sample::<f32, _>(StandardNormal));
    let axis = random - direction * direction.dot(&random);
    let angle = rng.random_range(min_deg..=max_deg).to_radians();
    match axis.try_normalize(f32::EPSILON) {
        Some(axis) => Quat::from_scaled_axis(axis * angle) * direction,
        None => direction,
    }
}

/// A body built into one format's skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct Character {
    /// The skeleton in `format`, at the body's rest pose.
    pub skeleton: Skeleton,
    /// Its keypoint format.
    pub format: Format,
    /// The body it was built from.
    pub body: Body,
}

impl Character {
    /// `body` as a `format` skeleton. Built-in formats take their own joint table (the golf
    /// markers' includes the club); a canonical skeleton has the 22 body joints, plus the club
    /// if `club`.
    ///
    /// # Errors
    /// [`SkeletonError`] for [`Format::Custom`], which has no joint table.
    pub fn new(body: Body, format: Format, club: bool) -> Result<Character, SkeletonError> {
        let rest = body.rest_positions();
        let at = |joint: Joint| rest[joint.index()];
        let skeleton = match format {
            Format::Canonical => {
                let joints: Vec<Joint> = Joint::ALL
                    .into_iter()
                    .filter(|j| club || !j.is_club())
                    .collect();
                let positions: Vec<Vec3> = joints.iter().map(|&j| at(j)).collect();
                Skeleton::canonical(&joints, &positions)?
            }
            _ => {
                let table = format.joints();
                let parents: Vec<Option<usize>> =
                    table.iter().map(|j| j.parent.map(usize::from)).collect();
                let positions: Vec<Vec3> = table.iter().map(|j| place(j.place, at)).collect();
                let joints: Vec<Option<Joint>> = table.iter().map(|j| j.joint).collect();
                Skeleton::from_rest_positions(format, &parents, &positions, &joints)?
            }
        };
        Ok(Character {
            skeleton,
            format,
            body,
        })
    }
}

/// Where `place` puts a joint on a body whose canonical joints are at `at`.
pub fn place(place: Place, at: impl Fn(Joint) -> Vec3) -> Vec3 {
    match place {
        Place::At(joint) => at(joint),
        Place::Between(a, b, t) => at(a) + (at(b) - at(a)) * t,
    }
}

/// A random character in `format` with varied proportions and rest pose ([`Variation::FULL`]),
/// without a club unless the format has one.
///
/// # Errors
/// As [`Character::new`].
pub fn sample_character(format: Format, rng: &mut impl Rng) -> Result<Character, SkeletonError> {
    sample_character_with(format, &Variation::FULL, false, rng)
}

/// A random character in `format` varied as `variation` says; a canonical one with a club if
/// `club`.
///
/// # Errors
/// As [`Character::new`].
pub fn sample_character_with(
    format: Format,
    variation: &Variation,
    club: bool,
    rng: &mut impl Rng,
) -> Result<Character, SkeletonError> {
    Character::new(Body::sample(variation, rng), format, club)
}

#[cfg(test)]
pub(crate) mod testing {
    //! Seeded characters for tests.
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A random character of `format`, seeded.
    pub fn character(format: Format, seed: u64) -> Character {
        sample_character(format, &mut ChaCha8Rng::seed_from_u64(seed)).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::FORMATS;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    const SAMPLES: u64 = 300;
    const LENGTH_TOLERANCE_M: f32 = 1e-5;

    fn rng(seed: u64) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(seed)
    }

    #[test]
    fn statures_and_proportions_stay_in_range() {
        let mut rng = rng(1);
        let mut mean = [0.0f32; JOINT_COUNT];
        for _ in 0..SAMPLES {
            let body = Body::sample(&Variation::FULL, &mut rng);
            assert!((MIN_STATURE_M..=MAX_STATURE_M).contains(&body.stature));
            let rest = body.rest_positions();
            let standing = rest[Joint::HeadTop.index()].y;
            assert!(
                (standing / body.stature - 1.0).abs() < 0.08,
                "standing height {standing} for stature {}",
                body.stature
            );
            for joint in Joint::ALL {
                if let Some((lo, hi)) = proportion_bounds(joint) {
                    let fraction = body.bone_length(joint) / body.stature;
                    assert!((lo..=hi).contains(&fraction), "{joint}: {fraction}");
                    mean[joint.index()] += fraction / SAMPLES as f32;
                }
            }
            let club = body.bone_length(Joint::ClubHead);
            assert!((CLUB_LENGTH_M.0..=CLUB_LENGTH_M.1).contains(&club));
        }
        for p in &PROPORTIONS {
            let m = mean[p.joint.index()];
            assert!((m / p.fraction - 1.0).abs() < 0.01, "{}: {m}", p.joint);
        }
    }

    #[test]
    fn left_and_right_are_correlated() {
        let mut rng = rng(2);
        for _ in 0..SAMPLES {
            let body = Body::sample(&Variation::FULL, &mut rng);
            let (l, r) = (
                body.bone_length(Joint::LeftKnee),
                body.bone_length(Joint::RightKnee),
            );
            let most = (1.0 + TRUNCATE_SD * ASYMMETRY_SD) / (1.0 - TRUNCATE_SD * ASYMMETRY_SD);
            assert!(l / r <= most && r / l <= most, "{l} vs {r}");
        }
    }

    #[test]
    fn posture_error_turns_every_body_bone_within_its_range_and_keeps_lengths() {
        let mut rng = rng(7);
        let body = Body::sample(&Variation::STANDARD_REST, &mut rng);
        let noisy = body.with_posture_error(3.0, 8.0, &mut rng);
        assert_eq!(noisy.stature, body.stature);
        for joint in Joint::ALL.into_iter().skip(1) {
            let (a, b) = (body.offsets[joint.index()], noisy.offsets[joint.index()]);
            assert!((a.norm() - b.norm()).abs() < LENGTH_TOLERANCE_M, "{joint}");
            let degrees = a.angle(&b).to_degrees();
            match joint.is_club() {
                true => assert!(degrees < 1e-3, "{joint}: {degrees}"),
                false => assert!((2.99..=8.01).contains(&degrees), "{joint}: {degrees}"),
            }
        }
    }

    #[test]
    fn rest_directions_turn_by_at_most_the_jitter() {
        let mut rng = rng(3);
        let body = Body::sample(&Variation::FULL, &mut rng);
        let rest = body.rest_positions();
        let mut largest = 0.0f32;
        for joint in Joint::ALL.into_iter().skip(1) {
            let parent = joint.parent().map_or(0, Joint::index);
            let bone = rest[joint.index()] - rest[parent];
            let angle = bone.angle(&template_bone(joint)).to_degrees();
            assert!(angle <= REST_JITTER_DEG + 1e-3, "{joint}: {angle}°");
            largest = largest.max(angle);
        }
        assert!(largest > 1.0, "no rest-pose variation at all");
        let standard = Body::sample(&Variation::STANDARD_REST, &mut rng).rest_positions();
        let bone = standard[Joint::LeftElbow.index()] - standard[Joint::LeftShoulder.index()];
        let turn = bone.normalize() - template_bone(Joint::LeftElbow).normalize();
        assert!(turn.norm() < 1e-5);
    }

    #[test]
    fn every_format_builds_with_the_sampled_bone_lengths() {
        let mut rng = rng(4);
        for format in FORMATS {
            let character = match sample_character_with(format, &Variation::FULL, true, &mut rng) {
                Ok(c) => c,
                Err(e) => panic!("{format}: {e}"),
            };
            let s = &character.skeleton;
            assert_eq!(s.format(), format);
            let expected = match format {
                Format::Canonical => JOINT_COUNT,
                _ => format.joints().len(),
            };
            assert_eq!(s.len(), expected, "{format}");
            let mut rest = vec![Vec3::zeros(); s.len()];
            s.rest_positions(&mut rest);
            let mut checked = 0;
            for k in 1..s.len() {
                let Some(joint) = s.joint(k) else { continue };
                let Some(parent) = joint.parent().and_then(|p| s.index_of(p)) else {
                    continue;
                };
                let length = (rest[k] - rest[parent]).norm();
                let sampled = character.body.bone_length(joint);
                assert!(
                    (length - sampled).abs() < LENGTH_TOLERANCE_M,
                    "{format} {joint}: {length} vs {sampled}"
                );
                checked += 1;
            }
            assert!(checked >= 10, "{format}: only {checked} bones checked");
            let h = s.height() / character.body.stature;
            assert!((0.9..1.15).contains(&h), "{format}: height/stature {h}");
        }
        assert!(sample_character(Format::Custom, &mut rng).is_err());
    }

    #[test]
    fn scaling_keeps_directions() {
        let body = Body::sample(&Variation::FULL, &mut rng(5));
        let big = body.scaled(1.2);
        let (a, b) = (body.rest_positions(), big.rest_positions());
        for (p, q) in a.iter().zip(&b) {
            assert!((p * 1.2 - q).norm() < LENGTH_TOLERANCE_M);
        }
    }
}
