//! Banded dynamic time warping between two pose sequences.
//!
//! A sequence is `3 · joints` channels of `frames` floats each, channel-major: the x of joint
//! 0 in every frame, then the x of joint 1, ..., then all y, then all z. A band row's costs are
//! then computed one joint at a time across the row's contiguous frames, a loop the compiler
//! vectorizes. Where there are vectors the recurrence too runs over whole rows, in passes that
//! end in the serial recurrence's values bit for bit; on the Cortex-M4F it goes cell after cell.
//! The cost of cell `(i, j)` is the weighted mean over joints of the Euclidean distance
//! between joint positions in frame `i` of `a` and frame `j` of `b` (callers put the root at
//! the origin). The accumulated distance is classic DTW: `D(i, j) = cost(i, j) +
//! min(D(i-1, j-1), D(i-1, j), D(i, j-1))`, ties going diagonal, then `a` advancing, then `b`.
//!
//! The [`Band`] is laid over a pair of sequences as a [`Window`]: `radius` columns around a
//! guide line through anchor cells: with no anchors the guide is the diagonal from `(0, 0)` to `(n-1, m-1)`;
//! with matched swing events as anchors each phase is banded around its own diagonal. Only
//! banded cells are computed: two rows of accumulated cost and 2 bits per banded cell for the
//! path, all in caller-provided scratch (see [`scratch_len`]). When the band covers the whole
//! matrix the result equals full DTW exactly.
//!
//! ```
//! use posecoach_core::band::Band;
//! use posecoach_core::dtw::{align, scratch_len, Sequence, Window};
//!
//! // One joint moving along x (channels x, y, z); `b` lingers on its second frame.
//! let a = [0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
//! let b = [0.0, 1.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
//! let (a, b) = (Sequence::new(&a, 1).unwrap(), Sequence::new(&b, 1).unwrap());
//! let window = Window::new(Band::global(1), &[]).unwrap();
//! let len = scratch_len(a.frames(), b.frames(), &window).unwrap();
//! let (mut cost, mut steps) = (vec![0.0; len.cost], vec![0u8; len.path_bytes]);
//! let mut path = [(0u16, 0u16); 7];
//! let result = align(&a, &b, &[], &window, &mut cost, &mut steps, &mut path).unwrap();
//! assert_eq!(result.distance, 0.0);
//! assert_eq!(&path[..result.path_len], &[(0, 0), (1, 1), (1, 2), (2, 3)]);
//! ```

use crate::band::Band;
use crate::config::MAX_JOINTS;
use crate::frames::{from_mm, Frames, Mm, Stored};
use crate::math::{rooted_distances, sqrt};
use crate::Vec3;

/// Largest number of anchors a band may have.
pub const MAX_ANCHORS: usize = 16;

/// Why an alignment could not be computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DtwError {
    /// A sequence is empty, longer than `u16::MAX` frames, or not a whole number of frames.
    SequenceShape,
    /// One sequence is channel-major, the other frame-major ([`Sequence::rooted`]).
    Layouts,
    /// The two sequences have different joint counts.
    JointMismatch {
        /// Joints in `a`.
        a: usize,
        /// Joints in `b`.
        b: usize,
    },
    /// `weights` is neither empty nor one per joint, or has a negative, non-finite or all-zero
    /// weight.
    Weights,
    /// Anchors must lie inside the matrix and increase strictly in both coordinates; at most
    /// [`MAX_ANCHORS`].
    Anchors,
    /// A scratch buffer or the path output is too short.
    Scratch {
        /// The buffer that is short: 0 cost, 1 path bits, 2 path output.
        which: u8,
        /// Length needed.
        needed: usize,
    },
}

impl core::fmt::Display for DtwError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DtwError::SequenceShape => {
                f.write_str("a sequence is empty, too long or not a whole number of frames")
            }
            DtwError::Layouts => {
                f.write_str("one sequence is channel-major and the other frame-major")
            }
            DtwError::JointMismatch { a, b } => {
                write!(f, "sequences have {a} and {b} joints; they must match")
            }
            DtwError::Weights => f.write_str(
                "weights must be empty or one finite, non-negative weight per joint, not all zero",
            ),
            DtwError::Anchors => {
                f.write_str("anchors must increase strictly and lie inside both sequences")
            }
            DtwError::Scratch { which, needed } => {
                let name =
                    ["cost scratch", "path scratch", "path output"][(*which as usize).min(2)];
                write!(f, "{name} too short: {needed} needed")
            }
        }
    }
}

impl core::error::Error for DtwError {}

/// A pose sequence: `3 · joints` channels (x of every joint, then y, then z) of `frames`
/// floats each, or frames of joint positions measured from their root ([`Sequence::rooted`]).
#[derive(Clone, Copy, Debug)]
pub struct Sequence<'a> {
    layout: Layout<'a>,
    joints: usize,
}

#[derive(Clone, Copy, Debug)]
enum Layout<'a> {
    /// Channel-major floats, as the caller measured them.
    Channels(&'a [f32]),
    /// Frame-major positions, each measured from its frame's first joint when costed.
    Rooted(Frames<'a>),
}

impl<'a> Sequence<'a> {
    /// Wraps channel-major `data` of `joints` joints.
    ///
    /// # Errors
    /// [`DtwError::SequenceShape`] for no joints or more than [`MAX_JOINTS`], no frames, a
    /// partial frame or more than `u16::MAX` frames.
    pub fn new(data: &'a [f32], joints: usize) -> Result<Self, DtwError> {
        check_shape(data.len(), 3 * joints, joints)?;
        Ok(Sequence {
            layout: Layout::Channels(data),
            joints,
        })
    }

    /// Wraps `frames` (a swing as it is stored), each position measured from its frame's
    /// first joint (the root) as it is costed. The costs are those of the channel-major
    /// sequence of the root-relative positions, to the bit, without the copy; cells are costed
    /// one at a time (no vectors across columns), which suits a microcontroller and is slower
    /// on the host.
    ///
    /// # Errors
    /// As [`Sequence::new`].
    pub fn rooted(frames: Frames<'a>) -> Result<Self, DtwError> {
        let joints = frames.joints();
        if !frames.is_whole() {
            return Err(DtwError::SequenceShape);
        }
        check_shape(frames.len() * joints, joints, joints)?;
        Ok(Sequence {
            layout: Layout::Rooted(frames),
            joints,
        })
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        match self.layout {
            Layout::Channels(data) => data.len() / (3 * self.joints),
            Layout::Rooted(frames) => frames.len(),
        }
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.joints
    }

    /// Each joint's x, y and z channels (empty for a rooted sequence).
    fn joint_channels(&self) -> impl Iterator<Item = [&'a [f32]; 3]> {
        let data = match self.layout {
            Layout::Channels(data) => data,
            Layout::Rooted(_) => &[],
        };
        let c = data.chunks_exact(self.frames().max(1));
        let (y, z) = (c.clone().skip(self.joints), c.clone().skip(2 * self.joints));
        c.zip(y).zip(z).map(|((x, y), z)| [x, y, z])
    }

    /// Value of channel `c` in frame `i`.
    #[cfg(test)]
    fn at(&self, c: usize, i: usize) -> f32 {
        match self.layout {
            Layout::Channels(data) => data[c * self.frames() + i],
            Layout::Rooted(frames) => {
                let (axis, k) = (c / self.joints, c % self.joints);
                (frames.at(i, k) - frames.at(i, 0))[axis]
            }
        }
    }
}

/// Checks a sequence of `len` values, `per_frame` to a frame, of `joints` joints.
fn check_shape(len: usize, per_frame: usize, joints: usize) -> Result<(), DtwError> {
    if joints == 0
        || joints > MAX_JOINTS
        || len == 0
        || !len.is_multiple_of(per_frame)
        || len / per_frame > u16::MAX as usize
    {
        return Err(DtwError::SequenceShape);
    }
    Ok(())
}

/// A [`Band`] laid over one pair of sequences: a Sakoe-Chiba window around the guide through
/// its anchor cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    radius: u16,
    anchors: [(u16, u16); MAX_ANCHORS],
    anchor_count: u8,
}

