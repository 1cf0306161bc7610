//! The int8 retargeter on the device (the `network` feature): its kernels counted, its golden
//! vectors checked bit for bit and one 64-frame window counted.

use crate::NETWORK;
use crate::{count, kernels};
use posecoach_core::blob::Aligned;
use posecoach_core::frames::Mm;
use posecoach_core::network;
use posecoach_core::reference::Reference;
use posecoach_core::weights::{Weights, WINDOW};
use posecoach_core::Vec3;

/// The committed int8 weights (`posecoach export`).
pub static WEIGHTS: &Aligned<[u8]> =
    &Aligned(*include_bytes!("../../../weights/distilled-int8.pcw"));
/// Their golden vectors: a coach swing at the network's rate, and its retargeting by the host.
static GOLDEN_IN: &Aligned<[u8]> = &Aligned(*include_bytes!(
    "../../../weights/distilled-int8.golden-in.pcr"
));
use crate::dtw::SWING as GOLDEN_OUT;

/// The embedded weights, once their kernels are counted and their golden vectors checked with
/// `scratch` (see [`check_golden`]); prints what each took.
#[inline(never)]
pub fn checked(scratch: &mut [Mm]) -> Result<Weights<'static>, &'static str> {
    let weights = Weights::from_bytes(&WEIGHTS.0).map_err(|_| "the weights are damaged")?;
    if *weights.architecture() != NETWORK {
        return Err("the weights are not the network the buffers were sized for");
    }
    defmt::println!(
        "KERNEL int8 shapes: {=u32} layer calls equal to a scalar loop",
        kernels::check_shapes()?
    );
    for (name, per_mac) in [
        ("linear", kernels::linear_per_mac_centi(&weights)?),
        ("conv1d", kernels::conv_per_mac_centi(&weights)?),
    ] {
        defmt::println!(
            "KERNEL int8 {=str}: {=u64}.{=u64:02} instructions per MAC",
            name,
            per_mac / 100,
            per_mac % 100
        );
    }
    let window = check_golden(&weights, scratch)?;
    defmt::println!("NETWORK window {=u64} instructions", window);
    Ok(weights)
}

/// Bytes of the golden vectors, which only the test embeds.
pub fn golden_bytes() -> usize {
    GOLDEN_IN.0.len() + GOLDEN_OUT.0.len()
}

/// Retargets the golden input onto the golden student with `scratch` (borrowed from the
/// session's ring before the session starts) and compares every bit of each frame with the
/// host's output as it is made; returns the instructions it took.
#[inline(never)]
fn check_golden(weights: &Weights<'_>, scratch: &mut [Mm]) -> Result<u64, &'static str> {
    let input = Reference::from_bytes(&GOLDEN_IN.0).map_err(|_| "golden input damaged")?;
    let expected = Reference::from_bytes(&GOLDEN_OUT.0).map_err(|_| "golden output damaged")?;
    let student = expected.skeleton();
    // One window: each frame is made once, as the host's output holds it.
    if input.frames() > WINDOW || expected.frames() != input.frames() {
        return Err("golden vectors not one window of frames");
    }
    // Stored in metres: the network's exact input, and its output to the bit.
    let source = input
        .positions()
        .as_metres()
        .ok_or("golden input not stored in metres")?;
    // The ring's room from its first word boundary, as the session takes it.
    let (_, room, _) = bytemuck::pod_align_to_mut::<u8, u32>(bytemuck::cast_slice_mut(scratch));
    let bits = |v: &Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let golden = expected.positions();
    let mut differ = false;
    // Counted without the comparison, then run again to compare each frame as it is made (no
    // buffer holds the output).
    let mut spent = 0;
    for compare in [false, true] {
        let start = count::now();
        network::retarget_each(
            weights,
            input.skeleton(),
            student,
            source,
            bytemuck::cast_slice_mut(&mut *room),
            &mut |f, pose| {
                differ |= compare
                    && (f >= golden.len()
                        || pose
                            .iter()
                            .enumerate()
                            .any(|(k, p)| bits(p) != bits(&golden.at(f, k))));
            },
        )
        .map_err(|_| "the network refused the golden input")?;
        if !compare {
            spent = count::now() - start;
        }
    }
    if differ {
        return Err("the int8 network's output differs from the host's golden vectors");
    }
    defmt::println!(
        "NETWORK golden: {=usize} frames of {=usize} joints onto {=usize}, equal to the bit",
        input.frames(),
        input.skeleton().len(),
        student.len()
    );
    Ok(spent)
}
