//! posecoach-teachfile: the float weights files, without burn.
//!
//! The teacher and the distilled network (`.pcw`, what `--weights` loads; written by `posecoach
//! train --teacher` and `distill --distilled`) and the training checkpoints (`.pcckpt`, written
//! by `train --out` and `distill --out`) share one layout. The trainer (`posecoach-train`)
//! fills and reads the parts, burn records; this crate owns the layout, the checksum and the
//! header's bounds, so that `posecoach inspect` reads a file without linking burn.
//!
//! ```text
//! offset   bytes  what
//! 0        8      magic `PCTEACH3` (format version 3)
//! 8        72     header: 9 words, u64 little-endian, in [`WORDS`] order (see [`Header`])
//! 80       8      part count N: 1 a network, 4 a checkpoint, 5 a distilling checkpoint ([`Kind`])
//! 88       ..     N parts, each a length L (u64 little-endian) then L bytes
//! end - 4  4      CRC-32/ISO-HDLC (the zlib CRC, as core's blobs) of every byte before it, LE
//! ```
//!
//! [`decode`] checks, in this order and before it allocates anything but the list of (at most
//! five) parts: the length (at most [`MAX_FILE_BYTES`]), the magic and version, the CRC, every
//! header word against its bound ([`Header::check`]), the part count, and each part's length
//! against the bytes left; the parts must end exactly at the CRC. Versions 1 and 2 (magic
//! `PCTEACH1`, `PCTEACH2`) carried no checksum and are refused ([`Error::Legacy`]).
// Unsafe only in the tests' allocation probe (a global allocator).
#![cfg_attr(not(test), forbid(unsafe_code))]
#![cfg_attr(test, deny(unsafe_code))]
#![warn(missing_docs)]

use std::fmt;

/// First bytes of a file: the family, then the format version as a digit.
pub const MAGIC: [u8; 8] = *b"PCTEACH3";
/// The format version this crate reads and writes.
pub const VERSION: u8 = 3;
/// What every version's magic starts with.
const FAMILY: &[u8; 7] = b"PCTEACH";
/// Words of the header.
pub const HEADER_WORDS: usize = 9;
/// The header's words, in file order.
pub const WORDS: [&str; HEADER_WORDS] = [
    "step",
    "seed",
    "batch",
    "features",
    "heads",
    "kernel",
    "switches",
    "learning_rate",
    "prior",
];
/// Name of the part count in errors.
pub const PARTS_WORD: &str = "parts";
/// Bytes of a word.
const WORD: usize = 8;
/// Bytes of the CRC.
const CRC_LEN: usize = 4;
/// Bytes before the first part: magic, header words, part count.
const PREFIX: usize = MAGIC.len() + (HEADER_WORDS + 1) * WORD;
/// The shortest file: a prefix, one part's length (no file has fewer parts) and the CRC.
pub const MIN_FILE_BYTES: usize = PREFIX + WORD + CRC_LEN;
/// The CRC, slice-by-16: a 343 KB teacher checks in well under a millisecond.
const CRC: crc::Crc<u32, crc::Table<16>> =
    crc::Crc::<u32, crc::Table<16>>::new(&crc::CRC_32_ISO_HDLC);

