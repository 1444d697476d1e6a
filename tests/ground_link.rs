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

mod common;

use common::{image_or_skip, skip, workspace};
use std::process::Command;

/// The test's name in what it says when skipped.
const TEST: &str = "ground station";

/// Exit status of the script when pymavlink is missing.
const NO_PYMAVLINK: i32 = 2;

#[test]
fn a_pymavlink_ground_station_tunes_restarts_and_flies_the_firmware() {
    let Some(elf) = image_or_skip(TEST) else {
        return;
    };
    let script = workspace().join("tests/ground_station.py");
    let output = match Command::new("python3")
        .arg(&script)
        .arg("--host-sim")
        .arg(env!("CARGO_BIN_EXE_host-sim"))
        .arg("--elf")
        .arg(&elf)
        .arg("--scenario")
        .arg(workspace().join("tests/scenarios/rect-ex1.toml"))
        .output()
    {
        Ok(output) => output,
        Err(e) => return skip(TEST, &format!("python3 cannot be run ({e})")),
    };
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    if output.status.code() == Some(NO_PYMAVLINK) {
        return skip(TEST, stderr.trim());
    }
    assert!(
        output.status.success(),
        "the ground station failed ({}):\n{stdout}\n{stderr}",
        output.status
    );
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{stdout}");
}
