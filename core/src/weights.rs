//! The quantized retargeter's weights as the device stores them: a [`blob`] (`.pcw`) read in
//! place, checked once by [`Weights::from_bytes`] so that nothing after it can fail.
//!
//! Header (postcard): format version, [`Architecture`], the activation [`Scales`] calibrated
//! on golf, and [`Training`] metadata (the skeleton formats among them). Payload: for each
//! [`Dense`] layer in [`Dense::ALL`] order, four arrays, each starting at a multiple of
//! [`blob::ALIGN`] bytes (zeros between):
//!
//! | array | type | length | holds |
//! | --- | --- | --- | --- |
//! | weights | `i8` | outputs × inputs | symmetric per output channel (a convolution's row: kernel tap major, then the group's inputs) |
//! | bias | `i32` | rows × outputs | in accumulator units; one row, or one per frame or segment ([`Dense::bias_rows`]) |
//! | scale | `f32` | outputs | the real value of one accumulator unit |
//! | requant | [`Requant`] | outputs | accumulator unit over the output's int8 scale |
//!
//! then the [`Table`]s of the segment tokens' attention, `f32`. All little-endian.
//!
//! A layer whose int8 input has per-channel scales (the motion features) has them folded into
//! its weights: its accumulators are in the same units whatever the input channel.

use crate::blob::{self, Blob, BlobError};
use crate::int8::{Requant, MAX_KERNEL};
use crate::skeleton::Segment;
use heapless::{String as HString, Vec as HVec};
use serde::{Deserialize, Serialize};

/// Magic of a weights blob.
pub const MAGIC: [u8; 4] = *b"PCW\x01";
/// Version of the header this build reads and writes.
pub const VERSION: u16 = 1;
/// Largest magnitude of a stored bias: an accumulator starts from its bias and adds a field's
/// products (below `2^23`), so it never wraps.
pub const MAX_BIAS: u32 = 1 << 30;
/// Most features per segment the core's scratch holds (the distilled network's `d`).
pub const MAX_FEATURES: usize = 16;
/// Most attention heads.
pub const MAX_HEADS: usize = 8;
/// Frames in a window.
pub const WINDOW: usize = 64;
/// Body segments: the motion encoder's tokens.
pub const SEGMENTS: usize = Segment::ALL.len();
/// Motion features per joint and frame: position relative to the parent, and its change.
pub const MOTION_CHANNELS: usize = 6;
/// Inputs of the motion encoder's first layer: the motion features and two zeros, so that
/// every int8 layer's rows are whole four-byte words.
pub const MOTION_INPUTS: usize = MOTION_CHANNELS.next_multiple_of(4);
/// Rest features per joint: offset from the parent, and position from the root.
pub const REST_CHANNELS: usize = 6;
/// Quaternion components the decoder outputs per joint.
pub const QUATERNION: usize = 4;
/// Longest training name, bytes.
pub const MAX_NAME: usize = 32;
/// Most skeleton formats listed as trained on.
pub const MAX_FORMATS: usize = 8;
/// Most bytes a header takes.
pub const MAX_HEADER: usize = 256;

#[cfg(target_endian = "big")]
compile_error!("weights store little-endian values and are viewed in place");

/// Why bytes are not usable weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WeightsError {
    /// Not a sound blob.
    Blob(BlobError),
    /// The header does not decode, or has bytes left over.
    Header,
    /// Written by another version of the format.
    Version(u16),
    /// Sizes this build cannot run (features over [`MAX_FEATURES`], another window, …).
    Architecture,
    /// An activation scale is not a positive finite number.
    Scale,
    /// The payload is not the architecture's tensors, or the blob is not 4-byte aligned.
    Payload,
    /// A stored value is out of range: a non-finite or non-positive scale, a non-finite table
    /// entry, a bias beyond [`MAX_BIAS`], or a requantization [`Requant::new`] cannot make.
    Value(Dense),
}

