//! A ground station that floods the link (docs/ground-link.md#under-a-flood): runs
//! `tests/flood.py` (pymavlink) against the firmware under QEMU through `host-sim hil --gcs`:
//! random bytes, a mix of bad requests, and parameter-list requests, each at 200 messages a
//! second for a whole mission. Each mission must deliver exactly as the clean run, the
//! vehicle's heartbeat must keep coming each second of its clock, and a parameter list must
//! still come whole after the flood. What it checks is listed at the top of the script. The
//! clean run is the flight the other tests of `hil --storage` share
//! ([`crate::storage_flight`]), handed to the script with `--clean-report`.
//!
//! Needs `python3` with `pymavlink` and `qemu-system-arm`; it builds the firmware's QEMU
//! image itself. Without one of them the test says it was skipped and why, and passes; with
//! `HIL_REQUIRED=1` (CI, which installs them) it fails instead.

use crate::common::{image_or_skip, run_python_check};
use crate::storage_flight;

/// The test's name in what it says when skipped.
const TEST: &str = "flood";

#[test]
fn a_flooding_ground_station_neither_starves_the_vehicle_nor_changes_its_mission() {
    let Some(elf) = image_or_skip(TEST) else {
        return;
    };
    let clean = std::env::temp_dir().join(format!("flood-clean-run-{}.json", std::process::id()));
    std::fs::write(&clean, &storage_flight::flown(&elf).report).expect("the clean run's report");
    let args = [std::ffi::OsStr::new("--clean-report"), clean.as_os_str()];
    run_python_check(TEST, "tests/flood.py", &elf, &args);
    let _ = std::fs::remove_file(&clean);
}
