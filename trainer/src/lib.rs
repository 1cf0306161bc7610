//! posecoach-train: the learned retargeter's training data and training, host side only.
//!
//! - [`bodies`]: random anthropometric characters in every keypoint format.
//! - [`clip`]: motions as rotations, put on any character; the ground truth.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bodies;
pub mod clip;
mod error;

pub use error::Error;
