//! The ground link's and the battery's failsafes in the physics plant: the
//! simulated ground station's heartbeat stops (`--inject gcs-loss@T`) or the pack's voltage
//! drops (`--inject battery:V@T`) in flight on rect-ex1, with each `FS_GCS_ACT`; and on the
//! ground neither a missing link nor a low pack lets the mission start.

use crate::common;
use common::load;

use host_sim::mission_run::{self, BatteryDrop, MissionOutcome, MissionSetup, Onset};
use shared::mission::supervision::{FenceAction, GcsLossAction};
use shared::mission::{AbortReason, CommandRefusal, MissionConfig};

/// What a run said: each phase and notice with its time, s.
struct Flown {
    outcome: MissionOutcome,
    said: Vec<(f32, String, String)>,
}

impl Flown {
    /// The first line whose kind is `name` and whose text contains `text`.
    fn find(&self, name: &str, text: &str) -> Option<(f32, &str)> {
        self.said
            .iter()
            .find(|(_, n, r)| n == name && r.contains(text))
            .map(|(t, _, r)| (*t, r.as_str()))
    }

    /// Horizontal position at `t` (the flight's 100 Hz series), m.
    fn xy_at(&self, t: f32) -> [f32; 2] {
        self.outcome
            .series
            .iter()
            .find(|s| s.t >= t)
            .map_or([f32::NAN; 2], |s| s.xy)
    }

    fn final_xy(&self) -> [f32; 2] {
        self.outcome.series.last().map_or([f32::NAN; 2], |s| s.xy)
    }
}

