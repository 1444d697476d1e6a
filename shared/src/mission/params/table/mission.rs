//! The mission's parameters on the ground: the estimation and the lift-off's detection, the
//! rail's limits, the mission's timing and limits.

use super::*;

/// Estimation and lift-off detection.
pub(super) const ESTIMATION: &[ParamSpec] = &[
    ParamSpec {
        name: "LIFT_SIGMA",
        unit: "N",
        min: 0.0,
        max: 5.0,
        integer: false,
        allowed: &[],
        #[cfg(feature = "docs")]
        doc: "standard deviation of a lift reading (estimator noise model); 0: the scenario's noise_sigma",
        get: |c| c.lift_noise_sigma.unwrap_or(0.0),
        set: |c, v| c.lift_noise_sigma = (v > 0.0).then_some(v),
    },
    param!(
        "LIFT_RAMP",
        "N/s",
        0.05,
        10.0,
        "thrust ramp of each robot of the lifting pair",
        |c| c.liftoff.ramp_rate
    ),
    param!(
        "LIFT_TILT",
        "rad",
        0.002,
        0.1,
        "tilt from the resting attitude that counts as lift-off",
        |c| c.liftoff.tilt_threshold
    ),
    param!(
        "LIFT_DELAY",
        "s",
        0.0,
        0.1,
        "attitude-estimate latency compensated at lift-off",
        |c| c.liftoff.detection_delay
    ),
    param!(
        "LIFT_ONSET",
        "-",
        0.05,
        0.95,
        "share of the tilt threshold below which the tilt has not started",
        |c| c.liftoff.onset_fraction
    ),
    param!(
        "LIFT_SETTLE",
        "s",
        0.1,
        5.0,
        "hold at the start and at maximum thrust of a lift",
        |c| c.liftoff.settle_time
    ),
    param!(
        whole "MIS_CONFIRM",
        "-",
        1.0,
        5.0,
        "consecutive lifts the stopping rule must hold for (1: the paper's rule)",
        |c| c.confirmations
    ),
];

/// Rail.
pub(super) const RAIL: &[ParamSpec] = &[
    param!(
        "RAIL_SPEED",
        "m/s",
        0.01,
        1.0,
        "largest speed of a robot along the rail",
        |c| c.rail_limits.max_speed
    ),
    param!(
        "RAIL_ACCEL",
        "m/s^2",
        0.05,
        5.0,
        "largest acceleration of a robot along the rail",
        |c| c.rail_limits.max_acceleration
    ),
];

/// Mission timing and limits.
pub(super) const TIMING: &[ParamSpec] = &[
    param!(
        "MIS_HOVER_MAX",
        "-",
        0.2,
        0.95,
        "largest share of total thrust the heaviest plausible payload may need to hover",
        |c| c.max_hover_fraction
    ),
    param!(
        "MIS_CHECKS_T",
        "s",
        1.0,
        60.0,
        "time on the ground, rotors off, before the estimation",
        |c| c.checks_time
    ),
    param!(
        "MIS_RELAX_T",
        "s",
        0.2,
        30.0,
        "time after each lift: the set-down, then rotors off",
        |c| c.relax_time
    ),
    param!(
        "MIS_ARM_T",
        "s",
        0.2,
        10.0,
        "time armed on the ground before take-off",
        |c| c.arm_time
    ),
    ParamSpec {
        name: "MIS_MIXER",
        unit: "-",
        min: 0.0,
        max: 1.0,
        integer: true,
        allowed: &[],
        #[cfg(feature = "docs")]
        doc: "flight mixer: 0 the paper's equal split, 1 full allocation",
        get: |c| match c.mixer {
            MixerKind::EqualSplit => 0.0,
            MixerKind::Allocation => 1.0,
        },
        set: |c, v| {
            c.mixer = if v >= 0.5 {
                MixerKind::Allocation
            } else {
                MixerKind::EqualSplit
            }
        },
    },
];
