//! The firmware's MAVLink input handling: a header of options (what the store holds at the
//! start, whether the board's IMU driver steps the control task, driver faults; see
//! `fuzz::vehicle::Options`), then an arbitrary byte stream through the frame parser, the
//! dispatch, the services (commands, parameters and their store, FTP and the payload
//! description's checks, signing, time sync, telemetry rates) and the mission behind them.
//! The vehicle checks its invariants as it goes (`fuzz::vehicle`); at the end a restart
//! must find in the store what was in force.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Some(vehicle) = fuzz::vehicle::run(data) {
        vehicle.restart_check();
    }
});
