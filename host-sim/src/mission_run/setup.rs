//! What a mission run is set up with ([`MissionSetup`]): the seed, the mission's
//! configuration, the operator's commands, and the failures injected into the plant
//! (docs/failures.md#failures: a load that shifts, rotors that stop, a stepper that stalls,
//! the IMU, the ground station, the pack's voltage).

use shared::control::vector::Vec3;
use shared::geometry::Vec2;
use shared::mission::{MissionConfig, OperatorCommand};
use std::path::PathBuf;

use super::MISSION_TIME_LIMIT;

/// One mission run's set-up.
#[derive(Clone, Debug)]
pub struct MissionSetup {
    /// Seed of sensor noise and disturbance.
    pub seed: u64,
    /// The rotors' command-to-thrust over-read factor.
    pub map_error: f32,
    /// The mission's configuration (in this process; the firmware has its own).
    pub config: MissionConfig,
    /// Failure injection: motion capture stops this long after take-off began, s.
    pub mocap_lost_after_takeoff: Option<f32>,
    /// The operator confirms the rail positions (the robots stand at their marks) with the
    /// first tick, and the start goes with the second: an autopilot takes one command a tick.
    /// The firmware needs it (its rails are unconfirmed at power-up; `hil` sets it unless
    /// `--unconfirmed-rails`); `shared`'s mission in process has them confirmed already, so
    /// there it only puts the start a tick later (as a HIL run has it).
    pub confirm_rails: bool,
    /// Operator commands after the start: (seconds after take-off began, command).
    pub commands: Vec<(f32, OperatorCommand)>,
    /// Stop after this much simulated time, s (at most [`MISSION_TIME_LIMIT`]).
    pub time_limit: f32,
    /// Failure injection: the payload's COM moves in flight.
    pub load_shift: Option<LoadShift>,
    /// Failure injection: this robot's stepper stalls halfway through the rearrangement and
    /// its driver says so (StallGuard on the board).
    pub stepper_stall: Option<usize>,
    /// Failure injection: the simulated ground station stops sending its heartbeat.
    pub gcs_loss: Option<Onset>,
    /// Failure injection: the pack's voltage drops.
    pub battery_drop: Option<BatteryDrop>,
    /// Failure injection: the IMU freezes or grows noisy.
    pub imu_fault: Option<ImuInjection>,
    /// Failure injection: rotors that stop in flight ([`crate::inject::rotors_out`] makes
    /// them from `--inject rotor-out:J@T`).
    pub rotors_out: Vec<RotorStop>,
    /// The ESCs report each rotor's RPM every tick (bidirectional DShot's telemetry).
    pub esc_telemetry: bool,
    /// How the flight controller drives the ESCs: DShot on its outputs, or DroneCAN on its
    /// CAN bus, whose ESCs report each rotor's RPM in their `Status` at 50 Hz.
    pub esc: EscLink,
    /// Write the mission's flight log (ULog) to this file.
    pub log: Option<PathBuf>,
    /// A ground station's route to fly instead of the scenario's target.
    pub route: Option<shared::flight::Route>,
    /// The gyro's constant bias, rad/s per body axis, in place of the one drawn from the seed
    /// (`hil --gyro-bias`).
    pub gyro_bias: Option<Vec3>,
    /// A person at the sticks, scripted (`--rc FILE`, docs/manual-control.md#stick-scripts).
    pub pilot: Option<crate::pilot_script::PilotScript>,
    /// How the plant departs from the model (the scenario's `[plant]`).
    pub plant: scenario_toml::PlantDepartures,
}

/// A rotor that stops: from `after` seconds after take-off began, robot `robot`'s rotor
/// (from 0) makes no thrust, whatever is commanded; or, with `fade` seconds, its thrust goes
/// from what is commanded to nothing over that time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotorStop {
    /// The robot, from 0.
    pub robot: usize,
    /// When, s after take-off began.
    pub after: f32,
    /// Seconds over which it fades to nothing (0: it stops at once).
    pub fade: f32,
}

/// An IMU that fails: from `after` seconds after take-off began (or after the mission's start,
/// `from_start`) every sample the autopilot gets is faulty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuInjection {
    /// How it fails.
    pub kind: ImuFaultKind,
    /// When, s.
    pub after: f32,
    /// `after` counts from the mission's start (the plant's time zero), not from take-off.
    pub from_start: bool,
}

/// How an injected IMU fails.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ImuFaultKind {
    /// It repeats the last sample it gave before the fault.
    Stuck,
    /// White noise of this many times the sensor's own is added to every axis.
    Noise(f32),
}

/// When an injected failure begins.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Onset {
    /// Before the start: the mission never sees it otherwise.
    FromStart,
    /// This many seconds after the mission's start (the plant's time zero).
    AfterStart(f32),
    /// This many seconds after take-off began.
    AfterTakeoff(f32),
}

impl Onset {
    /// Whether it has begun at `t`, take-off having begun at `takeoff_at` (infinite before).
    pub fn begun(self, t: f32, takeoff_at: f32) -> bool {
        match self {
            Self::FromStart => true,
            Self::AfterStart(after) => t >= after,
            Self::AfterTakeoff(after) => t >= takeoff_at + after,
        }
    }
}

/// A drop of the pack's open-circuit voltage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatteryDrop {
    /// The voltage it drops to, V.
    pub volts: f32,
    /// When.
    pub onset: Onset,
}

/// The simulated pack: the plant's ([`crate::plant::battery`]).
pub use crate::plant::battery::{PACK_SAG_VOLTS, PACK_VOLTS};

/// A load that shifts in flight: the payload's true COM moves by `offset` over
/// [`LOAD_SHIFT_TIME`], starting `after` seconds after take-off began (a mass sliding along
/// the plate).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadShift {
    /// How far the COM moves, body frame, m.
    pub offset: Vec2,
    /// When it starts, s after take-off began.
    pub after: f32,
}

/// Time a load shift takes, s.
pub const LOAD_SHIFT_TIME: f32 = 0.5;

impl Default for MissionSetup {
    /// Seed 1, an exact command-to-thrust map, the default mission, no failure, no command
    /// but the set-up the vehicle needs: the rails confirmed with the first tick and the start
    /// with the second, as the firmware takes them (so `mission` and `hil` fly the same ticks).
    fn default() -> Self {
        Self {
            seed: 1,
            map_error: 1.0,
            config: MissionConfig::default(),
            mocap_lost_after_takeoff: None,
            confirm_rails: true,
            commands: Vec::new(),
            time_limit: MISSION_TIME_LIMIT,
            load_shift: None,
            stepper_stall: None,
            imu_fault: None,
            gcs_loss: None,
            battery_drop: None,
            rotors_out: Vec::new(),
            esc_telemetry: false,
            esc: EscLink::Dshot,
            log: None,
            route: None,
            gyro_bias: None,
            pilot: None,
            plant: scenario_toml::PlantDepartures::MODEL,
        }
    }
}

/// How the flight controller drives the ESCs (`mission --esc`, `ESC_PROTOCOL`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum EscLink {
    /// DShot600 on the FMU outputs (`--esc-telemetry` adds bidirectional DShot's RPM).
    #[default]
    Dshot,
    /// DroneCAN ESCs on CAN1 (docs/hardware.md#can-escs): a `RawCommand` each step, each
    /// ESC's `Status` (its RPM) at 50 Hz, an ESC that falls silent named stopped.
    Dronecan,
}
