//! Flight-controller firmware for a payload carried by rail-riding rotor robots: the application
//! ([`app`]) written once over small board interfaces ([`board`]), for the Pixhawk 6C and for
//! QEMU's mps2-an500 (the HIL target).
//!
//! A thin layer: every algorithm lives in `shared` (which the simulator runs unchanged) and the
//! MAVLink protocol logic in `link` (host-tested); here are the tasks, their priorities and
//! their timing, and the boards' drivers.
#![no_std]
#![deny(missing_docs)]

pub mod app;
pub mod board;
