//! `host-sim calibrate WHAT`: bench measurements made into the vehicle's parameters, one
//! subcommand per calibration (docs/commands.md#calibrating-the-thrust-map). Today: `thrust`,
//! the ESC command-to-thrust map from a load-cell sweep.

pub mod thrust;

use anyhow::Result;
use clap::{Args, Subcommand};

use crate::cli::Outcome;

/// Arguments of `calibrate`.
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Which calibration.
    #[command(subcommand)]
    pub what: Calibration,
}

/// The calibrations.
#[derive(Debug, Subcommand)]
pub enum Calibration {
    /// The thrust map (THR_MAP_20 .. THR_MAP_80) from a motor bench sweep (CSV of `command`
    /// and `thrust_n`).
    Thrust(thrust::ThrustArgs),
}

/// Runs the calibration asked for.
pub fn run(args: &CalibrateArgs) -> Result<Outcome> {
    match &args.what {
        Calibration::Thrust(args) => thrust::run(args),
    }
}
