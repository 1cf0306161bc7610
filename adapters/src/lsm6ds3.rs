//! The ST LSM6DS3 / LSM6DS3TR-C accelerometer and gyroscope over I²C (any `embedded-hal` 1.0
//! bus), read into wire [`ImuSample`]s: the inertial unit of boards such as the Seeed XIAO
//! nRF52840 Sense.
//!
//! [`Lsm6ds3::start`] checks the chip's identity and sets both sensors to 208 Hz with the
//! widest ranges a golf swing needs (±16 g, ±2000 °/s); [`Lsm6ds3::sample`] returns a sample
//! once both have new data, an axis at full scale sent as the `i16` extreme (saturated, in the
//! wire's words).

use embedded_hal::i2c::I2c;
use posecoach_core::wire::ImuSample;

/// I²C address with SA0 low (the XIAO nRF52840 Sense wires it so); `0x6B` with SA0 high.
pub const ADDRESS: u8 = 0x6A;
/// Output data rate of both sensors, Hz.
pub const RATE_HZ: u16 = 208;

const WHO_AM_I: u8 = 0x0F;
/// WHO_AM_I of the LSM6DS3 and of the LSM6DS3TR-C.
const IDENTITIES: [u8; 2] = [0x69, 0x6A];
const CTRL1_XL: u8 = 0x10;
const CTRL2_G: u8 = 0x11;
const CTRL3_C: u8 = 0x12;
const STATUS: u8 = 0x1E;
/// First of the twelve output bytes: gyroscope X, Y, Z, then accelerometer X, Y, Z, each
/// little-endian.
const OUTX_L_G: u8 = 0x22;
/// 208 Hz (0101), ±16 g (01), default filter.
const ACCEL_208HZ_16G: u8 = 0b0101_0100;
/// 208 Hz (0101), ±2000 °/s (11).
const GYRO_208HZ_2000DPS: u8 = 0b0101_1100;
/// Block data update (outputs change only after both bytes are read), register address
/// auto-increment.
const BDU_IF_INC: u8 = 0b0100_0100;
/// STATUS bits: new accelerometer data, new gyroscope data.
const DATA_READY: u8 = 0b0000_0011;
/// Sensitivity at ±16 g: 0.488 mg per count, as a ratio.
const MG_PER_COUNT: (i32, i32) = (488, 1000);
/// Sensitivity at ±2000 °/s: 70 m°/s per count = 0.7 tenths of a degree per second.
const DDPS_PER_COUNT: (i32, i32) = (7, 10);

/// Why the sensor could not be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Lsm6ds3Error<E> {
    /// The bus failed.
    Bus(E),
    /// Another chip answered at the address (its WHO_AM_I).
    Identity(u8),
}

impl<E> From<E> for Lsm6ds3Error<E> {
    fn from(e: E) -> Self {
        Lsm6ds3Error::Bus(e)
    }
}

/// The sensor on its bus.
#[derive(Debug)]
pub struct Lsm6ds3<B> {
    bus: B,
    address: u8,
    /// The number its samples carry ([`ImuSample::sensor`]).
    sensor: u8,
}

impl<B: I2c> Lsm6ds3<B> {
    /// Checks the chip at `address` and starts both sensors; its samples carry `sensor`.
    ///
    /// # Errors
    /// [`Lsm6ds3Error::Bus`] if the bus fails, [`Lsm6ds3Error::Identity`] for another chip.
    pub fn start(mut bus: B, address: u8, sensor: u8) -> Result<Self, Lsm6ds3Error<B::Error>> {
        let mut id = [0];
        bus.write_read(address, &[WHO_AM_I], &mut id)?;
        if !IDENTITIES.contains(&id[0]) {
            return Err(Lsm6ds3Error::Identity(id[0]));
        }
        for (register, value) in [
            (CTRL3_C, BDU_IF_INC),
            (CTRL1_XL, ACCEL_208HZ_16G),
            (CTRL2_G, GYRO_208HZ_2000DPS),
        ] {
            bus.write(address, &[register, value])?;
        }
        Ok(Lsm6ds3 {
            bus,
            address,
            sensor,
        })
    }

