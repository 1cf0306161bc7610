//! Any bytes, at an aligned address, must never make the weights reader panic, and weights it
//! accepts must write back to bytes that read as the same weights, and run the network
//! without panicking. Each input is also tried with its CRC made right, so that mutations reach the header
//! and the tensors.
#![no_main]

use libfuzzer_sys::fuzz_target;
use posecoach_core::format::Format;
use posecoach_core::network::{self, retarget};
use posecoach_core::weights::{max_len, write, Dense, Table, Weights};
use posecoach_core::Vec3;

/// `bytes` copied to a 16-byte-aligned buffer, as a blob in flash would be placed.
fn aligned(bytes: &[u8]) -> Vec<u128> {
    let mut store = vec![0u128; bytes.len().div_ceil(16)];
    bytemuck::cast_slice_mut::<u128, u8>(&mut store)[..bytes.len()].copy_from_slice(bytes);
    store
}

fuzz_target!(|data: &[u8]| {
    check(data);
    if let Some(body) = data.len().checked_sub(4) {
        let mut fixed = data.to_vec();
        let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&data[..body]);
        fixed[body..].copy_from_slice(&crc.to_le_bytes());
        check(&fixed);
    }
});

fn bits(values: &[f32]) -> Vec<u32> {
    values.iter().map(|v| v.to_bits()).collect()
}

fn check(data: &[u8]) {
    let store = aligned(data);
    let bytes = &bytemuck::cast_slice::<u128, u8>(&store)[..data.len()];
    let Ok(weights) = Weights::from_bytes(bytes) else {
        return;
    };
    let layers = Dense::ALL.map(|l| *weights.layer(l));
    let tables = Table::ALL.map(|t| weights.table(t));
    let mut out = vec![0u8; max_len(weights.architecture())];
    let n = write(weights.header(), &layers, &tables, &mut out)
        .expect("accepted weights can be written again");
    let again = aligned(&out[..n]);
    let back = Weights::from_bytes(&bytemuck::cast_slice::<u128, u8>(&again)[..n])
        .expect("written weights read back");
    assert_eq!(back.header(), weights.header());
    for layer in Dense::ALL {
        let (a, b) = (back.layer(layer), weights.layer(layer));
        assert_eq!(
            (a.weights, a.bias, a.requant),
            (b.weights, b.bias, b.requant)
        );
        assert_eq!(bits(a.scale), bits(b.scale));
    }
    for table in Table::ALL {
        assert_eq!(bits(back.table(table)), bits(weights.table(table)));
    }
    // A short swing of a cross-format pair through every layer.
    let (source, target) = (
        Format::Cmu31.default_skeleton().unwrap(),
        Format::H36m17.default_skeleton().unwrap(),
    );
    let mut rest = vec![Vec3::zeros(); source.len()];
    source.rest_positions(&mut rest);
    let frames: Vec<Vec3> = (0..3)
        .flat_map(|f| {
            rest.iter()
                .map(move |p| p + Vec3::new(0.01 * f as f32, 0.0, 0.0))
        })
        .collect();
    let mut scratch = vec![0u32; network::MAX_SCRATCH / 4];
    let mut positions = vec![Vec3::zeros(); 3 * target.len()];
    retarget(
        &weights,
        &source,
        &target,
        &frames,
        bytemuck::cast_slice_mut(&mut scratch),
        &mut positions,
    )
    .expect("accepted weights retarget a sound swing");
}
