//! `posecoach bridge`: relays between a device's serial port and phone apps over TCP.
//!
//! Every frame the device sends goes to every connected client as one JSON line; every line a
//! client sends (one wire message as JSON) goes to the device as one wire frame. Lines:
//!
//! | direction | line |
//! | --- | --- |
//! | device → clients | `{"device": MESSAGE}` |
//! | bridge → clients | `{"bridge": {"event": "serial_connected", "port": P}}`, `{"bridge": {"event": "serial_lost", "reason": R}}`, and on connecting `{"bridge": {"event": "hello", "serial": "connected"}}` (or `"disconnected"`) |
//! | client → device | `MESSAGE` |
//! | bridge → that client | `{"error": WHY}` for a line that is not a message |
//!
//! `MESSAGE` is a [`Message`] as serde writes it: the variant's name holding its fields,
//! `{"CoachSelect": {"coach": 1}}`, `{"Ack": {"seq": 7}}`, `{"SwingReport": {"swing": 1,
//! "score_centi": 9570, ...}}`; enums without fields as their name (`"H36m17"`).
//!
//! The serial side reconnects with backoff (0.1 s doubling to 2 s) whenever the port fails or
//! disappears; the decoder starts afresh on each link, and a frame whose write failed is
//! written again, whole, on the next (the device drops the part it got). Frames from clients wait in a queue of
//! [`TO_DEVICE_QUEUE`] frames while the port is away; when it is full, the client's reader
//! waits (TCP pushes back on the phone), nothing is dropped. Each client has a queue of
//! [`CLIENT_QUEUE`] lines; the serial reader never waits for a client: one whose queue is full
//! is disconnected and counted, and may reconnect.

use crate::device_sim::{self, transient, until_interrupted, Outbox, Serial};
use anyhow::{Context, Result};
use posecoach_core::wire::{Decoder, Message, MAX_FRAME};
use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Frames from clients waiting for the device.
pub const TO_DEVICE_QUEUE: usize = 4096;
/// Lines waiting for one client.
pub const CLIENT_QUEUE: usize = 1024;
/// Longest line a client may send, bytes (the JSON of the largest message is under 4 KB).
pub const MAX_LINE: usize = 16 * 1024;
/// First wait before reopening a lost port; it doubles up to [`MAX_BACKOFF`].
const MIN_BACKOFF: Duration = Duration::from_millis(100);
/// Longest wait between attempts to reopen the port.
const MAX_BACKOFF: Duration = Duration::from_secs(2);
/// Frames taken from the queue for the link at a time.
const OUTBOX_FRAMES: usize = 64;
/// How often the accept loop looks at the stop flag.
const ACCEPT_POLL: Duration = Duration::from_millis(20);

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    serial: Serial,
    /// Where phone apps connect, as HOST:PORT: a name (`localhost:7879`) or an address
    /// (`0.0.0.0:7879`, `[::1]:7879`); port 0 takes a free one, and the line on standard error
    /// says which.
    #[arg(long)]
    listen: String,
    /// On Ctrl-C, print the counters as one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<String> {
    let listener = TcpListener::bind(args.listen.as_str()).with_context(|| {
        format!(
            "listening on {}: give HOST:PORT, a name or an address and a free port",
            args.listen
        )
    })?;
    eprintln!(
        "bridge: {} <-> {} (one JSON message per line; Ctrl-C to stop)",
        args.serial.port.display(),
        listener.local_addr().context("the listener's address")?
    );
    let c = serve(
        &args.serial.port,
        args.serial.baud,
        listener,
        &until_interrupted()?,
    )?;
    if args.json {
        let doc = json!({"from_device": c.from_device, "to_device": c.to_device, "links": c.links,
                         "slow_clients": c.slow_clients, "bad_lines": c.bad_lines});
        return Ok(format!("{doc}\n"));
    }
    Ok(format!("{c}\n"))
}

/// What a bridge has relayed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Frames from the device relayed to clients.
    pub from_device: u64,
    /// Frames written to the device.
    pub to_device: u64,
    /// Serial links opened.
    pub links: u64,
    /// Clients disconnected for not keeping up.
    pub slow_clients: u64,
    /// Client lines that were not messages.
    pub bad_lines: u64,
}

impl std::fmt::Display for Counters {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} frames from the device, {} to it, {} serial links, {} slow clients dropped, {} bad lines",
            self.from_device, self.to_device, self.links, self.slow_clients, self.bad_lines
        )
    }
}

/// [`Counters`] as the bridge's threads count.
#[derive(Debug, Default)]
struct Counting {
    from_device: AtomicU64,
    to_device: AtomicU64,
    links: AtomicU64,
    slow_clients: AtomicU64,
    bad_lines: AtomicU64,
}

