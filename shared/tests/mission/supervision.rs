//! The ground link's and the battery's failsafes in the miniature world: no start without a
//! link or with a low battery, a stop on the ground, and in flight each `FS_GCS_ACT` and the
//! battery's two thresholds.

use super::*;
use shared::mission::supervision::{GcsLossAction, LinkResponse, Notice};

/// Ticks a second.
const SECOND: u64 = 400;

/// The defaults with a 1 s link timeout, the given loss action and hold, and a 10 s hover
/// (so a loss in flight is seen before the plan's own landing).
fn config(action: GcsLossAction, hold: f32) -> MissionConfig {
    let mut c = MissionConfig::default();
    c.supervision.gcs_action = action;
    c.supervision.gcs_timeout = 1.0;
    c.supervision.gcs_hold_time = hold;
    c.flight.plan.hover_time = 10.0;
    c
}

/// A run with the notices and the heights seen, `change` called on the world before each
/// tick's step is taken into account (after the tick's output).
struct Seen {
    run: Run,
    notices: Vec<(u64, Notice)>,
    heights: Vec<f32>,
}

fn fly(
    s: &Scenario,
    config: MissionConfig,
    world: &mut World,
    mut change: impl FnMut(u64, &mut World),
) -> Seen {
    let mut notices = Vec::new();
    let mut heights = Vec::new();
    let run = run_with(
        s,
        config,
        world,
        Jobs::OnTime,
        &[(1, OperatorCommand::Start)],
        |tick, out, w| {
            if let Some(n) = out.notice {
                notices.push((tick, n));
            }
            heights.push(w.height);
            change(tick, w);
        },
        200_000,
    );
    Seen {
        run,
        notices,
        heights,
    }
}

fn landing_reason(run: &Run) -> Option<(u64, Reason)> {
    run.transitions
        .iter()
        .find(|(_, _, p)| *p == Phase::Flying(FlightPhase::Land))
        .map(|(t, r, _)| (*t, *r))
}

#[test]
fn without_a_ground_link_the_mission_does_not_start() {
    let s = straight_up_scenario(3.5);
    let mut world = World::new(&s);
    world.gcs_until = 0;
    let seen = fly(
        &s,
        config(GcsLossAction::HoldThenLand, 10.0),
        &mut world,
        |_, _| {},
    );
    assert_eq!(
        seen.run.replies.first().map(|(_, r)| r.outcome),
        Some(Err(CommandRefusal::NoGroundLink))
    );
    assert_eq!(seen.run.mission.phase(), Phase::Idle);
    assert!(seen.run.transitions.is_empty());
    // Not watched: it starts.
    let mut world = World::new(&s);
    world.gcs_until = 0;
    let seen = fly(&s, config(GcsLossAction::Off, 10.0), &mut world, |_, _| {});
    assert_eq!(seen.run.mission.phase(), Phase::Disarmed);
    assert_eq!(seen.run.mission.abort_reason(), None);
}

#[test]
fn a_link_lost_on_the_ground_stops_the_mission_before_take_off() {
    let s = straight_up_scenario(3.5);
    let mut world = World::new(&s);
    // The last heartbeat at 2 s, in the pre-flight checks; lost 1 s later.
    world.gcs_until = 2 * SECOND + 2;
    let seen = fly(
        &s,
        config(GcsLossAction::Continue, 10.0),
        &mut world,
        |_, _| {},
    );
    assert_eq!(seen.run.mission.abort_reason(), Some(AbortReason::GcsLost));
    let stopped = tick_of(&seen.run, Phase::Aborted);
    assert_eq!(stopped, 3 * SECOND + 2, "1 s after the last heartbeat");
    assert!(!phases(&seen.run).contains(&Phase::Arming), "never armed");
    assert!(seen.run.last.thrusts.iter().all(|&t| t == 0.0));
}

