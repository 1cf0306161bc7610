//! Keypoint samples as a file holds them, in any landmark vocabulary, unit, up axis and clock,
//! read as a motion in metres, +Y up, seconds ([`motion`]); what was detected and what was
//! given is kept as a [`Reading`].
//!
//! The keypoint readers ([`crate::csv`], [`crate::json`]) only parse: names, times as written,
//! positions as written. Everything that needs the whole file is decided here:
//!
//! - the landmark vocabulary ([`Landmarks::detect`]) and each canonical joint from it;
//! - the clock: seconds, milliseconds or frame numbers (by the column's name, else by its
//!   values: whole steps of 1 are frame numbers, other steps of 1 or more milliseconds), or no
//!   time column at all; frames the clock skips are kept as missing samples;
//! - the up axis ([`Up::detect`]) and the units ([`Units::detect`]), unless given.

use crate::landmarks::{self, Landmarks};
use crate::limits::{check_limits, LimitError, MAX_RATE_HZ, MIN_RATE_HZ};
use crate::motion::{hold_missing, measured_skeleton, Motion};
use crate::units::{StatureError, Units, Up};
use posecoach_core::format::t_pose;
use posecoach_core::joint::Joint;
use posecoach_core::score::HELD_ROOT_M;
use posecoach_core::skeleton::{Skeleton, SkeletonError};
use posecoach_core::Vec3;
use std::fmt;

/// The confidence under which a landmark sample is read as missing: the threshold MediaPipe's
/// own drawing takes for a visible landmark, a convention rather than a measured optimum.
pub const MIN_CONFIDENCE: f32 = 0.5;

/// Keypoint samples as a file holds them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Samples {
    /// Landmark names as the file spells them.
    pub names: Vec<String>,
    /// The time column's name, if the file has one.
    pub clock: Option<String>,
    /// Times as written, one per frame (empty without a time column).
    pub times: Vec<f64>,
    /// Positions in the file's units and axes, frame-major (`frames × names`).
    pub positions: Vec<Vec3>,
    /// Samples the file left empty or marked unsure, like `positions`.
    pub missing: Vec<bool>,
    /// Columns or keys that were not read, as spelt.
    pub ignored: Vec<String>,
}

/// What a person says about a file that the file does not say itself (`--units`, `--up`,
/// `--rate`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hints {
    /// The length unit.
    pub units: Option<Units>,
    /// The up axis.
    pub up: Option<Up>,
    /// Frames per second, for files with frame numbers or no time column.
    pub rate_hz: Option<f32>,
}

/// How a file's times are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clock {
    /// Seconds.
    Seconds,
    /// Milliseconds.
    Milliseconds,
    /// Frame numbers, at a rate given separately.
    Frames,
    /// No time column: one row per frame, at a rate given separately.
    Rows,
}

impl Clock {
    /// How reports name it.
    pub const fn title(self) -> &'static str {
        match self {
            Clock::Seconds => "seconds",
            Clock::Milliseconds => "milliseconds",
            Clock::Frames => "frame numbers",
            Clock::Rows => "none (one frame per row)",
        }
    }
}

/// How a keypoint file was read: what was detected and what was given.
#[derive(Clone, Debug, PartialEq)]
pub struct Reading {
    /// The landmark vocabulary.
    pub landmarks: Landmarks,
    /// Canonical joints made as the midpoint of two landmarks, with their names.
    pub midpoints: Vec<(Joint, String, String)>,
    /// The length unit, and whether it was given.
    pub units: (Units, bool),
    /// The up axis, and whether it was given.
    pub up: (Up, bool),
    /// How times are written, and the time column's name.
    pub clock: (Clock, Option<String>),
    /// Frames per second (0 for a single-row T-pose).
    pub rate_hz: f32,
    /// Frames the clock skips, kept as missing samples.
    pub skipped: usize,
    /// Columns or keys not read.
    pub ignored: Vec<String>,
    /// The hips were held at one place in every frame (MediaPipe's world landmarks are
    /// centred on them), and the body was placed on its planted ankles: each frame moved so
    /// that its planted ankle stays where it was at the first frame ([`HEEL_UP_M`] decides
    /// which is planted), then stood on the floor.
    pub on_its_feet: bool,
}

