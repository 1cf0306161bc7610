//! Reader for the point data of C3D motion-capture files.
//!
//! Supported subset of the format (see the C3D.ORG user guide):
//! - 512-byte blocks; block 1 is the header (byte 0 = first parameter block, byte 1 = `0x50`).
//! - Parameter section in Intel (processor type 84, little-endian IEEE floats), DEC (85,
//!   little-endian integers and VAX F-floats) or MIPS (86, big-endian) format; groups and
//!   parameters of type -1 (char), 1 (byte), 2 (int16) and 4 (float).
//! - Point data stored as int16 (`POINT:SCALE` > 0, values multiplied by the scale) or as floats
//!   (`POINT:SCALE` < 0, values as stored); analog samples interleaved after each frame are
//!   skipped, not decoded.
//!
//! - Parameters take precedence over the header: `POINT:USED`, `SCALE`, `RATE` and
//!   `DATA_START`, `ANALOG:USED` × (`ANALOG:RATE` / `POINT:RATE`), each falling back to its
//!   header word. The frame count is the header's last − first + 1 (`POINT:FRAMES` only when
//!   the header has none), or `TRIAL:ACTUAL_START_FIELD..=ACTUAL_END_FIELD` when that exceeds
//!   65535. Integer parameters holding counts are read as unsigned 16-bit words.
//!
//! Conventions: positions are converted to metres using `POINT:UNITS`; the axes are left as
//! stored. A sample is missing when its residual word is negative or a coordinate is not finite;
//! missing samples read as `[0.0; 3]` with `valid == false`. Events, analog values, force
//! plates, camera masks and residual magnitudes are not read.
//!
//! Parsing never panics and never reads outside the input: every declared size is checked
//! against the byte length first, and allocations are bounded by it.
use std::fmt;

/// Size of a C3D block in bytes.
const BLOCK: usize = 512;
/// Key stored in header byte 1.
const KEY: u8 = 0x50;

/// Default longest gap, in frames, that [`C3d::fill_gaps`] bridges.
///
/// 10 frames is 28 ms at 360 Hz, the longest gap the GearsSports exports declare as interpolable
/// (header word 6). Deleting 10-frame windows of valid data in the two golf trials and refilling
/// them gives errors of 1–4 mm on the pelvis and slow phases, but up to 2–3 cm on the wrists and
/// elbows and 6.5 cm on the shaft cluster in the downswing (5-frame gaps: 1 cm and 3 cm), so
/// longer gaps are left missing rather than bridged by guesswork.
pub const MAX_GAP_FRAMES: usize = 10;

/// Point data of a C3D file.
#[derive(Debug, Clone, PartialEq)]
pub struct C3d {
    /// `POINT:LABELS` (then `LABELS2`, `LABELS3`, ...), trimmed; `Uname*<n>` where absent.
    pub labels: Vec<String>,
    /// `POINT:RATE` in frames per second.
    pub rate_hz: f32,
    /// Number of frames.
    pub frames: usize,
    /// Number of the first frame (usually 1).
    pub first_frame: u32,
    /// Factor converting the stored units to metres (from `POINT:UNITS`).
    pub units_to_metres: f32,
    /// Positions in metres, `frames × labels`, row-major by frame, C3D axes.
    pub points: Vec<[f32; 3]>,
    /// Validity of each sample, `frames × labels`.
    pub valid: Vec<bool>,
}

/// Why a C3D file could not be read.
#[derive(Debug, Clone, PartialEq)]
pub struct C3dError {
    /// Byte offset in the file where the problem was found.
    pub offset: u64,
    /// What was wrong.
    pub kind: C3dErrorKind,
}

/// Kinds of [`C3dError`].
#[derive(Debug, Clone, PartialEq)]
pub enum C3dErrorKind {
    /// `what` would end at byte `end` but the file has only `len` bytes.
    Truncated { what: String, end: u64, len: u64 },
    /// Header byte 1 is not `0x50`.
    BadKey(u8),
    /// The header points the parameter section at block 0 or 1.
    BadParameterBlock(u8),
    /// The parameter section's processor type is not 84, 85 or 86.
    BadProcessor(u8),
    /// A parameter or group entry does not have the expected form or value.
    BadParameter {
        name: String,
        expected: &'static str,
    },
    /// `POINT:UNITS` is absent or not mm, cm or m.
    UnknownUnits(String),
}

impl fmt::Display for C3dError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "byte {}: ", self.offset)?;
        match &self.kind {
            C3dErrorKind::Truncated { what, end, len } => {
                write!(
                    f,
                    "{what} ends at byte {end} but the file has only {len} bytes"
                )
            }
            C3dErrorKind::BadKey(k) => write!(f, "header key is {k:#04x}, expected 0x50"),
            C3dErrorKind::BadParameterBlock(b) => {
                write!(
                    f,
                    "parameter section starts at block {b}, expected block 2 or later"
                )
            }
            C3dErrorKind::BadProcessor(p) => write!(
                f,
                "parameter block processor type {p} is not Intel (84), DEC (85) or MIPS (86)"
            ),
            C3dErrorKind::BadParameter { name, expected } => {
                write!(f, "parameter {name}: expected {expected}")
            }
            C3dErrorKind::UnknownUnits(u) => write!(f, "POINT:UNITS {u:?} is not mm, cm or m"),
        }
    }
}

