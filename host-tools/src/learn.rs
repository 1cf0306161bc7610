//! `posecoach train`, `posecoach distill`, `posecoach finetune` and `posecoach eval`: the
//! learned retargeter.
//!
//! Training draws every batch at random (clip, window, characters), so an *epoch* is a fixed
//! [`STEPS_PER_EPOCH`] steps rather than a pass over the data; a checkpoint is written after
//! each, and a run resumed from one continues exactly as if it had not stopped.

use crate::inspect;
use crate::progress::Progress;
use anyhow::{bail, Context, Result};
use burn::prelude::Device;
use posecoach_core::network;
use posecoach_core::weights::{self, Training, Weights};
use posecoach_io as io;
use posecoach_train::dataset::Pool;
use posecoach_train::infer::Retargeter;
use posecoach_train::losses::Switches;
use posecoach_train::metrics::{self, Baseline, Method, Table};
use posecoach_train::model::TeacherConfig;
use posecoach_train::prior::PriorKind;
use posecoach_train::quantize;
use posecoach_train::train::{StepLosses, TrainConfig, Trainer, BATCH, LEARNING_RATE};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Steps in an epoch.
pub const STEPS_PER_EPOCH: usize = 1000;
/// The progress bar's loss is the mean over this many steps; without a terminal for the bar,
/// a line of every loss's mean is printed instead.
pub const LOG_EVERY: usize = 100;
/// Synthetic golf swings and putts added to each split.
pub const SYNTHETIC_SWINGS: usize = 40;
/// Steps of a per-student fine-tune.
pub const FINETUNE_STEPS: usize = 200;
/// Learning rate of a fine-tune.
pub const FINETUNE_LEARNING_RATE: f64 = 2e-4;

/// Where the motion data is: `--data` folders, else `$POSECOACH_DATA`, else `../shared/data`.
#[derive(clap::Args)]
pub struct Data {
    /// Folders of motion files (.bvh, .c3d), searched recursively; repeatable.
    #[arg(long = "data")]
    dirs: Vec<PathBuf>,
    /// Synthetic golf swings and putts added to each split.
    #[arg(long, default_value_t = SYNTHETIC_SWINGS)]
    synthetic: usize,
}

impl Data {
    /// The clips of every folder, plus the synthetic swings seeded by `seed`.
    fn pool(&self, seed: u64) -> Result<Pool> {
        let dirs = match self.dirs.is_empty() {
            false => self.dirs.clone(),
            true => vec![std::env::var_os("POSECOACH_DATA")
                .map_or_else(|| PathBuf::from("../shared/data"), PathBuf::from)],
        };
        let mut pool = Pool::default();
        for dir in &dirs {
            if !dir.is_dir() {
                bail!(
                    "no motion data at {}: pass --data DIR or set POSECOACH_DATA",
                    dir.display()
                );
            }
            let more = Pool::load(dir).with_context(|| format!("loading {}", dir.display()))?;
            pool.train.extend(more.train);
            pool.eval.extend(more.eval);
            pool.raw_eval.extend(more.raw_eval);
        }
        pool.add_synthetic_golf(self.synthetic, seed)?;
        Ok(pool)
    }
}

/// The losses an ablation switches off.
#[derive(clap::Args)]
pub struct Ablations {
    /// Train without the cycle loss.
    #[arg(long)]
    no_cycle: bool,
    /// Train without the end-effector velocity loss.
    #[arg(long)]
    no_effectors: bool,
    /// Train without the adversarial loss.
    #[arg(long)]
    no_adversarial: bool,
    /// Train without the joint-distance-matrix loss.
    #[arg(long)]
    no_jdm: bool,
    /// Train without the geometry loss.
    #[arg(long)]
    no_geometry: bool,
}

impl Ablations {
    fn switches(&self) -> Switches {
        Switches {
            cycle: !self.no_cycle,
            effectors: !self.no_effectors,
            adversarial: !self.no_adversarial,
            joint_distances: !self.no_jdm,
            geometry: !self.no_geometry,
        }
    }
}

