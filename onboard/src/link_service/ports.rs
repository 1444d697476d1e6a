//! What the link's receive service needs from the rest of the vehicle: the board's clock and
//! limits, the queues to the send task, the state other tasks own (signing, time sync, the
//! telemetry schedule, the mission's state) and the hand-overs to the control, job and logger
//! tasks. The firmware implements it over its channels and atomics (`firmware/src/app/comms.rs`);
//! the tests and the fuzz targets over plain queues. Everything the service decides stays in
//! the service, where a host test sees it.

use link::esc::{EscError, EscRpmReport};
use link::frame::ParserStats;
use link::hil::MocapFix;
use link::log_transfer::LogRequest;
use link::param::Values;
use link::signing::Signing;
use link::status::MissionState;
use link::telemetry::Schedule;
use link::timesync::TimeSync;
use link::vehicle::Sender;
use shared::manual::ManualInput;
use shared::mission::MissionConfig;
use shared::mission::bringup::CalibrationKind;
use shared::mission::drives::BoardDrives;
use shared::mission::params::ParamValues;

use super::messages::{Bulk, Outbound, ParamBits, PendingCommand, Received, SensorSample};
use crate::autonomy::RouteChange;

/// The vehicle around the link's receive service (see the module's text).
// The firmware's executors are single-threaded and the host drives the futures with
// `block_on`: no caller needs the futures to be `Send`.
#[allow(async_fn_in_trait)]
pub trait VehiclePorts {
    /// The vehicle's clock, us.
    fn now_us(&self) -> u64;
    /// The robots this board drives with each ESC protocol.
    fn drives(&self) -> BoardDrives;
    /// A signing key may be set over the link in use (on a Pixhawk: over USB only).
    fn key_setup_allowed(&self) -> bool;
    /// The board keeps its parameters across a power cut.
    fn store_persistent(&self) -> bool;
    /// Resets the processor once the replies queued have gone out (on a board it does not
    /// return).
    async fn reboot(&mut self);

    /// Queues a reply for the send task without waiting: one that finds the queue full is
    /// dropped and counted (docs/ground-link.md#under-a-flood).
    fn reply(&mut self, message: Outbound);
    /// Queues a reply, waiting for room (at the start, and for texts that must not be lost).
    async fn reply_waiting(&mut self, message: Outbound);
    /// Queues a bulk transfer's message without waiting, as [`Self::reply`].
    fn bulk(&mut self, message: Bulk);
    /// Hands the parameter values in force to the send task (after every change).
    fn publish(&mut self, values: &ParamValues);
    /// Starts (or restarts) `to`'s list of every parameter value.
    fn list_params(&mut self, to: Sender);
    /// What the frame parser counted so far.
    fn parsed(&mut self, stats: ParserStats);

    /// The link's signing state, shared with the send task.
    fn signing<R>(&mut self, change: impl FnOnce(&mut Signing) -> R) -> R;
    /// The time synchronisation with the ground, shared with the send task.
    fn timesync<R>(&mut self, change: impl FnOnce(&mut TimeSync) -> R) -> R;
    /// The telemetry schedule, shared with the send task.
    fn telemetry<R>(&mut self, change: impl FnOnce(&mut Schedule) -> R) -> R;
    /// The schedule changed: the send task looks at it again.
    fn telemetry_changed(&mut self);
    /// The mission's state, as the control task last set it.
    fn mission_state(&self) -> MissionState;
    /// The rotors are armed.
    fn armed(&self) -> bool;
    /// The vehicle flies a HIL plant (a `HIL_SENSOR` came).
    fn in_hil(&self) -> bool;
    /// Robots of the payload description loaded (0: none).
    fn payload_robots(&self) -> usize;

    /// An IMU sample for the control task; `false` when its queue is full (the step is
    /// behind). The sample marks the vehicle as in HIL.
    fn sensor(&mut self, sample: SensorSample) -> bool;
    /// A motion-capture fix for the control task (the newest replaces one not yet taken).
    fn mocap(&mut self, fix: MocapFix);
    /// An operator command for the control task; `false` when its queue is full.
    fn command(&mut self, pending: PendingCommand) -> bool;
    /// A ground station's heartbeat came.
    fn gcs_heartbeat(&mut self);
    /// A ground station's joystick (`MANUAL_CONTROL`), checked, for the control task.
    fn manual_control(&mut self, input: ManualInput);
    /// The HIL plant's battery voltage, mV.
    fn battery_mv(&mut self, millivolts: u32);
    /// The HIL plant's rotor speeds.
    fn esc_rpm(&mut self, report: &EscRpmReport) -> Result<(), EscError>;
    /// Puts `config` in force for the next payload description and the control step now.
    fn apply_config(&mut self, config: MissionConfig);
    /// Loads the payload description again with the configuration in force (the mission is
    /// not running).
    fn reload(&mut self);
    /// Records `config` as in force, which the mission already has (a calibration's offsets).
    fn record_config(&mut self, config: MissionConfig);
    /// A calibration's offsets from the control task, to store as parameters.
    fn calibrated(&mut self) -> Option<(CalibrationKind, [f32; 3])>;
    /// Hands a route change to the control task, waiting for room; `items` is the mission's
    /// length in force.
    async fn route(&mut self, change: RouteChange, items: u16);

    /// Hands a checked payload description to the job task; `false` when it has not taken
    /// the last one yet.
    fn offer_payload(&mut self, received: Received) -> bool;
    /// Waits until the job task can take a payload description.
    async fn payload_room(&mut self);
    /// Hands a log request to the logger task; `false` when this board keeps no logs.
    fn log_request(&mut self, request: LogRequest) -> bool;
}

/// The `PARAM_VALUE`s a parameter request asks for, as replies: one at once, every one as
/// `from`'s list (which a new request from the same sender restarts).
pub(super) fn send_values(
    io: &mut impl VehiclePorts,
    values: &ParamValues,
    which: Values,
    from: Option<Sender>,
) {
    io.publish(values);
    match (which, from) {
        (Values::None, _) => {}
        (Values::One(index), _) => io.reply(Outbound::Params(ParamBits::one(index))),
        (Values::All, Some(from)) => io.list_params(from),
        // Every value without a requester: not asked for.
        (Values::All, None) => {}
    }
}
