//! The `posecoach` command-line tool's commands, as a library so that tests replay logs and
//! score swings through exactly the code the tool runs.
//!
//! Each command module has clap `Args` and a `run` that returns the text to print. The `learn`
//! feature adds the `learn` module's commands (train, distill, export, finetune, eval) and float
//! teacher weights on `score` and `retarget` (through [`teacher`]).

pub mod bench;
pub mod bridge;
pub mod coaches;
pub mod coaching;
pub mod demo;
pub mod device_sim;
pub mod failure;
pub mod html;
pub mod input;
pub mod inspect;
#[cfg(feature = "learn")]
pub mod learn;
pub mod phone;
pub mod progress;
pub mod reference;
pub mod replay;
pub mod report;
pub mod retarget;
pub mod score;
pub mod session;
pub mod swings;
pub mod synth;
pub mod synth_imu;
pub mod table;
pub mod teacher;
pub mod tpose;
