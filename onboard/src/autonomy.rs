//! The one seam between the firmware and the autonomy: the
//! mission of `shared`, exactly the code the simulator flies.
//!
//! The control task calls [`Autonomy::tick`] once per IMU sample (400 Hz) with a [`StepInput`]
//! and applies the [`StepOutput`]: rotor thrusts and rail positions to the actuators (or, in
//! HIL, to the plant over MAVLink), texts and values to the link, the command's
//! acknowledgement, and a job to start. The job task runs [`run_job`] on the
//! [`MissionPlanner`] in thread mode and hands its [`JobResult`] back in the `StepInput` of the
//! step at the request's deadline, exactly that step and no other, so runs are deterministic
//! (in lockstep HIL the control task holds that step's reply until the job is done).
//!
//! What goes to the ground: each transition as `STATUSTEXT` `phase: NAME: reason`, and as
//! `NAMED_VALUE_*` the chosen pair (`lift_pair`), each reading (`lift_N`, -1 when the pair
//! could not lift), the estimate (`est_x`, `est_y` in m, `est_m` in kg, `lifts`) and the
//! formation's `det`; each step of the in-flight adaptation to a load that shifts as
//! `STATUSTEXT` `adapt: ...`.

use core::fmt::Write as _;

use flight_log::recorder::step_texts;
use flight_log::session::MissionLog;
use flight_log::stream::{LogRing, NoRing};
use flight_log::ulog::LogLevel;
use heapless::Vec;
pub use link::command::OperatorCommand;
pub use link::hil::{ImuSample, MAX_ROBOTS, MocapFix};
use link::mission::wire::MissionProgress;
use link::modes::FlightMode;
use link::msg::MavLandedState;
pub use link::status::MissionState;
use link::status::Text;
use link::telemetry::RouteStatus;
use link::telemetry::VehicleSnapshot;
use shared::control::trajectory::FlightPhase;
use shared::estimation::Measurement;
use shared::flight::Route;
use shared::manual::source::Manual;
/// The mission's input of one step ([`StepInput::tick`]).
pub use shared::mission::TickInput;
use shared::mission::bringup::{BenchConfig, CalibrationFailure, CalibrationKind};
use shared::mission::supervision::BatteryLevel;
use shared::mission::{CommandRefusal, Mission, MissionConfig, MissionPlanner, Phase, Reason};
use shared::numbers::Fixed;
use shared::scenario::Scenario;

/// What one control step gets: the mission's tick input and what the tasks around the
/// autonomy add to it.
#[derive(Clone, Debug)]
pub struct StepInput<'a> {
    /// The mission's input (the vehicle's time, in HIL the plant's `HIL_SENSOR` time; the IMU
    /// sample; a fix, an operator command, the ESCs' RPM received since the last step; the
    /// drivers' faults; the supervision's heartbeat and pack voltage; manual control).
    pub tick: TickInput,
    /// Control steps before this one.
    pub step: u64,
    /// The job task is loading the planner with a description or new parameters (`LOADING`):
    /// a start now is refused as temporarily rejected (the ground tries again).
    pub loading: bool,
    /// A change of the ground station's route since the last step.
    pub route: Option<&'a RouteChange>,
    /// The parameters changed since the last step: the IMU's offsets and the hardware
    /// settings go in force now, with or without a payload.
    pub bench: Option<BenchConfig>,
}

/// A change of the ground station's route (docs/ground-link.md#missions).
// The route is carried whole (no allocator to box it); the channel holds two.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum RouteChange {
    /// Fly this route from the next start (empty: the payload description's target).
    Set(Route),
    /// Fly from this item (`MISSION_SET_CURRENT`).
    Current(u16),
}

/// How a command was taken (its `COMMAND_ACK`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandResult {
    /// Carried out.
    Accepted,
    /// Begun; a second acknowledgement says how it ended (a calibration).
    InProgress,
    /// Begun and failed (a calibration: a text says why).
    Failed,
    /// Not now (for example: already running).
    TemporarilyRejected,
    /// Not allowed (for example: start without a payload description).
    Denied,
}

