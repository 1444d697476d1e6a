//! Tests of the scenario checks: the paper's cases pass, and each rule refuses what it
//! must with the key named.

use super::problem::Number;
use super::*;
use crate::paper::rect_sim1;

#[test]
fn paper_rectangle_is_accepted_with_even_start() {
    let s = Scenario::from_input(&rect_sim1()).expect("valid");
    assert_eq!(s.robots.count(), 8);
    assert!((s.robots.initial[1] - 4.88 / 8.0).abs() < 1e-6);
    // floor(1/0.1)+1, floor(0.1/0.03)+1, floor(1.5/0.5)+1
    assert_eq!(
        [0, 1, 2].map(|a| s.estimation.axis_len(a)),
        [11, 4, 4],
        "the grid axis rule"
    );
}

#[test]
fn experiment_grid_counts_despite_f32_rounding() {
    let e = EstimationSetup {
        grid_min: [-0.26, -0.06, 2.2],
        grid_max: [0.26, 0.06, 4.0],
        resolution: [0.065, 0.04, 0.45],
        threshold: 0.53,
        noise_sigma: 1.0,
        max_measurements: 20,
    };
    assert_eq!([0, 1, 2].map(|a| e.axis_len(a)), [9, 4, 5]);
}

#[test]
fn each_bad_value_names_its_key() {
    let mut bad = rect_sim1();
    bad.estimation.resolution[1] = 0.0;
    assert_eq!(
        Scenario::from_input(&bad).unwrap_err().key,
        "estimation.resolution"
    );

    let mut bad = rect_sim1();
    bad.robots.count = 1;
    bad.robots.spin = &[1];
    assert_eq!(
        Scenario::from_input(&bad).unwrap_err().problem,
        Problem::FewerRobotsThanPair {
            count: 1,
            pair_size: 2
        }
    );

    let far = [0.12, 0.56, 5.0];
    let mut bad = rect_sim1();
    bad.candidates = &far;
    let err = Scenario::from_input(&bad).unwrap_err();
    assert_eq!(err.key, "payload.candidates");
    assert!(matches!(err.problem, Problem::OffRail { index: 2, .. }));

    let bow = [
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 1.0),
    ];
    let mut bad = rect_sim1();
    bad.footprint = &bow;
    assert_eq!(
        Scenario::from_input(&bad).unwrap_err().key,
        "payload.footprint"
    );

    let mut bad = rect_sim1();
    bad.truth = Some(Truth {
        com: Vec2::new(0.95, 0.0),
        mass: 3.0,
    });
    assert_eq!(
        Scenario::from_input(&bad).unwrap_err().problem,
        Problem::OutsideHull
    );
}

#[test]
fn initial_positions_must_keep_spacing_across_the_wrap() {
    let crowded = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.7];
    let mut bad = rect_sim1();
    bad.robots.initial = Some(&crowded);
    let err = Scenario::from_input(&bad).unwrap_err();
    assert_eq!(err.key, "robots.initial");
    assert!(matches!(err.problem, Problem::TooClose { index: 7, .. }));
}

use std::string::ToString;

