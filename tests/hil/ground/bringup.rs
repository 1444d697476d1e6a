//! The bring-up commands with a real ground-station client: runs `tests/bringup.py`
//! (pymavlink) against the firmware under QEMU through `host-sim hil --gcs
//! --unconfirmed-rails --gyro-bias ...`: the rails confirmed (a start refused before), a robot
//! jogged and a jog too far refused, the gyro and level calibrations (the offsets found against
//! the plant's gyro bias, kept as parameters), the motor test (ACTUATOR_OUTPUT_STATUS and
//! SERVO_OUTPUT_RAW, its timeout, stopped by another command, switched off by
//! COM_MOT_TEST_EN), a reboot on the ground the firmware comes back from, and each of them
//! refused while the mission runs. What it checks is listed at the top of the script.
//!
//! Needs `python3` with `pymavlink` and `qemu-system-arm`; it builds the firmware's QEMU
//! image itself. Without one of them the test says it was skipped and why, and passes; with
//! `HIL_REQUIRED=1` (CI, which installs them) it fails instead.
//!
//! The flags' own checks need neither.

use crate::common;

#[test]
fn the_bring_up_commands_confirm_jog_calibrate_test_the_motors_and_reboot() {
    common::python_check("bring-up", "tests/bringup.py");
}

#[test]
fn a_gyro_bias_that_is_not_three_numbers_within_half_a_radian_per_second_is_refused() {
    let scenario = common::scenario_path("rect-ex1");
    let scenario = scenario.to_str().expect("a UTF-8 path");
    // Not three numbers: a usage error (2); out of range: bad input (1), one line naming the
    // flag, as every command's ranges (docs/commands.md).
    for (bad, code, says) in [
        ("0.02,-0.015", 2, "expected 3 comma-separated numbers"),
        ("0.01,x,0", 2, "`x` is not a number"),
        ("nan,0,0", 2, "not a finite number"),
        (
            "0.6,0,0",
            1,
            "--gyro-bias 0.6: must be a finite number from -0.5 to 0.5",
        ),
        (
            "0,0,-0.51",
            1,
            "--gyro-bias -0.51: must be a finite number from -0.5",
        ),
    ] {
        let flag = format!("--gyro-bias={bad}");
        let out = common::host_sim(&["hil", "--scenario", scenario, "--qemu", "x.elf", &flag]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{flag}: {stderr}");
        assert!(
            stderr.contains("--gyro-bias") && stderr.contains(says),
            "{flag}: {stderr}"
        );
    }
}
