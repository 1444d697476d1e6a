//! The ESC outputs from the vehicle's snapshot through the thrust map:
//! `ACTUATOR_OUTPUT_STATUS`, and `SERVO_OUTPUT_RAW` for MAVProxy
//! (docs/ground-link.md#bring-up-commands).

use super::VehicleSnapshot;
use crate::hil::MAX_ROBOTS;
use crate::msg::{ACTUATOR_OUTPUT_STATUS_DATA, SERVO_OUTPUT_RAW_DATA};
use shared::control::thrust_map::ThrustMap;

/// Outputs in one `SERVO_OUTPUT_RAW` (its port).
pub const SERVOS_PER_PORT: usize = 8;

impl VehicleSnapshot {
    /// Each robot's ESC command, fraction of full, through the thrust map `map` (zero when
    /// disarmed).
    pub fn esc_commands(&self, map: &ThrustMap) -> [f32; MAX_ROBOTS] {
        let robots = usize::from(self.robots).min(MAX_ROBOTS);
        let mut commands = [0.0; MAX_ROBOTS];
        if self.armed {
            for (c, &t) in commands.iter_mut().zip(&self.thrust[..robots]) {
                *c = map.command(t);
            }
        }
        commands
    }

    /// `ACTUATOR_OUTPUT_STATUS`: each robot's ESC command through `map`, fraction of full
    /// (`active`: a bit per robot in use).
    pub fn actuator_output_status(&self, map: &ThrustMap) -> ACTUATOR_OUTPUT_STATUS_DATA {
        let robots = usize::from(self.robots).min(MAX_ROBOTS);
        let commands = self.esc_commands(map);
        let mut actuator = [0.0f32; 32];
        actuator[..MAX_ROBOTS].copy_from_slice(&commands);
        ACTUATOR_OUTPUT_STATUS_DATA {
            time_usec: self.time_us,
            active: if robots >= 32 {
                u32::MAX
            } else {
                (1u32 << robots) - 1
            },
            actuator,
        }
    }

    /// `SERVO_OUTPUT_RAW` of output port `port` (eight outputs a port, as PX4's MAIN 0 and
    /// AUX 1): robots `8 * port` to `8 * port + 7`'s ESC commands through `map` as the pulses
    /// a PWM ESC would get, 1000 us (stopped) to 2000 us (full).
    pub fn servo_output_raw(&self, map: &ThrustMap, port: u8) -> SERVO_OUTPUT_RAW_DATA {
        let c = self.esc_commands(map);
        let first = SERVOS_PER_PORT * usize::from(port);
        let us = |j: usize| {
            let command = c.get(first + j).copied().unwrap_or(0.0);
            1000 + (command.clamp(0.0, 1.0) * 1000.0 + 0.5) as u16
        };
        SERVO_OUTPUT_RAW_DATA {
            time_usec: self.time_us as u32,
            servo1_raw: us(0),
            servo2_raw: us(1),
            servo3_raw: us(2),
            servo4_raw: us(3),
            servo5_raw: us(4),
            servo6_raw: us(5),
            servo7_raw: us(6),
            servo8_raw: us(7),
            port,
        }
    }

    /// The `SERVO_OUTPUT_RAW` ports the robots in use fill (at least one).
    pub fn servo_ports(&self) -> u8 {
        usize::from(self.robots)
            .div_ceil(SERVOS_PER_PORT)
            .clamp(1, MAX_ROBOTS / SERVOS_PER_PORT) as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::telemetry::Stream;

    #[test]
    fn the_esc_outputs_are_the_thrust_maps_commands_and_stopped_when_disarmed() {
        let mut snap = VehicleSnapshot::START;
        snap.robots = 3;
        snap.armed = true;
        // The square law: 4 % and 16 % of full thrust are 20 % and 40 % command.
        snap.thrust[..3].copy_from_slice(&[0.04, 0.16, 0.0]);
        let map = ThrustMap::SQUARE;
        let status = snap.actuator_output_status(&map);
        assert_eq!(status.active, 0b111);
        assert!((status.actuator[0] - 0.2).abs() < 1e-5);
        assert!((status.actuator[1] - 0.4).abs() < 1e-5);
        assert_eq!(status.actuator[2], 0.0);
        let raw = snap.servo_output_raw(&map, 0);
        assert_eq!(
            (raw.servo1_raw, raw.servo2_raw, raw.servo3_raw),
            (1200, 1400, 1000)
        );
        assert_eq!(raw.servo8_raw, 1000);
        snap.armed = false;
        assert!(
            snap.actuator_output_status(&map)
                .actuator
                .iter()
                .all(|&a| a == 0.0)
        );
        assert_eq!(snap.servo_output_raw(&map, 0).servo1_raw, 1000);
        // Robots past the eighth on the second port (AUX), as PX4 sends them.
        snap.armed = true;
        snap.robots = 12;
        snap.thrust[9] = 0.16;
        assert_eq!(snap.servo_ports(), 2);
        let aux = snap.servo_output_raw(&map, 1);
        assert_eq!((aux.port, aux.servo2_raw, aux.servo5_raw), (1, 1400, 1000));
        snap.robots = 3;
        assert_eq!(snap.servo_ports(), 1);
        for stream in [Stream::ServoOutputRaw, Stream::ActuatorOutputStatus] {
            assert_eq!(Stream::of_message(stream.message_id()), Some(stream));
        }
    }
}
