//! The container of posecoach's binary assets: coach references ([`crate::reference`]) and,
//! with the same layout, int8 weights.
//!
//! ```text
//! offset   bytes  what
//! 0        4      magic: which asset
//! 4        4      header length H, u32 little-endian
//! 8        H      header, postcard
//! 8 + H    ..     zeros up to the next multiple of ALIGN
//! P        N      payload, at an ALIGN-aligned offset
//! P + N    4      CRC-32/ISO-HDLC (the zlib CRC) of every byte before it, little-endian
//! ```
//!
//! A blob is read in place from `&[u8]` (flash, `include_bytes!`); its payload can be viewed as
//! `f32` or `i8` arrays without a copy when the blob itself starts at an address aligned to
//! [`ALIGN`], which [`Aligned`] gives a `static`.

use serde::Serialize;

/// Alignment of the payload within a blob, bytes.
pub const ALIGN: usize = 16;
/// Bytes before the header: magic and header length.
pub(crate) const PREFIX: usize = 8;
/// Bytes of the CRC.
const CRC_LEN: usize = 4;
const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Bytes aligned to [`ALIGN`], for a blob in a `static`:
/// `static R: &Aligned<[u8]> = &Aligned(*include_bytes!("driver.pcr"));`.
#[repr(C, align(16))]
pub struct Aligned<B: ?Sized>(pub B);

const _: () = assert!(core::mem::align_of::<Aligned<[u8; 0]>>() == ALIGN);

/// Why bytes are not a blob.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BlobError {
    /// Shorter than its header and CRC say.
    Truncated,
    /// Another asset, or not a posecoach blob.
    Magic,
    /// The CRC does not match: the bytes are damaged.
    Crc,
    /// The output buffer is too small to write the blob into.
    TooSmall,
}

impl core::fmt::Display for BlobError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            BlobError::Truncated => "truncated",
            BlobError::Magic => "not this kind of posecoach file (wrong magic)",
            BlobError::Crc => "damaged (CRC mismatch)",
            BlobError::TooSmall => "output buffer too small",
        })
    }
}

impl core::error::Error for BlobError {}

/// A checked blob: its header bytes and its payload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Blob<'a> {
    /// The postcard header.
    pub header: &'a [u8],
    /// The payload, at an [`ALIGN`]-aligned offset from the blob's start.
    pub payload: &'a [u8],
}

