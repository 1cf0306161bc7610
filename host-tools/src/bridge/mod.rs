//! `posecoach bridge`: relays between a device's serial port and phone apps over TCP.
//!
//! Every frame the device sends goes to every client with a role as one JSON line; every line
//! the controller sends (one wire message as JSON) goes to the device as one wire frame.
//!
//! | direction | line |
//! | --- | --- |
//! | bridge → a new client | `{"bridge": {"event": "hello", "serial": "connected", "role": R}}` (`"disconnected"`), R `"controller"`, `"watcher"` or `"pairing"` |
//! | client → bridge, first, where a token is needed | `{"token": T}`, answered `{"bridge": {"event": "paired", "role": R}}` |
//! | device → clients | `{"device": MESSAGE}` |
//! | bridge → clients | `{"bridge": {"event": "serial_connected", "port": P}}`, `{"bridge": {"event": "serial_lost", "reason": R}}` |
//! | bridge → a watcher made controller | `{"bridge": {"event": "control"}}` |
//! | controller → device | `MESSAGE`; a blank line is a keep-alive |
//! | bridge → that client | `{"error": WHY}` for a line not sent; `{"bridge": {"event": "closed", "reason": R}}` before closing a silent client; `{"bridge": {"event": "full", "max_clients": N}}` before closing a connection turned away |
//!
//! `MESSAGE` is a [`Message`](posecoach_core::wire::Message) as serde writes it: the variant's
//! name holding its fields, `{"CoachSelect": {"seq": 3, "coach": 1}}`, `{"Ack": {"seq": 3}}`;
//! enums without fields as their name (`"H36m17"`).
//!
//! One thread (the `hub` module) serves every client with `mio`: no thread per client, and a client
//! costs one descriptor. At most [`Policy::max_clients`] clients hold a role; the first is the
//! controller, the others watchers, and when the controller leaves the watcher connected
//! longest takes control. Where a token is needed (always, unless the bridge listens on
//! loopback without `--token`), as many connections again may be pairing, the oldest turned
//! away for a new one. A client must send a line within [`HANDSHAKE`] of connecting and then
//! one every [`Policy::idle`] at least (a blank line will do). A client [`CLIENT_QUEUE`] lines
//! behind is dropped and counted, never waited for; a line over [`MAX_LINE`] bytes is dropped
//! as it comes; the controller's frames wait in a queue of [`TO_DEVICE_QUEUE`] frames, and
//! when it is full the controller is not read (TCP pushes back on it), nothing dropped.
//!
//! The serial side (the `serial` module) has a thread of its own: it reconnects with backoff (0.1 s
//! doubling to 2 s) whenever the port fails or disappears; the decoder starts afresh on each
//! link, and a frame whose write failed is written again, whole, on the next (the device drops
//! the part it got).

mod client;
mod hub;
mod lines;
mod serial;
mod token;

pub use client::CLIENT_QUEUE;
pub use lines::MAX_LINE;
pub use token::PairingToken;

use crate::device_sim::{until_interrupted, Serial};
use anyhow::{bail, Context, Result};
use hub::Hub;
use serde_json::json;
use std::net::TcpListener;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::sync_channel;
use std::sync::Arc;
use std::time::Duration;

/// Frames from the controller waiting for the device.
pub const TO_DEVICE_QUEUE: usize = 4096;
/// Lines from the serial side waiting for the event loop.
const NEWS_QUEUE: usize = 1024;
/// Connections the system holds for the bridge to accept (std listens with 128): a burst
/// waits for the next turn rather than having its connection requests dropped.
const BACKLOG: i32 = 1024;
/// Where the bridge listens unless told.
pub const DEFAULT_LISTEN: &str = "127.0.0.1:7878";
/// Clients holding a role at once, unless told.
pub const MAX_CLIENTS: u16 = 8;
/// Most clients `--max-clients` allows: with as many pairing, the bridge stays well within
/// the usual limit of 1 024 descriptors.
const MOST_CLIENTS: i64 = 256;
/// Seconds a client may be silent, unless told.
pub const IDLE_SECS: u64 = 30;
/// Longest `--idle-timeout`, seconds (a day).
const MOST_IDLE_SECS: u64 = 24 * 3600;
/// How long a new connection has to send its first line (its token, or any line where none is
/// needed), or the idle timeout if shorter.
pub const HANDSHAKE: Duration = Duration::from_secs(5);

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    serial: Serial,
    /// Where phone apps connect, as HOST:PORT: a name (`localhost:7878`) or an address
    /// (`0.0.0.0:7878`, `[::1]:7878`); port 0 takes a free one, and the first line on standard
    /// error says which. An address other hosts reach needs a pairing token.
    #[arg(long, default_value = DEFAULT_LISTEN)]
    listen: String,
    /// The pairing token: every client's first line must be `{"token": "TOKEN"}`. Listening
    /// beyond loopback without one, the bridge makes one and prints it once on standard error.
    #[arg(long, value_parser = PairingToken::parse)]
    token: Option<PairingToken>,
    /// Most clients at once (1 to 256): the first controls the device, the others watch;
    /// a connection beyond them is told `full` and closed.
    #[arg(long, default_value_t = MAX_CLIENTS,
          value_parser = clap::value_parser!(u16).range(1..=MOST_CLIENTS))]
    max_clients: u16,
    /// Seconds a client may go without sending a line (a blank line is a keep-alive) before
    /// it is closed; 1 to 86400.
    #[arg(long, default_value_t = IDLE_SECS,
          value_parser = clap::value_parser!(u64).range(1..=MOST_IDLE_SECS))]
    idle_timeout: u64,
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
    let local = listener.local_addr().context("the listener's address")?;
    eprintln!(
        "bridge: {} <-> {local} (one JSON message per line; Ctrl-C to stop)",
        args.serial.port.display(),
    );
    let token = match (&args.token, local.ip().is_loopback()) {
        (Some(token), _) => Some(token.clone()),
        (None, true) => None,
        (None, false) => {
            let token = PairingToken::generate();
            eprintln!(
                "bridge: {local} is reachable from other hosts: pairing token {} \
                 (each client's first line: {{\"token\": \"{}\"}})",
                token.as_str(),
                token.as_str()
            );
            Some(token)
        }
    };
    let policy = Policy {
        max_clients: usize::from(args.max_clients),
        idle: Duration::from_secs(args.idle_timeout),
        token,
    };
    let stop = until_interrupted()?;
    let c = serve(
        &args.serial.port,
        args.serial.baud,
        listener,
        &policy,
        &stop,
    )?;
    if args.json {
        let doc = json!({"from_device": c.from_device, "to_device": c.to_device, "links": c.links,
                         "slow_clients": c.slow_clients, "bad_lines": c.bad_lines,
                         "turned_away": c.turned_away, "timed_out": c.timed_out,
                         "bad_tokens": c.bad_tokens, "watcher_lines": c.watcher_lines,
                         "accept_errors": c.accept_errors});
        return Ok(format!("{doc}\n"));
    }
    Ok(format!("{c}\n"))
}

