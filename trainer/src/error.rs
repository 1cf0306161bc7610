//! The one error type of the training data pipeline, wrapping the core's and the adapters'.

use crate::golfgen::GenError;
use posecoach_core::contacts::ContactError;
use posecoach_core::events::EventError;
use posecoach_core::kinematics::LengthError;
use posecoach_core::retarget::RetargetError;
use posecoach_core::skeleton::SkeletonError;
use posecoach_io::{FileError, LimitError};
use posecoach_teachfile::Error as TeachFileError;
use std::fmt;

/// Why a character, clip, pair or metric could not be made.
#[derive(Debug)]
pub enum Error {
    /// A motion file could not be read.
    File(FileError),
    /// A skeleton could not be built (a format without a joint table, a malformed tree).
    Skeleton(SkeletonError),
    /// A frame does not fit its skeleton.
    Length(LengthError),
    /// The analytic retargeter refused a skeleton or frame.
    Retarget(RetargetError),
    /// Swing events could not be found in a coach's or ground truth's swing.
    Events(EventError),
    /// Golf's contacts could not be applied to a retargeted swing.
    Contacts(ContactError),
    /// Two motions compared frame by frame differ in frames or joints.
    #[allow(missing_docs)]
    Mismatch { expected: usize, actual: usize },
    /// A split has no clips to sample from.
    NoClips,
    /// A motion is too short for a window: `expected` frames from the window's start, `actual`
    /// there.
    #[allow(missing_docs)]
    TooShort { expected: usize, actual: usize },
    /// A batch needs at least one window.
    EmptyBatch,
    /// A synthetic swing could not be generated.
    Golf(GenError),
    /// A checkpoint could not be written or read.
    Checkpoint(String),
    /// A motion would be resampled beyond the readers' limits.
    Limit(LimitError),
    /// A float weights file or checkpoint is damaged (its CRC), of a version no longer read,
    /// or states a header word beyond its bound ([`posecoach_teachfile`]): found before
    /// anything is allocated for it.
    TeachFile(TeachFileError),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::File(e) => e.fmt(f),
            Error::Skeleton(e) => write!(f, "skeleton: {e}"),
            Error::Length(e) => write!(f, "frame: {e}"),
            Error::Retarget(e) => write!(f, "analytic retargeter: {e}"),
            Error::Events(e) => write!(f, "swing events: {e}"),
            Error::Contacts(e) => write!(f, "contacts: {e}"),
            Error::Mismatch { expected, actual } => write!(
                f,
                "motions differ in size: expected {expected} samples, got {actual}"
            ),
            Error::NoClips => f.write_str("no clips in this split: is the data folder complete?"),
            Error::TooShort { expected, actual } => write!(
                f,
                "a window needs {expected} frames from its start, the motion has {actual}: start earlier"
            ),
            Error::EmptyBatch => f.write_str("a batch needs at least one window"),
            Error::Golf(e) => write!(f, "synthetic swing: {e}"),
            Error::Checkpoint(why) => write!(f, "checkpoint: {why}"),
            Error::Limit(e) => write!(f, "resampling: {e}"),
            Error::TeachFile(e) => write!(f, "float weights: {e}"),
        }
    }
}

impl std::error::Error for Error {}

macro_rules! from {
    ($($source:ty => $variant:ident),*) => {$(
        impl From<$source> for Error {
            fn from(e: $source) -> Self {
                Error::$variant(e)
            }
        }
    )*};
}

from!(FileError => File, SkeletonError => Skeleton, LengthError => Length,
      RetargetError => Retarget, EventError => Events, ContactError => Contacts, GenError => Golf,
      LimitError => Limit, TeachFileError => TeachFile);
