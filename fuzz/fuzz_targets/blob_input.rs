//! Fuzz inputs as blobs: placed where a blob in flash would be, and tried as they are and with
//! their CRC made right, so that mutations also reach the header and payload.

/// `bytes` copied to a 16-byte-aligned buffer, as a blob in flash would be placed.
pub fn aligned(bytes: &[u8]) -> Vec<u128> {
    let mut store = vec![0u128; bytes.len().div_ceil(16)];
    bytemuck::cast_slice_mut::<u128, u8>(&mut store)[..bytes.len()].copy_from_slice(bytes);
    store
}

/// The first `len` bytes of an [`aligned`] store.
pub fn view(store: &[u128], len: usize) -> &[u8] {
    &bytemuck::cast_slice::<u128, u8>(store)[..len]
}

/// Calls `check` on `data`, then on `data` with its last four bytes the CRC-32 of the rest.
pub fn with_and_without_crc(data: &[u8], check: impl Fn(&[u8])) {
    check(data);
    if let Some(body) = data.len().checked_sub(4) {
        let mut fixed = data.to_vec();
        let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&data[..body]);
        fixed[body..].copy_from_slice(&crc.to_le_bytes());
        check(&fixed);
    }
}
