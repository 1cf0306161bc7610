//! Instructions per cell of the banded DTW, on a real swing.

use crate::count;
use posecoach_core::band::Band;
use posecoach_core::blob::Aligned;
use posecoach_core::dtw::{self, Sequence, Window};
use posecoach_core::frames::{to_mm, Frames};
use posecoach_core::math;
use posecoach_core::reference::Reference;
use posecoach_core::Vec3;

/// A real swing: the driver coach retargeted onto a 17-joint student by the int8 network, 55
/// frames at 30 Hz (the network's golden output, `posecoach export`).
pub static SWING: &Aligned<[u8]> = &Aligned(*include_bytes!(
    "../../../weights/distilled-int8.golden-out.pcr"
));

/// Band radius of the DTW benchmark, frames: scoring's at 30 Hz.
const DTW_RADIUS: u16 = 10;

/// Most positions of [`SWING`].
const SWING_POSITIONS: usize = 64 * 17;

/// Instructions per banded cell of `dtw::align` with the path, times 100: [`SWING`] aligned
/// with itself as scoring aligns swings (rooted frames, every joint weighing the same; the
/// student's as the detector's ring keeps them, in millimetres, the coach's in metres), in a
/// global band of [`DTW_RADIUS`]. Also returns the cells.
#[inline(never)]
pub fn per_cell_centi() -> Result<(u64, usize), &'static str> {
    let swing = Reference::from_bytes(&SWING.0).map_err(|_| "the DTW's swing is damaged")?;
    let positions = swing.positions();
    let (frames, joints) = (positions.len(), positions.joints());
    let mut mm = [[0i16; 3]; SWING_POSITIONS];
    let mm = mm
        .get_mut(..frames * joints)
        .ok_or("the DTW benchmark's swing is too long")?;
    for (m, p) in mm.iter_mut().zip(positions.iter()) {
        *m = to_mm(&p).ok_or("the DTW's swing is out of range")?;
    }
    let shape = |_| "the DTW's swing's shape";
    let a = Sequence::rooted(Frames::millimetres(mm, joints)).map_err(shape)?;
    let b = Sequence::rooted(positions).map_err(shape)?;
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
    let b = core::hint::black_box(b);
    let start = count::now();
    let aligned = dtw::align(&a, &b, &[], &window, cost, steps, path).map_err(|_| "DTW")?;
    let spent = count::now() - start;
    // Each joint and its root off by at most 0.87 mm: a cell on the diagonal by 1.8 mm.
    if aligned.path_len < frames || aligned.normalized > 1.8e-3 {
        return Err("a swing aligned with its millimetres is not near the diagonal");
    }
    Ok((spent * 100 / len.cells as u64, len.cells))
}

/// Joint counts [`check_rooted_distances`] tries: one alone, pairs only, a pair and one, and
/// up to the product's [`KERNEL_MOST_JOINTS`].
const KERNEL_JOINTS: [usize; 5] = [1, 2, 3, 16, KERNEL_MOST_JOINTS];

/// The most joints [`check_rooted_distances`] tries: the product's student.
const KERNEL_MOST_JOINTS: usize = 17;

/// Frames of [`SWING`] [`check_rooted_distances`] measures against its first.
const KERNEL_FRAMES: usize = 8;

/// Checks `math::rooted_distances` (an `asm!` loop on this FPU) against the same sum written
/// out in Rust, to the bit: [`SWING`]'s first frame against its next frames,
/// keeping each frame's first joints for each count of [`KERNEL_JOINTS`] (odd and even counts
/// take different paths through the loop). Returns how many costs were compared.
#[inline(never)]
pub fn check_rooted_distances() -> Result<usize, &'static str> {
    let swing = Reference::from_bytes(&SWING.0).map_err(|_| "the DTW's swing is damaged")?;
    let (positions, scale) = (swing.positions(), 1.0 / 3.0);
    let short = "the DTW's swing is too short for the kernel check";
    let mut compared = 0;
    for n in KERNEL_JOINTS {
        let mut here = [Vec3::zeros(); KERNEL_MOST_JOINTS];
        let here = here.get_mut(..n).ok_or("too many joints for the kernel check")?;
        // Not root-relative, so that every joint's distance counts, the first's too.
        first_joints(&positions, 0, here).ok_or(short)?;
        let mut frames = [Vec3::zeros(); KERNEL_FRAMES * KERNEL_MOST_JOINTS];
        let mut expected = [0.0f32; KERNEL_FRAMES];
        for (f, (other, e)) in frames.chunks_exact_mut(n).zip(&mut expected).enumerate() {
            first_joints(&positions, f + 1, other).ok_or(short)?;
            let mut sum = 0.0f32;
            for (h, p) in here.iter().zip(&*other) {
                let d = h - (p - other[0]);
                sum += math::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
            }
            *e = sum * scale;
        }
        let mut out = [f32::NAN; KERNEL_FRAMES];
        math::rooted_distances(here, &frames[..KERNEL_FRAMES * n], scale, &mut out);
        if out.iter().zip(&expected).any(|(o, e)| o.to_bits() != e.to_bits()) {
            return Err("math::rooted_distances differs from the compiled sum");
        }
        compared += KERNEL_FRAMES;
    }
    Ok(compared)
}

/// The first `out.len()` joints of frame `f` of `swing`, metres, into `out`; `None` past its
/// frames or a frame's joints.
fn first_joints(swing: &Frames<'_>, f: usize, out: &mut [Vec3]) -> Option<()> {
    if f >= swing.len() || out.len() > swing.joints() {
        return None;
    }
    for (j, o) in out.iter_mut().enumerate() {
        *o = swing.at(f, j);
    }
    Some(())
}
