//! BVH (Biovision Hierarchy) motion files: parsing, forward kinematics and writing.
//!
//! Conventions:
//! - Lengths are in file units (CMU conversions ≈ 5.6 cm, Bandai cm); angles in files and in
//!   [`Bvh::motion`] are degrees. Quaternions are `[w, x, y, z]`.
//! - Rotations are right-handed and act on column vectors. A joint's rotation channels compose in
//!   the order listed: `Zrotation Xrotation Yrotation` means `R = Rz(z) · Rx(x) · Ry(y)` (intrinsic).
//! - Forward kinematics: a joint's local translation `t` is its `OFFSET` with any position channel
//!   replacing the matching component; `G_j = G_parent · R_j` and `p_j = p_parent + G_parent · t_j`.
//! - [`Bvh::from_positions`] writes six channels (position + rotation) for every joint. Rotations
//!   alone cannot reproduce arbitrary joint positions (bones that stretch, children that move
//!   independently), so the position channels carry the exact local translation while the rotation
//!   channels carry a best-fit rotation: positions re-import exactly and rotations stay meaningful.
//! - The writer prints the shortest decimal that parses back to the same `f64`, so text round
//!   trips are exact.

use std::fmt;
use std::str::FromStr;

/// Most joints a file may declare (a parsing limit; a skeleton keeps at most
/// `posecoach_core::config::MAX_JOINTS` of them); this also bounds the nesting depth.
const MAX_DECLARED_JOINTS: usize = 256;
/// Most frames a file may declare (38 h at 120 fps).
const MAX_DECLARED_FRAMES: usize = 1 << 24;
/// Rotation values of frame 0 below this (degrees) count as zero in [`Bvh::first_frame_is_rest`].
const REST_EPS_DEG: f64 = 1e-6;
/// Vectors shorter than this (file units) have no usable direction.
const MIN_LEN: f64 = 1e-12;

type Vec3 = [f64; 3];
type Quat = [f64; 4];
const IDENTITY: Quat = [1.0, 0.0, 0.0, 0.0];

/// One joint of the hierarchy (End Sites are not joints; they are kept on their parent as `end_site`).
#[derive(Debug, Clone, PartialEq)]
pub struct BvhJoint {
    pub name: String,
    /// Index of the parent joint, smaller than this joint's index; `None` for a root.
    pub parent: Option<usize>,
    pub offset: [f64; 3],
    pub channels: Vec<Channel>,
    /// Offset of this joint's End Site, if it has one.
    pub end_site: Option<[f64; 3]>,
}

/// One BVH channel (declared X, Y, Z positions, then X, Y, Z rotations).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

impl Channel {
    /// Every channel, in declaration order, with its name.
    const ALL: [(Channel, &'static str); 6] = [
        (Channel::Xposition, "Xposition"),
        (Channel::Yposition, "Yposition"),
        (Channel::Zposition, "Zposition"),
        (Channel::Xrotation, "Xrotation"),
        (Channel::Yrotation, "Yrotation"),
        (Channel::Zrotation, "Zrotation"),
    ];

    /// The channel's name as written after `CHANNELS`.
    pub fn name(self) -> &'static str {
        Self::ALL[self as usize].1
    }

    /// Whether this is a rotation (not a position) channel.
    pub fn is_rotation(self) -> bool {
        self as usize >= 3
    }

    /// 0 for X, 1 for Y, 2 for Z.
    fn axis(self) -> usize {
        self as usize % 3
    }

    fn from_name(name: &str) -> Option<Channel> {
        let mut all = Self::ALL.into_iter();
        all.find_map(|(c, n)| n.eq_ignore_ascii_case(name).then_some(c))
    }
}

/// A parsed (or generated) BVH file.
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    /// Joints in depth-first file order; a parent's index is smaller than its children's.
    pub joints: Vec<BvhJoint>,
    /// Seconds per frame.
    pub frame_time: f64,
    pub frames: usize,
    /// `frames × channel_count()` values, row-major, in degrees and file units.
    pub motion: Vec<f64>,
}

/// Why a BVH text was rejected, and on which line (1-based).
#[derive(Debug, Clone, PartialEq)]
pub struct BvhError {
    pub line: usize,
    pub kind: BvhErrorKind,
}

/// What went wrong while parsing.
#[derive(Debug, Clone, PartialEq)]
pub enum BvhErrorKind {
    /// The text holds nothing but whitespace.
    Empty,
    /// A keyword, brace, name or channel was expected; `found` is `None` at end of input.
    UnexpectedToken {
        expected: String,
        found: Option<String>,
    },
    /// A token that should be a number, or a count in range, is not.
    BadNumber { what: &'static str, found: String },
    /// A number is NaN or infinite.
    NonFinite { found: String },
    /// The hierarchy declares more than `max` joints.
    TooManyJoints { max: usize },
    /// The motion data ends in frame `frame` (0-based) after `actual` of its `expected` values.
    WrongValueCount {
        frame: usize,
        expected: usize,
        actual: usize,
    },
    /// `extra` values follow the `frames` frames that `Frames:` declares.
    ExtraValues { frames: usize, extra: usize },
}

impl fmt::Display for BvhError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use BvhErrorKind as K;
        write!(f, "line {}: ", self.line)?;
        match &self.kind {
            K::Empty => write!(f, "empty input, expected `HIERARCHY`"),
            K::UnexpectedToken { expected, found } => {
                let found = found
                    .as_ref()
                    .map_or("end of input".into(), |t| format!("`{t}`"));
                write!(f, "expected {expected}, found {found}")
            }
            K::BadNumber { what, found } => write!(f, "expected {what}, found `{found}`"),
            K::NonFinite { found } => write!(f, "expected a finite number, found `{found}`"),
            K::TooManyJoints { max } => write!(f, "more than {max} joints"),
            K::WrongValueCount {
                frame,
                expected,
                actual,
            } => write!(f, "frame {frame} has {actual} of {expected} values"),
            K::ExtraValues { frames, extra } => {
                write!(f, "{extra} values follow the {frames} frames of `Frames:`")
            }
        }
    }
}

impl std::error::Error for BvhError {}

/// Whitespace-separated tokens with their 1-based line numbers.
struct Lexer<'a> {
    tokens: Vec<(usize, &'a str)>,
    pos: usize,
    /// Line of the last token taken (of the last token, at end of input).
    line: usize,
}

