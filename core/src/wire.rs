//! The serial wire protocol between a device, the bridge and a phone.
//!
//! One frame carries one [`Message`]:
//!
//! ```text
//! COBS( version:u8 · postcard(Message) · crc32:u32 little-endian ) · 0x00
//! ```
//!
//! The CRC is CRC-32/ISO-HDLC (the zlib/Ethernet CRC) over the version byte and the postcard
//! bytes. A frame is at most [`MAX_FRAME`] bytes, delimiter included. [`Decoder`] takes bytes
//! one at a time or in chunks into a fixed buffer, hands back each good message, and after any
//! damage (bad COBS, bad CRC, another version, undecodable message, overlong frame) drops
//! bytes up to the next `0x00` and counts what went wrong in [`Counters`]; a frame of another
//! protocol version is owed a [`NackReason::Version`] ([`Decoder::reply`]). Nothing panics and
//! nothing allocates.
//!
//! ```
//! use posecoach_core::wire::{encode, Decoder, Message, MAX_FRAME};
//!
//! let mut frame = [0u8; MAX_FRAME];
//! let n = encode(&Message::Ack { seq: 7 }, &mut frame).unwrap();
//! let mut decoder = Decoder::new();
//! let mut got = None;
//! for &byte in &frame[..n] {
//!     decoder.push(byte, |message| got = Some(message.clone()));
//! }
//! assert_eq!(got, Some(Message::Ack { seq: 7 }));
//! assert_eq!(decoder.counters().frames_ok, 1);
//! ```

use crate::band::Band;
use crate::config::{BODY_LEVEL, MAX_ADVICE, MAX_CHECKS, MAX_DEVIATIONS, MAX_GAPS, MAX_SET_ASIDE};
use crate::format::Format;
use crate::joint::Joint;
use heapless::Vec as HVec;
use serde::{Deserialize, Serialize};

/// The postcard variant index of [`Message::PoseFrame`] (a varint of one byte), which every
/// pose frame's message starts with.
const POSE_FRAME: u8 = 0;
/// The postcard variant index of [`Message::ImuSample`].
const IMU_SAMPLE: u8 = 1;

/// Protocol version carried in every frame.
pub const VERSION: u8 = 6;
/// Largest frame on the wire, delimiter included.
pub const MAX_FRAME: usize = 640;
/// Most joints a pose frame or profile carries (BlazePose's 33 landmarks fit).
pub const MAX_WIRE_JOINTS: usize = 33;
/// Most IMUs a [`SensorLayout`] places.
pub const MAX_SENSORS: usize = 8;
/// Bytes of payload (version, message, CRC) a frame can hold.
pub const MAX_PAYLOAD: usize = MAX_FRAME - 1 - (MAX_FRAME - 1).div_ceil(254);

const _: () = assert!(cobs::max_encoding_length(MAX_PAYLOAD) < MAX_FRAME);

const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// One 3D pose from a camera pose estimator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseFrame {
    /// Sender's sequence number.
    pub seq: u32,
    /// Capture time, microseconds on the sender's clock.
    pub t_us: u64,
    /// Keypoint format of `joints_mm` (its keypoint order).
    pub format: Format,
    /// Keypoints in millimetres, +Y up.
    pub joints_mm: HVec<[i16; 3], MAX_WIRE_JOINTS>,
    /// Per keypoint confidence, 0 (none) to 255 (certain).
    pub confidence: HVec<u8, MAX_WIRE_JOINTS>,
}

/// One inertial sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImuSample {
    /// Which sensor (as the layout configuration numbers them).
    pub sensor: u8,
    /// Sample time, microseconds.
    pub t_us: u64,
    /// Acceleration in milli-g (±32 g).
    pub accel_mg: [i16; 3],
    /// Angular rate in tenths of a degree per second (±3276 °/s).
    pub gyro_ddps: [i16; 3],
    /// Magnetic field in tenths of a microtesla, where the sensor has a magnetometer.
    pub mag_dut: Option<[i16; 3]>,
}

/// The student's T-pose.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudentProfile {
    /// Keypoint format of `joints_mm`.
    pub format: Format,
    /// T-pose keypoints in millimetres, +Y up.
    pub joints_mm: HVec<[i16; 3], MAX_WIRE_JOINTS>,
}

/// Where one IMU is strapped.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorPlacement {
    /// The sensor's number in [`ImuSample::sensor`].
    pub sensor: u8,
    /// The joint whose incoming bone carries the sensor ([`Joint::Pelvis`]: the pelvis itself).
    pub joint: Joint,
    /// Nominal mounting: the sensor's orientation in the segment's rest frame, a unit
    /// quaternion `(w, x, y, z)` in units of 1/16384. Only used to fix a sensor's heading when
    /// it has no magnetometer.
    pub mounting_q14: [i16; 4],
}

/// Which IMU sits on which segment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SensorLayout {
    /// One entry per sensor.
    pub sensors: HVec<SensorPlacement, MAX_SENSORS>,
}

/// Scoring settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Config {
    /// Rate swings are resampled to, Hz.
    pub model_rate_hz: u16,
    /// The DTW band, in frames at that rate (on the wire, its radius then its `anchored` flag).
    pub band: Band,
}

