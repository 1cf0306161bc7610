//! Training: batches drawn from the pool, one step of every loss, checkpoints.
//!
//! A step retargets each window `A` onto its own skeleton (reconstruction) and onto its target
//! `B` (`A → B`), then `A → B` back onto `A` (the cycle), sums the weighted losses of
//! [`crate::losses`] that are switched on and takes an Adam step; then the discriminator takes
//! its own step on real windows against `A → B`. Batches come from `(seed, step)` alone, so a
//! run resumed from a checkpoint continues exactly as the uninterrupted run would.
//!
//! Checkpoints and network files are float weights files ([`posecoach_teachfile`]): a reader
//! checks the whole file's CRC and every header word against its bound before it builds
//! anything from them.
//!
//! ```no_run
//! use burn::prelude::Device;
//! use posecoach_train::dataset::Pool;
//! use posecoach_train::train::{TrainConfig, Trainer};
//!
//! let pool = Pool::load("../shared/data".as_ref())?;
//! let mut trainer = Trainer::new(TrainConfig::default(), &Device::flex().autodiff());
//! while trainer.step() < 100 {
//!     let losses = trainer.train_step(&pool)?;
//!     println!("{}", losses.total);
//! }
//! trainer.save("teacher.pcckpt".as_ref())?;
//! # Ok::<(), posecoach_train::Error>(())
//! ```

use crate::bodies::Variation;
use crate::clip::counterparts;
use crate::dataset::{Example, Pool, SplitRng, Structure};
use crate::discriminator::Discriminator;
use crate::error::Error;
use crate::features::{motion_features, Batch, Window};
use crate::losses::{self, Reconstruction, Switches};
use crate::model::{Teacher, TeacherConfig};
use crate::prior::PriorKind;
use crate::skeletons::Skeletons;
use burn::module::{Module, ModuleVisitor, Param};
use burn::optim::{AdamConfig, GradientsAccumulator, GradientsParams, ModuleOptimizer};
use burn::prelude::{Device, Tensor, TensorData};
use burn::store::ModuleRecord;
use burn::tensor::Bytes;
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::Skeleton;
use posecoach_teachfile::{self as teachfile, TeachFile};
use rand::Rng;
use std::io::Read;
use std::path::Path;

/// Adam's starting learning rate. The teacher starts at the analytic solution and learns a
/// correction: 1e-3 and 3e-4 gave the same evaluation after 1 000 steps (3e-3 was chosen for
/// the network trained from scratch).
pub const LEARNING_RATE: f64 = 1e-3;
/// Steps after which the learning rate falls to a third: kept at 3e-3, a run blew up at step
/// 5 900 (reconstruction 0.9 to 8) and the discriminator took over.
pub const DECAY_STEPS: [usize; 2] = [5000, 15000];
/// Windows per batch.
pub const BATCH: usize = 8;
/// Threads a step splits its batch over: this machine's two cores (burn's CPU kernels leave
/// the second idle at these sizes).
pub const WORKERS: usize = 2;
/// Share of examples whose target is in the source's format.
pub const INTRA_SHARE: f64 = 0.5;

/// What a training run is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainConfig {
    /// The teacher's sizes.
    pub teacher: TeacherConfig,
    /// Windows per batch.
    pub batch: usize,
    /// Adam's learning rate.
    pub learning_rate: f64,
    /// The losses beyond the reconstruction.
    pub switches: Switches,
    /// Seeds the weights and every batch.
    pub seed: u64,
}

impl TrainConfig {
    /// Checks that a file can state this configuration: every size and rate within the
    /// bounds a reader holds them to ([`posecoach_teachfile::Header::check`]). Check before
    /// training: [`Trainer::save`] refuses a configuration out of bounds.
    ///
    /// # Errors
    /// [`Error::TeachFile`] naming the first value out of bounds.
    pub fn check(&self) -> Result<(), Error> {
        Ok(Header {
            config: *self,
            step: 0,
        }
        .to_file()
        .check()?)
    }
}

impl Default for TrainConfig {
    fn default() -> Self {
        TrainConfig {
            teacher: TeacherConfig::DEFAULT,
            batch: BATCH,
            learning_rate: LEARNING_RATE,
            switches: Switches::ALL,
            seed: 0,
        }
    }
}

/// One step's losses, unweighted (0 where switched off).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepLosses {
    /// The weighted sum the teacher descends.
    pub total: f32,
    /// Reconstruction.
    pub reconstruction: f32,
    /// Cycle.
    pub cycle: f32,
    /// End-effector velocities.
    pub effectors: f32,
    /// The teacher's adversarial loss.
    pub adversarial: f32,
    /// Joint-distance matrices.
    pub joint_distances: f32,
    /// Geometry.
    pub geometry: f32,
    /// The discriminator's loss.
    pub discriminator: f32,
    /// Distillation (the distilled network against its teacher).
    pub distillation: f32,
}

impl StepLosses {
    /// Each loss added to `other`'s.
    pub fn plus(&self, other: &StepLosses) -> StepLosses {
        self.zip(other, |a, b| a + b)
    }

    /// Each loss times `k`.
    pub fn times(&self, k: f32) -> StepLosses {
        self.zip(self, |a, _| a * k)
    }

    fn zip(&self, o: &StepLosses, f: impl Fn(f32, f32) -> f32) -> StepLosses {
        StepLosses {
            total: f(self.total, o.total),
            reconstruction: f(self.reconstruction, o.reconstruction),
            cycle: f(self.cycle, o.cycle),
            effectors: f(self.effectors, o.effectors),
            adversarial: f(self.adversarial, o.adversarial),
            joint_distances: f(self.joint_distances, o.joint_distances),
            geometry: f(self.geometry, o.geometry),
            discriminator: f(self.discriminator, o.discriminator),
            distillation: f(self.distillation, o.distillation),
        }
    }
}

/// One thread's share of a step.
#[derive(Clone, Debug)]
pub struct Part {
    /// Windows, each to retarget onto its target.
    pub batch: Batch,
    /// The same windows on their sources' bodies in their targets' formats
    /// ([`Example::twin`]): what retargeting each onto its own body in that format must give.
    pub twins: Batch,
}

