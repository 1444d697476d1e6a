//! The IMU's failsafes in the physics plant (`imu-stuck` and `imu-noise:X`): a
//! frozen or wildly noisy IMU is found within 100 ms (on the ground a noisy one within 0.6 s:
//! its noise must hold half a second there); in flight the vehicle lands where it is on motion
//! capture without dropping the payload and stops its rotors; on the ground the mission stops
//! with the reason and never arms; no normal mission is ever flagged.

use crate::common;
use common::{host_sim, load};

use host_sim::mission_run::{
    self, ImuFaultKind, ImuInjection, LoadShift, MissionOutcome, MissionSetup,
};
use shared::control::imu_monitor::{GROUND_NOISY_TICKS, ImuFailure};
use shared::geometry::Vec2;
use shared::mission::AbortReason;

/// Longest time from the first faulty sample to the detection, s (40 ticks at 400 Hz).
const DETECT_WITHIN: f32 = 0.1;

fn fly(name: &str, kind: ImuFaultKind, after: f32, from_start: bool) -> MissionOutcome {
    let setup = MissionSetup {
        imu_fault: Some(ImuInjection {
            kind,
            after,
            from_start,
        }),
        ..MissionSetup::default()
    };
    mission_run::run(&load(name), &setup, &mut |_, _, _| {})
        .expect("mission runs")
        .0
}

/// Time from the fault to its detection, s, and what was found.
fn detection(o: &MissionOutcome) -> (f32, ImuFailure) {
    let at = o.imu_fault_at.expect("the fault was injected");
    let (failure, found) = o.imu_detected.expect("the monitor found it");
    (found - at, failure)
}

/// In flight: found in time, landed where it was (within 0.25 m), not dropped, rotors off.
fn assert_landed_in_place(name: &str, what: &str, o: &MissionOutcome, reason: AbortReason) {
    let (delay, _) = detection(o);
    eprintln!(
        "{name} {what}: detected after {:.1} ms, moved {:.3} m, largest tilt {:.1} deg",
        1000.0 * delay,
        o.moved_after_imu_fault_m.unwrap_or(f32::NAN),
        o.max_tilt_deg
    );
    assert!(delay <= DETECT_WITHIN, "{name} {what}: {delay} s");
    assert_eq!(o.aborted, Some(reason), "{name} {what}");
    assert!(o.flew, "{name} {what}: the fault came in flight");
    assert!(!o.dropped, "{name} {what}");
    assert!(o.max_tilt_deg < 20.0, "{name} {what}: {}", o.max_tilt_deg);
    let moved = o.moved_after_imu_fault_m.expect("measured");
    assert!(moved < 0.25, "{name} {what}: landed {moved} m away");
    assert_eq!(
        o.phases.last().map(|(p, _)| p.as_str()),
        Some("disarmed"),
        "{name} {what}: landed and disarmed"
    );
    assert!(o.final_thrusts.iter().all(|&t| t == 0.0), "{name} {what}");
    // It landed where it was, not at the target it was flying to.
    assert!(!o.delivered, "{name} {what}");
}

#[test]
fn a_frozen_imu_in_flight_lands_where_it_is() {
    // 8 s after take-off: in transit on every case; 2 s: still climbing.
    for (name, after) in [("rect-ex1", 8.0), ("L-sim1", 8.0), ("rect-sim2", 2.0)] {
        let o = fly(name, ImuFaultKind::Stuck, after, false);
        assert_eq!(detection(&o).1, ImuFailure::Stuck);
        assert_landed_in_place(name, "stuck", &o, AbortReason::ImuStuck);
    }
}

#[test]
fn a_wildly_noisy_imu_in_flight_lands_where_it_is() {
    for x in [20.0, 100.0, 1000.0] {
        for name in ["rect-ex1", "L-sim1"] {
            let o = fly(name, ImuFaultKind::Noise(x), 8.0, false);
            assert_eq!(detection(&o).1, ImuFailure::Noisy);
            assert_landed_in_place(name, &format!("noise x{x}"), &o, AbortReason::ImuNoisy);
        }
    }
}

