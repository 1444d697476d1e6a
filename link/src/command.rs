//! The MAVLink command service (`COMMAND_LONG` or `COMMAND_INT`, answered by `COMMAND_ACK`) as
//! the vehicle reads it: which operator command a request is
//! (docs/ground-link.md#commands-long-or-int). Both messages are read into one [`Command`] and
//! classified here alone, so a command means the same whichever way it comes.
//!
//! | command | meaning |
//! |---|---|
//! | `MAV_CMD_MISSION_START` | [`OperatorCommand::Start`] the mission |
//! | `MAV_CMD_NAV_LAND` | [`OperatorCommand::LandNow`] |
//! | `MAV_CMD_DO_SET_MODE` with PX4's AUTO main mode (4) and a sub mode: MISSION (4), LOITER (3), LAND (6); or POSCTL (3) | [`OperatorCommand::Resume`], [`OperatorCommand::Hold`], [`OperatorCommand::LandNow`], [`OperatorCommand::Position`] ([`crate::modes`]); other modes `DENIED` |
//! | `MAV_CMD_DO_SET_STANDARD_MODE`: `MISSION`, `LAND`, `POSITION_HOLD` | [`OperatorCommand::Resume`], [`OperatorCommand::LandNow`], [`OperatorCommand::Position`]; other modes `DENIED` |
//! | `MAV_CMD_DO_PAUSE_CONTINUE`: param1 0, 1 | [`OperatorCommand::Hold`], [`OperatorCommand::Resume`] |
//! | `MAV_CMD_COMPONENT_ARM_DISARM`, param1 = 0 | [`OperatorCommand::Abort`] (the mission stops in a safe way) |
//! | the same with param2 = 21196 (forced), or `MAV_CMD_DO_FLIGHTTERMINATION` param1 > 0.5 | [`OperatorCommand::Kill`]: rotors off now |
//! | `MAV_CMD_REQUEST_MESSAGE` | [`Request::Message`] (the link answers it) |
//! | `MAV_CMD_GET_HOME_POSITION` (deprecated, MAVProxy's) | [`Request::Message`] of `HOME_POSITION` |
//! | `MAV_CMD_SET_MESSAGE_INTERVAL` | [`Request::SetInterval`] (the link's telemetry schedule) |
//! | `MAV_CMD_DO_SET_GLOBAL_ORIGIN` as `COMMAND_INT` in `MAV_FRAME_GLOBAL` (or its deprecated `_INT` twin) | [`Request::SetOrigin`]; as `COMMAND_LONG` refused `MAV_RESULT_COMMAND_INT_ONLY`, in another frame `MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME`, with an altitude not finite `DENIED` |
//! | [`CONFIRM_RAILS`] (`MAV_CMD_USER_1`, 31010), param1 = 1 | [`OperatorCommand::ConfirmRails`]: the robots stand at their start marks |
//! | [`JOG`] (`MAV_CMD_USER_2`, 31011): param1 the robot (from 1), param2 metres | [`OperatorCommand::Jog`] |
//! | `MAV_CMD_PREFLIGHT_CALIBRATION`: param1 = 1 the gyro, param5 = 2 the level | [`OperatorCommand::Calibrate`]; the other sensors `UNSUPPORTED` |
//! | `MAV_CMD_DO_MOTOR_TEST`: param1 the motor (from 1), param2 the throttle's type (0 percent, 1 PWM us), param3 the throttle, param4 the timeout (s), param5 the motor count | [`OperatorCommand::MotorTest`] |
//! | `MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN`, param1 = 1 | [`Request::Reboot`] |
//!
//! Arming by command is refused (the mission arms itself); any other command is unsupported.
//! The bring-up commands are docs/ground-link.md#bring-up-commands.

use crate::MessageData;
use crate::command_wire::{CommandAck, CommandId, CommandInt, CommandLong};
use crate::modes::FlightMode;
use crate::msg::{COMMAND_LONG_DATA, HOME_POSITION_DATA, MavCmd, MavFrame, MavResult};
pub use shared::mission::bringup::{CalibrationKind, MotorTestRequest};

