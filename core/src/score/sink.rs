//! What scoring tells a session as it goes ([`crate::session`]): each swing's body-level
//! results, then, where the session takes the swing, every judged joint's offset at every
//! event, which a report keeps only past their thresholds.

use super::tempo::PhaseTempo;
use crate::checks::BodyDeviation;
use crate::events::{Event, Side};
use crate::joint::Joint;
use crate::sequence::Gap;
use crate::Vec3;

/// One swing's body-level results, as a [`Sink`] hears them.
#[derive(Clone, Copy, Debug)]
pub struct BodyLevel<'a> {
    /// The golfer's lead side.
    pub lead: Side,
    /// Each phase's tempo.
    pub tempo: &'a [PhaseTempo; 3],
    /// How long the hands paused at the top, the student's and the coach's, seconds.
    pub pause_s: (f32, f32),
    /// The body checks both swings could be measured at.
    pub body: &'a [BodyDeviation],
    /// For each of them, in their order, how fast the coach's value moves at its position,
    /// its unit per second (empty where the teller knows none: a report keeps none).
    pub coach_rate: &'a [f32],
    /// The sequence's gaps both swings could be measured at.
    pub gaps: &'a [Gap],
}

/// A receiver of one swing's results as [`super::compare`] finds them.
pub trait Sink {
    /// The swing's body-level results; whether to be told its joints' offsets.
    fn body(&mut self, swing: &BodyLevel<'_>) -> bool;

    /// A joint at an event (`at`: the event, the skeleton's index of the joint and the joint):
    /// its offset from the coach beyond its usual one and the offset's uncertainty (one
    /// standard deviation) along each stance axis (toward the target, toward the ball, up),
    /// metres.
    fn offset(&mut self, at: (Event, usize, Joint), offset: Vec3, uncertainty: Vec3);
}

/// No receiver: a swing scored on its own.
impl Sink for () {
    fn body(&mut self, _: &BodyLevel<'_>) -> bool {
        false
    }

    fn offset(&mut self, _: (Event, usize, Joint), _: Vec3, _: Vec3) {}
}
