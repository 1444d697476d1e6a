//! The firmware's tasks: each one owns its peripherals and calls into `shared` for logic.

pub mod control;
pub mod heartbeat;
