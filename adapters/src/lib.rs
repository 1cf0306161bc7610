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
#![cfg_attr(not(any(test, feature = "std")), no_std)]
#![forbid(unsafe_code)]

pub mod fusion;
pub mod imu;
#[cfg(feature = "std")]
pub mod io;
pub mod log;
pub mod pose_stream;
pub mod session;
