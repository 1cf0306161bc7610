//! The reconstruction loss and one training step.
//!
//! **Reconstruction** (VPC eq. 10) retargets each motion onto its own character and compares
//! with the motion itself: parent-relative positions, plus 100 × root-relative positions, plus
//! 200 × the root trajectory, each a squared error summed over X, Y, Z and averaged over
//! frames and bones (the trajectory over frames). Positions are in the character's heights
//! ([`crate::features`]), which is the paper's `/h²` on the last two terms; the first term is
//! divided by `h²` as well, so that all three weigh the same on tall and short characters.
//!
//! ```no_run
//! use burn::prelude::Device;
//! use posecoach_train::features::{Batch, MAX_JOINTS};
//! use posecoach_train::model::TeacherConfig;
//! use posecoach_train::train::{train_step, Optimizer};
//!
//! # fn windows() -> Vec<posecoach_train::features::Window> { Vec::new() }
//! let device = Device::flex().autodiff();
//! let mut model = TeacherConfig::DEFAULT.init(&device);
//! let mut optimizer = Optimizer::adam();
//! let batch = Batch::reconstruction(&windows(), MAX_JOINTS, &device)?;
//! for _ in 0..100 {
//!     let loss;
//!     (model, loss) = train_step(model, &mut optimizer, &batch);
//!     println!("{loss}");
//! }
//! # Ok::<(), posecoach_train::Error>(())
//! ```

use crate::features::Batch;
use crate::model::{Retargeted, Teacher};
use burn::optim::{AdamConfig, GradientsParams, ModuleOptimizer};
use burn::prelude::Tensor;

/// Weight of the root-relative term.
pub const ROOT_RELATIVE_WEIGHT: f32 = 100.0;
/// Weight of the root trajectory term.
pub const TRAJECTORY_WEIGHT: f32 = 200.0;
/// Adam's default learning rate.
pub const LEARNING_RATE: f64 = 1e-3;

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
    /// The terms for `output` against the batch's truth.
    pub fn new(output: &Retargeted, batch: &Batch) -> Reconstruction {
        let (predicted, truth) = (output.positions.clone(), batch.truth.clone());
        let [b, t, j, _] = predicted.dims();
        let parents = batch.target.ancestors[0].clone();
        let bones = batch.target.bones.clone().reshape([b, 1, j, 1]);
        let samples = bones.clone().sum().mul_scalar(t as f32);
        let over_bones =
            |p: Tensor<4>, q: Tensor<4>| ((p - q).square() * bones.clone()).sum() / samples.clone();
        let from_parent = |p: Tensor<4>| {
            let joint_major = p.clone().swap_dims(1, 2).reshape([b, j, t * 3]);
            let above = parents.clone().matmul(joint_major).reshape([b, j, t, 3]);
            p - above.swap_dims(1, 2)
        };
        let from_root = |p: Tensor<4>| p.clone() - p.narrow(2, 0, 1);
        let root = |p: Tensor<4>| p.narrow(2, 0, 1);
        Reconstruction {
            parent: over_bones(from_parent(predicted.clone()), from_parent(truth.clone())),
            root_relative: over_bones(from_root(predicted.clone()), from_root(truth.clone())),
            trajectory: (root(predicted) - root(truth))
                .square()
                .sum()
                .div_scalar((b * t) as f32),
        }
    }

    /// The weighted sum.
    pub fn total(&self) -> Tensor<1> {
        self.parent.clone()
            + self.root_relative.clone().mul_scalar(ROOT_RELATIVE_WEIGHT)
            + self.trajectory.clone().mul_scalar(TRAJECTORY_WEIGHT)
    }
}

/// Adam over a teacher's parameters, with its learning rate.
pub struct Optimizer {
    adam: ModuleOptimizer,
    learning_rate: f64,
}

impl Optimizer {
    /// Adam (β = 0.9, 0.999) at [`LEARNING_RATE`].
    pub fn adam() -> Optimizer {
        Optimizer::adam_with(LEARNING_RATE)
    }

    /// Adam at `learning_rate`.
    pub fn adam_with(learning_rate: f64) -> Optimizer {
        Optimizer {
            adam: AdamConfig::new().init(),
            learning_rate,
        }
    }
}