/// Severity of a text, as MAVLink's `MAV_SEVERITY`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    /// Normal operation.
    Info,
    /// Worth a person's attention.
    Notice,
    /// Something is off but handled.
    Warning,
    /// Something failed.
    Error,
    /// The vehicle's safety is at stake.
    Critical,
}

/// One text for the ground (`STATUSTEXT`).
#[derive(Clone, Debug, PartialEq)]
pub struct StatusLine {
    /// Severity.
    pub severity: Severity,
    /// The text, for people (phases as `phase: NAME: reason`, see `link::status`).
    pub text: Text,
}

/// A named number for the ground (`NAMED_VALUE_FLOAT` or `NAMED_VALUE_INT`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NamedValue {
    /// Name, at most 10 bytes.
    pub name: &'static str,
    /// The value.
    pub value: Value,
}

/// A named value's number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// `NAMED_VALUE_FLOAT`.
    Float(f32),
    /// `NAMED_VALUE_INT`.
    Int(i32),
}

/// What one step reports beyond its commands.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// Texts, in order.
    pub texts: Vec<StatusLine, 3>,
    /// Values.
    pub values: Vec<NamedValue, 6>,
}

impl Report {
    /// Adds a text (dropped when the step already has three: the mission sends few).
    pub fn text(&mut self, severity: Severity, args: core::fmt::Arguments<'_>) {
        let mut text = Text::new();
        // A text longer than the link's maximum is cut there.
        let _ = text.write_fmt(args);
        let _ = self.texts.push(StatusLine { severity, text });
    }

    /// Adds a value (dropped when the step already has six).
    pub fn value(&mut self, name: &'static str, value: Value) {
        let _ = self.values.push(NamedValue { name, value });
    }
}

/// A long computation to run in thread mode, off the tick.
#[derive(Clone, Debug, PartialEq)]
pub struct JobRequest {
    /// Control steps after the request at which the result is taken (its worst case on the
    /// M7, rounded up).
    pub deadline_steps: u32,
    /// What to compute: one of the mission's jobs.
    pub work: shared::mission::JobRequest,
}

/// What a job returns.
pub type JobResult = shared::mission::JobResult;

/// Runs a job on the planner (in thread mode).
pub fn run_job(planner: &mut MissionPlanner, work: &shared::mission::JobRequest) -> JobResult {
    planner.run(work)
}

/// A calibration's offsets, for the parameters of its kind.
pub type Offsets = (CalibrationKind, [f32; 3]);

/// What one control step commands and reports.
#[derive(Clone, Debug, PartialEq)]
pub struct StepOutput {
    /// Robots in use.
    pub robots: usize,
    /// Rotor thrust of each robot, fraction of its maximum, `[0, 1]`.
    pub thrust: [f32; MAX_ROBOTS],
    /// Commanded position of each robot along the rail, arc length, m.
    pub rail: [f32; MAX_ROBOTS],
    /// The rotors may turn.
    pub armed: bool,
    /// A motor test spins rotors (armed on the ground, the mission not running).
    pub motor_test: bool,
    /// Where the mission stands.
    pub state: MissionState,
    /// The acknowledgement of this step's command.
    pub ack: Option<(OperatorCommand, CommandResult)>,
    /// A job to start now.
    pub job: Option<JobRequest>,
    /// Texts and values.
    pub report: Report,
    /// The state estimate after the step, for telemetry (time, IMU health and load are the
    /// control task's to fill).
    pub telemetry: VehicleSnapshot,
    /// The mode, the route's progress or the landed state in `telemetry` changed this step.
    pub status_changed: bool,
    /// A calibration ended this step: how (its command's second acknowledgement), and the
    /// offsets to store as parameters when it succeeded.
    pub calibrated: Option<(CommandResult, Option<Offsets>)>,
}

