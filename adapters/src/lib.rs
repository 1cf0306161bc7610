//! posecoach-adapters: turning files, byte streams and sensor samples into core frames.
//!
//! Without features the crate is `no_std` and allocation-free. The `std` feature adds host
//! file import and export in [`io`].
#![cfg_attr(not(any(test, feature = "std")), no_std)]
#![forbid(unsafe_code)]

#[cfg(feature = "std")]
pub mod io;
pub mod log;
pub mod pose_stream;
pub mod session;
