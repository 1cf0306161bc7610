//! The coach reference swings this build carries, numbered as `CoachSelect` numbers them.

use anyhow::{Context, Result};
use posecoach_adapters::io::{csv, Motion};
use posecoach_adapters::session::{BufferLens, Coach, OwnedBuffers, Session, RATES_HZ};
use posecoach_core::config::MAX_JOINTS;

/// Number, name and CSV text of each bundled reference (real swings, see the README).
const BUNDLED: [(&str, &str); 2] = [
    (
        "driver",
        include_str!("../../tests/fixtures/golf_driver_60hz.csv"),
    ),
    (
        "iron",
        include_str!("../../tests/fixtures/golf_iron_60hz.csv"),
    ),
];

/// The bundled references in order: reference `n` is `all()[n]`.
///
/// # Errors
/// Only if a bundled file were damaged.
pub fn all() -> Result<Vec<(&'static str, Motion)>> {
    BUNDLED
        .iter()
        .map(|(name, text)| {
            csv::read(text)
                .map(|m| (*name, m))
                .with_context(|| format!("bundled coach `{name}`"))
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
    let refs: Vec<Coach<'_>> = coaches
        .iter()
        .map(|(_, m)| Coach {
            skeleton: &m.skeleton,
            positions: &m.positions,
            rate_hz: m.rate_hz,
        })
        .collect();
    let longest = coaches.iter().map(|(_, m)| m.frames()).max().unwrap_or(0);
    let mut buffers = OwnedBuffers::new(BufferLens::new(MAX_JOINTS, longest, RATES_HZ.1));
    Ok(device(&mut Session::new(&refs, buffers.buffers())))
}
