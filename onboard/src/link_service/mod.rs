//! The vehicle's MAVLink receive path as one service (docs/ground-link.md): every frame the
//! link parses goes to its handler here (the HIL plant's sensors, the ground's commands,
//! parameters, the signing key's set-up, missions, the payload upload over FTP, the map
//! origin, log requests), and what the handler decides comes out through [`VehiclePorts`]:
//! replies for the send task, values for the control, job and logger tasks, writes to the
//! parameter store. The firmware's receive task only reads bytes and calls [`LinkService`];
//! the host tests and the fuzz targets call the same.

mod commands;
pub mod messages;
mod origin;
mod params;
mod payload;
pub mod ports;
pub mod queue_ports;
pub mod send_order;
mod signing_key;
mod stored_mission;

use crate::store::{ParamStore, StoreError};
use embedded_storage_async::nor_flash::NorFlash;
use link::frame::Parser;
use link::ftp::{ReadOnlyFile, Server};
use link::mission::MissionService;
use link::param::ParamService;
use link::signing::Verdict;
use link::status::MissionState;
use link::timesync::Received as SyncReceived;
use link::vehicle::{Inbound, crc_extra, dispatch};
use shared::mission::params::ParamValues;
use shared::scenario_wire::MAX_ENCODED_LEN;

pub use messages::{
    Bulk, Outbound, ParamBits, PendingCommand, Received, SensorSample, StepMessages, mav_result,
    mav_severity, report,
};
pub use ports::VehiclePorts;
pub use queue_ports::QueuePorts;

use crate::autonomy::Severity;

/// Largest payload description file the vehicle takes.
pub const FILE_CAPACITY: usize = MAX_ENCODED_LEN;

/// The link id the vehicle signs with (one link at a time).
pub const LINK_ID: u8 = 0;

/// Oldest a motion-capture fix may be when it arrives for its own stamp to be used, us (the
/// attitude estimator keeps 160 ms of history to compensate a fix's latency).
pub const MAX_FIX_AGE_US: u64 = 150_000;

/// The link's receive side: the frame parser, the FTP server with the payload description,
/// the mission protocol's service, the parameters and their store.
pub struct LinkService<F: NorFlash> {
    parser: Parser,
    ftp: Server<FILE_CAPACITY>,
    mission: MissionService,
    params: ParamService,
    store: Option<ParamStore<F>>,
    /// The read-only files the FTP server offers (the parameter metadata).
    files: &'static [ReadOnlyFile],
    /// The sender whose FTP was last refused (system << 8 | component, plus one; 0: none since
    /// the last FTP request answered).
    ftp_refused: u32,
}

impl<F: NorFlash> LinkService<F> {
    /// A service with the default parameters and no store, offering `files` for reading;
    /// [`Self::start`] opens the store.
    pub fn new(files: &'static [ReadOnlyFile]) -> Self {
        Self {
            parser: Parser::new(crc_extra),
            ftp: Server::new(),
            mission: MissionService::new(),
            params: ParamService::new(ParamValues::DEFAULT),
            store: None,
            files,
            ftp_refused: 0,
        }
    }

    /// The vehicle's start: takes the store (or the reason it did not open), puts the stored
    /// parameters, signing key, payload description and mission in force, and says what it
    /// found.
    pub async fn start(
        &mut self,
        store: Result<ParamStore<F>, StoreError>,
        io: &mut impl VehiclePorts,
    ) {
        self.open_params(store, io).await;
        self.restore_signing(io).await;
        self.restore_payload(io).await;
        self.restore_mission(io).await;
    }

    /// Takes received bytes: every whole frame to its handler, in order.
    pub async fn receive(&mut self, bytes: &[u8], io: &mut impl VehiclePorts) {
        for &byte in bytes {
            let Some((frame, integrity)) = self.parser.push(byte) else {
                continue;
            };
            let now = io.now_us();
            let verdict = io.signing(|s| s.check(frame, now));
            let inbound = dispatch(frame, integrity);
            self.handle(inbound, verdict, io).await;
        }
        io.parsed(self.parser.stats());
    }

    /// What waits on time or on another task: an upload's timeout, a calibration's offsets
    /// to store. Called whenever bytes come (in flight at least the ground station's
    /// heartbeat, once a second).
    pub async fn poll(&mut self, io: &mut impl VehiclePorts) {
        if let Some(outcome) = self.mission.poll(io.now_us()) {
            self.deliver_mission(outcome, io).await;
        }
        if let Some((kind, offsets)) = io.calibrated() {
            self.store_calibration(kind, offsets, io).await;
        }
    }

