//! The TMC2209 stepper driver's single-wire UART (Trinamic TMC2209 datasheet rev.
//! 1.09, section 4 "UART Single Wire Interface" and section 5 "Register Map"): datagrams with
//! their CRC8, register packing, the motor current setting and the `VACTUAL` velocity unit.
//!
//! Four drivers share one wire (node addresses 0..=3 from their MS1/MS2 pins); the master sees
//! its own request echoed before any reply. A write is 8 bytes (sync, node, register | 0x80,
//! data MSB first, CRC), a read request 4 (sync, node, register, CRC) answered by 8 (sync,
//! 0xFF, register, data, CRC). Writes are confirmed by `IFCNT`, which counts good writes.

/// Sync nibble and reserved bits of every datagram.
pub const SYNC: u8 = 0x05;
/// The node address the driver answers with.
pub const MASTER: u8 = 0xFF;
/// Highest node address (MS1/MS2 pins).
pub const MAX_NODE: u8 = 3;
/// The driver's internal clock, Hz (`VACTUAL` counts in its units).
pub const F_CLK_HZ: f32 = 12_000_000.0;
/// Largest `VACTUAL` magnitude (24-bit signed).
pub const VACTUAL_MAX: i32 = (1 << 23) - 1;
/// `IOIN`'s version field (bits 31..24) of a TMC2209.
pub const VERSION: u8 = 0x21;

/// Register addresses (datasheet section 5).
pub mod reg {
    /// Global configuration (RW).
    pub const GCONF: u8 = 0x00;
    /// Global status flags (R, write 1 to clear).
    pub const GSTAT: u8 = 0x01;
    /// Count of good write datagrams, modulo 256 (R).
    pub const IFCNT: u8 = 0x02;
    /// Inputs and the version (R).
    pub const IOIN: u8 = 0x06;
    /// Hold and run currents (W).
    pub const IHOLD_IRUN: u8 = 0x10;
    /// Lower velocity threshold of StallGuard and CoolStep (W).
    pub const TCOOLTHRS: u8 = 0x14;
    /// Velocity by UART, signed, 0 for the STEP input (W).
    pub const VACTUAL: u8 = 0x22;
    /// StallGuard threshold (W).
    pub const SGTHRS: u8 = 0x40;
    /// StallGuard result (R).
    pub const SG_RESULT: u8 = 0x41;
    /// Chopper configuration (RW).
    pub const CHOPCONF: u8 = 0x6C;
    /// Driver status flags (R).
    pub const DRV_STATUS: u8 = 0x6F;
}

/// The datagram CRC8 (polynomial x^8 + x^2 + x + 1, each byte least significant bit first),
/// as the datasheet's `swuart_calcCRC` computes it.
pub fn crc8(bytes: &[u8]) -> u8 {
    let mut crc = 0u8;
    for &byte in bytes {
        let mut current = byte;
        for _ in 0..8 {
            crc = if (crc >> 7) ^ (current & 1) != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
            current >>= 1;
        }
    }
    crc
}

/// A write datagram: `value` to register `register` of driver `node`.
pub fn write_datagram(node: u8, register: u8, value: u32) -> [u8; 8] {
    let [b3, b2, b1, b0] = value.to_be_bytes();
    let mut d = [SYNC, node, register | 0x80, b3, b2, b1, b0, 0];
    d[7] = crc8(&d[..7]);
    d
}

/// A read request for register `register` of driver `node`.
pub fn read_request(node: u8, register: u8) -> [u8; 4] {
    let mut d = [SYNC, node, register & 0x7F, 0];
    d[3] = crc8(&d[..3]);
    d
}

/// What is wrong with a reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReplyError {
    /// Fewer than 8 bytes came.
    Short {
        /// Bytes received.
        len: usize,
    },
    /// The first byte is not the sync byte or the second not the master address.
    Framing,
    /// The reply is for another register.
    WrongRegister {
        /// Register asked for.
        expected: u8,
        /// Register answered.
        got: u8,
    },
    /// The CRC does not match: a corrupted reply.
    Crc,
}

