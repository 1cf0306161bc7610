//! Motions as rotations, and the ground truth of retargeting.
//!
//! A [`Clip`] holds a motion as per-frame local rotations on its source skeleton (rotations
//! relative to that skeleton's rest pose, as in [`kinematics`]) and the root trajectory divided
//! by the source's height, so it can be put on any character with [`Clip::on`].
//!
//! **Ground truth** ([`ground_truth`]) is the *rotation copy through canonical names*: every
//! target joint with a counterpart in the source (the same joint of the same format and tree,
//! else the same canonical name) takes the source bone's global rotation *relative to rest*,
//! `G_t = G_s`, applied to the target's own rest offset; a target joint without a counterpart
//! keeps its parent's global rotation. The root follows the source's trajectory scaled by the
//! ratio of pelvis-to-ankle leg lengths ([`leg_length`]), so a body's ground truth has the same
//! root trajectory in every format (the analytic retargeter measures to the toes where both
//! skeletons have them; with uniformly scaled bodies both ratios agree).
//!
//! When rest poses differ, this means that the source and the target make *the same joint
//! rotations from their own rest poses*: a bone the target's rest pose tilts 5° forward stays
//! 5° forward of the source's bone throughout the motion, so the ground truth's bone
//! directions are the source's turned by the rest-pose difference, not copied. With identical
//! rest directions (whatever the bone lengths), it copies bone directions, as the analytic
//! retargeter does.
//!
//! Real captures do not all rest in a T-pose (Bandai's rest offsets lie along local X), so
//! [`standard_rest`] first re-rests a motion on its format's standard T-pose directions with
//! its own bone lengths: the positions are unchanged, only the rest the rotations are relative
//! to.

use crate::bodies::Character;
use crate::error::Error;
use posecoach_core::config::MAX_JOINTS;
use posecoach_core::contacts::{self, Contacts, Kept, Swing};
use posecoach_core::events;
use posecoach_core::joint::Joint;
use posecoach_core::kinematics::{self, inverse, LengthError};
use posecoach_core::retarget::RetargetError;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::{Quat, Vec3};
use posecoach_io::Motion;

/// A motion as rotations on its source skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// Where it came from (a file stem), for reports.
    pub name: String,
    /// The source skeleton the rotations are relative to.
    pub skeleton: Skeleton,
    /// Frames per second.
    pub rate_hz: f32,
    /// Per-bone local rotations, frame-major ([`kinematics::forward`]'s `local`).
    pub local: Vec<Quat>,
    /// Root position per frame divided by the source skeleton's height.
    pub root: Vec<Vec3>,
}

impl Clip {
    /// The rotations of `motion` relative to its skeleton's rest pose, by
    /// [`kinematics::inverse`]. Positions whose bones do not have the skeleton's lengths
    /// (joint centres from markers) become the nearest rigid motion.
    ///
    /// # Errors
    /// [`Error::Length`] if the motion's frames do not fit its skeleton.
    pub fn from_motion(name: &str, motion: &Motion) -> Result<Clip, Error> {
        let n = motion.skeleton.len();
        let mut local = vec![Quat::identity(); motion.positions.len()];
        let mut root = Vec::with_capacity(motion.frames());
        for (frame, out) in motion
            .positions
            .chunks_exact(n)
            .zip(local.chunks_exact_mut(n))
        {
            root.push(inverse(&motion.skeleton, frame, out)? / motion.skeleton.height());
        }
        Ok(Clip {
            name: name.to_string(),
            skeleton: motion.skeleton.clone(),
            rate_hz: motion.rate_hz,
            local,
            root,
        })
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.root.len()
    }

    /// Frames `start..start + frames`.
    ///
    /// # Errors
    /// [`Error::TooShort`] if the clip ends before.
    pub fn slice(&self, start: usize, frames: usize) -> Result<Clip, Error> {
        let available = self.frames().saturating_sub(start);
        if available < frames {
            return Err(Error::TooShort {
                expected: frames,
                actual: available,
            });
        }
        let n = self.skeleton.len();
        Ok(Clip {
            name: self.name.clone(),
            skeleton: self.skeleton.clone(),
            rate_hz: self.rate_hz,
            local: self.local[start * n..(start + frames) * n].to_vec(),
            root: self.root[start..start + frames].to_vec(),
        })
    }

