//! Scenario tests, run by `cargo test -p host-sim`: the paper's scenario files (the cases of
//! docs/system.md#paper-cases, in `tests/scenarios/`) load and pass every check. Broken files are in
//! `tests/broken-scenarios/` with their own test (`broken_scenarios.rs`).

use crate::common;
use common::{PAPER_CASES, host_sim, scenario_path};

use host_sim::scenario_file;

#[test]
fn every_paper_scenario_loads_with_the_grid_spec_md_defines() {
    for name in PAPER_CASES {
        let loaded = scenario_file::load(&scenario_path(name))
            .unwrap_or_else(|e| panic!("{name} must load: {e:#}"));
        assert_eq!(loaded.name, name);
        let s = &loaded.scenario;
        assert_eq!(s.robots.count(), 8, "{name}");
        let shape = [0, 1, 2].map(|a| s.estimation.axis_len(a));
        let expected = match &name[..4] {
            "rect" if name.contains("ex") => [9, 4, 5],
            "rect" => [11, 4, 4],
            _ => [9, 9, 5],
        };
        assert_eq!(shape, expected, "{name}: floor((max-min)/res + 1e-9) + 1");
        let truth = s.truth.expect("paper cases carry their truth");
        assert!(s.payload.hull.contains(truth.com, 0.0), "{name}");
    }
}

#[test]
fn validate_prints_one_json_object() {
    let path = scenario_path("L-sim1");
    let out = host_sim(&["validate", "--scenario", path.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is JSON");
    assert_eq!(v["name"], "L-sim1");
    assert_eq!(
        v["hull"].as_array().map(Vec::len),
        Some(5),
        "L hull drops the inner corner"
    );
    let rail = v["rail_length"].as_f64().unwrap();
    assert!((rail - 3.44).abs() < 1e-4, "L rail length {rail}");
}

#[test]
fn unknown_command_and_missing_file_are_clear_errors() {
    let out = host_sim(&["frobnicate"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("frobnicate"), "{err}");

    let out = host_sim(&["validate", "--scenario", "/nonexistent/none.toml"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cannot read scenario file /nonexistent/none.toml"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
}

/// `shared::paper` carries rect-sim1 and L-sim1 built in (for target benchmarks); they must be
/// the files' values.
#[test]
fn built_in_paper_cases_match_the_files() {
    use shared::paper;
    for (name, built_in) in [
        ("rect-sim1", paper::rect_sim1()),
        ("L-sim1", paper::l_sim1()),
    ] {
        let file = scenario_file::load(&scenario_path(name))
            .expect("loads")
            .scenario;
        let built_in = paper::checked(built_in);
        assert_eq!(file.payload, built_in.payload, "{name}");
        assert_eq!(file.robots, built_in.robots, "{name}");
        assert_eq!(file.estimation, built_in.estimation, "{name}");
        assert_eq!(file.formation, built_in.formation, "{name}");
        assert_eq!(file.truth, built_in.truth, "{name}");
    }
}