impl core::fmt::Display for WeightsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            WeightsError::Blob(e) => write!(f, "weights: {e}"),
            WeightsError::Header => f.write_str("weights: undecodable header"),
            WeightsError::Version(v) => write!(
                f,
                "weights format version {v}; this build reads version {VERSION}"
            ),
            WeightsError::Architecture => write!(
                f,
                "weights: sizes this build cannot run (at most {MAX_FEATURES} features and \
                 {MAX_HEADS} heads, kernel at most {MAX_KERNEL}, {WINDOW}-frame windows, \
                 {SEGMENTS} segments)"
            ),
            WeightsError::Scale => f.write_str("weights: an activation scale is not positive"),
            WeightsError::Payload => f.write_str(
                "weights: payload is not the architecture's tensors at a 4-byte-aligned address",
            ),
            WeightsError::Value(layer) => {
                write!(f, "weights: layer {} holds an invalid value", layer.name())
            }
        }
    }
}

impl core::error::Error for WeightsError {}

impl From<BlobError> for WeightsError {
    fn from(e: BlobError) -> WeightsError {
        WeightsError::Blob(e)
    }
}

/// The network's sizes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Architecture {
    /// Features per segment (`d`).
    pub features: u16,
    /// Attention heads (`d` divides into them).
    pub heads: u16,
    /// Kernel of the temporal convolutions (odd).
    pub kernel: u16,
    /// Frames per window ([`WINDOW`]).
    pub window: u16,
    /// Body segments ([`SEGMENTS`]).
    pub segments: u16,
    /// Frame rate the network runs at, Hz.
    pub rate_hz: f32,
}

impl Architecture {
    /// Whether this build can run it.
    pub fn is_supported(&self) -> bool {
        let (d, heads, kernel) = (
            usize::from(self.features),
            usize::from(self.heads),
            usize::from(self.kernel),
        );
        (2..=MAX_FEATURES).contains(&d)
            && d.is_multiple_of(2)
            && (1..=MAX_HEADS).contains(&heads)
            && d.is_multiple_of(heads)
            && kernel % 2 == 1
            && kernel <= MAX_KERNEL
            && usize::from(self.window) == WINDOW
            && usize::from(self.segments) == SEGMENTS
            && self.rate_hz.is_finite()
            && self.rate_hz > 0.0
    }

    /// Features per segment.
    pub fn d(&self) -> usize {
        usize::from(self.features)
    }
}

/// The int8 scales (real value of one unit) of the activations between layers, calibrated
/// as the largest magnitude each takes on golf windows over 127.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Scales {
    /// Each motion feature channel ([`MOTION_CHANNELS`]).
    pub motion: [f32; MOTION_CHANNELS],
    /// The motion encoder's hidden layer.
    pub hidden: f32,
    /// Joint embeddings with the time encoding: the attention's keys and values' input.
    pub joints: f32,
    /// The attention's context, before its output layer.
    pub context: f32,
    /// Segment tokens after attention: the first convolution's input.
    pub segments: f32,
    /// After the first downsampling convolution.
    pub down_1: f32,
    /// After the second, before its residual.
    pub down_2: f32,
    /// The motion feature plus the skeleton feature: the decoder's input.
    pub fused: f32,
    /// After the first decoder convolution.
    pub up_1: f32,
    /// After the second: the joint decoder's and the root's input.
    pub up_2: f32,
    /// The joint decoder's hidden layer.
    pub decoder: f32,
}

impl Scales {
    fn all(&self) -> impl Iterator<Item = f32> + '_ {
        self.motion.iter().copied().chain([
            self.hidden,
            self.joints,
            self.context,
            self.segments,
            self.down_1,
            self.down_2,
            self.fused,
            self.up_1,
            self.up_2,
            self.decoder,
        ])
    }
}

/// Where the weights came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Training {
    /// What the model was called (its checkpoint's stem).
    pub name: HString<MAX_NAME>,
    /// Training (for a distilled network: distillation) steps.
    pub steps: u32,
    /// Seed of the run.
    pub seed: u64,
    /// Golf windows the scales were calibrated on.
    pub calibration_windows: u32,
    /// Skeleton formats trained on.
    pub formats: HVec<crate::format::Format, MAX_FORMATS>,
}

/// Everything before the payload.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// [`VERSION`].
    pub version: u16,
    /// The sizes.
    pub architecture: Architecture,
    /// The activations' scales.
    pub scales: Scales,
    /// Provenance.
    pub training: Training,
}

