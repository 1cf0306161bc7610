//! Float teacher weights (`--weights` on `score` and `retarget`): the learned retargeter with
//! the `learn` feature; without it, an error that says how to build a tool that has it.

use anyhow::Result;
use posecoach_core::skeleton::Skeleton;
use posecoach_io::Motion;
use std::path::Path;

/// `coach` retargeted onto `student` by the teacher in `path` (`posecoach train --teacher`).
///
/// # Errors
/// If the file does not load as a teacher or the coach cannot be retargeted.
#[cfg(feature = "learn")]
pub fn retarget(path: &Path, coach: &Motion, student: &Skeleton) -> Result<Motion> {
    use anyhow::Context;
    let teacher = posecoach_train::infer::Retargeter::load(path)
        .with_context(|| format!("loading {}", path.display()))?;
    Ok(teacher.retarget(coach, student)?)
}

/// Without the `learn` feature no teacher can run.
///
/// # Errors
/// Always: this build has no learned retargeter.
#[cfg(not(feature = "learn"))]
pub fn retarget(path: &Path, _coach: &Motion, _student: &Skeleton) -> Result<Motion> {
    anyhow::bail!(
        "{}: float teacher weights need the learned retargeter, which this posecoach was built \
         without; rebuild it with `--features learn`, or leave out --weights for the analytic \
         retargeter",
        path.display()
    )
}
