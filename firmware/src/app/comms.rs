//! The MAVLink link's two tasks, on the link executor: receiving
//! (framing, dispatch to the services, the FTP server, the payload's checks, the parameter
//! service and its store, the log requests handed to the logger task) and sending (each
//! control step's messages in order, replies, heartbeat). The protocol logic is the `link`
//! crate's, host-tested; this is the glue to the board's byte stream and the other tasks.
//!
//! Each control step goes out as: its texts (`STATUSTEXT`), values (`NAMED_VALUE_*`), the
//! command's `COMMAND_ACK`, a `HEARTBEAT` when the mission state changed, then in HIL the
//! actuator commands (`ACTUATOR_OUTPUT_STATUS` past 8 robots, and `HIL_ACTUATOR_CONTROLS`,
//! the lockstep reply, last). So the plant has everything a step said before it steps on.

use core::sync::atomic::Ordering;

use embassy_futures::select::{select3, select4};
use embassy_time::{Duration, Instant, Timer};
use embedded_io_async::{Read, Write};
use link::MessageData;
use link::bandwidth::LinkBudget;
use link::command::{Request, ack};
use link::command_wire::CommandId;
use link::frame::{Encoder, Frame, Parser};
use link::ftp::{FileEvent, FtpMessage, Server, component_metadata};
use link::geo::{GeoOrigin, OriginError};
use link::hil::{Actuators, ImuSample};
use link::link_health::LinkHealth;
use link::log_transfer::{LogReply, LogRequest};
use link::mission::stored::{self, MAX_STORED_LEN};
use link::mission::wire::{MissionMessage, MissionReply};
use link::mission::{Context as MissionContext, MissionEvent, MissionService, Outcome, Peer};
use link::modes::{FlightMode, MODES};
use link::msg::{
    AUTOPILOT_VERSION_DATA, COMPONENT_METADATA_DATA, CURRENT_MODE_DATA, GPS_GLOBAL_ORIGIN_DATA,
    HOME_POSITION_DATA, MavResult, MavSeverity, TIMESYNC_DATA,
};
use link::param::{ParamRequest, ParamService, Values, value_message};
use link::param_lists::ParamLists;
use link::signing::{KEY_LEN, Verdict};
use link::status::{MissionState, Text, chunks, heartbeat, named_float, named_int};
use link::store::ParamStore;
use link::telemetry::{Home, RouteStatus, Stream, VehicleSnapshot, gps_global_origin};
use link::timesync::Received as SyncReceived;
use link::vehicle::{Inbound, Sender, crc_extra, dispatch};
use shared::control::thrust_map::ThrustMap;
use shared::mission::bringup::CalibrationKind;
use shared::mission::params::{COUNT as PARAM_COUNT, ParamValues, TABLE, is_origin};
use shared::scenario::Scenario;
use shared::scenario_wire::{
    MAX_ENCODED_LEN, MAX_NAME_LEN, PayloadError, decode_and_check, decode_for_board,
};
use static_cell::StaticCell;

/// The component metadata the FTP server serves (docs/ground-link.md#parameter-metadata),
/// written by the build script from the parameter table.
mod metadata {
    include!(concat!(env!("OUT_DIR"), "/metadata.rs"));
}

use super::autonomy::RouteChange;
use super::autonomy::{CommandResult, ImuReading, OperatorCommand, Report, Severity, Value};
use super::{
    ARMED, BULK, CALIBRATED, COMMANDS, GCS_HEARTBEAT, IN_HIL, LINK, LINK_BATTERY_MV, LIST_STARTED,
    MISSION_CONFIG, MISSION_ITEMS, MISSION_STATE, MOCAP, OUTBOX, RELOAD, ROUTE, ROUTE_SENT, SENSOR,
    STATUS_CHANGES, STEP_OUT, TELEMETRY_CHANGED, TO_LOAD, VEHICLE, signing, telemetry, timesync,
};
use crate::board::{Board, Selected};

/// An IMU sample for the control task.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorSample {
    /// The sample, stamped with the vehicle's time.
    pub imu: ImuSample,
    /// It came from the HIL plant (the step's reply goes back to it).
    pub hil: bool,
}

