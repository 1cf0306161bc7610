//! The training losses, on positions in heights ([`crate::features`]).
//!
//! | loss | compares | weight |
//! | --- | --- | --- |
//! | [`Reconstruction`] (VPC eq. 10) | a motion retargeted onto its own skeleton with itself | 1 |
//! | [`cycle`] (eq. 13 + 14) | `A → B → A` with `A`, and the motion features of `A` and `A → B` | 2.5 |
//! | [`effectors`] (eq. 12) | end-effector velocities of `A → B` and `A`, contacts weighed up | 50 |
//! | adversarial (LSGAN, [`crate::discriminator`]) | `A → B` against real motions | 1 |
//! | [`joint_distances`] (SMT) | row-normalized distance matrices of `A → B` and `A` | 10 |
//! | [`geometry`] (SMT) | arm joints of `A → B` inside the torso capsule | 1000 |
//!
//! Distillation ([`distillation`]) replaces them all: a smaller network learns to output what
//! the trained teacher outputs.
//!
//! Each is a mean, so batch size and window length leave the balance alone. The last two
//! are not in the papers' tables; their weights put them at the size of the reconstruction
//! loss on an untrained teacher.

use crate::model::Retargeted;
use crate::skeletons::Skeletons;
use burn::prelude::{Device, Tensor};
use burn::tensor::activation::relu;
use posecoach_core::joint::Joint;
use posecoach_core::joint::JOINT_COUNT;

/// Weight of the root-relative term of the reconstruction.
pub const ROOT_RELATIVE_WEIGHT: f32 = 100.0;
/// Weight of the root trajectory term of the reconstruction.
pub const TRAJECTORY_WEIGHT: f32 = 200.0;
/// Weight of the cycle loss.
pub const CYCLE_WEIGHT: f32 = 2.5;
/// Weight of the end-effector velocity loss.
pub const EFFECTOR_WEIGHT: f32 = 50.0;
/// Weight of the generator's adversarial loss.
pub const ADVERSARIAL_WEIGHT: f32 = 1.0;
/// Weight of the joint-distance-matrix loss.
pub const JOINT_DISTANCE_WEIGHT: f32 = 10.0;
/// Weight of the geometry loss.
pub const GEOMETRY_WEIGHT: f32 = 1000.0;
/// An end effector is in contact while it moves less than this (heights per frame)...
pub const CONTACT_SPEED: f32 = 0.005;
/// ...and its velocity error then counts this many times more.
pub const CONTACT_FACTOR: f32 = 5.0;
/// Rows of the distance matrix that count this many times more: golf is in the arms.
pub const ARM_ROW_FACTOR: f32 = 4.0;
/// The torso capsule's radius, as a fraction of the rest shoulder width.
pub const TORSO_RADIUS: f32 = 0.25;
/// Added under square roots and denominators.
const EPSILON: f32 = 1e-8;

/// The joints whose distance-matrix rows count [`ARM_ROW_FACTOR`] times.
const ARM_JOINTS: [Joint; 6] = [
    Joint::LeftElbow,
    Joint::LeftWrist,
    Joint::LeftHand,
    Joint::RightElbow,
    Joint::RightWrist,
    Joint::RightHand,
];

/// Which of the losses beyond the reconstruction are on (all by default): the ablation flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Switches {
    /// The cycle loss.
    pub cycle: bool,
    /// The end-effector velocity loss.
    pub effectors: bool,
    /// The adversarial loss and its discriminator.
    pub adversarial: bool,
    /// The joint-distance-matrix loss.
    pub joint_distances: bool,
    /// The geometry loss.
    pub geometry: bool,
}

impl Switches {
    /// Every loss on.
    pub const ALL: Switches = Switches {
        cycle: true,
        effectors: true,
        adversarial: true,
        joint_distances: true,
        geometry: true,
    };
}

impl Default for Switches {
    fn default() -> Self {
        Switches::ALL
    }
}

/// The terms of the reconstruction loss, unweighted.
#[derive(Clone, Debug)]
pub struct Reconstruction {
    /// Mean squared error of positions relative to their parent.
    pub parent: Tensor<1>,
    /// Mean squared error of positions relative to the root.
    pub root_relative: Tensor<1>,
    /// Mean squared error of the root trajectory.
    pub trajectory: Tensor<1>,
}

