//! posecoach-adapters: what runs on the device besides the core: sensor samples and a phone's
//! pose stream turned into frames on the student's skeleton, and the scoring session that
//! takes wire messages to swing reports.
//!
//! `no_std` and allocation-free. The `std` feature only lifts `no_std` and adds
//! `session::OwnedBuffers` (heap buffers for host tools and tests); host file formats are in
//! `posecoach-io`.
//!
//! ```text
//!  PoseFrame ──pose_stream (model-rate grid, duplicates, gaps, confidence)──▶ frames ─┐
//!  ImuSample ──fusion (wire units → SI, still-period bias, Mahony filter)──▶ attitudes│
//!            ──imu (T-pose calibration, sensor-to-segment offsets, FK)──▶ frames ────┤
//!                                                                                    ▼
//!  Message ──session (profile, coach, settings; detector, events, DTW, score)──▶ Outcome
//! ```
//!
//! - [`pose_stream`]: a phone's keypoint frames onto the model rate's time grid.
//! - [`fusion`]: one IMU's attitude.
//! - [`segment`]: what an IMU on a body segment measures.
//! - [`imu`]: the pose of a skeleton from a layout of IMUs.
//! - `lsm6ds3` (feature `lsm6ds3`): an IMU chip over any `embedded-hal` I²C bus.
//! - [`log`]: recorded sessions (`.pclog`): a header and the wire frames a device received.
//! - [`session`]: the device's scoring session, from wire messages to swing reports.
#![cfg_attr(not(any(test, feature = "std")), no_std)]
#![forbid(unsafe_code)]

pub mod fusion;
pub mod imu;
pub mod log;
#[cfg(any(test, feature = "lsm6ds3"))]
pub mod lsm6ds3;
pub mod pose_stream;
pub mod segment;
pub mod session;
