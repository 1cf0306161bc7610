//! How much motion a reader or resampler takes: rates, duration and samples, checked before
//! anything is allocated.

use std::fmt;

/// Slowest frame rate read or resampled to, Hz: a second between poses is no longer motion
/// capture (the real files run at 30 to 360 Hz).
pub const MIN_RATE_HZ: f32 = 1.0;

/// Fastest frame rate read or resampled to, Hz: high-speed optical capture (the golf files are
/// 360 Hz).
pub const MAX_RATE_HZ: f32 = 2000.0;

/// Longest motion read or resampled, seconds: ten minutes, for mocap clips (the longest real
/// file is 63 s) as well as swings (2 s). It bounds what resampling a file allocates.
pub const MAX_DURATION_S: f32 = 600.0;

/// Most samples (frames × joints) a motion may hold, 96 MiB of positions: ten minutes at
/// 360 Hz of 38 markers, or at 240 Hz of [`MAX_JOINTS`](posecoach_core::config::MAX_JOINTS)
/// joints, fit.
pub const MAX_SAMPLES: usize = 1 << 23;

/// Most files a folder of per-frame keypoint files may hold: ten minutes at 60 Hz, checked
/// before any is read.
pub const MAX_FOLDER_FILES: usize = 36_000;

/// A motion beyond the limits ([`MIN_RATE_HZ`], [`MAX_RATE_HZ`], [`MAX_DURATION_S`],
/// [`MAX_SAMPLES`]), refused before it is allocated.
#[derive(Clone, Debug, PartialEq)]
pub enum LimitError {
    /// A frame rate (Hz) outside [`MIN_RATE_HZ`] to [`MAX_RATE_HZ`].
    Rate(f32),
    /// A duration (seconds) over [`MAX_DURATION_S`].
    Duration(f32),
    /// More samples than [`MAX_SAMPLES`].
    Samples {
        /// Frames.
        frames: usize,
        /// Joints per frame.
        joints: usize,
    },
}

impl fmt::Display for LimitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LimitError::Rate(r) => write!(
                f,
                "a frame rate of {r} Hz is outside the limits of {MIN_RATE_HZ} to {MAX_RATE_HZ} Hz"
            ),
            LimitError::Duration(s) => {
                write!(
                    f,
                    "a duration of {s} s is over the limit of {MAX_DURATION_S} s: cut the \
                     recording into parts no longer"
                )
            }
            LimitError::Samples { frames, joints } => write!(
                f,
                "{frames} frames of {joints} joints are over the limit of {MAX_SAMPLES} samples"
            ),
        }
    }
}

impl std::error::Error for LimitError {}

/// Checks a motion of `frames × joints` samples at `rate_hz` against the limits, before any of
/// it is allocated. The rate and duration of a single frame (a T-pose) are not checked.
///
/// # Errors
/// The first [`LimitError`] found: rate, then duration, then samples.
pub fn check_limits(frames: usize, joints: usize, rate_hz: f32) -> Result<(), LimitError> {
    if frames > 1 {
        if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz) {
            return Err(LimitError::Rate(rate_hz));
        }
        let duration = (frames - 1) as f64 / f64::from(rate_hz);
        if duration > f64::from(MAX_DURATION_S) {
            return Err(LimitError::Duration(duration as f32));
        }
    }
    if frames.saturating_mul(joints) > MAX_SAMPLES {
        return Err(LimitError::Samples { frames, joints });
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use posecoach_core::config::MAX_JOINTS;

    #[test]
    fn limits_name_the_limit_and_the_value() {
        assert_eq!(check_limits(1, 17, 0.0), Ok(()));
        assert_eq!(check_limits(2, 22, 1.0), Ok(()));
        assert_eq!(check_limits(654, 38, 360.0), Ok(()));
        assert_eq!(check_limits(600 * 360 + 1, 38, 360.0), Ok(()));
        assert_eq!(check_limits(600 * 240 + 1, MAX_JOINTS, 240.0), Ok(()));
        for rate in [0.0, 0.001, 2000.5, f32::INFINITY, f32::NAN] {
            let e = check_limits(2, 22, rate).unwrap_err();
            assert!(matches!(e, LimitError::Rate(r) if r.to_bits() == rate.to_bits()));
        }
        assert_eq!(
            check_limits(2, 22, 0.001).unwrap_err().to_string(),
            "a frame rate of 0.001 Hz is outside the limits of 1 to 2000 Hz"
        );
        let e = check_limits(1202, 22, 2.0).unwrap_err();
        assert_eq!(e, LimitError::Duration(600.5));
        assert_eq!(
            e.to_string(),
            "a duration of 600.5 s is over the limit of 600 s: cut the recording into parts no longer"
        );
        let e = check_limits(300_000, 31, 2000.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "300000 frames of 31 joints are over the limit of 8388608 samples"
        );
        let e = check_limits(1, usize::MAX, 0.0).unwrap_err();
        assert!(matches!(e, LimitError::Samples { .. }));
    }
}