/// The network's layers with int8 weights, in payload order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Dense {
    /// Skeleton encoder, per joint: rest features → hidden (run in `f32`).
    SkeletonHidden,
    /// Skeleton encoder, per joint: hidden → joint feature.
    SkeletonOutput,
    /// Skeleton encoder, per segment: mean joint feature → segment feature.
    SkeletonSegment,
    /// Motion encoder, per joint and frame: motion features (padded to [`MOTION_INPUTS`]) →
    /// hidden.
    MotionFeatures,
    /// The same layer's rest-feature columns (once per source joint, in `f32`).
    MotionRest,
    /// Motion encoder: hidden → joint embedding; one bias row per frame (the time encoding).
    MotionOutput,
    /// Attention values, applied per head to the attention-weighted mean of the joints'
    /// embeddings (the weights sum to one, so this is the mean of the joints' values).
    Value,
    /// Attention output; one bias row per segment (its token, the residual).
    Output,
    /// First stride-2 convolution within segments.
    Down1,
    /// Second stride-2 convolution within segments.
    Down2,
    /// First decoder convolution.
    Up1,
    /// Second decoder convolution.
    Up2,
    /// Joint decoder, per target joint and frame: its segment's feature → hidden.
    DecoderFeatures,
    /// The same layer's rest-feature columns (once per target joint, in `f32`).
    DecoderRest,
    /// Joint decoder: hidden → the quaternion correction.
    DecoderOutput,
    /// All segments' features → the root's correction.
    Root,
}

impl Dense {
    /// Every layer, in payload order.
    pub const ALL: [Dense; 16] = [
        Dense::SkeletonHidden,
        Dense::SkeletonOutput,
        Dense::SkeletonSegment,
        Dense::MotionFeatures,
        Dense::MotionRest,
        Dense::MotionOutput,
        Dense::Value,
        Dense::Output,
        Dense::Down1,
        Dense::Down2,
        Dense::Up1,
        Dense::Up2,
        Dense::DecoderFeatures,
        Dense::DecoderRest,
        Dense::DecoderOutput,
        Dense::Root,
    ];

    /// Its name in tables and errors.
    pub const fn name(self) -> &'static str {
        match self {
            Dense::SkeletonHidden => "skeleton.hidden",
            Dense::SkeletonOutput => "skeleton.output",
            Dense::SkeletonSegment => "skeleton.segment",
            Dense::MotionFeatures => "motion.features",
            Dense::MotionRest => "motion.rest",
            Dense::MotionOutput => "motion.output",
            Dense::Value => "attention.value",
            Dense::Output => "attention.output",
            Dense::Down1 => "down_1",
            Dense::Down2 => "down_2",
            Dense::Up1 => "up_1",
            Dense::Up2 => "up_2",
            Dense::DecoderFeatures => "decoder.features",
            Dense::DecoderRest => "decoder.rest",
            Dense::DecoderOutput => "decoder.output",
            Dense::Root => "root",
        }
    }

    /// Inputs per output channel (a convolution's: kernel × features).
    pub fn inputs(self, a: &Architecture) -> usize {
        let d = a.d();
        match self {
            Dense::SkeletonHidden | Dense::MotionRest | Dense::DecoderRest => REST_CHANNELS,
            Dense::MotionFeatures => MOTION_INPUTS,
            Dense::Down1 | Dense::Down2 | Dense::Up1 | Dense::Up2 => usize::from(a.kernel) * d,
            Dense::Root => SEGMENTS * d,
            _ => d,
        }
    }

    /// Output channels.
    pub fn outputs(self, a: &Architecture) -> usize {
        let d = a.d();
        match self {
            Dense::Down1 | Dense::Down2 | Dense::Up1 | Dense::Up2 => SEGMENTS * d,
            Dense::DecoderOutput => QUATERNION,
            Dense::Root => 3,
            _ => d,
        }
    }

    /// Rows of biases: one per frame for the motion encoder's output (the time encoding
    /// folded in), one per segment for the attention's output (the token folded in), else one.
    pub fn bias_rows(self) -> usize {
        match self {
            Dense::MotionOutput => WINDOW,
            Dense::Output => SEGMENTS,
            _ => 1,
        }
    }
}

/// `f32` tables of the segment tokens' attention. A token's query is a constant, so its logit
/// for a joint is a fixed linear function of the joint's embedding: the keys are never
/// computed, only these dot products.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Table {
    /// `[segment][head][feature]`: the key layer's weights seen through each token's query
    /// (divided by the square root of the head's width, times the embeddings' int8 scale):
    /// a joint's logit is this row's dot product with its int8 embedding, plus the offset.
    JointLogits,
    /// `[segment][head]`: the key layer's bias seen through each token's query.
    LogitOffsets,
    /// `[segment][head]`: each token's logit for its own key.
    TokenLogits,
    /// `[segment][feature]`: each token's value.
    TokenValues,
}