impl Window {
    /// `band` around the piecewise-linear guide through `anchors` (matched frames `(i in a, j
    /// in b)`, e.g. swing events), each segment its own diagonal; a global band ignores them.
    ///
    /// # Errors
    /// [`DtwError::Anchors`] for an anchored band with more than [`MAX_ANCHORS`] anchors or
    /// anchors that do not increase strictly in both coordinates. [`align`] also requires them
    /// strictly inside the matrix: `0 < i < n-1` and `0 < j < m-1`.
    pub fn new(band: Band, anchors: &[(u16, u16)]) -> Result<Window, DtwError> {
        let mut window = Window {
            radius: band.radius,
            anchors: [(0, 0); MAX_ANCHORS],
            anchor_count: 0,
        };
        if !band.anchored {
            return Ok(window);
        }
        if anchors.len() > MAX_ANCHORS
            || anchors
                .windows(2)
                .any(|w| w[1].0 <= w[0].0 || w[1].1 <= w[0].1)
        {
            return Err(DtwError::Anchors);
        }
        window.anchors[..anchors.len()].copy_from_slice(anchors);
        window.anchor_count = anchors.len() as u8;
        Ok(window)
    }

    /// The anchors the window's guide runs through.
    pub fn anchors(&self) -> &[(u16, u16)] {
        &self.anchors[..self.anchor_count as usize]
    }

    /// The guide through `(0, 0)`, the anchors and `(n-1, m-1)`; `None` unless every anchor
    /// lies strictly inside the matrix (`0 < i < n-1`, `0 < j < m-1`).
    fn guide(&self, n: usize, m: usize) -> Option<Guide> {
        let mut points = [(0.0f32, 0.0f32); MAX_ANCHORS + 2];
        for (point, &(i, j)) in points[1..].iter_mut().zip(self.anchors()) {
            let (i, j) = (i as usize, j as usize);
            if i == 0 || j == 0 || i + 1 >= n || j + 1 >= m {
                return None;
            }
            *point = (i as f32, j as f32);
        }
        let count = self.anchors().len() + 2;
        points[count - 1] = ((n - 1) as f32, (m - 1) as f32);
        Some(Guide {
            points,
            count,
            n,
            m,
            radius: self.radius as usize,
        })
    }
}

struct Guide {
    points: [(f32, f32); MAX_ANCHORS + 2],
    count: usize,
    n: usize,
    m: usize,
    radius: usize,
}

impl Guide {
    /// Column of the guide line at row `i` (clamped to the last row).
    fn center(&self, i: usize) -> f32 {
        let x = i.min(self.n - 1) as f32;
        let points = &self.points[..self.count];
        for w in points.windows(2) {
            let ((i0, j0), (i1, j1)) = (w[0], w[1]);
            if x <= i1 {
                return if i1 > i0 {
                    j0 + (x - i0) * (j1 - j0) / (i1 - i0)
                } else {
                    j1
                };
            }
        }
        (self.m - 1) as f32
    }

    /// Banded columns `lo..=hi` of row `i`: `radius` columns either side of the guide, and up
    /// to the guide's next column, so both bounds never decrease and each row starts at most
    /// one column past the previous row's end: a path always exists. The first row starts at
    /// column 0 and the last row ends at column `m-1`.
    fn row(&self, i: usize) -> (usize, usize) {
        self.bounds(i, self.center(i), self.center(i + 1))
    }

    /// [`Guide::row`] of every row in turn, each guide column computed once.
    fn rows(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let mut c = self.center(0);
        (0..self.n).map(move |i| {
            let next = self.center(i + 1);
            let row = self.bounds(i, c, next);
            c = next;
            row
        })
    }

    /// [`Guide::row`] of row `i`, where the guide is at column `c` and at `next` on the next
    /// row.
    fn bounds(&self, i: usize, c: f32, next: f32) -> (usize, usize) {
        let last = self.m - 1;
        let lo = if i == 0 {
            0
        } else {
            (c as usize).saturating_sub(self.radius)
        };
        let hi = if i + 1 >= self.n {
            last
        } else {
            (ceil(c.max(next - 1.0)) + self.radius).min(last)
        };
        (lo.min(last), hi)
    }
}

/// The ceiling of `x >= 0` (the guide's columns are never negative; truncation is the floor).
fn ceil(x: f32) -> usize {
    let floor = x as usize;
    floor + usize::from((floor as f32) < x)
}

/// Scratch sizes for [`align`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScratchLen {
    /// Floats of cost scratch: two padded rows of accumulated cost, as wide as the band's
    /// widest step from one row to the next (two more where SIMD vectors compute whole rows),
    /// and one row of cell costs, rounded up to whole SIMD vectors of columns.
    pub cost: usize,
    /// Bytes of path scratch (2 bits per banded cell).
    pub path_bytes: usize,
    /// Banded cells.
    pub cells: usize,
}

/// Scratch needed to align `n` frames with `m` frames in `window`.
///
/// # Errors
/// [`DtwError::SequenceShape`] for an empty sequence, [`DtwError::Anchors`] for anchors
/// outside the matrix.
pub fn scratch_len(n: usize, m: usize, window: &Window) -> Result<ScratchLen, DtwError> {
    Ok(layout(n, m, window)?.0)
}