/// A command as [`classify`] reads it, from a `COMMAND_LONG` or a `COMMAND_INT`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Command {
    /// The command's number.
    pub id: CommandId,
    /// Parameters 1 to 4 (the same in both messages).
    pub params: [f32; 4],
    /// Parameter 5: a `COMMAND_LONG`'s, or a `COMMAND_INT`'s `x` as a number (a count or a
    /// choice, never a position, for the commands that read it).
    pub param5: f32,
    /// A `COMMAND_INT`'s position (parameters 5 to 7 and the frame); `None` from a
    /// `COMMAND_LONG`, whose float parameters 5 and 6 cannot hold a latitude to a centimetre.
    pub position: Option<Position>,
}

/// Parameters 5 to 7 of a `COMMAND_INT` and their frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Position {
    /// `x`: in a global frame the latitude, 1e-7 degrees.
    pub x: i32,
    /// `y`: in a global frame the longitude, 1e-7 degrees.
    pub y: i32,
    /// `z`: in a global frame the altitude, m.
    pub z: f32,
    /// The frame (`MAV_FRAME`, as sent).
    pub frame: u8,
}

impl From<&CommandLong> for Command {
    fn from(c: &CommandLong) -> Self {
        let [p1, p2, p3, p4, ..] = c.params;
        Self {
            id: CommandId(c.command),
            params: [p1, p2, p3, p4],
            param5: c.params[4],
            position: None,
        }
    }
}

impl From<&CommandInt> for Command {
    fn from(c: &CommandInt) -> Self {
        Self {
            id: CommandId(c.command),
            params: c.params,
            param5: c.x as f32,
            position: Some(Position {
                x: c.x,
                y: c.y,
                z: c.z,
                frame: c.frame,
            }),
        }
    }
}

/// Whether `frame` is global with the altitude above mean sea level: `MAV_FRAME_GLOBAL` or
/// its deprecated twin `MAV_FRAME_GLOBAL_INT` (the same frame; older senders use it).
#[allow(deprecated)]
fn global_msl(frame: u8) -> bool {
    frame == MavFrame::MAV_FRAME_GLOBAL as u8 || frame == MavFrame::MAV_FRAME_GLOBAL_INT as u8
}

/// Metres to whole millimetres, rounded (saturating: an altitude far out of range stays out
/// of range). `m` must be finite.
fn millimetres(m: f32) -> i32 {
    let mm = m * 1000.0;
    (if mm < 0.0 { mm - 0.5 } else { mm + 0.5 }) as i32
}

/// `MAV_CMD_GET_HOME_POSITION`: superseded by `MAV_CMD_REQUEST_MESSAGE`, still what MAVProxy
/// sends every few seconds; answered as a request of `HOME_POSITION`.
#[allow(deprecated)]
pub const GET_HOME_POSITION: MavCmd = MavCmd::MAV_CMD_GET_HOME_POSITION;

/// Confirms the rail positions (`MAV_CMD_USER_1`, 31010; param1 = 1): the robots stand at
/// the payload description's start positions.
pub const CONFIRM_RAILS: MavCmd = MavCmd::MAV_CMD_USER_1;
/// Jogs a robot along the rail (`MAV_CMD_USER_2`, 31011): param1 the robot from 1, param2
/// metres.
pub const JOG: MavCmd = MavCmd::MAV_CMD_USER_2;
/// Longest jog, m (a check of direction and steps per metre, not a move of the formation).
pub const MAX_JOG: f32 = 1.0;

/// Magic number of a forced disarm (MAVLink `MAV_CMD_COMPONENT_ARM_DISARM`, param2).
pub const FORCE_DISARM_MAGIC: f32 = 21196.0;

/// What the operator asks of the mission: the mission's own command, which the link reads
/// from `COMMAND_LONG`/`COMMAND_INT` ([`classify`]) and writes ([`CommandWire`]).
pub use shared::mission::OperatorCommand;

/// An operator command as MAVLink carries it: the command a ground station sends for it, and
/// the one its acknowledgement names.
pub trait CommandWire: Copy {
    /// The MAVLink command it came as (for its acknowledgement).
    fn mav_cmd(self) -> MavCmd;
    /// The number of [`Self::mav_cmd`].
    fn command_id(self) -> CommandId {
        CommandId::of(self.mav_cmd())
    }
    /// The `COMMAND_LONG` a ground station sends for it (read back by [`classify`]).
    fn to_command_long(self) -> COMMAND_LONG_DATA;
}

