//! A rotor that stops in flight (`rotor-out:J`), in the physics plant with
//! `shared`'s mission: the rotor monitor (`shared::flight::rotor_monitor`) finds it from the
//! vehicle's response, the mixer is rebuilt without it and the payload lands where it is.
//! The paper's 8-rotor payloads, every rotor, fixed seed; two rotors out, apart and at once
//! (`host_sim::rotor_faults`); a rotor that fades (`rotor-fade`); the ESCs' RPM.

use crate::common;

use common::load;
use host_sim::mission_run::{self, LoadShift, MissionOutcome, MissionSetup, RotorStop};
use host_sim::rotor_faults::{self, FADE_SECONDS};
use shared::geometry::Vec2;
use shared::mission::{AbortReason, MissionConfig};

/// The payload counts as dropped beyond this roll or pitch, degrees (the plant loop's own
/// `dropped` uses the same).
const DROP_TILT_DEG: f32 = 45.0;

/// Longest time from the rotor stopping to the monitor naming it, s. Measured 0.10 to 0.12 s
/// on every rotor of the six paper scenarios, in the climb, the transit and the hover
/// (confirmation takes 0.07 s of it); with the drift judged on one tick in eight (the change
/// then waits), at most 0.127 s on rect-ex1 and L-sim1.
const DETECTION_BOUND_S: f32 = 0.2;

/// Largest tilt after one rotor stops, degrees. Measured here up to 16.2 (rect-ex1's end
/// rotors) and 13.7 (L-sim1's lone rotor on the L's arm); over all six paper scenarios and
/// three times (climb, transit, hover) up to 32 (rect-sim1's end rotor in the hover: the
/// narrow rectangles' roll inertia is small, and the roll rate builds in the 0.1 s before
/// the rotor is named).
const ONE_ROTOR_TILT_DEG: f32 = 25.0;

/// Flies `name` with `stops` (robot from 1, seconds after take-off began).
fn fly(name: &str, stops: &[(usize, f32)]) -> MissionOutcome {
    let s = load(name);
    let setup = MissionSetup {
        seed: 1,
        config: MissionConfig::default(),
        rotors_out: stops
            .iter()
            .map(|&(robot, after)| RotorStop {
                robot: robot - 1,
                after,
                fade: 0.0,
            })
            .collect(),
        ..MissionSetup::default()
    };
    let (outcome, _) = mission_run::run(&s, &setup, &mut |_, _, _| {}).expect("runs");
    outcome
}

/// No flight without a stopped rotor names one: the paper's scenarios, with and without a
/// load that shifts in the hover (its torque is a rotor's size; its thrust is unchanged).
#[test]
fn no_rotor_is_named_on_the_normal_missions() {
    for name in ["rect-ex1", "L-sim1", "rect-sim1", "rect-sim2", "L-sim2"] {
        for shift in [None, Some([0.15, 0.0])] {
            let setup = MissionSetup {
                seed: 1,
                load_shift: shift.map(|[x, y]| LoadShift {
                    offset: Vec2::new(x, y),
                    after: 11.0,
                }),
                ..MissionSetup::default()
            };
            let (o, _) = mission_run::run(&load(name), &setup, &mut |_, _, _| {}).expect("runs");
            assert!(
                o.rotors_found.is_empty(),
                "{name}, shift {shift:?}: named {:?}",
                o.rotors_found
            );
            assert!(o.delivered, "{name}, shift {shift:?}: {:?}", o.aborted);
        }
    }
}

/// Time from robot `robot`'s rotor (from 0) stopping to the mission naming it, s.
fn detection_s(o: &MissionOutcome, robot: usize) -> Option<f32> {
    let stopped = o.rotors_stopped.iter().find(|(r, _)| *r == robot)?.1;
    Some(o.named_at(robot)? - stopped)
}

