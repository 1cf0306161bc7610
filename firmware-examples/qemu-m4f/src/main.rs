//! posecoach's device pipeline on a Cortex-M4F (QEMU `mps2-an386`).
//!
//! Replays the recorded session `tests/logs/device_h36m_30hz.pclog` (embedded; a 30 Hz model
//! rate) through the device's session with the bundled coach references (embedded `.pcr`
//! blobs): decode → pose stream → swing detection → retarget (the analytic retargeter, once
//! per student and coach, then golf's contacts) → events → DTW → report. Every reply the
//! device would send is encoded as on the serial link and compared with the host's
//! (`posecoach replay --wire`, committed as `device_h36m_30hz.device.bin`). Then, in a fresh
//! session, the hostile recording `tests/logs/hostile_h36m_30hz.pclog` (the same session with
//! bursts of what a broken or hostile phone sends, and IMU clocks that leap, restart and
//! wrap), its replies compared the same way, and no message of either allowed more than
//! [`MESSAGE_BUDGET`] instructions. Then (without the network) six IMUs at 200 Hz,
//! `tests/logs/imu_device_200hz.pclog`: a still T-pose and a driver swing, its replies compared
//! the same way. Prints each swing's score (its report is compared bit for bit), the instructions each stage took and what each stream
//! costs a second of wearing it (the battery: every message of the stream that does not end a
//! swing, decoding included, over the stream's own time) over defmt; exits 0 only if every bit
//! matched and every message kept to the budget.
//!
//! With the `network` feature the session retargets with the int8 network instead
//! (`weights/distilled-int8.pcw`, embedded), checked first against its golden vectors bit for
//! bit and its kernels and one 64-frame window counted; the replies are then compared with
//! `posecoach replay --weights … --wire` (`device_h36m_30hz.int8.device.bin`).
#![no_std]
#![no_main]

mod count;
mod dtw;
#[cfg(feature = "network")]
mod kernels;
#[cfg(feature = "network")]
mod network;
mod stack;

use cortex_m as _;
use cortex_m_rt::entry;
use count::Tally;
use defmt_semihosting as _;
use posecoach_adapters::log::LogReader;
use posecoach_adapters::session::{BufferLens, Buffers, Coach, Outcome, Session, DEFAULT_CONFIG};
use posecoach_core::blob::Aligned;
use posecoach_core::frames::Mm;
use posecoach_core::reference::{self, Reference};
use posecoach_core::session::JointTallies;
use posecoach_core::weights::Weights;
#[cfg(feature = "network")]
use posecoach_core::weights::{Architecture, SEGMENTS, WINDOW};
use posecoach_core::wire::{self, encode, Config, Message, MAX_FRAME};
use static_cell::ConstStaticCell;

static LOG: &Aligned<[u8]> = &Aligned(*include_bytes!(
    "../../../tests/logs/device_h36m_30hz.pclog"
));
#[cfg(not(feature = "network"))]
static EXPECTED: &[u8] = include_bytes!("../../../tests/logs/device_h36m_30hz.device.bin");
#[cfg(feature = "network")]
static EXPECTED: &[u8] = include_bytes!("../../../tests/logs/device_h36m_30hz.int8.device.bin");
static HOSTILE: &Aligned<[u8]> = &Aligned(*include_bytes!(
    "../../../tests/logs/hostile_h36m_30hz.pclog"
));
#[cfg(not(feature = "network"))]
static HOSTILE_EXPECTED: &[u8] = include_bytes!("../../../tests/logs/hostile_h36m_30hz.device.bin");
#[cfg(feature = "network")]
static HOSTILE_EXPECTED: &[u8] =
    include_bytes!("../../../tests/logs/hostile_h36m_30hz.int8.device.bin");
