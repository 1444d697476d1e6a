//! Monte Carlo of the estimation alone (docs/system.md#paper-cases;
//! `estimate`): random truths, readings from the lift-off model plus white noise (censored at
//! the robots' maximum thrust), and `shared`'s estimator choosing the lifts.
//!
//! The simulated reading is the only thing computed here, and it calls `shared`'s own model:
//! this is the harness, not a second implementation. Each trial has its own seeded random
//! stream, so results do not depend on how trials are spread over threads.

use anyhow::{Result, bail};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use shared::estimation::groups::lift_group;
use shared::estimation::{Estimator, EstimatorOptions, Measurement, Status};
use shared::geometry::Vec2;
use shared::liftoff_thrust::lift_off_thrust;
use shared::scenario::Scenario;

/// Most trials of one run. The paper runs 100; 10,000 pin a fraction such as
/// `within_one_resolution` to within about 1 % (95 % confidence: `2 sqrt(p (1 - p) / n)`
/// <= 0.01), and more add nothing. Every trial is kept and reported (`--json` lists them
/// all), so the 100,000,000 someone might type would run for hours and print gigabytes.
pub const MAX_TRIALS: usize = 10_000;

/// What to simulate.
#[derive(Clone, Copy, Debug)]
pub struct MonteCarloSetup {
    /// Number of trials.
    pub trials: usize,
    /// Seed of the whole run.
    pub seed: u64,
    /// The truth of every trial; `None` draws one per trial.
    pub truth: Option<[f32; 3]>,
    /// Factor by which the command-to-thrust map over-reads (1: exact map).
    pub map_error: f32,
    /// Estimator options (the bias term).
    pub options: EstimatorOptions,
}

/// One trial's outcome.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trial {
    /// The payload as it was: [COM x, COM y, mass].
    pub truth: [f32; 3],
    /// The estimate.
    pub estimate: [f32; 3],
    /// Lifts taken.
    pub measurements: u32,
    /// Whether the stopping rule was met.
    pub converged: bool,
    /// Posterior mean of the thrust-scale factor.
    pub thrust_scale: f32,
}

/// Statistics over trials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// Mean of (estimate - truth) / resolution per axis.
    pub mean_error_over_resolution: [f64; 3],
    /// Standard deviation of (estimate - truth) / resolution per axis.
    pub std_error_over_resolution: [f64; 3],
    /// Mean of |estimate - truth| / resolution per axis.
    pub mean_abs_error_over_resolution: [f64; 3],
    /// Fraction of trials with every axis error at most one resolution.
    pub within_one_resolution: f64,
    /// Mean number of lifts.
    pub mean_measurements: f64,
    /// Fraction of trials that met the stopping rule.
    pub converged_fraction: f64,
}

fn trial_rng(seed: u64, trial: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(trial as u64);
    rng
}

/// Draws a truth uniformly in the grid's box with its COM inside the footprint's hull.
pub fn draw_truth(scenario: &Scenario, rng: &mut ChaCha8Rng) -> Result<[f32; 3]> {
    let e = &scenario.estimation;
    for _ in 0..100_000 {
        let theta: [f32; 3] = [0, 1, 2].map(|a| {
            if e.grid_max[a] > e.grid_min[a] {
                rng.random_range(e.grid_min[a]..=e.grid_max[a])
            } else {
                e.grid_min[a]
            }
        });
        if scenario
            .payload
            .hull
            .contains(Vec2::new(theta[0], theta[1]), 0.0)
        {
            return Ok(theta);
        }
    }
    bail!("estimation.grid_min/grid_max: no COM in the grid's box lies inside the footprint's hull")
}

