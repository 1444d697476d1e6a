//! The vehicle's dispatch of received frames: which of its services a frame is for, decoded and
//! checked (docs/ground-link.md; commands: #commands-long-or-int). Only the messages the
//! vehicle handles are decoded, so the
//! firmware links those decoders and no others (decoding the whole dialect costs ~80 KB).
//!
//! Here: what a frame is for ([`dispatch`], [`Inbound`]) and the ground station's `HEARTBEAT`;
//! in `crc_extras` the `CRC_EXTRA` of every message the link speaks ([`crc_extra`]); in
//! `battery` `BATTERY_STATUS` both ways (docs/failures.md#failures).

use mavlink::MessageData;

use crate::command::{Request, classify};
use crate::command_wire::{CommandId, CommandInt, CommandLong};
use crate::frame::{Frame, Integrity};
use crate::ftp::{FtpMessage, PAYLOAD_LEN};
use crate::hil::{HilError, MocapFix, PlantSample, mocap_from_message};
use crate::log_transfer::LogRequest;
use crate::mission::wire::MissionMessage;
use crate::msg::{
    ATT_POS_MOCAP_DATA, BATTERY_STATUS_DATA, COMMAND_INT_DATA, COMMAND_LONG_DATA,
    FILE_TRANSFER_PROTOCOL_DATA, HEARTBEAT_DATA, HIL_SENSOR_DATA, LOG_ERASE_DATA,
    LOG_REQUEST_DATA_DATA, LOG_REQUEST_END_DATA, LOG_REQUEST_LIST_DATA, MANUAL_CONTROL_DATA,
    MavAutopilot, MavType, ODOMETRY_DATA, PARAM_REQUEST_LIST_DATA, PARAM_REQUEST_READ_DATA,
    PARAM_SET_DATA, SETUP_SIGNING_DATA, TIMESYNC_DATA,
};
use crate::param::ParamRequest;

mod battery;
mod crc_extras;
#[cfg(test)]
mod tests;

pub use battery::{battery_status, battery_volts, millivolts_of, pack_millivolts, volts_of};
pub use crc_extras::crc_extra;

/// `SET_GPS_GLOBAL_ORIGIN`: superseded (2025) by `MAV_CMD_DO_SET_GLOBAL_ORIGIN`, which needs
/// `COMMAND_INT`; still what pymavlink scripts and MAVROS send.
/// Read from its payload's bytes ([`set_origin`]), its fields being deprecated.
#[allow(deprecated, non_camel_case_types)]
type SET_GPS_GLOBAL_ORIGIN_DATA = crate::msg::SET_GPS_GLOBAL_ORIGIN_DATA;
/// `SET_MODE`: deprecated (2015) for `MAV_CMD_DO_SET_MODE`, still QGroundControl's.
#[allow(deprecated, non_camel_case_types)]
type SET_MODE_DATA = crate::msg::SET_MODE_DATA;

/// Who sent a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sender {
    /// System id.
    pub system: u8,
    /// Component id.
    pub component: u8,
}