#[cfg(not(feature = "network"))]
static IMU: &Aligned<[u8]> = &Aligned(*include_bytes!("../../../tests/logs/imu_device_200hz.pclog"));
#[cfg(not(feature = "network"))]
static IMU_EXPECTED: &[u8] = include_bytes!("../../../tests/logs/imu_device_200hz.device.bin");
/// The IMU recording replayed, with its transcript (none with the network: its int8 coach
/// changes nothing the stream costs).
#[cfg(not(feature = "network"))]
static IMU_RECORDING: Option<(&[u8], &[u8])> = Some((&IMU.0, IMU_EXPECTED));
#[cfg(feature = "network")]
static IMU_RECORDING: Option<(&[u8], &[u8])> = None;
const DRIVER: &Aligned<[u8]> = &Aligned(*include_bytes!("../../../coaches/driver.pcr"));
const IRON: &Aligned<[u8]> = &Aligned(*include_bytes!("../../../coaches/iron.pcr"));
static COACHES: [&Aligned<[u8]>; 2] = [DRIVER, IRON];

/// Joints of the log's student (H3.6M-17 keypoints).
const STUDENT_JOINTS: usize = 17;
/// The model rate the log's `Config` asks for, Hz.
const MODEL_RATE_HZ: u16 = 30;
/// Frames of the longest bundled coach reference at the model rate, read from the references.
const COACH_FRAMES: usize = reference::frames_at(&[&DRIVER.0, &IRON.0], MODEL_RATE_HZ as f32);
/// Joints of the bundled coaches (the canonical 22): the network's input.
#[cfg(feature = "network")]
const COACH_JOINTS: usize = 22;
/// Most instructions one message may take, whatever it holds: a quarter of a second of a
/// 64 MHz Cortex-M4F (the nRF52840's clock) at an instruction a cycle, the longest a phone
/// waits for a reply. The costliest message a phone can send is a set-up (a profile, coach
/// selection or sensor layout: the coach retargeted, about 4 M; 11 M by the network).
const MESSAGE_BUDGET: u64 = 16_000_000;
/// The embedded network's sizes (checked against its header at start).
#[cfg(feature = "network")]
const NETWORK: Architecture = Architecture {
    features: 16,
    heads: 2,
    kernel: 3,
    window: WINDOW as u16,
    segments: SEGMENTS as u16,
    rate_hz: 30.0,
};
#[cfg(not(feature = "network"))]
const LENS: BufferLens = BufferLens::new(STUDENT_JOINTS, COACH_FRAMES, MODEL_RATE_HZ);
#[cfg(feature = "network")]
const LENS: BufferLens = BufferLens::new(STUDENT_JOINTS, COACH_FRAMES, MODEL_RATE_HZ).with_network(
    &NETWORK,
    STUDENT_JOINTS,
    COACH_JOINTS,
    COACH_FRAMES,
);

static RING: ConstStaticCell<[Mm; LENS.ring]> = ConstStaticCell::new([[0; 3]; LENS.ring]);
static VIRTUAL_COACH: ConstStaticCell<[Mm; LENS.coach]> =
    ConstStaticCell::new([[0; 3]; LENS.coach]);
static FLOATS: ConstStaticCell<[f32; LENS.floats]> = ConstStaticCell::new([0.0; LENS.floats]);
static BYTES: ConstStaticCell<[u8; LENS.bytes]> = ConstStaticCell::new([0; LENS.bytes]);
static UNSURE: ConstStaticCell<[u64; LENS.unsure]> = ConstStaticCell::new([0; LENS.unsure]);
static TALLIES: ConstStaticCell<[JointTallies; LENS.tallies]> =
    ConstStaticCell::new([JointTallies::EMPTY; LENS.tallies]);