impl Table {
    /// Every table, in payload order.
    pub const ALL: [Table; 4] = [
        Table::JointLogits,
        Table::LogitOffsets,
        Table::TokenLogits,
        Table::TokenValues,
    ];

    /// Its name in tables.
    pub const fn name(self) -> &'static str {
        match self {
            Table::JointLogits => "tokens.joint_logits",
            Table::LogitOffsets => "tokens.logit_offsets",
            Table::TokenLogits => "tokens.token_logits",
            Table::TokenValues => "tokens.values",
        }
    }

    /// Its length for `a`.
    pub fn len(self, a: &Architecture) -> usize {
        let heads = usize::from(a.heads);
        match self {
            Table::JointLogits => SEGMENTS * heads * a.d(),
            Table::LogitOffsets | Table::TokenLogits => SEGMENTS * heads,
            Table::TokenValues => SEGMENTS * a.d(),
        }
    }
}

/// One layer's stored arrays.
#[derive(Clone, Copy, Debug)]
pub struct Tensors<'a> {
    /// Outputs × inputs.
    pub weights: &'a [i8],
    /// [`Dense::bias_rows`] × outputs, accumulator units.
    pub bias: &'a [i32],
    /// Per output: the real value of one accumulator unit.
    pub scale: &'a [f32],
    /// Per output: to the next activation's int8 scale.
    pub requant: &'a [Requant],
}

impl<'a> Tensors<'a> {
    /// Bias row `row` (frame or segment); the last row past the end.
    pub fn bias_row(&self, row: usize) -> &'a [i32] {
        let n = self.scale.len();
        let rows = self.bias.len() / n.max(1);
        let row = row.min(rows.saturating_sub(1));
        self.bias.get(row * n..(row + 1) * n).unwrap_or(&[])
    }
}

/// Checked weights, viewing their blob's arrays in place.
#[derive(Clone, Debug)]
pub struct Weights<'a> {
    header: Header,
    layers: [Tensors<'a>; Dense::ALL.len()],
    tables: [&'a [f32]; Table::ALL.len()],
}

/// Bytes each element of a layer's arrays takes, in payload order.
const ARRAYS: [usize; 4] = [1, 4, 4, 8];

impl<'a> Weights<'a> {
    /// Checks and reads a weights blob; after it succeeds every accessor's arrays have the
    /// lengths the architecture gives. The blob must start at a 4-byte-aligned address
    /// ([`blob::Aligned`] gives one).
    ///
    /// # Errors
    /// Any [`WeightsError`].
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Weights<'a>, WeightsError> {
        let blob = Blob::open(bytes, MAGIC)?;
        let (header, rest) =
            postcard::take_from_bytes::<Header>(blob.header).map_err(|_| WeightsError::Header)?;
        if !rest.is_empty() {
            return Err(WeightsError::Header);
        }
        if header.version != VERSION {
            return Err(WeightsError::Version(header.version));
        }
        let a = header.architecture;
        if !a.is_supported() {
            return Err(WeightsError::Architecture);
        }
        if !header.scales.all().all(positive) {
            return Err(WeightsError::Scale);
        }
        if blob.payload.len() != payload_len(&a) {
            return Err(WeightsError::Payload);
        }
        let mut at = Cursor {
            bytes: blob.payload,
            at: 0,
        };
        let empty = Tensors {
            weights: &[],
            bias: &[],
            scale: &[],
            requant: &[],
        };
        let mut layers = [empty; Dense::ALL.len()];
        for (slot, layer) in layers.iter_mut().zip(Dense::ALL) {
            let (n, m) = (layer.outputs(&a), layer.inputs(&a));
            let tensors = Tensors {
                weights: at.take(n * m)?,
                bias: at.take(layer.bias_rows() * n)?,
                scale: at.take(n)?,
                requant: at.take(n)?,
            };
            if !tensors.scale.iter().copied().all(positive)
                || !tensors.requant.iter().all(|r| r.is_valid())
                || tensors.bias.iter().any(|b| b.unsigned_abs() > MAX_BIAS)
            {
                return Err(WeightsError::Value(layer));
            }
            *slot = tensors;
        }
        let mut tables: [&[f32]; Table::ALL.len()] = [&[]; Table::ALL.len()];
        for (slot, table) in tables.iter_mut().zip(Table::ALL) {
            *slot = at.take(table.len(&a))?;
            if !slot.iter().all(|v| v.is_finite()) {
                return Err(WeightsError::Payload);
            }
        }
        Ok(Weights {
            header,
            layers,
            tables,
        })
    }

    /// The header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The sizes.
    pub fn architecture(&self) -> &Architecture {
        &self.header.architecture
    }

    /// The activation scales.
    pub fn scales(&self) -> &Scales {
        &self.header.scales
    }

    /// A layer's arrays.
    pub fn layer(&self, layer: Dense) -> &Tensors<'a> {
        &self.layers[layer as usize]
    }

    /// A token table, segments × features.
    pub fn table(&self, table: Table) -> &'a [f32] {
        self.tables[table as usize]
    }
}

