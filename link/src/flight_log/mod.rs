//! The flight log (docs/formats.md#flight-logs): what the vehicle records of a mission, as
//! ULog ([`crate::ulog`]) that PX4's tools open.
//!
//! - [`topics`]: the logged topics, PX4's names where the meaning is PX4's, with their
//!   formats, and the fixed-size [`topics::Record`] of each.
//! - [`recorder`]: what a control step records, from the mission's input and output.
//! - [`session`]: a mission's log from its start to its end (the recorder and the writer).
//! - [`stream`]: the control step's bytes to the task that stores them: whole messages or
//!   none, losses as dropouts, the start and end of a mission's log.
//! - [`keeper`]: the storing side: a numbered log per mission in storage, written in blocks.
//! - [`file`]: the log's definitions (formats, information, parameters, subscriptions) and
//!   each record as a ULog message.
//!
//! The firmware and the simulator record with the same code, so a simulated flight and a real
//! one are compared in one tool.

pub mod file;
pub mod keeper;
pub mod recorder;
pub mod session;
pub mod stream;
pub mod topics;
