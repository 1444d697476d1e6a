//! The flight log (docs/formats.md#flight-logs): what the vehicle records of a mission, as
//! ULog ([`ulog`]) that PX4's tools open. `no_std` and without allocation: the firmware, the
//! simulator and the target benchmark record with this crate, and the MAVLink log transfer
//! (`link`'s `log_transfer`) serves what it stored through [`keeper::LogStorage`]. Nothing here
//! knows MAVLink.
//!
//! - [`ulog`]: PX4's ULog flight log format, each message's encoder.
//! - [`topics`]: the logged topics, PX4's names where the meaning is PX4's, with their
//!   formats, and the fixed-size [`topics::Record`] of each.
//! - [`recorder`]: what a control step records, from the mission's input and output.
//! - [`session`]: a mission's log from its start to its end (the recorder and the writer).
//! - [`stream`]: the control step's bytes to the task that stores them: whole messages or
//!   none, losses as dropouts, the start and end of a mission's log.
//! - [`keeper`]: the storing side: a numbered log per mission in storage, written in blocks.
//! - [`file`](mod@file): the log's definitions (formats, information, parameters,
//!   subscriptions) and each record as a ULog message.
//! - `reader` (feature `std`): reads any ULog file back, the firmware's, the simulator's or
//!   PX4's (`host-sim plot`, docs/formats.md#plotting-a-flight-log).
//! - `memory` (feature `std`): logs kept in memory, the [`keeper::LogStorage`] of tests.
//!
//! The firmware and the simulator record with the same code, so a simulated flight and a real
//! one are compared in one tool.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

#[cfg(any(test, feature = "std"))]
extern crate std;

pub mod file;
pub mod keeper;
#[cfg(any(test, feature = "std"))]
pub mod memory;
#[cfg(feature = "std")]
pub mod reader;
pub mod recorder;
pub mod session;
pub mod stream;
pub mod topics;
pub mod ulog;
