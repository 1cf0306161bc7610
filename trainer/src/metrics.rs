//! Evaluation of a retargeted motion against the ground truth, and the baselines' numbers.
//!
//! - **Joint error** (VPC eq. 16): the mean distance between retargeted and true joint
//!   positions over frames and joints, divided by the target's height; *global* as is, *local*
//!   with the root moved to the origin in every frame. Joints are the target's body joints with
//!   a canonical name the source also has (a joint the source format lacks, such as COCO's
//!   missing toes, cannot be retargeted by anyone, and the club is not body).
//! - **Grip** (golf): how far apart the two wrists (which every format places alike) are at
//!   address and impact as [`events::detect`] finds them in the coach (else the ground truth);
//!   the error is the absolute difference from the coach's gap, metres (both hands on one grip,
//!   whatever the arms' lengths).
//! - **Foot slide**: over the frames where the coach (the source) plants a foot (its toe where
//!   both have toes, else ankle: [`contacts::feet`], [`contacts::planted`]), the mean
//!   horizontal speed (m/s) of the output's foot less the coach's own there.
//! - **Foot height**: over the same frames, the mean distance (m) between the output's foot
//!   height and the ground truth's: a planted foot off the ground or in it.
//! - **Club head** (golf, targets that carry a club): the distance (m) of the club head's
//!   height from the coach's club head height at the same address and impact, where the
//!   club is at the ball (from [`CLUB_HEAD_CLEARANCE_M`] above the floor where the coach
//!   tracks no club). It needs no ground truth, whose club, turned by the coach's rotations
//!   on another club length, misses the ball.
//! - **Posture error** ([`posture_error`]): how far the output moves (mean joint distance, m)
//!   when the target's T-pose has each body bone turned by 3-8°, as a phone's estimate of a
//!   student's T-pose has: a right answer takes the target's bone lengths from its T-pose, not
//!   the posture noise, and does not move.

use crate::bodies::{Body, Character, Variation};
use crate::clip::{motion, standard_rest, Clip};
use crate::dataset::{pair_on, Pair, Pool, Split, SplitRng, Structure, FORMATS};
use crate::error::Error;
use crate::infer::Retargeter;
use posecoach_core::contacts::{self, Contacts, Swing, CLUB_HEAD_CLEARANCE_M};
use posecoach_core::events::{self, SwingEvents};
use posecoach_core::format::Format;
use posecoach_core::joint::Joint;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::Vec3;
use posecoach_io::Motion;
use rand::Rng;

/// How one retargeted motion compares with the ground truth.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Mean joint error over the target's height.
    pub global: f32,
    /// The same with the root at the origin in every frame.
    pub local: f32,
    /// Hand-gap error against the coach's at address and impact (metres), for golf swings.
    pub hand_gap: Option<[f32; 2]>,
    /// Mean horizontal speed of the feet where the coach plants them, less the coach's (m/s).
    pub foot_slide: Option<f32>,
    /// Mean distance of those feet's heights from the ground truth's there (metres).
    pub foot_height: Option<f32>,
    /// The club head's height error against the coach's at address and impact (metres), for
    /// golf swings onto a target with a club.
    pub club_head: Option<[f32; 2]>,
}

