//! Differentiable forward kinematics: [`posecoach_core::kinematics::forward`] on batched,
//! padded tensors.
//!
//! Quaternions are `(w, x, y, z)` in the last dimension. The root carries no rotation (every
//! bone out of it has its own, which positions cannot tell apart from a root orientation), so
//! `G_0 = I`, `G_k = G_parent(k) · q_k` and `p_k = p_0 + Σ_a G_a · s_a` over the joints `a`
//! of `k`'s chain from the root ([`Target::chains`]). Global rotations are found in
//! [`Target::depth`] passes of `G ← G[parent] · q` over all joints at once: after pass `d`,
//! every joint at most `d` bones from the root is exact, whatever its tree.

use crate::features::Target;
use burn::prelude::Tensor;

/// The identity rotation.
pub const IDENTITY: [f32; 4] = [1.0, 0.0, 0.0, 0.0];
/// Added to a squared norm before its square root, so that a zero quaternion stays finite.
const NORM_EPSILON: f32 = 1e-12;

/// Unit quaternions `[B, T, J, 4]` from raw ones.
pub fn normalize(raw: Tensor<4>) -> Tensor<4> {
    let norm = raw
        .clone()
        .square()
        .sum_dim(3)
        .add_scalar(NORM_EPSILON)
        .sqrt();
    raw / norm
}

/// Joint positions `[B, T, J, 3]` from unit rotations `[B, T, J, 4]` of the bones into each
/// joint and root positions `[B, T, 3]`, on `target`'s skeletons (in its units: heights).
/// The root's rotation and padded joints' are ignored; padded joints sit at the root.
pub fn forward(rotations: Tensor<4>, root: Tensor<3>, target: &Target) -> Tensor<4> {
    let [b, t, j, _] = rotations.dims();
    let device = rotations.device();
    let bones = target.bones.clone().reshape([b, 1, j, 1]);
    let identity = Tensor::<1>::from_floats(IDENTITY, &device).reshape([1, 1, 1, 4]);
    let local = rotations * bones.clone() + identity.clone() * bones.neg().add_scalar(1.0);
    let parents = target
        .parents
        .clone()
        .reshape([b, 1, j, 1])
        .expand([b, t, j, 4]);
    let mut global = identity.expand([b, t, j, 4]);
    for _ in 0..target.depth {
        global = multiply(global.gather(2, parents.clone()), local.clone());
    }
    let offsets = target
        .offsets
        .clone()
        .reshape([b, 1, j, 3])
        .expand([b, t, j, 3]);
    let chains = target
        .chains
        .clone()
        .reshape([b, 1, j, j])
        .expand([b, t, j, j]);
    chains.matmul(rotate(global, offsets)) + root.reshape([b, t, 1, 3])
}

/// The `n` components of the last dimension.
fn parts<const N: usize>(q: Tensor<4>) -> [Tensor<4>; N] {
    core::array::from_fn(|i| q.clone().narrow(3, i, 1))
}

/// Hamilton product `a · b`.
fn multiply(a: Tensor<4>, b: Tensor<4>) -> Tensor<4> {
    let [aw, ax, ay, az] = parts(a);
    let [bw, bx, by, bz] = parts(b);
    let m = |x: &Tensor<4>, y: &Tensor<4>| x.clone() * y.clone();
    Tensor::cat(
        vec![
            m(&aw, &bw) - m(&ax, &bx) - m(&ay, &by) - m(&az, &bz),
            m(&aw, &bx) + m(&ax, &bw) + m(&ay, &bz) - m(&az, &by),
            m(&aw, &by) - m(&ax, &bz) + m(&ay, &bw) + m(&az, &bx),
            m(&aw, &bz) + m(&ax, &by) - m(&ay, &bx) + m(&az, &bw),
        ],
        3,
    )
}

