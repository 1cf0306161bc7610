//! Coach reference swings as the device stores them: a [`blob`] (`.pcr`) holding
//! the coach's skeleton and frames, read in place.
//!
//! Header (postcard): format version, name, keypoint format, frame rate, frame count, how the
//! positions are stored ([`Units`]), and per joint its canonical name, parent and rest offset.
//! Payload: frames × joints positions, frame-major, each three little-endian numbers (+Y up):
//! `i16` millimetres ([`Units::Millimetres`], 6 bytes a position: the bundled coaches) or `f32`
//! metres ([`Units::Metres`], 12 bytes: the exact floats, for golden vectors compared to the
//! bit). [`Reference::positions`] views the payload in place as [`Frames`], which reads either
//! as metres. Rest offsets are the exact `f32`s of the motion the reference was made from;
//! a position in millimetres is the motion's rounded to the nearest millimetre (at most 0.5 mm
//! off an axis, [`frames::to_mm`]).

use crate::blob::{self, Blob, BlobError};
use crate::config::MAX_JOINTS;
use crate::format::Format;
use crate::frames::{self, Frames, Mm};
use crate::joint::Joint;
use crate::resample;
use crate::skeleton::{Skeleton, SkeletonError};
use crate::Vec3;
use heapless::{String as HString, Vec as HVec};
use serde::{Deserialize, Serialize};

/// Magic of a coach reference blob.
pub const MAGIC: [u8; 4] = *b"PCR\x01";
/// Version of the header this build reads and writes (1 stored `f32` metres only, with no
/// [`Units`]; it is not read).
pub const VERSION: u16 = 2;
/// Longest name, bytes of UTF-8.
pub const MAX_NAME: usize = 32;
/// Most bytes a header takes.
pub const MAX_HEADER: usize = 64 + MAX_NAME + MAX_JOINTS * 20;

#[cfg(target_endian = "big")]
compile_error!("references store little-endian i16 and f32 and are viewed in place");

/// How a reference stores its positions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Units {
    /// `i16` millimetres ([`Mm`]), each axis the metres rounded to the nearest millimetre,
    /// within −32.768 m to 32.767 m: half the bytes of metres.
    Millimetres,
    /// `f32` metres, the exact floats.
    Metres,
}

impl Units {
    /// Bytes of one stored position.
    pub const fn position_len(self) -> usize {
        match self {
            Units::Millimetres => core::mem::size_of::<Mm>(),
            Units::Metres => core::mem::size_of::<Vec3>(),
        }
    }
}

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
    /// The payload is not one or more frames × joints positions, or not aligned for its
    /// numbers (2 bytes for millimetres, 4 for metres).
    Payload,
    /// A position is NaN or infinite.
    NonFinite,
    /// A position to be stored in millimetres lies beyond what `i16` millimetres hold
    /// (−32.768 m to 32.767 m an axis).
    Range,
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
                "coach reference format version {v}; this build reads version {VERSION} (remake the file with `posecoach reference`)"
            ),
            ReferenceError::Skeleton(e) => write!(f, "coach reference skeleton: {e}"),
            ReferenceError::Rate => f.write_str("coach reference: frame rate not positive"),
            ReferenceError::Payload => f.write_str(
                "coach reference: payload is not one or more frames × joints positions at an address aligned for its numbers",
            ),
            ReferenceError::NonFinite => f.write_str("coach reference: a position is not finite"),
            ReferenceError::Range => f.write_str(
                "coach reference: a position lies beyond ±32.767 m, past 16-bit millimetres",
            ),
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
    units: Units,
    joints: HVec<StoredJoint, MAX_JOINTS>,
}

/// A checked coach reference, viewing its blob's positions in place.
#[derive(Clone, Debug)]
pub struct Reference<'a> {
    name: HString<MAX_NAME>,
    skeleton: Skeleton,
    rate_hz: f32,
    units: Units,
    positions: Frames<'a>,
}

