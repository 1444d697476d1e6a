//! The flight controller's MAVLink input handling as one synchronous host program: what the
//! firmware's link task does with each byte (`firmware/src/app/comms.rs`, `receive` and
//! `handle`), with its control task (`control.rs`: one step of the autonomy per IMU sample,
//! the job's result at its deadline) and its job task (`jobs.rs`: the planner loaded with
//! each accepted payload description, and again when a parameter changes) behind it.
//!
//! The firmware's tasks are embassy tasks that only build for the Cortex-M7, so they are not
//! called here: this module calls the same `link` and `shared` functions they call, in the
//! same order, and the firmware's own autonomy seam ([`crate::autonomy`], compiled from
//! `firmware/src/app/autonomy.rs` as it is). Channels become queues of the same capacity
//! and each task's turn comes in the order the firmware gives it (a frame's handling, then
//! the control steps it causes, a job run at once and taken at its deadline, as in lockstep
//! HIL). The parameters' store runs on a [`MemFlash`] shaped as the Pixhawk 6C's FRAM.
//!
//! Every frame the vehicle sends goes through a ground-side parser (and, once signing is on,
//! the ground's signature check), so the send side's encoding is checked as well.
//!
//! [`Vehicle`] panics, with the reason, when one of these invariants breaks:
//! - a frame the vehicle ignores, or one it does not trust (signing on, unsigned or bad
//!   signature), changes nothing: parameters, the FTP file, queued commands;
//! - a refused parameter write leaves the value in force; every value in force is one the
//!   table accepts; no value changes while the mission runs;
//! - every command taken is acknowledged;
//! - the rotors are armed only in the phases that spin them (lift, arming, flight), with
//!   thrust only in lift and flight, every thrust a finite fraction in `[0, 1]`, every rail
//!   setpoint finite; never armed when the heartbeat says idle, completed or aborted, but for
//!   a motor test (on the ground, the mission not running);
//! - every frame sent parses back whole, its checksum (and signature) verified;
//! - after the input, a restart finds in the store exactly the parameters, the signing key
//!   and the payload description in force (unless the store reported an error).

use std::collections::VecDeque;

use crate::autonomy::RouteChange;
use embassy_futures::block_on;
use link::MessageData;
use link::command::{Request, ack};
use link::command_wire::CommandId;
use link::frame::{Encoder, Frame, Integrity, Parser};
use link::ftp::{FileEvent, FtpMessage, Server};
use link::geo::{GeoOrigin, OriginError};
use link::hil::{ImuSample, JobDeadline, MAX_ROBOTS, MocapFix, VehicleClock};
use link::log_transfer::LogRequest;
use link::mission::{Context as MissionContext, MissionEvent, MissionService, Outcome};
use link::msg::{
    AUTOPILOT_VERSION_DATA, GPS_GLOBAL_ORIGIN_DATA, HOME_POSITION_DATA, MavResult, MavSeverity,
    TIMESYNC_DATA,
};
use link::param::{ParamService, Values, value_message};
use link::param_lists::ParamLists;
use link::signing::{KEY_LEN, Signing, Verdict};
use link::status::{MissionState, PHASE_PREFIX, chunks, heartbeat, named_float, named_int};
use link::store::ParamStore;
use link::telemetry::{Home, Schedule, gps_global_origin};
use link::timesync::{Received as SyncReceived, TimeSync};
use link::vehicle::{Inbound, Sender, crc_extra, dispatch};
use shared::mission::params::{COUNT as PARAM_COUNT, ParamValues, check, is_origin};
use shared::mission::{HardwareFaults, MissionConfig, MissionPlanner, Supervision};
use shared::scenario::Scenario;
use shared::scenario_wire::{MAX_ENCODED_LEN, decode_and_check};

use crate::autonomy::{
    Autonomy, CommandResult, ImuReading, JobResult, OperatorCommand, Report, Severity, TickInput,
    Value,
};
use crate::flash::{MemFlash, PARAM_RANGE, PAYLOAD_RANGE};

/// The payload description's checksum (`shared::scenario_wire`'s).
const CRC32: crc::Crc<u32, crc::NoTable> =
    crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);
/// Largest payload description file the vehicle takes (the firmware's `FILE_CAPACITY`).
pub const FILE_CAPACITY: usize = MAX_ENCODED_LEN;
/// The signing key a seed's "key stored" option puts in the store before the start.
pub const SEED_KEY: [u8; KEY_LEN] = [7; KEY_LEN];
/// The signing timestamp stored with [`SEED_KEY`].
pub const SEED_KEY_TIMESTAMP: u64 = 1_000_000;
/// Board time one received byte takes (115,200 baud), us.
pub const BYTE_US: u64 = 87;
/// The control period of the board's IMU driver, us (400 Hz).
pub const TICK_US: u64 = 2_500;
/// Most steps the IMU driver takes in one run (50 s of the mission): bounds the time of one
/// fuzz input (about 0.1 s) without a plant to fly, the mission never gets further.
pub const MAX_DRIVER_STEPS: u64 = 20_000;
/// Oldest a motion-capture fix may be for its own stamp to be used (comms.rs), us.
const MAX_FIX_AGE_US: u64 = 150_000;
/// The link id the vehicle signs with.
const LINK_ID: u8 = 0;
/// Capacity of the firmware's `COMMANDS` channel.
const COMMANDS_CAPACITY: usize = 4;
/// Phases whose rotors may be armed (by their names in `phase: NAME: reason` texts).
const ARMED_PHASES: [&str; 7] = [
    "lift",
    "arming",
    "takeoff",
    "trajectory",
    "hover",
    "landing",
    "touchdown",
];
/// Phases whose rotors may push (armed, not idling on the ground before take-off).
const THRUST_PHASES: [&str; 6] = [
    "lift",
    "takeoff",
    "trajectory",
    "hover",
    "landing",
    "touchdown",
];
/// Phases of a mission that is not running (idle, or over).
const STOPPED_PHASES: [&str; 3] = ["idle", "disarmed", "aborted"];

