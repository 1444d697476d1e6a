//! [`VehiclePorts`] over plain queues with the firmware's capacities, for a harness that runs
//! the receive service without the firmware's tasks: the host tests and the fuzz targets. The
//! harness plays the other tasks: it takes what the service queued (replies, commands, route
//! changes, a payload to load) and sets what they would (the mission's state, the clock).

use heapless::Deque;
use link::esc::{EscError, EscRpmInbox, EscRpmReport};
use link::frame::ParserStats;
use link::hil::MocapFix;
use link::log_transfer::LogRequest;
use link::param_lists::ParamLists;
use link::signing::Signing;
use link::status::MissionState;
use link::telemetry::Schedule;
use link::timesync::TimeSync;
use link::vehicle::Sender;
use shared::manual::ManualInput;
use shared::mission::MissionConfig;
use shared::mission::bringup::CalibrationKind;
use shared::mission::drives::{BoardDrives, PIXHAWK_6C};
use shared::mission::params::ParamValues;

use super::{Bulk, Outbound, PendingCommand, Received, SensorSample, VehiclePorts};
use crate::autonomy::RouteChange;

/// Replies the firmware's send queue holds: a reply that finds it full is dropped.
pub const OUTBOX_CAPACITY: usize = 4;
/// Room for the replies the service waits to queue (the firmware waits for the send task;
/// here the harness drains the queue after each frame, and at the start).
pub const OUTBOX_WAITING_CAPACITY: usize = 8;
/// Bulk transfer messages the firmware's queue holds.
pub const BULK_CAPACITY: usize = 2;
/// Operator commands the control task's queue holds.
pub const COMMANDS_CAPACITY: usize = 4;
/// IMU samples the control task's queue holds.
pub const SENSOR_CAPACITY: usize = 2;
/// Route changes the control task's queue holds.
pub const ROUTES_CAPACITY: usize = 2;

/// The vehicle around the receive service, as queues and values (see the module's text).
pub struct QueuePorts {
    /// The vehicle's clock, us.
    pub now_us: u64,
    /// The board's outputs.
    pub drives: BoardDrives,
    /// A signing key may be set over this link.
    pub key_setup_allowed: bool,
    /// The store keeps its contents over a power cut.
    pub store_persistent: bool,
    /// Reboots the service asked for.
    pub reboots: u32,
    /// Replies for the send task.
    pub outbox: Deque<Outbound, OUTBOX_WAITING_CAPACITY>,
    /// Bulk transfer messages for the send task.
    pub bulk: Deque<Bulk, BULK_CAPACITY>,
    /// Replies and bulk messages dropped for want of room.
    pub dropped: u32,
    /// The parameter values the send task has.
    pub values: ParamValues,
    /// The parameter lists in flight.
    pub lists: ParamLists,
    /// What the frame parser counted.
    pub parsed: ParserStats,
    /// The link's signing state.
    pub signing: Signing,
    /// The time synchronisation with the ground.
    pub timesync: TimeSync,
    /// The telemetry schedule.
    pub telemetry: Schedule,
    /// The schedule changed since the harness last cleared this.
    pub telemetry_changed: bool,
    /// The mission's state (the harness's control task sets it).
    pub mission_state: MissionState,
    /// The rotors are armed (the harness's control task sets it).
    pub armed: bool,
    /// A `HIL_SENSOR` came.
    pub in_hil: bool,
    /// Robots of the payload loaded (the harness's job task sets it).
    pub payload_robots: usize,
    /// IMU samples for the control task.
    pub sensors: Deque<SensorSample, SENSOR_CAPACITY>,
    /// The newest motion-capture fix not yet taken.
    pub mocap: Option<MocapFix>,
    /// Operator commands for the control task.
    pub commands: Deque<PendingCommand, COMMANDS_CAPACITY>,
    /// A ground station's heartbeat came since the harness last cleared this.
    pub gcs_heartbeat: bool,
    /// The newest joystick input not yet taken.
    pub manual: Option<ManualInput>,
    /// The HIL plant's battery, mV (`u32::MAX`: none heard).
    pub battery_mv: u32,
    /// The HIL plant's rotor speeds.
    pub esc_rpm: EscRpmInbox,
    /// The configuration in force.
    pub config: MissionConfig,
    /// [`Self::config`] changed for the control step since the harness last cleared this.
    pub config_changed: bool,
    /// A reload of the payload was asked for since the harness last cleared this.
    pub reload: bool,
    /// A calibration's offsets for the service to store (the harness's control task sets it).
    pub calibrated: Option<(CalibrationKind, [f32; 3])>,
    /// Route changes for the control task (the oldest dropped when full: the newest is in
    /// force either way).
    pub routes: Deque<RouteChange, ROUTES_CAPACITY>,
    /// The mission's length in force.
    pub mission_items: u16,
    /// A checked payload description for the job task.
    pub to_load: Option<Received>,
    /// Payload descriptions offered (taken or not).
    pub offered: u32,
    /// Log requests handed to a logger (`None`: this board keeps no logs).
    pub logs: Option<Deque<LogRequest, 4>>,
}

