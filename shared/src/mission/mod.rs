//! The autonomous mission end to end (docs/system.md#pipeline): one state machine from pre-flight
//! checks through estimation, formation decision and rearrangement to the flight and disarm.
//!
//! - [`phases`]: the phases and the reasons of each transition.
//! - [`config`]: the mission's tuning.
//! - [`bringup`]: the IMU's calibrations and the motor test, on the bench.
//! - [`hardware`]: the drivers' settings (ESCs, thrust map, steppers).
//! - [`drives`]: how many robots a board drives, and the refusal of a payload with more.
//! - [`machine`]: the tick side, stepped at 400 Hz.
//! - [`jobs`]: the long computations the tick side hands off, and the planner that runs them.
//! - [`params`]: the tunables as named parameters (the ground link serves them).
//! - [`supervision`]: the ground link's and the battery's monitors.

pub mod bringup;
pub mod config;
pub mod drives;
pub mod esc_protocol;
pub mod hardware;
pub mod interface;
pub mod jobs;
pub mod machine;
pub mod params;
pub mod phases;
pub mod supervision;

pub use config::{DETECTOR_SIGMA, MissionConfig};
pub use hardware::HardwareConfig;
pub use jobs::{FormationPlan, JobRequest, JobResult, LiftPlan, MissionPlanner, MixerLeft};
pub use machine::{
    CommandRefusal, CommandReply, EscRpm, HardwareFaults, ImuDetection, Mission, OperatorCommand,
    SET_DOWN_CUT_TILT, SET_DOWN_TIME, TickInput, TickOutput,
};
pub use phases::{AbortReason, Phase, Reason, Transition};
pub use supervision::{Notice, Supervision, SupervisionConfig};
