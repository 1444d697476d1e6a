//! `hil`: the firmware as the autopilot of the `mission` command's plant loop
//! ([`crate::mission_run::fly`]), in lockstep.
//!
//! Before the loop: the firmware says who it is and takes the payload description over
//! MAVLink FTP. The firmware takes operator commands in its control steps, one a step, so the
//! rest of the set-up rides the first steps (the plant loop hands them, see
//! [`MissionSetup::confirm_rails`]): the rail positions confirmed with the first
//! (`MAV_CMD_USER_1`: the robots stand at the description's start positions; not with
//! `--unconfirmed-rails`), the start with the next (not with `--ground-start`), each of which
//! must be accepted with the step that takes it. Each control step (400 Hz): the
//! motion-capture fix due and the IMU sample go out; the plant then waits for the firmware's
//! actuator commands stamped with that sample's time, applies them (rotor thrust = fraction x
//! the robots' maximum; each robot moved to its commanded rail position) and advances its
//! physics by one step. Nothing advances without
//! the firmware's reply, so a run is the same however fast QEMU or the link is. `--speed X`
//! only slows the loop down to X times real time.
//!
//! The run ends when the firmware's heartbeat says its mission is over, when the payload tips
//! past 45 degrees, or at the time limit.
//!
//! A reboot a ground station asks for on the ground (`MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN`)
//! restarts the firmware under QEMU (a system reset reboots the guest); the session sends the
//! step's sample again until the new boot takes it ([`super::session`]), and the set-up is done
//! again: the payload description uploaded unless the firmware restored it from its storage,
//! the rails confirmed.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use anyhow::{Result, bail};
use link::command::CommandWire;
use link::hil::PlantSample;
use link::msg::{MavCmd, MavResult, MavSeverity};
use link::status::{MissionState, PHASE_PREFIX};
use shared::mission::OperatorCommand;
use shared::scenario_wire::{MAX_ENCODED_LEN, encode_scenario};

use super::gcs::GcsBridge;
use super::rc_link::RcLink;
use super::session::{FirmwareLog, LoggedText, Restart, Session};
use super::transport::{ByteCounts, Link};
use crate::inject::Injection;
use crate::mission_run::{
    self, Autopilot, Commanded, DELIVERY_RADIUS, Event, MISSION_TIME_LIMIT, MissionSetup, Sensed,
};
use crate::pilot_script::{PilotFrame, PilotScript};
use crate::scenario_file::LoadedScenario;

/// Plant steps between two `BATTERY_STATUS` (10 Hz, as PX4's battery status goes out).
pub const BATTERY_EVERY: u64 = 40;

/// How long the firmware may take to say whether it takes a payload description.
const PAYLOAD_TIMEOUT: Duration = Duration::from_secs(20);

/// Longest the plant waits after the mission for the firmware to say its flight log is
/// written (wall time): the logger runs below the control step and may still be draining its
/// ring into the file (seconds under a loaded host).
const FLIGHT_LOG_WAIT: Duration = Duration::from_secs(120);