/// A teacher in training, with its discriminator and both optimizers.
pub struct Trainer {
    config: TrainConfig,
    teacher: Teacher,
    discriminator: Discriminator,
    teacher_adam: ModuleOptimizer,
    discriminator_adam: ModuleOptimizer,
    step: usize,
    device: Device,
    student: Option<Skeleton>,
    /// While distilling: the trained teacher whose outputs the network learns, and its file's
    /// bytes (a checkpoint carries them).
    reference: Option<(Teacher, Vec<u8>)>,
}

impl Trainer {
    /// A fresh teacher and discriminator on `device` (an autodiff device), seeded.
    pub fn new(config: TrainConfig, device: &Device) -> Trainer {
        device.seed(config.seed);
        let teacher = initialized(config.teacher.init(device));
        let discriminator = initialized(Discriminator::new(device));
        Trainer {
            teacher,
            discriminator,
            teacher_adam: AdamConfig::new().init(),
            discriminator_adam: AdamConfig::new().init(),
            config,
            step: 0,
            device: device.clone(),
            student: None,
            reference: None,
        }
    }

    /// A run that distills the teacher in the checkpoint or teacher file `teacher` into a
    /// fresh network of `config`'s sizes: every step, the network's positions move toward the
    /// teacher's on the same batch ([`losses::distillation`]); no other loss is computed.
    ///
    /// # Errors
    /// As [`load_teacher`].
    pub fn distilling(
        teacher: &Path,
        config: TrainConfig,
        device: &Device,
    ) -> Result<Trainer, Error> {
        Trainer::distilling_bytes(read_weights(teacher)?, config, device)
    }

    fn distilling_bytes(
        bytes: Vec<u8>,
        config: TrainConfig,
        device: &Device,
    ) -> Result<Trainer, Error> {
        let (reference, _, _) = teacher_from_bytes(&bytes, device)?;
        let mut trainer = Trainer::new(config, device);
        trainer.reference = Some((reference, bytes));
        Ok(trainer)
    }

    /// A run that starts from the teacher in a checkpoint or teacher file (fresh optimizers
    /// and discriminator), configured as `config` but for the teacher's sizes.
    ///
    /// # Errors
    /// As [`load_teacher`].
    pub fn from_teacher(
        path: &Path,
        config: TrainConfig,
        device: &Device,
    ) -> Result<Trainer, Error> {
        let bytes = read_weights(path)?;
        let file = teachfile::decode(&bytes)?;
        let config = TrainConfig {
            teacher: Header::from_file(&file.header).config.teacher,
            ..config
        };
        let mut trainer = Trainer::new(config, device);
        trainer.teacher = load_module(trainer.teacher, network_part(&file)?)?.train();
        Ok(trainer)
    }

    /// Every example retargeted onto `student` from now on: the per-student fine-tune (SMT's
    /// second stage), which fits the teacher to one body.
    pub fn for_student(mut self, student: Skeleton) -> Trainer {
        self.student = Some(student);
        self
    }

    /// Steps taken.
    pub fn step(&self) -> usize {
        self.step
    }

    /// The run's configuration.
    pub fn config(&self) -> &TrainConfig {
        &self.config
    }

    /// The teacher.
    pub fn teacher(&self) -> &Teacher {
        &self.teacher
    }

    /// The batch of step `step` (a function of the seed and `step` alone), in [`WORKERS`]
    /// parts (fewer if the batch is smaller).
    ///
    /// # Errors
    /// As [`Pool::sample_example`] and [`Batch::new`].
    pub fn batch_for(&self, pool: &Pool, step: usize) -> Result<Vec<Part>, Error> {
        self.batch_in(pool, step, WORKERS)
    }

    /// The batch of step `step` in `parts` parts (fewer if the batch is smaller).
    ///
    /// # Errors
    /// As [`Trainer::batch_for`].
    pub fn batch_in(&self, pool: &Pool, step: usize, parts: usize) -> Result<Vec<Part>, Error> {
        let seed = self
            .config
            .seed
            .wrapping_mul(1 << 32)
            .wrapping_add(step as u64);
        let mut rng = SplitRng::new(crate::dataset::Split::Train, seed);
        let examples = (0..self.config.batch)
            .map(|_| {
                let structure = match rng.rng().random_bool(INTRA_SHARE) {
                    true => Structure::Intra,
                    false => Structure::Cross,
                };
                pool.sample_example(&mut rng, structure, &Variation::FULL)
            })
            .collect::<Result<Vec<Example>, Error>>()?;
        let part = self.config.batch.div_ceil(parts.max(1)).max(1);
        examples
            .chunks(part)
            .map(|examples| {
                let windows: Vec<Window> = examples.iter().map(|e| e.window.clone()).collect();
                let targets: Vec<&Skeleton> = examples
                    .iter()
                    .map(|e| self.student.as_ref().unwrap_or(&e.target))
                    .collect();
                let twins: Vec<Window> = examples.iter().map(|e| e.twin.clone()).collect();
                Ok(Part {
                    batch: Batch::new(&windows, &targets, &self.device)?,
                    twins: Batch::reconstruction(&twins, &self.device)?,
                })
            })
            .collect()
    }

    /// One step on the next batch of `pool`.
    ///
    /// # Errors
    /// As [`Trainer::batch_for`].
    pub fn train_step(&mut self, pool: &Pool) -> Result<StepLosses, Error> {
        let parts = self.batch_for(pool, self.step)?;
        self.step_on(&parts)
    }