impl SensorSample {
    /// The sample as the autonomy takes it.
    pub fn reading(&self) -> ImuReading {
        ImuReading {
            gyro: self.imu.gyro,
            accel: self.imu.accel,
        }
    }
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
    /// The `PARAM_VALUE`s of these indices (bit `i`: index `i`; the values a request changed
    /// go as one entry), from the values in force ([`LinkShared`]).
    Params(u128),
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

/// What the receive and send tasks share besides their queues ([`super::LINK`]).
pub struct LinkShared {
    /// The parameters in force (the receive task's, copied at each change): the send task's
    /// `PARAM_VALUE`s and map origin come from them.
    pub values: ParamValues,
    /// The parameter lists in flight.
    pub lists: ParamLists,
    /// What the link dropped.
    pub health: LinkHealth,
}

impl LinkShared {
    /// At start: the default values, no list, nothing dropped.
    pub const START: Self = Self {
        values: ParamValues::DEFAULT,
        lists: ParamLists::new(),
        health: LinkHealth::new(),
    };
}

// Every parameter's index is a bit of `Outbound::Params`.
const _: () = assert!(PARAM_COUNT <= 128);

/// Queues a reply for the send task without waiting: one that finds the queue full is dropped
/// and counted (docs/ground-link.md#under-a-flood).
fn reply(message: Outbound) {
    if OUTBOX.try_send(message).is_err() {
        LINK.lock(|l| l.borrow_mut().health.reply_dropped());
    }
}

/// Queues a bulk transfer's message without waiting, as [`reply`].
fn bulk(message: Bulk) {
    if BULK.try_send(message).is_err() {
        LINK.lock(|l| l.borrow_mut().health.reply_dropped());
    }
}

/// Hands the values in force to the send task (after every change).
fn publish(params: &ParamService) {
    LINK.lock(|l| l.borrow_mut().values = params.values().clone());
}

/// The parameters' store on this board.
type Store = ParamStore<<Selected as Board>::ParamFlash>;

/// The link id the vehicle signs with (one link at a time).
const LINK_ID: u8 = 0;

/// Oldest a motion-capture fix may be when it arrives for its own stamp to be used, us (the
/// attitude estimator keeps 160 ms of history to compensate a fix's latency).
const MAX_FIX_AGE_US: u64 = 150_000;

/// Most bytes the link's budget holds after a quiet spell (a few messages at once).
const LINK_BURST: u32 = 1024;

/// Largest payload description file the vehicle takes.
const FILE_CAPACITY: usize = MAX_ENCODED_LEN;

static FTP: StaticCell<Server<FILE_CAPACITY>> = StaticCell::new();
/// The mission protocol's service: the items in force and an upload's.
static MISSION: StaticCell<MissionService> = StaticCell::new();

/// A report of one text line, ready for the send task.
pub fn report(severity: Severity, args: core::fmt::Arguments<'_>) -> Outbound {
    let mut r = Report::default();
    r.text(severity, args);
    Outbound::Report(r)
}

/// Opens the parameters' store, reads the stored values and puts them in force; says what
/// it found.
async fn open_params(flash: <Selected as Board>::ParamFlash) -> (ParamService, Option<Store>) {
    let mut values = ParamValues::DEFAULT;
    let opened = ParamStore::new(flash, <Selected as Board>::PARAM_RANGE)
        .and_then(|s| s.with_payload(<Selected as Board>::PAYLOAD_RANGE))
        .and_then(|s| s.with_mission(<Selected as Board>::MISSION_RANGE));
    let store = match opened {
        Ok(mut store) => {
            let loaded = store.load(&mut values).await;
            // Built in a block: a report that was borrowed would be kept in the receive
            // task's future (a static) beside the copy in the wait for the link's queue.
            let r = {
                let mut r = Report::default();
                r.text(
                    Severity::Info,
                    format_args!(
                        "params: {} of {PARAM_COUNT} restored from storage",
                        loaded.restored
                    ),
                );
                if loaded.refused > 0 {
                    r.text(
                        Severity::Warning,
                        format_args!(
                            "params: {} stored values out of today's ranges, defaults used",
                            loaded.refused
                        ),
                    );
                }
                if let Some(e) = loaded.error {
                    r.text(Severity::Error, format_args!("params: {e}"));
                }
                if GeoOrigin::from_params(&values) == GeoOrigin::from_params(&ParamValues::DEFAULT)
                {
                    r.text(
                        Severity::Notice,
                        format_args!("origin: not set; the map shows PX4's simulation home"),
                    );
                }
                if !<Selected as Board>::PARAM_FLASH_PERSISTENT {
                    r.text(
                        Severity::Warning,
                        format_args!("params: kept in RAM on this board, lost at power-off"),
                    );
                }
                r
            };
            OUTBOX.send(Outbound::Report(r)).await;
            Some(store)
        }
        Err(e) => {
            OUTBOX
                .send(report(Severity::Error, format_args!("params: {e}")))
                .await;
            None
        }
    };
    let service = ParamService::new(values);
    super::set_config(service.values().config());
    // Waited for, as the texts above: the send task may not have begun.
    publish(&service);
    OUTBOX.send(Outbound::Origin).await;
    (service, store)
}

/// Reads the link, forever: every frame to its service.
#[embassy_executor::task]
pub async fn receive(
    mut rx: <Selected as Board>::LinkRx,
    param_flash: <Selected as Board>::ParamFlash,
) {
    let mut parser = Parser::new(crc_extra);
    let ftp = FTP.init(Server::new());
    let mission = MISSION.init(MissionService::new());
    let (mut params, mut store) = open_params(param_flash).await;
    restore_signing(&mut store).await;
    restore_payload(ftp, &mut store).await;
    restore_mission(mission, &params.origin(), &mut store).await;
    let mut buf = [0u8; 64];
    loop {
        // A board's read error (a UART framing error) loses bytes the parser resyncs over.
        let n = rx.read(&mut buf).await.unwrap_or(0);
        for &byte in &buf[..n] {
            let Some((frame, integrity)) = parser.push(byte) else {
                continue;
            };
            let verdict = signing(|s| s.check(frame, Instant::now().as_micros()));
            let inbound = dispatch(frame, integrity);
            handle(inbound, verdict, ftp, mission, &mut params, &mut store).await;
        }
        LINK.lock(|l| l.borrow_mut().health.parsed(parser.stats()));
        // A flood of bytes (each read ready at once) must not keep the send task, on this
        // executor, from the control step's messages and the heartbeat.
        embassy_futures::yield_now().await;
        // An upload's timeout, looked at whenever bytes come (in flight at least the ground
        // station's heartbeat, once a second).
        if let Some(outcome) = mission.poll(Instant::now().as_micros()) {
            deliver_mission(outcome, mission, &params.origin(), &mut store).await;
        }
        // A calibration's offsets, looked at whenever bytes come (as the upload's timeout).
        if let Ok((kind, offsets)) = CALIBRATED.try_receive() {
            store_calibration(kind, offsets, &mut params, &mut store).await;
        }
    }
}

/// Sets a calibration's offsets as their parameters (`CAL_GYRO0_*OFF` or `CAL_ACC0_*OFF`),
/// stores them and sends their `PARAM_VALUE`s (the mission has them in force already).
async fn store_calibration(
    kind: CalibrationKind,
    offsets: [f32; 3],
    params: &mut ParamService,
    store: &mut Option<Store>,
) {
    let names = match kind {
        CalibrationKind::Gyro => ["CAL_GYRO0_XOFF", "CAL_GYRO0_YOFF", "CAL_GYRO0_ZOFF"],
        CalibrationKind::Level => ["CAL_ACC0_XOFF", "CAL_ACC0_YOFF", "CAL_ACC0_ZOFF"],
    };
    let mut answered = 0u128;
    for (name, value) in names.into_iter().zip(offsets) {
        let mut id = [0u8; shared::mission::params::NAME_LEN];
        id[..name.len()].copy_from_slice(name.as_bytes());
        let answer = params.handle(&ParamRequest::Set { name: id, value }, None);
        if let Some((index, value)) = answer.changed {
            save_param(store, index, value).await;
        }
        if let Values::One(index) = answer.values {
            answered |= 1 << index;
        }
    }
    // The three values as one entry of the queue.
    publish(params);
    reply(Outbound::Params(answered));
    MISSION_CONFIG.lock(|c| c.set(params.values().config()));
}

/// Sends the `PARAM_VALUE`s a parameter request asks for, from the values in force (handed to
/// the send task first): one at once, every one as `from`'s list, which a new request from
/// the same sender restarts (docs/ground-link.md#under-a-flood).
fn send_values(params: &ParamService, which: Values, from: Option<Sender>) {
    publish(params);
    match (which, from) {
        (Values::None, _) => {}
        (Values::One(index), _) => reply(Outbound::Params(1 << index)),
        (Values::All, Some(from)) => {
            LINK.lock(|l| l.borrow_mut().lists.request(from));
            LIST_STARTED.signal(());
        }
        // Every value without a requester: not asked for.
        (Values::All, None) => {}
    }
}

/// Loads the stored payload description, if one is stored and passes the checks, as if it had
/// just been uploaded.
async fn restore_payload(ftp: &mut Server<FILE_CAPACITY>, store: &mut Option<Store>) {
    let Some(store) = store else {
        return;
    };
    let valid = |bytes: &[u8]| decode_and_check(bytes).is_ok();
    match store.load_payload(ftp.restore_buffer(), valid).await {
        Ok(Some(len)) => {
            ftp.restored(len);
            OUTBOX
                .send(report(
                    Severity::Info,
                    format_args!("payload description restored from storage"),
                ))
                .await;
            check_payload(ftp.file(), &mut None).await;
        }
        Ok(None) => {}
        Err(e) => {
            OUTBOX
                .send(report(
                    Severity::Error,
                    format_args!("payload description not read from storage: {e}"),
                ))
                .await;
        }
    }
}

/// Puts the stored signing key in force, if one is stored; says so.
async fn restore_signing(store: &mut Option<Store>) {
    let Some(store) = store else {
        return;
    };
    match store.load_signing().await {
        Ok(Some((key, timestamp))) => {
            signing(|s| s.set_key(key, timestamp, Instant::now().as_micros(), LINK_ID));
            OUTBOX
                .send(report(
                    Severity::Info,
                    format_args!("signing: on (key restored)"),
                ))
                .await;
        }
        Ok(None) => {}
        Err(e) => {
            OUTBOX
                .send(report(
                    Severity::Error,
                    format_args!("signing: stored key not read ({e}); signing off"),
                ))
                .await;
        }
    }
}

/// Sets (or with an all-zero key clears) the signing key, on a link that may (see
/// [`Board::key_setup_allowed`]); stores it before saying so.
async fn setup_signing(key: [u8; KEY_LEN], timestamp: u64, store: &mut Option<Store>) {
    if !<Selected as Board>::key_setup_allowed() {
        reply(report(
            Severity::Warning,
            format_args!("signing: key refused: it is set over USB only"),
        ));
        return;
    }
    let stored = match store {
        Some(store) => store.save_signing(&key, timestamp).await,
        None => Err(link::store::StoreError::Other),
    };
    let on = signing(|s| {
        s.set_key(key, timestamp, Instant::now().as_micros(), LINK_ID);
        s.enabled()
    });
    // Built in a block, as in `open_params`.
    let r = {
        let mut r = Report::default();
        if on {
            r.text(
                Severity::Notice,
                format_args!("signing: on; unsigned commands and parameter writes are refused"),
            );
        } else {
            r.text(Severity::Notice, format_args!("signing: off"));
        }
        if let Err(e) = stored {
            r.text(
                Severity::Error,
                format_args!("signing: key in force but not stored: {e}"),
            );
        }
        r
    };
    reply(Outbound::Report(r));
}

/// `MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN`: refused while armed or while the mission runs;
/// otherwise acknowledged, said, and the processor reset once both are out.
async fn reboot(command: CommandId) {
    let running = MISSION_STATE.load(Ordering::Relaxed) == MissionState::Running as u8;
    if ARMED.load(Ordering::Relaxed) || running {
        let why = "the vehicle is armed or the mission is running";
        refuse(command, MavResult::MAV_RESULT_DENIED, why).await;
        return;
    }
    let result = MavResult::MAV_RESULT_ACCEPTED;
    OUTBOX.send(Outbound::Ack { command, result }).await;
    OUTBOX
        .send(report(
            Severity::Notice,
            format_args!("rebooting the flight controller"),
        ))
        .await;
    // Time for the send task to put both on the wire (a few hundred bytes).
    Timer::after(Duration::from_millis(200)).await;
    cortex_m::peripheral::SCB::sys_reset();
}

/// Stores parameter `index` as `value`, already in force; says so when it cannot be stored.
async fn save_param(store: &mut Option<Store>, index: usize, value: f32) {
    let stored = match store {
        Some(store) => store.save(index, value).await,
        None => Err(link::store::StoreError::Other),
    };
    if let Err(e) = stored {
        reply(report(
            Severity::Error,
            format_args!("param {} in force but not stored: {e}", TABLE[index].name),
        ));
    }
}

/// Answers a parameter request, puts a changed value in force and stores it. The value is
/// stored before its `PARAM_VALUE` goes out, so a ground station that saw the answer may cut
/// the power.
async fn handle_param(
    request: ParamRequest,
    from: Sender,
    verdict: Verdict,
    params: &mut ParamService,
    store: &mut Option<Store>,
) {
    let running = MISSION_STATE.load(Ordering::Relaxed) == MissionState::Running as u8;
    let refuse_changes = if !verdict.trusted() {
        Some(verdict.reason())
    } else if running {
        Some("the mission is running")
    } else {
        None
    };
    let robots = usize::from(super::PAYLOAD_ROBOTS.load(Ordering::Relaxed));
    params.drive_robots(robots, <Selected as Board>::drives());
    let answer = params.handle(&request, refuse_changes);
    if let Some((index, value)) = answer.changed {
        save_param(store, index, value).await;
        if is_origin(index) {
            announce_origin(params);
        } else {
            // In force now for the loaded payload (the mission is not running) and the next.
            super::set_config(params.values().config());
            RELOAD.signal(());
        }
    }
    send_values(params, answer.values, Some(from));
    if let Some(text) = &answer.text {
        reply(report(Severity::Warning, format_args!("{text}")));
    }
}

/// Hands a log request to the logger task, which owns the storage; a board that keeps no
/// logs lists none, and an erase must be signed once signing is on.
async fn handle_log(request: LogRequest, verdict: Verdict) {
    if request == LogRequest::Erase && !verdict.trusted() {
        reply(report(
            Severity::Warning,
            format_args!("log erase refused: {}", verdict.reason()),
        ));
        return;
    }
    if !super::logger::request(request) {
        match request {
            LogRequest::List { .. } => {
                bulk(Bulk::Log(LogReply::Entry(
                    link::log_transfer::no_logs_entry(),
                )));
            }
            LogRequest::End => {}
            LogRequest::Data { .. } | LogRequest::Erase => {
                reply(report(
                    Severity::Warning,
                    format_args!("flight logs: this board keeps none"),
                ));
            }
        }
    }
}

async fn refuse(command: CommandId, result: MavResult, why: &str) {
    reply(Outbound::Ack { command, result });
    reply(report(
        Severity::Warning,
        format_args!("command {} refused: {why}", command.0),
    ));
}

/// Hands the map origin in force to the send task, which sends `GPS_GLOBAL_ORIGIN` and says
/// when the global position cannot be given (docs/ground-link.md#the-map-origin).
fn announce_origin(params: &ParamService) {
    publish(params);
    reply(Outbound::Origin);
}

/// The origin a `SET_GPS_GLOBAL_ORIGIN` or `MAV_CMD_DO_SET_GLOBAL_ORIGIN` asks for, checked:
/// refused as a `PARAM_SET` is (unsigned once signing is on, or while the mission runs), or
/// when it cannot place the vehicle (the reason).
fn checked_origin(
    (lat_e7, lon_e7, alt_mm): (i32, i32, i32),
    verdict: Verdict,
) -> Result<GeoOrigin, &'static str> {
    let running = MISSION_STATE.load(Ordering::Relaxed) == MissionState::Running as u8;
    if !verdict.trusted() {
        Err(verdict.reason())
    } else if running {
        Err("the mission is running")
    } else {
        GeoOrigin::from_message(lat_e7, lon_e7, alt_mm).map_err(OriginError::as_str)
    }
}

