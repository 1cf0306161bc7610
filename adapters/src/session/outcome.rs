//! What a message led to: a swing scored or not, or a refusal, and the frame a device sends
//! back for it.

use super::Refusal;
use posecoach_core::frames::Frames;
use posecoach_core::score::{Report, ScoreError};
use posecoach_core::session::Tendencies;
use posecoach_core::skeleton::Skeleton;
use posecoach_core::wire::Message;

/// Where a swing sits in the stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Swing {
    /// Swings found so far in this session, this one included.
    pub number: u32,
    /// Time of its first frame on the sender's clock, microseconds.
    pub start_us: u64,
    /// Its frames at the model rate.
    pub frames: usize,
    /// The coach reference it was scored against (as `CoachSelect` numbers them).
    pub coach: u16,
}

/// The two swings a report compares, on the student's skeleton: what a report view draws.
#[derive(Clone, Copy, Debug)]
pub struct Compared<'r> {
    /// The student's skeleton.
    pub skeleton: &'r Skeleton,
    /// The student's swing (as the detector's ring keeps it, in millimetres).
    pub student: Frames<'r>,
    /// Its frame rate.
    pub student_hz: f32,
    /// The virtual coach's swing (the coach retargeted onto the student, as the session keeps
    /// it in millimetres, read turned to face the student's target line).
    pub coach: Frames<'r>,
    /// Its frame rate.
    pub coach_hz: f32,
}

/// What a message led to.
#[derive(Debug)]
pub enum Outcome<'r> {
    /// A swing, scored.
    Scored {
        /// Where it is.
        swing: Swing,
        /// Its report.
        report: &'r Report,
        /// The swings the report compares.
        compared: Compared<'r>,
    },
    /// A swing that could not be scored (its events not found, or not like the coach's).
    Unscored {
        /// Where it is.
        swing: Swing,
        /// Why.
        error: ScoreError,
    },
    /// A set-up message was taken: applied, or the same as the one in force (a phone gets an
    /// `Ack`).
    Accepted,
    /// The message was refused (a phone gets a `Nack`).
    Refused(Refusal),
    /// The range session, after each swing scored and when asked (a phone gets a
    /// `SessionReport`).
    Session {
        /// Its tendencies.
        tendencies: &'r Tendencies<'r>,
        /// The coach its swings were scored against (`u16::MAX` before its first swing).
        coach: u16,
    },
}

impl Outcome<'_> {
    /// What a device answers to `message` when handling it led to this: a `SwingReport` for
    /// a scored swing, an `Ack` for a set-up message or session request taken, a `Nack` for a
    /// refusal (both of the message's `seq`; 0 for a message without one), a `SessionReport`
    /// for the session, nothing for a swing that could not be scored.
    pub fn reply(&self, message: &Message) -> Option<Message> {
        match self {
            Outcome::Scored { swing, report, .. } => Some(Message::SwingReport(
                report.to_wire(swing.number, swing.coach),
            )),
            Outcome::Unscored { .. } => None,
            Outcome::Accepted => Some(Message::Ack {
                seq: message.seq().unwrap_or(0),
            }),
            Outcome::Refused(why) => Some(Message::Nack {
                seq: message.seq().unwrap_or(0),
                reason: why.nack_reason(),
            }),
            Outcome::Session { tendencies, coach } => {
                Some(Message::SessionReport(tendencies.to_wire(*coach)))
            }
        }
    }
}
