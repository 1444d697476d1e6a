//! The autonomous mission end to end (SPEC.md section 2): one state machine from pre-flight
//! checks through estimation, formation decision and rearrangement to the flight and disarm.
//!
//! - [`phases`]: the phases and the reasons of each transition.
//! - [`machine`]: the mission itself, stepped at 400 Hz.

pub mod machine;
pub mod phases;

pub use machine::{ImuReading, Mission, MissionConfig, MissionOutputs};
pub use phases::{AbortReason, Phase, Reason, Transition};
