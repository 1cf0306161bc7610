//! `posecoach bench`: speed of the core's hot paths, measured against a reference in the same run.

use crate::score::score_swings;
use anyhow::{anyhow, bail, Result};
use posecoach_core::band::Band;
use posecoach_core::dtw::{align, scratch_len, Sequence, Window};
use posecoach_core::format::Format;
use posecoach_io::Motion;
use serde_json::{json, Value};
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(clap::Subcommand)]
enum What {
    /// Banded DTW with the path on random-walk data.
    Dtw(DtwArgs),
    /// Scoring one swing (events, DTW, report) on the host: the bundled iron against the
    /// bundled driver, both retarget onto a format's standard body, across rates, formats and
    /// band radii.
    Score(ScoreArgs),
    /// Whether the advice is true: planted flaws in real swings on other bodies, filmed by a
    /// noisy phone, through the device's session.
    Coaching(crate::coaching::Args),
}

#[derive(clap::Args)]
struct DtwArgs {
    /// Frames in each sequence.
    #[arg(long, default_value_t = 200)]
    n: usize,
    /// Values per frame (3 per joint).
    #[arg(long, default_value_t = 51)]
    dims: usize,
    /// DTW band radius in frames (a global band: random walks have no events).
    #[arg(long, default_value_t = 20)]
    band: u16,
    /// Seed of the random walk.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Minimum measuring time in seconds (per point with `--sweep`).
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
    /// Measure how the cost grows instead of one point: N from 100 to 5 000 frames (at D = 51,
    /// R = 20), D from 3 to 99 (at N = 200, R = 20) and R from 5 to 50 (at N = 200, D = 51);
    /// `--n`, `--dims` and `--band` are then not used.
    #[arg(long)]
    sweep: bool,
    /// Also write both sequences as little-endian f64, frame-major (n × dims each, `a` then
    /// `b`), for a reference implementation to run on the same data (one point, not a sweep).
    #[arg(long, conflicts_with = "sweep")]
    data_out: Option<PathBuf>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct ScoreArgs {
    /// Student formats (their joints make D = 3 × joints): h36m17 (51), canonical (66),
    /// cmu31 (93), blazepose33 (99), ...
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "h36m17,canonical,cmu31,blazepose33"
    )]
    formats: Vec<String>,
    /// Rates to score at, Hz (frames per swing grow with them; a swing may have at most
    /// `config::MAX_SWING_FRAMES` frames, 256).
    #[arg(long, value_delimiter = ',', default_value = "30,60,120")]
    rates: Vec<f32>,
    /// DTW band radii, frames.
    #[arg(long, value_delimiter = ',', default_value = "5,10,20,50")]
    bands: Vec<u16>,
    /// Minimum measuring time per point, seconds.
    #[arg(long, default_value_t = 0.5)]
    seconds: f64,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<String> {
    match &args.what {
        What::Dtw(a) if a.sweep => dtw_sweep(a),
        What::Dtw(a) => dtw(a),
        What::Score(a) => score(a),
        What::Coaching(a) => crate::coaching::run(a),
    }
}

/// A reproducible random walk: `frames × dims` values, frame-major, steps uniform in ±0.05.
fn random_walk(frames: usize, dims: usize, seed: u64) -> Vec<f32> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    let mut walk = vec![0.0f32; frames * dims];
    for f in 1..frames {
        for d in 0..dims {
            walk[f * dims + d] = walk[(f - 1) * dims + d] + 0.1 * uniform();
        }
    }
    walk
}

/// Frame-major `[x0 y0 z0 x1 ...]` rows to the core's channel-major layout (all frames of
/// each joint's x, then of each y, then of each z).
fn to_channels(frame_major: &[f32], dims: usize) -> Vec<f32> {
    let joints = dims / 3;
    (0..3)
        .flat_map(|axis| (0..joints).map(move |j| 3 * j + axis))
        .flat_map(|d| frame_major.chunks_exact(dims).map(move |f| f[d]))
        .collect()
}

