//! The bridge's event loop: one thread, woken by the sockets and by the serial side, serves
//! every client. It admits connections or turns them away, checks tokens, reads lines and
//! sends the controller's messages on to the device, writes the lines queued for each client,
//! closes clients that fall silent and hands control on when the controller leaves.

use super::client::{json_line, Client, Role, CLIENT_QUEUE};
use super::lines::{Line, MAX_LINE};
use super::serial::News;
use super::{Counting, Policy};
use crate::device_sim;
use anyhow::{Context, Result};
use mio::net::{TcpListener, TcpStream};
use mio::{Events, Interest, Poll, Token, Waker};
use posecoach_core::wire::Message;
use serde_json::json;
use std::io::{ErrorKind, Write};
use std::net::{Shutdown, SocketAddr};
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError};
use std::sync::Arc;
use std::time::{Duration, Instant};

const LISTENER: Token = Token(0);
const WAKER: Token = Token(1);
/// Longest sleep between turns: how soon a Ctrl-C, a deadline, or room again in the device's
/// queue, is seen.
const TICK: Duration = Duration::from_millis(20);
/// Wait before accepting again after accepting failed for want of a resource (descriptors,
/// memory): the clients already there are served meanwhile.
const ACCEPT_BACKOFF: Duration = Duration::from_millis(100);
/// Connections accepted, and lines or reads of one client, per turn: no one starves the others.
const PER_TURN: usize = 64;
/// Lines from the serial side taken per turn.
const NEWS_PER_TURN: usize = CLIENT_QUEUE;
/// How long a client told why it is closed has to read that line and close its end.
const LINGER: Duration = Duration::from_secs(1);
/// Events taken from the poller at a time.
const EVENTS: usize = 256;

/// The event loop's state.
pub struct Hub {
    poll: Poll,
    listener: TcpListener,
    policy: Policy,
    clients: Vec<Client>,
    /// The next client's number (and poller token).
    next_id: usize,
    /// Whether the serial port is open, for the hello.
    connected: bool,
    to_device: SyncSender<Vec<u8>>,
    news: Receiver<News>,
    counters: Arc<Counting>,
    /// Connections may be waiting to be accepted.
    backlog: bool,
    /// Accepting failed for want of a resource: not again before then.
    accept_after: Option<Instant>,
    /// Work was left for the next turn, which then comes at once.
    more: bool,
    /// The line being handled.
    line: Vec<u8>,
}

impl Hub {
    /// A loop serving `listener` (non-blocking already) under `policy`; client frames go to
    /// `to_device`, the device's lines come from `news`, whose sender must wake the loop with
    /// the waker returned.
    ///
    /// # Errors
    /// If the poller cannot be made or the listener watched.
    pub fn new(
        listener: std::net::TcpListener,
        policy: Policy,
        to_device: SyncSender<Vec<u8>>,
        news: Receiver<News>,
        counters: Arc<Counting>,
    ) -> Result<(Hub, Arc<Waker>)> {
        let poll = Poll::new().context("making the bridge's poller")?;
        let mut listener = TcpListener::from_std(listener);
        poll.registry()
            .register(&mut listener, LISTENER, Interest::READABLE)
            .context("watching the listener")?;
        let waker = Waker::new(poll.registry(), WAKER).context("making the bridge's waker")?;
        let hub = Hub {
            poll,
            listener,
            policy,
            clients: Vec::new(),
            next_id: 2,
            connected: false,
            to_device,
            news,
            counters,
            backlog: true,
            accept_after: None,
            more: false,
            line: Vec::with_capacity(MAX_LINE),
        };
        Ok((hub, Arc::new(waker)))
    }