impl std::error::Error for C3dError {}

fn err(offset: usize, kind: C3dErrorKind) -> C3dError {
    C3dError {
        offset: offset as u64,
        kind,
    }
}

fn bad(offset: usize, name: &str, expected: &'static str) -> C3dError {
    err(
        offset,
        C3dErrorKind::BadParameter {
            name: name.to_owned(),
            expected,
        },
    )
}

fn truncated(offset: usize, size: usize, len: usize, what: impl Into<String>) -> C3dError {
    let end = (offset as u64).saturating_add(size as u64);
    err(
        offset,
        C3dErrorKind::Truncated {
            what: what.into(),
            end,
            len: len as u64,
        },
    )
}

/// Number format of a file, from the processor type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Intel,
    Dec,
    Mips,
}

impl Format {
    fn u16(self, b: [u8; 2]) -> u16 {
        match self {
            Self::Mips => u16::from_be_bytes(b),
            Self::Intel | Self::Dec => u16::from_le_bytes(b),
        }
    }

    fn f32(self, b: [u8; 4]) -> f32 {
        match self {
            Self::Intel => f32::from_le_bytes(b),
            Self::Mips => f32::from_be_bytes(b),
            Self::Dec => vax_to_f32(b),
        }
    }
}

/// Decodes a VAX F-float as stored in DEC C3D files: two little-endian 16-bit words, the first
/// holding the sign, the 8-bit exponent (bias 128) and the top 7 fraction bits.
fn vax_to_f32(b: [u8; 4]) -> f32 {
    let bits = u32::from_le_bytes([b[2], b[3], b[0], b[1]]);
    if (bits >> 23) & 0xff == 0 {
        // Exponent 0 is zero, or the "reserved operand" when the sign bit is set.
        return if bits >> 31 == 0 { 0.0 } else { f32::NAN };
    }
    // Read as IEEE the same bits mean 1.f × 2^(e-127); VAX means 0.1f × 2^(e-128), a quarter.
    f32::from_bits(bits) / 4.0
}

/// The input bytes with the file's number format; every read is bounds-checked.
#[derive(Clone, Copy)]
struct Bytes<'a> {
    data: &'a [u8],
    format: Format,
}

impl<'a> Bytes<'a> {
    fn slice(&self, at: usize, size: usize, what: &str) -> Result<&'a [u8], C3dError> {
        at.checked_add(size)
            .and_then(|end| self.data.get(at..end))
            .ok_or_else(|| truncated(at, size, self.data.len(), what))
    }

    fn array<const N: usize>(&self, at: usize, what: &str) -> Result<[u8; N], C3dError> {
        let s = self.slice(at, N, what)?;
        s.try_into()
            .map_err(|_| truncated(at, N, self.data.len(), what))
    }

    fn u16(&self, at: usize, what: &str) -> Result<u16, C3dError> {
        Ok(self.format.u16(self.array(at, what)?))
    }

    fn f32(&self, at: usize, what: &str) -> Result<f32, C3dError> {
        Ok(self.format.f32(self.array(at, what)?))
    }
}

/// One parameter: its offset, group id, name, type (-1, 1, 2 or 4), dimensions and raw data.
struct Param<'a> {
    at: usize,
    group: u8,
    name: String,
    kind: i8,
    dims: Vec<usize>,
    data: &'a [u8],
}

impl Param<'_> {
    /// Element `i` as a number; int16 elements are read as unsigned when `unsigned`.
    fn number(&self, format: Format, i: usize, unsigned: bool) -> Option<f64> {
        let width = usize::from(self.kind.unsigned_abs());
        let at = i.checked_mul(width)?;
        Some(
            match (self.kind, self.data.get(at..at.checked_add(width)?)?) {
                (1, &[v]) => f64::from(v),
                (2, &[a, b]) if unsigned => f64::from(format.u16([a, b])),
                (2, &[a, b]) => f64::from(format.u16([a, b]) as i16),
                (4, &[a, b, c, d]) => f64::from(format.f32([a, b, c, d])),
                _ => return None,
            },
        )
    }

    /// A char parameter as its strings (rows of `dims[0]` characters), trimmed.
    fn strings(&self) -> Vec<String> {
        let width = self.dims.first().copied().unwrap_or(self.data.len());
        if self.kind != -1 || width == 0 {
            return Vec::new();
        }
        let text = |row| {
            String::from_utf8_lossy(row)
                .trim_matches(['\0', ' '])
                .trim()
                .to_owned()
        };
        self.data.chunks(width).map(text).collect()
    }
}

/// The parameter section: group names by id and the parameters.
struct Params<'a> {
    format: Format,
    groups: Vec<(u8, String)>,
    params: Vec<Param<'a>>,
}