impl<'a> Lexer<'a> {
    fn next(&mut self) -> Option<&'a str> {
        let &(line, tok) = self.tokens.get(self.pos)?;
        self.pos += 1;
        self.line = line;
        Some(tok)
    }

    fn peek_is(&self, word: &str) -> bool {
        self.tokens
            .get(self.pos)
            .is_some_and(|t| t.1.eq_ignore_ascii_case(word))
    }

    fn remaining(&self) -> usize {
        self.tokens.len().saturating_sub(self.pos)
    }

    fn fail<T>(&self, kind: BvhErrorKind) -> Result<T, BvhError> {
        Err(BvhError {
            line: self.line,
            kind,
        })
    }

    fn unexpected<T>(&self, expected: &str, found: Option<&str>) -> Result<T, BvhError> {
        let (expected, found) = (expected.to_string(), found.map(str::to_string));
        self.fail(BvhErrorKind::UnexpectedToken { expected, found })
    }

    /// Takes the next token, which must be `word` (ASCII case-insensitive).
    fn expect(&mut self, word: &str, expected: &str) -> Result<(), BvhError> {
        match self.next() {
            Some(t) if t.eq_ignore_ascii_case(word) => Ok(()),
            t => self.unexpected(expected, t),
        }
    }

    /// The next token parsed as `T` and accepted by `ok`.
    fn value<T: FromStr>(
        &mut self,
        what: &'static str,
        ok: impl Fn(&T) -> bool,
    ) -> Result<T, BvhError> {
        let Some(t) = self.next() else {
            return self.unexpected(what, None);
        };
        let found = t.to_string();
        match t.parse() {
            Ok(v) if ok(&v) => Ok(v),
            _ if t.parse::<f64>().is_ok_and(|v| !v.is_finite()) => {
                self.fail(BvhErrorKind::NonFinite { found })
            }
            _ => self.fail(BvhErrorKind::BadNumber { what, found }),
        }
    }

    fn number(&mut self, what: &'static str) -> Result<f64, BvhError> {
        self.value(what, |v: &f64| v.is_finite())
    }

    fn vec3(&mut self, what: &'static str) -> Result<Vec3, BvhError> {
        Ok([self.number(what)?, self.number(what)?, self.number(what)?])
    }

    /// One joint after its `ROOT`/`JOINT` keyword, up to and including its `CHANNELS` line.
    fn open_joint(
        &mut self,
        joints: &mut Vec<BvhJoint>,
        parent: Option<usize>,
    ) -> Result<usize, BvhError> {
        if joints.len() >= MAX_DECLARED_JOINTS {
            return self.fail(BvhErrorKind::TooManyJoints {
                max: MAX_DECLARED_JOINTS,
            });
        }
        let Some(name) = self.next().map(str::to_string) else {
            return self.unexpected("a joint name", None);
        };
        self.expect("{", "`{` after joint name")?;
        self.expect("OFFSET", "`OFFSET`")?;
        let offset = self.vec3("a number for OFFSET")?;
        let mut channels = Vec::new();
        if self.peek_is("CHANNELS") {
            self.next();
            for _ in 0..self.value("a channel count from 0 to 6", |n: &usize| *n <= 6)? {
                let t = self.next();
                match t.and_then(Channel::from_name) {
                    Some(c) => channels.push(c),
                    None => return self.unexpected("a channel name such as `Xrotation`", t),
                }
            }
        }
        joints.push(BvhJoint {
            name,
            parent,
            offset,
            channels,
            end_site: None,
        });
        Ok(joints.len() - 1)
    }

    /// One `ROOT` block (keyword already taken), read with an explicit stack so deep nesting
    /// cannot overflow the call stack.
    fn root(&mut self, joints: &mut Vec<BvhJoint>) -> Result<(), BvhError> {
        let mut open = vec![self.open_joint(joints, None)?];
        while let Some(&top) = open.last() {
            match self.next() {
                Some("}") => drop(open.pop()),
                Some(t) if t.eq_ignore_ascii_case("JOINT") => {
                    open.push(self.open_joint(joints, Some(top))?)
                }
                Some(t) if t.eq_ignore_ascii_case("End") => {
                    self.expect("Site", "`Site` after `End`")?;
                    self.expect("{", "`{` after `End Site`")?;
                    self.expect("OFFSET", "`OFFSET`")?;
                    let site = self.vec3("a number for the End Site OFFSET")?;
                    self.expect("}", "`}` closing the End Site")?;
                    if let Some(joint) = joints.get_mut(top) {
                        joint.end_site = Some(site);
                    }
                }
                t => return self.unexpected("`JOINT`, `End Site` or `}`", t),
            }
        }
        Ok(())
    }
}

impl Bvh {
    /// Parses BVH text: any channel order and subset, CRLF, and motion values wrapped onto lines
    /// arbitrarily (they are read as one token stream after `Frame Time:`).
    ///
    /// # Errors
    /// A [`BvhError`] naming the line and what was expected: malformed hierarchy, more than 256
    /// joints, bad or non-finite numbers, or motion data that is not exactly `frames × channels`.
    pub fn parse(text: &str) -> Result<Bvh, BvhError> {
        let lines = text.lines().enumerate();
        let tokens: Vec<_> = lines
            .flat_map(|(i, l)| l.split_whitespace().map(move |t| (i + 1, t)))
            .collect();
        let mut lx = Lexer {
            tokens,
            pos: 0,
            line: 1,
        };
        if lx.tokens.is_empty() {
            return lx.fail(BvhErrorKind::Empty);
        }
        lx.expect("HIERARCHY", "`HIERARCHY`")?;
        lx.expect("ROOT", "`ROOT`")?;
        let mut joints = Vec::new();
        lx.root(&mut joints)?;
        while lx.peek_is("ROOT") {
            lx.next();
            lx.root(&mut joints)?;
        }
        lx.expect("MOTION", "`MOTION` or `ROOT`")?;
        lx.expect("Frames:", "`Frames:`")?;
        let frames = lx.value("a frame count up to 16777216", |n: &usize| {
            *n <= MAX_DECLARED_FRAMES
        })?;
        lx.expect("Frame", "`Frame Time:`")?;
        lx.expect("Time:", "`Frame Time:`")?;
        let frame_time = lx.value("a positive frame time", |t: &f64| t.is_finite() && *t > 0.0)?;
        let width: usize = joints.iter().map(|j| j.channels.len()).sum();
        let total = frames * width; // At most 2^24 · 256 · 6.
        let mut motion = Vec::with_capacity(total.min(lx.remaining()));
        while motion.len() < total {
            if lx.remaining() == 0 {
                // `total > 0`, so `width > 0`.
                let (frame, actual) = (motion.len() / width, motion.len() % width);
                return lx.fail(BvhErrorKind::WrongValueCount {
                    frame,
                    expected: width,
                    actual,
                });
            }
            motion.push(lx.number("a motion value")?);
        }
        let extra = lx.remaining();
        if extra > 0 {
            lx.next();
            return lx.fail(BvhErrorKind::ExtraValues { frames, extra });
        }
        Ok(Bvh {
            joints,
            frame_time,
            frames,
            motion,
        })
    }

