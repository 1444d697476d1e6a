//! Real ground-station clients against the firmware under QEMU, through `host-sim hil --gcs`:
//! the Python checks `tests/*.py` (pymavlink, MAVProxy, MAVSDK-Python), one test each (the
//! log download's is `flight_log::download`). Each
//! needs `python3` with its packages and `qemu-system-arm`; without one the test says it was
//! skipped and why, and passes; with `HIL_REQUIRED=1` (CI, which installs them) it fails.

mod bringup;
mod flood;
mod ground_station;
mod mavsdk_mission;
mod mission_protocol;
