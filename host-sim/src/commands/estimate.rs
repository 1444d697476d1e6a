//! `host-sim estimate --trials N --seed S [--truth X,Y,M] [--output DIR]`: Monte Carlo of the
//! estimation (docs/formats.md#estimate), with the optional thrust-scale bias term and a simulated map
//! error; with `--output`, the trials as CSV and the paper's Figs. 6 and 7
//! ([`crate::estimate_report`]).

use std::path::PathBuf;

use anyhow::{Result, anyhow, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use shared::estimation::grid::MAX_SCALE_POINTS;
use shared::estimation::{EstimationError, Estimator, EstimatorOptions, ThrustScaleAxis};
use shared::geometry::Vec2;

use crate::cli::{
    Common, Outcome, THRUST_MAP_FACTOR, check_map_error, check_mass, check_range, show, triple,
};
use crate::monte_carlo::{self, MAX_TRIALS, MonteCarloSetup, Summary, Trial};
use crate::report::print_json;
use crate::say;
use crate::{estimate_report, scenario_file, trial_trace};

/// Arguments of `estimate`.
#[derive(Debug, Args)]
pub struct EstimateArgs {
    #[command(flatten)]
    common: Common,
    /// Number of trials (1 to 10000).
    #[arg(long, default_value_t = 100)]
    trials: usize,
    /// Seed of the run (each trial draws its own stream from it).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Use this truth X,Y,M for every trial instead of random ones.
    #[arg(long, value_name = "X,Y,M", value_parser = triple, allow_hyphen_values = true)]
    truth: Option<[f64; 3]>,
    /// Simulate a command-to-thrust map that over-reads by this factor (1.1: 10 % high;
    /// 0.5 to 2).
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    map_error: f64,
    /// Estimate the unknown thrust scale alongside theta (axis 0.9..1.2 step 0.05).
    #[arg(long)]
    bias_term: bool,
    /// Estimate the thrust scale on this axis MIN,MAX,STEP (implies --bias-term; factors
    /// 0.5 to 2, at most 16 values).
    #[arg(long, value_name = "MIN,MAX,STEP", value_parser = triple)]
    thrust_scale: Option<[f64; 3]>,
    /// Write the trials (CSV), the first trial step by step (JSON) and figures (the error
    /// summary; the posterior and each pair's information at each lift of the first trial)
    /// into this folder.
    #[arg(long, value_name = "DIR")]
    output: Option<PathBuf>,
}

/// Checks `--trials` against [`MAX_TRIALS`].
fn check_trials(trials: usize) -> Result<()> {
    if trials == 0 {
        bail!("--trials 0: must be at least 1");
    }
    if trials > MAX_TRIALS {
        bail!(
            "--trials {trials}: at most {MAX_TRIALS}; the paper uses 100, {MAX_TRIALS} already pin the fraction within one resolution to about 1 % (95 % confidence), and every trial is kept and reported"
        );
    }
    Ok(())
}

/// Checks `--thrust-scale MIN,MAX,STEP`: factors within [`THRUST_MAP_FACTOR`], `MIN <= MAX`,
/// a step above zero, at most [`MAX_SCALE_POINTS`] values.
fn check_thrust_scale([min, max, step]: [f64; 3]) -> Result<ThrustScaleAxis> {
    let (low, high) = THRUST_MAP_FACTOR;
    let flag = "--thrust-scale";
    let min32 = check_range(flag, min, (low, false), high, "(MIN)")?;
    let max32 = check_range(flag, max, (low, false), high, "(MAX)")?;
    if max < min {
        bail!(
            "{flag} {},{},{}: MAX must not be below MIN",
            show(min),
            show(max),
            show(step)
        );
    }
    let step32 = check_range(flag, step, (0.0, true), high - low, "(STEP)")?;
    let values = ((max - min) / step + 1e-4).floor() + 1.0;
    if values > MAX_SCALE_POINTS as f64 {
        bail!(
            "{flag} {},{},{}: {values} values, at most {MAX_SCALE_POINTS}",
            show(min),
            show(max),
            show(step)
        );
    }
    Ok(ThrustScaleAxis {
        min: min32,
        max: max32,
        step: step32,
    })
}

/// Runs the command.
pub fn run(args: &EstimateArgs) -> Result<Outcome> {
    // Flags first: a bad flag is named before the scenario is read.
    check_trials(args.trials)?;
    let map_error = check_map_error(args.map_error)?;
    let thrust_scale = match (args.thrust_scale, args.bias_term) {
        (Some(axis), _) => Some(check_thrust_scale(axis)?),
        (None, true) => Some(ThrustScaleAxis::DEFAULT),
        (None, false) => None,
    };
    let truth_mass = match args.truth {
        Some(t) => Some(check_mass("--truth (its mass M)", t[2])?),
        None => None,
    };
    let loaded = scenario_file::load(&args.common.scenario)?;
    let scenario = &loaded.scenario;
    let truth = match (args.truth, truth_mass) {
        (Some([x, y, _]), Some(mass)) => {
            let com = Vec2::new(x as f32, y as f32);
            if !scenario.payload.hull.contains(com, 0.0) {
                bail!(
                    "--truth: COM {},{} lies outside the footprint's convex hull",
                    show(x),
                    show(y)
                );
            }
            Some([com.x, com.y, mass])
        }
        _ => None,
    };
    let setup = MonteCarloSetup {
        trials: args.trials,
        seed: args.seed,
        truth,
        map_error,
        options: EstimatorOptions { thrust_scale },
    };
    // Check the set-up once before spreading it over threads. The scenario passed its checks,
    // so a grid that cannot be built is the thrust-scale axis's doing.
    Estimator::new(scenario, setup.options).map_err(|e| match e {
        EstimationError::Grid(grid) if thrust_scale.is_some() => anyhow!(
            "{}: {grid} (with the thrust-scale axis of --bias-term/--thrust-scale)",
            if args.thrust_scale.is_some() {
                "--thrust-scale"
            } else {
                "--bias-term"
            }
        ),
        other => anyhow!("{}: {other}", loaded.path.display()),
    })?;

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
    let resolution = scenario.estimation.resolution;
    let summary = monte_carlo::summarise(&trials, resolution);
    let written = match &args.output {
        Some(dir) => {
            // The first trial again, step by step: the same trial, lift for lift.
            let trace = trial_trace::trace(scenario, &setup, 0)?;
            estimate_report::write(dir, &loaded.name, &summary, &trials, resolution, &trace)?
        }
        None => Vec::new(),
    };
    if args.common.json {
        let mut value = report(&loaded.name, &setup, &summary, &trials);
        if args.output.is_some() {
            value["files"] = json!(
                written
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
            );
        }
        print_json(value)?;
    } else {
        print_human(&loaded.name, &setup, &summary)?;
        for p in &written {
            say!("  wrote {}", p.display())?;
        }
    }
    Ok(Outcome::Done)
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

fn print_human(name: &str, setup: &MonteCarloSetup, s: &Summary) -> Result<()> {
    say!(
        "{name}: {} trials, seed {}, map error x{}, bias term {}",
        setup.trials,
        setup.seed,
        setup.map_error,
        if setup.options.thrust_scale.is_some() {
            "on"
        } else {
            "off"
        }
    )?;
    say!("  error / resolution      COM x    COM y     mass")?;
    let row =
        |label: &str, v: [f64; 3]| say!("  {label:<20} {:>8.3} {:>8.3} {:>8.3}", v[0], v[1], v[2]);
    row("mean", s.mean_error_over_resolution)?;
    row("standard deviation", s.std_error_over_resolution)?;
    row("mean absolute", s.mean_abs_error_over_resolution)?;
    say!(
        "  within one resolution: {:.0} %; converged: {:.0} %; mean lifts: {:.2}",
        100.0 * s.within_one_resolution,
        100.0 * s.converged_fraction,
        s.mean_measurements
    )
}