impl StepOutput {
    /// A step's output before a step fills it: no robots, nothing said.
    pub fn new() -> Self {
        Self {
            robots: 0,
            thrust: [0.0; MAX_ROBOTS],
            rail: [0.0; MAX_ROBOTS],
            armed: false,
            motor_test: false,
            state: MissionState::Idle,
            ack: None,
            job: None,
            report: Report::default(),
            telemetry: VehicleSnapshot::START,
            status_changed: false,
            calibrated: None,
        }
    }
}

impl Default for StepOutput {
    fn default() -> Self {
        Self::new()
    }
}

/// The autonomy: the mission's tick side. Its job side, the [`MissionPlanner`], lives with
/// the job task; it is loaded with the payload description before the description reaches
/// the mission (see `super::jobs`).
pub struct Autonomy {
    mission: Mission,
    /// The mode, route and landed state last worked out for the ground.
    status: Status,
    loaded: bool,
    /// A payload description came while the mission ran: the next step says it was ignored.
    payload_ignored: bool,
    /// The mission's flight log.
    log: MissionLog,
}

impl Default for Autonomy {
    fn default() -> Self {
        Self::new()
    }
}

/// Control steps between two workings-out of the ground's [`Status`].
const STATUS_EVERY: u64 = 8;

/// What the ground is shown of the mode, the route, the landing and the rotors out.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Status {
    mode: u8,
    route: RouteStatus,
    landed: u8,
    /// Rotors found stopped in flight, bit `i` for robot `i`.
    rotors_out: u16,
}

/// The `STATUSTEXT` severity of a text's level.
fn severity(level: LogLevel) -> Severity {
    match level {
        LogLevel::Emergency | LogLevel::Alert | LogLevel::Critical => Severity::Critical,
        LogLevel::Error => Severity::Error,
        LogLevel::Warning => Severity::Warning,
        LogLevel::Notice => Severity::Notice,
        LogLevel::Info | LogLevel::Debug => Severity::Info,
    }
}

/// A `STATUSTEXT` severity as a logged string's level (the inverse of [`severity`]).
fn level(severity: Severity) -> LogLevel {
    match severity {
        Severity::Critical => LogLevel::Critical,
        Severity::Error => LogLevel::Error,
        Severity::Warning => LogLevel::Warning,
        Severity::Notice => LogLevel::Notice,
        Severity::Info => LogLevel::Info,
    }
}

impl Autonomy {
    /// Idle, no payload description, built at run time (see [`Mission::unloaded`]).
    pub fn new() -> Self {
        Self {
            mission: Mission::unloaded(),
            status: Status {
                mode: 0,
                route: RouteStatus::NONE,
                landed: VehicleSnapshot::START.landed,
                rotors_out: 0,
            },
            loaded: false,
            payload_ignored: false,
            log: MissionLog::without_step_texts(),
        }
    }

    /// Where the mission stands, for the heartbeat.
    fn state(&self) -> MissionState {
        match self.mission.phase() {
            Phase::Idle => MissionState::Idle,
            Phase::Disarmed if self.mission.abort_reason().is_none() => MissionState::Completed,
            Phase::Disarmed | Phase::Aborted => MissionState::Aborted,
            _ => MissionState::Running,
        }
    }

    /// The flight mode ground stations show (docs/ground-link.md#flight-modes).
    pub fn mode(&self) -> FlightMode {
        let flight = self.mission.flight();
        match self.mission.phase() {
            Phase::Idle | Phase::Disarmed | Phase::Aborted => FlightMode::Ready,
            Phase::Flying(_) if flight.is_some_and(|f| f.landing_cause().is_some()) => {
                FlightMode::Land
            }
            Phase::Flying(_) if self.mission.position_mode() => FlightMode::Position,
            Phase::Flying(_) if flight.is_some_and(|f| f.holding()) => FlightMode::Hold,
            _ => FlightMode::Mission,
        }
    }