/// `a × b` of 3-vectors given as components.
fn cross(a: &[Tensor<4>; 3], b: &[Tensor<4>; 3]) -> [Tensor<4>; 3] {
    let m = |x: &Tensor<4>, y: &Tensor<4>| x.clone() * y.clone();
    [
        m(&a[1], &b[2]) - m(&a[2], &b[1]),
        m(&a[2], &b[0]) - m(&a[0], &b[2]),
        m(&a[0], &b[1]) - m(&a[1], &b[0]),
    ]
}

/// Vectors `[.., 3]` rotated by unit quaternions `[.., 4]`: `v + w·t + u × t` with
/// `t = 2 u × v`.
fn rotate(q: Tensor<4>, v: Tensor<4>) -> Tensor<4> {
    let [w, x, y, z] = parts(q);
    let u = [x, y, z];
    let v: [Tensor<4>; 3] = parts(v);
    let t = cross(&u, &v).map(|c| c.mul_scalar(2.0));
    let ut = cross(&u, &t);
    let [v, t, ut] = [v, t, ut].map(|c| Tensor::cat(c.to_vec(), 3));
    v + w * t + ut
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::testing::character;
    use crate::features::MAX_JOINTS;
    use burn::prelude::{Device, TensorData};
    use posecoach_core::format::Format;
    use posecoach_core::kinematics;
    use posecoach_core::{Quat, Vec3};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const FRAMES: usize = 3;
    const TOLERANCE_M: f32 = 1e-5;
    const FORMATS: [Format; 3] = [Format::Cmu31, Format::H36m17, Format::GolfMarkers];

    #[test]
    fn positions_match_the_cores_forward_kinematics() {
        let device = Device::flex();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let characters: Vec<_> = FORMATS
            .iter()
            .enumerate()
            .map(|(i, &f)| character(f, i as u64))
            .collect();
        let skeletons: Vec<_> = characters.iter().map(|c| &c.skeleton).collect();
        let target = Target::new(&skeletons, MAX_JOINTS, &device).unwrap();
        let b = skeletons.len();
        let mut raw = vec![0.0f32; b * FRAMES * MAX_JOINTS * 4];
        rng.fill(&mut raw[..]);
        let raw: Vec<f32> = raw.iter().map(|v| 2.0 * v - 1.0).collect();
        let roots: Vec<f32> = (0..b * FRAMES * 3)
            .map(|_| rng.random_range(-1.0..1.0))
            .collect();
        let rotations = normalize(Tensor::from_data(
            TensorData::new(raw.clone(), [b, FRAMES, MAX_JOINTS, 4]),
            &device,
        ));
        let root = Tensor::from_data(TensorData::new(roots.clone(), [b, FRAMES, 3]), &device);
        let positions: Vec<f32> = forward(rotations, root, &target)
            .to_data()
            .try_to_vec::<f32>()
            .unwrap();
        for (i, skeleton) in skeletons.iter().enumerate() {
            let h = skeleton.height();
            for f in 0..FRAMES {
                let at = |k: usize| (i * FRAMES + f) * MAX_JOINTS + k;
                let local: Vec<Quat> = (0..skeleton.len())
                    .map(|k| match k {
                        0 => Quat::identity(),
                        k => {
                            let r = &raw[at(k) * 4..at(k) * 4 + 4];
                            Quat::new_normalize(nalgebra::Quaternion::new(r[0], r[1], r[2], r[3]))
                        }
                    })
                    .collect();
                let r = &roots[(i * FRAMES + f) * 3..][..3];
                let mut expected = vec![Vec3::zeros(); skeleton.len()];
                let root = Vec3::new(r[0], r[1], r[2]) * h;
                kinematics::forward(skeleton, &local, root, &mut expected).unwrap();
                for (k, e) in expected.iter().enumerate() {
                    let p = &positions[at(k) * 3..at(k) * 3 + 3];
                    let got = Vec3::new(p[0], p[1], p[2]) * h;
                    let gap = (got - e).norm();
                    assert!(gap <= TOLERANCE_M, "{} joint {k}: {gap} m", FORMATS[i]);
                }
            }
        }
    }
}
