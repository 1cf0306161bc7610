//! Train/eval splits of motions and characters, and retargeting pairs with their ground truth.
//!
//! **Characters** are split by random stream: a [`SplitRng`] is ChaCha8 seeded by the caller
//! on stream 0 for training and stream 1 for evaluation, so no evaluation character can come
//! out of any training seed. **Motions** are split by file: the files named in [`HELD_OUT`]
//! are for evaluation only (one golf swing, the iron; one of the two CMU trials; four Bandai
//! clips, of styles otherwise unseen: tired, happy, elderly walking and waving), every other
//! file is for training.
//!
//! A [`Pair`] is a clip of the split put on a random character `A` in format `X` (the source),
//! a random character `B` in format `Y` (the target), and the clip on `B` (the ground truth,
//! [`crate::clip::ground_truth`]); `X == Y` for [`Structure::Intra`] pairs.

use crate::bodies::{Body, Character, Variation};
use crate::clip::{standard_rest, Clip};
use crate::error::Error;
use crate::features::{Window, RATE_HZ, WINDOW};
use crate::golfgen::{self, SwingParams};
use posecoach_core::format::{t_pose, Format};
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
use posecoach_io::{self as io, Motion};
use rand::seq::IndexedRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

/// Rate every clip is resampled to (frames per second): swing events need 60 Hz.
pub const CLIP_RATE_HZ: f32 = 60.0;

/// File stems held out for evaluation.
pub const HELD_OUT: [&str; 6] = [
    "gears_tour_iron",
    "131_02",
    "dataset-1_walk_tired_001",
    "dataset-1_run_happy_001",
    "dataset-1_bye_normal_001",
    "dataset-2_walk_elderly_001",
];

/// The formats characters are built in.
pub const FORMATS: [Format; 6] = [
    Format::H36m17,
    Format::Coco17,
    Format::Cmu31,
    Format::Bandai22,
    Format::GolfMarkers,
    Format::Canonical,
];

/// Training or evaluation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Split {
    /// Used to fit the model.
    Train,
    /// Never seen in training.
    Eval,
}

impl Split {
    /// The ChaCha stream of this split's characters.
    const fn stream(self) -> u64 {
        match self {
            Split::Train => 0,
            Split::Eval => 1,
        }
    }

    /// `train` or `eval`.
    pub const fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Eval => "eval",
        }
    }
}

/// A random source that belongs to one split: characters and pairs drawn from it are that
/// split's.
#[derive(Clone, Debug)]
pub struct SplitRng {
    split: Split,
    rng: ChaCha8Rng,
}

impl SplitRng {
    /// The `seed`th generator of `split`.
    pub fn new(split: Split, seed: u64) -> SplitRng {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(split.stream());
        SplitRng { split, rng }
    }

    /// The split this generator draws for.
    pub fn split(&self) -> Split {
        self.split
    }

    /// The generator itself.
    pub fn rng(&mut self) -> &mut ChaCha8Rng {
        &mut self.rng
    }
}

/// Which capture a motion file comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dataset {
    /// Bandai Namco Research Motion Dataset (BVH).
    Bandai,
    /// CMU Graphics Lab, subject 131 (BVH).
    Cmu,
    /// The GearsSports tour swings (C3D).
    Golf,
}

impl Dataset {
    const ALL: [Dataset; 3] = [Dataset::Bandai, Dataset::Cmu, Dataset::Golf];

    /// Folder under the data folder, and the files' extension.
    const fn place(self) -> (&'static str, &'static str) {
        match self {
            Dataset::Bandai => ("bvh/bandai", "bvh"),
            Dataset::Cmu => ("bvh/cmu", "bvh"),
            Dataset::Golf => ("golf", "c3d"),
        }
    }
}

/// One motion file and its split.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MotionFile {
    /// The file.
    pub path: PathBuf,
    /// Its capture.
    pub dataset: Dataset,
    /// Its split.
    pub split: Split,
}

impl MotionFile {
    /// The file name without extension.
    pub fn stem(&self) -> &str {
        self.path.file_stem().and_then(|s| s.to_str()).unwrap_or("")
    }
}