/// `SET_GPS_GLOBAL_ORIGIN`: the origin's five parameters set and stored together
/// ([`checked_origin`]); answered with their `PARAM_VALUE`s and `GPS_GLOBAL_ORIGIN`.
async fn set_origin(
    origin: (i32, i32, i32),
    verdict: Verdict,
    params: &mut ParamService,
    store: &mut Option<Store>,
) {
    match checked_origin(origin, verdict) {
        Ok(origin) => store_origin(&origin, params, store).await,
        Err(why) => {
            reply(report(
                Severity::Warning,
                format_args!("origin not changed: {why}"),
            ));
        }
    }
}

/// `MAV_CMD_DO_SET_GLOBAL_ORIGIN` (a `COMMAND_INT`): as `SET_GPS_GLOBAL_ORIGIN`, acknowledged
/// first (a refusal `DENIED` with the reason; docs/ground-link.md#commands-long-or-int).
async fn command_origin(
    command: CommandId,
    origin: (i32, i32, i32),
    verdict: Verdict,
    params: &mut ParamService,
    store: &mut Option<Store>,
) {
    match checked_origin(origin, verdict) {
        Ok(origin) => {
            let result = MavResult::MAV_RESULT_ACCEPTED;
            reply(Outbound::Ack { command, result });
            store_origin(&origin, params, store).await;
        }
        Err(why) => refuse(command, MavResult::MAV_RESULT_DENIED, why).await,
    }
}