/// Floats of cost scratch that any window over `m` columns fits in: a bound on
/// [`ScratchLen::cost`] for callers that size their scratch once.
pub const fn cost_len_bound(m: usize) -> usize {
    (3 + PASS_ROWS) * (m + 2)
}

/// [`scratch_len`] and the width of an accumulated-cost row in the cost scratch.
fn layout(n: usize, m: usize, window: &Window) -> Result<(ScratchLen, usize), DtwError> {
    if n == 0 || m == 0 {
        return Err(DtwError::SequenceShape);
    }
    let guide = window.guide(n, m).ok_or(DtwError::Anchors)?;
    // Accumulated-cost rows must reach from one column before the previous row's start to
    // one column after this row's end.
    let (mut cells, mut span, mut prev_lo) = (0, 0, 0);
    for (lo, hi) in guide.rows() {
        cells += hi - lo + 1;
        span = span.max(hi + 1 - prev_lo.min(lo));
        prev_lo = lo;
    }
    let width = span + 2;
    let len = ScratchLen {
        cost: (2 + PASS_ROWS) * width + span.next_multiple_of(VECTOR).min(m),
        path_bytes: cells.div_ceil(4),
        cells,
    };
    Ok((len, width))
}

/// The result of [`align`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alignment {
    /// Sum of cell costs along the path (the unit of the coordinates).
    pub distance: f32,
    /// `distance` divided by the path length.
    pub normalized: f32,
    /// Number of path cells written to the path output.
    pub path_len: usize,
}

/// Cells whose path steps are packed together: a group of `c` cells takes `2c` bits, the
/// first `c` saying "from the left" and the next `c` "from above", last cell lowest.
const GROUP: usize = 16;

const DIAGONAL: u8 = 0;
const ADVANCE_A: u8 = 1;
const ADVANCE_B: u8 = 2;

/// Aligns `a` to `b` within `window` and writes the warping path, `(frame of a, frame of b)`
/// from `(0, 0)` to the last frames, into `path` (which needs `a.frames() + b.frames() - 1`
/// entries at most).
///
/// `weights` is empty (every joint counts the same) or one weight per joint.
///
/// # Errors
/// [`DtwError`] for mismatched sequences, bad weights or anchors, or short buffers.
pub fn align(
    a: &Sequence<'_>,
    b: &Sequence<'_>,
    weights: &[f32],
    window: &Window,
    cost: &mut [f32],
    steps: &mut [u8],
    path: &mut [(u16, u16)],
) -> Result<Alignment, DtwError> {
    let joints = a.joints();
    if matches!(a.layout, Layout::Rooted(_)) != matches!(b.layout, Layout::Rooted(_)) {
        return Err(DtwError::Layouts);
    }
    if b.joints() != joints {
        return Err(DtwError::JointMismatch {
            a: joints,
            b: b.joints(),
        });
    }
    let weight_sum: f32 = weights.iter().sum();
    if !(weights.is_empty()
        || (weights.len() == joints
            && weights.iter().all(|w| w.is_finite() && *w >= 0.0)
            && weight_sum > 0.0))
    {
        return Err(DtwError::Weights);
    }
    let (n, m) = (a.frames(), b.frames());
    let guide = window.guide(n, m).ok_or(DtwError::Anchors)?;
    let (len, width) = layout(n, m, window)?;
    let short = |which: u8, needed: usize| DtwError::Scratch { which, needed };
    if cost.len() < len.cost {
        return Err(short(0, len.cost));
    }
    if steps.len() < len.path_bytes {
        return Err(short(1, len.path_bytes));
    }
    if path.len() < n + m - 1 {
        return Err(short(2, n + m - 1));
    }
    let (weights, scale) = match weights {
        [] => (&ONES[..joints], 1.0 / joints as f32),
        w => (w, 1.0 / weight_sum),
    };
    let cell = CellCost {
        weights,
        unit: weights.iter().all(|&w| w == 1.0),
        scale,
    };

    // Accumulated-cost rows are stored from one column left of the row's first column, with
    // infinity there and after the row's end, so neighbours need no range checks.
    let (rows, rest) = cost[..len.cost].split_at_mut(2 * width);
    let (passes, here) = rest.split_at_mut(PASS_ROWS * width);
    let (mut prev, mut curr) = rows.split_at_mut(width);
    prev.fill(f32::INFINITY);
    // A virtual diagonal predecessor of cell (0, 0) with distance 0 starts the path.
    prev[0] = 0.0;
    let mut prev_lo = 0usize;
    let mut bits = StepWriter {
        steps: &mut *steps,
        offset: 0,
        acc: 0,
        count: 0,
    };
    for (i, (lo, hi)) in guide.rows().enumerate() {
        let w = hi - lo + 1;
        // Costs are computed for whole vectors of columns, shifted left at the matrix's end.
        let padded = w.next_multiple_of(VECTOR).min(m);
        let first = lo.min(m - padded);
        row_costs(&cell, a, i, b, first, &mut here[..padded]);
        let cells = &here[lo - first..][..w];
        // prev[k] holds column prev_lo + k - 1, so the cells above this row's columns
        // lo - 1 ..= hi start at prev[lo - prev_lo].
        let above = &prev[lo - prev_lo..][..w + 1];
        curr[0] = f32::INFINITY;
        curr[w + 1..].fill(f32::INFINITY);
        let row = &mut curr[..=w];
        if VECTOR > 1 && w >= SETTLED_FROM {
            let (spare, best) = passes.split_at_mut(width);
            settle(
                row,
                &mut spare[..=w],
                &mut best[..w],
                cells,
                above,
                &mut bits,
            );
        } else {
            recur(row, cells, above, &mut bits);
        }
        core::mem::swap(&mut prev, &mut curr);
        prev_lo = lo;
    }
    bits.flush();
    let distance = prev[m - prev_lo];

    // Walk back from (n-1, m-1), recomputing each row's range and its offset in `steps`.
    let (mut i, mut j) = (n - 1, m - 1);
    let (mut lo, mut hi) = guide.row(i);
    let mut center = guide.center(i);
    let mut row_start = len.cells - (m - lo);
    let mut written = 0;
    let bit = |at: usize| steps[at / 8] >> (at % 8) & 1 == 1;
    loop {
        path[written] = (i as u16, j as u16);
        written += 1;
        if i == 0 && j == 0 {
            break;
        }
        let (group, k) = ((j - lo) / GROUP, (j - lo) % GROUP);
        let count = (hi + 1 - lo - group * GROUP).min(GROUP);
        let at = 2 * (row_start + group * GROUP) + count - 1 - k;
        let step = if bit(at) {
            ADVANCE_B
        } else if bit(at + count) {
            ADVANCE_A
        } else {
            DIAGONAL
        };
        if step != ADVANCE_B {
            i -= 1;
            let next = center;
            center = guide.center(i);
            (lo, hi) = guide.bounds(i, center, next);
            row_start -= hi - lo + 1;
        }
        if step != ADVANCE_A {
            j -= 1;
        }
    }
    path[..written].reverse();
    Ok(Alignment {
        distance,
        normalized: distance / written as f32,
        path_len: written,
    })
}