impl Reconstruction {
    /// The terms for `predicted` against `truth`, both `[B, T, J, 3]` on `skeletons`: squared
    /// errors summed over X, Y, Z and averaged over each window's frames and bones (the
    /// trajectory over its frames), then over windows. In heights, which is the paper's `/h²` on the last two terms; the first is
    /// divided by `h²` as well, so that all three weigh the same on tall and short characters.
    pub fn new(predicted: Tensor<4>, truth: Tensor<4>, skeletons: &Skeletons) -> Reconstruction {
        let [b, _, j, _] = predicted.dims();
        let device = predicted.device();
        let (windows, joints) = (Tensor::ones([b], &device), Tensor::ones([b, j], &device));
        Reconstruction::masked(predicted, truth, skeletons, windows, joints)
    }

    /// [`Reconstruction::new`] over the windows where `windows` (`[B]`) is 1 and, of their
    /// bones, those where `joints` (`[B, J]`) is 1. Each window's mean weighs the same and a
    /// window not counted adds zero, so the means of a batch's parts, weighted by their
    /// windows, add up to the whole batch's.
    pub fn masked(
        predicted: Tensor<4>,
        truth: Tensor<4>,
        skeletons: &Skeletons,
        windows: Tensor<1>,
        joints: Tensor<2>,
    ) -> Reconstruction {
        let [b, t, j, _] = predicted.dims();
        let bones = (skeletons.bones.clone() * joints).reshape([b, 1, j, 1]);
        let samples = bones.clone().sum_dim(2).reshape([b]).mul_scalar(t as f32);
        let weight = (windows.clone() / samples.add_scalar(EPSILON)).div_scalar(b as f32);
        let per_window = |x: Tensor<4>| x.sum_dim(3).sum_dim(2).sum_dim(1).reshape([b]);
        let over_bones = |p: Tensor<4>, q: Tensor<4>| {
            (per_window((p - q).square() * bones.clone()) * weight.clone()).sum()
        };
        let from_root = |p: Tensor<4>| p.clone() - p.narrow(2, 0, 1);
        let root = |p: Tensor<4>| p.narrow(2, 0, 1);
        let trajectory = per_window((root(predicted.clone()) - root(truth.clone())).square());
        Reconstruction {
            parent: over_bones(
                skeletons.from_parent(predicted.clone()),
                skeletons.from_parent(truth.clone()),
            ),
            root_relative: over_bones(from_root(predicted), from_root(truth)),
            trajectory: (trajectory * windows).sum().div_scalar((b * t) as f32),
        }
    }

    /// The weighted sum.
    pub fn total(&self) -> Tensor<1> {
        self.parent.clone()
            + self.root_relative.clone().mul_scalar(ROOT_RELATIVE_WEIGHT)
            + self.trajectory.clone().mul_scalar(TRAJECTORY_WEIGHT)
    }
}

/// The cycle loss over the windows where `windows` (`[B]`) is 1 (each window's mean weighing
/// the same, the others adding zero): `back` (`A → B → A`) reconstructs `source` (`A`,
/// `[B, T, J, 3]` on `skeletons`), and the motion features of `A → B` (`back.features`)
/// equal those of `A` (`forth.features`) in L1.
pub fn cycle(
    forth: &Retargeted,
    back: &Retargeted,
    source: Tensor<4>,
    skeletons: &Skeletons,
    windows: Tensor<1>,
) -> Tensor<1> {
    let [b, channels, t] = forth.features.dims();
    let joints = Tensor::ones(skeletons.bones.dims(), &source.device());
    let positions = Reconstruction::masked(
        back.positions.clone(),
        source,
        skeletons,
        windows.clone(),
        joints,
    )
    .total();
    let features = ((forth.features.clone() - back.features.clone()).abs()
        * windows.reshape([b, 1, 1]))
    .sum()
    .div_scalar((b * channels * t) as f32);
    positions + features
}

/// The end-effector velocity loss: per frame, in heights, the velocities of `predicted`'s
/// end effectors (on `target`) against `source`'s (on `skeletons`); [`CONTACT_FACTOR`] times
/// where the source's effector is in contact.
pub fn effectors(
    predicted: Tensor<4>,
    target: &Skeletons,
    source: Tensor<4>,
    skeletons: &Skeletons,
) -> Tensor<1> {
    let velocity = |x: Tensor<4>| {
        let t = x.dims()[1];
        x.clone().narrow(1, 1, t - 1) - x.narrow(1, 0, t - 1)
    };
    let predicted = velocity(Skeletons::select(&target.effectors, predicted));
    let source = velocity(Skeletons::select(&skeletons.effectors, source));
    let speed = source.clone().square().sum_dim(3).sqrt();
    let contact = speed.lower_elem(CONTACT_SPEED).float();
    let weight = contact.mul_scalar(CONTACT_FACTOR - 1.0).add_scalar(1.0);
    ((predicted - source).square().sum_dim(3) * weight).mean()
}