/// What a device has counted since it started; each count stops at `u32::MAX`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Frames decoded.
    pub frames_ok: u32,
    /// Frames whose CRC did not match.
    pub crc_errors: u32,
    /// Frames with bad COBS or an undecodable message.
    pub malformed: u32,
    /// Frames of another protocol version (each answered with a `Nack`).
    pub versions: u32,
    /// Frames longer than [`MAX_FRAME`], dropped.
    pub overflows: u32,
    /// Messages or samples dropped for lack of room downstream.
    pub drops: u32,
}

/// One joint off at one position, in a compact form.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireDeviation {
    /// The position's index, P1 = 0 .. P10 = 9, as in [`SwingReport::student_positions`] (only
    /// GolfDB's eight events are judged: P1-P5, P7, P8, P10).
    pub position: u8,
    /// Canonical joint index.
    pub joint: u8,
    /// Direction: 0 toward target, 1 away, 2 toward ball, 3 away, 4 up, 5 down.
    pub direction: u8,
    /// Student minus coach in the stance frame, millimetres: toward target, toward ball, up.
    pub offset_mm: [i16; 3],
    /// The offset's uncertainty along it, millimetres.
    pub uncertainty_mm: u16,
}

/// One body check ([`crate::checks::CHECKS`]) in a compact form: the student's and the
/// coach's change since address and its uncertainty, in tenths of a degree for an angle and in
/// millimetres for a shift.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireCheck {
    /// Its index in `CHECKS`.
    pub check: u8,
    /// The student's change.
    pub student: i16,
    /// The coach's change.
    pub coach: i16,
    /// The difference's uncertainty (one standard deviation).
    pub uncertainty: u16,
}

/// One gap of the kinematic sequence ([`crate::sequence::GAPS`]) in a compact form: how long
/// after the first link's peak the second's comes, student and coach, and its uncertainty,
/// milliseconds (negative: before).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireGap {
    /// Its index in `GAPS`.
    pub gap: u8,
    /// The student's gap.
    pub student_ms: i16,
    /// The coach's gap.
    pub coach_ms: i16,
    /// The student's uncertainty (one standard deviation).
    pub uncertainty_ms: u16,
}

/// A swing's report, small enough for one frame (the frame correspondence stays on the device).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[cfg_attr(feature = "phone", derive(Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SwingReport {
    /// Swing number since start.
    pub swing: u32,
    /// The coach reference it was scored against (`CoachSelect`'s numbering).
    pub coach: u16,
    /// Score in hundredths (0..=10000).
    pub score_centi: u16,
    /// Student's frames of P1 to P10 at the model rate (`u16::MAX` where a swing has none: a
    /// putt has P1, P4, P7 and P10).
    pub student_positions: [u16; 10],
    /// Coach's frames of P1 to P10.
    pub coach_positions: [u16; 10],
    /// Student and coach durations of backswing, downswing, follow-through, milliseconds.
    pub phases_ms: [[u16; 2]; 3],
    /// Each phase's tempo verdict: 0 ok, 1 slow, 2 fast (given only where the ratio is clear
    /// of its uncertainty, so not to be recomputed from `phases_ms`).
    pub verdicts: [u8; 3],
    /// The deviations, largest per event first.
    pub deviations: HVec<WireDeviation, MAX_DEVIATIONS>,
    /// The body checks both swings could be measured at, in `CHECKS` order.
    pub checks: HVec<WireCheck, MAX_CHECKS>,
    /// The sequence's gaps both swings could be measured at, in `GAPS` order.
    pub gaps: HVec<WireGap, MAX_GAPS>,
}

/// One body-level quantity of a range session in a compact form: the session's estimate of
/// the student's value beside the coach's, its uncertainty and the golfer's swing-to-swing
/// spread net of the noise, in the unit [`SwingReport`] gives it: milliseconds for a phase,
/// the pause and a gap, tenths of a degree or millimetres for a body check.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireMetric {
    /// Which: 0-2 the backswing, downswing and follow-through, 3 the pause at the top, 4-12 a
    /// body check (`CHECKS` index + 4), 13-14 a gap of the sequence (`GAPS` index + 13).
    pub quantity: u8,
    /// Swings it was measured in.
    pub swings: u8,
    /// Of those, how many were past its tolerance above the coach's (slower, more).
    pub above: u8,
    /// And below (faster, less).
    pub below: u8,
    /// 0 within tolerance or not yet clear, 1 clearly above (slow), 2 clearly below (fast): as
    /// the session's advice judges it, so not to be recomputed.
    pub verdict: u8,
    /// The session's estimate of the student's value.
    pub student: i16,
    /// The coach's value.
    pub coach: i16,
    /// The estimate's uncertainty (one standard deviation; `u16::MAX`: none yet).
    pub uncertainty: u16,
    /// The golfer's swing-to-swing spread net of the noise (one standard deviation).
    pub spread: u16,
}

/// One of a range session's tendencies, in the order the session ranks them (causes before
/// the symptoms they may explain).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireTendency {
    /// What it is about: below [`BODY_LEVEL`] the [`WireMetric::quantity`] of that number,
    /// else the joint offset `spatial[item - BODY_LEVEL]`.
    pub item: u8,
    /// Swings it was measured in.
    pub swings: u8,
    /// Of those, how many were past the tolerance the way it says.
    pub past: u8,
}

/// A swing a range session set aside, and why.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireSetAside {
    /// The swing's number in the session, from 1.
    pub swing: u16,
    /// In how many body-level quantities it was unlike the session's other swings.
    pub unlike: u8,
    /// The [`WireMetric::quantity`] it was most unlike them in.
    pub worst: u8,
    /// How far off in that one, tenths of a predictive standard deviation.
    pub z_tenths: i16,
}

