//! The MAVLink link's two tasks, on the link executor, as glue between the board's byte
//! stream, the other tasks and the link's logic (docs/ground-link.md):
//! - receiving: bytes from the board into [`onboard::link_service::LinkService`], which
//!   decides everything a frame causes (host-tested there); [`Ports`] moves its decisions to
//!   the firmware's channels, atomics and parameter store;
//! - sending ([`send`]): frames out in priority order within the link's rate.

use core::sync::atomic::Ordering;

use embassy_time::{Duration, Instant, Timer};
use embedded_io_async::Read;
use link::esc::{EscError, EscRpmReport};
use link::frame::ParserStats;
use link::hil::MocapFix;
use link::link_health::LinkHealth;
use link::log_transfer::LogRequest;
use link::param_lists::ParamLists;
use link::signing::Signing;
use link::status::MissionState;
use link::telemetry::Schedule;
use link::timesync::TimeSync;
use link::vehicle::Sender;
use onboard::link_service::{LinkService, VehiclePorts};
use onboard::store::ParamStore;
use shared::mission::MissionConfig;
use shared::mission::bringup::CalibrationKind;
use shared::mission::drives::BoardDrives;
use shared::mission::params::ParamValues;
use static_cell::StaticCell;

pub use onboard::link_service::{
    Bulk, Outbound, PendingCommand, Received, SensorSample, StepMessages, report,
};

mod send;
pub use send::send;

/// The component metadata the FTP server serves (docs/ground-link.md#parameter-metadata),
/// written by the build script from the parameter table.
mod metadata {
    include!(concat!(env!("OUT_DIR"), "/metadata.rs"));
}

use super::autonomy::RouteChange;
use super::{
    ARMED, BULK, CALIBRATED, COMMANDS, GCS_HEARTBEAT, IN_HIL, LINK, LINK_BATTERY_MV, LIST_STARTED,
    MISSION_CONFIG, MISSION_ITEMS, MISSION_STATE, MOCAP, OUTBOX, RELOAD, ROUTE, ROUTE_SENT, SENSOR,
    TELEMETRY_CHANGED, TO_LOAD, signing, telemetry, timesync,
};
use crate::board::{Board, Selected};

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

/// The link's receive service on this board's parameter flash.
type Service = LinkService<<Selected as Board>::ParamFlash>;

/// The receive service: a static (the FTP file and the mission's items are kilobytes).
static SERVICE: StaticCell<Service> = StaticCell::new();

/// The firmware's side of [`VehiclePorts`]: the channels, atomics and shared state of
/// `super`, and the board's limits.
struct Ports;

impl VehiclePorts for Ports {
    fn now_us(&self) -> u64 {
        Instant::now().as_micros()
    }

    fn drives(&self) -> BoardDrives {
        <Selected as Board>::drives()
    }

    fn key_setup_allowed(&self) -> bool {
        <Selected as Board>::key_setup_allowed()
    }

    fn store_persistent(&self) -> bool {
        <Selected as Board>::PARAM_FLASH_PERSISTENT
    }

    async fn reboot(&mut self) {
        // Time for the send task to put the acknowledgement and the text on the wire (a few
        // hundred bytes).
        Timer::after(Duration::from_millis(200)).await;
        cortex_m::peripheral::SCB::sys_reset();
    }

    fn reply(&mut self, message: Outbound) {
        if OUTBOX.try_send(message).is_err() {
            LINK.lock(|l| l.borrow_mut().health.reply_dropped());
        }
    }

    async fn reply_waiting(&mut self, message: Outbound) {
        OUTBOX.send(message).await;
    }

    fn bulk(&mut self, message: Bulk) {
        if BULK.try_send(message).is_err() {
            LINK.lock(|l| l.borrow_mut().health.reply_dropped());
        }
    }

    fn publish(&mut self, values: &ParamValues) {
        LINK.lock(|l| l.borrow_mut().values = values.clone());
    }

    fn list_params(&mut self, to: Sender) {
        LINK.lock(|l| l.borrow_mut().lists.request(to));
        LIST_STARTED.signal(());
    }

    fn parsed(&mut self, stats: ParserStats) {
        LINK.lock(|l| l.borrow_mut().health.parsed(stats));
    }

    fn signing<R>(&mut self, change: impl FnOnce(&mut Signing) -> R) -> R {
        signing(change)
    }