/// The accumulated costs of a row, `row(k + 1) = cells(k) + min(best(k), row(k))` with
/// `best(k)` the better of the diagonal `above(k)` and the upper `above(k + 1)`, and `row(0)`
/// the infinity left of the row, cell after cell; the path bits go to `bits`. Where there are
/// no vectors to compute whole rows with ([`settle`]).
fn recur(row: &mut [f32], cells: &[f32], above: &[f32], bits: &mut StepWriter<'_>) {
    let row = &mut row[1..];
    // The better of the diagonal and upper neighbours, for all cells at once.
    for ((t, &diagonal), &up) in row.iter_mut().zip(above).zip(&above[1..]) {
        *t = if up < diagonal { up } else { diagonal };
    }
    // Then the left neighbour, cell after cell, a group of cells to a word of path bits.
    let mut left = f32::INFINITY;
    let (rows, row_rest) = row.as_chunks_mut::<GROUP>();
    let (cell_groups, cell_rest) = cells.as_chunks::<GROUP>();
    let (above_groups, above_rest) = above[..cells.len()].as_chunks::<GROUP>();
    for ((row, cells), above) in rows.iter_mut().zip(cell_groups).zip(above_groups) {
        bits.push(from_left(row, cells, above, &mut left), 2 * GROUP as u32);
    }
    let rest = from_left(row_rest, cell_rest, above_rest, &mut left);
    bits.push(rest, 2 * row_rest.len() as u32);
}

/// The serial part of the recurrence over a group of cells: `row` holds the better of each
/// cell's diagonal and upper neighbours and gets the accumulated costs, `left` is the
/// accumulated cost left of the group and then of its last cell. Returns the group's path bits.
#[inline(always)]
fn from_left(row: &mut [f32], cells: &[f32], above: &[f32], left: &mut f32) -> u32 {
    let (mut ups, mut lefts) = (0u32, 0u32);
    for ((d, &c), &diagonal) in row.iter_mut().zip(cells).zip(above) {
        let t = *d;
        let from_left = *left < t;
        ups = ups << 1 | u32::from(t < diagonal);
        lefts = lefts << 1 | u32::from(from_left);
        *left = c + if from_left { *left } else { t };
        *d = *left;
    }
    ups << row.len() | lefts
}

/// The fewest cells of a row that [`settle`] computes; narrower rows go cell after cell
/// ([`recur`]), as the passes' work per row outweighs the wait they save. Measured on an Intel
/// Xeon with AVX-512 (D = 51): rows of 11 cells (radius 5) 10 % slower in passes, of 21 about
/// the same, of 29 a little faster, of 41 (radius 20) 10 % faster.
const SETTLED_FROM: usize = 24;

/// Rows of cost scratch that [`settle`] takes besides the two accumulated-cost rows: none where
/// the serial recurrence runs.
const PASS_ROWS: usize = if VECTOR > 1 { 2 } else { 0 };

/// The accumulated costs of a row with vectors: `row(k + 1) = cells(k) + min(best(k), row(k))`
/// with `best(k)` the better of the diagonal `above(k)` and the upper `above(k + 1)`, and
/// `row(0)` the infinity left of the row.
///
/// The serial recurrence is a chain of a comparison and an addition a cell, which a CPU waits
/// on cell after cell. Here passes over the whole row replace it, each computing every cell
/// from its left neighbour's value after the pass before ([`step`]). The first takes no cell
/// from the left, which settles the row's first cell; a cell depends only on the one before it,
/// so each further pass settles one more at the least, and by the `w`-th one pass changes
/// nothing. The values are then the serial recurrence's, bit for bit: the same comparisons and
/// additions of the same values. A row takes as many passes as its longest run of steps from
/// the left, plus two (2.1 a row on average for random walks at `D = 51`). `spare` alternates
/// with `row` (both `w + 1` values); `best` receives the better neighbours above.
#[multiversion::multiversion(targets("x86_64+avx512f", "x86_64+avx2+fma"))]
fn settle(
    row: &mut [f32],
    spare: &mut [f32],
    best: &mut [f32],
    cells: &[f32],
    above: &[f32],
    bits: &mut StepWriter<'_>,
) {
    let firsts = row[1..].iter_mut().zip(best.iter_mut());
    for (((d, t), &c), (&diagonal, &up)) in firsts.zip(cells).zip(above.iter().zip(&above[1..])) {
        *t = if up < diagonal { up } else { diagonal };
        *d = c + *t;
    }
    spare[0] = f32::INFINITY;
    let (mut from, mut to) = (row, spare);
    for _ in 0..best.len() {
        if !step(from, to, best, cells) {
            break;
        }
        core::mem::swap(&mut from, &mut to);
    }
    let w = best.len();
    let (lefts, left_rest) = from[..w].as_chunks::<GROUP>();
    let (bests, best_rest) = best.as_chunks::<GROUP>();
    let (diagonals, diagonal_rest) = above[..w].as_chunks::<GROUP>();
    for ((lefts, best), diagonals) in lefts.iter().zip(bests).zip(diagonals) {
        bits.push(path_bits(lefts, best, diagonals), 2 * GROUP as u32);
    }
    let rest = path_bits(left_rest, best_rest, diagonal_rest);
    bits.push(rest, 2 * best_rest.len() as u32);
}

/// One pass of [`settle`] from `from` into `to`. Returns whether any value differs from
/// `from`'s, bit for bit.
#[inline(always)]
fn step(from: &[f32], to: &mut [f32], best: &[f32], cells: &[f32]) -> bool {
    let mut changed = 0u32;
    let lefts = from.iter().zip(&from[1..]);
    for ((d, (&left, &old)), (&t, &c)) in to[1..].iter_mut().zip(lefts).zip(best.iter().zip(cells))
    {
        let new = c + if left < t { left } else { t };
        changed |= new.to_bits() ^ old.to_bits();
        *d = new;
    }
    changed != 0
}

