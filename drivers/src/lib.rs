//! Driver cores for the Pixhawk 6C board: the parts of each driver that are plain
//! computation (frame encoding, checksums, packet parsing, unit scaling, register packing),
//! kept apart from the embassy glue in `firmware/src/board` as Hubris splits a driver core from
//! its server, so that they are tested on the host against the datasheets' own examples.
//!
//! | module | device |
//! |---|---|
//! | [`dronecan`] | CAN ESCs over DroneCAN: RawCommand, Status, NodeStatus, frames, bus load |
//! | [`dshot`] | ESC frames, DShot600 (the DShot protocol's frame and its 4-bit checksum) |
//! | [`dshot_telemetry`] | bidirectional DShot's answer: each ESC's RPM from its line's edges |
//! | [`esc_gate`] | what the ESC outputs send: armed commands, stops, protocol changes |
//! | [`pulse`] | ESC pulses for ESCs without DShot: PWM (1000-2000 us) and OneShot125 |
//! | [`thrust_map`] | rotor thrust to ESC command, a table replaceable by a bench calibration |
//! | [`icm42688`] | the ICM-42688-P IMU: registers, start-up, 20-byte FIFO packets, scaling |
//! | [`imu`] | mounting rotation, anti-alias filter and decimation to the tick, IMU health |
//! | [`biquad`] | second-order filters: the IMU's anti-alias low-pass and notches |
//! | [`rotor_notch`] | notches following each rotor's rotation and blade-pass frequencies |
//! | [`tmc2209`] | the TMC2209 stepper driver's single-wire UART: datagrams, CRC, registers |
//! | [`stepper`] | a robot's rail axis on a TMC2209: velocity commands, arc length, stalls |
//! | [`reset`] | why the STM32H7 last reset (RCC_RSR), for the start-up report |
//! | [`battery`] | the power module's pack voltage from ADC counts (divider, reference) |
//! | [`rc`] | the safety pilot's RC channels in microseconds, whichever receiver carries them |
//! | [`crsf`] | CRSF (ExpressLRS, TBS Crossfire) receivers: frames, CRC, channels, link statistics |
//! | [`sbus`] | SBUS receivers: 25-byte frames, idle-line framing, failsafe and frame-lost flags |
//! | [`rc_receiver`] | the receiver's port: protocol and line, which UART, reads to frames, frames counted |
//! | [`sd_logs`] | the flight logs as numbered files on the microSD card's FAT volume |
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

#[cfg(test)]
extern crate std;

pub mod battery;
pub mod biquad;
pub mod crsf;
pub mod dronecan;
pub mod dshot;
pub mod dshot_telemetry;
pub mod esc_gate;
pub mod icm42688;
pub mod imu;
pub mod pulse;
pub mod rc;
pub mod rc_receiver;
pub mod reset;
pub mod rotor_notch;
pub mod sbus;
pub mod sd_logs;
pub mod stepper;
/// The thrust map lives with the mission (its motor test spins a rotor at an ESC command).
pub use shared::control::thrust_map;
pub mod tmc2209;
