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
use posecoach_adapters::io::Motion;
use posecoach_core::events;
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
use std::fmt::Write;

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

/// Means of some metrics (each optional one over the pairs that have it).
#[derive(Clone, Copy, Debug, Default)]
struct Mean {
    pairs: usize,
    global: f32,
    local: f32,
    gap: [f32; 2],
    golf: usize,
    slide: f32,
    slid: usize,
}

impl Mean {
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

    fn row(&self) -> String {
        let per = |sum: f32, n: usize, scale: f32| match n {
            0 => "-".to_string(),
            n => format!("{:.2}", sum * scale / n as f32),
        };
        format!(
            "{:>5} {:>9} {:>9} {:>5} {:>10} {:>10} {:>11}",
            self.pairs,
            per(self.global, self.pairs, 100.0),
            per(self.local, self.pairs, 100.0),
            self.golf,
            per(self.gap[0], self.golf, 100.0),
            per(self.gap[1], self.golf, 100.0),
            per(self.slide, self.slid, 100.0),
        )
    }
}

/// The variations the table compares, with their names.
const VARIATIONS: [(&str, Variation); 2] = [
    ("standard rest", Variation::STANDARD_REST),
    ("varied rest", Variation::FULL),
];

/// Pairs per golf clip and cell in the table's golf block (hand gaps need swings).
pub const GOLF_PAIRS: usize = 5;

/// A table of every [`Baseline`]'s mean metrics on the evaluation clips, characters from the
/// evaluation stream at `seed`: one pair per clip, structure and variation, then
/// [`GOLF_PAIRS`] per golf clip for the hand gaps.
///
/// # Errors
/// [`Error::NoClips`] without evaluation clips, else the first pair that fails.
pub fn baseline_table(pool: &Pool, seed: u64) -> Result<String, Error> {
    if pool.eval.is_empty() {
        return Err(Error::NoClips);
    }
    let mut rng = SplitRng::new(Split::Eval, seed);
    let mut out = String::from("eval clips (frames at 60 Hz):");
    for clip in &pool.eval {
        let _ = write!(out, " {} ({})", clip.name, clip.frames());
    }
    let _ = writeln!(
        out,
        "\n{:<6} {:<14} {:<14} {:>5} {:>9} {:>9} {:>5} {:>10} {:>10} {:>11}",
        "pairs",
        "rest poses",
        "baseline",
        "n",
        "global %h",
        "local %h",
        "golf",
        "gap@addr cm",
        "gap@imp cm",
        "slide cm/s"
    );
    let all: Vec<&Clip> = pool.eval.iter().collect();
    let golf: Vec<&Clip> = all.iter().copied().filter(|c| c.has_club()).collect();
    let golf: Vec<&Clip> = golf
        .iter()
        .copied()
        .cycle()
        .take(golf.len() * GOLF_PAIRS)
        .collect();
    for (title, clips) in [("every eval clip", all), ("golf swings only", golf)] {
        let _ = writeln!(out, "-- {title}");
        block(&mut out, &clips, &mut rng)?;
    }
    Ok(out)
}

/// The table's rows for pairs on `clips`, one per clip, per structure and variation.
fn block(out: &mut String, clips: &[&Clip], rng: &mut SplitRng) -> Result<(), Error> {
    for structure in [Structure::Intra, Structure::Cross] {
        for (name, variation) in &VARIATIONS {
            let mut means = [Mean::default(); Baseline::ALL.len()];
            for clip in clips {
                let pair = pair_on(clip, rng, structure, variation)?;
                for (mean, baseline) in means.iter_mut().zip(Baseline::ALL) {
                    mean.add(&evaluate(&pair, &baseline.retarget(&pair)?)?);
                }
            }
            for (mean, baseline) in means.iter().zip(Baseline::ALL) {
                let _ = writeln!(
                    out,
                    "{:<6} {:<14} {:<14} {}",
                    format!("{structure:?}").to_lowercase(),
                    name,
                    baseline.name(),
                    mean.row()
                );
            }
        }
    }
    Ok(())
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
        let table = baseline_table(&pool, 0).unwrap();
        println!("{table}");
        // Intra-structure pairs on standard rest poses: the analytic retargeter's poses are the
        // ground truth's (the root differs by the leg-length convention, see `clip`).
        let first = table.lines().nth(3).unwrap();
        let local: f32 = first.split_whitespace().nth(6).unwrap().parse().unwrap();
        assert!(local < 0.05, "{first}");
    }
}