#[test]
fn a_link_lost_in_flight_with_continue_flies_the_plan_to_its_landing() {
    let s = straight_up_scenario(3.5);
    let takeoff = takeoff_tick(&s);
    let mut world = World::new(&s);
    world.gcs_until = takeoff + SECOND;
    let seen = fly(
        &s,
        config(GcsLossAction::Continue, 10.0),
        &mut world,
        |_, _| {},
    );
    let lost: Vec<_> = seen
        .notices
        .iter()
        .filter(|(_, n)| matches!(n, Notice::LinkLost { .. }))
        .collect();
    assert_eq!(lost.len(), 1, "{:?}", seen.notices);
    assert!(matches!(
        lost[0].1,
        Notice::LinkLost {
            response: LinkResponse::Continue,
            ..
        }
    ));
    // The last heartbeat came in the tick before `gcs_until`'s second: lost 1 s later.
    assert!(
        lost[0].0 <= takeoff + 2 * SECOND + 2,
        "seen at {}",
        lost[0].0
    );
    assert!(phases(&seen.run).contains(&Phase::Flying(FlightPhase::Hover)));
    assert_eq!(
        landing_reason(&seen.run).map(|(_, r)| r),
        Some(Reason::PlanAdvanced)
    );
    assert_eq!(seen.run.mission.phase(), Phase::Disarmed);
    assert_eq!(seen.run.mission.abort_reason(), None);
}

#[test]
fn a_link_lost_in_flight_with_hold_holds_then_lands_in_place() {
    let s = straight_up_scenario(3.5);
    let takeoff = takeoff_tick(&s);
    let mut world = World::new(&s);
    world.gcs_until = takeoff + 3 * SECOND;
    let seen = fly(
        &s,
        config(GcsLossAction::HoldThenLand, 2.0),
        &mut world,
        |_, _| {},
    );
    let (seen_at, notice) = *seen
        .notices
        .iter()
        .find(|(_, n)| matches!(n, Notice::LinkLost { .. }))
        .expect("a lost-link notice");
    assert!(
        matches!(notice, Notice::LinkLost { silent, response: LinkResponse::Hold(t) }
            if (silent - 1.0025).abs() < 1e-4 && t == 2.0),
        "{notice:?}"
    );
    let (landing_at, reason) = landing_reason(&seen.run).expect("a landing");
    assert_eq!(reason, Reason::Abort(AbortReason::GcsLost));
    let held = landing_at - seen_at;
    assert!(
        (2 * SECOND - 1..=2 * SECOND + 1).contains(&held),
        "held {held} ticks"
    );
    // Held at its height (the world is vertical: the hover's 0.5 m).
    let during = &seen.heights[(seen_at + SECOND / 2) as usize..landing_at as usize];
    let (lo, hi) = during
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), &h| (lo.min(h), hi.max(h)));
    assert!(hi - lo < 0.05 && lo > 0.3, "held between {lo} and {hi} m");
    assert_eq!(
        seen.run.mission.phase(),
        Phase::Disarmed,
        "landed, not dropped"
    );
    assert_eq!(seen.run.mission.abort_reason(), Some(AbortReason::GcsLost));
}

#[test]
fn a_link_back_during_the_hold_resumes_the_plan() {
    let s = straight_up_scenario(3.5);
    let takeoff = takeoff_tick(&s);
    let mut world = World::new(&s);
    world.gcs_until = takeoff + 3 * SECOND;
    let back = takeoff + 5 * SECOND;
    let seen = fly(
        &s,
        config(GcsLossAction::HoldThenLand, 10.0),
        &mut world,
        |tick, w| {
            if tick == back {
                w.gcs_until = u64::MAX;
            }
        },
    );
    assert!(
        seen.notices
            .iter()
            .any(|(_, n)| *n == Notice::LinkRegained { resumed: true }),
        "{:?}",
        seen.notices
    );
    assert_eq!(
        landing_reason(&seen.run).map(|(_, r)| r),
        Some(Reason::PlanAdvanced)
    );
    assert_eq!(seen.run.mission.abort_reason(), None);
    assert_eq!(seen.run.mission.phase(), Phase::Disarmed);
}

