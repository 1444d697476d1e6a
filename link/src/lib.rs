//! The vehicle's MAVLink link as plain, synchronous, `no_std` logic:
//! what the firmware and the hardware-in-the-loop plant say to each other, and how.
//!
//! - [`bandwidth`]: the link's rate as a budget of bytes (what may wait goes within it).
//! - [`frame`]: MAVLink 2 framing: a byte-at-a-time parser that survives any byte stream, and
//!   the encoder (the `mavlink` crate's message types, CRCs and payload encoding).
//! - [`geo`]: the map origin: the local position to a latitude, longitude and altitude.
//! - [`hil_ethernet`]: the HIL link's Ethernet framing (QEMU's LAN9118 to the plant's UDP).
//! - [`hil`]: PX4's simulator MAVLink API: `HIL_SENSOR` and `ATT_POS_MOCAP` in,
//!   `HIL_ACTUATOR_CONTROLS` (and `ACTUATOR_OUTPUT_STATUS` past 8 robots) out, with the channel
//!   map, and the lockstep bookkeeping of both sides.
//! - [`odometry`]: `ODOMETRY` from motion capture, as a fix.
//! - [`command`]: `COMMAND_LONG` to the operator's commands, and their `COMMAND_ACK`s.
//! - [`command_wire`]: those two messages with the command as its number.
//! - [`ftp`]: MAVLink FTP: the vehicle's minimal server (one writable file, the payload
//!   description; read-only files, the parameter metadata) and the ground side's upload.
//! - [`link_health`]: what the link dropped, counted for `SYS_STATUS` and told.
//! - [`log_transfer`]: MAVLink's log protocol: the flight logs (the `flight-log` crate's
//!   storage) listed, downloaded, erased.
//! - [`mission`]: MAVLink's mission protocol: a ground station's route uploaded (checked,
//!   atomic, with timeouts), downloaded, cleared, flown from an item; stored.
//! - [`modes`]: the flight modes, in PX4's numbers and the standard modes protocol.
//! - [`param`]: MAVLink's parameter protocol over the mission's parameter table.
//! - [`param_lists`]: the parameter lists in flight, one per requester, sent as room allows.
//! - [`signing`]: MAVLink 2 message signing (SHA-256), both ways.
//! - [`status`]: `STATUSTEXT` (long texts in chunks, and their reassembly) and named values.
//! - [`telemetry`]: `SYS_STATUS`, `ATTITUDE_QUATERNION`, `LOCAL_POSITION_NED`,
//!   `GLOBAL_POSITION_INT` at set rates; `HOME_POSITION` and `GPS_GLOBAL_ORIGIN`.
//! - [`timesync`]: `TIMESYNC`: the motion-capture computer's clock on the vehicle's.
//! - [`vehicle`]: the vehicle's dispatch of received frames.
//!
//! Nothing here does I/O, allocates or panics on input: the firmware runs it under embassy on
//! a Cortex-M7 and the host tests it and runs it in the plant. The `mavlink` crate needs one of
//! its `std` or `embedded` features, which this crate passes through (`std` on the host,
//! `embedded` in the firmware, never both).
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

#[cfg(all(feature = "std", feature = "embedded"))]
compile_error!("link: enable `std` (host) or `embedded` (firmware), not both");

#[cfg(test)]
extern crate std;

pub mod bandwidth;
pub mod command;
pub mod command_wire;
pub mod esc;
pub mod frame;
pub mod ftp;
pub mod geo;
pub mod hil;
pub mod hil_ethernet;
pub mod link_health;
pub mod log_transfer;
pub mod mission;
pub mod modes;
pub mod odometry;
pub mod param;
pub mod param_lists;
pub mod signing;
pub mod status;
pub mod telemetry;
pub mod timesync;
pub mod vehicle;

/// The trait of every message type (its id, `CRC_EXTRA`, encoding).
pub use mavlink::MessageData;
/// The MAVLink common dialect's messages and enums, as this crate uses them.
pub use mavlink::dialects::common as msg;

/// MAVLink system id of the vehicle.
pub const VEHICLE_SYSTEM_ID: u8 = 1;
/// MAVLink component id of the flight controller (`MAV_COMP_ID_AUTOPILOT1`).
pub const VEHICLE_COMPONENT_ID: u8 = 1;
/// MAVLink system id the HIL plant and its ground tools use (a ground station's).
pub const PLANT_SYSTEM_ID: u8 = 255;
/// MAVLink component id of the HIL plant (`MAV_COMP_ID_MISSIONPLANNER`).
pub const PLANT_COMPONENT_ID: u8 = 190;
