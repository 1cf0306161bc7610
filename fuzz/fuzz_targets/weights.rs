//! Any bytes, at an aligned address, must never make the weights reader panic, and weights it
//! accepts must write back to bytes that read as the same weights, and run the network
//! without panicking. Each input is also tried with its CRC made right, so that mutations reach the header
//! and the tensors.
#![no_main]

mod blob_input;

use blob_input::{aligned, view, with_and_without_crc};
use libfuzzer_sys::fuzz_target;
use posecoach_core::format::Format;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::network::{self, retarget};
use posecoach_core::weights::{max_len, write, Dense, Table, Weights};
use posecoach_core::Vec3;

fuzz_target!(|data: &[u8]| with_and_without_crc(data, check));

fn bits(values: &[f32]) -> Vec<u32> {
    values.iter().map(|v| v.to_bits()).collect()
}

fn check(data: &[u8]) {
    let store = aligned(data);
    let bytes = view(&store, data.len());
    let Ok(weights) = Weights::from_bytes(bytes) else {
        return;
    };
    let layers = Dense::ALL.map(|l| *weights.layer(l));
    let tables = Table::ALL.map(|t| weights.table(t));
    let mut out = vec![0u8; max_len(weights.architecture())];
    let n = write(weights.header(), &layers, &tables, &mut out)
        .expect("accepted weights can be written again");
    let again = aligned(&out[..n]);
    let back = Weights::from_bytes(view(&again, n)).expect("written weights read back");
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
        Skeleton::standard(Format::Cmu31).unwrap(),
        Skeleton::standard(Format::H36m17).unwrap(),
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