fn dtw(args: &DtwArgs) -> Result<String> {
    let point = dtw_point(args, args.n, args.dims, args.band)?;
    Ok(if args.json {
        format!("{point}\n")
    } else {
        format!(
            "banded DTW, n = {}, dims = {}, band = {}: {} cells, {:.1} us per call with the path, {:.2} ns per cell ({} calls); scratch {} bytes\n",
            point["n"], point["dims"], point["band"], point["cells"], number(&point, "us_per_call"),
            number(&point, "ns_per_cell"), point["calls"], point["scratch_bytes"],
        )
    })
}

/// The points `bench dtw --sweep` measures: `(n, dims, band)`, each axis moved alone from
/// the benchmark's point (200, 51, 20).
pub const SWEEP: [(usize, usize, u16); 14] = [
    (100, 51, 20),
    (200, 51, 20),
    (500, 51, 20),
    (1000, 51, 20),
    (2000, 51, 20),
    (5000, 51, 20),
    (200, 3, 20),
    (200, 15, 20),
    (200, 33, 20),
    (200, 99, 20),
    (200, 51, 5),
    (200, 51, 10),
    (200, 51, 30),
    (200, 51, 50),
];

fn dtw_sweep(args: &DtwArgs) -> Result<String> {
    let mut points = Vec::with_capacity(SWEEP.len());
    for (k, &(n, dims, band)) in SWEEP.iter().enumerate() {
        eprintln!(
            "bench dtw: point {} of {}: n = {n}, dims = {dims}, band = {band}",
            k + 1,
            SWEEP.len()
        );
        points.push(dtw_point(args, n, dims, band)?);
    }
    if args.json {
        return Ok(format!("{}\n", json!({ "points": points })));
    }
    let mut out = String::from("| n | dims | band | cells | ns per cell | us per call | calls per second |\n| --- | --- | --- | --- | --- | --- | --- |\n");
    for p in &points {
        out += &format!(
            "| {} | {} | {} | {} | {:.2} | {:.1} | {:.0} |\n",
            p["n"],
            p["dims"],
            p["band"],
            p["cells"],
            number(p, "ns_per_cell"),
            number(p, "us_per_call"),
            1e6 / number(p, "us_per_call"),
        );
    }
    Ok(out)
}

/// One banded DTW with the path on random walks of `n` frames of `dims` values, timed for at
/// least `args.seconds`.
fn dtw_point(args: &DtwArgs, n: usize, dims: usize, band: u16) -> Result<Value> {
    if dims == 0 || !dims.is_multiple_of(3) {
        bail!("--dims {dims} must be a positive multiple of 3 (x, y, z per joint)");
    }
    if n < 2 || n > u16::MAX as usize {
        bail!("--n {n} must be between 2 and {}", u16::MAX);
    }
    let a = random_walk(n, dims, args.seed);
    let b = random_walk(n, dims, args.seed + 1);
    if let Some(path) = &args.data_out {
        let bytes: Vec<u8> = a
            .iter()
            .chain(&b)
            .flat_map(|&v| f64::from(v).to_le_bytes())
            .collect();
        std::fs::write(path, bytes)?;
    }
    let (ab, bb) = (to_channels(&a, dims), to_channels(&b, dims));
    let joints = dims / 3;
    let (sa, sb) = (Sequence::new(&ab, joints)?, Sequence::new(&bb, joints)?);
    let window = Window::new(Band::global(band), &[])?;
    let len = scratch_len(n, n, &window)?;
    let mut cost = vec![0.0; len.cost];
    let mut steps = vec![0u8; len.path_bytes];
    let mut path = vec![(0u16, 0u16); 2 * n - 1];

    let mut result = align(&sa, &sb, &[], &window, &mut cost, &mut steps, &mut path)?;
    let (calls, per_call) = timed(args.seconds, || {
        result = align(&sa, &sb, &[], &window, &mut cost, &mut steps, &mut path)?;
        Ok(())
    })?;
    Ok(json!({
        "n": n, "dims": dims, "band": band, "cells": len.cells,
        "calls": calls, "us_per_call": per_call * 1e6, "ns_per_cell": per_call * 1e9 / len.cells as f64,
        "distance": result.distance, "path_len": result.path_len,
        "scratch_bytes": len.cost * 4 + len.path_bytes,
    }))
}

