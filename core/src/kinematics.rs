//! Forward and inverse kinematics.
//!
//! Rotations are per bone: `local[k]` rotates the bone from `parent(k)` to `k` relative to its
//! parent bone's frame, so the global rotation is `G_k = G_parent(k) · local[k]` and
//! `p_k = p_parent(k) + G_k · s_k` with `s_k` the rest offset. `local[0]` is the root's
//! orientation (`G_0`), applied to every bone through the chain. Bone lengths therefore always
//! equal the skeleton's.
//!
//! ```
//! use posecoach_core::format::Format;
//! use posecoach_core::skeleton::Skeleton;
//! use posecoach_core::kinematics::{forward, inverse};
//! use posecoach_core::{Quat, Vec3};
//!
//! let skeleton = Skeleton::standard(Format::H36m17).unwrap();
//! let mut rest = [Vec3::zeros(); 17];
//! skeleton.rest_positions(&mut rest);
//! let mut local = [Quat::identity(); 17];
//! let root = inverse(&skeleton, &rest, &mut local).unwrap();
//! let mut again = [Vec3::zeros(); 17];
//! forward(&skeleton, &local, root, &mut again).unwrap();
//! assert!((again[13] - rest[13]).norm() < 1e-6);
//! ```

use crate::config::MAX_JOINTS;
use crate::skeleton::Skeleton;
use crate::{math, Quat, Vec3};
use nalgebra::Quaternion;

/// Bones shorter than this (metres) have no direction: they keep their parent's rotation.
pub const MIN_BONE: f32 = 1e-6;

/// A child bone turns its parent's twist only where its rest offset leaves the parent's axis by
/// more than this fraction of its length (0.06°): closer, its sideways part is rounding.
const MIN_TWIST_LEVER: f32 = 1e-3;

/// A slice has the wrong length for the skeleton.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LengthError {
    /// Joints the skeleton has.
    pub expected: usize,
    /// Length of the slice given.
    pub actual: usize,
}

impl core::fmt::Display for LengthError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "expected {} joints, got {}", self.expected, self.actual)
    }
}

impl core::error::Error for LengthError {}

/// Checks that `slice_len` can hold one value per joint of `skeleton`.
pub(crate) fn check_len(skeleton: &Skeleton, slice_len: usize) -> Result<(), LengthError> {
    if slice_len < skeleton.len() {
        return Err(LengthError {
            expected: skeleton.len(),
            actual: slice_len,
        });
    }
    Ok(())
}

/// Joint positions from per-bone local rotations and the root position.
///
/// # Errors
/// [`LengthError`] if `local` or `out` is shorter than the skeleton.
pub fn forward(
    skeleton: &Skeleton,
    local: &[Quat],
    root: Vec3,
    out: &mut [Vec3],
) -> Result<(), LengthError> {
    check_len(skeleton, local.len())?;
    check_len(skeleton, out.len())?;
    let mut global = [Quat::identity(); MAX_JOINTS];
    global[0] = local[0];
    out[0] = root;
    for k in 1..skeleton.len() {
        let p = skeleton.parent(k).unwrap_or(0);
        global[k] = compose(global[p], local[k]);
        out[k] = out[p] + global[k] * skeleton.offset(k);
    }
    Ok(())
}

/// Per-bone local rotations that reproduce `positions` through [`forward`]; returns the root
/// position.
///
/// Each bone takes the smallest rotation that turns its rest direction onto the observed one,
/// then the twist about itself that best aligns its child bones (least squares), so rotations
/// stay continuous and small. The root's orientation is fitted the same way from its longest
/// child bone and twisted by the others. Positions are reproduced exactly whenever their bone
/// lengths equal the skeleton's.
///
/// # Errors
/// [`LengthError`] if `positions` or `local` is shorter than the skeleton.
pub fn inverse(
    skeleton: &Skeleton,
    positions: &[Vec3],
    local: &mut [Quat],
) -> Result<Vec3, LengthError> {
    check_len(skeleton, positions.len())?;
    check_len(skeleton, local.len())?;
    let mut global = [Quat::identity(); MAX_JOINTS];
    let primary = (1..skeleton.len())
        .filter(|&c| skeleton.parent(c) == Some(0))
        .max_by(|&a, &b| {
            let (la, lb) = (
                math::norm(&skeleton.offset(a)),
                math::norm(&skeleton.offset(b)),
            );
            la.total_cmp(&lb)
        });
    global[0] = match primary {
        Some(c) => fit(
            skeleton,
            positions,
            0,
            Quat::identity(),
            skeleton.offset(c),
            positions[c] - positions[0],
        ),
        None => Quat::identity(),
    };
    local[0] = global[0];
    for k in 1..skeleton.len() {
        let p = skeleton.parent(k).unwrap_or(0);
        let rest = global[p] * skeleton.offset(k);
        let observed = positions[k] - positions[p];
        let fitted = fit(skeleton, positions, k, global[p], rest, observed);
        local[k] = compose(global[p].inverse(), fitted);
        // Carry the rotation on exactly as `forward` recomposes it, so rounding cannot drift
        // down long chains (a 1 m club at the end of the arm).
        global[k] = compose(global[p], local[k]);
    }
    Ok(positions[0])
}

