//! The vehicle's dispatch of received frames: which of its services a frame is for, decoded and
//! checked (docs/ground-link.md; commands: #commands-long-or-int). Only the messages the
//! vehicle handles are decoded, so the
//! firmware links those decoders and no others (decoding the whole dialect costs ~80 KB).

use mavlink::MessageData;

use crate::command::{Request, classify};
use crate::command_wire::{CommandId, CommandInt, CommandLong};
use crate::frame::{Frame, Integrity};
use crate::ftp::{FtpMessage, PAYLOAD_LEN};
use crate::hil::{HilError, ImuSample, MocapFix};
use crate::log_transfer::LogRequest;
use crate::mission::wire::MissionMessage;
use crate::msg::{
    ACTUATOR_OUTPUT_STATUS_DATA, ATT_POS_MOCAP_DATA, ATTITUDE_QUATERNION_DATA,
    AUTOPILOT_VERSION_DATA, BATTERY_STATUS_DATA, COMMAND_ACK_DATA, COMMAND_INT_DATA,
    COMMAND_LONG_DATA, DEBUG_FLOAT_ARRAY_DATA, FILE_TRANSFER_PROTOCOL_DATA,
    GLOBAL_POSITION_INT_DATA, GPS_GLOBAL_ORIGIN_DATA, HEARTBEAT_DATA, HIL_ACTUATOR_CONTROLS_DATA,
    HIL_SENSOR_DATA, HOME_POSITION_DATA, LOCAL_POSITION_NED_DATA, LOG_DATA_DATA, LOG_ENTRY_DATA,
    LOG_ERASE_DATA, LOG_REQUEST_DATA_DATA, LOG_REQUEST_END_DATA, LOG_REQUEST_LIST_DATA,
    MISSION_COUNT_DATA, MISSION_REQUEST_LIST_DATA, MavAutopilot, MavBatteryFunction, MavType,
    NAMED_VALUE_FLOAT_DATA, NAMED_VALUE_INT_DATA, ODOMETRY_DATA, PARAM_REQUEST_LIST_DATA,
    PARAM_REQUEST_READ_DATA, PARAM_SET_DATA, PARAM_VALUE_DATA, SETUP_SIGNING_DATA, STATUSTEXT_DATA,
    SYS_STATUS_DATA, TIMESYNC_DATA,
};
use crate::param::ParamRequest;

/// `SET_GPS_GLOBAL_ORIGIN`: superseded (2025) by `MAV_CMD_DO_SET_GLOBAL_ORIGIN`, which needs
/// `COMMAND_INT`; still what pymavlink scripts and MAVROS send.
/// Read from its payload's bytes ([`set_origin`]), its fields being deprecated.
#[allow(deprecated, non_camel_case_types)]
type SET_GPS_GLOBAL_ORIGIN_DATA = crate::msg::SET_GPS_GLOBAL_ORIGIN_DATA;
/// `SET_MODE`: deprecated (2015) for `MAV_CMD_DO_SET_MODE`, still QGroundControl's.
#[allow(deprecated, non_camel_case_types)]
type SET_MODE_DATA = crate::msg::SET_MODE_DATA;
/// `MISSION_REQUEST` and `MISSION_SET_CURRENT`: deprecated, still sent by older tools
/// (read by [`crate::mission::wire`]).
#[allow(deprecated, non_camel_case_types)]
type MISSION_REQUEST_DATA = crate::msg::MISSION_REQUEST_DATA;
#[allow(deprecated, non_camel_case_types)]
type MISSION_SET_CURRENT_DATA = crate::msg::MISSION_SET_CURRENT_DATA;

macro_rules! crc_extras {
    ($($m:ty),* $(,)?) => {
        /// `CRC_EXTRA` of the messages this link speaks (either direction), `None` for others.
        pub fn crc_extra(id: u32) -> Option<u8> {
            match id {
                $(<$m>::ID => Some(<$m>::EXTRA_CRC),)*
                _ => None,
            }
        }
    };
}

