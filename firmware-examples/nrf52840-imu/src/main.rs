//! posecoach on a Seeed XIAO nRF52840 Sense: the wearable's hub.
//!
//! Its own LSM6DS3TR-C (I²C, through `embedded-hal`) is one sensor of the layout; the other
//! sensors' samples, the student's profile, the sensor layout, settings and coach selection
//! arrive from the phone over the UART as wire frames. Everything goes into the device's
//! [`Session`] with the bundled coach references; each reply (a `SwingReport` and the range
//! session's `SessionReport` per scored swing, an `Ack` per set-up taken, a `Nack` per refused
//! message) goes back over the UART.
//!
//! Pins are the XIAO nRF52840 Sense's (check them against your board's schematic): IMU power
//! P1.08, IMU SCL P0.27, SDA P0.07; UART TX P1.11 (D6), RX P1.12 (D7), 115 200 baud.
#![no_std]
#![no_main]

use cortex_m as _;
use cortex_m_rt::entry;
use defmt_rtt as _;
use nrf52840_hal::gpio::{p0, p1, Level};
use nrf52840_hal::pac::{self, TIMER1};
use nrf52840_hal::timer::Periodic;
use nrf52840_hal::twim::{self, Twim};
use nrf52840_hal::uarte::{self, Baudrate, Parity, Uarte};
use nrf52840_hal::Timer;
use panic_probe as _;
use posecoach_adapters::lsm6ds3::{Lsm6ds3, ADDRESS};
use posecoach_adapters::session::{BufferLens, Buffers, Coach, Session, DEFAULT_CONFIG};
use posecoach_core::blob::Aligned;
use posecoach_core::frames::Mm;
use posecoach_core::reference::{self, Reference};
use posecoach_core::session::JointTallies;
use posecoach_core::wire::{encode, Config, Decoder, Message, MAX_FRAME};
use static_cell::ConstStaticCell;

const DRIVER: &Aligned<[u8]> = &Aligned(*include_bytes!("../../../coaches/driver.pcr"));
const IRON: &Aligned<[u8]> = &Aligned(*include_bytes!("../../../coaches/iron.pcr"));
static COACHES: [&Aligned<[u8]>; 2] = [DRIVER, IRON];

/// This board's sensor number in the layout the phone sends (the lead wrist's, by convention).
const SENSOR: u8 = 5;
/// Most joints of a student (H36M-17 keypoints).
const STUDENT_JOINTS: usize = 17;
/// The model rate this board has buffers for (a phone asking for more gets a `Nack`), Hz.
const MODEL_RATE_HZ: u16 = 30;
/// Frames of the longest bundled coach reference at the model rate, read from the references.
const COACH_FRAMES: usize = reference::frames_at(&[&DRIVER.0, &IRON.0], MODEL_RATE_HZ as f32);
const LENS: BufferLens = BufferLens::new(STUDENT_JOINTS, COACH_FRAMES, MODEL_RATE_HZ);
/// Microseconds a UART read waits for a byte before the loop polls the IMU again.
const UART_WAIT_US: u32 = 200;

static RING: ConstStaticCell<[Mm; LENS.ring]> = ConstStaticCell::new([[0; 3]; LENS.ring]);
static VIRTUAL_COACH: ConstStaticCell<[Mm; LENS.coach]> =
    ConstStaticCell::new([[0; 3]; LENS.coach]);
static FLOATS: ConstStaticCell<[f32; LENS.floats]> = ConstStaticCell::new([0.0; LENS.floats]);
static BYTES: ConstStaticCell<[u8; LENS.bytes]> = ConstStaticCell::new([0; LENS.bytes]);
static UNSURE: ConstStaticCell<[u64; LENS.unsure]> = ConstStaticCell::new([0; LENS.unsure]);
static TALLIES: ConstStaticCell<[JointTallies; LENS.tallies]> =
    ConstStaticCell::new([JointTallies::EMPTY; LENS.tallies]);

/// A microsecond clock from a free-running 32-bit timer, extended to 64 bits.
struct Clock {
    timer: Timer<TIMER1, Periodic>,
    high: u64,
    last: u32,
}

impl Clock {
    fn now_us(&mut self) -> u64 {
        let low = self.timer.read();
        if low < self.last {
            self.high += 1 << 32;
        }
        self.last = low;
        self.high | u64::from(low)
    }
}