impl core::fmt::Display for ReplyError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Short { len } => write!(f, "stepper reply cut short ({len} of 8 bytes)"),
            Self::Framing => f.write_str("stepper reply without its sync byte or master address"),
            Self::WrongRegister { expected, got } => write!(
                f,
                "stepper reply for register {got:#04x}, asked for {expected:#04x}"
            ),
            Self::Crc => f.write_str("stepper reply with a bad CRC"),
        }
    }
}

/// The register value of the 8-byte reply to a read of `register`.
pub fn parse_reply(reply: &[u8], register: u8) -> Result<u32, ReplyError> {
    let reply: &[u8; 8] = reply
        .get(..8)
        .and_then(|r| r.try_into().ok())
        .ok_or(ReplyError::Short { len: reply.len() })?;
    if reply[0] != SYNC || reply[1] != MASTER {
        return Err(ReplyError::Framing);
    }
    if crc8(&reply[..7]) != reply[7] {
        return Err(ReplyError::Crc);
    }
    if reply[2] != register {
        return Err(ReplyError::WrongRegister {
            expected: register,
            got: reply[2],
        });
    }
    Ok(u32::from_be_bytes([reply[3], reply[4], reply[5], reply[6]]))
}

/// `GCONF` for UART control: `pdn_disable` (the PDN_UART pin is the UART),
/// `mstep_reg_select` (microsteps from `CHOPCONF.MRES`), `multistep_filt`; StealthChop
/// (`en_SpreadCycle` clear), which StallGuard4 needs; the internal current reference.
pub const GCONF_UART: u32 = (1 << 6) | (1 << 7) | (1 << 8);

/// `CHOPCONF`'s reset value (TOFF 3, HSTRT 5, TBL 2, intpol, 256 microsteps).
pub const CHOPCONF_RESET: u32 = 0x1000_0053;

/// `CHOPCONF.vsense`: the high-sensitivity sense voltage (for small currents).
pub const VSENSE: u32 = 1 << 17;

/// A microstep resolution a TMC2209 does not have (1, 2, 4, .., 256 are).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadMicrosteps(pub u16);

impl core::fmt::Display for BadMicrosteps {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} microsteps: the TMC2209 has 1, 2, 4, 8, 16, 32, 64, 128 or 256",
            self.0
        )
    }
}

/// `CHOPCONF` with `microsteps` per full step (`MRES` = 8 - log2) and `vsense`, the rest of
/// `base` kept.
pub fn chopconf(base: u32, microsteps: u16, vsense: bool) -> Result<u32, BadMicrosteps> {
    if !microsteps.is_power_of_two() || microsteps > 256 {
        return Err(BadMicrosteps(microsteps));
    }
    let mres = 8 - microsteps.trailing_zeros();
    let cleared = base & !(0xF << 24) & !VSENSE;
    Ok(cleared | (mres << 24) | if vsense { VSENSE } else { 0 })
}

/// `IHOLD_IRUN`: run and hold current scales (0..=31, cut to 5 bits) and the hold delay.
pub fn ihold_irun(hold: u8, run: u8, hold_delay: u8) -> u32 {
    u32::from(hold & 0x1F) | (u32::from(run & 0x1F) << 8) | (u32::from(hold_delay & 0x0F) << 16)
}

/// A motor current the driver cannot set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BadCurrent {
    /// The RMS current asked for, A.
    pub rms_a: f32,
    /// The most the sense resistor allows, A.
    pub max_a: f32,
}

impl core::fmt::Display for BadCurrent {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        // Milliamps, not `f32` formatting (which costs the firmware 14 KB of flash).
        write!(
            f,
            "stepper current {} mA RMS is outside what the sense resistor allows (up to {} mA)",
            (self.rms_a * 1000.0) as i32,
            (self.max_a * 1000.0) as i32
        )
    }
}