crc_extras!(
    HEARTBEAT_DATA,
    COMMAND_LONG_DATA,
    COMMAND_INT_DATA,
    COMMAND_ACK_DATA,
    STATUSTEXT_DATA,
    NAMED_VALUE_FLOAT_DATA,
    NAMED_VALUE_INT_DATA,
    HIL_SENSOR_DATA,
    ATT_POS_MOCAP_DATA,
    HIL_ACTUATOR_CONTROLS_DATA,
    ACTUATOR_OUTPUT_STATUS_DATA,
    FILE_TRANSFER_PROTOCOL_DATA,
    AUTOPILOT_VERSION_DATA,
    PARAM_REQUEST_LIST_DATA,
    PARAM_REQUEST_READ_DATA,
    PARAM_SET_DATA,
    PARAM_VALUE_DATA,
    MISSION_REQUEST_LIST_DATA,
    MISSION_COUNT_DATA,
    crate::msg::MISSION_ITEM_INT_DATA,
    crate::msg::MISSION_REQUEST_INT_DATA,
    MISSION_REQUEST_DATA,
    crate::msg::MISSION_ACK_DATA,
    crate::msg::MISSION_CLEAR_ALL_DATA,
    MISSION_SET_CURRENT_DATA,
    crate::msg::MISSION_CURRENT_DATA,
    crate::msg::MISSION_ITEM_REACHED_DATA,
    crate::msg::AVAILABLE_MODES_DATA,
    crate::msg::CURRENT_MODE_DATA,
    crate::msg::EXTENDED_SYS_STATE_DATA,
    SET_MODE_DATA,
    SYS_STATUS_DATA,
    ATTITUDE_QUATERNION_DATA,
    LOCAL_POSITION_NED_DATA,
    ODOMETRY_DATA,
    TIMESYNC_DATA,
    SETUP_SIGNING_DATA,
    DEBUG_FLOAT_ARRAY_DATA,
    BATTERY_STATUS_DATA,
    crate::msg::ESC_STATUS_DATA,
    crate::msg::ESC_INFO_DATA,
    LOG_REQUEST_LIST_DATA,
    LOG_ENTRY_DATA,
    LOG_REQUEST_DATA_DATA,
    LOG_DATA_DATA,
    LOG_ERASE_DATA,
    LOG_REQUEST_END_DATA,
    GLOBAL_POSITION_INT_DATA,
    HOME_POSITION_DATA,
    GPS_GLOBAL_ORIGIN_DATA,
    SET_GPS_GLOBAL_ORIGIN_DATA,
    crate::msg::COMPONENT_METADATA_DATA,
);

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
    Sensor(ImuSample),
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
            match ImuSample::from_message(&m, sensor_id) {
                Ok(s) => Inbound::Sensor(s),
                Err(e) => Inbound::Invalid(e),
            }
        }),
        ATT_POS_MOCAP_DATA::ID => frame.decode::<ATT_POS_MOCAP_DATA>().map_or(ignored, |m| {
            match MocapFix::from_message(&m) {
                Ok(f) => Inbound::Mocap(f),
                Err(e) => Inbound::Invalid(e),
            }
        }),
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
/// Offset of `BATTERY_STATUS`'s `voltages` in its payload (after two `int32` and an `int16`).
const BATTERY_VOLTAGES_OFFSET: usize = 10;