impl Counting {
    fn now(&self) -> Counters {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        Counters {
            from_device: get(&self.from_device),
            to_device: get(&self.to_device),
            links: get(&self.links),
            slow_clients: get(&self.slow_clients),
            bad_lines: get(&self.bad_lines),
        }
    }
}

/// A connected client: its number, its queue and its socket (to close it).
struct Client {
    id: u64,
    lines: SyncSender<String>,
    stream: TcpStream,
}

/// The state the bridge's threads share.
struct Shared {
    clients: Mutex<Vec<Client>>,
    connected: AtomicBool,
    counters: Counting,
    /// Clients accepted so far: the next one's number.
    accepted: AtomicU64,
}

impl Shared {
    /// Forgets client `id` and closes its socket, which ends its writer: a client that left
    /// holds nothing, whether or not the device speaks.
    fn forget(&self, id: u64) {
        if let Ok(mut clients) = self.clients.lock() {
            clients.retain(|c| {
                let keep = c.id != id;
                if !keep {
                    let _ = c.stream.shutdown(std::net::Shutdown::Both);
                }
                keep
            });
        }
    }

    /// Queues `line` for every client; drops a client whose queue is full or gone.
    fn broadcast(&self, line: &str) {
        let Ok(mut clients) = self.clients.lock() else {
            return;
        };
        clients.retain(|c| match c.lines.try_send(line.to_string()) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                self.counters.slow_clients.fetch_add(1, Ordering::Relaxed);
                if let Ok(peer) = c.stream.peer_addr() {
                    eprintln!("bridge: client {peer} dropped: {CLIENT_QUEUE} lines behind");
                }
                let _ = c.stream.shutdown(std::net::Shutdown::Both);
                false
            }
            Err(TrySendError::Disconnected(_)) => false,
        });
    }

    /// Tells every client, and the operator on stderr, about the serial port.
    fn event(&self, event: &str, detail: Value) {
        let mut body = json!({"event": event});
        if let (Some(body), Value::Object(more)) = (body.as_object_mut(), detail) {
            body.extend(more);
        }
        let line = json!({ "bridge": body }).to_string();
        eprintln!("bridge: {line}");
        self.broadcast(&line);
    }
}

/// Relays between `port` and the clients of `listener` until `stop` is set; returns what it
/// relayed.
///
/// # Errors
/// If the listener cannot be polled.
pub fn serve(
    port: &Path,
    baud: u32,
    listener: TcpListener,
    stop: &Arc<AtomicBool>,
) -> Result<Counters> {
    let shared = Arc::new(Shared {
        clients: Mutex::new(Vec::new()),
        connected: AtomicBool::new(false),
        counters: Counting::default(),
        accepted: AtomicU64::new(0),
    });
    let (to_device, frames) = sync_channel::<Vec<u8>>(TO_DEVICE_QUEUE);
    let serial = {
        let (shared, stop, port) = (shared.clone(), stop.clone(), port.to_path_buf());
        std::thread::spawn(move || serial_loop(&port, baud, &frames, &shared, &stop))
    };
    listener
        .set_nonblocking(true)
        .context("setting the listener non-blocking")?;
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, from)) => {
                eprintln!("bridge: client {from} connected");
                add_client(stream, &shared, &to_device);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(ACCEPT_POLL);
            }
            Err(e) => eprintln!("bridge: accepting a client: {e}"),
        }
    }
    if let Ok(clients) = shared.clients.lock() {
        for c in clients.iter() {
            let _ = c.stream.shutdown(std::net::Shutdown::Both);
        }
    }
    let _ = serial.join();
    Ok(shared.counters.now())
}

/// Registers a client and starts its writer and reader.
fn add_client(stream: TcpStream, shared: &Arc<Shared>, to_device: &SyncSender<Vec<u8>>) {
    let _ = stream.set_nonblocking(false);
    let (Ok(writer), Ok(closer)) = (stream.try_clone(), stream.try_clone()) else {
        return;
    };
    let (lines, queue) = sync_channel::<String>(CLIENT_QUEUE);
    let serial = match shared.connected.load(Ordering::Relaxed) {
        true => "connected",
        false => "disconnected",
    };
    let hello = json!({"bridge": {"event": "hello", "serial": serial}}).to_string();
    let _ = lines.try_send(hello);
    let id = shared.accepted.fetch_add(1, Ordering::Relaxed);
    if let Ok(mut clients) = shared.clients.lock() {
        clients.push(Client {
            id,
            lines: lines.clone(),
            stream: closer,
        });
    }
    std::thread::spawn(move || write_lines(writer, &queue));
    let (shared, to_device) = (shared.clone(), to_device.clone());
    std::thread::spawn(move || {
        read_lines(stream, &lines, &shared, &to_device);
        shared.forget(id);
    });
}