    /// One step on a batch given in parts, one thread each; every loss is the mean over the
    /// parts' means, weighted by their windows.
    ///
    /// # Errors
    /// As [`Batch::on`], for the reconstruction and the cycle's way back.
    pub fn step_on(&mut self, parts: &[Part]) -> Result<StepLosses, Error> {
        if self.reference.is_some() {
            return self.distill_on(parts);
        }
        let switches = self.config.switches;
        let windows: usize = parts.iter().map(|p| p.batch.len()).sum();
        let shares: Vec<f32> = parts
            .iter()
            .map(|p| p.batch.len() as f32 / windows.max(1) as f32)
            .collect();
        // Each thread differentiates its own copy, with the same parameter ids: one autodiff
        // graph per thread, gradients summed by id.
        let (teacher, discriminator) = (&self.teacher, &self.discriminator);
        let passes: Vec<(GradientsParams, StepLosses, Tensor<4>)> = std::thread::scope(|scope| {
            let handles: Vec<_> = parts
                .iter()
                .zip(&shares)
                .map(|(part, &share)| {
                    let (t, d) = (teacher.valid().train(), discriminator.valid().train());
                    scope.spawn(move || teacher_pass(&t, &d, part, switches, share))
                })
                .collect();
            handles.into_iter().map(joined).collect::<Result<_, _>>()
        })?;
        let mut report = StepLosses::default();
        let mut sum = GradientsAccumulator::<Teacher>::new();
        let mut fakes = Vec::new();
        for (grads, losses, fake) in passes {
            sum.accumulate(&self.teacher, grads);
            report = report.plus(&losses);
            fakes.push(fake);
        }
        let lr = self.learning_rate();
        self.teacher = self
            .teacher_adam
            .step(lr, self.teacher.clone(), sum.grads());
        if switches.adversarial {
            let discriminator = &self.discriminator;
            let passes: Vec<(GradientsParams, f32)> = std::thread::scope(|scope| {
                let handles: Vec<_> = parts
                    .iter()
                    .zip(fakes)
                    .zip(&shares)
                    .map(|((part, fake), &share)| {
                        let d = discriminator.valid().train();
                        scope.spawn(move || discriminator_pass(&d, &part.batch, fake, share))
                    })
                    .collect();
                handles.into_iter().map(joined).collect()
            });
            let mut sum = GradientsAccumulator::<Discriminator>::new();
            for (grads, loss) in passes {
                sum.accumulate(&self.discriminator, grads);
                report.discriminator += loss;
            }
            self.discriminator =
                self.discriminator_adam
                    .step(lr, self.discriminator.clone(), sum.grads());
        }
        self.step += 1;
        Ok(report)
    }

    /// One distillation step on a batch given in parts, one thread each.
    fn distill_on(&mut self, parts: &[Part]) -> Result<StepLosses, Error> {
        let Some((reference, _)) = &self.reference else {
            return Err(checkpoint("not distilling"));
        };
        let windows: usize = parts.iter().map(|p| p.batch.len()).sum();
        let distilled = &self.teacher;
        let passes: Vec<(GradientsParams, f32)> = std::thread::scope(|scope| {
            let handles: Vec<_> = parts
                .iter()
                .map(|Part { batch: part, .. }| {
                    let (s, r) = (distilled.valid().train(), reference.valid().train());
                    let share = part.len() as f32 / windows.max(1) as f32;
                    scope.spawn(move || {
                        let target = r.forward(part).positions.detach();
                        let loss = losses::distillation(s.forward(part).positions, target)
                            .mul_scalar(share);
                        let value = scalar(&loss);
                        (GradientsParams::from_grads(loss.backward(), &s), value)
                    })
                })
                .collect();
            handles.into_iter().map(joined).collect()
        });
        let mut report = StepLosses::default();
        let mut sum = GradientsAccumulator::<Teacher>::new();
        for (grads, loss) in passes {
            sum.accumulate(&self.teacher, grads);
            report.distillation += loss;
        }
        report.total = report.distillation;
        let lr = self.learning_rate();
        self.teacher = self
            .teacher_adam
            .step(lr, self.teacher.clone(), sum.grads());
        self.step += 1;
        Ok(report)
    }

    /// The learning rate of the next step: the configured one, a third of it after each of
    /// [`DECAY_STEPS`].
    pub fn learning_rate(&self) -> f64 {
        let decays = DECAY_STEPS.iter().filter(|&&s| self.step >= s).count();
        self.config.learning_rate / 3f64.powi(decays as i32)
    }

    /// Writes everything a resumed run needs to `path`.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] if a part cannot be encoded or the file written.
    pub fn save(&self, path: &Path) -> Result<(), Error> {
        let mut parts = vec![
            module_bytes(&self.teacher)?,
            module_bytes(&self.discriminator)?,
            self.teacher_adam.into_bytes().map_err(checkpoint)?.to_vec(),
            self.discriminator_adam
                .into_bytes()
                .map_err(checkpoint)?
                .to_vec(),
        ];
        if let Some((_, teacher_file)) = &self.reference {
            parts.push(teacher_file.clone());
        }
        write_file(path, &self.header(), &parts)
    }

    /// Writes the network alone to `path` (the distilled network, while distilling): what
    /// `--weights` loads.
    ///
    /// # Errors
    /// As [`Trainer::save`].
    pub fn save_teacher(&self, path: &Path) -> Result<(), Error> {
        write_file(path, &self.header(), &[module_bytes(&self.teacher)?])
    }

    /// A run resumed from a checkpoint written by [`Trainer::save`].
    ///
    /// # Errors
    /// [`Error::Checkpoint`] if the file cannot be read or is not a full checkpoint.
    pub fn load(path: &Path, device: &Device) -> Result<Trainer, Error> {
        let bytes = read_weights(path)?;
        let file = teachfile::decode(&bytes)?;
        let header = Header::from_file(&file.header);
        let [teacher, discriminator, teacher_adam, discriminator_adam, reference @ ..] =
            file.parts.as_slice()
        else {
            return Err(checkpoint("holds the teacher alone, not a training state"));
        };
        let mut trainer = match reference.first() {
            Some(bytes) => Trainer::distilling_bytes(bytes.to_vec(), header.config, device)?,
            None => Trainer::new(header.config, device),
        };
        trainer.teacher = load_module(trainer.teacher, teacher.to_vec())?.train();
        trainer.discriminator = load_module(trainer.discriminator, discriminator.to_vec())?.train();
        trainer.teacher_adam = trainer
            .teacher_adam
            .from_bytes(Bytes::from_bytes_vec(teacher_adam.to_vec()))
            .map_err(checkpoint)?;
        trainer.discriminator_adam = trainer
            .discriminator_adam
            .from_bytes(Bytes::from_bytes_vec(discriminator_adam.to_vec()))
            .map_err(checkpoint)?;
        trainer.step = header.step;
        Ok(trainer)
    }

