//! Evaluation of a retargeted motion against the ground truth, and the baselines' numbers.
//!
//! - **Joint error** (VPC eq. 16): the mean distance between retargeted and true joint
//!   positions over frames and joints, divided by the target's height; *global* as is, *local*
//!   with the root moved to the origin in every frame. Joints are the target's body joints with
//!   a canonical name the source also has (a joint the source format lacks, such as COCO's
//!   missing toes, cannot be retargeted by anyone, and the club is not body).
//! - **Hand gap** (golf): how far apart the two hands (else wrists) are on the grip, at address
//!   and impact as [`events::detect`] finds them in the ground truth; the error is the absolute
//!   difference of the gaps, metres.
//! - **Foot slide**: the mean horizontal speed (m/s) of each foot (toe, else ankle) over the
//!   frames where it is planted in the ground truth: within [`CONTACT_HEIGHT_M`] of its lowest
//!   point and slower than [`CONTACT_SPEED_M_S`] there.

use crate::bodies::Variation;
use crate::clip::{motion, standard_rest, Clip};
use crate::dataset::{pair_on, Pair, Pool, Split, SplitRng, Structure};
use crate::error::Error;
use crate::infer::Retargeter;
use posecoach_core::events;
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
use posecoach_io::Motion;

/// A foot counts as planted within this height above its lowest point (metres)...
pub const CONTACT_HEIGHT_M: f32 = 0.03;
/// ...while it moves slower than this (m/s, horizontal).
pub const CONTACT_SPEED_M_S: f32 = 0.3;

/// How one retargeted motion compares with the ground truth.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Mean joint error over the target's height.
    pub global: f32,
    /// The same with the root at the origin in every frame.
    pub local: f32,
    /// Hand-gap error at address and impact (metres), for golf swings.
    pub hand_gap: Option<[f32; 2]>,
    /// Mean horizontal speed of the feet where the ground truth plants them (m/s).
    pub foot_slide: Option<f32>,
}

/// Compares `retargeted` (on the pair's target skeleton) with the pair's ground truth.
///
/// # Errors
/// [`Error::Mismatch`] if the two motions differ in size; [`Error::Events`] if a golf pair's
/// ground truth has no detectable swing.
pub fn evaluate(pair: &Pair, retargeted: &Motion) -> Result<Metrics, Error> {
    let truth = &pair.ground_truth;
    if retargeted.positions.len() != truth.positions.len() {
        return Err(Error::Mismatch {
            expected: truth.positions.len(),
            actual: retargeted.positions.len(),
        });
    }
    let joints = scored_joints(&pair.source.skeleton, &truth.skeleton);
    let height = truth.skeleton.height();
    Ok(Metrics {
        global: joint_error(truth, retargeted, &joints, false) / height,
        local: joint_error(truth, retargeted, &joints, true) / height,
        hand_gap: match pair.golf {
            true => Some(hand_gap_error(truth, retargeted)?),
            false => None,
        },
        foot_slide: foot_slide(truth, retargeted),
    })
}

/// Target body joints with a canonical name the source also has.
fn scored_joints(source: &Skeleton, target: &Skeleton) -> Vec<usize> {
    (0..target.len())
        .filter(|&k| {
            target
                .joint(k)
                .is_some_and(|j| !j.is_club() && source.index_of(j).is_some())
        })
        .collect()
}

/// Mean distance over frames and `joints`, with the root at the origin if `local`.
fn joint_error(truth: &Motion, other: &Motion, joints: &[usize], local: bool) -> f32 {
    let n = truth.skeleton.len();
    let mut sum = 0.0f64;
    for (a, b) in truth
        .positions
        .chunks_exact(n)
        .zip(other.positions.chunks_exact(n))
    {
        let (ra, rb) = match local {
            true => (a[0], b[0]),
            false => (Vec3::zeros(), Vec3::zeros()),
        };
        sum += joints
            .iter()
            .map(|&k| f64::from(((a[k] - ra) - (b[k] - rb)).norm()))
            .sum::<f64>();
    }
    let count = (truth.frames() * joints.len()).max(1);
    (sum / count as f64) as f32
}

