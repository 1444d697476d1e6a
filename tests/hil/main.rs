//! The firmware in the loop: its ARM image (`cargo fw-qemu`'s build, made by the tests when
//! missing or stale; `FIRMWARE_QEMU_ELF` names another) on `qemu-system-arm -M mps2-an500`,
//! the plant in lockstep over MAVLink. `lockstep` drives it from this process, `rc` plays stick
//! scripts into its RC receiver UART (`hil --rc`), `flight_log`
//! checks its log (kept as the simulator's, downloaded by pymavlink and MAVProxy), and
//! `ground` runs the other Python ground stations against it (`tests/*.py`). Without QEMU (or
//! Python and its packages) each test says it was skipped and why, and passes; with
//! `HIL_REQUIRED=1` (CI) it fails instead.
//!
//! The tests run side by side (libtest's threads) and take turns at QEMU: at most `HIL_JOBS`
//! (default 2) firmware runs at once (`common::qemu_slot`). The one flight three tests need is
//! flown once (`storage_flight`). `cargo test -p host-sim --test hil`; the Python checks
//! alone: `... --test hil -- ground:: flight_log::download`.

#[path = "../common/mod.rs"]
mod common;

mod flight_log;
mod ground;
mod lockstep;
mod rc;
mod storage_flight;
