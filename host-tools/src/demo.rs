//! `posecoach demo`: the whole product on bundled data, with nothing but the repository.
//!
//! A recorded session of an amateur (`tests/logs/short_cmu_30hz.pclog`: CMU-31 keypoints at
//! 30 Hz from a 1.60 m golfer whose backswings take 1.5 times the tour player's, made by
//! `tests/logs/make.sh` from the real swings in `tests/fixtures`; the iron, then the driver) is
//! replayed through the device's pipeline as `posecoach replay` does. The session selects no
//! coach, so the device scores each swing against the bundled coach whose set-up its own is
//! nearest: the iron against the iron, the driver against the driver. The report is written as
//! `report.html` and `report.json` and the advice printed.

use crate::{html, replay};
use anyhow::{Context, Result};
use std::path::PathBuf;

/// The bundled student session.
const SESSION: &[u8] = include_bytes!("../../tests/logs/short_cmu_30hz.pclog");
/// Where the session comes from, for the report.
const PROVENANCE: &str = "Bundled session: tests/logs/short_cmu_30hz.pclog, an amateur (1.60 m, \
     CMU-31 keypoints at 30 Hz) with a 1.5x slower backswing, made from real tour swings by \
     tests/logs/make.sh; coach: the bundled iron or driver reference, chosen by the device from \
     each swing's set-up; retargeter: analytic \
     (the device's, until int8 weights are bundled)";

#[derive(clap::Args)]
pub struct Args {
    /// Folder for report.html and report.json (created if missing): `--out-dir`, as a folder
    /// is named everywhere (`--out` is always a file).
    #[arg(long, default_value = "posecoach-demo")]
    out_dir: PathBuf,
    /// Print one JSON object (the report) instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<String> {
    let replay = replay::replay(SESSION, None).context("replaying the bundled session")?;
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("creating {}", args.out_dir.display()))?;
    let json = replay.to_json();
    let (html_path, json_path) = (
        args.out_dir.join("report.html"),
        args.out_dir.join("report.json"),
    );
    let page = html::page(
        "posecoach demo: an amateur's session",
        &[PROVENANCE.to_string()],
        replay.session.page.as_ref(),
        &replay.pages,
    );
    std::fs::write(&html_path, page).with_context(|| format!("writing {}", html_path.display()))?;
    std::fs::write(&json_path, format!("{json:#}\n"))
        .with_context(|| format!("writing {}", json_path.display()))?;
    if args.json {
        return Ok(format!("{json}\n"));
    }
    Ok(format!(
        "{}\nreport: {} (open it in a browser) and {}\n",
        replay.text,
        html_path.display(),
        json_path.display()
    ))
}