/// Why keypoint samples are not a motion.
#[derive(Clone, Debug, PartialEq)]
pub enum KeypointError {
    /// Samples whose lengths disagree (positions, missing flags and times for the names):
    /// built by hand, as the readers never make them.
    Shape,
    /// No pelvis, and no hips to place it between; the columns or keys not read are listed.
    NoPelvis(Landmarks, Vec<String>),
    /// Frame numbers or no time column, and no `--rate`.
    NeedRate(Clock),
    /// A `--rate` outside the limits.
    Rate(f32),
    /// No axis dominates the body's feet-to-head direction (file axes).
    Up([f32; 3]),
    /// A stature that is no golfer's.
    Stature(StatureError),
    /// A one-row T-pose with a joint missing.
    MissingInTPose(Joint),
    /// The joints do not make a skeleton.
    Skeleton(SkeletonError),
    /// The motion is beyond the limits.
    Limit(LimitError),
}

impl fmt::Display for KeypointError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            KeypointError::Shape => f.write_str(
                "the samples' positions, missing flags and times do not match their landmarks",
            ),
            KeypointError::NoPelvis(landmarks, ignored) => {
                write!(
                    f,
                    "no pelvis, and no left and right hip to place it between (read as {landmarks})"
                )?;
                if !ignored.is_empty() {
                    write!(f, "; not read: {}", ignored.join(", "))?;
                }
                Ok(())
            }
            KeypointError::NeedRate(clock) => write!(
                f,
                "the time column holds {}: give the frame rate with --rate",
                clock.title()
            ),
            KeypointError::Rate(r) => write!(
                f,
                "--rate {r} is outside the limits of {MIN_RATE_HZ} to {MAX_RATE_HZ} Hz"
            ),
            KeypointError::Up([x, y, z]) => write!(
                f,
                "cannot tell which way is up: the body's mean feet-to-head direction is ({x:.2}, {y:.2}, \
                 {z:.2}); give it with --up (y, z, -y, ...)"
            ),
            KeypointError::Stature(e) => e.fmt(f),
            KeypointError::MissingInTPose(j) => {
                write!(f, "a one-row T-pose needs every joint; `{j}` is empty")
            }
            KeypointError::Skeleton(e) => write!(f, "the joints do not form a skeleton: {e}"),
            KeypointError::Limit(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for KeypointError {}

/// Whether a column's name says it is time (names compared as [`landmarks::key`]): `None`
/// for another column, `Some(None)` for time whose unit the values must tell (`time`, `t`,
/// `timestamp`), `Some(Some(clock))` where the name says the unit.
pub fn clock_of(name: &str) -> Option<Option<Clock>> {
    let k = landmarks::key(name);
    let clock = match k.as_str() {
        "ms" | "msec" | "millis" | "milliseconds" | "timems" | "timestampms" | "tms" => {
            Some(Clock::Milliseconds)
        }
        "" | "frame" | "frames" | "frameindex" | "framenumber" | "frameno" | "frameid"
        | "frameidx" | "index" | "idx" | "unnamed0" => Some(Clock::Frames),
        "s" | "sec" | "secs" | "seconds" | "times" | "timesec" | "timeseconds" => {
            Some(Clock::Seconds)
        }
        // Said to be time, without a unit: decided by the values.
        "time" | "t" | "timestamp" => None,
        _ => return None,
    };
    Some(clock)
}

/// Which of `names` (a header's cells, a frame's keys, in order; `None` for one that cannot be
/// the time) is the time: the first whose name says time ([`clock_of`]), before the first that
/// only counts frames (pandas writes its row index first, unnamed; a frame may carry its
/// counter beside its timestamp).
pub fn time_among<'a>(names: impl IntoIterator<Item = Option<&'a str>>) -> Option<usize> {
    let mut counter = None;
    for (i, name) in names.into_iter().enumerate() {
        match name.and_then(clock_of) {
            Some(Some(Clock::Frames)) => {
                counter.get_or_insert(i);
            }
            Some(_) => return Some(i),
            None => {}
        }
    }
    counter
}

