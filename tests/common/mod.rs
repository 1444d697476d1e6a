//! Helpers the scenario tests share: where the scenario files are, loading one, running the
//! `host-sim` binary.
#![allow(dead_code)] // each test crate uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Path of `tests/scenarios/<name>.toml`.
pub fn scenario_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/scenarios")
        .join(format!("{name}.toml"))
}

/// A paper scenario, read and checked.
pub fn load(name: &str) -> shared::scenario::Scenario {
    host_sim::scenario_file::load(&scenario_path(name))
        .expect("paper scenario")
        .scenario
}

/// Runs the `host-sim` binary with `args`.
pub fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim runs")
}