/// The path bits of `best.len() <= GROUP` settled cells, as [`from_left`] returns them:
/// `lefts` holds the accumulated cost left of each cell, `best` its better neighbour above,
/// `diagonals` its diagonal neighbour. Each cell's comparison sets bit `k` (which a vector's
/// comparison mask gives at once), then the order is reversed to put the last cell lowest.
#[inline(always)]
fn path_bits(lefts: &[f32], best: &[f32], diagonals: &[f32]) -> u32 {
    let (mut ups, mut from_left) = (0u32, 0u32);
    for (k, ((&left, &t), &diagonal)) in lefts.iter().zip(best).zip(diagonals).enumerate() {
        ups |= u32::from(t < diagonal) << k;
        from_left |= u32::from(left < t) << k;
    }
    let len = best.len() as u32;
    let first_highest = |bits: u32| bits.reverse_bits().checked_shr(32 - len).unwrap_or(0);
    first_highest(ups) << len | first_highest(from_left)
}

/// Weights used when the caller gives none.
const ONES: [f32; MAX_JOINTS] = [1.0; MAX_JOINTS];

/// Floats in the widest SIMD vector [`row_costs`] is compiled for on the target: costs are
/// computed for whole vectors of columns (AVX-512's 16 lanes take two of them).
const VECTOR: usize = if cfg!(target_arch = "x86_64") {
    8
} else if cfg!(any(target_feature = "sse", target_feature = "neon")) {
    4
} else {
    1
};

/// [`CellCost::row`], compiled for each x86-64 vector width and chosen when first called for
/// the CPU it runs on (with `std`; `multiversion` checks the CPU's features once and calls the
/// widest clone it has): AVX-512 (16 square roots an instruction), AVX2 with FMA (8), or the
/// baseline SSE2 (4). Elsewhere (aarch64's NEON, the Cortex-M4F) the one version the target
/// compiles. Every clone computes the same bits: the same operations in the same order. The
/// macro's call of the clone it checked the CPU for is the one `unsafe` this brings, in the
/// `multiversion` crate's expansion rather than this crate's code.
#[multiversion::multiversion(targets("x86_64+avx512f", "x86_64+avx2+fma"))]
fn row_costs<'w, 'a, 'b>(
    cell: &CellCost<'w>,
    a: &Sequence<'a>,
    i: usize,
    b: &Sequence<'b>,
    first: usize,
    out: &mut [f32],
) {
    cell.row(a, i, b, first, out);
}

/// The per-cell cost: weighted mean joint distance.
struct CellCost<'w> {
    /// One weight per joint.
    weights: &'w [f32],
    /// Whether every weight is 1 (the unweighted mean), so that none needs multiplying.
    unit: bool,
    /// One over the sum of the weights.
    scale: f32,
}

impl CellCost<'_> {
    /// Costs of frame `i` of `a` against frames `first..first + out.len()` of `b`, into `out`;
    /// inlined into each of [`row_costs`]'s clones.
    #[inline(always)]
    fn row(&self, a: &Sequence<'_>, i: usize, b: &Sequence<'_>, first: usize, out: &mut [f32]) {
        if self.unit {
            self.sum(a, i, b, first, out, |_, d| d);
        } else {
            self.sum(a, i, b, first, out, |w, d| w * d);
        }
    }

    /// [`CellCost::row`] with `weigh(w, d)` the part of a joint of weight `w` at distance `d`:
    /// blocks of `2 · VECTOR` columns, then of `VECTOR`, then single ones ([`CellCost::block`]).
    #[inline(always)]
    fn sum(
        &self,
        a: &Sequence<'_>,
        i: usize,
        b: &Sequence<'_>,
        first: usize,
        out: &mut [f32],
        weigh: impl Fn(f32, f32) -> f32,
    ) {
        if let (Layout::Rooted(fa), Layout::Rooted(fb)) = (a.layout, b.layout) {
            return self.sum_rooted(fa, i, fb, first, out, weigh);
        }
        let mut column = first;
        // Without vectors (the Cortex-M4F), column after column: no blocks to compile.
        let rest = if VECTOR > 1 {
            let (wide, rest) = out.as_chunks_mut::<{ 2 * VECTOR }>();
            for out in wide {
                self.block(a, i, b, column, out, &weigh);
                column += 2 * VECTOR;
            }
            let (narrow, rest) = rest.as_chunks_mut::<VECTOR>();
            for out in narrow {
                self.block(a, i, b, column, out, &weigh);
                column += VECTOR;
            }
            rest
        } else {
            out
        };
        for out in rest.as_chunks_mut::<1>().0 {
            self.block(a, i, b, column, out, &weigh);
            column += 1;
        }
    }

    /// The costs of frame `i` of `a` against frames `first..first + L` of `b`, into `out`:
    /// joint after joint, each joint's distances added to `L` sums kept in registers (a loop
    /// across the columns that the compiler vectorizes), then scaled.
    #[inline(always)]
    fn block<const L: usize>(
        &self,
        a: &Sequence<'_>,
        i: usize,
        b: &Sequence<'_>,
        first: usize,
        out: &mut [f32; L],
        weigh: &impl Fn(f32, f32) -> f32,
    ) {
        let mut sums = [0.0f32; L];
        let joints = a.joint_channels().zip(b.joint_channels());
        for (&w, ([ax, ay, az], [bx, by, bz])) in self.weights.iter().zip(joints) {
            let (x, y, z) = (ax[i], ay[i], az[i]);
            let (Some(bx), Some(by), Some(bz)) = (
                bx.get(first..first + L),
                by.get(first..first + L),
                bz.get(first..first + L),
            ) else {
                return;
            };
            for l in 0..L {
                let (dx, dy, dz) = (bx[l] - x, by[l] - y, bz[l] - z);
                sums[l] += weigh(w, sqrt(dx * dx + dy * dy + dz * dz));
            }
        }
        for (o, sum) in out.iter_mut().zip(sums) {
            *o = sum * self.scale;
        }
    }
}

