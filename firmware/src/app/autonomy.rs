//! THE INTEGRATION POINT: the one seam between the firmware and the autonomy (issue 11,
//! sections 1 and 2).
//!
//! The control task calls [`Autonomy::tick`] once per IMU sample (400 Hz) with a [`TickInput`]
//! and applies the [`TickOutput`]: rotor thrusts and rail positions to the actuators (or, in
//! HIL, to the plant over MAVLink), texts and values to the link, the command's
//! acknowledgement, and a job to start. The job task runs [`run_job`] in thread mode and hands
//! its [`JobResult`] back in the `TickInput` of the step at the request's deadline, exactly
//! that step and no other, so runs are deterministic (in lockstep HIL the control task holds
//! that step's reply until the job is done).
//!
//! What is here now is a PLACEHOLDER, written without `shared`'s mission so the firmware's
//! plumbing can be proven alone: it holds zero thrust and never arms, keeps the robots where
//! the payload description puts them, takes the start command, asks for one synthetic job (a
//! checksum loop that outlasts its deadline, so the lockstep hold is exercised) and
//! completes two seconds after the start. The real mission replaces [`Autonomy`],
//! [`JobWork`], [`JobResult`] and [`run_job`]; the types the control and link tasks use
//! ([`TickInput`], [`TickOutput`], [`Report`], [`JobRequest`]) are meant to stay.

use core::fmt::Write as _;

use heapless::Vec;
pub use link::command::OperatorCommand;
pub use link::hil::{MAX_ROBOTS, MocapFix};
pub use link::status::MissionState;
use link::status::Text;
use shared::scenario::Scenario;

/// One IMU sample, body frame (FRD).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImuReading {
    /// Body rates, rad/s.
    pub gyro: [f32; 3],
    /// Specific force, m/s^2 (`[0, 0, -9.81]` at rest).
    pub accel: [f32; 3],
}

/// What one control step gets.
#[derive(Clone, Copy, Debug)]
pub struct TickInput<'a> {
    /// The vehicle's time, us (in HIL: the plant's `HIL_SENSOR` time).
    pub time_us: u64,
    /// Control steps before this one.
    pub step: u64,
    /// The IMU sample of this step.
    pub imu: ImuReading,
    /// A motion-capture fix received since the last step (NED; stamped when taken).
    pub mocap: Option<MocapFix>,
    /// An operator command received since the last step.
    pub command: Option<OperatorCommand>,
    /// A payload description received (and checked) since the last step.
    pub payload: Option<&'a Scenario>,
    /// The result of the job asked for `deadline_steps` ago, in exactly that step.
    pub job: Option<JobResult>,
}

/// How a command was taken (its `COMMAND_ACK`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandResult {
    /// Carried out.
    Accepted,
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
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JobRequest {
    /// Control steps after the request at which the result is taken (its worst case on the
    /// M7, rounded up).
    pub deadline_steps: u32,
    /// What to compute.
    pub work: JobWork,
}

/// What a job computes. PLACEHOLDER: the mission's jobs (pair selection, posterior update,
/// formation solve, mixer build) replace it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JobWork {
    /// `iterations` steps of xorshift32 from [`CHECKSUM_SEED`], xor-folded.
    Checksum {
        /// Steps.
        iterations: u32,
    },
}

/// What a job returns. PLACEHOLDER (see [`JobWork`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JobResult {
    /// The checksum of [`JobWork::Checksum`].
    Checksum(u32),
}

/// Seed of the placeholder job's checksum.
pub const CHECKSUM_SEED: u32 = 0x1234_5678;

/// Runs a job (in thread mode).
pub fn run_job(work: &JobWork) -> JobResult {
    match *work {
        JobWork::Checksum { iterations } => {
            let mut x = CHECKSUM_SEED;
            let mut folded = 0u32;
            for _ in 0..iterations {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                folded ^= x;
            }
            JobResult::Checksum(folded)
        }
    }
}

/// What one control step commands and reports.
#[derive(Clone, Debug, PartialEq)]
pub struct TickOutput {
    /// Robots in use.
    pub robots: usize,
    /// Rotor thrust of each robot, fraction of its maximum, `[0, 1]`.
    pub thrust: [f32; MAX_ROBOTS],
    /// Commanded position of each robot along the rail, arc length, m.
    pub rail: [f32; MAX_ROBOTS],
    /// The rotors may turn.
    pub armed: bool,
    /// Where the mission stands.
    pub state: MissionState,
    /// The acknowledgement of this step's command.
    pub ack: Option<(OperatorCommand, CommandResult)>,
    /// A job to start now.
    pub job: Option<JobRequest>,
    /// Texts and values.
    pub report: Report,
}

