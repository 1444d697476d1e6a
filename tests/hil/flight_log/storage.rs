//! The firmware's flight log (docs/formats.md#flight-logs): rect-ex1 flown under QEMU with
//! `hil --storage` ([`crate::storage_flight`], the flight the log download and the flood's clean
//! run share) leaves the simulator's log in its storage, message for message (but the pack
//! voltage, which the plant sends at 10 Hz in millivolts), and pyulog opens it too. The
//! simulator's own log has its tests in `simulation::flight_log`. Without python3 and pyulog,
//! or QEMU, the test says it was skipped and why; with `HIL_REQUIRED=1` (CI, which installs
//! them) it fails instead.

use crate::common;
use crate::storage_flight;

use ::flight_log::topics::Topic;
use common::ulog::{fly_logged, messages, pyulog_check};
use common::{image_or_skip, skip};

#[test]
fn the_firmware_in_the_loop_keeps_the_simulators_log_in_its_storage() {
    let Some(elf) = image_or_skip("flight log in the loop") else {
        return;
    };
    let (_, host_log) = fly_logged("hil", true);
    let flight = storage_flight::flown(&elf);
    let firmware_bytes = flight
        .file("log-000.ulg")
        .expect("the firmware left its log");
    let host_bytes = std::fs::read(&host_log).expect("the host's log");
    let data = |all: &[u8]| -> Vec<Vec<u8>> {
        messages(all)
            .into_iter()
            .filter(|m| b"DLO".contains(&m.kind))
            .map(|m| [&[m.kind][..], m.payload].concat())
            .collect()
    };
    let (host, firmware) = (data(&host_bytes), data(firmware_bytes));
    assert_eq!(host.len(), firmware.len(), "as many messages");
    let battery = Topic::BatteryStatus.msg_id().to_le_bytes();
    for (i, (h, f)) in host.iter().zip(&firmware).enumerate() {
        if h[0] == b'D' && h[1..3] == battery {
            assert_eq!(
                f[..11],
                h[..11],
                "message {i}: a battery record at the same time"
            );
        } else {
            assert_eq!(f, h, "message {i} differs");
        }
    }
    // pyulog reads it from a file of its own.
    let firmware_log = host_log.with_file_name("firmware-log-000.ulg");
    std::fs::write(&firmware_log, firmware_bytes).expect("the firmware's log copied");
    match pyulog_check(&firmware_log) {
        Ok(report) => {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "firmware's log: {report}");
        }
        Err(why) => skip("flight log in the loop with pyulog", &why),
    }
    let _ = std::fs::remove_file(&firmware_log);
    let _ = std::fs::remove_file(&host_log);
}