/// The two hands' joints (hands, else wrists).
fn hands(skeleton: &Skeleton) -> Option<[usize; 2]> {
    Some([
        skeleton.find(&[Joint::LeftHand, Joint::LeftWrist])?,
        skeleton.find(&[Joint::RightHand, Joint::RightWrist])?,
    ])
}

/// Hand-gap errors at the ground truth's address and impact.
fn hand_gap_error(truth: &Motion, other: &Motion) -> Result<[f32; 2], Error> {
    let swing = events::detect(&truth.skeleton, &truth.positions, truth.rate_hz)?;
    let [l, r] = hands(&truth.skeleton).ok_or(Error::Events(events::EventError::MissingJoint(
        Joint::LeftWrist,
    )))?;
    let gap = |m: &Motion, f: usize| (m.frame(f)[l] - m.frame(f)[r]).norm();
    Ok([swing.address(), swing.impact()].map(|f| (gap(other, f) - gap(truth, f)).abs()))
}

/// The feet's joints (toes, else ankles).
fn feet(skeleton: &Skeleton) -> Option<[usize; 2]> {
    Some([
        skeleton.find(&[Joint::LeftToe, Joint::LeftAnkle])?,
        skeleton.find(&[Joint::RightToe, Joint::RightAnkle])?,
    ])
}

/// Horizontal speed of joint `k` of `m` between frames `f - 1` and `f`.
fn horizontal_speed(m: &Motion, k: usize, f: usize) -> f32 {
    let d = m.frame(f)[k] - m.frame(f - 1)[k];
    (d.x * d.x + d.z * d.z).sqrt() * m.rate_hz
}

/// Mean horizontal speed of `other`'s feet over the frames where `truth` plants them.
fn foot_slide(truth: &Motion, other: &Motion) -> Option<f32> {
    let mut speeds = Vec::new();
    for foot in feet(&truth.skeleton)? {
        let lowest = (0..truth.frames())
            .map(|f| truth.frame(f)[foot].y)
            .fold(f32::INFINITY, f32::min);
        speeds.extend((1..truth.frames()).filter_map(|f| {
            let planted = truth.frame(f)[foot].y <= lowest + CONTACT_HEIGHT_M
                && horizontal_speed(truth, foot, f) < CONTACT_SPEED_M_S;
            planted.then(|| horizontal_speed(other, foot, f))
        }));
    }
    (!speeds.is_empty()).then(|| speeds.iter().sum::<f32>() / speeds.len() as f32)
}

/// A way of retargeting a pair's source onto its target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Baseline {
    /// [`posecoach_core::retarget::Analytic`]: bone-direction copy.
    Analytic,
    /// Rotations of the source relative to its format's standard T-pose (the source's own rest
    /// pose is unknown to a retargeter), copied through canonical names onto the target's rest.
    RotationCopy,
    /// The ground truth itself (zero joint error; its own foot slide, for reference).
    GroundTruth,
}

impl Baseline {
    /// Every baseline, in table order.
    pub const ALL: [Baseline; 3] = [
        Baseline::Analytic,
        Baseline::RotationCopy,
        Baseline::GroundTruth,
    ];

    /// Short name for tables.
    pub const fn name(self) -> &'static str {
        match self {
            Baseline::Analytic => "analytic",
            Baseline::RotationCopy => "rotation copy",
            Baseline::GroundTruth => "ground truth",
        }
    }

    /// The pair's source retargeted onto its target.
    ///
    /// # Errors
    /// As [`posecoach_core::retarget::Analytic`], [`standard_rest`] and [`Clip::on`].
    pub fn retarget(self, pair: &Pair) -> Result<Motion, Error> {
        match self {
            Baseline::Analytic => {
                let student = motion(&pair.target.skeleton, 0.0, Vec::new());
                pair.source
                    .retarget_analytic(&student)
                    .map_err(|(_, e)| Error::Retarget(e))
            }
            Baseline::RotationCopy => {
                let clip = Clip::from_motion(&pair.clip, &standard_rest(&pair.source)?)?;
                clip.on(&pair.target)
            }
            Baseline::GroundTruth => Ok(pair.ground_truth.clone()),
        }
    }
}

/// A retargeter the table compares: a baseline or a trained teacher.
#[derive(Clone, Copy, Debug)]
pub enum Method<'a> {
    /// A baseline.
    Baseline(Baseline),
    /// A trained teacher.
    Teacher(&'a Retargeter),
}