/// Most training steps a header may state: 2^32, 13 years of steps at a tenth of a second
/// each, and far from where counting one more step could overflow.
pub const MAX_STEP: u64 = 1 << 32;
/// Most windows per batch: 128 times the default 8. A resumed run draws this many windows at
/// every step, so a header must not ask for more than a training run could hold.
pub const MAX_BATCH: u64 = 1024;
/// Fewest features per segment: even (the sinusoidal time encoding pairs them) and at least
/// one per head.
pub const MIN_FEATURES: u64 = 2;
/// Most features per segment: 8 times the trained teacher's 32. A network this wide holds
/// 5.3 million floats (21 MB) at kernel 3 and 24 million (97 MB) at [`MAX_KERNEL`]: the most
/// any header can make a loader build (its temporal convolutions grow as the square of the
/// width).
pub const MAX_FEATURES: u64 = 256;
/// Widest temporal kernel (odd, at least 1: padding keeps a sequence's length only for an odd
/// kernel): 15 already spans the 16 steps a window is downsampled to.
pub const MAX_KERNEL: u64 = 15;
/// The loss switches, bit `i` for the `i`-th; no other bit may be set.
pub const SWITCHES: [&str; 5] = [
    "cycle",
    "effectors",
    "adversarial",
    "joint_distances",
    "geometry",
];
/// Largest learning rate (it must also be finite and above 0): Adam moves every weight by
/// about the rate at each step, and weights start near 0.1, so at 1 training is noise.
pub const MAX_LEARNING_RATE: f64 = 1.0;
/// The geometric solutions a network corrects, by the `prior` word: 0 the analytic
/// retargeter's chords, 1 the rotation transfer.
pub const PRIORS: [&str; 2] = ["chords", "rotations"];
/// Largest file: 1 GiB, over twice a distilling checkpoint of the widest network (about
/// 400 MB: its network, its optimizer's two moments, the teacher file it distills).
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// What a file holds, by its part count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A network alone: the teacher or the distilled network (`.pcw`, `--weights`).
    Network,
    /// A training run's state: network, discriminator and both optimizers.
    Checkpoint,
    /// A distillation's state: a checkpoint and the teacher file it distills.
    Distilling,
}

impl Kind {
    /// Every kind.
    pub const ALL: [Kind; 3] = [Kind::Network, Kind::Checkpoint, Kind::Distilling];

    /// The kind of a file of `count` parts.
    pub fn from_count(count: u64) -> Option<Kind> {
        Kind::ALL
            .into_iter()
            .find(|k| k.parts().len() as u64 == count)
    }

    /// Its parts' names, in file order.
    pub fn parts(self) -> &'static [&'static str] {
        const PARTS: [&str; 5] = [
            "network",
            "discriminator",
            "network optimizer",
            "discriminator optimizer",
            "teacher file",
        ];
        match self {
            Kind::Network => &PARTS[..1],
            Kind::Checkpoint => &PARTS[..4],
            Kind::Distilling => &PARTS[..5],
        }
    }

    /// What it is called.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Network => "network",
            Kind::Checkpoint => "checkpoint",
            Kind::Distilling => "distilling checkpoint",
        }
    }
}

/// What a file says about itself: how its network was trained and its sizes. Every field is
/// within its bound once [`Header::check`] (which [`decode`] and [`encode`] call) passed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Header {
    /// Steps trained; at most [`MAX_STEP`].
    pub step: u64,
    /// Seeds the weights and every batch; any value.
    pub seed: u64,
    /// Windows per batch; 1 to [`MAX_BATCH`].
    pub batch: u64,
    /// Features per segment; even, [`MIN_FEATURES`] to [`MAX_FEATURES`].
    pub features: u64,
    /// Attention heads; at least 1 and dividing `features`.
    pub heads: u64,
    /// Temporal kernel; odd, 1 to [`MAX_KERNEL`].
    pub kernel: u64,
    /// Loss switches, bit `i` for [`SWITCHES`]`[i]`.
    pub switches: u64,
    /// Adam's learning rate (stored as its bits); finite, above 0, at most
    /// [`MAX_LEARNING_RATE`].
    pub learning_rate: f64,
    /// Index into [`PRIORS`].
    pub prior: u64,
}

impl Header {
    /// Its words, in file order.
    pub fn to_words(&self) -> [u64; HEADER_WORDS] {
        [
            self.step,
            self.seed,
            self.batch,
            self.features,
            self.heads,
            self.kernel,
            self.switches,
            self.learning_rate.to_bits(),
            self.prior,
        ]
    }

    /// The header of `words`, checked.
    ///
    /// # Errors
    /// As [`Header::check`].
    pub fn from_words(w: [u64; HEADER_WORDS]) -> Result<Header, Error> {
        let header = Header {
            step: w[0],
            seed: w[1],
            batch: w[2],
            features: w[3],
            heads: w[4],
            kernel: w[5],
            switches: w[6],
            learning_rate: f64::from_bits(w[7]),
            prior: w[8],
        };
        header.check()?;
        Ok(header)
    }

