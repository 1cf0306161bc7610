//! Coach reference swings as the device stores them: a [`blob`] (`.pcr`) holding
//! the coach's skeleton and frames, read in place.
//!
//! Header (postcard): format version, name, frame rate, frame count, and per joint its
//! canonical name, parent and rest offset. Payload: frames × joints positions, each three
//! `f32` little-endian (metres, +Y up), so [`Reference::positions`] is the payload itself.
//! Offsets and positions are the exact `f32`s of the motion the reference was made from: a
//! reference scores exactly as that motion does.

use crate::blob::{self, Blob, BlobError};
use crate::config::MAX_JOINTS;
use crate::format::Format;
use crate::joint::Joint;
use crate::skeleton::{Skeleton, SkeletonError};
use crate::Vec3;
use heapless::{String as HString, Vec as HVec};
use serde::{Deserialize, Serialize};

/// Magic of a coach reference blob.
pub const MAGIC: [u8; 4] = *b"PCR\x01";
/// Version of the header this build reads and writes.
pub const VERSION: u16 = 1;
/// Longest name, bytes of UTF-8.
pub const MAX_NAME: usize = 32;
/// Most bytes a header takes.
pub const MAX_HEADER: usize = 64 + MAX_NAME + MAX_JOINTS * 20;
/// Bytes per stored position.
const POSITION: usize = core::mem::size_of::<Vec3>();

#[cfg(target_endian = "big")]
compile_error!("references store little-endian f32 and are viewed in place");

/// Why bytes are not a coach reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReferenceError {
    /// Not a sound blob.
    Blob(BlobError),
    /// The header does not decode, or has bytes left over.
    Header,
    /// Written by another version of the format.
    Version(u16),
    /// The joints do not make a skeleton.
    Skeleton(SkeletonError),
    /// The frame rate is not a positive number.
    Rate,
    /// The payload is not one or more frames × joints positions, or not aligned for `f32`.
    Payload,
    /// A position is NaN or infinite.
    NonFinite,
    /// The name is longer than [`MAX_NAME`] bytes.
    Name,
}

impl core::fmt::Display for ReferenceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ReferenceError::Blob(e) => write!(f, "coach reference: {e}"),
            ReferenceError::Header => f.write_str("coach reference: undecodable header"),
            ReferenceError::Version(v) => write!(
                f,
                "coach reference format version {v}; this build reads version {VERSION}"
            ),
            ReferenceError::Skeleton(e) => write!(f, "coach reference skeleton: {e}"),
            ReferenceError::Rate => f.write_str("coach reference: frame rate not positive"),
            ReferenceError::Payload => f.write_str(
                "coach reference: payload is not one or more frames × joints positions at a 4-byte-aligned address",
            ),
            ReferenceError::NonFinite => f.write_str("coach reference: a position is not finite"),
            ReferenceError::Name => write!(f, "coach reference: name over {MAX_NAME} bytes"),
        }
    }
}

impl core::error::Error for ReferenceError {}

impl From<BlobError> for ReferenceError {
    fn from(e: BlobError) -> ReferenceError {
        ReferenceError::Blob(e)
    }
}

/// One joint of the stored skeleton.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct StoredJoint {
    joint: Option<Joint>,
    parent: Option<u8>,
    offset: [f32; 3],
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Header {
    version: u16,
    name: HString<MAX_NAME>,
    format: Format,
    rate_hz: f32,
    frames: u32,
    joints: HVec<StoredJoint, MAX_JOINTS>,
}

/// A checked coach reference, viewing its blob's positions in place.
#[derive(Clone, Debug)]
pub struct Reference<'a> {
    name: HString<MAX_NAME>,
    skeleton: Skeleton,
    rate_hz: f32,
    positions: &'a [Vec3],
}