/// The split of a file with stem `stem`.
pub fn split_of(stem: &str) -> Split {
    match HELD_OUT.contains(&stem) {
        true => Split::Eval,
        false => Split::Train,
    }
}

/// Every motion file under `data_dir` (`bvh/bandai`, `bvh/cmu`, `golf`), sorted within each
/// dataset, with its split. Missing folders list nothing.
pub fn motion_files(data_dir: &Path) -> Vec<MotionFile> {
    let mut files = Vec::new();
    for dataset in Dataset::ALL {
        let (folder, ext) = dataset.place();
        let mut paths: Vec<PathBuf> = std::fs::read_dir(data_dir.join(folder))
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == ext))
            .collect();
        paths.sort();
        files.extend(paths.into_iter().map(|path| {
            let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
            MotionFile {
                split: split_of(stem),
                dataset,
                path,
            }
        }));
    }
    files
}

/// Same or different skeleton formats on both sides of a pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Structure {
    /// Source and target in the same format.
    Intra,
    /// Source and target in different formats.
    Cross,
}

/// A retargeting example.
#[derive(Clone, Debug)]
pub struct Pair {
    /// The clip's name.
    pub clip: String,
    /// Whether the clip is a golf swing (its source tracks a club).
    pub golf: bool,
    /// The clip on a source character `A` (format `X`).
    pub source: Motion,
    /// The target character `B` (format `Y`).
    pub target: Character,
    /// The clip on `B`: what a retargeter of `source` onto `B` should output.
    pub ground_truth: Motion,
}

/// What training sees: a window of a clip on a character, and a target skeleton (no ground
/// truth: training is unsupervised), and the same window on the source's body in the
/// target's format (its reconstruction across formats: the same take as two keypoint sets).
#[derive(Clone, Debug)]
pub struct Example {
    /// The source motion.
    pub window: Window,
    /// The skeleton to retarget it onto.
    pub target: Skeleton,
    /// The source motion on the source's body in the target's format.
    pub twin: Window,
}

/// Clip frames at [`CLIP_RATE_HZ`] that resample to one [`WINDOW`].
pub fn window_frames() -> usize {
    ((WINDOW - 1) as f32 * CLIP_RATE_HZ / RATE_HZ).ceil() as usize + 1
}

/// The clips of both splits.
#[derive(Clone, Debug, Default)]
pub struct Pool {
    /// Training clips.
    pub train: Vec<Clip>,
    /// Evaluation clips.
    pub eval: Vec<Clip>,
    /// The evaluation BVH files as read, on their own rest poses (CMU's arms hang, Bandai's
    /// are its own), at [`CLIP_RATE_HZ`], with their names: what a coach file hands over
    /// before any re-resting.
    pub raw_eval: Vec<(String, Motion)>,
}

impl Pool {
    /// Every motion file under `data_dir` as a clip, in its split: read, resampled to
    /// [`CLIP_RATE_HZ`], re-rested on its format's standard T-pose ([`standard_rest`]) and
    /// turned into rotations ([`Clip::from_motion`]).
    ///
    /// # Errors
    /// The first file that cannot be loaded.
    pub fn load(data_dir: &Path) -> Result<Pool, Error> {
        let mut pool = Pool::default();
        for file in motion_files(data_dir) {
            let motion = io::load(&file.path)?.resampled(CLIP_RATE_HZ)?;
            let clip = Clip::from_motion(file.stem(), &standard_rest(&motion)?)?;
            match file.split {
                Split::Train => pool.train.push(clip),
                Split::Eval => {
                    pool.eval.push(clip);
                    if file.dataset != Dataset::Golf {
                        pool.raw_eval.push((file.stem().to_string(), motion));
                    }
                }
            }
        }
        Ok(pool)
    }

    /// The clips of `split`.
    pub fn clips(&self, split: Split) -> &[Clip] {
        match split {
            Split::Train => &self.train,
            Split::Eval => &self.eval,
        }
    }

