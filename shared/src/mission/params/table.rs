//! The parameter table: every tunable's name, unit, range, default and where it lives in the
//! [`MissionConfig`], in the order the protocol numbers them.

use super::*;

/// Every parameter, in the order the protocol numbers them (`param_index`).
pub static TABLE: [ParamSpec; COUNT] = [
    // Estimation and lift-off detection.
    ParamSpec {
        name: "LIFT_SIGMA",
        unit: "N",
        min: 0.0,
        max: 5.0,
        integer: false,
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
    // Rail.
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
    // Mission timing and limits.
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
        "time with rotors off after each lift",
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
    // Flight failsafes.
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
    // Flight plan.
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
    // The cascade (shared::control::params), one parameter per axis.
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
    // In-flight adaptation to a load that shifts (flight::adapt).
    ParamSpec {
        name: "ADPT_ENABLE",
        unit: "-",
        min: 0.0,
        max: 1.0,
        integer: true,
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
    // The drivers (mission::hardware): ESCs, thrust map, steppers.
    param!(
        whole "ESC_PROTOCOL",
        "-",
        0.0,
        2.0,
        "ESC protocol on the FMU outputs: 0 DShot600, 1 PWM, 2 OneShot125 (taken while disarmed)",
        |c| c.hardware.esc_protocol
    ),
    param!(
        "THR_MAP_20",
        "-",
        0.001,
        0.999,
        "thrust at 20 % ESC command, fraction of full thrust (a bench calibration; rising with the command)",
        |c| c.hardware.thrust_map[0]
    ),
    param!(
        "THR_MAP_40",
        "-",
        0.001,
        0.999,
        "thrust at 40 % ESC command, fraction of full thrust",
        |c| c.hardware.thrust_map[1]
    ),
    param!(
        "THR_MAP_60",
        "-",
        0.001,
        0.999,
        "thrust at 60 % ESC command, fraction of full thrust",
        |c| c.hardware.thrust_map[2]
    ),
    param!(
        "THR_MAP_80",
        "-",
        0.001,
        0.999,
        "thrust at 80 % ESC command, fraction of full thrust",
        |c| c.hardware.thrust_map[3]
    ),
    param!(
        whole "STP_STEPS_REV",
        "-",
        24.0,
        400.0,
        "full steps per stepper revolution (200 for 1.8 deg motors)",
        |c| c.hardware.drive.steps_per_rev
    ),
    param!(
        whole "STP_MICROSTEPS",
        "-",
        1.0,
        256.0,
        "microsteps per full step set in the TMC2209s (a power of two)",
        |c| c.hardware.drive.microsteps
    ),
    param!(
        "STP_PINION_D",
        "m",
        0.005,
        0.1,
        "pitch diameter of the robots' pinions",
        |c| c.hardware.drive.pinion_pitch_diameter
    ),
    param!(
        "STP_CURRENT",
        "A",
        0.1,
        2.0,
        "stepper motor current, RMS",
        |c| c.hardware.stepper_current
    ),
    param!(
        "STP_RSENSE",
        "ohm",
        0.05,
        0.5,
        "sense resistors of the TMC2209 boards",
        |c| c.hardware.stepper_r_sense
    ),
    param!(
        whole "STP_SGTHRS",
        "-",
        0.0,
        255.0,
        "StallGuard threshold (SGTHRS): stalled when SG_RESULT <= 2x this at speed; 0 off (tune on the bench)",
        |c| c.hardware.stall_threshold
    ),
    // The ground link's and the battery's failsafes (mission::supervision).
    ParamSpec {
        name: "FS_GCS_ACT",
        unit: "-",
        min: 0.0,
        max: 2.0,
        integer: true,
        #[cfg(feature = "docs")]
        doc: "ground link lost in flight: 0 not watched (no start refused), 1 fly on to the target and land, 2 hold FS_GCS_HOLD_T then land in place",
        get: |c| c.supervision.gcs_action as u8 as f32,
        set: |c, v| c.supervision.gcs_action = GcsLossAction::from_value(v),
    },
    param!(
        "FS_GCS_LOSS_T",
        "s",
        1.0,
        60.0,
        "time without a ground station's heartbeat before the link counts as lost (PX4's COM_DL_LOSS_T)",
        |c| c.supervision.gcs_timeout
    ),
    param!(
        "FS_GCS_HOLD_T",
        "s",
        0.0,
        300.0,
        "with FS_GCS_ACT 2: time held where the vehicle is before it lands in place (a link back meanwhile resumes the plan)",
        |c| c.supervision.gcs_hold_time
    ),
    param!(
        "BAT_LOW_V",
        "V",
        0.0,
        100.0,
        "filtered pack voltage below which the battery is low: a warning, and no start; 0 off",
        |c| c.supervision.battery_low
    ),
    param!(
        "BAT_CRIT_V",
        "V",
        0.0,
        100.0,
        "filtered pack voltage below which the battery is critical: landing in place (stop on the ground); 0 off",
        |c| c.supervision.battery_critical
    ),
    // The map origin: the ground link's (a ground station's map), no field of the
    // configuration. Degrees split in a whole part and a part in 1e-7 degrees, each exact as a
    // REAL32 (one float of degrees rounds to 1.7 m); docs/ground-link.md#the-map-origin.
    param!(
        link "ORIG_LAT_DEG",
        "deg",
        -90.0,
        90.0,
        47.0,
        "map origin's latitude (the local frame's origin), whole degrees; plus ORIG_LAT_E7 (default: PX4's simulation home)"
    ),
    param!(
        link "ORIG_LAT_E7",
        "1e-7 deg",
        -9_999_999.0,
        9_999_999.0,
        3_977_420.0,
        "map origin's latitude past ORIG_LAT_DEG, 1e-7 degrees (the same sign)"
    ),
    param!(
        link "ORIG_LON_DEG",
        "deg",
        -180.0,
        180.0,
        8.0,
        "map origin's longitude, whole degrees (east positive); plus ORIG_LON_E7"
    ),
    param!(
        link "ORIG_LON_E7",
        "1e-7 deg",
        -9_999_999.0,
        9_999_999.0,
        5_455_940.0,
        "map origin's longitude past ORIG_LON_DEG, 1e-7 degrees (the same sign)"
    ),
    ParamSpec {
        name: "ORIG_ALT",
        unit: "m",
        min: -1_000.0,
        max: 10_000.0,
        integer: false,
        #[cfg(feature = "docs")]
        doc: "map origin's altitude above mean sea level",
        get: |_| ORIGIN_DEFAULT_ALT,
        set: |_, _| {},
    },
    // The IMU's calibration and the motor test (mission::bringup), PX4's names.
    param!(
        "CAL_GYRO0_XOFF",
        "rad/s",
        -0.35,
        0.35,
        "gyro offset on x, taken off every sample (MAV_CMD_PREFLIGHT_CALIBRATION param1 1 measures it at rest)",
        |c| c.sensors.gyro[0]
    ),
    param!(
        "CAL_GYRO0_YOFF",
        "rad/s",
        -0.35,
        0.35,
        "gyro offset on y, taken off every sample (MAV_CMD_PREFLIGHT_CALIBRATION param1 1 measures it at rest)",
        |c| c.sensors.gyro[1]
    ),
    param!(
        "CAL_GYRO0_ZOFF",
        "rad/s",
        -0.35,
        0.35,
        "gyro offset on z, taken off every sample (MAV_CMD_PREFLIGHT_CALIBRATION param1 1 measures it at rest)",
        |c| c.sensors.gyro[2]
    ),
    param!(
        "CAL_ACC0_XOFF",
        "m/s^2",
        -2.0,
        2.0,
        "accelerometer offset on x, taken off every sample (the level calibration, param5 2, measures it level at rest)",
        |c| c.sensors.accel[0]
    ),
    param!(
        "CAL_ACC0_YOFF",
        "m/s^2",
        -2.0,
        2.0,
        "accelerometer offset on y, taken off every sample (the level calibration, param5 2, measures it level at rest)",
        |c| c.sensors.accel[1]
    ),
    param!(
        "CAL_ACC0_ZOFF",
        "m/s^2",
        -2.0,
        2.0,
        "accelerometer offset on z, taken off every sample (the level calibration, param5 2, measures it level at rest)",
        |c| c.sensors.accel[2]
    ),
    param!(
        flag "COM_MOT_TEST_EN",
        "motor tests (MAV_CMD_DO_MOTOR_TEST) allowed: 1 yes, 0 refused",
        |c| c.hardware.motor_test_enabled
    ),
    param!(
        flag "DSHOT_BIDIR_EN",
        "bidirectional DShot: each ESC answers with its RPM, which the rotor monitor reads (1 on; BLHeli_32, AM32 or Bluejay ESCs; taken while disarmed)",
        |c| c.hardware.dshot_bidirectional
    ),
    param!(
        whole "MOT_POLE_COUNT",
        "-",
        2.0,
        64.0,
        "the motors' magnet poles (RPM is the ESC's electrical RPM over half of them)",
        |c| c.hardware.motor_poles
    ),
];
