//! Reader and writer for the point data of C3D motion-capture files.
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
//! missing samples read as zero with `valid == false`. Events, analog values, force
//! plates, camera masks and residual magnitudes are not read.
//!
//! Parsing never panics and never reads outside the input: every declared size is checked
//! against the byte length first, and allocations are bounded by it.
//!
//! [`C3d::to_bytes`] writes Intel files with metres as units and no analog channels, in either
//! [`Storage`].
use crate::limits::{check_limits, LimitError};
use posecoach_core::Vec3;
use std::fmt;

/// Size of a C3D block in bytes.
const BLOCK: usize = 512;
/// Key stored in header byte 1.
const KEY: u8 = 0x50;

/// Longest gap, in seconds, that the golf import bridges with [`C3d::fill_gaps`].
///
/// 10 frames at 360 Hz (28 ms), the longest gap the GearsSports exports declare as interpolable
/// (header word 6). Deleting 10-frame windows of valid data in the two golf trials and refilling
/// them gives errors of 1–4 mm on the pelvis and slow phases, but up to 2–3 cm on the wrists and
/// elbows and 6.5 cm on the shaft cluster in the downswing (5-frame gaps: 1 cm and 3 cm), so
/// longer gaps are left missing rather than bridged by guesswork. It is a duration, not a
/// frame count, so that a file resampled to 60 Hz is not bridged over 167 ms.
pub const MAX_GAP_S: f32 = 10.0 / 360.0;

/// [`MAX_GAP_S`] in frames at `rate_hz` (at least one frame).
pub fn max_gap_frames(rate_hz: f32) -> usize {
    ((rate_hz * MAX_GAP_S).round() as usize).max(1)
}

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
    pub points: Vec<Vec3>,
    /// Validity of each sample, `frames × labels`.
    pub valid: Vec<bool>,
}