impl<'a> Params<'a> {
    /// Parses the entries of the section `start..end` (`end` within the file).
    fn parse(data: &'a [u8], format: Format, start: usize, end: usize) -> Result<Self, C3dError> {
        let section = Bytes {
            data: data.get(..end).unwrap_or_default(),
            format,
        };
        let mut out = Params {
            format,
            groups: Vec::new(),
            params: Vec::new(),
        };
        let mut at = start + 4;
        while at + 2 <= end {
            let [len, id] = section.array(at, "parameter header")?.map(|b| b as i8);
            if len == 0 {
                break;
            }
            let name = section.slice(at + 2, usize::from(len.unsigned_abs()), "parameter name")?;
            let link = at + 2 + name.len();
            let name = String::from_utf8_lossy(name).trim().to_owned();
            let next = section.u16(link, "parameter link")? as i16;
            if id == 0 {
                return Err(bad(at + 1, &name, "a non-zero group id"));
            } else if id < 0 {
                out.groups.push((id.unsigned_abs(), name));
            } else {
                let what = format!("parameter {name} of group {id}");
                let [kind, ndims] = section.array(link + 2, &what)?;
                let kind = kind as i8;
                if ![-1, 1, 2, 4].contains(&kind) {
                    return Err(bad(link + 2, &name, "type -1, 1, 2 or 4"));
                }
                let dims = section.slice(link + 4, usize::from(ndims), &what)?;
                let dims: Vec<usize> = dims.iter().map(|&d| usize::from(d)).collect();
                let at_data = link + 4 + dims.len();
                // Up to 255 dimensions of up to 255 each: the product may overflow.
                let width = usize::from(kind.unsigned_abs());
                let size = dims.iter().try_fold(width, |acc, &d| acc.checked_mul(d));
                let data = section.slice(at_data, size.unwrap_or(usize::MAX), &what)?;
                let group = id.unsigned_abs();
                out.params.push(Param {
                    at,
                    group,
                    name,
                    kind,
                    dims,
                    data,
                });
            }
            if next <= 0 {
                break;
            }
            at = link + next.unsigned_abs() as usize;
        }
        Ok(out)
    }

    fn get(&self, group: &str, name: &str) -> Option<&Param<'a>> {
        let (id, _) = self
            .groups
            .iter()
            .find(|(_, g)| g.eq_ignore_ascii_case(group))?;
        let mut params = self.params.iter();
        params.find(|p| p.group == *id && p.name.eq_ignore_ascii_case(name))
    }

    /// First element of `group:name` as a number (int16 signed).
    fn value(&self, group: &str, name: &str) -> Option<f64> {
        self.get(group, name)?.number(self.format, 0, false)
    }

    /// Element `i` of `group:name` as a count (int16 unsigned).
    fn count(&self, group: &str, name: &str, i: usize) -> Option<usize> {
        let v = self.get(group, name)?.number(self.format, i, true)?;
        (v >= 0.0).then_some(v as usize)
    }

    /// A 32-bit field stored as two unsigned words, low word first (`TRIAL:*_FIELD`).
    fn field(&self, name: &str) -> Option<usize> {
        Some(self.count("TRIAL", name, 0)? + (self.count("TRIAL", name, 1)? << 16))
    }
}

