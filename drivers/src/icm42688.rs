//! The ICM-42688-P IMU over SPI (TDK InvenSense ICM-42688-P datasheet DS-000347
//! rev. 1.8): its registers, the start-up sequence, and its FIFO's 20-byte packets in
//! high-resolution mode (packet 4: accelerometer and gyro in 20 bits, temperature, timestamp).
//!
//! The IMU samples both sensors at 2 kHz into its FIFO and raises INT1 (data ready, PE6 on the
//! Pixhawk 6C) each time two records wait; the board's task reads them in one SPI burst. The
//! `icm426xx` crate (0.4) reads the same 20-byte packets, but through its own generated
//! register layer, an `embedded-hal-async` `SpiDevice` and a delay, and returns no saturation
//! or invalid-sample marks; with the image 6 KiB under its flash budget this core (a table of
//! writes and a packet parser, tested against hand-built packets) is used instead.

use shared::scenario::GRAVITY;

/// `WHO_AM_I` of an ICM-42688-P.
pub const WHO_AM_I_VALUE: u8 = 0x47;
/// Set on the register address of an SPI read.
pub const READ: u8 = 0x80;
/// Bytes of a FIFO packet in high-resolution mode.
pub const PACKET_LEN: usize = 20;
/// Accelerometer sensitivity of the 20-bit FIFO data at +-16 g: 2^19 / 16 LSB per g.
pub const ACCEL_LSB_PER_G: f32 = 32_768.0;
/// Gyro sensitivity of the 20-bit FIFO data at +-2000 deg/s: 2^19 / 2000 LSB per deg/s.
pub const GYRO_LSB_PER_DPS: f32 = 262.144;
/// The FIFO's mark of a sample the sensor had no data for (-2^19).
pub const INVALID: i32 = -524_288;
/// Output data rate of both sensors, Hz.
pub const ODR_HZ: f32 = 2000.0;
/// FIFO records that raise the data-ready interrupt.
pub const WATERMARK_RECORDS: u16 = 2;

/// Bank 0 register addresses.
pub mod reg {
    /// Soft reset (`DEVICE_CONFIG`).
    pub const DEVICE_CONFIG: u8 = 0x11;
    /// INT1 and INT2 pin configuration.
    pub const INT_CONFIG: u8 = 0x14;
    /// FIFO mode.
    pub const FIFO_CONFIG: u8 = 0x16;
    /// Interrupt status (reading clears it).
    pub const INT_STATUS: u8 = 0x2D;
    /// FIFO count, high byte (low byte follows).
    pub const FIFO_COUNTH: u8 = 0x2E;
    /// FIFO data port.
    pub const FIFO_DATA: u8 = 0x30;
    /// FIFO flush.
    pub const SIGNAL_PATH_RESET: u8 = 0x4B;
    /// Endianness and the FIFO count's unit.
    pub const INTF_CONFIG0: u8 = 0x4C;
    /// Sensor power modes.
    pub const PWR_MGMT0: u8 = 0x4E;
    /// Gyro full scale and rate.
    pub const GYRO_CONFIG0: u8 = 0x4F;
    /// Accelerometer full scale and rate.
    pub const ACCEL_CONFIG0: u8 = 0x50;
    /// What the FIFO holds.
    pub const FIFO_CONFIG1: u8 = 0x5F;
    /// FIFO watermark, low byte.
    pub const FIFO_CONFIG2: u8 = 0x60;
    /// FIFO watermark, high nibble.
    pub const FIFO_CONFIG3: u8 = 0x61;
    /// Interrupt timing.
    pub const INT_CONFIG1: u8 = 0x64;
    /// What raises INT1.
    pub const INT_SOURCE0: u8 = 0x65;
    /// Device identity.
    pub const WHO_AM_I: u8 = 0x75;
    /// Register bank select.
    pub const REG_BANK_SEL: u8 = 0x76;
}

/// `DEVICE_CONFIG` value that resets the chip (then wait 1 ms).
pub const SOFT_RESET: u8 = 0x01;
/// `SIGNAL_PATH_RESET` value that flushes the FIFO.
pub const FIFO_FLUSH: u8 = 0x02;

