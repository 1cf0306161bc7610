//! The coach reference swings this build carries, numbered as `CoachSelect` numbers them.

use anyhow::{Context, Result};
use posecoach_adapters::io::{csv, Motion};

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
