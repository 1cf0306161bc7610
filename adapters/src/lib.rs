//! posecoach-adapters: turning files, byte streams and sensor samples into core frames.
//!
//! Without features the crate is `no_std` and allocation-free. The `std` feature adds host
//! file import and export in the `io` module.
//!
//! ```text
//!  ImuSample ──fusion (wire units → SI, still-period bias, Mahony filter)──▶ orientations
//!            ──imu (T-pose calibration, sensor-to-segment offsets, forward kinematics)──▶ frames
//! ```
//!
//! - [`fusion`]: one IMU's attitude.
//! - [`imu`]: the pose of a skeleton from a layout of IMUs.
//! - `lsm6ds3` (feature `lsm6ds3`): an IMU chip over any `embedded-hal` I²C bus.
#![cfg_attr(not(any(test, feature = "std")), no_std)]
#![forbid(unsafe_code)]

pub mod fusion;
pub mod imu;
pub mod log;
#[cfg(any(test, feature = "lsm6ds3"))]
pub mod lsm6ds3;
pub mod pose_stream;
pub mod session;