    /// The parameters in force.
    pub fn params(&self) -> &ParamService {
        &self.params
    }

    /// The payload description file as the FTP server holds it.
    pub fn payload_file(&self) -> &[u8] {
        self.ftp.file()
    }

    /// The mission protocol's service (the items in force).
    pub fn mission(&self) -> &MissionService {
        &self.mission
    }

    /// The store, taken back (a test's or the fuzzer's restart).
    pub fn take_store(&mut self) -> Option<ParamStore<F>> {
        self.store.take()
    }

    /// One frame's handling.
    pub async fn handle(&mut self, inbound: Inbound, verdict: Verdict, io: &mut impl VehiclePorts) {
        match inbound {
            Inbound::Sensor(sample) => {
                let sample = SensorSample {
                    time_us: sample.time_us,
                    imu: sample.imu,
                    hil: true,
                };
                if !io.sensor(sample) {
                    io.reply(report(
                        Severity::Warning,
                        format_args!("HIL_SENSOR dropped: the control step is behind"),
                    ));
                }
            }
            Inbound::Mocap(mut fix) => {
                // In HIL the plant's clock is the vehicle's (lockstep); a real motion-capture
                // computer's stamp is mapped to the vehicle's clock (or the arrival is used).
                if !io.in_hil() {
                    let arrival_us = io.now_us();
                    fix.stamp_us =
                        io.timesync(|t| t.stamp(fix.stamp_us, arrival_us, MAX_FIX_AGE_US));
                }
                io.mocap(fix);
            }
            Inbound::TimeSync { tc1, ts1 } => {
                let now_ns = io.now_us().saturating_mul(1000) as i64;
                let message = link::msg::TIMESYNC_DATA { tc1, ts1 };
                if let SyncReceived::Answer(a) = io.timesync(|t| t.receive(&message, now_ns)) {
                    io.reply(Outbound::TimeSync {
                        tc1: a.tc1,
                        ts1: a.ts1,
                    });
                }
            }
            Inbound::Command {
                command,
                request,
                from,
            } => self.command(command, request, from, verdict, io).await,
            Inbound::Param { request, from } => {
                self.handle_param(request, from, verdict, io).await;
            }
            Inbound::SetupSigning { key, timestamp, .. } => {
                self.setup_signing(key, timestamp, io).await;
            }
            Inbound::Mission { message, from } => {
                self.handle_mission(&message, from, verdict, io).await;
            }
            Inbound::Log { request, .. } => commands::handle_log(request, verdict, io),
            Inbound::SetOrigin {
                lat_e7,
                lon_e7,
                alt_mm,
                ..
            } => self.set_origin((lat_e7, lon_e7, alt_mm), verdict, io).await,
            Inbound::Ftp { message, from } => self.handle_ftp(&message, from, verdict, io).await,
            Inbound::Invalid(e) => {
                io.reply(report(
                    Severity::Warning,
                    format_args!("HIL message refused: {e}"),
                ));
            }
            // The ground link is up: the next control step takes it.
            Inbound::GcsHeartbeat(_) => io.gcs_heartbeat(),
            Inbound::Battery { volts, .. } => io.battery_mv(link::vehicle::millivolts_of(volts)),
            // The plant's RPM, in HIL only (on a board the ESCs answer over DShot).
            Inbound::EscStatus(rpm) if io.in_hil() => {
                if let Err(e) = io.esc_rpm(&rpm) {
                    io.reply(report(Severity::Warning, format_args!("{e}")));
                }
            }
            Inbound::EscStatus(_) => {}
            // A joystick: taken signed once signing is on, as a command; an axis out of its
            // range is no input.
            Inbound::ManualControl { x, y, z, r, .. } => {
                if verdict.trusted()
                    && let Some(input) = shared::manual::from_manual_control(x, y, z, r)
                {
                    io.manual_control(input);
                }
            }
            Inbound::Heartbeat(_) | Inbound::Ignored { .. } => {}
        }
    }
}

/// Why a change (a parameter write, a new origin) is refused now: unsigned once signing is on,
/// or while the mission runs.
fn change_refused(verdict: Verdict, io: &impl VehiclePorts) -> Option<&'static str> {
    if !verdict.trusted() {
        Some(verdict.reason())
    } else if io.mission_state() == MissionState::Running {
        Some("the mission is running")
    } else {
        None
    }
}

#[cfg(test)]
mod tests;
