//! `posecoach bridge` under abuse, as its own process so that its descriptors and memory can be
//! read from `/proc`: thousands of clients that connect and leave, a 10 MB line, binary
//! garbage, a device that floods the serial port while a client never reads. Each run ends
//! with a signal, which must stop the bridge and print its counters.
#![allow(clippy::unwrap_used, clippy::panic)] // test helpers fail the test by unwrapping

use posecoach_cli::bridge::CLIENT_QUEUE;
use posecoach_cli::device_sim::frame;
use posecoach_core::wire::Message;
use serde_json::Value;
use serialport::{SerialPort, TTYPort};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Longest wait for anything the bridge does.
const PATIENCE: Duration = Duration::from_secs(30);
/// Growth of the bridge's resident memory allowed over a run, KiB: its queues are bounded
/// (4 096 frames to the device, 1 024 lines per client, one 16 KiB line per reader).
const GROWTH_KIB: u64 = 16 * 1024;

/// Between the flooding device's bursts of 64 frames.
const FLOOD_PAUSE: Duration = Duration::from_millis(5);
/// One run at a time: each measures a process, and a starved client is rightly dropped.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// A running bridge.
struct Bridge {
    child: Child,
    addr: SocketAddr,
    dir: PathBuf,
}

impl Bridge {
    /// Starts a bridge on a free loopback port, its serial port at `port` (which may not exist).
    fn start(name: &str, port: Option<&Path>) -> Bridge {
        let dir =
            std::env::temp_dir().join(format!("posecoach-abuse-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let port = port.map_or_else(|| dir.join("absent"), Path::to_path_buf);
        let addr = TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap();
        let child = Command::new(env!("CARGO_BIN_EXE_posecoach"))
            .args(["bridge", "--json", "--listen", &addr.to_string(), "--port"])
            .arg(&port)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while TcpStream::connect(addr).is_err() {
            assert!(start.elapsed() < PATIENCE, "the bridge never listened");
            std::thread::sleep(Duration::from_millis(20));
        }
        Bridge { child, addr, dir }
    }

    /// Open descriptors and resident memory (KiB).
    fn usage(&self) -> (usize, u64) {
        let proc = PathBuf::from(format!("/proc/{}", self.child.id()));
        let fds = std::fs::read_dir(proc.join("fd")).unwrap().count();
        let status = std::fs::read_to_string(proc.join("status")).unwrap();
        let rss = status
            .lines()
            .find_map(|l| l.strip_prefix("VmRSS:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
            .unwrap();
        (fds, rss)
    }

    /// Waits until the bridge holds at most `fds` descriptors; what it holds then.
    fn settle(&self, fds: usize) -> (usize, u64) {
        let start = Instant::now();
        loop {
            let now = self.usage();
            if now.0 <= fds || start.elapsed() > PATIENCE {
                return now;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Sends `signal`; the counters the bridge prints as it stops.
    fn stop(mut self, signal: &str) -> Value {
        let out = stop(&mut self.child, signal);
        let _ = std::fs::remove_dir_all(&self.dir);
        serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out:?}"))
    }
}

/// Sends `signal` to `child`, which must end; what it printed.
fn stop(child: &mut Child, signal: &str) -> String {
    let ok = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok);
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < PATIENCE, "{signal} ignored");
        std::thread::sleep(Duration::from_millis(20));
    }
    let mut out = String::new();
    child
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut out)
        .unwrap();
    out
}

/// A client and the bridge's hello to it.
fn client(addr: SocketAddr) -> (BufReader<TcpStream>, String) {
    let mut reader = BufReader::new(TcpStream::connect(addr).unwrap());
    reader.get_ref().set_read_timeout(Some(PATIENCE)).unwrap();
    let mut hello = String::new();
    reader.read_line(&mut hello).unwrap();
    assert!(hello.contains("hello"), "{hello}");
    (reader, hello)
}

/// `n` clients that connect, read their hello and leave, a hundred at a time.
fn come_and_go(addr: SocketAddr, n: usize) {
    for _ in 0..n / 100 {
        let batch: Vec<_> = (0..100)
            .map(|_| TcpStream::connect(addr).unwrap())
            .collect();
        for stream in batch {
            stream.set_read_timeout(Some(PATIENCE)).unwrap();
            let mut hello = String::new();
            BufReader::new(stream).read_line(&mut hello).unwrap();
            assert!(hello.contains("hello"), "{hello}");
        }
    }
}

/// A bridge told to listen on a host name and port 0 says on standard error where it listens,
/// and a client reaches it there.
#[test]
fn a_bridge_listens_on_a_name_and_says_where() {
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut child = Command::new(env!("CARGO_BIN_EXE_posecoach"))
        .args([
            "bridge",
            "--listen",
            "localhost:0",
            "--port",
            "/nonexistent/tty",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    // The bridge logs on: keep reading what it says.
    let drain = std::thread::spawn(move || std::io::copy(&mut stderr, &mut std::io::sink()));
    // "bridge: PORT <-> ADDRESS (one JSON message per line; ...)"
    let addr: SocketAddr = line
        .split(" <-> ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    assert!(addr.ip().is_loopback() && addr.port() != 0, "{addr}");
    client(addr);
    stop(&mut child, "-TERM");
    drain.join().unwrap().unwrap();
}

#[test]
fn ten_thousand_clients_that_come_and_go_leave_nothing_behind() {
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let bridge = Bridge::start("cycles", None);
    come_and_go(bridge.addr, 100);
    let before = bridge.settle(0);
    come_and_go(bridge.addr, 10_000);
    let after = bridge.settle(before.0);
    eprintln!("10 000 connect/close cycles: descriptors {before:?} -> {after:?} (fds, KiB)");
    assert!(after.0 <= before.0, "descriptors {before:?} -> {after:?}");
    assert!(
        after.1 <= before.1 + GROWTH_KIB,
        "memory {before:?} -> {after:?}"
    );
    let counters = bridge.stop("-TERM");
    assert_eq!(counters["bad_lines"], 0);
}

#[test]
fn a_ten_megabyte_line_and_garbage_are_answered_in_bounded_memory() {
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let bridge = Bridge::start("lines", None);
    let (mut reader, _) = client(bridge.addr);
    let before = bridge.usage();
    let mut stream = reader.get_ref().try_clone().unwrap();
    let writer = std::thread::spawn(move || {
        let chunk = vec![b'x'; 1 << 20];
        for _ in 0..10 {
            stream.write_all(&chunk).unwrap();
        }
        stream.write_all(b"\n").unwrap();
        // Binary garbage: every byte value, twenty lines of it.
        let garbage: Vec<u8> = (0..=255u8).filter(|&b| b != b'\n').collect();
        for _ in 0..20 {
            stream.write_all(&garbage).unwrap();
            stream.write_all(b"\n").unwrap();
        }
        writeln!(
            stream,
            "{}",
            serde_json::to_string(&Message::Ack { seq: 1 }).unwrap()
        )
        .unwrap();
        stream
    });
    let mut errors = Vec::new();
    for _ in 0..21 {
        let mut line = String::new();
        reader.read_line(&mut line).unwrap();
        let line: Value = serde_json::from_str(&line).unwrap();
        errors.push(line["error"].as_str().unwrap().to_string());
    }
    assert!(
        errors[0].starts_with("line 1: longer than"),
        "{}",
        errors[0]
    );
    assert!(
        errors[20].starts_with("line 21: not a message"),
        "{}",
        errors[20]
    );
    let peak = bridge.usage();
    eprintln!("10 MB line and garbage: {before:?} -> {peak:?} (fds, KiB)");
    assert!(
        peak.1 <= before.1 + GROWTH_KIB,
        "memory {before:?} -> {peak:?}"
    );
    let stream = writer.join().unwrap();
    stream.shutdown(Shutdown::Both).unwrap();
    let counters = bridge.stop("-INT");
    assert_eq!(counters["bad_lines"], 21);
}

#[test]
fn a_flooding_device_drops_the_client_that_never_reads_and_serves_the_others() {
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (mut master, slave) = TTYPort::pair().unwrap();
    let dir = std::env::temp_dir().join(format!("posecoach-abuse-pty-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let port = dir.join("device");
    let _ = std::fs::remove_file(&port);
    std::os::unix::fs::symlink(slave.name().unwrap(), &port).unwrap();
    let bridge = Bridge::start("flood", Some(&port));
    // A client that came before the port was open is told so.
    let (mut reader, hello) = client(bridge.addr);
    let mut line = hello;
    while !line.contains(r#""serial":"connected""#) && !line.contains("serial_connected") {
        line.clear();
        reader.read_line(&mut line).unwrap();
    }
    // Frames the reading client has received: the flood waits for it, so that it is never
    // dropped for being starved of CPU on a loaded machine, while the idle client falls behind.
    let received = Arc::new(AtomicU64::new(0));
    let reading = {
        let received = received.clone();
        std::thread::spawn(move || {
            for line in reader.lines() {
                if line.unwrap().contains("\"device\"") {
                    received.fetch_add(1, Ordering::Relaxed);
                }
            }
            received.load(Ordering::Relaxed)
        })
    };
    let (idle, _) = client(bridge.addr);
    let before = bridge.usage();
    // Frames and garbage, 64 frames every 5 ms (eight times what a 115 200 baud link carries),
    // until the idle client is dropped (its three descriptors closed); never more than
    // `AHEAD` frames ahead of the reading client.
    const BURST: u64 = 64;
    const AHEAD: u64 = CLIENT_QUEUE as u64 / 2;
    let frames: Vec<u8> = (0..BURST as u32)
        .flat_map(|seq| frame(&Message::Ack { seq }).unwrap())
        .chain([0xFF; 64])
        .chain([0])
        .collect();
    let flooding = Arc::new(AtomicBool::new(true));
    let flood = {
        let (flooding, received) = (flooding.clone(), received.clone());
        std::thread::spawn(move || {
            let mut sent = 0u64;
            while flooding.load(Ordering::Relaxed) {
                if sent < received.load(Ordering::Relaxed) + AHEAD {
                    master.write_all(&frames).unwrap();
                    sent += BURST;
                }
                std::thread::sleep(FLOOD_PAUSE);
            }
            master
        })
    };
    let start = Instant::now();
    let (mut fds, mut rss) = before;
    while fds + 3 > before.0 && start.elapsed() < PATIENCE {
        std::thread::sleep(Duration::from_millis(20));
        let now = bridge.usage();
        (fds, rss) = (now.0, rss.max(now.1));
    }
    flooding.store(false, Ordering::Relaxed);
    let _master = flood.join().unwrap();
    eprintln!("a flooding device: {before:?} -> ({fds}, {rss}) (fds, peak KiB)");
    assert!(
        fds + 3 <= before.0,
        "the idle client was never dropped: {before:?} -> {fds}"
    );
    assert!(rss <= before.1 + GROWTH_KIB, "memory {before:?} -> {rss}");
    drop(idle);
    drop(slave);
    let counters = bridge.stop("-INT");
    let got = reading.join().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(counters["slow_clients"], 1, "{counters}");
    assert!(got > 1024, "{got} frames");
    assert!(
        counters["from_device"].as_u64().unwrap() >= got,
        "{counters}"
    );
}

#[test]
fn device_sim_stops_on_sigterm_without_a_port() {
    let dir = std::env::temp_dir().join(format!("posecoach-abuse-sim-{}", std::process::id()));
    let mut child = Command::new(env!("CARGO_BIN_EXE_posecoach"))
        .args(["device-sim", "--json", "--port"])
        .arg(dir.join("absent"))
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let totals: Value = serde_json::from_str(&stop(&mut child, "-TERM")).unwrap();
    assert_eq!(totals["links"], 0);
}