/// The joint-distance-matrix loss: over the canonical joints both sides have, each frame's
/// matrix of pairwise distances, each row divided by its sum (scale-free), of `predicted`
/// (on `target`) against `source` (on `skeletons`); mean absolute difference, the arm rows
/// [`ARM_ROW_FACTOR`] times.
pub fn joint_distances(
    predicted: Tensor<4>,
    target: &Skeletons,
    source: Tensor<4>,
    skeletons: &Skeletons,
) -> Tensor<1> {
    let b = predicted.dims()[0];
    let device = predicted.device();
    let c = JOINT_COUNT;
    let both = target.present.clone() * skeletons.present.clone();
    let pairs = both.clone().reshape([b, 1, c, 1]) * both.reshape([b, 1, 1, c]);
    let normalized = |x: Tensor<4>, on: &Skeletons| {
        let q = Skeletons::select(&on.canonical, x);
        let [b, t, c, _] = q.dims();
        let gaps = q.clone().reshape([b, t, c, 1, 3]) - q.reshape([b, t, 1, c, 3]);
        let distances = gaps
            .square()
            .sum_dim(4)
            .add_scalar(EPSILON)
            .sqrt()
            .reshape([b, t, c, c])
            * pairs.clone();
        let sums = distances.clone().sum_dim(3).add_scalar(EPSILON);
        distances / sums
    };
    let rows = arm_rows(&device);
    let difference = (normalized(predicted, target) - normalized(source, skeletons)).abs();
    let t = difference.dims()[1];
    let weight = (pairs * rows.clone()).sum().mul_scalar(t as f32);
    (difference * rows).sum() / weight.add_scalar(EPSILON)
}

/// `[1, 1, C, 1]` the weight of each distance-matrix row.
fn arm_rows(device: &Device) -> Tensor<4> {
    let rows = Joint::ALL.map(|j| match ARM_JOINTS.contains(&j) {
        true => ARM_ROW_FACTOR,
        false => 1.0,
    });
    Tensor::<1>::from_floats(rows, device).reshape([1, 1, JOINT_COUNT, 1])
}

/// The geometry loss: the torso is a capsule from the hips' midpoint to the shoulders'
/// midpoint, [`TORSO_RADIUS`] rest shoulder widths around; the squared depth by which the
/// elbows, wrists and hands of `predicted` (on `target`) enter it, averaged over the joints
/// the skeletons have and frames.
pub fn geometry(predicted: Tensor<4>, target: &Skeletons) -> Tensor<1> {
    let [b, t, _, _] = predicted.dims();
    let q = Skeletons::select(&target.canonical, predicted);
    let joint = |j: Joint| q.clone().narrow(2, j as usize, 1);
    let middle = |a: Joint, b: Joint| (joint(a) + joint(b)).mul_scalar(0.5);
    let bottom = middle(Joint::LeftHip, Joint::RightHip);
    let axis = middle(Joint::LeftShoulder, Joint::RightShoulder) - bottom.clone();
    let rest = target
        .canonical
        .clone()
        .matmul(target.rest.clone())
        .reshape([b, 1, JOINT_COUNT, 3]);
    let width = (rest.clone().narrow(2, Joint::LeftShoulder as usize, 1)
        - rest.narrow(2, Joint::RightShoulder as usize, 1))
    .square()
    .sum_dim(3)
    .sqrt();
    let radius = width.mul_scalar(TORSO_RADIUS);
    let arms = Tensor::cat(ARM_JOINTS.map(joint).to_vec(), 2);
    let present = Tensor::cat(
        ARM_JOINTS
            .map(|j| target.present.clone().narrow(1, j as usize, 1))
            .to_vec(),
        1,
    )
    .reshape([b, 1, ARM_JOINTS.len(), 1]);
    let from_bottom = arms - bottom;
    let along = (from_bottom.clone() * axis.clone()).sum_dim(3)
        / axis.clone().square().sum_dim(3).add_scalar(EPSILON);
    let along = along.clamp(0.0, 1.0);
    let distance = (from_bottom - axis * along)
        .square()
        .sum_dim(3)
        .add_scalar(EPSILON)
        .sqrt();
    let depth = relu(radius - distance) * present.clone();
    depth.square().sum() / present.sum().mul_scalar(t as f32).add_scalar(EPSILON)
}