/// The samples as a motion in metres, +Y up, at an even rate, with how they were read.
///
/// # Errors
/// A [`KeypointError`] for a body without a pelvis, a clock without a rate, an unknown up, a
/// body of no golfer's size, joints that make no skeleton, or a motion beyond the limits.
pub fn motion(samples: &Samples, hints: &Hints) -> Result<(Motion, Reading), KeypointError> {
    let keys: Vec<String> = samples.names.iter().map(|n| landmarks::key(n)).collect();
    let vocabulary = Landmarks::detect(&keys);
    let made = landmarks::make(vocabulary, &keys);
    if made.first().map(|m| m.joint) != Some(Joint::Pelvis) {
        return Err(KeypointError::NoPelvis(vocabulary, samples.ignored.clone()));
    }
    let joints: Vec<Joint> = made.iter().map(|m| m.joint).collect();
    let n = joints.len();
    let rest: Vec<Vec3> = joints.iter().map(|&j| t_pose(j)).collect();
    let template = Skeleton::canonical(&joints, &rest).map_err(KeypointError::Skeleton)?;

    let width = samples.names.len();
    let rows = samples.positions.len().checked_div(width).unwrap_or(0);
    let timed = samples.clock.is_none() || samples.times.len() == rows;
    if rows * width != samples.positions.len()
        || samples.missing.len() != samples.positions.len()
        || !timed
    {
        return Err(KeypointError::Shape);
    }
    let (clock, rate_hz, slots) = timing(samples, rows, hints)?;
    let frames = slots.last().map_or(0, |&s| s + 1);
    check_limits(frames, n, rate_hz).map_err(KeypointError::Limit)?;

    let mut positions = vec![Vec3::zeros(); frames * n];
    let mut missing = vec![true; frames * n];
    for (row, &slot) in slots.iter().enumerate() {
        let at = |i: usize| row * width + i;
        for (k, m) in made.iter().enumerate() {
            let [a, b] = m.from;
            positions[slot * n + k] = (samples.positions[at(a)] + samples.positions[at(b)]) * 0.5;
            missing[slot * n + k] = samples.missing[at(a)] || samples.missing[at(b)];
        }
    }

    let up = match hints.up {
        Some(up) => up,
        None => {
            let rise = rise(&joints, &positions, &missing);
            Up::detect(rise).ok_or(KeypointError::Up([rise.x, rise.y, rise.z]))?
        }
    };
    for p in &mut positions {
        *p = up.to_y_up(*p);
    }

    let tpose = frames == 1;
    if tpose {
        if let Some(k) = missing.iter().position(|&m| m) {
            return Err(KeypointError::MissingInTPose(joints[k]));
        }
    }
    let build = |positions: &[Vec3]| {
        if tpose {
            Skeleton::canonical(&joints, positions)
        } else {
            measured_skeleton(&template, positions, &missing)
        }
        .map_err(KeypointError::Skeleton)
    };
    let height = build(&positions)?.height();
    let units = match hints.units {
        Some(units) => units.check(height),
        None => Units::detect(height),
    }
    .map_err(KeypointError::Stature)?;
    for p in &mut positions {
        *p *= units.metres();
    }
    let skeleton = build(&positions)?;
    hold_missing(n, &mut positions, &missing);
    let on_its_feet = !tpose && on_its_feet(&joints, &mut positions);

    let midpoints = made
        .iter()
        .filter(|m| m.from[0] != m.from[1])
        .map(|m| {
            let name = |i: usize| samples.names[i].clone();
            (m.joint, name(m.from[0]), name(m.from[1]))
        })
        .collect();
    // Landmarks neither used nor known to the vocabulary (a typing error, another tool's
    // extra points) are reported with the columns not read.
    let known: Vec<String> = vocabulary.names().into_iter().map(landmarks::key).collect();
    let mut ignored = samples.ignored.clone();
    ignored.extend(
        samples
            .names
            .iter()
            .zip(&keys)
            .enumerate()
            .filter(|(i, (_, k))| !known.contains(k) && !made.iter().any(|m| m.from.contains(i)))
            .map(|(_, (name, _))| name.clone()),
    );
    let reading = Reading {
        landmarks: vocabulary,
        midpoints,
        units: (units, hints.units.is_some()),
        up: (up, hints.up.is_some()),
        clock: (clock, samples.clock.clone()),
        rate_hz,
        skipped: frames - rows,
        ignored,
        on_its_feet,
    };
    let motion = Motion {
        skeleton,
        names: joints.iter().map(|j| j.name().to_string()).collect(),
        rate_hz,
        positions,
        missing,
    };
    Ok((motion, reading))
}