/// The start-up writes after the soft reset, in order, each read back (register, value):
/// FIFO count in records, big endian; stream-to-FIFO; 20-bit packets of accelerometer, gyro,
/// temperature and timestamp, watermark interrupt when above the threshold; the watermark;
/// +-2000 deg/s and +-16 g at 2 kHz; INT1 push-pull, active high, pulsed, and the FIFO
/// threshold on it (with `INT_ASYNC_RESET` clear, as the datasheet requires for INT1); both
/// sensors in low-noise mode last (the gyro then needs 30 ms).
pub const START: [(u8, u8); 11] = [
    (reg::INTF_CONFIG0, 0x70),
    (reg::FIFO_CONFIG, 0x40),
    (reg::FIFO_CONFIG1, 0x37),
    (reg::FIFO_CONFIG2, (WATERMARK_RECORDS & 0xFF) as u8),
    (reg::FIFO_CONFIG3, (WATERMARK_RECORDS >> 8) as u8),
    (reg::GYRO_CONFIG0, 0x05),
    (reg::ACCEL_CONFIG0, 0x05),
    (reg::INT_CONFIG, 0x03),
    (reg::INT_CONFIG1, 0x00),
    (reg::INT_SOURCE0, 0x04),
    (reg::PWR_MGMT0, 0x0F),
];

/// One FIFO record, in the sensor's own axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawSample {
    /// Accelerometer, 20-bit counts.
    pub accel: [i32; 3],
    /// Gyro, 20-bit counts.
    pub gyro: [i32; 3],
    /// Die temperature, counts (high-resolution FIFO format).
    pub temperature: i16,
    /// The IMU's 16-bit timestamp.
    pub timestamp: u16,
}

/// Why a FIFO packet was not a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PacketError {
    /// The header says the FIFO was empty (the read outran the data).
    Empty,
    /// The header is not a 20-bit accelerometer-and-gyro packet: the FIFO is out of step or
    /// the IMU was reconfigured.
    Header(u8),
    /// The sensor marked a value invalid (it had no data yet).
    Invalid,
}

impl core::fmt::Display for PacketError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Empty => f.write_str("IMU FIFO packet marked empty"),
            Self::Header(h) => write!(
                f,
                "IMU FIFO packet with header {h:#04x}, not a 20-bit packet"
            ),
            Self::Invalid => f.write_str("IMU FIFO packet with a value marked invalid"),
        }
    }
}

/// Header bits: FIFO empty; accelerometer, gyro, 20-bit data present.
const HEADER_EMPTY: u8 = 0x80;
const HEADER_SAMPLE: u8 = 0x70;

fn twenty_bits(high: u8, low: u8, nibble: u8) -> i32 {
    let raw = (u32::from(high) << 12) | (u32::from(low) << 4) | u32::from(nibble & 0x0F);
    // Sign-extend bit 19.
    ((raw << 12) as i32) >> 12
}

/// Parses one 20-byte packet: header; accelerometer X, Y, Z and gyro X, Y, Z (bits 19..4, big
/// endian); temperature; timestamp; three extension bytes with bits 3..0 of each axis
/// (accelerometer in the high nibble, gyro in the low).
pub fn parse_packet(p: &[u8; PACKET_LEN]) -> Result<RawSample, PacketError> {
    let header = p[0];
    if header & HEADER_EMPTY != 0 {
        return Err(PacketError::Empty);
    }
    if header & HEADER_SAMPLE != HEADER_SAMPLE {
        return Err(PacketError::Header(header));
    }
    let mut accel = [0; 3];
    let mut gyro = [0; 3];
    for axis in 0..3 {
        let ext = p[17 + axis];
        accel[axis] = twenty_bits(p[1 + 2 * axis], p[2 + 2 * axis], ext >> 4);
        gyro[axis] = twenty_bits(p[7 + 2 * axis], p[8 + 2 * axis], ext);
    }
    if accel.contains(&INVALID) || gyro.contains(&INVALID) {
        return Err(PacketError::Invalid);
    }
    Ok(RawSample {
        accel,
        gyro,
        temperature: i16::from_be_bytes([p[13], p[14]]),
        timestamp: u16::from_be_bytes([p[15], p[16]]),
    })
}

impl RawSample {
    /// Accelerometer, m/s^2, sensor axes.
    pub fn accel_m_s2(&self) -> [f32; 3] {
        self.accel.map(|c| c as f32 * (GRAVITY / ACCEL_LSB_PER_G))
    }

    /// Gyro, rad/s, sensor axes.
    pub fn gyro_rad_s(&self) -> [f32; 3] {
        self.gyro
            .map(|c| c as f32 * (core::f32::consts::PI / 180.0 / GYRO_LSB_PER_DPS))
    }

