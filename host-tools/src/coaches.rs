//! What the device carries: the coach reference swings, numbered as `CoachSelect` numbers
//! them (the blobs in `coaches/`, real swings, see the README; the same bytes the firmware
//! embeds), and optionally the int8 network's weights.

use anyhow::{bail, Context, Result};
use posecoach_adapters::session::{BufferLens, Coach, OwnedBuffers, Session, RATES_HZ};
use posecoach_core::blob::Aligned;
use posecoach_core::config::MAX_JOINTS;
use posecoach_core::reference::Reference;
use posecoach_core::weights::Weights;
use std::path::Path;

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

/// Bundled reference `n` as a motion (the coach's swing on its own skeleton, at its rate).
///
/// # Errors
/// For no such reference, or if a bundled file were damaged.
pub fn motion(n: usize) -> Result<posecoach_io::Motion> {
    let blob = BUNDLED
        .get(n)
        .with_context(|| format!("no bundled coach {n}"))?;
    posecoach_io::Motion::from_reference(&blob.0).with_context(|| format!("bundled coach {n}"))
}

/// The bundled reference named `name` (`driver`, `iron`: the names `posecoach reference
/// --name` gave them) as a motion, if there is one.
///
/// # Errors
/// Only if a bundled file were damaged.
pub fn named(name: &str) -> Result<Option<posecoach_io::Motion>> {
    match all()?.iter().position(|r| r.name() == name) {
        Some(n) => motion(n).map(Some),
        None => Ok(None),
    }
}

/// The bundled references' names, in order.
///
/// # Errors
/// Only if a bundled file were damaged.
pub fn names() -> Result<Vec<String>> {
    Ok(all()?.iter().map(|r| r.name().to_owned()).collect())
}

/// A weights blob read from a file, kept aligned for the core's in-place view.
#[derive(Clone, Debug)]
pub struct Network {
    words: Vec<u32>,
    len: usize,
}

impl Network {
    /// The int8 weights in `path` (a `.pcw` from `posecoach export`).
    ///
    /// # Errors
    /// If the file cannot be read or is not sound weights.
    pub fn load(path: &Path) -> Result<Network> {
        let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
        let mut words = vec![0u32; bytes.len().div_ceil(4)];
        bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(&bytes);
        let network = Network {
            words,
            len: bytes.len(),
        };
        if bytes.starts_with(&posecoach_teachfile::MAGIC) {
            bail!(
                "{} holds float weights (a network from `posecoach train` or `distill`); a \
                 device runs int8 weights: make them with `posecoach export` and give that file",
                path.display()
            );
        }
        network
            .weights()
            .with_context(|| format!("reading {}", path.display()))?;
        Ok(network)
    }

    /// The checked view.
    ///
    /// # Errors
    /// Never after [`Network::load`] succeeded.
    pub fn weights(&self) -> Result<Weights<'_>> {
        Ok(Weights::from_bytes(
            &bytemuck::cast_slice(&self.words)[..self.len],
        )?)
    }
}

/// Runs `f` with the int8 weights in `path`, if given (a command's `--weights`).
///
/// # Errors
/// If the file cannot be read or is not sound weights; `f`'s error.
pub fn with_network<R>(
    path: Option<&Path>,
    f: impl FnOnce(Option<&Weights<'_>>) -> Result<R>,
) -> Result<R> {
    let network = path.map(Network::load).transpose()?;
    let weights = network.as_ref().map(Network::weights).transpose()?;
    f(weights.as_ref())
}

/// Runs `device` on the device's pipeline: a session with every bundled reference, the int8
/// `network` if given, and buffers for any student and model rate.
///
/// # Errors
/// Only if a bundled file were damaged.
pub fn session<R>(
    network: Option<&Weights<'_>>,
    device: impl FnOnce(&mut Session<'_>) -> R,
) -> Result<R> {
    let coaches = all()?;
    let refs: Vec<Coach<'_>> = coaches.iter().map(Coach::from).collect();
    let longest = refs
        .iter()
        .map(|c| c.frames_at(RATES_HZ.1))
        .max()
        .unwrap_or(0);
    let mut lens = BufferLens::new(MAX_JOINTS, longest, RATES_HZ.1);
    if let Some(w) = network {
        lens = lens.with_network(w.architecture(), MAX_JOINTS, MAX_JOINTS, longest);
    }
    let mut buffers = OwnedBuffers::new(lens);
    let session = Session::new(&refs, buffers.buffers());
    Ok(device(&mut match network {
        Some(w) => session.with_network(w),
        None => session,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_core::reference::Units;
    use posecoach_io as io;
    use std::path::Path;

    /// The blobs are what `posecoach reference` makes of the real swings in
    /// `tests/fixtures` (see `coaches/README.md`), byte for byte.
    #[test]
    fn bundled_references_are_the_fixtures_stored() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        for (blob, name) in BUNDLED.iter().zip(["driver", "iron"]) {
            let file = root.join(format!("tests/fixtures/golf_{name}_60hz.csv"));
            let motion = io::load(&file).unwrap();
            assert_eq!(
                motion.to_reference(name, Units::Millimetres).unwrap(),
                &blob.0,
                "{name}"
            );
        }
    }

    #[test]
    fn a_bundled_coach_is_found_by_its_name() {
        assert_eq!(names().unwrap(), ["driver", "iron"]);
        let iron = named("iron").unwrap().unwrap();
        assert_eq!(iron.frames(), motion(1).unwrap().frames());
        assert!(named("putter").unwrap().is_none());
    }
}
