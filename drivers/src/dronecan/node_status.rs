//! `uavcan.protocol.NodeStatus` (341), the heartbeat every DroneCAN node sends at least once a
//! second: uptime, health, mode, and a vendor's status code. A node not heard for
//! [`OFFLINE_TIMEOUT_US`] (the data type's `OFFLINE_TIMEOUT_MS`, 3 s) is offline.

use super::bits::{BitReader, BitWriter, OutOfRoom};

/// `uavcan.protocol.NodeStatus`'s data type ID.
pub const NODE_STATUS_ID: u16 = 341;
/// `uavcan.protocol.NodeStatus`'s data type signature.
pub const NODE_STATUS_SIGNATURE: u64 = 0x0F08_68D0_C1A7_C6F1;
/// A node silent this long is offline, us.
pub const OFFLINE_TIMEOUT_US: u64 = 3_000_000;

/// A node's health.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Health {
    /// Functioning properly.
    Ok = 0,
    /// A minor failure, or a parameter out of range.
    Warning = 1,
    /// A major failure.
    Error = 2,
    /// A fatal malfunction.
    Critical = 3,
}

/// A node's mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Normal operation.
    Operational,
    /// Starting up.
    Initialization,
    /// Calibration, bootloader and the like.
    Maintenance,
    /// Loading new firmware.
    SoftwareUpdate,
    /// No longer available.
    Offline,
    /// A value the standard does not define (4 to 6).
    Other(u8),
}

/// One `NodeStatus`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeStatus {
    /// Seconds since the node started.
    pub uptime_sec: u32,
    /// Its health.
    pub health: Health,
    /// Its mode.
    pub mode: Mode,
    /// Mode-specific detail (0 to 7).
    pub sub_mode: u8,
    /// The vendor's status code.
    pub vendor_specific_status_code: u16,
}

/// Bytes of a `NodeStatus`.
pub const NODE_STATUS_BYTES: usize = 7;

impl NodeStatus {
    /// Encodes the status into `buffer` (at least [`NODE_STATUS_BYTES`]).
    pub fn encode(&self, buffer: &mut [u8]) -> Result<usize, OutOfRoom> {
        let mode = match self.mode {
            Mode::Operational => 0,
            Mode::Initialization => 1,
            Mode::Maintenance => 2,
            Mode::SoftwareUpdate => 3,
            Mode::Offline => 7,
            Mode::Other(m) => m & 7,
        };
        let mut w = BitWriter::new(buffer);
        w.write(u64::from(self.uptime_sec), 32)?;
        w.write(self.health as u64, 2)?;
        w.write(u64::from(mode), 3)?;
        w.write(u64::from(self.sub_mode & 7), 3)?;
        w.write(u64::from(self.vendor_specific_status_code), 16)?;
        Ok(w.bytes())
    }

    /// Decodes a `NodeStatus` payload; `None` when it is too short.
    pub fn decode(payload: &[u8]) -> Option<Self> {
        let mut r = BitReader::new(payload);
        let uptime_sec = r.read(32).ok()? as u32;
        let health = match r.read(2).ok()? {
            0 => Health::Ok,
            1 => Health::Warning,
            2 => Health::Error,
            _ => Health::Critical,
        };
        let mode = match r.read(3).ok()? as u8 {
            0 => Mode::Operational,
            1 => Mode::Initialization,
            2 => Mode::Maintenance,
            3 => Mode::SoftwareUpdate,
            7 => Mode::Offline,
            other => Mode::Other(other),
        };
        Some(Self {
            uptime_sec,
            health,
            mode,
            sub_mode: r.read(3).ok()? as u8,
            vendor_specific_status_code: r.read(16).ok()? as u16,
        })
    }
}