/// The current scale `CS` (0..=31) and `vsense` for an RMS motor current with sense resistors
/// of `r_sense` ohm (datasheet section 9: I_rms = (CS + 1) / 32 * V_fs / (R_sense + 20 mOhm)
/// / sqrt 2, V_fs 0.325 V, or 0.180 V with `vsense`), rounded down so the current never
/// exceeds the request. The 0.325 V range unless it leaves fewer than 16 steps of scale, then
/// the finer 0.180 V range.
pub fn current_scale(rms_a: f32, r_sense: f32) -> Result<(u8, bool), BadCurrent> {
    let per_volt = 32.0 * core::f32::consts::SQRT_2 * (r_sense + 0.02);
    let max_a = 0.325 / per_volt * 32.0;
    if !(rms_a > 0.0 && rms_a <= max_a * 1.0001 && r_sense > 0.0) {
        return Err(BadCurrent { rms_a, max_a });
    }
    let cs_low = shared::math::floor(rms_a * per_volt / 0.325 + 1e-4) - 1.0;
    if cs_low >= 16.0 {
        return Ok((cs_low.min(31.0) as u8, false));
    }
    let cs_high = shared::math::floor(rms_a * per_volt / 0.180 + 1e-4) - 1.0;
    Ok((shared::math::clamp(cs_high, 0.0, 31.0) as u8, true))
}

/// The RMS current a setting gives, A.
pub fn current_of(cs: u8, vsense: bool, r_sense: f32) -> f32 {
    let v_fs = if vsense { 0.180 } else { 0.325 };
    (f32::from(cs.min(31)) + 1.0) / 32.0 * v_fs / (r_sense + 0.02) / core::f32::consts::SQRT_2
}

/// `VACTUAL` for a velocity of `microsteps_per_s` (v = VACTUAL * f_CLK / 2^24), rounded to the
/// nearest unit and saturated at 24 bits; 0 for a non-finite velocity.
pub fn vactual(microsteps_per_s: f32) -> i32 {
    if !microsteps_per_s.is_finite() {
        return 0;
    }
    let units = shared::math::round(microsteps_per_s * (16_777_216.0 / F_CLK_HZ));
    shared::math::clamp(units, -(VACTUAL_MAX as f32), VACTUAL_MAX as f32) as i32
}

/// The velocity a `VACTUAL` value runs at, microsteps per second.
pub fn velocity_of(vactual: i32) -> f32 {
    vactual as f32 * (F_CLK_HZ / 16_777_216.0)
}

/// `VACTUAL`'s 24-bit two's-complement register value.
pub fn vactual_register(vactual: i32) -> u32 {
    (vactual.clamp(-VACTUAL_MAX, VACTUAL_MAX) as u32) & 0x00FF_FFFF
}

/// Why a driver cannot be configured as the parameters ask.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SettingsError {
    /// The current is outside what the sense resistors allow.
    Current(BadCurrent),
    /// The microstep resolution does not exist.
    Microsteps(BadMicrosteps),
}

impl core::fmt::Display for SettingsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Current(e) => e.fmt(f),
            Self::Microsteps(e) => e.fmt(f),
        }
    }
}

/// The start-up writes of a driver, in order (register, value): `GCONF` for UART control,
/// `CHOPCONF` with the microsteps and the current range, `IHOLD_IRUN` (hold at half the run
/// current, hold delay 8), `TCOOLTHRS` at its maximum (StallGuard from the lowest speeds) and
/// `SGTHRS`. `GCONF` and `CHOPCONF` read back; `IFCNT` counts all five.
pub fn settings(
    current_a: f32,
    r_sense: f32,
    microsteps: u16,
    stall_threshold: u8,
) -> Result<[(u8, u32); 5], SettingsError> {
    let (cs, vsense) = current_scale(current_a, r_sense).map_err(SettingsError::Current)?;
    let chop = chopconf(CHOPCONF_RESET, microsteps, vsense).map_err(SettingsError::Microsteps)?;
    Ok([
        (reg::GCONF, GCONF_UART),
        (reg::CHOPCONF, chop),
        (reg::IHOLD_IRUN, ihold_irun(cs / 2, cs, 8)),
        (reg::TCOOLTHRS, 0x000F_FFFF),
        (reg::SGTHRS, u32::from(stall_threshold)),
    ])
}