/// Runs `call` at least ten times and for at least `seconds`: the calls and the seconds per
/// call.
fn timed(seconds: f64, mut call: impl FnMut() -> Result<()>) -> Result<(u32, f64)> {
    let budget = Duration::from_secs_f64(seconds);
    let mut calls = 0u32;
    let start = Instant::now();
    while start.elapsed() < budget || calls < 10 {
        call()?;
        calls += 1;
    }
    Ok((calls, start.elapsed().as_secs_f64() / f64::from(calls)))
}

/// `point[key]` as a number (0 if it is none).
fn number(point: &Value, key: &str) -> f64 {
    point[key].as_f64().unwrap_or(0.0)
}

fn score(args: &ScoreArgs) -> Result<String> {
    let [driver, iron] = [0, 1].map(crate::coaches::motion);
    let (driver, iron) = (driver?, iron?);
    let total = args.formats.len() * args.rates.len() * args.bands.len();
    let mut points = Vec::with_capacity(total);
    for name in &args.formats {
        let format = Format::from_name(name)
            .filter(|&f| f != Format::Custom)
            .ok_or_else(|| anyhow!("unknown format `{name}`"))?;
        let body = crate::tpose::standard(format, 1.75)?;
        let onto = |m: &Motion| {
            m.retarget_analytic(&body)
                .map_err(|(f, e)| anyhow!("frame {f} onto a {format} body: {e}"))
        };
        let (student, coach) = (onto(&iron)?, onto(&driver)?);
        for &rate in &args.rates {
            let (student, coach) = (student.resampled(rate)?, coach.resampled(rate)?);
            for &radius in &args.bands {
                eprintln!(
                    "bench score: point {} of {total}: {format}, {rate} Hz, band {radius}",
                    points.len() + 1
                );
                let band = Band {
                    radius,
                    anchored: true,
                };
                let mut report = score_swings(&student, &coach, band, &mut ())?;
                let (calls, per_swing) = timed(args.seconds, || {
                    report = score_swings(&student, &coach, band, &mut ())?;
                    Ok(())
                })?;
                let (n, m) = report.path.last().map_or((0, 0), |&(i, j)| (i + 1, j + 1));
                points.push(json!({
                    "format": format.to_string(), "dims": 3 * body.skeleton.len(), "rate_hz": rate,
                    "band": radius, "student_frames": n, "coach_frames": m, "cells": report.cells,
                    "calls": calls, "us_per_swing": per_swing * 1e6,
                    "swings_per_second": 1.0 / per_swing,
                    "ns_per_cell": per_swing * 1e9 / f64::from(report.cells.max(1)),
                    "score": report.score,
                }));
            }
        }
    }
    if args.json {
        return Ok(format!("{}\n", json!({ "points": points })));
    }
    let mut out = String::from("| format | dims | rate, Hz | band | frames, student x coach | cells | us per swing | swings per second | ns per cell |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
    for p in &points {
        out += &format!(
            "| {} | {} | {} | {} | {} x {} | {} | {:.0} | {:.0} | {:.0} |\n",
            p["format"].as_str().unwrap_or(""),
            p["dims"],
            p["rate_hz"],
            p["band"],
            p["student_frames"],
            p["coach_frames"],
            p["cells"],
            number(p, "us_per_swing"),
            number(p, "swings_per_second"),
            number(p, "ns_per_cell"),
        );
    }
    Ok(out)
}
