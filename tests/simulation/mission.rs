//! The autonomous mission end to end in the physics plant (docs/system.md#pipeline;
//! `mission`): estimation by real lift-off detection, formation decision, rearrangement,
//! flight, delivery; and the refusals that keep a real vehicle on the ground.

use crate::common;
use common::{load, scenario_path};

use std::path::Path;
use std::process::Command;

use host_sim::mission_run::{self, MissionOutcome, MissionSetup};
use host_sim::scenario_file;
use shared::estimation::{EstimatorOptions, ThrustScaleAxis};
use shared::mission::{AbortReason, MissionConfig, Reason};
use shared::scenario::Scenario;

fn run(scenario: &Scenario, map_error: f32, bias_term: bool) -> (MissionOutcome, Vec<Reason>) {
    let setup = MissionSetup {
        seed: 1,
        map_error,
        config: MissionConfig {
            estimator: EstimatorOptions {
                thrust_scale: bias_term.then_some(ThrustScaleAxis::DEFAULT),
            },
            ..MissionConfig::default()
        },
        ..MissionSetup::default()
    };
    let (outcome, autopilot) =
        mission_run::run(scenario, &setup, &mut |_, _, _| {}).expect("mission runs");
    (outcome, autopilot.reasons)
}

/// Estimate error per axis, in resolutions.
fn error_over_resolution(s: &Scenario, estimate: [f32; 3]) -> [f32; 3] {
    let t = s.truth.expect("truth");
    let truth = [t.com.x, t.com.y, t.mass];
    [0, 1, 2].map(|a| (estimate[a] - truth[a]).abs() / s.estimation.resolution[a])
}

#[test]
fn delivers_the_payload_with_the_estimate_within_one_resolution() {
    // With the detector's characterised noise (MissionConfig's default) every axis is within
    // one resolution on all three cases.
    for name in ["rect-ex1", "rect-ex2", "L-sim1"] {
        let s = load(name);
        let (outcome, reasons) = run(&s, 1.0, false);
        let estimate = outcome.estimate.expect("estimation converged");
        let error = error_over_resolution(&s, estimate);
        eprintln!(
            "{name}: estimate {estimate:?}, error/resolution {error:?}, lifts {:?}",
            outcome.lifts
        );
        assert!(outcome.delivered, "{name}: {:?}", outcome.aborted);
        assert!(!outcome.dropped, "{name}");
        assert!(
            outcome.final_position_error_m < 0.1,
            "{name}: {}",
            outcome.final_position_error_m
        );
        assert!(error.iter().all(|&e| e <= 1.0), "{name}: {error:?}");
        assert!(
            outcome.measurements >= 2 && outcome.measurements <= 20,
            "{name}"
        );
        // Every reading came from the plant's physics and sits within the noise the estimator
        // assumes (sigma 1 N) of the model's lift-off.
        for (pair, reading, model) in &outcome.lifts {
            let reading = reading.expect("these pairs can lift");
            assert!(
                (reading - model).abs() < 0.8,
                "{name} pair {pair}: {reading} vs {model}"
            );
        }
        // The phases ran in the pipeline's order.
        let names: Vec<&str> = outcome.phases.iter().map(|(n, _)| n.as_str()).collect();
        let order = [
            "preflight-checks",
            "lift",
            "decide-formation",
            "rearrange",
            "arming",
            "takeoff",
            "hover",
            "landing",
            "disarmed",
        ];
        let mut at = 0;
        for want in order {
            let found = names[at..].iter().position(|n| *n == want);
            assert!(
                found.is_some(),
                "{name}: {want} missing or out of order in {names:?}"
            );
            at += found.unwrap_or(0);
        }
        assert!(reasons.iter().any(|r| matches!(r, Reason::Landed)));
    }
}

#[test]
fn bias_term_keeps_the_mass_within_a_resolution_under_a_ten_percent_map_error() {
    for name in ["rect-ex1", "L-sim1"] {
        let s = load(name);
        let (off, _) = run(&s, 1.1, false);
        let (on, _) = run(&s, 1.1, true);
        let e_off = error_over_resolution(&s, off.estimate.expect("converged"))[2];
        let e_on = error_over_resolution(&s, on.estimate.expect("converged"))[2];
        eprintln!("{name}: mass error/resolution off {e_off}, on {e_on}");
        assert!(on.delivered, "{name}: {:?}", on.aborted);
        assert!(e_on <= 1.0, "{name}: {e_on}");
        assert!(
            e_on < e_off,
            "{name}: the bias term must help: {e_on} vs {e_off}"
        );
    }
}