/// The clock, the rate and each row's frame ([`place`]). The rate is the median step's, or
/// for unevenly stepped times the frames filled over their span.
fn timing(
    samples: &Samples,
    rows: usize,
    hints: &Hints,
) -> Result<(Clock, f32, Vec<usize>), KeypointError> {
    let named = samples.clock.as_deref().and_then(clock_of).flatten();
    let times = &samples.times;
    let steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let median = {
        let mut s = steps.clone();
        s.sort_by(f64::total_cmp);
        s.get(s.len() / 2).copied().unwrap_or(0.0)
    };
    let clock = match (&samples.clock, named) {
        (None, _) => Clock::Rows,
        (Some(_), Some(clock)) => clock,
        (Some(_), None) if median < 1.0 => Clock::Seconds,
        (Some(_), None) if median == 1.0 && times.iter().all(|t| t.fract() == 0.0) => Clock::Frames,
        (Some(_), None) => Clock::Milliseconds,
    };
    if rows <= 1 {
        return Ok((clock, 0.0, (0..rows).collect()));
    }
    // The rate from the median step in `f32` of times from the first: the same bits as a
    // file's times read as `f32` from zero.
    let step = {
        let mut s: Vec<f32> = times
            .windows(2)
            .map(|w| (w[1] - times[0]) as f32 - (w[0] - times[0]) as f32)
            .collect();
        s.sort_by(f32::total_cmp);
        s.get(s.len() / 2).copied().unwrap_or(0.0)
    };
    let (rate_hz, seconds_per_unit) = match (clock, hints.rate_hz) {
        (Clock::Seconds, _) => (1.0 / step, 1.0),
        (Clock::Milliseconds, _) => (1000.0 / step, 1e-3),
        // A file with its own times keeps them; `--rate` is for those without.
        (Clock::Frames | Clock::Rows, None) => return Err(KeypointError::NeedRate(clock)),
        (Clock::Frames | Clock::Rows, Some(rate)) => {
            if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate) {
                return Err(KeypointError::Rate(rate));
            }
            (rate, 1.0 / f64::from(rate))
        }
    };
    if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz) {
        return Err(KeypointError::Limit(LimitError::Rate(rate_hz)));
    }
    if clock == Clock::Rows {
        return Ok((clock, rate_hz, (0..rows).collect()));
    }
    // Times stepped unevenly (rounded to the millisecond, jittered) give the rate of the line
    // through them: each row's frame counted in median steps (a step of about two is a skipped
    // frame), the period the least-squares slope of time over frame. Whole milliseconds at
    // 30 Hz step 33, 33, 34 and are 30 Hz, where the median step alone says 30.3 and a
    // skipped frame would appear every 3 s. Even steps keep their own.
    let (low, high) = steps
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &s| {
            (l.min(s), h.max(s))
        });
    if matches!(clock, Clock::Seconds | Clock::Milliseconds)
        && high - low > 1e-6 * median
        && median > 0.0
    {
        if let Some(period) = fitted_period(times, median) {
            let rate_hz = (1.0 / (period * seconds_per_unit)) as f32;
            if (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz) {
                return Ok((clock, rate_hz, place(times, seconds_per_unit, rate_hz)));
            }
        }
    }
    Ok((clock, rate_hz, place(times, seconds_per_unit, rate_hz)))
}