/// One run's set-up.
#[derive(Clone, Debug)]
pub struct HilSetup {
    /// Seed of the sensors' noise.
    pub seed: u64,
    /// Pace the lockstep to this many times real time (`None`: as fast as it goes).
    pub speed: Option<f64>,
    /// Stop after this much simulated time even if the mission goes on, s.
    pub duration_s: Option<f64>,
    /// How long the plant waits for each reply before giving up.
    pub reply_timeout: Duration,
    /// Bridge non-HIL traffic to this ground station.
    pub gcs: Option<std::net::SocketAddr>,
    /// The rotors' command-to-thrust over-read factor.
    pub map_error: f32,
    /// Failure injection: motion capture stops this long after take-off began, s.
    pub mocap_lost_after_takeoff: Option<f32>,
    /// The ground station (through `gcs`) starts the mission, not the plant: the plant
    /// uploads the payload and steps the idle vehicle until the firmware reports it running.
    pub ground_start: bool,
    /// After the mission, the firmware and the ground link stay up this long at most (wall
    /// time), until the ground station is silent for [`super::session::GCS_SILENCE`]
    /// (`--linger`).
    pub linger: Option<Duration>,
    /// The plant confirms the rail positions (`MAV_CMD_USER_1`) with the first step, as an
    /// operator who placed the robots at their marks; `false` leaves it to a ground station
    /// (`--unconfirmed-rails`).
    pub confirm_rails: bool,
    /// The gyro's constant bias, rad/s per body axis, in place of the one drawn from the seed
    /// (`--gyro-bias`).
    pub gyro_bias: Option<[f32; 3]>,
    /// The firmware keeps flight logs (`--storage`): after the mission the plant waits until
    /// it says the log it started is written, so that stopping it loses none of the log's
    /// tail.
    pub keeps_logs: bool,
    /// The plant sends each rotor's RPM (`ESC_STATUS`) with every step, as ESCs with
    /// bidirectional DShot would report it (`--esc-telemetry`).
    pub esc_telemetry: bool,
    /// Failure injection in the plant, as `mission --inject` (`crate::inject`): rotors that
    /// stop, a load that shifts, a frozen or noisy IMU (in the `HIL_SENSOR` samples), motion
    /// capture lost, the ground link lost (the plant's heartbeat stops and nothing from a
    /// bridged ground station passes), the pack's voltage (its `BATTERY_STATUS`).
    pub injections: Vec<Injection>,
    /// A stick script (`--rc`, docs/hil.md): its RC frames go into the board's RC receiver UART
    /// as CRSF, its joystick frames as `MANUAL_CONTROL`; its parameters
    /// ([`PilotScript::parameters`]) are set on the vehicle before the payload goes up.
    pub pilot: Option<PilotScript>,
    /// Operator commands after the start, as a ground station sends them: (seconds after
    /// take-off began, command), each a `COMMAND_LONG` (`DO_SET_MODE` for a mode).
    pub commands: Vec<(f32, OperatorCommand)>,
}

impl Default for HilSetup {
    fn default() -> Self {
        Self {
            seed: 1,
            speed: None,
            duration_s: None,
            reply_timeout: Duration::from_secs(10),
            gcs: None,
            map_error: 1.0,
            ground_start: false,
            linger: None,
            confirm_rails: true,
            gyro_bias: None,
            keeps_logs: false,
            esc_telemetry: false,
            mocap_lost_after_takeoff: None,
            injections: Vec::new(),
            pilot: None,
            commands: Vec::new(),
        }
    }
}

/// What a run did.
#[derive(Clone, Debug)]
pub struct HilOutcome {
    /// The board the firmware reported.
    pub firmware: String,
    /// The firmware's estimate [COM x, COM y, mass], if its estimation converged.
    pub estimate: Option<[f32; 3]>,
    /// Lifts taken.
    pub measurements: u32,
    /// Each lift: group, reading (N, `None` when it could not lift), model lift-off thrust.
    pub lifts: Vec<(usize, Option<f32>, f32)>,
    /// Landed at the target, completed, with no abort on the way.
    pub delivered: bool,
    /// Why the firmware aborted (or landed in place), as it said it.
    pub aborted: Option<String>,
    /// Lockstep exchanges (control steps).
    pub ticks: u64,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall-clock time of the lockstep, s.
    pub wall_s: f64,
    /// Bytes that crossed the link during the lockstep.
    pub link_bytes: ByteCounts,
    /// A bridged ground station's frames forwarded and dropped by the radio link
    /// (`--gcs`; over the whole run).
    pub gcs_link: Option<super::gcs::GcsCounts>,
    /// The firmware's mission state at the end.
    pub state: MissionState,
    /// The acknowledgement of the start command.
    pub start_ack: Option<MavResult>,
    /// Roll or pitch passed 45 degrees.
    pub dropped: bool,
    /// Distance of the payload from the flight target's landing point at the end, m (from the
    /// start point when the scenario has no flight target).
    pub final_position_error_m: f64,
    /// The robots' last commanded rail positions, m (the flight formation once flown).
    pub positions: Vec<f32>,
    /// Each phase the firmware reported (`phase: NAME: ...`) and how long it lasted, s.
    pub phases: Vec<(String, f64)>,
    /// When the take-off began, simulated s (`None`: no take-off).
    pub takeoff_at_s: Option<f64>,
    /// Everything the firmware said.
    pub log: FirmwareLog,
    /// The flight, sampled at 100 Hz from take-off.
    pub series: Vec<crate::mission_run::FlightSample>,
    /// Largest roll or pitch while airborne, degrees.
    pub max_tilt_deg: f64,
    /// When the stick script first sent the kill switch on, simulated s.
    pub kill_sent_at: Option<f64>,
    /// The first step from the kill switch's frame on whose every rotor command was zero,
    /// simulated s.
    pub rotors_zero_at: Option<f64>,
    /// RC frames written into the board's receiver UART, and the wall time spent waiting for
    /// QEMU to take them, s.
    pub rc_frames_sent: (u64, f64),
}

