//! posecoach-train: the learned retargeter's training data and training, host side only.
//!
//! - [`bodies`]: random anthropometric characters in every keypoint format.
//! - [`clip`]: motions as rotations, put on any character; the ground truth.
//! - [`dataset`]: train/eval splits of files and characters, retargeting pairs.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bodies;
pub mod clip;
pub mod dataset;
mod error;

pub use error::Error;
