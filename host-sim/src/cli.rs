//! The `host-sim` command line (SPEC.md section 5, "The simulator's command line").
//!
//! Every command takes `--scenario FILE` and `--json`; with `--json`, stdout is one JSON object
//! and nothing else. A value that starts with `-` is given as `--com=-0.2,0.1`.

use std::ffi::OsString;
use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};
use serde_json::json;

use crate::scenario_file::{self, LoadedScenario};

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
        Command::Validate(common) => validate(&common).map_err(CliError::Failed),
    }
}

fn validate(common: &Common) -> Result<()> {
    let loaded = scenario_file::load(&common.scenario)?;
    let report = validate_report(&loaded);
    if common.json {
        println!("{report}");
    } else {
        let s = &loaded.scenario;
        println!(
            "scenario {} ({}): valid",
            loaded.name,
            loaded.path.display()
        );
        println!(
            "  footprint {} vertices, hull {} vertices; rail {:.3} m; {} candidates",
            s.payload.footprint.len(),
            s.payload.hull.vertices().len(),
            s.payload.rail.perimeter(),
            s.payload.candidates.len()
        );
        println!(
            "  {} robots, lifting {} at a time; grid {} x {} x {} = {} points",
            s.robots.count(),
            s.robots.pair_size,
            s.estimation.axis_len(0),
            s.estimation.axis_len(1),
            s.estimation.axis_len(2),
            s.estimation.grid_points()
        );
    }
    Ok(())
}

fn validate_report(loaded: &LoadedScenario) -> serde_json::Value {
    let s = &loaded.scenario;
    let xy = |p: shared::geometry::Vec2| [p.x, p.y];
    let grid_shape = [0, 1, 2].map(|a| s.estimation.axis_len(a));
    json!({
        "name": loaded.name,
        "valid": true,
        "hull": s.payload.hull.vertices().iter().map(|&p| xy(p)).collect::<Vec<_>>(),
        "rail_length": s.payload.rail.perimeter(),
        "candidates": s.payload.candidates.iter()
            .map(|&c| json!({"arc_length": c, "point": xy(s.payload.rail.point_at(c))}))
            .collect::<Vec<_>>(),
        "robots": s.robots.count(),
        "pair_size": s.robots.pair_size,
        "grid_shape": grid_shape,
        "grid_points": s.estimation.grid_points(),
    })
}