/// Writes the client's lines as they come, all that are waiting in one write.
fn write_lines(stream: TcpStream, queue: &Receiver<String>) {
    let mut out = std::io::BufWriter::new(stream);
    while let Ok(first) = queue.recv() {
        let mut next = Some(first);
        while let Some(line) = next {
            if writeln!(out, "{line}").is_err() {
                return;
            }
            next = queue.try_recv().ok();
        }
        if out.flush().is_err() {
            return;
        }
    }
}

/// Each line of a client as a frame for the device; an error line back for one that is not a
/// message.
fn read_lines(
    stream: impl Read,
    replies: &SyncSender<String>,
    shared: &Shared,
    to_device: &SyncSender<Vec<u8>>,
) {
    let mut reader = BufReader::new(stream);
    let mut line = Vec::new();
    for n in 1u64.. {
        let frame = match next_line(&mut reader, &mut line) {
            Ok(None) | Err(_) => return,
            // (Before the blank case: the too-long line's bytes are already gone.)
            Ok(Some(false)) => Err(format!(
                "line {n}: longer than {MAX_LINE} bytes, dropped: no message is that long"
            )),
            Ok(Some(true)) if line.trim_ascii().is_empty() => continue,
            Ok(Some(true)) => serde_json::from_slice::<Message>(&line)
                .map_err(|e| {
                    format!(
                        "line {n}: not a message ({e}): send one wire message as JSON per line, such as {}",
                        r#"{"CoachSelect": {"coach": 0}}"#
                    )
                })
                .and_then(|m| {
                    device_sim::frame(&m).ok_or_else(|| format!("line {n}: too long for one frame"))
                }),
        };
        match frame {
            Ok(frame) => {
                if to_device.send(frame).is_err() {
                    return;
                }
            }
            Err(why) => {
                shared.counters.bad_lines.fetch_add(1, Ordering::Relaxed);
                let _ = replies.try_send(json!({ "error": why }).to_string());
            }
        }
    }
}

/// Reads the next line of `reader` into `line`, without its newline: `None` at the end, else
/// whether it was at most [`MAX_LINE`] bytes. Of a longer line no more than that is kept: the
/// rest is read and dropped.
///
/// # Errors
/// When reading fails.
fn next_line(reader: &mut impl BufRead, line: &mut Vec<u8>) -> std::io::Result<Option<bool>> {
    let limit = MAX_LINE as u64 + 1;
    line.clear();
    if reader.by_ref().take(limit).read_until(b'\n', line)? == 0 {
        return Ok(None);
    }
    if line.last() == Some(&b'\n') {
        line.pop();
        return Ok(Some(true));
    }
    if line.len() <= MAX_LINE {
        return Ok(Some(true));
    }
    loop {
        line.clear();
        let n = reader.by_ref().take(limit).read_until(b'\n', line)?;
        if n == 0 || line.last() == Some(&b'\n') {
            line.clear();
            return Ok(Some(false));
        }
    }
}