#[test]
fn a_low_battery_refuses_the_start_and_stops_the_mission_on_the_ground() {
    let s = straight_up_scenario(3.5);
    let mut world = World::new(&s);
    world.battery = Some(13.5);
    let seen = fly(&s, MissionConfig::default(), &mut world, |_, _| {});
    assert_eq!(
        seen.run.replies.first().map(|(_, r)| r.outcome),
        Some(Err(CommandRefusal::BatteryLow { millivolts: 13_500 }))
    );
    assert_eq!(seen.run.mission.phase(), Phase::Idle);
    // Said once, in idle.
    assert_eq!(seen.notices.len(), 1, "{:?}", seen.notices);
    // Falling after the start, on the ground: stopped.
    let mut world = World::new(&s);
    world.battery = Some(16.0);
    let seen = fly(&s, MissionConfig::default(), &mut world, |tick, w| {
        if tick == 2 * SECOND {
            w.battery = Some(13.5);
        }
    });
    assert!(matches!(
        seen.run.mission.abort_reason(),
        Some(AbortReason::BatteryLow { volts }) if volts < 14.0 && volts > 13.5
    ));
    assert!(!phases(&seen.run).contains(&Phase::Arming), "never armed");
}

#[test]
fn a_low_battery_in_flight_warns_and_the_flight_goes_on() {
    let s = straight_up_scenario(3.5);
    let takeoff = takeoff_tick(&s);
    let mut world = World::new(&s);
    world.battery = Some(16.0);
    let seen = fly(&s, MissionConfig::default(), &mut world, |tick, w| {
        if tick == takeoff + SECOND {
            w.battery = Some(13.8);
        }
    });
    let warned: Vec<_> = seen.notices.iter().collect();
    assert_eq!(warned.len(), 1, "{warned:?}");
    assert!(matches!(warned[0].1, Notice::BatteryLow { threshold, .. } if threshold == 14.0));
    // 16 V to 13.8 V crosses 14 V after ln(2.2 / 0.2) = 2.4 filter time constants.
    let after = (warned[0].0 - takeoff - SECOND) as f32 / SECOND as f32;
    assert!((after - 2.4).abs() < 0.1, "warned {after} s after the drop");
    assert_eq!(seen.run.mission.phase(), Phase::Disarmed);
    assert_eq!(seen.run.mission.abort_reason(), None);
}

#[test]
fn a_critical_battery_in_flight_lands_in_place() {
    let s = straight_up_scenario(3.5);
    let takeoff = takeoff_tick(&s);
    let mut world = World::new(&s);
    world.battery = Some(16.0);
    let drop = takeoff + 3 * SECOND;
    let seen = fly(
        &s,
        config(GcsLossAction::HoldThenLand, 10.0),
        &mut world,
        |tick, w| {
            if tick == drop {
                w.battery = Some(12.0);
            }
        },
    );
    let (landing_at, reason) = landing_reason(&seen.run).expect("a landing");
    assert!(
        matches!(reason, Reason::Abort(AbortReason::BatteryCritical { volts }) if volts < 13.2),
        "{reason:?}"
    );
    // Below 13.2 V 1.2 filter time constants after the drop (the low warning before it).
    let after = (landing_at - drop) as f32 / SECOND as f32;
    assert!(
        (after - 1.2).abs() < 0.05,
        "landing {after} s after the drop"
    );
    assert!(matches!(seen.notices[0].1, Notice::BatteryLow { .. }));
    assert_eq!(
        seen.run.mission.phase(),
        Phase::Disarmed,
        "landed, not dropped"
    );
    assert!(matches!(
        seen.run.mission.abort_reason(),
        Some(AbortReason::BatteryCritical { .. })
    ));
}