    /// Number of channels over all joints (values per frame).
    pub fn channel_count(&self) -> usize {
        self.joints.iter().map(|j| j.channels.len()).sum()
    }

    /// The motion values of `frame`, if it exists.
    fn row(&self, frame: usize) -> Option<&[f64]> {
        let width = self.channel_count();
        let start = frame.checked_mul(width).filter(|_| frame < self.frames)?;
        self.motion.get(start..start.checked_add(width)?)
    }

    /// Local (rotation, translation) of every joint for a motion row; `None` gives the rest pose.
    fn local_poses(&self, row: Option<&[f64]>) -> Vec<(Quat, Vec3)> {
        let mut k = 0;
        let poses = self.joints.iter().map(|joint| {
            let n = joint.channels.len();
            let values = row.and_then(|r| r.get(k..k + n)).unwrap_or(&[]);
            k += n;
            local_pose(joint, values)
        });
        poses.collect()
    }

    /// Global positions by forward kinematics for a motion row (`None`: rest pose).
    fn forward(&self, row: Option<&[f64]>, out: &mut [[f64; 3]]) {
        let mut global: Vec<(Quat, Vec3)> = Vec::with_capacity(self.joints.len());
        for (j, (joint, (r, t))) in self.joints.iter().zip(self.local_poses(row)).enumerate() {
            let parent = parent_before(joint, j).and_then(|p| global.get(p).copied());
            let g = chain(parent, r, t);
            global.push(g);
            if let Some(o) = out.get_mut(j) {
                *o = g.1;
            }
        }
    }

    /// Local rotation of every joint at `frame` as unit quaternions `[w, x, y, z]`, composed from
    /// the Euler channels in the order they appear in `CHANNELS` (`Zrotation Xrotation Yrotation`
    /// means `Rz · Rx · Ry`). Joints without rotation channels, and every joint for a frame out of
    /// range, get identity. Fills `out[..min(out.len(), joints)]`.
    pub fn local_rotations(&self, frame: usize, out: &mut [[f64; 4]]) {
        for (o, (q, _)) in out.iter_mut().zip(self.local_poses(self.row(frame))) {
            *o = q;
        }
    }

    /// Global joint positions at `frame` in file units by forward kinematics (see the module doc).
    /// A frame out of range gives the rest pose. Fills `out[..min(out.len(), joints)]`.
    pub fn positions(&self, frame: usize, out: &mut [[f64; 3]]) {
        self.forward(self.row(frame), out);
    }

    /// Rest (zero-rotation) global positions from the OFFSETs alone.
    pub fn rest_positions(&self, out: &mut [[f64; 3]]) {
        self.forward(None, out);
    }

    /// Whether frame 0 is a T-pose/reference frame as some CMU conversions write it: there is
    /// more than one frame and at least one rotation channel, and every rotation value of
    /// frame 0 is zero (below 1e-6°).
    pub fn first_frame_is_rest(&self) -> bool {
        let Some(row) = self.row(0).filter(|_| self.frames > 1) else {
            return false;
        };
        let channels = self.joints.iter().flat_map(|j| &j.channels);
        let mut rotations = channels
            .zip(row)
            .filter(|(c, _)| c.is_rotation())
            .peekable();
        rotations.peek().is_some() && rotations.all(|(_, v)| v.abs() < REST_EPS_DEG)
    }

    /// Removes frame 0 (no-op without frames).
    pub fn drop_first_frame(&mut self) {
        if self.frames > 0 {
            let width = self.channel_count().min(self.motion.len());
            self.motion.drain(..width);
            self.frames -= 1;
        }
    }

    /// Builds a BVH from global joint positions (file units) that re-imports to these positions
    /// (up to float rounding).
    ///
    /// `names`, `parents` (`parents[i] < i`, depth-first order, `parents[0] == None`) and `offsets`
    /// (rest offsets from the parent) describe the hierarchy; missing entries count as no parent
    /// and zero offset. `positions` is `frames × joints` (a trailing partial frame is ignored).
    /// `order` is the Euler order to write; unless it is three distinct rotation channels,
    /// `Zrotation Xrotation Yrotation` is used. Every leaf gets an End Site (its `end_sites` entry,
    /// else a zero offset).
    ///
    /// Every joint gets six channels: the position channels hold the local translation
    /// `G_parent⁻¹ (p_j − p_parent)` (the root: `p_root`), the rotation channels `G_parent⁻¹ G_j`,
    /// where the global rotation `G_j` swings the first child's rest offset onto its observed
    /// direction, then twists about that direction to best align the other children (least
    /// squares); a leaf, or a joint without usable child vectors, keeps its parent's rotation.
    /// Each frame takes the Euler solution (of the two, with ±360° wraps) nearest the previous one.
    pub fn from_positions(
        names: &[String],
        parents: &[Option<usize>],
        offsets: &[[f64; 3]],
        end_sites: &[Option<[f64; 3]>],
        positions: &[[f64; 3]],
        frame_time: f64,
        order: [Channel; 3],
    ) -> Bvh {
        use Channel::{Xposition, Xrotation, Yposition, Yrotation, Zposition, Zrotation};
        let (order, axes) = match euler_axes(order) {
            Some(axes) => (order, axes),
            None => ([Zrotation, Xrotation, Yrotation], [2, 0, 1]),
        };
        let n = names.len();
        let parent_of = |j: usize| parents.get(j).copied().flatten().filter(|&p| p < j);
        let mut children = vec![Vec::new(); n];
        for j in 0..n {
            if let Some(kids) = parent_of(j).and_then(|p| children.get_mut(p)) {
                kids.push(j);
            }
        }
        let channels = [[Xposition, Yposition, Zposition], order].concat();
        let joints: Vec<BvhJoint> = (names.iter().zip(&children).enumerate())
            .map(|(j, (name, kids))| BvhJoint {
                name: name.clone(),
                parent: parent_of(j),
                offset: offsets.get(j).copied().unwrap_or_default(),
                channels: channels.clone(),
                end_site: end_sites
                    .get(j)
                    .copied()
                    .flatten()
                    .or(kids.is_empty().then_some([0.0; 3])),
            })
            .collect();

        let frames = positions.len().checked_div(n).unwrap_or(0);
        let mut motion = Vec::with_capacity(frames * n * 6);
        let mut prev: Vec<Option<Vec3>> = vec![None; n];
        for pose in positions.chunks_exact(n.max(1)).take(frames) {
            let mut global: Vec<(Quat, Vec3)> = Vec::with_capacity(n);
            let per_joint = joints.iter().zip(&children).zip(&mut prev).zip(pose);
            for (((joint, kids), prev), &p) in per_joint {
                let parent = joint.parent.and_then(|q| global.get(q).copied());
                let (gq, gp) = parent.unwrap_or((IDENTITY, [0.0; 3]));
                let pairs = kids
                    .iter()
                    .filter_map(|&k| Some((joints.get(k)?.offset, sub(*pose.get(k)?, p))));
                let inv = qconj(gq);
                let euler =
                    continuous_euler(qmul(inv, fit_rotation(pairs).unwrap_or(gq)), axes, *prev);
                *prev = Some(euler);
                let t = qrot(inv, sub(p, gp));
                let values = [t[0], t[1], t[2], euler[0], euler[1], euler[2]];
                motion.extend_from_slice(&values);
                // Chain exactly what a reader will compute from the written values.
                let (r, t) = local_pose(joint, &values);
                global.push(chain(parent, r, t));
            }
        }
        Bvh {
            joints,
            frame_time,
            frames,
            motion,
        }
    }