impl C3d {
    /// Parses a C3D file held in memory.
    ///
    /// # Errors
    /// Returns a [`C3dError`] naming the byte offset when the header key or processor type is
    /// wrong, a parameter entry is malformed, `POINT:UNITS` is missing or unknown, `POINT:SCALE`
    /// is zero, `POINT:RATE` is not positive, or a declared section extends past the end of the
    /// input.
    pub fn parse(data: &[u8]) -> Result<C3d, C3dError> {
        let len = data.len();
        let (param_block, key) = match data {
            &[a, b, ..] => (a, b),
            _ => return Err(truncated(0, 2, len, "header")),
        };
        if key != KEY {
            return Err(err(1, C3dErrorKind::BadKey(key)));
        }
        if param_block < 2 {
            return Err(err(0, C3dErrorKind::BadParameterBlock(param_block)));
        }
        let start = (usize::from(param_block) - 1) * BLOCK;
        let Some(&[_, _, blocks, processor]) = data.get(start..start + 4) else {
            return Err(truncated(start, 4, len, "parameter section header"));
        };
        let format = match processor {
            84 => Format::Intel,
            85 => Format::Dec,
            86 => Format::Mips,
            _ => return Err(err(start + 3, C3dErrorKind::BadProcessor(processor))),
        };
        let end = start + usize::from(blocks) * BLOCK;
        if blocks == 0 {
            return Err(bad(
                start + 2,
                "section header",
                "at least one parameter block",
            ));
        } else if end > len {
            let what = format!("parameter section of {blocks} blocks");
            return Err(truncated(start, end - start, len, what));
        }
        let params = Params::parse(data, format, start, end)?;
        let bytes = Bytes { data, format };
        let word = |n: usize| bytes.u16(2 * (n - 1), "header").map(usize::from);
        let point_bad = |name: &str, expected| {
            let at = params.get("POINT", name).map_or(start, |p| p.at);
            bad(at, &format!("POINT:{name}"), expected)
        };

        let count = params
            .count("POINT", "USED", 0)
            .map_or_else(|| word(2), Ok)?;
        let header_scale = f64::from(bytes.f32(12, "header")?);
        let scale = params.value("POINT", "SCALE").unwrap_or(header_scale);
        if scale == 0.0 || !scale.is_finite() {
            return Err(point_bad("SCALE", "a non-zero scale"));
        }
        let rate = params
            .value("POINT", "RATE")
            .unwrap_or(f64::from(bytes.f32(20, "header")?));
        if !(rate > 0.0 && rate.is_finite()) {
            return Err(point_bad("RATE", "a positive frame rate"));
        }
        let units = params.get("POINT", "UNITS");
        let (units_at, units) =
            units.map_or((start, String::new()), |p| (p.at, p.strings().concat()));
        let units_to_metres = match units.to_ascii_lowercase().as_str() {
            "mm" => 0.001,
            "cm" => 0.01,
            "m" => 1.0,
            _ => return Err(err(units_at, C3dErrorKind::UnknownUnits(units))),
        };
        let label_param = |n: usize| match n {
            1 => params.get("POINT", "LABELS"),
            _ => params.get("POINT", &format!("LABELS{n}")),
        };
        let labels = (1..).map_while(label_param).flat_map(|p| p.strings());
        let mut labels: Vec<String> = labels.take(count).collect();
        labels.extend((labels.len()..count).map(|i| format!("Uname*{}", i + 1)));

        let data_block = match params.count("POINT", "DATA_START", 0) {
            Some(b) if b > 0 => b,
            _ => word(9)?,
        };
        if data_block < 2 {
            return Err(point_bad("DATA_START", "a block number of 2 or more"));
        }
        let per_channel = match params.value("ANALOG", "RATE") {
            Some(r) if r > 0.0 => (r / rate).round() as usize,
            _ => word(10)?,
        };
        let analog = match params.count("ANALOG", "USED", 0) {
            Some(used) => used.saturating_mul(per_channel),
            None => word(3)?,
        };
        // Prefer the header's frame range (POINT:FRAMES may be stale); the TRIAL fields hold
        // ranges beyond the 16-bit header words.
        let (first, last) = (word(4)?, word(5)?);
        let (frames, first_frame) = match (
            params.field("ACTUAL_START_FIELD"),
            params.field("ACTUAL_END_FIELD"),
        ) {
            (Some(s), Some(e)) if e >= s && e - s >= usize::from(u16::MAX) => (e - s + 1, s),
            _ if last >= first && last > 0 => (last - first + 1, first),
            _ => (params.count("POINT", "FRAMES", 0).unwrap_or(0), first),
        };

        let float = scale < 0.0;
        let (width, factor) = if float { (4, 1.0) } else { (2, scale as f32) };
        let data_start = (data_block - 1) * BLOCK;
        let frame_bytes = count
            .saturating_mul(4)
            .saturating_add(analog)
            .saturating_mul(width);
        let what = format!("data section of {frames} frames × {frame_bytes} bytes");
        let total = frame_bytes.saturating_mul(frames);
        bytes.slice(data_start, total, &what)?;

        let value = |at: usize| match float {
            true => bytes.f32(at, "point data"),
            false => bytes.u16(at, "point data").map(|v| f32::from(v as i16)),
        };
        let mut points = Vec::with_capacity(frames * count);
        let mut valid = Vec::with_capacity(frames * count);
        for i in 0..frames * count {
            let at = data_start + i / count * frame_bytes + i % count * 4 * width;
            let xyz = [value(at)?, value(at + width)?, value(at + 2 * width)?];
            let xyz = xyz.map(|v| v * factor * units_to_metres);
            let ok = value(at + 3 * width)? >= 0.0 && xyz.iter().all(|v| v.is_finite());
            points.push(if ok { xyz } else { [0.0; 3] });
            valid.push(ok);
        }
        let rate_hz = rate as f32;
        Ok(C3d {
            labels,
            rate_hz,
            frames,
            first_frame: first_frame as u32,
            units_to_metres,
            points,
            valid,
        })
    }

    /// Index of the marker labelled exactly `label` (after trimming).
    pub fn label_index(&self, label: &str) -> Option<usize> {
        self.labels.iter().position(|l| l == label.trim())
    }

    /// Position of marker `label` in `frame`, or `None` when missing or out of range.
    pub fn point(&self, frame: usize, label: usize) -> Option<[f32; 3]> {
        let i = self.index(frame, label)?;
        match (self.valid.get(i), self.points.get(i)) {
            (Some(true), Some(&p)) => Some(p),
            _ => None,
        }
    }

    fn index(&self, frame: usize, label: usize) -> Option<usize> {
        let n = self.labels.len();
        (frame < self.frames && label < n).then_some(frame * n + label)
    }

    fn set(&mut self, frame: usize, label: usize, p: [f32; 3]) {
        let Some(i) = self.index(frame, label) else {
            return;
        };
        if let (Some(slot), Some(ok)) = (self.points.get_mut(i), self.valid.get_mut(i)) {
            (*slot, *ok) = (p, true);
        }
    }