#[derive(clap::Args)]
pub struct TrainArgs {
    #[command(flatten)]
    data: Data,
    /// Epochs of STEPS_PER_EPOCH (1000) steps, counting those a resumed checkpoint has done.
    #[arg(long, default_value_t = 14)]
    epochs: usize,
    /// Seeds the weights and every batch.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Windows per batch.
    #[arg(long, default_value_t = BATCH)]
    batch: usize,
    /// Adam's starting learning rate (a third of it after each of 5 000 and 15 000 steps).
    #[arg(long, default_value_t = LEARNING_RATE)]
    learning_rate: f64,
    /// Continue the run in this checkpoint.
    #[arg(long)]
    resume: Option<PathBuf>,
    /// The checkpoint, rewritten after every epoch.
    #[arg(long)]
    out: PathBuf,
    /// Also write the teacher alone here at the end (what `--weights` needs; small).
    #[arg(long)]
    teacher: Option<PathBuf>,
    /// Correct the analytic retargeter's bone directions (as the device's network does)
    /// instead of the rotation transfer.
    #[arg(long)]
    chords: bool,
    #[command(flatten)]
    ablations: Ablations,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn train(args: &TrainArgs) -> Result<String> {
    let device = Device::flex().autodiff();
    let prior = match args.chords {
        true => PriorKind::Chords,
        false => PriorKind::Rotations,
    };
    let config = TrainConfig {
        teacher: TeacherConfig {
            prior,
            ..TeacherConfig::DEFAULT
        },
        batch: args.batch,
        learning_rate: args.learning_rate,
        switches: args.ablations.switches(),
        seed: args.seed,
    };
    let trainer = match &args.resume {
        Some(path) => Trainer::load(path, &device)
            .with_context(|| format!("resuming from {}", path.display()))?,
        None => {
            // What the checkpoints could not state is refused now, not at the first one.
            config.check()?;
            Trainer::new(config, &device)
        }
    };
    let pool = args.data.pool(trainer.config().seed)?;
    let steps = args.epochs * STEPS_PER_EPOCH;
    run(
        trainer,
        &pool,
        steps,
        &args.out,
        args.teacher.as_deref(),
        args.json,
    )
}

/// The distilled network's default sizes: half the teacher's features per segment.
pub const DISTILLED: TeacherConfig = TeacherConfig {
    features: 16,
    heads: 2,
    kernel: 3,
    prior: PriorKind::Chords,
};

#[derive(clap::Args)]
pub struct DistillArgs {
    /// The trained teacher (checkpoint or teacher file).
    #[arg(long)]
    teacher: PathBuf,
    #[command(flatten)]
    data: Data,
    /// Epochs of STEPS_PER_EPOCH (1000) steps, counting those a resumed checkpoint has done.
    #[arg(long, default_value_t = 10)]
    epochs: usize,
    /// Seeds the distilled network's weights and every batch.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Features per segment of the distilled network (even, a multiple of `--heads`).
    #[arg(long, default_value_t = DISTILLED.features)]
    features: usize,
    /// Attention heads of the distilled network.
    #[arg(long, default_value_t = DISTILLED.heads)]
    heads: usize,
    /// Kernel size of the distilled network's temporal convolutions (odd).
    #[arg(long, default_value_t = DISTILLED.kernel)]
    kernel: usize,
    /// Windows per batch.
    #[arg(long, default_value_t = BATCH)]
    batch: usize,
    /// Adam's starting learning rate (a third of it after each of 5 000 and 15 000 steps).
    #[arg(long, default_value_t = LEARNING_RATE)]
    learning_rate: f64,
    /// Continue the distillation in this checkpoint (it carries the teacher).
    #[arg(long)]
    resume: Option<PathBuf>,
    /// The checkpoint, rewritten after every epoch.
    #[arg(long)]
    out: PathBuf,
    /// Also write the distilled network alone here at the end (what `--weights` and `export`
    /// read).
    #[arg(long)]
    distilled: Option<PathBuf>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn distill(args: &DistillArgs) -> Result<String> {
    let device = Device::flex().autodiff();
    let sizes = TeacherConfig {
        features: args.features,
        heads: args.heads,
        kernel: args.kernel,
        prior: DISTILLED.prior,
    };
    if sizes.heads == 0
        || !sizes.features.is_multiple_of(2 * sizes.heads)
        || sizes.kernel.is_multiple_of(2)
    {
        bail!(
            "--features {} must be even and a multiple of --heads {}, and --kernel {} odd",
            sizes.features,
            sizes.heads,
            sizes.kernel
        );
    }
    let trainer = match &args.resume {
        Some(path) => Trainer::load(path, &device)
            .with_context(|| format!("resuming from {}", path.display()))?,
        None => {
            let config = TrainConfig {
                teacher: sizes,
                batch: args.batch,
                learning_rate: args.learning_rate,
                seed: args.seed,
                ..TrainConfig::default()
            };
            config.check()?;
            Trainer::distilling(&args.teacher, config, &device)
                .with_context(|| format!("loading {}", args.teacher.display()))?
        }
    };
    let pool = args.data.pool(trainer.config().seed)?;
    let steps = args.epochs * STEPS_PER_EPOCH;
    run(
        trainer,
        &pool,
        steps,
        &args.out,
        args.distilled.as_deref(),
        args.json,
    )
}

#[derive(clap::Args)]
pub struct FinetuneArgs {
    /// The trained teacher (checkpoint or teacher file).
    #[arg(long)]
    weights: PathBuf,
    /// The student's T-pose: a one-row CSV, or any motion file whose skeleton is used.
    #[arg(long)]
    student_tpose: PathBuf,
    #[command(flatten)]
    data: Data,
    /// Fine-tuning steps.
    #[arg(long, default_value_t = FINETUNE_STEPS)]
    steps: usize,
    /// Seeds the batches.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Where to write the student's teacher.
    #[arg(long)]
    out: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn finetune(args: &FinetuneArgs) -> Result<String> {
    let device = Device::flex().autodiff();
    let student = io::load(&args.student_tpose)?.skeleton;
    let config = TrainConfig {
        learning_rate: FINETUNE_LEARNING_RATE,
        seed: args.seed,
        ..TrainConfig::default()
    };
    let trainer = Trainer::from_teacher(&args.weights, config, &device)
        .with_context(|| format!("loading {}", args.weights.display()))?
        .for_student(student);
    let pool = args.data.pool(args.seed)?;
    run(trainer, &pool, args.steps, &args.out, None, args.json)
}

/// Trains until `steps`, checkpointing every epoch and at the end.
fn run(
    mut trainer: Trainer,
    pool: &Pool,
    steps: usize,
    out: &Path,
    teacher: Option<&Path>,
    json: bool,
) -> Result<String> {
    let bar = Progress::new(steps as u64, "steps").at(trainer.step() as u64);
    let start = Instant::now();
    let first = trainer.step();
    let mut epochs = Vec::new();
    let (mut sums, mut count) = (StepLosses::default(), 0);
    let (mut recent, mut recent_count) = (StepLosses::default(), 0);
    while trainer.step() < steps {
        let losses = trainer.train_step(pool)?;
        sums = sums.plus(&losses);
        recent = recent.plus(&losses);
        (count, recent_count) = (count + 1, recent_count + 1);
        bar.inc();
        if trainer.step().is_multiple_of(LOG_EVERY) {
            let mean = recent.times(1.0 / recent_count as f32);
            bar.set_message(format!("loss {:.3}", mean.total));
            if bar.is_hidden() {
                let elapsed = start.elapsed().as_secs_f64();
                eprintln!(
                    "step {:>6}/{steps} {elapsed:>6.0} s  {}",
                    trainer.step(),
                    describe(&mean)
                );
            }
            (recent, recent_count) = (StepLosses::default(), 0);
        }
        if trainer.step().is_multiple_of(STEPS_PER_EPOCH) || trainer.step() == steps {
            trainer.save(out)?;
            let mean = sums.times(1.0 / count.max(1) as f32);
            let line = format!(
                "epoch done at step {:>6}: {}",
                trainer.step(),
                describe(&mean)
            );
            match bar.is_hidden() {
                true => eprintln!("{line}"),
                false => bar.println(&line),
            }
            epochs.push(json!({"step": trainer.step(), "losses": losses_json(&mean)}));
            (sums, count) = (StepLosses::default(), 0);
        }
    }
    bar.finish_and_clear();
    // Nothing left to train (`--epochs 0`, or a checkpoint already there): the checkpoint
    // named is still written, as it stands (at step 0, the untrained prior).
    if trainer.step() == first {
        trainer.save(out)?;
    }
    if let Some(path) = teacher {
        trainer.save_teacher(path)?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let taken = trainer.step() - first;
    let summary = json!({
        "steps": trainer.step(),
        "steps_this_run": taken,
        "seconds": seconds,
        "ms_per_step": 1e3 * seconds / taken.max(1) as f64,
        "epochs": epochs,
        "checkpoint": out.display().to_string(),
        "teacher": teacher.map(|p| p.display().to_string()),
    });
    Ok(match json {
        true => format!("{summary}\n"),
        false => format!(
            "{taken} steps in {seconds:.0} s ({:.0} ms per step); checkpoint {}{}\n",
            1e3 * seconds / taken.max(1) as f64,
            out.display(),
            teacher.map_or(String::new(), |p| format!(", teacher {}", p.display())),
        ),
    })
}

fn losses_json(l: &StepLosses) -> Value {
    json!({
        "total": l.total, "reconstruction": l.reconstruction, "cycle": l.cycle,
        "effectors": l.effectors, "adversarial": l.adversarial,
        "joint_distances": l.joint_distances, "geometry": l.geometry,
        "discriminator": l.discriminator, "distillation": l.distillation,
    })
}

fn describe(l: &StepLosses) -> String {
    if l.distillation > 0.0 {
        return format!("distillation {:.7}", l.distillation);
    }
    format!(
        "total {:.4}  rec {:.4}  cycle {:.4}  eff {:.5}  adv {:.3}  jdm {:.4}  geo {:.6}  disc {:.3}",
        l.total,
        l.reconstruction,
        l.cycle,
        l.effectors,
        l.adversarial,
        l.joint_distances,
        l.geometry,
        l.discriminator
    )
}

#[derive(clap::Args)]
pub struct EvalArgs {
    /// A trained teacher (checkpoint or teacher file); repeatable.
    #[arg(long)]
    weights: Vec<PathBuf>,
    /// Include the analytic retargeter (bone-direction copy).
    #[arg(long)]
    analytic: bool,
    /// Include the rotation copy from the format's standard T-pose.
    #[arg(long)]
    copy: bool,
    /// Include the ground truth itself: no joint error by definition, but its own grip, foot
    /// slide and club head, which its convention gives.
    #[arg(long)]
    truth: bool,
    /// Also each method (the ground truth aside) with golf's contacts kept: planted feet, both
    /// hands on one grip, the club head at the ball (`posecoach_core::contacts`).
    #[arg(long)]
    contacts: bool,
    #[command(flatten)]
    data: Data,
    /// Seeds the evaluation characters.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn eval(args: &EvalArgs) -> Result<String> {
    let teachers = args
        .weights
        .iter()
        .map(|p| Retargeter::load(p).with_context(|| format!("loading {}", p.display())))
        .collect::<Result<Vec<_>>>()?;
    let mut retargeters: Vec<Method> = teachers.iter().map(Method::Teacher).collect();
    if args.analytic {
        retargeters.push(Method::Baseline(Baseline::Analytic));
    }
    if args.copy {
        retargeters.push(Method::Baseline(Baseline::RotationCopy));
    }
    let mut methods = retargeters.clone();
    if args.contacts {
        methods.extend(retargeters.iter().map(Method::Contacts));
    }
    if args.truth {
        methods.push(Method::Baseline(Baseline::GroundTruth));
    }
    if methods.is_empty() {
        bail!("nothing to evaluate: pass --weights FILE, --analytic, --copy or --truth");
    }
    let pool = args.data.pool(args.seed)?;
    let bar = Progress::new(0, "pairs");
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let mut table = metrics::table(&pool, args.seed, &methods, progress)?;
    // The golf blocks need golf swings, the rest-pose block BVH files: without them, left out.
    let (mut posture, mut raw) = (Vec::new(), Vec::new());
    if pool.eval.iter().any(|c| c.has_club()) {
        bar.set_message("onto phone formats");
        table.rows.extend(metrics::onto_phone_formats(
            &pool, args.seed, &methods, progress,
        )?);
        bar.set_message("posture error");
        posture = metrics::posture_error(&pool, args.seed, &methods, progress)?;
    }
    if !pool.raw_eval.is_empty() {
        bar.set_message("coach files' own rest poses");
        raw = metrics::raw_rests(&pool, args.seed, &methods, progress)?;
    }
    bar.finish_and_clear();
    Ok(match args.json {
        true => {
            let mut doc = table_json(&table, &args.weights, &teachers);
            doc["posture_error"] = posture_json(&posture);
            doc["raw_rests"] = raw_json(&raw);
            format!("{doc}\n")
        }
        false => {
            let mut text = String::new();
            for (path, t) in args.weights.iter().zip(&teachers) {
                text += &format!("teacher {}: {} steps\n", path.display(), t.steps);
            }
            let (lo, hi) = metrics::POSTURE_ERROR_DEG;
            text += &table.to_string();
            if !posture.is_empty() {
                text += &format!(
                    "-- golf swings onto a T-pose with each body bone turned {lo}-{hi} degrees: how far the output moves\n{:<6} {:<14} {:>5} {:>13} {:>12}\n",
                    "pairs", "method", "n", "mean cm", "largest cm"
                );
                for row in &posture {
                    text += &format!("{row}\n");
                }
            }
            if !raw.is_empty() {
                text += &format!(
                    "-- BVH files on their own rest poses, and re-rested on the standard T-pose (the same positions)\n{:<6} {:<14} {:>5} {:>15} {:>15}\n",
                    "pairs", "method", "n", "own rest %h", "standard %h"
                );
                for row in &raw {
                    text += &format!("{row}\n");
                }
            }
            text
        }
    })
}

fn raw_json(rows: &[metrics::RawRow]) -> Value {
    Value::Array(
        rows.iter()
            .map(|r| {
                json!({
                    "structure": format!("{:?}", r.structure).to_lowercase(),
                    "method": r.method,
                    "pairs": r.pairs,
                    "own_rest_pct_height": r.raw * 100.0,
                    "standard_rest_pct_height": r.standard * 100.0,
                })
            })
            .collect(),
    )
}

fn posture_json(rows: &[metrics::PostureRow]) -> Value {
    let (lo, hi) = metrics::POSTURE_ERROR_DEG;
    json!({
        "turn_deg": [lo, hi],
        "rows": rows.iter().map(|r| json!({
            "structure": format!("{:?}", r.structure).to_lowercase(),
            "method": r.method,
            "pairs": r.pairs,
            "mean_cm": r.mean * 100.0,
            "max_cm": r.max * 100.0,
        })).collect::<Vec<_>>(),
    })
}

fn table_json(table: &Table, paths: &[PathBuf], teachers: &[Retargeter]) -> Value {
    let rows: Vec<Value> = table
        .rows
        .iter()
        .map(|r| {
            json!({
                "block": r.block,
                "structure": format!("{:?}", r.structure).to_lowercase(),
                "rest": r.rest,
                "method": r.method,
                "pairs": r.pairs,
                "global_pct_height": r.global * 100.0,
                "local_pct_height": r.local * 100.0,
                "golf_pairs": r.golf,
                "hand_gap_error_cm": r.hand_gap.map(|g| [g[0] * 100.0, g[1] * 100.0]),
                "foot_slide_beyond_coach_cm_s": r.foot_slide.map(|s| s * 100.0),
                "foot_height_error_cm": r.foot_height.map(|h| h * 100.0),
                "club_pairs": r.clubs,
                "club_head_error_cm": r.club_head.map(|h| [h[0] * 100.0, h[1] * 100.0]),
            })
        })
        .collect();
    json!({
        "teachers": paths.iter().zip(teachers).map(|(p, t)| json!({
            "file": p.display().to_string(), "steps": t.steps})).collect::<Vec<_>>(),
        "clips": table.clips.iter().map(|(n, f)| json!({"name": n, "frames": f})).collect::<Vec<_>>(),
        "rows": rows,
    })
}

/// Golf windows the activation scales are calibrated on by default.
pub const CALIBRATION_WINDOWS: usize = 512;
/// Windows per calibration batch.
const CALIBRATION_BATCH: usize = 32;
/// Height of the default golden student, metres.
const GOLDEN_HEIGHT_M: f32 = 1.70;

#[derive(clap::Args)]
pub struct ExportArgs {
    /// The trained network to quantize: the distilled network (teacher file or checkpoint).
    #[arg(long)]
    model: PathBuf,
    /// Golf windows the activation scales are calibrated on.
    #[arg(long, default_value_t = CALIBRATION_WINDOWS)]
    windows: usize,
    #[command(flatten)]
    data: Data,
    /// Seeds the calibration windows.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Where to write the weights blob (.pcw).
    #[arg(long)]
    out: PathBuf,
    /// Also write golden vectors: this coach swing at the network's rate (OUT with
    /// `.golden-in.pcr`) and the int8 network's retargeting of it (`.golden-out.pcr`), both
    /// in `f32` metres.
    #[arg(long)]
    golden: Option<PathBuf>,
    /// The golden retargeting's student (a T-pose file); H36M-17 at 1.70 m by default.
    #[arg(long)]
    golden_student: Option<PathBuf>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn export(args: &ExportArgs) -> Result<String> {
    let device = Device::flex();
    let (model, config, steps) = posecoach_train::train::load_teacher(&args.model, &device)
        .with_context(|| format!("loading {}", args.model.display()))?;
    if args.windows == 0 {
        bail!("--windows must be at least 1");
    }
    let pool = args.data.pool(args.seed)?;
    let bar = Progress::new(args.windows as u64, "windows");
    bar.set_message("calibrating");
    let calibration = quantize::calibrate(
        &model,
        &pool,
        args.windows,
        CALIBRATION_BATCH,
        args.seed,
        &device,
    )?;
    bar.finish_and_clear();
    let name: String = args
        .model
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy().into_owned());
    let training = Training {
        name: truncated(&name),
        steps: steps as u32,
        seed: config.seed,
        calibration_windows: calibration.windows as u32,
        formats: quantize::trained_formats(),
    };
    let scales = calibration.scales();
    let bytes = quantize::export(&model, &config.teacher, &scales, training)?;
    std::fs::write(&args.out, &bytes).with_context(|| format!("writing {}", args.out.display()))?;
    let golden = match &args.golden {
        Some(coach) => Some(write_golden(
            &bytes,
            coach,
            args.golden_student.as_deref(),
            &args.out,
        )?),
        None => None,
    };
    let header = inspect::weights_header(&bytes)?;
    if args.json {
        let doc = json!({"out": args.out.display().to_string(), "bytes": bytes.len(),
            "header": header, "golden": golden.map(|(i, o)| [i.display().to_string(), o.display().to_string()])});
        return Ok(format!("{doc}\n"));
    }
    let mut text = format!(
        "wrote int8 weights ({} bytes, scales from {} golf windows) to {}\n",
        bytes.len(),
        calibration.windows,
        args.out.display()
    );
    if let Some((i, o)) = golden {
        text += &format!("golden vectors: {} -> {}\n", i.display(), o.display());
    }
    Ok(text + &inspect::weights_text(&header))
}

/// Writes the golden vectors of `bytes` next to `out`; returns their paths.
fn write_golden(
    bytes: &[u8],
    coach: &Path,
    student: Option<&Path>,
    out: &Path,
) -> Result<(PathBuf, PathBuf)> {
    let mut words = vec![0u32; bytes.len().div_ceil(4)];
    bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
    let weights = Weights::from_bytes(&bytemuck::cast_slice::<u32, u8>(&words)[..bytes.len()])?;
    let rate = weights.architecture().rate_hz;
    let source = io::load(coach)?.resampled(rate)?;
    if source.frames() == 0 {
        bail!("{} holds no frames", coach.display());
    }
    let student = match student {
        Some(path) => io::load(path)?.skeleton,
        None => {
            let standard = posecoach_core::skeleton::Skeleton::standard(
                posecoach_core::format::Format::H36m17,
            )?;
            let scale = GOLDEN_HEIGHT_M / standard.height();
            let offsets: Vec<_> = standard.offsets().iter().map(|o| o * scale).collect();
            let parents: Vec<_> = (0..standard.len()).map(|k| standard.parent(k)).collect();
            posecoach_core::skeleton::Skeleton::new(
                standard.format(),
                &parents,
                &offsets,
                standard.joints(),
            )?
        }
    };
    let mut scratch = vec![0u32; network::MAX_SCRATCH.div_ceil(4)];
    let mut positions = vec![posecoach_core::Vec3::zeros(); source.frames() * student.len()];
    network::retarget(
        &weights,
        &source.skeleton,
        &student,
        &source.positions,
        bytemuck::cast_slice_mut(&mut scratch),
        &mut positions,
    )?;
    let result = io::Motion {
        missing: vec![false; positions.len()],
        names: (0..student.len())
            .map(|k| {
                student
                    .joint(k)
                    .map_or(String::new(), |j| j.name().to_string())
            })
            .collect(),
        skeleton: student,
        rate_hz: rate,
        positions,
    };
    let path = |suffix: &str| out.with_extension(suffix);
    let (input, output) = (path("golden-in.pcr"), path("golden-out.pcr"));
    // In metres: the exact floats the network takes and gives, which the tests and the
    // firmware compare to the bit.
    let metres = posecoach_core::reference::Units::Metres;
    std::fs::write(&input, source.to_reference("golden-in", metres)?)?;
    std::fs::write(&output, result.to_reference("golden-out", metres)?)?;
    Ok((input, output))
}

/// `name` cut to the header's [`weights::MAX_NAME`] bytes at a character boundary.
fn truncated(name: &str) -> heapless::String<{ weights::MAX_NAME }> {
    let mut out = heapless::String::new();
    for c in name.chars() {
        if out.push(c).is_err() {
            break;
        }
    }
    out
}
