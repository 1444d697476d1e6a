//! The vehicle's dispatch tested over the wire: each message encoded as a ground station or
//! the plant sends it, parsed and dispatched.

use super::*;
use crate::command::{CommandWire, FORCE_DISARM_MAGIC, OperatorCommand, command_long};
use crate::frame::{Encoder, Parser};
use crate::ftp::Opcode;
use crate::msg::{MISSION_REQUEST_LIST_DATA, MavCmd};

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
            position: shared::control::vector::Vec3::new(1.0, 0.0, 0.0),
            attitude: shared::control::vector::Quat::IDENTITY,
        }))
    );
}

#[test]
#[allow(deprecated)] // SET_GPS_GLOBAL_ORIGIN's fields
fn each_service_gets_its_messages() {
    let s = PlantSample {
        time_us: 2500,
        ..PlantSample::AT_REST
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
    let mut bad = PlantSample::AT_REST.to_message();
    bad.xacc = f32::INFINITY;
    assert!(matches!(through_the_wire(&bad), Inbound::Invalid(_)));
    // A second IMU (extension field id = 1) is not the one the vehicle steps on.
    let mut enc = Encoder::new(crate::PLANT_SYSTEM_ID, crate::PLANT_COMPONENT_ID);
    let mut f = Frame::default();
    enc.encode_extended(&PlantSample::AT_REST.to_message(), &[1], &mut f);
    let mut p = Parser::new(crc_extra);
    let got = f
        .bytes()
        .iter()
        .find_map(|&b| p.push(b).map(|(fr, i)| dispatch(fr, i)));
    assert_eq!(got, Some(Inbound::Invalid(HilError::OtherSensor { id: 1 })));
}

#[test]
fn a_joystick_reaches_the_vehicle_and_another_vehicles_does_not() {
    let to_us = crate::msg::MANUAL_CONTROL_DATA {
        target: crate::VEHICLE_SYSTEM_ID,
        x: 250,
        y: -1000,
        z: 500,
        r: 7,
        buttons: 0b101,
    };
    match through_the_wire(&to_us) {
        Inbound::ManualControl {
            x,
            y,
            z,
            r,
            buttons,
            ..
        } => assert_eq!((x, y, z, r, buttons), (250, -1000, 500, 7, 0b101)),
        other => panic!("not taken as manual control: {other:?}"),
    }
    let elsewhere = crate::msg::MANUAL_CONTROL_DATA {
        target: crate::VEHICLE_SYSTEM_ID.wrapping_add(1),
        ..to_us
    };
    assert!(matches!(
        through_the_wire(&elsewhere),
        Inbound::Ignored { .. }
    ));
}