/// Every rotor of `name`, stopped `after` seconds after take-off began: named within
/// [`DETECTION_BOUND_S`], no other rotor named, landed and disarmed with the rotors stopped,
/// never tilted beyond [`ONE_ROTOR_TILT_DEG`].
fn every_rotor(name: &str, after: f32) {
    let mut worst_detection = 0.0f32;
    let mut worst_tilt = 0.0f32;
    for robot in 1..=8 {
        let o = fly(name, &[(robot, after)]);
        let case = format!("{name}, rotor {robot} at {after} s");
        assert_eq!(
            o.rotors_stopped.len(),
            1,
            "{case}: the rotor stopped in flight"
        );
        assert!(!o.dropped, "{case}: dropped");
        assert!(
            o.max_tilt_deg < ONE_ROTOR_TILT_DEG,
            "{case}: tilt {} deg",
            o.max_tilt_deg
        );
        assert_eq!(
            o.aborted,
            Some(AbortReason::RotorOut {
                robot: (robot - 1) as u8
            }),
            "{case}"
        );
        assert_eq!(
            o.rotors_found
                .iter()
                .map(|(r, _)| r + 1)
                .collect::<Vec<_>>(),
            vec![robot],
            "{case}: only this rotor named"
        );
        let detection = detection_s(&o, robot - 1).expect("named");
        assert!(
            (0.0..DETECTION_BOUND_S).contains(&detection),
            "{case}: named {detection} s after it stopped"
        );
        assert!(
            o.phases.last().is_some_and(|(p, _)| p == "disarmed"),
            "{case}: landed and disarmed: {:?}",
            o.phases.last()
        );
        assert!(
            o.final_thrusts.iter().all(|&t| t == 0.0),
            "{case}: rotors stopped: {:?}",
            o.final_thrusts
        );
        let offset = o.rotor_landing_offset_m.expect("stopped");
        eprintln!(
            "{case}: named after {:.3} s, tilt {:.1} deg, largest command {:.0} %, came down {offset:.3} m from where it stopped",
            detection,
            o.max_tilt_deg,
            100.0 * o.max_thrust_fraction
        );
        // Landing "where it is": the transit's speed carries it on while it stops.
        assert!(offset < 0.5, "{case}: came down {offset} m away");
        worst_detection = worst_detection.max(detection);
        worst_tilt = worst_tilt.max(o.max_tilt_deg);
    }
    eprintln!("{name}: worst detection {worst_detection:.3} s, worst tilt {worst_tilt:.1} deg");
}

/// rect-ex1 (the paper's experiment): each rotor stopping in the transit, 8 s after take-off
/// began (the plan reaches its hover about 10.6 s after).
#[test]
fn rect_ex1_any_rotor_in_transit() {
    every_rotor("rect-ex1", 8.0);
}

/// L-sim1 (the paper's L-shaped payload): each rotor stopping in the hover, 11 s after
/// take-off began.
#[test]
fn l_sim1_any_rotor_in_hover() {
    every_rotor("L-sim1", 11.0);
}

/// Two rotors, two seconds apart (the second in the landing the first began): measured on
/// every pair of rect-ex1 and L-sim1 (first at 11 s, in the hover), none drops. The second is
/// named 0.09 to 0.11 s after it stops, unless the degraded mixer was not flying it, or the
/// payload is already within 9 cm of the ground.
#[test]
fn two_rotors_apart() {
    for (name, a, b) in [("rect-ex1", 1, 2), ("rect-ex1", 6, 7), ("L-sim1", 3, 4)] {
        let o = fly(name, &[(a, 11.0), (b, 13.0)]);
        let case = format!("{name}, rotors {a} at 11 s and {b} at 13 s");
        eprintln!(
            "{case}: dropped {}, tilt {:.1} deg, named {:?}, came down {:?} m from where the first stopped",
            o.dropped, o.max_tilt_deg, o.rotors_found, o.rotor_landing_offset_m
        );
        assert!(!o.dropped && o.max_tilt_deg < DROP_TILT_DEG, "{case}");
        for robot in [a, b] {
            let detection = detection_s(&o, robot - 1).expect("named");
            assert!(
                detection < DETECTION_BOUND_S,
                "{case}: {robot} after {detection} s"
            );
        }
        assert!(
            o.phases.last().is_some_and(|(p, _)| p == "disarmed"),
            "{case}"
        );
    }
}

