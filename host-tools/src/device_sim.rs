//! `posecoach device-sim`: the device's pipeline built for the host, speaking the wire protocol
//! over a serial port, for tests and for phone developers without hardware.
//!
//! Every frame read goes through the device's [`Decoder`] into the device's
//! [`Session`] with the bundled coach references, exactly as `posecoach replay` runs a log.
//! It answers with wire frames: a `SwingReport`, a `Status` (the decoder's counters) and the
//! range session's `SessionReport` per scored swing, an `Ack` per set-up message taken (and an
//! `Ack` and a `SessionReport` per `SessionRequest`) and a `Nack` per refused message (each
//! of the message's `seq`, else 0). Frames not yet written when the link fails are kept and written, whole, once a
//! link is back; the session carries on across links. At most [`REPLY_QUEUE`] replies wait for
//! the link: when its peer does not read and the queue is full, a new reply is dropped and
//! counted, so a peer that never reads costs a bounded amount of memory.

use crate::coaches;
use anyhow::{Context, Result};
use posecoach_adapters::session::{Outcome, Session};
use posecoach_core::weights::Weights;
use posecoach_core::wire::{encode, Decoder, Message, MAX_FRAME};
use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// The serial link's default speed, baud (ignored by pseudo-terminals).
pub const DEFAULT_BAUD: u32 = 115_200;
/// How long a read waits for bytes before the loop looks at its other work.
pub const READ_TIMEOUT: Duration = Duration::from_millis(20);
/// Wait before trying a port again that could not be opened or failed.
const RETRY: Duration = Duration::from_millis(200);
/// Replies waiting for the link (each at most [`MAX_FRAME`] bytes): when the peer reads, a
/// handful at most wait.
pub const REPLY_QUEUE: usize = 256;

/// A serial port's arguments, as `device-sim` and `bridge` take them.
#[derive(clap::Args)]
pub struct Serial {
    /// The serial port: a device path, or a pseudo-terminal such as one end of
    /// `socat -d -d pty,raw,echo=0 pty,raw,echo=0`.
    #[arg(long)]
    pub port: PathBuf,
    /// Speed of the port (pseudo-terminals ignore it).
    #[arg(long, default_value_t = DEFAULT_BAUD)]
    pub baud: u32,
}

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    serial: Serial,
    /// On Ctrl-C, print the totals as one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Carry these int8 weights (.pcw) as a device would: coaches are retargeted with them
    /// when the model rate is the network's.
    #[arg(long)]
    weights: Option<PathBuf>,
}

/// What a simulated device did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Totals {
    /// Links served (the first, then one per reconnection).
    pub links: u32,
    /// Swing reports sent.
    pub reports: u32,
    /// Messages refused.
    pub refused: u32,
    /// Replies dropped because [`REPLY_QUEUE`] replies were waiting for a peer that did not read.
    pub dropped: u64,
}

pub fn run(args: &Args) -> Result<String> {
    eprintln!(
        "device-sim: serving {} (Ctrl-C to stop)",
        args.serial.port.display()
    );
    let stop = until_interrupted()?;
    let mut failing = false;
    let connect = || match open(&args.serial.port, args.serial.baud) {
        Ok(port) => {
            failing = false;
            Some(port)
        }
        Err(e) => {
            if !failing {
                eprintln!(
                    "device-sim: {}: {e}; retrying until it opens",
                    args.serial.port.display()
                );
            }
            failing = true;
            None
        }
    };
    let totals = coaches::with_network(args.weights.as_deref(), |weights| {
        simulate(connect, &stop, weights)
    })?;
    if args.json {
        let doc = serde_json::json!({"links": totals.links, "reports": totals.reports,
                                     "refused": totals.refused, "dropped_replies": totals.dropped});
        return Ok(format!("{doc}\n"));
    }
    Ok(format!(
        "{} links, {} swing reports, {} refused, {} replies dropped for a peer that did not read\n",
        totals.links, totals.reports, totals.refused, totals.dropped
    ))
}

/// A flag that Ctrl-C or SIGTERM sets; a second one ends the process at once (status 130),
/// so that nothing can keep it from stopping.
///
/// # Errors
/// If a signal handler is already installed.
pub fn until_interrupted() -> Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::Relaxed) {
            eprintln!("interrupted again: stopping now");
            std::process::exit(130);
        }
    })
    .context("installing the Ctrl-C handler")?;
    Ok(stop)
}

/// Opens `port` with [`READ_TIMEOUT`].
///
/// # Errors
/// When the port is absent, busy or not a terminal.
pub fn open(port: &Path, baud: u32) -> serialport::Result<serialport::TTYPort> {
    serialport::new(port.to_string_lossy(), baud)
        .timeout(READ_TIMEOUT)
        .open_native()
}

