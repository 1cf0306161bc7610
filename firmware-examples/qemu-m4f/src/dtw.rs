//! Instructions per cell of the banded DTW, on a real swing.

use crate::count;
use posecoach_core::blob::Aligned;
use posecoach_core::dtw::{self, Band, Sequence, Window};
use posecoach_core::frames::Frames;
use posecoach_core::reference::Reference;

/// A real swing: the driver coach retargeted onto a 17-joint student by the int8 network, 55
/// frames at 30 Hz (the network's golden output, `posecoach export`).
pub static SWING: &Aligned<[u8]> = &Aligned(*include_bytes!(
    "../../../weights/distilled-int8.golden-out.pcr"
));

/// Band radius of the DTW benchmark, frames: scoring's at 30 Hz.
const DTW_RADIUS: u16 = 10;

/// Instructions per banded cell of `dtw::align` with the path, times 100: [`SWING`] aligned
/// with itself as scoring aligns swings (rooted frames, every joint weighing the same), in a
/// global band of [`DTW_RADIUS`]. Also returns the cells.
#[inline(never)]
pub fn per_cell_centi() -> Result<(u64, usize), &'static str> {
    let swing = Reference::from_bytes(&SWING.0).map_err(|_| "the DTW's swing is damaged")?;
    let (frames, joints) = (swing.frames(), swing.skeleton().len());
    let a = Sequence::rooted(Frames::metres(swing.positions(), joints))
        .map_err(|_| "the DTW's swing's shape")?;
    let window = Window::new(Band::global(DTW_RADIUS), &[]).map_err(|_| "band")?;
    let len = dtw::scratch_len(frames, frames, &window).map_err(|_| "band")?;
    let mut cost = [0.0f32; 128];
    let mut steps = [0u8; 512];
    let mut path = [(0u16, 0u16); 2 * 64];
    let (Some(cost), Some(steps), Some(path)) = (
        cost.get_mut(..len.cost),
        steps.get_mut(..len.path_bytes),
        path.get_mut(..2 * frames - 1),
    ) else {
        return Err("the DTW benchmark's scratch is too short for its swing");
    };
    let b = core::hint::black_box(a);
    let start = count::now();
    let aligned = dtw::align(&a, &b, &[], &window, cost, steps, path).map_err(|_| "DTW")?;
    let spent = count::now() - start;
    if aligned.path_len != frames || aligned.distance != 0.0 {
        return Err("a swing aligned with itself is not the diagonal");
    }
    Ok((spent * 100 / len.cells as u64, len.cells))
}
