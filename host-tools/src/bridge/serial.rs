//! The bridge's serial side, on a thread of its own: opens the port (again, with backoff, when
//! it fails), writes the clients' frames to it and tells the event loop what the device said.

use super::Counting;
use crate::device_sim::{self, transient, Outbox};
use mio::Waker;
use posecoach_core::wire::{Decoder, MAX_FRAME};
use serde_json::{json, Value};
use std::io::Read;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender};
use std::time::Duration;

/// First wait before reopening a lost port; it doubles up to [`MAX_BACKOFF`].
const MIN_BACKOFF: Duration = Duration::from_millis(100);
/// Longest wait between attempts to reopen the port.
const MAX_BACKOFF: Duration = Duration::from_secs(2);
/// Frames taken from the queue for the link at a time.
const OUTBOX_FRAMES: usize = 64;

/// What the serial side tells the event loop: a line for every client with a role.
pub enum News {
    /// A frame from the device, as its line.
    Device(String),
    /// The port opened (`true`) or was lost, and the event line saying so.
    Link(bool, String),
}

/// The event loop, as the serial side reaches it.
pub struct Loop {
    pub news: SyncSender<News>,
    pub waker: std::sync::Arc<Waker>,
    pub counters: std::sync::Arc<Counting>,
}

impl Loop {
    /// Hands `news` to the loop (waiting while its queue is full: the loop never waits for
    /// anyone) and wakes it if there was any; `false` once the loop has ended.
    fn tell(&self, news: impl IntoIterator<Item = News>) -> bool {
        let mut told = false;
        for news in news {
            if self.news.send(news).is_err() {
                return false;
            }
            told = true;
        }
        if told {
            let _ = self.waker.wake();
        }
        true
    }

    /// Tells the clients, and the operator on stderr, that the port opened or was lost.
    fn link(&self, up: bool, event: &str, detail: Value) -> bool {
        let mut body = json!({ "event": event });
        if let (Some(body), Value::Object(more)) = (body.as_object_mut(), detail) {
            body.extend(more);
        }
        let line = json!({ "bridge": body }).to_string();
        eprintln!("bridge: {line}");
        self.tell([News::Link(up, format!("{line}\n"))])
    }
}

/// Opens the port, relays until it fails, and again, until `stop` or the loop's end.
pub fn relay(port: &Path, baud: u32, frames: &Receiver<Vec<u8>>, to: &Loop, stop: &AtomicBool) {
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
        to.counters.links.fetch_add(1, Ordering::Relaxed);
        let detail = json!({"port": port.display().to_string()});
        if !to.link(true, "serial_connected", detail) {
            return;
        }
        let mut decoder = Decoder::phone();
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
            to.counters.to_device.fetch_add(written, Ordering::Relaxed);
            match link.read(&mut buf) {
                Ok(n) => {
                    let mut lines = Vec::new();
                    decoder.push_all(&buf[..n], |m| {
                        lines.push(News::Device(format!("{}\n", json!({ "device": m }))));
                    });
                    let heard = lines.len() as u64;
                    to.counters.from_device.fetch_add(heard, Ordering::Relaxed);
                    if !to.tell(lines) {
                        return;
                    }
                }
                Err(e) if transient(&e) => {}
                Err(e) => break format!("reading: {e}"),
            }
        };
        if !to.link(false, "serial_lost", json!({ "reason": lost })) {
            return;
        }
        std::thread::sleep(backoff);
    }
}