/// Opens the port, relays until it fails, and again, until `stop`.
fn serial_loop(
    port: &Path,
    baud: u32,
    frames: &Receiver<Vec<u8>>,
    shared: &Shared,
    stop: &AtomicBool,
) {
    let mut backoff = MIN_BACKOFF;
    let mut outbox = Outbox::new(OUTBOX_FRAMES);
    let mut buf = [0u8; MAX_FRAME];
    while !stop.load(Ordering::Relaxed) {
        let mut link = match device_sim::open(port, baud) {
            Ok(link) => link,
            Err(e) => {
                if backoff == MIN_BACKOFF {
                    eprintln!("bridge: {}: {e}; retrying until it opens", port.display());
                }
                std::thread::sleep(backoff);
                backoff = (backoff * 2).min(MAX_BACKOFF);
                continue;
            }
        };
        backoff = MIN_BACKOFF;
        shared.counters.links.fetch_add(1, Ordering::Relaxed);
        shared.connected.store(true, Ordering::Relaxed);
        shared.event(
            "serial_connected",
            json!({"port": port.display().to_string()}),
        );
        let mut decoder = Decoder::new();
        let lost = loop {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            for frame in frames.try_iter().take(outbox.room()) {
                let queued = outbox.push(frame);
                debug_assert!(queued, "room was made for it");
            }
            let queued = outbox.len();
            if let Err(e) = outbox.flush(&mut link) {
                break format!("writing: {e}");
            }
            let written = (queued - outbox.len()) as u64;
            shared
                .counters
                .to_device
                .fetch_add(written, Ordering::Relaxed);
            match link.read(&mut buf) {
                Ok(n) => decoder.push_all(&buf[..n], |m| {
                    shared.counters.from_device.fetch_add(1, Ordering::Relaxed);
                    shared.broadcast(&json!({ "device": m }).to_string());
                }),
                Err(e) if transient(&e) => {}
                Err(e) => break format!("reading: {e}"),
            }
        };
        shared.connected.store(false, Ordering::Relaxed);
        shared.event("serial_lost", json!({ "reason": lost }));
        std::thread::sleep(backoff);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shared() -> Shared {
        Shared {
            clients: Mutex::new(Vec::new()),
            connected: AtomicBool::new(true),
            counters: Counting::default(),
            accepted: AtomicU64::new(0),
        }
    }

    /// A client socket (its peer is returned too, to keep the connection open).
    fn socket() -> (TcpStream, TcpStream) {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let near = TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        (near, listener.accept().unwrap().0)
    }

    #[test]
    fn a_client_that_falls_behind_is_dropped_and_counted_without_waiting() {
        let shared = shared();
        let (slow_stream, _slow_peer) = socket();
        let (fast_stream, _fast_peer) = socket();
        let (slow, _slow_queue) = sync_channel(2);
        let (fast, fast_queue) = sync_channel(2);
        if let Ok(mut clients) = shared.clients.lock() {
            clients.push(Client {
                id: 0,
                lines: slow,
                stream: slow_stream,
            });
            clients.push(Client {
                id: 1,
                lines: fast,
                stream: fast_stream,
            });
        }
        for n in 0..5 {
            shared.broadcast(&n.to_string());
            while fast_queue.try_recv().is_ok() {}
        }
        assert_eq!(shared.clients.lock().map(|c| c.len()).ok(), Some(1));
        assert_eq!(shared.counters.now().slow_clients, 1);
    }

    #[test]
    fn an_endless_line_is_dropped_in_bounded_memory_and_reading_goes_on() {
        let long = "x".repeat(3 * MAX_LINE);
        let text = format!("a\n{long}\n\nb");
        let mut reader = std::io::Cursor::new(text.as_bytes());
        let mut line = Vec::new();
        let mut got = Vec::new();
        while let Some(whole) = next_line(&mut reader, &mut line).unwrap() {
            assert!(line.capacity() <= 2 * (MAX_LINE + 1));
            got.push((whole, String::from_utf8(line.clone()).unwrap()));
        }
        let expected = [(true, "a"), (false, ""), (true, ""), (true, "b")];
        let expected: Vec<_> = expected.iter().map(|&(w, s)| (w, s.to_string())).collect();
        assert_eq!(got, expected);
    }

    #[test]
    fn an_over_long_line_is_answered_and_counted_and_the_next_one_goes_through() {
        let shared = shared();
        let text = format!(
            "{}\n\n{}\n",
            "x".repeat(MAX_LINE + 1),
            r#"{"Ack": {"seq": 7}}"#
        );
        let (replies, answers) = sync_channel(4);
        let (to_device, frames) = sync_channel(4);
        read_lines(text.as_bytes(), &replies, &shared, &to_device);
        let answer = answers.try_recv().unwrap();
        assert!(answer.contains("line 1: longer than"), "{answer}");
        assert!(answers.try_recv().is_err());
        assert_eq!(shared.counters.now().bad_lines, 1);
        let ack = device_sim::frame(&Message::Ack { seq: 7 }).unwrap();
        assert_eq!(frames.try_recv().ok(), Some(ack));
    }

    #[test]
    fn a_client_that_closes_is_forgotten_at_once_though_the_device_is_silent() {
        let shared = Arc::new(shared());
        let (to_device, _frames) = sync_channel(4);
        let (near, far) = socket();
        add_client(near, &shared, &to_device);
        assert_eq!(shared.clients.lock().map(|c| c.len()).ok(), Some(1));
        drop(far);
        let start = std::time::Instant::now();
        while shared.clients.lock().map(|c| c.len()).ok() != Some(0) {
            assert!(start.elapsed() < Duration::from_secs(10), "never forgotten");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn a_client_that_left_is_forgotten_without_counting() {
        let shared = shared();
        let (stream, _peer) = socket();
        let (lines, queue) = sync_channel(2);
        drop(queue);
        if let Ok(mut clients) = shared.clients.lock() {
            clients.push(Client {
                id: 0,
                lines,
                stream,
            });
        }
        shared.event("serial_lost", json!({"reason": "test"}));
        assert_eq!(shared.clients.lock().map(|c| c.len()).ok(), Some(0));
        assert_eq!(shared.counters.now(), Counters::default());
    }
}