/// Distillation: the mean squared distance, in target heights, between the distilled network's
/// joint positions and the teacher's (both `[B, T, J, 3]`; padded joints are zero in both).
pub fn distillation(distilled: Tensor<4>, teacher: Tensor<4>) -> Tensor<1> {
    (distilled - teacher).square().mean()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::testing::character;
    use crate::features::testing::window;
    use crate::features::{Batch, WINDOW};
    use burn::prelude::TensorData;
    use posecoach_core::format::Format;

    fn value(t: Tensor<1>) -> f32 {
        t.into_scalar::<f32>()
    }

    fn batch(format: Format) -> Batch {
        let skeleton = character(format, 4).skeleton;
        Batch::reconstruction(&[window(&skeleton)], &Device::flex()).unwrap()
    }

    #[test]
    fn a_motion_against_itself_costs_nothing_and_a_change_costs() {
        let b = batch(Format::Cmu31);
        let p = b.positions.clone();
        let s = &b.source;
        assert_eq!(
            value(Reconstruction::new(p.clone(), p.clone(), s).total()),
            0.0
        );
        assert_eq!(value(effectors(p.clone(), s, p.clone(), s)), 0.0);
        assert!(value(joint_distances(p.clone(), s, p.clone(), s)) < 1e-6);
        let moved = p.clone() * p.clone().add_scalar(1.0);
        assert!(value(Reconstruction::new(moved.clone(), p.clone(), s).total()) > 0.0);
        assert!(value(effectors(moved.clone(), s, p.clone(), s)) > 0.0);
        assert!(value(joint_distances(moved, s, p, s)) > 1e-4);
    }

    #[test]
    fn a_reconstruction_counts_only_the_windows_it_is_given() {
        let b = batch(Format::H36m17);
        let p = b.positions.clone();
        let moved = p.clone() * p.clone().add_scalar(1.0);
        let two = |x: Tensor<4>| Tensor::cat(vec![x.clone(), x], 0);
        let skeletons = Batch::reconstruction(
            &[
                window(&b.source.skeletons[0]),
                window(&b.source.skeletons[0]),
            ],
            &Device::flex(),
        )
        .unwrap()
        .source;
        let both = Tensor::cat(vec![moved.clone(), p.clone()], 0);
        let weights = |w: [f32; 2]| Tensor::<1>::from_floats(w, &Device::flex());
        let all = Tensor::ones(skeletons.bones.dims(), &Device::flex());
        let loss = |w| {
            let r =
                Reconstruction::masked(both.clone(), two(p.clone()), &skeletons, w, all.clone());
            value(r.total())
        };
        let alone = value(Reconstruction::new(moved, p.clone(), &b.source).total());
        assert_eq!(loss(weights([0.0, 1.0])), 0.0);
        assert!((loss(weights([1.0, 0.0])) - 0.5 * alone).abs() <= 1e-5 * alone);
        assert!((loss(weights([1.0, 1.0])) - 0.5 * alone).abs() <= 1e-5 * alone);
    }

    #[test]
    fn arms_inside_the_torso_cost_and_a_t_pose_does_not() {
        let b = batch(Format::H36m17);
        let skeleton = &b.source.skeletons[0];
        let n = skeleton.len();
        let rest: Vec<f32> = b.source.rest.clone().into_data().try_to_vec().unwrap();
        let t_pose = Tensor::<1>::from_floats(rest.as_slice(), &Device::flex())
            .reshape([1, 1, n, 3])
            .expand([1, WINDOW, n, 3]);
        assert_eq!(value(geometry(t_pose.clone(), &b.source)), 0.0);
        let wrist = skeleton.index_of(Joint::LeftWrist).unwrap();
        let spine = skeleton.index_of(Joint::Spine).unwrap();
        let mut inside = rest.clone();
        inside.copy_within(spine * 3..spine * 3 + 3, wrist * 3);
        let inside = Tensor::<4>::from_data(TensorData::new(inside, [1, 1, n, 3]), &Device::flex())
            .expand([1, WINDOW, n, 3]);
        assert!(value(geometry(inside, &b.source)) > 0.0);
    }
}
