//! Why the session refuses a message, and the `Nack` a phone hears for it.

use super::RATES_HZ;
use crate::imu::ImuError;
use crate::pose_stream::StreamError;
use posecoach_core::detector::DetectorError;
use posecoach_core::events::EventError;
use posecoach_core::format::Format;
use posecoach_core::plausible::Implausible;
use posecoach_core::skeleton::SkeletonError;
use posecoach_core::wire::NackReason;

/// Why a message was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refusal {
    /// Pose frames or a sensor layout before any `StudentProfile`.
    NoProfile,
    /// The profile's keypoints do not make a skeleton.
    Profile(SkeletonError),
    /// The profile's body is beyond human limits.
    Implausible(Implausible),
    /// The profile's head is not above its feet along +Y: frames sent y-down (a pose
    /// estimator's image axis, as MediaPipe's world landmarks are) or a body lying down.
    NotUpright,
    /// The profile's format has no joint table, or its keypoint count is wrong.
    ProfileFormat(Format),
    /// No stored coach reference has this number.
    UnknownCoach(u16),
    /// The buffers are too small for this student, coach or rate.
    Buffers,
    /// A set-up that would change the session while a swing may be under way: refused so that
    /// the swing is not lost; the phone sends it again (it is taken once the golfer is still).
    SwingUnderWay,
    /// A model rate outside [`RATES_HZ`] or a zero band.
    Config,
    /// The student's skeleton lacks what swing detection needs.
    Detector(DetectorError),
    /// The pose frame does not fit the stream.
    Stream(StreamError),
    /// The coach cannot be retargeted onto the student (degenerate skeleton).
    Retarget,
    /// No swing found in the coach reference on the student's body.
    CoachSwing(EventError),
    /// IMU samples before a `SensorLayout`, or pose frames after one.
    Input,
    /// The layout does not fit the student, or a sample is degenerate.
    Imu(ImuError),
}

impl Refusal {
    /// The reason a `Nack` gives: the message came at the wrong time, did not fit the session
    /// now, or is wrong in itself.
    pub fn nack_reason(self) -> NackReason {
        match self {
            Refusal::NoProfile | Refusal::Input => NackReason::Unexpected,
            Refusal::Buffers | Refusal::SwingUnderWay => NackReason::Busy,
            _ => NackReason::Invalid,
        }
    }
}

impl core::fmt::Display for Refusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Refusal::NoProfile => {
                f.write_str("pose frames or a sensor layout before a student profile")
            }
            Refusal::Profile(e) => write!(f, "student profile: {e}"),
            Refusal::Implausible(e) => write!(f, "student profile: {e}"),
            Refusal::NotUpright => f.write_str(
                "student profile: the head is not above the feet along +Y (upside down, as a \
                 y-down image axis sends it, or lying down): send +Y up",
            ),
            Refusal::ProfileFormat(format) => write!(
                f,
                "student profile in format `{}` with no joint table or the wrong keypoint count",
                format.name()
            ),
            Refusal::UnknownCoach(n) => write!(f, "no coach reference number {n}"),
            Refusal::Buffers => f.write_str("buffers too small for this student, coach or rate"),
            Refusal::SwingUnderWay => f.write_str(
                "a set-up change while a swing may be under way: send it again once the golfer \
                 is still",
            ),
            Refusal::Config => write!(
                f,
                "model rate outside {} to {} Hz, or a zero band",
                RATES_HZ.0, RATES_HZ.1
            ),
            Refusal::Detector(e) => write!(f, "swing detection: {e}"),
            Refusal::Stream(e) => write!(f, "pose stream: {e}"),
            Refusal::Retarget => f.write_str("the coach cannot be retargeted onto the student"),
            Refusal::CoachSwing(e) => write!(f, "the coach reference on this student: {e}"),
            Refusal::Input => f.write_str(
                "IMU samples before a sensor layout, or pose frames in a session with IMUs",
            ),
            Refusal::Imu(e) => write!(f, "IMU: {e}"),
        }
    }
}