/// Sets and stores a checked origin's parameters; sends their `PARAM_VALUE`s and
/// `GPS_GLOBAL_ORIGIN`.
async fn store_origin(origin: &GeoOrigin, params: &mut ParamService, store: &mut Option<Store>) {
    let Ok(changed) = params.set_origin(origin) else {
        return;
    };
    let mut answered = 0u128;
    for &(index, value) in &changed {
        if let Some(store) = store
            && let Err(e) = store.save(index, value).await
        {
            reply(report(
                Severity::Error,
                format_args!("param {} in force but not stored: {e}", TABLE[index].name),
            ));
        }
        answered |= 1 << index;
    }
    // One entry for the five values: the queue keeps room for the origin after them (whose
    // announcement hands the send task the values in force).
    reply(Outbound::Params(answered));
    announce_origin(params);
}

/// The sender whose MAVLink FTP was last refused (system << 8 | component, plus one; 0: none
/// since the last FTP request answered).
static FTP_REFUSED: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

async fn handle(
    inbound: Inbound,
    verdict: Verdict,
    ftp: &mut Server<FILE_CAPACITY>,
    mission: &mut MissionService,
    params: &mut ParamService,
    store: &mut Option<Store>,
) {
    match inbound {
        Inbound::Sensor(imu) => {
            // Known here already, so a fix right behind the first sample is taken as HIL's.
            IN_HIL.store(true, Ordering::Relaxed);
            if SENSOR.try_send(SensorSample { imu, hil: true }).is_err() {
                reply(report(
                    Severity::Warning,
                    format_args!("HIL_SENSOR dropped: the control step is behind"),
                ));
            }
        }
        Inbound::Mocap(mut fix) => {
            // In HIL the plant's clock is the vehicle's (lockstep); a real motion-capture
            // computer's stamp is mapped to the vehicle's clock (or the arrival is used).
            if !IN_HIL.load(Ordering::Relaxed) {
                let arrival_us = Instant::now().as_micros();
                fix.stamp_us = timesync(|t| t.stamp(fix.stamp_us, arrival_us, MAX_FIX_AGE_US));
            }
            MOCAP.signal(fix)
        }
        Inbound::TimeSync { tc1, ts1 } => {
            let now_ns = Instant::now().as_micros().saturating_mul(1000) as i64;
            let message = TIMESYNC_DATA { tc1, ts1 };
            if let SyncReceived::Answer(a) = timesync(|t| t.receive(&message, now_ns)) {
                reply(Outbound::TimeSync {
                    tc1: a.tc1,
                    ts1: a.ts1,
                });
            }
        }
        Inbound::Command {
            command,
            request,
            from,
        } => match request {
            Request::AvailableModes(index) => {
                if usize::from(index) > MODES.len() {
                    let result = MavResult::MAV_RESULT_DENIED;
                    refuse(command, result, "no mode of that index").await;
                } else {
                    let result = MavResult::MAV_RESULT_ACCEPTED;
                    reply(Outbound::Ack { command, result });
                    reply(Outbound::AvailableModes(index));
                }
            }
            Request::Message(id) if id == CURRENT_MODE_DATA::ID => {
                let result = MavResult::MAV_RESULT_ACCEPTED;
                reply(Outbound::Ack { command, result });
                reply(Outbound::CurrentMode);
            }
            Request::Message(id) if id == AUTOPILOT_VERSION_DATA::ID => {
                let result = MavResult::MAV_RESULT_ACCEPTED;
                reply(Outbound::Ack { command, result });
                reply(Outbound::Identity);
            }
            Request::Message(id) if id == COMPONENT_METADATA_DATA::ID => {
                let result = MavResult::MAV_RESULT_ACCEPTED;
                reply(Outbound::Ack { command, result });
                reply(Outbound::ComponentMetadata);
            }
            Request::Message(id)
                if id == HOME_POSITION_DATA::ID || id == GPS_GLOBAL_ORIGIN_DATA::ID =>
            {
                if let Err(e) = params.origin().check() {
                    let result = MavResult::MAV_RESULT_DENIED;
                    refuse(command, result, e.as_str()).await;
                } else {
                    let result = MavResult::MAV_RESULT_ACCEPTED;
                    reply(Outbound::Ack { command, result });
                    reply(if id == HOME_POSITION_DATA::ID {
                        Outbound::Home
                    } else {
                        Outbound::Origin
                    });
                }
            }
            Request::Message(id) => {
                if telemetry(|t| t.request_once(id)) {
                    TELEMETRY_CHANGED.signal(());
                    let result = MavResult::MAV_RESULT_ACCEPTED;
                    reply(Outbound::Ack { command, result });
                } else {
                    let result = MavResult::MAV_RESULT_UNSUPPORTED;
                    refuse(command, result, "that message is not sent on request").await;
                }
            }
            // Once signing is on, only reading goes without a signature.
            _ if !verdict.trusted() => {
                refuse(command, MavResult::MAV_RESULT_DENIED, verdict.reason()).await;
            }
            Request::Operator(operator) => {
                let pending = PendingCommand {
                    command: operator,
                    mav_cmd: command,
                    from,
                };
                if COMMANDS.try_send(pending).is_err() {
                    let result = MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
                    reply(Outbound::Ack { command, result });
                }
            }
            Request::SetInterval {
                message_id,
                interval_us,
            } => {
                let now = Instant::now().as_micros();
                let result = telemetry(|t| t.set_interval(message_id, interval_us, now));
                match result {
                    MavResult::MAV_RESULT_ACCEPTED => {
                        TELEMETRY_CHANGED.signal(());
                        reply(Outbound::Ack { command, result });
                    }
                    MavResult::MAV_RESULT_UNSUPPORTED => {
                        refuse(command, result, "that message is not streamed").await;
                    }
                    _ => {
                        refuse(
                            command,
                            result,
                            "the interval must be -1, 0 or 5,000 us to 1 hour",
                        )
                        .await;
                    }
                }
            }
            Request::SetOrigin {
                lat_e7,
                lon_e7,
                alt_mm,
            } => command_origin(command, (lat_e7, lon_e7, alt_mm), verdict, params, store).await,
            Request::Refused(result) => {
                refuse(command, result, link::command::refusal(command, result)).await;
            }
            Request::Reboot => reboot(command).await,
        },
        Inbound::Param { request, from } => {
            handle_param(request, from, verdict, params, store).await;
        }
        Inbound::SetupSigning { key, timestamp, .. } => {
            setup_signing(key, timestamp, store).await;
        }
        Inbound::Mission { message, from } => {
            handle_mission(&message, from, verdict, mission, params, store).await;
        }
        Inbound::Log { request, .. } => handle_log(request, verdict).await,
        Inbound::SetOrigin {
            lat_e7,
            lon_e7,
            alt_mm,
            ..
        } => set_origin((lat_e7, lon_e7, alt_mm), verdict, params, store).await,
        Inbound::Ftp { message, from } if !verdict.trusted() => {
            bulk(Bulk::Ftp {
                message: link::ftp::refusal(&message),
                to: from,
            });
            // Said once per sender in a row: a ground station that retries its file reads
            // (MAVProxy's) would fill its own console with the same line.
            let sender = 1 + (u32::from(from.system) << 8 | u32::from(from.component));
            if FTP_REFUSED.swap(sender, Ordering::Relaxed) != sender {
                reply(report(
                    Severity::Warning,
                    format_args!("payload upload refused: {}", verdict.reason()),
                ));
            }
        }
        Inbound::Ftp { message, from } => {
            FTP_REFUSED.store(0, Ordering::Relaxed);
            let (answer, event) = ftp.handle_with(&message, &metadata::FILES);
            bulk(Bulk::Ftp {
                message: answer,
                to: from,
            });
            if let FileEvent::Written { .. } = event {
                check_payload(ftp.file(), store).await;
            }
        }
        Inbound::Invalid(e) => {
            reply(report(
                Severity::Warning,
                format_args!("HIL message refused: {e}"),
            ));
        }
        // The ground link is up: the next control step takes it.
        Inbound::GcsHeartbeat(_) => GCS_HEARTBEAT.store(true, Ordering::Relaxed),
        Inbound::Battery { volts, .. } => {
            LINK_BATTERY_MV.store((volts * 1000.0) as u32, Ordering::Relaxed);
        }
        // The plant's RPM, in HIL only (on a board the ESCs answer over DShot).
        Inbound::EscStatus(rpm) if IN_HIL.load(Ordering::Relaxed) => {
            let taken = super::LINK_ESC_RPM.lock(|inbox| inbox.borrow_mut().receive(&rpm));
            if let Err(e) = taken {
                reply(report(Severity::Warning, format_args!("{e}")));
            }
        }
        Inbound::EscStatus(_) => {}
        Inbound::Heartbeat(_) | Inbound::Ignored { .. } => {}
    }
}

