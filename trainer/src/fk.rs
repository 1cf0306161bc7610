//! Differentiable forward kinematics: [`posecoach_core::kinematics::forward`] on batched,
//! padded tensors.
//!
//! Quaternions are `(w, x, y, z)` in the last dimension, joint-major: `[B, J, T, 4]`, so that
//! picking every joint's ancestor is one product with a `[B, J, J]` one-hot matrix. The root
//! carries no rotation (every bone out of it has its own, which positions cannot tell apart
//! from a root orientation), so `G_0 = I`, `G_k = G_parent(k) · q_k` and
//! `p_k = p_0 + Σ_a G_a · s_a` over the joints `a` of `k`'s chain from the root
//! ([`Skeletons::chains`]). Global rotations come from pointer doubling
//! ([`Skeletons::ancestors`]): after pass `i`, `P_k` is the product of the `2^i` bones ending at
//! `k`, and `P_k ← P_{2^i-th ancestor} · P_k` doubles that, so a skeleton `D` bones deep
//! takes `⌈log2 D⌉` passes. Products of quaternions and rotations of vectors are each a
//! single product with a constant table, over the outer product of their operands: few,
//! large tensor operations rather than many narrow ones.

use crate::skeletons::Skeletons;
use burn::prelude::{Device, Tensor, TensorData};

/// The identity rotation.
pub const IDENTITY: [f32; 4] = [1.0, 0.0, 0.0, 0.0];
/// Added to a squared norm before its square root, so that a zero quaternion stays finite.
const NORM_EPSILON: f32 = 1e-12;

/// Unit quaternions from raw ones (last dimension).
pub fn normalize(raw: Tensor<4>) -> Tensor<4> {
    let norm = raw
        .clone()
        .square()
        .sum_dim(3)
        .add_scalar(NORM_EPSILON)
        .sqrt();
    raw / norm
}

/// Joint positions `[B, T, J, 3]` from unit rotations `[B, J, T, 4]` of the bones into each
/// joint and root positions `[B, T, 3]`, on `target`'s skeletons (in its units: heights).
/// The root's rotation and padded joints' are ignored; padded joints sit at the root.
pub fn forward(rotations: Tensor<4>, root: Tensor<3>, target: &Skeletons) -> Tensor<4> {
    let [b, j, t, _] = rotations.dims();
    let device = rotations.device();
    let bones = target.bones.clone().reshape([b, j, 1, 1]);
    let identity = Tensor::<1>::from_floats(IDENTITY, &device).reshape([1, 1, 1, 4]);
    let mut global = rotations * bones.clone() + identity * bones.neg().add_scalar(1.0);
    for up in &target.ancestors {
        let above = up
            .clone()
            .matmul(global.clone().reshape([b, j, t * 4]))
            .reshape([b, j, t, 4]);
        global = multiply(above, global);
    }
    let offsets = target.offsets.clone().reshape([b, j, 1, 3]);
    let rotated = rotate(global, offsets).reshape([b, j, t * 3]);
    let positions = target.chains.clone().matmul(rotated).reshape([b, j, t, 3]);
    positions.swap_dims(1, 2) + root.reshape([b, t, 1, 3])
}

/// `[N, 16]` outer products `a_i · b_j` (at `4i + j`) of quaternions `[B, J, T, 4]`.
fn outer(a: Tensor<4>, b: Tensor<4>) -> Tensor<2> {
    let [n, j, t, _] = a.dims();
    let product = a.reshape([n, j, t, 4, 1]) * b.reshape([n, j, t, 1, 4]);
    product.reshape([n * j * t, 16])
}

/// Rotations relative to the parent bone from global ones (`[B, J, T, 4]`, unit):
/// `q_k = Ḡ_parent(k) · G_k`, the inverse of what [`forward`] composes.
pub fn local(global: Tensor<4>, target: &Skeletons) -> Tensor<4> {
    let [b, j, t, _] = global.dims();
    let conjugate = Tensor::<1>::from_floats([1.0, -1.0, -1.0, -1.0], &global.device());
    let parents = target.ancestors[0]
        .clone()
        .matmul(global.clone().reshape([b, j, t * 4]))
        .reshape([b, j, t, 4]);
    multiply(parents * conjugate.reshape([1, 1, 1, 4]), global)
}

/// Hamilton products `a · b` of quaternions `[B, J, T, 4]`.
pub fn multiply(a: Tensor<4>, b: Tensor<4>) -> Tensor<4> {
    let dims = a.dims();
    let table = table(&a.device(), 4, |i, j| hamilton(basis(i), basis(j)).to_vec());
    outer(a, b).matmul(table).reshape(dims)
}

/// Vectors `v` (`[B, J, 1, 3]`, or `[B, J, T, 3]`) rotated by unit quaternions
/// `q` (`[B, J, T, 4]`): `q · v · q̄` as the matrix `R(q) = Σ q_i q_j M_ij`.
fn rotate(q: Tensor<4>, v: Tensor<4>) -> Tensor<4> {
    let [b, j, t, _] = q.dims();
    let [_, _, tv, _] = v.dims();
    let table = table(&q.device(), 9, |i, k| {
        let sandwich = |c: usize| {
            let mut axis = [0.0; 4];
            axis[c + 1] = 1.0;
            hamilton(hamilton(basis(i), axis), conjugate(basis(k)))
        };
        let columns = [0, 1, 2].map(sandwich);
        (0..9).map(|rc| columns[rc % 3][rc / 3 + 1]).collect()
    });
    let matrices = outer(q.clone(), q).matmul(table).reshape([b, j, t, 3, 3]);
    (matrices * v.reshape([b, j, tv, 1, 3]))
        .sum_dim(4)
        .reshape([b, j, t, 3])
}

/// The `[16, width]` table whose row `4i + j` is `entry(i, j)`.
fn table(device: &Device, width: usize, entry: impl Fn(usize, usize) -> Vec<f32>) -> Tensor<2> {
    let rows: Vec<f32> = (0..16).flat_map(|r| entry(r / 4, r % 4)).collect();
    Tensor::from_data(TensorData::new(rows, [16, width]), device)
}

/// Unit quaternion `i` of the basis `(1, i, j, k)`.
fn basis(i: usize) -> [f32; 4] {
    let mut e = [0.0; 4];
    e[i] = 1.0;
    e
}

fn conjugate([w, x, y, z]: [f32; 4]) -> [f32; 4] {
    [w, -x, -y, -z]
}

/// Hamilton product of two quaternions.
fn hamilton([aw, ax, ay, az]: [f32; 4], [bw, bx, by, bz]: [f32; 4]) -> [f32; 4] {
    [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::testing::character;
    use crate::skeletons::MAX_JOINTS;
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
        let target = Skeletons::padded(&skeletons, MAX_JOINTS, &device).unwrap();
        let b = skeletons.len();
        let mut raw = vec![0.0f32; b * MAX_JOINTS * FRAMES * 4];
        rng.fill(&mut raw[..]);
        let raw: Vec<f32> = raw.iter().map(|v| 2.0 * v - 1.0).collect();
        let roots: Vec<f32> = (0..b * FRAMES * 3)
            .map(|_| rng.random_range(-1.0..1.0))
            .collect();
        let rotations = normalize(Tensor::from_data(
            TensorData::new(raw.clone(), [b, MAX_JOINTS, FRAMES, 4]),
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
                            let q = ((i * MAX_JOINTS + k) * FRAMES + f) * 4;
                            let r = &raw[q..q + 4];
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