/// The key and problem of the error `edit` makes of rect-sim1.
fn refusal(edit: impl FnOnce(&mut ScenarioInput<'static>)) -> ScenarioError {
    let mut input = rect_sim1();
    edit(&mut input);
    Scenario::from_input(&input).expect_err("must be refused")
}

#[test]
fn coordinates_beyond_the_bound_are_refused_before_lengths_overflow() {
    static FAR: [Vec2; 4] = [
        Vec2::new(-0.88, -0.1),
        Vec2::new(1e20, -0.1),
        Vec2::new(0.88, 0.1),
        Vec2::new(-0.88, 0.1),
    ];
    let err = refusal(|s| s.footprint = &FAR);
    assert_eq!(err.key, "payload.footprint");
    assert_eq!(
        err.problem,
        Problem::FarCoordinate {
            index: 1,
            value: 1e20
        }
    );
    let err = refusal(|s| s.rail = &FAR);
    assert_eq!(err.key, "payload.rail");
    assert!(err.to_string().contains("1e20"), "{err}");
}

#[test]
fn the_rail_must_run_close_around_the_footprint() {
    static FAR_AWAY: [Vec2; 4] = [
        Vec2::new(-5.88, -5.1),
        Vec2::new(5.88, -5.1),
        Vec2::new(5.88, 5.1),
        Vec2::new(-5.88, 5.1),
    ];
    static INSIDE: [Vec2; 4] = [
        Vec2::new(-0.8, -0.05),
        Vec2::new(0.8, -0.05),
        Vec2::new(0.8, 0.05),
        Vec2::new(-0.8, 0.05),
    ];
    static CROSSING: [Vec2; 4] = [
        Vec2::new(-0.5, -0.22),
        Vec2::new(0.5, -0.22),
        Vec2::new(0.5, 0.22),
        Vec2::new(-0.5, 0.22),
    ];
    static BESIDE: [Vec2; 4] = [
        Vec2::new(1.0, -0.22),
        Vec2::new(1.5, -0.22),
        Vec2::new(1.5, 0.22),
        Vec2::new(1.0, 0.22),
    ];
    let err = refusal(|s| s.rail = &FAR_AWAY);
    assert_eq!(err.key, "payload.rail");
    assert!(matches!(err.problem, Problem::RailTooFar { distance, .. } if distance > 4.9));
    let err = refusal(|s| s.rail = &INSIDE);
    assert_eq!(err.problem, Problem::RailDoesNotEnclose { vertex: 0 });
    let err = refusal(|s| s.rail = &CROSSING);
    assert!(matches!(err.problem, Problem::RailCrossesFootprint { .. }));
    let err = refusal(|s| s.rail = &BESIDE);
    assert_eq!(err.problem, Problem::RailDoesNotEnclose { vertex: 0 });
    // Just inside the bound is fine: the rail's corners are sqrt(2) * 0.7 = 0.99 m out.
    static WIDE: [Vec2; 4] = [
        Vec2::new(-1.58, -0.8),
        Vec2::new(1.58, -0.8),
        Vec2::new(1.58, 0.8),
        Vec2::new(-1.58, 0.8),
    ];
    let mut wide = rect_sim1();
    wide.rail = &WIDE;
    wide.candidates = &[0.12, 0.56, 1.0];
    Scenario::from_input(&wide).expect("0.99 m of clearance is within the bound");
}

#[test]
fn lifting_groups_that_cannot_be_formed_are_refused() {
    let err = refusal(|s| {
        s.candidates = &[0.12, 0.56];
        s.robots.pair_size = 3;
    });
    assert_eq!(err.key, "robots.pair_size");
    assert_eq!(
        err.problem,
        Problem::GroupLargerThanCandidates {
            pair_size: 3,
            candidates: 2
        }
    );
    // rect-sim1's candidates are 0.34 to 0.44 m apart.
    let err = refusal(|s| s.robots.min_spacing = 0.5);
    assert_eq!(err.key, "payload.candidates");
    assert!(err.to_string().contains("robots.min_spacing 0.5"), "{err}");
}

#[test]
fn a_payload_no_pair_can_tip_at_the_grids_heaviest_mass_is_refused_and_threes_lift_it() {
    // rect-sim1's grid up to 12 kg: at some grid COM every pair needs more than 14.2 N per
    // robot (a pair across the long side lifts 0.16 of the weight there at best).
    let err = refusal(|s| s.estimation.grid_max[2] = 12.0);
    assert_eq!(err.key, "robots.pair_size");
    let Problem::NoGroupTips {
        pair_size,
        mass,
        needed,
        max_thrust,
        ..
    } = err.problem
    else {
        panic!("{err}");
    };
    assert_eq!((pair_size, mass, max_thrust), (2, 12.0, 14.2));
    assert!(needed > 14.2 && needed < 20.0, "{needed}");
    assert!(err.to_string().contains("the grid's heaviest"), "{err}");
    // Up to 4 kg (the paper's) every grid COM has a pair that tips it.
    Scenario::from_input(&rect_sim1()).expect("the paper's rectangle");
    // Groups of three robots tip 12 kg.
    let mut threes = rect_sim1();
    threes.estimation.grid_max[2] = 12.0;
    threes.robots.pair_size = 3;
    Scenario::from_input(&threes).expect("threes lift it");
}

#[test]
fn a_grid_wholly_outside_the_hull_is_refused() {
    let err = refusal(|s| {
        s.estimation.grid_min[0] = 0.9;
        s.estimation.grid_max[0] = 1.2;
    });
    assert_eq!(err.key, "estimation.grid_min/grid_max");
    assert_eq!(err.problem, Problem::GridOutsideHull);
    // One column on the hull's edge is enough.
    let mut edge = rect_sim1();
    edge.estimation.grid_min[0] = 0.88;
    edge.estimation.grid_max[0] = 1.2;
    Scenario::from_input(&edge).expect("x = 0.88 lies on the hull");
}

#[test]
fn yaw_needs_both_spin_directions() {
    let err = refusal(|s| s.robots.spin = &[1; 8]);
    assert_eq!(err.key, "robots.spin");
    assert_eq!(err.problem, Problem::OneSpinDirection { sign: 1 });
    let err = refusal(|s| s.robots.spin = &[-1; 8]);
    assert_eq!(err.problem, Problem::OneSpinDirection { sign: -1 });
    // Unequal counts can still balance yaw with unequal thrusts.
    let mut uneven = rect_sim1();
    uneven.robots.spin = &[1, 1, 1, -1, 1, 1, 1, 1];
    Scenario::from_input(&uneven).expect("both directions present");
}

#[test]
fn absurd_magnitudes_name_their_key() {
    type Edit = fn(&mut ScenarioInput<'static>);
    let cases: [(Edit, &str); 10] = [
        (
            |s| s.robots.torque_per_thrust = 1e6,
            "robots.torque_per_thrust",
        ),
        (
            |s| s.robots.torque_per_thrust = 0.0,
            "robots.torque_per_thrust",
        ),
        (|s| s.robots.mass = 50.0, "robots.mass"),
        (|s| s.robots.max_thrust = 1e4, "robots.max_thrust"),
        (|s| s.estimation.grid_max[2] = 1e5, "estimation.grid_max"),
        (
            |s| s.estimation.noise_sigma = 100.0,
            "estimation.noise_sigma",
        ),
        (
            |s| s.estimation.max_measurements = 1000,
            "estimation.max_measurements",
        ),
        (|s| s.formation.balance_eps = 5.0, "formation.balance_eps"),
        (
            |s| {
                s.truth = Some(Truth {
                    com: Vec2::new(0.3, 0.0),
                    mass: 1e6,
                })
            },
            "truth.mass",
        ),
        (
            |s| {
                s.flight = Some(FlightSetup {
                    target: [0.3, 1.98, 0.5],
                    disturbance_torque: 1e6,
                })
            },
            "flight.disturbance_torque",
        ),
    ];
    for (edit, key) in cases {
        let err = refusal(edit);
        assert_eq!(err.key, key, "{err}");
    }
    for target in [[1e6, 0.0, 0.5], [0.3, 1.98, 1e6], [0.3, 1.98, 0.0]] {
        let err = refusal(|s| {
            s.flight = Some(FlightSetup {
                target,
                disturbance_torque: 0.3,
            })
        });
        assert_eq!(err.key, "flight.target", "{target:?}");
    }
    // A payload too heavy for the robots is a vehicle that exists: the mission must find
    // out and refuse to fly, so the scenario stays valid.
    let mut heavy = rect_sim1();
    heavy.truth = Some(Truth {
        com: Vec2::new(0.33, 0.01),
        mass: 20.0,
    });
    Scenario::from_input(&heavy).expect("20 kg is a payload that exists");
}

#[test]
fn a_grid_too_fine_to_count_says_so_in_words() {
    let err = refusal(|s| s.estimation.resolution[0] = 1e-6);
    assert_eq!(err.key, "estimation.resolution");
    assert_eq!(err.problem, Problem::TooManyGridPoints { found: None });
    let text = err.to_string();
    assert!(text.contains("more than 4096"), "{text}");
    assert!(!text.contains("18446744073709551615"), "{text}");
    // 1001 x 4 x 4 points: counted exactly.
    let err = refusal(|s| s.estimation.resolution[0] = 0.001);
    assert_eq!(
        err.problem,
        Problem::TooManyGridPoints {
            found: Some(1001 * 16)
        }
    );
}

#[test]
fn numbers_in_messages_stay_readable() {
    assert_eq!(Number(0.2).to_string(), "0.2");
    assert_eq!(Number(1e20).to_string(), "1e20");
    assert_eq!(Number(f32::MAX).to_string(), "over 3.40282e38");
    assert_eq!(Number(-f32::MAX).to_string(), "under -3.40282e38");
}
