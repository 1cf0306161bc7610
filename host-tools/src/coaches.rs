//! The coach reference swings this build carries, numbered as `CoachSelect` numbers them: the
//! blobs in `coaches/` (real swings, see the README), the same bytes the firmware embeds.

use anyhow::{Context, Result};
use posecoach_adapters::session::{BufferLens, Coach, OwnedBuffers, Session, RATES_HZ};
use posecoach_core::blob::Aligned;
use posecoach_core::config::MAX_JOINTS;
use posecoach_core::reference::Reference;

/// The bundled reference blobs in order: reference `n` is `BUNDLED[n]`.
static BUNDLED: [&Aligned<[u8]>; 2] = [
    &Aligned(*include_bytes!("../../coaches/driver.pcr")),
    &Aligned(*include_bytes!("../../coaches/iron.pcr")),
];

/// The bundled references in order: reference `n` is `all()[n]`.
///
/// # Errors
/// Only if a bundled file were damaged.
pub fn all() -> Result<Vec<Reference<'static>>> {
    BUNDLED
        .iter()
        .enumerate()
        .map(|(n, blob)| {
            Reference::from_bytes(&blob.0).with_context(|| format!("bundled coach {n}"))
        })
        .collect()
}

/// Runs `device` on the device's pipeline: a session with every bundled reference and buffers
/// for any student and model rate.
///
/// # Errors
/// Only if a bundled file were damaged.
pub fn session<R>(device: impl FnOnce(&mut Session<'_>) -> R) -> Result<R> {
    let coaches = all()?;
    let refs: Vec<Coach<'_>> = coaches.iter().map(Coach::from).collect();
    let longest = refs
        .iter()
        .map(|c| c.frames_at(RATES_HZ.1))
        .max()
        .unwrap_or(0);
    let mut buffers = OwnedBuffers::new(BufferLens::new(MAX_JOINTS, longest, RATES_HZ.1));
    Ok(device(&mut Session::new(&refs, buffers.buffers())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_adapters::io;
    use std::path::Path;

    /// The blobs are what `posecoach reference` makes of the real swings in
    /// `tests/fixtures` (see `coaches/README.md`), byte for byte.
    #[test]
    fn bundled_references_are_the_fixtures_stored() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        for (blob, name) in BUNDLED.iter().zip(["driver", "iron"]) {
            let file = root.join(format!("tests/fixtures/golf_{name}_60hz.csv"));
            let motion = io::load(&file).unwrap();
            assert_eq!(motion.to_reference(name).unwrap(), &blob.0, "{name}");
        }
    }
}
