//! posecoach-core: the no_std, allocation-free heart of posecoach.
//!
//! Everything here runs unchanged on a Cortex-M4F and on the host, on caller-owned buffers,
//! without panicking on any input. `docs/ARCHITECTURE.md` draws the whole device path; the
//! core's part of it:
//!
//! ```text
//!  bytes ──wire::Decoder──▶ Message          Report::to_wire ──wire::encode──▶ bytes
//!                                                  ▲
//!  student T-pose ──format──▶ skeleton             │
//!  coach reference ──resample──▶ model rate        │
//!     ──retarget::Analytic / network (int8)──▶ virtual coach ─┐
//!  student frames ──detector──▶ swing ──events──▶ dtw (Band) ─┴─▶ score::Report
//! ```
//!
//! Modules, in data-flow order:
//! - [`config`]: the capacity constants more than one module shares.
//! - [`math`]: square root and length, on the device's FPU; median and selection.
//! - [`joint`]: the canonical joint vocabulary and its parent table.
//! - [`format`](mod@format): built-in keypoint formats mapped onto the vocabulary.
//! - [`skeleton`]: joints, parents, rest offsets, body segments, end effectors, height.
//! - [`plausible`]: the human limits a body and its motion must keep (stature, bones, speed).
//! - [`kinematics`]: forward and inverse kinematics with per-bone rotations.
//! - [`resample`]: linear resampling from one frame rate to another.
//! - [`frames`]: a swing as stored (`f32` metres or 16-bit millimetres), read as metres.
//! - [`retarget`]: the analytic retargeter.
//! - [`detector`]: which stretch of a live pose stream is a swing.
//! - [`events`]: the eight swing events.
//! - [`contacts`]: golf's contacts kept on a virtual coach (planted feet, grip, club at the ball).
//! - [`body`]: the angles and shifts coaches read a swing by (turn, bend, sway, X-factor).
//! - [`checks`]: the body metrics advice speaks of, at the positions it speaks of them.
//! - [`sequence`]: the kinematic sequence, and its gaps against the coach's.
//! - [`band`]: the DTW's band, a radius around the diagonal or the matched swing events.
//! - [`dtw`]: banded dynamic time warping between a student's swing and the virtual swing.
//! - [`score`]: the score, tempo, spatial deviations and advice of one swing.
//! - [`tally`]: one quantity's running robust statistics over a session's swings.
//! - [`session`]: what a range session's swings say together: estimates, set-aside swings,
//!   tendencies.
//! - [`setup`]: a swing's set-up, and the coach whose set-up (so club) it is nearest.
//! - [`wire`]: the serial protocol: messages, COBS + CRC-32 framing, a streaming decoder.
//! - [`int8`]: int8 arithmetic of the quantized retargeter (requantization, dot products, layers).
//! - [`blob`]: the container of stored assets (header, aligned payload, CRC-32).
//! - [`reference`](mod@reference): coach reference swings stored as blobs, read in place.
//! - [`weights`]: the quantized retargeter's weights stored as a blob, checked once.
//! - [`network`]: the quantized retargeter itself, on those weights.
#![cfg_attr(not(any(test, feature = "std")), no_std)]
// `deny`, not `forbid`: `asm!` is the exception, in two modules, each block with its proof:
// the FPU's square root and a row of DTW cells' summed joint distances (`math`), and, with the
// `dsp` feature, the int8 kernels' DSP instructions (`int8`), which read only the slices they
// are given.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod band;
pub mod blob;
pub mod body;
pub mod checks;
pub mod config;
pub mod contacts;
pub mod detector;
pub mod dtw;
pub mod events;
pub mod format;
pub mod frames;
pub mod int8;
pub mod joint;
pub mod kinematics;
pub mod math;
pub mod network;
pub mod plausible;
pub mod reference;
pub mod resample;
pub mod retarget;
pub mod score;
pub mod sequence;
pub mod session;
pub mod setup;
pub mod skeleton;
pub mod tally;
pub mod weights;
pub mod wire;

/// A position or offset in metres (+Y up).
pub type Vec3 = nalgebra::Vector3<f32>;

/// A rotation.
pub type Quat = nalgebra::UnitQuaternion<f32>;
