//! A ground station that floods the link (docs/ground-link.md#under-a-flood): runs
//! `tests/flood.py` (pymavlink) against the firmware under QEMU through `host-sim hil --gcs`:
//! random bytes, a mix of bad requests, and parameter-list requests, each at 200 messages a
//! second for a whole mission. Each mission must
//! deliver exactly as the clean run, the vehicle's heartbeat must keep coming each second of
//! its clock, and a parameter list must still come whole after the flood. What it checks is listed at the top of the script.
//!
//! Needs `python3` with `pymavlink` and `qemu-system-arm`; it builds the firmware's QEMU
//! image itself. Without one of them the test says it was skipped and why, and passes; with
//! `HIL_REQUIRED=1` (CI, which installs them) it fails instead.

mod common;

#[test]
fn a_flooding_ground_station_neither_starves_the_vehicle_nor_changes_its_mission() {
    common::python_check("flood", "tests/flood.py");
}
