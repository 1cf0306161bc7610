//! `posecoach bench`: speed of the core's hot paths, measured against a reference in the same run.

use anyhow::{bail, Result};
use posecoach_core::dtw::{align, scratch_len, Band, Sequence, Window};
use serde_json::json;
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
    /// Minimum measuring time in seconds.
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
    /// Also write both sequences as little-endian f64, frame-major (n × dims each, `a` then
    /// `b`), for a reference implementation to run on the same data.
    #[arg(long)]
    data_out: Option<PathBuf>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<String> {
    match &args.what {
        What::Dtw(a) => dtw(a),
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
    if args.dims == 0 || !args.dims.is_multiple_of(3) {
        bail!(
            "--dims {} must be a positive multiple of 3 (x, y, z per joint)",
            args.dims
        );
    }
    if args.n < 2 || args.n > u16::MAX as usize {
        bail!("--n {} must be between 2 and {}", args.n, u16::MAX);
    }
    let a = random_walk(args.n, args.dims, args.seed);
    let b = random_walk(args.n, args.dims, args.seed + 1);
    if let Some(path) = &args.data_out {
        let bytes: Vec<u8> = a
            .iter()
            .chain(&b)
            .flat_map(|&v| f64::from(v).to_le_bytes())
            .collect();
        std::fs::write(path, bytes)?;
    }
    let (ab, bb) = (to_channels(&a, args.dims), to_channels(&b, args.dims));
    let joints = args.dims / 3;
    let (sa, sb) = (Sequence::new(&ab, joints)?, Sequence::new(&bb, joints)?);
    let window = Window::new(Band::global(args.band), &[])?;
    let len = scratch_len(args.n, args.n, &window)?;
    let mut cost = vec![0.0; len.cost];
    let mut steps = vec![0u8; len.path_bytes];
    let mut path = vec![(0u16, 0u16); 2 * args.n - 1];

    let mut calls = 0u32;
    let mut result = align(&sa, &sb, &[], &window, &mut cost, &mut steps, &mut path)?;
    let budget = Duration::from_secs_f64(args.seconds);
    let start = Instant::now();
    while start.elapsed() < budget || calls < 10 {
        result = align(&sa, &sb, &[], &window, &mut cost, &mut steps, &mut path)?;
        calls += 1;
    }
    let per_call = start.elapsed().as_secs_f64() / f64::from(calls);
    let report = json!({
        "n": args.n, "dims": args.dims, "band": args.band, "cells": len.cells,
        "calls": calls, "us_per_call": per_call * 1e6, "ns_per_cell": per_call * 1e9 / len.cells as f64,
        "distance": result.distance, "path_len": result.path_len,
        "scratch_bytes": len.cost * 4 + len.path_bytes,
    });
    Ok(if args.json {
        format!("{report}\n")
    } else {
        format!(
            "banded DTW, n = {}, dims = {}, band = {}: {} cells, {:.1} us per call with the path, {:.2} ns per cell ({} calls); scratch {} bytes\n",
            args.n, args.dims, args.band, len.cells, per_call * 1e6, per_call * 1e9 / len.cells as f64, calls,
            len.cost * 4 + len.path_bytes,
        )
    })
}
