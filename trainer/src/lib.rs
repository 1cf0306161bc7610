//! posecoach-train: the learned retargeter's training data and training, host side only.
//!
//! ```text
//!  motion files ──dataset (split by file)──▶ clips (rotations, clip)
//!  golfgen ──▶ synthetic swings and putts (motions)
//!  seeds ──dataset (split by stream)──▶ characters (bodies)
//!  clip on character A = source, clip on character B = ground truth ──▶ pairs
//!  retargeted vs ground truth ──metrics──▶ eq. 16 errors, hand gap, foot slide
//!  windows ──features (skeletons, prior)──▶ tensors ──model (teacher, fk)──▶ positions
//!  positions ──losses, train──▶ Adam steps
//! ```
//!
//! - [`bodies`]: random anthropometric characters in every keypoint format.
//! - [`clip`]: motions as rotations, put on any character; the ground truth.
//! - [`golfgen`]: parametric synthetic golf swings and putts, both hands on one grip.
//! - [`dataset`]: train/eval splits of files and characters, retargeting pairs.
//! - [`metrics`]: evaluation against the ground truth, and the baselines' table.
//! - [`skeletons`]: skeletons and T-poses as padded, batched tensors.
//! - [`fk`]: differentiable forward kinematics.
//! - [`prior`]: the geometric solutions the teacher corrects (the rotation transfer, the
//!   analytic retargeter's chords).
//! - [`features`]: motion windows as padded, batched tensors, with their skeletons and prior.
//! - [`calibration`]: the activations the int8 network keeps, and their largest magnitudes.
//! - [`model`]: the teacher network.
//! - [`losses`]: the training losses.
//! - [`discriminator`]: the adversarial loss's discriminator.
//! - [`train`]: training steps and checkpoints.
//! - [`infer`]: a trained teacher retargeting whole motions.
//! - [`quantize`]: int8 quantization and export of a trained network as a weights blob.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bodies;
pub mod calibration;
pub mod clip;
pub mod dataset;
pub mod discriminator;
mod error;
pub mod features;
pub mod fk;
pub mod golfgen;
pub mod infer;
pub mod losses;
pub mod metrics;
pub mod model;
pub mod prior;
pub mod quantize;
pub mod skeletons;
pub mod train;

pub use error::Error;

#[cfg(test)]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;