/// The reading of lifting group `group` on the payload `truth`: the model's lift-off thrust,
/// as the over-reading map reports it, plus noise; censored at the robots' maximum thrust.
pub fn simulated_reading(
    scenario: &Scenario,
    group: usize,
    truth: [f32; 3],
    map_error: f32,
    rng: &mut ChaCha8Rng,
) -> Result<Measurement> {
    let Some(g) = lift_group(scenario, group) else {
        bail!("lifting group {group} does not exist");
    };
    let Some(lambda) = lift_off_thrust(
        &scenario.payload.hull,
        Vec2::new(truth[0], truth[1]),
        truth[2],
        &g.rotor_points,
        scenario.robots.mass,
    ) else {
        bail!("the truth's COM lies outside the footprint's hull");
    };
    let noise = Normal::new(0.0f32, scenario.estimation.noise_sigma)?;
    let reading = map_error * lambda + noise.sample(rng);
    Ok(if reading >= scenario.robots.max_thrust {
        Measurement::CouldNotLift
    } else {
        Measurement::Lifted {
            thrust: reading.max(0.0),
        }
    })
}

/// Runs one trial: lifts chosen by the estimator until it stops.
pub fn run_trial(scenario: &Scenario, setup: &MonteCarloSetup, index: usize) -> Result<Trial> {
    run_trial_observed(scenario, setup, index, &mut |_, _, _| {})
}

/// What a trial's observer is shown at each step: the estimator (before its next choice), the
/// truth, and the lift that led there (`None` at the start).
pub type Observer<'a> = dyn FnMut(&mut Estimator, [f32; 3], Option<(usize, Measurement)>) + 'a;

/// [`run_trial`], showing `observe` the estimator before the first lift and after each lift
/// (the same trial, lift for lift: the observer draws no random number).
pub fn run_trial_observed(
    scenario: &Scenario,
    setup: &MonteCarloSetup,
    index: usize,
    observe: &mut Observer<'_>,
) -> Result<Trial> {
    let mut rng = trial_rng(setup.seed, index);
    let truth = match setup.truth {
        Some(t) => t,
        None => draw_truth(scenario, &mut rng)?,
    };
    let mut estimator = Estimator::new(scenario, setup.options)?;
    observe(&mut estimator, truth, None);
    while estimator.status() == Status::Measuring {
        let choice = estimator.select_group()?;
        let reading = simulated_reading(scenario, choice.group, truth, setup.map_error, &mut rng)?;
        estimator.update(choice.group, reading)?;
        observe(&mut estimator, truth, Some((choice.group, reading)));
    }
    let est = estimator.estimate();
    Ok(Trial {
        truth,
        estimate: est.theta,
        measurements: est.measurements,
        converged: est.status == Status::Converged,
        thrust_scale: est.thrust_scale,
    })
}

/// Runs every trial in parallel (at most [`MAX_TRIALS`]); `progress` is called once per
/// finished trial.
pub fn run(
    scenario: &Scenario,
    setup: &MonteCarloSetup,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<Trial>> {
    if setup.trials > MAX_TRIALS {
        bail!("--trials {}: at most {MAX_TRIALS}", setup.trials);
    }
    (0..setup.trials)
        .into_par_iter()
        .map(|i| {
            let trial = run_trial(scenario, setup, i);
            progress();
            trial
        })
        .collect()
}

/// Statistics of `trials` with errors in units of `resolution`.
pub fn summarise(trials: &[Trial], resolution: [f32; 3]) -> Summary {
    let n = trials.len().max(1) as f64;
    let err =
        |t: &Trial, a: usize| f64::from(t.estimate[a] - t.truth[a]) / f64::from(resolution[a]);
    let mean = [0, 1, 2].map(|a| trials.iter().map(|t| err(t, a)).sum::<f64>() / n);
    let std = [0, 1, 2].map(|a| {
        (trials
            .iter()
            .map(|t| (err(t, a) - mean[a]).powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
    });
    let mean_abs = [0, 1, 2].map(|a| trials.iter().map(|t| err(t, a).abs()).sum::<f64>() / n);
    let within = trials
        .iter()
        .filter(|t| (0..3).all(|a| err(t, a).abs() <= 1.0))
        .count() as f64;
    Summary {
        mean_error_over_resolution: mean,
        std_error_over_resolution: std,
        mean_abs_error_over_resolution: mean_abs,
        within_one_resolution: within / n,
        mean_measurements: trials
            .iter()
            .map(|t| f64::from(t.measurements))
            .sum::<f64>()
            / n,
        converged_fraction: trials.iter().filter(|t| t.converged).count() as f64 / n,
    }
}