/// Placeholder: steps the synthetic job takes (about 48 million instructions: some 100 ms on
/// the M7 at 480 MHz, the size of a formation solve).
const PLACEHOLDER_JOB_ITERATIONS: u32 = 6_000_000;
/// Placeholder: the job's deadline, control steps (the next step). Deliberately far shorter
/// than the job, so that in lockstep the control task must hold that step's reply until the
/// job is done (the path a mission job takes when the M7 is slower than its worst case
/// promised); off HIL the step goes on without it and reports the job late.
const PLACEHOLDER_JOB_DEADLINE: u32 = 1;
/// Placeholder: the mission completes this long after its start, us.
const PLACEHOLDER_MISSION_US: u64 = 2_000_000;

/// The autonomy. PLACEHOLDER: holds zero thrust (see the module documentation).
pub struct Autonomy {
    robots: usize,
    rail: [f32; MAX_ROBOTS],
    loaded: bool,
    state: MissionState,
    started_us: u64,
}

impl Default for Autonomy {
    fn default() -> Self {
        Self::new()
    }
}

impl Autonomy {
    /// Idle, no payload description.
    pub const fn new() -> Self {
        Self {
            robots: 0,
            rail: [0.0; MAX_ROBOTS],
            loaded: false,
            state: MissionState::Idle,
            started_us: 0,
        }
    }

    /// One control step.
    pub fn tick(&mut self, input: &TickInput<'_>) -> TickOutput {
        let mut report = Report::default();
        let mut ack = None;
        let mut job = None;
        if let Some(scenario) = input.payload {
            if self.state == MissionState::Running {
                report.text(
                    Severity::Warning,
                    format_args!("payload description ignored: the mission is running"),
                );
            } else {
                self.robots = scenario.robots.count().min(MAX_ROBOTS);
                self.rail = [0.0; MAX_ROBOTS];
                self.rail[..self.robots].copy_from_slice(&scenario.robots.initial[..self.robots]);
                self.loaded = true;
            }
        }
        if let Some(command) = input.command {
            let result = match (command, self.state) {
                (OperatorCommand::Start, MissionState::Running) => {
                    CommandResult::TemporarilyRejected
                }
                (OperatorCommand::Start, _) if !self.loaded => {
                    report.text(
                        Severity::Error,
                        format_args!("start refused: no payload description loaded"),
                    );
                    CommandResult::Denied
                }
                (OperatorCommand::Start, _) => {
                    self.state = MissionState::Running;
                    self.started_us = input.time_us;
                    report.text(
                        Severity::Info,
                        format_args!(
                            "phase: running: started with {} robots (placeholder autonomy: zero thrust)",
                            self.robots
                        ),
                    );
                    job = Some(JobRequest {
                        deadline_steps: PLACEHOLDER_JOB_DEADLINE,
                        work: JobWork::Checksum {
                            iterations: PLACEHOLDER_JOB_ITERATIONS,
                        },
                    });
                    report.value("job_req", Value::Int(input.step as i32));
                    CommandResult::Accepted
                }
                (OperatorCommand::Abort | OperatorCommand::Kill, MissionState::Running) => {
                    self.state = MissionState::Aborted;
                    report.text(
                        Severity::Warning,
                        format_args!("phase: aborted: operator {:?}", command),
                    );
                    CommandResult::Accepted
                }
                (OperatorCommand::LandNow, MissionState::Running) => {
                    self.state = MissionState::Completed;
                    report.text(
                        Severity::Info,
                        format_args!("phase: completed: landed on the operator's command"),
                    );
                    CommandResult::Accepted
                }
                _ => CommandResult::Denied,
            };
            ack = Some((command, result));
        }
        if let Some(JobResult::Checksum(sum)) = input.job {
            report.text(
                Severity::Info,
                format_args!("job: checksum {sum:#010x} taken at step {}", input.step),
            );
            report.value("job_sum", Value::Int(sum as i32));
            report.value("job_step", Value::Int(input.step as i32));
        }
        if self.state == MissionState::Running
            && input.time_us.saturating_sub(self.started_us) >= PLACEHOLDER_MISSION_US
        {
            self.state = MissionState::Completed;
            report.text(
                Severity::Info,
                format_args!("phase: completed: placeholder mission held zero thrust for 2 s"),
            );
        }
        TickOutput {
            robots: self.robots,
            thrust: [0.0; MAX_ROBOTS],
            rail: self.rail,
            armed: false,
            state: self.state,
            ack,
            job,
            report,
        }
    }
}
