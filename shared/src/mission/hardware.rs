//! The vehicle's hardware settings, which the flight controller's drivers read: the
//! ESC protocol and the thrust map, the steppers' drive train, current and stall threshold.
//! They are parameters like the mission's tuning ([`super::params`]), so a bench calibration
//! replaces them without a new image; the mission itself does not use them.

use crate::manual::rc_map::RcMap;
use crate::mission::esc_protocol::{EscProtocol, UnknownProtocol};
use crate::rail::stepper::DriveConfig;

/// The hardware settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HardwareConfig {
    /// ESC protocol, [`EscProtocol::value`]: 0 DShot600, 1 PWM (1000-2000 us), 2 OneShot125 on
    /// the FMU outputs; 3 DroneCAN ESCs on the CAN bus (docs/hardware.md#can-escs). The
    /// parameter's number; [`Self::esc`] is the type.
    pub esc_protocol: u8,
    /// This flight controller's DroneCAN node ID (`UAVCAN_NODE_ID`, PX4's name and default 1).
    pub can_node_id: u8,
    /// Thrust (fraction of full thrust) at 20, 40, 60 and 80 % ESC command; rising, inside
    /// (0, 1). The default is the square law of a fixed-pitch propeller.
    pub thrust_map: [f32; 4],
    /// The robots' drive train (motor steps, microsteps, pinion).
    pub drive: DriveConfig,
    /// Stepper motor current, A RMS.
    pub stepper_current: f32,
    /// The stepper drivers' sense resistors, ohm.
    pub stepper_r_sense: f32,
    /// StallGuard threshold (TMC2209 `SGTHRS`, 0..=255): a robot whose `SG_RESULT` falls to
    /// twice this at speed has stalled. 0 turns stall detection off; it must be tuned on the
    /// bench for the motor and the load.
    pub stall_threshold: u8,
    /// Motor tests (`MAV_CMD_DO_MOTOR_TEST`) are allowed (`COM_MOT_TEST_EN`, PX4's name).
    pub motor_test_enabled: bool,
    /// Bidirectional DShot: each ESC answers every frame with its electrical RPM
    /// (`DSHOT_BIDIR_EN`, PX4's name). Only with DShot; the ESCs must support it (BLHeli_32,
    /// AM32, Bluejay).
    pub dshot_bidirectional: bool,
    /// The motors' magnet poles: RPM = electrical RPM / (poles / 2) (`MOT_POLE_COUNT`, PX4's
    /// name).
    pub motor_poles: u8,
    /// The RC receiver's protocol (`RC_INPUT_PROTO`, PX4's numbers): 0 none, 2 SBUS, 6 CRSF.
    pub rc_protocol: u8,
    /// The FMU port the RC receiver is wired to (`RC_PORT_CONFIG`, PX4's numbers): 0 none,
    /// 103 TELEM3, 202 GPS2 (docs/hardware.md#rc-receivers).
    pub rc_port: u16,
    /// Which receiver channel carries each stick and switch (`RC_MAP_*`).
    pub rc_map: RcMap,
}

impl HardwareConfig {
    /// The ESC protocol `esc_protocol` names.
    pub fn esc(&self) -> Result<EscProtocol, UnknownProtocol> {
        EscProtocol::from_value(i32::from(self.esc_protocol))
    }

    /// DShot600, the square law, 200-step motors at 16 microsteps on a 20 mm pinion, 0.8 A
    /// through 0.11 ohm sense resistors (the common TMC2209 boards), stall detection off, motor tests allowed, no ESC telemetry, 14-pole motors.
    pub const DEFAULT: Self = Self {
        esc_protocol: 0,
        can_node_id: 1,
        thrust_map: [0.04, 0.16, 0.36, 0.64],
        drive: DriveConfig::DEFAULT,
        stepper_current: 0.8,
        stepper_r_sense: 0.11,
        stall_threshold: 0,
        motor_test_enabled: true,
        dshot_bidirectional: false,
        motor_poles: 14,
        rc_protocol: 6,
        rc_port: 202,
        rc_map: RcMap::AETR,
    };
}

impl Default for HardwareConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