/// Runs the device (with the int8 `network` if given) on the links `connect` gives (`None`:
/// none now, try again later) until `stop` is set.
///
/// # Errors
/// Only if a bundled coach reference were damaged.
pub fn simulate<L: Read + Write>(
    connect: impl FnMut() -> Option<L>,
    stop: &AtomicBool,
    network: Option<&Weights<'_>>,
) -> Result<Totals> {
    coaches::session(network, |session| serve(session, connect, stop))
}

/// [`simulate`] on `session`.
fn serve<L: Read + Write>(
    session: &mut Session<'_>,
    mut connect: impl FnMut() -> Option<L>,
    stop: &AtomicBool,
) -> Totals {
    let mut totals = Totals::default();
    let mut unsent = Outbox::new(REPLY_QUEUE);
    let mut buf = [0u8; MAX_FRAME];
    while !stop.load(Ordering::Relaxed) {
        let Some(mut link) = connect() else {
            std::thread::sleep(RETRY);
            continue;
        };
        totals.links += 1;
        // A frame cut off on the last link is dropped by this decoder, not joined to the next.
        let mut decoder = Decoder::new();
        while !stop.load(Ordering::Relaxed) {
            if let Err(e) = unsent.flush(&mut link) {
                eprintln!("device-sim: link lost writing: {e}");
                break;
            }
            let n = match link.read(&mut buf) {
                Ok(n) => n,
                Err(e) if transient(&e) => continue,
                Err(e) => {
                    eprintln!("device-sim: link lost reading: {e}");
                    break;
                }
            };
            let mut messages = Vec::new();
            decoder.push_all(&buf[..n], |m| messages.push(m.clone()));
            // Frames of another protocol version are told so, once per read.
            if let Some(nack) = decoder.reply() {
                totals.refused += 1;
                totals.send(&mut unsent, &nack);
            }
            for message in &messages {
                session.handle(message, |outcome| {
                    match &outcome {
                        Outcome::Scored { .. } => totals.reports += 1,
                        Outcome::Unscored { swing, error } => {
                            eprintln!("device-sim: swing {} not scored: {error}", swing.number);
                        }
                        Outcome::Refused(_) => totals.refused += 1,
                        Outcome::Accepted | Outcome::Session { .. } => {}
                    }
                    if let Some(reply) = outcome.reply(message) {
                        totals.send(&mut unsent, &reply);
                        if matches!(reply, Message::SwingReport(_)) {
                            totals.send(&mut unsent, &Message::Status(decoder.counters()));
                        }
                    }
                });
            }
        }
        std::thread::sleep(RETRY);
    }
    totals
}

impl Totals {
    /// Queues `reply` in `unsent`, or counts it dropped when the queue is full.
    fn send(&mut self, unsent: &mut Outbox, reply: &Message) {
        if let Some(frame) = frame(reply) {
            if !unsent.push(frame) {
                self.dropped += 1;
            }
        }
    }
}

/// A read or write that found the link not ready, rather than failed.
pub fn transient(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
    )
}

/// Frames queued for a link, in order, the first possibly written in part; at most a capacity
/// of them.
#[derive(Debug)]
pub struct Outbox {
    frames: VecDeque<Vec<u8>>,
    written: usize,
    capacity: usize,
}

impl Outbox {
    /// An empty queue that holds up to `capacity` frames.
    pub fn new(capacity: usize) -> Outbox {
        Outbox {
            frames: VecDeque::with_capacity(capacity),
            written: 0,
            capacity,
        }
    }

    /// Queues a frame, unless the queue is full: whether it was queued.
    #[must_use]
    pub fn push(&mut self, frame: Vec<u8>) -> bool {
        if self.frames.len() >= self.capacity {
            return false;
        }
        self.frames.push_back(frame);
        true
    }

    /// Frames queued.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Frames that may still be queued.
    pub fn room(&self) -> usize {
        self.capacity - self.frames.len()
    }

    /// Whether nothing is queued.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Writes what `link` takes now; returns when it is all written or the link is busy.
    ///
    /// # Errors
    /// When the link fails; the frame it failed in is then written again from its start on
    /// the next link (whose reader has dropped the part it got).
    pub fn flush(&mut self, link: &mut impl Write) -> std::io::Result<()> {
        while let Some(frame) = self.frames.front() {
            match link.write(&frame[self.written..]) {
                Ok(0) => {
                    self.written = 0;
                    return Err(ErrorKind::WriteZero.into());
                }
                Ok(n) => {
                    self.written += n;
                    if self.written == frame.len() {
                        self.frames.pop_front();
                        self.written = 0;
                    }
                }
                Err(e) if transient(&e) => return Ok(()),
                Err(e) => {
                    self.written = 0;
                    return Err(e);
                }
            }
        }
        Ok(())
    }
}