pub use crate::options::Options;

/// An operator command waiting for the control task (comms.rs `PendingCommand`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct PendingCommand {
    command: OperatorCommand,
    mav_cmd: CommandId,
}

/// The vehicle: the link task's state, the control task's and the job task's.
pub struct Vehicle {
    options: Options,
    /// The board's clock (embassy's `Instant`), us.
    now_us: u64,
    next_beat_us: u64,
    frames: u32,
    driver_steps: u64,
    parser: Parser,
    signing: Signing,
    timesync: TimeSync,
    telemetry: Schedule,
    ftp: Box<Server<FILE_CAPACITY>>,
    mission: Box<MissionService>,
    /// Route changes for the control task (`ROUTE`, capacity 2).
    routes: VecDeque<RouteChange>,
    params: ParamService,
    /// The parameter lists in flight.
    lists: ParamLists,
    store: Option<ParamStore<MemFlash>>,
    /// `MISSION_CONFIG`.
    config: MissionConfig,
    /// `CONFIG_CHANGED`.
    config_changed: bool,
    /// A store operation failed: a restart may legitimately find older values.
    store_failed: bool,
    /// What a restart must find in the store.
    stored_key: Option<[u8; KEY_LEN]>,
    stored_payload: Option<Vec<u8>>,
    /// `COMMANDS`.
    commands: VecDeque<PendingCommand>,
    /// `MOCAP`.
    mocap: Option<MocapFix>,
    /// `GCS_HEARTBEAT`: a ground station's heartbeat since the last control step.
    gcs_heartbeat: bool,
    /// `LINK_BATTERY_MV`: the plant's pack, mV (`u32::MAX`: none heard).
    link_battery_mv: u32,
    /// `LINK_ESC_RPM`: the plant's rotor RPM.
    link_esc_rpm: link::esc::EscRpmInbox,
    /// comms.rs `FTP_REFUSED`: the sender whose FTP was last refused (0: none).
    ftp_refused: u32,
    /// `PAYLOAD`: the newest description loaded into the planner, for the control task.
    payload: Option<(Scenario, MissionConfig)>,
    /// The job task's last accepted description.
    last: Option<Scenario>,
    autonomy: Box<Autonomy>,
    planner: Box<MissionPlanner>,
    clock: VehicleClock,
    deadline: JobDeadline,
    job_id: u32,
    job_result: Option<(u32, JobResult)>,
    /// `MISSION_STATE`, `ARMED`, `IN_HIL`.
    mission_state: MissionState,
    armed: bool,
    in_hil: bool,
    /// The phase as the vehicle last reported it (`phase: NAME: reason`).
    phase: String,
    /// The send side.
    encoder: Encoder,
    frame: Frame,
    text_id: u16,
    ground: Parser,
    ground_signing: Signing,
    /// Frames sent, and control steps taken (for the seed generator's checks).
    pub sent: u32,
    /// Control steps taken.
    pub steps: u64,
    /// The phases the mission went through, in order, with their reasons.
    pub phases: Vec<String>,
}

/// The description the "payload stored" option puts in the store: rect-sim1, encoded.
pub fn stored_payload() -> &'static [u8] {
    use std::sync::OnceLock;
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| crate::seeds::encoded_scenario(crate::seeds::SCENARIOS[4].1))
}

impl Vehicle {
    /// The vehicle after its start with `options`: the store opened and read, the signing key
    /// and payload description restored (comms.rs `receive` before its loop).
    pub fn start(options: Options) -> Self {
        let mut flash = MemFlash::new();
        if options.payload_stored || options.key_stored {
            let mut store = open(flash).expect("the store opens on a blank flash");
            if options.payload_stored {
                block_on(store.save_payload(stored_payload())).expect("payload stored");
            }
            if options.key_stored {
                block_on(store.save_signing(&SEED_KEY, SEED_KEY_TIMESTAMP)).expect("key stored");
            }
            flash = store.into_flash().expect("the flash back");
        }
        let mut v = Self {
            options,
            now_us: 0,
            next_beat_us: 0,
            frames: 0,
            driver_steps: 0,
            parser: Parser::new(crc_extra),
            signing: Signing::new(),
            timesync: TimeSync::new(),
            telemetry: Schedule::new(),
            ftp: Box::new(Server::new()),
            mission: Box::new(MissionService::new()),
            routes: VecDeque::with_capacity(2),
            params: ParamService::new(ParamValues::DEFAULT),
            lists: ParamLists::new(),
            store: None,
            config: MissionConfig::DEFAULT,
            config_changed: false,
            store_failed: false,
            stored_key: None,
            stored_payload: None,
            commands: VecDeque::with_capacity(COMMANDS_CAPACITY),
            mocap: None,
            gcs_heartbeat: false,
            link_battery_mv: u32::MAX,
            link_esc_rpm: link::esc::EscRpmInbox::new(),
            ftp_refused: 0,
            payload: None,
            last: None,
            autonomy: Box::new(Autonomy::new()),
            planner: Box::new(MissionPlanner::UNLOADED),
            clock: VehicleClock::new(),
            deadline: JobDeadline::new(),
            job_id: 0,
            job_result: None,
            mission_state: MissionState::Idle,
            armed: false,
            in_hil: false,
            phase: "idle".into(),
            encoder: Encoder::new(link::VEHICLE_SYSTEM_ID, link::VEHICLE_COMPONENT_ID),
            frame: Frame::default(),
            text_id: 0,
            ground: Parser::new(crc_extra),
            ground_signing: Signing::new(),
            sent: 0,
            steps: 0,
            phases: Vec::new(),
        };
        v.send_identity();
        v.open_params(flash);
        v.restore_signing();
        v.restore_payload();
        v
    }

