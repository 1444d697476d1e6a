//! The simulator and bench tool around `shared`: scenario files, the command line and (as they
//! arrive) the physics plant and the harness that runs `shared` at the firmware's rates.
//!
//! No algorithm lives here: everything the vehicle decides is computed by `shared`.

// The workspace's rust-version went to 1.88 (mavlink 0.21); clippy then asks for
// `is_multiple_of` in code written for 1.85 (the harness). Allowed until that code adopts it.
#![allow(clippy::manual_is_multiple_of)]

pub mod bench_csv;
pub mod campaign;
pub mod cli;
pub mod commands;
pub mod estimate_report;
pub mod figures;
pub mod flight_log;
pub mod formation_report;
pub mod harness;
pub mod hil;
pub mod inject;
pub mod log_summary;
pub mod mission_figures;
pub mod mission_run;
pub mod monte_carlo;
pub mod pilot_script;
pub mod plant;
pub mod report;
pub mod rotor_faults;
/// Reading scenario files: the `scenario-toml` crate, which the fuzz targets share.
pub use scenario_toml as scenario_file;
pub mod thrust_calibration;
pub mod trial_trace;