    fn timesync<R>(&mut self, change: impl FnOnce(&mut TimeSync) -> R) -> R {
        timesync(change)
    }

    fn telemetry<R>(&mut self, change: impl FnOnce(&mut Schedule) -> R) -> R {
        telemetry(change)
    }

    fn telemetry_changed(&mut self) {
        TELEMETRY_CHANGED.signal(());
    }

    fn mission_state(&self) -> MissionState {
        MissionState::from_custom_mode(u32::from(MISSION_STATE.load(Ordering::Relaxed)))
            .unwrap_or(MissionState::Idle)
    }

    fn armed(&self) -> bool {
        ARMED.load(Ordering::Relaxed)
    }

    fn in_hil(&self) -> bool {
        IN_HIL.load(Ordering::Relaxed)
    }

    fn payload_robots(&self) -> usize {
        usize::from(super::PAYLOAD_ROBOTS.load(Ordering::Relaxed))
    }

    fn sensor(&mut self, sample: SensorSample) -> bool {
        // Known here already, so a fix right behind the first sample is taken as HIL's.
        IN_HIL.store(true, Ordering::Relaxed);
        SENSOR.try_send(sample).is_ok()
    }

    fn mocap(&mut self, fix: MocapFix) {
        MOCAP.signal(fix);
    }

    fn command(&mut self, pending: PendingCommand) -> bool {
        COMMANDS.try_send(pending).is_ok()
    }

    fn gcs_heartbeat(&mut self) {
        GCS_HEARTBEAT.store(true, Ordering::Relaxed);
    }

    fn manual_control(&mut self, input: shared::manual::ManualInput) {
        super::MANUAL.signal(input);
    }

    fn battery_mv(&mut self, millivolts: u32) {
        LINK_BATTERY_MV.store(millivolts, Ordering::Relaxed);
    }

    fn esc_rpm(&mut self, report: &EscRpmReport) -> Result<(), EscError> {
        super::LINK_ESC_RPM.lock(|inbox| inbox.borrow_mut().receive(report))
    }

    fn apply_config(&mut self, config: MissionConfig) {
        super::set_config(config);
    }

    fn reload(&mut self) {
        RELOAD.signal(());
    }

    fn record_config(&mut self, config: MissionConfig) {
        MISSION_CONFIG.lock(|c| c.set(config));
    }

    fn calibrated(&mut self) -> Option<(CalibrationKind, [f32; 3])> {
        CALIBRATED.try_receive().ok()
    }

    async fn route(&mut self, change: RouteChange, items: u16) {
        MISSION_ITEMS.store(items, Ordering::Relaxed);
        ROUTE.send(change).await;
        ROUTE_SENT.store(true, Ordering::Release);
    }

    fn offer_payload(&mut self, received: Received) -> bool {
        TO_LOAD.try_send(received).is_ok()
    }

    async fn payload_room(&mut self) {
        core::future::poll_fn(|cx| TO_LOAD.poll_ready_to_send(cx)).await;
    }

    fn log_request(&mut self, request: LogRequest) -> bool {
        super::logger::request(request)
    }
}

/// Reads the link, forever: the store opened, then every byte to the receive service.
#[embassy_executor::task]
pub async fn receive(
    mut rx: <Selected as Board>::LinkRx,
    param_flash: <Selected as Board>::ParamFlash,
) {
    let service = SERVICE.init_with(|| LinkService::new(&metadata::FILES));
    let store = ParamStore::new(param_flash, <Selected as Board>::PARAM_RANGE)
        .and_then(|s| s.with_payload(<Selected as Board>::PAYLOAD_RANGE))
        .and_then(|s| s.with_mission(<Selected as Board>::MISSION_RANGE));
    let mut ports = Ports;
    service.start(store, &mut ports).await;
    let mut buf = [0u8; 64];
    loop {
        // A board's read error (a UART framing error) loses bytes the parser resyncs over.
        let n = rx.read(&mut buf).await.unwrap_or(0);
        service.receive(&buf[..n], &mut ports).await;
        // A flood of bytes (each read ready at once) must not keep the send task, on this
        // executor, from the control step's messages and the heartbeat.
        embassy_futures::yield_now().await;
        service.poll(&mut ports).await;
    }
}
