//! The simulator and bench tool around `shared`: scenario files, the command line and (as they
//! arrive) the physics plant and the harness that runs `shared` at the firmware's rates.
//!
//! No algorithm lives here: everything the vehicle decides is computed by `shared`.

pub mod cli;
pub mod commands;
pub mod figures;
pub mod harness;
pub mod hil;
pub mod mission_run;
pub mod monte_carlo;
pub mod plant;
pub mod report;
pub mod scenario_file;