/// The period of `times` (increasing, in their unit): the least-squares slope of each time over
/// its frame, frames counted in steps of `median` (each step at least one frame). `None` for
/// fewer than two times.
fn fitted_period(times: &[f64], median: f64) -> Option<f64> {
    let t0 = *times.first()?;
    let (mut frame, mut last) = (0.0, t0);
    let (mut n, mut sk, mut st, mut skk, mut skt) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (i, &t) in times.iter().enumerate() {
        if i > 0 {
            frame += ((t - last) / median).round().max(1.0);
        }
        last = t;
        let t = t - t0;
        n += 1.0;
        sk += frame;
        st += t;
        skk += frame * frame;
        skt += frame * t;
    }
    let spread = n * skk - sk * sk;
    (n >= 2.0 && spread > 0.0).then(|| (n * skt - sk * st) / spread)
}

/// A body whose root (`joints[0]`, the pelvis) stays within [`HELD_ROOT_M`] of one place in
/// every frame, as MediaPipe's world landmarks hold it at the hips' midpoint, is put back on
/// its feet: each frame moved so that its planted ankle stays where it was at the first frame
/// (the address), then the whole motion raised or lowered so that the first frame's lowest foot
/// joint stands on the floor (`y = 0`). Both ankles are planted at the address; once one rises
/// against the other (a trail heel coming up through impact and the finish, a step) it is
/// planted less, by the share its rise takes of [`HEEL_UP_M`], and the frame follows the other.
/// Each frame is placed from the first, not from the frame before, so noise does not add up.
/// Returns whether it moved the body (`positions`: frames of `joints`, metres, +Y up, every
/// sample filled).
fn on_its_feet(joints: &[Joint], positions: &mut [Vec3]) -> bool {
    let n = joints.len();
    let at = |j: Joint| joints.iter().position(|&k| k == j);
    let (Some(left), Some(right)) = (at(Joint::LeftAnkle), at(Joint::RightAnkle)) else {
        return false;
    };
    let feet: Vec<usize> = [Joint::LeftToe, Joint::RightToe]
        .into_iter()
        .filter_map(at)
        .chain([left, right])
        .collect();
    let frames: Vec<&[Vec3]> = positions.chunks_exact(n).collect();
    let Some(first) = frames.first() else {
        return false;
    };
    if frames
        .iter()
        .any(|f| (f[0] - first[0]).norm() >= HELD_ROOT_M)
    {
        return false;
    }
    let floor = feet
        .iter()
        .map(|&k| first[k].y)
        .fold(f32::INFINITY, f32::min);
    let ground = Vec3::new(0.0, floor, 0.0);
    let shifts: Vec<Vec3> = frames
        .iter()
        .map(|f| {
            // How far the left ankle rose against the right since the address.
            let rise = (f[left].y - f[right].y) - (first[left].y - first[right].y);
            let w = (0.5 - rise / (2.0 * HEEL_UP_M)).clamp(0.0, 1.0);
            let planted = |k: usize| first[k] - f[k];
            planted(left) * w + planted(right) * (1.0 - w) - ground
        })
        .collect();
    for (frame, shift) in positions.chunks_exact_mut(n).zip(shifts) {
        for p in frame.iter_mut() {
            *p += shift;
        }
    }
    true
}

/// How far one ankle rises against the other before a body held at its hips is placed on
/// the other foot alone (`Reading::on_its_feet`), m: a heel well off the ground. A convention,
/// not fitted.
pub const HEEL_UP_M: f32 = 0.05;