fn positive(v: f32) -> bool {
    v.is_finite() && v > 0.0
}

/// Bytes of a payload for `a`.
pub fn payload_len(a: &Architecture) -> usize {
    let aligned = |n: usize| n.next_multiple_of(blob::ALIGN);
    let layers: usize = Dense::ALL
        .iter()
        .map(|l| {
            let (n, m) = (l.outputs(a), l.inputs(a));
            let counts = [n * m, l.bias_rows() * n, n, n];
            counts
                .iter()
                .zip(ARRAYS)
                .map(|(c, b)| aligned(c * b))
                .sum::<usize>()
        })
        .sum();
    layers
        + Table::ALL
            .iter()
            .map(|t| aligned(t.len(a) * 4))
            .sum::<usize>()
}

/// Bytes [`write()`] may need for `a`.
pub fn max_len(a: &Architecture) -> usize {
    blob::max_len(MAX_HEADER, payload_len(a))
}

/// Reads consecutive aligned arrays out of a payload.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take<T: bytemuck::Pod>(&mut self, count: usize) -> Result<&'a [T], WeightsError> {
        let len = count * core::mem::size_of::<T>();
        let bytes = self
            .bytes
            .get(self.at..self.at + len)
            .ok_or(WeightsError::Payload)?;
        self.at += len.next_multiple_of(blob::ALIGN);
        bytemuck::try_cast_slice(bytes).map_err(|_| WeightsError::Payload)
    }
}