impl CellCost<'_> {
    /// [`CellCost::sum`] of rooted sequences, cell by cell, with the same arithmetic in the
    /// same order (each joint's root-relative position, the squared distance summed x, y, z,
    /// joints added in order from zero, then scaled), so the costs equal the channel-major
    /// ones to the bit.
    ///
    /// `b`'s frames are read as they are stored: `f32` metres as they are, millimetres each
    /// turned into metres ([`from_mm`]) first. Millimetres read turned
    /// ([`Frames::millimetres_turned`]) are read as stored and `a`'s root-relative pose turned
    /// back instead: the same distances (a turn about the vertical keeps them), to within their
    /// rounding, for one turn a row rather than one a cell's every joint.
    #[inline(always)]
    fn sum_rooted(
        &self,
        a: Frames<'_>,
        i: usize,
        b: Frames<'_>,
        first: usize,
        out: &mut [f32],
        weigh: impl Fn(f32, f32) -> f32,
    ) {
        let joints = a.joints();
        let mut here = [Vec3::zeros(); MAX_JOINTS];
        let root = a.at(i, 0);
        for (k, h) in here.iter_mut().enumerate().take(joints) {
            *h = a.at(i, k) - root;
        }
        let (p, turn) = match b.stored() {
            Stored::Metres(p) => {
                return self.rooted_costs(&here[..joints], &p[first * joints..], out, &weigh)
            }
            Stored::Millimetres(p) => (p, None),
            Stored::Turned(p, turn) => (p, Some(turn)),
        };
        if let Some(turn) = turn {
            for h in here.iter_mut().take(joints) {
                *h = turn.back(h);
            }
        }
        self.decoded_costs(&here[..joints], &p[first * joints..], out, &weigh);
    }

    /// [`CellCost::rooted_costs`] of frames of millimetres, each frame turned into metres
    /// ([`from_mm`]) first.
    #[inline(always)]
    fn decoded_costs(
        &self,
        here: &[Vec3],
        frames: &[Mm],
        out: &mut [f32],
        weigh: &impl Fn(f32, f32) -> f32,
    ) {
        let joints = here.len();
        let mut decoded = [Vec3::zeros(); MAX_JOINTS];
        for (o, frame) in out.iter_mut().zip(frames.chunks_exact(joints)) {
            for (m, p) in decoded.iter_mut().zip(frame) {
                *m = from_mm(*p);
            }
            let o = core::slice::from_mut(o);
            self.rooted_costs(here, &decoded[..joints], o, weigh);
        }
    }

    /// The costs of `here` (root-relative positions) against consecutive whole frames of
    /// `frames` (each taken relative to its first joint), into `out`.
    #[inline(always)]
    fn rooted_costs(
        &self,
        here: &[Vec3],
        frames: &[Vec3],
        out: &mut [f32],
        weigh: &impl Fn(f32, f32) -> f32,
    ) {
        if self.unit {
            return rooted_distances(here, frames, self.scale, out);
        }
        for (o, frame) in out.iter_mut().zip(frames.chunks_exact(here.len())) {
            let root = frame[0];
            let joints = here.iter().zip(frame).zip(self.weights);
            let sum = joints.fold(0.0, |sum, ((h, p), &w)| {
                let d = h - (p - root);
                sum + weigh(w, sqrt(d.x * d.x + d.y * d.y + d.z * d.z))
            });
            *o = sum * self.scale;
        }
    }
}

/// Packs path steps into `steps`, 2 bits per cell, densely across rows.
struct StepWriter<'s> {
    steps: &'s mut [u8],
    offset: usize,
    acc: u64,
    count: u32,
}