/// A command of the plant's own set-up that must be accepted with the step that takes it.
#[derive(Clone, Copy, Debug)]
struct Awaited {
    command: OperatorCommand,
    /// Acknowledgements and texts logged before it went.
    acks_before: usize,
    texts_before: usize,
}

impl HilOutcome {
    /// Simulated seconds per wall-clock second of the lockstep.
    pub fn real_time_factor(&self) -> f64 {
        if self.wall_s > 0.0 {
            self.simulated_s / self.wall_s
        } else {
            0.0
        }
    }

    /// The processor's busy time per control step, averaged over the run and at its worst
    /// second: the name of the firmware's report (`busy_insn` under QEMU, instructions;
    /// `busy_cyc` on a board, cycles), the mean and the largest per step. Each report covers
    /// one second of steps; the first, which covers the start-up, is left out.
    pub fn busy_per_step(&self) -> Option<(&'static str, f64, f64)> {
        let steps_per_report = 400.0;
        ["busy_insn", "busy_cyc"].into_iter().find_map(|name| {
            let reports: Vec<f64> = self
                .log
                .values
                .iter()
                .filter(|v| v.name == name)
                .skip(1)
                .map(|v| v.value / steps_per_report)
                .collect();
            if reports.is_empty() {
                return None;
            }
            let mean = reports.iter().sum::<f64>() / reports.len() as f64;
            let worst = reports.iter().copied().fold(0.0, f64::max);
            Some((name, mean, worst))
        })
    }

    /// The worst control-step cost the firmware reported: its name (`tick_insn` under QEMU,
    /// instructions; `tick_cyc` on a board, cycles) and value.
    pub fn worst_tick(&self) -> Option<(&'static str, f64)> {
        ["tick_insn", "tick_cyc"]
            .into_iter()
            .find_map(|name| self.log.last_value(name).map(|v| (name, v)))
    }
}

/// The firmware as the plant loop's autopilot: each tick's sensors go out over the link and
/// the tick waits for the firmware's actuator commands; what it says becomes the loop's
/// events.
struct Firmware {
    session: Session,
    robots: usize,
    reply_timeout: Duration,
    speed: Option<f64>,
    wall: Instant,
    texts_seen: usize,
    values_seen: usize,
    was_running: bool,
    ground_start: bool,
    /// Commands to send, one a step (the firmware takes one a step).
    queue: VecDeque<OperatorCommand>,
    /// The set-up command sent with this step, whose acceptance is checked after it.
    awaited: Option<Awaited>,
    confirm_rails: bool,
    /// The payload description's wire form (uploaded again after a restart that lost it).
    payload: Vec<u8>,
    restarts_seen: usize,
    /// The board's RC receiver UART (`--rc` with an RC script).
    rc: Option<RcLink>,
    /// A command the firmware answered TEMPORARILY_REJECTED (a payload description still
    /// loading), to send again at this step, and the tries left.
    retry: Option<(u64, OperatorCommand, u32)>,
}

/// Steps between tries of a command the firmware answered TEMPORARILY_REJECTED (0.25 s of
/// the vehicle's clock), and the tries: the command protocol's "try again", for up to 10 s.
const RETRY_STEPS: u64 = 100;
const RETRIES: u32 = 40;

impl Firmware {
    /// Checks that the firmware accepted `awaited` with the step just done; `Ok(false)` when
    /// it answered TEMPORARILY_REJECTED, to be tried again.
    fn check_accepted(&self, awaited: Awaited) -> Result<bool> {
        let log = self.session.log();
        let cmd = awaited.command.mav_cmd();
        let what = match awaited.command {
            OperatorCommand::Start => "the mission start",
            OperatorCommand::ConfirmRails => "the rail confirmation (MAV_CMD_USER_1, param1 = 1)",
            _ => "a command of the plant's",
        };
        match log.acks[awaited.acks_before..]
            .iter()
            .find(|(c, _)| *c == cmd)
            .map(|(_, r)| *r)
        {
            Some(MavResult::MAV_RESULT_ACCEPTED) => Ok(true),
            Some(MavResult::MAV_RESULT_TEMPORARILY_REJECTED) => Ok(false),
            Some(result) => {
                let why = said_since(log, awaited.texts_before)
                    .or_else(|| last_error(log))
                    .unwrap_or_default();
                bail!("the firmware refused {what} ({result:?}){why}")
            }
            None => bail!("the firmware did not acknowledge {cmd:?} with the step that took it"),
        }
    }