    /// The landed state ground stations show (`EXTENDED_SYS_STATE`).
    fn landed_state(&self) -> MavLandedState {
        let Some(flight) = self.mission.flight().filter(|f| f.stopped().is_none()) else {
            return MavLandedState::MAV_LANDED_STATE_ON_GROUND;
        };
        match self.mission.phase() {
            Phase::Flying(FlightPhase::Takeoff) if !flight.airborne() => {
                MavLandedState::MAV_LANDED_STATE_TAKEOFF
            }
            Phase::Flying(_) if !flight.airborne() => MavLandedState::MAV_LANDED_STATE_ON_GROUND,
            Phase::Flying(FlightPhase::Land | FlightPhase::Done) => {
                MavLandedState::MAV_LANDED_STATE_LANDING
            }
            Phase::Flying(_) if flight.landing_cause().is_some() => {
                MavLandedState::MAV_LANDED_STATE_LANDING
            }
            Phase::Flying(_) => MavLandedState::MAV_LANDED_STATE_IN_AIR,
            _ => MavLandedState::MAV_LANDED_STATE_ON_GROUND,
        }
    }

    /// Where the vehicle is along its route, for `MISSION_CURRENT`.
    fn route_status(&self, mode: FlightMode) -> RouteStatus {
        let Some((current, reached)) = self.mission.route_progress() else {
            return RouteStatus::NONE;
        };
        let last = self.mission.route().len().saturating_sub(1) as u8;
        let progress = match self.state() {
            MissionState::Idle => MissionProgress::NotStarted,
            MissionState::Completed if reached == Some(last) => MissionProgress::Complete,
            _ if mode == FlightMode::Hold => MissionProgress::Paused,
            _ => MissionProgress::Active,
        };
        RouteStatus {
            current: u16::from(current),
            reached: reached.map(u16::from),
            progress,
        }
    }

    /// Puts a change of the route in force, or says why it is not.
    fn change_route(&mut self, change: &RouteChange, report: &mut Report) {
        match change {
            RouteChange::Set(route) => {
                if let Err(e) = self.mission.set_route(route) {
                    report.text(
                        Severity::Warning,
                        format_args!("mission not flown this time: {e}; it is for the next start"),
                    );
                }
            }
            RouteChange::Current(item) => {
                let item = u8::try_from(*item).unwrap_or(u8::MAX);
                match self.mission.set_route_item(item) {
                    Ok(()) => report.text(
                        Severity::Info,
                        format_args!("mission: flying from item {item}"),
                    ),
                    Err(e) => report.text(
                        Severity::Warning,
                        format_args!("mission: not flying from item {item}: {e}"),
                    ),
                }
            }
        }
    }

    /// Takes a payload description received (and checked) since the last step, with the
    /// configuration (from the parameters) the planner was loaded with, before the step:
    /// loaded when the mission is idle or over (handed over, not copied), otherwise ignored
    /// and the step says so.
    pub fn take_payload(&mut self, scenario: Scenario, config: MissionConfig) {
        if self.mission.phase() == Phase::Idle || self.state().is_over() {
            self.mission.load_owned(scenario, config);
            self.loaded = true;
        } else {
            self.payload_ignored = true;
        }
    }

    /// The result of the job asked for `deadline_steps` ago, handed over by value before the
    /// step that is its deadline (it is dropped by the mission when it no longer waits for it,
    /// after an abort). Not a copy of the step's input: the flight model is 2.8 KB, and a
    /// copy of it costs the step over 1,000 instructions.
    pub fn deliver_job(&mut self, result: JobResult) {
        self.mission.deliver(result);
    }

    /// One control step, keeping no log.
    pub fn tick(&mut self, input: &StepInput<'_>) -> StepOutput {
        self.tick_logged(input, &mut NoRing)
    }

    /// One control step, its flight log (from the mission's start to its end) into `ring`.
    pub fn tick_logged(&mut self, input: &StepInput<'_>, ring: &mut impl LogRing) -> StepOutput {
        let mut step = StepOutput::new();
        self.tick_into(input, ring, &mut step);
        step
    }