/// Two rotors at the same instant, from the vehicle's response alone: pairs the monitor names
/// together, both within [`DETECTION_BOUND_S`], and flies home on the six left (the full
/// sweep, `.ci/rotor-faults`, measured 22 of rect-ex1's 28 pairs and all 28 of L-sim1's held;
/// before pairs were judged, 8 and 25). rect-ex1 1+2, the two rotors at one end, has no static
/// hover on the six left and is held all the same.
#[test]
fn two_rotors_at_once_from_the_response() {
    for (name, a, b) in [
        ("rect-ex1", 1, 2),
        ("rect-ex1", 3, 6),
        ("rect-ex1", 4, 7),
        ("L-sim1", 1, 6),
        ("L-sim1", 4, 8),
    ] {
        let case = format!("{name}, rotors {a} and {b} at once");
        let c = rotor_faults::pair(&load(name), a, b, false).expect("runs");
        eprintln!(
            "{case}: holdable {}, dropped {}, tilt {:.1} deg, named {:?} after {:?} s",
            c.holdable,
            c.outcome.dropped,
            c.outcome.max_tilt_deg,
            c.named(),
            c.detection_s()
        );
        assert!(!c.outcome.dropped, "{case}: dropped");
        let mut named = c.named();
        named.sort_unstable();
        assert_eq!(named, vec![a, b], "{case}: both named, no other");
        assert!(
            c.detection_s().is_some_and(|s| s < DETECTION_BOUND_S),
            "{case}: named after {:?} s",
            c.detection_s()
        );
    }
}

/// Longest time from a rotor's RPM collapsing to the monitor naming it, s (the requirement:
/// 30 ms; measured 7 ms on every pair).
const RPM_DETECTION_BOUND_S: f32 = 0.03;

/// With the ESCs' RPM, two rotors at once: the pairs the response alone cannot hold (it names
/// the wrong pair or too late) are named from their RPM within [`RPM_DETECTION_BOUND_S`] and
/// held. The full sweep held all 56, holdable or not.
#[test]
fn two_rotors_at_once_with_rpm() {
    for (name, a, b) in [
        ("rect-ex1", 1, 6),
        ("rect-ex1", 2, 4),
        ("rect-ex1", 6, 7),
        ("rect-ex1", 1, 8),
        ("L-sim1", 6, 8),
    ] {
        let case = format!("{name}, rotors {a} and {b} at once, with RPM");
        let c = rotor_faults::pair(&load(name), a, b, true).expect("runs");
        assert!(!c.outcome.dropped, "{case}: dropped");
        assert!(
            c.outcome.max_tilt_deg < ONE_ROTOR_TILT_DEG,
            "{case}: tilt {} deg",
            c.outcome.max_tilt_deg
        );
        let mut named = c.named();
        named.sort_unstable();
        assert_eq!(named, vec![a, b], "{case}: both named, no other");
        let detection = c.detection_s().expect("named");
        assert!(
            detection < RPM_DETECTION_BOUND_S,
            "{case}: named after {detection} s"
        );
    }
}

/// Longest time from two rotors stopping to the monitor naming them from their DroneCAN
/// ESCs' Status, s (the requirement: 20 ms).
const DRONECAN_DETECTION_BOUND_S: f32 = 0.02;

