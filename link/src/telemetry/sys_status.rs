//! `SYS_STATUS` (the sensors, the geofence, the battery, the flight log's storage:
//! docs/formats.md#flight-logs) and `EXTENDED_SYS_STATE` from the vehicle's snapshot.

use super::VehicleSnapshot;
use crate::msg::{
    EXTENDED_SYS_STATE_DATA, MavLandedState, MavSysStatusSensor, MavVtolState, SYS_STATUS_DATA,
};
use shared::scenario::{MAX_TARGET_DISTANCE, MAX_TARGET_HEIGHT};

/// The flight log's storage as `SYS_STATUS` reports it (`MAV_SYS_STATUS_LOGGING`,
/// docs/formats.md#flight-logs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogHealth {
    /// The vehicle keeps no logs (the bit is not present).
    Absent,
    /// The storage works: present, enabled and healthy.
    Ready,
    /// The storage failed (a card missing, full or failing): present and enabled, not
    /// healthy, until a log is opened again.
    Failed,
}

impl VehicleSnapshot {
    /// `EXTENDED_SYS_STATE`: the landed state (MAVSDK's `landed_state` and `in_air`).
    pub fn extended_sys_state(&self) -> EXTENDED_SYS_STATE_DATA {
        let landed = [
            MavLandedState::MAV_LANDED_STATE_ON_GROUND,
            MavLandedState::MAV_LANDED_STATE_IN_AIR,
            MavLandedState::MAV_LANDED_STATE_TAKEOFF,
            MavLandedState::MAV_LANDED_STATE_LANDING,
        ]
        .into_iter()
        .find(|s| *s as u8 == self.landed)
        .unwrap_or(MavLandedState::MAV_LANDED_STATE_UNDEFINED);
        EXTENDED_SYS_STATE_DATA {
            vtol_state: MavVtolState::MAV_VTOL_STATE_UNDEFINED,
            landed_state: landed,
        }
    }

    /// `SYS_STATUS` as [`Self::sys_status`] gives it, with the flight log's storage
    /// (`MAV_SYS_STATUS_LOGGING`: present unless the vehicle keeps no logs, healthy while its
    /// storage works).
    pub fn sys_status_with_log(&self, log: LogHealth) -> SYS_STATUS_DATA {
        let mut status = self.sys_status();
        let logging = MavSysStatusSensor::MAV_SYS_STATUS_LOGGING;
        if log != LogHealth::Absent {
            status.onboard_control_sensors_present |= logging;
            status.onboard_control_sensors_enabled |= logging;
        }
        if log == LogHealth::Ready {
            status.onboard_control_sensors_health |= logging;
        }
        status
    }

    /// `SYS_STATUS`: gyro, accelerometer, motion capture (as vision position), the motor
    /// outputs, the geofence, once heard manual control (as the RC receiver, healthy while
    /// not lost: docs/manual-control.md) and, once measured, the battery (its voltage; healthy above its
    /// low threshold); health clear for a failed IMU, no recent fix, or the vehicle outside
    /// the bounds it keeps its flights in. Current and remaining are not measured
    /// (-1, as MAVLink marks unknown values; so is a voltage not measured, `u16::MAX`).
    pub fn sys_status(&self) -> SYS_STATUS_DATA {
        let imu = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
            | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL;
        let mocap = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_VISION_POSITION;
        let motors = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS;
        // The bounds every target and route item must keep (docs/ground-link.md#missions), as
        // PX4 reports its geofence: always there and in force (MAVProxy and QGroundControl
        // read a missing bit as a breach).
        let fence = MavSysStatusSensor::MAV_SYS_STATUS_GEOFENCE;
        let present = imu | mocap | motors | fence;
        let mut enabled = imu | mocap | fence;
        if self.armed {
            enabled |= motors;
        }
        let mut health = motors;
        if self.inside_bounds() {
            health |= fence;
        }
        if self.imu_healthy {
            health |= imu;
        }
        if self.position_valid {
            health |= mocap;
        }
        let (mut present, mut enabled) = (present, enabled);
        // Manual control as PX4 reports its RC receiver (QGroundControl's RC indicator):
        // present once heard, healthy while not lost.
        if self.manual_present {
            let rc = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_RC_RECEIVER;
            present |= rc;
            enabled |= rc;
            if self.manual_valid {
                health |= rc;
            }
        }
        if self.battery_mv != u16::MAX {
            let battery = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_BATTERY;
            present |= battery;
            enabled |= battery;
            if self.battery_ok {
                health |= battery;
            }
        }
        SYS_STATUS_DATA {
            onboard_control_sensors_present: present,
            onboard_control_sensors_enabled: enabled,
            onboard_control_sensors_health: health,
            load: self.load_permille.min(1000),
            voltage_battery: self.battery_mv,
            current_battery: -1,
            battery_remaining: -1,
            ..Default::default()
        }
    }

