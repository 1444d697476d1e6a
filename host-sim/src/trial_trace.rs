//! One trial of `estimate`'s Monte Carlo, step by step, for the figures of the estimation per
//! lift (the paper's Fig. 6): at the start and after each lift, the posterior's marginals over
//! (COM x, COM y) and over mass, and each lifting group's mutual information for the next lift.
//!
//! The trial is [`monte_carlo::run_trial_observed`]'s, so it is lift for lift the trial of the
//! same index in the Monte Carlo; everything is read through `shared`'s public estimator.

use anyhow::Result;
use shared::estimation::estimator::Estimate;
use shared::estimation::grid::Grid;
use shared::estimation::groups::lift_group;
use shared::estimation::{Estimator, Measurement};
use shared::geometry::Vec2;
use shared::liftoff_thrust::lift_off_thrust;
use shared::scenario::Scenario;

use crate::monte_carlo::{self, MonteCarloSetup};

/// The estimation at one step: the start, or just after a lift.
#[derive(Clone, Debug)]
pub struct EstimationStep {
    /// The lift that led here: its group and reading (`None`: the start).
    pub lift: Option<(usize, Measurement)>,
    /// The model's lift-off thrust of that lift's group for the truth, N per robot.
    pub model: Option<f32>,
    /// Posterior marginal over the COM, in the grid's COM order (`ix * ny + iy`).
    pub com_marginal: Vec<f32>,
    /// Posterior marginal over the mass, one value per mass point.
    pub mass_marginal: Vec<f32>,
    /// Each group's mutual information with theta for the next lift, nats (`None`: the robots
    /// cannot stand there); empty once the estimation is over.
    pub information: Vec<Option<f32>>,
    /// The group lifted next (`None`: the estimation is over).
    pub next: Option<usize>,
    /// The estimate at this step.
    pub estimate: Estimate,
}

/// A trial step by step.
#[derive(Clone, Debug)]
pub struct TrialTrace {
    /// The payload as it was: [COM x, COM y, mass].
    pub truth: [f32; 3],
    /// The estimator's grid.
    pub grid: Grid,
    /// The start, then one step per lift.
    pub steps: Vec<EstimationStep>,
}

/// Runs trial `index` of `setup` and records each step.
pub fn trace(scenario: &Scenario, setup: &MonteCarloSetup, index: usize) -> Result<TrialTrace> {
    let mut steps: Vec<EstimationStep> = Vec::new();
    let mut grid = None;
    let mut truth_seen = [0.0; 3];
    monte_carlo::run_trial_observed(scenario, setup, index, &mut |estimator, truth, lift| {
        truth_seen = truth;
        grid = Some(*estimator.grid());
        steps.push(step(scenario, estimator, truth, lift));
    })?;
    // Each step's next lift is the following step's lift.
    let lifts: Vec<Option<usize>> = steps.iter().map(|s| s.lift.map(|(g, _)| g)).collect();
    for (k, s) in steps.iter_mut().enumerate() {
        s.next = lifts.get(k + 1).copied().flatten();
        if s.next.is_none() {
            s.information.clear();
        }
    }
    let grid = grid.ok_or_else(|| anyhow::anyhow!("the trial recorded no step"))?;
    Ok(TrialTrace {
        truth: truth_seen,
        grid,
        steps,
    })
}

fn step(
    scenario: &Scenario,
    estimator: &mut Estimator,
    truth: [f32; 3],
    lift: Option<(usize, Measurement)>,
) -> EstimationStep {
    let grid = *estimator.grid();
    let [nx, ny, nm] = grid.shape();
    let mut theta = vec![0.0; grid.theta_len()];
    estimator.posterior().theta_marginal(&grid, &mut theta);
    let mut com_marginal = vec![0.0; nx * ny];
    let mut mass_marginal = vec![0.0; nm];
    for (t, p) in theta.iter().enumerate() {
        com_marginal[t / nm] += p;
        mass_marginal[t % nm] += p;
    }
    let mut information = vec![None; estimator.group_count()];
    estimator.information_per_group(&mut information);
    let model = lift.and_then(|(group, _)| {
        let g = lift_group(scenario, group)?;
        lift_off_thrust(
            &scenario.payload.hull,
            Vec2::new(truth[0], truth[1]),
            truth[2],
            &g.rotor_points,
            scenario.robots.mass,
        )
    });
    EstimationStep {
        lift,
        model,
        com_marginal,
        mass_marginal,
        information,
        next: None,
        estimate: estimator.estimate(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::estimation::EstimatorOptions;

    #[test]
    fn the_traced_trial_is_the_monte_carlo_trial_of_the_same_index() {
        let text = include_str!("../../tests/scenarios/rect-sim1.toml");
        let loaded = crate::scenario_file::parse(text, std::path::Path::new("rect-sim1.toml"))
            .expect("paper scenario");
        let setup = MonteCarloSetup {
            trials: 2,
            seed: 7,
            truth: None,
            map_error: 1.0,
            options: EstimatorOptions::default(),
        };
        for index in 0..2 {
            let trial = monte_carlo::run_trial(&loaded.scenario, &setup, index).expect("trial");
            let trace = trace(&loaded.scenario, &setup, index).expect("trace");
            assert_eq!(trace.truth, trial.truth);
            assert_eq!(trace.steps.len(), trial.measurements as usize + 1);
            let last = trace.steps.last().expect("a step");
            assert_eq!(last.estimate.theta, trial.estimate);
            assert!(last.next.is_none() && last.information.is_empty());
            // Every step but the last names the pair lifted next, which the next step read.
            for pair in trace.steps.windows(2) {
                assert_eq!(pair[0].next, pair[1].lift.map(|(g, _)| g));
                let marginal: f32 = pair[1].com_marginal.iter().sum();
                assert!((marginal - 1.0).abs() < 1e-3, "{marginal}");
            }
        }
    }
}
