//! What the link's receive service hands the rest of the vehicle, and what the send task
//! sends (docs/ground-link.md#under-a-flood): the replies and bulk transfers the receive side
//! queues, a control step's messages, the samples and commands for the control task, and a
//! checked payload description for the job task.

use link::command_wire::CommandId;
use link::ftp::FtpMessage;
use link::hil::{Actuators, ImuSample};
use link::log_transfer::LogReply;
use link::mission::Peer;
use link::mission::wire::MissionReply;
use link::msg::{MavResult, MavSeverity};
use link::status::MissionState;
use link::vehicle::Sender;
use shared::scenario::Scenario;
use shared::scenario_wire::MAX_NAME_LEN;

use crate::autonomy::{CommandResult, OperatorCommand, Report, Severity};

/// An IMU sample for the control task.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorSample {
    /// The vehicle's time of the sample, us (in HIL the plant's).
    pub time_us: u64,
    /// The sample.
    pub imu: ImuSample,
    /// It came from the HIL plant (the step's reply goes back to it).
    pub hil: bool,
}

/// An operator command waiting for the autonomy, with what its acknowledgement needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PendingCommand {
    /// The command.
    pub command: OperatorCommand,
    /// The MAVLink command it came as.
    pub mav_cmd: CommandId,
    /// Who sent it.
    pub from: Sender,
}

/// One control step's messages, sent before anything else queued (in HIL the plant waits for
/// them).
#[derive(Clone, Debug, PartialEq)]
pub struct StepMessages {
    /// The vehicle's time of the step, us.
    pub time_us: u64,
    /// Texts and values.
    pub report: Report,
    /// The step's command and how it was taken.
    pub ack: Option<(PendingCommand, CommandResult)>,
    /// A command begun earlier (a calibration) that ended this step, and how.
    pub done: Option<(PendingCommand, CommandResult)>,
    /// The mission state after the step.
    pub state: MissionState,
    /// In HIL: the actuator commands for the plant.
    pub actuators: Option<Actuators>,
}

/// Replies, texts and values the send task sends after a step's messages and the heartbeat.
// A report is 728 bytes, the other replies a few: the queue holds four, and no_std has no box.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Outbound {
    /// Texts and values outside a step.
    Report(Report),
    /// A command's acknowledgement decided by the link itself.
    Ack {
        /// The command.
        command: CommandId,
        /// The result.
        result: MavResult,
    },
    /// `AUTOPILOT_VERSION` and the board's name, on request.
    Identity,
    /// `COMPONENT_METADATA` (where the general metadata file is), on request.
    ComponentMetadata,
    /// The `PARAM_VALUE`s of these indices (the values a request changed go as one entry),
    /// from the values in force.
    Params(ParamBits),
    /// `TIMESYNC`: an answer to a request.
    TimeSync {
        /// The vehicle's time, ns.
        tc1: i64,
        /// The request's time.
        ts1: i64,
    },
    /// `AVAILABLE_MODES`: the mode of this index (from 1), or every mode (0).
    AvailableModes(u8),
    /// `CURRENT_MODE`, on request.
    CurrentMode,
    /// `GPS_GLOBAL_ORIGIN`, the map origin in force (at start, set, or asked for).
    Origin,
    /// `HOME_POSITION`, on request.
    Home,
}

/// A bulk transfer's message: sent when nothing else waits and the link has room.
#[derive(Clone, Debug, PartialEq)]
pub enum Bulk {
    /// An FTP answer.
    Ftp {
        /// The answer.
        message: FtpMessage,
        /// To whom.
        to: Sender,
    },
    /// A mission-protocol reply.
    Mission {
        /// The reply.
        reply: MissionReply,
        /// To whom (system, component).
        to: Peer,
    },
    /// A log-protocol answer (`LOG_ENTRY`, `LOG_DATA`), from the logger task.
    Log(LogReply),
}

/// A payload description that passed the checks, on its way to the planner.
#[derive(Clone, Debug, PartialEq)]
pub struct Received {
    /// Its name.
    pub name: heapless::String<MAX_NAME_LEN>,
    /// The checked description.
    pub scenario: Scenario,
}

/// A report of one text line, ready for the send task.
pub fn report(severity: Severity, args: core::fmt::Arguments<'_>) -> Outbound {
    let mut r = Report::default();
    r.text(severity, args);
    Outbound::Report(r)
}

/// A text's MAVLink severity.
pub fn mav_severity(s: Severity) -> MavSeverity {
    match s {
        Severity::Info => MavSeverity::MAV_SEVERITY_INFO,
        Severity::Notice => MavSeverity::MAV_SEVERITY_NOTICE,
        Severity::Warning => MavSeverity::MAV_SEVERITY_WARNING,
        Severity::Error => MavSeverity::MAV_SEVERITY_ERROR,
        Severity::Critical => MavSeverity::MAV_SEVERITY_CRITICAL,
    }
}

/// A command result's MAVLink value.
pub fn mav_result(r: CommandResult) -> MavResult {
    match r {
        CommandResult::Accepted => MavResult::MAV_RESULT_ACCEPTED,
        CommandResult::InProgress => MavResult::MAV_RESULT_IN_PROGRESS,
        CommandResult::Failed => MavResult::MAV_RESULT_FAILED,
        CommandResult::TemporarilyRejected => MavResult::MAV_RESULT_TEMPORARILY_REJECTED,
        CommandResult::Denied => MavResult::MAV_RESULT_DENIED,
    }
}

/// A set of parameter indices, one bit each (room for [`ParamBits::CAPACITY`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ParamBits([u32; 5]);

impl ParamBits {
    /// Indices it can hold.
    pub const CAPACITY: usize = 160;

    /// The set of `index` alone.
    pub fn one(index: usize) -> Self {
        let mut bits = Self::default();
        bits.insert(index);
        bits
    }

    /// Adds `index` (one beyond the capacity is not held).
    pub fn insert(&mut self, index: usize) {
        if let Some(word) = self.0.get_mut(index / 32) {
            *word |= 1 << (index % 32);
        }
    }

    /// Whether `index` is in the set.
    pub fn contains(&self, index: usize) -> bool {
        self.0
            .get(index / 32)
            .is_some_and(|w| w & (1 << (index % 32)) != 0)
    }

    /// Whether the set holds no index.
    pub fn is_empty(&self) -> bool {
        self.0.iter().all(|w| *w == 0)
    }
}