    /// Serves until `stop` is set.
    ///
    /// # Errors
    /// If the poller fails.
    pub fn run(&mut self, stop: &AtomicBool) -> Result<()> {
        let mut events = Events::with_capacity(EVENTS);
        while !stop.load(Ordering::Relaxed) {
            let wait = if std::mem::take(&mut self.more) {
                Duration::ZERO
            } else {
                TICK
            };
            match self.poll.poll(&mut events, Some(wait)) {
                Ok(()) => {}
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e).context("waiting on the sockets"),
            }
            for event in &events {
                match event.token() {
                    LISTENER => self.backlog = true,
                    WAKER => {}
                    Token(id) => {
                        if let Some(c) = self.clients.iter_mut().find(|c| c.id == id) {
                            c.readable |= event.is_readable() || event.is_read_closed();
                            c.writable |= event.is_writable() || event.is_write_closed();
                            c.readable |= event.is_error();
                        }
                    }
                }
            }
            self.turn(Instant::now());
        }
        Ok(())
    }

    /// One turn: the device's lines out, new connections in, every client served, the gone
    /// ones closed.
    fn turn(&mut self, now: Instant) {
        self.relay_news();
        // Clients dropped for falling behind give their places back before new ones come.
        self.sweep();
        self.accept(now);
        for i in 0..self.clients.len() {
            self.read(i, now);
            self.finish(i, now);
        }
        self.sweep();
    }

    fn count(&self, counter: impl Fn(&Counting) -> &AtomicU64) {
        counter(&self.counters).fetch_add(1, Ordering::Relaxed);
    }

    /// The controller, unless it is leaving.
    fn controller(&self) -> Option<&Client> {
        self.clients
            .iter()
            .find(|c| c.role == Role::Controller && c.listening())
    }

    /// Clients holding a role (leaving ones too: they still hold a socket).
    fn with_roles(&self) -> usize {
        let held = |c: &&Client| c.role != Role::Pairing && !c.gone;
        self.clients.iter().filter(held).count()
    }

    /// Queues `line` for client `i`; drops it, counted, if it has fallen behind.
    fn tell(&mut self, i: usize, line: Rc<str>) {
        let c = &mut self.clients[i];
        if !c.gone && !c.send(line) {
            c.gone = true;
            self.counters.slow_clients.fetch_add(1, Ordering::Relaxed);
            eprintln!(
                "bridge: client {} dropped: {CLIENT_QUEUE} lines behind",
                c.peer
            );
        }
    }

    /// Tells client `i` why it is closed; it is closed once that is written and the peer is
    /// done, or after [`LINGER`].
    fn dismiss(&mut self, i: usize, why: Rc<str>, now: Instant) {
        self.tell(i, why);
        let c = &mut self.clients[i];
        c.leaving = true;
        c.blocked = None;
        c.deadline = now + LINGER;
        c.input.clear();
    }

    /// The line for a connection turned away: the clients are full.
    fn full(&self) -> Rc<str> {
        json_line(&json!({"bridge": {"event": "full", "max_clients": self.policy.max_clients}}))
    }

    /// Queues the serial side's lines for every client with a role.
    fn relay_news(&mut self) {
        let news: Vec<News> = self.news.try_iter().take(NEWS_PER_TURN).collect();
        self.more |= news.len() == NEWS_PER_TURN;
        for news in news {
            let text = match news {
                News::Device(text) => text,
                News::Link(up, text) => {
                    self.connected = up;
                    text
                }
            };
            let text = Rc::from(text);
            for i in 0..self.clients.len() {
                if self.clients[i].listening() {
                    self.tell(i, Rc::clone(&text));
                }
            }
        }
    }

    /// Accepts what waits in the backlog, backing off when the system refuses.
    fn accept(&mut self, now: Instant) {
        if !self.backlog || self.accept_after.is_some_and(|t| now < t) {
            return;
        }
        for _ in 0..PER_TURN {
            match self.listener.accept() {
                Ok((stream, peer)) => {
                    if self.accept_after.take().is_some() {
                        eprintln!("bridge: accepting clients again");
                    }
                    self.admit(stream, peer, now);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    self.backlog = false;
                    return;
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        ErrorKind::Interrupted
                            | ErrorKind::ConnectionAborted
                            | ErrorKind::ConnectionReset
                    ) => {}
                Err(e) => {
                    // Out of descriptors or memory: what waits stays in the backlog.
                    self.count(|c| &c.accept_errors);
                    if self.accept_after.replace(now + ACCEPT_BACKOFF).is_none() {
                        eprintln!(
                            "bridge: accepting a client: {e}; trying again every {} ms meanwhile",
                            ACCEPT_BACKOFF.as_millis()
                        );
                    }
                    return;
                }
            }
        }
        self.more = true;
    }

    /// Gives a new connection its role, or turns it away.
    fn admit(&mut self, mut stream: TcpStream, peer: SocketAddr, now: Instant) {
        if self.with_roles() >= self.policy.max_clients {
            self.count(|c| &c.turned_away);
            let _ = stream.write(self.full().as_bytes());
            let _ = stream.shutdown(Shutdown::Write);
            return;
        }
        let role = if self.policy.token.is_some() {
            self.make_room_to_pair();
            Role::Pairing
        } else if self.controller().is_some() {
            Role::Watcher
        } else {
            Role::Controller
        };
        let id = self.next_id;
        let interest = Interest::READABLE | Interest::WRITABLE;
        if let Err(e) = self
            .poll
            .registry()
            .register(&mut stream, Token(id), interest)
        {
            self.count(|c| &c.accept_errors);
            eprintln!("bridge: client {peer} not served: {e}");
            return;
        }
        self.next_id += 1;
        let deadline = now + self.policy.handshake();
        self.clients
            .push(Client::new(id, stream, peer, role, deadline));
        let serial = if self.connected {
            "connected"
        } else {
            "disconnected"
        };
        let hello = json!({"bridge": {"event": "hello", "serial": serial, "role": role.name()}});
        self.tell(self.clients.len() - 1, json_line(&hello));
        if role != Role::Pairing {
            eprintln!("bridge: client {peer} connected, {}", role.name());
        }
    }

    /// With a connection pairing per client allowed already, turns the oldest one away (and
    /// closes it at once: the descriptors held never pass one per place).
    fn make_room_to_pair(&mut self) {
        let pairing = |c: &&Client| c.role == Role::Pairing && !c.gone;
        if self.clients.iter().filter(pairing).count() < self.policy.max_clients {
            return;
        }
        if let Some(i) = self.clients.iter().position(|c| pairing(&c)) {
            self.count(|c| &c.turned_away);
            let mut oldest = self.clients.remove(i);
            let _ = oldest.stream.write(self.full().as_bytes());
            let _ = self.poll.registry().deregister(&mut oldest.stream);
        }
    }

    /// Takes client `i`'s lines while the device's queue has room, [`PER_TURN`] at most.
    fn read(&mut self, i: usize, now: Instant) {
        let mut line = std::mem::take(&mut self.line);
        for _ in 0..PER_TURN {
            let c = &mut self.clients[i];
            if c.gone {
                break;
            }
            if let Some(frame) = c.blocked.take() {
                match self.to_device.try_send(frame) {
                    Ok(()) => continue,
                    Err(TrySendError::Full(frame)) => {
                        c.blocked = Some(frame);
                        break;
                    }
                    Err(TrySendError::Disconnected(_)) => {
                        c.gone = true;
                        break;
                    }
                }
            }
            if !c.leaving {
                if let Some((n, kind)) = c.input.next(&mut line) {
                    self.take(i, n, kind, &line, now);
                    continue;
                }
            }
            if c.ended {
                match c.input.rest(&mut line).filter(|_| !c.leaving) {
                    Some((n, kind)) => self.take(i, n, kind, &line, now),
                    None => c.gone = true,
                }
                continue;
            }
            if !c.readable {
                break;
            }
            match c.input.fill(&mut c.stream) {
                Ok(0) => c.ended = true,
                // A leaving client's bytes are read only to see its end.
                Ok(_) if c.leaving => c.input.clear(),
                Ok(_) => {}
                Err(e) if e.kind() == ErrorKind::WouldBlock => c.readable = false,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => c.gone = true,
            }
        }
        let c = &self.clients[i];
        self.more |= c.readable && c.blocked.is_none() && !c.gone;
        self.line = line;
    }

    /// Handles line `n` of client `i`.
    fn take(&mut self, i: usize, n: u64, kind: Line, line: &[u8], now: Instant) {
        if self.clients[i].role == Role::Pairing {
            return self.pair(i, kind, line, now);
        }
        let c = &mut self.clients[i];
        c.heard = true;
        c.deadline = now + self.policy.idle;
        let role = c.role;
        let refusal = match kind {
            Line::TooLong => {
                self.count(|c| &c.bad_lines);
                format!("line {n}: longer than {MAX_LINE} bytes, dropped: no message is that long")
            }
            // A keep-alive.
            Line::Whole if line.trim_ascii().is_empty() => return,
            Line::Whole if role == Role::Watcher => {
                self.count(|c| &c.watcher_lines);
                format!(
                    "line {n}: not sent: this client is a watcher; only the controller's \
                     messages reach the device"
                )
            }
            Line::Whole => match to_frame(line) {
                Ok(frame) => {
                    self.clients[i].blocked = Some(frame);
                    return;
                }
                Err(why) => {
                    self.count(|c| &c.bad_lines);
                    format!("line {n}: {why}")
                }
            },
        };
        self.tell(i, json_line(&json!({ "error": refusal })));
    }

    /// Handles the first line of client `i`, pairing: the token, or it is dismissed.
    fn pair(&mut self, i: usize, kind: Line, line: &[u8], now: Instant) {
        let opens = kind == Line::Whole
            && self
                .policy
                .token
                .as_ref()
                .is_some_and(|token| token.opens(line));
        if !opens {
            self.count(|c| &c.bad_tokens);
            eprintln!(
                "bridge: client {} dismissed: its first line is not the pairing token",
                self.clients[i].peer
            );
            let why = "line 1: not the pairing token: the first line to this bridge must be \
                       {\"token\": \"...\"} with the token it was given or printed";
            return self.dismiss(i, json_line(&json!({ "error": why })), now);
        }
        if self.with_roles() >= self.policy.max_clients {
            self.count(|c| &c.turned_away);
            return self.dismiss(i, self.full(), now);
        }
        let role = match self.controller() {
            Some(_) => Role::Watcher,
            None => Role::Controller,
        };
        let c = &mut self.clients[i];
        (c.role, c.heard, c.deadline) = (role, true, now + self.policy.idle);
        eprintln!("bridge: client {} paired, {}", c.peer, role.name());
        let paired = json!({"bridge": {"event": "paired", "role": role.name()}});
        self.tell(i, json_line(&paired));
    }

    /// Writes client `i`'s queue, and closes it if its deadline has passed.
    fn finish(&mut self, i: usize, now: Instant) {
        let idle = self.policy.idle;
        let c = &mut self.clients[i];
        if c.gone {
            return;
        }
        if c.blocked.is_some() {
            // Waiting on the device is not silence.
            c.deadline = now + idle;
        }
        if now >= c.deadline {
            if c.leaving {
                c.gone = true;
                return;
            }
            self.count(|c| &c.timed_out);
            let reason = match self.clients[i].heard {
                true => format!("idle: no line for {} s", idle.as_secs()),
                false => format!(
                    "silent: no line within {} s of connecting",
                    self.policy.handshake().as_secs()
                ),
            };
            eprintln!("bridge: client {} closed, {reason}", self.clients[i].peer);
            let closed = json!({"bridge": {"event": "closed", "reason": reason}});
            self.dismiss(i, json_line(&closed), now);
        }
        let c = &mut self.clients[i];
        if c.flush().is_err() {
            c.gone = true;
        }
    }

    /// Closes the gone clients and, if the controller left, hands control to the watcher
    /// connected longest.
    fn sweep(&mut self) {
        let registry = self.poll.registry();
        self.clients.retain_mut(|c| {
            if c.gone {
                let _ = registry.deregister(&mut c.stream);
                if c.role != Role::Pairing {
                    eprintln!("bridge: client {} left", c.peer);
                }
            }
            !c.gone
        });
        while self.controller().is_none() {
            let watcher = |c: &&Client| c.role == Role::Watcher && c.listening();
            let Some(i) = self.clients.iter().position(|c| watcher(&c)) else {
                return;
            };
            self.clients[i].role = Role::Controller;
            eprintln!("bridge: client {} now controls", self.clients[i].peer);
            self.tell(i, json_line(&json!({"bridge": {"event": "control"}})));
        }
    }
}