    /// Takes the received bytes `stream`, one at a time, as the link task does.
    pub fn receive(&mut self, stream: &[u8]) {
        for &byte in stream {
            self.now_us += BYTE_US;
            self.heartbeat_due();
            let Some((frame, integrity)) = self.parser.push(byte) else {
                continue;
            };
            let frame = frame.clone();
            let verdict = self.signing.check(&frame, self.now_us);
            let inbound = dispatch(&frame, integrity);
            if integrity == Integrity::Unverified {
                assert!(
                    matches!(inbound, Inbound::Ignored { .. }),
                    "an unverified frame was dispatched: {inbound:?}"
                );
            }
            self.handle_checked(inbound, verdict);
            self.frames = self.frames.saturating_add(1);
            if self.options.imu_driver {
                for _ in 0..self.options.ticks {
                    if self.driver_steps < MAX_DRIVER_STEPS {
                        self.driver_step();
                    }
                }
            }
        }
    }

    /// The end of the input: the board restarts and must find in its store what was in force.
    pub fn restart_check(mut self) {
        let Some(store) = self.store.take() else {
            return;
        };
        if self.store_failed {
            return;
        }
        let flash = store.into_flash().expect("the flash back from the store");
        let mut store = open(flash).expect("the store opens again");
        let mut values = ParamValues::DEFAULT;
        let loaded = block_on(store.load(&mut values));
        assert_eq!(loaded.error, None, "the store fails after a restart");
        assert_eq!(
            &values,
            self.params.values(),
            "parameters lost in a restart"
        );
        let key = block_on(store.load_signing()).expect("the signing key reads back");
        assert_eq!(
            key.map(|(k, _)| k),
            self.stored_key,
            "signing key lost in a restart"
        );
        let mut buffer = vec![0u8; FILE_CAPACITY];
        let valid = |bytes: &[u8]| decode_and_check(bytes).is_ok();
        let payload = block_on(store.load_payload(&mut buffer, valid))
            .expect("the payload description reads back");
        assert_eq!(
            payload.map(|len| buffer[..len].to_vec()),
            self.stored_payload,
            "payload description lost in a restart"
        );
    }

    fn heartbeat_due(&mut self) {
        if self.now_us >= self.next_beat_us {
            let beat = heartbeat(
                self.mission_state,
                self.autonomy.mode(),
                self.armed,
                self.in_hil,
            );
            self.send(&beat);
            let request = self.timesync.request(ns(self.now_us));
            self.send(&request);
            self.next_beat_us = self.now_us + 1_000_000;
        }
    }

    fn open_params(&mut self, flash: MemFlash) {
        let mut values = ParamValues::DEFAULT;
        match open(flash) {
            Ok(mut store) => {
                let loaded = block_on(store.load(&mut values));
                assert_eq!(loaded.refused, 0, "stored values refused at the start");
                if let Some(e) = loaded.error {
                    self.report_text(Severity::Error, &format!("params: {e}"));
                    self.store_failed = true;
                }
                self.store = Some(store);
            }
            Err(e) => panic!("the store does not open: {e}"),
        }
        self.params = ParamService::new(values);
        self.config = self.params.values().config();
        self.config_changed = true;
    }

    fn restore_signing(&mut self) {
        let Some(store) = &mut self.store else {
            return;
        };
        match block_on(store.load_signing()) {
            Ok(Some((key, timestamp))) => {
                self.set_key(key, timestamp);
                self.stored_key = Some(key);
            }
            Ok(None) => {}
            Err(e) => panic!("the stored key does not read: {e}"),
        }
    }

    fn restore_payload(&mut self) {
        let Some(store) = &mut self.store else {
            return;
        };
        let valid = |bytes: &[u8]| decode_and_check(bytes).is_ok();
        match block_on(store.load_payload(self.ftp.restore_buffer(), valid)) {
            Ok(Some(len)) => {
                self.ftp.restored(len);
                let file = self.ftp.file().to_vec();
                self.stored_payload = Some(file.clone());
                self.check_payload(&file, false);
            }
            Ok(None) => {}
            Err(e) => panic!("the stored payload does not read: {e}"),
        }
    }

    fn set_key(&mut self, key: [u8; KEY_LEN], timestamp: u64) {
        self.signing.set_key(key, timestamp, self.now_us, LINK_ID);
        // The ground station takes the key at the same moment (its own link id).
        self.ground_signing
            .set_key(key, timestamp, self.now_us, LINK_ID + 1);
    }

    fn faults(&self) -> HardwareFaults {
        if self.frames < u32::from(self.options.faults_from) {
            return HardwareFaults::NONE;
        }
        HardwareFaults {
            imu: self.options.imu_fault,
            stalled_robots: self.options.stalled_robots,
            rotors_out: 0,
        }
    }

