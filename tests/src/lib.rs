//! Shared helpers for the integration tests: where the committed fixtures and the real data
//! in `../shared/data` live.

use std::path::PathBuf;

/// A committed fixture in `tests/fixtures`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// The real motion-capture folder: `$POSECOACH_DATA`, else `../shared/data` beside the
/// repository. `None`, with a message on stderr, when it is absent (a user's machine).
pub fn shared_data(test: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("POSECOACH_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"));
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "{test}: skipped: no real data at {} (set POSECOACH_DATA)",
            dir.display()
        );
        None
    }
}

/// Every file under `dir` with extension `ext`, sorted.
pub fn files(dir: &std::path::Path, ext: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == ext) {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}
