//! Estimation tests (docs/system.md#paper-cases: they reproduce the paper's):
//! 100 random truths per shape with a fixed seed, readings from the model plus unit-variance
//! noise; the mean and the standard deviation of the error, in resolutions, must stay below 1 on
//! every axis. Also the `lift` and `estimate` command lines.

use crate::common;
use common::{host_sim, scenario_path};

use host_sim::monte_carlo::{self, MonteCarloSetup, Summary};
use host_sim::scenario_file;
use shared::estimation::{EstimatorOptions, ThrustScaleAxis};

fn monte_carlo(name: &str, map_error: f32, scale: Option<ThrustScaleAxis>) -> Summary {
    let loaded = scenario_file::load(&scenario_path(name)).expect("paper scenario");
    let setup = MonteCarloSetup {
        trials: 100,
        seed: 2025,
        truth: None,
        map_error,
        options: EstimatorOptions {
            thrust_scale: scale,
        },
    };
    let trials = monte_carlo::run(&loaded.scenario, &setup, &|| {}).expect("trials run");
    assert_eq!(trials.len(), 100);
    monte_carlo::summarise(&trials, loaded.scenario.estimation.resolution)
}

#[test]
fn paper_reproduction_errors_stay_within_one_resolution() {
    for name in ["rect-sim1", "L-sim1"] {
        let s = monte_carlo(name, 1.0, None);
        eprintln!("{name}: {s:?}");
        for axis in 0..3 {
            let mean = s.mean_error_over_resolution[axis];
            let std = s.std_error_over_resolution[axis];
            assert!(mean.abs() < 1.0, "{name} axis {axis}: mean {mean}");
            assert!(std < 1.0, "{name} axis {axis}: std {std}");
        }
        assert!(s.converged_fraction >= 0.95, "{name}: {s:?}");
        // The paper's example converged by the 4th lift; allow some spread over truths.
        assert!(s.mean_measurements <= 6.0, "{name}: {s:?}");
        assert!(s.within_one_resolution >= 0.5, "{name}: {s:?}");
    }
}

#[test]
fn bias_term_reduces_the_mass_bias_of_an_over_reading_map() {
    let off = monte_carlo("L-sim1", 1.1, None);
    let on = monte_carlo("L-sim1", 1.1, Some(ThrustScaleAxis::DEFAULT));
    eprintln!("map error 1.1, bias term off: {off:?}\nbias term on: {on:?}");
    let (bias_off, bias_on) = (
        off.mean_error_over_resolution[2],
        on.mean_error_over_resolution[2],
    );
    assert!(
        bias_off > 0.3,
        "an over-reading map reads mass high: {bias_off}"
    );
    assert!(
        bias_on < 0.75 * bias_off,
        "the bias term must cut the mass bias: {bias_on} vs {bias_off}"
    );
}

#[test]
fn lift_reports_thrust_and_feasibility_with_negative_coordinates() {
    let path = scenario_path("rect-sim1");
    let path = path.to_str().unwrap();
    let out = host_sim(&[
        "lift",
        "--scenario",
        path,
        "--pair",
        "0",
        "--com=-0.2,0.01",
        "--mass",
        "3",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let thrust = v["thrust"].as_f64().unwrap();
    assert!(thrust > 0.1 * 9.80665 && thrust < 14.2, "{thrust}");
    assert_eq!(v["feasible"], true);

    // A heavy payload at the far end cannot be lifted by the near pair.
    let out = host_sim(&[
        "lift",
        "--scenario",
        path,
        "--pair",
        "5",
        "--com=-0.45,0",
        "--mass",
        "40",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(v["feasible"], false, "{v}");
    assert!(v["thrust"].as_f64().unwrap() > 14.2);

    for (args, names) in [
        (
            vec!["--pair", "12", "--com", "0,0", "--mass", "3"],
            "--pair 12",
        ),
        (vec!["--pair", "0", "--com", "2,0", "--mass", "3"], "--com"),
        (vec!["--pair", "0", "--com", "0,0", "--mass=-3"], "--mass"),
    ] {
        let mut all = vec!["lift", "--scenario", path];
        all.extend(args);
        let out = host_sim(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains(names), "must name {names}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
}

#[test]
fn estimate_json_has_the_spec_keys_and_is_reproducible() {
    let path = scenario_path("L-sim1");
    let args = [
        "estimate",
        "--scenario",
        path.to_str().unwrap(),
        "--trials",
        "8",
        "--seed",
        "7",
        "--json",
    ];
    let first = host_sim(&args);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&first.stdout).expect("one JSON object");
    for key in [
        "mean_error_over_resolution",
        "std_error_over_resolution",
        "within_one_resolution",
        "mean_measurements",
        "converged_fraction",
    ] {
        assert!(!v["summary"][key].is_null(), "summary.{key} missing");
    }
    let trials = v["trials"].as_array().expect("trials");
    assert_eq!(trials.len(), 8);
    for t in trials {
        for key in ["truth", "estimate", "measurements", "converged"] {
            assert!(!t[key].is_null(), "trial.{key} missing");
        }
    }
    let again = host_sim(&args);
    assert_eq!(first.stdout, again.stdout, "same seed, same result");

    let fixed = host_sim(&[
        "estimate",
        "--scenario",
        path.to_str().unwrap(),
        "--trials",
        "3",
        "--truth",
        "0.31,0.1,3.5",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&fixed.stdout).expect("one JSON object");
    for t in v["trials"].as_array().unwrap() {
        assert_eq!(t["truth"][2].as_f64().unwrap() as f32, 3.5);
    }
}