    /// A random pair of `rng`'s split: a clip, two characters varied as `variation` says, in
    /// formats drawn from [`FORMATS`] (equal for [`Structure::Intra`], different for
    /// [`Structure::Cross`]). Canonical characters carry a club where the clip has one.
    ///
    /// # Errors
    /// [`Error::NoClips`] if the split has none, else as [`Character::new`] and [`Clip::on`].
    pub fn sample_pair(
        &self,
        rng: &mut SplitRng,
        structure: Structure,
        variation: &Variation,
    ) -> Result<Pair, Error> {
        let clip = self
            .clips(rng.split())
            .choose(rng.rng())
            .ok_or(Error::NoClips)?;
        pair_on(clip, rng, structure, variation)
    }

    /// A random [`Example`] of `rng`'s split: a window of a clip long enough, on a character
    /// `A`, and a character `B` as [`Pool::sample_pair`] draws them.
    ///
    /// # Errors
    /// [`Error::NoClips`] if no clip of the split holds a window, else as [`Character::new`]
    /// and [`Clip::on`].
    pub fn sample_example(
        &self,
        rng: &mut SplitRng,
        structure: Structure,
        variation: &Variation,
    ) -> Result<Example, Error> {
        let frames = window_frames();
        let long: Vec<&Clip> = self
            .clips(rng.split())
            .iter()
            .filter(|c| c.frames() >= frames)
            .collect();
        let clip = long.choose(rng.rng()).ok_or(Error::NoClips)?;
        let start = rng.rng().random_range(0..=clip.frames() - frames);
        let (from, onto) = formats(structure, rng.rng());
        let club = clip.has_club();
        let source = Character::new(Body::sample(variation, rng.rng()), from, club)?;
        let target = Character::new(Body::sample(variation, rng.rng()), onto, club)?;
        let slice = clip.slice(start, frames)?;
        let window = Window::new(&slice.on(&source)?, 0)?;
        let twin = match onto == from {
            true => window.clone(),
            false => {
                let twin = Character::new(source.body, onto, club)?;
                Window::new(&slice.on(&twin)?, 0)?
            }
        };
        Ok(Example {
            window,
            target: target.skeleton,
            twin,
        })
    }

    /// Adds `count` synthetic swings and putts ([`crate::golfgen`]) to each split, drawn from
    /// the split's stream of `seed`.
    ///
    /// # Errors
    /// As [`golfgen::generate`] and [`Clip::from_motion`].
    pub fn add_synthetic_golf(&mut self, count: usize, seed: u64) -> Result<(), Error> {
        let rest: Vec<Vec3> = Joint::ALL.iter().map(|&j| t_pose(j)).collect();
        let skeleton = Skeleton::canonical(&Joint::ALL, &rest)?;
        for split in [Split::Train, Split::Eval] {
            let mut rng = SplitRng::new(split, seed);
            for i in 0..count {
                let params = SwingParams::sample(rng.rng());
                let swing = golfgen::generate(&skeleton, &params, rng.rng())?;
                let motion = swing.motion.resampled(CLIP_RATE_HZ)?;
                let name = format!("synthetic_{}_{i}", split.name());
                let clip = Clip::from_motion(&name, &standard_rest(&motion)?)?;
                match split {
                    Split::Train => self.train.push(clip),
                    Split::Eval => self.eval.push(clip),
                }
            }
        }
        Ok(())
    }
}

/// A pair on `clip`, as [`Pool::sample_pair`] makes them, with characters of `rng`'s split.
///
/// # Errors
/// As [`Character::new`] and [`Clip::on`].
pub fn pair_on(
    clip: &Clip,
    rng: &mut SplitRng,
    structure: Structure,
    variation: &Variation,
) -> Result<Pair, Error> {
    let (from, onto) = formats(structure, rng.rng());
    let club = clip.has_club();
    let source = Character::new(Body::sample(variation, rng.rng()), from, club)?;
    let target = Character::new(Body::sample(variation, rng.rng()), onto, club)?;
    Ok(Pair {
        clip: clip.name.clone(),
        golf: club,
        source: clip.coach_on(&source)?,
        ground_truth: clip.on(&target)?,
        target,
    })
}