/// `line` as a frame for the device, or why it is not a message.
fn to_frame(line: &[u8]) -> Result<Vec<u8>, String> {
    let message = serde_json::from_slice::<Message>(line).map_err(|e| {
        format!(
            "not a message ({e}): send one wire message as JSON per line, such as {}",
            r#"{"CoachSelect": {"seq": 1, "coach": 0}}"#
        )
    })?;
    device_sim::frame(&message).ok_or_else(|| "too long for one frame".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::{Counters, PairingToken};
    use serde_json::Value;
    use std::io::{BufRead, BufReader};
    use std::net::TcpStream as Socket;
    use std::sync::mpsc::{sync_channel, Receiver, SyncSender};

    /// Longest wait for anything the loop does.
    const PATIENCE: Duration = Duration::from_secs(20);
    const TOKEN: &str = "s3cret";

    /// A loop on its own thread, on a loopback port, with no serial side: the test reads the
    /// frames for the device and makes the device's lines.
    struct Rig {
        addr: SocketAddr,
        stop: Arc<AtomicBool>,
        frames: Receiver<Vec<u8>>,
        news: SyncSender<News>,
        waker: Arc<Waker>,
        counters: Arc<Counting>,
        thread: std::thread::JoinHandle<()>,
    }

    impl Rig {
        fn start(policy: Policy, device_queue: usize) -> Rig {
            let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
            listener.set_nonblocking(true).unwrap();
            let addr = listener.local_addr().unwrap();
            let (to_device, frames) = sync_channel(device_queue);
            let (news, heard) = sync_channel(NEWS_PER_TURN);
            let counters = Arc::new(Counting::default());
            let stop = Arc::new(AtomicBool::new(false));
            let (wakers, waker) = sync_channel(1);
            let thread = {
                let (counters, stop) = (counters.clone(), stop.clone());
                std::thread::spawn(move || {
                    let (mut hub, waker) =
                        Hub::new(listener, policy, to_device, heard, counters).unwrap();
                    wakers.send(waker).unwrap();
                    hub.run(&stop).unwrap();
                })
            };
            let waker = waker.recv().unwrap();
            Rig {
                addr,
                stop,
                frames,
                news,
                waker,
                counters,
                thread,
            }
        }

        /// A line from the device, to every client with a role.
        fn device_says(&self, seq: u32) {
            let line = json!({ "device": Message::Ack { seq } });
            self.news.send(News::Device(format!("{line}\n"))).unwrap();
            self.waker.wake().unwrap();
        }

        /// The next frame for the device.
        fn frame(&self) -> Vec<u8> {
            self.frames.recv_timeout(PATIENCE).unwrap()
        }

        fn stop(self) -> Counters {
            self.stop.store(true, Ordering::Relaxed);
            self.thread.join().unwrap();
            self.counters.now()
        }
    }

    fn policy(max_clients: usize, idle_secs: u64, token: Option<&str>) -> Policy {
        Policy {
            max_clients,
            idle: Duration::from_secs(idle_secs),
            token: token.map(|t| PairingToken::parse(t).unwrap()),
        }
    }

    /// A phone: writes lines, reads the bridge's.
    struct Phone {
        reader: BufReader<Socket>,
        stream: Socket,
    }

    impl Phone {
        fn connect(addr: SocketAddr) -> Phone {
            let stream = Socket::connect(addr).unwrap();
            stream.set_read_timeout(Some(PATIENCE)).unwrap();
            let reader = BufReader::new(stream.try_clone().unwrap());
            Phone { reader, stream }
        }

        /// Connects and reads the hello: the role it gives.
        fn hello(addr: SocketAddr) -> (Phone, String) {
            let mut phone = Phone::connect(addr);
            let hello = phone.line();
            assert_eq!(hello["bridge"]["event"], "hello", "{hello}");
            let role = hello["bridge"]["role"].as_str().unwrap().to_string();
            (phone, role)
        }

        fn line(&mut self) -> Value {
            let mut line = String::new();
            let n = self.reader.read_line(&mut line).unwrap();
            assert!(n > 0, "the bridge closed the connection");
            serde_json::from_str(&line).unwrap()
        }

        /// Whether the bridge closes the connection, after any lines.
        fn closed(&mut self) -> bool {
            let mut line = String::new();
            loop {
                line.clear();
                match self.reader.read_line(&mut line) {
                    Ok(0) => return true,
                    Ok(_) => {}
                    Err(e) => return e.kind() == ErrorKind::ConnectionReset,
                }
            }
        }

        fn send(&mut self, line: &str) {
            writeln!(self.stream, "{line}").unwrap();
        }

        fn ack(&mut self, seq: u32) {
            self.send(&serde_json::to_string(&Message::Ack { seq }).unwrap());
        }
    }

    fn ack(seq: u32) -> Vec<u8> {
        device_sim::frame(&Message::Ack { seq }).unwrap()
    }

    #[test]
    fn the_first_client_controls_and_the_others_watch() {
        let rig = Rig::start(policy(3, 30, None), 16);
        let (mut first, role) = Phone::hello(rig.addr);
        assert_eq!(role, "controller");
        let (mut second, role) = Phone::hello(rig.addr);
        assert_eq!(role, "watcher");
        second.ack(1);
        let refusal = second.line();
        let why = refusal["error"].as_str().unwrap();
        assert!(
            why.starts_with("line 1: not sent: this client is a watcher"),
            "{why}"
        );
        first.ack(2);
        assert_eq!(rig.frame(), ack(2));
        rig.device_says(3);
        for phone in [&mut first, &mut second] {
            assert_eq!(phone.line()["device"]["Ack"]["seq"], 3);
        }
        let counters = rig.stop();
        assert_eq!(counters.watcher_lines, 1);
        assert_eq!(counters.bad_lines, 0);
    }

    #[test]
    fn control_passes_to_the_watcher_connected_longest() {
        let rig = Rig::start(policy(3, 30, None), 16);
        let (first, _) = Phone::hello(rig.addr);
        let (mut second, _) = Phone::hello(rig.addr);
        let (mut third, role) = Phone::hello(rig.addr);
        assert_eq!(role, "watcher");
        drop(first);
        assert_eq!(second.line()["bridge"]["event"], "control");
        second.ack(4);
        assert_eq!(rig.frame(), ack(4));
        third.ack(5);
        assert!(third.line()["error"].as_str().unwrap().contains("watcher"));
        rig.stop();
    }

    #[test]
    fn a_connection_beyond_the_cap_is_told_full_and_closed() {
        let rig = Rig::start(policy(2, 30, None), 16);
        let (first, _) = Phone::hello(rig.addr);
        let (_second, _) = Phone::hello(rig.addr);
        let mut third = Phone::connect(rig.addr);
        let full = third.line();
        assert_eq!(full["bridge"]["event"], "full", "{full}");
        assert_eq!(full["bridge"]["max_clients"], 2);
        assert!(third.closed());
        // A place freed is a place taken.
        drop(first);
        let start = Instant::now();
        loop {
            let mut next = Phone::connect(rig.addr);
            if next.line()["bridge"]["event"] == "hello" {
                break;
            }
            assert!(start.elapsed() < PATIENCE, "the place was never freed");
            std::thread::sleep(Duration::from_millis(10));
        }
        assert!(rig.stop().turned_away >= 1);
    }

    #[test]
    fn a_silent_client_is_closed_and_a_keep_alive_keeps_one() {
        let rig = Rig::start(policy(3, 1, None), 16);
        let (mut talking, _) = Phone::hello(rig.addr);
        let (mut silent, _) = Phone::hello(rig.addr);
        // Blank lines for three times the idle timeout, then a message.
        for _ in 0..15 {
            talking.send("");
            std::thread::sleep(Duration::from_millis(200));
        }
        talking.ack(6);
        assert_eq!(rig.frame(), ack(6));
        let closed = silent.line();
        assert_eq!(closed["bridge"]["event"], "closed", "{closed}");
        let reason = closed["bridge"]["reason"].as_str().unwrap();
        assert!(reason.starts_with("silent"), "{reason}");
        assert!(silent.closed());
        // Now silent itself: closed as idle.
        let closed = talking.line();
        assert!(closed["bridge"]["reason"]
            .as_str()
            .unwrap()
            .starts_with("idle"));
        assert!(talking.closed());
        assert_eq!(rig.stop().timed_out, 2);
    }

    #[test]
    fn a_token_is_required_checked_and_counted() {
        let rig = Rig::start(policy(3, 30, Some(TOKEN)), 16);
        let (mut wrong, role) = Phone::hello(rig.addr);
        assert_eq!(role, "pairing");
        wrong.send(r#"{"token": "guess"}"#);
        let refusal = wrong.line();
        let why = refusal["error"].as_str().unwrap();
        assert!(why.starts_with("line 1: not the pairing token"), "{why}");
        assert!(wrong.closed());
        // A message without the token is refused the same way, and never reaches the device.
        let (mut tokenless, _) = Phone::hello(rig.addr);
        tokenless.ack(7);
        assert!(tokenless.line()["error"].is_string());
        assert!(tokenless.closed());
        let (mut right, _) = Phone::hello(rig.addr);
        right.send(&format!(r#"{{"token": "{TOKEN}"}}"#));
        let paired = right.line();
        assert_eq!(paired["bridge"]["event"], "paired", "{paired}");
        assert_eq!(paired["bridge"]["role"], "controller");
        right.ack(8);
        assert_eq!(rig.frame(), ack(8));
        assert!(rig.frames.try_recv().is_err());
        assert_eq!(rig.stop().bad_tokens, 2);
    }

    #[test]
    fn connections_pairing_beyond_the_cap_make_way_for_new_ones() {
        let rig = Rig::start(policy(1, 30, Some(TOKEN)), 16);
        let (mut idle, _) = Phone::hello(rig.addr);
        let (mut phone, _) = Phone::hello(rig.addr);
        assert_eq!(idle.line()["bridge"]["event"], "full");
        assert!(idle.closed());
        phone.send(&format!(r#"{{"token": "{TOKEN}"}}"#));
        assert_eq!(phone.line()["bridge"]["role"], "controller");
        // The one place with a role is held: a new connection is turned away at once.
        let mut late = Phone::connect(rig.addr);
        assert_eq!(late.line()["bridge"]["event"], "full");
        assert!(late.closed());
        assert_eq!(rig.stop().turned_away, 2);
    }

    #[test]
    fn a_full_device_queue_stops_reading_the_controller_and_drops_nothing() {
        const SENT: u32 = 50;
        let rig = Rig::start(policy(1, 30, None), 2);
        let (mut phone, _) = Phone::hello(rig.addr);
        for seq in 0..SENT {
            phone.ack(seq);
        }
        for seq in 0..SENT {
            std::thread::sleep(Duration::from_millis(2));
            assert_eq!(rig.frame(), ack(seq));
        }
        assert_eq!(rig.stop(), Counters::default());
    }

    #[test]
    fn a_client_that_falls_behind_is_dropped_and_counted() {
        let rig = Rig::start(policy(2, 30, None), 2);
        let (mut reading, _) = Phone::hello(rig.addr);
        // Never reads: its socket's buffers fill, then its queue.
        let (_deaf, _) = Phone::hello(rig.addr);
        let long = "d".repeat(6_000);
        let start = Instant::now();
        while rig.counters.now().slow_clients == 0 {
            assert!(
                start.elapsed() < PATIENCE,
                "the deaf client was never dropped"
            );
            for _ in 0..64 {
                let line = json!({ "device": long });
                rig.news.send(News::Device(format!("{line}\n"))).unwrap();
            }
            rig.waker.wake().unwrap();
            for _ in 0..64 {
                assert!(reading.line()["device"].is_string());
            }
        }
        assert_eq!(rig.stop().slow_clients, 1);
    }
}