    /// The newest sample, stamped `t_us`, if both sensors have new data since the last.
    ///
    /// # Errors
    /// [`Lsm6ds3Error::Bus`] if the bus fails.
    pub fn sample(&mut self, t_us: u64) -> Result<Option<ImuSample>, Lsm6ds3Error<B::Error>> {
        let mut status = [0];
        self.bus.write_read(self.address, &[STATUS], &mut status)?;
        if status[0] & DATA_READY != DATA_READY {
            return Ok(None);
        }
        let mut raw = [0u8; 12];
        self.bus.write_read(self.address, &[OUTX_L_G], &mut raw)?;
        let word = |k: usize| i16::from_le_bytes([raw[2 * k], raw[2 * k + 1]]);
        // An axis at full scale has clipped: the wire's saturated mark says so (its scaled
        // value would pass for a reading, 2 294 °/s and 15.99 g).
        let scaled = |k: usize, (num, den): (i32, i32)| match word(k) {
            clipped @ (i16::MIN | i16::MAX) => clipped,
            w => (i32::from(w) * num / den) as i16,
        };
        Ok(Some(ImuSample {
            sensor: self.sensor,
            t_us,
            accel_mg: [3, 4, 5].map(|k| scaled(k, MG_PER_COUNT)),
            gyro_ddps: [0, 1, 2].map(|k| scaled(k, DDPS_PER_COUNT)),
            mag_dut: None,
        }))
    }

    /// The bus back.
    pub fn release(self) -> B {
        self.bus
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal::i2c::{ErrorKind, ErrorType, Operation};

    /// A register map behind an I²C address, with auto-increment, as the chip behaves.
    #[derive(Debug)]
    struct Chip {
        registers: [u8; 128],
        address: u8,
    }

    impl ErrorType for Chip {
        type Error = ErrorKind;
    }

    impl I2c for Chip {
        fn transaction(&mut self, address: u8, ops: &mut [Operation<'_>]) -> Result<(), ErrorKind> {
            if address != self.address {
                return Err(ErrorKind::NoAcknowledge(
                    embedded_hal::i2c::NoAcknowledgeSource::Address,
                ));
            }
            let mut at = 0usize;
            for op in ops {
                match op {
                    Operation::Write(bytes) => {
                        at = usize::from(bytes[0]);
                        for &b in &bytes[1..] {
                            self.registers[at] = b;
                            at += 1;
                        }
                    }
                    Operation::Read(out) => {
                        for o in out.iter_mut() {
                            *o = self.registers[at];
                            at += 1;
                        }
                    }
                }
            }
            Ok(())
        }
    }

    fn chip(identity: u8) -> Chip {
        let mut registers = [0; 128];
        registers[usize::from(WHO_AM_I)] = identity;
        Chip {
            registers,
            address: ADDRESS,
        }
    }

    #[test]
    fn start_configures_both_sensors_and_samples_scale_to_wire_units() {
        let mut imu = Lsm6ds3::start(chip(0x6A), ADDRESS, 5).unwrap();
        let regs = &imu.bus.registers;
        assert_eq!(regs[usize::from(CTRL1_XL)], ACCEL_208HZ_16G);
        assert_eq!(regs[usize::from(CTRL2_G)], GYRO_208HZ_2000DPS);
        assert_eq!(regs[usize::from(CTRL3_C)], BDU_IF_INC);
        assert_eq!(imu.sample(10).unwrap(), None);
        // 1 g on Y (2049 counts at 0.488 mg), 100 °/s about Z (1429 counts at 70 m°/s).
        let counts: [i16; 6] = [0, 0, 1429, 0, 2049, -2049];
        for (k, c) in counts.iter().enumerate() {
            let at = usize::from(OUTX_L_G) + 2 * k;
            imu.bus.registers[at..at + 2].copy_from_slice(&c.to_le_bytes());
        }
        imu.bus.registers[usize::from(STATUS)] = DATA_READY;
        let sample = imu.sample(1234).unwrap().unwrap();
        assert_eq!(sample.sensor, 5);
        assert_eq!(sample.t_us, 1234);
        assert_eq!(sample.accel_mg, [0, 999, -999]);
        assert_eq!(sample.gyro_ddps, [0, 0, 1000]);
        // Full scale clips: the wire's extremes, not 2 294 °/s or 15.99 g.
        let counts: [i16; 6] = [i16::MAX, i16::MIN, i16::MAX - 1, i16::MIN, 0, 0];
        for (k, c) in counts.iter().enumerate() {
            let at = usize::from(OUTX_L_G) + 2 * k;
            imu.bus.registers[at..at + 2].copy_from_slice(&c.to_le_bytes());
        }
        let sample = imu.sample(1239).unwrap().unwrap();
        assert_eq!(sample.gyro_ddps, [i16::MAX, i16::MIN, 22_936]);
        assert_eq!(sample.accel_mg, [i16::MIN, 0, 0]);
    }

    #[test]
    fn another_chip_or_a_silent_bus_is_an_error() {
        assert_eq!(
            Lsm6ds3::start(chip(0x33), ADDRESS, 0).unwrap_err(),
            Lsm6ds3Error::Identity(0x33)
        );
        assert!(matches!(
            Lsm6ds3::start(chip(0x6A), 0x6B, 0).unwrap_err(),
            Lsm6ds3Error::Bus(ErrorKind::NoAcknowledge(_))
        ));
    }
}
