//! The simulator's tests: the paper's pipeline and the autonomous mission flown in the
//! physics plant with `shared`'s code (estimation, formation, flight, the mission and its
//! failsafes, the route, the formation's adaptation, the flight log), in this process or
//! through the `host-sim` binary. No firmware, no QEMU: each module's tests run side by side
//! with the others' (libtest's threads). `cargo test -p host-sim --test simulation`; one
//! module: `... --test simulation rotor_out::`.

#[path = "../common/mod.rs"]
mod common;

mod adaptation;
mod estimation;
mod flight;
mod flight_log;
mod formation;
mod ground_contact;
mod ground_loss_battery;
mod imu_faults;
mod manual_control;
mod mission;
mod plant_departures;
mod rotor_out;
mod route;
mod vibration;