/// Puts the stored mission in force, if one is stored and still makes a route with the map
/// origin; says what it found.
async fn restore_mission(
    mission: &mut MissionService,
    origin: &GeoOrigin,
    store: &mut Option<Store>,
) {
    let Some(store) = store else {
        return;
    };
    let mut bytes = [0u8; MAX_STORED_LEN];
    let valid = |b: &[u8]| stored::decode(b).is_some();
    let loaded = store.load_mission(&mut bytes, valid).await;
    let items = match loaded {
        Ok(Some(len)) => stored::decode(&bytes[..len]).unwrap_or_default(),
        Ok(None) => return,
        Err(e) => {
            OUTBOX
                .send(report(
                    Severity::Error,
                    format_args!("mission not read from storage: {e}"),
                ))
                .await;
            return;
        }
    };
    if items.is_empty() {
        return;
    }
    match mission.restore(&items, origin) {
        Ok(()) => {
            offer_route(mission, origin).await;
            OUTBOX
                .send(report(
                    Severity::Info,
                    format_args!("mission of {} items restored from storage", items.len()),
                ))
                .await;
        }
        Err((i, problem)) => {
            OUTBOX
                .send(report(
                    Severity::Warning,
                    format_args!("stored mission not flown: item {i}: {problem}"),
                ))
                .await;
        }
    }
}

/// Hands the mission in force to the autonomy as a route to fly (an empty one when it cannot
/// be flown with `origin`: the payload description's target then).
async fn offer_route(mission: &MissionService, origin: &GeoOrigin) {
    let route = mission.route(origin).unwrap_or_default();
    MISSION_ITEMS.store(mission.items().len() as u16, Ordering::Relaxed);
    ROUTE.send(RouteChange::Set(route)).await;
    ROUTE_SENT.store(true, Ordering::Release);
}

/// A mission-protocol message: answered, and a mission replaced or cleared is handed to the
/// autonomy and stored. Downloads need no signature; changes do, and none while the mission
/// runs but a set-current (docs/ground-link.md#missions).
async fn handle_mission(
    message: &MissionMessage,
    from: Sender,
    verdict: Verdict,
    mission: &mut MissionService,
    params: &ParamService,
    store: &mut Option<Store>,
) {
    let running = MISSION_STATE.load(Ordering::Relaxed) == MissionState::Running as u8;
    let locked = if !verdict.trusted() {
        Some(verdict.reason())
    } else if running {
        Some(link::mission::RUNNING)
    } else {
        None
    };
    let origin = params.origin();
    let context = MissionContext {
        origin: &origin,
        locked,
    };
    let now = Instant::now().as_micros();
    let outcome = mission.handle(message, (from.system, from.component), now, &context);
    deliver_mission(outcome, mission, &origin, store).await;
}

/// Sends a mission outcome's reply and refusal; puts a new mission in force and stores it.
async fn deliver_mission(
    outcome: Outcome,
    mission: &mut MissionService,
    origin: &GeoOrigin,
    store: &mut Option<Store>,
) {
    if let Some((reply, to)) = outcome.reply {
        bulk(Bulk::Mission { reply, to });
    }
    if let Some(text) = &outcome.refusal {
        reply(report(Severity::Warning, format_args!("{text}")));
    }
    match outcome.event {
        Some(MissionEvent::Replaced | MissionEvent::Cleared) => {
            offer_route(mission, origin).await;
            let count = mission.items().len();
            let saved = save_mission(mission, store).await;
            let mut r = Report::default();
            if count == 0 {
                r.text(
                    Severity::Info,
                    format_args!("mission cleared: the payload description's target is flown"),
                );
            } else {
                r.text(
                    Severity::Info,
                    format_args!("mission of {count} items accepted"),
                );
            }
            if let Err(e) = saved {
                r.text(
                    Severity::Error,
                    format_args!("mission in force but not stored: {e}"),
                );
            }
            reply(Outbound::Report(r));
        }
        Some(MissionEvent::SetCurrent(seq)) => {
            ROUTE.send(RouteChange::Current(seq)).await;
            ROUTE_SENT.store(true, Ordering::Release);
        }
        None => {}
    }
}

/// Stores the mission in force.
async fn save_mission(
    mission: &MissionService,
    store: &mut Option<Store>,
) -> Result<(), link::store::StoreError> {
    let Some(store) = store else {
        return Err(link::store::StoreError::Other);
    };
    let mut bytes = [0u8; MAX_STORED_LEN];
    let len = stored::encode(mission.items(), &mut bytes);
    store.save_mission(&bytes[..len]).await
}

/// A payload description that passed the checks, on its way to the planner.
pub struct Received {
    /// Its name.
    pub name: heapless::String<MAX_NAME_LEN>,
    /// The checked description.
    pub scenario: Scenario,
}

