//! Telemetry at set rates: `SYS_STATUS`, `ATTITUDE_QUATERNION`,
//! `LOCAL_POSITION_NED`, each robot's rail position (`DEBUG_FLOAT_ARRAY` named `rail`: the
//! formation once the robots have moved to it; not a number until the positions are
//! confirmed), `GLOBAL_POSITION_INT` (through the map origin,
//! docs/ground-link.md#the-map-origin) and the ESC outputs (`ACTUATOR_OUTPUT_STATUS`, and
//! `SERVO_OUTPUT_RAW` for MAVProxy: docs/ground-link.md#bring-up-commands), the ESCs' own
//! telemetry (`ESC_STATUS`, `ESC_INFO`: [`crate::esc`]), the RC receiver's channels
//! (`RC_CHANNELS`, [`RcStatus`]), each on its own interval that a ground station
//! sets with `MAV_CMD_SET_MESSAGE_INTERVAL` (or asks for once with `MAV_CMD_REQUEST_MESSAGE`),
//! as MAVLink's message interval protocol has it; the messages built from a
//! [`VehicleSnapshot`], the vehicle's state after its last control step; and the take-off
//! point ([`Home`], `HOME_POSITION`) and the origin (`GPS_GLOBAL_ORIGIN`) on request.
//!
//! The schedule is plain logic over the vehicle's microsecond clock: the firmware's send task
//! asks [`Schedule::next_due`] when to wake and [`Schedule::take_due`] what to send.
//!
//! This file holds the snapshot ([`VehicleSnapshot`], [`RouteStatus`]); the schedule is in
//! `schedule`; the messages are built from the snapshot one group of streams a file, as PX4
//! keeps one file a stream: `sys_status` (`SYS_STATUS`,
//! `EXTENDED_SYS_STATE`), `attitude_position` (`ATTITUDE_QUATERNION`, `LOCAL_POSITION_NED`),
//! `rail` (the rail positions' `DEBUG_FLOAT_ARRAY`), `outputs` (`ACTUATOR_OUTPUT_STATUS`,
//! `SERVO_OUTPUT_RAW`), `global` (`GLOBAL_POSITION_INT`, `HOME_POSITION`,
//! `GPS_GLOBAL_ORIGIN`) and `rc` (the RC receiver's `RC_CHANNELS`, from its own status rather
//! than the snapshot).

mod attitude_position;
mod global;
mod outputs;
mod rail;
mod rc;
mod schedule;
mod sys_status;

pub use global::{Home, gps_global_origin};
pub use outputs::SERVOS_PER_PORT;
pub use rail::{RAIL_ARRAY_ID, RAIL_ARRAY_NAME};
pub use rc::{RC_CHANNELS, RcStatus};
pub use schedule::{MAX_INTERVAL_US, MIN_INTERVAL_US, STREAMS, Schedule, Stream};
pub use sys_status::LogHealth;

use crate::hil::MAX_ROBOTS;
use crate::msg::MavLandedState;

/// The vehicle's state after its last control step, for telemetry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleSnapshot {
    /// Vehicle time of the step, us.
    pub time_us: u64,
    /// Attitude, body (FRD) to NED, `[w, x, y, z]`.
    pub attitude: [f32; 4],
    /// Body rates, rad/s (roll, pitch, yaw).
    pub rates: [f32; 3],
    /// Position from the take-off point, NED, m.
    pub position: [f32; 3],
    /// Velocity, NED, m/s.
    pub velocity: [f32; 3],
    /// The position is from a recent motion-capture fix.
    pub position_valid: bool,
    /// The IMU works (no driver fault).
    pub imu_healthy: bool,
    /// The rotors may spin.
    pub armed: bool,
    /// Robots in use.
    pub robots: u8,
    /// Each robot's commanded position along the rail, arc length, m.
    pub rail: [f32; MAX_ROBOTS],
    /// The rail positions are known (confirmed by the operator): until then the ground is
    /// sent not a number for each.
    pub rail_known: bool,
    /// Each robot's rotor thrust command, fraction of its maximum (zero unless armed).
    pub thrust: [f32; MAX_ROBOTS],
    /// The control loop's load: the worst step since the last `SYS_STATUS`, in thousandths
    /// of the step's period.
    pub load_permille: u16,
    /// The pack's filtered voltage, mV (`u16::MAX`: not measured).
    pub battery_mv: u16,
    /// The battery is above its low threshold.
    pub battery_ok: bool,
    /// The flight mode ([`crate::modes::FlightMode::code`]).
    pub mode: u8,
    /// The route's progress, for `MISSION_CURRENT` and `MISSION_ITEM_REACHED`.
    pub route: RouteStatus,
    /// `EXTENDED_SYS_STATE`'s `landed_state` (`MAV_LANDED_STATE`).
    pub landed: u8,
    /// The rotors the vehicle flies without (found stopped), bit `i` for robot `i`.
    pub rotors_out: u16,
    /// Manual control (an RC receiver or a joystick) has been heard since power-up.
    pub manual_present: bool,
    /// Manual control is in force and fresh (not lost).
    pub manual_valid: bool,
}