/// Source and target formats for a pair of `structure`.
fn formats(structure: Structure, rng: &mut impl Rng) -> (Format, Format) {
    let from = FORMATS[rng.random_range(0..FORMATS.len())];
    let onto = match structure {
        Structure::Intra => from,
        Structure::Cross => {
            let others: Vec<Format> = FORMATS.into_iter().filter(|&f| f != from).collect();
            others[rng.random_range(0..others.len())]
        }
    };
    (from, onto)
}

/// The real-data folder for tests: `$POSECOACH_DATA`, else `../../shared/data` from this
/// crate; `None`, with a message naming `test`, when it is absent.
pub fn shared_data(test: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("POSECOACH_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"));
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "{test}: skipped: no real data at {} (set POSECOACH_DATA)",
            dir.display()
        );
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bodies::sample_character;
    use std::collections::HashSet;

    const SEEDS: u64 = 200;

    #[test]
    fn character_streams_are_disjoint_and_deterministic() {
        let stature = |split, seed| {
            let mut rng = SplitRng::new(split, seed);
            sample_character(Format::H36m17, rng.rng())
                .map(|c| c.body.stature.to_bits())
                .unwrap()
        };
        let train: HashSet<u32> = (0..SEEDS).map(|s| stature(Split::Train, s)).collect();
        let eval: HashSet<u32> = (0..SEEDS).map(|s| stature(Split::Eval, s)).collect();
        assert_eq!(train.len() as u64, SEEDS);
        assert!(train.is_disjoint(&eval));
        assert_eq!(stature(Split::Eval, 3), stature(Split::Eval, 3));
    }

    #[test]
    fn file_splits_are_disjoint_deterministic_and_cover_every_dataset() {
        let Some(dir) = shared_data("file_splits") else {
            return;
        };
        let files = motion_files(&dir);
        assert_eq!(files, motion_files(&dir));
        let in_split = |split| -> HashSet<&Path> {
            files
                .iter()
                .filter(|f| f.split == split)
                .map(|f| f.path.as_path())
                .collect()
        };
        let (train, eval) = (in_split(Split::Train), in_split(Split::Eval));
        assert!(train.is_disjoint(&eval));
        assert_eq!(train.len() + eval.len(), files.len());
        for dataset in Dataset::ALL {
            for split in [Split::Train, Split::Eval] {
                assert!(
                    files
                        .iter()
                        .any(|f| f.dataset == dataset && f.split == split),
                    "{dataset:?} has no {split:?} file"
                );
            }
        }
        let eval_stems: HashSet<&str> = files
            .iter()
            .filter(|f| f.split == Split::Eval)
            .map(MotionFile::stem)
            .collect();
        assert_eq!(eval_stems, HELD_OUT.into_iter().collect());
    }

    #[test]
    fn pairs_have_the_asked_structure_and_are_reproducible() {
        let mut rng = SplitRng::new(Split::Eval, 0);
        let source = crate::bodies::sample_character(Format::Cmu31, rng.rng()).unwrap();
        let clip =
            Clip::from_motion("wave", &crate::clip::testing::wave(&source.skeleton)).unwrap();
        let pool = Pool {
            eval: vec![clip],
            ..Pool::default()
        };
        let draw = |seed, structure| {
            let mut rng = SplitRng::new(Split::Eval, seed);
            pool.sample_pair(&mut rng, structure, &Variation::FULL)
                .unwrap()
        };
        for seed in 0..20 {
            let intra = draw(seed, Structure::Intra);
            assert_eq!(intra.source.skeleton.format(), intra.target.format);
            let cross = draw(seed, Structure::Cross);
            assert_ne!(cross.source.skeleton.format(), cross.target.format);
            assert_eq!(cross.ground_truth.skeleton, cross.target.skeleton);
            assert_eq!(
                draw(seed, Structure::Cross).ground_truth.positions,
                cross.ground_truth.positions
            );
        }
        let mut train = SplitRng::new(Split::Train, 0);
        assert!(matches!(
            pool.sample_pair(&mut train, Structure::Intra, &Variation::FULL),
            Err(Error::NoClips)
        ));
    }
}
