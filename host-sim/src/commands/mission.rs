//! `host-sim mission`: the whole autonomous pipeline in the physics plant (SPEC.md section 5):
//! estimation by real lift-off detection, formation decision, rearrangement, flight. Without
//! `--scenario` it runs the paper's experiment case rect-ex1 (built into the binary), printing
//! each phase as it happens. This is the project's main job.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use serde_json::json;
use shared::estimation::{EstimatorOptions, ThrustScaleAxis};
use shared::mission::MissionConfig;

use crate::commands::fly::MixerArg;
use crate::mission_run::{self, MissionSetup};
use crate::scenario_file;

/// The paper's experiment case, built in.
const RECT_EX1: &str = include_str!("../../../tests/scenarios/rect-ex1.toml");

/// Arguments of `mission`.
#[derive(Debug, Args)]
pub struct MissionArgs {
    /// Scenario file (default: the paper's experiment case rect-ex1, built in).
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// Print one JSON object on stdout and nothing else.
    #[arg(long)]
    json: bool,
    /// Seed of sensor noise and disturbance.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The rotors' command-to-thrust map over-reads by this factor.
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    map_error: f64,
    /// Estimate the thrust-scale factor alongside theta (axis 0.9..1.2 step 0.05).
    #[arg(long)]
    bias_term: bool,
    /// Standard deviation of the lift detector's readings, N: the estimator's noise model for
    /// the lifts (default 0.5, the detector's characterised bound).
    #[arg(long, value_name = "N", conflicts_with = "scenario_sigma")]
    lift_sigma: Option<f64>,
    /// Use the scenario's noise_sigma (the paper's simulated noise) as the lifts' noise model.
    #[arg(long)]
    scenario_sigma: bool,
    /// Failure injection: motion capture stops this many seconds after take-off.
    #[arg(long, value_name = "S")]
    mocap_lost_after: Option<f64>,
    /// Mixer for the flight.
    #[arg(long, value_enum, default_value = "equal-split")]
    mixer: MixerArg,
}

/// Runs the command.
pub fn run(args: &MissionArgs) -> Result<()> {
    let loaded = match &args.scenario {
        Some(path) => scenario_file::load(path)?,
        None => scenario_file::parse(RECT_EX1, std::path::Path::new("rect-ex1 (built in)"))?,
    };
    if !(args.map_error.is_finite() && args.map_error > 0.0) {
        anyhow::bail!("--map-error {}: must be a positive factor", args.map_error);
    }
    let config = MissionConfig {
        estimator: EstimatorOptions {
            thrust_scale: args.bias_term.then_some(ThrustScaleAxis::DEFAULT),
        },
        mixer: args.mixer.kind(),
        lift_noise_sigma: if args.scenario_sigma {
            None
        } else {
            Some(
                args.lift_sigma
                    .map_or(shared::mission::DETECTOR_SIGMA, |s| s as f32),
            )
        },
        ..MissionConfig::default()
    };
    let setup = MissionSetup {
        seed: args.seed,
        map_error: args.map_error as f32,
        config,
        mocap_lost_after_takeoff: args.mocap_lost_after.map(|s| s as f32),
        ..MissionSetup::default()
    };
    let json = args.json;
    if !json {
        println!("mission on {}", loaded.name);
    }
    let started = Instant::now();
    let (outcome, _) = mission_run::run(&loaded.scenario, &setup, &mut |t, name, reason| {
        if !json {
            println!("  {t:7.2} s  {name:<17} {reason}");
        }
    })?;
    let wall_s = started.elapsed().as_secs_f64();
    if json {
        let v = json!({
            "scenario": loaded.name,
            "estimate": outcome.estimate,
            "measurements": outcome.measurements,
            "positions": outcome.positions,
            "delivered": outcome.delivered,
            "dropped": outcome.dropped,
            "final_position_error_m": outcome.final_position_error_m,
            "phases": outcome.phases.iter().map(|(name, d)| json!({"name": name, "duration_s": d})).collect::<Vec<_>>(),
            "lifts": outcome.lifts.iter().map(|(g, r, m)| json!({"pair": g, "reading": r, "model": m})).collect::<Vec<_>>(),
            "aborted": outcome.aborted.map(|r| r.to_string()),
            "simulated_s": outcome.simulated_s,
            "wall_s": wall_s,
        });
        println!("{v}");
    } else {
        for (g, r, m) in &outcome.lifts {
            match r {
                Some(r) => println!("lift with pair {g}: read {r:.3} N, the model says {m:.3} N"),
                None => println!("lift with pair {g}: could not lift, the model says {m:.3} N"),
            }
        }
        match outcome.estimate {
            Some(e) => println!(
                "estimate: COM ({:.3}, {:.3}) m, mass {:.2} kg after {} lifts",
                e[0], e[1], e[2], outcome.measurements
            ),
            None => println!("no estimate ({} lifts)", outcome.measurements),
        }
        println!(
            "{}: final position error {:.3} m; {:.1} s simulated in {:.1} s",
            if outcome.delivered {
                "delivered"
            } else if outcome.dropped {
                "DROPPED"
            } else {
                "NOT delivered"
            },
            outcome.final_position_error_m,
            outcome.simulated_s,
            wall_s
        );
        if let Some(why) = &outcome.aborted {
            println!("aborted: {why}");
        }
    }
    Ok(())
}
