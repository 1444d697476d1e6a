//! The `host-sim` command line (docs/formats.md#command-line).
//!
//! Every command takes `--scenario FILE` and `--json`; with `--json`, stdout is one JSON object
//! and nothing else. Negative numbers work as `--mass -3`, `--com -0.2,0.1` and
//! `--com=-0.2,0.1`. Flag values are checked before anything runs; an error names the flag.
//!
//! How a run ends is its exit code ([`Outcome::exit_code`], docs/commands.md#exit-codes): 0 done,
//! 1 bad input, 2 usage (clap's), 3 mission aborted, 4 not delivered, 5 payload dropped.

use std::ffi::OsString;
use std::path::PathBuf;

use anyhow::{Result, bail};
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
    Validate(commands::validate::ValidateArgs),
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
    Hil(Box<commands::hil::HilArgs>),
    /// The vehicle's parameters (MAVLink parameter protocol): name, unit, range, default.
    Params(commands::params::ParamsArgs),
    /// The one-page mission summary drawn from a flight log (ULog), saying what it lacks.
    Plot(commands::plot::PlotArgs),
    /// Bench measurements made into the vehicle's parameters (`calibrate thrust`: the thrust
    /// map from a motor sweep).
    Calibrate(commands::calibrate::CalibrateArgs),
    /// Many missions on the paper's cases, each plant drawn from a dispersion of the
    /// `[plant]` departures; `campaign merge` joins shards.
    Campaign(commands::campaign::CampaignArgs),
}

/// Options every command takes.
#[derive(Debug, Args)]
pub struct Common {
    /// Scenario file (TOML, see docs/formats.md; at most 1 MiB).
    #[arg(long, value_name = "FILE")]
    pub scenario: PathBuf,
    /// Print one JSON object on stdout and nothing else.
    #[arg(long)]
    pub json: bool,
}

/// Exit code of a bad input: a scenario or flag value that breaks a rule, a bench file a
/// calibration cannot use, a file that cannot be read.
pub const EXIT_BAD_INPUT: u8 = 1;
/// Exit code of a command line clap cannot parse (clap's own).
pub const EXIT_USAGE: u8 = 2;
/// Exit code of a mission that aborted (it stopped itself with a reason).
pub const EXIT_ABORTED: u8 = 3;
/// Exit code of a mission or flight that ended without delivering the payload at the target
/// (time limit, or landed elsewhere), without aborting or dropping it.
pub const EXIT_NOT_DELIVERED: u8 = 4;
/// Exit code of a mission or flight that dropped the payload (roll or pitch beyond 45 deg).
pub const EXIT_DROPPED: u8 = 5;

/// How a command that ran to its end came out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// It did what was asked (for `mission` and `fly`: delivered).
    Done,
    /// The mission aborted.
    Aborted,
    /// The mission or flight ended without delivering.
    NotDelivered,
    /// The payload was dropped.
    Dropped,
}

impl Outcome {
    /// How a mission or flight ended: a drop outranks an abort, an abort outranks not
    /// delivering.
    pub fn of_run(dropped: bool, aborted: bool, delivered: bool) -> Self {
        if dropped {
            Self::Dropped
        } else if aborted {
            Self::Aborted
        } else if delivered {
            Self::Done
        } else {
            Self::NotDelivered
        }
    }

    /// The process exit code.
    pub fn exit_code(self) -> u8 {
        match self {
            Self::Done => 0,
            Self::Aborted => EXIT_ABORTED,
            Self::NotDelivered => EXIT_NOT_DELIVERED,
            Self::Dropped => EXIT_DROPPED,
        }
    }
}

/// Why a run of the command line ended without an outcome.
#[derive(Debug)]
pub enum CliError {
    /// The arguments are wrong (or help/version was asked for): clap prints it.
    Usage(clap::Error),
    /// The command failed: one line for the user.
    Failed(anyhow::Error),
}

