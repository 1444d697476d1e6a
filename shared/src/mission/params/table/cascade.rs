//! The cascade's parameters (shared::control::params): the position, velocity, attitude and
//! rate controllers' gains and limits, one parameter per axis.

use super::*;

/// The cascade (shared::control::params), one parameter per axis.
pub(super) const CASCADE: &[ParamSpec] = &[
    param!(
        "POS_P_X",
        "1/s",
        0.1,
        5.0,
        "position error to velocity, x",
        |c| c.flight.control.position_p.x
    ),
    param!(
        "POS_P_Y",
        "1/s",
        0.1,
        5.0,
        "position error to velocity, y",
        |c| c.flight.control.position_p.y
    ),
    param!(
        "POS_P_Z",
        "1/s",
        0.1,
        5.0,
        "position error to velocity, z",
        |c| c.flight.control.position_p.z
    ),
    param!(
        "VEL_P_X",
        "1/s",
        0.1,
        10.0,
        "velocity error to acceleration, x",
        |c| c.flight.control.velocity_p.x
    ),
    param!(
        "VEL_P_Y",
        "1/s",
        0.1,
        10.0,
        "velocity error to acceleration, y",
        |c| c.flight.control.velocity_p.y
    ),
    param!(
        "VEL_P_Z",
        "1/s",
        0.1,
        10.0,
        "velocity error to acceleration, z",
        |c| c.flight.control.velocity_p.z
    ),
    param!(
        "VEL_I_X",
        "1/s^2",
        0.0,
        5.0,
        "velocity integral gain, x",
        |c| c.flight.control.velocity_i.x
    ),
    param!(
        "VEL_I_Y",
        "1/s^2",
        0.0,
        5.0,
        "velocity integral gain, y",
        |c| c.flight.control.velocity_i.y
    ),
    param!(
        "VEL_I_Z",
        "1/s^2",
        0.0,
        5.0,
        "velocity integral gain, z",
        |c| c.flight.control.velocity_i.z
    ),
    param!(
        "VEL_D_X",
        "-",
        0.0,
        2.0,
        "velocity derivative gain, x",
        |c| c.flight.control.velocity_d.x
    ),
    param!(
        "VEL_D_Y",
        "-",
        0.0,
        2.0,
        "velocity derivative gain, y",
        |c| c.flight.control.velocity_d.y
    ),
    param!(
        "VEL_D_Z",
        "-",
        0.0,
        2.0,
        "velocity derivative gain, z",
        |c| c.flight.control.velocity_d.z
    ),
    param!(
        "VEL_ILIM_X",
        "m/s^2",
        0.0,
        8.0,
        "largest velocity integral, x",
        |c| c.flight.control.velocity_integral_limit.x
    ),
    param!(
        "VEL_ILIM_Y",
        "m/s^2",
        0.0,
        8.0,
        "largest velocity integral, y",
        |c| c.flight.control.velocity_integral_limit.y
    ),
    param!(
        "VEL_ILIM_Z",
        "m/s^2",
        0.0,
        8.0,
        "largest velocity integral, z",
        |c| c.flight.control.velocity_integral_limit.z
    ),
    param!(
        "ATT_P_R",
        "1/s",
        0.1,
        30.0,
        "attitude error to body rate, roll",
        |c| c.flight.control.attitude_p.x
    ),
    param!(
        "ATT_P_P",
        "1/s",
        0.1,
        30.0,
        "attitude error to body rate, pitch",
        |c| c.flight.control.attitude_p.y
    ),
    param!(
        "ATT_P_Y",
        "1/s",
        0.1,
        30.0,
        "attitude error to body rate, yaw",
        |c| c.flight.control.attitude_p.z
    ),
    param!(
        "RATE_MAX_R",
        "rad/s",
        0.1,
        6.0,
        "largest body-rate setpoint, roll",
        |c| c.flight.control.max_rate.x
    ),
    param!(
        "RATE_MAX_P",
        "rad/s",
        0.1,
        6.0,
        "largest body-rate setpoint, pitch",
        |c| c.flight.control.max_rate.y
    ),
    param!(
        "RATE_MAX_Y",
        "rad/s",
        0.1,
        6.0,
        "largest body-rate setpoint, yaw",
        |c| c.flight.control.max_rate.z
    ),
    param!(
        "RATE_P_R",
        "1/s",
        0.1,
        100.0,
        "rate error to angular acceleration, roll",
        |c| c.flight.control.rate_p.x
    ),
    param!(
        "RATE_P_P",
        "1/s",
        0.1,
        100.0,
        "rate error to angular acceleration, pitch",
        |c| c.flight.control.rate_p.y
    ),
    param!(
        "RATE_P_Y",
        "1/s",
        0.1,
        100.0,
        "rate error to angular acceleration, yaw",
        |c| c.flight.control.rate_p.z
    ),
    param!(
        "RATE_I_R",
        "1/s^2",
        0.0,
        200.0,
        "rate integral gain, roll",
        |c| c.flight.control.rate_i.x
    ),
    param!(
        "RATE_I_P",
        "1/s^2",
        0.0,
        200.0,
        "rate integral gain, pitch",
        |c| c.flight.control.rate_i.y
    ),
    param!(
        "RATE_I_Y",
        "1/s^2",
        0.0,
        200.0,
        "rate integral gain, yaw",
        |c| c.flight.control.rate_i.z
    ),
    param!(
        "RATE_D_R",
        "-",
        0.0,
        2.0,
        "rate derivative gain, roll",
        |c| c.flight.control.rate_d.x
    ),
    param!(
        "RATE_D_P",
        "-",
        0.0,
        2.0,
        "rate derivative gain, pitch",
        |c| c.flight.control.rate_d.y
    ),
    param!(
        "RATE_D_Y",
        "-",
        0.0,
        2.0,
        "rate derivative gain, yaw",
        |c| c.flight.control.rate_d.z
    ),
    param!(
        "RATE_ILIM_R",
        "rad/s^2",
        0.0,
        40.0,
        "largest rate integral, roll",
        |c| c.flight.control.rate_integral_limit.x
    ),
    param!(
        "RATE_ILIM_P",
        "rad/s^2",
        0.0,
        40.0,
        "largest rate integral, pitch",
        |c| c.flight.control.rate_integral_limit.y
    ),
    param!(
        "RATE_ILIM_Y",
        "rad/s^2",
        0.0,
        40.0,
        "largest rate integral, yaw",
        |c| c.flight.control.rate_integral_limit.z
    ),
    param!(
        "RATE_ACC_R",
        "rad/s^2",
        0.5,
        200.0,
        "largest angular acceleration command, roll",
        |c| c.flight.control.max_angular_acceleration.x
    ),
    param!(
        "RATE_ACC_P",
        "rad/s^2",
        0.5,
        200.0,
        "largest angular acceleration command, pitch",
        |c| c.flight.control.max_angular_acceleration.y
    ),
    param!(
        "RATE_ACC_Y",
        "rad/s^2",
        0.5,
        200.0,
        "largest angular acceleration command, yaw",
        |c| c.flight.control.max_angular_acceleration.z
    ),
    param!(
        "POS_SPD_XY",
        "m/s",
        0.1,
        5.0,
        "largest horizontal velocity setpoint",
        |c| c.flight.control.max_speed_xy
    ),
    param!(
        "POS_SPD_Z",
        "m/s",
        0.1,
        3.0,
        "largest vertical velocity setpoint",
        |c| c.flight.control.max_speed_z
    ),
    param!(
        "VEL_D_CUT",
        "Hz",
        1.0,
        100.0,
        "cut-off of the velocity derivative low-pass",
        |c| c.flight.control.velocity_d_cutoff_hz
    ),
    param!(
        "MAX_TILT",
        "rad",
        0.05,
        0.7,
        "largest tilt of the thrust vector from vertical",
        |c| c.flight.control.max_tilt
    ),
    param!(
        "RATE_D_CUT",
        "Hz",
        1.0,
        150.0,
        "cut-off of the rate derivative low-pass",
        |c| c.flight.control.rate_d_cutoff_hz
    ),
    param!(
        "MAX_COLLECTIVE",
        "-",
        0.3,
        0.98,
        "largest collective thrust, share of the rotors' total",
        |c| c.flight.control.max_collective_fraction
    ),
];