/// The question nearest to a tendency that a range session cannot settle yet.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WireOpen {
    /// A [`WireMetric::quantity`], or [`BODY_LEVEL`] for a joint's offset.
    pub quantity: u8,
    /// A joint's offset only (else 0): its position, P1 = 0 .. P10 = 9.
    pub position: u8,
    /// A joint's offset only (else 0): the canonical joint index.
    pub joint: u8,
    /// A joint's offset only (else 0): its direction, as [`WireDeviation::direction`].
    pub direction: u8,
    /// The estimate: the student's value less the coach's in the quantity's unit, or the
    /// joint's offset in millimetres.
    pub value: i16,
    /// Its uncertainty (`u16::MAX`: none yet).
    pub uncertainty: u16,
    /// About how many more swings would settle it.
    pub more_swings: u16,
}

/// What a range session's swings say together, small enough for one frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[cfg_attr(feature = "phone", derive(Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SessionReport {
    /// Swings heard since the session started, counted or set aside.
    pub swings: u16,
    /// Of those, swings counted.
    pub used: u16,
    /// The coach reference the session's swings were scored against.
    pub coach: u16,
    /// The body-level quantities measured in at least one swing, in `quantity` order.
    pub metrics: HVec<WireMetric, BODY_LEVEL>,
    /// The tendencies, most important first.
    pub tendencies: HVec<WireTendency, MAX_ADVICE>,
    /// The joint offsets the tendencies name, as [`SwingReport::deviations`]' entries with the
    /// session's estimates.
    pub spatial: HVec<WireDeviation, MAX_ADVICE>,
    /// The latest swings set aside.
    pub set_aside: HVec<WireSetAside, MAX_SET_ASIDE>,
    /// With no tendency yet, the nearest open question.
    pub open: Option<WireOpen>,
}

/// Without the `phone` feature a device does not decode the reports it sends: their payload
/// fails at once (the message's variant index is still read, so every other message keeps
/// its own), and the decoder counts the frame malformed.
#[cfg(not(feature = "phone"))]
macro_rules! undecodable {
    ($($report:ty),*) => {$(
        impl<'de> Deserialize<'de> for $report {
            fn deserialize<D: serde::Deserializer<'de>>(_: D) -> Result<Self, D::Error> {
                Err(serde::de::Error::custom("a report a device sends"))
            }
        }
    )*};
}

#[cfg(not(feature = "phone"))]
undecodable!(SwingReport, SessionReport);

/// Why a message was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NackReason {
    /// The message is not valid in the current state.
    Unexpected,
    /// The message's content is out of range.
    Invalid,
    /// No room to take it now.
    Busy,
    /// The frame is of another protocol version than the device's ([`VERSION`], the first
    /// byte of every frame it sends).
    Version,
}

/// Every message of protocol version [`VERSION`]. Without the `phone` feature, the messages a
/// phone sends do not encode ([`EncodeError::PhoneSide`]) and those a device sends do not decode
/// (counted malformed): a device links only its own half.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Message {
    /// Phone → device: a 3D pose.
    #[cfg_attr(not(feature = "phone"), serde(skip_serializing))]
    PoseFrame(PoseFrame),
    /// Device internal or device → phone on request: an IMU sample.
    ImuSample(ImuSample),
    /// Phone → device: the student's T-pose.
    #[cfg_attr(not(feature = "phone"), serde(skip_serializing))]
    StudentProfile {
        /// Sender's sequence number, which the device's `Ack` or `Nack` carries back.
        seq: u32,
        /// The T-pose.
        profile: StudentProfile,
    },
    /// Phone → device: which stored coach reference to use.
    #[cfg_attr(not(feature = "phone"), serde(skip_serializing))]
    CoachSelect {
        /// Sender's sequence number, as in `StudentProfile`.
        seq: u32,
        /// Reference number.
        coach: u16,
    },
    /// Phone → device: scoring settings.
    #[cfg_attr(not(feature = "phone"), serde(skip_serializing))]
    Config {
        /// Sender's sequence number, as in `StudentProfile`.
        seq: u32,
        /// The settings.
        config: Config,
    },
    /// Device → phone: a scored swing.
    SwingReport(SwingReport),
    /// Device → phone: counters.
    Status(Counters),
    /// Either way: message `seq` taken.
    Ack {
        /// Sequence number acknowledged.
        seq: u32,
    },
    /// Either way: message `seq` refused.
    Nack {
        /// Sequence number refused.
        seq: u32,
        /// Why.
        reason: NackReason,
    },
    /// Phone → device: where the IMUs are.
    #[cfg_attr(not(feature = "phone"), serde(skip_serializing))]
    SensorLayout {
        /// Sender's sequence number, as in `StudentProfile`.
        seq: u32,
        /// The sensors.
        layout: SensorLayout,
    },
    /// Device → phone: the range session, after each `SwingReport` and on request.
    SessionReport(SessionReport),
    /// Phone → device: send the range session (`reset`: start a new one first).
    #[cfg_attr(not(feature = "phone"), serde(skip_serializing))]
    SessionRequest {
        /// Sender's sequence number, as in `StudentProfile`.
        seq: u32,
        /// Start a new session before answering.
        reset: bool,
    },
}