impl QueuePorts {
    /// A Pixhawk 6C at rest at time 0: nothing queued, the mission idle, no logger.
    pub fn new() -> Self {
        Self {
            now_us: 0,
            drives: PIXHAWK_6C,
            key_setup_allowed: true,
            store_persistent: true,
            reboots: 0,
            outbox: Deque::new(),
            bulk: Deque::new(),
            dropped: 0,
            values: ParamValues::DEFAULT,
            lists: ParamLists::new(),
            parsed: ParserStats::default(),
            signing: Signing::new(),
            timesync: TimeSync::new(),
            telemetry: Schedule::new(),
            telemetry_changed: false,
            mission_state: MissionState::Idle,
            armed: false,
            in_hil: false,
            payload_robots: 0,
            sensors: Deque::new(),
            mocap: None,
            commands: Deque::new(),
            gcs_heartbeat: false,
            manual: None,
            battery_mv: u32::MAX,
            esc_rpm: EscRpmInbox::new(),
            config: MissionConfig::DEFAULT,
            config_changed: false,
            reload: false,
            calibrated: None,
            routes: Deque::new(),
            mission_items: 0,
            to_load: None,
            offered: 0,
            logs: None,
        }
    }
}

impl Default for QueuePorts {
    fn default() -> Self {
        Self::new()
    }
}

impl VehiclePorts for QueuePorts {
    fn now_us(&self) -> u64 {
        self.now_us
    }

    fn drives(&self) -> BoardDrives {
        self.drives
    }

    fn key_setup_allowed(&self) -> bool {
        self.key_setup_allowed
    }

    fn store_persistent(&self) -> bool {
        self.store_persistent
    }

    async fn reboot(&mut self) {
        self.reboots += 1;
    }

    fn reply(&mut self, message: Outbound) {
        if self.outbox.len() >= OUTBOX_CAPACITY || self.outbox.push_back(message).is_err() {
            self.dropped += 1;
        }
    }

    async fn reply_waiting(&mut self, message: Outbound) {
        if self.outbox.push_back(message).is_err() {
            self.dropped += 1;
        }
    }

    fn bulk(&mut self, message: Bulk) {
        if self.bulk.push_back(message).is_err() {
            self.dropped += 1;
        }
    }

    fn publish(&mut self, values: &ParamValues) {
        self.values = values.clone();
    }

    fn list_params(&mut self, to: Sender) {
        self.lists.request(to);
    }

    fn parsed(&mut self, stats: ParserStats) {
        self.parsed = stats;
    }

    fn signing<R>(&mut self, change: impl FnOnce(&mut Signing) -> R) -> R {
        change(&mut self.signing)
    }

    fn timesync<R>(&mut self, change: impl FnOnce(&mut TimeSync) -> R) -> R {
        change(&mut self.timesync)
    }

    fn telemetry<R>(&mut self, change: impl FnOnce(&mut Schedule) -> R) -> R {
        change(&mut self.telemetry)
    }

    fn telemetry_changed(&mut self) {
        self.telemetry_changed = true;
    }

    fn mission_state(&self) -> MissionState {
        self.mission_state
    }

    fn armed(&self) -> bool {
        self.armed
    }

    fn in_hil(&self) -> bool {
        self.in_hil
    }

    fn payload_robots(&self) -> usize {
        self.payload_robots
    }

    fn sensor(&mut self, sample: SensorSample) -> bool {
        self.in_hil = true;
        self.sensors.push_back(sample).is_ok()
    }

    fn mocap(&mut self, fix: MocapFix) {
        self.mocap = Some(fix);
    }

    fn command(&mut self, pending: PendingCommand) -> bool {
        self.commands.push_back(pending).is_ok()
    }

    fn gcs_heartbeat(&mut self) {
        self.gcs_heartbeat = true;
    }

    fn manual_control(&mut self, input: ManualInput) {
        self.manual = Some(input);
    }

    fn battery_mv(&mut self, millivolts: u32) {
        self.battery_mv = millivolts;
    }

    fn esc_rpm(&mut self, report: &EscRpmReport) -> Result<(), EscError> {
        self.esc_rpm.receive(report)
    }

    fn apply_config(&mut self, config: MissionConfig) {
        self.config = config;
        self.config_changed = true;
    }

    fn reload(&mut self) {
        self.reload = true;
    }

    fn record_config(&mut self, config: MissionConfig) {
        self.config = config;
    }

    fn calibrated(&mut self) -> Option<(CalibrationKind, [f32; 3])> {
        self.calibrated.take()
    }

    async fn route(&mut self, change: RouteChange, items: u16) {
        self.mission_items = items;
        if self.routes.is_full() {
            self.routes.pop_front();
        }
        let _ = self.routes.push_back(change);
    }

    fn offer_payload(&mut self, received: Received) -> bool {
        if self.to_load.is_some() {
            return false;
        }
        self.offered += 1;
        self.to_load = Some(received);
        true
    }

    async fn payload_room(&mut self) {
        // No job task takes it while the service waits: the newest description wins, as it
        // would once the job task had taken the older one.
        self.to_load = None;
    }

    fn log_request(&mut self, request: LogRequest) -> bool {
        match &mut self.logs {
            Some(logs) => {
                if logs.push_back(request).is_err() {
                    self.dropped += 1;
                }
                true
            }
            None => false,
        }
    }
}
