//! One module per `host-sim` command: argument types, the run, and its report.

pub mod calibrate;
pub mod campaign;
pub mod estimate;
pub mod fly;
pub mod formation;
pub mod hil;
pub mod lift;
pub mod mission;
pub mod params;
pub mod plot;
pub mod validate;