    /// Whether the source tracks a club.
    pub fn has_club(&self) -> bool {
        self.skeleton.index_of(Joint::ClubGrip).is_some()
    }

    /// The clip as a coach on `character`: [`Clip::on`], and for a golf swing the club turned
    /// about its grip so that its head is at the recording's ball at address and impact
    /// ([`Kept::CLUB`], the recording on the clip's skeleton as the coach). The
    /// rotation copy alone turns a club of another length by the recording's rotations and
    /// misses the ball by up to a quarter of a metre, which no coach does; the body is left as
    /// the rotation copy makes it, so joint errors, which leave the club out, are unchanged.
    ///
    /// # Errors
    /// As [`Clip::on_skeleton`], [`events::detect`] (a golf swing without detectable events)
    /// and [`Contacts::apply`].
    pub fn coach_on(&self, character: &Character) -> Result<Motion, Error> {
        let mut coach = self.on(character)?;
        if !self.has_club() {
            return Ok(coach);
        }
        let recording = self.on_skeleton(&self.skeleton)?;
        let swing = events::detect(&self.skeleton, recording.swing(), self.rate_hz)?;
        let swing = Some(Swing::from(&swing));
        Contacts::new(&self.skeleton, &coach.skeleton)
            .keeping(Kept::CLUB)
            .apply(
                contacts::frames(&recording.positions, self.skeleton.len()),
                self.rate_hz,
                swing,
                &mut coach.positions,
            )?;
        Ok(coach)
    }

    /// The clip on `character`: the rotation copy through canonical names (see the module).
    ///
    /// # Errors
    /// As [`Clip::on_skeleton`].
    pub fn on(&self, character: &Character) -> Result<Motion, Error> {
        self.on_skeleton(&character.skeleton)
    }

    /// The clip on `target`, by the rotation copy through canonical names.
    ///
    /// # Errors
    /// [`Error::Retarget`] if the source's legs have no length.
    pub fn on_skeleton(&self, target: &Skeleton) -> Result<Motion, Error> {
        let source_legs = leg_length(&self.skeleton);
        if source_legs <= f32::EPSILON {
            return Err(Error::Retarget(RetargetError::DegenerateSource));
        }
        let scale = self.skeleton.height() * leg_length(target) / source_legs;
        let counterpart = counterparts(&self.skeleton, target);
        let (n, m) = (self.skeleton.len(), target.len());
        let mut positions = vec![Vec3::zeros(); self.frames() * m];
        let mut source_global = vec![Quat::identity(); n];
        let mut global = vec![Quat::identity(); m];
        for ((local, root), out) in self
            .local
            .chunks_exact(n)
            .zip(&self.root)
            .zip(positions.chunks_exact_mut(m))
        {
            globals(&self.skeleton, local, &mut source_global);
            transfer(target, &counterpart, &source_global, &mut global);
            out[0] = root * scale;
            for k in 1..m {
                let parent = target.parent(k).unwrap_or(0);
                out[k] = out[parent] + global[k] * target.offset(k);
            }
        }
        Ok(motion(target, self.rate_hz, positions))
    }
}

/// The ground truth of retargeting `source` onto `target`: [`Clip::on`].
///
/// # Errors
/// As [`Clip::on`].
pub fn ground_truth(source: &Clip, target: &Character) -> Result<Motion, Error> {
    source.on(target)
}

/// Mean chain length from the root to both ankles (every built-in format has ankles; else the
/// skeleton's own leg length): the ground truth's root scale, the same whatever format a body
/// is dressed in.
pub fn leg_length(skeleton: &Skeleton) -> f32 {
    let chain = |joint| skeleton.index_of(joint).map(|k| skeleton.chain_length(k));
    match (chain(Joint::LeftAnkle), chain(Joint::RightAnkle)) {
        (Some(left), Some(right)) => 0.5 * (left + right),
        _ => skeleton.leg_length(),
    }
}