/// `a · b`, renormalized: an unnormalized product's norm error would grow geometrically down a
/// chain of compositions.
fn compose(a: Quat, b: Quat) -> Quat {
    math::rotation(a.into_inner() * b.into_inner())
}

/// Rotates `base` by the swing taking `rest` onto `observed`, then twists it about `observed`
/// to align the rest offsets of joint `k`'s children with their observed bones.
fn fit(
    skeleton: &Skeleton,
    positions: &[Vec3],
    k: usize,
    base: Quat,
    rest: Vec3,
    observed: Vec3,
) -> Quat {
    let length = math::norm(&observed);
    if math::norm(&rest) < MIN_BONE || length < MIN_BONE {
        return base;
    }
    let swung = swing(rest, observed) * base;
    let axis = observed / length;
    let (mut sin, mut cos) = (0.0f32, 0.0f32);
    for c in (k + 1)..skeleton.len() {
        if skeleton.parent(c) != Some(k) {
            continue;
        }
        let perp = |v: Vec3| v - axis * axis.dot(&v);
        let offset = skeleton.offset(c);
        let predicted = perp(swung * offset);
        // A child at rest on the bone's axis says nothing of its twist: its sideways part is
        // rounding, and would choose the twist at random.
        if predicted.norm_squared() <= MIN_TWIST_LEVER * MIN_TWIST_LEVER * offset.norm_squared() {
            continue;
        }
        let actual = perp(positions[c] - positions[k]);
        sin += axis.dot(&predicted.cross(&actual));
        cos += predicted.dot(&actual);
    }
    if sin.abs() + cos.abs() < MIN_BONE * MIN_BONE {
        return swung;
    }
    let half = 0.5 * libm::atan2f(sin, cos);
    let (s, c) = crate::math::sin_cos(half);
    let twist = Quat::new_unchecked(Quaternion::new(c, axis.x * s, axis.y * s, axis.z * s));
    twist * swung
}

/// The smallest rotation taking the direction of `from` onto the direction of `to`.
///
/// Zero vectors give the identity. Opposite directions are handled by a half turn about an
/// axis perpendicular to `from`, which keeps the result accurate near 180°.
pub fn swing(from: Vec3, to: Vec3) -> Quat {
    let (Some(f), Some(t)) = (unit(from), unit(to)) else {
        return Quat::identity();
    };
    let d = f.dot(&t);
    if d >= 0.0 {
        let c = f.cross(&t);
        return math::rotation(Quaternion::new(1.0 + d, c.x, c.y, c.z));
    }
    // Half turn about an axis perpendicular to f (in the f-t plane's normal where defined),
    // then the well-conditioned swing from -f to t.
    let mut axis = f.cross(&t);
    if math::norm(&axis) < 1e-3 {
        axis = if f.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        }
        .cross(&f);
    }
    axis -= f * f.dot(&axis);
    let half_turn = match unit(axis) {
        Some(a) => Quat::new_unchecked(Quaternion::new(0.0, a.x, a.y, a.z)),
        None => return Quat::identity(),
    };
    swing(-f, t) * half_turn
}

fn unit(v: Vec3) -> Option<Vec3> {
    math::unit(v, MIN_BONE)
}

/// Random poses for property tests.
#[cfg(test)]
pub(crate) mod testing {
    use super::*;
    use nalgebra::Quaternion;
    use std::vec::Vec;

    /// Rotations from raw uniform draws in ±1, biased toward the identity so chains stay
    /// readable (a rotation of at most about 80° per bone).
    pub(crate) fn rotations(raw: &[[f32; 4]]) -> Vec<Quat> {
        raw.iter()
            .map(|a| Quat::new_normalize(Quaternion::new(a[0] + 1.5, a[1], a[2], a[3])))
            .collect()
    }