/// Decodes and checks a received payload description with the host's checks; stores it (in
/// `store`, when given) and hands it to the job task to load (which then says it was
/// accepted), or says which key is wrong.
///
/// The receive task's future is a static, so the decoded description (2.5 KB with its wire
/// form) is never kept across a wait: [`hand_over`] decodes it on the stack and sends it if
/// `TO_LOAD` has room; if the job task has not taken the last one yet, this waits for room
/// and decodes the same bytes again.
async fn check_payload(file: &[u8], store: &mut Option<Store>) {
    let accepted = loop {
        match hand_over(file) {
            Ok(true) => break true,
            Ok(false) => core::future::poll_fn(|cx| TO_LOAD.poll_ready_to_send(cx)).await,
            Err(e) => {
                OUTBOX
                    .send(report(
                        Severity::Error,
                        format_args!("payload refused: {e}"),
                    ))
                    .await;
                break false;
            }
        }
    };
    // Stored after it went to the planner, so the description (1.4 KB) is not held across the
    // store's wait.
    if accepted
        && let Some(store) = store
        && let Err(e) = store.save_payload(file).await
    {
        OUTBOX
            .send(report(
                Severity::Error,
                format_args!("payload description in use but not stored: {e}"),
            ))
            .await;
    }
}

/// Decodes and checks `file`; a description that passes goes to the job task if `TO_LOAD` has
/// room (`true`), else it is dropped (`false`: [`check_payload`] waits for room and comes
/// again; the receive task is `TO_LOAD`'s only sender, so once is enough).
fn hand_over(file: &[u8]) -> Result<bool, PayloadError> {
    // The board must drive every robot with the ESC protocol in force.
    let esc_protocol = MISSION_CONFIG.lock(|c| c.get().hardware.esc_protocol);
    let (wire, scenario) = decode_for_board(file, &<Selected as Board>::drives(), esc_protocol)?;
    let received = Received {
        name: wire.name,
        scenario,
    };
    Ok(TO_LOAD.try_send(received).is_ok())
}

fn mav_severity(s: Severity) -> MavSeverity {
    match s {
        Severity::Info => MavSeverity::MAV_SEVERITY_INFO,
        Severity::Notice => MavSeverity::MAV_SEVERITY_NOTICE,
        Severity::Warning => MavSeverity::MAV_SEVERITY_WARNING,
        Severity::Error => MavSeverity::MAV_SEVERITY_ERROR,
        Severity::Critical => MavSeverity::MAV_SEVERITY_CRITICAL,
    }
}

fn mav_result(r: CommandResult) -> MavResult {
    match r {
        CommandResult::Accepted => MavResult::MAV_RESULT_ACCEPTED,
        CommandResult::InProgress => MavResult::MAV_RESULT_IN_PROGRESS,
        CommandResult::Failed => MavResult::MAV_RESULT_FAILED,
        CommandResult::TemporarilyRejected => MavResult::MAV_RESULT_TEMPORARILY_REJECTED,
        CommandResult::Denied => MavResult::MAV_RESULT_DENIED,
    }
}

/// The send side: numbered frames onto the board's byte stream.
struct Sending<W> {
    tx: W,
    encoder: Encoder,
    frame: Frame,
    text_id: u16,
    /// The link's rate: what may wait goes only while it holds bytes.
    budget: LinkBudget,
    /// What is sent now spends from the budget (not a HIL step's messages: the lockstep runs
    /// at the simulator's pace, many times the vehicle's clock under QEMU).
    charged: bool,
    /// The take-off point.
    home: Home,
    /// The flight mode, the route's progress and the landed state last said.
    said: Said,
    /// [`STATUS_CHANGES`] when they were said.
    status_changes: u32,
    /// `ESC_INFO`s sent (its `counter`).
    esc_infos: u16,
}

/// What the send task last said of the mode, the route, the landed state and the rotors out.
#[derive(Clone, Copy, PartialEq)]
struct Said {
    mode: u8,
    route: RouteStatus,
    landed: u8,
    rotors_out: u16,
}

impl<W: Write> Sending<W> {
    /// Encodes `message` into the frame; [`Self::flush`] sends it. (Two steps, so that the
    /// asynchronous part is one function for every message type, not one per type.)
    fn encode<M: MessageData>(&mut self, message: &M) {
        self.encoder.encode(message, &mut self.frame);
    }

    /// Sends the frame, signed once signing is on.
    async fn flush(&mut self) {
        if let Some(extra) = crc_extra(self.frame.message_id()) {
            let now = Instant::now().as_micros();
            signing(|s| s.sign(&mut self.frame, extra, now));
        }
        if self.charged {
            self.budget.spend(self.frame.bytes().len());
        }
        // A board link cannot fail in a way the firmware could mend; the bytes are dropped.
        let _ = self.tx.write_all(self.frame.bytes()).await;
    }

    async fn text(&mut self, severity: Severity, text: &str) {
        self.text_id = self.text_id.wrapping_add(1).max(1);
        for chunk in chunks(text, mav_severity(severity), self.text_id) {
            chunk.encode(&mut self.encoder, &mut self.frame);
            self.flush().await;
        }
    }

    async fn report(&mut self, report: &Report, time_ms: u32) {
        for line in &report.texts {
            self.text(line.severity, &line.text).await;
        }
        for v in &report.values {
            match v.value {
                Value::Float(x) => self.encode(&named_float(v.name, x, time_ms)),
                Value::Int(x) => self.encode(&named_int(v.name, x, time_ms)),
            }
            self.flush().await;
        }
    }

    async fn heartbeat(&mut self) {
        let state =
            MissionState::from_custom_mode(u32::from(MISSION_STATE.load(Ordering::Relaxed)))
                .unwrap_or(MissionState::Idle);
        let mode = VEHICLE.lock(|v| v.get()).mode;
        let beat = heartbeat(
            state,
            FlightMode::from_code(mode).unwrap_or(FlightMode::Ready),
            ARMED.load(Ordering::Relaxed),
            IN_HIL.load(Ordering::Relaxed),
        );
        self.encode(&beat);
        self.flush().await;
    }