/// Global rotations from local ones, `G_k = G_parent · q_k`.
fn globals(skeleton: &Skeleton, local: &[Quat], out: &mut [Quat]) {
    for k in 0..skeleton.len() {
        out[k] = match skeleton.parent(k) {
            Some(p) => out[p] * local[k],
            None => local[k],
        };
    }
}

/// Each `target` joint's global rotation from the source's, `source_global`, through
/// `counterpart` ([`counterparts`]): a joint without a counterpart keeps its parent's.
///
/// # Panics
/// If `counterpart` or `global` is shorter than `target`, or a counterpart is beyond
/// `source_global`.
pub fn transfer(
    target: &Skeleton,
    counterpart: &[Option<usize>],
    source_global: &[Quat],
    global: &mut [Quat],
) {
    global[0] = source_global[0];
    for k in 1..target.len() {
        let parent = target.parent(k).unwrap_or(0);
        global[k] = counterpart[k].map_or(global[parent], |c| source_global[c]);
    }
}

/// Per target joint, its source counterpart: by index when both are the same built-in format
/// with the same tree, else by canonical name (as the analytic retargeter matches them).
pub fn counterparts(source: &Skeleton, target: &Skeleton) -> Vec<Option<usize>> {
    let same_tree = source.format() == target.format()
        && source.format().joints().len() == source.len()
        && source.len() == target.len()
        && (0..source.len()).all(|i| source.parent(i) == target.parent(i));
    (0..target.len())
        .map(|k| match same_tree {
            true => Some(k),
            false => target.joint(k).and_then(|j| source.index_of(j)),
        })
        .collect()
}

/// A motion on `skeleton` from positions, named as its format names its joints.
pub fn motion(skeleton: &Skeleton, rate_hz: f32, positions: Vec<Vec3>) -> Motion {
    Motion {
        skeleton: skeleton.clone(),
        names: joint_names(skeleton),
        rate_hz,
        missing: vec![false; positions.len()],
        positions,
    }
}

/// Joint names as `skeleton`'s format writes them: its table's, else canonical names, else
/// `joint<k>`.
pub fn joint_names(skeleton: &Skeleton) -> Vec<String> {
    let table = skeleton.format().joints();
    (0..skeleton.len())
        .map(|k| match (table.get(k), skeleton.joint(k)) {
            (Some(j), _) if table.len() == skeleton.len() => j.name.to_string(),
            (_, Some(joint)) => joint.name().to_string(),
            _ => format!("joint{k}"),
        })
        .collect()
}

/// `motion` with its skeleton re-rested ([`Skeleton::standard_rest`]); positions unchanged.
///
/// # Errors
/// As [`Skeleton::standard_rest`].
pub fn standard_rest(motion: &Motion) -> Result<Motion, Error> {
    Ok(Motion {
        skeleton: motion.skeleton.standard_rest()?,
        ..motion.clone()
    })
}

/// Rounds of [`Rotations::globals`]: a second halves the first's error on varied rest poses,
/// more change it by under 0.01 % of height (measured on the evaluation split).
pub const CONVENTION_ROUNDS: usize = 2;

/// The rotations of a motion on a skeleton whose rest pose is not its format's standard one,
/// estimated as the clips define them: each bone's rotation turns its *own* rest offset onto
/// its observed direction exactly, with the twist about itself that the standard rest pose
/// would give ([`Skeleton::standard_rest`], as [`standard_rest`] and [`Clip::from_motion`] make
/// every clip's rotations).
///
/// Positions tell each bone's direction but not its twist. Inverse kinematics on the
/// skeleton's own rest pose takes the smallest twist from *that* pose; a rest pose turned by a
/// few degrees then turns the twists by as much, and the children, rotated with them, miss
/// by the product of both angles. Each round poses the standard skeleton with the current
/// rotations, takes the rotations inverse kinematics finds there (the standard pose's
/// twists), then turns each bone by the smallest rotation that puts its own rest offset back
/// onto the observed direction.
#[derive(Clone, Debug)]
pub struct Rotations {
    own: Skeleton,
    standard: Skeleton,
}