    /// Die temperature, deg C (FIFO format: counts / 132.48 + 25).
    pub fn temperature_c(&self) -> f32 {
        f32::from(self.temperature) / 132.48 + 25.0
    }

    /// Whether any axis is within 1 % of full scale (the reading cannot be trusted).
    pub fn saturated(&self) -> bool {
        const LIMIT: i32 = 519_000; // 0.99 x 2^19
        self.accel
            .iter()
            .chain(&self.gyro)
            .any(|c| c.abs() >= LIMIT)
    }
}

/// Records waiting, from `FIFO_COUNTH` and `FIFO_COUNTL` (big endian, in records).
pub fn fifo_records(count_h: u8, count_l: u8) -> u16 {
    u16::from_be_bytes([count_h, count_l])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A packet built by hand: accel X = +1 g (32768 = 0x08000: bytes 08 00, nibble 0),
    /// Y = -1 count (0xFFFFF), Z = 0x12345; gyro X = 262144 (1000 deg/s: 0x40000), Y = -262144,
    /// Z = 5; temperature 132 (about 26 deg C); timestamp 0xBEEF.
    fn packet() -> [u8; PACKET_LEN] {
        [
            0x78, // accel, gyro, 20-bit, timestamp field
            0x08, 0x00, 0xFF, 0xFF, 0x12, 0x34, // accel bits 19..4
            0x40, 0x00, 0xC0, 0x00, 0x00, 0x00, // gyro bits 19..4
            0x00, 0x84, // temperature
            0xBE, 0xEF, // timestamp
            0x00, 0xF0, 0x55, // accel | gyro low nibbles
        ]
    }

    #[test]
    fn a_hand_built_packet_parses_to_its_values() {
        let s = parse_packet(&packet()).unwrap();
        assert_eq!(s.accel, [32_768, -1, 0x12345]);
        assert_eq!(s.gyro, [262_144, -262_144, 5]);
        assert_eq!(s.temperature, 132);
        assert_eq!(s.timestamp, 0xBEEF);
        let a = s.accel_m_s2();
        assert!((a[0] - GRAVITY).abs() < 1e-5);
        let w = s.gyro_rad_s();
        assert!((w[0] - 1000f32.to_radians()).abs() < 1e-4);
        assert!((w[1] + 1000f32.to_radians()).abs() < 1e-4);
        assert!((s.temperature_c() - 25.996).abs() < 1e-3);
        assert!(!s.saturated());
    }

    #[test]
    fn full_scale_is_saturated() {
        let mut p = packet();
        // Gyro Z = 0x7FFFF, the positive limit.
        p[11] = 0x7F;
        p[12] = 0xFF;
        p[19] = 0x5F;
        let s = parse_packet(&p).unwrap();
        assert_eq!(s.gyro[2], 0x7FFFF);
        assert!(s.saturated());
    }

    #[test]
    fn empty_foreign_and_invalid_packets_are_named() {
        let mut p = packet();
        p[0] = 0x80;
        assert_eq!(parse_packet(&p), Err(PacketError::Empty));
        p[0] = 0x68; // accel and gyro, 16-bit packet
        assert_eq!(parse_packet(&p), Err(PacketError::Header(0x68)));
        let mut p = packet();
        p[1] = 0x80; // accel X = -2^19
        p[2] = 0x00;
        p[17] = 0x00;
        assert_eq!(parse_packet(&p), Err(PacketError::Invalid));
    }

    #[test]
    fn start_sequence_configures_what_the_parser_expects() {
        let value = |r| {
            START
                .iter()
                .find(|(reg, _)| *reg == r)
                .map(|(_, v)| *v)
                .unwrap()
        };
        // 20-bit packets with accel, gyro and temperature.
        assert_eq!(value(reg::FIFO_CONFIG1) & 0x17, 0x17);
        // Both sensors at 2 kHz (ODR code 5) and the widest range (FS_SEL 0).
        assert_eq!(value(reg::GYRO_CONFIG0), 0x05);
        assert_eq!(value(reg::ACCEL_CONFIG0), 0x05);
        // FIFO counts in records, so the watermark and [`fifo_records`] agree.
        assert_eq!(value(reg::INTF_CONFIG0) & 0x40, 0x40);
        assert_eq!(START.last().map(|(r, _)| *r), Some(reg::PWR_MGMT0));
        assert_eq!(fifo_records(0x01, 0x02), 258);
    }
}
