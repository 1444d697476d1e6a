//! Manual control's parameters (docs/manual-control.md), PX4's names and numbers: the
//! source, its loss and what the vehicle does then, the kill switch, the mode switch's slots,
//! Position mode's speeds, and the RC receiver's port, protocol and channels.

use super::*;
use crate::manual::source::InputMode;
use crate::manual::{ManualLossAction, PilotMode};

/// A mode-switch slot's parameter: PX4's mode numbers; -1 and modes this vehicle does not fly
/// leave the slot unassigned.
macro_rules! flight_mode {
    ($name:literal, $slot:literal) => {
        ParamSpec {
            name: $name,
            unit: "-",
            min: -1.0,
            max: 11.0,
            integer: true,
            allowed: &[-1.0, 2.0, 3.0, 4.0, 11.0],
            #[cfg(feature = "docs")]
            doc: concat!(
                "the mode switch's slot ",
                $slot,
                ": -1 unassigned, 2 Position, 3 Mission, 4 Hold, 11 Land (PX4's numbers)"
            ),
            get: |c| c.manual.flight_modes[$slot - 1].map_or(-1.0, PilotMode::param_value),
            set: |c, v| c.manual.flight_modes[$slot - 1] = PilotMode::from_param(v),
        }
    };
}

/// The manual control group.
pub(super) const MANUAL_CONTROL: &[ParamSpec] = &[
    ParamSpec {
        name: "COM_RC_IN_MODE",
        unit: "-",
        min: 0.0,
        max: 4.0,
        integer: true,
        allowed: &[],
        #[cfg(feature = "docs")]
        doc: "manual control's source: 0 RC only (no start without it), 1 joystick (MANUAL_CONTROL) only, 2 RC, the joystick while RC is silent, 3 the first valid kept, 4 none",
        get: |c| c.manual.input_mode as u8 as f32,
        set: |c, v| c.manual.input_mode = InputMode::from_param(v).unwrap_or(InputMode::KeepFirst),
    },
    param!(
        "COM_RC_LOSS_T",
        "s",
        0.1,
        35.0,
        "time without a valid RC frame or MANUAL_CONTROL before manual control counts as lost",
        |c| c.manual.loss_time
    ),
    param!(
        "COM_KILL_DISARM",
        "s",
        0.0,
        30.0,
        "time the kill switch keeps the vehicle armed with its rotors off (switched back within it, the rotors come back), then it disarms",
        |c| c.manual.kill_disarm_time
    ),
    ParamSpec {
        name: "NAV_RCL_ACT",
        unit: "-",
        min: 1.0,
        max: 5.0,
        integer: true,
        allowed: &[1.0, 3.0, 5.0],
        #[cfg(feature = "docs")]
        doc: "manual control lost in Position mode, after holding COM_FAIL_ACT_T: 1 hold, 3 land in place, 5 stop the rotors (PX4's numbers; no Return: no home to return to)",
        get: |c| match c.manual.loss_action {
            ManualLossAction::Hold => 1.0,
            ManualLossAction::Land => 3.0,
            ManualLossAction::Terminate => 5.0,
        },
        set: |c, v| {
            c.manual.loss_action = ManualLossAction::from_param(v).unwrap_or(ManualLossAction::Land)
        },
    },
    param!(
        "COM_FAIL_ACT_T",
        "s",
        0.0,
        25.0,
        "time held where the vehicle is after manual control is lost in Position mode, before NAV_RCL_ACT (the sticks back meanwhile steer again)",
        |c| c.manual.failsafe_delay
    ),
    flight_mode!("COM_FLTMODE1", 1),
    flight_mode!("COM_FLTMODE2", 2),
    flight_mode!("COM_FLTMODE3", 3),
    flight_mode!("COM_FLTMODE4", 4),
    flight_mode!("COM_FLTMODE5", 5),
    flight_mode!("COM_FLTMODE6", 6),
    param!(
        "MPC_VEL_MANUAL",
        "m/s",
        0.05,
        2.0,
        "Position mode: horizontal speed at full stick",
        |c| c.manual.limits.horizontal_speed
    ),
    param!(
        "MPC_Z_VEL_MAX_UP",
        "m/s",
        0.05,
        1.0,
        "Position mode: climb rate at full throttle",
        |c| c.manual.limits.climb_speed
    ),
    param!(
        "MPC_Z_VEL_MAX_DN",
        "m/s",
        0.05,
        1.0,
        "Position mode: descent rate at zero throttle",
        |c| c.manual.limits.descent_speed
    ),
    ParamSpec {
        name: "MPC_MAN_Y_MAX",
        unit: "deg/s",
        min: 0.0,
        max: 90.0,
        integer: false,
        allowed: &[],
        #[cfg(feature = "docs")]
        doc: "Position mode: yaw rate at full stick",
        get: |c| c.manual.limits.yaw_rate,
        set: |c, v| c.manual.limits.yaw_rate = v,
    },
    param!(
        "MPC_HOLD_DZ",
        "-",
        0.0,
        0.5,
        "Position mode: stick travel about the centre (of full travel) that counts as centred",
        |c| c.manual.limits.dead_zone
    ),
    ParamSpec {
        name: "RC_INPUT_PROTO",
        unit: "-",
        min: 0.0,
        max: 6.0,
        integer: true,
        allowed: &[0.0, 2.0, 6.0],
        #[cfg(feature = "docs")]
        doc: "the RC receiver's protocol: 0 none, 2 SBUS (100,000 baud 8E2 inverted), 6 CRSF (420,000 baud; PX4's numbers)",
        get: |c| f32::from(c.hardware.rc_protocol),
        set: |c, v| c.hardware.rc_protocol = v as u8,
    },
    ParamSpec {
        name: "RC_PORT_CONFIG",
        unit: "-",
        min: 0.0,
        max: 202.0,
        integer: true,
        allowed: &[0.0, 103.0, 202.0],
        #[cfg(feature = "docs")]
        doc: "the FMU port the RC receiver is on: 0 none, 103 TELEM3 (shared with steppers 5 to 8), 202 GPS2 (PX4's numbers)",
        get: |c| f32::from(c.hardware.rc_port),
        set: |c, v| c.hardware.rc_port = v as u16,
    },
    param!(
        whole "RC_MAP_ROLL",
        "-",
        0.0,
        16.0,
        "the RC channel (from 1; 0 none) of the roll stick",
        |c| c.hardware.rc_map.roll
    ),
    param!(
        whole "RC_MAP_PITCH",
        "-",
        0.0,
        16.0,
        "the RC channel (from 1; 0 none) of the pitch stick",
        |c| c.hardware.rc_map.pitch
    ),
    param!(
        whole "RC_MAP_THROTTLE",
        "-",
        0.0,
        16.0,
        "the RC channel (from 1; 0 none) of the throttle stick",
        |c| c.hardware.rc_map.throttle
    ),
    param!(
        whole "RC_MAP_YAW",
        "-",
        0.0,
        16.0,
        "the RC channel (from 1; 0 none) of the yaw stick",
        |c| c.hardware.rc_map.yaw
    ),
    param!(
        whole "RC_MAP_KILL_SW",
        "-",
        0.0,
        16.0,
        "the RC channel (from 1; 0 none) of the kill switch (on above 1750 us)",
        |c| c.hardware.rc_map.kill_switch
    ),
    param!(
        whole "RC_MAP_FLTMODE",
        "-",
        0.0,
        16.0,
        "the RC channel (from 1; 0 none) of the mode switch (six slots, COM_FLTMODE1..6)",
        |c| c.hardware.rc_map.mode_switch
    ),
];
