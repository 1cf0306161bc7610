//! The rotation transfer on the device (`posecoach_core::transfer`): the network's golden
//! input, one 64-frame window of a 22-joint coach, retargeted onto its golden student and
//! counted, each output bone checked to have the student's length.

use crate::count;
use crate::network::{GOLDEN_IN, GOLDEN_OUT};
use posecoach_core::reference::Reference;
use posecoach_core::transfer::Transfer;
use posecoach_core::Vec3;

/// Most a bone of the output may differ from the student's, metres.
const BONE_TOLERANCE_M: f32 = 1e-4;

/// Retargets the golden input onto the golden student into `out` (borrowed from the session's
/// virtual coach before the session starts); returns the instructions it took.
#[inline(never)]
pub fn window(out: &mut [Vec3]) -> Result<u64, &'static str> {
    let input = Reference::from_bytes(&GOLDEN_IN.0).map_err(|_| "golden input damaged")?;
    let student = Reference::from_bytes(&GOLDEN_OUT.0).map_err(|_| "golden output damaged")?;
    let (source, target) = (input.skeleton(), student.skeleton());
    let (n, m) = (source.len(), target.len());
    let out = out
        .get_mut(..input.frames() * m)
        .ok_or("virtual coach buffer shorter than the window")?;
    let start = count::now();
    let transfer =
        Transfer::new(source, target).map_err(|_| "the transfer refused the skeletons")?;
    for (frame, pose) in input
        .positions()
        .chunks_exact(n)
        .zip(out.chunks_exact_mut(m))
    {
        transfer
            .frame(frame, pose)
            .map_err(|_| "the transfer refused a frame")?;
    }
    let spent = count::now() - start;
    for pose in out.chunks_exact(m) {
        for k in 1..m {
            let bone = pose[k] - pose[target.parent(k).unwrap_or(0)];
            if (posecoach_core::math::norm(&bone) - posecoach_core::math::norm(&target.offset(k)))
                .abs()
                > BONE_TOLERANCE_M
            {
                return Err("the transfer's output lost a bone's length");
            }
        }
    }
    Ok(spent)
}