impl CommandWire for OperatorCommand {
    fn mav_cmd(self) -> MavCmd {
        match self {
            Self::Start => MavCmd::MAV_CMD_MISSION_START,
            Self::Abort => MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            Self::LandNow => MavCmd::MAV_CMD_NAV_LAND,
            Self::Kill => MavCmd::MAV_CMD_DO_FLIGHTTERMINATION,
            Self::Hold | Self::Resume => MavCmd::MAV_CMD_DO_PAUSE_CONTINUE,
            Self::Position => MavCmd::MAV_CMD_DO_SET_MODE,
            Self::Calibrate(_) => MavCmd::MAV_CMD_PREFLIGHT_CALIBRATION,
            Self::MotorTest(_) => MavCmd::MAV_CMD_DO_MOTOR_TEST,
            Self::ConfirmRails => CONFIRM_RAILS,
            Self::Jog { .. } => JOG,
        }
    }

    fn to_command_long(self) -> COMMAND_LONG_DATA {
        match self {
            Self::Start => command_long(MavCmd::MAV_CMD_MISSION_START, 0.0, 0.0),
            Self::Abort => command_long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 0.0, 0.0),
            Self::LandNow => command_long(MavCmd::MAV_CMD_NAV_LAND, 0.0, 0.0),
            Self::Kill => command_long(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, 1.0, 0.0),
            Self::Hold => command_long(MavCmd::MAV_CMD_DO_PAUSE_CONTINUE, 0.0, 0.0),
            Self::Resume => command_long(MavCmd::MAV_CMD_DO_PAUSE_CONTINUE, 1.0, 0.0),
            // PX4's custom mode: MAV_MODE_FLAG_CUSTOM_MODE_ENABLED (1), main mode POSCTL (3).
            Self::Position => COMMAND_LONG_DATA {
                param3: 0.0,
                ..command_long(MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 3.0)
            },
            Self::ConfirmRails => command_long(CONFIRM_RAILS, 1.0, 0.0),
            Self::Jog { robot, micrometres } => {
                command_long(JOG, f32::from(robot), micrometres as f32 * 1e-6)
            }
            Self::Calibrate(CalibrationKind::Gyro) => {
                command_long(MavCmd::MAV_CMD_PREFLIGHT_CALIBRATION, 1.0, 0.0)
            }
            Self::Calibrate(CalibrationKind::Level) => COMMAND_LONG_DATA {
                param5: 2.0,
                ..command_long(MavCmd::MAV_CMD_PREFLIGHT_CALIBRATION, 0.0, 0.0)
            },
            Self::MotorTest(MotorTestRequest {
                first,
                count,
                permille,
                millis,
            }) => COMMAND_LONG_DATA {
                param3: f32::from(permille) * 0.1,
                param4: f32::from(millis) * 1e-3,
                param5: f32::from(count),
                ..command_long(MavCmd::MAV_CMD_DO_MOTOR_TEST, f32::from(first), 0.0)
            },
        }
    }
}

/// A received command, classified.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Request {
    /// For the mission; acknowledged once the mission has taken it.
    Operator(OperatorCommand),
    /// `MAV_CMD_REQUEST_MESSAGE` of this message id.
    Message(u32),
    /// `MAV_CMD_REQUEST_MESSAGE` of `AVAILABLE_MODES`: the mode of this index (from 1), or
    /// every mode (0).
    AvailableModes(u8),
    /// `MAV_CMD_SET_MESSAGE_INTERVAL`: param1 and param2 as sent (checked by
    /// [`crate::telemetry::Schedule::set_interval`]).
    SetInterval {
        /// The message id.
        message_id: f32,
        /// The interval, us (-1 off, 0 the default).
        interval_us: f32,
    },
    /// `MAV_CMD_DO_SET_GLOBAL_ORIGIN`: the map origin (docs/ground-link.md#the-map-origin),
    /// not yet checked, as `SET_GPS_GLOBAL_ORIGIN` gives it.
    SetOrigin {
        /// Latitude, 1e-7 degrees.
        lat_e7: i32,
        /// Longitude, 1e-7 degrees.
        lon_e7: i32,
        /// Altitude above mean sea level, mm.
        alt_mm: i32,
    },
    /// `MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN` with param1 = 1: restart the flight controller
    /// (refused while armed).
    Reboot,
    /// Refused at once with this result ([`refusal`] says why).
    Refused(MavResult),
}