/// Instructions per kind of work.
#[derive(Default)]
struct Stages {
    /// Reading one message from the log's bytes (COBS, CRC, postcard).
    decode: Tally,
    /// A pose frame that did not end a swing: pose stream, skeleton fit, detector.
    frame: Tally,
    /// A pose frame or IMU sample that ended a swing: the above, the copy out, events, DTW,
    /// report.
    swing: Tally,
    /// An IMU sample that did not end a swing: the adapter, and detection of the frames it
    /// completes.
    imu: Tally,
    /// A profile, settings, coach selection or sensor layout: the coach retargeted onto the
    /// student, its events; or a refusal.
    setup: Tally,
    /// Encoding a reply for the serial link.
    reply: Tally,
    /// Decoding the pose frames and IMU samples, instructions.
    stream_decode: u64,
    /// The first and last capture time of a pose frame or IMU sample, microseconds.
    stream_us: Option<(u64, u64)>,
}

#[entry]
fn main() -> ! {
    let core = cortex_m::Peripherals::take();
    let status = match core {
        Some(core) => {
            count::start(core.SYST);
            run()
        }
        None => Err("core peripherals taken twice"),
    };
    match status {
        Ok(()) => {
            defmt::println!("PASS: every reply equals the host's");
            semihosting::process::exit(0)
        }
        Err(why) => {
            defmt::println!("FAIL: {}", why);
            semihosting::process::exit(1)
        }
    }
}

fn run() -> Result<(), &'static str> {
    count::check()?;
    let compared = dtw::check_rooted_distances()?;
    defmt::println!(
        "KERNEL rooted distances: {=usize} costs of 1 to 17 joints equal to the compiled sum",
        compared
    );
    let (per_cell, cells) = dtw::per_cell_centi()?;
    defmt::println!(
        "KERNEL DTW cell ({=usize} cells): {=u64}.{=u64:02} instructions per cell",
        cells,
        per_cell / 100,
        per_cell % 100
    );
    let mut references = [None, None];
    for (slot, blob) in references.iter_mut().zip(COACHES) {
        *slot = Some(Reference::from_bytes(&blob.0).map_err(|_| "a coach reference is damaged")?);
    }
    let [Some(driver), Some(iron)] = references else {
        return Err("a coach reference is missing");
    };
    let coaches = [Coach::from(&driver), Coach::from(&iron)];
    let (ring, coach) = (RING.take(), VIRTUAL_COACH.take());
    #[cfg(feature = "network")]
    let weights = Some(network::checked(ring)?);
    #[cfg(not(feature = "network"))]
    let weights: Option<Weights<'_>> = None;
    let weights = weights.as_ref();
    // The benchmarks' (and the network's checks') depth: nothing has repainted the stack since
    // reset; the replays measure each message's from a freshly painted stack.
    let checks_stack = stack::high_water();
    let (floats, bytes, unsure) = (FLOATS.take(), BYTES.take(), UNSURE.take());
    let tallies = TALLIES.take();
    // Every recording through one call of the replay.
    let mut replayed: [Option<Replayed>; 3] = [None, None, None];
    let recordings = [
        Some((&LOG.0[..], EXPECTED)),
        Some((&HOSTILE.0[..], HOSTILE_EXPECTED)),
        IMU_RECORDING,
    ];
    for (slot, (log, expected)) in replayed
        .iter_mut()
        .zip(recordings)
        .filter_map(|(slot, r)| Some((slot, r?)))
    {
        let buffers = Buffers {
            ring: &mut *ring,
            coach: &mut *coach,
            floats: &mut *floats,
            bytes: &mut *bytes,
            unsure: &mut *unsure,
            tallies: &mut *tallies,
        };
        *slot = Some(replay(&coaches, weights, buffers, log, expected)?);
    }
    let [Some(clean), Some(hostile), imu] = replayed else {
        return Err("a recording was not replayed");
    };
    let imu_deepest = imu.as_ref().map_or(0, |r| r.stages.deepest());
    print("STAGE", &clean.stages);
    defmt::println!(
        "RAM ring {=usize} coach {=usize} floats {=usize} bytes {=usize} unsure {=usize} tallies {=usize} stack {=usize}",
        LENS.ring * core::mem::size_of::<Mm>(),
        LENS.coach * core::mem::size_of::<Mm>(),
        LENS.floats * core::mem::size_of::<f32>(),
        LENS.bytes,
        LENS.unsure * core::mem::size_of::<u64>(),
        LENS.tallies * core::mem::size_of::<JointTallies>(),
        checks_stack.max(clean.stages.deepest()).max(imu_deepest)
    );
    print("HOSTILE", &hostile.stages);
    // How deep the hostile recording took the stack (the clean session's depth is above).
    defmt::println!("STACK hostile recording {=usize}", hostile.stages.deepest());
    if let Some(imu) = &imu {
        print("IMU", &imu.stages);
    }
    defmt::println!(
        "BATTERY pose per_second {=u64} imu per_second {=u64} instructions",
        clean.stages.per_second(),
        imu.as_ref().map_or(0, |r| r.stages.per_second())
    );
    #[cfg(feature = "network")]
    let (vectors, weights) = (network::golden_bytes(), network::WEIGHTS.0.len());
    #[cfg(not(feature = "network"))]
    let (vectors, weights) = (dtw::SWING.0.len(), 0);
    defmt::println!(
        "EMBEDDED log {=usize} transcript {=usize} vectors {=usize} weights {=usize} hostile {=usize} imu {=usize}",
        LOG.0.len(),
        EXPECTED.len(),
        vectors,
        weights,
        HOSTILE.0.len() + HOSTILE_EXPECTED.len(),
        IMU_RECORDING.map_or(0, |(log, expected)| log.len() + expected.len())
    );
    let costliest = clean
        .stages
        .costliest()
        .max(hostile.stages.costliest())
        .max(imu.as_ref().map_or(0, |r| r.stages.costliest()));
    defmt::println!(
        "BUDGET costliest message {=u64} budget {=u64}",
        costliest,
        MESSAGE_BUDGET
    );
    if !clean.matched {
        return Err("a reply differs from the host's");
    }
    if !hostile.matched {
        return Err("a reply to the hostile recording differs from the host's");
    }
    if imu.is_some_and(|r| !r.matched) {
        return Err("a reply to the IMU recording differs from the host's");
    }
    if costliest > MESSAGE_BUDGET {
        return Err("a message took more instructions than the budget");
    }
    Ok(())
}