    /// The set-up again after the firmware restarted: the payload description (unless it
    /// restored its own from storage) and the rails confirmed with the next step.
    fn set_up_again(&mut self, restart: Restart) -> Result<()> {
        let restored = self.session.log().texts[restart.texts_before..]
            .iter()
            .any(|t| t.text.contains("restored from storage"));
        if restored {
            let end = Instant::now() + PAYLOAD_TIMEOUT;
            self.session.payload_verdict(restart.texts_before, end)?;
        } else {
            self.session
                .upload_payload(&self.payload, PAYLOAD_TIMEOUT)?;
        }
        if self.confirm_rails {
            self.queue.push_front(OperatorCommand::ConfirmRails);
        }
        Ok(())
    }
}

impl Autopilot for Firmware {
    fn step(&mut self, sensed: &Sensed) -> Result<Commanded> {
        // The plant is the ground station too: its heartbeat and the pack's voltage go before
        // the step's command, so the vehicle has them when the start comes.
        self.session.cut_ground(sensed.gcs_lost);
        if sensed.gcs_heartbeat {
            self.session.send_gcs_heartbeat()?;
        }
        if self.session.steps().is_multiple_of(BATTERY_EVERY) {
            self.session.send_battery(sensed.battery_volts)?;
        }
        // The stick script's frame, before the sample: an RC frame into the receiver UART (in
        // by the time the sample goes, `RcLink::send`), a joystick's as MANUAL_CONTROL.
        match (&sensed.pilot, &mut self.rc) {
            (Some(PilotFrame::Rc(channels)), Some(rc)) => rc.send(channels)?,
            (Some(PilotFrame::Rc(_)), None) => {
                bail!("an RC stick script needs the board's receiver UART (hil --qemu)")
            }
            (Some(PilotFrame::Joystick(axes)), _) => self.session.send_manual_control(*axes)?,
            (None, _) => {}
        }
        if let Some(rpm) = &sensed.esc_rpm {
            self.session
                .send_esc_rpm(sensed.time_us, rpm, self.robots)?;
        }
        if let Some(command) = sensed.command {
            // With the ground station starting the mission, the plant's own start is not sent.
            if !(self.ground_start && command == OperatorCommand::Start) {
                self.queue.push_back(command);
            }
        }
        if let Some((at, command, left)) = self.retry
            && self.session.steps() >= at
        {
            self.queue.push_front(command);
            self.retry = Some((u64::MAX, command, left));
        }
        if let Some(command) = self.queue.pop_front() {
            if matches!(
                command,
                OperatorCommand::Start | OperatorCommand::ConfirmRails
            ) {
                let log = self.session.log();
                self.awaited = Some(Awaited {
                    command,
                    acks_before: log.acks.len(),
                    texts_before: log.texts.len(),
                });
            }
            self.session.send_command(command)?;
        }
        let sample = PlantSample {
            time_us: sensed.time_us,
            imu: sensed.imu,
        };
        let reply = self.session.step(
            &sample,
            sensed.mocap.as_slice(),
            self.robots,
            self.reply_timeout,
        )?;
        let accepted = match self.awaited.take() {
            Some(awaited) => Some((awaited, self.check_accepted(awaited)?)),
            None => None,
        };
        if let Some((awaited, true)) = accepted
            && self.retry.is_some_and(|(_, c, _)| c == awaited.command)
        {
            self.retry = None;
        }
        if let Some((awaited, false)) = accepted {
            let left = match self.retry {
                Some((_, c, left)) if c == awaited.command => left,
                _ => RETRIES,
            };
            if left == 0 {
                let why = said_since(self.session.log(), awaited.texts_before).unwrap_or_default();
                bail!(
                    "the firmware kept answering {:?} TEMPORARILY_REJECTED for 10 s{why}",
                    awaited.command.mav_cmd()
                );
            }
            self.retry = Some((
                self.session.steps() + RETRY_STEPS,
                awaited.command,
                left - 1,
            ));
        }
        if let Some(&restart) = self.session.log().restarts.get(self.restarts_seen) {
            self.restarts_seen += 1;
            self.set_up_again(restart)?;
        }
        let log = self.session.log();
        let mut events = Vec::new();
        for t in &log.texts[self.texts_seen..] {
            if let Some(rest) = t.text.strip_prefix(PHASE_PREFIX) {
                let (name, reason) = rest.split_once(':').unwrap_or((rest, ""));
                events.push(Event::Phase {
                    name: name.trim().to_string(),
                    reason: reason.trim().to_string(),
                });
            }
        }
        for v in &log.values[self.values_seen..] {
            match v.name.as_str() {
                "lift_pair" => events.push(Event::PairChosen(v.value as usize)),
                "lift_N" => {
                    events.push(Event::LiftRead((v.value >= 0.0).then_some(v.value as f32)));
                }
                _ => {}
            }
        }
        self.texts_seen = log.texts.len();
        self.values_seen = log.values.len();
        match log.state {
            Some(MissionState::Running) => self.was_running = true,
            Some(MissionState::Idle) if self.was_running => {
                bail!("the firmware's mission went back to idle while running (did it restart?)")
            }
            _ => {}
        }
        if let Some(speed) = self.speed.filter(|s| *s > 0.0) {
            let due = Duration::from_secs_f64(sensed.time_us as f64 * 1e-6 / speed);
            if let Some(wait) = due.checked_sub(self.wall.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        Ok(Commanded {
            thrust: reply.thrust[..self.robots].to_vec(),
            rail: reply.rail[..self.robots].to_vec(),
            armed: reply.armed,
            events,
            over: log.state.is_some_and(MissionState::is_over),
        })
    }
}

/// Runs `scenario` against the firmware on `link`; `on_text` sees each text with the lockstep
/// step it arrived at.
pub fn run(
    scenario: &LoadedScenario,
    link: Link,
    setup: &HilSetup,
    on_text: Box<dyn FnMut(&LoggedText) + Send>,
) -> Result<HilOutcome> {
    run_with_rc(scenario, link, None, setup, on_text)
}

/// How long the firmware may take to answer a `PARAM_SET`.
const PARAM_TIMEOUT: Duration = Duration::from_secs(10);

/// As [`run`], with the board's RC receiver UART `rc` (QEMU's, [`super::qemu::Qemu::take_rc`])
/// for a stick script's RC frames.
pub fn run_with_rc(
    scenario: &LoadedScenario,
    link: Link,
    rc: Option<RcLink>,
    setup: &HilSetup,
    on_text: Box<dyn FnMut(&LoggedText) + Send>,
) -> Result<HilOutcome> {
    let s = &scenario.scenario;
    if s.truth.is_none() {
        bail!("[truth]: hil needs the scenario's truth to simulate the payload");
    }
    let gcs = match setup.gcs {
        Some(addr) => Some(GcsBridge::start(addr, link.writer())?),
        None => None,
    };
    let mut session = Session::new(link, gcs, on_text);
    let firmware = session.identify(Duration::from_secs(20))?;
    // The script's switches mapped on the vehicle, before the payload is loaded with them.
    if setup.pilot.is_some() {
        for (name, value) in PilotScript::parameters() {
            session.set_param(name, value, PARAM_TIMEOUT)?;
        }
    }

    let mut file = [0u8; MAX_ENCODED_LEN];
    let len = encode_scenario(&scenario.name, s, &mut file).map_err(|e| {
        anyhow::anyhow!(
            "{}: cannot encode for the firmware: {e}",
            scenario.path.display()
        )
    })?;
    session.upload_payload(&file[..len], PAYLOAD_TIMEOUT)?;

    let mut autopilot = Firmware {
        session,
        robots: s.robots.count(),
        reply_timeout: setup.reply_timeout,
        speed: setup.speed,
        wall: Instant::now(),
        texts_seen: 0,
        values_seen: 0,
        was_running: false,
        ground_start: setup.ground_start,
        queue: VecDeque::new(),
        awaited: None,
        confirm_rails: setup.confirm_rails,
        payload: file[..len].to_vec(),
        restarts_seen: 0,
        rc,
        retry: None,
    };
    autopilot.texts_seen = autopilot.session.log().texts.len();
    autopilot.values_seen = autopilot.session.log().values.len();
    let plant_setup = crate::inject::apply(
        &setup.injections,
        MissionSetup {
            seed: setup.seed,
            map_error: setup.map_error,
            mocap_lost_after_takeoff: setup.mocap_lost_after_takeoff,
            time_limit: setup.duration_s.map_or(MISSION_TIME_LIMIT, |d| d as f32),
            // The rails confirmed with the first step, the start with the second.
            confirm_rails: setup.confirm_rails,
            esc_telemetry: setup.esc_telemetry,
            gyro_bias: setup
                .gyro_bias
                .map(|[x, y, z]| shared::control::vector::Vec3::new(x, y, z)),
            pilot: setup.pilot.clone(),
            commands: setup.commands.clone(),
            // The scenario's `[plant]`: the plant side's, never sent to the vehicle.
            plant: scenario.plant,
            ..MissionSetup::default()
        },
    );
    let wall = Instant::now();
    let bytes_before = autopilot.session.byte_counts();
    let record = mission_run::fly(s, &plant_setup, &mut autopilot, &mut |_, _, _| {})?;
    let wall_s = wall.elapsed().as_secs_f64();
    let bytes_after = autopilot.session.byte_counts();
    if setup.keeps_logs {
        autopilot.session.wait_for_logs_closed(FLIGHT_LOG_WAIT)?;
    }
    if let Some(linger) = setup.linger {
        autopilot.session.linger(linger)?;
    }
    let link_bytes = ByteCounts {
        to_firmware: bytes_after.to_firmware - bytes_before.to_firmware,
        from_firmware: bytes_after.from_firmware - bytes_before.from_firmware,
    };
    let log = autopilot.session.log().clone();
    let state = log.state.unwrap_or(MissionState::Idle);
    let estimate = match (
        log.last_value("est_x"),
        log.last_value("est_y"),
        log.last_value("est_m"),
    ) {
        (Some(x), Some(y), Some(m)) => Some([x as f32, y as f32, m as f32]),
        _ => None,
    };
    let aborted = log
        .texts
        .iter()
        .filter_map(|t| t.text.split_once("ABORT: ").map(|(_, why)| why.to_string()))
        .next_back();
    Ok(HilOutcome {
        firmware,
        ticks: autopilot.session.steps(),
        simulated_s: f64::from(record.simulated_s),
        wall_s,
        link_bytes,
        gcs_link: autopilot.session.gcs_counts(),
        state,
        start_ack: log.ack_of(MavCmd::MAV_CMD_MISSION_START),
        delivered: state == MissionState::Completed
            && aborted.is_none()
            && !record.dropped
            && record.final_position_error_m < DELIVERY_RADIUS,
        estimate,
        measurements: record.lifts.len() as u32,
        aborted,
        dropped: record.dropped,
        final_position_error_m: f64::from(record.final_position_error_m),
        positions: record.final_rail,
        phases: record
            .phases
            .iter()
            .map(|(n, d)| (n.clone(), f64::from(*d)))
            .collect(),
        takeoff_at_s: record.takeoff_at.map(f64::from),
        lifts: record.lifts,
        log,
        series: record.series,
        max_tilt_deg: f64::from(record.max_tilt_deg),
        kill_sent_at: record.kill_sent_at.map(f64::from),
        rotors_zero_at: record.rotors_zero_at.map(f64::from),
        rc_frames_sent: autopilot.rc.as_ref().map_or((0, 0.0), |rc| {
            let (n, waited) = rc.sent();
            (n, waited.as_secs_f64())
        }),
    })
}

/// What the firmware said since its text `texts_before` at warning or worse (a refusal's
/// reason), as `": TEXT"` (the last).
fn said_since(log: &FirmwareLog, texts_before: usize) -> Option<String> {
    log.texts[texts_before.min(log.texts.len())..]
        .iter()
        .rev()
        .find(|t| (t.severity as u8) <= MavSeverity::MAV_SEVERITY_WARNING as u8)
        .map(|t| format!(": {}", t.text))
}

/// The firmware's last error text, as `": TEXT"`.
fn last_error(log: &FirmwareLog) -> Option<String> {
    log.texts
        .iter()
        .rev()
        .find(|t| (t.severity as u8) <= 3)
        .map(|t| format!(": {}", t.text))
}