impl Method<'_> {
    /// Short name for tables.
    pub fn name(self) -> String {
        match self {
            Method::Baseline(b) => b.name().to_string(),
            Method::Teacher(t) => t.name.clone(),
        }
    }

    /// The pair's source retargeted onto its target.
    ///
    /// # Errors
    /// As [`Baseline::retarget`] and [`Retargeter::retarget`].
    pub fn retarget(self, pair: &Pair) -> Result<Motion, Error> {
        match self {
            Method::Baseline(b) => b.retarget(pair),
            Method::Teacher(t) => t.retarget(&pair.source, &pair.target.skeleton),
        }
    }
}

/// One row of the table: a method's means over the pairs of one cell. The optional means
/// are over the pairs that have them.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// `"every eval clip"` or `"golf swings only"`.
    pub block: &'static str,
    /// Same or different formats.
    pub structure: Structure,
    /// `"standard rest"` or `"varied rest"`.
    pub rest: &'static str,
    /// The method's name.
    pub method: String,
    /// Pairs.
    pub pairs: usize,
    /// Mean global joint error, fraction of the target's height.
    pub global: f32,
    /// Mean local joint error, fraction of the target's height.
    pub local: f32,
    /// Golf pairs.
    pub golf: usize,
    /// Mean hand-gap errors at address and impact, metres.
    pub hand_gap: Option<[f32; 2]>,
    /// Mean foot slide, metres per second.
    pub foot_slide: Option<f32>,
}

/// The evaluation table: every method's means per cell.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The evaluation clips and their frames at the clip rate.
    pub clips: Vec<(String, usize)>,
    /// The rows, block by block, cell by cell, method by method.
    pub rows: Vec<Row>,
}

/// Sums of some metrics towards a [`Row`].
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    pairs: usize,
    global: f32,
    local: f32,
    gap: [f32; 2],
    golf: usize,
    slide: f32,
    slid: usize,
}

impl Sums {
    fn add(&mut self, m: &Metrics) {
        self.pairs += 1;
        self.global += m.global;
        self.local += m.local;
        if let Some([a, i]) = m.hand_gap {
            self.golf += 1;
            self.gap[0] += a;
            self.gap[1] += i;
        }
        if let Some(s) = m.foot_slide {
            self.slid += 1;
            self.slide += s;
        }
    }
}

/// The variations the table compares, with their names.
const VARIATIONS: [(&str, Variation); 2] = [
    ("standard rest", Variation::STANDARD_REST),
    ("varied rest", Variation::FULL),
];

/// Pairs per golf clip and cell in the table's golf block (hand gaps need swings).
pub const GOLF_PAIRS: usize = 5;

/// Every method's mean metrics on the evaluation clips, characters from the evaluation stream
/// at `seed`: one pair per clip, structure and variation, then [`GOLF_PAIRS`] per golf clip for
/// the hand gaps. Every method sees the same pairs. `progress` is called after each pair.
///
/// # Errors
/// [`Error::NoClips`] without evaluation clips, else the first pair that fails.
pub fn table(
    pool: &Pool,
    seed: u64,
    methods: &[Method],
    mut progress: impl FnMut(usize, usize),
) -> Result<Table, Error> {
    if pool.eval.is_empty() {
        return Err(Error::NoClips);
    }
    let mut rng = SplitRng::new(Split::Eval, seed);
    let all: Vec<&Clip> = pool.eval.iter().collect();
    let golf: Vec<&Clip> = all.iter().copied().filter(|c| c.has_club()).collect();
    let golf: Vec<&Clip> = golf
        .iter()
        .copied()
        .cycle()
        .take(golf.len() * GOLF_PAIRS)
        .collect();
    let cells = 2 * VARIATIONS.len();
    let total = (all.len() + golf.len()) * cells;
    let mut done = 0;
    let mut rows = Vec::new();
    for (block, clips) in [("every eval clip", all), ("golf swings only", golf)] {
        for structure in [Structure::Intra, Structure::Cross] {
            for &(rest, variation) in &VARIATIONS {
                let mut sums = vec![Sums::default(); methods.len()];
                for clip in &clips {
                    let pair = pair_on(clip, &mut rng, structure, &variation)?;
                    for (sum, method) in sums.iter_mut().zip(methods) {
                        sum.add(&evaluate(&pair, &method.retarget(&pair)?)?);
                    }
                    done += 1;
                    progress(done, total);
                }
                rows.extend(sums.iter().zip(methods).map(|(s, m)| Row {
                    block,
                    structure,
                    rest,
                    method: m.name(),
                    pairs: s.pairs,
                    global: s.global / s.pairs.max(1) as f32,
                    local: s.local / s.pairs.max(1) as f32,
                    golf: s.golf,
                    hand_gap: (s.golf > 0).then(|| s.gap.map(|g| g / s.golf as f32)),
                    foot_slide: (s.slid > 0).then(|| s.slide / s.slid as f32),
                }));
            }
        }
    }
    let clips = pool
        .eval
        .iter()
        .map(|c| (c.name.clone(), c.frames()))
        .collect();
    Ok(Table { clips, rows })
}