/// What `command` (a `&CommandLong`, a `&CommandInt` or a [`Command`]) asks for.
pub fn classify(command: impl Into<Command>) -> Request {
    let command: Command = command.into();
    let id = command.id;
    let [param1, param2, ..] = command.params;
    if id.is(MavCmd::MAV_CMD_MISSION_START) {
        Request::Operator(OperatorCommand::Start)
    } else if id.is(MavCmd::MAV_CMD_NAV_LAND) {
        Request::Operator(OperatorCommand::LandNow)
    } else if id.is(MavCmd::MAV_CMD_DO_SET_MODE) {
        let [_, main, sub, _] = command.params;
        mode_request(FlightMode::from_px4(main, sub))
    } else if id.is(MavCmd::MAV_CMD_DO_SET_STANDARD_MODE) {
        mode_request(FlightMode::from_standard(param1))
    } else if id.is(MavCmd::MAV_CMD_DO_PAUSE_CONTINUE) && (param1 == 0.0 || param1 == 1.0) {
        Request::Operator(if param1 == 0.0 {
            OperatorCommand::Hold
        } else {
            OperatorCommand::Resume
        })
    } else if id.is(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION) && param1 > 0.5 {
        Request::Operator(OperatorCommand::Kill)
    } else if id.is(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM) {
        if param1 != 0.0 {
            Request::Refused(MavResult::MAV_RESULT_DENIED)
        } else if param2 == FORCE_DISARM_MAGIC {
            Request::Operator(OperatorCommand::Kill)
        } else {
            Request::Operator(OperatorCommand::Abort)
        }
    } else if id.is(MavCmd::MAV_CMD_REQUEST_MESSAGE)
        && param1 == crate::msg::AVAILABLE_MODES_DATA::ID as f32
    {
        let index = if param2.is_finite() && (0.0..=255.0).contains(&param2) {
            param2 as u8
        } else {
            0
        };
        Request::AvailableModes(index)
    } else if id.is(MavCmd::MAV_CMD_REQUEST_MESSAGE) && param1.is_finite() && param1 >= 0.0 {
        Request::Message(param1 as u32)
    } else if id.is(GET_HOME_POSITION) {
        Request::Message(HOME_POSITION_DATA::ID)
    } else if id.is(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL) {
        Request::SetInterval {
            message_id: param1,
            interval_us: param2,
        }
    } else if id.is(MavCmd::MAV_CMD_DO_SET_GLOBAL_ORIGIN) {
        match command.position {
            None => Request::Refused(MavResult::MAV_RESULT_COMMAND_INT_ONLY),
            Some(p) if !global_msl(p.frame) => {
                Request::Refused(MavResult::MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME)
            }
            Some(p) if !p.z.is_finite() => Request::Refused(MavResult::MAV_RESULT_DENIED),
            Some(p) => Request::SetOrigin {
                lat_e7: p.x,
                lon_e7: p.y,
                alt_mm: millimetres(p.z),
            },
        }
    } else {
        bench_request(&command)
    }
}

