//! What the fuzz targets (`fuzz_targets/`) run, and the seed corpora they start from. See
//! `fuzz/README.md`.
//!
//! The targets call the code the vehicle and the simulator run, from their crates: the
//! firmware's receive service and autonomy seam (`onboard`), the payload description's
//! decoder and checks (`shared`), the host's scenario loader (`scenario-toml`). What is this
//! crate's own: the harness that plays the firmware's other tasks ([`vehicle`], [`tasks`]), a
//! ground side that reads back what the vehicle sends ([`ground`]), a flash in RAM
//! ([`flash`]), and the seeds.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod flash;
pub mod ground;
pub mod options;
pub mod seeds;
pub mod tasks;
pub mod vehicle;

/// A gyro reading of a vehicle at rest at step `i`: noise of about 0.6 mrad/s, as a real
/// sensor's (the same for the same `i`, so a seed replays the same).
pub fn rest_noise(i: u64) -> f32 {
    let h = i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
    (h as f32 / (1u64 << 24) as f32 - 0.5) * 2e-3
}