/// Where the vehicle is along its route (docs/ground-link.md#missions).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RouteStatus {
    /// The item flown (the first one before the flight).
    pub current: u16,
    /// The last item reached, if any.
    pub reached: Option<u16>,
    /// `MISSION_CURRENT`'s `mission_state`.
    pub progress: crate::mission::wire::MissionProgress,
}

impl RouteStatus {
    /// No route.
    pub const NONE: Self = Self {
        current: 0,
        reached: None,
        progress: crate::mission::wire::MissionProgress::NoMission,
    };
}

impl VehicleSnapshot {
    /// Before the first control step: level, at rest, nothing valid.
    pub const START: Self = Self {
        time_us: 0,
        attitude: [1.0, 0.0, 0.0, 0.0],
        rates: [0.0; 3],
        position: [0.0; 3],
        velocity: [0.0; 3],
        position_valid: false,
        imu_healthy: true,
        armed: false,
        robots: 0,
        rail: [0.0; MAX_ROBOTS],
        rail_known: false,
        thrust: [0.0; MAX_ROBOTS],
        load_permille: 0,
        battery_mv: u16::MAX,
        battery_ok: true,
        mode: 0,
        route: RouteStatus::NONE,
        landed: MavLandedState::MAV_LANDED_STATE_ON_GROUND as u8,
        rotors_out: 0,
        manual_present: false,
        manual_valid: false,
    };

    fn time_boot_ms(&self) -> u32 {
        (self.time_us / 1000) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::MavSysStatusSensor;

    #[test]
    fn the_messages_carry_the_snapshot() {
        let snap = VehicleSnapshot {
            time_us: 12_345_678,
            attitude: [0.5, 0.5, -0.5, 0.5],
            rates: [0.1, -0.2, 0.3],
            position: [1.0, 2.0, -3.0],
            velocity: [0.5, 0.0, -0.25],
            position_valid: true,
            imu_healthy: false,
            armed: true,
            robots: 3,
            rail: [
                0.5, 1.25, 2.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0, 9.0,
            ],
            rail_known: true,
            load_permille: 1500,
            battery_mv: u16::MAX,
            battery_ok: true,
            ..VehicleSnapshot::START
        };
        let (array, data, len) = snap.rail_positions();
        assert_eq!(
            (array.array_id, array.name.to_str().ok()),
            (RAIL_ARRAY_ID, Some("rail"))
        );
        assert_eq!(len, 12);
        let arcs: std::vec::Vec<f32> = data[..len]
            .chunks(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(arcs, [0.5, 1.25, 2.0]);
        // Not confirmed: not a number for each robot.
        let unknown = VehicleSnapshot {
            rail_known: false,
            ..snap
        };
        let (_, data, len) = unknown.rail_positions();
        assert!(
            data[..len]
                .chunks(4)
                .all(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]).is_nan())
        );
        let q = snap.attitude_quaternion();
        assert_eq!(q.time_boot_ms, 12_345);
        assert_eq!([q.q1, q.q2, q.q3, q.q4], snap.attitude);
        assert_eq!([q.rollspeed, q.pitchspeed, q.yawspeed], snap.rates);
        let p = snap.local_position_ned();
        assert_eq!(
            [p.x, p.y, p.z, p.vx, p.vy, p.vz],
            [1.0, 2.0, -3.0, 0.5, 0.0, -0.25]
        );
        let st = snap.sys_status();
        let gyro = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO;
        let vision = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_VISION_POSITION;
        assert!(st.onboard_control_sensors_present.contains(gyro));
        assert!(!st.onboard_control_sensors_health.contains(gyro));
        assert!(st.onboard_control_sensors_health.contains(vision));
        assert_eq!(st.load, 1000);
        assert_eq!(st.voltage_battery, u16::MAX);
        let resting = VehicleSnapshot::START.sys_status();
        assert!(resting.onboard_control_sensors_health.contains(gyro));
        assert!(!resting.onboard_control_sensors_health.contains(vision));
        let battery = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_BATTERY;
        assert!(!resting.onboard_control_sensors_present.contains(battery));
    }
}
