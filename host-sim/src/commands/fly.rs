//! `host-sim fly --formation even|optimized [--mixer equal-split|allocation] [--com X,Y]
//! [--mass M]`: one closed-loop flight in the physics plant (docs/formats.md#fly), with the
//! time series as CSV and figures when `--output DIR` is given.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use clap::{Args, ValueEnum};
use serde_json::json;
use shared::control::allocation::MixerKind;
use shared::geometry::Vec2;

use crate::cli::{Common, Outcome, check_map_error, check_mass, pair, show};
use crate::harness::{self, FlightOutcome, FlightSetup, FormationChoice, mixer_name};
use crate::report::{self, print_json};
use crate::say;
use crate::scenario_file;

/// Farthest from its landing point a flight may end and count as delivered, m (as the
/// mission's `delivered`).
pub const DELIVERY_RADIUS_M: f32 = 0.25;

/// Formation on the command line.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum FormationArg {
    /// Robot j at j * perimeter / count (or the scenario's initial positions).
    Even,
    /// The formation that maximises det(B B^T), balanced about the believed COM.
    Optimized,
}

/// Mixer on the command line.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MixerArg {
    /// The paper's: collective split equally, torques through B^T (B B^T)^-1.
    EqualSplit,
    /// Pseudo-inverse of the full effectiveness matrix: each rotor its own trim.
    Allocation,
}

impl MixerArg {
    /// The mixer it names.
    pub fn kind(self) -> MixerKind {
        match self {
            Self::EqualSplit => MixerKind::EqualSplit,
            Self::Allocation => MixerKind::Allocation,
        }
    }
}

/// Arguments of `fly`.
#[derive(Debug, Args)]
pub struct FlyArgs {
    #[command(flatten)]
    common: Common,
    /// Formation to fly.
    #[arg(long, value_enum)]
    formation: FormationArg,
    /// Mixer.
    #[arg(long, value_enum, default_value = "equal-split")]
    mixer: MixerArg,
    /// COM the controller believes, X,Y (default: the truth).
    #[arg(long, value_name = "X,Y", value_parser = pair, allow_hyphen_values = true)]
    com: Option<[f64; 2]>,
    /// Payload mass the controller believes, kg (default: the truth; above 0, at most 1000).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    mass: Option<f64>,
    /// Seed of sensor noise and disturbance.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The rotors' command-to-thrust map over-reads by this factor (0.5 to 2).
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    map_error: f64,
    /// Write the time series (CSV) and figures (PNG) into this folder (file names from the
    /// scenario's name, made plain: nothing is written outside the folder).
    #[arg(long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Also fly the other formation and draw both heights in one figure (needs --output).
    #[arg(long, requires = "output")]
    compare: bool,
}

/// How a flight came out, for the exit code: dropped, delivered (landed within
/// [`DELIVERY_RADIUS_M`] of the landing point), or not.
pub fn outcome_of(flight: &FlightOutcome) -> Outcome {
    let delivered = flight.landed && flight.final_position_error_m < DELIVERY_RADIUS_M;
    Outcome::of_run(flight.dropped, false, delivered)
}

/// One flight's keys of the JSON report.
fn flight_json(setup: &FlightSetup, outcome: &FlightOutcome) -> serde_json::Value {
    json!({
        "formation": setup.formation.name(),
        "mixer": mixer_name(setup.mixer),
        "dropped": outcome.dropped,
        "delivered": outcome_of(outcome) == Outcome::Done,
        "max_tilt_deg": outcome.max_tilt_deg,
        "rms_tracking_error_m": outcome.rms_tracking_error_m,
        "final_position_error_m": outcome.final_position_error_m,
        "max_thrust_fraction": outcome.max_thrust_fraction,
        "landed": outcome.landed,
        "max_height_m": outcome.max_height_m,
        "positions": outcome.positions,
        "simulated_s": outcome.simulated_s,
    })
}