impl<'a> Reference<'a> {
    /// Checks and reads a reference blob. The blob must start at a 4-byte-aligned address
    /// ([`blob::Aligned`] gives one).
    ///
    /// # Errors
    /// Any [`ReferenceError`].
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Reference<'a>, ReferenceError> {
        let blob = Blob::open(bytes, MAGIC)?;
        let (header, rest) =
            postcard::take_from_bytes::<Header>(blob.header).map_err(|_| ReferenceError::Header)?;
        if !rest.is_empty() {
            return Err(ReferenceError::Header);
        }
        if header.version != VERSION {
            return Err(ReferenceError::Version(header.version));
        }
        if !(header.rate_hz.is_finite() && header.rate_hz > 0.0) {
            return Err(ReferenceError::Rate);
        }
        let n = header.joints.len();
        let mut parents = [None; MAX_JOINTS];
        let mut offsets = [Vec3::zeros(); MAX_JOINTS];
        let mut joints = [None; MAX_JOINTS];
        for (k, stored) in header.joints.iter().enumerate() {
            parents[k] = stored.parent.map(usize::from);
            offsets[k] = Vec3::from(stored.offset);
            joints[k] = stored.joint;
        }
        let skeleton = Skeleton::new(header.format, &parents[..n], &offsets[..n], &joints[..n])
            .map_err(ReferenceError::Skeleton)?;
        let expected = (header.frames as usize)
            .checked_mul(n * POSITION)
            .ok_or(ReferenceError::Payload)?;
        // A swing of no frames is nothing a writer makes (write refuses it).
        if header.frames == 0 || blob.payload.len() != expected {
            return Err(ReferenceError::Payload);
        }
        let positions: &[Vec3] =
            bytemuck::try_cast_slice(blob.payload).map_err(|_| ReferenceError::Payload)?;
        if !positions
            .iter()
            .flat_map(|p| p.iter())
            .all(|v| v.is_finite())
        {
            return Err(ReferenceError::NonFinite);
        }
        Ok(Reference {
            name: header.name,
            skeleton,
            rate_hz: header.rate_hz,
            positions,
        })
    }

    /// The name it was stored under (e.g. "driver").
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The coach's skeleton.
    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    /// Frame rate, Hz.
    pub fn rate_hz(&self) -> f32 {
        self.rate_hz
    }

    /// Frames × joints of [`Reference::skeleton`], frame-major.
    pub fn positions(&self) -> &'a [Vec3] {
        self.positions
    }

    /// Frames.
    pub fn frames(&self) -> usize {
        self.positions.len() / self.skeleton.len()
    }
}

/// Bytes [`write()`] may need for a reference of `joints` joints and `frames` frames.
pub const fn max_len(joints: usize, frames: usize) -> usize {
    blob::max_len(MAX_HEADER, joints * frames * POSITION)
}