/// Compares `retargeted` (on the pair's target skeleton) with the pair's ground truth and,
/// for what needs no convention, with the coach (the pair's source).
///
/// # Errors
/// [`Error::Mismatch`] if the motions differ in size; [`Error::Events`] if neither a golf
/// pair's coach nor its ground truth has a detectable swing (its address and impact are where
/// the grip and the club head are measured).
pub fn evaluate(pair: &Pair, retargeted: &Motion) -> Result<Metrics, Error> {
    let (truth, coach) = (&pair.ground_truth, &pair.source);
    for m in [retargeted, coach] {
        if m.frames() != truth.frames() {
            return Err(Error::Mismatch {
                expected: truth.frames(),
                actual: m.frames(),
            });
        }
    }
    if retargeted.positions.len() != truth.positions.len() {
        return Err(Error::Mismatch {
            expected: truth.positions.len(),
            actual: retargeted.positions.len(),
        });
    }
    let joints = scored_joints(&coach.skeleton, &truth.skeleton);
    let height = truth.skeleton.height();
    // The coach's address and impact, where its club is at the ball; the ground truth's for
    // a coach whose swing the detector does not find.
    let detect = |m: &Motion| events::detect(&m.skeleton, m.swing(), m.rate_hz);
    let swing = match pair.golf {
        true => Some(detect(coach).or_else(|_| detect(truth))?),
        false => None,
    };
    let (foot_slide, foot_height) = planted_feet(coach, truth, retargeted);
    Ok(Metrics {
        global: joint_error(truth, retargeted, &joints, false) / height,
        local: joint_error(truth, retargeted, &joints, true) / height,
        hand_gap: swing
            .as_ref()
            .and_then(|s| hand_gap_error(coach, retargeted, s)),
        foot_slide,
        foot_height,
        club_head: swing.as_ref().and_then(|s| club_head(coach, retargeted, s)),
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

/// The two wrists in `a` and in `b` (the grip's joints: every format places them alike).
fn hands(a: &Skeleton, b: &Skeleton) -> Option<[[usize; 2]; 2]> {
    let wrists = |s: &Skeleton| {
        Some([
            s.index_of(Joint::LeftWrist)?,
            s.index_of(Joint::RightWrist)?,
        ])
    };
    Some([wrists(a)?, wrists(b)?])
}

/// Hand-gap errors of `other` against `coach` at `swing`'s address and impact.
fn hand_gap_error(coach: &Motion, other: &Motion, swing: &SwingEvents) -> Option<[f32; 2]> {
    let [c, o] = hands(&coach.skeleton, &other.skeleton)?;
    let gap = |m: &Motion, [l, r]: [usize; 2], f: usize| (m.frame(f)[l] - m.frame(f)[r]).norm();
    Some([swing.address(), swing.impact()].map(|f| (gap(other, o, f) - gap(coach, c, f)).abs()))
}

/// Horizontal speed of joint `k` of `m` between frames `f - 1` and `f`.
fn horizontal_speed(m: &Motion, k: usize, f: usize) -> f32 {
    let d = m.frame(f)[k] - m.frame(f - 1)[k];
    (d.x * d.x + d.z * d.z).sqrt() * m.rate_hz
}

/// Over the frames where `coach` plants a foot: the mean horizontal speed of `other`'s foot
/// there less the coach's, and the mean distance of its height from `truth`'s.
fn planted_feet(coach: &Motion, truth: &Motion, other: &Motion) -> (Option<f32>, Option<f32>) {
    let (mut slide, mut heights) = (Vec::new(), Vec::new());
    let n = coach.skeleton.len();
    for [c, o] in contacts::feet(&coach.skeleton, &other.skeleton)
        .into_iter()
        .flatten()
    {
        let at = contacts::frames(&coach.positions, n);
        let planted = contacts::planted(&at, coach.frames(), c, coach.rate_hz);
        for f in (1..coach.frames()).filter(|&f| planted(f)) {
            slide.push(horizontal_speed(other, o, f) - horizontal_speed(coach, c, f));
            heights.push((other.frame(f)[o].y - truth.frame(f)[o].y).abs());
        }
    }
    let mean = |v: &[f32]| (!v.is_empty()).then(|| v.iter().sum::<f32>() / v.len() as f32);
    (mean(&slide), mean(&heights))
}

/// How far the club head's height in `other` is from the coach's at `swing`'s address and
/// impact ([`CLUB_HEAD_CLEARANCE_M`] where the coach tracks no club), if `other` carries a
/// club.
fn club_head(coach: &Motion, other: &Motion, swing: &SwingEvents) -> Option<[f32; 2]> {
    let head = other.skeleton.index_of(Joint::ClubHead)?;
    let coach_head = coach.skeleton.index_of(Joint::ClubHead);
    Some([swing.address(), swing.impact()].map(|f| {
        let reference = coach_head.map_or(CLUB_HEAD_CLEARANCE_M, |h| coach.frame(f)[h].y);
        (other.frame(f)[head].y - reference).abs()
    }))
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
    /// A method's output moved onto golf's contacts ([`Contacts`]).
    Contacts(&'a Method<'a>),
}

impl Method<'_> {
    /// Short name for tables.
    pub fn name(self) -> String {
        match self {
            Method::Baseline(b) => b.name().to_string(),
            Method::Teacher(t) => t.name.clone(),
            Method::Contacts(m) => format!("{} + contacts", m.name()),
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
            Method::Contacts(m) => {
                let mut out = m.retarget(pair)?;
                let coach = &pair.source;
                // A coach without a detectable swing keeps only its feet, as on the device.
                let events = match pair.golf {
                    true => events::detect(&coach.skeleton, coach.swing(), coach.rate_hz)
                        .ok()
                        .map(|s| Swing::from(&s)),
                    false => None,
                };
                Contacts::new(&coach.skeleton, &out.skeleton).apply(
                    contacts::frames(&coach.positions, coach.skeleton.len()),
                    coach.rate_hz,
                    events,
                    &mut out.positions,
                )?;
                Ok(out)
            }
        }
    }
}

/// One row of the table: a method's means over the pairs of one cell. The optional means
/// are over the pairs that have them.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// `"every eval clip"`, `"golf swings only"`, or `"onto FORMAT"` ([`onto_phone_formats`]).
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
    /// Mean hand-gap errors against the coach's at address and impact, metres.
    pub hand_gap: Option<[f32; 2]>,
    /// Mean foot slide beyond the coach's where the coach plants a foot, metres per second.
    pub foot_slide: Option<f32>,
    /// Mean foot height error there against the ground truth, metres.
    pub foot_height: Option<f32>,
    /// Golf pairs whose target carries a club.
    pub clubs: usize,
    /// The club head's mean height error against the coach's at address and impact, metres.
    pub club_head: Option<[f32; 2]>,
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
    height: f32,
    slid: usize,
    head: [f32; 2],
    clubs: usize,
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
        if let (Some(s), Some(h)) = (m.foot_slide, m.foot_height) {
            self.slid += 1;
            self.slide += s;
            self.height += h;
        }
        if let Some([a, i]) = m.club_head {
            self.clubs += 1;
            self.head[0] += a;
            self.head[1] += i;
        }
    }

    /// The means as a table row.
    fn row(
        &self,
        block: &'static str,
        structure: Structure,
        rest: &'static str,
        method: String,
    ) -> Row {
        let mean = |sum: f32, n: usize| (n > 0).then(|| sum / n as f32);
        Row {
            block,
            structure,
            rest,
            method,
            pairs: self.pairs,
            global: self.global / self.pairs.max(1) as f32,
            local: self.local / self.pairs.max(1) as f32,
            golf: self.golf,
            hand_gap: (self.golf > 0).then(|| self.gap.map(|g| g / self.golf as f32)),
            foot_slide: mean(self.slide, self.slid),
            foot_height: mean(self.height, self.slid),
            clubs: self.clubs,
            club_head: (self.clubs > 0).then(|| self.head.map(|h| h / self.clubs as f32)),
        }
    }
}