/// One flight in a line for people.
fn flight_line(setup: &FlightSetup, outcome: &FlightOutcome) -> String {
    format!(
        "{}, {} mixer: {}; max tilt {:.1} deg, rms tracking {:.3} m, final error {:.3} m, max thrust {:.0} %",
        setup.formation.label(),
        mixer_name(setup.mixer),
        match outcome_of(outcome) {
            Outcome::Dropped => "DROPPED",
            Outcome::Done => "delivered",
            _ if outcome.landed => "NOT delivered (landed away from the target)",
            _ => "NOT delivered (did not land)",
        },
        outcome.max_tilt_deg,
        outcome.rms_tracking_error_m,
        outcome.final_position_error_m,
        100.0 * outcome.max_thrust_fraction
    )
}

/// Runs the command.
pub fn run(args: &FlyArgs) -> Result<Outcome> {
    let given_mass = args.mass.map(|m| check_mass("--mass", m)).transpose()?;
    let map_error = check_map_error(args.map_error)?;
    let loaded = scenario_file::load(&args.common.scenario)?;
    let s = &loaded.scenario;
    let Some(truth) = s.truth else {
        bail!(
            "{}: [truth]: fly needs the scenario's truth",
            loaded.path.display()
        );
    };
    if s.flight.is_none() {
        bail!(
            "{}: [flight]: fly needs the scenario's flight target",
            loaded.path.display()
        );
    }
    let com = match args.com {
        Some([x, y]) => {
            let com = Vec2::new(x as f32, y as f32);
            if !s.payload.hull.contains(com, 0.0) {
                bail!(
                    "--com {},{}: lies outside the footprint's convex hull",
                    show(x),
                    show(y)
                );
            }
            com
        }
        None => truth.com,
    };
    let mass = given_mass.unwrap_or(truth.mass);
    let setup = FlightSetup {
        formation: match args.formation {
            FormationArg::Even => FormationChoice::Even,
            FormationArg::Optimized => FormationChoice::Optimized,
        },
        mixer: args.mixer.kind(),
        believed_com: com,
        believed_mass: mass,
        seed: args.seed,
        map_error,
        plant: loaded.plant,
    };
    let started = Instant::now();
    let outcome = harness::fly_formation(s, &setup)?;
    let wall_s = started.elapsed().as_secs_f64();
    let mut written = Vec::new();
    let mut other = None;
    if let Some(dir) = &args.output {
        written = report::write_flight(dir, &loaded.name, &setup, &outcome)?;
        if args.compare {
            let other_setup = FlightSetup {
                formation: setup.formation.other(),
                ..setup
            };
            let flight = harness::fly_formation(s, &other_setup)?;
            written.extend(report::write_flight(
                dir,
                &loaded.name,
                &other_setup,
                &flight,
            )?);
            let flights = [
                (setup.formation.label(), &outcome),
                (other_setup.formation.label(), &flight),
            ];
            match report::write_comparison(dir, &loaded.name, &flights) {
                Ok(path) => written.push(path),
                Err(e) => report::warn(&format!("figure skipped: {e:#}")),
            }
            other = Some((other_setup, flight));
        }
    }
    let realtime = f64::from(outcome.simulated_s) / wall_s.max(1e-9);
    if args.common.json {
        let mut report = flight_json(&setup, &outcome);
        report["scenario"] = json!(loaded.name);
        report["wall_s"] = json!(wall_s);
        report["realtime_factor"] = json!(realtime);
        report["files"] = json!(
            written
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
        );
        if let Some((other_setup, flight)) = &other {
            report["compared"] = flight_json(other_setup, flight);
        }
        print_json(report)?;
    } else {
        say!("{}:", loaded.name)?;
        say!("  {}", flight_line(&setup, &outcome))?;
        if let Some((other_setup, flight)) = &other {
            say!("  {}", flight_line(other_setup, flight))?;
        }
        say!(
            "  {:.1} s simulated in {:.2} s ({:.0}x real time)",
            outcome.simulated_s,
            wall_s,
            realtime
        )?;
        for p in &written {
            say!("  wrote {}", p.display())?;
        }
    }
    Ok(outcome_of(&outcome))
}
