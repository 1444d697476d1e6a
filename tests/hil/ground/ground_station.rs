//! The ground link driven by a real ground-station client: runs
//! `tests/ground_station.py` (pymavlink) against the firmware under QEMU through
//! `host-sim hil --gcs`: identity, every parameter, refusals, a value kept over a restart,
//! the mission started from the ground and followed to the landing. What it checks is
//! listed at the top of the script.
//!
//! Needs `python3` with `pymavlink` and `qemu-system-arm`; it builds the firmware's QEMU
//! image itself (`FIRMWARE_QEMU_ELF` names another). Without one of them the test says it
//! was skipped and why, and passes; with `HIL_REQUIRED=1` (CI, which installs them) it fails
//! instead.

use crate::common;

#[test]
fn a_pymavlink_ground_station_tunes_restarts_and_flies_the_firmware() {
    common::python_check("ground station", "tests/ground_station.py");
}