impl Message {
    /// The sender's sequence number of a message that carries one (a pose frame or a set-up
    /// message), which the device's `Ack` or `Nack` for it carries back.
    pub fn seq(&self) -> Option<u32> {
        match self {
            Message::PoseFrame(PoseFrame { seq, .. })
            | Message::StudentProfile { seq, .. }
            | Message::CoachSelect { seq, .. }
            | Message::Config { seq, .. }
            | Message::SensorLayout { seq, .. }
            | Message::SessionRequest { seq, .. } => Some(*seq),
            _ => None,
        }
    }

    /// Whether only a device sends this message (`SwingReport`, `SessionReport`, `Status`): a
    /// device's [`Decoder`] drops it.
    pub fn from_device(&self) -> bool {
        matches!(
            self,
            Message::SwingReport(_) | Message::SessionReport(_) | Message::Status(_)
        )
    }

    /// Whether this is a set-up message (`StudentProfile`, `CoachSelect`, `Config`,
    /// `SensorLayout`): one a device acknowledges.
    pub fn is_setup(&self) -> bool {
        matches!(
            self,
            Message::StudentProfile { .. }
                | Message::CoachSelect { .. }
                | Message::Config { .. }
                | Message::SensorLayout { .. }
        )
    }
}

/// Why a message could not be framed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The message does not fit in [`MAX_PAYLOAD`] bytes, or `out` is too short.
    TooLong,
    /// A message a phone sends, encoded without the `phone` feature.
    PhoneSide,
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EncodeError::TooLong => {
                write!(f, "the message does not fit in a {MAX_FRAME}-byte frame")
            }
            EncodeError::PhoneSide => {
                write!(f, "a phone's message, encoded without the phone feature")
            }
        }
    }
}

impl core::error::Error for EncodeError {}

/// Frames `message` into `out`; returns the frame's length, delimiter included.
///
/// # Errors
/// [`EncodeError::TooLong`] if the message does not fit, [`EncodeError::PhoneSide`] for a
/// phone's message without the `phone` feature.
pub fn encode(message: &Message, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut payload = [0u8; MAX_PAYLOAD];
    payload[0] = VERSION;
    let body = postcard::to_slice(message, &mut payload[1..MAX_PAYLOAD - 4])
        .map_err(|e| match e {
            postcard::Error::SerializeBufferFull => EncodeError::TooLong,
            _ => EncodeError::PhoneSide,
        })?
        .len();
    let crc = CRC.checksum(&payload[..1 + body]);
    payload[1 + body..5 + body].copy_from_slice(&crc.to_le_bytes());
    let n = cobs::try_encode(&payload[..5 + body], out).map_err(|_| EncodeError::TooLong)?;
    let delimiter = out.get_mut(n).ok_or(EncodeError::TooLong)?;
    *delimiter = 0;
    Ok(n + 1)
}

/// A streaming frame decoder with a fixed [`MAX_FRAME`] buffer: a device's
/// ([`Decoder::new`]), which drops the messages a device sends ([`Message::from_device`]) as
/// malformed, or with the `phone` feature a phone's ([`Decoder::phone`]), which takes every
/// message.
#[derive(Clone, Debug)]
pub struct Decoder {
    buffer: [u8; MAX_FRAME],
    len: usize,
    /// Skipping to the next delimiter after an overflow.
    skipping: bool,
    counters: Counters,
    /// A frame of another version came since [`Decoder::reply`] was last asked.
    owed: bool,
    /// Whether it takes the messages a device sends.
    phone: bool,
}

impl Default for Decoder {
    fn default() -> Self {
        Decoder::new()
    }
}

impl Decoder {
    /// An empty decoder.
    pub const fn new() -> Decoder {
        Decoder {
            buffer: [0; MAX_FRAME],
            len: 0,
            skipping: false,
            owed: false,
            phone: false,
            counters: Counters {
                frames_ok: 0,
                crc_errors: 0,
                malformed: 0,
                versions: 0,
                overflows: 0,
                drops: 0,
            },
        }
    }

    /// An empty decoder for a phone (or the bridge): it takes every message, those a device
    /// sends too.
    #[cfg(feature = "phone")]
    pub const fn phone() -> Decoder {
        Decoder {
            phone: true,
            ..Decoder::new()
        }
    }

    /// What has been decoded and dropped so far.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Takes one byte; when it completes a good frame, hands the frame's message to
    /// `on_message`. The message is lent, not returned: a [`Message`] is as large as its largest
    /// variant (the `SwingReport`, some 470 bytes), and each move of one out of the decoder cost
    /// more than decoding an IMU sample (its 31-byte frame: COBS, CRC and postcard, about 1 200
    /// instructions on a Cortex-M4F).
    pub fn push(&mut self, byte: u8, on_message: impl FnOnce(&Message)) {
        if byte == 0 {
            self.end(on_message);
        } else {
            self.extend(&[byte]);
        }
    }

    /// Takes a chunk of bytes and hands `on_message` each good frame's message in it, copying
    /// the bytes between delimiters as runs (a byte at a time cost some 20 instructions).
    pub fn push_all(&mut self, bytes: &[u8], mut on_message: impl FnMut(&Message)) {
        let mut rest = bytes;
        while let Some(at) = rest.iter().position(|&b| b == 0) {
            self.extend(&rest[..at]);
            self.end(&mut on_message);
            rest = &rest[at + 1..];
        }
        self.extend(rest);
    }

