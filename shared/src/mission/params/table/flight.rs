//! The flight's parameters, but for the cascade's: the failsafes, the flight plan, and the
//! adaptation to a load that shifts in flight.

use super::*;

/// Flight failsafes.
pub(super) const FLIGHT_FAILSAFES: &[ParamSpec] = &[
    param!(
        "FS_TAKEOFF_T",
        "s",
        0.5,
        20.0,
        "time at take-off thrust on the ground before the take-off counts as failed",
        |c| c.flight.takeoff_timeout
    ),
    param!(
        "FS_ARRIVE_TOL",
        "m",
        0.02,
        1.0,
        "distance from a segment's end within which the vehicle has arrived",
        |c| c.flight.arrival_tolerance
    ),
    param!(
        "FS_ARRIVE_T",
        "s",
        1.0,
        120.0,
        "time past a segment's end without arriving before landing where it is",
        |c| c.flight.arrival_timeout
    ),
    param!(
        "FS_TOUCHDOWN_T",
        "s",
        0.5,
        30.0,
        "time after the plan's end near the ground before the rotors stop",
        |c| c.flight.touchdown_timeout
    ),
    param!(
        "FS_DESCENT_MRG",
        "s",
        0.0,
        10.0,
        "margin past the expected touchdown of a blind descent",
        |c| c.flight.failsafe_margin
    ),
];

/// Flight plan.
pub(super) const FLIGHT_PLAN: &[ParamSpec] = &[
    param!("PLN_CLIMB_SPD", "m/s", 0.05, 2.0, "peak climb speed", |c| c
        .flight
        .plan
        .climb_speed),
    param!(
        "PLN_CRUISE_SPD",
        "m/s",
        0.05,
        3.0,
        "peak horizontal speed",
        |c| c.flight.plan.cruise_speed
    ),
    param!(
        "PLN_DESC_SPD",
        "m/s",
        0.05,
        1.0,
        "peak descent speed",
        |c| c.flight.plan.descent_speed
    ),
    param!(
        "PLN_HOVER_T",
        "s",
        0.0,
        60.0,
        "time over the target before landing",
        |c| c.flight.plan.hover_time
    ),
];

/// In-flight adaptation to a load that shifts (flight::adapt).
pub(super) const ADAPTATION: &[ParamSpec] = &[
    ParamSpec {
        name: "ADPT_ENABLE",
        unit: "-",
        min: 0.0,
        max: 1.0,
        integer: true,
        allowed: &[],
        #[cfg(feature = "docs")]
        doc: "re-form in flight when the measured COM moves: 1 on, 0 off",
        get: |c| if c.adapt.enabled { 1.0 } else { 0.0 },
        set: |c, v| c.adapt.enabled = v >= 0.5,
    },
    param!(
        "ADPT_THRESH",
        "m",
        0.02,
        0.5,
        "COM distance from the formation's that calls for a new formation",
        |c| c.adapt.threshold
    ),
    param!(
        "ADPT_HOLD",
        "s",
        0.1,
        10.0,
        "time a confident shift must last before the robots move",
        |c| c.adapt.hold
    ),
    param!(
        "ADPT_MAX_HOLD",
        "s",
        1.0,
        120.0,
        "longest the hover is held for one adaptation",
        |c| c.adapt.max_hold
    ),
    param!(
        "ADPT_RAIL_SPD",
        "m/s",
        0.01,
        0.5,
        "rail speed of the robots in flight",
        |c| c.adapt.rail.max_speed
    ),
    param!(
        "ADPT_RAIL_ACC",
        "m/s^2",
        0.01,
        1.0,
        "rail acceleration of the robots in flight",
        |c| c.adapt.rail.max_acceleration
    ),
    param!(
        "ADPT_TRIM_WIN",
        "s",
        0.5,
        10.0,
        "averaging window of the in-flight COM trim",
        |c| c.adapt.trim.window
    ),
    param!(
        "ADPT_TRIM_STDY",
        "m",
        0.005,
        0.2,
        "largest difference of the window's halves for a steady trim",
        |c| c.adapt.trim.steadiness
    ),
];
