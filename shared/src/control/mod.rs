//! Flight control as the firmware runs it at 400 Hz (docs/models.md#flight-cascade).
//!
//! - [`vector`]: 3-vectors and quaternions (body FRD, world NED).
//! - [`attitude_estimator`]: Mahony filter with gyro bias, heading from motion capture.
//! - [`position_estimator`]: position and velocity from the accelerometer and late fixes.
//! - [`pid`]: PID with derivative on the measurement and anti-windup.
//! - [`params`]: every gain and limit, with units.
//! - [`vehicle`]: mass, inertia and thrust of the vehicle from the estimate.
//! - [`controller`]: the cascade, position to torque.
//! - [`allocation`]: the two mixers, rebuilt from the formation, with desaturation.
//! - [`trajectory`]: take-off, transit, hover, landing.
//! - [`land_detector`]: on the ground, airborne, landed.
//! - [`navigator`]: both estimators together, fed by the IMU and motion capture.
//! - [`imu_monitor`]: the IMU's samples checked every tick: frozen, or wildly noisy.
//! - [`thrust_map`]: rotor thrust to ESC command, a table a bench calibration replaces.
//! - [`voltage_compensation`]: the rotors' commands raised for a pack that sags.

pub mod allocation;
pub mod attitude_estimator;
pub mod controller;
pub mod imu_monitor;
pub mod land_detector;
pub mod navigator;
pub mod params;
pub mod pid;
pub mod position_estimator;
pub mod thrust_map;
pub mod trajectory;
pub mod vector;
pub mod vehicle;
pub mod voltage_compensation;