#[test]
fn mild_noise_is_not_flagged_and_the_payload_is_delivered() {
    let o = fly("rect-ex1", ImuFaultKind::Noise(5.0), 8.0, false);
    assert!(o.imu_fault_at.is_some());
    assert_eq!(o.imu_detected, None);
    assert!(o.delivered, "{:?}", o.aborted);
}

#[test]
fn a_faulty_imu_on_the_ground_stops_the_mission_before_the_rotors_arm() {
    for (kind, reason) in [
        (ImuFaultKind::Stuck, AbortReason::ImuStuck),
        (ImuFaultKind::Noise(100.0), AbortReason::ImuNoisy),
    ] {
        // From the first sample, and 3 s into the pre-flight checks.
        for after in [0.0, 3.0] {
            let o = fly("rect-ex1", kind, after, true);
            let (delay, _) = detection(&o);
            eprintln!("{kind:?} from {after} s after the start: stopped after {delay:.4} s");
            let within = match kind {
                ImuFaultKind::Noise(_) => DETECT_WITHIN + f32::from(GROUND_NOISY_TICKS) / 400.0,
                _ => DETECT_WITHIN,
            };
            assert!(delay <= within, "{kind:?}@{after}: {delay}");
            assert_eq!(o.aborted, Some(reason), "{kind:?}@{after}");
            assert!(!o.armed, "{kind:?}@{after}: rotors never armed");
            assert!(!o.flew, "{kind:?}@{after}");
            assert_eq!(o.measurements, 0, "{kind:?}@{after}: no lift");
            assert_eq!(
                o.phases.last().map(|(p, _)| p.as_str()),
                Some("aborted"),
                "{kind:?}@{after}"
            );
        }
    }
}

#[test]
fn a_frozen_imu_during_a_lift_stops_the_rotors_on_the_ground() {
    // 8 s after the start rect-ex1 is ramping its first pair.
    let o = fly("rect-ex1", ImuFaultKind::Stuck, 8.0, true);
    assert!(detection(&o).0 <= DETECT_WITHIN);
    assert_eq!(o.aborted, Some(AbortReason::ImuStuck));
    assert!(o.armed, "the lift's rotors were running");
    assert!(!o.flew);
    assert!(o.final_thrusts.iter().all(|&t| t == 0.0));
}

/// No normal mission is flagged: every scenario, with and without a load shift in flight (its
/// lifts, touchdowns and re-formation included).
#[test]
fn no_normal_mission_is_flagged() {
    for name in [
        "L-sim1",
        "L-sim2",
        "rect-ex1",
        "rect-ex2",
        "rect-sim1",
        "rect-sim2",
    ] {
        for shift in [false, true] {
            let setup = MissionSetup {
                load_shift: shift.then_some(LoadShift {
                    offset: Vec2::new(0.15, 0.0),
                    after: 11.0,
                }),
                ..MissionSetup::default()
            };
            let (o, _) =
                mission_run::run(&load(name), &setup, &mut |_, _, _| {}).expect("mission runs");
            assert_eq!(o.imu_detected, None, "{name}, shift {shift}");
            assert!(
                !matches!(
                    o.aborted,
                    Some(AbortReason::ImuStuck | AbortReason::ImuNoisy)
                ),
                "{name}, shift {shift}"
            );
            assert!(o.flew && !o.dropped, "{name}, shift {shift}");
        }
    }
}

#[test]
fn the_command_line_injects_and_reports_imu_faults() {
    let out = host_sim(&["mission", "--inject", "imu-stuck@start+0", "--json"]);
    assert_eq!(out.status.code(), Some(3), "aborted");
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let aborted = report["aborted"].as_str().expect("a reason");
    assert!(aborted.starts_with("IMU frozen"), "{aborted}");
    assert_eq!(report["imu_fault"]["detected"], "stuck");
    assert_eq!(report["imu_fault"]["injected_s"], 0.0);
    for (bad, says) in [
        ("imu-noise:0@3", "above 0"),
        ("imu-noise:2000@3", "at most 1000"),
        ("load-shift:0.1,0@start+3", "happens in flight"),
    ] {
        let out = host_sim(&["mission", "--inject", bad]);
        assert_eq!(out.status.code(), Some(2), "{bad}: clap's value parser");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{bad}: {err}");
    }
}