/// What a replay measured, and whether every reply equalled the host's.
struct Replayed {
    stages: Stages,
    matched: bool,
}

/// Replays `log` through a fresh session on `buffers`, comparing every reply with the host's
/// frames in `expected`.
///
/// Out of line, called once for both recordings (from one loop). Inlined it measured 0.5 KiB
/// less peak stack but 1.8 KiB more flash, which the flash budget could not take (2026-12-07);
/// inlined into two calls the two sessions' frames stopped sharing their slots once the session
/// kept its range session (39.3 KiB of stack). The benchmarks and the golden check before it are
/// kept out of line: inlined into `run`, their arrays (12 KiB for the convolution's) stayed in
/// its frame through both replays.
#[inline(never)]
#[cfg_attr(not(feature = "network"), allow(unused_variables))]
fn replay(
    coaches: &[Coach<'_>],
    weights: Option<&Weights<'_>>,
    buffers: Buffers<'_>,
    log: &[u8],
    mut expected: &[u8],
) -> Result<Replayed, &'static str> {
    let own = Config {
        model_rate_hz: MODEL_RATE_HZ,
        ..DEFAULT_CONFIG
    };
    let mut session =
        Session::with_config(coaches, buffers, own).map_err(|_| "the device's own settings")?;
    #[cfg(feature = "network")]
    if let Some(w) = weights {
        session = session.with_network(w);
    }
    let mut reader = LogReader::new(log).map_err(|_| "an embedded log is not a log")?;
    let mut stages = Stages::default();
    let mut mismatch = false;
    // The harness's own frames (this replay's session, reader and expected replies among
    // them), which every message's stack figure includes.
    defmt::println!(
        "BASE stack {=usize} session {=usize}",
        stack::in_use(),
        core::mem::size_of_val(&session)
    );
    // Each message is handled where the decoder lends it, as on a device
    // ([`LogReader::read`]): its stack figures include the decoder's frames.
    loop {
        stack::repaint();
        let start = count::now();
        let more = reader.read(|message| {
            let decoded = count::now() - start;
            stages.decode.add(decoded);
            if let Message::PoseFrame(wire::PoseFrame { t_us, .. })
            | Message::ImuSample(wire::ImuSample { t_us, .. }) = message
            {
                stages.stream_decode += decoded;
                let (first, _) = stages.stream_us.get_or_insert((*t_us, *t_us));
                stages.stream_us = Some((*first, *t_us));
            }
            stages.decode.reached(stack::high_water());
            stack::repaint();
            let mut scored = false;
            let start = count::now();
            session.handle(message, |outcome| {
                let at = count::now();
                scored |= matches!(outcome, Outcome::Scored { .. });
                match &outcome {
                    Outcome::Scored { report, .. } => {
                        defmt::println!("swing scored: {}", report.score)
                    }
                    Outcome::Unscored { swing, error } => {
                        defmt::println!("swing {} not scored: {}", swing.number, error)
                    }
                    Outcome::Refused(why) => defmt::println!("refused: {}", why),
                    Outcome::Accepted | Outcome::Session { .. } => {}
                }
                if let Some(reply) = outcome.reply(message) {
                    let mut frame = [0u8; MAX_FRAME];
                    match encode(&reply, &mut frame) {
                        Ok(n) if expected.starts_with(&frame[..n]) => expected = &expected[n..],
                        _ => mismatch = true,
                    }
                }
                stages.reply.add(count::now() - at);
            });
            let spent = count::now() - start;
            let stage = match message {
                Message::PoseFrame(_) | Message::ImuSample(_) if scored => &mut stages.swing,
                Message::PoseFrame(_) => &mut stages.frame,
                Message::ImuSample(_) => &mut stages.imu,
                _ => &mut stages.setup,
            };
            stage.add(spent);
            stage.reached(stack::high_water());
        });
        if !more {
            break;
        }
    }
    Ok(Replayed {
        stages,
        matched: !mismatch && expected.is_empty(),
    })
}