/// Who may connect and for how long.
#[derive(Clone, Debug)]
pub struct Policy {
    /// Clients holding a role at once; as many again may be pairing.
    pub max_clients: usize,
    /// How long a client may go without sending a line.
    pub idle: Duration,
    /// The token each client's first line must carry, if any.
    pub token: Option<PairingToken>,
}

impl Default for Policy {
    /// [`MAX_CLIENTS`], [`IDLE_SECS`], no token: for a bridge on loopback.
    fn default() -> Policy {
        Policy {
            max_clients: usize::from(MAX_CLIENTS),
            idle: Duration::from_secs(IDLE_SECS),
            token: None,
        }
    }
}

impl Policy {
    /// How long a new connection has to send its first line.
    pub fn handshake(&self) -> Duration {
        HANDSHAKE.min(self.idle)
    }
}

/// What a bridge has relayed and refused.
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
    /// Connections turned away: the clients were full, or a newer connection needed a place
    /// to pair.
    pub turned_away: u64,
    /// Clients closed for sending no line in time.
    pub timed_out: u64,
    /// Connections whose first line was not the pairing token.
    pub bad_tokens: u64,
    /// Message lines from watchers, refused.
    pub watcher_lines: u64,
    /// Connections the system would not let the bridge accept (out of descriptors or memory).
    pub accept_errors: u64,
}

impl std::fmt::Display for Counters {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} frames from the device, {} to it, {} serial links, {} slow clients dropped, \
             {} bad lines, {} connections turned away, {} clients timed out, {} bad tokens, \
             {} watcher lines refused, {} failed accepts",
            self.from_device,
            self.to_device,
            self.links,
            self.slow_clients,
            self.bad_lines,
            self.turned_away,
            self.timed_out,
            self.bad_tokens,
            self.watcher_lines,
            self.accept_errors
        )
    }
}

/// [`Counters`] as the bridge's two threads count.
#[derive(Debug, Default)]
pub struct Counting {
    from_device: AtomicU64,
    to_device: AtomicU64,
    links: AtomicU64,
    slow_clients: AtomicU64,
    bad_lines: AtomicU64,
    turned_away: AtomicU64,
    timed_out: AtomicU64,
    bad_tokens: AtomicU64,
    watcher_lines: AtomicU64,
    accept_errors: AtomicU64,
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
            turned_away: get(&self.turned_away),
            timed_out: get(&self.timed_out),
            bad_tokens: get(&self.bad_tokens),
            watcher_lines: get(&self.watcher_lines),
            accept_errors: get(&self.accept_errors),
        }
    }
}

/// Relays between `port` and the clients of `listener` under `policy` until `stop` is set;
/// returns what it relayed.
///
/// # Errors
/// If `listener` is reachable from other hosts and `policy` has no token, or the event loop
/// or the serial side's thread cannot be started, or polling fails.
pub fn serve(
    port: &Path,
    baud: u32,
    listener: TcpListener,
    policy: &Policy,
    stop: &AtomicBool,
) -> Result<Counters> {
    let local = listener.local_addr().context("the listener's address")?;
    if policy.token.is_none() && !local.ip().is_loopback() {
        bail!("{local} is reachable from other hosts: the bridge needs a pairing token there");
    }
    listener
        .set_nonblocking(true)
        .context("setting the listener non-blocking")?;
    if let Err(e) = socket2::SockRef::from(&listener).listen(BACKLOG) {
        eprintln!("bridge: the listen backlog stays the system's: {e}");
    }
    let counters = Arc::new(Counting::default());
    let (to_device, frames) = sync_channel::<Vec<u8>>(TO_DEVICE_QUEUE);
    let (news, heard) = sync_channel(NEWS_QUEUE);
    let (mut hub, waker) = Hub::new(listener, policy.clone(), to_device, heard, counters.clone())?;
    let ending = Arc::new(AtomicBool::new(false));
    let serial = {
        let to = serial::Loop {
            news,
            waker,
            counters: counters.clone(),
        };
        let (port, ending) = (port.to_path_buf(), ending.clone());
        std::thread::Builder::new()
            .name("bridge-serial".into())
            .spawn(move || serial::relay(&port, baud, &frames, &to, &ending))
            .context("starting the serial side's thread")?
    };
    let served = hub.run(stop);
    ending.store(true, Ordering::Relaxed);
    // Ends the serial side's wait for the loop, if any.
    drop(hub);
    let _ = serial.join();
    served?;
    Ok(counters.now())
}