    /// Serializes as BVH text (tabs for indentation); see the [`fmt::Display`] impl.
    pub fn to_text(&self) -> String {
        self.to_string()
    }
}

/// BVH text: joints depth-first from each root, motion columns in the same order, numbers in
/// their shortest exact form.
impl fmt::Display for Bvh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut children = vec![Vec::new(); self.joints.len()];
        let mut roots = Vec::new();
        let mut columns = Vec::with_capacity(self.joints.len());
        for (j, joint) in self.joints.iter().enumerate() {
            match parent_before(joint, j).and_then(|p| children.get_mut(p)) {
                Some(kids) => kids.push(j),
                None => roots.push(j),
            }
            let start = columns.last().map_or(0, |c: &std::ops::Range<usize>| c.end);
            columns.push(start..start + joint.channels.len());
        }
        f.write_str("HIERARCHY\n")?;
        let mut order = Vec::new(); // motion columns in written order
        let mut stack: Vec<_> = roots.iter().rev().map(|&r| (r, 0, false)).collect();
        while let Some((j, depth, closing)) = stack.pop() {
            let Some(joint) = self.joints.get(j) else {
                continue;
            };
            let tabs = "\t".repeat(depth);
            if closing {
                if let Some(site) = joint.end_site {
                    write!(f, "{tabs}\tEnd Site\n{tabs}\t{{\n{tabs}\t\tOFFSET ")?;
                    write_values(f, &site)?;
                    write!(f, "\n{tabs}\t}}\n")?;
                }
                writeln!(f, "{tabs}}}")?;
                continue;
            }
            let keyword = if depth == 0 { "ROOT" } else { "JOINT" };
            let name = &joint.name;
            write!(f, "{tabs}{keyword} {name}\n{tabs}{{\n{tabs}\tOFFSET ")?;
            write_values(f, &joint.offset)?;
            write!(f, "\n{tabs}\tCHANNELS {}", joint.channels.len())?;
            for c in &joint.channels {
                write!(f, " {}", c.name())?;
            }
            f.write_str("\n")?;
            order.extend(columns.get(j).cloned().unwrap_or_default());
            stack.push((j, depth, true));
            let kids = children.get(j).map_or(&[][..], Vec::as_slice);
            stack.extend(kids.iter().rev().map(|&c| (c, depth + 1, false)));
        }
        write!(f, "MOTION\nFrames: {}\nFrame Time: ", self.frames)?;
        write_values(f, &[self.frame_time])?;
        for row in (0..self.frames).map_while(|frame| self.row(frame)) {
            f.write_str("\n")?;
            let values: Vec<f64> = order.iter().filter_map(|&c| row.get(c).copied()).collect();
            write_values(f, &values)?;
        }
        f.write_str("\n")
    }
}

/// Writes values separated by single spaces, each in the shortest form that parses back to the
/// same `f64` (exponent form only for very small or large magnitudes).
fn write_values(f: &mut fmt::Formatter<'_>, values: &[f64]) -> fmt::Result {
    for (i, &v) in values.iter().enumerate() {
        let (sep, v) = (if i == 0 { "" } else { " " }, v + 0.0); // `+ 0.0`: no "-0"
        if v == 0.0 || (1e-5..1e15).contains(&v.abs()) {
            write!(f, "{sep}{v}")?;
        } else {
            write!(f, "{sep}{v:e}")?;
        }
    }
    Ok(())
}

/// The joint's parent index if it comes before joint `j` (otherwise the joint counts as a root).
fn parent_before(joint: &BvhJoint, j: usize) -> Option<usize> {
    joint.parent.filter(|&p| p < j)
}

/// Local rotation and translation of a joint from its channel values (missing values: rest).
fn local_pose(joint: &BvhJoint, values: &[f64]) -> (Quat, Vec3) {
    let (mut r, mut t) = (IDENTITY, joint.offset);
    for (c, &v) in joint.channels.iter().zip(values) {
        if c.is_rotation() {
            r = qmul(r, axis_angle(unit(c.axis()), v.to_radians()));
        } else {
            t[c.axis()] = v;
        }
    }
    (r, t)
}

/// One forward-kinematics step: global (rotation, position) from the parent's and a local pose.
fn chain(parent: Option<(Quat, Vec3)>, r: Quat, t: Vec3) -> (Quat, Vec3) {
    match parent {
        Some((gq, gp)) => (qmul(gq, r), add(gp, qrot(gq, t))),
        None => (r, t),
    }
}