    /// Fills gaps of at most `max_gap` consecutive missing frames per marker by cubic Hermite
    /// interpolation with Catmull-Rom tangents from the valid samples around the gap; the curve
    /// is a straight line when a side has only one valid sample. Longer gaps and gaps at the
    /// start or end stay missing. Returns how many samples were filled.
    pub fn fill_gaps(&mut self, max_gap: usize) -> usize {
        let mut filled = 0;
        for m in 0..self.labels.len() {
            let orig: Vec<Option<[f32; 3]>> = (0..self.frames).map(|f| self.point(f, m)).collect();
            let at = |f: Option<usize>| f.and_then(|f| orig.get(f).copied().flatten());
            let mut f = 0;
            while f < self.frames {
                let start = f;
                while orig.get(f).is_some_and(Option::is_none) {
                    f += 1;
                }
                if f == start {
                    f += 1;
                    continue;
                }
                let (Some(a), Some(b)) = (at(start.checked_sub(1)), at(Some(f))) else {
                    continue;
                };
                if f - start > max_gap {
                    continue;
                }
                // Hermite parameter t runs from 0 at `a` (frame start-1) to 1 at `b` (frame f),
                // h frames apart; Catmull-Rom tangents span the neighbours one frame further out.
                let h = (f - start + 1) as f32;
                let (ta, tb) = match (at(start.checked_sub(2)), at(Some(f + 1))) {
                    (Some(a0), Some(b1)) => {
                        let s = h / (h + 1.0);
                        (
                            vec3::scale(vec3::sub(b, a0), s),
                            vec3::scale(vec3::sub(b1, a), s),
                        )
                    }
                    _ => (vec3::sub(b, a), vec3::sub(b, a)),
                };
                for k in start..f {
                    let t = (k + 1 - start) as f32 / h;
                    let (t2, t3) = (t * t, t * t * t);
                    let basis = [
                        2.0 * t3 - 3.0 * t2 + 1.0,
                        t3 - 2.0 * t2 + t,
                        3.0 * t2 - 2.0 * t3,
                        t3 - t2,
                    ];
                    let terms = [a, ta, b, tb].into_iter().zip(basis);
                    self.set(k, m, terms.fold([0.0; 3], |p, (v, w)| vec3::mad(p, v, w)));
                    filled += 1;
                }
            }
        }
        filled
    }

    /// Fills the missing samples of marker `target` from three markers `frame_of = [a, b, c]`
    /// assumed rigid with it. The target's position in the cluster's orthonormal frame (origin
    /// `a`, x toward `b`, z = x × (c − a) normalised, y = z × x), averaged over the frames where
    /// all four are valid, is re-applied where the three are valid and the target is not.
    /// Returns the number of samples filled (0 when no frame has all four).
    pub fn fill_rigid(&mut self, target: usize, frame_of: [usize; 3]) -> usize {
        let frame_at = |c: &C3d, f: usize| {
            let [a, b, d] = frame_of.map(|m| c.point(f, m));
            Frame::new(a?, b?, d?)
        };
        let (mut sum, mut n) = ([0.0f64; 3], 0u32);
        for f in 0..self.frames {
            if let (Some(fr), Some(p)) = (frame_at(self, f), self.point(f, target)) {
                let l = fr.local(p);
                sum = [0, 1, 2].map(|i| sum[i] + f64::from(l[i]));
                n += 1;
            }
        }
        if n == 0 {
            return 0;
        }
        let local = sum.map(|s| (s / f64::from(n)) as f32);
        let mut filled = 0;
        for f in 0..self.frames {
            if let (None, Some(fr)) = (self.point(f, target), frame_at(self, f)) {
                self.set(f, target, fr.global(local));
                filled += 1;
            }
        }
        filled
    }
}

/// Right-handed orthonormal frame from three points: origin `a`, x toward `b`,
/// z = x × (c − a) normalised, y = z × x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Frame {
    /// Origin, the first point.
    pub origin: [f32; 3],
    /// Unit x, y and z axes.
    pub axes: [[f32; 3]; 3],
}