    /// Checks every word against its bound, in file order.
    ///
    /// # Errors
    /// [`Error::Word`] naming the first word out of bounds, its value and its bound.
    pub fn check(&self) -> Result<(), Error> {
        let (f, h, k) = (self.features, self.heads, self.kernel);
        let lr = self.learning_rate;
        let checks = [
            (self.step <= MAX_STEP, Bound::Step),
            (true, Bound::Seed),
            ((1..=MAX_BATCH).contains(&self.batch), Bound::Batch),
            (
                (MIN_FEATURES..=MAX_FEATURES).contains(&f) && f % 2 == 0,
                Bound::Features,
            ),
            (
                (1..=f).contains(&h) && f % h == 0,
                Bound::Heads { features: f },
            ),
            ((1..=MAX_KERNEL).contains(&k) && k % 2 == 1, Bound::Kernel),
            (self.switches >> SWITCHES.len() == 0, Bound::Switches),
            (
                lr.is_finite() && lr > 0.0 && lr <= MAX_LEARNING_RATE,
                Bound::LearningRate,
            ),
            (self.prior < PRIORS.len() as u64, Bound::Prior),
        ];
        let words = self.to_words();
        match checks.iter().position(|(ok, _)| !ok) {
            None => Ok(()),
            Some(i) => Err(Error::Word {
                word: WORDS[i],
                value: words[i],
                bound: checks[i].1,
            }),
        }
    }

    /// The names of the switches that are on.
    pub fn switches_on(&self) -> impl Iterator<Item = &'static str> + '_ {
        SWITCHES
            .iter()
            .enumerate()
            .filter(|&(i, _)| self.switches >> i & 1 == 1)
            .map(|(_, &name)| name)
    }
}

/// The bound a word breaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bound {
    /// [`Header::step`]'s.
    Step,
    /// [`Header::seed`]'s: none (every value is a seed).
    Seed,
    /// [`Header::batch`]'s.
    Batch,
    /// [`Header::features`]'.
    Features,
    /// [`Header::heads`]', given the features.
    #[allow(missing_docs)]
    Heads { features: u64 },
    /// [`Header::kernel`]'s.
    Kernel,
    /// [`Header::switches`]'.
    Switches,
    /// [`Header::learning_rate`]'s.
    LearningRate,
    /// [`Header::prior`]'s.
    Prior,
    /// The part count's.
    Parts,
}

impl fmt::Display for Bound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Bound::Step => write!(f, "at most {MAX_STEP}"),
            Bound::Seed => f.write_str("any value"),
            Bound::Batch => write!(f, "from 1 to {MAX_BATCH}"),
            Bound::Features => write!(f, "even, from {MIN_FEATURES} to {MAX_FEATURES}"),
            Bound::Heads { features } => {
                write!(f, "from 1 to the features ({features}), dividing them")
            }
            Bound::Kernel => write!(f, "odd, from 1 to {MAX_KERNEL}"),
            Bound::Switches => write!(
                f,
                "only bits 0 to {} set ({})",
                SWITCHES.len() - 1,
                SWITCHES.join(", ")
            ),
            Bound::LearningRate => write!(f, "finite, above 0, at most {MAX_LEARNING_RATE}"),
            Bound::Prior => write!(f, "0 ({}) or 1 ({})", PRIORS[0], PRIORS[1]),
            Bound::Parts => {
                f.write_str("1 (a network), 4 (a checkpoint) or 5 (a distilling checkpoint)")
            }
        }
    }
}

