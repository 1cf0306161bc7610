//! The int8 retargeter: the committed weights against their golden vectors, and `export`,
//! `inspect` and `eval` on them through the command line.

use posecoach_core::network;
use posecoach_core::weights::Weights;
use posecoach_io as io;
use std::path::PathBuf;
#[cfg(feature = "learn")]
use {
    posecoach_cli::{inspect, learn},
    posecoach_tests::parse,
};

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path)
}

/// `bytes` in words, aligned as the core views weights in place.
fn aligned(bytes: &[u8]) -> Vec<u32> {
    let mut words = vec![0u32; bytes.len().div_ceil(4)];
    bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..bytes.len()].copy_from_slice(bytes);
    words
}

/// The committed weights retarget the golden input onto the golden student to exactly the
/// golden output's bits: what the firmware checks on the Cortex-M4F.
#[test]
fn committed_weights_reproduce_their_golden_vectors_bit_for_bit() {
    let bytes = std::fs::read(repo("weights/distilled-int8.pcw")).unwrap();
    let input = io::load(&repo("weights/distilled-int8.golden-in.pcr")).unwrap();
    let expected = io::load(&repo("weights/distilled-int8.golden-out.pcr")).unwrap();
    let words = aligned(&bytes);
    let weights = Weights::from_bytes(&bytemuck::cast_slice(&words)[..bytes.len()]).unwrap();
    assert_eq!(input.rate_hz, weights.architecture().rate_hz);
    let mut scratch = vec![0u32; network::MAX_SCRATCH / 4];
    let mut out = vec![posecoach_core::Vec3::zeros(); input.frames() * expected.skeleton.len()];
    network::retarget(
        &weights,
        &input.skeleton,
        &expected.skeleton,
        &input.positions,
        bytemuck::cast_slice_mut(&mut scratch),
        &mut out,
    )
    .unwrap();
    assert_eq!(out.len(), expected.positions.len());
    for (i, (got, want)) in out.iter().zip(&expected.positions).enumerate() {
        let bits = |v: &posecoach_core::Vec3| v.map(f32::to_bits);
        assert_eq!(
            bits(got),
            bits(want),
            "position {i}: {got:?} against {want:?}"
        );
    }
}

/// Needs the `learn` feature (export and eval).
#[cfg(feature = "learn")]
#[test]
fn export_writes_weights_that_inspect_reads_and_eval_ranks() {
    let Some(data) = posecoach_tests::shared_data("export_writes_weights") else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("posecoach-export-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("int8.pcw").display().to_string();
    let model = repo("weights/distilled.pcw").display().to_string();
    let coach = repo("coaches/iron.pcr").display().to_string();
    let data = data.display().to_string();
    let args: learn::ExportArgs = parse(&[
        "--model",
        &model,
        "--windows",
        "64",
        "--data",
        &data,
        "--synthetic",
        "2",
        "--out",
        &out,
        "--golden",
        &coach,
        "--json",
    ]);
    let report: serde_json::Value = serde_json::from_str(&learn::export(&args).unwrap()).unwrap();
    assert_eq!(report["header"]["architecture"]["features"], 16);
    assert_eq!(report["header"]["training"]["calibration_windows"], 64);
    let golden = io::load(&dir.join("int8.golden-out.pcr")).unwrap();
    assert_eq!(golden.skeleton.len(), 17);
    let args: inspect::Args = parse(&[&out, "--json"]);
    let header: serde_json::Value = serde_json::from_str(&inspect::run(&args).unwrap()).unwrap();
    assert_eq!(header, report["header"]);
    assert_eq!(header["layers"].as_array().unwrap().len(), 16);
    let args: learn::EvalArgs = parse(&[
        "--weights",
        &out,
        "--weights",
        &model,
        "--analytic",
        "--data",
        &data,
        "--synthetic",
        "1",
        "--json",
    ]);
    let table: serde_json::Value = serde_json::from_str(&learn::eval(&args).unwrap()).unwrap();
    let rows = table["rows"].as_array().unwrap();
    let cross = |m: &str| {
        rows.iter()
            .find(|r| r["method"] == m && r["structure"] == "cross")
            .unwrap()["global_pct_height"]
            .as_f64()
            .unwrap()
    };
    // The int8 network is the float distilled network's to within a few per cent of its error.
    let (int8, float) = (cross("int8"), cross("distilled"));
    assert!(
        (int8 - float).abs() < 0.05 * float,
        "{int8} against {float}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
