//! Tests of the estimation loop: noiseless lifts converge on the truth, the information falls
//! as the posterior concentrates, readings outside the grid or censored end the estimation as
//! they should, and bad input is an error, never a panic.

use super::*;
use crate::liftoff_thrust::lift_off_thrust;
use crate::paper::{checked, l_sim1, rect_sim1};

/// The model's reading for the scenario's truth (no noise).
fn true_reading(scenario: &Scenario, group: usize, scale: f32) -> Measurement {
    let truth = scenario.truth.expect("fixture truth");
    let g = lift_group(scenario, group).expect("group");
    let lambda = lift_off_thrust(
        &scenario.payload.hull,
        truth.com,
        truth.mass,
        &g.rotor_points,
        scenario.robots.mass,
    )
    .expect("truth inside hull")
        * scale;
    if lambda >= scenario.robots.max_thrust {
        Measurement::CouldNotLift
    } else {
        Measurement::Lifted { thrust: lambda }
    }
}

fn run_noiseless(scenario: &Scenario, options: EstimatorOptions, scale: f32) -> Estimate {
    let mut e = Estimator::new(scenario, options).expect("estimator");
    while e.status() == Status::Measuring {
        let choice = e.select_group().expect("a group");
        e.update(choice.group, true_reading(scenario, choice.group, scale))
            .expect("update");
    }
    e.estimate()
}

#[test]
fn noiseless_lifts_converge_on_the_truth_within_a_resolution() {
    for input in [rect_sim1(), l_sim1()] {
        let scenario = checked(input);
        let est = run_noiseless(&scenario, EstimatorOptions::default(), 1.0);
        let truth = scenario.truth.unwrap();
        let truth = [truth.com.x, truth.com.y, truth.mass];
        assert_eq!(est.status, Status::Converged, "{est:?}");
        for a in 0..3 {
            let err = (est.theta[a] - truth[a]).abs() / scenario.estimation.resolution[a];
            assert!(err <= 1.0, "axis {a}: {est:?} vs {truth:?}");
        }
        assert!(est.measurements <= 8, "{est:?}");
    }
}

#[test]
fn the_estimate_carries_its_spread_and_the_models_lift_for_the_last_pair() {
    let scenario = checked(rect_sim1());
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    let prior = e.estimate();
    assert_eq!(prior.model_lift, None, "no update yet");
    let mut last = None;
    let mut spread = prior.spread;
    while e.status() == Status::Measuring {
        let g = e.select_group().unwrap().group;
        let reading = true_reading(&scenario, g, 1.0);
        e.update(g, reading).unwrap();
        let est = e.estimate();
        // The spread narrows as lifts come in (never below a cell's own width).
        for a in 0..3 {
            let cell = scenario.estimation.resolution[a] / 12f32.sqrt();
            assert!(est.spread[a] >= cell * 0.999, "axis {a}: {est:?}");
        }
        spread = est.spread;
        last = Some((g, reading, est));
    }
    let (g, reading, est) = last.expect("at least one lift");
    let res = scenario.estimation.resolution;
    for (a, ((now, before), res)) in spread.iter().zip(prior.spread).zip(res).enumerate() {
        assert!(*now < before, "axis {a}: {prior:?} -> {est:?}");
        assert!(*now <= 1.5 * res, "{est:?}");
    }
    // The model at the estimate explains the noiseless reading of its pair within about
    // a resolution's change of prediction.
    let group = lift_group(&scenario, g).unwrap();
    let model = lift_off_thrust(
        &scenario.payload.hull,
        Vec2::new(est.theta[0], est.theta[1]),
        est.theta[2],
        &group.rotor_points,
        scenario.robots.mass,
    );
    assert_eq!(est.model_lift, model);
    if let (Measurement::Lifted { thrust }, Some(m)) = (reading, est.model_lift) {
        assert!((thrust - m).abs() < 0.5, "reading {thrust} N, model {m} N");
    }
}

#[test]
fn l_shape_groups_closer_than_min_spacing_are_unreachable() {
    // Candidates 1.5, 1.72, 1.94 are 0.22 m apart, and 3.3 -> 0.1 across the rail's start
    // is 0.24 m: closer than min_spacing 0.25.
    let e = Estimator::new(&checked(l_sim1()), EstimatorOptions::default()).unwrap();
    let reachable: heapless::Vec<bool, 16> =
        (0..e.group_count()).map(|g| e.is_reachable(g)).collect();
    let unreachable: heapless::Vec<usize, 16> =
        (0..reachable.len()).filter(|&g| !reachable[g]).collect();
    assert_eq!(unreachable.as_slice(), &[4, 5, 10]);
}

