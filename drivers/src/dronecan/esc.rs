//! The DroneCAN ESC messages PX4 drives its CAN ESCs with (DroneCAN's standard data types,
//! `uavcan.equipment.esc`):
//!
//! - `RawCommand` (1030): one 14-bit signed command per ESC, `-8192..=8191`, in ESC index
//!   order, at most 20; a rotor that only spins one way is commanded `0..=8191`, 0 stopped.
//!   The array is the message's last field, so it goes without a length (DroneCAN's tail
//!   array optimisation): the receiver counts the commands from the payload's length.
//! - `Status` (1034): each ESC's error count, voltage, current, temperature (kelvin, as
//!   float16), RPM (int18), power rating (%) and its own ESC index, 14 bytes.

use half::f16;

use super::bits::{BitReader, BitWriter, OutOfRoom};
use super::transfer::{CanFrame, MAX_PAYLOAD, MessageId, frames};

/// `uavcan.equipment.esc.RawCommand`'s data type ID.
pub const RAW_COMMAND_ID: u16 = 1030;
/// `uavcan.equipment.esc.RawCommand`'s data type signature.
pub const RAW_COMMAND_SIGNATURE: u64 = 0x217F_5C87_D7EC_951D;
/// `uavcan.equipment.esc.Status`'s data type ID.
pub const STATUS_ID: u16 = 1034;
/// `uavcan.equipment.esc.Status`'s data type signature.
pub const STATUS_SIGNATURE: u64 = 0xA9AF_28AE_A2FB_B254;

/// Commands one `RawCommand` carries at most.
pub const MAX_COMMANDS: usize = 20;
/// The full-forward raw command.
pub const RAW_FULL: i16 = 8191;
/// Bytes of an ESC `Status`.
pub const STATUS_BYTES: usize = 14;
/// The priority an ESC sends its `Status` at: DroneCAN's default, 16.
pub const STATUS_PRIORITY: u8 = 16;

/// The raw command for a rotor's command fraction: `[0, 1]` to `0..=8191`, rounded; zero (a
/// stopped rotor) at or below 0 and for a fraction that is not a number.
pub fn raw_command(fraction: f32) -> i16 {
    if fraction.is_nan() || fraction <= 0.0 {
        return 0;
    }
    shared::math::round(fraction.min(1.0) * f32::from(RAW_FULL)) as i16
}

/// A raw command's fraction of full forward (negative for reverse).
pub fn command_fraction(raw: i16) -> f32 {
    f32::from(raw) / f32::from(RAW_FULL)
}

/// Encodes `RawCommand` with `commands` (at most [`MAX_COMMANDS`], each clamped to
/// `-8192..=8191`) into `buffer`; the payload's length.
pub fn encode_raw_command(commands: &[i16], buffer: &mut [u8]) -> Result<usize, OutOfRoom> {
    if commands.len() > MAX_COMMANDS {
        return Err(OutOfRoom);
    }
    let mut w = BitWriter::new(buffer);
    for &c in commands {
        w.write_signed(i64::from(c.clamp(-8192, RAW_FULL)), 14)?;
    }
    Ok(w.bytes())
}

/// The commands of a `RawCommand` payload, into `commands`; how many there were (the payload's
/// whole 14-bit fields, at most [`MAX_COMMANDS`] and `commands.len()`).
pub fn decode_raw_command(payload: &[u8], commands: &mut [i16]) -> usize {
    let mut r = BitReader::new(payload);
    let mut n = 0;
    while n < commands.len().min(MAX_COMMANDS) {
        let Ok(c) = r.read_signed(14) else { break };
        commands[n] = c as i16;
        n += 1;
    }
    n
}

/// One ESC's `Status`. A field the ESC does not measure is NaN.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EscStatus {
    /// Errors since the motor last started.
    pub error_count: u32,
    /// Supply voltage, V.
    pub voltage: f32,
    /// Current, A (negative when braking regeneratively).
    pub current: f32,
    /// Temperature, K.
    pub temperature: f32,
    /// Rotor speed, RPM (negative in reverse).
    pub rpm: i32,
    /// Power demand, % of the maximum (0 to 127).
    pub power_rating_pct: u8,
    /// The ESC's index in `RawCommand` (0 to 31).
    pub esc_index: u8,
}

/// The int18 RPM field's range.
const RPM_LIMIT: i32 = 1 << 17;

impl EscStatus {
    /// Encodes the status into `buffer` (at least [`STATUS_BYTES`]); the payload's length.
    pub fn encode(&self, buffer: &mut [u8]) -> Result<usize, OutOfRoom> {
        let mut w = BitWriter::new(buffer);
        w.write(u64::from(self.error_count), 32)?;
        for v in [self.voltage, self.current, self.temperature] {
            w.write(u64::from(f16::from_f32(v).to_bits()), 16)?;
        }
        w.write_signed(i64::from(self.rpm.clamp(-RPM_LIMIT, RPM_LIMIT - 1)), 18)?;
        w.write(u64::from(self.power_rating_pct.min(127)), 7)?;
        w.write(u64::from(self.esc_index.min(31)), 5)?;
        Ok(w.bytes())
    }

    /// The frames node `node` sends this status in as transfer `transfer`, each to `send`:
    /// the ESC's side of the bus.
    pub fn send(&self, node: u8, transfer: u8, mut send: impl FnMut(CanFrame)) {
        let mut payload = [0u8; MAX_PAYLOAD];
        let Ok(len) = self.encode(&mut payload) else {
            return;
        };
        let id = MessageId {
            priority: STATUS_PRIORITY,
            data_type: STATUS_ID,
            source: node,
        };
        frames(id, STATUS_SIGNATURE, transfer, &payload[..len]).for_each(&mut send);
    }

    /// Decodes a `Status` payload; `None` when it is shorter than [`STATUS_BYTES`].
    pub fn decode(payload: &[u8]) -> Option<Self> {
        let mut r = BitReader::new(payload);
        let error_count = r.read(32).ok()? as u32;
        let mut half = || r.read(16).ok().map(|b| f16::from_bits(b as u16).to_f32());
        let (voltage, current, temperature) = (half()?, half()?, half()?);
        Some(Self {
            error_count,
            voltage,
            current,
            temperature,
            rpm: r.read_signed(18).ok()? as i32,
            power_rating_pct: r.read(7).ok()? as u8,
            esc_index: r.read(5).ok()? as u8,
        })
    }
}
