//! Commands (`COMMAND_LONG`, `COMMAND_INT`) and log requests as the link takes them
//! (docs/ground-link.md#commands-long-or-int): the requests for a message answered here, the
//! telemetry rates, the operator's commands handed to the control task, the map origin and
//! the reboot; once signing is on, only reading goes without a signature.

use embedded_storage_async::nor_flash::NorFlash;
use link::MessageData;
use link::command::Request;
use link::command_wire::CommandId;
use link::log_transfer::{LogReply, LogRequest};
use link::modes::MODES;
use link::msg::{
    AUTOPILOT_VERSION_DATA, COMPONENT_METADATA_DATA, CURRENT_MODE_DATA, GPS_GLOBAL_ORIGIN_DATA,
    HOME_POSITION_DATA, MavResult,
};
use link::signing::Verdict;
use link::status::MissionState;
use link::vehicle::Sender;

use super::{Bulk, LinkService, Outbound, PendingCommand, VehiclePorts, report};
use crate::autonomy::Severity;

/// Refuses `command` with `result`, and says why.
pub(super) fn refuse(io: &mut impl VehiclePorts, command: CommandId, result: MavResult, why: &str) {
    io.reply(Outbound::Ack { command, result });
    io.reply(report(
        Severity::Warning,
        format_args!("command {} refused: {why}", command.0),
    ));
}

/// Acknowledges `command` as accepted.
fn accept(io: &mut impl VehiclePorts, command: CommandId) {
    let result = MavResult::MAV_RESULT_ACCEPTED;
    io.reply(Outbound::Ack { command, result });
}

impl<F: NorFlash> LinkService<F> {
    /// A command's request, from `from`.
    pub(super) async fn command(
        &mut self,
        command: CommandId,
        request: Request,
        from: Sender,
        verdict: Verdict,
        io: &mut impl VehiclePorts,
    ) {
        match request {
            Request::AvailableModes(index) => {
                if usize::from(index) > MODES.len() {
                    refuse(
                        io,
                        command,
                        MavResult::MAV_RESULT_DENIED,
                        "no mode of that index",
                    );
                } else {
                    accept(io, command);
                    io.reply(Outbound::AvailableModes(index));
                }
            }
            Request::Message(id) if id == CURRENT_MODE_DATA::ID => {
                accept(io, command);
                io.reply(Outbound::CurrentMode);
            }
            Request::Message(id) if id == AUTOPILOT_VERSION_DATA::ID => {
                accept(io, command);
                io.reply(Outbound::Identity);
            }
            Request::Message(id) if id == COMPONENT_METADATA_DATA::ID => {
                accept(io, command);
                io.reply(Outbound::ComponentMetadata);
            }
            Request::Message(id)
                if id == HOME_POSITION_DATA::ID || id == GPS_GLOBAL_ORIGIN_DATA::ID =>
            {
                if let Err(e) = self.params.origin().check() {
                    refuse(io, command, MavResult::MAV_RESULT_DENIED, e.as_str());
                } else {
                    accept(io, command);
                    io.reply(if id == HOME_POSITION_DATA::ID {
                        Outbound::Home
                    } else {
                        Outbound::Origin
                    });
                }
            }
            Request::Message(id) => {
                if io.telemetry(|t| t.request_once(id)) {
                    io.telemetry_changed();
                    accept(io, command);
                } else {
                    let result = MavResult::MAV_RESULT_UNSUPPORTED;
                    refuse(io, command, result, "that message is not sent on request");
                }
            }
            // Once signing is on, only reading goes without a signature.
            _ if !verdict.trusted() => {
                refuse(io, command, MavResult::MAV_RESULT_DENIED, verdict.reason());
            }
            Request::Operator(operator) => {
                let pending = PendingCommand {
                    command: operator,
                    mav_cmd: command,
                    from,
                };
                if !io.command(pending) {
                    let result = MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
                    io.reply(Outbound::Ack { command, result });
                }
            }
            Request::SetInterval {
                message_id,
                interval_us,
            } => {
                let now = io.now_us();
                let result = io.telemetry(|t| t.set_interval(message_id, interval_us, now));
                match result {
                    MavResult::MAV_RESULT_ACCEPTED => {
                        io.telemetry_changed();
                        io.reply(Outbound::Ack { command, result });
                    }
                    MavResult::MAV_RESULT_UNSUPPORTED => {
                        refuse(io, command, result, "that message is not streamed");
                    }
                    _ => refuse(
                        io,
                        command,
                        result,
                        "the interval must be -1, 0 or 5,000 us to 1 hour",
                    ),
                }
            }
            Request::SetOrigin {
                lat_e7,
                lon_e7,
                alt_mm,
            } => {
                self.command_origin(command, (lat_e7, lon_e7, alt_mm), verdict, io)
                    .await;
            }
            Request::Refused(result) => {
                refuse(io, command, result, link::command::refusal(command, result));
            }
            Request::Reboot => reboot(command, io).await,
        }
    }
}

/// `MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN`: refused while armed or while the mission runs;
/// otherwise acknowledged, said, and the processor reset once both are out.
async fn reboot(command: CommandId, io: &mut impl VehiclePorts) {
    if io.armed() || io.mission_state() == MissionState::Running {
        let why = "the vehicle is armed or the mission is running";
        refuse(io, command, MavResult::MAV_RESULT_DENIED, why);
        return;
    }
    let result = MavResult::MAV_RESULT_ACCEPTED;
    io.reply_waiting(Outbound::Ack { command, result }).await;
    io.reply_waiting(report(
        Severity::Notice,
        format_args!("rebooting the flight controller"),
    ))
    .await;
    io.reboot().await;
}

/// Hands a log request to the logger task, which owns the storage; a board that keeps no
/// logs lists none, and an erase must be signed once signing is on.
pub(super) fn handle_log(request: LogRequest, verdict: Verdict, io: &mut impl VehiclePorts) {
    if request == LogRequest::Erase && !verdict.trusted() {
        io.reply(report(
            Severity::Warning,
            format_args!("log erase refused: {}", verdict.reason()),
        ));
        return;
    }
    if !io.log_request(request) {
        match request {
            LogRequest::List { .. } => {
                io.bulk(Bulk::Log(LogReply::Entry(
                    link::log_transfer::no_logs_entry(),
                )));
            }
            LogRequest::End => {}
            LogRequest::Data { .. } | LogRequest::Erase => {
                io.reply(report(
                    Severity::Warning,
                    format_args!("flight logs: this board keeps none"),
                ));
            }
        }
    }
}