    fn header(&self) -> Header {
        Header {
            config: self.config,
            step: self.step,
        }
    }
}

/// The teacher's losses on one part of a batch: their gradients for `teacher` scaled by
/// `share`, the losses (scaled likewise, so that parts add up to the batch's means), and the
/// retargeted motions' features, detached, for the discriminator.
fn teacher_pass(
    teacher: &Teacher,
    discriminator: &Discriminator,
    part: &Part,
    switches: Switches,
    share: f32,
) -> Result<(GradientsParams, StepLosses, Tensor<4>), Error> {
    let Part { batch, twins } = part;
    let mut report = StepLosses::default();
    let mut terms = Vec::new();
    let mut add = |value: &mut f32, loss: Tensor<1>, weight: f32| {
        *value = scalar(&loss) * share;
        terms.push(loss.mul_scalar(weight));
    };
    let reconstruct = Batch::on(
        batch.source.clone(),
        batch.positions.clone(),
        twins.source.clone(),
    )?;
    let own = teacher.forward(&reconstruct);
    let truth = batch.positions.clone();
    let rec = Reconstruction::masked(
        own.positions,
        twins.positions.clone(),
        &twins.source,
        Tensor::ones([batch.len()], &truth.device()),
        known_joints(&batch.source, &twins.source, &truth.device()),
    );
    add(&mut report.reconstruction, rec.total(), 1.0);
    let forth = teacher.forward(batch);
    if switches.cycle {
        let back = Batch::on(
            batch.target.clone(),
            forth.positions.clone(),
            batch.source.clone(),
        )?;
        let back = teacher.forward(&back);
        let intra = batch
            .source
            .skeletons
            .iter()
            .zip(&batch.target.skeletons)
            .map(|(a, b)| f32::from(u8::from(a.format() == b.format())))
            .collect::<Vec<f32>>();
        let intra = Tensor::from_floats(intra.as_slice(), &truth.device());
        let loss = losses::cycle(&forth, &back, truth.clone(), &batch.source, intra);
        add(&mut report.cycle, loss, losses::CYCLE_WEIGHT);
    }
    let predicted = forth.positions;
    if switches.effectors {
        let loss = losses::effectors(
            predicted.clone(),
            &batch.target,
            truth.clone(),
            &batch.source,
        );
        add(&mut report.effectors, loss, losses::EFFECTOR_WEIGHT);
    }
    if switches.joint_distances {
        let loss = losses::joint_distances(predicted.clone(), &batch.target, truth, &batch.source);
        add(
            &mut report.joint_distances,
            loss,
            losses::JOINT_DISTANCE_WEIGHT,
        );
    }
    if switches.geometry {
        let loss = losses::geometry(predicted.clone(), &batch.target);
        add(&mut report.geometry, loss, losses::GEOMETRY_WEIGHT);
    }
    let fake = motion_features(predicted, &batch.target);
    if switches.adversarial {
        let loss = discriminator.loss(fake.clone(), &batch.target, 1.0);
        add(&mut report.adversarial, loss, losses::ADVERSARIAL_WEIGHT);
    }
    let total = terms
        .into_iter()
        .reduce(|a, b| a + b)
        .map(|t| t.mul_scalar(share))
        .unwrap_or_else(|| Tensor::zeros([1], &batch.positions.device()));
    report.total = scalar(&total);
    let grads = GradientsParams::from_grads(total.backward(), teacher);
    Ok((grads, report, fake.detach()))
}

/// `[B, J]` 0 where a joint of `target` is on a club that `source` does not track: nothing in
/// the body's motion tells where a club points. Body joints the source lacks (a spine,
/// fingers) count: the others' motion implies them.
fn known_joints(source: &Skeletons, target: &Skeletons, device: &Device) -> Tensor<2> {
    let joints = target.joints();
    let mut known = vec![0.0; target.len() * joints];
    for (i, (s, t)) in source.skeletons.iter().zip(&target.skeletons).enumerate() {
        for (k, c) in counterparts(s, t).iter().enumerate() {
            let club = t.joint(k).is_some_and(Joint::is_club);
            known[i * joints + k] = f32::from(u8::from(c.is_some() || !club));
        }
    }
    Tensor::from_data(TensorData::new(known, [target.len(), joints]), device)
}

/// The discriminator's loss on one part: real windows against their retargeted `fake`
/// features; its gradients and value, scaled by `share`.
fn discriminator_pass(
    discriminator: &Discriminator,
    batch: &Batch,
    fake: Tensor<4>,
    share: f32,
) -> (GradientsParams, f32) {
    let real = discriminator.loss(batch.motion.clone(), &batch.source, 1.0);
    let fake = discriminator.loss(fake, &batch.target, 0.0);
    let loss = (real + fake).mul_scalar(0.5 * share);
    let value = scalar(&loss);
    (
        GradientsParams::from_grads(loss.backward(), discriminator),
        value,
    )
}

/// A trained teacher from a checkpoint or teacher file, for inference (no autodiff), with
/// the configuration and steps it was trained with.
///
/// # Errors
/// As [`teacher_from_bytes`]; [`Error::Checkpoint`] if the file cannot be read.
pub fn load_teacher(path: &Path, device: &Device) -> Result<(Teacher, TrainConfig, usize), Error> {
    teacher_from_bytes(&read_weights(path)?, device)
}

/// [`load_teacher`] of a file's bytes. The file is checked whole (its CRC, every header word
/// against its bound, its parts' lengths: [`posecoach_teachfile::decode`]) before the network
/// is built from its header.
///
/// # Errors
/// [`Error::TeachFile`] if the bytes are not a sound float weights file;
/// [`Error::Checkpoint`] if its network's part does not load into the network it describes.
pub fn teacher_from_bytes(
    bytes: &[u8],
    device: &Device,
) -> Result<(Teacher, TrainConfig, usize), Error> {
    let file = teachfile::decode(bytes)?;
    let header = Header::from_file(&file.header);
    let teacher = load_module(header.config.teacher.init(device), network_part(&file)?)?;
    Ok((teacher, header.config, header.step))
}

