//! The `host-sim` command line as its user meets it, and the repository's own checks: flags,
//! exit codes and scenario files (good and broken), the figures and the flight log's plot,
//! the thrust calibration, and the citations of `docs/`. `cargo test -p host-sim --test
//! tools`; one module: `... --test tools plot::`.

#[path = "../common/mod.rs"]
mod common;

mod broken_scenarios;
mod campaign;
mod command_line;
mod docs_links;
mod figures;
mod plot;
mod scenarios;
mod thrust_calibration;