    /// The vehicle is within the bounds its flights keep: [`MAX_TARGET_DISTANCE`] from the
    /// origin and [`MAX_TARGET_HEIGHT`] above it.
    pub fn inside_bounds(&self) -> bool {
        let [north, east, down] = self.position;
        north * north + east * east <= MAX_TARGET_DISTANCE * MAX_TARGET_DISTANCE
            && -down <= MAX_TARGET_HEIGHT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flight_logs_storage_is_present_and_healthy_while_it_works() {
        let logging = MavSysStatusSensor::MAV_SYS_STATUS_LOGGING;
        let snap = VehicleSnapshot::START;
        let none = snap.sys_status_with_log(LogHealth::Absent);
        assert!(!none.onboard_control_sensors_present.contains(logging));
        assert_eq!(none, snap.sys_status());
        let ready = snap.sys_status_with_log(LogHealth::Ready);
        assert!(ready.onboard_control_sensors_present.contains(logging));
        assert!(ready.onboard_control_sensors_enabled.contains(logging));
        assert!(ready.onboard_control_sensors_health.contains(logging));
        let failed = snap.sys_status_with_log(LogHealth::Failed);
        assert!(failed.onboard_control_sensors_present.contains(logging));
        assert!(!failed.onboard_control_sensors_health.contains(logging));
    }

    #[test]
    fn the_geofence_is_reported_as_px4_reports_it_and_breached_outside_the_bounds() {
        let fence = MavSysStatusSensor::MAV_SYS_STATUS_GEOFENCE;
        let at = |position| VehicleSnapshot {
            position,
            ..VehicleSnapshot::START
        };
        for inside in [[0.0, 0.0, 0.0], [19.0, -5.0, -9.5]] {
            let st = at(inside).sys_status();
            assert!(st.onboard_control_sensors_present.contains(fence));
            assert!(st.onboard_control_sensors_enabled.contains(fence));
            assert!(
                st.onboard_control_sensors_health.contains(fence),
                "{inside:?}"
            );
        }
        for outside in [[15.0, 15.0, -1.0], [0.0, 0.0, -10.5]] {
            let st = at(outside).sys_status();
            assert!(st.onboard_control_sensors_present.contains(fence));
            assert!(
                !st.onboard_control_sensors_health.contains(fence),
                "{outside:?}"
            );
        }
    }

    #[test]
    fn a_measured_battery_is_reported_with_its_health() {
        let battery = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_BATTERY;
        let good = VehicleSnapshot {
            battery_mv: 15_730,
            ..VehicleSnapshot::START
        }
        .sys_status();
        assert_eq!(good.voltage_battery, 15_730);
        assert!(good.onboard_control_sensors_present.contains(battery));
        assert!(good.onboard_control_sensors_health.contains(battery));
        let low = VehicleSnapshot {
            battery_mv: 13_100,
            battery_ok: false,
            ..VehicleSnapshot::START
        }
        .sys_status();
        assert!(low.onboard_control_sensors_enabled.contains(battery));
        assert!(!low.onboard_control_sensors_health.contains(battery));
    }

    #[test]
    fn manual_control_is_the_rc_receiver_present_once_heard_and_healthy_while_not_lost() {
        let rc = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_RC_RECEIVER;
        let never = VehicleSnapshot::START.sys_status();
        assert!(!never.onboard_control_sensors_present.contains(rc));
        let valid = VehicleSnapshot {
            manual_present: true,
            manual_valid: true,
            ..VehicleSnapshot::START
        }
        .sys_status();
        assert!(valid.onboard_control_sensors_present.contains(rc));
        assert!(valid.onboard_control_sensors_health.contains(rc));
        let lost = VehicleSnapshot {
            manual_present: true,
            ..VehicleSnapshot::START
        }
        .sys_status();
        assert!(lost.onboard_control_sensors_enabled.contains(rc));
        assert!(!lost.onboard_control_sensors_health.contains(rc));
    }
}