/// One Adam step on the reconstruction loss of `batch` (on an autodiff device); returns the
/// updated teacher and the loss before the step.
pub fn train_step(model: Teacher, optimizer: &mut Optimizer, batch: &Batch) -> (Teacher, f32) {
    let loss = Reconstruction::new(&model.forward(batch), batch).total();
    let value = loss.clone().into_scalar::<f32>();
    let grads = GradientsParams::from_grads(loss.backward(), &model);
    let model = optimizer.adam.step(optimizer.learning_rate, model, grads);
    (model, value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::testing::{character, window};
    use crate::features::{Window, MAX_JOINTS};
    use crate::model::TeacherConfig;
    use burn::prelude::Device;
    use posecoach_core::format::Format;
    use std::time::Instant;

    const SEED: u64 = 7;
    const SMOKE_STEPS: usize = 20;
    const SMOKE_LEARNING_RATE: f64 = 1e-2;
    /// The loss must fall at least this many times over the smoke test.
    const SMOKE_FACTOR: f32 = 3.0;
    const TIMED_BATCH: usize = 8;
    const TIMED_STEPS: usize = 5;

    fn windows(formats: &[Format], count: usize) -> Vec<Window> {
        (0..count)
            .map(|i| window(&character(formats[i % formats.len()], i as u64).skeleton))
            .collect()
    }

    #[test]
    fn the_loss_of_the_truth_is_zero() {
        let device = Device::flex();
        let batch = Batch::reconstruction(&windows(&[Format::Coco17], 1), 17, &device).unwrap();
        let truth = Retargeted {
            rotations: Tensor::zeros([1, 1, 1, 4], &device),
            root: Tensor::zeros([1, 1, 3], &device),
            positions: batch.truth.clone(),
        };
        assert_eq!(
            Reconstruction::new(&truth, &batch)
                .total()
                .into_scalar::<f32>(),
            0.0
        );
    }

    #[test]
    fn training_reduces_the_reconstruction_loss() {
        let device = Device::flex().autodiff();
        device.seed(SEED);
        let formats = [Format::H36m17, Format::Cmu31, Format::Coco17];
        let batch = Batch::reconstruction(&windows(&formats, 3), MAX_JOINTS, &device).unwrap();
        let mut model = TeacherConfig::TINY.init(&device);
        let mut optimizer = Optimizer::adam_with(SMOKE_LEARNING_RATE);
        let start = Instant::now();
        let mut losses = Vec::new();
        for _ in 0..SMOKE_STEPS {
            let loss;
            (model, loss) = train_step(model, &mut optimizer, &batch);
            losses.push(loss);
        }
        eprintln!("smoke losses {losses:.4?} in {:?}", start.elapsed());
        let (first, last) = (losses[0], losses[SMOKE_STEPS - 1]);
        assert!(last * SMOKE_FACTOR < first, "{first} -> {last}");
    }

    /// Time per training step of the default teacher (batch 8): run in release with
    /// `cargo test --release -p posecoach-train -- --ignored --nocapture step_time`.
    #[test]
    #[ignore = "a timing, run in release"]
    fn step_time() {
        let device = Device::flex().autodiff();
        device.seed(SEED);
        let windows = windows(&crate::dataset::FORMATS, TIMED_BATCH);
        let joints = windows.iter().map(|w| w.skeleton().len()).max().unwrap();
        let batch = Batch::reconstruction(&windows, joints, &device).unwrap();
        let mut model = TeacherConfig::DEFAULT.init(&device);
        let mut optimizer = Optimizer::adam();
        (model, _) = train_step(model, &mut optimizer, &batch);
        let start = Instant::now();
        for _ in 0..TIMED_STEPS {
            (model, _) = train_step(model, &mut optimizer, &batch);
        }
        let per_step = start.elapsed() / TIMED_STEPS as u32;
        let params = burn::module::Module::num_params(&model);
        eprintln!(
            "default teacher ({params} parameters), batch {TIMED_BATCH}: {per_step:?} per step"
        );
    }
}