/// The pack voltage of a `BATTERY_STATUS` payload, V, as MAVLink puts it: the whole pack in
/// `voltages[0]` (mV) when the cells are not measured, continued in `voltages[1]` when it
/// reaches 65,534 mV; with cells measured, their sum. `None` when no voltage is given.
pub fn battery_volts(payload: &[u8]) -> Option<f32> {
    let cell = |i: usize| {
        let at = BATTERY_VOLTAGES_OFFSET + 2 * i;
        // Trailing zero bytes dropped by MAVLink 2 read as zero.
        let lo = payload.get(at).copied().unwrap_or(0);
        let hi = payload.get(at + 1).copied().unwrap_or(0);
        u16::from_le_bytes([lo, hi])
    };
    let first = cell(0);
    if first == u16::MAX {
        return None;
    }
    let mut millivolts = u32::from(first);
    // The pack beyond 65,534 mV, or the other cells: summed until the first unused one.
    for i in 1..10 {
        let c = cell(i);
        if c == u16::MAX || (c == 0 && first != u16::MAX - 1) {
            break;
        }
        millivolts += u32::from(c);
    }
    Some(millivolts as f32 * 1e-3)
}

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

/// `BATTERY_STATUS` of a pack at `volts` whose cells are not measured (the whole pack in
/// `voltages[0]`, the others unused), as the HIL plant reports its simulated pack.
pub fn battery_status(volts: f32) -> BATTERY_STATUS_DATA {
    let mv = volts * 1000.0;
    // Not a number: 0; below zero: 0 (`as` saturates); above: the largest pack entry.
    let millivolts = if mv.is_nan() {
        0
    } else {
        mv.min(65_534.0) as u16
    };
    let mut voltages = [u16::MAX; 10];
    voltages[0] = millivolts;
    BATTERY_STATUS_DATA {
        voltages,
        current_consumed: -1,
        energy_consumed: -1,
        temperature: i16::MAX,
        current_battery: -1,
        battery_remaining: -1,
        battery_function: MavBatteryFunction::MAV_BATTERY_FUNCTION_ALL,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::{FORCE_DISARM_MAGIC, OperatorCommand, command_long};
    use crate::frame::{Encoder, Parser};
    use crate::ftp::Opcode;
    use crate::msg::MavCmd;

    fn through_the_wire<M: MessageData>(m: &M) -> Inbound {
        let mut enc = Encoder::new(crate::PLANT_SYSTEM_ID, crate::PLANT_COMPONENT_ID);
        let mut f = Frame::default();
        enc.encode(m, &mut f);
        let mut p = Parser::new(crc_extra);
        let mut out = None;
        for &b in f.bytes() {
            if let Some((frame, integrity)) = p.push(b) {
                out = Some(dispatch(frame, integrity));
            }
        }
        out.expect("one frame")
    }

    #[test]
    fn a_command_the_dialect_does_not_list_is_refused_with_its_number() {
        let unknown = CommandLong {
            command: 0xfffe,
            target_system: crate::VEHICLE_SYSTEM_ID,
            ..Default::default()
        };
        assert_eq!(
            through_the_wire(&unknown),
            Inbound::Command {
                command: CommandId(0xfffe),
                request: Request::Refused(crate::msg::MavResult::MAV_RESULT_UNSUPPORTED),
                from: Sender {
                    system: crate::PLANT_SYSTEM_ID,
                    component: crate::PLANT_COMPONENT_ID,
                },
            }
        );
    }

    /// The `COMMAND_INT` a ground station sends for `long`'s command and parameters 1 to 4
    /// (pymavlink's `command_int_send`).
    fn as_command_int(long: &crate::msg::COMMAND_LONG_DATA, frame: u8) -> CommandInt {
        CommandInt {
            params: [long.param1, long.param2, long.param3, long.param4],
            x: 0,
            y: 0,
            z: 0.0,
            command: long.command as u16,
            target_system: long.target_system,
            target_component: long.target_component,
            frame,
            ..Default::default()
        }
    }

    #[test]
    fn command_int_is_read_as_command_long_is() {
        let mut sent = std::vec![
            OperatorCommand::Start.to_command_long(),
            OperatorCommand::Abort.to_command_long(),
            OperatorCommand::LandNow.to_command_long(),
            OperatorCommand::Kill.to_command_long(),
            command_long(
                MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                0.0,
                FORCE_DISARM_MAGIC
            ),
            command_long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0),
            command_long(MavCmd::MAV_CMD_REQUEST_MESSAGE, 148.0, 0.0),
            command_long(MavCmd::MAV_CMD_REQUEST_MESSAGE, 49.0, 0.0),
            command_long(crate::command::GET_HOME_POSITION, 0.0, 0.0),
            command_long(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, 31.0, 20_000.0),
            command_long(MavCmd::MAV_CMD_NAV_TAKEOFF, 0.0, 0.0),
            command_long(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, 0.0, 0.0),
            // Hostile: parameters not numbers, infinite, negative.
            command_long(MavCmd::MAV_CMD_REQUEST_MESSAGE, f32::NAN, 0.0),
            command_long(MavCmd::MAV_CMD_REQUEST_MESSAGE, -1.0, 0.0),
            command_long(MavCmd::MAV_CMD_REQUEST_MESSAGE, f32::INFINITY, 0.0),
            command_long(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, f32::NAN, 0.0),
            command_long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, f32::NAN, f32::NAN),
            command_long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 0.0, f32::NAN),
            command_long(
                MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
                f32::NAN,
                f32::NEG_INFINITY
            ),
        ];
        // Addressed to every system, to another one, to another component.
        let mut anyone = command_long(MavCmd::MAV_CMD_MISSION_START, 0.0, 0.0);
        anyone.target_system = 0;
        anyone.target_component = 0;
        sent.push(anyone.clone());
        sent.push(crate::msg::COMMAND_LONG_DATA {
            target_system: 42,
            ..anyone.clone()
        });
        sent.push(crate::msg::COMMAND_LONG_DATA {
            target_component: 7,
            ..anyone
        });
        // The frame does not matter to a command without a position: any, also one the
        // dialect does not list.
        for frame in [0, 1, 6, 200, 255] {
            for long in &sent {
                let int = as_command_int(long, frame);
                let (got, want) = (through_the_wire(&int), through_the_wire(long));
                if let Inbound::Ignored { id } = got {
                    // Not for this vehicle: ignored as the COMMAND_LONG is.
                    assert_eq!(id, CommandInt::ID);
                    assert_eq!(
                        want,
                        Inbound::Ignored {
                            id: CommandLong::ID
                        },
                        "{long:?}"
                    );
                } else {
                    // NaN parameters make `Request` unequal to itself: compare its debug text.
                    assert_eq!(
                        std::format!("{got:?}"),
                        std::format!("{want:?}"),
                        "{long:?}"
                    );
                }
            }
        }
        // A command the dialect does not list: unsupported, with its number.
        let unknown = CommandInt {
            command: 0xfffe,
            target_system: crate::VEHICLE_SYSTEM_ID,
            frame: 0xee,
            ..Default::default()
        };
        assert!(matches!(
            through_the_wire(&unknown),
            Inbound::Command {
                command: CommandId(0xfffe),
                request: Request::Refused(crate::msg::MavResult::MAV_RESULT_UNSUPPORTED),
                ..
            }
        ));
    }

    #[test]
    fn the_map_origin_comes_as_command_int_in_a_global_frame() {
        let origin = CommandInt {
            x: -338_688_123,
            y: 1_512_093_456,
            z: 58.25,
            command: MavCmd::MAV_CMD_DO_SET_GLOBAL_ORIGIN as u16,
            target_system: 1,
            target_component: 1,
            frame: crate::msg::MavFrame::MAV_FRAME_GLOBAL as u8,
            ..Default::default()
        };
        let set = Request::SetOrigin {
            lat_e7: -338_688_123,
            lon_e7: 1_512_093_456,
            alt_mm: 58_250,
        };
        assert!(matches!(
            through_the_wire(&origin),
            Inbound::Command { request, .. } if request == set
        ));
        let refused = |c: &CommandInt| match through_the_wire(c) {
            Inbound::Command {
                request: Request::Refused(r),
                ..
            } => Some(r),
            _ => None,
        };
        use crate::msg::MavResult;
        // Altitude above the ground or the terrain, a local frame, a frame nobody knows.
        for frame in [3, 10, 1, 0xee] {
            assert_eq!(
                refused(&CommandInt { frame, ..origin }),
                Some(MavResult::MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME)
            );
        }
        for z in [f32::NAN, f32::INFINITY] {
            assert_eq!(
                refused(&CommandInt { z, ..origin }),
                Some(MavResult::MAV_RESULT_DENIED)
            );
        }
        // Out of range is the origin's checks' to refuse (with the reason): taken as sent.
        let far = CommandInt {
            x: i32::MAX,
            z: -1e30,
            ..origin
        };
        assert!(matches!(
            through_the_wire(&far),
            Inbound::Command {
                request: Request::SetOrigin {
                    lat_e7: i32::MAX,
                    alt_mm: i32::MIN,
                    ..
                },
                ..
            }
        ));
        // As COMMAND_LONG its float latitude would lose a metre: refused.
        let long = command_long(MavCmd::MAV_CMD_DO_SET_GLOBAL_ORIGIN, 0.0, 0.0);
        assert!(matches!(
            through_the_wire(&long),
            Inbound::Command {
                request: Request::Refused(MavResult::MAV_RESULT_COMMAND_INT_ONLY),
                ..
            }
        ));
        // Another vehicle's origin is not this one's.
        let other = CommandInt {
            target_system: 9,
            ..origin
        };
        assert!(matches!(through_the_wire(&other), Inbound::Ignored { .. }));
    }

    #[test]
    fn time_sync_and_motion_capture_odometry_reach_the_vehicle() {
        let request = TIMESYNC_DATA { tc1: 0, ts1: 42 };
        assert_eq!(
            through_the_wire(&request),
            Inbound::TimeSync { tc1: 0, ts1: 42 }
        );
        let odometry = ODOMETRY_DATA {
            time_usec: 77,
            x: 1.0,
            q: [1.0, 0.0, 0.0, 0.0],
            frame_id: crate::msg::MavFrame::MAV_FRAME_LOCAL_NED,
            ..Default::default()
        };
        let mocap = crate::msg::MavEstimatorType::MAV_ESTIMATOR_TYPE_MOCAP as u8;
        let mut f = Frame::default();
        Encoder::new(crate::PLANT_SYSTEM_ID, crate::PLANT_COMPONENT_ID).encode_extended(
            &odometry,
            &[0, mocap],
            &mut f,
        );
        let mut p = Parser::new(crc_extra);
        let mut got = None;
        for &b in f.bytes() {
            if let Some((frame, integrity)) = p.push(b) {
                got = Some(dispatch(frame, integrity));
            }
        }
        assert_eq!(
            got,
            Some(Inbound::Mocap(MocapFix {
                stamp_us: 77,
                position: [1.0, 0.0, 0.0],
                attitude: [1.0, 0.0, 0.0, 0.0],
            }))
        );
    }

    #[test]
    #[allow(deprecated)] // SET_GPS_GLOBAL_ORIGIN's fields
    fn each_service_gets_its_messages() {
        let s = ImuSample {
            time_us: 2500,
            gyro: [0.0; 3],
            accel: [0.0, 0.0, -9.81],
        };
        assert_eq!(through_the_wire(&s.to_message()), Inbound::Sensor(s));
        let start = command_long(MavCmd::MAV_CMD_MISSION_START, 0.0, 0.0);
        assert!(matches!(
            through_the_wire(&start),
            Inbound::Command {
                request: Request::Operator(OperatorCommand::Start),
                from: Sender {
                    system: 255,
                    component: 190
                },
                ..
            }
        ));
        let ftp = FtpMessage::command(3, Opcode::ResetSessions).to_message(1, 1);
        assert!(matches!(through_the_wire(&ftp), Inbound::Ftp { message, .. } if message.seq == 3));
        let list = PARAM_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
        };
        assert!(matches!(
            through_the_wire(&list),
            Inbound::Param {
                request: ParamRequest::List,
                ..
            }
        ));
        let read = PARAM_REQUEST_READ_DATA {
            param_index: -1,
            target_system: 1,
            target_component: 0,
            param_id: "MAX_TILT".into(),
        };
        let mut name = [0u8; 16];
        name[..8].copy_from_slice(b"MAX_TILT");
        assert_eq!(
            through_the_wire(&read),
            Inbound::Param {
                request: ParamRequest::ReadName(name),
                from: Sender {
                    system: 255,
                    component: 190
                }
            }
        );
        let set = PARAM_SET_DATA {
            param_value: 0.25,
            target_system: 1,
            target_component: 1,
            param_id: "MAX_TILT".into(),
            param_type: crate::msg::MavParamType::MAV_PARAM_TYPE_REAL32,
        };
        assert!(matches!(
            through_the_wire(&set),
            Inbound::Param {
                request: ParamRequest::Set { value, .. },
                ..
            } if value == 0.25
        ));
        let missions = MISSION_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
        };
        assert!(matches!(
            through_the_wire(&missions),
            Inbound::Mission {
                message: MissionMessage::RequestList { mission_type: 0 },
                ..
            }
        ));
        #[allow(deprecated)]
        let hold = crate::msg::SET_MODE_DATA {
            custom_mode: crate::modes::FlightMode::Hold.px4_custom_mode(),
            target_system: 1,
            base_mode: crate::msg::MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
        };
        assert!(matches!(
            through_the_wire(&hold),
            Inbound::Command {
                request: Request::Operator(OperatorCommand::Hold),
                ..
            }
        ));
        let origin = SET_GPS_GLOBAL_ORIGIN_DATA {
            latitude: -338_688_000,
            longitude: 1_512_093_000,
            altitude: 58_000,
            target_system: 1,
        };
        assert!(matches!(
            through_the_wire(&origin),
            Inbound::SetOrigin {
                lat_e7: -338_688_000,
                lon_e7: 1_512_093_000,
                alt_mm: 58_000,
                ..
            }
        ));
        let elsewhere = SET_GPS_GLOBAL_ORIGIN_DATA {
            target_system: 7,
            ..origin
        };
        assert!(matches!(
            through_the_wire(&elsewhere),
            Inbound::Ignored { .. }
        ));
    }

    #[test]
    fn log_requests_reach_the_log_service() {
        let from = Sender {
            system: crate::PLANT_SYSTEM_ID,
            component: crate::PLANT_COMPONENT_ID,
        };
        let list = LOG_REQUEST_LIST_DATA {
            start: 0,
            end: 0xFFFF,
            target_system: 1,
            target_component: 1,
        };
        assert_eq!(
            through_the_wire(&list),
            Inbound::Log {
                request: LogRequest::List {
                    start: 0,
                    end: 0xFFFF
                },
                from
            }
        );
        let data = LOG_REQUEST_DATA_DATA {
            ofs: 900,
            count: u32::MAX,
            id: 3,
            target_system: 1,
            target_component: 0,
        };
        assert_eq!(
            through_the_wire(&data),
            Inbound::Log {
                request: LogRequest::Data {
                    id: 3,
                    ofs: 900,
                    count: u32::MAX
                },
                from
            }
        );
        let end = LOG_REQUEST_END_DATA {
            target_system: 1,
            target_component: 1,
        };
        assert!(matches!(
            through_the_wire(&end),
            Inbound::Log {
                request: LogRequest::End,
                ..
            }
        ));
        let erase = LOG_ERASE_DATA {
            target_system: 1,
            target_component: 1,
        };
        assert!(matches!(
            through_the_wire(&erase),
            Inbound::Log {
                request: LogRequest::Erase,
                ..
            }
        ));
        // Another vehicle's erase is not this one's.
        let other = LOG_ERASE_DATA {
            target_system: 2,
            target_component: 1,
        };
        assert!(matches!(through_the_wire(&other), Inbound::Ignored { .. }));
    }

    #[test]
    fn a_ground_stations_heartbeat_is_told_from_others() {
        let from_plant = Sender {
            system: crate::PLANT_SYSTEM_ID,
            component: crate::PLANT_COMPONENT_ID,
        };
        assert_eq!(
            through_the_wire(&gcs_heartbeat()),
            Inbound::GcsHeartbeat(from_plant)
        );
        // A vehicle's heartbeat (a quadrotor's, an onboard computer's) is not a link.
        let other = HEARTBEAT_DATA {
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            ..gcs_heartbeat()
        };
        assert_eq!(through_the_wire(&other), Inbound::Heartbeat(from_plant));
        // Nor is a GCS-typed heartbeat from the vehicle's own system (an echo).
        let mut f = Frame::default();
        Encoder::new(crate::VEHICLE_SYSTEM_ID, 191).encode(&gcs_heartbeat(), &mut f);
        let mut p = Parser::new(crc_extra);
        let got = f
            .bytes()
            .iter()
            .find_map(|&b| p.push(b).map(|(fr, i)| dispatch(fr, i)));
        assert!(matches!(got, Some(Inbound::Heartbeat(_))), "{got:?}");
    }

    #[test]
    fn a_packs_voltage_comes_through_battery_status() {
        let got = through_the_wire(&battery_status(15.734));
        assert!(
            matches!(got, Inbound::Battery { volts, .. } if (volts - 15.734).abs() < 1e-3),
            "{got:?}"
        );
        // Cells measured: their sum.
        let mut cells = battery_status(0.0);
        cells.voltages = [4100, 4050, 4000, 3950, u16::MAX, 0, 0, 0, 0, 0];
        let near = |got: Option<f32>, want: f32| got.is_some_and(|v| (v - want).abs() < 1e-3);
        assert!(near(battery_volts(&payload_of(&cells)), 16.1));
        // A pack above 65.534 V continues in the second entry.
        cells.voltages = [65_534, 1_000, u16::MAX, 0, 0, 0, 0, 0, 0, 0];
        assert!(near(battery_volts(&payload_of(&cells)), 66.534));
        // No voltage, or a payload cut short: nothing, or zero volts.
        cells.voltages = [u16::MAX; 10];
        assert_eq!(battery_volts(&payload_of(&cells)), None);
        assert_eq!(battery_volts(&[0u8; 4]), Some(0.0));
        assert_eq!(battery_status(f32::NAN).voltages[0], 0);
        assert_eq!(battery_status(1e9).voltages[0], 65_534);
    }

    /// A message's payload as it goes on the wire.
    fn payload_of<M: MessageData>(m: &M) -> std::vec::Vec<u8> {
        let mut f = Frame::default();
        Encoder::new(crate::PLANT_SYSTEM_ID, crate::PLANT_COMPONENT_ID).encode(m, &mut f);
        f.payload().to_vec()
    }

    #[test]
    fn commands_for_other_vehicles_and_bad_sensor_data_are_not_acted_on() {
        let mut start = command_long(MavCmd::MAV_CMD_MISSION_START, 0.0, 0.0);
        start.target_system = 42;
        assert!(matches!(through_the_wire(&start), Inbound::Ignored { .. }));
        let mut bad = ImuSample::default().to_message();
        bad.xacc = f32::INFINITY;
        assert!(matches!(through_the_wire(&bad), Inbound::Invalid(_)));
        // A second IMU (extension field id = 1) is not the one the vehicle steps on.
        let mut enc = Encoder::new(crate::PLANT_SYSTEM_ID, crate::PLANT_COMPONENT_ID);
        let mut f = Frame::default();
        enc.encode_extended(&ImuSample::default().to_message(), &[1], &mut f);
        let mut p = Parser::new(crc_extra);
        let got = f
            .bytes()
            .iter()
            .find_map(|&b| p.push(b).map(|(fr, i)| dispatch(fr, i)));
        assert_eq!(got, Some(Inbound::Invalid(HilError::OtherSensor { id: 1 })));
    }
}