/// Why bytes are not a sound float weights file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error {
    /// Larger than [`MAX_FILE_BYTES`].
    #[allow(missing_docs)]
    TooLarge { len: u64 },
    /// Shorter than [`MIN_FILE_BYTES`], or than its magic.
    #[allow(missing_docs)]
    Truncated { len: usize },
    /// Not a float weights file: no `PCTEACH` magic.
    Magic,
    /// Format version 1 or 2, from before the files carried a checksum.
    #[allow(missing_docs)]
    Legacy { version: u8 },
    /// A `PCTEACH` magic whose version byte is not one this crate knows.
    #[allow(missing_docs)]
    UnknownVersion { byte: u8 },
    /// The CRC does not match: the bytes are damaged.
    #[allow(missing_docs)]
    Checksum { stored: u32, computed: u32 },
    /// A header word, or the part count ([`PARTS_WORD`]), out of its bound.
    #[allow(missing_docs)]
    Word {
        word: &'static str,
        value: u64,
        bound: Bound,
    },
    /// The file ends before part `part`'s length (counting from 0).
    #[allow(missing_docs)]
    MissingPart { part: usize },
    /// Part `part` (counting from 0) is longer than the bytes left before the CRC.
    #[allow(missing_docs)]
    PartLength {
        part: usize,
        length: u64,
        left: usize,
    },
    /// Bytes between the last part and the CRC.
    #[allow(missing_docs)]
    Trailing { bytes: usize },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::TooLarge { len } => write!(
                f,
                "{len} bytes, more than any posecoach weights file ({MAX_FILE_BYTES} at most)"
            ),
            Error::Truncated { len } => write!(
                f,
                "truncated: {len} bytes, fewer than the smallest file ({MIN_FILE_BYTES})"
            ),
            Error::Magic => f.write_str("not a posecoach float weights file (no PCTEACH magic)"),
            Error::Legacy { version } => write!(
                f,
                "format version {version} (magic PCTEACH{version}), from before these files \
                 carried a checksum, is no longer read (this posecoach reads version \
                 {VERSION}): re-save the file as version {VERSION}, or train it again"
            ),
            Error::UnknownVersion { byte } => write!(
                f,
                "unknown format version (magic PCTEACH then byte {byte:#04x}); this posecoach \
                 reads version {VERSION}"
            ),
            Error::Checksum { stored, computed } => write!(
                f,
                "damaged: its CRC-32 is {computed:#010x}, the file says {stored:#010x}"
            ),
            Error::Word { word, value, bound } => {
                write!(f, "header word `{word}` is ")?;
                match bound {
                    Bound::LearningRate => {
                        write!(f, "{} (bits {value:#x})", f64::from_bits(value))?
                    }
                    Bound::Switches => write!(f, "{value:#b}")?,
                    _ => write!(f, "{value}")?,
                }
                write!(f, "; it must be {bound}")
            }
            Error::MissingPart { part } => {
                write!(f, "the file ends before part {part}'s length")
            }
            Error::PartLength { part, length, left } => write!(
                f,
                "part {part} says it is {length} bytes long, but {left} are left before the \
                 checksum"
            ),
            Error::Trailing { bytes } => {
                write!(f, "{bytes} bytes after the last part, before the checksum")
            }
        }
    }
}

impl std::error::Error for Error {}

/// A checked file: its header, what it holds and its parts, in place.
#[derive(Clone, Debug, PartialEq)]
pub struct TeachFile<'a> {
    /// The header, every word within its bound.
    pub header: Header,
    /// What it holds; as many parts as [`Kind::parts`] names.
    pub kind: Kind,
    /// The parts' bytes.
    pub parts: Vec<&'a [u8]>,
    /// Its CRC-32, which matched.
    pub crc: u32,
}

/// Whether `bytes` start as a float weights file of any version (what `inspect` dispatches on).
pub fn is_float_weights(bytes: &[u8]) -> bool {
    bytes.starts_with(FAMILY)
}

/// The CRC-32/ISO-HDLC a file stores of every byte before its last four.
pub fn checksum(bytes: &[u8]) -> u32 {
    CRC.checksum(bytes)
}

