//! The flight logs served over MAVLink's log protocol (docs/formats.md#downloading-the-logs):
//! flies rect-ex1 with the firmware under QEMU and `hil --storage DIR`, then restarts the
//! firmware on that storage and runs `tests/log_download.py` (pymavlink, then MAVProxy)
//! against it: the list, the log downloaded block by block byte for byte the file in DIR
//! (and the speed, and the heartbeats that kept coming), a log that is not kept, requests past
//! the end, MAVProxy's `log download`, and the erase. What it checks is listed at the top of
//! the script.
//!
//! Needs `python3` with `pymavlink` (and MAVProxy) and `qemu-system-arm`; it builds the
//! firmware's QEMU image itself. Without one of them the test says it was skipped and why,
//! and passes; with `HIL_REQUIRED=1` (CI, which installs them) it fails instead.

mod common;

use common::{image_or_skip, run_python_check, workspace};
use std::process::Command;

/// The test's name in what it says when skipped.
const TEST: &str = "log download";

#[test]
fn a_ground_station_lists_downloads_and_erases_the_firmwares_flight_log() {
    let Some(elf) = image_or_skip(TEST) else {
        return;
    };
    let storage = std::env::temp_dir().join(format!("log-download-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&storage);
    std::fs::create_dir_all(&storage).expect("a temporary folder");
    let scenario = workspace().join("tests/scenarios/rect-ex1.toml");
    let flight = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("hil")
        .arg("--scenario")
        .arg(&scenario)
        .arg("--qemu")
        .arg(&elf)
        .arg("--storage")
        .arg(&storage)
        .output()
        .expect("host-sim runs");
    assert!(
        flight.status.success(),
        "the flight: {}",
        String::from_utf8_lossy(&flight.stderr)
    );
    assert!(
        storage.join("log-000.ulg").is_file(),
        "the flight left no log in {}",
        storage.display()
    );
    let args = [std::ffi::OsStr::new("--storage"), storage.as_os_str()];
    run_python_check(TEST, "tests/log_download.py", &elf, &args);
    let _ = std::fs::remove_dir_all(&storage);
}
