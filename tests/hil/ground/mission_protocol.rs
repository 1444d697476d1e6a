//! The mission protocol's edge cases with a real ground-station client: runs
//! `tests/mission_protocol.py` (pymavlink) against the firmware under QEMU through
//! `host-sim hil --gcs`: a count over capacity, items out of order, bad items, an upload that
//! stops, a clear and an upload in flight, the modes, every item reached and the payload
//! delivered. What it checks is listed at the top of the script.
//!
//! Needs `python3` with `pymavlink` and `qemu-system-arm`; it builds the firmware's QEMU
//! image itself. Without one of them the test says it was skipped and why, and passes; with
//! `HIL_REQUIRED=1` (CI, which installs them) it fails instead.

use crate::common;

#[test]
fn the_mission_protocol_holds_its_edge_cases_and_flies_the_uploaded_mission() {
    common::python_check("mission protocol", "tests/mission_protocol.py");
}
