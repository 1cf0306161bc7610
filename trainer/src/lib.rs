//! posecoach-train: the learned retargeter's training data and training, host side only.
//!
//! - [`bodies`]: random anthropometric characters in every keypoint format.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bodies;