/// DroneCAN ESCs (`--esc dronecan`): two rotors at once named from their ESCs' Status, which
/// come at 50 Hz from each ESC (sixteen ESCs and the 400 Hz commands then fill 56 % of the
/// 1 Mbit/s bus), within [`DRONECAN_DETECTION_BOUND_S`]: the wait for the next Status (up
/// to 20 ms) after the rotor has slowed, the first low Status confirming (it is CRC-checked
/// and the ESC's own measurement; DShot's 4-bit answers take 10 ms of them). All 28 pairs of
/// rect-ex1: 2 to 17 ms, median 12 ms. The bus's load, counted frame by frame, at most 60 %.
#[test]
fn two_rotors_at_once_named_from_dronecan_escs_status() {
    for (name, a, b) in [("rect-ex1", 1, 6), ("rect-ex1", 2, 5), ("L-sim1", 6, 8)] {
        let case = format!("{name}, rotors {a} and {b} at once, DroneCAN ESCs");
        let c =
            rotor_faults::pair(&load(name), a, b, rotor_faults::RpmSource::DroneCan).expect("runs");
        assert!(!c.outcome.dropped, "{case}: dropped");
        let mut named = c.named();
        named.sort_unstable();
        assert_eq!(named, vec![a, b], "{case}: both named, no other");
        let detection = c.detection_s().expect("named");
        assert!(
            detection < DRONECAN_DETECTION_BOUND_S,
            "{case}: named after {detection} s"
        );
        let (frames, share) = c.outcome.can_bus_load.expect("a CAN bus");
        assert!(
            (2_000.0..3_000.0).contains(&frames) && share <= 0.6,
            "{case}: {frames} frames/s, {share} of the bus"
        );
    }
}

/// Largest tilt before a fading rotor is named, degrees (measured at most 1.6).
const FADE_TILT_DEG: f32 = 20.0;

/// A rotor fading over 4 s in the hover: named before the payload tilts [`FADE_TILT_DEG`],
/// the payload held and landed; with RPM, once its thrust is half its command (2.0 s). From
/// the response alone, among them the rotors whose neighbour along the rail reads much the
/// same drift (rect-ex1's 3, 4 and 5, L-sim1's 2 and 7: the neighbour was named when the
/// loss was sized against the fading rotor's raised command).
#[test]
fn a_fading_rotor_is_named_before_it_tilts_the_payload() {
    for (name, robot, rpm) in [
        ("rect-ex1", 1, false),
        ("rect-ex1", 3, false),
        ("rect-ex1", 4, false),
        ("rect-ex1", 5, false),
        ("L-sim1", 2, false),
        ("L-sim1", 7, false),
        ("rect-ex1", 4, true),
        ("L-sim1", 2, true),
    ] {
        let case = format!("{name}, rotor {robot} fading over {FADE_SECONDS} s, RPM {rpm}");
        let c = rotor_faults::fade(&load(name), robot, FADE_SECONDS, rpm).expect("runs");
        let detection = c.detection_s();
        let tilt = c.tilt_when_named_deg();
        eprintln!("{case}: named after {detection:?} s, tilt by then {tilt:?} deg");
        assert!(!c.outcome.dropped, "{case}: dropped");
        assert_eq!(
            c.outcome
                .rotors_found
                .iter()
                .map(|(r, _)| r + 1)
                .collect::<Vec<_>>(),
            vec![robot],
            "{case}: only this rotor named"
        );
        assert!(
            tilt.is_some_and(|t| t < FADE_TILT_DEG),
            "{case}: tilt {tilt:?}"
        );
        if rpm {
            // Half its thrust gone at half the fade; RPM's confirmation on top.
            assert!(
                detection.is_some_and(|s| s < FADE_SECONDS / 2.0 + 0.1),
                "{case}: {detection:?}"
            );
        }
        assert!(
            c.outcome
                .phases
                .last()
                .is_some_and(|(p, _)| p == "disarmed"),
            "{case}: landed and disarmed"
        );
    }
}

/// The normal missions with the ESCs' RPM: no rotor named.
#[test]
fn no_rotor_is_named_from_the_rpm_on_the_normal_missions() {
    for name in ["rect-ex1", "L-sim1", "rect-sim2"] {
        let o = rotor_faults::fly(&load(name), &[], true).expect("runs");
        assert!(
            o.rotors_found.is_empty(),
            "{name}: named {:?}",
            o.rotors_found
        );
        assert!(o.delivered, "{name}: {:?}", o.aborted);
    }
}