/// Adds each method's metrics on `pair` to its sums.
fn add_pair(sums: &mut [Sums], methods: &[Method], pair: &Pair) -> Result<(), Error> {
    for (sum, method) in sums.iter_mut().zip(methods) {
        sum.add(&evaluate(pair, &method.retarget(pair)?)?);
    }
    Ok(())
}

/// Each method's row of a table cell from its sums.
fn means<'a>(
    sums: &'a [Sums],
    methods: &'a [Method],
    block: &'static str,
    structure: Structure,
    rest: &'static str,
) -> impl Iterator<Item = Row> + 'a {
    sums.iter()
        .zip(methods)
        .map(move |(s, m)| s.row(block, structure, rest, m.name()))
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
                    add_pair(&mut sums, methods, &pair)?;
                    done += 1;
                    progress(done, total);
                }
                rows.extend(means(&sums, methods, block, structure, rest));
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

/// The keypoint formats phone pose estimators hand over, which [`onto_phone_formats`] targets:
/// COCO-17 (its thorax directly on the pelvis) and MediaPipe's 33 landmarks.
pub const PHONE_FORMATS: [Format; 2] = [Format::Coco17, Format::BlazePose33];

/// For [`GOLF_PAIRS`] pairs per golf clip and each of [`PHONE_FORMATS`]: the clip from a
/// character in another of the training [`FORMATS`] onto a character in that format (standard
/// rest poses), every method's means, one row per format and method (block `"onto FORMAT"`).
/// `progress` is called after each pair.
///
/// # Errors
/// [`Error::NoClips`] without evaluation golf clips, else the first pair that fails.
pub fn onto_phone_formats(
    pool: &Pool,
    seed: u64,
    methods: &[Method],
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<Row>, Error> {
    let golf: Vec<&Clip> = pool.eval.iter().filter(|c| c.has_club()).collect();
    if golf.is_empty() {
        return Err(Error::NoClips);
    }
    let mut rng = SplitRng::new(Split::Eval, seed);
    let total = PHONE_FORMATS.len() * golf.len() * GOLF_PAIRS;
    let (mut done, mut rows) = (0, Vec::new());
    for (onto, block) in PHONE_FORMATS
        .into_iter()
        .zip(["onto COCO-17", "onto MediaPipe-33"])
    {
        let mut sums = vec![Sums::default(); methods.len()];
        for clip in golf.iter().cycle().take(golf.len() * GOLF_PAIRS) {
            let others: Vec<Format> = FORMATS.into_iter().filter(|&f| f != onto).collect();
            let from = others[rng.rng().random_range(0..others.len())];
            let variation = Variation::STANDARD_REST;
            let source = Character::new(Body::sample(&variation, rng.rng()), from, true)?;
            let target = Character::new(Body::sample(&variation, rng.rng()), onto, true)?;
            let pair = Pair {
                clip: clip.name.clone(),
                golf: true,
                source: clip.coach_on(&source)?,
                ground_truth: clip.on(&target)?,
                target,
            };
            add_pair(&mut sums, methods, &pair)?;
            done += 1;
            progress(done, total);
        }
        rows.extend(means(
            &sums,
            methods,
            block,
            Structure::Cross,
            "standard rest",
        ));
    }
    Ok(rows)
}

/// The range of the turn [`posture_error`] gives each bone of the target's T-pose, degrees.
pub const POSTURE_ERROR_DEG: (f32, f32) = (3.0, 8.0);

/// How far one method's output moves under posture error in the target's T-pose.
#[derive(Clone, Debug, PartialEq)]
pub struct PostureRow {
    /// Same or different formats.
    pub structure: Structure,
    /// The method's name.
    pub method: String,
    /// Pairs.
    pub pairs: usize,
    /// Mean over the pairs of the output's mean joint movement, metres.
    pub mean: f32,
    /// The largest pair's mean joint movement, metres.
    pub max: f32,
}

/// For [`GOLF_PAIRS`] pairs per golf clip in each structure (targets on their standard rest
/// pose), every method's output onto the target against its output onto the same body whose
/// T-pose has each body bone turned by [`POSTURE_ERROR_DEG`]: the mean distance between the
/// two, over frames and the target's body joints. Every method sees the same pairs and the
/// same turned T-poses; the ground truth, which is no retargeting of the source, is left out.
/// `progress` is called after each pair.
///
/// # Errors
/// [`Error::NoClips`] without evaluation golf clips, else the first pair that fails.
pub fn posture_error(
    pool: &Pool,
    seed: u64,
    methods: &[Method],
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<PostureRow>, Error> {
    let methods: Vec<Method> = methods
        .iter()
        .copied()
        .filter(|m| !matches!(m, Method::Baseline(Baseline::GroundTruth)))
        .collect();
    let golf: Vec<&Clip> = pool.eval.iter().filter(|c| c.has_club()).collect();
    if golf.is_empty() {
        return Err(Error::NoClips);
    }
    let mut rng = SplitRng::new(Split::Eval, seed);
    let total = 2 * golf.len() * GOLF_PAIRS;
    let (mut done, mut rows) = (0, Vec::new());
    for structure in [Structure::Intra, Structure::Cross] {
        let mut moved = vec![Vec::new(); methods.len()];
        for clip in golf.iter().cycle().take(golf.len() * GOLF_PAIRS) {
            let pair = pair_on(clip, &mut rng, structure, &Variation::STANDARD_REST)?;
            let (lo, hi) = POSTURE_ERROR_DEG;
            let body = pair.target.body.with_posture_error(lo, hi, rng.rng());
            let noisy = Pair {
                target: Character::new(body, pair.target.format, pair.golf)?,
                ..pair.clone()
            };
            let joints: Vec<usize> = (0..pair.target.skeleton.len())
                .filter(|&k| pair.target.skeleton.joint(k).is_none_or(|j| !j.is_club()))
                .collect();
            for (moved, method) in moved.iter_mut().zip(&methods) {
                let (clean, turned) = (method.retarget(&pair)?, method.retarget(&noisy)?);
                moved.push(joint_error(&clean, &turned, &joints, false));
            }
            done += 1;
            progress(done, total);
        }
        rows.extend(moved.iter().zip(&methods).map(|(m, method)| PostureRow {
            structure,
            method: method.name(),
            pairs: m.len(),
            mean: m.iter().sum::<f32>() / m.len().max(1) as f32,
            max: m.iter().copied().fold(0.0, f32::max),
        }));
    }
    Ok(rows)
}

/// Pairs per raw evaluation BVH file and structure in [`raw_rests`].
pub const RAW_PAIRS: usize = 5;

/// One method's error on coach files as they are read, on their own rest poses, against the
/// same positions on their format's standard T-pose.
#[derive(Clone, Debug, PartialEq)]
pub struct RawRow {
    /// Same or different formats.
    pub structure: Structure,
    /// The method's name.
    pub method: String,
    /// Pairs.
    pub pairs: usize,
    /// Mean global joint error, fraction of the target's height, from the file's own rest.
    pub raw: f32,
    /// The same from the standard rest (the same positions).
    pub standard: f32,
}

/// The evaluation BVH files as read ([`Pool::raw_eval`]: CMU's rest pose has the arms
/// hanging, Bandai's is its own), each retargeted as it is and re-rested on its format's
/// standard T-pose (positions unchanged: a retargeter that reads positions should not tell
/// them apart) onto [`RAW_PAIRS`] held-out characters per structure (standard rest poses),
/// against the ground truth. The ground truth is left out. `progress` is called after each
/// pair.
///
/// # Errors
/// [`Error::NoClips`] without raw evaluation files, else the first pair that fails.
pub fn raw_rests(
    pool: &Pool,
    seed: u64,
    methods: &[Method],
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<RawRow>, Error> {
    if pool.raw_eval.is_empty() {
        return Err(Error::NoClips);
    }
    let methods: Vec<Method> = methods
        .iter()
        .copied()
        .filter(|m| !matches!(m, Method::Baseline(Baseline::GroundTruth)))
        .collect();
    let mut rng = SplitRng::new(Split::Eval, seed);
    let total = 2 * pool.raw_eval.len() * RAW_PAIRS;
    let (mut done, mut rows) = (0, Vec::new());
    for structure in [Structure::Intra, Structure::Cross] {
        let mut sums = vec![(0usize, 0.0f32, 0.0f32); methods.len()];
        for (name, raw) in &pool.raw_eval {
            let standard = standard_rest(raw)?;
            let clip = Clip::from_motion(name, &standard)?;
            let from = raw.skeleton.format();
            for _ in 0..RAW_PAIRS {
                let onto = match structure {
                    Structure::Intra => from,
                    Structure::Cross => {
                        let others: Vec<Format> =
                            FORMATS.into_iter().filter(|&f| f != from).collect();
                        others[rng.rng().random_range(0..others.len())]
                    }
                };
                let body = Body::sample(&Variation::STANDARD_REST, rng.rng());
                let target = Character::new(body, onto, false)?;
                let re_rested = Pair {
                    clip: name.clone(),
                    golf: false,
                    source: standard.clone(),
                    ground_truth: clip.on(&target)?,
                    target,
                };
                let as_read = Pair {
                    source: raw.clone(),
                    ..re_rested.clone()
                };
                let pair = &re_rested;
                for (sum, method) in sums.iter_mut().zip(&methods) {
                    let error = |p: &Pair| -> Result<f32, Error> {
                        Ok(evaluate(pair, &method.retarget(p)?)?.global)
                    };
                    sum.0 += 1;
                    sum.1 += error(&as_read)?;
                    sum.2 += error(&re_rested)?;
                }
                done += 1;
                progress(done, total);
            }
        }
        rows.extend(
            sums.iter()
                .zip(&methods)
                .map(|(&(n, raw, standard), m)| RawRow {
                    structure,
                    method: m.name(),
                    pairs: n,
                    raw: raw / n.max(1) as f32,
                    standard: standard / n.max(1) as f32,
                }),
        );
    }
    Ok(rows)
}

impl std::fmt::Display for RawRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:<6} {:<14} {:>5} {:>15.2} {:>15.2}",
            format!("{:?}", self.structure).to_lowercase(),
            self.method,
            self.pairs,
            self.raw * 100.0,
            self.standard * 100.0
        )
    }
}