/// A received frame, for the vehicle.
// The FTP variant is a whole FTP message (~250 bytes); values of this type live briefly on the
// stack of the link task, and no_std has no box to shrink it.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Inbound {
    /// `HIL_SENSOR`: a control step in lockstep.
    Sensor(PlantSample),
    /// A motion-capture fix: `ATT_POS_MOCAP`, or `ODOMETRY` from motion capture, stamped
    /// with the sender's clock.
    Mocap(MocapFix),
    /// `TIMESYNC` (a request to answer, or an answer to the vehicle's): for
    /// [`crate::timesync::TimeSync::receive`].
    TimeSync {
        /// `tc1` (0: a request).
        tc1: i64,
        /// `ts1`.
        ts1: i64,
    },
    /// `COMMAND_LONG` or `COMMAND_INT` addressed to the vehicle, classified (the same way
    /// whichever it came as).
    Command {
        /// The command as sent (for its acknowledgement).
        command: CommandId,
        /// What it asks for.
        request: Request,
        /// Its sender (the acknowledgement's target).
        from: Sender,
    },
    /// `FILE_TRANSFER_PROTOCOL` addressed to the vehicle.
    Ftp {
        /// The FTP command.
        message: FtpMessage,
        /// Its sender.
        from: Sender,
    },
    /// A parameter request addressed to the vehicle.
    Param {
        /// What it asks.
        request: ParamRequest,
        /// Its sender.
        from: Sender,
    },
    /// `SETUP_SIGNING` addressed to the vehicle: a new signing key (all zeros: signing off)
    /// and the timestamp to start from.
    SetupSigning {
        /// The key.
        key: [u8; crate::signing::KEY_LEN],
        /// The initial timestamp, 10 us units since 2015-01-01.
        timestamp: u64,
        /// Its sender.
        from: Sender,
    },
    /// A log-protocol request (`LOG_REQUEST_LIST`, `LOG_REQUEST_DATA`, `LOG_REQUEST_END`,
    /// `LOG_ERASE`) addressed to the vehicle.
    Log {
        /// What it asks.
        request: LogRequest,
        /// Its sender.
        from: Sender,
    },
    /// A mission-protocol message addressed to the vehicle ([`crate::mission`]).
    Mission {
        /// The message.
        message: MissionMessage,
        /// Its sender.
        from: Sender,
    },
    /// A ground station's `HEARTBEAT` (type `MAV_TYPE_GCS`, from another system than the
    /// vehicle's): the ground link is up.
    GcsHeartbeat(Sender),
    /// Any other `HEARTBEAT` (a companion computer, another vehicle, an echo).
    Heartbeat(Sender),
    /// `MANUAL_CONTROL` addressed to the vehicle: a ground station's joystick, its axes as
    /// sent (x forward, y right, z thrust, r yaw; `shared::manual::from_manual_control` reads
    /// them).
    ManualControl {
        /// Forward, -1000..1000.
        x: i16,
        /// Right, -1000..1000.
        y: i16,
        /// Thrust, 0..1000 (500 centred).
        z: i16,
        /// Yaw, -1000..1000.
        r: i16,
        /// The joystick's buttons, a bit each.
        buttons: u16,
        /// Its sender.
        from: Sender,
    },
    /// `BATTERY_STATUS`: a pack's voltage. The vehicle takes it only in hardware-in-the-loop,
    /// from the plant (on a board its own ADC measures the pack).
    Battery {
        /// The pack's voltage, V.
        volts: f32,
        /// Its sender.
        from: Sender,
    },
    /// `ESC_STATUS`: four ESCs' RPM. The vehicle takes it only in hardware-in-the-loop, from
    /// the plant (on a board the ESCs answer over bidirectional DShot).
    EscStatus(crate::esc::EscRpmReport),
    /// `SET_GPS_GLOBAL_ORIGIN` addressed to the vehicle: the map origin
    /// (docs/ground-link.md#the-map-origin), not yet checked.
    SetOrigin {
        /// Latitude, 1e-7 degrees.
        lat_e7: i32,
        /// Longitude, 1e-7 degrees.
        lon_e7: i32,
        /// Altitude above mean sea level, mm.
        alt_mm: i32,
        /// Its sender.
        from: Sender,
    },
    /// A HIL message that does not hold (the text says why).
    Invalid(HilError),
    /// Not for the vehicle, or not a message it handles.
    Ignored {
        /// Message id.
        id: u32,
    },
}

fn for_us(system: u8, component: u8) -> bool {
    (system == 0 || system == crate::VEHICLE_SYSTEM_ID)
        && (component == 0 || component == crate::VEHICLE_COMPONENT_ID)
}