impl Frame {
    /// `None` when the three points are (nearly) collinear or coincident.
    pub fn new(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Option<Frame> {
        let x = vec3::normalize(vec3::sub(b, a))?;
        let z = vec3::normalize(vec3::cross(x, vec3::sub(c, a)))?;
        Some(Frame {
            origin: a,
            axes: [x, vec3::cross(z, x), z],
        })
    }

    /// Coordinates of global point `p` in this frame.
    pub fn local(&self, p: [f32; 3]) -> [f32; 3] {
        let d = vec3::sub(p, self.origin);
        self.axes.map(|axis| vec3::dot(d, axis))
    }

    /// Global point with local coordinates `l`.
    pub fn global(&self, l: [f32; 3]) -> [f32; 3] {
        self.axes
            .iter()
            .zip(l)
            .fold(self.origin, |p, (&axis, s)| vec3::mad(p, axis, s))
    }
}

/// Small 3-vector helpers shared with the joint-centre code.
pub(crate) mod vec3 {
    pub fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
    pub fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }
    pub fn scale(a: [f32; 3], s: f32) -> [f32; 3] {
        a.map(|v| v * s)
    }
    /// `a + s·b`.
    pub fn mad(a: [f32; 3], b: [f32; 3], s: f32) -> [f32; 3] {
        add(a, scale(b, s))
    }
    pub fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    pub fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    pub fn norm(a: [f32; 3]) -> f32 {
        dot(a, a).sqrt()
    }
    /// `a / |a|`, or `None` when `|a|` is below 1e-9 or not finite.
    pub fn normalize(a: [f32; 3]) -> Option<[f32; 3]> {
        let n = norm(a);
        (n > 1e-9 && n.is_finite()).then(|| scale(a, 1.0 / n))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
pub(crate) mod tests {
    use super::*;
    use std::path::PathBuf;

    const RATE: f32 = 50.0;
    const INT_SCALE: f32 = 0.25;
    const FLOAT_SCALE: f32 = -0.01;
    /// One analog channel sampled at twice the point rate.
    const ANALOG_PER_FRAME: i16 = 2;
    /// Written where an analog sample is: visible if the reader mistakes it for point data.
    const ANALOG_VALUE: f32 = -7777.0;
    const LABELS: [&str; 3] = ["LASI", "RASI", "Club:Head"];
    const FRAMES: usize = 4;
    /// Header, one parameter block, then data.
    const DATA_BLOCK: i16 = 3;
    /// (frame, marker) of the one missing sample.
    const MISSING: (usize, usize) = (2, 1);

    /// The folder of the golf C3D files: `$POSECOACH_DATA/golf` when that variable is set,
    /// else the shared data folder beside the workspace; `None` when absent.
    pub(crate) fn data_dir() -> Option<PathBuf> {
        let base = std::env::var_os("POSECOACH_DATA").map_or_else(
            || PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data")),
            PathBuf::from,
        );
        let dir = base.join("golf");
        dir.is_dir().then_some(dir)
    }

    /// Stored coordinates: multiples of 0.25, exact in both storage formats.
    fn sample(f: usize, m: usize) -> [f32; 3] {
        let (f, m) = (f as f32, m as f32);
        [1.5 * f + m, 100.0 - 2.0 * f, -0.25 * (m + f)]
    }

    fn enc16(format: Format, v: i16) -> [u8; 2] {
        match format {
            Format::Mips => v.to_be_bytes(),
            _ => v.to_le_bytes(),
        }
    }

    fn enc32(format: Format, v: f32) -> [u8; 4] {
        match format {
            Format::Intel => v.to_le_bytes(),
            Format::Mips => v.to_be_bytes(),
            Format::Dec => {
                // VAX has no negative zero: sign + zero exponent is the reserved operand.
                let v = if v == 0.0 { 0.0 } else { v };
                let b = (v * 4.0).to_bits().to_le_bytes();
                [b[2], b[3], b[0], b[1]]
            }
        }
    }

    /// Parameter record: group id, name, type, dimensions, encoded data.
    type Rec = (u8, &'static str, i8, Vec<u8>, Vec<u8>);

    /// A small C3D file: 3 markers (labels split over LABELS and LABELS2), 4 frames, one
    /// missing sample, one analog channel; `extra` parameters are appended.
    fn write(format: Format, float: bool, units: &str, extra: &[Rec]) -> Vec<u8> {
        let scale = if float { FLOAT_SCALE } else { INT_SCALE };
        let w = |v: i16| enc16(format, v).to_vec();
        let fl = |v: f32| enc32(format, v).to_vec();
        let text = |s: &str| s.as_bytes().to_vec();
        let mut recs: Vec<Rec> = vec![
            (1, "USED", 2, vec![], w(3)),
            (1, "SCALE", 4, vec![], fl(scale)),
            (1, "RATE", 4, vec![], fl(RATE)),
            (1, "FRAMES", 2, vec![], w(FRAMES as i16)),
            (1, "DATA_START", 2, vec![], w(DATA_BLOCK)),
            (1, "UNITS", -1, vec![units.len() as u8], text(units)),
            (1, "LABELS", -1, vec![5, 2], text("LASI RASI ")),
            (1, "LABELS2", -1, vec![9, 1], text(LABELS[2])),
            (2, "USED", 2, vec![], w(1)),
            (2, "RATE", 4, vec![], fl(RATE * f32::from(ANALOG_PER_FRAME))),
        ];
        recs.extend_from_slice(extra);
        let code = [(Format::Intel, 84), (Format::Dec, 85), (Format::Mips, 86)];
        let code = code.iter().find(|c| c.0 == format).map_or(0, |c| c.1);
        let mut p = vec![1, KEY, 1, code];
        for (id, name) in [(1i8, "POINT"), (2, "ANALOG"), (3, "TRIAL")] {
            p.extend(
                [name.len() as u8, (-id) as u8]
                    .into_iter()
                    .chain(text(name)),
            );
            p.extend(w(3).into_iter().chain([0]));
        }
        for (k, (group, name, kind, dims, data)) in recs.iter().enumerate() {
            let next = if k + 1 == recs.len() {
                0
            } else {
                5 + dims.len() + data.len()
            };
            p.extend([name.len() as u8, *group].into_iter().chain(text(name)));
            p.extend(
                w(next as i16)
                    .into_iter()
                    .chain([*kind as u8, dims.len() as u8]),
            );
            p.extend(dims.iter().chain(data).chain(&[0]));
        }
        assert!(p.len() <= BLOCK);
        p.resize(BLOCK, 0);

        // Header words 1-12 in order: parameter block and key, points, analog values per
        // frame, first and last frame, interpolation gap, scale, data block, analog samples
        // per channel and frame, rate.
        let (frames, analog) = (w(FRAMES as i16), w(ANALOG_PER_FRAME));
        let h = [
            vec![2, KEY],
            w(3),
            analog.clone(),
            w(1),
            frames,
            w(10),
            fl(scale),
        ];
        let mut h = [h.concat(), w(DATA_BLOCK), analog, fl(RATE)].concat();
        h.resize(BLOCK, 0);

        let num = |v: f32| if float { fl(v) } else { w(v as i16) };
        let mut d = Vec::new();
        for f in 0..FRAMES {
            for m in 0..LABELS.len() {
                let residual = if (f, m) == MISSING { -1.0 } else { 0.0 };
                let xyz = sample(f, m).map(|v| if float { v } else { v / INT_SCALE });
                d.extend(xyz.into_iter().chain([residual]).flat_map(num));
            }
            d.extend((0..ANALOG_PER_FRAME).flat_map(|_| num(ANALOG_VALUE)));
        }
        [h, p, d].concat()
    }

    #[test]
    fn parses_every_format_exactly() {
        let cases = [
            (Format::Intel, true, "m", 1.0),
            (Format::Intel, false, "mm", 0.001),
            (Format::Mips, true, "cm", 0.01),
            (Format::Mips, false, "mm", 0.001),
            (Format::Dec, true, "m", 1.0),
        ];
        for (format, float, units, factor) in cases {
            let c = C3d::parse(&write(format, float, units, &[])).unwrap();
            assert_eq!(c.labels, LABELS, "{format:?}");
            assert_eq!((c.rate_hz, c.frames, c.first_frame), (RATE, FRAMES, 1));
            assert_eq!(c.units_to_metres, factor);
            for f in 0..FRAMES {
                for m in 0..LABELS.len() {
                    let want = ((f, m) != MISSING).then(|| sample(f, m).map(|v| v * factor));
                    assert_eq!(
                        c.point(f, m),
                        want,
                        "{format:?} float {float} frame {f} marker {m}"
                    );
                }
            }
            assert_eq!(c.points[MISSING.0 * 3 + MISSING.1], [0.0; 3]);
            assert_eq!(c.label_index(" Club:Head "), Some(2));
            assert_eq!(c.point(FRAMES, 0), None);
        }
    }

    #[test]
    fn vax_floats() {
        // VAX F-float bytes as stored by DEC: [fraction-high|exponent-low, sign|exponent-high, low word].
        assert_eq!(vax_to_f32([0x80, 0x40, 0, 0]), 1.0);
        assert_eq!(vax_to_f32([0x20, 0xc1, 0, 0]), -2.5);
        assert_eq!(vax_to_f32([0x20, 0x3f, 0, 0]), 0.15625);
        assert_eq!(vax_to_f32([0x80, 0x40, 0x01, 0]), 1.0 + f32::EPSILON);
        assert_eq!(vax_to_f32([0, 0, 0, 0]), 0.0);
        assert!(vax_to_f32([0, 0x80, 0, 0]).is_nan());
    }

    #[test]
    fn rejects_bad_files_with_offsets() {
        let good = write(Format::Intel, true, "m", &[]);
        let mut bad = good.clone();
        bad[BLOCK + 3] = 99;
        let e = C3d::parse(&bad).unwrap_err();
        assert_eq!(e.kind, C3dErrorKind::BadProcessor(99));
        assert_eq!(
            e.to_string(),
            "byte 515: parameter block processor type 99 is not Intel (84), DEC (85) or MIPS (86)"
        );
        bad = good.clone();
        bad[1] = 0x51;
        assert_eq!(
            C3d::parse(&bad).unwrap_err().kind,
            C3dErrorKind::BadKey(0x51)
        );
        let e = C3d::parse(&write(Format::Intel, true, "in", &[])).unwrap_err();
        assert_eq!(e.kind, C3dErrorKind::UnknownUnits("in".into()));
        let e = C3d::parse(&good[..good.len() - 1]).unwrap_err();
        assert!(matches!(e.kind, C3dErrorKind::Truncated { .. }), "{e}");
        assert!(
            e.to_string()
                .starts_with("byte 1024: data section of 4 frames"),
            "{e}"
        );
    }

    #[test]
    fn long_trials_use_the_trial_fields() {
        let w = |v: u16| v.to_le_bytes();
        let field = |v: u32| [w(v as u16), w((v >> 16) as u16)].concat();
        let extra = [
            (3, "ACTUAL_START_FIELD", 2, vec![2], field(1)),
            (3, "ACTUAL_END_FIELD", 2, vec![2], field(70_000)),
        ];
        let e = C3d::parse(&write(Format::Intel, false, "mm", &extra)).unwrap_err();
        assert!(
            e.to_string().contains("data section of 70000 frames"),
            "{e}"
        );
    }

    #[test]
    fn corrupt_input_never_panics() {
        const FLIPS: usize = 3000;
        for format in [Format::Intel, Format::Dec, Format::Mips] {
            let good = write(format, format != Format::Mips, "mm", &[]);
            for n in 0..good.len() {
                let _ = C3d::parse(&good[..n]);
            }
            let mut state = 0x2545_f491_u32;
            let mut next = || {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 8) as usize
            };
            for _ in 0..FLIPS {
                let mut bad = good.clone();
                for _ in 0..1 + next() % 3 {
                    // Mostly the header and parameters, where a flip changes the layout.
                    let at = next()
                        % if next() % 4 == 0 {
                            bad.len()
                        } else {
                            2 * BLOCK
                        };
                    bad[at] ^= 1 << (next() % 8);
                }
                let _ = C3d::parse(&bad);
            }
        }
    }

    fn synthetic(frames: usize, labels: usize, at: impl Fn(usize, usize) -> [f32; 3]) -> C3d {
        let points = (0..frames * labels)
            .map(|i| at(i / labels, i % labels))
            .collect();
        C3d {
            labels: (0..labels).map(|m| format!("m{m}")).collect(),
            rate_hz: 100.0,
            frames,
            first_frame: 1,
            units_to_metres: 1.0,
            points,
            valid: vec![true; frames * labels],
        }
    }

    #[test]
    fn fill_gaps_bridges_short_gaps_only() {
        const MAX_GAP: usize = 4;
        let line = |f: usize| [0.1 * f as f32, 1.0 - 0.2 * f as f32, 0.05 * f as f32];
        let mut c = synthetic(30, 1, |f, _| line(f));
        let gaps = [0..2, 5..8, 12..18, 20..24, 28..30];
        for f in gaps.iter().cloned().flatten() {
            c.valid[f] = false;
        }
        // 5..8 has one valid sample before it: linear; 20..24 has two on both sides: Catmull-Rom.
        assert_eq!(c.fill_gaps(MAX_GAP), 3 + 4);
        for f in 0..30 {
            let missing = [0..2, 12..18, 28..30].iter().any(|g| g.contains(&f));
            match c.point(f, 0) {
                Some(p) => (0..3).for_each(|i| assert!((p[i] - line(f)[i]).abs() < 1e-6, "{f}")),
                None => assert!(missing, "frame {f} not filled"),
            }
        }
    }

    #[test]
    fn fill_rigid_follows_a_rotating_cluster() {
        const TOLERANCE: f32 = 1e-5;
        let body = [
            [0.0, 0.0, 0.0],
            [0.2, 0.0, 0.0],
            [0.0, 0.15, 0.05],
            [0.1, 0.1, 0.3],
        ];
        let pose = |f: usize, m: usize| {
            let (s, c) = (0.07 * f as f32).sin_cos();
            let [x, y, z] = body[m];
            [
                c * x - s * z + 0.01 * f as f32,
                y + 1.0,
                s * x + c * z - 0.02 * f as f32,
            ]
        };
        let mut c = synthetic(40, 4, pose);
        for f in 10..40 {
            c.valid[f * 4 + 3] = false;
        }
        c.valid[5 * 4] = false;
        assert_eq!(c.fill_rigid(3, [0, 1, 2]), 30);
        for f in 10..40 {
            let (p, want) = (c.point(f, 3).unwrap(), pose(f, 3));
            assert!(
                vec3::norm(vec3::sub(p, want)) < TOLERANCE,
                "frame {f}: {p:?} vs {want:?}"
            );
        }
        let mut none = synthetic(3, 4, pose);
        none.valid[3..].fill(false);
        assert_eq!(none.fill_rigid(3, [0, 1, 2]), 0);
    }

    #[test]
    fn reads_the_golf_files() {
        let Some(dir) = data_dir() else {
            eprintln!("skipping: golf data folder not found (set POSECOACH_DATA)");
            return;
        };
        for (file, frames, rate, right_top_missing) in [
            ("gears_tour_driver.c3d", 654, 360.0, 526),
            ("gears_tour_iron.c3d", 657, 359.0, 562),
        ] {
            let c = C3d::parse(&std::fs::read(dir.join(file)).unwrap()).unwrap();
            assert_eq!(
                (c.frames, c.rate_hz, c.labels.len()),
                (frames, rate, 38),
                "{file}"
            );
            assert_eq!((c.first_frame, c.units_to_metres), (1, 1.0));
            assert_eq!(c.label_index("WaistLeft"), Some(1));
            let rst = c.label_index("RShoulderTop").unwrap();
            let missing = (0..frames).filter(|&f| c.point(f, rst).is_none()).count();
            assert_eq!(missing, right_top_missing, "{file}");
        }
    }
}