impl Rotations {
    /// The estimator for motions on `skeleton`.
    ///
    /// # Errors
    /// As [`Skeleton::standard_rest`].
    pub fn new(skeleton: &Skeleton) -> Result<Rotations, Error> {
        Ok(Rotations {
            standard: skeleton.standard_rest()?,
            own: skeleton.clone(),
        })
    }

    /// Each bone's global rotation in `frame` (the rotation of its rest offset, the root's
    /// included), into `global`.
    ///
    /// # Errors
    /// [`Error::Length`] if `frame` or `global` does not fit the skeleton.
    pub fn globals(&self, frame: &[Vec3], global: &mut [Quat]) -> Result<(), Error> {
        let n = self.own.len();
        if global.len() < n {
            return Err(Error::Length(LengthError {
                expected: n,
                actual: global.len(),
            }));
        }
        let mut local = [Quat::identity(); MAX_JOINTS];
        let mut posed = [Vec3::zeros(); MAX_JOINTS];
        let (local, posed) = (&mut local[..n], &mut posed[..n]);
        inverse(&self.own, frame, local)?;
        for _ in 0..CONVENTION_ROUNDS {
            kinematics::forward(&self.standard, local, frame[0], posed)?;
            inverse(&self.standard, posed, local)?;
            globals(&self.own, local, global);
            for k in 1..n {
                let parent = self.own.parent(k).unwrap_or(0);
                let observed = frame[k] - frame[parent];
                global[k] = kinematics::swing(global[k] * self.own.offset(k), observed) * global[k];
            }
            for k in (1..n).rev() {
                let parent = self.own.parent(k).unwrap_or(0);
                local[k] = global[parent].inverse() * global[k];
            }
            local[0] = global[0];
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod testing {
    //! A synthetic swing-like motion for tests that must run without the real data.
    use super::*;

    /// Frames of the synthetic motion.
    pub const FRAMES: usize = 90;
    /// Its rate.
    pub const RATE_HZ: f32 = 60.0;

    /// Every bone waving about its own axes with its own phase, the root drifting.
    pub fn wave(skeleton: &Skeleton) -> Motion {
        wave_frames(skeleton, FRAMES)
    }

    /// [`wave`] lasting `frames` frames at [`RATE_HZ`].
    pub fn wave_frames(skeleton: &Skeleton, frames: usize) -> Motion {
        let n = skeleton.len();
        let mut positions = vec![Vec3::zeros(); frames * n];
        let mut local = vec![Quat::identity(); n];
        for (f, out) in positions.chunks_exact_mut(n).enumerate() {
            let t = f as f32 / RATE_HZ;
            for (k, q) in local.iter_mut().enumerate() {
                let phase = k as f32 * 0.7;
                let axis = Vec3::new((phase).sin(), (2.0 * phase).cos(), 0.5);
                *q = Quat::from_scaled_axis(axis * 0.4 * (3.0 * t + phase).sin());
            }
            let root = Vec3::new(0.3 * t, 0.9 + 0.05 * (5.0 * t).sin(), 0.1 * t);
            kinematics::forward(skeleton, &local, root, out).unwrap();
        }
        motion(skeleton, RATE_HZ, positions)
    }
}

#[cfg(test)]
mod tests {
    use super::testing::wave;
    use super::*;
    use crate::bodies::{sample_character_with, Body, Variation};
    use crate::dataset::FORMATS;
    use posecoach_core::format::Format;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    const SAME_M: f32 = 1e-4;
    const ANALYTIC_M: f32 = 1e-3;

    fn largest_gap(a: &Motion, b: &Motion) -> f32 {
        assert_eq!(a.positions.len(), b.positions.len());
        a.positions
            .iter()
            .zip(&b.positions)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f32::max)
    }

    #[test]
    fn a_clip_on_its_own_character_reproduces_the_source() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for format in FORMATS {
            let character = sample_character_with(format, &Variation::FULL, true, &mut rng)
                .unwrap_or_else(|e| panic!("{format}: {e}"));
            let source = wave(&character.skeleton);
            let clip = Clip::from_motion("wave", &source).unwrap();
            let again = clip.on(&character).unwrap();
            let gap = largest_gap(&source, &again);
            assert!(gap <= SAME_M, "{format}: {gap} m");
            assert_eq!(again.names, source.names);
        }
    }

    #[test]
    fn re_resting_keeps_positions() {
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        for format in FORMATS {
            let character =
                sample_character_with(format, &Variation::FULL, false, &mut rng).unwrap();
            let source = wave(&character.skeleton);
            let rested = standard_rest(&source).unwrap();
            let clip = Clip::from_motion("wave", &rested).unwrap();
            let gap = largest_gap(&source, &clip.on_skeleton(&rested.skeleton).unwrap());
            assert!(gap <= SAME_M, "{format}: {gap} m");
            let standard = Skeleton::standard(format).unwrap();
            let mut a = vec![Vec3::zeros(); standard.len()];
            let mut b = a.clone();
            standard.rest_positions(&mut a);
            rested.skeleton.rest_positions(&mut b);
            let last = standard.len() - 1;
            let parent = standard.parent(last).unwrap();
            let arm = |p: &[Vec3]| p[last] - p[parent];
            let turn = (arm(&a).normalize() - arm(&b).normalize()).norm();
            assert!(turn < 1e-5, "{format}: {turn}");
        }
    }

    /// With the same rest directions (one body, scaled), the ground truth copies bone
    /// directions and scales the root by the leg ratio, as the analytic retargeter does: they
    /// agree on every joint whose whole chain from the root has counterparts in the source.
    /// They differ by design below a joint the source lacks (H36M's head top below CMU's neck,
    /// the canonical hands and club below the golf markers' wrists) and where a target bone
    /// spans several source bones (COCO's pelvis-to-thorax over Bandai's spine): the ground
    /// truth turns it with one source bone's full rotation (twist included), the analytic
    /// retargeter with the smallest rotation of the chord; there only bone lengths agree.
    #[test]
    fn ground_truth_equals_analytic_on_identical_rest_poses() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        for (from, onto) in [
            (Format::Cmu31, Format::Cmu31),
            (Format::H36m17, Format::H36m17),
            (Format::GolfMarkers, Format::GolfMarkers),
            (Format::Canonical, Format::Canonical),
            (Format::Cmu31, Format::H36m17),
            (Format::Bandai22, Format::Coco17),
            (Format::GolfMarkers, Format::Canonical),
        ] {
            let body = Body::sample(&Variation::FULL, &mut rng);
            let small = Character::new(body.clone(), from, true).unwrap();
            let large = Character::new(body.scaled(1.15), onto, true).unwrap();
            let source = wave(&small.skeleton);
            let clip = Clip::from_motion("wave", &source).unwrap();
            let truth = ground_truth(&clip, &large).unwrap();
            let analytic = source.retarget_analytic(&truth).unwrap();
            let matched = counterparts(&small.skeleton, &large.skeleton);
            let chained = |k: usize| {
                large
                    .skeleton
                    .ancestry(k)
                    .all(|a| same_bone(&small, &large, &matched, a))
            };
            let n = large.skeleton.len();
            let mut compared = 0;
            for k in (0..n).filter(|&k| chained(k)) {
                for f in 0..truth.frames() {
                    let gap = (truth.frame(f)[k] - analytic.frame(f)[k]).norm();
                    assert!(gap <= ANALYTIC_M, "{from} onto {onto}, joint {k}: {gap} m");
                }
                compared += 1;
            }
            // At least the pelvis, hips, knees and ankles.
            assert!(compared >= 7, "{from} onto {onto}: {compared} of {n}");
            for k in 1..n {
                let p = large.skeleton.parent(k).unwrap();
                let bone = (analytic.frame(9)[k] - analytic.frame(9)[p]).norm();
                let truth_bone = (truth.frame(9)[k] - truth.frame(9)[p]).norm();
                assert!((bone - truth_bone).abs() < SAME_M);
            }
        }
    }