impl std::fmt::Display for Table {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{} eval clips (frames at 60 Hz):", self.clips.len())?;
        for (name, frames) in &self.clips {
            writeln!(f, "  {name} ({frames})")?;
        }
        writeln!(
            f,
            "{:<6} {:<14} {:<14} {:>5} {:>9} {:>9} {:>5} {:>11} {:>10} {:>11}",
            "pairs",
            "rest poses",
            "method",
            "n",
            "global %h",
            "local %h",
            "golf",
            "gap@addr cm",
            "gap@imp cm",
            "slide cm/s"
        )?;
        let mut block = "";
        for row in &self.rows {
            if row.block != block {
                block = row.block;
                writeln!(f, "-- {block}")?;
            }
            let cm = |v: Option<f32>| v.map_or("-".to_string(), |v| format!("{:.2}", v * 100.0));
            writeln!(
                f,
                "{:<6} {:<14} {:<14} {:>5} {:>9.2} {:>9.2} {:>5} {:>11} {:>10} {:>11}",
                format!("{:?}", row.structure).to_lowercase(),
                row.rest,
                row.method,
                row.pairs,
                row.global * 100.0,
                row.local * 100.0,
                row.golf,
                cm(row.hand_gap.map(|g| g[0])),
                cm(row.hand_gap.map(|g| g[1])),
                cm(row.foot_slide),
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::testing::wave;
    use crate::dataset::shared_data;

    #[test]
    fn the_ground_truth_scores_zero_and_offsets_score_their_size() {
        let mut rng = SplitRng::new(Split::Eval, 5);
        let character =
            crate::bodies::sample_character(posecoach_core::format::Format::H36m17, rng.rng())
                .unwrap();
        let clip = Clip::from_motion("wave", &wave(&character.skeleton)).unwrap();
        let pair = pair_on(&clip, &mut rng, Structure::Intra, &Variation::FULL).unwrap();
        let perfect = evaluate(&pair, &pair.ground_truth).unwrap();
        assert_eq!((perfect.global, perfect.local), (0.0, 0.0));
        let mut shifted = pair.ground_truth.clone();
        const SHIFT_M: f32 = 0.1;
        for p in &mut shifted.positions {
            p.x += SHIFT_M;
        }
        let m = evaluate(&pair, &shifted).unwrap();
        let h = pair.target.skeleton.height();
        assert!((m.global - SHIFT_M / h).abs() < 1e-5, "{}", m.global);
        assert!(m.local < 1e-6);
        shifted.positions.pop();
        assert!(matches!(
            evaluate(&pair, &shifted),
            Err(Error::Mismatch { .. })
        ));
    }

    #[test]
    fn analytic_baseline_table() {
        let Some(dir) = shared_data("analytic_baseline_table") else {
            return;
        };
        let pool = Pool::load(&dir).unwrap();
        let methods = Baseline::ALL.map(Method::Baseline);
        let table = table(&pool, 0, &methods, |_, _| {}).unwrap();
        println!("{table}");
        // Intra-structure pairs on standard rest poses: the analytic retargeter's poses are the
        // ground truth's (the root differs by the leg-length convention, see `clip`).
        let first = &table.rows[0];
        assert_eq!(
            (first.structure, first.method.as_str()),
            (Structure::Intra, "analytic")
        );
        assert!(first.local < 0.0005, "{first:?}");
    }
}