/// Parses `args` (program name first) and runs the command.
pub fn run<I, T>(args: I) -> Result<Outcome, CliError>
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = Cli::try_parse_from(args).map_err(CliError::Usage)?;
    match cli.command {
        Command::Validate(args) => commands::validate::run(&args),
        Command::Lift(args) => commands::lift::run(&args),
        Command::Estimate(args) => commands::estimate::run(&args),
        Command::Formation(args) => commands::formation::run(&args),
        Command::Fly(args) => commands::fly::run(&args),
        Command::Mission(args) => commands::mission::run(&args),
        Command::Hil(args) => commands::hil::run(&args),
        Command::Params(args) => commands::params::run(&args),
        Command::Plot(args) => commands::plot::run(&args),
        Command::Calibrate(args) => commands::calibrate::run(&args),
        Command::Campaign(args) => commands::campaign::run(&args),
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

/// A number for a message: plain when ordinary, exponent form when huge or tiny.
pub fn show(v: f64) -> String {
    let magnitude = v.abs();
    if v.is_finite() && (magnitude >= 1e6 || (magnitude < 1e-4 && v != 0.0)) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Checks that flag `flag`'s value `v` is finite and lies in `low..=high` (above `low` when
/// `low_open`); `unit` follows the numbers in the message (empty for a plain factor). The
/// error names the flag, the value and the range. Returns the value as `f32`.
pub fn check_range(
    flag: &str,
    v: f64,
    (low, low_open): (f64, bool),
    high: f64,
    unit: &str,
) -> Result<f32> {
    let above = if low_open { v > low } else { v >= low };
    if !(v.is_finite() && above && v <= high) {
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        let range = if low_open {
            format!("above {} and at most {}{unit}", show(low), show(high))
        } else {
            format!("from {} to {}{unit}", show(low), show(high))
        };
        bail!("{flag} {}: must be a finite number {range}", show(v));
    }
    Ok(v as f32)
}

/// Smallest and largest factor by which a simulated command-to-thrust map may be off
/// (`--map-error`, `--thrust-scale`): real ESC maps are off by tens of percent; a factor of
/// two is a wiring or calibration fault, not an error to simulate.
pub const THRUST_MAP_FACTOR: (f64, f64) = (0.5, 2.0);

/// Checks `--map-error`.
pub fn check_map_error(v: f64) -> Result<f32> {
    check_range(
        "--map-error",
        v,
        (THRUST_MAP_FACTOR.0, false),
        THRUST_MAP_FACTOR.1,
        "",
    )
}

/// Checks a payload mass flag (`--mass`, the mass of `--truth`): above zero, at most the
/// scenario bound `shared::scenario::MAX_PAYLOAD_MASS`.
pub fn check_mass(flag: &str, v: f64) -> Result<f32> {
    check_range(
        flag,
        v,
        (0.0, true),
        f64::from(shared::scenario::MAX_PAYLOAD_MASS),
        "kg",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_way_a_run_ends_has_its_own_exit_code() {
        let codes = [
            Outcome::of_run(false, false, true),
            Outcome::of_run(false, false, false),
            Outcome::of_run(false, true, false),
            Outcome::of_run(true, true, false),
            Outcome::of_run(true, false, false),
        ]
        .map(Outcome::exit_code);
        assert_eq!(
            codes,
            [
                0,
                EXIT_NOT_DELIVERED,
                EXIT_ABORTED,
                EXIT_DROPPED,
                EXIT_DROPPED
            ]
        );
        let mut all = [
            0,
            EXIT_BAD_INPUT,
            EXIT_USAGE,
            EXIT_ABORTED,
            EXIT_NOT_DELIVERED,
            EXIT_DROPPED,
        ];
        all.sort_unstable();
        assert!(all.windows(2).all(|w| w[0] != w[1]), "{all:?}");
    }

    #[test]
    fn flag_ranges_name_the_flag_and_the_range() {
        assert_eq!(check_mass("--mass", 3.5).unwrap(), 3.5);
        let err = check_mass("--mass", 1e40).unwrap_err().to_string();
        assert_eq!(
            err,
            "--mass 1e40: must be a finite number above 0 and at most 1000 kg"
        );
        let err = check_map_error(f64::NAN).unwrap_err().to_string();
        assert_eq!(
            err,
            "--map-error NaN: must be a finite number from 0.5 to 2"
        );
        assert!(check_map_error(0.5).is_ok() && check_map_error(2.0).is_ok());
    }
}