/// The bytes of the weights file at `path`, refused unread if larger than any weights file.
///
/// # Errors
/// [`Error::Checkpoint`] if it cannot be read, [`Error::TeachFile`] if it is too large.
pub(crate) fn read_weights(path: &Path) -> Result<Vec<u8>, Error> {
    let io = |e: std::io::Error| checkpoint(format!("{}: {e}", path.display()));
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| {
            f.take(teachfile::MAX_FILE_BYTES + 1)
                .read_to_end(&mut bytes)
        })
        .map_err(io)?;
    match bytes.len() as u64 {
        len if len > teachfile::MAX_FILE_BYTES => Err(teachfile::Error::TooLarge { len }.into()),
        _ => Ok(bytes),
    }
}

/// A file's first part, its network's record.
fn network_part(file: &TeachFile<'_>) -> Result<Vec<u8>, Error> {
    file.parts
        .first()
        .map(|p| p.to_vec())
        .ok_or_else(|| checkpoint("holds no network"))
}

/// `module` with every parameter drawn now: burn draws them lazily, at first use, from the
/// device's generator, which would make a run depend on what else used it in between.
fn initialized<M: Module>(module: M) -> M {
    struct Touch;
    impl ModuleVisitor for Touch {
        fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<D>>) {
            param.val();
        }
    }
    module.visit(&mut Touch);
    module
}

