//! Hardware in the loop: the plant side of PX4's simulator MAVLink API, in lockstep, against
//! the real firmware (docs/firmware.md#hil-protocol).
//!
//! - [`transport`]: the byte link (QEMU's UART on a local socket, a serial device), framed.
//! - [`qemu`]: runs the firmware's QEMU image under `qemu-system-arm`.
//! - [`session`]: the conversation: identity, the payload description over MAVLink FTP, the
//!   start command, lockstep steps, and the log of what the firmware said.
//! - [`gcs`]: the ground-station bridge (`--gcs`).
//! - [`rc_link`]: the board's RC receiver UART, CRSF frames from a stick script (`--rc`).
//! - [`run`]: the plant loop: physics, sensors, lockstep, pacing, the outcome.
//!
//! The protocol logic itself (framing, messages, FTP, lockstep matching) is the `link` crate's,
//! the same code the firmware runs.

pub mod gcs;
pub mod qemu;
pub mod rc_link;
pub mod run;
pub mod session;
pub mod transport;