#[test]
fn refuses_to_take_off_without_thrust_margin_or_convergence() {
    // An operator limit of 30 % of the rotors' total thrust for hover: the paper's payload
    // needs about 35 %, so the mission must refuse after estimating, before arming.
    let s = load("rect-ex1");
    let setup = MissionSetup {
        seed: 1,
        map_error: 1.0,
        config: MissionConfig {
            max_hover_fraction: 0.3,
            ..MissionConfig::default()
        },
        ..MissionSetup::default()
    };
    let (outcome, autopilot) = mission_run::run(&s, &setup, &mut |_, _, _| {}).expect("runs");
    let reasons = autopilot.reasons;
    assert!(!outcome.delivered);
    assert!(outcome.estimate.is_some(), "estimated first");
    assert!(
        matches!(
            outcome.aborted,
            Some(AbortReason::ThrustMarginTooSmall { .. })
        ),
        "{:?}",
        outcome.aborted
    );
    assert!(
        !reasons.iter().any(|r| matches!(r, Reason::Armed)),
        "never armed"
    );

    // One lift allowed and a strict threshold: estimation cannot converge.
    let text = std::fs::read_to_string(scenario_path("L-sim1"))
        .expect("file")
        .replace("max_measurements = 20", "max_measurements = 1")
        .replace("threshold = 0.8", "threshold = 0.999");
    let strict = scenario_file::parse(&text, Path::new("strict.toml"))
        .expect("valid")
        .scenario;
    let (outcome, _) = run(&strict, 1.0, false);
    assert_eq!(outcome.measurements, 1);
    assert_eq!(
        outcome.aborted,
        Some(AbortReason::EstimationNotConverged),
        "{:?}",
        outcome.aborted
    );
    assert!(outcome.phases.iter().all(|(n, _)| n != "takeoff"));
}

#[test]
fn mission_json_has_the_spec_keys() {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "mission",
            "--scenario",
            scenario_path("L-sim1").to_str().unwrap(),
            "--json",
        ])
        .output()
        .expect("host-sim runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    for key in [
        "estimate",
        "measurements",
        "positions",
        "delivered",
        "dropped",
        "final_position_error_m",
        "phases",
    ] {
        assert!(!v[key].is_null(), "{key} missing");
    }
    assert_eq!(v["estimate"].as_array().map(Vec::len), Some(3));
    let phases = v["phases"].as_array().expect("phases");
    assert!(
        phases
            .iter()
            .all(|p| p["name"].is_string() && p["duration_s"].is_number())
    );
    assert_eq!(v["delivered"], true);
}

#[test]
fn losing_motion_capture_in_flight_lands_in_place_instead_of_falling() {
    let s = load("L-sim1");
    let setup = MissionSetup {
        seed: 1,
        map_error: 1.0,
        config: MissionConfig::default(),
        // Take-off lasts ~3 s: lost during the transit, ~0.5 m above ground.
        mocap_lost_after_takeoff: Some(6.0),
        ..MissionSetup::default()
    };
    let (outcome, autopilot) = mission_run::run(&s, &setup, &mut |_, _, _| {}).expect("runs");
    let reasons = autopilot.reasons;
    assert!(!outcome.dropped, "kept flying: {outcome:?}");
    assert_eq!(
        outcome.aborted,
        Some(AbortReason::PositionLost),
        "{:?}",
        outcome.aborted
    );
    assert!(!outcome.delivered, "an aborted flight is not a delivery");
    assert!(
        reasons.iter().any(|r| matches!(r, Reason::Landed)),
        "landed and disarmed"
    );
    assert!(
        outcome.phases.last().is_some_and(|(n, _)| n == "disarmed"),
        "{:?}",
        outcome.phases
    );
}

/// A robot's stepper stalls halfway to its place in the formation (`stepper-stall:2` on
/// rect-ex1; `stepper-stall:12`, the last of sixteen bits the drivers report, on rect-12): the
/// mission must not fly with a robot off its planned place, so it stops on the ground with the
/// robot named, no take-off, rotors stopped, the robot where it stalled.
#[test]
fn a_stepper_stalled_during_the_rearrangement_stops_the_mission_on_the_ground() {
    for (name, robot) in [("rect-ex1", 1), ("rect-12", 11)] {
        let s = load(name);
        let setup = MissionSetup {
            stepper_stall: Some(robot),
            ..MissionSetup::default()
        };
        let (outcome, autopilot) = mission_run::run(&s, &setup, &mut |_, _, _| {}).expect("runs");
        assert_eq!(
            outcome.aborted,
            Some(AbortReason::RobotStalled { robot: robot as u8 }),
            "{name}: {:?}",
            autopilot.reasons
        );
        assert!(!outcome.flew, "{name}: never left the ground");
        assert!(
            !outcome.phases.iter().any(|(n, _)| n == "takeoff"),
            "{name}: no take-off: {:?}",
            outcome.phases
        );
        assert!(
            outcome.final_thrusts.iter().all(|&t| t == 0.0),
            "{name}: rotors stopped: {:?}",
            outcome.final_thrusts
        );
        assert!(
            outcome.phases.iter().any(|(n, _)| n == "rearrange"),
            "{name}: stalled while rearranging: {:?}",
            outcome.phases
        );
        // Where it stopped: short of its place in the formation (how far along is the unit
        // test's: `mission_run`'s `a_stalled_stepper_stops_halfway`).
        let rail = &s.payload.rail;
        let place = outcome.positions.as_ref().expect("a formation was chosen")[robot];
        let stopped = outcome.final_rail[robot];
        let gap = rail.forward_gap(stopped, place);
        assert!(
            gap.min(rail.perimeter() - gap) > 0.05,
            "{name}: robot {} stopped at {stopped:.3} m, its place {place:.3} m",
            robot + 1
        );
    }
}