    /// One control step written into `step` (every field: what it held before is gone), its
    /// flight log into `ring`. For the firmware's control step: its texts and telemetry (about
    /// 1.3 KB) are written where the caller keeps them, never copied on return (a copy costs
    /// the step about 1,000 instructions).
    pub fn tick_into(
        &mut self,
        input: &StepInput<'_>,
        ring: &mut impl LogRing,
        step: &mut StepOutput,
    ) {
        step.report.texts.clear();
        step.report.values.clear();
        let report = &mut step.report;
        if core::mem::take(&mut self.payload_ignored) {
            report.text(
                Severity::Warning,
                format_args!("payload description ignored: the mission is running"),
            );
        }
        if let Some(change) = input.route {
            self.change_route(change, report);
        }
        if let Some(config) = &input.bench {
            self.mission.configure_bench(config);
        }
        // A start while the planner is being loaded would fly a mission the planner no longer
        // matches: refused for now, the mission never sees it.
        let held_back = input.loading && input.tick.command == Some(OperatorCommand::Start);
        let command = input.tick.command.filter(|_| !held_back);
        let mission_input = TickInput {
            command,
            ..input.tick
        };
        let out = self.mission.step(&mission_input);
        // Its COMMAND_ACK says TEMPORARILY_REJECTED, and a text says why and what to do.
        let ack = if held_back {
            report.text(
                Severity::Warning,
                format_args!(
                    "start refused for now: the payload description is being loaded; start again in a moment"
                ),
            );
            Some((OperatorCommand::Start, CommandResult::TemporarilyRejected))
        } else {
            command.zip(out.reply).map(|(given, reply)| {
                let result = match reply.outcome {
                    Ok(()) if matches!(given, OperatorCommand::Calibrate(_)) => {
                        CommandResult::InProgress
                    }
                    Ok(()) => CommandResult::Accepted,
                    Err(CommandRefusal::AlreadyStarted | CommandRefusal::BenchBusy) => {
                        CommandResult::TemporarilyRejected
                    }
                    Err(_) => CommandResult::Denied,
                };
                (given, result)
            })
        };
        // What the step says to people (the log keeps the same texts).
        step_texts(&out, &mut |level, text| report.text(severity(level), text));
        let calibrated = out
            .calibrated
            .map(|(kind, result)| calibration_report(kind, result, report));
        if let Some(t) = out.transition {
            match t.reason {
                Reason::PairChosen { group, .. } => {
                    report.value("lift_pair", Value::Int(group as i32));
                }
                Reason::LiftRead(Measurement::Lifted { thrust }) => {
                    report.value("lift_N", Value::Float(thrust));
                }
                Reason::LiftRead(Measurement::CouldNotLift) => {
                    report.value("lift_N", Value::Float(-1.0));
                }
                Reason::Converged(theta) | Reason::Settled { theta, .. } => {
                    report.value("est_x", Value::Float(theta[0]));
                    report.value("est_y", Value::Float(theta[1]));
                    report.value("est_m", Value::Float(theta[2]));
                    report.value("lifts", Value::Int(self.mission.measurements() as i32));
                }
                Reason::FormationChosen(det) => report.value("det", Value::Float(det)),
                _ => {}
            }
        }
        // Every text of the step, as the ground gets it (formatted once), goes in the log too.
        let texts = &report.texts;
        self.log.step(
            &mission_input,
            &out,
            &self.mission,
            self.mission.robot_max_thrust(),
            ring,
            |log| {
                for line in texts {
                    let level = level(line.severity);
                    log.text_str(level, input.tick.time_us, &line.text);
                }
            },
        );
        let robots = if self.loaded {
            out.robots.len().min(MAX_ROBOTS)
        } else {
            0
        };
        let max_thrust = self.mission.robot_max_thrust().max(f32::MIN_POSITIVE);
        let mut thrust = [0.0; MAX_ROBOTS];
        let mut rail = [0.0; MAX_ROBOTS];
        for j in 0..robots {
            thrust[j] = (out.thrusts[j] / max_thrust).clamp(0.0, 1.0);
            rail[j] = out.robots[j];
        }

        let (attitude, position) = (&out.nav.attitude, &out.nav.position);
        let q = attitude.attitude;
        // The mode, the route's progress and the landed state, for the ground at 50 Hz (each
        // eighth step: they cost the step about 80 instructions), and at the mission's end
        // (the last item is reached at the touchdown, and the plant may stop stepping there).
        // Not at every transition: a job's result is taken in one, the busiest steps there are.
        let ended = out
            .transition
            .is_some_and(|t| matches!(t.to, Phase::Disarmed | Phase::Aborted));
        let mut status_changed = false;
        if input.step.is_multiple_of(STATUS_EVERY) || ended {
            let mode = self.mode();
            let status = Status {
                mode: mode.code(),
                route: self.route_status(mode),
                landed: self.landed_state() as u8,
                rotors_out: self.mission.flight().map_or(0, |f| f.rotors_out()),
            };
            status_changed = status != self.status;
            self.status = status;
        }
        let status = self.status;
        let manual = match self.mission.manual() {
            Manual::Never => ManualState::Never,
            Manual::Valid(..) => ManualState::Valid,
            Manual::Lost(_) => ManualState::Lost,
        };
        step.telemetry = VehicleSnapshot {
            attitude: [q.w, q.x, q.y, q.z],
            rates: [attitude.rate.x, attitude.rate.y, attitude.rate.z],
            position: [
                position.position.x,
                position.position.y,
                position.position.z,
            ],
            velocity: [
                position.velocity.x,
                position.velocity.y,
                position.velocity.z,
            ],
            position_valid: position.valid,
            armed: out.armed,
            robots: robots as u8,
            rail,
            rail_known: self.mission.rails_confirmed(),
            thrust,
            battery_mv: self
                .mission
                .battery_volts()
                .map_or(u16::MAX, |v| (v * 1000.0).min(65_534.0) as u16),
            battery_ok: self.mission.battery_level() == BatteryLevel::Ok,
            mode: status.mode,
            route: status.route,
            landed: status.landed,
            rotors_out: status.rotors_out,
            manual_present: manual != ManualState::Never,
            manual_valid: manual == ManualState::Valid,
            ..VehicleSnapshot::START
        };
        step.robots = robots;
        step.thrust = thrust;
        step.rail = rail;
        step.armed = out.armed;
        step.motor_test = out.motor_test;
        step.status_changed = status_changed;
        step.calibrated = calibrated;
        step.state = self.state();
        step.ack = ack;
        step.job = out.job.map(|work| JobRequest {
            deadline_steps: work.deadline_ticks(),
            work,
        });
    }
}

/// Says how a calibration ended (a text for people) and gives its second acknowledgement and
/// the offsets to store.
fn calibration_report(
    kind: CalibrationKind,
    result: Result<[f32; 3], CalibrationFailure>,
    report: &mut Report,
) -> (CommandResult, Option<Offsets>) {
    let name = kind.name();
    match result {
        Ok(o) => {
            let unit = match kind {
                CalibrationKind::Gyro => "rad/s",
                CalibrationKind::Level => "m/s^2",
            };
            report.text(
                Severity::Info,
                format_args!(
                    "calibration: {name} done: offsets {} {} {} {unit}",
                    Fixed(o[0], 4),
                    Fixed(o[1], 4),
                    Fixed(o[2], 4)
                ),
            );
            (CommandResult::Accepted, Some((kind, o)))
        }
        Err(why) => {
            report.text(
                Severity::Error,
                format_args!("calibration: {name} failed: {why}"),
            );
            (CommandResult::Failed, None)
        }
    }
}

/// Whether manual control was heard and is in force, for telemetry.
#[derive(Clone, Copy, PartialEq, Eq)]
enum ManualState {
    Never,
    Valid,
    Lost,
}