    /// Appends bytes of a frame (no delimiter among them); a frame grown past [`MAX_FRAME`] is
    /// counted once and skipped to its delimiter.
    fn extend(&mut self, bytes: &[u8]) {
        if self.skipping || bytes.is_empty() {
            return;
        }
        match self.buffer.get_mut(self.len..self.len + bytes.len()) {
            Some(free) if self.len + bytes.len() < MAX_FRAME => {
                free.copy_from_slice(bytes);
                self.len += bytes.len();
            }
            _ => {
                self.counters.overflows = self.counters.overflows.saturating_add(1);
                self.skipping = true;
                self.len = 0;
            }
        }
    }

    /// A delimiter: the frame it ends is checked and decoded, and counted by its fate.
    fn end(&mut self, on_message: impl FnOnce(&Message)) {
        let len = core::mem::take(&mut self.len);
        if core::mem::take(&mut self.skipping) || len == 0 {
            return;
        }
        let counter = match self.frame(len, on_message) {
            Ok(()) => &mut self.counters.frames_ok,
            Err(FrameFault::Crc) => &mut self.counters.crc_errors,
            Err(FrameFault::Malformed) => &mut self.counters.malformed,
            Err(FrameFault::Version) => {
                self.owed = true;
                &mut self.counters.versions
            }
        };
        *counter = counter.saturating_add(1);
    }

    /// What a device owes its peer for the frames refused since it last asked: one `Nack` (seq
    /// 0, [`NackReason::Version`]) however many frames of another protocol version came, so
    /// that a phone speaking another version learns why nothing it sends is taken.
    pub fn reply(&mut self) -> Option<Message> {
        core::mem::take(&mut self.owed).then_some(Message::Nack {
            seq: 0,
            reason: NackReason::Version,
        })
    }

    /// Checks and decodes the frame of `len` bytes in the buffer, and lends its message to
    /// `on_message`, decoded in place.
    fn frame(&mut self, len: usize, on_message: impl FnOnce(&Message)) -> Result<(), FrameFault> {
        let payload = &mut self.buffer[..len];
        let n = cobs::decode_in_place(payload).map_err(|_| FrameFault::Malformed)?;
        let payload = payload.get(..n).ok_or(FrameFault::Malformed)?;
        if n < 6 {
            return Err(FrameFault::Malformed);
        }
        let (body, crc) = payload.split_at(n - 4);
        let expected = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
        if CRC.checksum(body) != expected {
            return Err(FrameFault::Crc);
        }
        if body[0] != VERSION {
            return Err(FrameFault::Version);
        }
        // Without the `phone` feature a device cannot decode the reports it sends; with it, a
        // device's decoder drops them (and `Status`) all the same, so it counts them alike
        // either way.
        match &decode(&body[1..]) {
            Ok(m) if self.phone || !m.from_device() => {
                on_message(m);
                Ok(())
            }
            _ => Err(FrameFault::Malformed),
        }
    }
}

/// A frame's message from its postcard bytes. The stream's two messages are decoded as their
/// variant's fields: decoding the enum moves a whole [`Message`] (some 470 bytes) through
/// serde's layers, two thirds of an IMU sample's cost. Kept out of line so that its
/// temporaries are off the stack by the time the message is handled.
#[inline(never)]
fn decode(message: &[u8]) -> Result<Message, postcard::Error> {
    match message {
        [POSE_FRAME, fields @ ..] => postcard::from_bytes(fields).map(Message::PoseFrame),
        [IMU_SAMPLE, fields @ ..] => postcard::from_bytes(fields).map(Message::ImuSample),
        _ => postcard::from_bytes(message),
    }
}

