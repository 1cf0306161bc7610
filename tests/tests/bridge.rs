//! The serial bridge end to end: `device-sim` on the master side of a pseudo-terminal pair,
//! `bridge` on the slave side (through a symlink, as a phone developer would name a port), and
//! a phone app as a TCP client that streams a recorded session as JSON lines. The swing
//! reports it gets back must equal `posecoach replay` of the same log, even when the serial
//! port is pulled away in the middle of a swing and plugged back in.

use posecoach_adapters::log::LogReader;
use posecoach_cli::bridge::{serve, Counters, Policy};
use posecoach_cli::device_sim::{self, simulate, Totals};
use posecoach_cli::replay::replay;
use posecoach_core::checks::CHECKS;
use posecoach_core::events::Position;
use posecoach_core::joint::Joint;
use posecoach_core::sequence::GAPS;
use posecoach_core::wire::Message;
use serde_json::Value;
use serialport::{SerialPort, TTYPort};
use std::io::{self, BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{channel, Receiver};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

const LOG: &[u8] = include_bytes!("../logs/short_cmu_30hz.pclog");
/// Longest wait for anything the rig does; the whole session takes about a second.
const PATIENCE: Duration = Duration::from_secs(60);
/// How long to keep listening after the last expected report, for duplicates.
const AFTERWARDS: Duration = Duration::from_millis(500);
/// The symlink, in the rig's folder, that names the port the bridge opens.
const PORT: &str = "device";
/// Wire direction codes, as the wire module documents them.
const DIRECTIONS: [&str; 6] = [
    "toward_target",
    "away_from_target",
    "toward_ball",
    "away_from_ball",
    "up",
    "down",
];

/// The device's end of one plugged-in pseudo-terminal; it fails, as an unplugged cable does,
/// once the rig has plugged in another.
struct Link {
    port: TTYPort,
    plugged: Arc<AtomicUsize>,
    mine: usize,
    bytes_read: Arc<AtomicUsize>,
}

impl Link {
    fn plugged(&self) -> io::Result<()> {
        match self.plugged.load(Ordering::SeqCst) == self.mine {
            true => Ok(()),
            false => Err(io::Error::new(io::ErrorKind::BrokenPipe, "unplugged")),
        }
    }
}

impl Read for Link {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.plugged()?;
        let n = self.port.read(buf)?;
        self.bytes_read.fetch_add(n, Ordering::SeqCst);
        Ok(n)
    }
}

impl Write for Link {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.plugged()?;
        self.port.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.port.flush()
    }
}

/// A simulated device and a bridge joined by a pseudo-terminal that can be replaced.
struct Rig {
    dir: PathBuf,
    /// The master end waiting for the device to take it.
    waiting: Arc<Mutex<Option<TTYPort>>>,
    /// Slave ends, held open so that a master never sees a hang-up before the bridge opens it.
    slaves: Vec<TTYPort>,
    plugged: Arc<AtomicUsize>,
    bytes_read: Arc<AtomicUsize>,
    stop: Arc<AtomicBool>,
    device: JoinHandle<Totals>,
    bridge: JoinHandle<Counters>,
    addr: SocketAddr,
}