impl std::fmt::Display for PostureRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:<6} {:<14} {:>5} {:>13.2} {:>12.2}",
            format!("{:?}", self.structure).to_lowercase(),
            self.method,
            self.pairs,
            self.mean * 100.0,
            self.max * 100.0
        )
    }
}

impl std::fmt::Display for Table {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{} eval clips (frames at 60 Hz):", self.clips.len())?;
        for (name, frames) in &self.clips {
            writeln!(f, "  {name} ({frames})")?;
        }
        writeln!(
            f,
            "{:<6} {:<14} {:<14} {:>5} {:>9} {:>9} {:>5} {:>11} {:>10} {:>11} {:>10} {:>5} {:>12} {:>11}",
            "pairs",
            "rest poses",
            "method",
            "n",
            "global %h",
            "local %h",
            "golf",
            "gap@addr cm",
            "gap@imp cm",
            "slide+ cm/s",
            "foot y cm",
            "clubs",
            "head@addr cm",
            "head@imp cm"
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
                "{:<6} {:<14} {:<14} {:>5} {:>9.2} {:>9.2} {:>5} {:>11} {:>10} {:>11} {:>10} {:>5} {:>12} {:>11}",
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
                cm(row.foot_height),
                row.clubs,
                cm(row.club_head.map(|h| h[0])),
                cm(row.club_head.map(|h| h[1])),
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

    /// A pool of `count` synthetic swings and putts per split (each tracks a club).
    fn synthetic_pool(count: usize) -> Pool {
        let mut pool = Pool::default();
        pool.add_synthetic_golf(count, 3).unwrap();
        pool
    }

    #[test]
    fn posture_error_moves_the_rotation_copy_and_not_the_analytic_retargeter() {
        // The analytic retargeter copies each bone's direction and takes only its length from
        // the T-pose; the rotation copy turns the T-pose's own bones, posture error and all.
        let pool = synthetic_pool(2);
        let methods = [
            Baseline::Analytic,
            Baseline::RotationCopy,
            Baseline::GroundTruth,
        ]
        .map(Method::Baseline);
        let rows = posture_error(&pool, 1, &methods, |_, _| {}).unwrap();
        assert_eq!(
            rows.len(),
            4,
            "two structures, the ground truth left out: {rows:?}"
        );
        for row in &rows {
            assert_eq!(row.pairs, 2 * GOLF_PAIRS);
            assert!(row.max >= row.mean);
            match row.method.as_str() {
                "analytic" => assert!(row.mean < 0.005, "{row:?}"),
                _ => assert!(row.mean > 0.01, "{row:?}"),
            }
        }
    }

    #[test]
    fn phone_formats_are_targets_of_their_own_block() {
        let pool = synthetic_pool(1);
        let methods = [Baseline::Analytic, Baseline::GroundTruth].map(Method::Baseline);
        let rows = onto_phone_formats(&pool, 2, &methods, |_, _| {}).unwrap();
        let blocks: Vec<&str> = rows.iter().map(|r| r.block).collect();
        assert_eq!(
            blocks,
            [
                "onto COCO-17",
                "onto COCO-17",
                "onto MediaPipe-33",
                "onto MediaPipe-33"
            ]
        );
        for row in &rows {
            assert_eq!(row.pairs, GOLF_PAIRS);
            match row.method.as_str() {
                "ground truth" => assert_eq!(row.global, 0.0),
                _ => assert!(row.global > 0.0, "{row:?}"),
            }
        }
    }

    #[test]
    fn the_club_head_reads_its_distance_from_the_coachs() {
        let pool = synthetic_pool(1);
        let clip = &pool.eval[0];
        let mut rng = SplitRng::new(Split::Eval, 4);
        let mut pair =
            pair_on(clip, &mut rng, Structure::Intra, &Variation::STANDARD_REST).unwrap();
        // Onto a canonical character with a club.
        let body = crate::bodies::Body::sample(&Variation::STANDARD_REST, rng.rng());
        pair.target =
            Character::new(body, posecoach_core::format::Format::Canonical, true).unwrap();
        pair.ground_truth = clip.on(&pair.target).unwrap();
        let (truth, coach) = (&pair.ground_truth, &pair.source);
        let swing = events::detect(&coach.skeleton, coach.swing(), coach.rate_hz).unwrap();
        let reference = |f: usize| match coach.skeleton.index_of(Joint::ClubHead) {
            Some(h) => coach.frame(f)[h].y,
            None => CLUB_HEAD_CLEARANCE_M,
        };
        let head = truth.skeleton.index_of(Joint::ClubHead).unwrap();
        let mut grounded = truth.clone();
        let n = grounded.skeleton.len();
        for f in [swing.address(), swing.impact()] {
            grounded.positions[f * n + head].y = reference(f);
        }
        assert_eq!(
            evaluate(&pair, &grounded).unwrap().club_head,
            Some([0.0, 0.0])
        );
        // Raised 5 cm at address, the head reads 5 cm there.
        grounded.positions[swing.address() * n + head].y += 0.05;
        let raised = evaluate(&pair, &grounded).unwrap().club_head.unwrap();
        assert!(
            (raised[0] - 0.05).abs() < 1e-6 && raised[1] == 0.0,
            "{raised:?}"
        );
        // The ground truth's feet are where they are; lifted 2 cm, they read 2 cm.
        assert_eq!(evaluate(&pair, truth).unwrap().foot_height, Some(0.0));
        let mut lifted = truth.clone();
        lifted.positions.iter_mut().for_each(|p| p.y += 0.02);
        let height = evaluate(&pair, &lifted).unwrap().foot_height.unwrap();
        assert!((height - 0.02).abs() < 1e-5, "{height}");
    }

    #[test]
    fn contacts_keep_the_grip_the_planted_feet_and_the_club_head() {
        // Across formats with varied bodies: the analytic retargeter misses every contact
        // somewhere; with the contacts kept the grip and club head are the coach's wherever
        // the trail arm and the club reach, and the feet slide no more than the coach's.
        let pool = synthetic_pool(2);
        let analytic = Method::Baseline(Baseline::Analytic);
        let methods = [analytic, Method::Contacts(&analytic)];
        let mut rng = SplitRng::new(Split::Eval, 6);
        let (mut free_sum, mut kept_sum) = ([0.0f32; 3], [0.0f32; 3]);
        for clip in &pool.eval {
            for structure in [Structure::Intra, Structure::Cross] {
                let mut pair =
                    pair_on(clip, &mut rng, structure, &Variation::STANDARD_REST).unwrap();
                let body = crate::bodies::Body::sample(&Variation::STANDARD_REST, rng.rng());
                pair.target = Character::new(body, Format::GolfMarkers, true).unwrap();
                pair.ground_truth = clip.on(&pair.target).unwrap();
                let [free, kept] =
                    methods.map(|m| evaluate(&pair, &m.retarget(&pair).unwrap()).unwrap());
                for (sum, m) in [(&mut free_sum, &free), (&mut kept_sum, &kept)] {
                    let (gap, head) = (m.hand_gap.unwrap(), m.club_head.unwrap());
                    sum[0] += gap[0] + gap[1];
                    sum[1] += m.foot_slide.unwrap();
                    sum[2] += head[0] + head[1];
                }
            }
        }
        // Means over the pairs (two gaps and two heads each).
        let pairs = 2.0 * pool.eval.len() as f32;
        let [free, kept] =
            [free_sum, kept_sum].map(|s| [s[0] / 2.0, s[1], s[2] / 2.0].map(|v| v / pairs));
        assert!(
            kept[0] < 0.002 && kept[1] < 0.005 && kept[2] < 0.01,
            "{kept:?}"
        );
        assert!(kept[1] < free[1], "{kept:?} against {free:?}");
        assert!(
            free[0] > 0.005 && free[1] > 0.001 && free[2] > 0.05,
            "{free:?}"
        );
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
