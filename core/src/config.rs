//! Capacity constants: every fixed-size buffer in the core is sized by one of these.
//!
//! Each constant's RAM cost is listed in the README's "Configuration" section.

/// Most joints one skeleton may have (BlazePose-33 landmarks and CMU-31 fit).
pub const MAX_JOINTS: usize = 40;

/// Longest swing, in frames, that can be scored (4.2 s at 60 Hz, 8.5 s at 30 Hz).
pub const MAX_SWING_FRAMES: usize = 256;