#[test]
fn information_falls_as_the_posterior_concentrates() {
    let scenario = checked(rect_sim1());
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    let first = e.select_group().unwrap();
    assert!(first.information > 0.5, "{first:?}");
    for _ in 0..12 {
        let g = e.select_group().unwrap().group;
        e.update(g, true_reading(&scenario, g, 1.0)).unwrap();
    }
    let later = e.select_group().unwrap();
    assert!(
        later.information < 0.5 * first.information,
        "{first:?} {later:?}"
    );
}

#[test]
fn a_thousand_updates_never_underflow() {
    let scenario = checked(rect_sim1());
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    for k in 0..1000 {
        // Deliberately inconsistent readings: the likelihood of every point keeps falling.
        // (The estimator itself stops taking them once no point explains them; the
        // posterior underneath must survive them all.)
        let thrust = if k % 2 == 0 { 2.0 } else { 13.0 };
        let g = e.groups[k % 12];
        let cell = CellModel {
            hull: &e.hull,
            centroid: g.centroid,
            size: g.size,
            robot_mass: e.robot_mass,
        };
        e.posterior.update(
            &e.grid,
            &cell,
            &e.likelihood,
            Measurement::Lifted { thrust },
        );
    }
    e.summarise();
    let ln = e.posterior().ln_values();
    assert!(ln.iter().all(|v| !v.is_nan()));
    assert!(ln.contains(&0.0), "renormalised to a max of 0");
    assert!(e.estimate().confidence.is_finite());
}

#[test]
fn a_reading_no_grid_point_explains_ends_the_estimation_outside_the_grid() {
    let mut scenario = checked(rect_sim1());
    scenario.estimation.noise_sigma = 0.2;
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    // 14 N per robot on a long side: many sigma above what any payload of the grid (at
    // most 4 kg) needs there (about 10 N at most).
    let status = e.update(6, Measurement::Lifted { thrust: 14.0 }).unwrap();
    assert!(
        matches!(
            status,
            Status::OutsideGrid(OutsideGrid::Unexplained { group: 6, .. })
        ),
        "{status:?}"
    );
    assert_eq!(
        e.update(4, Measurement::Lifted { thrust: 5.0 }),
        Err(EstimationError::Finished),
        "no more readings once outside"
    );
}

#[test]
fn a_payload_too_heavy_for_the_grid_is_outside_not_converged() {
    // rect-sim1's truth at 20 kg: beyond what the grid (2.5 to 4 kg) allows. Every lift the
    // MI picks reads "could not lift" where every grid point would have lifted.
    let mut scenario = checked(rect_sim1());
    if let Some(t) = scenario.truth.as_mut() {
        t.mass = 20.0;
    }
    // The mission's noise model (the lift detector's 0.5 N).
    scenario.estimation.noise_sigma = 0.5;
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    let mut status = Status::Measuring;
    while status == Status::Measuring {
        let g = e.select_group().unwrap().group;
        let reading = true_reading(&scenario, g, 1.0);
        assert_eq!(reading, Measurement::CouldNotLift);
        status = e.update(g, reading).unwrap();
    }
    // Either no grid point explains a reading, or the layer beyond the grid's top mass
    // holds far more than the whole grid: outside, either way, within a few lifts.
    assert!(
        matches!(
            status,
            Status::OutsideGrid(
                OutsideGrid::Unexplained { .. }
                    | OutsideGrid::BeyondEdge {
                        axis: 2,
                        above: true
                    }
            )
        ),
        "{status:?} at 20 kg"
    );
    assert!(e.estimate().measurements <= 4, "{:?}", e.estimate());
}

#[test]
fn censored_readings_alone_never_converge() {
    // A censored reading that the grid can explain (a heavy payload far from the pair)
    // bounds the payload but never locates it: no convergence on it alone, however
    // lenient the threshold.
    let mut scenario = checked(rect_sim1());
    scenario.estimation.threshold = 0.05;
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    // Pair 4 (candidates 1.88, 2.22) at a short end: heavy payloads whose COM lies
    // towards the other end cannot be tipped from there (up to 15 N on the grid).
    let status = e.update(4, Measurement::CouldNotLift).unwrap();
    assert_eq!(status, Status::Measuring, "{:?}", e.estimate());
    assert!(e.estimate().confidence > 0.05, "{:?}", e.estimate());
}

#[test]
fn a_posterior_against_the_top_mass_bounds_the_mass_beyond_the_grid() {
    // Truth 5 kg on a grid that ends at 4 kg: every pair lifts, and two lifts cannot tell
    // a 5 kg payload from a 4 kg one with its COM elsewhere, so the estimate sits on the
    // top edge. The 95 % mass bound (for the thrust-margin check) must then count the
    // layer just above the grid instead of stopping at the grid's top cell.
    let mut scenario = checked(rect_sim1());
    if let Some(t) = scenario.truth.as_mut() {
        t.mass = 5.0;
        t.com = Vec2::new(0.1, 0.0);
    }
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    let mut status = Status::Measuring;
    while status == Status::Measuring {
        let g = e.select_group().unwrap().group;
        status = e.update(g, true_reading(&scenario, g, 1.0)).unwrap();
    }
    let est = e.estimate();
    let top = scenario.estimation.grid_max[2];
    let res = scenario.estimation.resolution[2];
    assert!(
        est.mass_upper_95 > top + 0.5 * res + 1e-3,
        "{est:?}: the bound stops at the grid's top cell"
    );
}