impl Rig {
    fn start(name: &str) -> Rig {
        let dir = std::env::temp_dir().join(format!("posecoach-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let waiting = Arc::new(Mutex::new(None));
        let plugged = Arc::new(AtomicUsize::new(0));
        let bytes_read = Arc::new(AtomicUsize::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let device = {
            let (waiting, plugged, bytes_read, stop) = (
                waiting.clone(),
                plugged.clone(),
                bytes_read.clone(),
                stop.clone(),
            );
            std::thread::spawn(move || {
                let connect = || {
                    let port = waiting.lock().unwrap().take()?;
                    Some(Link {
                        port,
                        mine: plugged.load(Ordering::SeqCst),
                        plugged: plugged.clone(),
                        bytes_read: bytes_read.clone(),
                    })
                };
                simulate(connect, &stop, None).unwrap()
            })
        };
        // The bridge finds no port at first and retries until `plug` makes one.
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        let bridge = {
            let (port, stop) = (dir.join(PORT), stop.clone());
            std::thread::spawn(move || {
                serve(&port, 0, listener, &Policy::default(), &stop).unwrap()
            })
        };
        let mut rig = Rig {
            dir,
            waiting,
            slaves: Vec::new(),
            plugged,
            bytes_read,
            stop,
            device,
            bridge,
            addr,
        };
        rig.plug();
        rig
    }

    /// Unplugs the current pseudo-terminal (if any) and plugs in a new one at the same path.
    fn plug(&mut self) {
        let (master, slave) = TTYPort::pair().unwrap();
        let staged = self.dir.join("device.new");
        std::os::unix::fs::symlink(slave.name().unwrap(), &staged).unwrap();
        std::fs::rename(&staged, self.dir.join(PORT)).unwrap();
        self.slaves.push(slave);
        self.plugged.fetch_add(1, Ordering::SeqCst);
        *self.waiting.lock().unwrap() = Some(master);
    }

    fn stop(self) -> (Totals, Counters) {
        self.stop.store(true, Ordering::SeqCst);
        let totals = self.device.join().unwrap();
        let counters = self.bridge.join().unwrap();
        let _ = std::fs::remove_dir_all(&self.dir);
        (totals, counters)
    }
}

/// A phone app: writes messages as JSON lines, reads the bridge's lines.
struct Phone {
    stream: TcpStream,
    lines: Receiver<Value>,
    /// Every line received so far.
    seen: Vec<Value>,
}

impl Phone {
    fn connect(addr: SocketAddr) -> Phone {
        let stream = TcpStream::connect(addr).unwrap();
        let (tx, lines) = channel();
        let reader = BufReader::new(stream.try_clone().unwrap());
        std::thread::spawn(move || {
            for line in reader.lines() {
                let Ok(line) = line else { return };
                let value = serde_json::from_str(&line).unwrap_or_else(|e| {
                    panic!("the bridge sent a line that is not JSON: {e}: {line}")
                });
                if tx.send(value).is_err() {
                    return;
                }
            }
        });
        Phone {
            stream,
            lines,
            seen: Vec::new(),
        }
    }

    fn send(&mut self, messages: &[Message]) {
        for m in messages {
            writeln!(self.stream, "{}", serde_json::to_string(m).unwrap()).unwrap();
        }
    }

    /// Reads lines until `done` holds for what has been seen, or `within` has passed.
    fn wait(&mut self, within: Duration, done: impl Fn(&[Value]) -> bool) -> bool {
        let end = Instant::now() + within;
        while !done(&self.seen) {
            let left = end.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) => self.seen.push(line),
                Err(_) => return false,
            }
        }
        true
    }

    /// Waits for `done`, failing the test with what was seen if it does not come.
    fn expect(&mut self, what: &str, done: impl Fn(&[Value]) -> bool) {
        assert!(
            self.wait(PATIENCE, done),
            "no {what}; the bridge sent:\n{}",
            lines(&self.seen)
        );
    }

    fn reports(&self) -> Vec<&Value> {
        reports(&self.seen)
    }
}

fn reports(seen: &[Value]) -> Vec<&Value> {
    seen.iter()
        .filter_map(|l| l["device"].get("SwingReport"))
        .collect()
}

fn bridge_events(seen: &[Value], event: &str) -> usize {
    seen.iter()
        .filter(|l| l["bridge"]["event"] == event)
        .count()
}

/// Whether the bridge announced `second` after `first`.
fn announced_after(seen: &[Value], first: &str, second: &str) -> bool {
    seen.iter()
        .skip_while(|l| l["bridge"]["event"] != first)
        .any(|l| l["bridge"]["event"] == second)
}

fn lines(seen: &[Value]) -> String {
    seen.iter().map(|l| format!("{l}\n")).collect()
}

/// Checks a wire report against `posecoach replay`'s JSON of the same swing, field by field.
fn same_report(wire: &Value, replayed: &Value) {
    let report = &replayed["report"];
    let context = format!("swing {}: wire {wire}", replayed["swing"]);
    assert_eq!(wire["swing"], replayed["swing"], "{context}");
    // The wire's score in hundredths, the JSON's to 0.1 point (each rounded once).
    let score = report["score"].as_f64().unwrap() * 100.0;
    let centi = wire["score_centi"].as_f64().unwrap();
    assert!((centi - score).abs() <= 5.0 + 1e-6, "{context}");
    for (side, key) in [
        ("student_frame", "student_positions"),
        ("coach_frame", "coach_positions"),
    ] {
        for (i, position) in Position::ALL.iter().enumerate() {
            let frame = report["positions"]
                .as_array()
                .unwrap()
                .iter()
                .find(|p| p["position"] == position.name())
                .and_then(|p| p[side].as_u64())
                .unwrap_or(u64::from(u16::MAX));
            assert_eq!(
                wire[key][i].as_u64().unwrap(),
                frame,
                "{context}: {side} {}",
                position.name()
            );
        }
    }
    // Body checks: tenths of a degree or millimetres on the wire, a tenth of a degree or of a
    // centimetre in the JSON (each rounded once, so within one unit).
    let checks = report["body_checks"].as_array().unwrap();
    let wired = wire["checks"].as_array().unwrap();
    assert_eq!(wired.len(), checks.len(), "{context}");
    for (w, c) in wired.iter().zip(checks) {
        let check = CHECKS[w["check"].as_u64().unwrap() as usize];
        assert_eq!(check.position.name(), c["position"], "{context}");
        assert_eq!(check.measure.name(), c["measure"], "{context}");
        for key in ["student", "coach", "uncertainty"] {
            let json = c[key].as_f64().unwrap() * 10.0;
            let got = w[key].as_f64().unwrap();
            assert!(
                (got - json).abs() <= 1.0,
                "{context}: {key} {got} against {json}"
            );
        }
    }
    // Gaps of the sequence: milliseconds on the wire and in the JSON (each rounded once).
    let gaps = report["kinematic_sequence"]["gaps"].as_array().unwrap();
    let wired = wire["gaps"].as_array().unwrap();
    assert_eq!(wired.len(), gaps.len(), "{context}");
    for (w, g) in wired.iter().zip(gaps) {
        let (first, then) = GAPS[w["gap"].as_u64().unwrap() as usize];
        assert_eq!(
            (first.name(), then.name()),
            (g["first"].as_str().unwrap(), g["then"].as_str().unwrap()),
            "{context}"
        );
        for key in ["student_ms", "coach_ms", "uncertainty_ms"] {
            let (got, json) = (w[key].as_f64().unwrap(), g[key].as_f64().unwrap());
            assert!(
                (got - json).abs() <= 1.0,
                "{context}: {key} {got} against {json}"
            );
        }
    }
    let phases = report["tempo"]["phases"].as_array().unwrap();
    for (i, phase) in phases.iter().enumerate() {
        for (k, side) in ["student_s", "coach_s"].iter().enumerate() {
            let ms = (phase[side].as_f64().unwrap() * 1000.0).round();
            assert_eq!(
                wire["phases_ms"][i][k].as_f64().unwrap(),
                ms,
                "{context}: {phase}"
            );
        }
    }
    let spatial = report["spatial"].as_array().unwrap();
    let deviations = wire["deviations"].as_array().unwrap();
    assert_eq!(deviations.len(), spatial.len(), "{context}");
    for (d, s) in deviations.iter().zip(spatial) {
        let event = Position::ALL[d["position"].as_u64().unwrap() as usize]
            .event()
            .unwrap();
        let joint = Joint::from_index(d["joint"].as_u64().unwrap() as usize).unwrap();
        assert_eq!(event.name(), s["event"], "{context}");
        assert_eq!(joint.name(), s["joint"], "{context}");
        assert_eq!(
            DIRECTIONS[d["direction"].as_u64().unwrap() as usize],
            s["direction"]
        );
        for (k, axis) in ["toward_target", "toward_ball", "up"].iter().enumerate() {
            let mm = (s["offset_cm"][axis].as_f64().unwrap() * 10.0).round();
            assert_eq!(d["offset_mm"][k].as_f64().unwrap(), mm, "{context}: {s}");
        }
    }
}

/// The replay's scored swings, checked to be the ones the phone got, once each and in order.
fn check_reports(phone: &Phone) {
    let replayed = replay(LOG, None).unwrap();
    let scored: Vec<&Value> = replayed
        .swings
        .iter()
        .filter(|s| s["report"].is_object())
        .collect();
    assert!(scored.len() >= 2, "the log should hold two scored swings");
    let got = phone.reports();
    assert_eq!(got.len(), scored.len(), "reports:\n{}", lines(&phone.seen));
    for (wire, replayed) in got.iter().zip(&scored) {
        same_report(wire, replayed);
    }
    let nacks = phone
        .seen
        .iter()
        .filter(|l| l["device"].get("Nack").is_some());
    assert_eq!(nacks.count(), replayed.refused.len(), "refusals");
    let sessions: Vec<&Value> = phone
        .seen
        .iter()
        .filter_map(|l| l["device"].get("SessionReport"))
        .collect();
    assert_eq!(
        sessions.len(),
        scored.len(),
        "a session report after each swing's"
    );
    same_session(sessions.last().unwrap(), &replayed.to_json()["session"]);
}

/// Checks the last session report against `posecoach replay`'s session JSON: its counts, its
/// tendencies, each phase in milliseconds and each body check in tenths of a degree or
/// millimetres (each rounded once, so within one unit).
fn same_session(wire: &Value, replayed: &Value) {
    let context = format!("wire {wire}\nreplay {replayed}");
    assert_eq!(wire["swings"], replayed["swings"], "{context}");
    assert_eq!(wire["used"], replayed["used"], "{context}");
    let advice = replayed["advice"].as_array().unwrap();
    assert_eq!(
        wire["tendencies"].as_array().unwrap().len(),
        advice.len(),
        "{context}"
    );
    let metric = |quantity: usize| {
        wire["metrics"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["quantity"] == quantity)
    };
    let close = |got: &Value, want: f64| {
        let got = got.as_f64().unwrap();
        assert!(
            (got - want).abs() <= 1.0 + 1e-6,
            "{got} against {want}: {context}"
        );
    };
    let phases = replayed["tempo"]["phases"].as_array().unwrap();
    assert!(!phases.is_empty(), "{context}");
    for (i, name) in ["backswing", "downswing", "follow_through"]
        .iter()
        .enumerate()
    {
        let Some(p) = phases.iter().find(|p| p["phase"] == *name) else {
            continue;
        };
        let m = metric(i).unwrap_or_else(|| panic!("{name}: {context}"));
        close(&m["student"], p["student_s"].as_f64().unwrap() * 1000.0);
        close(&m["coach"], p["coach_s"].as_f64().unwrap() * 1000.0);
    }
    for c in replayed["body_checks"].as_array().unwrap() {
        let i = CHECKS
            .iter()
            .position(|k| k.position.name() == c["position"] && k.measure.name() == c["measure"])
            .unwrap();
        let m = metric(4 + i).unwrap_or_else(|| panic!("{c}: {context}"));
        for key in ["student", "coach"] {
            close(&m[key], c[key].as_f64().unwrap() * 10.0);
        }
    }
}

fn messages() -> Vec<Message> {
    LogReader::new(LOG).unwrap().collect()
}

#[test]
fn the_phone_gets_the_reports_replay_gives() {
    let rig = Rig::start("bridge-relay");
    let mut phone = Phone::connect(rig.addr);
    phone.expect("hello", |seen| bridge_events(seen, "hello") == 1);
    phone.send(&messages());
    let swings = replay(LOG, None).unwrap().swings.len();
    phone.expect("reports", |seen| reports(seen).len() >= swings);
    phone.wait(AFTERWARDS, |_| false);
    check_reports(&phone);
    let (totals, counters) = rig.stop();
    assert_eq!(totals.links, 1);
    assert_eq!(counters.links, 1);
    assert_eq!(counters.bad_lines, 0);
}

#[test]
fn a_port_pulled_mid_swing_loses_and_repeats_nothing() {
    let messages = messages();
    // Unplug halfway through the second swing, at a message boundary the device has read:
    // a cable pulled while bytes are in flight loses them, which no bridge can undo.
    let sidecar: Value =
        serde_json::from_str(include_str!("../logs/short_cmu_30hz.swings.json")).unwrap();
    let second = &sidecar["swings"][1];
    let mid_us = (second["start_s"].as_f64().unwrap() + second["end_s"].as_f64().unwrap()) * 0.5e6;
    let cut = messages
        .iter()
        .position(|m| matches!(m, Message::PoseFrame(f) if f.t_us as f64 >= mid_us))
        .unwrap();
    let cut_bytes: usize = messages[..cut]
        .iter()
        .map(|m| device_sim::frame(m).unwrap().len())
        .sum();

    let mut rig = Rig::start("bridge-unplug");
    let mut phone = Phone::connect(rig.addr);
    phone.send(&messages[..cut]);
    phone.expect("first report", |seen| reports(seen).len() == 1);
    let deadline = Instant::now() + PATIENCE;
    while rig.bytes_read.load(Ordering::SeqCst) < cut_bytes {
        assert!(
            Instant::now() < deadline,
            "the device did not read what was sent"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(rig.bytes_read.load(Ordering::SeqCst), cut_bytes);

    rig.plug();
    phone.expect("serial_lost", |seen| {
        bridge_events(seen, "serial_lost") == 1
    });
    phone.send(&messages[cut..]);
    phone.expect("reconnection", |seen| {
        announced_after(seen, "serial_lost", "serial_connected")
    });
    phone.expect("second report", |seen| reports(seen).len() >= 2);
    phone.wait(AFTERWARDS, |_| false);
    check_reports(&phone);

    // A phone that connects now is told the port is there and gets what follows.
    let mut late = Phone::connect(rig.addr);
    late.expect("hello", |seen| {
        seen.first()
            .is_some_and(|l| l["bridge"]["serial"] == "connected")
    });
    let (totals, counters) = rig.stop();
    assert_eq!(totals.links, 2);
    assert_eq!(counters.links, 2);
}

#[test]
fn the_readme_examples_are_messages() {
    let readme = include_str!("../../docs/PROTOCOL.md");
    let section = &readme[readme.find("## Serial bridge").unwrap()..];
    let block = section.split("```json\n").nth(1).unwrap();
    let block = &block[..block.find("```").unwrap()];
    let lines: Vec<&str> = block.lines().collect();
    assert!(lines.len() >= 5);
    for line in lines {
        serde_json::from_str::<Message>(line)
            .unwrap_or_else(|e| panic!("README example is not a message: {e}: {line}"));
    }
}