    /// Whether target joint `k`'s bone is its counterpart's bone in the source: the target's
    /// parent is the source's, past source joints that sit on their parent (CMU's hip joints).
    fn same_bone(
        source: &Character,
        target: &Character,
        matched: &[Option<usize>],
        k: usize,
    ) -> bool {
        let (s, t) = (&source.skeleton, &target.skeleton);
        let (Some(mut c), Some(parent)) = (matched[k], t.parent(k)) else {
            return matched[k].is_some();
        };
        while let Some(p) = s.parent(c) {
            if Some(p) == matched[parent] {
                return true;
            }
            if s.offset(p).norm() > kinematics::MIN_BONE {
                return false;
            }
            c = p;
        }
        false
    }

    #[test]
    fn a_bodys_root_trajectory_is_the_same_in_every_format() {
        let mut rng = ChaCha8Rng::seed_from_u64(15);
        let source = sample_character_with(Format::Cmu31, &Variation::FULL, false, &mut rng);
        let clip = Clip::from_motion("wave", &wave(&source.unwrap().skeleton)).unwrap();
        let body = Body::sample(&Variation::FULL, &mut rng);
        let roots: Vec<Vec<Vec3>> = FORMATS
            .iter()
            .map(|&f| {
                let truth = ground_truth(&clip, &Character::new(body.clone(), f, false).unwrap());
                let truth = truth.unwrap();
                (0..truth.frames()).map(|i| truth.frame(i)[0]).collect()
            })
            .collect();
        for (format, root) in FORMATS.iter().zip(&roots) {
            let gap = root
                .iter()
                .zip(&roots[0])
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f32::max);
            assert!(gap < SAME_M, "{format}: {gap} m");
        }
    }

    #[test]
    fn rest_pose_differences_are_kept_not_copied() {
        let mut rng = ChaCha8Rng::seed_from_u64(14);
        let a = sample_character_with(Format::H36m17, &Variation::FULL, false, &mut rng).unwrap();
        let b = sample_character_with(Format::H36m17, &Variation::FULL, false, &mut rng).unwrap();
        let source = wave(&a.skeleton);
        let truth = ground_truth(&Clip::from_motion("wave", &source).unwrap(), &b).unwrap();
        // The angle between the two characters' forearms is the same in every frame: the rest
        // difference carried through the shared rotation.
        let forearm = |m: &Motion, f: usize| m.frame(f)[13] - m.frame(f)[12];
        let rest_angle = forearm(&source, 0).angle(&forearm(&truth, 0));
        assert!(rest_angle > 1e-3);
        for f in 1..source.frames() {
            let angle = forearm(&source, f).angle(&forearm(&truth, f));
            assert!((angle - rest_angle).abs() < 1e-3, "frame {f}");
        }
    }

    #[test]
    fn estimated_rotations_turn_each_own_rest_offset_onto_its_observed_bone() {
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        for format in FORMATS {
            let body = Body::sample(&Variation::FULL, &mut rng);
            let skeleton = Character::new(body, format, false).unwrap().skeleton;
            let motion = wave(&skeleton);
            let rotations = Rotations::new(&skeleton).unwrap();
            let mut estimated = vec![Quat::identity(); skeleton.len()];
            for f in 0..motion.frames() {
                let frame = motion.frame(f);
                rotations.globals(frame, &mut estimated).unwrap();
                for k in 1..skeleton.len() {
                    let parent = skeleton.parent(k).unwrap();
                    let bone = estimated[k] * skeleton.offset(k);
                    let gap = (bone - (frame[k] - frame[parent])).norm();
                    assert!(gap < SAME_M, "{format:?} frame {f} bone {k}: {gap}");
                }
            }
            assert!(rotations.globals(&[], &mut estimated).is_err());
        }
    }
}