    /// `handle` with the invariants of what an ignored or untrusted frame may change.
    fn handle_checked(&mut self, inbound: Inbound, verdict: Verdict) {
        let inert = matches!(
            inbound,
            Inbound::Ignored { .. }
                | Inbound::Heartbeat(_)
                | Inbound::GcsHeartbeat(_)
                | Inbound::Battery { .. }
                | Inbound::EscStatus(_)
        );
        let untrusted = !verdict.trusted();
        let before = (
            self.params.values().clone(),
            self.ftp.file().to_vec(),
            self.commands.clone(),
            self.telemetry,
            self.signing,
        );
        let was_running = self.mission_state == MissionState::Running;
        self.handle(inbound, verdict);
        if inert {
            let after = (
                self.params.values().clone(),
                self.ftp.file().to_vec(),
                self.commands.clone(),
                self.telemetry,
                self.signing,
            );
            assert_eq!(before.0, after.0, "an ignored frame changed a parameter");
            assert_eq!(before.1, after.1, "an ignored frame changed the FTP file");
            assert_eq!(before.2, after.2, "an ignored frame queued a command");
            assert_eq!(
                before.3, after.3,
                "an ignored frame changed the telemetry rates"
            );
            assert_eq!(
                before.4, after.4,
                "an ignored frame changed the signing state"
            );
        }
        if untrusted || was_running {
            assert_eq!(
                &before.0,
                self.params.values(),
                "a parameter changed (untrusted {untrusted}, running {was_running})"
            );
        }
        if untrusted {
            assert_eq!(
                before.1,
                self.ftp.file(),
                "an untrusted upload wrote the file"
            );
            assert!(
                self.commands.len() <= before.2.len(),
                "an untrusted command was queued"
            );
        }
        for i in 0..PARAM_COUNT {
            let v = self
                .params
                .values()
                .get(i)
                .expect("every index has a value");
            assert!(check(i, v).is_ok(), "parameter {i} = {v} is out of range");
        }
    }