/// Rotation taking rest child offsets onto observed child vectors (`(offset, vector)` pairs): the
/// swing of the first usable pair, then the least-squares twist about its observed direction.
/// `None` when no pair has two non-zero vectors.
fn fit_rotation(pairs: impl Iterator<Item = (Vec3, Vec3)>) -> Option<Quat> {
    let mut pairs = pairs.filter(|(o, v)| norm(*o) > MIN_LEN && norm(*v) > MIN_LEN);
    let (o0, v0) = pairs.next()?;
    let (u, axis) = (normalize(o0), normalize(v0));
    let swing = match dot(u, axis) {
        // Opposite directions: half turn about an axis perpendicular to `u`.
        d if d < -1.0 + 1e-12 => {
            let a = normalize(cross(u, unit(usize::from(u[0].abs() >= 0.6))));
            [0.0, a[0], a[1], a[2]]
        }
        d => {
            let c = cross(u, axis);
            let n = ((1.0 + d) * (1.0 + d) + dot(c, c)).sqrt();
            [(1.0 + d) / n, c[0] / n, c[1] / n, c[2] / n]
        }
    };
    // Maximize Σ v⊥ · Rot(axis, θ) r⊥ over θ: tan θ = Σ axis · (r × v) / Σ r⊥ · v⊥.
    let (mut sin_sum, mut cos_sum) = (0.0, 0.0);
    for (o, v) in pairs {
        let r = qrot(swing, o);
        sin_sum += dot(axis, cross(r, v));
        cos_sum += dot(r, v) - dot(r, axis) * dot(v, axis);
    }
    Some(qmul(axis_angle(axis, sin_sum.atan2(cos_sum)), swing))
}

/// Axis indices of a valid Euler order (three distinct rotation channels).
fn euler_axes(order: [Channel; 3]) -> Option<[usize; 3]> {
    let [a, b, c] = order.map(Channel::axis);
    let valid = order.iter().all(|c| c.is_rotation()) && a != b && b != c && a != c;
    valid.then_some([a, b, c])
}

/// Euler angles (radians) with `q = R_i(α) · R_j(β) · R_k(γ)` for distinct axes `[i, j, k]`.
/// α comes from column k of the matrix; β and γ from `R_i(−α) · q`, exact even at gimbal lock.
fn quat_to_euler(q: Quat, [i, j, k]: [usize; 3]) -> Vec3 {
    let s = if (i + 1) % 3 == j { 1.0 } else { -1.0 }; // +1 for cyclic orders (XYZ, YZX, ZXY)
    let col_k = qrot(q, unit(k));
    let a = (-s * col_k[j]).atan2(col_k[k]);
    let rest = qmul(axis_angle(unit(i), -a), q);
    let col = |n: usize| qrot(rest, unit(n));
    [
        a,
        (s * col(k)[i]).atan2(col(k)[k]),
        (s * col(i)[j]).atan2(col(j)[j]),
    ]
}

/// Euler angles (degrees) of `q` for `axes`, choosing between the two solutions `(α, β, γ)` and
/// `(α + 180, 180 − β, γ + 180)`, each angle wrapped by 360°, the one nearest `prev`.
fn continuous_euler(q: Quat, axes: [usize; 3], prev: Option<Vec3>) -> Vec3 {
    let [a, b, c] = quat_to_euler(q, axes).map(f64::to_degrees);
    let Some(prev) = prev else { return [a, b, c] };
    let near = |mut sol: Vec3| {
        for (x, p) in sol.iter_mut().zip(prev) {
            *x += 360.0 * ((p - *x) / 360.0).round();
        }
        (norm(sub(sol, prev)), sol)
    };
    let (first, second) = (near([a, b, c]), near([a + 180.0, 180.0 - b, c + 180.0]));
    if first.0 <= second.0 {
        first.1
    } else {
        second.1
    }
}

fn unit(axis: usize) -> Vec3 {
    let mut e = [0.0; 3];
    if let Some(x) = e.get_mut(axis) {
        *x = 1.0;
    }
    e
}

fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    let ([x, y, z], [p, q, r]) = (a, b);
    [y * r - z * q, z * p - x * r, x * q - y * p]
}

fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

fn normalize(a: Vec3) -> Vec3 {
    let n = norm(a);
    if n > 0.0 {
        a.map(|x| x / n)
    } else {
        a
    }
}

fn qmul([aw, ax, ay, az]: Quat, [bw, bx, by, bz]: Quat) -> Quat {
    [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]
}

fn qconj([w, x, y, z]: Quat) -> Quat {
    [w, -x, -y, -z]
}

/// Rotates `v` by the unit quaternion `q`.
fn qrot([w, x, y, z]: Quat, v: Vec3) -> Vec3 {
    let u = [x, y, z];
    let t = cross(u, v).map(|c| 2.0 * c);
    add(add(v, t.map(|c| w * c)), cross(u, t))
}