#[entry]
fn main() -> ! {
    let Some(p) = pac::Peripherals::take() else {
        defmt::panic!("peripherals taken twice");
    };
    let (port0, port1) = (p0::Parts::new(p.P0), p1::Parts::new(p.P1));
    let _imu_power = port1.p1_08.into_push_pull_output(Level::High);
    let i2c = Twim::new(
        p.TWIM0,
        twim::Pins {
            scl: port0.p0_27.into_floating_input().degrade(),
            sda: port0.p0_07.into_floating_input().degrade(),
        },
        twim::Frequency::K400,
    );
    let mut uart = Uarte::new(
        p.UARTE0,
        uarte::Pins {
            txd: port1.p1_11.into_push_pull_output(Level::High).degrade(),
            rxd: port1.p1_12.into_floating_input().degrade(),
            cts: None,
            rts: None,
        },
        Parity::EXCLUDED,
        Baudrate::BAUD115200,
    );
    let mut clock = Clock {
        timer: {
            let mut t = Timer::periodic(p.TIMER1);
            t.start(u32::MAX);
            t
        },
        high: 0,
        last: 0,
    };
    let mut wait = Timer::new(p.TIMER2);
    let mut imu = match Lsm6ds3::start(i2c, ADDRESS, SENSOR) {
        Ok(imu) => imu,
        Err(e) => defmt::panic!("IMU: {}", defmt::Debug2Format(&e)),
    };

    let mut references = [None, None];
    for (slot, blob) in references.iter_mut().zip(COACHES) {
        match Reference::from_bytes(&blob.0) {
            Ok(r) => *slot = Some(r),
            Err(e) => defmt::panic!("coach reference: {}", e),
        }
    }
    let [Some(driver), Some(iron)] = references else {
        defmt::panic!("a coach reference is missing");
    };
    let coaches = [Coach::from(&driver), Coach::from(&iron)];
    let buffers = Buffers {
        ring: RING.take(),
        coach: VIRTUAL_COACH.take(),
        floats: FLOATS.take(),
        bytes: BYTES.take(),
        unsure: UNSURE.take(),
        tallies: TALLIES.take(),
    };
    let own = Config {
        model_rate_hz: MODEL_RATE_HZ,
        ..DEFAULT_CONFIG
    };
    let Ok(mut session) = Session::with_config(&coaches, buffers, own) else {
        defmt::panic!("the device's own settings are not valid");
    };
    let mut decoder = Decoder::new();
    let mut byte = [0u8; 1];
    defmt::info!("posecoach ready: IMU is sensor {}", SENSOR);
    loop {
        if uart
            .read_timeout(&mut byte, &mut wait, UART_WAIT_US)
            .is_ok()
        {
            decoder.push(byte[0], |message| handle(&mut session, &mut uart, message));
            // A frame of another protocol version is told so.
            if let Some(nack) = decoder.reply() {
                send(&mut uart, &nack);
            }
        }
        match imu.sample(clock.now_us()) {
            Ok(Some(sample)) => handle(&mut session, &mut uart, &Message::ImuSample(sample)),
            Ok(None) => {}
            Err(e) => defmt::warn!("IMU read: {}", defmt::Debug2Format(&e)),
        }
    }
}

/// Hands `message` to the session and sends its replies.
fn handle(session: &mut Session<'_>, uart: &mut Uarte<pac::UARTE0>, message: &Message) {
    session.handle(message, |outcome| {
        let Some(reply) = outcome.reply(message) else {
            return;
        };
        if let Message::SwingReport(report) = &reply {
            defmt::info!(
                "swing {} scored {}/100",
                report.swing,
                report.score_centi / 100
            );
        }
        send(uart, &reply);
    });
}

/// Frames `message` and writes it to the phone.
fn send(uart: &mut Uarte<pac::UARTE0>, message: &Message) {
    let mut frame = [0u8; MAX_FRAME];
    match encode(message, &mut frame) {
        Ok(n) => {
            if uart.write(&frame[..n]).is_err() {
                defmt::warn!("UART write failed");
            }
        }
        Err(e) => defmt::warn!("reply not encoded: {}", e),
    }
}