enum FrameFault {
    Crc,
    Malformed,
    Version,
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn frame(message: &Message) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = encode(message, &mut out).unwrap();
        out[..n].to_vec()
    }

    /// Every message in `bytes`, as a phone takes them, and the counts.
    fn decode_all(bytes: &[u8]) -> (Vec<Message>, Counters) {
        let mut decoder = Decoder::phone();
        let mut got = Vec::new();
        decoder.push_all(bytes, |m| got.push(m.clone()));
        (got, decoder.counters())
    }

    fn joints() -> impl Strategy<Value = HVec<[i16; 3], MAX_WIRE_JOINTS>> {
        prop::collection::vec(any::<[i16; 3]>(), 0..=MAX_WIRE_JOINTS)
            .prop_map(|v| v.into_iter().collect())
    }

    fn format() -> impl Strategy<Value = Format> {
        prop::sample::select(Format::BUILT_IN.to_vec())
    }

    fn message() -> impl Strategy<Value = Message> {
        prop_oneof![
            (
                any::<u32>(),
                any::<u64>(),
                format(),
                joints(),
                prop::collection::vec(any::<u8>(), 0..=MAX_WIRE_JOINTS)
            )
                .prop_map(|(seq, t_us, format, joints_mm, c)| Message::PoseFrame(
                    PoseFrame {
                        seq,
                        t_us,
                        format,
                        joints_mm,
                        confidence: c.into_iter().collect()
                    }
                )),
            (
                any::<u8>(),
                any::<u64>(),
                any::<[i16; 3]>(),
                any::<[i16; 3]>(),
                any::<Option<[i16; 3]>>()
            )
                .prop_map(|(sensor, t_us, accel_mg, gyro_ddps, mag_dut)| {
                    Message::ImuSample(ImuSample {
                        sensor,
                        t_us,
                        accel_mg,
                        gyro_ddps,
                        mag_dut,
                    })
                }),
            (any::<u32>(), format(), joints()).prop_map(|(seq, format, joints_mm)| {
                Message::StudentProfile {
                    seq,
                    profile: StudentProfile { format, joints_mm },
                }
            }),
            (any::<u32>(), any::<u16>())
                .prop_map(|(seq, coach)| Message::CoachSelect { seq, coach }),
            (any::<u32>(), any::<u16>(), any::<u16>(), any::<bool>()).prop_map(
                |(seq, model_rate_hz, radius, anchored)| Message::Config {
                    seq,
                    config: Config {
                        model_rate_hz,
                        band: Band { radius, anchored }
                    }
                }
            ),
            (
                (any::<u32>(), any::<u16>(), any::<u16>()),
                any::<[u16; 10]>(),
                any::<[u16; 10]>(),
                (any::<[[u16; 2]; 3]>(), any::<[u8; 3]>()),
                prop::collection::vec(
                    (any::<u8>(), any::<i16>(), any::<i16>(), any::<u16>()),
                    0..=MAX_CHECKS
                ),
                prop::collection::vec(
                    (any::<u8>(), any::<i16>(), any::<i16>(), any::<u16>()),
                    0..=MAX_GAPS
                ),
                prop::collection::vec(
                    (
                        any::<u8>(),
                        any::<u8>(),
                        any::<u8>(),
                        any::<[i16; 3]>(),
                        any::<u16>()
                    ),
                    0..=MAX_DEVIATIONS
                )
            )
                .prop_map(
                    |(
                        (swing, coach, score_centi),
                        student_positions,
                        coach_positions,
                        (phases_ms, verdicts),
                        checks,
                        gaps,
                        d,
                    )| {
                        Message::SwingReport(SwingReport {
                            swing,
                            coach,
                            score_centi,
                            student_positions,
                            coach_positions,
                            checks: checks
                                .into_iter()
                                .map(|(check, student, coach, uncertainty)| WireCheck {
                                    check,
                                    student,
                                    coach,
                                    uncertainty,
                                })
                                .collect(),
                            gaps: gaps
                                .into_iter()
                                .map(|(gap, student_ms, coach_ms, uncertainty_ms)| WireGap {
                                    gap,
                                    student_ms,
                                    coach_ms,
                                    uncertainty_ms,
                                })
                                .collect(),
                            phases_ms,
                            verdicts,
                            deviations: d
                                .into_iter()
                                .map(|(position, joint, direction, offset_mm, uncertainty_mm)| {
                                    WireDeviation {
                                        position,
                                        joint,
                                        direction,
                                        offset_mm,
                                        uncertainty_mm,
                                    }
                                })
                                .collect(),
                        })
                    }
                ),
            (
                any::<u32>(),
                any::<u32>(),
                any::<u32>(),
                any::<u32>(),
                any::<u32>(),
                any::<u32>()
            )
                .prop_map(
                    |(frames_ok, crc_errors, malformed, versions, overflows, drops)| {
                        Message::Status(Counters {
                            frames_ok,
                            crc_errors,
                            malformed,
                            versions,
                            overflows,
                            drops,
                        })
                    }
                ),
            any::<u32>().prop_map(|seq| Message::Ack { seq }),
            (
                any::<u32>(),
                prop::sample::select(vec![
                    NackReason::Unexpected,
                    NackReason::Invalid,
                    NackReason::Busy,
                    NackReason::Version
                ])
            )
                .prop_map(|(seq, reason)| Message::Nack { seq, reason }),
            (
                any::<u32>(),
                prop::collection::vec(
                    (any::<u8>(), 0..Joint::ALL.len(), any::<[i16; 4]>()),
                    0..=MAX_SENSORS
                )
            )
                .prop_map(|(seq, sensors)| Message::SensorLayout {
                    seq,
                    layout: SensorLayout {
                        sensors: sensors
                            .into_iter()
                            .map(|(sensor, j, mounting_q14)| SensorPlacement {
                                sensor,
                                joint: Joint::ALL[j],
                                mounting_q14,
                            })
                            .collect()
                    }
                }),
            (any::<u32>(), any::<bool>())
                .prop_map(|(seq, reset)| Message::SessionRequest { seq, reset }),
            (
                any::<[u16; 3]>(),
                prop::collection::vec(
                    (any::<[u8; 5]>(), any::<[i16; 2]>(), any::<[u16; 2]>()),
                    0..=BODY_LEVEL
                ),
                prop::collection::vec(any::<[u8; 3]>(), 0..=MAX_ADVICE),
                prop::collection::vec((any::<(u16, u8, u8)>(), any::<i16>()), 0..=MAX_SET_ASIDE),
                any::<Option<([u8; 4], i16, [u16; 2])>>()
            )
                .prop_map(
                    |([swings, used, coach], metrics, tendencies, set_aside, open)| {
                        Message::SessionReport(SessionReport {
                            swings,
                            used,
                            coach,
                            metrics: metrics
                                .into_iter()
                                .map(
                                    |(
                                        [quantity, swings, above, below, verdict],
                                        [student, coach],
                                        [uncertainty, spread],
                                    )| WireMetric {
                                        quantity,
                                        swings,
                                        above,
                                        below,
                                        verdict,
                                        student,
                                        coach,
                                        uncertainty,
                                        spread,
                                    },
                                )
                                .collect(),
                            tendencies: tendencies
                                .into_iter()
                                .map(|[item, swings, past]| WireTendency { item, swings, past })
                                .collect(),
                            spatial: HVec::new(),
                            set_aside: set_aside
                                .into_iter()
                                .map(|((swing, unlike, worst), z_tenths)| WireSetAside {
                                    swing,
                                    unlike,
                                    worst,
                                    z_tenths,
                                })
                                .collect(),
                            open: open.map(
                                |(
                                    [quantity, position, joint, direction],
                                    value,
                                    [uncertainty, more_swings],
                                )| WireOpen {
                                    quantity,
                                    position,
                                    joint,
                                    direction,
                                    value,
                                    uncertainty,
                                    more_swings,
                                },
                            ),
                        })
                    }
                ),
        ]
    }

    proptest! {
        #[test]
        fn every_message_round_trips(messages in prop::collection::vec(message(), 1..6), noise in prop::collection::vec(1u8..=255, 0..40)) {
            // Frames back to back, with a run of junk (and its delimiter) before them.
            let mut stream = noise.clone();
            stream.push(0);
            for m in &messages {
                let f = frame(m);
                prop_assert!(f.len() <= MAX_FRAME && f[..f.len() - 1].iter().all(|&b| b != 0));
                stream.extend(f);
            }
            let (got, counters) = decode_all(&stream);
            prop_assert_eq!(&got, &messages);
            prop_assert_eq!(counters.frames_ok as usize, messages.len());
            prop_assert_eq!(counters.crc_errors + counters.malformed, u32::from(!noise.is_empty()));
        }

        #[test]
        fn the_stream_messages_decode_as_the_enum_does(message in message(), tail in prop::collection::vec(any::<u8>(), 0..8), junk in prop::collection::vec(any::<u8>(), 0..60), tag in 0u8..2) {
            // A message's postcard bytes (with trailing bytes, which both ignore), and junk
            // after either stream variant's tag: the variant's own decoding must agree.
            let mut buffer = [0u8; MAX_PAYLOAD];
            let mut bytes = postcard::to_slice(&message, &mut buffer).unwrap().to_vec();
            bytes.extend(&tail);
            let mut junk = junk;
            junk.insert(0, tag);
            for b in [bytes, junk] {
                let (fast, generic) = (decode(&b), postcard::from_bytes::<Message>(&b));
                prop_assert_eq!(fast.ok(), generic.ok());
            }
        }

        #[test]
        fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000)) {
            let (_, counters) = decode_all(&bytes);
            let delimiters = bytes.iter().filter(|&&b| b == 0).count() as u32;
            prop_assert!(counters.frames_ok + counters.crc_errors + counters.malformed <= delimiters);
        }

        #[test]
        fn a_damaged_frame_is_lost_alone(message in message(), at in any::<prop::sample::Index>(), flip in 1u8..=255) {
            let (f, next) = (frame(&message), frame(&Message::Ack { seq: 1 }));
            let mut damaged = f.clone();
            let i = at.index(f.len() - 1);
            damaged[i] ^= flip;
            let mut stream = damaged;
            stream.extend(&next);
            let (got, counters) = decode_all(&stream);
            // The good frame after it always survives; the damaged one never comes out changed.
            prop_assert_eq!(got.last(), Some(&Message::Ack { seq: 1 }));
            prop_assert!(got.len() == 1 || (got.len() == 2 && got[0] == message));
            prop_assert!(counters.frames_ok >= 1);
        }
    }

    #[test]
    fn a_frame_of_another_version_is_counted_and_owed_one_nack() {
        let mut old = frame(&Message::CoachSelect { seq: 1, coach: 3 });
        // The same frame in version 2: its version byte and CRC rewritten, COBS again.
        let mut payload = [0u8; MAX_FRAME];
        let n = cobs::decode(&old[..old.len() - 1], &mut payload)
            .unwrap()
            .frame_size();
        payload[0] = 2;
        let crc = CRC.checksum(&payload[..n - 4]).to_le_bytes();
        payload[n - 4..n].copy_from_slice(&crc);
        let mut out = [0u8; MAX_FRAME];
        let m = cobs::encode(&payload[..n], &mut out);
        old = out[..m].to_vec();
        old.push(0);
        let mut stream = old.clone();
        stream.extend(&old);
        stream.extend(frame(&Message::CoachSelect { seq: 1, coach: 4 }));
        let mut decoder = Decoder::new();
        let mut got = Vec::new();
        decoder.push_all(&stream, |m| got.push(m.clone()));
        assert_eq!(got, [Message::CoachSelect { seq: 1, coach: 4 }]);
        let counters = decoder.counters();
        assert_eq!(
            (counters.versions, counters.malformed, counters.crc_errors),
            (2, 0, 0)
        );
        // Two old frames, one Nack; none owed after it.
        assert_eq!(
            decoder.reply(),
            Some(Message::Nack {
                seq: 0,
                reason: NackReason::Version
            })
        );
        assert_eq!(decoder.reply(), None);
    }

    #[test]
    fn a_device_drops_what_a_device_sends_as_malformed() {
        let sent = [
            Message::Status(Counters::default()),
            Message::SessionReport(SessionReport {
                swings: 1,
                used: 1,
                coach: 0,
                metrics: HVec::new(),
                tendencies: HVec::new(),
                spatial: HVec::new(),
                set_aside: HVec::new(),
                open: None,
            }),
            Message::SessionRequest {
                seq: 3,
                reset: false,
            },
        ];
        let stream: Vec<u8> = sent.iter().flat_map(frame).collect();
        let mut device = Decoder::new();
        let mut got = Vec::new();
        device.push_all(&stream, |m| got.push(m.clone()));
        assert_eq!(got, sent[2..]);
        assert_eq!(
            (device.counters().frames_ok, device.counters().malformed),
            (1, 2)
        );
        assert_eq!(decode_all(&stream).0, sent);
    }

    #[test]
    fn an_overlong_frame_is_dropped_and_the_next_one_read() {
        let mut stream = std::vec![0x55u8; 3 * MAX_FRAME];
        stream.push(0);
        stream.extend(frame(&Message::CoachSelect { seq: 1, coach: 3 }));
        let (got, counters) = decode_all(&stream);
        assert_eq!(got, [Message::CoachSelect { seq: 1, coach: 3 }]);
        assert_eq!((counters.overflows, counters.frames_ok), (1, 1));
    }

    #[test]
    fn the_largest_messages_fit_a_frame() {
        let widest = WireDeviation {
            position: 255,
            joint: 255,
            direction: 255,
            offset_mm: [i16::MIN; 3],
            uncertainty_mm: u16::MAX,
        };
        let full = |v: [i16; 3]| -> HVec<[i16; 3], MAX_WIRE_JOINTS> {
            core::iter::repeat_n(v, MAX_WIRE_JOINTS).collect()
        };
        let biggest = [
            Message::PoseFrame(PoseFrame {
                seq: u32::MAX,
                t_us: u64::MAX,
                format: Format::BlazePose33,
                joints_mm: full([i16::MIN; 3]),
                confidence: core::iter::repeat_n(255, MAX_WIRE_JOINTS).collect(),
            }),
            Message::SwingReport(SwingReport {
                swing: u32::MAX,
                coach: u16::MAX,
                score_centi: u16::MAX,
                student_positions: [u16::MAX; 10],
                coach_positions: [u16::MAX; 10],
                phases_ms: [[u16::MAX; 2]; 3],
                verdicts: [u8::MAX; 3],
                checks: core::iter::repeat_n(
                    WireCheck {
                        check: 255,
                        student: i16::MIN,
                        coach: i16::MIN,
                        uncertainty: u16::MAX,
                    },
                    MAX_CHECKS,
                )
                .collect(),
                gaps: core::iter::repeat_n(
                    WireGap {
                        gap: 255,
                        student_ms: i16::MIN,
                        coach_ms: i16::MIN,
                        uncertainty_ms: u16::MAX,
                    },
                    MAX_GAPS,
                )
                .collect(),
                deviations: core::iter::repeat_n(widest, MAX_DEVIATIONS).collect(),
            }),
            Message::SessionReport(SessionReport {
                swings: u16::MAX,
                used: u16::MAX,
                coach: u16::MAX,
                metrics: core::iter::repeat_n(
                    WireMetric {
                        quantity: 255,
                        swings: 255,
                        above: 255,
                        below: 255,
                        verdict: 255,
                        student: i16::MIN,
                        coach: i16::MIN,
                        uncertainty: u16::MAX,
                        spread: u16::MAX,
                    },
                    BODY_LEVEL,
                )
                .collect(),
                tendencies: core::iter::repeat_n(
                    WireTendency {
                        item: 255,
                        swings: 255,
                        past: 255,
                    },
                    MAX_ADVICE,
                )
                .collect(),
                spatial: core::iter::repeat_n(widest, MAX_ADVICE).collect(),
                set_aside: core::iter::repeat_n(
                    WireSetAside {
                        swing: u16::MAX,
                        unlike: 255,
                        worst: 255,
                        z_tenths: i16::MIN,
                    },
                    MAX_SET_ASIDE,
                )
                .collect(),
                open: Some(WireOpen {
                    quantity: 255,
                    position: 255,
                    joint: 255,
                    direction: 255,
                    value: i16::MIN,
                    uncertainty: u16::MAX,
                    more_swings: u16::MAX,
                }),
            }),
        ];
        for m in &biggest {
            let mut out = [0u8; MAX_FRAME];
            let n = encode(m, &mut out).unwrap();
            assert!(n <= MAX_FRAME);
            assert_eq!(decode_all(&out[..n]).0, core::slice::from_ref(m));
        }
        let mut short = [0u8; 4];
        assert_eq!(
            encode(&Message::Ack { seq: 1 }, &mut short),
            Err(EncodeError::TooLong)
        );
    }

    #[test]
    fn a_config_carries_its_band_as_radius_then_flag() {
        // Variant 4, sequence number 9, model rate 60, radius 10 (varints), anchored (one
        // byte).
        let f = frame(&Message::Config {
            seq: 9,
            config: Config {
                model_rate_hz: 60,
                band: Band::DEFAULT,
            },
        });
        let mut payload = f[..f.len() - 1].to_vec();
        let n = cobs::decode_in_place(&mut payload).unwrap();
        assert_eq!(&payload[..n - 4], &[VERSION, 4, 9, 60, 10, 1]);
    }

    #[test]
    fn frames_have_the_documented_layout() {
        // Ack { seq: 7 }: the version, variant 7 (varint), seq 7 (varint), CRC-32 LE; COBS; 0x00.
        let f = frame(&Message::Ack { seq: 7 });
        let mut payload = f[..f.len() - 1].to_vec();
        let n = cobs::decode_in_place(&mut payload).unwrap();
        let crc = CRC.checksum(&[VERSION, 7, 7]).to_le_bytes();
        assert_eq!(
            &payload[..n],
            &[VERSION, 7, 7, crc[0], crc[1], crc[2], crc[3]]
        );
        assert_eq!(*f.last().unwrap(), 0);
    }
}