/// A payload the robots cannot lift (the grid allows at most 4 kg; eight rotors make 113.6 N):
/// the mission must stop on the ground with the reason, rotors off, never armed for flight.
#[test]
fn a_payload_beyond_the_grid_and_the_rotors_aborts_on_the_ground() {
    let base = std::fs::read_to_string(scenario_path("rect-sim1")).expect("file");
    for (label, text, map_error) in [
        ("20 kg", base.replace("mass = 3.5", "mass = 20.0"), 1.0),
        (
            "1000 kg, the largest payload a scenario may describe",
            base.replace("mass = 3.5", "mass = 1000.0"),
            1.0,
        ),
        ("rotors making nothing", base.clone(), 1e30),
    ] {
        assert!(label == "rotors making nothing" || text != base, "{label}");
        let s = scenario_file::parse(&text, Path::new("heavy.toml"))
            .expect("valid")
            .scenario;
        let setup = MissionSetup {
            map_error,
            ..MissionSetup::default()
        };
        let (outcome, autopilot) = mission_run::run(&s, &setup, &mut |_, _, _| {}).expect("runs");
        let reasons = autopilot.reasons;
        eprintln!(
            "{label}: aborted {:?}, lifts {:?}",
            outcome.aborted, outcome.lifts
        );
        assert!(!outcome.delivered, "{label}");
        assert!(!outcome.flew, "{label}: the payload never left the ground");
        assert!(
            !reasons.iter().any(|r| matches!(r, Reason::Armed)),
            "{label}: never armed for flight"
        );
        assert!(
            matches!(outcome.aborted, Some(AbortReason::PayloadOutsideGrid(_))),
            "{label}: {:?}",
            outcome.aborted
        );
        assert!(
            outcome.final_thrusts.iter().all(|&t| t == 0.0),
            "{label}: rotors off at the end: {:?}",
            outcome.final_thrusts
        );
        assert!(
            outcome.estimate.is_none(),
            "{label}: no estimate is believed"
        );
        let text = outcome.aborted.map(|a| a.to_string()).unwrap_or_default();
        assert!(
            text.contains("outside the estimation grid"),
            "{label}: {text}"
        );
    }
}

/// The rotors make far less thrust than commanded (a command-to-thrust map that over-reads
/// 2.5 times): the payload cannot leave the ground, and the flight stack stops the rotors a
/// few seconds into the take-off instead of walking the plan on the clock.
#[test]
fn a_take_off_that_does_not_leave_the_ground_stops_the_rotors() {
    use host_sim::harness::{self, FlightSetup, FormationChoice};
    use shared::control::allocation::MixerKind;
    use shared::flight::FlightStop;
    let s = load("rect-sim1");
    let truth = s.truth.expect("truth");
    let setup = FlightSetup {
        formation: FormationChoice::Optimized,
        mixer: MixerKind::EqualSplit,
        believed_com: truth.com,
        believed_mass: truth.mass,
        seed: 3,
        // The rotors make 1/2.5 of what is commanded: at most 45 N against 44 N of weight,
        // held back further by the collective limit.
        map_error: 2.5,
        plant: host_sim::scenario_file::PlantDepartures::MODEL,
    };
    let out = harness::fly_formation(&s, &setup).expect("flight runs");
    assert!(
        matches!(out.stop, Some(FlightStop::TakeoffFailed { .. })),
        "{:?}",
        out.stop
    );
    assert!(out.max_height_m < 0.05, "{}", out.max_height_m);
    assert!(!out.dropped);
    // Stopped within a few seconds of take-off thrust, not at the end of the plan.
    assert!(out.simulated_s < 1.0 + 6.0, "{}", out.simulated_s);
}