/// The bring-up commands (docs/ground-link.md#bring-up-commands), each checked for what it
/// can be before the mission sees it; anything else is unsupported.
fn bench_request(command: &Command) -> Request {
    let id = command.id;
    let [param1, param2, param3, param4] = command.params;
    let denied = Request::Refused(MavResult::MAV_RESULT_DENIED);
    if id.is(CONFIRM_RAILS) {
        if param1 == 1.0 {
            Request::Operator(OperatorCommand::ConfirmRails)
        } else {
            denied
        }
    } else if id.is(JOG) {
        let robot = whole(param1, 1.0, 255.0);
        match robot {
            Some(robot) if param2.is_finite() && param2.abs() <= MAX_JOG && param2 != 0.0 => {
                Request::Operator(OperatorCommand::Jog {
                    robot: robot as u8,
                    micrometres: (param2 * 1e6) as i32,
                })
            }
            _ => denied,
        }
    } else if id.is(MavCmd::MAV_CMD_PREFLIGHT_CALIBRATION) {
        // Param1 gyro, 2 magnetometer, 3 ground pressure, 4 radio, 5 accelerometer (1), level
        // (2), 6 compass/motor, 7 airspeed: this vehicle has the gyro and the level.
        let others = [param2, param3, param4].iter().any(|&p| p != 0.0);
        if param1 == 1.0 && !others && command.param5 == 0.0 {
            Request::Operator(OperatorCommand::Calibrate(CalibrationKind::Gyro))
        } else if param1 == 0.0 && !others && command.param5 == 2.0 {
            Request::Operator(OperatorCommand::Calibrate(CalibrationKind::Level))
        } else {
            Request::Refused(MavResult::MAV_RESULT_UNSUPPORTED)
        }
    } else if id.is(MavCmd::MAV_CMD_DO_MOTOR_TEST) {
        // Throttle type 0: percent; 1: a PWM pulse, 1000 to 2000 us.
        let command_fraction = match param2 {
            t if t == 0.0 && (0.0..=100.0).contains(&param3) => Some(param3 * 0.01),
            t if t == 1.0 && (1000.0..=2000.0).contains(&param3) => Some((param3 - 1000.0) * 1e-3),
            _ => None,
        };
        let motor = whole(param1, 1.0, 255.0);
        let count = if command.param5 == 0.0 {
            Some(1.0)
        } else {
            whole(command.param5, 1.0, 255.0)
        };
        match (motor, count, command_fraction) {
            (Some(motor), Some(count), Some(c)) if param4.is_finite() => {
                Request::Operator(OperatorCommand::MotorTest(MotorTestRequest {
                    first: motor as u8,
                    count: count as u8,
                    permille: (c * 1000.0 + 0.5) as u16,
                    millis: (param4.clamp(0.0, 60.0) * 1000.0) as u16,
                }))
            }
            _ => denied,
        }
    } else if id.is(MavCmd::MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN) {
        if param1 == 1.0 {
            Request::Reboot
        } else {
            Request::Refused(MavResult::MAV_RESULT_UNSUPPORTED)
        }
    } else {
        Request::Refused(MavResult::MAV_RESULT_UNSUPPORTED)
    }
}

/// `value` if it is a whole number within `[min, max]`.
fn whole(value: f32, min: f32, max: f32) -> Option<f32> {
    (value.is_finite() && value >= min && value <= max && value == (value as i32) as f32)
        .then_some(value)
}

/// The operator command that switches to `mode`: Ready is not commanded (the vehicle is in
/// it on the ground), and a mode the vehicle does not have is refused.
pub fn mode_request(mode: Option<FlightMode>) -> Request {
    match mode {
        Some(FlightMode::Mission) => Request::Operator(OperatorCommand::Resume),
        Some(FlightMode::Hold) => Request::Operator(OperatorCommand::Hold),
        Some(FlightMode::Land) => Request::Operator(OperatorCommand::LandNow),
        Some(FlightMode::Position) => Request::Operator(OperatorCommand::Position),
        Some(FlightMode::Ready) | None => Request::Refused(MavResult::MAV_RESULT_DENIED),
    }
}

/// Why [`classify`] refused `command` with `result` ([`Request::Refused`]), for the
/// `STATUSTEXT` that goes with the acknowledgement.
pub fn refusal(command: CommandId, result: MavResult) -> &'static str {
    match result {
        MavResult::MAV_RESULT_COMMAND_INT_ONLY => "send it as COMMAND_INT",
        MavResult::MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME => {
            "the frame must be MAV_FRAME_GLOBAL (altitude above mean sea level)"
        }
        _ if command.is(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM) => {
            "the mission arms the rotors itself, at take-off"
        }
        _ if command.is(MavCmd::MAV_CMD_DO_SET_GLOBAL_ORIGIN) => "the altitude is not a number",
        _ if command.is(CONFIRM_RAILS) => "confirm with param1 = 1",
        _ if command.is(JOG) => {
            "param1 the robot (from 1), param2 the distance in metres (not 0, at most 1 m either way)"
        }
        _ if command.is(MavCmd::MAV_CMD_PREFLIGHT_CALIBRATION) => {
            "this vehicle calibrates the gyro (param1 = 1) and the level (param5 = 2), one at a time"
        }
        _ if command.is(MavCmd::MAV_CMD_DO_MOTOR_TEST) => {
            "param1 the motor (from 1), param2 0 with param3 0-100 % or 1 with param3 1000-2000 us, param4 the timeout (s), param5 the count"
        }
        _ if command.is(MavCmd::MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN) => {
            "only a restart of the flight controller (param1 = 1)"
        }
        _ if command.is(MavCmd::MAV_CMD_DO_SET_MODE)
            || command.is(MavCmd::MAV_CMD_DO_SET_STANDARD_MODE) =>
        {
            "the modes are Mission, Hold, Land and Position (PX4's AUTO 4/4, 4/3, 4/6 and POSCTL 3)"
        }
        _ => "not supported",
    }
}

