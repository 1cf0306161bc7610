//! One connected client: its socket, its role, the lines it sent and those waiting for it.

use super::lines::Lines;
use mio::net::TcpStream;
use serde_json::Value;
use std::collections::VecDeque;
use std::io::{self, ErrorKind, IoSlice, Write};
use std::net::{Shutdown, SocketAddr};
use std::rc::Rc;
use std::time::Instant;

/// Lines waiting for one client.
pub const CLIENT_QUEUE: usize = 1024;
/// Lines given to the socket in one write.
const LINES_PER_WRITE: usize = 32;

/// What a client may do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Connected to a bridge with a token, and has not sent it yet: gets nothing but its hello.
    Pairing,
    /// Gets every line from the device; its messages are refused.
    Watcher,
    /// Gets every line from the device, and its messages go to the device.
    Controller,
}

impl Role {
    /// The role as the bridge's lines name it.
    pub fn name(self) -> &'static str {
        match self {
            Role::Pairing => "pairing",
            Role::Watcher => "watcher",
            Role::Controller => "controller",
        }
    }
}

/// `value` as a line for a client, newline included.
pub fn json_line(value: &Value) -> Rc<str> {
    Rc::from(format!("{value}\n"))
}

/// A connected client.
pub struct Client {
    /// Its number, in order of connection; its token with the poller.
    pub id: usize,
    pub stream: TcpStream,
    pub peer: SocketAddr,
    pub role: Role,
    /// Whether it has sent a line (or its token): until then its deadline is the handshake's.
    pub heard: bool,
    /// When it is closed unless it sends a line; once leaving, when it is closed anyway.
    pub deadline: Instant,
    /// Told why it is closed: its lines are dropped, its queue written, then its socket closed.
    pub leaving: bool,
    /// To be closed at the end of this turn.
    pub gone: bool,
    /// The socket may have bytes to read, or its end.
    pub readable: bool,
    /// The socket may take bytes.
    pub writable: bool,
    /// The peer has sent all it will.
    pub ended: bool,
    pub input: Lines,
    /// Its next frame for the device, waiting for room in the device's queue: the client is not
    /// read meanwhile.
    pub blocked: Option<Vec<u8>>,
    queue: VecDeque<Rc<str>>,
    /// Bytes of the queue's first line already written.
    written: usize,
    /// Whether its sending side is shut (once leaving and all written).
    shut: bool,
}

impl Client {
    pub fn new(
        id: usize,
        stream: TcpStream,
        peer: SocketAddr,
        role: Role,
        deadline: Instant,
    ) -> Client {
        Client {
            id,
            stream,
            peer,
            role,
            heard: false,
            deadline,
            leaving: false,
            gone: false,
            readable: true,
            writable: true,
            ended: false,
            input: Lines::default(),
            blocked: None,
            queue: VecDeque::new(),
            written: 0,
            shut: false,
        }
    }

    /// Whether it has a role and is not on its way out: it gets the device's lines.
    pub fn listening(&self) -> bool {
        self.role != Role::Pairing && !self.leaving && !self.gone
    }

    /// Queues `line`, unless [`CLIENT_QUEUE`] lines already wait: whether it was queued.
    #[must_use]
    pub fn send(&mut self, line: Rc<str>) -> bool {
        if self.queue.len() >= CLIENT_QUEUE {
            return false;
        }
        self.queue.push_back(line);
        true
    }

    /// Writes queued lines while the socket takes them; once leaving and all written, shuts
    /// the sending side.
    ///
    /// # Errors
    /// When the socket fails.
    pub fn flush(&mut self) -> io::Result<()> {
        while !self.queue.is_empty() && self.writable {
            let mut slices = [IoSlice::new(&[]); LINES_PER_WRITE];
            for (slot, (k, line)) in slices.iter_mut().zip(self.queue.iter().enumerate()) {
                let skip = if k == 0 { self.written } else { 0 };
                *slot = IoSlice::new(&line.as_bytes()[skip..]);
            }
            let count = self.queue.len().min(LINES_PER_WRITE);
            match self.stream.write_vectored(&slices[..count]) {
                Ok(0) => return Err(ErrorKind::WriteZero.into()),
                Ok(n) => self.advance(n),
                Err(e) if e.kind() == ErrorKind::WouldBlock => self.writable = false,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        if self.leaving && self.queue.is_empty() && !self.shut {
            self.shut = true;
            let _ = self.stream.shutdown(Shutdown::Write);
        }
        Ok(())
    }

    /// Drops the `n` bytes written from the front of the queue.
    fn advance(&mut self, mut n: usize) {
        while let Some(front) = self.queue.front() {
            let left = front.len() - self.written;
            if n < left {
                self.written += n;
                return;
            }
            n -= left;
            self.written = 0;
            self.queue.pop_front();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    /// A client on one end of a loopback connection, and the other end.
    fn pair() -> (Client, std::net::TcpStream) {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let far = std::net::TcpStream::connect(listener.local_addr().unwrap()).unwrap();
        let (near, peer) = listener.accept().unwrap();
        near.set_nonblocking(true).unwrap();
        let client = Client::new(
            2,
            TcpStream::from_std(near),
            peer,
            Role::Watcher,
            Instant::now(),
        );
        (client, far)
    }

    #[test]
    fn the_queue_holds_at_most_its_lines() {
        let (mut client, _far) = pair();
        for _ in 0..CLIENT_QUEUE {
            assert!(client.send(Rc::from("x\n")));
        }
        assert!(!client.send(Rc::from("x\n")));
    }

    #[test]
    fn lines_are_written_whole_and_in_order_across_partial_writes() {
        let (mut client, mut far) = pair();
        let long: String = "l".repeat(100_000) + "\n";
        let lines = ["a\n", long.as_str(), "b\n"];
        for line in lines {
            assert!(client.send(Rc::from(line)));
        }
        client.leaving = true;
        let reader = std::thread::spawn(move || {
            let mut got = String::new();
            far.read_to_string(&mut got).unwrap();
            got
        });
        while client.flush().is_ok() && !client.shut {
            client.writable = true;
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        assert_eq!(reader.join().unwrap(), lines.concat());
    }
}