impl Stages {
    /// Instructions of the costliest message handled (decoding excluded).
    fn costliest(&self) -> u64 {
        [&self.frame, &self.swing, &self.imu, &self.setup]
            .iter()
            .map(|t| t.max)
            .max()
            .unwrap_or(0)
    }
}

impl Stages {
    /// Instructions a second of the stream takes: decoding and handling every pose frame and
    /// IMU sample that did not end a swing, over the time from the first to the last.
    fn per_second(&self) -> u64 {
        let span_us = self.stream_us.map_or(0, |(first, last)| last.saturating_sub(first));
        let spent = self.stream_decode + self.frame.total + self.imu.total;
        // Under 2^44 instructions for a recording (hours of QEMU time): no overflow.
        spent.saturating_mul(1_000_000) / span_us.max(1)
    }

    /// Bytes of stack the deepest message reached, its decoding and reply included.
    fn deepest(&self) -> usize {
        [
            &self.decode,
            &self.frame,
            &self.swing,
            &self.imu,
            &self.setup,
        ]
        .iter()
        .map(|t| t.stack)
        .max()
        .unwrap_or(0)
    }
}

/// One line per stage, each starting with `tag`.
fn print(tag: &str, stages: &Stages) {
    for (name, tally) in [
        ("decode", &stages.decode),
        ("frame", &stages.frame),
        ("swing", &stages.swing),
        ("imu", &stages.imu),
        ("setup", &stages.setup),
        ("reply", &stages.reply),
    ] {
        defmt::println!(
            "{=str} {=str} calls {=u32} mean {=u64} max {=u64} total {=u64} stack {=usize}",
            tag,
            name,
            tally.calls,
            tally.mean(),
            tally.max,
            tally.total,
            tally.stack
        );
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    defmt::println!("FAIL: panicked");
    semihosting::process::exit(101)
}
