//! The vehicle's hardware as parameters: the drivers (ESCs, thrust map, steppers), the IMU's
//! calibration and the motor test.

use super::*;

/// The drivers (mission::hardware): ESCs, thrust map, steppers.
pub(super) const DRIVERS: &[ParamSpec] = &[
    param!(
        whole "ESC_PROTOCOL",
        "-",
        0.0,
        (crate::mission::esc_protocol::EscProtocol::ALL.len() - 1) as f32,
        "ESC protocol: 0 DShot600, 1 PWM, 2 OneShot125 on the FMU outputs; 3 DroneCAN ESCs on CAN1 (taken while disarmed)",
        |c| c.hardware.esc_protocol
    ),
    param!(
        whole "UAVCAN_NODE_ID",
        "-",
        1.0,
        125.0,
        "this flight controller's DroneCAN node ID on the ESCs' bus (PX4's name; taken while disarmed)",
        |c| c.hardware.can_node_id
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
];

/// The IMU's calibration and the motor test (mission::bringup), PX4's names.
pub(super) const BRING_UP: &[ParamSpec] = &[
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
