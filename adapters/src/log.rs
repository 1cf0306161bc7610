//! Recorded sessions (`.pclog`): exactly the bytes a device reads from its serial link.
//!
//! ```text
//! log    = header · wire bytes
//! header = "PCLOG" · log version:u8 (=1) · wire version:u8 · flags:u8 (=0)
//! ```
//!
//! The wire bytes are frames of the [wire protocol](posecoach_core::wire) back to back, as
//! they arrived: a session's `StudentProfile`, `Config`, `CoachSelect` and `SensorLayout`,
//! then its `PoseFrame`s or `ImuSample`s, whose own timestamps carry the timing. Damage in the
//! bytes is the decoder's business, as on the device: [`LogReader`] hands back the messages
//! that survive and counts the rest.
//!
//! ```
//! use posecoach_adapters::log::{header, LogReader};
//! use posecoach_core::wire::{encode, Message, MAX_FRAME};
//!
//! let mut log = header().to_vec();
//! let mut frame = [0u8; MAX_FRAME];
//! let n = encode(&Message::CoachSelect { seq: 1, coach: 1 }, &mut frame).unwrap();
//! log.extend_from_slice(&frame[..n]);
//! let messages: Vec<Message> = LogReader::new(&log).unwrap().collect();
//! assert_eq!(messages, [Message::CoachSelect { seq: 1, coach: 1 }]);
//! ```

use posecoach_core::wire::{self, Counters, Decoder, Message};

/// First bytes of every log.
pub const MAGIC: [u8; 5] = *b"PCLOG";
/// Version of the log layout.
pub const LOG_VERSION: u8 = 1;
/// Bytes before the wire bytes.
pub const HEADER_LEN: usize = 8;

/// The header of a log written now.
pub const fn header() -> [u8; HEADER_LEN] {
    [
        MAGIC[0],
        MAGIC[1],
        MAGIC[2],
        MAGIC[3],
        MAGIC[4],
        LOG_VERSION,
        wire::VERSION,
        0,
    ]
}

/// Why bytes are not a log this reader can replay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LogError {
    /// Shorter than the header, or not starting with [`MAGIC`].
    NotALog,
    /// A log layout version this reader does not know.
    LogVersion(u8),
    /// Frames of a wire protocol version this reader does not speak.
    WireVersion(u8),
    /// Flags this reader does not know.
    Flags(u8),
}

impl core::fmt::Display for LogError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LogError::NotALog => f.write_str("not a posecoach log (no `PCLOG` header)"),
            LogError::LogVersion(v) => {
                write!(f, "log layout version {v}; this build reads {LOG_VERSION}")
            }
            LogError::WireVersion(v) => write!(
                f,
                "wire protocol version {v}; this build speaks {}",
                wire::VERSION
            ),
            LogError::Flags(v) => write!(f, "unknown log flags {v:#04x}"),
        }
    }
}

impl core::error::Error for LogError {}

/// The messages of a log, in order.
#[derive(Clone, Debug)]
pub struct LogReader<'a> {
    bytes: &'a [u8],
    cut: bool,
    decoder: Decoder,
}

impl<'a> LogReader<'a> {
    /// Checks the header of `log` and reads from the first wire byte.
    ///
    /// # Errors
    /// [`LogError`] for a missing or unknown header.
    pub fn new(log: &'a [u8]) -> Result<LogReader<'a>, LogError> {
        let (head, bytes) = log
            .split_first_chunk::<HEADER_LEN>()
            .ok_or(LogError::NotALog)?;
        if head[..MAGIC.len()] != MAGIC {
            return Err(LogError::NotALog);
        }
        let [.., log_version, wire_version, flags] = *head;
        if log_version != LOG_VERSION {
            return Err(LogError::LogVersion(log_version));
        }
        if wire_version != wire::VERSION {
            return Err(LogError::WireVersion(wire_version));
        }
        if flags != 0 {
            return Err(LogError::Flags(flags));
        }
        Ok(LogReader {
            bytes,
            cut: bytes.last().is_some_and(|&b| b != 0),
            decoder: Decoder::new(),
        })
    }

    /// Whether the log ends inside a frame: a whole log ends with a frame's delimiter (0), so
    /// one that does not was cut short and its last frame is lost.
    pub fn cut(&self) -> bool {
        self.cut
    }

    /// Frames read and dropped so far.
    pub fn counters(&self) -> Counters {
        self.decoder.counters()
    }

    /// Wire bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.bytes.len()
    }