    /// Joint positions of `skeleton` posed by [`rotations`] of `raw` with the root at `root`.
    pub(crate) fn pose(skeleton: &Skeleton, raw: &[[f32; 4]], root: [f32; 3]) -> Vec<Vec3> {
        let mut out = std::vec![Vec3::zeros(); skeleton.len()];
        let local = rotations(&raw[..skeleton.len()]);
        forward(skeleton, &local, Vec3::from(root), &mut out).unwrap();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::Format;
    use proptest::prelude::*;

    const TOLERANCE_M: f32 = 1e-5;

    proptest! {
        #[test]
        fn swing_maps_from_onto_to(a in prop::array::uniform3(-1.0f32..1.0), b in prop::array::uniform3(-1.0f32..1.0)) {
            let (a, b) = (Vec3::from(a), Vec3::from(b));
            prop_assume!(a.norm() > 0.1 && b.norm() > 0.1);
            let r = swing(a, b) * a.normalize();
            prop_assert!((r - b.normalize()).norm() < 1e-5);
            let back = swing(a, -a) * a.normalize();
            prop_assert!((back + a.normalize()).norm() < 1e-5);
        }

        #[test]
        fn forward_of_inverse_reproduces_positions(
            format in prop::sample::select(Format::BUILT_IN.to_vec()),
            raw in prop::collection::vec(prop::array::uniform4(-1.0f32..1.0), MAX_JOINTS),
            root in prop::array::uniform3(-3.0f32..3.0),
        ) {
            let skeleton = Skeleton::standard(format).unwrap();
            let n = skeleton.len();
            let local = testing::rotations(&raw[..n]);
            let mut positions = [Vec3::zeros(); MAX_JOINTS];
            forward(&skeleton, &local, Vec3::from(root), &mut positions).unwrap();
            let mut fitted = [Quat::identity(); MAX_JOINTS];
            let fitted_root = inverse(&skeleton, &positions[..n], &mut fitted).unwrap();
            let mut again = [Vec3::zeros(); MAX_JOINTS];
            forward(&skeleton, &fitted[..n], fitted_root, &mut again).unwrap();
            for k in 0..n {
                prop_assert!((again[k] - positions[k]).norm() <= TOLERANCE_M, "{format} joint {k}: {}", (again[k] - positions[k]).norm());
            }
        }
    }

    #[test]
    fn inverse_of_rest_pose_is_nearly_identity() {
        let skeleton = Skeleton::standard(Format::Smpl24).unwrap();
        let mut rest = [Vec3::zeros(); 24];
        skeleton.rest_positions(&mut rest);
        let mut local = [Quat::identity(); 24];
        inverse(&skeleton, &rest, &mut local).unwrap();
        for q in local {
            assert!(q.angle() < 1e-3, "{}", q.angle());
        }
    }

    #[test]
    fn a_child_on_its_parents_axis_does_not_twist_it() {
        // Every bone of every format whose only child lies on its axis at rest: with the whole
        // body turned and that child bent about 29 degrees (0.5 rad), the bone itself keeps
        // its rest rotation (its children cannot tell its twist; rounding must not choose one).
        let mut checked = 0;
        // Under Miri, which takes seconds over each bone, H36M's one such bone alone (the
        // proptest above poses every format's).
        let formats: &[Format] = if cfg!(miri) {
            &[Format::H36m17]
        } else {
            &Format::BUILT_IN
        };
        for &format in formats {
            let skeleton = Skeleton::standard(format).unwrap();
            let n = skeleton.len();
            for k in 1..n {
                let children: std::vec::Vec<usize> = (k + 1..n)
                    .filter(|&c| skeleton.parent(c) == Some(k))
                    .collect();
                let [c] = children[..] else { continue };
                let (bone, child) = (skeleton.offset(k), skeleton.offset(c));
                if bone.norm() < 1e-3 || bone.cross(&child).norm() > 1e-6 * child.norm() {
                    continue;
                }
                let mut local = [Quat::identity(); MAX_JOINTS];
                local[0] = Quat::from_euler_angles(0.3, 1.1, -0.4);
                let across = bone.cross(&Vec3::new(0.3, 0.5, 0.7)).normalize();
                local[c] = Quat::from_axis_angle(&nalgebra::Unit::new_normalize(across), 0.5);
                let mut posed = [Vec3::zeros(); MAX_JOINTS];
                forward(&skeleton, &local[..n], Vec3::zeros(), &mut posed[..n]).unwrap();
                let mut found = [Quat::identity(); MAX_JOINTS];
                inverse(&skeleton, &posed[..n], &mut found[..n]).unwrap();
                assert!(
                    found[k].angle() < 1e-3,
                    "{format} joint {k}: {}",
                    found[k].angle()
                );
                checked += 1;
            }
        }
        assert!(checked > 0, "no format has such a bone");
    }

    #[test]
    fn short_slices_are_errors() {
        let skeleton = Skeleton::standard(Format::Coco17).unwrap();
        let mut out = [Vec3::zeros(); 3];
        assert_eq!(
            forward(&skeleton, &[Quat::identity(); 15], Vec3::zeros(), &mut out),
            Err(LengthError {
                expected: 15,
                actual: 3
            })
        );
    }
}
