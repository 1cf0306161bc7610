//! What the IMU recordings' tests share: the built `posecoach`, run to success, and the
//! committed fixtures.

use std::path::{Path, PathBuf};
use std::process::Command;

/// `posecoach args`'s standard output; the test fails if it fails.
pub fn posecoach(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_posecoach"))
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "posecoach {args:?}: {err}");
    String::from_utf8(out.stdout).unwrap()
}

/// A file of `tests/fixtures`.
pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/fixtures")
        .join(name)
}
