//! `ATTITUDE_QUATERNION` and `LOCAL_POSITION_NED` from the vehicle's snapshot: its attitude,
//! body rates, position and velocity in the local frame (NED from the take-off point).

use super::VehicleSnapshot;
use crate::msg::{ATTITUDE_QUATERNION_DATA, LOCAL_POSITION_NED_DATA};

impl VehicleSnapshot {
    /// `ATTITUDE_QUATERNION`.
    pub fn attitude_quaternion(&self) -> ATTITUDE_QUATERNION_DATA {
        let [w, x, y, z] = self.attitude;
        ATTITUDE_QUATERNION_DATA {
            time_boot_ms: self.time_boot_ms(),
            q1: w,
            q2: x,
            q3: y,
            q4: z,
            rollspeed: self.rates[0],
            pitchspeed: self.rates[1],
            yawspeed: self.rates[2],
        }
    }

    /// `LOCAL_POSITION_NED`.
    pub fn local_position_ned(&self) -> LOCAL_POSITION_NED_DATA {
        LOCAL_POSITION_NED_DATA {
            time_boot_ms: self.time_boot_ms(),
            x: self.position[0],
            y: self.position[1],
            z: self.position[2],
            vx: self.velocity[0],
            vy: self.velocity[1],
            vz: self.velocity[2],
        }
    }
}