/// Whether `IFCNT` read `before` and `after` a run of `writes` good writes counted them all.
pub fn writes_counted(before: u32, after: u32, writes: usize) -> bool {
    (after.wrapping_sub(before) & 0xFF) as usize == writes % 256
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An independent reading of the datasheet's algorithm: the CRC register shifted left,
    /// the data fed in least significant bit first, as one 8-bit polynomial division.
    fn crc_by_division(bytes: &[u8]) -> u8 {
        let mut bits = 0u64;
        let mut n = 0;
        for &b in bytes {
            for i in 0..8 {
                bits = (bits << 1) | u64::from((b >> i) & 1);
                n += 1;
            }
        }
        // Remainder of bits * x^8 modulo 0x107.
        let mut rem = 0u16;
        for i in (0..n).rev() {
            rem = (rem << 1) | ((bits >> i) & 1) as u16;
            if rem & 0x100 != 0 {
                rem ^= 0x107;
            }
        }
        for _ in 0..8 {
            rem <<= 1;
            if rem & 0x100 != 0 {
                rem ^= 0x107;
            }
        }
        rem as u8
    }

    #[test]
    fn crc_of_the_well_known_gconf_read() {
        // Read GCONF of node 0: 05 00 00 48, the request every TMC2209 bring-up log shows.
        assert_eq!(read_request(0, reg::GCONF), [0x05, 0x00, 0x00, 0x48]);
        for datagram in [
            &[0x05, 0x00, 0x00][..],
            &[0x05, 0x03, 0x6F],
            &[0x05, 0x01, 0xA2, 0x00, 0x00, 0x02, 0x9C],
            &[0x05, 0xFF, 0x6C, 0x14, 0x00, 0x00, 0x53],
        ] {
            assert_eq!(crc8(datagram), crc_by_division(datagram), "{datagram:02x?}");
        }
    }

    #[test]
    fn write_datagrams_carry_the_value_msb_first() {
        let d = write_datagram(2, reg::VACTUAL, 0x00AB_CDEF);
        assert_eq!(&d[..7], &[0x05, 0x02, 0xA2, 0x00, 0xAB, 0xCD, 0xEF]);
        assert_eq!(d[7], crc8(&d[..7]));
    }

    #[test]
    fn replies_parse_and_corruption_is_named() {
        let mut reply = [0x05, 0xFF, reg::IOIN, 0x21, 0x00, 0x00, 0x40, 0];
        reply[7] = crc8(&reply[..7]);
        let value = parse_reply(&reply, reg::IOIN).unwrap();
        assert_eq!((value >> 24) as u8, VERSION);
        assert_eq!(
            parse_reply(&reply[..5], reg::IOIN),
            Err(ReplyError::Short { len: 5 })
        );
        assert_eq!(
            parse_reply(&reply, reg::GCONF),
            Err(ReplyError::WrongRegister {
                expected: 0x00,
                got: 0x06
            })
        );
        let mut bad = reply;
        bad[4] ^= 0x10;
        assert_eq!(parse_reply(&bad, reg::IOIN), Err(ReplyError::Crc));
        bad = reply;
        bad[1] = 0x00;
        assert_eq!(parse_reply(&bad, reg::IOIN), Err(ReplyError::Framing));
    }

    #[test]
    fn chopconf_sets_the_microstep_resolution() {
        // 16 microsteps: MRES = 4, the reset value's other fields kept.
        assert_eq!(chopconf(CHOPCONF_RESET, 16, false), Ok(0x1400_0053));
        assert_eq!(chopconf(CHOPCONF_RESET, 256, true), Ok(0x1002_0053));
        assert_eq!(chopconf(CHOPCONF_RESET, 1, false), Ok(0x1800_0053));
        assert_eq!(chopconf(CHOPCONF_RESET, 12, false), Err(BadMicrosteps(12)));
        assert_eq!(
            chopconf(CHOPCONF_RESET, 512, false),
            Err(BadMicrosteps(512))
        );
    }

    #[test]
    fn ihold_irun_packs_its_fields() {
        assert_eq!(ihold_irun(8, 17, 10), 0x000A_1108);
        assert_eq!(ihold_irun(0xFF, 0xFF, 0xFF), 0x000F_1F1F);
    }

    /// 0.11 ohm sense resistors (the common TMC2209 boards): 1 A RMS is CS 17 at 0.325 V
    /// (18/32 * 0.325 / 0.13 / sqrt 2 = 0.994 A); 0.3 A would be CS 4 there, so it takes the
    /// 0.180 V range: CS 8, 9/32 * 0.180 / 0.13 / sqrt 2 = 0.275 A.
    #[test]
    fn current_scale_by_hand() {
        let (cs, vsense) = current_scale(1.0, 0.11).unwrap();
        assert_eq!((cs, vsense), (17, false));
        assert!((current_of(cs, vsense, 0.11) - 0.9944).abs() < 1e-3);
        let (cs, vsense) = current_scale(0.3, 0.11).unwrap();
        assert!(vsense, "small currents use the finer range");
        assert_eq!(cs, 8);
        assert!((current_of(cs, vsense, 0.11) - 0.2754).abs() < 1e-3);
        assert!(current_scale(2.0, 0.11).is_err());
        assert!(current_scale(0.0, 0.11).is_err());
        assert!(current_scale(f32::NAN, 0.11).is_err());
    }

    /// The defaults (0.8 A, 0.11 ohm, 16 microsteps, stall detection off): CS 13 would be
    /// coarse at 0.325 V, so 0.180 V and CS 25 (26/32 * 0.180 / 0.13 / sqrt 2 = 0.796 A).
    #[test]
    fn start_up_settings_by_hand() {
        let w = settings(0.8, 0.11, 16, 0).unwrap();
        assert_eq!(w[0], (reg::GCONF, 0x1C0));
        assert_eq!(w[1], (reg::CHOPCONF, 0x1402_0053));
        assert_eq!(w[2], (reg::IHOLD_IRUN, 0x0008_190C));
        assert_eq!(w[4], (reg::SGTHRS, 0));
        assert!(matches!(
            settings(0.8, 0.11, 12, 0),
            Err(SettingsError::Microsteps(_))
        ));
        assert!(matches!(
            settings(3.0, 0.11, 16, 0),
            Err(SettingsError::Current(_))
        ));
        assert!(writes_counted(250, 255, 5));
        assert!(writes_counted(253, 2, 5), "IFCNT wraps at 256");
        assert!(!writes_counted(250, 254, 5), "a write lost");
    }

    /// v = VACTUAL * 12 MHz / 2^24: 1000 microsteps/s is VACTUAL 1398 (0.7152 microsteps/s
    /// per unit); negative velocities are two's complement in 24 bits.
    #[test]
    fn vactual_units_for_the_internal_clock() {
        assert_eq!(vactual(1000.0), 1398);
        assert!((velocity_of(1398) - 999.93).abs() < 0.01);
        assert_eq!(vactual(-1000.0), -1398);
        assert_eq!(vactual_register(-1), 0x00FF_FFFF);
        assert_eq!(vactual_register(-1398), 0x00FF_FA8A);
        assert_eq!(vactual(1e12), VACTUAL_MAX);
        assert_eq!(vactual(f32::NAN), 0);
    }
}
