//! What a person says about the motion files a command reads that the files do not say
//! themselves (`--units`, `--up`, `--rate`), and a note of how a keypoint file was read when
//! anything was converted.

use crate::coaches;
use anyhow::{bail, Result};
use posecoach_io::keypoints::Clock;
use posecoach_io::landmarks::Landmarks;
use posecoach_io::units::{Units, Up};
use posecoach_io::{self as io, Hints, Motion, Reading};
use std::path::Path;

#[derive(clap::Args, Clone, Debug, Default)]
#[group(id = "input")]
pub struct Args {
    /// Length unit of the input files (m, cm, mm, in; cmu for BVH). Keypoint files: found
    /// from the body's stature when not given.
    #[arg(long)]
    units: Option<Units>,
    /// Up axis of keypoint files (y, z, -y, -z, x, -x): found from the body when not given.
    #[arg(long, allow_hyphen_values = true)]
    up: Option<Up>,
    /// Frames per second of keypoint files whose time column holds frame numbers, or that
    /// have no time column.
    #[arg(long)]
    rate: Option<f32>,
}

impl Args {
    /// The hints given.
    pub fn hints(&self) -> Hints {
        Hints {
            units: self.units,
            up: self.up,
            rate_hz: self.rate,
        }
    }

    /// Loads a motion with the hints given; a keypoint file read with anything converted
    /// (another vocabulary, unit, up axis or clock, columns not read, frames skipped) is noted
    /// on stderr.
    ///
    /// # Errors
    /// As [`io::load_with`].
    pub fn load(&self, path: &Path) -> Result<Motion> {
        let (motion, reading) = io::load_with(path, &self.hints())?;
        if let Some(note) = reading.as_ref().and_then(note) {
            eprintln!("note: {}: {note}", path.display());
        }
        Ok(motion)
    }

    /// Loads a coach: a bundled coach by its name (`driver`, `iron`: a bare name, no
    /// extension), or a motion file as [`Args::load`] does.
    ///
    /// # Errors
    /// As [`Args::load`]; a bare name that is neither a file nor a bundled coach is told the
    /// bundled names.
    pub fn load_coach(&self, path: &Path) -> Result<Motion> {
        let bare = path.extension().is_none() && path.components().count() == 1;
        if bare && !path.exists() {
            let name = path.to_string_lossy();
            return match coaches::named(&name)? {
                Some(coach) => Ok(coach),
                None => bail!(
                    "{name}: no such file, and no bundled coach of that name (bundled: {})",
                    coaches::names()?.join(", ")
                ),
            };
        }
        self.load(path)
    }

    /// Loads a motion with the hints given, and how it was read.
    ///
    /// # Errors
    /// As [`io::load_with`].
    pub fn load_read(&self, path: &Path) -> Result<(Motion, Option<Reading>)> {
        Ok(io::load_with(path, &self.hints())?)
    }
}

/// One line saying what was converted, if anything was.
pub fn note(r: &Reading) -> Option<String> {
    let said = |given: bool| if given { "given" } else { "detected" };
    let mut parts = Vec::new();
    if r.landmarks != Landmarks::Canonical {
        parts.push(format!("read as {}", r.landmarks));
    }
    if r.units.0 != Units::M {
        parts.push(format!("units {} ({})", r.units.0, said(r.units.1)));
    }
    if r.up.0 != Up::Y {
        parts.push(format!("up {} ({}), turned to +y", r.up.0, said(r.up.1)));
    }
    if !matches!(r.clock.0, Clock::Seconds) {
        parts.push(format!(
            "time in {} at {:.1} Hz",
            r.clock.0.title(),
            r.rate_hz
        ));
    }
    if r.on_its_feet {
        parts.push(
            "the hips held at one place in every frame: the body placed on its planted feet"
                .to_string(),
        );
    }
    if r.skipped > 0 {
        parts.push(format!("{} skipped frames kept as missing", r.skipped));
    }
    if !r.ignored.is_empty() {
        parts.push(format!("not read: {}", r.ignored.join(", ")));
    }
    (!parts.is_empty()).then(|| parts.join("; "))
}