    /// The mode, the route's progress, the landed state and the rotors out
    /// (docs/ground-link.md#missions): each change at once (a new mode with a `HEARTBEAT` and
    /// `CURRENT_MODE`, an item reached as `MISSION_ITEM_REACHED`, a rotor out as `ESC_INFO`),
    /// and with every heartbeat (`every_second`) the route's `MISSION_CURRENT` and
    /// `EXTENDED_SYS_STATE`.
    async fn mission_status(&mut self, every_second: bool) {
        let changes = STATUS_CHANGES.load(Ordering::Acquire);
        if !every_second && changes == self.status_changes {
            return;
        }
        self.status_changes = changes;
        let vehicle = VEHICLE.lock(|v| v.get());
        let now = Said {
            mode: vehicle.mode,
            route: vehicle.route,
            landed: vehicle.landed,
            rotors_out: vehicle.rotors_out,
        };
        let before = self.said;
        self.said = now;
        // A rotor found stopped: `ESC_INFO`'s failure flags at once (while the ESCs report).
        if now.rotors_out != before.rotors_out {
            telemetry(|t| t.request_once(link::msg::ESC_INFO_DATA::ID));
        }
        if now.mode != before.mode {
            let mode = FlightMode::from_code(now.mode).unwrap_or(FlightMode::Ready);
            self.heartbeat().await;
            self.encode(&mode.current(mode));
            self.flush().await;
            // In words too: MAVProxy and pymavlink name PX4's modes only for a PX4 autopilot.
            let mut text = Text::new();
            let _ = core::fmt::write(&mut text, format_args!("mode: {}", mode.name()));
            self.text(Severity::Info, &text).await;
        }
        if let Some(reached) = now.route.reached
            && before.route.reached != Some(reached)
        {
            let first = before.route.reached.map_or(0, |r| r + 1).min(reached);
            for seq in first..=reached {
                link::mission::wire::encode_reached(seq, &mut self.encoder, &mut self.frame);
                self.flush().await;
            }
        }
        if every_second || now.route != before.route {
            let total = MISSION_ITEMS.load(Ordering::Relaxed);
            let r = now.route;
            let in_mission = now.mode == FlightMode::Mission.code();
            link::mission::wire::encode_current(
                r.current,
                total,
                r.progress,
                in_mission,
                &mut self.encoder,
                &mut self.frame,
            );
            self.flush().await;
        }
        if every_second || now.landed != before.landed {
            self.encode(&vehicle.extended_sys_state());
            self.flush().await;
        }
    }

    /// Every telemetry stream due now, from the last control step's state.
    async fn telemetry(&mut self) {
        let now = Instant::now().as_micros();
        while let Some(stream) = telemetry(|t| t.take_due(now)) {
            let vehicle = VEHICLE.lock(|v| v.get());
            if self.home.observe(&vehicle) {
                self.home_position().await;
            }
            match stream {
                Stream::SysStatus => {
                    let mut status = vehicle.sys_status_with_log(super::logger::health());
                    LINK.lock(|l| l.borrow().health.fill(&mut status));
                    self.encode(&status)
                }
                Stream::AttitudeQuaternion => self.encode(&vehicle.attitude_quaternion()),
                Stream::LocalPositionNed => self.encode(&vehicle.local_position_ned()),
                Stream::RailPositions => {
                    let (array, data, len) = vehicle.rail_positions();
                    self.encoder
                        .encode_extended(&array, &data[..len], &mut self.frame);
                }
                Stream::ServoOutputRaw | Stream::ActuatorOutputStatus => {
                    let table = MISSION_CONFIG.lock(|c| c.get().hardware.thrust_map);
                    let map = ThrustMap::new(table).unwrap_or_default();
                    if stream == Stream::ServoOutputRaw {
                        // One message a port of eight outputs (robots 9 to 16 on the second);
                        // the last is sent below, as every stream's.
                        let last = vehicle.servo_ports() - 1;
                        for port in 0..last {
                            self.encode(&vehicle.servo_output_raw(&map, port));
                            self.flush().await;
                        }
                        self.encode(&vehicle.servo_output_raw(&map, last));
                    } else {
                        self.encode(&vehicle.actuator_output_status(&map));
                    }
                }
                Stream::GlobalPositionInt => match vehicle.global_position_int(&origin()) {
                    Some(m) => self.encode(&m),
                    // An unusable origin (said at start): nothing to send.
                    None => continue,
                },
                // Only while ESCs report: one message per four of them.
                Stream::EscStatus | Stream::EscInfo => {
                    let Some(rpm) = super::ESC_RPM.lock(|r| r.get()) else {
                        continue;
                    };
                    if !link::esc::reporting(&vehicle, &rpm) {
                        continue;
                    }
                    for message in 0..link::esc::messages(vehicle.robots) {
                        if stream == Stream::EscStatus {
                            self.encode(&link::esc::esc_status(&vehicle, &rpm, message));
                        } else {
                            let counter = self.esc_infos;
                            self.encode(&link::esc::esc_info(&vehicle, &rpm, message, counter));
                        }
                        self.flush().await;
                    }
                    if stream == Stream::EscInfo {
                        self.esc_infos = self.esc_infos.wrapping_add(1);
                    }
                    continue;
                }
            }
            self.flush().await;
        }
    }

    /// `HOME_POSITION` (nothing with an unusable origin).
    async fn home_position(&mut self) {
        if let Some(m) = self.home.home_position(&origin()) {
            self.encode(&m);
            self.flush().await;
        }
    }

    /// `COMPONENT_METADATA`: the general metadata file's URI and CRC-32.
    async fn component_metadata(&mut self) {
        let now_ms = Instant::now().as_millis() as u32;
        let uri = shared::mission::params::metadata::GENERAL_URI;
        self.encode(&component_metadata(now_ms, metadata::GENERAL_CRC, uri));
        self.flush().await;
    }

    /// Sends a control step's messages; `state` is the mission state last said in a
    /// `HEARTBEAT` (a step that changes it says the new one). By reference: the task keeps the
    /// messages it took from the queue, and no copy of them, across the link's waits.
    async fn step(&mut self, step: &StepMessages, state: &mut MissionState) {
        self.report(&step.report, (step.time_us / 1000) as u32)
            .await;
        for (pending, result) in step.ack.iter().chain(&step.done) {
            self.encode(&ack(pending.mav_cmd, mav_result(*result)));
            self.flush().await;
        }
        if step.state != *state {
            *state = step.state;
            self.heartbeat().await;
        }
        if let Some(actuators) = &step.actuators {
            let messages = actuators.to_messages();
            if let Some(status) = &messages.status {
                self.encode(status);
                self.flush().await;
            }
            self.encode(&messages.controls);
            self.flush().await;
        }
    }

    /// Sends one reply of the queue.
    async fn outbound(&mut self, message: &Outbound) {
        match message {
            Outbound::Report(report) => {
                self.report(report, Instant::now().as_millis() as u32).await;
            }
            Outbound::Identity => self.identity().await,
            Outbound::ComponentMetadata => self.component_metadata().await,
            Outbound::Params(indices) => {
                for index in (0..PARAM_COUNT).filter(|i| indices & (1 << i) != 0) {
                    self.param_value(index).await;
                }
            }
            Outbound::Ack { command, result } => {
                self.encode(&ack(*command, *result));
                self.flush().await;
            }
            Outbound::TimeSync { tc1, ts1 } => {
                self.encode(&TIMESYNC_DATA {
                    tc1: *tc1,
                    ts1: *ts1,
                });
                self.flush().await;
            }
            Outbound::Origin => {
                let origin = origin();
                if let Err(e) = origin.check() {
                    let mut text = Text::new();
                    let _ = core::fmt::write(
                        &mut text,
                        format_args!("origin: unusable ({e}); no global position"),
                    );
                    self.text(Severity::Warning, &text).await;
                }
                self.encode(&gps_global_origin(&origin));
                self.flush().await;
            }
            Outbound::Home => self.home_position().await,
            Outbound::CurrentMode => {
                let mode = VEHICLE.lock(|v| v.get()).mode;
                let mode = FlightMode::from_code(mode).unwrap_or(FlightMode::Ready);
                self.encode(&mode.current(mode));
                self.flush().await;
            }
            Outbound::AvailableModes(index) => {
                for (i, mode) in MODES.iter().enumerate() {
                    if *index == 0 || usize::from(*index) == i + 1 {
                        self.encode(&mode.available());
                        self.flush().await;
                    }
                }
            }
        }
    }