/// How [`C3d::to_bytes`] stores coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Storage {
    /// 32-bit floats (`POINT:SCALE` −1): positions are kept exactly.
    Float,
    /// 16-bit integers counting steps of `scale` metres (`POINT:SCALE`), half the size of float
    /// storage. Positions are rounded to the nearest step; a sample beyond ±32767 steps on any
    /// axis is written as missing. A scale of 0.0005 holds ±16.38 m in 0.5 mm steps (error at
    /// most 0.25 mm).
    Integer {
        /// Metres per step; positive and finite.
        scale: f32,
    },
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
    /// The point data is beyond the limits, a label counting as a joint.
    Limit(LimitError),
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
            C3dErrorKind::Limit(e) => write!(f, "point data: {e}"),
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
    /// Processor type in the parameter section header.
    fn processor(self) -> u8 {
        match self {
            Self::Intel => 84,
            Self::Dec => 85,
            Self::Mips => 86,
        }
    }

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

    fn u16_bytes(self, v: u16) -> [u8; 2] {
        match self {
            Self::Mips => v.to_be_bytes(),
            Self::Intel | Self::Dec => v.to_le_bytes(),
        }
    }

    fn f32_bytes(self, v: f32) -> [u8; 4] {
        match self {
            Self::Intel => v.to_le_bytes(),
            Self::Mips => v.to_be_bytes(),
            Self::Dec => f32_to_vax(v),
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

/// Encodes a VAX F-float: the inverse of [`vax_to_f32`] for zero and magnitudes from 2^-128 up
/// to 2^126.
fn f32_to_vax(v: f32) -> [u8; 4] {
    // VAX has no negative zero: sign + zero exponent is the reserved operand.
    let v = if v == 0.0 { 0.0 } else { v };
    let b = (v * 4.0).to_bits().to_le_bytes();
    [b[2], b[3], b[0], b[1]]
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
    /// is zero, `POINT:RATE` is not positive, a declared section extends past the end of the
    /// input, or the point data is beyond the limits ([`check_limits`], checked before it is
    /// read).
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
        let formats = [Format::Intel, Format::Dec, Format::Mips];
        let Some(format) = formats.into_iter().find(|f| f.processor() == processor) else {
            return Err(err(start + 3, C3dErrorKind::BadProcessor(processor)));
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
        let rate_hz = rate as f32;
        let limit = |e| err(data_start, C3dErrorKind::Limit(e));
        check_limits(frames, count, rate_hz).map_err(limit)?;

        let value = |at: usize| match float {
            true => bytes.f32(at, "point data"),
            false => bytes.u16(at, "point data").map(|v| f32::from(v as i16)),
        };
        let mut points = Vec::with_capacity(frames * count);
        let mut valid = Vec::with_capacity(frames * count);
        for i in 0..frames * count {
            let at = data_start + i / count * frame_bytes + i % count * 4 * width;
            let xyz = Vec3::new(value(at)?, value(at + width)?, value(at + 2 * width)?);
            let xyz = xyz * factor * units_to_metres;
            let ok = value(at + 3 * width)? >= 0.0 && xyz.iter().all(|v| v.is_finite());
            points.push(if ok { xyz } else { Vec3::zeros() });
            valid.push(ok);
        }
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

    /// The points as a C3D file: Intel byte order, `POINT:UNITS` m, no analog channels, and the
    /// frame range in the header and in `TRIAL:ACTUAL_START_FIELD`/`ACTUAL_END_FIELD` (read for
    /// trials longer than 65535 frames).
    ///
    /// [`C3d::parse`] gives back the labels, rate, frame count, first frame, validity and
    /// positions: exactly with [`Storage::Float`], to within half a step with
    /// [`Storage::Integer`]. Invalid samples, non-finite ones and those out of the integer range
    /// are written as missing (negative residual) with zero coordinates. `units_to_metres` is
    /// not used: points are in metres. Labels are cut to 255 bytes and read back trimmed; the
    /// first frame reads back as 1 when a trial of at most 65535 frames ends past frame 65535
    /// (the header holds 16-bit frame numbers). More than 65535 labels, or labels that overflow
    /// the 255-block parameter section (about 5000 of 24 characters), make a file that
    /// [`C3d::parse`] rejects.
    pub fn to_bytes(&self, storage: Storage) -> Vec<u8> {
        let n = self.labels.len();
        let width = self.labels.iter().map(String::len).max();
        let width = width.unwrap_or(0).clamp(1, usize::from(u8::MAX));
        // A record links to the next by a signed 16-bit offset: at most 32760 bytes of data.
        let rows = (32_760 / width).min(usize::from(u8::MAX));
        let mut records = vec![point_text("UNITS".into(), 1, &["m"])];
        for (k, chunk) in self.labels.chunks(rows).enumerate() {
            let name = match k {
                0 => "LABELS".to_owned(),
                _ => format!("LABELS{}", k + 1),
            };
            records.push(point_text(name, width, chunk));
        }
        let frames = u32::try_from(self.frames).unwrap_or(u32::MAX);
        let last = self.first_frame.saturating_add(frames).saturating_sub(1);
        records.extend([
            trial_field(Format::Intel, "ACTUAL_START_FIELD", self.first_frame),
            trial_field(Format::Intel, "ACTUAL_END_FIELD", last),
        ]);

        let (scale, max) = match storage {
            Storage::Float => (-1.0, f32::MAX),
            Storage::Integer { scale } => (scale, f32::from(i16::MAX)),
        };
        // Metres as floats, or whole steps of `scale`.
        let stored = |p: Vec3| match scale < 0.0 {
            true => p,
            false => (p / scale).map(f32::round),
        };
        let sample = |i: usize| match self.point(i / n, i % n).map(stored) {
            Some(p) if p.iter().all(|v| v.abs() <= max) => [p.x, p.y, p.z, 0.0],
            _ => [0.0, 0.0, 0.0, -1.0],
        };
        let layout = Layout {
            format: Format::Intel,
            scale,
            rate: self.rate_hz,
            first_frame: self.first_frame as usize,
            frames: self.frames,
            points: n,
            analog: [0, 1],
        };
        layout.write(
            &records,
            (0..self.frames.saturating_mul(n)).flat_map(sample),
        )
    }

    /// Index of the marker labelled exactly `label` (after trimming).
    pub fn label_index(&self, label: &str) -> Option<usize> {
        self.labels.iter().position(|l| l == label.trim())
    }

    /// Position of marker `label` in `frame`, or `None` when missing or out of range.
    pub fn point(&self, frame: usize, label: usize) -> Option<Vec3> {
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

    fn set(&mut self, frame: usize, label: usize, p: Vec3) {
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
            let orig: Vec<Option<Vec3>> = (0..self.frames).map(|f| self.point(f, m)).collect();
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
                        ((b - a0) * s, (b1 - a) * s)
                    }
                    _ => (b - a, b - a),
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
                    self.set(k, m, terms.fold(Vec3::zeros(), |p, (v, w)| p + v * w));
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
        let (mut sum, mut n) = (Vec3::zeros().cast::<f64>(), 0u32);
        for f in 0..self.frames {
            if let (Some(fr), Some(p)) = (frame_at(self, f), self.point(f, target)) {
                sum += fr.local(p).cast::<f64>();
                n += 1;
            }
        }
        if n == 0 {
            return 0;
        }
        let local = (sum / f64::from(n)).cast::<f32>();
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

/// A parameter for [`Layout::write`]: group (1 POINT, 2 ANALOG, 3 TRIAL), name, type (-1 char,
/// 2 int16, 4 float), dimensions, and data encoded in the file's format.
type Record = (u8, String, i8, Vec<u8>, Vec<u8>);

/// A char parameter of group POINT: `rows` padded with spaces, or cut, to `width` bytes.
fn point_text(name: String, width: usize, rows: &[impl AsRef<str>]) -> Record {
    let padded = rows.iter().flat_map(|row| {
        let bytes = row.as_ref().bytes();
        bytes.chain(std::iter::repeat(b' ')).take(width)
    });
    let data = padded.collect();
    (1, name, -1, vec![width as u8, rows.len() as u8], data)
}

/// `TRIAL:name` holding `v` as two 16-bit words, low word first.
fn trial_field(format: Format, name: &str, v: u32) -> Record {
    let words = [v as u16, (v >> 16) as u16];
    let data = words
        .into_iter()
        .flat_map(|w| format.u16_bytes(w))
        .collect();
    (3, name.to_owned(), 2, vec![2], data)
}

/// What the header and the standard parameters of a file to write say.
struct Layout {
    format: Format,
    /// `POINT:SCALE`: negative for float storage.
    scale: f32,
    /// Frames per second.
    rate: f32,
    first_frame: usize,
    frames: usize,
    /// Number of points.
    points: usize,
    /// Analog channels, and samples per channel and frame.
    analog: [u16; 2],
}

impl Layout {
    /// The file: header; parameter section with the groups POINT, ANALOG and TRIAL, the
    /// parameters `POINT:USED`, `SCALE`, `RATE`, `FRAMES`, `DATA_START`, `ANALOG:USED` and
    /// `RATE`, then `records`; data section. `data` holds, frame by frame, x, y, z and residual
    /// of every point then the analog samples, in stored units (int16 storage truncates them).
    /// Counts beyond 65535 are written as 65535; a file with more than 65535 points or 255
    /// parameter blocks, as one that does not parse.
    fn write(&self, records: &[Record], data: impl IntoIterator<Item = f32>) -> Vec<u8> {
        let format = self.format;
        let word = |v: usize| {
            format
                .u16_bytes(u16::try_from(v).unwrap_or(u16::MAX))
                .to_vec()
        };
        let float = |v: f32| format.f32_bytes(v).to_vec();
        let [channels, per_channel] = self.analog;
        let section = |data_block: usize| {
            let standard = [
                (1, "USED", 2, word(self.points)),
                (1, "SCALE", 4, float(self.scale)),
                (1, "RATE", 4, float(self.rate)),
                (1, "FRAMES", 2, word(self.frames)),
                (1, "DATA_START", 2, word(data_block)),
                (2, "USED", 2, word(channels.into())),
                (2, "RATE", 4, float(self.rate * f32::from(per_channel))),
            ];
            let standard = standard
                .map(|(group, name, kind, data)| (group, name.to_owned(), kind, Vec::new(), data));
            let mut p = vec![1, KEY, 0, format.processor()];
            for (id, name) in [(1u8, "POINT"), (2, "ANALOG"), (3, "TRIAL")] {
                // A negative id makes a group; the link skips itself and an empty description.
                p.extend(
                    [name.len() as u8, id.wrapping_neg()]
                        .into_iter()
                        .chain(name.bytes()),
                );
                p.extend(word(3).into_iter().chain([0]));
            }
            let all: Vec<&Record> = standard.iter().chain(records).collect();
            for (k, (group, name, kind, dims, data)) in all.iter().enumerate() {
                // The link covers itself, type, dimensions, data and an empty description.
                let next = match k + 1 < all.len() {
                    true => 5 + dims.len() + data.len(),
                    false => 0,
                };
                p.extend([name.len() as u8, *group].into_iter().chain(name.bytes()));
                p.extend(
                    word(next)
                        .into_iter()
                        .chain([*kind as u8, dims.len() as u8]),
                );
                p.extend(dims.iter().chain(data).chain(&[0]));
            }
            p
        };
        let blocks = section(0).len().div_ceil(BLOCK);
        let data_block = 2 + blocks;
        let mut params = section(data_block);
        // What the 8-bit block count and 16-bit point count cannot hold gets a block count of 0,
        // which the reader rejects.
        let fits = blocks <= usize::from(u8::MAX) && self.points <= usize::from(u16::MAX);
        params[2] = if fits { blocks as u8 } else { 0 };
        params.resize(blocks * BLOCK, 0);

        // 16-bit frame numbers: a range ending past 65535 is written as 1..=frames.
        let last = self
            .first_frame
            .saturating_add(self.frames)
            .saturating_sub(1);
        let (first, last) = match u16::try_from(last) {
            Ok(_) => (self.first_frame, last),
            Err(_) => (1, self.frames),
        };
        // Header words 1-12: parameter block and key, points, analog samples per frame, first
        // and last frame, longest interpolated gap (not recorded), scale, data block, analog
        // samples per channel and frame, rate.
        let mut out = [
            vec![2, KEY],
            word(self.points),
            word(usize::from(channels) * usize::from(per_channel)),
            word(first),
            word(last),
            word(0),
            float(self.scale),
            word(data_block),
            word(per_channel.into()),
            float(self.rate),
        ]
        .concat();
        out.resize(BLOCK, 0);
        out.extend(params);
        for v in data {
            match self.scale < 0.0 {
                true => out.extend(format.f32_bytes(v)),
                false => out.extend(format.u16_bytes(v as i16 as u16)),
            }
        }
        out
    }
}

/// Right-handed orthonormal frame from three points: origin `a`, x toward `b`,
/// z = x × (c − a) normalised, y = z × x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Frame {
    /// Origin, the first point.
    pub origin: Vec3,
    /// Unit x, y and z axes.
    pub axes: [Vec3; 3],
}

impl Frame {
    /// `None` when the three points are (nearly) collinear or coincident.
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Option<Frame> {
        // `v / |v|`, or `None` when `|v|` is below 1e-9 or not finite.
        let unit = |v: Vec3| {
            let n = v.norm();
            (n > 1e-9 && n.is_finite()).then(|| v * (1.0 / n))
        };
        let x = unit(b - a)?;
        let z = unit(x.cross(&(c - a)))?;
        Some(Frame {
            origin: a,
            axes: [x, z.cross(&x), z],
        })
    }

    /// Coordinates of global point `p` in this frame.
    pub fn local(&self, p: Vec3) -> Vec3 {
        let d = p - self.origin;
        self.axes.map(|axis| d.dot(&axis)).into()
    }

    /// Global point with local coordinates `l`.
    pub fn global(&self, l: Vec3) -> Vec3 {
        let terms = self.axes.iter().zip(l.iter());
        terms.fold(self.origin, |p, (&axis, &s)| p + axis * s)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::path::PathBuf;

    const RATE: f32 = 50.0;
    const INT_SCALE: f32 = 0.25;
    const FLOAT_SCALE: f32 = -0.01;
    /// One analog channel sampled at twice the point rate.
    const ANALOG_PER_FRAME: u16 = 2;
    /// Written where an analog sample is: visible if the reader mistakes it for point data.
    const ANALOG_VALUE: f32 = -7777.0;
    const LABELS: [&str; 3] = ["LASI", "RASI", "Club:Head"];
    const FRAMES: usize = 4;
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
    fn sample(f: usize, m: usize) -> Vec3 {
        let (f, m) = (f as f32, m as f32);
        Vec3::new(1.5 * f + m, 100.0 - 2.0 * f, -0.25 * (m + f))
    }

    /// A small C3D file: 3 markers (labels split over LABELS and LABELS2), 4 frames, one
    /// missing sample, one analog channel; `extra` parameters are appended.
    fn write(format: Format, float: bool, units: &str, extra: &[Record]) -> Vec<u8> {
        let mut records = vec![
            point_text("UNITS".into(), units.len(), &[units]),
            point_text("LABELS".into(), 5, &LABELS[..2]),
            point_text("LABELS2".into(), 9, &LABELS[2..]),
        ];
        records.extend_from_slice(extra);
        let layout = Layout {
            format,
            scale: if float { FLOAT_SCALE } else { INT_SCALE },
            rate: RATE,
            first_frame: 1,
            frames: FRAMES,
            points: LABELS.len(),
            analog: [1, ANALOG_PER_FRAME],
        };
        let point = |f, m| {
            let xyz = if float {
                sample(f, m)
            } else {
                sample(f, m) / INT_SCALE
            };
            let residual = if (f, m) == MISSING { -1.0 } else { 0.0 };
            [xyz.x, xyz.y, xyz.z, residual]
        };
        let analog = [ANALOG_VALUE; ANALOG_PER_FRAME as usize];
        let frame = |f| {
            (0..LABELS.len())
                .flat_map(move |m| point(f, m))
                .chain(analog)
        };
        layout.write(&records, (0..FRAMES).flat_map(frame))
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
            assert_eq!(c.points[MISSING.0 * 3 + MISSING.1], Vec3::zeros());
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
    fn point_data_beyond_the_limits_is_refused_before_it_is_read() {
        // The golf fixture's shape at 0.001 Hz (30 h): resampling it took 1.8 GB.
        let mut slow = synthetic(109, 38, |f, m| Vec3::new(f as f32, m as f32, 1.0));
        slow.rate_hz = 0.001;
        let e = C3d::parse(&slow.to_bytes(Storage::Integer { scale: STEP })).unwrap_err();
        assert_eq!(e.kind, C3dErrorKind::Limit(LimitError::Rate(0.001)));
        let message = "point data: a frame rate of 0.001 Hz is outside the limits of 1 to 2000 Hz";
        assert!(e.to_string().ends_with(message), "{e}");
        // 70000 frames at 100 Hz: 700 s.
        let long = synthetic(70_000, 1, |_, _| Vec3::zeros());
        let e = C3d::parse(&long.to_bytes(Storage::Float)).unwrap_err();
        assert_eq!(e.kind, C3dErrorKind::Limit(LimitError::Duration(699.99)));
    }

    #[test]
    fn long_trials_use_the_trial_fields() {
        let extra = [
            trial_field(Format::Intel, "ACTUAL_START_FIELD", 1),
            trial_field(Format::Intel, "ACTUAL_END_FIELD", 70_000),
        ];
        let e = C3d::parse(&write(Format::Intel, false, "mm", &extra)).unwrap_err();
        assert!(
            e.to_string().contains("data section of 70000 frames"),
            "{e}"
        );
    }

    /// 0.5 mm steps: ±16.38 m.
    const STEP: f32 = 0.0005;

    /// Values the writer keeps: trimmed labels, points within ±16 m, zero where missing.
    fn any_c3d() -> impl Strategy<Value = C3d> {
        (0..6usize, 0..12usize).prop_flat_map(|(n, frames)| {
            let labels = prop::collection::vec("[A-Za-z0-9_:*]{0,12}", n);
            let xyz = prop::array::uniform3(-16.0f32..16.0);
            let samples = prop::collection::vec((xyz, prop::bool::weighted(0.8)), n * frames);
            let fields = (labels, samples, 1.0f32..2000.0, 0..1000u32);
            fields.prop_map(move |(labels, samples, rate_hz, first_frame)| C3d {
                labels,
                rate_hz,
                frames,
                first_frame,
                units_to_metres: 1.0,
                points: samples
                    .iter()
                    .map(|&(p, ok)| if ok { p.into() } else { Vec3::zeros() })
                    .collect(),
                valid: samples.iter().map(|&(_, ok)| ok).collect(),
            })
        })
    }

    proptest! {
        #[test]
        fn to_bytes_round_trips(c in any_c3d()) {
            prop_assert_eq!(&C3d::parse(&c.to_bytes(Storage::Float)).unwrap(), &c);
            let back = C3d::parse(&c.to_bytes(Storage::Integer { scale: STEP })).unwrap();
            let key = |c: &C3d| {
                (c.labels.clone(), c.rate_hz, c.frames, c.first_frame, c.valid.clone())
            };
            prop_assert_eq!(key(&back), key(&c));
            // Half a step, plus f32 rounding at 16 m.
            let worst = back.points.iter().zip(&c.points).map(|(a, b)| (a - b).amax());
            prop_assert!(worst.fold(0.0, f32::max) <= 0.5 * STEP + 64.0 * f32::EPSILON);
        }
    }

    #[test]
    fn to_bytes_handles_long_label_lists_long_trials_and_unstorable_samples() {
        // 300 labels of 200 bytes: split over LABELS and LABELS2 by the 16-bit record links.
        let mut wide = synthetic(2, 300, |f, m| Vec3::new(f as f32, m as f32, -0.5));
        wide.labels = (0..300).map(|m| format!("{m:_>200}")).collect();
        // 70000 frames: the frame range only fits the TRIAL fields (194 s at 360 Hz, within
        // MAX_DURATION_S).
        let mut long = synthetic(70_000, 1, |f, _| Vec3::new(0.0, 1e-4 * f as f32, 0.0));
        (long.first_frame, long.rate_hz) = (3, 360.0);
        for c in [wide, long] {
            assert_eq!(C3d::parse(&c.to_bytes(Storage::Float)).unwrap(), c);
        }
        let mut too_many = synthetic(1, 6000, |_, _| Vec3::zeros());
        too_many.labels = (0..6000).map(|m| format!("{m:_>24}")).collect();
        let e = C3d::parse(&too_many.to_bytes(Storage::Float)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "byte 514: parameter section header: expected at least one parameter block"
        );
        let mut late = synthetic(3, 3, |_, m| Vec3::new(15.5 + 0.5 * m as f32, 0.0, 0.0));
        late.first_frame = 65_534;
        late.points[0].y = f32::NAN;
        let back = C3d::parse(&late.to_bytes(Storage::Integer { scale: STEP })).unwrap();
        assert_eq!((back.frames, back.first_frame), (3, 1));
        // A NaN, then 16 m and 16.5 m against a range of 16.38 m.
        assert_eq!(back.valid[..3], [false, true, false]);
        assert_eq!(back.points[2], Vec3::zeros());
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

    fn synthetic(frames: usize, labels: usize, at: impl Fn(usize, usize) -> Vec3) -> C3d {
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
        let line = |f: usize| Vec3::new(0.1 * f as f32, 1.0 - 0.2 * f as f32, 0.05 * f as f32);
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
            Vec3::new(
                c * x - s * z + 0.01 * f as f32,
                y + 1.0,
                s * x + c * z - 0.02 * f as f32,
            )
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
                (p - want).norm() < TOLERANCE,
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
