//! Capacity constants: every fixed-size buffer in the core is sized by one of these.
//!
//! Each constant's RAM cost is listed in the README's "Configuration" section.

/// Most joints one skeleton may have (BlazePose-33 landmarks and CMU-31 fit).
pub const MAX_JOINTS: usize = 40;

/// Most body segments a skeleton is cut into (spine, head, two arms, two legs).
pub const MAX_SEGMENTS: usize = 6;

/// Deepest parent chain a skeleton may have (root to the deepest joint, in bones).
pub const MAX_DEPTH: usize = 16;