/// Each time's frame at `rate_hz`: the nearest, and at least one after the one before, so a
/// skipped frame stays a gap in time.
fn place(times: &[f64], seconds_per_unit: f64, rate_hz: f32) -> Vec<usize> {
    let t0 = times.first().copied().unwrap_or(0.0);
    let mut slots = Vec::with_capacity(times.len());
    let mut next = 0usize;
    for &t in times {
        let at = ((t - t0) * seconds_per_unit * f64::from(rate_hz)).round();
        // Bounded before the cast: the limits refuse such a motion just after.
        let slot = (at.clamp(0.0, 1e12) as usize).max(next);
        slots.push(slot);
        next = slot + 1;
    }
    slots
}

/// The body's mean feet-to-head vector over the frames, in the file's axes: the mean of the
/// upper joints seen less the mean of the lower ones seen, summed over frames.
fn rise(joints: &[Joint], positions: &[Vec3], missing: &[bool]) -> Vec3 {
    use Joint::*;
    let upper = [Thorax, Neck, Head, HeadTop, LeftShoulder, RightShoulder];
    let lower = [
        LeftAnkle, RightAnkle, LeftToe, RightToe, LeftKnee, RightKnee,
    ];
    let hips = [LeftHip, RightHip, Pelvis];
    let lower: &[Joint] = if joints.iter().any(|j| lower.contains(j)) {
        &lower
    } else {
        &hips
    };
    let n = joints.len();
    let mut total = Vec3::zeros();
    for (frame, gone) in positions.chunks_exact(n).zip(missing.chunks_exact(n)) {
        let mean = |set: &[Joint]| {
            let seen: Vec<Vec3> = (0..n)
                .filter(|&k| set.contains(&joints[k]) && !gone[k])
                .map(|k| frame[k])
                .collect();
            (!seen.is_empty()).then(|| seen.iter().sum::<Vec3>() / seen.len() as f32)
        };
        if let (Some(top), Some(bottom)) = (mean(&upper), mean(lower)) {
            total += top - bottom;
        }
    }
    total
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// The standard T-pose's body joints as samples named `names(joint)`, in `units`, with up
    /// `up`, at `rate` rows per second (one row if `rows` is 1), `time` in the given column.
    fn samples(
        rows: usize,
        scale: f32,
        turn: impl Fn(Vec3) -> Vec3,
        clock: Option<(&str, f64)>,
    ) -> Samples {
        let joints: Vec<Joint> = Joint::ALL
            .iter()
            .copied()
            .filter(|j| !j.is_club())
            .collect();
        let names = joints.iter().map(|j| j.name().to_string()).collect();
        let mut positions = Vec::new();
        for f in 0..rows {
            for &j in &joints {
                positions.push(turn(t_pose(j) + Vec3::new(0.01 * f as f32, 0.0, 0.0)) * scale);
            }
        }
        Samples {
            names,
            clock: clock.map(|(c, _)| c.to_string()),
            times: clock.map_or(vec![], |(_, step)| {
                (0..rows).map(|f| 1000.0 + f as f64 * step).collect()
            }),
            missing: vec![false; positions.len()],
            positions,
            ignored: vec![],
        }
    }

    #[test]
    fn units_up_and_clock_are_detected() {
        let z_up = |v: Vec3| Vec3::new(v.x, -v.z, v.y);
        let cases = [
            ("time", 1.0 / 60.0, Clock::Seconds),
            ("time", 1000.0 / 60.0, Clock::Milliseconds),
            ("timestamp_ms", 1000.0 / 60.0, Clock::Milliseconds),
        ];
        for (column, step, clock) in cases {
            let s = samples(30, 1000.0, z_up, Some((column, step)));
            let (m, r) = motion(&s, &Hints::default()).unwrap();
            assert_eq!(r.units, (Units::Mm, false));
            assert_eq!(
                r.up,
                (
                    Up {
                        axis: 2,
                        negative: false
                    },
                    false
                )
            );
            assert_eq!(r.clock.0, clock, "{column}");
            assert!((m.rate_hz - 60.0).abs() < 1e-3);
            let (metres, _) = motion(
                &samples(30, 1.0, |v| v, Some(("time_s", 0.01))),
                &Hints::default(),
            )
            .unwrap();
            assert!((m.skeleton.height() - metres.skeleton.height()).abs() < 1e-4);
            assert!((m.frame(0)[0] - t_pose(Joint::Pelvis)).norm() < 1e-5);
        }
    }

    #[test]
    fn frame_numbers_need_a_rate_and_skipped_frames_stay_gaps() {
        let mut s = samples(10, 1.0, |v| v, Some(("frame", 1.0)));
        assert_eq!(
            motion(&s, &Hints::default()).unwrap_err(),
            KeypointError::NeedRate(Clock::Frames)
        );
        s.times[5..].iter_mut().for_each(|t| *t += 2.0);
        let hints = Hints {
            rate_hz: Some(30.0),
            ..Hints::default()
        };
        let (m, r) = motion(&s, &hints).unwrap();
        assert_eq!((m.frames(), r.skipped), (12, 2));
        assert!(m.missing[5 * m.skeleton.len()] && !m.missing[7 * m.skeleton.len()]);
        let seconds = samples(10, 1.0, |v| v, Some(("t", 0.01)));
        // A file with its own times keeps them.
        assert!((motion(&seconds, &hints).unwrap().0.rate_hz - 100.0).abs() < 1e-3);
    }

    #[test]
    fn samples_whose_lengths_disagree_are_refused() {
        let whole = samples(3, 1.0, |v| v, Some(("t", 0.01)));
        let mut short_times = whole.clone();
        short_times.times.pop();
        let mut short_missing = whole.clone();
        short_missing.missing.pop();
        let mut ragged = whole.clone();
        ragged.positions.pop();
        ragged.missing.pop();
        for s in [short_times, short_missing, ragged] {
            assert_eq!(
                motion(&s, &Hints::default()).unwrap_err(),
                KeypointError::Shape
            );
        }
        assert!(motion(&whole, &Hints::default()).is_ok());
    }

    #[test]
    fn whole_millisecond_timestamps_are_read_at_their_true_rate() {
        // Whole milliseconds (30 Hz: 0, 33, 67, 100, ...; 60 Hz: 16, 17, 17, ...) over 10 s,
        // one frame dropped: the rate the clock ran at, and only that frame skipped.
        for rate in [24.0, 25.0, 30.0, 50.0, 60.0, 120.0] {
            let rows = (10.0 * rate) as usize;
            let mut s = samples(rows, 1.0, |v| v, Some(("timestamp_ms", 1.0)));
            s.times = (0..rows)
                .map(|f| ((f + usize::from(f >= rows / 2)) as f64 * 1000.0 / rate).round())
                .collect();
            let (m, r) = motion(&s, &Hints::default()).unwrap();
            assert!(
                (f64::from(m.rate_hz) - rate).abs() < 0.01,
                "{rate}: {}",
                m.rate_hz
            );
            assert_eq!((m.frames(), r.skipped), (rows + 1, 1), "{rate}");
        }
    }

    #[test]
    fn a_body_of_no_golfers_size_is_refused_saying_how_tall() {
        let s = samples(1, 0.3, |v| v, None);
        let e = motion(&s, &Hints::default()).unwrap_err();
        assert!(
            matches!(e, KeypointError::Stature(StatureError { given: None, .. })),
            "{e}"
        );
        let hints = Hints {
            units: Some(Units::M),
            ..Hints::default()
        };
        let e = motion(&samples(1, 1000.0, |v| v, None), &hints).unwrap_err();
        assert!(e.to_string().contains("m tall in m, outside"), "{e}");
    }

    #[test]
    fn a_lying_body_needs_up() {
        let lying = |v: Vec3| Vec3::new(v.y, v.y, v.x);
        let e = motion(&samples(1, 1.0, lying, None), &Hints::default()).unwrap_err();
        assert!(matches!(e, KeypointError::Up(_)), "{e}");
    }
}
