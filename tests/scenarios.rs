//! Scenario tests, run by `cargo test -p host-sim`: the paper's scenario files (copied from
//! SPEC.md's set into `tests/scenarios/`) and the command line's handling of bad input
//! (SPEC.md section 5: a one-line error naming the key, a non-zero exit, never a panic).

mod common;
use common::{host_sim, scenario_path};

use std::path::PathBuf;

use host_sim::scenario_file;

const PAPER_CASES: [&str; 6] = [
    "rect-sim1",
    "rect-sim2",
    "L-sim1",
    "L-sim2",
    "rect-ex1",
    "rect-ex2",
];

/// Writes `text` to a fresh temporary scenario file and returns its path.
fn temp_scenario(tag: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(format!("{tag}.toml"));
    std::fs::write(&path, text).expect("write temp scenario");
    path
}

fn paper_text(name: &str) -> String {
    std::fs::read_to_string(scenario_path(name)).expect("paper scenario present")
}

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

/// Each broken scenario must fail with one line on stderr naming the key.
#[test]
fn bad_scenarios_name_the_key_and_never_panic() {
    let base = paper_text("rect-sim1");
    let cases: [(&str, String, &str); 7] = [
        (
            "malformed",
            base.replace("count = 8", "count = = 8"),
            "line",
        ),
        (
            "resolution",
            base.replace(
                "resolution = [0.1, 0.03, 0.5]",
                "resolution = [0.1, 0.0, 0.5]",
            ),
            "estimation.resolution",
        ),
        (
            "self-intersecting",
            base.replace(
                "footprint = [[-0.88, -0.1], [0.88, -0.1], [0.88, 0.1], [-0.88, 0.1]]",
                "footprint = [[-0.88, -0.1], [0.88, 0.1], [0.88, -0.1], [-0.88, 0.1]]",
            ),
            "payload.footprint",
        ),
        (
            "fewer-robots",
            base.replace("count = 8", "count = 1")
                .replace("spin = [1, -1, 1, -1, 1, -1, 1, -1]", "spin = [1]"),
            "robots.pair_size",
        ),
        (
            "unreachable-candidate",
            base.replace("4.32, 4.66]", "4.32, 6.5]"),
            "payload.candidates",
        ),
        (
            "missing-key",
            base.replace("threshold = 0.8\n", ""),
            "threshold",
        ),
        (
            "truth-outside",
            base.replace("com = [0.33, 0.01]", "com = [0.95, 0.01]"),
            "truth.com",
        ),
    ];
    for (tag, text, key) in cases {
        assert_ne!(text, base, "{tag}: the edit must change the file");
        let path = temp_scenario(tag, &text);
        let out = host_sim(&["validate", "--scenario", path.to_str().unwrap(), "--json"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{tag}: {err}");
        assert!(out.stdout.is_empty(), "{tag}: nothing on stdout");
        assert!(err.contains(key), "{tag}: error must name {key}: {err}");
        assert!(!err.contains("panicked"), "{tag}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{tag}: one line: {err}");
    }
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
