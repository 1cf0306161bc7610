//! Which joints a live stream was unsure of, frame by frame, read for a swing cut from it.

/// Which joints a stream was unsure of, frame by frame: a ring of bit masks (bit `k` for
/// skeleton joint `k`) written at stream frame `n` into slot `n % ring.len()`, and where a swing
/// starts in the stream. A frame whose slot has since been written again counts as sure.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unsure<'a> {
    ring: &'a [u64],
    /// The slot of the swing's first frame.
    first: usize,
    /// The swing's frames whose masks the ring still holds, `from..to`.
    kept: (usize, usize),
    /// Joints the input never measures, unsure at every frame.
    never: u64,
}

impl<'a> Unsure<'a> {
    /// A swing starting at stream frame `start` of a stream that has pushed `seen` frames, its
    /// masks in `ring`.
    pub fn new(ring: &'a [u64], start: u64, seen: u64) -> Unsure<'a> {
        let len = ring.len() as u64;
        // Stream frame `n` is still held from `seen - len` up to `seen`.
        let frame = |n: u64| usize::try_from(n.saturating_sub(start)).unwrap_or(usize::MAX);
        Unsure {
            ring,
            first: start.checked_rem(len).unwrap_or(0) as usize,
            kept: if len == 0 {
                (0, 0)
            } else {
                (frame(seen.saturating_sub(len)), frame(seen))
            },
            never: 0,
        }
    }

    /// These masks, and the joints `never` (bit `k` for joint `k`) unsure at every frame: what
    /// the input does not measure (an IMU layout's unsensed limbs), which scoring then leaves
    /// out of every judgement as it does a joint the stream lost.
    pub fn with_never(self, never: u64) -> Unsure<'a> {
        Unsure { never, ..self }
    }

    /// The joints unsure at the swing's frame `frame`.
    pub fn at(&self, frame: usize) -> u64 {
        if !(self.kept.0..self.kept.1).contains(&frame) {
            return self.never;
        }
        // The slot of stream frame `start + frame`, without a 64-bit division.
        let len = self.ring.len();
        self.ring[(self.first + frame % len) % len] | self.never
    }
}

#[cfg(test)]
mod tests {
    use super::Unsure;

    #[test]
    fn unsure_masks_are_read_where_the_ring_still_holds_them() {
        // A ring of 4 slots after 10 frames: frames 6 to 9 are held, in slots 2, 3, 0, 1.
        let ring = [0b01, 0b10, 0b100, 0b1000];
        let swing = Unsure::new(&ring, 5, 10);
        assert_eq!(swing.at(0), 0); // frame 5: written over
        assert_eq!(swing.at(1), 0b100); // frame 6
        assert_eq!(swing.at(4), 0b10); // frame 9
        assert_eq!(swing.at(5), 0); // frame 10: not yet pushed
        assert_eq!(Unsure::default().at(3), 0);
        let never = swing.with_never(0b1_0000);
        assert_eq!(never.at(0), 0b1_0000);
        assert_eq!(never.at(1), 0b1_0100);
        assert_eq!(Unsure::default().with_never(0b11).at(7), 0b11);
    }

    proptest::proptest! {
        #[test]
        fn unsure_reads_stream_frame_start_plus_frame_from_its_slot_while_the_ring_holds_it(
            len in 0usize..9,
            start in 0u64..(1 << 40),
            back in 0u64..60,
            frame in 0usize..60,
        ) {
            let ring: std::vec::Vec<u64> = (0..len as u64).map(|i| 1 << i).collect();
            let seen = (start + back).saturating_sub(20);
            // Stream frame n is in slot n % len, written over once n + len < seen.
            let n = start + frame as u64;
            let held = len > 0 && n < seen && n + len as u64 >= seen;
            let expected = if held { ring[(n % len as u64) as usize] } else { 0 };
            proptest::prop_assert_eq!(Unsure::new(&ring, start, seen).at(frame), expected);
        }
    }
}
