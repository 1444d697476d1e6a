//! What the fuzz targets (`fuzz_targets/`) run, and the seed corpora they start from. See
//! `fuzz/README.md`.
//!
//! Two source files of crates that do not build here are compiled in as they are, so the
//! targets run exactly their code:
//! - `firmware/src/app/autonomy.rs` ([`autonomy`]): the firmware's seam to the mission (the
//!   firmware crate itself only builds for the Cortex-M7: embassy, cortex-m);
//! - `host-sim/src/scenario_file.rs` ([`scenario_file`]): the host's scenario TOML loader
//!   (host-sim itself pulls rapier3d and plotters, many minutes to build instrumented).
//!
//! Both use only `link`, `shared`, `heapless`, and `std`, `anyhow`, `serde`, `toml`; should
//! either start using more, this crate needs it too (CI's `.ci/fuzz` builds it).
#![forbid(unsafe_code)]
#![deny(missing_docs)]

#[path = "../../firmware/src/app/autonomy.rs"]
pub mod autonomy;
pub mod flash;
pub mod options;
#[path = "../../host-sim/src/scenario_file.rs"]
pub mod scenario_file;
pub mod seeds;
pub mod vehicle;

/// A gyro reading of a vehicle at rest at step `i`: noise of about 0.6 mrad/s, as a real
/// sensor's (the same for the same `i`, so a seed replays the same).
pub fn rest_noise(i: u64) -> f32 {
    let h = i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
    (h as f32 / (1u64 << 24) as f32 - 0.5) * 2e-3
}