/// `message` as one wire frame.
pub fn frame(message: &Message) -> Option<Vec<u8>> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode(message, &mut out).ok()?;
    Some(out[..n].to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Takes up to `chunk` bytes per write, is busy every other call, and fails for good
    /// after `fail_after` bytes.
    struct Stingy {
        got: Vec<u8>,
        chunk: usize,
        busy: bool,
        fail_after: usize,
    }

    impl Write for Stingy {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.busy = !self.busy;
            if self.busy {
                return Err(ErrorKind::WouldBlock.into());
            }
            if self.got.len() >= self.fail_after {
                return Err(ErrorKind::BrokenPipe.into());
            }
            let n = buf.len().min(self.chunk);
            self.got.extend_from_slice(&buf[..n]);
            Ok(n)
        }

        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    fn frames() -> Vec<Vec<u8>> {
        (0..3u32)
            .map(|seq| frame(&Message::Ack { seq }).unwrap())
            .collect()
    }

    fn full(frames: Vec<Vec<u8>>) -> Outbox {
        let mut outbox = Outbox::new(frames.len());
        for frame in frames {
            assert!(outbox.push(frame));
        }
        assert_eq!(outbox.room(), 0);
        outbox
    }

    #[test]
    fn a_busy_link_gets_every_frame_whole_and_in_order() {
        let mut outbox = full(frames());
        let mut link = Stingy {
            got: Vec::new(),
            chunk: 2,
            busy: false,
            fail_after: usize::MAX,
        };
        let mut calls = 0;
        while !outbox.is_empty() {
            outbox.flush(&mut link).unwrap();
            calls += 1;
            assert!(calls < 100, "flush makes no progress");
        }
        assert_eq!(link.got, frames().concat());
    }

    #[test]
    fn a_frame_cut_by_a_failed_link_is_sent_again_whole() {
        let mut outbox = full(frames());
        let first = frames()[0].len();
        let mut broken = Stingy {
            got: Vec::new(),
            chunk: 2,
            busy: false,
            fail_after: first + 2,
        };
        let failed = loop {
            if let Err(e) = outbox.flush(&mut broken) {
                break e;
            }
        };
        assert_eq!(failed.kind(), ErrorKind::BrokenPipe);
        assert_eq!(outbox.len(), 2);
        let mut next = Stingy {
            got: Vec::new(),
            chunk: 64,
            busy: false,
            fail_after: usize::MAX,
        };
        while !outbox.is_empty() {
            outbox.flush(&mut next).unwrap();
        }
        assert_eq!(next.got, frames()[1..].concat());
    }

    /// A peer that sends a pose frame on every read, `left` in all (then stops the device),
    /// and never reads a reply.
    struct Deaf<'a> {
        frames: Vec<Vec<u8>>,
        sent: usize,
        left: usize,
        stop: &'a AtomicBool,
    }

    impl Read for Deaf<'_> {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.sent == self.left {
                self.stop.store(true, Ordering::Relaxed);
                return Err(ErrorKind::TimedOut.into());
            }
            let frame = &self.frames[self.sent % self.frames.len()];
            buf[..frame.len()].copy_from_slice(frame);
            self.sent += 1;
            Ok(frame.len())
        }
    }

    impl Write for Deaf<'_> {
        fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
            Err(ErrorKind::WouldBlock.into())
        }

        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn replies_to_a_peer_that_never_reads_are_dropped_and_counted_past_the_queue() {
        const EXTRA: usize = 100;
        let log = include_bytes!("../../tests/logs/short_cmu_30hz.pclog");
        // Pose frames without a student profile: each is refused with a `Nack`.
        let frames: Vec<Vec<u8>> = posecoach_adapters::log::LogReader::new(log)
            .unwrap()
            .filter(|m| matches!(m, Message::PoseFrame(_)))
            .map(|m| frame(&m).unwrap())
            .collect();
        let stop = AtomicBool::new(false);
        let mut peer = Some(Deaf {
            frames,
            sent: 0,
            left: REPLY_QUEUE + EXTRA,
            stop: &stop,
        });
        let totals = simulate(|| peer.take(), &stop, None).unwrap();
        assert_eq!(totals.refused as usize, REPLY_QUEUE + EXTRA);
        assert_eq!(totals.dropped as usize, EXTRA);
    }
}