/// The value of a one-element tensor.
/// A scoped thread's result; its panic, if it panicked, carries on in the caller.
fn joined<T>(handle: std::thread::ScopedJoinHandle<'_, T>) -> T {
    handle
        .join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

fn scalar(t: &Tensor<1>) -> f32 {
    t.clone().into_scalar::<f32>()
}

fn checkpoint(why: impl std::fmt::Display) -> Error {
    Error::Checkpoint(why.to_string())
}

fn module_bytes<M: Module>(module: &M) -> Result<Vec<u8>, Error> {
    let record = module.valid().into_record();
    Ok(record.into_bytes().map_err(checkpoint)?.to_vec())
}

fn load_module<M: Module>(module: M, bytes: Vec<u8>) -> Result<M, Error> {
    let record = ModuleRecord::from_bytes(Bytes::from_bytes_vec(bytes)).map_err(checkpoint)?;
    module.try_load_record(record).map_err(checkpoint)
}

/// What a checkpoint says about itself.
#[derive(Clone, Copy, Debug)]
struct Header {
    config: TrainConfig,
    step: usize,
}

impl Header {
    /// As a file's header (step, seed, batch, d, heads, kernel, switches, learning rate,
    /// prior: [`posecoach_teachfile::Header`]).
    fn to_file(self) -> teachfile::Header {
        let c = self.config;
        let s = c.switches;
        let switches = [
            s.cycle,
            s.effectors,
            s.adversarial,
            s.joint_distances,
            s.geometry,
        ]
        .iter()
        .enumerate()
        .map(|(i, &on)| u64::from(on) << i)
        .sum();
        teachfile::Header {
            step: self.step as u64,
            seed: c.seed,
            batch: c.batch as u64,
            features: c.teacher.features as u64,
            heads: c.teacher.heads as u64,
            kernel: c.teacher.kernel as u64,
            switches,
            learning_rate: c.learning_rate,
            prior: u64::from(c.teacher.prior == PriorKind::Rotations),
        }
    }

    /// A checked file header's (every word within its bound, so every size fits a `usize`).
    fn from_file(h: &teachfile::Header) -> Header {
        let on = |i: u32| h.switches >> i & 1 == 1;
        Header {
            step: h.step as usize,
            config: TrainConfig {
                seed: h.seed,
                batch: h.batch as usize,
                teacher: TeacherConfig {
                    features: h.features as usize,
                    heads: h.heads as usize,
                    kernel: h.kernel as usize,
                    prior: match h.prior {
                        0 => PriorKind::Chords,
                        _ => PriorKind::Rotations,
                    },
                },
                switches: Switches {
                    cycle: on(0),
                    effectors: on(1),
                    adversarial: on(2),
                    joint_distances: on(3),
                    geometry: on(4),
                },
                learning_rate: h.learning_rate,
            },
        }
    }
}

/// The header and parts as a float weights file ([`posecoach_teachfile`]: with its CRC),
/// written whole to a temporary file that then replaces `path`.
fn write_file(path: &Path, header: &Header, parts: &[Vec<u8>]) -> Result<(), Error> {
    let out = teachfile::encode(&header.to_file(), parts)?;
    let partial = path.with_extension("partial");
    std::fs::write(&partial, out)
        .and_then(|()| std::fs::rename(&partial, path))
        .map_err(|e| checkpoint(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::testing::character;
    use crate::clip::testing::wave_frames;
    use crate::clip::Clip;
    use crate::dataset::window_frames;
    use std::time::Instant;

    const SEED: u64 = 7;
    const SMOKE_STEPS: usize = 20;
    const SMOKE_LEARNING_RATE: f64 = 1e-3;
    /// The distillation loss must fall at least this many times over the smoke test.
    const SMOKE_FACTOR: f32 = 1.1;
    /// Adam's rate for the smoke test of the reconstruction: a correction of a prior that is
    /// close already takes small steps (at 1e-3 the first steps overshoot).
    const CORRECTION_LEARNING_RATE: f64 = 1e-4;
    /// Steps of that smoke test...
    const CORRECTION_STEPS: usize = 80;
    /// ...and how many times the loss must fall over them: most of it is joints the other
    /// format lacks, which a tiny network learns slowly (1.3 % measured).
    const CORRECTION_FACTOR: f32 = 1.01;
    const TIMED_STEPS: usize = 5;

    /// A pool of synthetic waves, one per format, long enough for a few windows.
    fn pool() -> Pool {
        let train = crate::dataset::FORMATS
            .iter()
            .enumerate()
            .map(|(i, &f)| {
                let skeleton = character(f, i as u64).skeleton;
                let motion = wave_frames(&skeleton, 2 * window_frames());
                Clip::from_motion("wave", &motion).unwrap()
            })
            .collect();
        Pool {
            train,
            ..Pool::default()
        }
    }

    fn tiny(batch: usize) -> TrainConfig {
        TrainConfig {
            teacher: TeacherConfig::TINY,
            batch,
            learning_rate: SMOKE_LEARNING_RATE,
            switches: Switches::ALL,
            seed: SEED,
        }
    }

    #[test]
    fn training_reduces_the_reconstruction_across_formats() {
        // An untrained teacher is its prior. The tiny teacher's, the chords, reconstruct a
        // motion on its own body exactly in its own format but not in another (joints one
        // format has and the other lacks): what training must first reduce.
        let device = Device::flex().autodiff();
        let reconstruction_only = TrainConfig {
            switches: Switches {
                cycle: false,
                effectors: false,
                adversarial: false,
                joint_distances: false,
                geometry: false,
            },
            learning_rate: CORRECTION_LEARNING_RATE,
            ..tiny(3)
        };
        let mut trainer = Trainer::new(reconstruction_only, &device);
        let batch = trainer.batch_for(&pool(), 0).unwrap();
        let start = Instant::now();
        let losses: Vec<f32> = (0..CORRECTION_STEPS)
            .map(|_| trainer.step_on(&batch).unwrap().reconstruction)
            .collect();
        eprintln!("smoke reconstruction {losses:.6?} in {:?}", start.elapsed());
        let (first, last) = (losses[0], losses[CORRECTION_STEPS - 1]);
        assert!(last * CORRECTION_FACTOR < first, "{first} -> {last}");
    }

    #[test]
    fn every_loss_is_computed_when_switched_on() {
        let device = Device::flex().autodiff();
        let mut trainer = Trainer::new(tiny(6), &device);
        let batch = trainer.batch_for(&pool(), 0).unwrap();
        let on = trainer.step_on(&batch).unwrap();
        assert!(on.total.is_finite());
        assert!(on.reconstruction > 0.0 && on.cycle > 0.0, "{on:?}");
        assert!(on.effectors > 0.0 && on.joint_distances > 0.0, "{on:?}");
        assert!(on.adversarial > 0.0 && on.discriminator > 0.0, "{on:?}");
    }

    #[test]
    fn distillation_moves_a_smaller_network_toward_the_teacher_and_resumes_exactly() {
        let device = Device::flex().autodiff();
        let pool = pool();
        let dir = std::env::temp_dir().join(format!("posecoach-distill-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // A teacher moved off the analytic solution, which an untrained distilled network
        // already is.
        let mut teacher = Trainer::new(
            TrainConfig {
                learning_rate: 1e-2,
                ..tiny(2)
            },
            &device,
        );
        let batch = teacher.batch_for(&pool, 0).unwrap();
        for _ in 0..5 {
            teacher.step_on(&batch).unwrap();
        }
        let teacher_file = dir.join("teacher.pcw");
        teacher.save_teacher(&teacher_file).unwrap();
        let distilled = TrainConfig {
            teacher: TeacherConfig {
                features: 4,
                ..TeacherConfig::TINY
            },
            ..tiny(2)
        };
        let mut distiller = Trainer::distilling(&teacher_file, distilled, &device).unwrap();
        let losses: Vec<f32> = (0..SMOKE_STEPS)
            .map(|_| distiller.step_on(&batch).unwrap().distillation)
            .collect();
        eprintln!("distillation {losses:.6?}");
        assert!(losses[0] > 0.0);
        assert!(
            losses[SMOKE_STEPS - 1] * SMOKE_FACTOR < losses[0],
            "{losses:?}"
        );
        let checkpoint = dir.join("distilled.pcckpt");
        distiller.save(&checkpoint).unwrap();
        let mut resumed = Trainer::load(&checkpoint, &device).unwrap();
        for _ in 0..2 {
            assert_eq!(
                distiller.train_step(&pool).unwrap(),
                resumed.train_step(&pool).unwrap()
            );
        }
        let distilled_file = dir.join("distilled.pcw");
        resumed.save_teacher(&distilled_file).unwrap();
        let (_, config, steps) = load_teacher(&distilled_file, &Device::flex()).unwrap();
        assert_eq!((config.teacher.features, steps), (4, SMOKE_STEPS + 2));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn switched_off_losses_are_not_computed() {
        let device = Device::flex().autodiff();
        let mut config = tiny(2);
        config.switches = Switches {
            cycle: false,
            effectors: false,
            adversarial: false,
            joint_distances: false,
            geometry: false,
        };
        let mut trainer = Trainer::new(config, &device);
        let losses = trainer.train_step(&pool()).unwrap();
        assert_eq!(losses.total, losses.reconstruction);
        assert_eq!(losses.discriminator, 0.0);
    }

    #[test]
    fn a_resumed_run_continues_as_the_uninterrupted_one() {
        let device = Device::flex().autodiff();
        let pool = pool();
        let dir = std::env::temp_dir().join(format!("posecoach-resume-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("run.pcckpt");
        let mut straight = Trainer::new(tiny(2), &device);
        for _ in 0..2 {
            straight.train_step(&pool).unwrap();
        }
        straight.save(&path).unwrap();
        let mut resumed = Trainer::load(&path, &device).unwrap();
        assert_eq!(resumed.step(), 2);
        for _ in 0..2 {
            let a = straight.train_step(&pool).unwrap();
            let b = resumed.train_step(&pool).unwrap();
            assert_eq!(a, b);
        }
        let teacher = dir.join("teacher.pcw");
        straight.save_teacher(&teacher).unwrap();
        assert!(matches!(
            Trainer::load(&teacher, &device),
            Err(Error::Checkpoint(_))
        ));
        let (_, config, steps) = load_teacher(&teacher, &Device::flex()).unwrap();
        assert_eq!((config, steps), (tiny(2), 4));
        std::fs::write(&teacher, b"PCTEACH1 short").unwrap();
        assert!(matches!(
            load_teacher(&teacher, &Device::flex()),
            Err(Error::TeachFile(teachfile::Error::Legacy { version: 1 }))
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_batch_in_parts_steps_as_the_whole_on_the_per_window_losses() {
        let device = Device::flex().autodiff();
        let pool = pool();
        let dir = std::env::temp_dir().join(format!("posecoach-parts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("start.pcckpt");
        // The adversarial and joint-distance terms are left out: their first step already
        // differs between the whole and its parts (the discriminator and the distance
        // matrices see each part alone), and Adam carries that into every later step.
        let per_window = TrainConfig {
            switches: Switches {
                adversarial: false,
                joint_distances: false,
                ..Switches::ALL
            },
            ..tiny(4)
        };
        Trainer::new(per_window, &device).save(&path).unwrap();
        let mut whole = Trainer::load(&path, &device).unwrap();
        let mut split = Trainer::load(&path, &device).unwrap();
        let one = whole.batch_in(&pool, 0, 1).unwrap();
        let two = split.batch_in(&pool, 0, 2).unwrap();
        assert_eq!((one.len(), two.len()), (1, 2));
        for _ in 0..2 {
            let (a, b) = (whole.step_on(&one).unwrap(), split.step_on(&two).unwrap());
            // Relative to the loss, or to 0.01 for one near zero (an untrained teacher
            // reconstructs exactly, so what is left is float summation order).
            let close = |x: f32, y: f32| (x - y).abs() <= 1e-3 * x.abs().max(1e-2);
            assert!(close(a.reconstruction, b.reconstruction), "{a:?}\n{b:?}");
            assert!(
                close(a.cycle, b.cycle) && close(a.effectors, b.effectors),
                "{a:?}\n{b:?}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The smallest network the bounds allow: 2 features, one head, kernel 1.
    const SMALLEST: TeacherConfig = TeacherConfig {
        features: 2,
        heads: 1,
        kernel: 1,
        prior: PriorKind::Chords,
    };

    /// A network file of `teacher`'s sizes, untrained, as `save_teacher` writes it.
    fn network_file(teacher: TeacherConfig, name: &str) -> Vec<u8> {
        let dir = std::env::temp_dir().join(format!("posecoach-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("net.pcw");
        let config = TrainConfig { teacher, ..tiny(2) };
        Trainer::new(config, &Device::flex().autodiff())
            .save_teacher(&path)
            .unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        bytes
    }

    /// `bytes` with header word `i` (the part count at `HEADER_WORDS`) set to `value` and the
    /// CRC made to match again: what a deliberate edit, not damage, looks like.
    fn forged(bytes: &[u8], i: usize, value: u64) -> Vec<u8> {
        let mut out = bytes.to_vec();
        let at = teachfile::MAGIC.len() + 8 * i;
        out[at..at + 8].copy_from_slice(&value.to_le_bytes());
        let n = out.len() - 4;
        let crc = teachfile::checksum(&out[..n]);
        out[n..].copy_from_slice(&crc.to_le_bytes());
        out
    }

    #[test]
    fn every_single_bit_flip_of_a_small_network_file_is_rejected() {
        let mut bytes = network_file(SMALLEST, "flips");
        let device = Device::flex();
        let (teacher, config, _) = teacher_from_bytes(&bytes, &device).unwrap();
        assert_eq!(config.teacher, SMALLEST);
        let start = Instant::now();
        for bit in 0..bytes.len() * 8 {
            bytes[bit / 8] ^= 1 << (bit % 8);
            match teacher_from_bytes(&bytes, &device) {
                Err(Error::TeachFile(_)) => {}
                Err(e) => panic!("bit {bit}: {e}"),
                Ok(_) => panic!("bit {bit} flipped was read"),
            }
            bytes[bit / 8] ^= 1 << (bit % 8);
        }
        eprintln!(
            "{} bits of a {}-byte file ({} parameters), each flip rejected, in {:?}",
            bytes.len() * 8,
            bytes.len(),
            teacher.num_params(),
            start.elapsed()
        );
    }

    /// What a header word set to a value does to the smallest network's file.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Outcome {
        /// Refused by its bound, naming the word.
        Refused,
        /// Within bounds and the network loads.
        Loads,
        /// Within bounds, but the network it describes is not the file's: burn's record
        /// refuses its shapes.
        Mismatch,
    }

    #[test]
    fn header_words_out_of_bounds_are_refused_before_the_network_is_built() {
        use Outcome::{Loads, Mismatch, Refused};
        // 0, odd, huge and all ones, as the hostile-input campaign tried them.
        const VALUES: [u64; 4] = [0, 3, 1 << 40, u64::MAX];
        let cases: [(&str, [Outcome; 4]); teachfile::HEADER_WORDS + 1] = [
            ("step", [Loads, Loads, Refused, Refused]),
            ("seed", [Loads, Loads, Loads, Loads]),
            ("batch", [Refused, Loads, Refused, Refused]),
            ("features", [Refused, Refused, Refused, Refused]),
            // 3 heads exceed 2 features.
            ("heads", [Refused, Refused, Refused, Refused]),
            ("kernel", [Refused, Mismatch, Refused, Refused]),
            ("switches", [Loads, Loads, Refused, Refused]),
            // As bits: 0.0, two positive subnormals, a NaN.
            ("learning_rate", [Refused, Loads, Loads, Refused]),
            ("prior", [Loads, Refused, Refused, Refused]),
            (teachfile::PARTS_WORD, [Refused; 4]),
        ];
        let bytes = network_file(SMALLEST, "words");
        let device = Device::flex();
        for (i, (name, outcomes)) in cases.iter().enumerate() {
            for (&value, &want) in VALUES.iter().zip(outcomes) {
                let got =
                    match teacher_from_bytes(&forged(&bytes, i, value), &device) {
                        Ok(_) => Loads,
                        Err(Error::TeachFile(teachfile::Error::Word {
                            word, value: v, ..
                        })) if word == *name && v == value => Refused,
                        Err(Error::Checkpoint(_)) => Mismatch,
                        Err(e) => panic!("{name} = {value}: {e}"),
                    };
                assert_eq!(got, want, "{name} = {value}");
            }
        }
        let error = teacher_from_bytes(&forged(&bytes, 3, 1 << 40), &device).unwrap_err();
        assert_eq!(
            error.to_string(),
            "float weights: header word `features` is 1099511627776; it must be even, \
             from 2 to 256"
        );
    }

    #[test]
    fn a_header_that_describes_another_network_than_its_part_is_refused() {
        let bytes = network_file(SMALLEST, "other");
        let device = Device::flex();
        // Wider, or a wider kernel: the record's shapes are not the network's.
        for (word, value) in [(3, 4), (3, teachfile::MAX_FEATURES), (5, 15)] {
            assert!(
                matches!(
                    teacher_from_bytes(&forged(&bytes, word, value), &device),
                    Err(Error::Checkpoint(_))
                ),
                "word {word} = {value}"
            );
        }
        // Heads and prior are no parameters' shapes: the network loads, and runs.
        let heads = forged(&bytes, 4, 2);
        let prior = forged(&heads, 8, 1);
        let (teacher, config, _) = teacher_from_bytes(&prior, &device).unwrap();
        assert_eq!(
            (config.teacher.heads, teacher.prior()),
            (2, PriorKind::Rotations)
        );
    }

    #[test]
    fn networks_at_the_size_bounds_train_without_panicking() {
        let device = Device::flex().autodiff();
        let pool = pool();
        for teacher in [
            SMALLEST,
            TeacherConfig {
                features: 2,
                heads: 2,
                kernel: teachfile::MAX_KERNEL as usize,
                prior: PriorKind::Rotations,
            },
            TeacherConfig {
                features: 6,
                heads: 3,
                kernel: 5,
                prior: PriorKind::Chords,
            },
        ] {
            let config = TrainConfig { teacher, ..tiny(2) };
            config.check().unwrap();
            let mut trainer = Trainer::new(config, &device);
            let batch = trainer.batch_for(&pool, 0).unwrap();
            let losses = trainer.step_on(&batch).unwrap();
            assert!(losses.total.is_finite(), "{teacher:?}: {losses:?}");
        }
        let wide = TrainConfig {
            teacher: TeacherConfig {
                features: 7,
                ..TeacherConfig::TINY
            },
            ..tiny(2)
        };
        assert!(matches!(
            wide.check(),
            Err(Error::TeachFile(teachfile::Error::Word {
                word: "features",
                value: 7,
                ..
            }))
        ));
    }

    fn committed(name: &str) -> Vec<u8> {
        let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../weights")
            .join(name);
        std::fs::read(path).unwrap()
    }

    /// The committed float networks, converted to version 3 with their words and parts
    /// unchanged: the headers they were trained with.
    #[test]
    fn the_committed_networks_are_version_3_with_their_training_headers() {
        let rotations = |features| TeacherConfig {
            features,
            prior: PriorKind::Rotations,
            ..TeacherConfig::DEFAULT
        };
        let chords = |features| TeacherConfig {
            features,
            prior: PriorKind::Chords,
            ..TeacherConfig::DEFAULT
        };
        for (name, teacher, steps, learning_rate) in [
            ("teacher.pcw", rotations(32), 10_000, 1e-4),
            ("teacher-chords.pcw", chords(32), 20_000, 1e-3),
            ("distilled.pcw", chords(16), 10_000, 1e-3),
        ] {
            let bytes = committed(name);
            assert_eq!(&bytes[..8], b"PCTEACH3", "{name}");
            let file = teachfile::decode(&bytes).unwrap();
            assert_eq!(file.kind, teachfile::Kind::Network, "{name}");
            let header = Header::from_file(&file.header);
            let want = TrainConfig {
                teacher,
                batch: 8,
                learning_rate,
                switches: Switches::ALL,
                seed: 0,
            };
            assert_eq!((header.config, header.step), (want, steps), "{name}");
        }
    }

    /// Flips of the committed teacher, seeded: every one is refused.
    #[test]
    fn sampled_bit_flips_of_the_committed_teacher_are_rejected() {
        use rand::SeedableRng;
        const FLIPS: usize = 2000;
        let mut bytes = committed("teacher.pcw");
        let device = Device::flex();
        assert!(teacher_from_bytes(&bytes, &device).is_ok());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(SEED);
        let (mut damaged, mut magic) = (0, 0);
        let start = Instant::now();
        for _ in 0..FLIPS {
            let bit = rng.random_range(0..bytes.len() * 8);
            bytes[bit / 8] ^= 1 << (bit % 8);
            match teacher_from_bytes(&bytes, &device) {
                Err(Error::TeachFile(teachfile::Error::Checksum { .. })) => damaged += 1,
                Err(Error::TeachFile(_)) if bit < 64 => magic += 1,
                Err(e) => panic!("bit {bit}: {e}"),
                Ok(_) => panic!("bit {bit} flipped was read"),
            }
            bytes[bit / 8] ^= 1 << (bit % 8);
        }
        eprintln!(
            "{FLIPS} flips of the committed teacher: {damaged} by the checksum, {magic} by the \
             magic, in {:?}",
            start.elapsed()
        );
        assert_eq!(damaged + magic, FLIPS);
    }

    /// Time per training step of the default teacher with every loss (batch 8): run in
    /// release with `cargo test --release -p posecoach-train -- --ignored --nocapture step_time`.
    #[test]
    #[ignore = "a timing, run in release"]
    fn step_time() {
        let device = Device::flex().autodiff();
        let mut trainer = Trainer::new(
            TrainConfig {
                seed: SEED,
                ..TrainConfig::default()
            },
            &device,
        );
        let batch = trainer.batch_for(&pool(), 0).unwrap();
        trainer.step_on(&batch).unwrap();
        let start = Instant::now();
        for _ in 0..TIMED_STEPS {
            trainer.step_on(&batch).unwrap();
        }
        let per_step = start.elapsed() / TIMED_STEPS as u32;
        let params = trainer.teacher().num_params();
        eprintln!("default teacher ({params} parameters), batch {BATCH}, every loss: {per_step:?} per step");
    }
}
