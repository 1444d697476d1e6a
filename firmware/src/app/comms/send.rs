//! The link's send task (docs/ground-link.md#under-a-flood): each control step's messages in
//! order (its texts, values, the command's `COMMAND_ACK`, a `HEARTBEAT` when the mission state
//! changed, then in HIL the actuator commands, `ACTUATOR_OUTPUT_STATUS` past 8 robots and
//! `HIL_ACTUATOR_CONTROLS`, the lockstep reply, last), the heartbeat each second, then within
//! the link's rate the replies, the telemetry streams due, the bulk transfers and the
//! parameter lists. So the plant has everything a step said before it steps on.

use core::sync::atomic::Ordering;

use embassy_futures::select::{select3, select4};
use embassy_time::{Instant, Timer};
use embedded_io_async::Write;
use link::MessageData;
use link::bandwidth::LinkBudget;
use link::command::ack;
use link::frame::{Encoder, Frame};
use link::ftp::component_metadata;
use link::geo::GeoOrigin;
use link::log_transfer::LogReply;
use link::modes::{FlightMode, MODES};
use link::msg::{AUTOPILOT_VERSION_DATA, TIMESYNC_DATA};
use link::param::value_message;
use link::status::{MissionState, Text, chunks, heartbeat, named_float, named_int};
use link::telemetry::{Home, RouteStatus, Stream, VehicleSnapshot, gps_global_origin};
use link::vehicle::crc_extra;
use onboard::link_service::send_order::{HeartbeatClock, Source, Waiting, next_source, wake_at};
use onboard::link_service::{Bulk, Outbound, StepMessages, mav_result, mav_severity};
use shared::control::thrust_map::ThrustMap;
use shared::mission::params::COUNT as PARAM_COUNT;

use super::metadata;
use crate::app::autonomy::{Report, Severity, Value};
use crate::app::{
    ARMED, BULK, IN_HIL, LINK, LIST_STARTED, MISSION_CONFIG, MISSION_ITEMS, MISSION_STATE, OUTBOX,
    STATUS_CHANGES, STEP_OUT, TELEMETRY_CHANGED, VEHICLE, signing, telemetry, timesync,
};
use crate::board::{Board, Selected};

/// Most bytes the link's budget holds after a quiet spell (a few messages at once).
const LINK_BURST: u32 = 1024;

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
                    let mut status = vehicle.sys_status_with_log(crate::app::logger::health());
                    LINK.lock(|l| l.borrow().health.fill(&mut status));
                    crate::app::RC_STATUS.lock(|r| r.get().fill_sys_status(&mut status));
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
                // Only once a receiver has been heard.
                Stream::RcChannels => {
                    let time_ms = Instant::now().as_millis() as u32;
                    match crate::app::RC_STATUS.lock(|r| r.get().rc_channels(time_ms)) {
                        Some(m) => self.encode(&m),
                        None => continue,
                    }
                }
                Stream::GlobalPositionInt => match vehicle.global_position_int(&origin()) {
                    Some(m) => self.encode(&m),
                    // An unusable origin (said at start): nothing to send.
                    None => continue,
                },
                // Only while ESCs report: one message per four of them.
                Stream::EscStatus | Stream::EscInfo => {
                    let Some(rpm) = crate::app::ESC_RPM.lock(|r| r.get()) else {
                        continue;
                    };
                    if !link::esc::reporting(&vehicle, &rpm) {
                        continue;
                    }
                    for message in 0..link::esc::messages(vehicle.robots) {
                        {
                            // Read for this message alone (not kept across the flush).
                            let e = <Selected as Board>::esc_electrical(message);
                            if stream == Stream::EscStatus {
                                self.encode(&link::esc::esc_status(
                                    &vehicle,
                                    &rpm,
                                    e.as_ref(),
                                    message,
                                ));
                            } else {
                                let counter = self.esc_infos;
                                self.encode(&link::esc::esc_info(
                                    &vehicle,
                                    &rpm,
                                    e.as_ref(),
                                    message,
                                    counter,
                                ));
                            }
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
                for index in (0..PARAM_COUNT).filter(|&i| indices.contains(i)) {
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

/// What the send task does next, taken from the source [`next_source`] chose.
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
    let mut beat = HeartbeatClock::new();
    loop {
        let now = Instant::now();
        let telemetry_due = telemetry(|t| t.next_due());
        let may_wait_goes = out.budget.allows(now.as_micros());
        let waiting = Waiting {
            step: !STEP_OUT.is_empty(),
            heartbeat_due: beat.due(now.as_micros()),
            budget_allows: may_wait_goes,
            reply: !OUTBOX.is_empty(),
            telemetry_due: telemetry_due.is_some_and(|due| due <= now.as_micros()),
            bulk: !BULK.is_empty(),
            list: LINK.lock(|l| l.borrow().lists.busy()),
        };
        // This task is each queue's only receiver: what it found waiting is there to take.
        let next = match next_source(&waiting) {
            Source::Step => STEP_OUT.try_receive().map_or(Next::Wait, Next::Step),
            Source::Heartbeat => Next::Heartbeat,
            Source::Reply => OUTBOX.try_receive().map_or(Next::Wait, Next::Reply),
            Source::Telemetry => Next::Telemetry,
            Source::Bulk => BULK.try_receive().map_or(Next::Wait, Next::Bulk),
            Source::ListValue => LINK
                .lock(|l| l.borrow_mut().lists.next(PARAM_COUNT))
                .map_or(Next::Wait, Next::ListValue),
            Source::Wait => Next::Wait,
        };
        match &next {
            // Before the step's messages: the lockstep reply goes last, and after the last
            // one (the touchdown) the plant may stop listening.
            Next::Step(step) => {
                out.charged = step.actuators.is_none();
                beat.step_time(step.time_us);
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
                beat.sent(Instant::now().as_micros());
            }
            Next::Reply(message) => {
                out.mission_status(false).await;
                out.outbound(message).await;
            }
            Next::Telemetry => out.telemetry().await,
            Next::Bulk(message) => out.bulk(message).await,
            Next::ListValue(index) => out.param_value(*index).await,
            Next::Wait => {
                let wake = Instant::from_micros(wake_at(
                    beat.next_board_us(),
                    may_wait_goes,
                    out.budget.ready_at(),
                    telemetry_due,
                ));
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