#[test]
fn truths_on_the_grids_edge_still_converge() {
    // The paper's grids with the truth on an edge cell: noiseless lifts converge inside.
    for input in [rect_sim1(), l_sim1()] {
        let base = checked(input);
        let setup = base.estimation;
        for theta in [
            [setup.grid_max[0], 0.0, setup.grid_max[2]],
            [
                setup.grid_min[0] + 0.3,
                setup.grid_min[1],
                setup.grid_min[2],
            ],
        ] {
            let mut scenario = base.clone();
            let com = Vec2::new(theta[0], theta[1]);
            if !scenario.payload.hull.contains(com, 0.0) {
                continue;
            }
            scenario.truth = Some(crate::scenario::Truth {
                com,
                mass: theta[2],
            });
            let est = run_noiseless(&scenario, EstimatorOptions::default(), 1.0);
            assert_eq!(est.status, Status::Converged, "{theta:?}: {est:?}");
        }
    }
}

#[test]
fn could_not_lift_rules_out_the_light_payloads() {
    let scenario = checked(rect_sim1());
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    // Group 8 (candidates 3.44, 3.88) sits on the far long side near the middle.
    e.update(8, Measurement::CouldNotLift).unwrap();
    let grid = *e.grid();
    let mut marginal = [0.0f32; MAX_GRID_POINTS];
    e.posterior().theta_marginal(&grid, &mut marginal);
    let light: f32 = (0..grid.theta_len())
        .filter(|&t| grid.theta(t)[2] < 2.6)
        .map(|t| marginal[t])
        .sum();
    let heavy: f32 = (0..grid.theta_len())
        .filter(|&t| grid.theta(t)[2] > 3.9)
        .map(|t| marginal[t])
        .sum();
    assert!(heavy > light, "heavy {heavy} light {light}");
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let scenario = checked(rect_sim1());
    let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
    assert_eq!(
        e.update(99, Measurement::Lifted { thrust: 5.0 }),
        Err(EstimationError::UnknownGroup(99))
    );
    assert_eq!(
        e.update(0, Measurement::Lifted { thrust: f32::NAN }),
        Err(EstimationError::BadReading)
    );
    let too_fine = EstimatorOptions {
        thrust_scale: Some(ThrustScaleAxis {
            min: 0.5,
            max: 2.0,
            step: 0.01,
        }),
    };
    assert!(matches!(
        Estimator::new(&scenario, too_fine),
        Err(EstimationError::Grid(_))
    ));
}

/// Runs noiseless lifts of `scenario`'s truth until the estimation ends; its estimate.
fn lift_until_done(scenario: &Scenario) -> Estimate {
    let mut e = Estimator::new(scenario, EstimatorOptions::default()).expect("estimator");
    while e.status() == Status::Measuring {
        let choice = e.select_group().expect("a group");
        e.update(choice.group, true_reading(scenario, choice.group, 1.0))
            .expect("update");
    }
    e.estimate()
}

#[test]
fn out_of_lifts_a_tight_posterior_settles_and_a_loose_one_does_not_converge() {
    // A threshold no posterior reaches: the lifts run out every time. After eight exact lifts
    // the posterior is tight (each axis's spread within a cell): settled, the estimate within
    // a cell of the truth. After one lift it is not: not converged.
    let mut scenario = checked(rect_sim1());
    scenario.estimation.threshold = 1.0;
    scenario.estimation.max_measurements = 8;
    let settled = lift_until_done(&scenario);
    assert_eq!(settled.status, Status::Settled, "{settled:?}");
    let res = scenario.estimation.resolution;
    for (a, (spread, res)) in settled.spread.iter().zip(res).enumerate() {
        assert!(*spread <= res, "axis {a}: {settled:?}");
    }
    let truth = scenario.truth.unwrap();
    let truth = [truth.com.x, truth.com.y, truth.mass];
    for a in 0..3 {
        let err = (settled.theta[a] - truth[a]).abs() / scenario.estimation.resolution[a];
        assert!(err <= 1.0, "axis {a}: {settled:?} vs {truth:?}");
    }
    scenario.estimation.max_measurements = 1;
    let loose = lift_until_done(&scenario);
    assert_eq!(loose.status, Status::NotConverged, "{loose:?}");
    assert!((0..3).any(|a| loose.spread[a] > res[a]), "{loose:?}");
}
