//! The autonomy of a payload carried by `n` single-rotor robots riding a common rail around it
//! (docs/system.md; the models: docs/models.md).
//!
//! Everything here is plain synchronous code: no allocation, no executor, no time source,
//! fixed capacities and `f32`. The flight controller (`firmware`) and the simulator
//! (`host-sim`) run exactly this code, so what the simulator tests is what flies.
//!
//! Math goes through [`libm`] explicitly (see [`math`]) so that host and target compute with the
//! same functions.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

// Tests may print and format; the library itself never uses std.
#[cfg(test)]
extern crate std;

pub mod control;
pub mod estimation;
pub mod flight;
pub mod formation;
pub mod geometry;
pub mod liftoff_detector;
pub mod liftoff_thrust;
pub mod manual;
pub mod math;
pub mod mission;
pub mod numbers;
pub mod paper;
pub mod rail;
pub mod scenario;
pub mod scenario_wire;
pub mod timing;