    /// comms.rs `handle`.
    fn handle(&mut self, inbound: Inbound, verdict: Verdict) {
        match inbound {
            Inbound::Sensor(imu) => {
                self.in_hil = true;
                self.control_step(imu, true);
            }
            Inbound::Mocap(mut fix) => {
                if !self.in_hil {
                    fix.stamp_us = self
                        .timesync
                        .stamp(fix.stamp_us, self.now_us, MAX_FIX_AGE_US);
                }
                self.mocap = Some(fix);
            }
            Inbound::TimeSync { tc1, ts1 } => {
                let message = TIMESYNC_DATA { tc1, ts1 };
                if let SyncReceived::Answer(a) = self.timesync.receive(&message, ns(self.now_us)) {
                    self.send(&TIMESYNC_DATA {
                        tc1: a.tc1,
                        ts1: a.ts1,
                    });
                }
            }
            Inbound::Command {
                command, request, ..
            } => match request {
                Request::AvailableModes(index) => {
                    let modes = &link::modes::MODES;
                    if usize::from(index) > modes.len() {
                        self.refuse(
                            command,
                            MavResult::MAV_RESULT_DENIED,
                            "no mode of that index",
                        );
                    } else {
                        self.send(&ack(command, MavResult::MAV_RESULT_ACCEPTED));
                        for (i, mode) in modes.iter().enumerate() {
                            if index == 0 || usize::from(index) == i + 1 {
                                self.send(&mode.available());
                            }
                        }
                    }
                }
                Request::Message(id) if id == AUTOPILOT_VERSION_DATA::ID => {
                    self.send(&ack(command, MavResult::MAV_RESULT_ACCEPTED));
                    self.send_identity();
                }
                Request::Message(id)
                    if id == HOME_POSITION_DATA::ID || id == GPS_GLOBAL_ORIGIN_DATA::ID =>
                {
                    let origin = self.params.origin();
                    if let Err(e) = origin.check() {
                        self.refuse(command, MavResult::MAV_RESULT_DENIED, e.as_str());
                    } else {
                        self.send(&ack(command, MavResult::MAV_RESULT_ACCEPTED));
                        if id == HOME_POSITION_DATA::ID {
                            let home = Home::START.home_position(&origin);
                            self.send(&home.expect("a usable origin places the home"));
                        } else {
                            self.send(&gps_global_origin(&origin));
                        }
                    }
                }
                Request::Message(id) => {
                    if self.telemetry.request_once(id) {
                        self.send(&ack(command, MavResult::MAV_RESULT_ACCEPTED));
                    } else {
                        let result = MavResult::MAV_RESULT_UNSUPPORTED;
                        self.refuse(command, result, "that message is not sent on request");
                    }
                }
                _ if !verdict.trusted() => {
                    self.refuse(command, MavResult::MAV_RESULT_DENIED, verdict.reason());
                }
                Request::Operator(operator) => {
                    if self.commands.len() < COMMANDS_CAPACITY {
                        self.commands.push_back(PendingCommand {
                            command: operator,
                            mav_cmd: command,
                        });
                    } else {
                        self.send(&ack(command, MavResult::MAV_RESULT_TEMPORARILY_REJECTED));
                    }
                }
                Request::SetInterval {
                    message_id,
                    interval_us,
                } => {
                    let result = self
                        .telemetry
                        .set_interval(message_id, interval_us, self.now_us);
                    match result {
                        MavResult::MAV_RESULT_ACCEPTED => self.send(&ack(command, result)),
                        MavResult::MAV_RESULT_UNSUPPORTED => {
                            self.refuse(command, result, "that message is not streamed");
                        }
                        _ => self.refuse(command, result, "the interval is out of range"),
                    }
                }
                Request::Refused(result) => {
                    self.refuse(command, result, link::command::refusal(command, result));
                }
                // comms.rs `reboot`: the host's vehicle does not restart; refused while armed.
                Request::Reboot => {
                    let result = if self.armed {
                        MavResult::MAV_RESULT_DENIED
                    } else {
                        MavResult::MAV_RESULT_ACCEPTED
                    };
                    self.send(&ack(command, result));
                }
                // comms.rs `command_origin`.
                Request::SetOrigin {
                    lat_e7,
                    lon_e7,
                    alt_mm,
                } => match self.checked_origin((lat_e7, lon_e7, alt_mm), verdict) {
                    Ok(origin) => {
                        self.send(&ack(command, MavResult::MAV_RESULT_ACCEPTED));
                        self.store_origin(&origin);
                    }
                    Err(why) => self.refuse(command, MavResult::MAV_RESULT_DENIED, why),
                },
            },
            Inbound::Param { request, from } => {
                let running = self.mission_state == MissionState::Running;
                let refuse_changes = if !verdict.trusted() {
                    Some(verdict.reason())
                } else if running {
                    Some("the mission is running")
                } else {
                    None
                };
                let before = self.params.values().clone();
                let answer = self.params.handle(&request, refuse_changes);
                match answer.changed {
                    Some((index, value)) => {
                        assert!(refuse_changes.is_none(), "a refused write changed {index}");
                        assert_eq!(self.params.values().get(index), Some(value));
                        if let Some(store) = &mut self.store
                            && let Err(e) = block_on(store.save(index, value))
                        {
                            self.store_failed = true;
                            self.report_text(Severity::Error, &format!("param: {e}"));
                        }
                        if is_origin(index) {
                            self.send(&gps_global_origin(&self.params.origin()));
                        } else {
                            self.config = self.params.values().config();
                            self.config_changed = true;
                            self.reload();
                        }
                    }
                    None => assert_eq!(
                        &before,
                        self.params.values(),
                        "a parameter changed without being reported"
                    ),
                }
                // The send task's order: one value at once, a list as the sender's list in
                // flight (sent whole here, the link always having room).
                match answer.values {
                    Values::None => {}
                    Values::One(i) => {
                        let m = value_message(self.params.values(), i).expect("an index in range");
                        self.send(&m);
                    }
                    Values::All => self.lists.request(from),
                }
                while let Some(i) = self.lists.next(PARAM_COUNT) {
                    let m = value_message(self.params.values(), i).expect("an index in range");
                    self.send(&m);
                }
                if let Some(text) = &answer.text {
                    self.report_text(Severity::Warning, text);
                }
            }
            Inbound::SetupSigning { key, timestamp, .. } => {
                if !self.options.key_setup_allowed {
                    self.report_text(Severity::Warning, "signing: key refused");
                    return;
                }
                let stored = match &mut self.store {
                    Some(store) => block_on(store.save_signing(&key, timestamp)),
                    None => Err(link::store::StoreError::Other),
                };
                match stored {
                    Ok(()) => self.stored_key = (key != [0; KEY_LEN]).then_some(key),
                    Err(_) => self.store_failed = true,
                }
                self.set_key(key, timestamp);
                let on = self.signing.enabled();
                assert_eq!(on, key != [0; KEY_LEN], "signing on with an all-zero key");
            }
            // As comms.rs's `handle_log` when no logger task runs (the fuzzed vehicle keeps
            // no logs): a list of none, the rest refused with a text.
            Inbound::Log { request, .. } => match request {
                LogRequest::Erase if !verdict.trusted() => {
                    self.report_text(Severity::Warning, "log erase refused");
                }
                LogRequest::List { .. } => self.send(&link::log_transfer::no_logs_entry()),
                LogRequest::End => {}
                LogRequest::Data { .. } | LogRequest::Erase => {
                    self.report_text(Severity::Warning, "flight logs: this board keeps none");
                }
            },
            Inbound::SetOrigin {
                lat_e7,
                lon_e7,
                alt_mm,
                ..
            } => {
                // comms.rs `set_origin`.
                match self.checked_origin((lat_e7, lon_e7, alt_mm), verdict) {
                    Ok(origin) => self.store_origin(&origin),
                    Err(why) => self.report_text(Severity::Warning, why),
                }
            }
            Inbound::Mission { message, from } => {
                // comms.rs `handle_mission`.
                let running = self.mission_state == MissionState::Running;
                let locked = if !verdict.trusted() {
                    Some(verdict.reason())
                } else if running {
                    Some(link::mission::RUNNING)
                } else {
                    None
                };
                let origin = self.params.origin();
                let context = MissionContext {
                    origin: &origin,
                    locked,
                };
                let before = self.mission.items().to_vec();
                let outcome = self.mission.handle(
                    &message,
                    (from.system, from.component),
                    self.now_us,
                    &context,
                );
                if locked.is_some() && !matches!(outcome.event, Some(MissionEvent::SetCurrent(_))) {
                    assert_eq!(
                        before,
                        self.mission.items(),
                        "a locked mission changed ({locked:?})"
                    );
                }
                self.deliver_mission(outcome);
            }
            Inbound::Ftp { message, from } if !verdict.trusted() => {
                self.send_ftp(&link::ftp::refusal(&message), from);
                // Said once per sender in a row (comms.rs `FTP_REFUSED`).
                let sender = 1 + (u32::from(from.system) << 8 | u32::from(from.component));
                if core::mem::replace(&mut self.ftp_refused, sender) != sender {
                    self.report_text(Severity::Warning, "payload upload refused");
                }
            }
            Inbound::Ftp { message, from } => {
                self.ftp_refused = 0;
                let (answer, event) = self.ftp.handle(&message);
                assert_eq!(
                    answer.seq,
                    message.seq.wrapping_add(1),
                    "FTP answer numbered"
                );
                self.send_ftp(&answer, from);
                if let FileEvent::Written { len } = event {
                    assert_eq!(len, self.ftp.file().len());
                    if self.options.fix_payload_checksum && len >= 4 {
                        let crc = CRC32.checksum(&self.ftp.file()[..len - 4]);
                        self.ftp.restore_buffer()[len - 4..len].copy_from_slice(&crc.to_le_bytes());
                    }
                    let file = self.ftp.file().to_vec();
                    self.check_payload(&file, true);
                }
            }
            Inbound::Invalid(e) => self.report_text(Severity::Warning, &format!("HIL: {e}")),
            Inbound::GcsHeartbeat(_) => self.gcs_heartbeat = true,
            Inbound::Battery { volts, .. } => self.link_battery_mv = (volts * 1000.0) as u32,
            Inbound::EscStatus(rpm) if self.in_hil => {
                if let Err(e) = self.link_esc_rpm.receive(&rpm) {
                    self.report_text(Severity::Warning, &format!("{e}"));
                }
            }
            Inbound::EscStatus(_) => {}
            Inbound::Heartbeat(_) | Inbound::Ignored { .. } => {}
        }
    }