    /// Reads to the end of the next good frame and lends its message to `on_message`, as a
    /// device's decoder does ([`Decoder::push`]); `false` once the log holds no more.
    pub fn read(&mut self, on_message: impl FnOnce(&Message)) -> bool {
        let mut on_message = Some(on_message);
        while on_message.is_some() && !self.bytes.is_empty() {
            // Up to and with the next delimiter: at most one frame.
            let end = self
                .bytes
                .iter()
                .position(|&b| b == 0)
                .map_or(self.bytes.len(), |at| at + 1);
            let (frame, rest) = self.bytes.split_at(end);
            self.bytes = rest;
            self.decoder.push_all(frame, |m| {
                if let Some(f) = on_message.take() {
                    f(m);
                }
            });
        }
        on_message.is_none()
    }
}

/// Owned messages, for the host: each is a clone of the one [`LogReader::read`] lends.
impl Iterator for LogReader<'_> {
    type Item = Message;

    fn next(&mut self) -> Option<Message> {
        let mut got = None;
        self.read(|m| got = Some(m.clone()));
        got
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use posecoach_core::wire::{encode, MAX_FRAME};
    use std::vec::Vec;

    fn log(messages: &[Message]) -> Vec<u8> {
        let mut out = header().to_vec();
        for m in messages {
            let mut frame = [0u8; MAX_FRAME];
            let n = encode(m, &mut frame).unwrap();
            out.extend_from_slice(&frame[..n]);
        }
        out
    }

    #[test]
    fn a_log_cut_inside_a_frame_says_so() {
        let whole = log(&[Message::Ack { seq: 7 }, Message::Ack { seq: 8 }]);
        assert!(!LogReader::new(&whole).unwrap().cut());
        let cut = &whole[..whole.len() - 2];
        let reader = LogReader::new(cut).unwrap();
        assert!(reader.cut());
        assert_eq!(reader.count(), 1);
        assert!(!LogReader::new(&whole[..HEADER_LEN]).unwrap().cut());
    }

    #[test]
    fn headers_are_checked() {
        let good = log(&[]);
        assert!(LogReader::new(&good).is_ok());
        assert_eq!(LogReader::new(&good[..7]).err(), Some(LogError::NotALog));
        assert_eq!(
            LogReader::new(b"PCLOX\x01\x01\x00").err(),
            Some(LogError::NotALog)
        );
        assert_eq!(
            LogReader::new(b"PCLOG\x02\x01\x00").err(),
            Some(LogError::LogVersion(2))
        );
        assert_eq!(
            LogReader::new(b"PCLOG\x01\x09\x00").err(),
            Some(LogError::WireVersion(9))
        );
        assert_eq!(
            LogReader::new(&[b'P', b'C', b'L', b'O', b'G', 1, wire::VERSION, 0x80]).err(),
            Some(LogError::Flags(0x80))
        );
    }

    #[test]
    fn damaged_frames_are_counted_and_skipped() {
        let messages = [
            Message::CoachSelect { seq: 1, coach: 1 },
            Message::Ack { seq: 2 },
            Message::Ack { seq: 3 },
        ];
        let mut bytes = log(&messages);
        // Flip a byte inside the second frame.
        let second = HEADER_LEN + bytes[HEADER_LEN..].iter().position(|&b| b == 0).unwrap() + 2;
        bytes[second] ^= 0x40;
        let mut reader = LogReader::new(&bytes).unwrap();
        let got: Vec<Message> = reader.by_ref().collect();
        assert_eq!(got, [messages[0].clone(), messages[2].clone()]);
        let c = reader.counters();
        assert_eq!((c.frames_ok, c.crc_errors + c.malformed), (2, 1));
        assert_eq!(reader.remaining(), 0);
    }
}