/// What `frame` is for the vehicle.
pub fn dispatch(frame: &Frame, integrity: Integrity) -> Inbound {
    let id = frame.message_id();
    if integrity != Integrity::Verified {
        return Inbound::Ignored { id };
    }
    let from = Sender {
        system: frame.system_id(),
        component: frame.component_id(),
    };
    let ignored = Inbound::Ignored { id };
    match id {
        HIL_SENSOR_DATA::ID => frame.decode::<HIL_SENSOR_DATA>().map_or(ignored, |m| {
            // The extension field `id` follows the base fields.
            let sensor_id = frame
                .payload()
                .get(HIL_SENSOR_DATA::ENCODED_LEN)
                .copied()
                .unwrap_or(0);
            match PlantSample::from_message(&m, sensor_id) {
                Ok(s) => Inbound::Sensor(s),
                Err(e) => Inbound::Invalid(e),
            }
        }),
        ATT_POS_MOCAP_DATA::ID => {
            frame
                .decode::<ATT_POS_MOCAP_DATA>()
                .map_or(ignored, |m| match mocap_from_message(&m) {
                    Ok(f) => Inbound::Mocap(f),
                    Err(e) => Inbound::Invalid(e),
                })
        }
        COMMAND_LONG_DATA::ID => match frame.decode::<CommandLong>() {
            Some(c) if for_us(c.target_system, c.target_component) => Inbound::Command {
                command: CommandId(c.command),
                request: classify(&c),
                from,
            },
            _ => ignored,
        },
        COMMAND_INT_DATA::ID => match frame.decode::<CommandInt>() {
            Some(c) if for_us(c.target_system, c.target_component) => Inbound::Command {
                command: CommandId(c.command),
                request: classify(&c),
                from,
            },
            _ => ignored,
        },
        ODOMETRY_DATA::ID => match crate::odometry::mocap_fix(frame.payload()) {
            Ok(Some(f)) => Inbound::Mocap(f),
            Ok(None) => ignored,
            Err(e) => Inbound::Invalid(e),
        },
        SETUP_SIGNING_DATA::ID => match frame.decode::<SETUP_SIGNING_DATA>() {
            Some(m) if for_us(m.target_system, m.target_component) => Inbound::SetupSigning {
                key: m.secret_key,
                timestamp: m.initial_timestamp,
                from,
            },
            _ => ignored,
        },
        TIMESYNC_DATA::ID => match frame.decode::<TIMESYNC_DATA>() {
            // The extension fields `target_system`, `target_component` follow the base fields
            // (absent: 0, everyone).
            Some(t) => {
                let target = frame.payload().get(TIMESYNC_DATA::ENCODED_LEN).copied();
                if for_us(target.unwrap_or(0), 0) {
                    Inbound::TimeSync {
                        tc1: t.tc1,
                        ts1: t.ts1,
                    }
                } else {
                    ignored
                }
            }
            None => ignored,
        },
        FILE_TRANSFER_PROTOCOL_DATA::ID => match frame.decode::<FILE_TRANSFER_PROTOCOL_DATA>() {
            Some(f) if for_us(f.target_system, f.target_component) => {
                let payload: &[u8; PAYLOAD_LEN] = &f.payload;
                Inbound::Ftp {
                    message: FtpMessage::from_payload(payload),
                    from,
                }
            }
            _ => ignored,
        },
        PARAM_REQUEST_LIST_DATA::ID => match frame.decode::<PARAM_REQUEST_LIST_DATA>() {
            Some(m) if for_us(m.target_system, m.target_component) => Inbound::Param {
                request: ParamRequest::from_list(&m),
                from,
            },
            _ => ignored,
        },
        PARAM_REQUEST_READ_DATA::ID => match frame.decode::<PARAM_REQUEST_READ_DATA>() {
            Some(m) if for_us(m.target_system, m.target_component) => Inbound::Param {
                request: ParamRequest::from_read(&m),
                from,
            },
            _ => ignored,
        },
        PARAM_SET_DATA::ID => match frame.decode::<PARAM_SET_DATA>() {
            Some(m) if for_us(m.target_system, m.target_component) => Inbound::Param {
                request: ParamRequest::from_set(&m),
                from,
            },
            _ => ignored,
        },
        id if crate::mission::wire::READ_IDS.contains(&id) => {
            match crate::mission::wire::read(frame) {
                Some((message, system, component)) if for_us(system, component) => {
                    Inbound::Mission { message, from }
                }
                _ => ignored,
            }
        }
        LOG_REQUEST_LIST_DATA::ID => match frame.decode::<LOG_REQUEST_LIST_DATA>() {
            Some(m) if for_us(m.target_system, m.target_component) => Inbound::Log {
                request: LogRequest::from_list(&m),
                from,
            },
            _ => ignored,
        },
        LOG_REQUEST_DATA_DATA::ID => match frame.decode::<LOG_REQUEST_DATA_DATA>() {
            Some(m) if for_us(m.target_system, m.target_component) => Inbound::Log {
                request: LogRequest::from_data(&m),
                from,
            },
            _ => ignored,
        },
        LOG_REQUEST_END_DATA::ID => match frame.decode::<LOG_REQUEST_END_DATA>() {
            Some(m) if for_us(m.target_system, m.target_component) => Inbound::Log {
                request: LogRequest::End,
                from,
            },
            _ => ignored,
        },
        LOG_ERASE_DATA::ID => match frame.decode::<LOG_ERASE_DATA>() {
            Some(m) if for_us(m.target_system, m.target_component) => Inbound::Log {
                request: LogRequest::Erase,
                from,
            },
            _ => ignored,
        },
        SET_GPS_GLOBAL_ORIGIN_DATA::ID => {
            let [lat_e7, lon_e7, alt_mm, target] = set_origin(frame.payload());
            if for_us(target as u8, 0) {
                Inbound::SetOrigin {
                    lat_e7,
                    lon_e7,
                    alt_mm,
                    from,
                }
            } else {
                ignored
            }
        }
        // `SET_MODE` (deprecated, still what QGroundControl sends from its mode menu): the
        // mode in `custom_mode`, as `MAV_CMD_DO_SET_MODE` with PX4's numbers.
        SET_MODE_DATA::ID => {
            let p = frame.payload();
            let byte = |i: usize| p.get(i).copied().unwrap_or(0);
            let custom_mode = u32::from_le_bytes([byte(0), byte(1), byte(2), byte(3)]);
            if for_us(byte(4), 0) {
                Inbound::Command {
                    command: CommandId::of(crate::msg::MavCmd::MAV_CMD_DO_SET_MODE),
                    request: crate::command::mode_request(crate::modes::flight_mode(custom_mode)),
                    from,
                }
            } else {
                ignored
            }
        }
        HEARTBEAT_DATA::ID => {
            // `type` follows `custom_mode` (MAVLink 2 drops trailing zero bytes: absent is 0).
            let kind = frame.payload().get(HEARTBEAT_TYPE_OFFSET).copied();
            if kind == Some(MavType::MAV_TYPE_GCS as u8) && from.system != crate::VEHICLE_SYSTEM_ID
            {
                Inbound::GcsHeartbeat(from)
            } else {
                Inbound::Heartbeat(from)
            }
        }
        MANUAL_CONTROL_DATA::ID => match frame.decode::<MANUAL_CONTROL_DATA>() {
            Some(m) if m.target == crate::VEHICLE_SYSTEM_ID => Inbound::ManualControl {
                x: m.x,
                y: m.y,
                z: m.z,
                r: m.r,
                buttons: m.buttons,
                from,
            },
            _ => ignored,
        },
        BATTERY_STATUS_DATA::ID => {
            battery_volts(frame.payload()).map_or(ignored, |volts| Inbound::Battery { volts, from })
        }
        crate::msg::ESC_STATUS_DATA::ID => frame
            .decode::<crate::msg::ESC_STATUS_DATA>()
            .map_or(ignored, |m| {
                Inbound::EscStatus(crate::esc::EscRpmReport::from(&m))
            }),
        _ => ignored,
    }
}

/// `SET_GPS_GLOBAL_ORIGIN`'s latitude, longitude, altitude and target system from its
/// payload (MAVLink 2 drops trailing zero bytes: what is absent is 0).
fn set_origin(payload: &[u8]) -> [i32; 4] {
    let byte = |i: usize| payload.get(i).copied().unwrap_or(0);
    let int = |at: usize| i32::from_le_bytes([byte(at), byte(at + 1), byte(at + 2), byte(at + 3)]);
    [int(0), int(4), int(8), i32::from(byte(12))]
}

/// Offset of `HEARTBEAT`'s `type` in its payload.
const HEARTBEAT_TYPE_OFFSET: usize = 4;

/// A ground station's `HEARTBEAT` (type `MAV_TYPE_GCS`, autopilot `MAV_AUTOPILOT_INVALID`), as
/// QGroundControl sends it once a second; the HIL plant sends it as the simulated ground
/// station.
pub fn gcs_heartbeat() -> HEARTBEAT_DATA {
    HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        mavlink_version: 3,
        ..Default::default()
    }
}