    /// comms.rs `checked_origin`.
    fn checked_origin(
        &self,
        (lat_e7, lon_e7, alt_mm): (i32, i32, i32),
        verdict: Verdict,
    ) -> Result<GeoOrigin, &'static str> {
        if !verdict.trusted() {
            Err(verdict.reason())
        } else if self.mission_state == MissionState::Running {
            Err("the mission is running")
        } else {
            GeoOrigin::from_message(lat_e7, lon_e7, alt_mm).map_err(OriginError::as_str)
        }
    }

    /// comms.rs `store_origin`.
    fn store_origin(&mut self, origin: &GeoOrigin) {
        let changed = self
            .params
            .set_origin(origin)
            .expect("a checked origin fits its parameters");
        assert_eq!(self.params.origin(), *origin);
        for &(index, value) in &changed {
            if let Some(store) = &mut self.store
                && block_on(store.save(index, value)).is_err()
            {
                self.store_failed = true;
            }
            let m = value_message(self.params.values(), index).expect("an index in range");
            self.send(&m);
        }
        self.send(&gps_global_origin(origin));
    }

    fn refuse(&mut self, command: CommandId, result: MavResult, why: &str) {
        self.send(&ack(command, result));
        self.report_text(
            Severity::Warning,
            &format!("command {} refused: {why}", command.0),
        );
    }

    /// comms.rs `check_payload` and the job task's turn with it (jobs.rs).
    fn check_payload(&mut self, file: &[u8], store: bool) {
        match decode_and_check(file) {
            Ok((wire, scenario)) => {
                // The job task: the planner first, then the control task.
                match self.planner.load(&scenario, self.config) {
                    Ok(()) => {
                        self.report_text(
                            Severity::Info,
                            &format!("payload {} accepted", wire.name),
                        );
                        self.payload = Some((scenario.clone(), self.config));
                        self.last = Some(scenario);
                    }
                    Err(why) => {
                        self.report_text(Severity::Error, &format!("payload refused: {why}"))
                    }
                }
                if store && let Some(s) = &mut self.store {
                    match block_on(s.save_payload(file)) {
                        Ok(()) => self.stored_payload = Some(file.to_vec()),
                        Err(_) => self.store_failed = true,
                    }
                }
            }
            Err(e) => self.report_text(Severity::Error, &format!("payload refused: {e}")),
        }
    }

    /// The job task on `RELOAD`.
    fn reload(&mut self) {
        let running = self.mission_state == MissionState::Running;
        if let (Some(scenario), false) = (&self.last, running) {
            match self.planner.load(scenario, self.config) {
                Ok(()) => self.payload = Some((scenario.clone(), self.config)),
                Err(why) => {
                    let text = format!("params not applied: {why}");
                    self.report_text(Severity::Error, &text);
                }
            }
        }
    }

    /// A step of the board's IMU driver: a sample at rest on the board's clock.
    fn driver_step(&mut self) {
        self.driver_steps += 1;
        self.now_us += TICK_US;
        if self.options.mocap {
            self.mocap = Some(MocapFix {
                stamp_us: self.now_us,
                position: [0.0; 3],
                attitude: [1.0, 0.0, 0.0, 0.0],
            });
        }
        let imu = ImuSample {
            time_us: self.now_us,
            // A real sensor never repeats itself: the mission's IMU monitor stops on one that
            // does (shared::control::imu_monitor), so the driver's rest has a little noise.
            gyro: [0.0, 0.0, crate::rest_noise(self.driver_steps)],
            accel: [0.0, 0.0, -shared::scenario::GRAVITY],
        };
        self.control_step(imu, false);
        self.heartbeat_due();
    }

    /// control.rs: one step of the autonomy on an IMU sample.
    fn control_step(&mut self, imu: ImuSample, hil: bool) {
        let Ok(step) = self.clock.on_sensor(imu.time_us) else {
            self.report_text(Severity::Error, "sensor refused");
            return;
        };
        self.steps += 1;
        self.in_hil = hil;
        let job = if self.deadline.is_due(step.index) {
            self.deadline.taken();
            // The job ran at once: in lockstep the step would wait for it, off HIL it is in.
            match self.job_result.take() {
                Some((id, result)) if id == self.job_id => Some(result),
                _ => None,
            }
        } else {
            None
        };
        // The payload goes to the autonomy before the step, as the firmware's control task
        // hands it over.
        let payload = self.payload.take();
        let loaded_config = payload.as_ref().map(|(_, config)| *config);
        let loads_payload = payload.is_some();
        if let Some((scenario, config)) = payload {
            self.autonomy.take_payload(scenario, config);
        }
        if let Some(result) = job {
            self.autonomy.deliver_job(result);
        }
        let pending = self.commands.pop_front();
        let route = self.routes.pop_front();
        let input = TickInput {
            time_us: step.time_us,
            step: step.index,
            imu: ImuReading {
                gyro: imu.gyro,
                accel: imu.accel,
            },
            mocap: self.mocap.take(),
            command: pending.map(|p| p.command),
            faults: if hil {
                HardwareFaults::NONE
            } else {
                self.faults()
            },
            // The job task runs each load to the end before the next frame here.
            loading: false,
            route: route.as_ref(),
            // The plant's RPM in HIL; no ESC telemetry off HIL (no board here).
            esc_rpm: if hil {
                self.link_esc_rpm.rpm_at(step.time_us)
            } else {
                None
            },
            // The parameters' IMU offsets and hardware settings, as the firmware's control
            // task hands them over after a change.
            // (Not in a step that loads a payload: the settings go in the next.)
            bench: if loads_payload {
                None
            } else {
                core::mem::take(&mut self.config_changed).then(|| (&self.config).into())
            },
            supervision: Supervision {
                gcs_heartbeat: core::mem::take(&mut self.gcs_heartbeat),
                // The plant's pack in HIL; off HIL the board's ADC (none on the host).
                battery_volts: match self.link_battery_mv {
                    u32::MAX => None,
                    mv if hil => Some(mv as f32 * 1e-3),
                    _ => None,
                },
            },
        };
        let mut out = self.autonomy.tick(&input);
        if let Some(config) = loaded_config
            && !out.report.texts.iter().any(|t| t.text.contains("ignored"))
        {
            // Loaded: the mission is idle again, without a transition.
            assert_eq!(
                config, self.config,
                "the payload came with stale parameters"
            );
            self.phase = "idle".into();
        }
        for line in &out.report.texts {
            if let Some(rest) = line.text.strip_prefix(PHASE_PREFIX) {
                let name = rest.split(':').next().unwrap_or_default();
                self.phase = name.to_string();
                self.phases.push(rest.to_string());
            }
        }
        self.check_output(&out);
        if let Some(request) = out.job.take() {
            let next_id = self.job_id.wrapping_add(1);
            match self.deadline.request(step.index, request.deadline_steps) {
                Ok(_) => {
                    self.job_id = next_id;
                    let result = crate::autonomy::run_job(&mut self.planner, &request.work);
                    self.job_result = Some((next_id, result));
                }
                Err(_) => {
                    self.deadline.taken();
                    out.report
                        .text(Severity::Error, format_args!("job refused: busy"));
                }
            }
        }
        self.mission_state = out.state;
        self.armed = out.armed;
        // Every command is acknowledged.
        if let Some(p) = pending {
            let result = out.ack.map_or(CommandResult::Accepted, |(given, result)| {
                assert_eq!(given, p.command, "the ack is for another command");
                result
            });
            let result = match result {
                CommandResult::Accepted => MavResult::MAV_RESULT_ACCEPTED,
                CommandResult::InProgress => MavResult::MAV_RESULT_IN_PROGRESS,
                CommandResult::Failed => MavResult::MAV_RESULT_FAILED,
                CommandResult::TemporarilyRejected => MavResult::MAV_RESULT_TEMPORARILY_REJECTED,
                CommandResult::Denied => MavResult::MAV_RESULT_DENIED,
            };
            self.send(&ack(p.mav_cmd, result));
        }
        let time_ms = (step.time_us / 1000) as u32;
        self.send_report(&out.report, time_ms);
        if hil {
            let actuators = link::hil::Actuators {
                time_us: step.time_us,
                robots: out.robots,
                thrust: out.thrust,
                rail: out.rail,
                armed: out.armed,
            };
            let messages = actuators.to_messages();
            if let Some(status) = &messages.status {
                self.send(status);
            }
            self.send(&messages.controls);
        }
    }

    fn check_output(&self, out: &crate::autonomy::TickOutput) {
        assert!(out.robots <= MAX_ROBOTS);
        for j in 0..MAX_ROBOTS {
            let (t, r) = (out.thrust[j], out.rail[j]);
            assert!((0.0..=1.0).contains(&t), "thrust {j} is {t}");
            assert!(r.is_finite(), "rail setpoint {j} is {r}");
            if j >= out.robots {
                assert_eq!((t, r), (0.0, 0.0), "an output past the robots in use");
            }
        }
        let pushing = out.thrust.iter().any(|&t| t > 0.0);
        let phase = self.phase.as_str();
        if out.motor_test {
            assert!(out.armed, "a motor test disarmed");
            assert_ne!(
                out.state,
                MissionState::Running,
                "a motor test in the mission"
            );
            return;
        }
        assert_eq!(
            out.armed,
            ARMED_PHASES.contains(&phase),
            "armed {} in phase {phase}",
            out.armed
        );
        assert!(
            !pushing || THRUST_PHASES.contains(&phase),
            "thrust in phase {phase}"
        );
        assert!(out.armed || !pushing, "thrust while disarmed");
        let stopped = out.state != MissionState::Running;
        assert_eq!(
            stopped,
            STOPPED_PHASES.contains(&phase),
            "state {:?} in phase {phase}",
            out.state
        );
        assert!(!(stopped && out.armed), "armed while {:?}", out.state);
    }

    fn send_report(&mut self, report: &Report, time_ms: u32) {
        for line in &report.texts {
            let text = line.text.clone();
            self.report_text(line.severity, &text);
        }
        for v in &report.values {
            match v.value {
                Value::Float(x) => self.send(&named_float(v.name, x, time_ms)),
                Value::Int(x) => self.send(&named_int(v.name, x, time_ms)),
            }
        }
    }

    fn report_text(&mut self, severity: Severity, text: &str) {
        let severity = match severity {
            Severity::Info => MavSeverity::MAV_SEVERITY_INFO,
            Severity::Notice => MavSeverity::MAV_SEVERITY_NOTICE,
            Severity::Warning => MavSeverity::MAV_SEVERITY_WARNING,
            Severity::Error => MavSeverity::MAV_SEVERITY_ERROR,
            Severity::Critical => MavSeverity::MAV_SEVERITY_CRITICAL,
        };
        self.text_id = self.text_id.wrapping_add(1).max(1);
        for chunk in chunks(text, severity, self.text_id) {
            chunk.encode(&mut self.encoder, &mut self.frame);
            self.flush();
        }
    }

    fn send_identity(&mut self) {
        self.send(&AUTOPILOT_VERSION_DATA {
            capabilities: link::status::capabilities(),
            ..Default::default()
        });
        self.report_text(Severity::Info, "board: fuzz (firmware 0.1.0)");
    }

    /// comms.rs `deliver_mission`: the reply, the refusal, a route change for the autonomy.
    fn deliver_mission(&mut self, outcome: Outcome) {
        if let Some((reply, to)) = outcome.reply {
            reply.encode(to, &mut self.encoder, &mut self.frame);
            self.flush();
        }
        if let Some(text) = &outcome.refusal {
            self.report_text(Severity::Warning, text);
        }
        let change = match outcome.event {
            Some(MissionEvent::Replaced | MissionEvent::Cleared) => {
                let route = self
                    .mission
                    .route(&self.params.origin())
                    .unwrap_or_default();
                Some(RouteChange::Set(route))
            }
            Some(MissionEvent::SetCurrent(seq)) => Some(RouteChange::Current(seq)),
            None => None,
        };
        if let Some(change) = change {
            // The firmware's link task waits for room (the control task takes one a step);
            // with no step to wait for here, the oldest is dropped: the newest is in force
            // either way.
            if self.routes.len() == 2 {
                self.routes.pop_front();
            }
            self.routes.push_back(change);
        }
    }

    fn send_ftp(&mut self, message: &FtpMessage, to: Sender) {
        self.send(&message.to_message(to.system, to.component));
    }

    fn send<M: MessageData>(&mut self, message: &M) {
        self.encoder.encode(message, &mut self.frame);
        self.flush();
    }

    /// Signs the frame when signing is on, and checks that the ground reads it back.
    fn flush(&mut self) {
        if let Some(extra) = crc_extra(self.frame.message_id()) {
            self.signing.sign(&mut self.frame, extra, self.now_us);
        }
        self.sent += 1;
        let bytes = self.frame.bytes().to_vec();
        let mut got = None;
        for (i, &b) in bytes.iter().enumerate() {
            if let Some((frame, integrity)) = self.ground.push(b) {
                assert_eq!(i + 1, bytes.len(), "a sent frame parsed short");
                assert_eq!(
                    integrity,
                    Integrity::Verified,
                    "a sent frame does not verify"
                );
                got = Some(frame.clone());
            }
        }
        let frame = got.expect("a sent frame does not parse");
        assert_eq!(frame.bytes(), &bytes[..]);
        if self.signing.enabled() {
            let verdict = self.ground_signing.check(&frame, self.now_us);
            // At the end of its 48 bits the timestamp stays there: then equal timestamps are
            // replays, as they must be (a key set that close to the end leaves no room).
            let ended = self.signing.timestamp(self.now_us) == (1 << 48) - 1;
            if !(ended && verdict == Verdict::Replayed) {
                assert_eq!(verdict, Verdict::Valid, "a signed frame does not check");
            }
        }
    }
}