impl<'a> Blob<'a> {
    /// Checks `bytes`' magic, lengths and CRC.
    ///
    /// # Errors
    /// [`BlobError::Truncated`], [`BlobError::Magic`] or [`BlobError::Crc`].
    pub fn open(bytes: &'a [u8], magic: [u8; 4]) -> Result<Blob<'a>, BlobError> {
        let (Some(found), Some(len)) = (bytes.get(..4), bytes.get(4..PREFIX)) else {
            return Err(BlobError::Truncated);
        };
        if found != magic {
            return Err(BlobError::Magic);
        }
        let header_len = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
        let payload_at = payload_offset(header_len).ok_or(BlobError::Truncated)?;
        let body_len = bytes
            .len()
            .checked_sub(CRC_LEN)
            .filter(|&n| n >= payload_at)
            .ok_or(BlobError::Truncated)?;
        let (body, crc) = bytes.split_at(body_len);
        if CRC.checksum(body).to_le_bytes() != crc {
            return Err(BlobError::Crc);
        }
        Ok(Blob {
            header: &body[PREFIX..PREFIX + header_len],
            payload: &body[payload_at..],
        })
    }
}

/// Where the payload starts after a header of `header_len` bytes.
fn payload_offset(header_len: usize) -> Option<usize> {
    PREFIX
        .checked_add(header_len)?
        .checked_next_multiple_of(ALIGN)
}

/// Writes a blob of `header` and `payload` into `out`; returns its length.
///
/// # Errors
/// [`BlobError::TooSmall`] if `out` cannot hold it.
pub fn write(
    magic: [u8; 4],
    header: &impl Serialize,
    payload: &[u8],
    out: &mut [u8],
) -> Result<usize, BlobError> {
    write_with(magic, header, payload.len(), out, |room| {
        room.copy_from_slice(payload);
        Ok(())
    })
}

/// Writes a blob of `header` and a payload of `payload_len` bytes that `fill` writes in
/// place (given exactly that many zeroed bytes) into `out`; returns its length.
///
/// # Errors
/// [`BlobError::TooSmall`] if `out` cannot hold it; `fill`'s error.
pub fn write_with<E: From<BlobError>>(
    magic: [u8; 4],
    header: &impl Serialize,
    payload_len: usize,
    out: &mut [u8],
    fill: impl FnOnce(&mut [u8]) -> Result<(), E>,
) -> Result<usize, E> {
    let room = out.get_mut(PREFIX..).ok_or(BlobError::TooSmall)?;
    let header_len = postcard::to_slice(header, room)
        .map_err(|_| BlobError::TooSmall)?
        .len();
    let payload_at = payload_offset(header_len).ok_or(BlobError::TooSmall)?;
    let end = payload_at + payload_len;
    if out.len() < end + CRC_LEN {
        return Err(BlobError::TooSmall.into());
    }
    out[..4].copy_from_slice(&magic);
    out[4..PREFIX].copy_from_slice(&(header_len as u32).to_le_bytes());
    out[PREFIX + header_len..end].fill(0);
    fill(&mut out[payload_at..end])?;
    let crc = CRC.checksum(&out[..end]);
    out[end..end + CRC_LEN].copy_from_slice(&crc.to_le_bytes());
    Ok(end + CRC_LEN)
}

/// Length of a blob whose header takes at most `header_len` bytes and whose payload takes
/// `payload_len`: enough room for [`write()`].
pub const fn max_len(header_len: usize, payload_len: usize) -> usize {
    (PREFIX + header_len).next_multiple_of(ALIGN) + payload_len + CRC_LEN
}

#[cfg(test)]
mod tests {
    use super::*;

    const MAGIC: [u8; 4] = *b"TEST";

    fn sample() -> Vec<u8> {
        let mut out = vec![0; max_len(16, 8)];
        let n = write(MAGIC, &(7u16, 1.5f32), &[1, 2, 3, 4, 5, 6, 7, 8], &mut out).unwrap();
        out.truncate(n);
        out
    }

    #[test]
    fn a_written_blob_opens_with_its_header_and_an_aligned_payload() {
        let bytes = sample();
        let blob = Blob::open(&bytes, MAGIC).unwrap();
        assert_eq!(
            postcard::from_bytes::<(u16, f32)>(blob.header).unwrap(),
            (7, 1.5)
        );
        assert_eq!(blob.payload, &[1, 2, 3, 4, 5, 6, 7, 8]);
        let offset = blob.payload.as_ptr() as usize - bytes.as_ptr() as usize;
        assert_eq!(offset % ALIGN, 0);
    }

    #[test]
    fn every_flipped_bit_and_every_cut_is_an_error() {
        let bytes = sample();
        for i in 0..bytes.len() * 8 {
            let mut bad = bytes.clone();
            bad[i / 8] ^= 1 << (i % 8);
            assert!(Blob::open(&bad, MAGIC).is_err(), "bit {i}");
        }
        for n in 0..bytes.len() {
            assert!(Blob::open(&bytes[..n], MAGIC).is_err(), "cut at {n}");
        }
    }

    #[test]
    fn another_magic_is_refused_before_the_crc() {
        assert_eq!(Blob::open(&sample(), *b"PCR1"), Err(BlobError::Magic));
    }

    #[test]
    fn a_short_output_is_refused() {
        let mut out = [0u8; 20];
        assert_eq!(
            write(MAGIC, &(7u16, 1.5f32), &[0; 8], &mut out),
            Err(BlobError::TooSmall)
        );
    }

    #[test]
    fn a_huge_header_length_is_truncation_not_overflow() {
        let mut bytes = sample();
        bytes[4..8].copy_from_slice(&u32::MAX.to_le_bytes());
        assert_eq!(Blob::open(&bytes, MAGIC), Err(BlobError::Truncated));
    }
}