    /// Sends one bulk transfer's message.
    async fn bulk(&mut self, message: &Bulk) {
        match message {
            Bulk::Ftp { message, to } => {
                self.encode(&message.to_message(to.system, to.component));
            }
            Bulk::Log(LogReply::Entry(entry)) => self.encode(entry),
            Bulk::Log(LogReply::Data(data)) => self.encode(data),
            Bulk::Mission { reply, to } => {
                reply.encode(*to, &mut self.encoder, &mut self.frame);
            }
        }
        self.flush().await;
    }

    /// The `PARAM_VALUE` of `index`, from the values in force.
    async fn param_value(&mut self, index: usize) {
        let message = LINK.lock(|l| value_message(&l.borrow().values, index));
        if let Some(m) = message {
            self.encode(&m);
            self.flush().await;
        }
    }

    /// What the link dropped since it was last said, at most once every few seconds.
    async fn drops(&mut self) {
        let now = Instant::now().as_micros();
        let due = LINK.lock(|l| {
            let mut l = l.borrow_mut();
            let restarted = l.lists.restarted();
            l.health.lists_restarted(restarted);
            l.health.report_due(now)
        });
        if let Some(drops) = due {
            let mut text = Text::new();
            let _ = core::fmt::write(&mut text, format_args!("{drops}"));
            self.text(Severity::Warning, &text).await;
        }
    }

    async fn identity(&mut self) {
        let version = AUTOPILOT_VERSION_DATA {
            capabilities: link::status::capabilities(),
            flight_sw_version: 0x0001_0000,
            ..Default::default()
        };
        self.encode(&version);
        self.flush().await;
        let mut text = Text::new();
        let _ = core::fmt::write(
            &mut text,
            format_args!(
                "{}{} (firmware {})",
                link::status::BOARD_PREFIX,
                <Selected as Board>::NAME,
                env!("CARGO_PKG_VERSION")
            ),
        );
        self.text(Severity::Info, &text).await;
    }
}

/// The map origin in force (from the receive task's parameters).
fn origin() -> GeoOrigin {
    LINK.lock(|l| GeoOrigin::from_params(&l.borrow().values))
}

/// What the send task does next (docs/ground-link.md#under-a-flood).
enum Next {
    /// A control step's messages: at once.
    Step(StepMessages),
    /// The heartbeat (with the mission's status and a time-sync request): when due.
    Heartbeat,
    /// A reply: within the link's rate.
    Reply(Outbound),
    /// The telemetry streams due: within the link's rate.
    Telemetry,
    /// A bulk transfer's message: within the link's rate.
    Bulk(Bulk),
    /// A parameter list's next value: within the link's rate.
    ListValue(usize),
    /// Nothing now: wait for something to send or for the time to send it.
    Wait,
}

/// Sends, forever, by priority: a control step's messages, the heartbeat each second, then
/// within the link's rate ([`Board::link_rate`]) the replies, the telemetry streams due, the bulk
/// transfers and the parameter lists in flight.
#[embassy_executor::task]
pub async fn send(tx: <Selected as Board>::LinkTx) {
    let mut out = Sending {
        tx,
        encoder: Encoder::new(link::VEHICLE_SYSTEM_ID, link::VEHICLE_COMPONENT_ID),
        frame: Frame::default(),
        text_id: 0,
        budget: LinkBudget::new(
            <Selected as Board>::link_rate(),
            LINK_BURST,
            Instant::now().as_micros(),
        ),
        charged: true,
        home: Home::START,
        esc_infos: 0,
        said: Said {
            mode: FlightMode::Ready.code(),
            route: RouteStatus::NONE,
            landed: VehicleSnapshot::START.landed,
            rotors_out: 0,
        },
        status_changes: 0,
    };
    out.identity().await;
    let _ = out.tx.flush().await;
    let mut state = MissionState::Idle;
    let mut next_beat = Instant::now();
    loop {
        let now = Instant::now();
        let telemetry_due = telemetry(|t| t.next_due());
        let may_wait_goes = out.budget.allows(now.as_micros());
        let next = if let Ok(step) = STEP_OUT.try_receive() {
            Next::Step(step)
        } else if now >= next_beat {
            Next::Heartbeat
        } else if !may_wait_goes {
            Next::Wait
        } else if let Ok(message) = OUTBOX.try_receive() {
            Next::Reply(message)
        } else if telemetry_due.is_some_and(|due| due <= now.as_micros()) {
            Next::Telemetry
        } else if let Ok(message) = BULK.try_receive() {
            Next::Bulk(message)
        } else if let Some(index) = LINK.lock(|l| l.borrow_mut().lists.next(PARAM_COUNT)) {
            Next::ListValue(index)
        } else {
            Next::Wait
        };
        match &next {
            // Before the step's messages: the lockstep reply goes last, and after the last
            // one (the touchdown) the plant may stop listening.
            Next::Step(step) => {
                out.charged = step.actuators.is_none();
                out.mission_status(false).await;
                out.step(step, &mut state).await;
                out.charged = true;
            }
            Next::Heartbeat => {
                out.heartbeat().await;
                out.mission_status(true).await;
                // A time-sync request with every heartbeat (as PX4 asks once a second).
                let now_ns = Instant::now().as_micros().saturating_mul(1000) as i64;
                out.encode(&timesync(|t| t.request(now_ns)));
                out.flush().await;
                out.drops().await;
                next_beat = Instant::now() + Duration::from_secs(1);
            }
            Next::Reply(message) => {
                out.mission_status(false).await;
                out.outbound(message).await;
            }
            Next::Telemetry => out.telemetry().await,
            Next::Bulk(message) => out.bulk(message).await,
            Next::ListValue(index) => out.param_value(*index).await,
            Next::Wait => {
                let mut wake = next_beat;
                if !may_wait_goes {
                    wake = wake.min(Instant::from_micros(out.budget.ready_at()));
                } else if let Some(due) = telemetry_due {
                    wake = wake.min(Instant::from_micros(due));
                }
                let more = async {
                    if may_wait_goes {
                        select4(
                            OUTBOX.ready_to_receive(),
                            BULK.ready_to_receive(),
                            LIST_STARTED.wait(),
                            TELEMETRY_CHANGED.wait(),
                        )
                        .await;
                    } else {
                        core::future::pending::<()>().await;
                    }
                };
                select3(STEP_OUT.ready_to_receive(), Timer::at(wake), more).await;
                continue;
            }
        }
        // The group's end: a link that frames (the QEMU board's Ethernet) sends it now, as
        // one frame.
        let _ = out.tx.flush().await;
        // A fast link never makes this task wait: the receive task, on this executor, gets
        // its turn between two groups (else a flood's answers would keep it from the input).
        embassy_futures::yield_now().await;
    }
}
