//! The frame's vibration on the IMU's raw 2 kHz path (`[plant]` `imu_vibration`,
//! `gyro_vibration`: docs/formats.md#the-plant-section), through the board's own front end
//! (`drivers::imu`: the anti-alias filter and the notches that follow each rotor's RPM). A
//! healthy vehicle with a real frame's vibration flies every paper case; the IMU monitor still
//! catches a wildly noisy IMU on the same path.

use crate::common::scenario_path;
use host_sim::inject::{self, Injection};
use host_sim::mission_run::{self, MissionOutcome, MissionSetup};
use host_sim::scenario_file::{self, PlantDepartures};
use shared::mission::AbortReason;

/// A real frame's vibration (ArduPilot calls under 15 m/s^2 normal),
/// with the rotors, inertia and lag all off the model.
const SHAKING: PlantDepartures = PlantDepartures {
    imu_vibration: 10.0,
    gyro_vibration: 0.3,
    rotor_efficiency_spread: 0.08,
    motor_time_constant: 0.04,
    inertia_scale: 1.5,
    ..PlantDepartures::MODEL
};

fn mission(case: &str, plant: PlantDepartures, inject: Option<&str>) -> MissionOutcome {
    let loaded = scenario_file::load(&scenario_path(case)).expect("a paper case");
    let injections: Vec<Injection> = inject
        .map(|text| Injection::parse(text).expect("a fault"))
        .into_iter()
        .collect();
    let setup = inject::apply(
        &injections,
        MissionSetup {
            plant,
            ..MissionSetup::default()
        },
    );
    mission_run::run(&loaded.scenario, &setup, &mut |_, _, _| {})
        .expect("runs")
        .0
}

#[test]
fn every_paper_case_delivers_on_a_vibrating_frame() {
    for case in [
        "rect-ex1",
        "rect-ex2",
        "rect-sim1",
        "rect-sim2",
        "L-sim1",
        "L-sim2",
    ] {
        let o = mission(case, SHAKING, None);
        assert!(
            o.delivered && o.final_position_error_m < 0.1,
            "{case}: {:?} {} m",
            o.aborted,
            o.final_position_error_m
        );
    }
}

#[test]
fn vibration_changes_the_flight_and_a_noisy_imu_is_still_caught_on_the_raw_path() {
    let model = mission("rect-ex1", PlantDepartures::MODEL, None);
    let shaking = mission("rect-ex1", SHAKING, None);
    assert_ne!(
        model.final_position_error_m, shaking.final_position_error_m,
        "the raw path flies differently"
    );
    let noisy = mission("rect-ex1", SHAKING, Some("imu-noise:20@3"));
    assert_eq!(noisy.aborted, Some(AbortReason::ImuNoisy), "{noisy:?}");
}
