//! The `host-sim` command line (SPEC.md section 5, "The simulator's command line").
//!
//! Every command takes `--scenario FILE` and `--json`; with `--json`, stdout is one JSON object
//! and nothing else. A value that starts with `-` may be given as `--com=-0.2,0.1`.

use std::ffi::OsString;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use crate::commands;

/// Simulator and bench tool for the rail-riding rotor transport.
#[derive(Debug, Parser)]
#[command(name = "host-sim", version, about, long_about = None)]
pub struct Cli {
    /// What to run.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Read and check a scenario file; print its derived geometry (hull, rail, grid).
    Validate(Common),
    /// The model's lift-off thrust of one adjacent candidate pair for a given COM and mass.
    Lift(commands::lift::LiftArgs),
    /// Monte Carlo of the estimation: random (or given) truths, noisy model readings.
    Estimate(commands::estimate::EstimateArgs),
    /// The formation that maximises det(B B^T), balanced about the COM, beside the even one.
    Formation(commands::formation::FormationArgs),
    /// Closed-loop flight in the physics plant: take off, fly to the target, hover, land.
    Fly(commands::fly::FlyArgs),
    /// The whole autonomous mission in the physics plant (default: the paper's rect-ex1).
    Mission(commands::mission::MissionArgs),
    /// The mission with the firmware in the loop (PX4's HIL MAVLink messages, in lockstep):
    /// under QEMU, on a board over serial, or behind a TCP socket.
    Hil(commands::hil::HilArgs),
}

/// Options every command takes.
#[derive(Debug, Args)]
pub struct Common {
    /// Scenario file (TOML, SPEC.md section 5).
    #[arg(long, value_name = "FILE")]
    pub scenario: PathBuf,
    /// Print one JSON object on stdout and nothing else.
    #[arg(long)]
    pub json: bool,
}

/// Why a run of the command line ended without success.
#[derive(Debug)]
pub enum CliError {
    /// The arguments are wrong (or help/version was asked for): clap prints it.
    Usage(clap::Error),
    /// The command failed: one line for the user.
    Failed(anyhow::Error),
}

/// Parses `args` (program name first) and runs the command.
pub fn run<I, T>(args: I) -> Result<(), CliError>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = Cli::try_parse_from(args).map_err(CliError::Usage)?;
    match cli.command {
        Command::Validate(common) => commands::validate::run(&common),
        Command::Lift(args) => commands::lift::run(&args),
        Command::Estimate(args) => commands::estimate::run(&args),
        Command::Formation(args) => commands::formation::run(&args),
        Command::Fly(args) => commands::fly::run(&args),
        Command::Mission(args) => commands::mission::run(&args),
        Command::Hil(args) => commands::hil::run(&args),
    }
    .map_err(CliError::Failed)
}

/// Parses `N` comma-separated numbers, as in `--com 0.3,0.01`.
pub fn parse_list<const N: usize>(text: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(format!(
            "expected {N} comma-separated numbers, got `{text}`"
        ));
    }
    let mut out = [0.0; N];
    for (slot, part) in out.iter_mut().zip(parts) {
        let v: f64 = part
            .parse()
            .map_err(|_| format!("`{part}` is not a number"))?;
        if !v.is_finite() {
            return Err(format!("`{part}` is not a finite number"));
        }
        *slot = v;
    }
    Ok(out)
}

/// Clap value parser for two numbers.
pub fn pair(text: &str) -> Result<[f64; 2], String> {
    parse_list::<2>(text)
}

/// Clap value parser for three numbers.
pub fn triple(text: &str) -> Result<[f64; 3], String> {
    parse_list::<3>(text)
}
