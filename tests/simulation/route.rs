//! A ground station's route flown end to end in the physics plant (docs/ground-link.md#missions):
//! the estimation, formation and take-off as for the payload description's target, then each
//! item in order (an item is reached only when the vehicle is at its point), a hold in flight
//! that stops the vehicle where it is until the mission mode is asked for again, and the
//! landing below the last item.

use crate::common;
use common::load;

use host_sim::mission_run::{self, MissionSetup};
use shared::flight::{Route, RouteItem, RoutePoint};
use shared::mission::{CommandRefusal, OperatorCommand, Phase};

fn point(north: f32, east: f32, height: f32) -> RoutePoint {
    RoutePoint {
        north,
        east,
        height,
    }
}

/// Take off to 0.5 m, fly 1 m north climbing to 0.7 m, hover 2 s, fly on to (1, 1) m at
/// 0.5 m, land there.
fn route() -> Route {
    Route::new(&[
        RouteItem::Takeoff { height: 0.5 },
        RouteItem::Waypoint(point(1.0, 0.0, 0.7)),
        RouteItem::Loiter {
            at: None,
            seconds: 2.0,
        },
        RouteItem::Waypoint(point(1.0, 1.0, 0.5)),
        RouteItem::Land {
            at: Some(point(1.0, 1.0, 0.0)),
        },
    ])
    .expect("a route within bounds")
}

#[test]
fn a_route_is_flown_item_by_item_and_lands_below_its_last_point() {
    let s = load("rect-ex1");
    let setup = MissionSetup {
        route: Some(route()),
        ..MissionSetup::default()
    };
    let (outcome, autopilot) = mission_run::run(&s, &setup, &mut |_, _, _| {}).expect("runs");
    let mission = autopilot.mission();
    assert_eq!(mission.phase(), Phase::Disarmed, "{:?}", outcome.phases);
    assert!(outcome.delivered, "phases {:?}", outcome.phases);
    assert!(
        outcome.final_position_error_m < 0.15,
        "landed {} m from (1, 1)",
        outcome.final_position_error_m
    );
    // Every item reached, the last one last.
    assert_eq!(mission.route_progress(), Some((4, Some(4))));
    let hovers = outcome.phases.iter().filter(|(n, _)| n == "hover").count();
    let moves = outcome
        .phases
        .iter()
        .filter(|(n, _)| n == "trajectory")
        .count();
    assert_eq!((hovers, moves), (1, 2), "{:?}", outcome.phases);
}

#[test]
fn a_hold_in_flight_stops_the_route_until_the_mission_mode_resumes_it() {
    let s = load("rect-ex1");
    let free = MissionSetup {
        route: Some(route()),
        ..MissionSetup::default()
    };
    let (flown, _) = mission_run::run(&s, &free, &mut |_, _, _| {}).expect("runs");
    // Held 4 s from 3 s after take-off began (on the way to the first waypoint).
    let held = MissionSetup {
        commands: vec![(3.0, OperatorCommand::Hold), (7.0, OperatorCommand::Resume)],
        ..free
    };
    let (outcome, autopilot) = mission_run::run(&s, &held, &mut |_, _, _| {}).expect("runs");
    assert!(outcome.delivered, "phases {:?}", outcome.phases);
    assert_eq!(autopilot.mission().route_progress(), Some((4, Some(4))));
    let longer = outcome.simulated_s - flown.simulated_s;
    assert!(
        (3.0..6.0).contains(&longer),
        "a 4 s hold made the mission {longer:.2} s longer"
    );
    // The operator's, after the set-up's (the rails' confirmation and the start).
    let replies: Vec<_> = autopilot
        .replies
        .iter()
        .skip_while(|(c, _)| *c != OperatorCommand::Start)
        .skip(1)
        .cloned()
        .collect();
    assert_eq!(
        replies,
        [
            (OperatorCommand::Hold, Ok(())),
            (OperatorCommand::Resume, Ok(()))
        ]
    );
}

#[test]
fn a_hold_on_the_ground_is_refused_and_the_mission_goes_on() {
    let s = load("rect-ex1");
    let setup = MissionSetup {
        route: Some(route()),
        // As take-off begins: the payload is still on the ground.
        commands: vec![(0.0, OperatorCommand::Hold)],
        ..MissionSetup::default()
    };
    let (outcome, autopilot) = mission_run::run(&s, &setup, &mut |_, _, _| {}).expect("runs");
    assert!(outcome.delivered, "phases {:?}", outcome.phases);
    assert_eq!(
        autopilot.replies.last(),
        Some(&(OperatorCommand::Hold, Err(CommandRefusal::NotFlying))),
        "the hold on the ground was taken"
    );
}