impl StepWriter<'_> {
    /// Appends the low `count` bits of `bits` (at most 32).
    fn push(&mut self, bits: u32, count: u32) {
        self.acc |= u64::from(bits) << self.count;
        self.count += count;
        if self.count >= 32 {
            if let Some(word) = self.steps.get_mut(self.offset..self.offset + 4) {
                word.copy_from_slice(&(self.acc as u32).to_le_bytes());
            }
            self.offset += 4;
            self.acc >>= 32;
            self.count -= 32;
        }
    }

    /// Stores the bits still pending at the end (a partial last byte is padded with zeros).
    fn flush(&mut self) {
        let bytes = (self.count as usize).div_ceil(8);
        let end = (self.offset + bytes).min(self.steps.len());
        for (byte, value) in self.steps[self.offset..end]
            .iter_mut()
            .zip(self.acc.to_le_bytes())
        {
            *byte = value;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frames::{to_mm, Turn};
    use proptest::prelude::*;
    use std::vec::Vec;

    /// Full-matrix DTW with the same cost (summed in joint order), recurrence and tie-breaking.
    fn naive(a: &Sequence<'_>, b: &Sequence<'_>, weights: &[f32]) -> (f32, Vec<(u16, u16)>) {
        let (n, m, joints) = (a.frames(), b.frames(), a.joints());
        let scale = 1.0
            / if weights.is_empty() {
                joints as f32
            } else {
                weights.iter().sum::<f32>()
            };
        let cost = |i: usize, j: usize| {
            let mut total = 0.0f32;
            for k in 0..joints {
                let d = |axis: usize| a.at(axis * joints + k, i) - b.at(axis * joints + k, j);
                let (dx, dy, dz) = (d(0), d(1), d(2));
                total +=
                    weights.get(k).copied().unwrap_or(1.0) * (dx * dx + dy * dy + dz * dz).sqrt();
            }
            total * scale
        };
        let mut d = vec![vec![f32::INFINITY; m]; n];
        let mut step = vec![vec![DIAGONAL; m]; n];
        for i in 0..n {
            for j in 0..m {
                let here = cost(i, j);
                if i == 0 && j == 0 {
                    d[i][j] = here;
                    continue;
                }
                let diagonal = if i > 0 && j > 0 {
                    d[i - 1][j - 1]
                } else {
                    f32::INFINITY
                };
                let up = if i > 0 { d[i - 1][j] } else { f32::INFINITY };
                let left = if j > 0 { d[i][j - 1] } else { f32::INFINITY };
                let (best, s) = if diagonal <= up && diagonal <= left {
                    (diagonal, DIAGONAL)
                } else if up <= left {
                    (up, ADVANCE_A)
                } else {
                    (left, ADVANCE_B)
                };
                d[i][j] = here + best;
                step[i][j] = s;
            }
        }
        let (mut i, mut j) = (n - 1, m - 1);
        let mut path = vec![(i as u16, j as u16)];
        while (i, j) != (0, 0) {
            match step[i][j] {
                DIAGONAL => (i, j) = (i - 1, j - 1),
                ADVANCE_A => i -= 1,
                _ => j -= 1,
            }
            path.push((i as u16, j as u16));
        }
        path.reverse();
        (d[n - 1][m - 1], path)
    }

    fn run(
        a: &Sequence<'_>,
        b: &Sequence<'_>,
        weights: &[f32],
        window: &Window,
    ) -> (Alignment, Vec<(u16, u16)>) {
        let len = scratch_len(a.frames(), b.frames(), window).unwrap();
        let mut cost = vec![0.0; len.cost];
        let mut steps = vec![0u8; len.path_bytes];
        let mut path = vec![(0, 0); a.frames() + b.frames() - 1];
        let r = align(a, b, weights, window, &mut cost, &mut steps, &mut path).unwrap();
        path.truncate(r.path_len);
        (r, path)
    }

    /// Bounds (exclusive) on the joints and frames of [`sequences`]: smaller under Miri, which
    /// interprets every cell's cost.
    const BOUNDS: (usize, usize) = if cfg!(miri) { (6, 20) } else { (12, 40) };

    fn sequences() -> impl Strategy<Value = (usize, Vec<f32>, Vec<f32>, Vec<f32>)> {
        let (joints, frames) = BOUNDS;
        (1..joints, 1..frames, 1..frames).prop_flat_map(|(joints, n, m)| {
            (
                Just(joints),
                prop::collection::vec(-1.0f32..1.0, 3 * joints * n),
                prop::collection::vec(-1.0f32..1.0, 3 * joints * m),
                prop::collection::vec(0.0f32..2.0, joints),
            )
        })
    }

    /// Channel-major root-relative features of frame-major positions, as callers make them.
    fn channels(frames: &[Vec3], joints: usize) -> Vec<f32> {
        let n = frames.len() / joints;
        let mut out = vec![0.0; 3 * frames.len()];
        for (f, frame) in frames.chunks_exact(joints).enumerate() {
            for (k, p) in frame.iter().enumerate() {
                let d = p - frame[0];
                for axis in 0..3 {
                    out[(axis * joints + k) * n + f] = d[axis];
                }
            }
        }
        out
    }

    proptest! {
        #[test]
        fn rooted_frames_align_as_their_root_relative_channels_to_the_bit(
            (joints, a, b, w) in sequences(), radius in 0u16..8, weighted in any::<bool>(),
        ) {
            // The channel data read as frames of positions (any floats will do).
            let frames = |c: &[f32]| -> Vec<Vec3> { c.chunks_exact(3).map(|v| Vec3::new(v[0], v[1], v[2])).collect() };
            let (fa, fb) = (frames(&a), frames(&b));
            let (ca, cb) = (channels(&fa, joints), channels(&fb, joints));
            let weights: &[f32] = if weighted && w.iter().sum::<f32>() > 0.0 { &w } else { &[] };
            let window = Window::new(Band::global(radius), &[]).unwrap();
            let rooted = run(&Sequence::rooted(Frames::metres(&fa, joints)).unwrap(), &Sequence::rooted(Frames::metres(&fb, joints)).unwrap(), weights, &window);
            let copied = run(&Sequence::new(&ca, joints).unwrap(), &Sequence::new(&cb, joints).unwrap(), weights, &window);
            prop_assert_eq!(rooted.0.distance.to_bits(), copied.0.distance.to_bits());
            prop_assert_eq!(rooted.1, copied.1);
        }

        #[test]
        fn millimetre_frames_align_as_the_metres_they_hold_to_the_bit(
            (joints, a, b, w) in sequences(), radius in 0u16..8, weighted in any::<bool>(),
        ) {
            let mm = |c: &[f32]| -> Vec<Mm> { c.chunks_exact(3).filter_map(|v| to_mm(&Vec3::new(v[0], v[1], v[2]))).collect() };
            let (ma, mb) = (mm(&a), mm(&b));
            prop_assume!(3 * ma.len() == a.len() && 3 * mb.len() == b.len());
            let metres = |m: &[Mm]| -> Vec<Vec3> { m.iter().map(|&p| from_mm(p)).collect() };
            let (fa, fb) = (metres(&ma), metres(&mb));
            let weights: &[f32] = if weighted && w.iter().sum::<f32>() > 0.0 { &w } else { &[] };
            let window = Window::new(Band::global(radius), &[]).unwrap();
            let stored = run(&Sequence::rooted(Frames::millimetres(&ma, joints)).unwrap(), &Sequence::rooted(Frames::millimetres(&mb, joints)).unwrap(), weights, &window);
            let read = run(&Sequence::rooted(Frames::metres(&fa, joints)).unwrap(), &Sequence::rooted(Frames::metres(&fb, joints)).unwrap(), weights, &window);
            prop_assert_eq!(stored.0.distance.to_bits(), read.0.distance.to_bits());
            prop_assert_eq!(stored.1, read.1);
        }

        #[test]
        fn turned_millimetre_frames_align_as_the_turned_metres_they_read(
            (joints, a, b, w) in sequences(), radius in 0u16..8, angle in -3.2f32..3.2,
        ) {
            let mm = |c: &[f32]| -> Vec<Mm> { c.chunks_exact(3).filter_map(|v| to_mm(&Vec3::new(v[0], v[1], v[2]))).collect() };
            let (ma, mb) = (mm(&a), mm(&b));
            prop_assume!(3 * ma.len() == a.len() && 3 * mb.len() == b.len());
            let turn = Turn::new(Vec3::new(0.3, 0.0, -1.2), angle.sin(), angle.cos());
            let fa: Vec<Vec3> = ma.iter().map(|&p| from_mm(p)).collect();
            let fb: Vec<Vec3> = mb.iter().map(|&p| turn.apply(&from_mm(p))).collect();
            let weights: &[f32] = if w.iter().sum::<f32>() > 0.0 { &w } else { &[] };
            let window = Window::new(Band::global(radius), &[]).unwrap();
            let stored = run(&Sequence::rooted(Frames::millimetres(&ma, joints)).unwrap(), &Sequence::rooted(Frames::millimetres_turned(&mb, joints, &turn)).unwrap(), weights, &window);
            let read = run(&Sequence::rooted(Frames::metres(&fa, joints)).unwrap(), &Sequence::rooted(Frames::metres(&fb, joints)).unwrap(), weights, &window);
            // The row turned back rather than the columns turned: the same up to rounding.
            let (d, e) = (stored.0.distance, read.0.distance);
            prop_assert!((d - e).abs() <= 1e-5 * (1.0 + e.abs()), "{} against {}", d, e);
        }

        #[test]
        fn whole_row_passes_equal_the_serial_recurrence_to_the_bit(
            (above, cells) in (1usize..80).prop_flat_map(|w| (
                // Few distinct values, so that ties are common; infinity as outside the band.
                prop::collection::vec(prop::sample::select(vec![0.0f32, 0.5, 1.0, 1.5, 2.5, f32::INFINITY]), w + 1),
                prop::collection::vec(prop::sample::select(vec![0.0f32, 0.25, 0.5, 1.0]), w),
            )),
        ) {
            let w = cells.len();
            let written = |settled: bool| {
                let mut row = vec![f32::NAN; w + 1];
                row[0] = f32::INFINITY;
                let mut steps = vec![0u8; w.div_ceil(4)];
                let mut bits = StepWriter { steps: &mut steps, offset: 0, acc: 0, count: 0 };
                if settled {
                    let (mut spare, mut best) = (vec![f32::NAN; w + 1], vec![f32::NAN; w]);
                    settle(&mut row, &mut spare, &mut best, &cells, &above, &mut bits);
                } else {
                    recur(&mut row, &cells, &above, &mut bits);
                }
                bits.flush();
                (row.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), steps)
            };
            prop_assert_eq!(written(true), written(false));
        }

        #[test]
        fn a_band_covering_the_matrix_is_classic_dtw((joints, a, b, w) in sequences(), weighted in any::<bool>()) {
            let (a, b) = (Sequence::new(&a, joints).unwrap(), Sequence::new(&b, joints).unwrap());
            let weights: &[f32] = if weighted && w.iter().sum::<f32>() > 0.0 { &w } else { &[] };
            let (expected, expected_path) = naive(&a, &b, weights);
            let (got, path) = run(&a, &b, weights, &Window::new(Band::global(u16::MAX), &[]).unwrap());
            prop_assert_eq!(got.distance, expected);
            prop_assert_eq!(path, expected_path);
        }

        #[test]
        fn banded_paths_are_valid_and_no_shorter_than_classic(
            (joints, a, b, _) in sequences(), radius in 0u16..6, cuts in prop::collection::vec((0.0f32..1.0, 0.0f32..1.0), 0..4),
        ) {
            let (a, b) = (Sequence::new(&a, joints).unwrap(), Sequence::new(&b, joints).unwrap());
            let (n, m) = (a.frames(), b.frames());
            // Anchors strictly inside the matrix, increasing in both coordinates.
            let mut anchors: Vec<(u16, u16)> = Vec::new();
            let (mut fi, mut fj): (Vec<f32>, Vec<f32>) = cuts.into_iter().unzip();
            fi.sort_by(f32::total_cmp);
            fj.sort_by(f32::total_cmp);
            for (x, y) in fi.into_iter().zip(fj) {
                let (i, j) = (1 + (x * (n as f32 - 2.0)) as u16, 1 + (y * (m as f32 - 2.0)) as u16);
                if (i as usize) < n - 1 && (j as usize) < m - 1 && anchors.last().is_none_or(|&(pi, pj)| i > pi && j > pj) {
                    anchors.push((i, j));
                }
            }
            let window = Window::new(Band { radius, anchored: true }, &anchors).unwrap();
            let guide = window.guide(n, m).unwrap();
            let mut previous = (0, 0);
            for i in 0..n {
                let (lo, hi) = guide.row(i);
                prop_assert!(lo <= hi && hi < m);
                if i > 0 {
                    prop_assert!(lo >= previous.0 && hi >= previous.1 && lo <= previous.1 + 1);
                }
                previous = (lo, hi);
            }
            for &(i, j) in &anchors {
                let (lo, hi) = guide.row(i as usize);
                prop_assert!(lo <= j as usize && j as usize <= hi, "anchor outside the band");
            }
            let (banded, path) = run(&a, &b, &[], &window);
            prop_assert_eq!(path[0], (0, 0));
            prop_assert_eq!(*path.last().unwrap(), ((n - 1) as u16, (m - 1) as u16));
            for w in path.windows(2) {
                let step = (w[1].0 - w[0].0, w[1].1 - w[0].1);
                prop_assert!(matches!(step, (1, 1) | (1, 0) | (0, 1)));
            }
            for &(i, j) in &path {
                let (lo, hi) = guide.row(i as usize);
                prop_assert!(lo <= j as usize && j as usize <= hi);
            }
            let (classic, _) = naive(&a, &b, &[]);
            prop_assert!(banded.distance >= classic);
        }
    }

    #[test]
    fn rows_of_whole_and_partial_vector_blocks_are_classic_dtw() {
        const JOINTS: usize = 2;
        let walk = |frames: usize, seed: usize| -> Vec<f32> {
            (0..3 * JOINTS * frames)
                .map(|k| ((k * 7919 + seed) % 1013) as f32 / 506.5 - 1.0)
                .collect()
        };
        // 197 columns: whole blocks of 2 · VECTOR columns, then one of VECTOR and single ones
        // wherever VECTOR > 1. Under Miri, which takes minutes over 70 rows of 197, 29 columns
        // (16 + 8 + 5 at VECTOR = 8, 3 · 8 + 4 + 1 at 4; rows of 24 or more settle) on 12 rows.
        let (rows, columns) = if cfg!(miri) { (12, 29) } else { (70, 197) };
        let (a, b) = (walk(rows, 1), walk(columns, 2));
        let (a, b) = (
            Sequence::new(&a, JOINTS).unwrap(),
            Sequence::new(&b, JOINTS).unwrap(),
        );
        for weights in [&[][..], &[0.5, 2.0]] {
            let (expected, expected_path) = naive(&a, &b, weights);
            let (got, path) = run(
                &a,
                &b,
                weights,
                &Window::new(Band::global(u16::MAX), &[]).unwrap(),
            );
            assert_eq!(got.distance, expected);
            assert_eq!(path, expected_path);
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let a = [0.0f32; 6];
        assert_eq!(
            Sequence::new(&a[..5], 1).err(),
            Some(DtwError::SequenceShape)
        );
        assert_eq!(Sequence::new(&a, 0).err(), Some(DtwError::SequenceShape));
        let (s1, s2) = (Sequence::new(&a, 1).unwrap(), Sequence::new(&a, 2).unwrap());
        let window = Window::new(Band::global(2), &[]).unwrap();
        let mut path = [(0, 0); 8];
        let positions = [Vec3::zeros(); 2];
        let rooted = Sequence::rooted(Frames::metres(&positions, 1)).unwrap();
        assert_eq!(
            align(
                &s1,
                &rooted,
                &[],
                &window,
                &mut [0.0; 8],
                &mut [0; 8],
                &mut path
            ),
            Err(DtwError::Layouts)
        );
        assert_eq!(
            Sequence::rooted(Frames::metres(&positions, 3)).err(),
            Some(DtwError::SequenceShape)
        );
        assert_eq!(
            align(
                &s1,
                &s2,
                &[],
                &window,
                &mut [0.0; 8],
                &mut [0; 8],
                &mut path
            ),
            Err(DtwError::JointMismatch { a: 1, b: 2 })
        );
        assert_eq!(
            align(
                &s1,
                &s1,
                &[1.0, 1.0],
                &window,
                &mut [0.0; 8],
                &mut [0; 8],
                &mut path
            ),
            Err(DtwError::Weights)
        );
        let needed = scratch_len(2, 2, &window).unwrap().cost;
        assert_eq!(
            align(
                &s1,
                &s1,
                &[],
                &window,
                &mut [0.0; 1],
                &mut [0; 8],
                &mut path
            ),
            Err(DtwError::Scratch { which: 0, needed })
        );
        assert_eq!(
            Window::new(
                Band {
                    radius: 1,
                    anchored: true
                },
                &[(3, 3), (2, 4)]
            )
            .err(),
            Some(DtwError::Anchors)
        );
        let edge = Window::new(
            Band {
                radius: 1,
                anchored: true,
            },
            &[(0, 1)],
        )
        .unwrap();
        assert_eq!(scratch_len(2, 2, &edge).err(), Some(DtwError::Anchors));
    }
}