/// The acknowledgement of `command` with `result`.
pub fn ack(command: CommandId, result: MavResult) -> CommandAck {
    CommandAck { command, result }
}

/// A `COMMAND_LONG` of `command` to the vehicle with `param1` and `param2` (the ground side).
pub fn command_long(command: MavCmd, param1: f32, param2: f32) -> COMMAND_LONG_DATA {
    COMMAND_LONG_DATA {
        command,
        param1,
        param2,
        target_system: crate::VEHICLE_SYSTEM_ID,
        target_component: crate::VEHICLE_COMPONENT_ID,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::{MavlinkVersion, MessageData};

    /// What the vehicle reads of what a ground station sends (through the wire bytes).
    fn received(sent: &COMMAND_LONG_DATA) -> CommandLong {
        let mut bytes = [0u8; 255];
        let n = sent.ser(MavlinkVersion::V2, &mut bytes);
        CommandLong::deser(MavlinkVersion::V2, &bytes[..n]).expect("a COMMAND_LONG decodes")
    }

    fn classify(sent: &COMMAND_LONG_DATA) -> Request {
        super::classify(&received(sent))
    }

    #[test]
    fn each_operator_command_is_read_back_from_what_a_ground_station_sends() {
        for c in [
            OperatorCommand::Start,
            OperatorCommand::Abort,
            OperatorCommand::LandNow,
            OperatorCommand::Kill,
        ] {
            let sent = c.to_command_long();
            assert_eq!(classify(&sent), Request::Operator(c));
            assert_eq!(sent.command, c.mav_cmd());
        }
    }

    #[test]
    fn the_operator_commands_are_read_from_their_mavlink_commands() {
        let start = command_long(MavCmd::MAV_CMD_MISSION_START, 0.0, 0.0);
        assert_eq!(classify(&start), Request::Operator(OperatorCommand::Start));
        let land = command_long(MavCmd::MAV_CMD_NAV_LAND, 0.0, 0.0);
        assert_eq!(classify(&land), Request::Operator(OperatorCommand::LandNow));
        let disarm = command_long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 0.0, 0.0);
        assert_eq!(classify(&disarm), Request::Operator(OperatorCommand::Abort));
        let forced = command_long(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            0.0,
            FORCE_DISARM_MAGIC,
        );
        assert_eq!(classify(&forced), Request::Operator(OperatorCommand::Kill));
        let terminate = command_long(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, 1.0, 0.0);
        assert_eq!(
            classify(&terminate),
            Request::Operator(OperatorCommand::Kill)
        );
        for c in [
            OperatorCommand::Start,
            OperatorCommand::Abort,
            OperatorCommand::LandNow,
            OperatorCommand::Kill,
        ] {
            let again = command_long(c.mav_cmd(), 0.0, 0.0);
            // Kill by flight termination needs param1 = 1; the others come back as themselves.
            if c != OperatorCommand::Kill {
                assert_eq!(classify(&again), Request::Operator(c));
            }
        }
    }

    #[test]
    fn arming_and_unknown_commands_are_refused() {
        let arm = command_long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0);
        assert_eq!(
            classify(&arm),
            Request::Refused(MavResult::MAV_RESULT_DENIED)
        );
        let takeoff = command_long(MavCmd::MAV_CMD_NAV_TAKEOFF, 0.0, 0.0);
        assert_eq!(
            classify(&takeoff),
            Request::Refused(MavResult::MAV_RESULT_UNSUPPORTED)
        );
        let no_termination = command_long(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, 0.0, 0.0);
        assert_eq!(
            classify(&no_termination),
            Request::Refused(MavResult::MAV_RESULT_UNSUPPORTED)
        );
    }

    #[test]
    fn message_requests_carry_the_message_id() {
        let req = command_long(MavCmd::MAV_CMD_REQUEST_MESSAGE, 148.0, 0.0);
        assert_eq!(classify(&req), Request::Message(148));
        let home = command_long(GET_HOME_POSITION, 0.0, 0.0);
        assert_eq!(classify(&home), Request::Message(242));
        let rate = command_long(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, 31.0, 20_000.0);
        assert_eq!(
            classify(&rate),
            Request::SetInterval {
                message_id: 31.0,
                interval_us: 20_000.0
            }
        );
    }

    #[test]
    fn each_bring_up_command_is_read_back_from_what_a_ground_station_sends() {
        for c in [
            OperatorCommand::ConfirmRails,
            OperatorCommand::Jog {
                robot: 3,
                micrometres: -25_000,
            },
            OperatorCommand::Calibrate(CalibrationKind::Gyro),
            OperatorCommand::Calibrate(CalibrationKind::Level),
            OperatorCommand::MotorTest(MotorTestRequest {
                first: 2,
                count: 3,
                permille: 150,
                millis: 2_000,
            }),
        ] {
            assert_eq!(
                classify(&c.to_command_long()),
                Request::Operator(c),
                "{c:?}"
            );
        }
        assert_eq!(CONFIRM_RAILS as u32, 31010);
        assert_eq!(JOG as u32, 31011);
    }

    #[test]
    fn a_motor_test_reads_percent_or_pwm_and_refuses_the_rest() {
        let test = |p1: f32, p2: f32, p3: f32, p4: f32, p5: f32| {
            classify(&COMMAND_LONG_DATA {
                param3: p3,
                param4: p4,
                param5: p5,
                ..command_long(MavCmd::MAV_CMD_DO_MOTOR_TEST, p1, p2)
            })
        };
        // MAVProxy's `motortest 1 0 12 2`: motor 1 at 12 % for 2 s, the count left 0 (one).
        assert_eq!(
            test(1.0, 0.0, 12.0, 2.0, 0.0),
            Request::Operator(OperatorCommand::MotorTest(MotorTestRequest {
                first: 1,
                count: 1,
                permille: 120,
                millis: 2_000
            }))
        );
        // A 1150 us pulse is 15 %.
        assert_eq!(
            test(4.0, 1.0, 1150.0, 1.0, 1.0),
            Request::Operator(OperatorCommand::MotorTest(MotorTestRequest {
                first: 4,
                count: 1,
                permille: 150,
                millis: 1_000
            }))
        );
        let denied = Request::Refused(MavResult::MAV_RESULT_DENIED);
        assert_eq!(test(0.0, 0.0, 10.0, 1.0, 0.0), denied, "motor 0");
        assert_eq!(test(1.5, 0.0, 10.0, 1.0, 0.0), denied, "motor 1.5");
        assert_eq!(test(1.0, 0.0, 120.0, 1.0, 0.0), denied, "120 %");
        assert_eq!(test(1.0, 2.0, 10.0, 1.0, 0.0), denied, "pilot throttle");
        assert_eq!(test(1.0, 0.0, f32::NAN, 1.0, 0.0), denied, "NaN");
        assert_eq!(test(1.0, 0.0, 10.0, f32::INFINITY, 0.0), denied, "endless");
    }

    #[test]
    fn calibrations_jogs_and_reboots_outside_what_the_vehicle_does_are_refused() {
        let calibration = |p1: f32, p5: f32| {
            classify(&COMMAND_LONG_DATA {
                param5: p5,
                ..command_long(MavCmd::MAV_CMD_PREFLIGHT_CALIBRATION, p1, 0.0)
            })
        };
        let unsupported = Request::Refused(MavResult::MAV_RESULT_UNSUPPORTED);
        // The accelerometer's six-sided calibration, the magnetometer's, both at once.
        assert_eq!(calibration(0.0, 1.0), unsupported);
        assert_eq!(
            classify(&command_long(
                MavCmd::MAV_CMD_PREFLIGHT_CALIBRATION,
                0.0,
                1.0
            )),
            unsupported
        );
        assert_eq!(calibration(1.0, 2.0), unsupported);
        let denied = Request::Refused(MavResult::MAV_RESULT_DENIED);
        assert_eq!(classify(&command_long(JOG, 1.0, 0.0)), denied);
        assert_eq!(classify(&command_long(JOG, 1.0, 5.0)), denied);
        assert_eq!(classify(&command_long(JOG, 0.0, 0.1)), denied);
        assert_eq!(classify(&command_long(JOG, 2.0, f32::NAN)), denied);
        assert_eq!(classify(&command_long(CONFIRM_RAILS, 0.0, 0.0)), denied);
        let reboot = MavCmd::MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN;
        assert_eq!(classify(&command_long(reboot, 1.0, 0.0)), Request::Reboot);
        assert_eq!(classify(&command_long(reboot, 2.0, 0.0)), unsupported);
        assert_eq!(classify(&command_long(reboot, 3.0, 0.0)), unsupported);
    }
}
