//! The caller's buffers a session runs in, and their sizing: every buffer belongs to the
//! caller (statics on a device), sized once by [`BufferLens`].

use super::RING_S;
use posecoach_core::config::MAX_SWING_FRAMES;
use posecoach_core::frames::Mm;
use posecoach_core::network;
use posecoach_core::score;
use posecoach_core::session::JointTallies;
use posecoach_core::weights::Architecture;
use posecoach_core::Vec3;

/// Lengths of the buffers a session needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferLens {
    /// Positions of the detector's history, in millimetres.
    pub ring: usize,
    /// Positions of the virtual coach, in millimetres.
    pub coach: usize,
    /// Scoring floats.
    pub floats: usize,
    /// Scoring bytes.
    pub bytes: usize,
    /// Masks of the joints the pose stream was unsure of, one per frame of the ring.
    pub unsure: usize,
    /// The range session's tallies of each joint ([`JointTallies`]).
    pub tallies: usize,
}

impl BufferLens {
    /// For students of up to `joints` joints, coaches of up to `coach_frames` frames at the
    /// model rate ([`Coach::frames_at`](super::Coach::frames_at)) and model rates up to `rate_hz`.
    pub const fn new(joints: usize, coach_frames: usize, rate_hz: u16) -> BufferLens {
        let ring_frames = (RING_S * rate_hz as f32) as usize;
        // A swing is scored in the ring, so it is never longer than the ring.
        let swing = if ring_frames < MAX_SWING_FRAMES {
            ring_frames
        } else {
            MAX_SWING_FRAMES
        };
        let scratch = score::scratch_len(swing, coach_frames);
        BufferLens {
            ring: joints * ring_frames,
            coach: joints * coach_frames,
            floats: scratch.floats,
            bytes: scratch.bytes,
            unsure: ring_frames,
            tallies: joints,
        }
    }

    /// These lengths with a ring that also holds, while the session is set up, the int8
    /// network `a`'s input (`coach_frames` frames of a coach of `coach_joints` joints, `f32`
    /// metres from the ring's first 4-byte boundary) and its scratch, for students of up to
    /// `joints` joints.
    pub const fn with_network(
        self,
        a: &Architecture,
        joints: usize,
        coach_joints: usize,
        coach_frames: usize,
    ) -> BufferLens {
        let bytes = network::scratch_len(a, coach_joints, joints);
        let room = coach_frames * coach_joints * core::mem::size_of::<Vec3>()
            + bytes.next_multiple_of(core::mem::size_of::<Vec3>())
            + core::mem::align_of::<Vec3>();
        let ring = room.div_ceil(core::mem::size_of::<Mm>());
        BufferLens {
            ring: if ring > self.ring { ring } else { self.ring },
            ..self
        }
    }
}

/// The caller's buffers, at least [`BufferLens`] long.
#[derive(Debug)]
pub struct Buffers<'b> {
    /// The detector's history, in millimetres (and the network's room while a session is set
    /// up).
    pub ring: &'b mut [Mm],
    /// The virtual coach, in millimetres.
    pub coach: &'b mut [Mm],
    /// Scoring floats.
    pub floats: &'b mut [f32],
    /// Scoring bytes.
    pub bytes: &'b mut [u8],
    /// Masks of the joints the pose stream was unsure of, one per frame.
    pub unsure: &'b mut [u64],
    /// The range session's tallies, one per joint of the largest student.
    pub tallies: &'b mut [JointTallies],
}

/// [`Buffers`] of the given lengths on the heap, for host tools and tests.
#[cfg(feature = "std")]
#[derive(Clone, Debug)]
pub struct OwnedBuffers {
    ring: std::vec::Vec<Mm>,
    coach: std::vec::Vec<Mm>,
    floats: std::vec::Vec<f32>,
    bytes: std::vec::Vec<u8>,
    unsure: std::vec::Vec<u64>,
    tallies: std::vec::Vec<JointTallies>,
}

#[cfg(feature = "std")]
impl OwnedBuffers {
    /// Zeroed buffers of `lens`.
    pub fn new(lens: BufferLens) -> OwnedBuffers {
        OwnedBuffers {
            ring: std::vec![[0; 3]; lens.ring],
            coach: std::vec![[0; 3]; lens.coach],
            floats: std::vec![0.0; lens.floats],
            bytes: std::vec![0; lens.bytes],
            unsure: std::vec![0; lens.unsure],
            tallies: std::vec![JointTallies::EMPTY; lens.tallies],
        }
    }

    /// The buffers, for [`Session::new`](super::Session::new).
    pub fn buffers(&mut self) -> Buffers<'_> {
        Buffers {
            ring: &mut self.ring,
            coach: &mut self.coach,
            floats: &mut self.floats,
            bytes: &mut self.bytes,
            unsure: &mut self.unsure,
            tallies: &mut self.tallies,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scoring_scratch_is_sized_for_a_swing_as_long_as_the_ring() {
        let at_30 = BufferLens::new(17, 55, 30);
        assert_eq!(at_30.ring, 17 * 180);
        assert_eq!(at_30.floats, score::scratch_len(180, 55).floats);
        let at_60 = BufferLens::new(17, 110, 60);
        assert_eq!(
            at_60.floats,
            score::scratch_len(MAX_SWING_FRAMES, 110).floats
        );
    }
}