/// Checks `bytes` as a float weights file and views its parts.
///
/// # Errors
/// The first of the checks of the crate's documentation that fails.
pub fn decode(bytes: &[u8]) -> Result<TeachFile<'_>, Error> {
    let len = bytes.len();
    if len as u64 > MAX_FILE_BYTES {
        return Err(Error::TooLarge { len: len as u64 });
    }
    let Some(magic) = bytes.get(..MAGIC.len()) else {
        return Err(match FAMILY.starts_with(&bytes[..len.min(FAMILY.len())]) {
            true => Error::Truncated { len },
            false => Error::Magic,
        });
    };
    if magic != MAGIC {
        return Err(match (magic.strip_prefix(FAMILY.as_slice()), magic[7]) {
            (None, _) => Error::Magic,
            (Some(_), b @ b'1'..=b'2') => Error::Legacy { version: b - b'0' },
            (Some(_), byte) => Error::UnknownVersion { byte },
        });
    }
    if len < MIN_FILE_BYTES {
        return Err(Error::Truncated { len });
    }
    let (body, stored) = bytes.split_at(len - CRC_LEN);
    let stored = u32::from_le_bytes([stored[0], stored[1], stored[2], stored[3]]);
    let computed = checksum(body);
    if stored != computed {
        return Err(Error::Checksum { stored, computed });
    }
    let mut reader = Reader(&body[MAGIC.len()..]);
    let mut words = [0u64; HEADER_WORDS];
    for w in &mut words {
        *w = reader.word().ok_or(Error::Truncated { len })?;
    }
    let header = Header::from_words(words)?;
    let count = reader.word().ok_or(Error::Truncated { len })?;
    let kind = Kind::from_count(count).ok_or(Error::Word {
        word: PARTS_WORD,
        value: count,
        bound: Bound::Parts,
    })?;
    let mut parts = Vec::with_capacity(kind.parts().len());
    for part in 0..kind.parts().len() {
        let length = reader.word().ok_or(Error::MissingPart { part })?;
        let left = reader.0.len();
        parts.push(
            reader
                .take(length)
                .ok_or(Error::PartLength { part, length, left })?,
        );
    }
    match reader.0.len() {
        0 => Ok(TeachFile {
            header,
            kind,
            parts,
            crc: computed,
        }),
        bytes => Err(Error::Trailing { bytes }),
    }
}

/// A file of `header` and `parts`, with its CRC.
///
/// # Errors
/// As [`Header::check`]; [`Error::Word`] for a part count that is no [`Kind`]'s;
/// [`Error::TooLarge`] for a file larger than [`MAX_FILE_BYTES`].
pub fn encode<P: AsRef<[u8]>>(header: &Header, parts: &[P]) -> Result<Vec<u8>, Error> {
    header.check()?;
    let count = parts.len() as u64;
    if Kind::from_count(count).is_none() {
        return Err(Error::Word {
            word: PARTS_WORD,
            value: count,
            bound: Bound::Parts,
        });
    }
    let len = PREFIX + parts.iter().map(|p| WORD + p.as_ref().len()).sum::<usize>() + CRC_LEN;
    if len as u64 > MAX_FILE_BYTES {
        return Err(Error::TooLarge { len: len as u64 });
    }
    let mut out = Vec::with_capacity(len);
    out.extend(MAGIC);
    out.extend(header.to_words().iter().flat_map(|w| w.to_le_bytes()));
    out.extend(count.to_le_bytes());
    for part in parts {
        let part = part.as_ref();
        out.extend((part.len() as u64).to_le_bytes());
        out.extend(part);
    }
    out.extend(checksum(&out).to_le_bytes());
    Ok(out)
}

/// Reads a file's bytes front to back.
struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, n: u64) -> Option<&'a [u8]> {
        let (head, tail) = self.0.split_at_checked(usize::try_from(n).ok()?)?;
        self.0 = tail;
        Some(head)
    }

    fn word(&mut self) -> Option<u64> {
        let (head, tail) = self.0.split_first_chunk::<WORD>()?;
        self.0 = tail;
        Some(u64::from_le_bytes(*head))
    }
}

#[cfg(test)]
mod tests;
