//! Runs a mission against the physics plant (docs/system.md#pipeline; `mission`, `hil`): the
//! estimation lifts are real lift-offs of the simulated payload read from the simulated IMU,
//! the robots move along the rail as commanded, and the flight is the plant's.
//!
//! One plant loop, [`fly`], serves both commands. What flies is an [`Autopilot`]: `shared`'s
//! mission in this process ([`InProcess`], the `mission` command) or the firmware over PX4's
//! HIL MAVLink API (`crate::hil`). Either way the loop hands it the same sensor samples tick
//! by tick and takes back rotor commands as fractions of the rotors' maximum (as
//! `HIL_ACTUATOR_CONTROLS` carries them) and rail positions, so the same seed gives the same
//! flight whichever runs the mission.
//!
//! Here: the autopilot's side of the loop ([`Autopilot`], [`Sensed`], [`Commanded`]); in
//! `setup` what a run is set up with and the failures injected ([`MissionSetup`]); in
//! `plant_loop` the loop itself ([`fly`]) and what the plant saw ([`PlantRecord`]); in
//! `in_process` `shared`'s mission as the autopilot ([`InProcess`], [`run`]).

use crate::pilot_script::PilotFrame;
use anyhow::Result;
use shared::control::navigator::{ImuSample, MocapFix};
use shared::flight::AdaptEvent;
use shared::mission::{EscRpm, HardwareFaults, OperatorCommand};

mod in_process;
mod plant_loop;
mod setup;

pub use in_process::{DELIVERY_RADIUS, InProcess, MissionOutcome, run};
pub use plant_loop::{Adaptation, FlightSample, PlantRecord, SERIES_EVERY, fly, model_lift};
pub use setup::{
    BatteryDrop, EscLink, ImuFaultKind, ImuInjection, LOAD_SHIFT_TIME, LoadShift, MissionSetup,
    Onset, PACK_SAG_VOLTS, PACK_VOLTS, RotorStop,
};

/// Longest mission simulated, s.
pub const MISSION_TIME_LIMIT: f32 = 900.0;

/// What the autopilot gets each tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensed {
    /// The sample's time, us.
    pub time_us: u64,
    /// The IMU sample.
    pub imu: ImuSample,
    /// A motion-capture fix that arrived since the last tick.
    pub mocap: Option<MocapFix>,
    /// An operator command.
    pub command: Option<OperatorCommand>,
    /// What the board's drivers report failed (the plant stands in for them).
    pub faults: HardwareFaults,
    /// Each rotor's RPM as its ESC's telemetry reports it, if the vehicle has it.
    pub esc_rpm: Option<EscRpm>,
    /// The simulated ground station's heartbeat (once a second) is due with this tick.
    pub gcs_heartbeat: bool,
    /// The ground link is lost (injected): nothing from any ground station reaches the
    /// vehicle.
    pub gcs_lost: bool,
    /// The pack's voltage at its terminals, V.
    pub battery_volts: f32,
    /// What a person's RC receiver or joystick sent with this tick (`--rc`).
    pub pilot: Option<PilotFrame>,
}

/// Something the autopilot reported this tick.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// The mission entered phase `name` for `reason` (both as people read them).
    Phase {
        /// The phase's short name (`Phase::name`).
        name: String,
        /// Why.
        reason: String,
    },
    /// The next lift's pair.
    PairChosen(usize),
    /// A lift's reading, N per robot (`None`: could not lift).
    LiftRead(Option<f32>),
    /// The in-flight adaptation did something.
    Adapted(AdaptEvent),
    /// The formation the robots move to before take-off, arc lengths, m.
    FormationChosen(Vec<f32>),
    /// Something the mission's supervision tells people (ground link, battery), as it says it.
    Notice(String),
    /// The start command was refused: why, as the autopilot says it. The run ends.
    StartRefused(String),
    /// The sticks steer the payload (Position mode) from this tick on (`true`), or no longer.
    Steered(bool),
}

/// What the autopilot commands each tick.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Commanded {
    /// Each rotor's thrust command as a fraction of its maximum.
    pub thrust: Vec<f32>,
    /// Each robot's rail position, arc length, m.
    pub rail: Vec<f32>,
    /// The rotors may turn.
    pub armed: bool,
    /// What happened.
    pub events: Vec<Event>,
    /// The mission is over (landed and disarmed, or aborted).
    pub over: bool,
}

/// What flies the payload.
pub trait Autopilot {
    /// One control tick.
    fn step(&mut self, sensed: &Sensed) -> Result<Commanded>;
}
