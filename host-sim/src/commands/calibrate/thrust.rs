//! `host-sim calibrate thrust --bench FILE.csv [--scenario FILE] [--json]`: the thrust map's
//! parameters from a motor bench sweep (docs/commands.md#calibrating-the-thrust-map; the file:
//! docs/formats.md#thrust-bench-files; the JSON: docs/formats.md#calibrate-thrust). The maths
//! is `crate::thrust_calibration`; this module reads the file and prints the result: the
//! sweep against the map, the measured full thrust, and the four `param set` lines to paste
//! into MAVProxy.

use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::Args;
use serde_json::{Map, Value, json};

use crate::bench_csv;
use crate::cli::Outcome;
use crate::report::print_json;
use crate::say;
use crate::scenario_file;
use crate::thrust_calibration::{PARAMS, Reading, ThrustCalibration, calibrate};

/// Arguments of `calibrate thrust`.
#[derive(Debug, Args)]
pub struct ThrustArgs {
    /// The bench sweep: CSV with a header row naming the columns `command` (ESC command, 0 to
    /// 1) and `thrust_n` (load cell, N); others are ignored.
    #[arg(long, value_name = "FILE.csv")]
    bench: PathBuf,
    /// The vehicle's scenario: its robots' maximum thrust (the controller's full thrust) is
    /// set beside the measured one.
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// Print one JSON object on stdout and nothing else.
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(args: &ThrustArgs) -> Result<Outcome> {
    let rows = bench_csv::read(&args.bench, ["command", "thrust_n"])?;
    let readings: Vec<Reading> = rows
        .iter()
        .map(|r| Reading {
            line: r.line,
            command: r.values[0],
            thrust_n: r.values[1],
        })
        .collect();
    let cal = calibrate(&readings).map_err(|e| anyhow!("{}: {e}", args.bench.display()))?;
    let max_thrust = args
        .scenario
        .as_deref()
        .map(|path| scenario_file::load(path).map(|l| l.scenario.robots.max_thrust))
        .transpose()?;
    if args.json {
        print_json(report(args, &cal, max_thrust))?;
    } else {
        tell(args, &cal, max_thrust)?;
    }
    Ok(Outcome::Done)
}

/// The result for people: the sweep against the map, full thrust, the parameters to set.
fn tell(args: &ThrustArgs, cal: &ThrustCalibration, max_thrust: Option<f32>) -> Result<()> {
    say!(
        "{}: {} readings at {} commands; tare {:.3} N{}",
        args.bench.display(),
        cal.readings,
        cal.points.len(),
        cal.tare_n,
        if cal.points.first().is_some_and(|p| p.command == 0.0) {
            " (the mean at command 0, taken off every reading)"
        } else {
            " (no readings at command 0: taken as tared)"
        }
    )?;
    say!("")?;
    say!("command  readings  measured N  fitted N   error")?;
    for p in &cal.points {
        say!(
            "{:>7}  {:>8}  {:>10.3}  {:>8.3}  {:>+6.2} %",
            command_text(p.command),
            p.lines.len(),
            p.measured_n,
            p.fitted_n,
            (p.fitted_n - p.measured_n) / cal.full_thrust_n * 100.0
        )?;
    }
    say!("")?;
    let reach = if cal.top_command < 1.0 {
        format!(
            "extrapolated from the readings up to command {}",
            cal.top_command
        )
    } else {
        "the sweep reached it".to_string()
    };
    say!(
        "full thrust {:.3} N (the map's thrust at command 1; {reach})",
        cal.full_thrust_n
    )?;
    say!(
        "largest error of the map: {:.2} % of full thrust, at command {}",
        cal.max_error_fraction * 100.0,
        cal.max_error_command
    )?;
    match max_thrust {
        Some(max) => {
            let off = (cal.full_thrust_n / f64::from(max) - 1.0) * 100.0;
            say!(
                "the scenario's robots.max_thrust is {max} N, the measured full thrust {:.2} % {} \
                 (the controller's full thrust is robots.max_thrust: set it to the measured \
                 value if they differ by more than the bench's accuracy)",
                off.abs(),
                if off < 0.0 { "less" } else { "more" }
            )?;
        }
        None => say!(
            "check it against the scenario's robots.max_thrust, the controller's full thrust \
             (--scenario FILE sets them side by side)"
        )?,
    }
    say!("")?;
    say!("MAVProxy:")?;
    for (name, value) in PARAMS.iter().zip(cal.params) {
        say!("param set {name} {value:.4}")?;
    }
    Ok(())
}

/// A command for the table: two decimals, more when it has them (up to six).
fn command_text(command: f64) -> String {
    (2..=6)
        .map(|places| format!("{command:.places$}"))
        .find(|text| text.parse() == Ok(command))
        .unwrap_or_else(|| format!("{command:.6}"))
}

/// The JSON report (docs/formats.md#calibrate-thrust).
fn report(args: &ThrustArgs, cal: &ThrustCalibration, max_thrust: Option<f32>) -> Value {
    let params: Map<String, Value> = PARAMS
        .iter()
        .zip(cal.params)
        .map(|(name, value)| (name.to_string(), json!(value)))
        .collect();
    json!({
        "bench": args.bench.display().to_string(),
        "readings": cal.readings,
        "tare_n": cal.tare_n,
        "full_thrust_n": cal.full_thrust_n,
        "top_command": cal.top_command,
        "extrapolated": cal.top_command < 1.0,
        "params": params,
        "max_error_fraction": cal.max_error_fraction,
        "max_error_command": cal.max_error_command,
        "points": cal.points.iter().map(|p| json!({
            "command": p.command,
            "readings": p.lines.len(),
            "lines": p.lines,
            "measured_n": p.measured_n,
            "fitted_n": p.fitted_n,
        })).collect::<Vec<_>>(),
        "scenario_max_thrust_n": max_thrust,
    })
}