/// Writes the reference `name` (`skeleton` moving through `positions` at `rate_hz`) into
/// `out`, at most [`max_len`] bytes; returns its length.
///
/// # Errors
/// [`ReferenceError::Name`] for a long name, [`ReferenceError::Rate`],
/// [`ReferenceError::Payload`] if `positions` is not whole frames of `skeleton`,
/// [`ReferenceError::NonFinite`], and [`BlobError::TooSmall`] if `out` is short.
pub fn write(
    name: &str,
    skeleton: &Skeleton,
    rate_hz: f32,
    positions: &[Vec3],
    out: &mut [u8],
) -> Result<usize, ReferenceError> {
    let joints_len = skeleton.len();
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(ReferenceError::Rate);
    }
    if positions.is_empty() || !positions.len().is_multiple_of(joints_len) {
        return Err(ReferenceError::Payload);
    }
    if !positions
        .iter()
        .flat_map(|p| p.iter())
        .all(|v| v.is_finite())
    {
        return Err(ReferenceError::NonFinite);
    }
    let mut joints = HVec::new();
    for k in 0..joints_len {
        let offset = skeleton.offset(k);
        // At most MAX_JOINTS joints, so neither fails.
        let _ = joints.push(StoredJoint {
            joint: skeleton.joint(k),
            parent: skeleton.parent(k).map(|p| p as u8),
            offset: [offset.x, offset.y, offset.z],
        });
    }
    let header = Header {
        version: VERSION,
        name: HString::try_from(name).map_err(|_| ReferenceError::Name)?,
        format: skeleton.format(),
        rate_hz,
        frames: (positions.len() / joints_len) as u32,
        joints,
    };
    Ok(blob::write(
        MAGIC,
        &header,
        bytemuck::cast_slice(positions),
        out,
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blob::Aligned;

    fn swing() -> (Skeleton, Vec<Vec3>) {
        let skeleton = Skeleton::standard(Format::H36m17).unwrap();
        let mut rest = vec![Vec3::zeros(); skeleton.len()];
        skeleton.rest_positions(&mut rest);
        let positions = (0..5)
            .flat_map(|t| {
                rest.iter()
                    .map(move |p| p + Vec3::new(0.01 * t as f32, 0.0, 0.0))
            })
            .collect();
        (skeleton, positions)
    }

    #[test]
    fn a_reference_reads_back_bit_for_bit() {
        let (skeleton, positions) = swing();
        let mut out = Aligned([0u8; max_len(17, 5)]);
        let n = write("driver", &skeleton, 60.0, &positions, &mut out.0).unwrap();
        let reference = Reference::from_bytes(&out.0[..n]).unwrap();
        assert_eq!(reference.name(), "driver");
        assert_eq!(reference.rate_hz(), 60.0);
        assert_eq!(reference.frames(), 5);
        assert_eq!(reference.positions(), &positions[..]);
        assert_eq!(reference.skeleton(), &skeleton);
    }

    #[test]
    fn a_misaligned_blob_is_refused_not_misread() {
        let (skeleton, positions) = swing();
        let mut out = Aligned([0u8; max_len(17, 5) + 1]);
        let n = write("driver", &skeleton, 60.0, &positions, &mut out.0[1..]).unwrap();
        assert_eq!(
            Reference::from_bytes(&out.0[1..1 + n]).unwrap_err(),
            ReferenceError::Payload
        );
    }

    /// A blob with `header` and `payload`, as a later or damaged writer could make it.
    fn raw(header: &Header, payload: &[u8]) -> Result<(), ReferenceError> {
        let mut out = Aligned([0u8; 4096]);
        let n = blob::write(MAGIC, header, payload, &mut out.0).unwrap();
        Reference::from_bytes(&out.0[..n]).map(|_| ())
    }

    fn header(frames: u32) -> Header {
        let (skeleton, _) = swing();
        let joints = (0..skeleton.len())
            .map(|k| StoredJoint {
                joint: skeleton.joint(k),
                parent: skeleton.parent(k).map(|p| p as u8),
                offset: skeleton.offset(k).into(),
            })
            .collect();
        Header {
            version: VERSION,
            name: HString::new(),
            format: skeleton.format(),
            rate_hz: 30.0,
            frames,
            joints,
        }
    }

    #[test]
    fn each_bad_header_field_has_its_error() {
        let payload = vec![0u8; 17 * POSITION * 2];
        assert_eq!(raw(&header(2), &payload), Ok(()));
        assert_eq!(raw(&header(3), &payload), Err(ReferenceError::Payload));
        assert_eq!(raw(&header(0), &[]), Err(ReferenceError::Payload));
        assert_eq!(
            raw(
                &Header {
                    version: 2,
                    ..header(2)
                },
                &payload
            ),
            Err(ReferenceError::Version(2))
        );
        assert_eq!(
            raw(
                &Header {
                    rate_hz: f32::NAN,
                    ..header(2)
                },
                &payload
            ),
            Err(ReferenceError::Rate)
        );
        let mut orphan = header(2);
        orphan.joints[3].parent = Some(9);
        assert_eq!(
            raw(&orphan, &payload),
            Err(ReferenceError::Skeleton(SkeletonError::BadParent {
                joint: 3
            }))
        );
        let mut nan = payload.clone();
        nan[8..12].copy_from_slice(&f32::INFINITY.to_le_bytes());
        assert_eq!(raw(&header(2), &nan), Err(ReferenceError::NonFinite));
        let huge = header(u32::MAX);
        assert_eq!(raw(&huge, &payload), Err(ReferenceError::Payload));
    }

    #[test]
    fn writing_refuses_what_could_not_be_read() {
        let (skeleton, positions) = swing();
        let mut out = vec![0u8; max_len(17, 5)];
        let long = "x".repeat(MAX_NAME + 1);
        assert_eq!(
            write(&long, &skeleton, 60.0, &positions, &mut out),
            Err(ReferenceError::Name)
        );
        assert_eq!(
            write("d", &skeleton, 0.0, &positions, &mut out),
            Err(ReferenceError::Rate)
        );
        assert_eq!(
            write("d", &skeleton, 60.0, &positions[1..], &mut out),
            Err(ReferenceError::Payload)
        );
        assert_eq!(
            write("d", &skeleton, 60.0, &positions, &mut out[..100]),
            Err(ReferenceError::Blob(BlobError::TooSmall))
        );
    }
}