/// Rotation by `rad` about the unit vector `axis`.
fn axis_angle(axis: Vec3, rad: f64) -> Quat {
    let (s, c) = (0.5 * rad).sin_cos();
    [c, s * axis[0], s * axis[1], s * axis[2]]
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use Channel::{Xrotation as X, Yrotation as Y, Zrotation as Z};

    /// Three joints and an End Site, mixed channel orders, a 6-channel non-root joint, CRLF,
    /// tabs, `End site`, odd numbers and motion values wrapped across lines.
    const SMALL_BVH: &str = "HIERARCHY\r\nROOT Hips\r\n{\r\n\tOFFSET 1 2 3\r\n\tCHANNELS 6 Xposition \
        Yposition Zposition Zrotation Yrotation Xrotation\r\n\tJOINT Spine\r\n\t{\r\n\t\tOFFSET 0 10 0\r\n\
        \t\tCHANNELS 3 Zrotation Xrotation Yrotation\r\n\t\tJOINT Head\r\n\t\t{\r\n\t\t\tOFFSET 0 5 0\r\n\
        \t\t\tCHANNELS 0\r\n\t\t\tEnd site\r\n\t\t\t{\r\n\t\t\t\tOFFSET 0 3 0\r\n\t\t\t}\r\n\t\t}\r\n\t}\r\n\
        \tJOINT LeftLeg\r\n\t{\r\n\t\tOFFSET 4 -1 0\r\n\t\tCHANNELS 6 Yrotation Xposition Yposition \
        Zposition Xrotation Zrotation\r\n\t}\r\n}\r\nMOTION\r\nFrames:\t2\r\nFrame Time:\t.0083333\r\n\
        0 0 0 -0.00000 0 0 0 0 0 0 4 -1 0 0 0\r\n1 2 3 9.0e1 0 0\r\n0 90\r\n0 0 5 -1 0 1.87007e-05\r\n0\r\n";
    const SMALL_FRAME0: [Vec3; 4] = [
        [0.0; 3],
        [0.0, 10.0, 0.0],
        [0.0, 15.0, 0.0],
        [4.0, -1.0, 0.0],
    ];
    /// Frame 1 of `SMALL_BVH` by hand: root at (1, 2, 3) turned 90° about Z, Spine 90° about X,
    /// LeftLeg moved to (5, -1, 0) by its position channels.
    const SMALL_FRAME1: [Vec3; 4] = [
        [1.0, 2.0, 3.0],
        [-9.0, 2.0, 3.0],
        [-9.0, 2.0, 8.0],
        [2.0, 7.0, 3.0],
    ];
    const SMALL_REST: [Vec3; 4] = [
        [1.0, 2.0, 3.0],
        [1.0, 12.0, 3.0],
        [1.0, 17.0, 3.0],
        [5.0, 1.0, 3.0],
    ];
    /// Root R (6 channels) with children A and B; A (3 channels) with leaves A1 and A2.
    const RIGID_HIERARCHY: &str = "HIERARCHY\nROOT R\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition \
        Zposition Zrotation Yrotation Xrotation\nJOINT A\n{\nOFFSET 3 1 0\nCHANNELS 3 Xrotation Yrotation \
        Zrotation\nJOINT A1\n{\nOFFSET 0 4 1\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\nJOINT A2\n{\nOFFSET 1 -2 3\n\
        CHANNELS 0\n}\n}\nJOINT B\n{\nOFFSET -2 0 1\n}\n}\nMOTION\n";
    const ORDERS: [[Channel; 3]; 6] = [
        [X, Y, Z],
        [X, Z, Y],
        [Y, X, Z],
        [Y, Z, X],
        [Z, X, Y],
        [Z, Y, X],
    ];
    /// Middle Euler angles at and next to gimbal lock.
    const GIMBAL_BETAS: [f64; 4] = [90.0, -90.0, 90.0 - 1e-7, -90.0 + 1e-9];
    /// (1, 2, 3) turned 90° about X, Y and Z.
    const QUARTER_TURNS: [Vec3; 3] = [[1.0, -3.0, 2.0], [3.0, 2.0, -1.0], [-2.0, 1.0, 3.0]];
    const DATA_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/bvh");

    /// Tiny deterministic generator for test data.
    struct Lcg(u64);
    impl Lcg {
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1);
            lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn vec3(&mut self, r: f64) -> Vec3 {
            [(); 3].map(|_| self.uniform(-r, r))
        }
    }

    fn close(a: Vec3, b: Vec3, tol: f64) -> bool {
        norm(sub(a, b)) <= tol * norm(b).max(1.0)
    }

    fn same_rotation(a: Quat, b: Quat) -> bool {
        1.0 - a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>().abs() < 1e-12
    }

    fn all_positions(bvh: &Bvh) -> Vec<Vec3> {
        let mut out = vec![[0.0; 3]; bvh.frames * bvh.joints.len()];
        for (f, chunk) in out.chunks_mut(bvh.joints.len()).enumerate() {
            bvh.positions(f, chunk);
        }
        out
    }

    /// `from_positions` with `bvh`'s hierarchy, written as text and parsed again.
    fn export(bvh: &Bvh, positions: &[Vec3], order: [Channel; 3]) -> Bvh {
        let names: Vec<String> = bvh.joints.iter().map(|j| j.name.clone()).collect();
        let parents: Vec<_> = bvh.joints.iter().map(|j| j.parent).collect();
        let offsets: Vec<_> = bvh.joints.iter().map(|j| j.offset).collect();
        let sites: Vec<_> = bvh.joints.iter().map(|j| j.end_site).collect();
        let out = Bvh::from_positions(&names, &parents, &offsets, &sites, positions, 0.1, order);
        let back = Bvh::parse(&out.to_text()).unwrap();
        assert_eq!(back, out);
        back
    }

    #[test]
    fn small_file() {
        let mut bvh = Bvh::parse(SMALL_BVH).unwrap();
        let names: Vec<&str> = bvh.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, ["Hips", "Spine", "Head", "LeftLeg"]);
        let parents: Vec<_> = bvh.joints.iter().map(|j| j.parent).collect();
        assert_eq!(parents, [None, Some(0), Some(1), Some(0)]);
        assert_eq!(bvh.joints[1].channels, [Z, X, Y]);
        assert_eq!(bvh.joints[2].end_site, Some([0.0, 3.0, 0.0]));
        assert_eq!(bvh.joints[3].end_site, None);
        assert_eq!(
            (bvh.channel_count(), bvh.frames, bvh.frame_time),
            (15, 2, 0.0083333)
        );
        assert_eq!(bvh.motion[28..], [1.87007e-05, 0.0]);
        assert_eq!(Bvh::parse(&bvh.to_text()).unwrap(), bvh);

        let mut p = [[0.0; 3]; 4];
        bvh.rest_positions(&mut p);
        assert_eq!(p, SMALL_REST);
        bvh.positions(0, &mut p);
        assert_eq!(p, SMALL_FRAME0);
        bvh.positions(1, &mut p);
        assert!(
            p.iter().zip(SMALL_FRAME1).all(|(a, b)| close(*a, b, 1e-4)),
            "{p:?}"
        );
        bvh.positions(7, &mut p); // out of range: rest pose
        assert_eq!(p, SMALL_REST);
        let mut q = [[0.0; 4]; 4];
        bvh.local_rotations(1, &mut q);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(same_rotation(q[0], [h, 0.0, 0.0, h]) && same_rotation(q[1], [h, h, 0.0, 0.0]));
        assert_eq!(q[2], IDENTITY);

        assert!(bvh.first_frame_is_rest());
        bvh.drop_first_frame();
        assert_eq!((bvh.frames, bvh.motion.len(), bvh.motion[0]), (1, 15, 1.0));
        assert!(!bvh.first_frame_is_rest());
    }

    #[test]
    fn quarter_turns_in_every_order() {
        // A rotating root at (10, 20, 30) with a child at offset (1, 2, 3).
        let child = |channels: &[&str], values: &[&str]| {
            let text = format!(
                "HIERARCHY\nROOT A\n{{\nOFFSET 10 20 30\nCHANNELS {} {}\nJOINT B\n{{\nOFFSET 1 2 3\n}}\n}}\n\
                 MOTION\nFrames: 1\nFrame Time: 0.1\n{}",
                channels.len(),
                channels.join(" "),
                values.join(" ")
            );
            let mut p = [[0.0; 3]; 2];
            Bvh::parse(&text).unwrap().positions(0, &mut p);
            sub(p[1], [10.0, 20.0, 30.0])
        };
        for order in ORDERS {
            for (axis, expected) in QUARTER_TURNS.into_iter().enumerate() {
                let values = order.map(|c| if c.axis() == axis { "90" } else { "0" });
                let got = child(&order.map(Channel::name), &values);
                assert!(close(got, expected, 1e-12), "{order:?} {values:?}: {got:?}");
            }
        }
        // Listed order is application order from the left: Rz·Rx·v, and Rx·Rz·v.
        let zx = child(&["Zrotation", "Xrotation"], &["90", "90"]);
        let xz = child(&["Xrotation", "Zrotation"], &["90", "90"]);
        assert!(close(zx, [3.0, 1.0, 2.0], 1e-12) && close(xz, [-2.0, -3.0, 1.0], 1e-12));
    }

    #[test]
    fn euler_round_trip_all_orders() {
        let mut rng = Lcg(7);
        for order in ORDERS {
            let axes = euler_axes(order).unwrap();
            let compose = |e: Vec3| {
                let [a, b, c] = [0, 1, 2].map(|n| axis_angle(unit(axes[n]), e[n].to_radians()));
                qmul(qmul(a, b), c)
            };
            for n in 0..400 {
                let b = GIMBAL_BETAS
                    .get(n % 5)
                    .copied()
                    .unwrap_or(rng.uniform(-89.0, 89.0));
                let e = [rng.uniform(-180.0, 180.0), b, rng.uniform(-180.0, 180.0)];
                let q = compose(e);
                let got = quat_to_euler(q, axes).map(f64::to_degrees);
                assert!(same_rotation(compose(got), q), "{order:?} {e:?} -> {got:?}");
                assert!(
                    b.abs() > 89.0 || close(got, e, 1e-9),
                    "{order:?} {e:?} -> {got:?}"
                );
                let alt =
                    continuous_euler(q, axes, Some([got[0] + 170.0, 180.0 - b, got[2] - 190.0]));
                assert!(same_rotation(compose(alt), q) && (alt[1] + got[1] - 180.0).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn from_positions_round_trips() {
        // Children moving independently: only the position channels can reproduce them.
        let parents = [None, Some(0), Some(1), Some(1), Some(0), Some(4), Some(5)];
        let names: Vec<String> = (0..parents.len()).map(|j| format!("j{j}")).collect();
        let mut rng = Lcg(42);
        let offsets: Vec<Vec3> = parents.iter().map(|_| rng.vec3(10.0)).collect();
        let positions: Vec<Vec3> = (0..30 * parents.len()).map(|_| rng.vec3(50.0)).collect();
        for order in ORDERS {
            let bvh = Bvh::from_positions(&names, &parents, &offsets, &[], &positions, 0.1, order);
            assert_eq!(bvh.joints[0].channels[3..], order);
            assert_eq!(bvh.joints[6].end_site, Some([0.0; 3]));
            let back = Bvh::parse(&bvh.to_text()).unwrap();
            assert_eq!(back, bvh);
            let got = all_positions(&back);
            assert!(got.iter().zip(&positions).all(|(a, b)| close(*a, *b, 1e-9)));
        }

        // Rigid motion: the fit recovers every local rotation, and translations equal offsets.
        let mut text = format!("{RIGID_HIERARCHY}Frames: 40\nFrame Time: 0.1\n");
        for _ in 0..40 * 9 {
            text += &format!(" {}", rng.uniform(-180.0, 180.0));
        }
        let source = Bvh::parse(&text).unwrap();
        let fitted = export(&source, &all_positions(&source), [Z, Y, X]);
        let (mut qa, mut qb) = ([[0.0; 4]; 5], [[0.0; 4]; 5]);
        for f in 0..source.frames {
            source.local_rotations(f, &mut qa);
            fitted.local_rotations(f, &mut qb);
            assert!(qa.iter().zip(qb).all(|(a, b)| same_rotation(*a, b)));
            let row = fitted.row(f).unwrap();
            for (j, joint) in fitted.joints.iter().enumerate().skip(1) {
                let t = [row[6 * j], row[6 * j + 1], row[6 * j + 2]];
                assert!(close(t, joint.offset, 1e-12));
            }
        }
    }

    #[test]
    fn malformed_inputs_are_errors() {
        use BvhErrorKind as K;
        let one_joint = |frames: &str, time: &str, values: &str| {
            format!(
                "HIERARCHY\nROOT A\n{{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}}\n\
                 MOTION\nFrames: {frames}\nFrame Time: {time}\n{values}"
            )
        };
        let kind = |text: &str| Bvh::parse(text).unwrap_err().kind;
        assert!(Bvh::parse(&one_joint("2", "0.1", "1 2 3\n4 5 6")).is_ok());
        assert_eq!(kind(" \r\n\t"), K::Empty);
        let short = kind(&one_joint("2", "0.1", "1 2 3\n4 5"));
        assert!(matches!(
            short,
            K::WrongValueCount {
                frame: 1,
                expected: 3,
                actual: 2
            }
        ));
        let none = kind(&one_joint("1000000", "0.1", ""));
        assert!(matches!(
            none,
            K::WrongValueCount {
                frame: 0,
                expected: 3,
                actual: 0
            }
        ));
        let extra = kind(&one_joint("1", "0.1", "1 2 3 4"));
        assert!(matches!(
            extra,
            K::ExtraValues {
                frames: 1,
                extra: 1
            }
        ));
        for (frames, time, values) in [
            ("-1", "0.1", ""),
            ("1.5", "0.1", ""),
            ("99999999999999999999", "0.1", ""),
            ("16777217", "0.1", ""),
            ("1", "0", "1 2 3"),
            ("1", "-0.1", "1 2 3"),
            ("1", "fast", "1 2 3"),
            ("1", "0.1", "1 2 x"),
        ] {
            let err = kind(&one_joint(frames, time, values));
            assert!(matches!(err, K::BadNumber { .. }), "{err:?}");
        }
        for bad in ["nan", "inf", "-infinity", "1e999"] {
            let err = kind(&one_joint("1", "0.1", &format!("1 {bad} 3")));
            assert_eq!(err, K::NonFinite { found: bad.into() });
        }
        for body in [
            "",
            "{ OFFSET 0 0 0 }",
            "A { OFFSET 0 0 }",
            "A { OFFSET 0 0 0 CHANNELS 7 }",
            "A { OFFSET 0 0 0 CHANNELS 1 Wrotation }",
            "A { OFFSET 0 0 0 End Site OFFSET 0 0 0 }",
            "A { OFFSET 0 0 0 { { } }",
            "A { OFFSET 0 0 0 } }",
        ] {
            let text = format!("HIERARCHY ROOT {body} MOTION Frames: 0 Frame Time: 1");
            assert!(Bvh::parse(&text).is_err(), "{body}");
        }
        let missing_brace = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nJOINT B\nOFFSET 1 0 0\n}\n}\n";
        let err = Bvh::parse(missing_brace).unwrap_err().to_string();
        assert_eq!(err, "line 6: expected `{` after joint name, found `OFFSET`");
    }

    #[test]
    fn only_rotations_make_a_rest_frame() {
        let frames = |channels: &str, values: &str| {
            let text = format!(
                "HIERARCHY ROOT A {{ OFFSET 0 0 0 CHANNELS {channels} }} MOTION Frames: 3 \
                 Frame Time: 0.1 {values}"
            );
            let mut bvh = Bvh::parse(&text).unwrap();
            if bvh.first_frame_is_rest() {
                bvh.drop_first_frame();
            }
            bvh.frames
        };
        assert_eq!(frames("0", ""), 3);
        assert_eq!(frames("1 Xposition", "0 1 2"), 3);
        assert_eq!(frames("1 Xrotation", "0 1 2"), 2);
        assert_eq!(frames("2 Xposition Xrotation", "5 0 5 1 5 2"), 2);
    }

    #[test]
    fn hostile_inputs_never_panic() {
        let deep = "HIERARCHY\nROOT A\n{ OFFSET 0 0 0\n".to_string()
            + &"JOINT B { OFFSET 0 1 0\n".repeat(1000);
        let too_many = BvhErrorKind::TooManyJoints {
            max: MAX_DECLARED_JOINTS,
        };
        assert_eq!(Bvh::parse(&deep).unwrap_err().kind, too_many);
        assert!(Bvh::parse(&format!("HIERARCHY\nROOT A\n{}", "{\n".repeat(100_000))).is_err());
        let last_token = SMALL_BVH.trim_end().len() - 1;
        for (cut, _) in SMALL_BVH.char_indices() {
            assert!(cut >= last_token || Bvh::parse(&SMALL_BVH[..cut]).is_err());
        }
        let tokens: Vec<&str> = SMALL_BVH.split_whitespace().collect();
        for i in 0..tokens.len() {
            for junk in ["x", "{", "}", "-1", "1e999", "JOINT", "End", "ROOT"] {
                let mut t = tokens.clone();
                t[i] = junk;
                let _ = Bvh::parse(&t.join(" "));
            }
        }
    }

    /// Every real clip, or `None` (with a message) where `../shared/data` is absent.
    fn real_clips() -> Option<Vec<(Bvh, String)>> {
        let mut clips = Vec::new();
        for set in ["cmu", "bandai"] {
            let dir = std::path::Path::new(DATA_DIR).join(set);
            let Ok(entries) = std::fs::read_dir(&dir) else {
                eprintln!("skipping real-data BVH test: {} not found", dir.display());
                return None;
            };
            let mut paths: Vec<_> = entries.map(|e| e.unwrap().path()).collect();
            paths.retain(|p| p.extension().is_some_and(|x| x == "bvh"));
            paths.sort();
            for path in paths {
                let name = format!("{set}/{}", path.file_name().unwrap().to_string_lossy());
                let bvh = Bvh::parse(&std::fs::read_to_string(&path).unwrap());
                clips.push((bvh.unwrap_or_else(|e| panic!("{name}: {e}")), name));
            }
        }
        Some(clips)
    }

    #[test]
    fn real_clips_are_plausible_and_round_trip() {
        let Some(clips) = real_clips() else { return };
        assert_eq!(clips.len(), 24);
        for (bvh, name) in &clips {
            let cmu = name.starts_with("cmu");
            let shape = if cmu { (31, 96) } else { (22, 132) };
            assert_eq!((bvh.joints.len(), bvh.channel_count()), shape, "{name}");
            let (n, p) = (bvh.joints.len(), all_positions(bvh));
            let index = |name: &str| bvh.joints.iter().position(|j| j.name == name).unwrap();
            let y = |f: usize, j: usize| p[f * n + j][1];
            // Bones below the root's children (Bandai's Hips carries the translation).
            let (mut drift, mut offset_dev, mut round_trip) = (0.0_f64, 0.0_f64, 0.0_f64);
            let parents: Vec<usize> = bvh.joints.iter().map(|j| j.parent.unwrap_or(0)).collect();
            let bones: Vec<usize> = (0..n).filter(|&j| parents[j] > 0).collect();
            let bone = |f: usize, j: usize| norm(sub(p[f * n + j], p[f * n + parents[j]]));
            for f in 0..bvh.frames {
                for &j in &bones {
                    drift = drift.max((bone(f, j) - bone(0, j)).abs() / bone(0, j).max(1e-9));
                }
            }
            let toes = [["LeftToe", "Toes_L"], ["RightToe", "Toes_R"]]
                .map(|t| index(t[usize::from(!cmu)]));
            let lowest_toe = (0..bvh.frames * 2)
                .map(|i| y(i / 2, toes[i % 2]))
                .fold(f64::MAX, f64::min);
            let (head, hips) = (index("Head"), index("Hips"));
            let head_above_hips = (0..bvh.frames).all(|f| y(f, head) > y(f, hips));

            let back = export(bvh, &p, [Z, X, Y]);
            for (a, b) in all_positions(&back).iter().zip(&p) {
                round_trip = round_trip.max(norm(sub(*a, *b)) / norm(*b).max(1.0));
            }
            for f in 0..back.frames {
                let row = back.row(f).unwrap();
                for &j in &bones {
                    let t = [row[6 * j], row[6 * j + 1], row[6 * j + 2]];
                    offset_dev = offset_dev.max(norm(sub(t, back.joints[j].offset)));
                }
            }
            eprintln!(
                "{name}: {} frames, bone drift {drift:.1e}, lowest toe y {lowest_toe:.3}, round trip \
                 {round_trip:.1e}, |translation - offset| {offset_dev:.1e}, rest frame 0 {}",
                bvh.frames,
                bvh.first_frame_is_rest()
            );
            let floor = if cmu { 1.0 } else { 6.0 }; // CMU units are about 5.6 cm; Bandai cm
            assert!(drift < 1e-6 && head_above_hips, "{name}");
            assert!((0.0..floor).contains(&lowest_toe), "{name}");
            assert!(round_trip < 1e-9 && offset_dev < 1e-4, "{name}");
        }
    }
}
