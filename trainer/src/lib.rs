//! posecoach-train: the learned retargeter's training data and training, host side only.
pub mod golfgen;