/// Writes weights with `header`, `layers` (in [`Dense::ALL`] order) and `tables` (in
/// [`Table::ALL`] order) into `out`, at most [`max_len`] bytes; returns its length.
///
/// # Errors
/// [`WeightsError::Architecture`], [`WeightsError::Payload`] if an array's length is not the
/// architecture's, [`BlobError::TooSmall`] if `out` is short.
pub fn write(
    header: &Header,
    layers: &[Tensors<'_>; Dense::ALL.len()],
    tables: &[&[f32]; Table::ALL.len()],
    out: &mut [u8],
) -> Result<usize, WeightsError> {
    let a = header.architecture;
    if !a.is_supported() {
        return Err(WeightsError::Architecture);
    }
    blob::write_with(MAGIC, header, payload_len(&a), out, |payload| {
        let mut at = 0;
        let mut put = |bytes: &[u8]| -> Result<(), WeightsError> {
            payload
                .get_mut(at..at + bytes.len())
                .ok_or(WeightsError::Payload)?
                .copy_from_slice(bytes);
            at += bytes.len().next_multiple_of(blob::ALIGN);
            Ok(())
        };
        for (layer, t) in Dense::ALL.iter().zip(layers) {
            let (n, m) = (layer.outputs(&a), layer.inputs(&a));
            if t.weights.len() != n * m
                || t.bias.len() != layer.bias_rows() * n
                || t.scale.len() != n
                || t.requant.len() != n
            {
                return Err(WeightsError::Payload);
            }
            put(bytemuck::cast_slice(t.weights))?;
            put(bytemuck::cast_slice(t.bias))?;
            put(bytemuck::cast_slice(t.scale))?;
            put(bytemuck::cast_slice(t.requant))?;
        }
        for (values, table) in tables.iter().zip(Table::ALL) {
            if values.len() != table.len(&a) {
                return Err(WeightsError::Payload);
            }
            put(bytemuck::cast_slice(values))?;
        }
        Ok(())
    })
}

/// Made-up weights for tests.
#[cfg(test)]
pub(crate) mod testing {
    use super::*;
    use std::vec::Vec;

    /// The distilled network's sizes.
    pub(crate) const DISTILLED: Architecture = Architecture {
        features: 16,
        heads: 2,
        kernel: 3,
        window: WINDOW as u16,
        segments: SEGMENTS as u16,
        rate_hz: 30.0,
    };

    pub(crate) fn header(a: Architecture) -> Header {
        let s = 0.02;
        Header {
            version: VERSION,
            architecture: a,
            scales: Scales {
                motion: [0.004; MOTION_CHANNELS],
                hidden: s,
                joints: s,
                context: s,
                segments: s,
                down_1: s,
                down_2: s,
                fused: s,
                up_1: s,
                up_2: s,
                decoder: s,
            },
            training: Training {
                name: HString::try_from("test").unwrap(),
                steps: 2,
                seed: 3,
                calibration_windows: 4,
                formats: HVec::from_slice(&[crate::format::Format::H36m17]).unwrap(),
            },
        }
    }

    /// A blob of `a` with pseudo-random values from `seed`; the decoder's corrections are
    /// zero if `zero_corrections` (then the network is the analytic retargeter).
    pub(crate) fn blob(a: Architecture, seed: u64, zero_corrections: bool) -> Vec<u8> {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        struct Owned {
            weights: Vec<i8>,
            bias: Vec<i32>,
            scale: Vec<f32>,
            requant: Vec<Requant>,
        }
        let owned: Vec<Owned> = Dense::ALL
            .iter()
            .map(|&layer| {
                let (n, m) = (layer.outputs(&a), layer.inputs(&a));
                let zero = zero_corrections && matches!(layer, Dense::DecoderOutput | Dense::Root);
                let mut value = |range: u64| match zero {
                    true => 0,
                    false => (next() % (2 * range + 1)) as i64 - range as i64,
                };
                Owned {
                    weights: (0..n * m).map(|_| value(127) as i8).collect(),
                    bias: (0..layer.bias_rows() * n)
                        .map(|_| value(500) as i32)
                        .collect(),
                    scale: (0..n).map(|i| 0.002 + 0.0001 * i as f32).collect(),
                    requant: (0..n)
                        .map(|i| Requant::new(0.003 + 0.001 * i as f32).unwrap())
                        .collect(),
                }
            })
            .collect();
        let layers: Vec<Tensors<'_>> = owned
            .iter()
            .map(|o| Tensors {
                weights: &o.weights,
                bias: &o.bias,
                scale: &o.scale,
                requant: &o.requant,
            })
            .collect();
        let tables: Vec<Vec<f32>> = Table::ALL
            .iter()
            .map(|t| {
                (0..t.len(&a))
                    .map(|_| (next() % 2001) as f32 / 1000.0 - 1.0)
                    .collect()
            })
            .collect();
        let tables = [
            &tables[0][..],
            &tables[1][..],
            &tables[2][..],
            &tables[3][..],
        ];
        let mut out = std::vec![0u8; max_len(&a)];
        let n = write(
            &header(a),
            &layers.try_into().ok().unwrap(),
            &tables,
            &mut out,
        )
        .unwrap();
        out.truncate(n);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::testing::{blob, header, DISTILLED};
    use super::*;

    /// `bytes` copied to a 4-byte-aligned buffer, viewed as bytes.
    fn aligned(bytes: &[u8]) -> std::vec::Vec<u32> {
        let mut words = std::vec![0u32; bytes.len().div_ceil(4)];
        bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
        words
    }

    fn open(bytes: &[u8]) -> Result<Header, WeightsError> {
        let words = aligned(bytes);
        let view = &bytemuck::cast_slice::<u32, u8>(&words)[..bytes.len()];
        Weights::from_bytes(view).map(|w| w.header().clone())
    }

    /// Rewrites the blob with a changed header (the CRC made right).
    fn with_header(bytes: &[u8], change: impl Fn(&mut Header)) -> std::vec::Vec<u8> {
        let words = aligned(bytes);
        let view = &bytemuck::cast_slice::<u32, u8>(&words)[..bytes.len()];
        let blob = Blob::open(view, MAGIC).unwrap();
        let mut h: Header = postcard::from_bytes(blob.header).unwrap();
        change(&mut h);
        let mut out = std::vec![0u8; bytes.len() + 64];
        let n = blob::write(MAGIC, &h, blob.payload, &mut out).unwrap();
        out.truncate(n);
        out
    }

    #[test]
    fn written_weights_read_back_with_every_array_in_place() {
        let bytes = blob(DISTILLED, 1, false);
        let words = aligned(&bytes);
        let view = &bytemuck::cast_slice::<u32, u8>(&words)[..bytes.len()];
        let w = Weights::from_bytes(view).unwrap();
        assert_eq!(w.header(), &header(DISTILLED));
        for layer in Dense::ALL {
            let t = w.layer(layer);
            assert_eq!(
                t.weights.len(),
                layer.outputs(&DISTILLED) * layer.inputs(&DISTILLED)
            );
            assert_eq!(t.bias.len(), layer.bias_rows() * t.scale.len());
            assert_eq!(
                t.bias_row(usize::MAX).len(),
                t.scale.len(),
                "{}",
                layer.name()
            );
        }
        assert_eq!(w.table(Table::TokenValues).len(), SEGMENTS * 16);
        assert_eq!(w.table(Table::JointLogits).len(), SEGMENTS * 2 * 16);
    }

    #[test]
    fn damaged_or_foreign_blobs_are_typed_errors() {
        let bytes = blob(DISTILLED, 2, false);
        assert_eq!(
            open(&bytes[..bytes.len() - 1]),
            Err(WeightsError::Blob(BlobError::Crc))
        );
        let mut flipped = bytes.clone();
        flipped[300] ^= 1;
        assert_eq!(open(&flipped), Err(WeightsError::Blob(BlobError::Crc)));
        let mut foreign = bytes.clone();
        foreign[..4].copy_from_slice(b"PCR\x01");
        assert_eq!(open(&foreign), Err(WeightsError::Blob(BlobError::Magic)));
        let old = with_header(&bytes, |h| h.version = 0);
        assert_eq!(open(&old), Err(WeightsError::Version(0)));
        let wide = with_header(&bytes, |h| h.architecture.features = 32);
        assert_eq!(open(&wide), Err(WeightsError::Architecture));
        let even = with_header(&bytes, |h| h.architecture.kernel = 5);
        assert_eq!(open(&even), Err(WeightsError::Payload));
        let scale = with_header(&bytes, |h| h.scales.fused = f32::NAN);
        assert_eq!(open(&scale), Err(WeightsError::Scale));
        // One byte past a word boundary (a Vec<u8> may start anywhere: Miri places it so).
        let mut store = vec![0u32; bytes.len() / 4 + 2];
        let unaligned = &mut bytemuck::cast_slice_mut::<u32, u8>(&mut store)[1..=bytes.len()];
        unaligned.copy_from_slice(&bytes);
        assert_eq!(
            Weights::from_bytes(unaligned).err(),
            Some(WeightsError::Payload)
        );
    }

    #[test]
    fn a_bad_requantization_or_bias_is_refused() {
        let a = DISTILLED;
        let bytes = blob(a, 3, false);
        let words = aligned(&bytes);
        let view = &bytemuck::cast_slice::<u32, u8>(&words)[..bytes.len()];
        let blob = Blob::open(view, MAGIC).unwrap();
        // The first layer's first bias (after its weights) and first requant (after its
        // weights, bias and scale).
        let (n, m) = (
            Dense::SkeletonHidden.outputs(&a),
            Dense::SkeletonHidden.inputs(&a),
        );
        let start = |arrays: &[usize]| {
            arrays
                .iter()
                .map(|b| b.next_multiple_of(blob::ALIGN))
                .sum::<usize>()
        };
        let bias = start(&[n * m]);
        let requant = start(&[n * m, 4 * n, 4 * n]) + 4;
        let bad_bias = (MAX_BIAS + 1) as i32;
        for (at, value) in [(requant, 40i32), (bias, bad_bias), (bias, -bad_bias)] {
            let mut payload = blob.payload.to_vec();
            payload[at..at + 4].copy_from_slice(&value.to_le_bytes());
            let h: Header = postcard::from_bytes(blob.header).unwrap();
            let mut out = std::vec![0u8; bytes.len() + 64];
            let len = blob::write(MAGIC, &h, &payload, &mut out).unwrap();
            assert_eq!(
                open(&out[..len]),
                Err(WeightsError::Value(Dense::SkeletonHidden)),
                "{value} at {at}"
            );
        }
    }
}