impl<'a> Reference<'a> {
    /// Checks and reads a reference blob. The blob must start at an address aligned for its
    /// numbers, 2 bytes for millimetres, 4 for metres ([`blob::Aligned`] gives 16).
    ///
    /// # Errors
    /// Any [`ReferenceError`] but [`ReferenceError::Range`] and [`ReferenceError::Name`].
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
            .checked_mul(n * header.units.position_len())
            .ok_or(ReferenceError::Payload)?;
        // A swing of no frames is nothing a writer makes (write refuses it).
        if header.frames == 0 || blob.payload.len() != expected {
            return Err(ReferenceError::Payload);
        }
        let positions = match header.units {
            Units::Millimetres => Frames::millimetres(
                bytemuck::try_cast_slice(blob.payload).map_err(|_| ReferenceError::Payload)?,
                n,
            ),
            Units::Metres => Frames::metres(
                bytemuck::try_cast_slice(blob.payload).map_err(|_| ReferenceError::Payload)?,
                n,
            ),
        };
        if !positions.is_finite() {
            return Err(ReferenceError::NonFinite);
        }
        Ok(Reference {
            name: header.name,
            skeleton,
            rate_hz: header.rate_hz,
            units: header.units,
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

    /// How the positions are stored.
    pub fn units(&self) -> Units {
        self.units
    }

    /// The frames, [`Reference::skeleton`]'s joints to a frame, viewed in place: read as
    /// metres whatever the [`Units`].
    pub fn positions(&self) -> Frames<'a> {
        self.positions
    }

    /// Frames.
    pub fn frames(&self) -> usize {
        self.positions.len()
    }
}

/// Frames the longest of the reference blobs `blobs` holds once resampled to `model_rate_hz`,
/// read from their headers in a const context, so that a firmware sizes its virtual coach from
/// the references it embeds; bytes that do not begin as a reference count 0. Only the
/// headers' leading fields are read: [`Reference::from_bytes`] checks each whole blob when
/// the firmware starts.
pub const fn frames_at(blobs: &[&[u8]], model_rate_hz: f32) -> usize {
    let (mut most, mut k) = (0, 0);
    while k < blobs.len() {
        let frames = blob_frames_at(blobs[k], model_rate_hz);
        if frames > most {
            most = frames;
        }
        k += 1;
    }
    most
}

/// [`frames_at`] of one blob.
const fn blob_frames_at(blob: &[u8], model_rate_hz: f32) -> usize {
    // After the blob's prefix (magic, header length), the header's postcard: version and name
    // length (varints), the name's bytes, format (a varint), rate (f32, little-endian),
    // frames (a varint).
    if blob.len() < blob::PREFIX
        || blob[0] != MAGIC[0]
        || blob[1] != MAGIC[1]
        || blob[2] != MAGIC[2]
        || blob[3] != MAGIC[3]
    {
        return 0;
    }
    let Some((_, at)) = varint(blob, blob::PREFIX) else {
        return 0;
    };
    let Some((name, at)) = varint(blob, at) else {
        return 0;
    };
    let Some((_, at)) = varint(blob, at.saturating_add(name as usize)) else {
        return 0;
    };
    if blob.len() < at.saturating_add(4) {
        return 0;
    }
    let rate = f32::from_le_bytes([blob[at], blob[at + 1], blob[at + 2], blob[at + 3]]);
    let Some((frames, _)) = varint(blob, at + 4) else {
        return 0;
    };
    if !(rate > 0.0 && rate.is_finite() && model_rate_hz > 0.0) || frames > u32::MAX as u64 {
        return 0;
    }
    resample::frames(frames as usize, rate, model_rate_hz)
}

/// A postcard varint at `at` in `bytes`: its value and where the next field starts.
const fn varint(bytes: &[u8], mut at: usize) -> Option<(u64, usize)> {
    let (mut value, mut shift) = (0u64, 0);
    while at < bytes.len() && shift < 64 {
        let byte = bytes[at];
        value |= ((byte & 0x7f) as u64) << shift;
        at += 1;
        if byte & 0x80 == 0 {
            return Some((value, at));
        }
        shift += 7;
    }
    None
}

/// Bytes [`write()`] may need for a reference of `joints` joints and `frames` frames, in
/// either [`Units`].
pub const fn max_len(joints: usize, frames: usize) -> usize {
    blob::max_len(MAX_HEADER, joints * frames * Units::Metres.position_len())
}

/// Writes the reference `name` (`skeleton` moving through `positions` at `rate_hz`) into
/// `out`, at most [`max_len`] bytes, its positions stored in `units`; returns its length.
/// Millimetres are each axis's metres rounded to the nearest millimetre.
///
/// # Errors
/// [`ReferenceError::Name`] for a long name, [`ReferenceError::Rate`],
/// [`ReferenceError::Payload`] if `positions` is not whole frames of `skeleton`'s joints,
/// [`ReferenceError::NonFinite`], [`ReferenceError::Range`] for a position beyond
/// millimetres' range, and [`BlobError::TooSmall`] if `out` is short. (`out`'s bytes are
/// then unspecified.)
pub fn write(
    name: &str,
    skeleton: &Skeleton,
    rate_hz: f32,
    positions: Frames<'_>,
    units: Units,
    out: &mut [u8],
) -> Result<usize, ReferenceError> {
    let joints_len = skeleton.len();
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(ReferenceError::Rate);
    }
    if positions.joints() != joints_len || !positions.is_whole() || positions.is_empty() {
        return Err(ReferenceError::Payload);
    }
    if !positions.is_finite() {
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
        frames: positions.len() as u32,
        units,
        joints,
    };
    let len = positions.len() * joints_len * units.position_len();
    blob::write_with(MAGIC, &header, len, out, |room| {
        let stored = room.chunks_exact_mut(units.position_len());
        for (bytes, p) in stored.zip(positions.iter()) {
            match units {
                Units::Millimetres => {
                    let mm = frames::to_mm(&p).ok_or(ReferenceError::Range)?;
                    for (b, v) in bytes.chunks_exact_mut(2).zip(mm) {
                        b.copy_from_slice(&v.to_le_bytes());
                    }
                }
                Units::Metres => {
                    for (b, v) in bytes.chunks_exact_mut(4).zip(p.iter()) {
                        b.copy_from_slice(&v.to_le_bytes());
                    }
                }
            }
        }
        Ok(())
    })
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
                    .map(move |p| p + Vec3::new(0.0123 * t as f32, 0.0, -0.0004))
            })
            .collect();
        (skeleton, positions)
    }

    const UNITS: [Units; 2] = [Units::Millimetres, Units::Metres];

    #[test]
    fn a_reference_reads_back_to_the_millimetre_or_bit_for_bit() {
        let (skeleton, positions) = swing();
        for units in UNITS {
            let mut out = Aligned([0u8; max_len(17, 5)]);
            let frames = Frames::metres(&positions, 17);
            let n = write("driver", &skeleton, 60.0, frames, units, &mut out.0).unwrap();
            let reference = Reference::from_bytes(&out.0[..n]).unwrap();
            assert_eq!(reference.name(), "driver");
            assert_eq!(reference.rate_hz(), 60.0);
            assert_eq!(reference.units(), units);
            assert_eq!(reference.frames(), 5);
            assert_eq!(reference.positions().joints(), 17);
            assert_eq!(reference.skeleton(), &skeleton);
            let back: Vec<Vec3> = reference.positions().iter().collect();
            match units {
                Units::Millimetres => {
                    let rounded: Vec<Vec3> = positions
                        .iter()
                        .map(|p| frames::from_mm(frames::to_mm(p).unwrap()))
                        .collect();
                    assert_eq!(back, rounded);
                }
                Units::Metres => {
                    assert_eq!(reference.positions().as_metres(), Some(&positions[..]))
                }
            }
        }
    }

    #[test]
    fn a_firmware_reads_the_frames_it_needs_from_the_header_at_compile_time() {
        // The frame counts and names of these (5 and 130 frames, a name of 0 to the most
        // bytes) move the header's varints through their one- and two-byte forms.
        let (skeleton, one) = swing();
        let long_name = "n".repeat(MAX_NAME);
        for (frames, name, rate) in [
            (5, "driver", 60.0),
            (130, "", 240.0),
            (130, long_name.as_str(), 29.97),
        ] {
            let positions: Vec<Vec3> = one.iter().cycle().take(17 * frames).copied().collect();
            for units in UNITS {
                let mut out = Aligned([0u8; max_len(17, 130)]);
                let stored = Frames::metres(&positions, 17);
                let n = write(name, &skeleton, rate, stored, units, &mut out.0).unwrap();
                let blob = &out.0[..n];
                let reference = Reference::from_bytes(blob).unwrap();
                for model in [30.0, 60.0, rate] {
                    let expected = resample::frames(reference.frames(), reference.rate_hz(), model);
                    assert_eq!(
                        frames_at(&[blob], model),
                        expected,
                        "{frames} frames at {rate} Hz"
                    );
                }
                // Cut before its frames field (within the first 64 bytes, the longest name's
                // included), or not a reference: nothing, and no panic.
                let whole = frames_at(&[blob], 30.0);
                for cut in 0..64 {
                    let got = frames_at(&[&blob[..cut]], 30.0);
                    assert!(got == 0 || got == whole, "cut at {cut}: {got}");
                }
                assert_eq!(frames_at(&[&blob[..blob::PREFIX + 2]], 30.0), 0);
                let mut other = blob.to_vec();
                other[2] = b'X';
                assert_eq!(frames_at(&[&other], 30.0), 0);
            }
        }
        assert_eq!(frames_at(&[], 60.0), 0);
    }

    /// The bundled coaches: the longer one's frames (natively only: their CRC and reading
    /// take Miri a minute, and the test above covers the header's reading).
    #[test]
    #[cfg(not(miri))]
    fn the_bundled_coaches_are_sized_by_the_longer() {
        const DRIVER: &Aligned<[u8]> = &Aligned(*include_bytes!("../../coaches/driver.pcr"));
        const IRON: &Aligned<[u8]> = &Aligned(*include_bytes!("../../coaches/iron.pcr"));
        const LONGEST: usize = frames_at(&[&DRIVER.0, &IRON.0], 60.0);
        let frames = [&DRIVER.0, &IRON.0].map(|b| Reference::from_bytes(b).unwrap().frames());
        assert_eq!(LONGEST, frames[0].max(frames[1]));
    }

    #[test]
    fn millimetres_take_half_the_bytes_and_write_back_the_same() {
        let (skeleton, positions) = swing();
        let mut lens = [0; 2];
        let mut mm = vec![0u8; max_len(17, 5)];
        for (units, len) in UNITS.into_iter().zip(&mut lens) {
            let mut out = Aligned([0u8; max_len(17, 5)]);
            *len = write(
                "d",
                &skeleton,
                60.0,
                Frames::metres(&positions, 17),
                units,
                &mut out.0,
            )
            .unwrap();
            if units == Units::Millimetres {
                mm[..*len].copy_from_slice(&out.0[..*len]);
            }
        }
        assert_eq!(lens[1] - lens[0], 17 * 5 * 6);
        let mut store = Aligned([0u8; max_len(17, 5)]);
        store.0[..lens[0]].copy_from_slice(&mm[..lens[0]]);
        let reference = Reference::from_bytes(&store.0[..lens[0]]).unwrap();
        let mut again = vec![0u8; max_len(17, 5)];
        let n = write(
            "d",
            &skeleton,
            60.0,
            reference.positions(),
            Units::Millimetres,
            &mut again,
        )
        .unwrap();
        assert_eq!(&again[..n], &mm[..lens[0]]);
    }

    #[test]
    fn a_misaligned_blob_is_refused_not_misread() {
        let (skeleton, positions) = swing();
        for (units, at) in [
            (Units::Millimetres, 1),
            (Units::Metres, 1),
            (Units::Metres, 2),
        ] {
            let mut out = Aligned([0u8; max_len(17, 5) + 2]);
            let frames = Frames::metres(&positions, 17);
            let n = write("driver", &skeleton, 60.0, frames, units, &mut out.0[at..]).unwrap();
            assert_eq!(
                Reference::from_bytes(&out.0[at..at + n]).unwrap_err(),
                ReferenceError::Payload,
                "{units:?} at {at}"
            );
        }
    }

    /// A blob with `header` and `payload`, as a later or damaged writer could make it.
    fn raw(header: &Header, payload: &[u8]) -> Result<(), ReferenceError> {
        let mut out = Aligned([0u8; 4096]);
        let n = blob::write(MAGIC, header, payload, &mut out.0).unwrap();
        Reference::from_bytes(&out.0[..n]).map(|_| ())
    }

    fn header(frames: u32, units: Units) -> Header {
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
            units,
            joints,
        }
    }

    #[test]
    fn each_bad_header_field_has_its_error() {
        let payload = vec![0u8; 17 * 6 * 2];
        let mm = |frames| header(frames, Units::Millimetres);
        assert_eq!(raw(&mm(2), &payload), Ok(()));
        assert_eq!(raw(&mm(3), &payload), Err(ReferenceError::Payload));
        assert_eq!(raw(&mm(0), &[]), Err(ReferenceError::Payload));
        // Millimetres' bytes are one frame of metres.
        assert_eq!(raw(&header(1, Units::Metres), &payload), Ok(()));
        assert_eq!(
            raw(&header(2, Units::Metres), &payload),
            Err(ReferenceError::Payload)
        );
        assert_eq!(
            raw(
                &Header {
                    version: 1,
                    ..mm(2)
                },
                &payload
            ),
            Err(ReferenceError::Version(1))
        );
        assert_eq!(
            raw(
                &Header {
                    rate_hz: f32::NAN,
                    ..mm(2)
                },
                &payload
            ),
            Err(ReferenceError::Rate)
        );
        let mut orphan = mm(2);
        orphan.joints[3].parent = Some(9);
        assert_eq!(
            raw(&orphan, &payload),
            Err(ReferenceError::Skeleton(SkeletonError::BadParent {
                joint: 3
            }))
        );
        let mut nan = payload.clone();
        nan[8..12].copy_from_slice(&f32::INFINITY.to_le_bytes());
        assert_eq!(
            raw(&header(1, Units::Metres), &nan),
            Err(ReferenceError::NonFinite)
        );
        // The same bytes as millimetres are a position like any other.
        assert_eq!(raw(&mm(2), &nan), Ok(()));
        let huge = mm(u32::MAX);
        assert_eq!(raw(&huge, &payload), Err(ReferenceError::Payload));
    }

    #[test]
    fn writing_refuses_what_could_not_be_read() {
        let (skeleton, positions) = swing();
        let frames = Frames::metres(&positions, 17);
        for units in UNITS {
            let mut out = vec![0u8; max_len(17, 5)];
            let long = "x".repeat(MAX_NAME + 1);
            assert_eq!(
                write(&long, &skeleton, 60.0, frames, units, &mut out),
                Err(ReferenceError::Name)
            );
            assert_eq!(
                write("d", &skeleton, 0.0, frames, units, &mut out),
                Err(ReferenceError::Rate)
            );
            let partial = Frames::metres(&positions[1..], 17);
            assert_eq!(
                write("d", &skeleton, 60.0, partial, units, &mut out),
                Err(ReferenceError::Payload)
            );
            let other = Frames::metres(&positions, 5);
            assert_eq!(
                write("d", &skeleton, 60.0, other, units, &mut out),
                Err(ReferenceError::Payload)
            );
            let mut nan = positions.clone();
            nan[20].y = f32::NAN;
            assert_eq!(
                write(
                    "d",
                    &skeleton,
                    60.0,
                    Frames::metres(&nan, 17),
                    units,
                    &mut out
                ),
                Err(ReferenceError::NonFinite)
            );
            assert_eq!(
                write("d", &skeleton, 60.0, frames, units, &mut out[..100]),
                Err(ReferenceError::Blob(BlobError::TooSmall))
            );
        }
    }

    #[test]
    fn millimetres_refuse_what_i16_cannot_hold_and_metres_keep_it() {
        let (skeleton, mut positions) = swing();
        let mut out = vec![0u8; max_len(17, 5)];
        for (far, fits) in [
            (32.767, true),
            (-32.768, true),
            (32.768, false),
            (-40.0, false),
        ] {
            positions[40].z = far;
            let frames = Frames::metres(&positions, 17);
            let mm = write("d", &skeleton, 60.0, frames, Units::Millimetres, &mut out);
            assert_eq!(mm.is_ok(), fits, "{far}");
            if !fits {
                assert_eq!(mm, Err(ReferenceError::Range));
            }
            assert!(write("d", &skeleton, 60.0, frames, Units::Metres, &mut out).is_ok());
        }
    }
}
