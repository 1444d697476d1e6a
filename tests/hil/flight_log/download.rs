//! The flight logs served over MAVLink's log protocol (docs/formats.md#downloading-the-logs):
//! rect-ex1 flown with the firmware under QEMU and `hil --storage DIR` (the flight the other
//! tests of `hil --storage` share, [`crate::storage_flight`]; a copy of its storage), then the
//! firmware restarted on that storage and `tests/log_download.py` (pymavlink, then MAVProxy)
//! run against it: the list, the log downloaded block by block byte for byte the file in DIR
//! (and the speed, and the heartbeats that kept coming), a log that is not kept, requests past
//! the end, MAVProxy's `log download`, and the erase. What it checks is listed at the top of
//! the script.
//!
//! Needs `python3` with `pymavlink` (and MAVProxy) and `qemu-system-arm`; it builds the
//! firmware's QEMU image itself. Without one of them the test says it was skipped and why,
//! and passes; with `HIL_REQUIRED=1` (CI, which installs them) it fails instead.

use crate::common::{image_or_skip, run_python_check};
use crate::storage_flight;

/// The test's name in what it says when skipped.
const TEST: &str = "log download";

#[test]
fn a_ground_station_lists_downloads_and_erases_the_firmwares_flight_log() {
    let Some(elf) = image_or_skip(TEST) else {
        return;
    };
    let storage = std::env::temp_dir().join(format!("log-download-test-{}", std::process::id()));
    storage_flight::flown(&elf).copy_storage_to(&storage);
    assert!(
        storage.join("log-000.ulg").is_file(),
        "the flight left no log in {}",
        storage.display()
    );
    let args = [std::ffi::OsStr::new("--storage"), storage.as_os_str()];
    run_python_check(TEST, "tests/log_download.py", &elf, &args);
    let _ = std::fs::remove_dir_all(&storage);
}
