//! `host-sim estimate --trials N --seed S [--truth X,Y,M]`: Monte Carlo of the estimation
//! (SPEC.md section 5), with the optional thrust-scale bias term and a simulated map error.

use anyhow::{Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use shared::estimation::{EstimatorOptions, ThrustScaleAxis};

use crate::cli::{Common, triple};
use crate::monte_carlo::{self, MonteCarloSetup, Summary, Trial};
use crate::scenario_file;

/// Arguments of `estimate`.
#[derive(Debug, Args)]
pub struct EstimateArgs {
    #[command(flatten)]
    common: Common,
    /// Number of trials.
    #[arg(long, default_value_t = 100)]
    trials: usize,
    /// Seed of the run (each trial draws its own stream from it).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Use this truth X,Y,M for every trial instead of random ones.
    #[arg(long, value_name = "X,Y,M", value_parser = triple, allow_hyphen_values = true)]
    truth: Option<[f64; 3]>,
    /// Simulate a command-to-thrust map that over-reads by this factor (1.1: 10 % high).
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    map_error: f64,
    /// Estimate the unknown thrust scale alongside theta (axis 0.9..1.2 step 0.05).
    #[arg(long)]
    bias_term: bool,
    /// Estimate the thrust scale on this axis MIN,MAX,STEP (implies --bias-term).
    #[arg(long, value_name = "MIN,MAX,STEP", value_parser = triple)]
    thrust_scale: Option<[f64; 3]>,
}

/// Runs the command.
pub fn run(args: &EstimateArgs) -> Result<()> {
    let loaded = scenario_file::load(&args.common.scenario)?;
    let scenario = &loaded.scenario;
    if args.trials == 0 {
        bail!("--trials: must be at least 1");
    }
    if !(args.map_error.is_finite() && args.map_error > 0.0) {
        bail!("--map-error {}: must be a positive factor", args.map_error);
    }
    let truth = args.truth.map(|t| t.map(|v| v as f32));
    if let Some(t) = truth {
        let com = shared::geometry::Vec2::new(t[0], t[1]);
        if !scenario.payload.hull.contains(com, 0.0) {
            bail!(
                "--truth: COM {},{} lies outside the footprint's convex hull",
                t[0],
                t[1]
            );
        }
        if t[2] <= 0.0 {
            bail!("--truth: mass {} must be positive", t[2]);
        }
    }
    let thrust_scale = match (args.thrust_scale, args.bias_term) {
        (Some([min, max, step]), _) => Some(ThrustScaleAxis {
            min: min as f32,
            max: max as f32,
            step: step as f32,
        }),
        (None, true) => Some(ThrustScaleAxis::DEFAULT),
        (None, false) => None,
    };
    let setup = MonteCarloSetup {
        trials: args.trials,
        seed: args.seed,
        truth,
        map_error: args.map_error as f32,
        options: EstimatorOptions { thrust_scale },
    };
    // Check the set-up once before spreading it over threads.
    shared::estimation::Estimator::new(scenario, setup.options)
        .map_err(|e| anyhow::anyhow!("{}: {e}", loaded.path.display()))?;

    let bar = if args.common.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(args.trials as u64).with_style(
            ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} trials, {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        )
    };
    bar.set_message(format!("estimating {}", loaded.name));
    let trials = monte_carlo::run(scenario, &setup, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let summary = monte_carlo::summarise(&trials, scenario.estimation.resolution);
    if args.common.json {
        println!("{}", report(&loaded.name, &setup, &summary, &trials));
    } else {
        print_human(&loaded.name, &setup, &summary);
    }
    Ok(())
}

fn report(name: &str, setup: &MonteCarloSetup, s: &Summary, trials: &[Trial]) -> serde_json::Value {
    json!({
        "scenario": name,
        "seed": setup.seed,
        "map_error": setup.map_error,
        "bias_term": setup.options.thrust_scale.is_some(),
        "summary": {
            "mean_error_over_resolution": s.mean_error_over_resolution,
            "std_error_over_resolution": s.std_error_over_resolution,
            "mean_abs_error_over_resolution": s.mean_abs_error_over_resolution,
            "within_one_resolution": s.within_one_resolution,
            "mean_measurements": s.mean_measurements,
            "converged_fraction": s.converged_fraction,
        },
        "trials": trials.iter().map(|t| json!({
            "truth": t.truth,
            "estimate": t.estimate,
            "measurements": t.measurements,
            "converged": t.converged,
            "thrust_scale": t.thrust_scale,
        })).collect::<Vec<_>>(),
    })
}

fn print_human(name: &str, setup: &MonteCarloSetup, s: &Summary) {
    println!(
        "{name}: {} trials, seed {}, map error x{}, bias term {}",
        setup.trials,
        setup.seed,
        setup.map_error,
        if setup.options.thrust_scale.is_some() {
            "on"
        } else {
            "off"
        }
    );
    println!("  error / resolution      COM x    COM y     mass");
    let row = |label: &str, v: [f64; 3]| {
        println!("  {label:<20} {:>8.3} {:>8.3} {:>8.3}", v[0], v[1], v[2]);
    };
    row("mean", s.mean_error_over_resolution);
    row("standard deviation", s.std_error_over_resolution);
    row("mean absolute", s.mean_abs_error_over_resolution);
    println!(
        "  within one resolution: {:.0} %; converged: {:.0} %; mean lifts: {:.2}",
        100.0 * s.within_one_resolution,
        100.0 * s.converged_fraction,
        s.mean_measurements
    );
}