fn ns(us: u64) -> i64 {
    us.saturating_mul(1000) as i64
}

/// The store over `flash` with the Pixhawk 6C's ranges (comms.rs `open_params`).
fn open(flash: MemFlash) -> Result<ParamStore<MemFlash>, link::store::StoreError> {
    ParamStore::new(flash, PARAM_RANGE).and_then(|s| s.with_payload(PAYLOAD_RANGE))
}

/// Runs one `link_input` fuzz input: the header's options, then the byte stream.
pub fn run(data: &[u8]) -> Option<Vehicle> {
    let header: [u8; Options::HEADER_LEN] = data.get(..Options::HEADER_LEN)?.try_into().ok()?;
    let options = Options::from_header(header);
    let mut vehicle = Vehicle::start(options);
    if options.fix_checksums {
        let mut stream = data[Options::HEADER_LEN..].to_vec();
        fix_checksums(&mut stream);
        vehicle.receive(&stream);
    } else {
        vehicle.receive(&data[Options::HEADER_LEN..]);
    }
    Some(vehicle)
}

/// Recomputes the checksum of each frame of `stream` whose message the vehicle knows, where
/// the parser ([`link::frame::Parser`]) will find it: its state machine, followed over the
/// bytes (a start byte begins a frame; a MAVLink 2 header with flags other than "signed" is
/// dropped; a whole frame is taken, and the search goes on after it).
pub fn fix_checksums(stream: &mut [u8]) {
    use link::frame::{STX_V1, STX_V2};
    use link::signing::{IFLAG_SIGNED, SIGNATURE_LEN};
    let mut i = 0;
    while i < stream.len() {
        let stx = stream[i];
        if stx != STX_V1 && stx != STX_V2 {
            i += 1;
            continue;
        }
        let v1 = stx == STX_V1;
        let header = if v1 { 6 } else { 10 };
        if i + header > stream.len() {
            return;
        }
        let h = &stream[i..i + header];
        if !v1 && h[2] & !IFLAG_SIGNED != 0 {
            i += header;
            continue;
        }
        let crc_end = i + header + usize::from(h[1]);
        let id = if v1 {
            u32::from(h[5])
        } else {
            u32::from_le_bytes([h[7], h[8], h[9], 0])
        };
        let signature = if !v1 && h[2] & IFLAG_SIGNED != 0 {
            SIGNATURE_LEN
        } else {
            0
        };
        if crc_end + 2 + signature > stream.len() {
            return;
        }
        if let Some(extra) = crc_extra(id) {
            let crc = mavlink::calculate_crc(&stream[i + 1..crc_end], extra);
            stream[crc_end..crc_end + 2].copy_from_slice(&crc.to_le_bytes());
        }
        i = crc_end + 2 + signature;
    }
}