fn distance(a: [f32; 2], b: [f32; 2]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

fn fly(config: MissionConfig, setup: MissionSetup) -> Flown {
    let s = load("rect-ex1");
    let setup = MissionSetup { config, ..setup };
    let mut said = Vec::new();
    let (outcome, _) = mission_run::run(&s, &setup, &mut |t, name, reason| {
        said.push((t, name.to_string(), reason.to_string()))
    })
    .expect("runs");
    Flown { outcome, said }
}

fn gcs_config(action: GcsLossAction, hold: f32) -> MissionConfig {
    let mut c = MissionConfig::default();
    c.supervision.gcs_action = action;
    c.supervision.gcs_hold_time = hold;
    c
}

fn gcs_lost(after: f32) -> MissionSetup {
    MissionSetup {
        gcs_loss: Some(Onset::AfterTakeoff(after)),
        ..MissionSetup::default()
    }
}

/// The ground station stops 1 s into the flight (its last heartbeat at most 1 s before):
/// lost 5 s (`FS_GCS_LOSS_T`) after that heartbeat, during the transit.
#[test]
fn gcs_loss_in_flight_with_continue_flies_on_and_delivers() {
    let f = fly(gcs_config(GcsLossAction::Continue, 10.0), gcs_lost(1.0));
    let stopped = f.outcome.gcs_lost_at.expect("the ground station stopped");
    let (seen, text) = f
        .find("notice", "ground link lost")
        .expect("the loss is told");
    assert!(text.contains("flying on to the target"), "{text}");
    let last_beat = stopped.floor();
    let detect = seen - last_beat;
    eprintln!(
        "continue: stopped at {stopped:.2} s, seen at {seen:.2} s ({detect:.3} s after the last heartbeat); final error {:.3} m, tilt {:.1} deg",
        f.outcome.final_position_error_m, f.outcome.max_tilt_deg
    );
    assert!(
        (detect - 5.0).abs() < 0.01,
        "detected {detect} s after the last heartbeat"
    );
    assert!(f.outcome.delivered, "{:?}", f.outcome.aborted);
    assert!(!f.outcome.dropped);
    assert_eq!(f.outcome.aborted, None);
}

#[test]
fn gcs_loss_in_flight_with_hold_holds_then_lands_where_it_is() {
    let f = fly(gcs_config(GcsLossAction::HoldThenLand, 10.0), gcs_lost(1.0));
    let (seen, text) = f
        .find("notice", "ground link lost")
        .expect("the loss is told");
    assert!(
        text.contains("holding 10 s, then landing in place"),
        "{text}"
    );
    let (landing, reason) = f.find("landing", "ABORT").expect("a landing in place");
    assert!(reason.contains("ground link lost"), "{reason}");
    assert!(
        (landing - seen - 10.0).abs() < 0.01,
        "held {} s",
        landing - seen
    );
    // Held where it was (after stopping from the transit's speed) and landed there.
    let held_at = f.xy_at(seen + 2.0);
    let drift = distance(held_at, f.xy_at(landing));
    let landed_from_hold = distance(held_at, f.final_xy());
    eprintln!(
        "hold: seen at {seen:.2} s, landing at {landing:.2} s; drift in the hold {drift:.3} m, landed {landed_from_hold:.3} m from the hold point, {:.3} m from the target; tilt {:.1} deg",
        f.outcome.final_position_error_m, f.outcome.max_tilt_deg
    );
    assert!(drift < 0.1, "drifted {drift} m while holding");
    assert!(landed_from_hold < 0.1, "landed {landed_from_hold} m away");
    assert!(
        f.outcome.final_position_error_m > 0.25,
        "in place, not at the target"
    );
    assert!(!f.outcome.dropped);
    assert_eq!(f.outcome.aborted, Some(AbortReason::GcsLost));
    assert!(
        f.find("disarmed", "landed").is_some(),
        "landed and disarmed"
    );
}

#[test]
fn gcs_loss_with_no_hold_lands_at_once_and_off_ignores_it() {
    let f = fly(gcs_config(GcsLossAction::HoldThenLand, 0.0), gcs_lost(1.0));
    let (seen, _) = f.find("notice", "ground link lost").expect("told");
    let (landing, reason) = f.find("landing", "ABORT").expect("a landing in place");
    assert!(reason.contains("ground link lost"), "{reason}");
    assert!(landing - seen < 0.01, "landing {} s after", landing - seen);
    assert!(!f.outcome.dropped);
    assert_eq!(f.outcome.aborted, Some(AbortReason::GcsLost));
    // Not watched: nothing said, nothing done, delivered.
    let f = fly(gcs_config(GcsLossAction::Off, 10.0), gcs_lost(1.0));
    assert!(f.find("notice", "ground link").is_none());
    assert!(f.outcome.delivered, "{:?}", f.outcome.aborted);
}

#[test]
fn without_a_ground_station_the_mission_never_takes_off() {
    let f = fly(
        MissionConfig::default(),
        MissionSetup {
            gcs_loss: Some(Onset::FromStart),
            ..MissionSetup::default()
        },
    );
    assert_eq!(f.outcome.start_refused, Some(CommandRefusal::NoGroundLink));
    assert!(!f.outcome.armed && !f.outcome.flew);
    assert!(f.find("refused", "no ground link").is_some());
}

fn battery(volts: f32, onset: Onset) -> MissionSetup {
    MissionSetup {
        battery_drop: Some(BatteryDrop { volts, onset }),
        ..MissionSetup::default()
    }
}

#[test]
fn a_battery_below_the_warning_warns_and_the_flight_goes_on() {
    let f = fly(
        MissionConfig::default(),
        battery(13.8, Onset::AfterTakeoff(2.0)),
    );
    let dropped = f.outcome.battery_dropped_at.expect("dropped");
    let (warned, text) = f.find("notice", "battery low").expect("a warning");
    eprintln!(
        "battery 13.8 V: warned {:.2} s after the drop: {text}; min {:.2} V",
        warned - dropped,
        f.outcome.min_battery_volts
    );
    assert!(
        warned - dropped < 3.0,
        "warned {} s after",
        warned - dropped
    );
    assert!(f.outcome.delivered, "{:?}", f.outcome.aborted);
    assert!(f.find("notice", "critical").is_none());
}

#[test]
fn a_critical_battery_in_flight_lands_where_it_is() {
    let f = fly(
        MissionConfig::default(),
        battery(12.0, Onset::AfterTakeoff(2.0)),
    );
    let dropped = f.outcome.battery_dropped_at.expect("dropped");
    let (landing, reason) = f.find("landing", "ABORT").expect("a landing in place");
    assert!(reason.contains("battery critical"), "{reason}");
    let at = f.xy_at(landing);
    let landed = distance(at, f.final_xy());
    eprintln!(
        "battery 12 V: landing {:.2} s after the drop, landed {landed:.3} m from where it began, {:.3} m from the target; tilt {:.1} deg",
        landing - dropped,
        f.outcome.final_position_error_m,
        f.outcome.max_tilt_deg
    );
    assert!(landing - dropped < 2.0, "{} s", landing - dropped);
    // Landing from the transit's speed: it stops within a few tens of centimetres.
    assert!(landed < 0.5, "landed {landed} m away");
    assert!(f.outcome.final_position_error_m > 0.25, "not at the target");
    assert!(!f.outcome.dropped);
    assert!(matches!(
        f.outcome.aborted,
        Some(AbortReason::BatteryCritical { .. })
    ));
}

#[test]
fn a_low_battery_on_the_ground_refuses_the_start() {
    let f = fly(MissionConfig::default(), battery(13.5, Onset::FromStart));
    assert!(matches!(
        f.outcome.start_refused,
        Some(CommandRefusal::BatteryLow { .. })
    ));
    assert!(!f.outcome.armed && !f.outcome.flew);
    let (_, text) = f
        .find("refused", "battery low")
        .expect("refused with the reason");
    assert!(text.contains("13.5"), "{text}");
}

fn fence_config(action: FenceAction, horizontal: f32, vertical: f32) -> MissionConfig {
    let mut c = MissionConfig::default();
    c.supervision.fence_action = action;
    c.supervision.fence_horizontal = horizontal;
    c.supervision.fence_vertical = vertical;
    c
}

/// A vehicle that climbs past its geofence (rect-ex1's plan hovers 0.5 m up; the fence is
/// 0.3 m) lands where it is, saying why, and is not dropped.
#[test]
fn a_climb_past_the_geofence_lands_where_it_is() {
    let f = fly(
        fence_config(FenceAction::Land, 20.0, 0.3),
        MissionSetup::default(),
    );
    let Some(AbortReason::GeofenceBreached { height, distance }) = f.outcome.aborted else {
        panic!("{:?}", f.outcome.aborted);
    };
    assert!((0.3..0.35).contains(&height), "breached at {height} m");
    assert!(distance < 1.0, "{distance}");
    assert!(!f.outcome.dropped);
    assert!(
        f.outcome.phases.iter().any(|(p, _)| p == "disarmed"),
        "landed and disarmed"
    );
    let top = f
        .outcome
        .series
        .iter()
        .map(|s| s.height)
        .fold(0.0f32, f32::max);
    assert!(
        top < 0.45,
        "the climb stopped short of the plan's 0.5 m: {top}"
    );
    let (at, text) = f
        .find("landing", "geofence breached")
        .expect("the landing says why");
    assert!(text.contains("landing where it is"), "{text}");
    assert!(at > 0.0);
}

/// Across the ground: a fence 1 m round the take-off point, the target 2 m away. With the
/// warning alone the flight goes on and delivers; with landing it comes down near the fence.
#[test]
fn a_flight_past_the_geofence_across_the_ground_warns_or_lands() {
    let warned = fly(
        fence_config(FenceAction::Warning, 1.0, 10.0),
        MissionSetup::default(),
    );
    let (_, text) = warned
        .find("notice", "geofence breached")
        .expect("the breach is told");
    assert!(text.contains("m from the take-off point"), "{text}");
    assert!(warned.outcome.delivered, "{:?}", warned.outcome.aborted);
    let landed = fly(
        fence_config(FenceAction::Land, 1.0, 10.0),
        MissionSetup::default(),
    );
    assert!(
        matches!(
            landed.outcome.aborted,
            Some(AbortReason::GeofenceBreached { .. })
        ),
        "{:?}",
        landed.outcome.aborted
    );
    assert!(!landed.outcome.dropped);
    let from_start = distance(landed.final_xy(), landed.xy_at(0.0));
    assert!(
        (0.9..1.6).contains(&from_start),
        "landed {from_start} m from where it started"
    );
}
