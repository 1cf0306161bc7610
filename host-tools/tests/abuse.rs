//! `posecoach bridge` under abuse, as its own process so that its descriptors and memory can be
//! read from `/proc`: thousands of clients that connect and leave, a thousand held sockets
//! while a phone's swing is scored, a bridge out of descriptors, a 10 MB line, binary garbage,
//! a device that floods the serial port while a client never reads. Each run ends with a
//! signal, which must stop the bridge and print its counters.
#![allow(clippy::unwrap_used, clippy::panic)] // test helpers fail the test by unwrapping

use posecoach_adapters::log::LogReader;
use posecoach_cli::bridge::{CLIENT_QUEUE, MAX_CLIENTS};
use posecoach_cli::device_sim::{frame, simulate};
use posecoach_core::wire::Message;
use serde_json::Value;
use serialport::{SerialPort, TTYPort};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpStream};
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

/// Descriptors the bridge may hold for clients with every place taken: one per client with a
/// role and one per connection pairing, and one being turned away.
const CLIENT_FDS: usize = 2 * MAX_CLIENTS as usize + 1;
/// The pairing token of the runs that need one.
const TOKEN: &str = "abuse-token";
const LOG: &[u8] = include_bytes!("../../tests/logs/short_cmu_30hz.pclog");

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
    /// Starts a bridge on a free loopback port, its serial port at `port` (which may not exist),
    /// with more flags.
    fn start(name: &str, port: Option<&Path>, flags: &[&str]) -> Bridge {
        Bridge::start_in(name, port, flags, None)
    }

    /// [`Bridge::start`], under a shell's `ulimit -n` of `descriptors` if given. The bridge
    /// picks its own port and says which on standard error, so no other socket can take it
    /// first; the rest of its log goes to this test's standard error when `ABUSE_LOG` is set,
    /// else nowhere.
    fn start_in(
        name: &str,
        port: Option<&Path>,
        flags: &[&str],
        descriptors: Option<usize>,
    ) -> Bridge {
        let dir =
            std::env::temp_dir().join(format!("posecoach-abuse-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let port = port.map_or_else(|| dir.join("absent"), Path::to_path_buf);
        let bin = env!("CARGO_BIN_EXE_posecoach");
        let mut command = match descriptors {
            Some(n) => {
                let mut sh = Command::new("sh");
                sh.args(["-c", &format!("ulimit -n {n} && exec \"$0\" \"$@\""), bin]);
                sh
            }
            None => Command::new(bin),
        };
        let mut child = command
            .args(["bridge", "--json", "--listen", "127.0.0.1:0", "--port"])
            .arg(&port)
            .args(flags)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut log = BufReader::new(child.stderr.take().unwrap());
        let addr = listening_at(&mut log);
        std::thread::spawn(move || {
            if std::env::var_os("ABUSE_LOG").is_some() {
                std::io::copy(&mut log, &mut std::io::stderr())
            } else {
                std::io::copy(&mut log, &mut std::io::sink())
            }
        });
        let probe = TcpStream::connect(addr).unwrap();
        // Leaves, and waits until the bridge has closed it: the first client is the controller.
        probe.shutdown(Shutdown::Write).unwrap();
        probe.set_read_timeout(Some(PATIENCE)).unwrap();
        let _ = (&probe).read_to_end(&mut Vec::new());
        Bridge { child, addr, dir }
    }

    /// Open descriptors and resident memory (KiB).
    fn usage(&self) -> (usize, u64) {
        usage(self.child.id())
    }

    /// Waits until the bridge's descriptors stay the same for a tenth of a second; what it
    /// holds then.
    fn quiet(&self) -> (usize, u64) {
        let start = Instant::now();
        let mut last = self.usage();
        loop {
            std::thread::sleep(Duration::from_millis(100));
            let now = self.usage();
            if now.0 == last.0 || start.elapsed() > PATIENCE {
                return now;
            }
            last = now;
        }
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

/// The address a bridge's first line of log names: "bridge: PORT <-> ADDRESS (...)".
fn listening_at(log: &mut impl BufRead) -> SocketAddr {
    let mut line = String::new();
    log.read_line(&mut line).unwrap();
    line.split(" <-> ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("no address in {line:?}"))
}

/// Open descriptors and resident memory (KiB) of process `pid`.
fn usage(pid: u32) -> (usize, u64) {
    let proc = PathBuf::from(format!("/proc/{pid}"));
    let fds = std::fs::read_dir(proc.join("fd")).unwrap().count();
    let status = std::fs::read_to_string(proc.join("status")).unwrap();
    let rss = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap();
    (fds, rss)
}

/// CPU time process `pid` has used, in clock ticks.
fn cpu_ticks(pid: u32) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap();
    // After the command's name in parentheses: state, then 10 fields, then utime and stime.
    let fields: Vec<&str> = stat[stat.rfind(')').unwrap() + 2..].split(' ').collect();
    fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap()
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

/// `n` clients that connect, read their first line (a hello, or `full` beyond the bridge's
/// places) and leave, a hundred at a time.
fn come_and_go(addr: SocketAddr, n: usize) {
    for _ in 0..n / 100 {
        let batch: Vec<_> = (0..100)
            .map(|_| TcpStream::connect(addr).unwrap())
            .collect();
        for stream in batch {
            stream.set_read_timeout(Some(PATIENCE)).unwrap();
            let mut first = String::new();
            BufReader::new(stream).read_line(&mut first).unwrap();
            assert!(first.contains("hello") || first.contains("full"), "{first}");
        }
    }
}

/// Raises this process's soft limit on open descriptors to its hard limit; the limit now.
fn raise_descriptor_limit() -> u64 {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: `limit` is a valid rlimit for the call to fill, then to read.
    unsafe {
        assert_eq!(libc::getrlimit(libc::RLIMIT_NOFILE, &mut limit), 0);
        limit.rlim_cur = limit.rlim_max;
        assert_eq!(libc::setrlimit(libc::RLIMIT_NOFILE, &limit), 0);
    }
    limit.rlim_cur
}

/// A pseudo-terminal whose master end a simulated device serves in this process, its slave
/// end named by a symlink for the bridge.
struct Device {
    dir: PathBuf,
    port: PathBuf,
    stop: Arc<AtomicBool>,
    thread: std::thread::JoinHandle<()>,
    /// Held open so that the device never sees a hang-up before the bridge opens it.
    _slave: TTYPort,
}

impl Device {
    fn start(name: &str) -> Device {
        let (master, slave) = TTYPort::pair().unwrap();
        let dir = std::env::temp_dir().join(format!(
            "posecoach-abuse-device-{name}-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let port = dir.join("device");
        std::os::unix::fs::symlink(slave.name().unwrap(), &port).unwrap();
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (stop, mut master) = (stop.clone(), Some(master));
            std::thread::spawn(move || {
                simulate(|| master.take(), &stop, None).unwrap();
            })
        };
        Device {
            dir,
            port,
            stop,
            thread,
            _slave: slave,
        }
    }

    fn stop(self) {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.join().unwrap();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// A phone paired with a bridge that needs [`TOKEN`], once it is the controller: connects
/// again while it is turned away (the places are full, or new connections pushed it out before its token
/// was read). Returns its connection and whether it saw the bridge's serial port open.
fn controller(addr: SocketAddr) -> (BufReader<TcpStream>, bool) {
    let start = Instant::now();
    loop {
        assert!(start.elapsed() < PATIENCE, "the phone never got control");
        let mut stream = TcpStream::connect(addr).unwrap();
        stream.set_read_timeout(Some(PATIENCE)).unwrap();
        if writeln!(stream, r#"{{"token": "{TOKEN}"}}"#).is_err() {
            continue;
        }
        let mut reader = BufReader::new(stream);
        let mut connected = false;
        let mut line = String::new();
        while matches!(reader.read_line(&mut line), Ok(n) if n > 0) {
            let value: Value = serde_json::from_str(&line).unwrap();
            connected |= value["bridge"]["serial"] == "connected";
            connected |= value["bridge"]["event"] == "serial_connected";
            // A client the bridge has not yet seen leave may hold control a moment longer.
            let paired = value["bridge"]["event"] == "paired";
            if (paired && value["bridge"]["role"] == "controller")
                || value["bridge"]["event"] == "control"
            {
                return (reader, connected);
            }
            if value["bridge"]["event"] == "full" {
                break;
            }
            line.clear();
        }
        std::thread::sleep(Duration::from_millis(20));
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
    let addr = listening_at(&mut stderr);
    // The bridge logs on: keep reading what it says.
    let drain = std::thread::spawn(move || std::io::copy(&mut stderr, &mut std::io::sink()));
    assert!(addr.ip().is_loopback() && addr.port() != 0, "{addr}");
    client(addr);
    stop(&mut child, "-TERM");
    drain.join().unwrap().unwrap();
}

#[test]
fn ten_thousand_clients_that_come_and_go_leave_nothing_behind() {
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let bridge = Bridge::start("cycles", None, &[]);
    come_and_go(bridge.addr, 100);
    let before = bridge.quiet();
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
    let bridge = Bridge::start("lines", None, &[]);
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
    let bridge = Bridge::start("flood", Some(&port), &["--idle-timeout", "600"]);
    // A client that came before the port was open is told so. Each client sends a blank line
    // first: silent, it would be closed within 5 s.
    let (mut reader, hello) = client(bridge.addr);
    reader.get_mut().write_all(b"\n").unwrap();
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
    let (mut idle, _) = client(bridge.addr);
    idle.get_mut().write_all(b"\n").unwrap();
    let before = bridge.usage();
    // Frames and garbage, 64 frames every 5 ms (eight times what a 115 200 baud link carries),
    // until the idle client is dropped (its descriptor closed); never more than
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
    while fds + 1 > before.0 && start.elapsed() < PATIENCE {
        std::thread::sleep(Duration::from_millis(20));
        let now = bridge.usage();
        (fds, rss) = (now.0, rss.max(now.1));
    }
    flooding.store(false, Ordering::Relaxed);
    let _master = flood.join().unwrap();
    eprintln!("a flooding device: {before:?} -> ({fds}, {rss}) (fds, peak KiB)");
    assert!(
        fds < before.0,
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

/// A bridge that needs a token, under siege: a thousand sockets held (half idle, half with
/// their sending side shut) and ten thousand that connect and leave, while a phone pairs,
/// takes control and streams a recorded session to a simulated device until a swing report
/// comes back. The bridge's descriptors stay within one per place and its memory bounded.
#[test]
fn a_phone_is_served_through_a_flood_and_a_thousand_held_sockets() {
    const HOLD: usize = 1000;
    const FLOOD: usize = 10_000;
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let limit = raise_descriptor_limit();
    let hold = if limit >= HOLD as u64 + 256 {
        HOLD
    } else {
        eprintln!("the hold of {HOLD} sockets skipped: at most {limit} descriptors here");
        0
    };
    let device = Device::start("siege");
    let bridge = Bridge::start("siege", Some(&device.port), &["--token", TOKEN]);
    let addr = bridge.addr;
    // The bridge with its port open and no client: its own descriptors.
    while !controller(addr).1 {
        std::thread::sleep(Duration::from_millis(50));
    }
    let before = bridge.quiet();

    let started = Instant::now();
    let held: Vec<TcpStream> = (0..hold)
        .map(|k| {
            let stream = TcpStream::connect(addr).unwrap();
            if k % 2 == 1 {
                stream.shutdown(Shutdown::Write).unwrap();
            }
            stream
        })
        .collect();
    let peak = Arc::new(Mutex::new(before));
    let watching = Arc::new(AtomicBool::new(true));
    let watch = {
        let (peak, watching, pid) = (peak.clone(), watching.clone(), bridge.child.id());
        std::thread::spawn(move || {
            while watching.load(Ordering::Relaxed) {
                let (fds, rss) = usage(pid);
                let mut peak = peak.lock().unwrap();
                *peak = (peak.0.max(fds), peak.1.max(rss));
                drop(peak);
                std::thread::sleep(Duration::from_millis(10));
            }
        })
    };
    let flood = std::thread::spawn(move || {
        for _ in 0..FLOOD {
            drop(TcpStream::connect(addr).unwrap());
        }
    });

    let (mut phone, _) = controller(addr);
    let mut stream = phone.get_ref().try_clone().unwrap();
    let writer = std::thread::spawn(move || {
        for message in LogReader::new(LOG).unwrap() {
            writeln!(stream, "{}", serde_json::to_string(&message).unwrap()).unwrap();
        }
        stream
    });
    let mut line = String::new();
    loop {
        line.clear();
        assert!(phone.read_line(&mut line).unwrap() > 0, "the bridge closed");
        let value: Value = serde_json::from_str(&line).unwrap();
        assert!(value["error"].is_null(), "{line}");
        if value["device"]["SwingReport"].is_object() {
            break;
        }
    }
    let scored = started.elapsed();
    flood.join().unwrap();
    let stream = writer.join().unwrap();
    watching.store(false, Ordering::Relaxed);
    watch.join().unwrap();
    let peak = *peak.lock().unwrap();
    drop(held);
    drop((phone, stream));
    let after = bridge.settle(before.0);
    eprintln!(
        "{hold} held and {FLOOD} passing sockets, a swing scored after {:.1} s: \
         {before:?} -> peak {peak:?} -> {after:?} (fds, KiB); whole run {:.1} s",
        scored.as_secs_f64(),
        started.elapsed().as_secs_f64()
    );
    assert!(
        peak.0 <= before.0 + CLIENT_FDS,
        "descriptors {before:?} -> {peak:?}"
    );
    assert!(
        peak.1 <= before.1 + GROWTH_KIB,
        "memory {before:?} -> {peak:?}"
    );
    assert!(after.0 <= before.0, "descriptors {before:?} -> {after:?}");
    let mut bridge = bridge;
    assert!(
        bridge.child.try_wait().unwrap().is_none(),
        "the bridge ended"
    );
    let counters = bridge.stop("-TERM");
    device.stop();
    let turned_away = counters["turned_away"].as_u64().unwrap();
    assert!(turned_away as usize + CLIENT_FDS >= hold, "{counters}");
    assert_eq!(counters["bad_lines"], 0, "{counters}");
}

/// A bridge allowed a dozen descriptors: accepting fails once its clients hold the rest, and
/// the bridge waits without spinning, serves the clients it has, and takes the waiting
/// connections once one leaves.
#[test]
fn a_bridge_out_of_descriptors_backs_off_and_serves_the_clients_it_has() {
    const DESCRIPTORS: usize = 12;
    const WAITING: usize = 20;
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let bridge = Bridge::start_in("starved", None, &[], Some(DESCRIPTORS));
    let (base, _) = bridge.usage();
    // Clients until the bridge can hold no more: each gets its hello.
    let clients: Vec<_> = (base..DESCRIPTORS).map(|_| client(bridge.addr).0).collect();
    let waiting: Vec<_> = (0..WAITING)
        .map(|_| TcpStream::connect(bridge.addr).unwrap())
        .collect();
    let ticks = cpu_ticks(bridge.child.id());
    std::thread::sleep(Duration::from_secs(1));
    let spent = cpu_ticks(bridge.child.id()) - ticks;
    // The clients it has are served: a line is answered.
    let mut first = clients.into_iter().next().unwrap();
    first.get_mut().write_all(b"not json\n").unwrap();
    let mut answer = String::new();
    while !answer.contains("error") {
        answer.clear();
        assert!(first.read_line(&mut answer).unwrap() > 0, "closed");
    }
    assert!(answer.contains("not a message"), "{answer}");
    // Ticks are hundredths of a second: a bridge spinning on `accept` would spend about 100.
    eprintln!("{DESCRIPTORS} descriptors, {WAITING} waiting: {spent} ticks of CPU in 1 s");
    assert!(spent < 50, "{spent} ticks");
    // One leaves: the waiting ones are taken, one by one, as places free.
    drop(first);
    let mut next = BufReader::new(waiting.into_iter().next().unwrap());
    next.get_ref().set_read_timeout(Some(PATIENCE)).unwrap();
    let mut line = String::new();
    next.read_line(&mut line).unwrap();
    assert!(line.contains("hello") || line.contains("full"), "{line}");
    let counters = bridge.stop("-TERM");
    assert!(
        counters["accept_errors"].as_u64().unwrap() > 0,
        "{counters}"
    );
}
