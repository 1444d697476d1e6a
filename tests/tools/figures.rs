//! `--output DIR` of `estimate`, `formation` and `mission` (the paper's figures):
//! each writes the files it lists under `files` in its JSON, named from the scenario's `name`
//! (not its file name), inside the folder, the PNGs and SVGs well formed; the text output
//! names the same files. Small trial counts keep them fast.

use crate::common;
use common::{host_sim, scenario_path};

use std::path::{Path, PathBuf};

/// A fresh folder for one test's files.
fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-fig-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A copy of paper scenario `paper` in `dir` whose `name` is `name`.
fn renamed(dir: &Path, paper: &str, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenario_path(paper))
        .expect("paper scenario")
        .replace(
            &format!("name = \"{paper}\""),
            &format!("name = \"{name}\""),
        );
    let path = dir.join("renamed.toml");
    std::fs::write(&path, text).expect("write");
    path
}

/// Runs `args` with `--json`, checks the run and returns the files its JSON lists, each
/// checked: inside `out`, present, and a well-formed PNG or SVG where it is one.
fn files_of(args: &[&str], out: &Path) -> (serde_json::Value, Vec<String>) {
    let output = host_sim(&[args, &["--json"]].concat());
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{args:?}: {stderr}");
    assert!(!stderr.contains("figure"), "a figure was skipped: {stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    let files: Vec<String> = v["files"]
        .as_array()
        .expect("files")
        .iter()
        .map(|f| f.as_str().expect("path").to_string())
        .collect();
    let mut names = Vec::new();
    for f in &files {
        let path = PathBuf::from(f);
        assert_eq!(path.parent(), Some(out), "{f} outside {out:?}");
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{f}: {e}"));
        if f.ends_with(".png") {
            assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{f}: not a PNG");
        }
        if f.ends_with(".svg") {
            let text = String::from_utf8_lossy(&bytes);
            assert!(text.contains("<svg") && text.contains("</svg>"), "{f}");
        }
        names.push(
            path.file_name()
                .expect("name")
                .to_string_lossy()
                .into_owned(),
        );
    }
    (v, names)
}

/// Asserts that `names` holds each of `expected`.
fn assert_holds(names: &[String], expected: &[String]) {
    for e in expected {
        assert!(names.contains(e), "{e} not listed: {names:?}");
    }
}

#[test]
fn estimate_writes_the_trials_the_steps_and_the_papers_figures_6_and_7() {
    let dir = temp_dir("estimate");
    let scenario = renamed(&dir, "rect-sim1", "estimate figures");
    let out = dir.join("out");
    let args = [
        "estimate",
        "--scenario",
        path_str(&scenario),
        "--trials",
        "3",
        "--seed",
        "2",
        "--output",
        path_str(&out),
    ];
    let (_, names) = files_of(&args, &out);
    let stem = "estimate_figures-estimate";
    let mut expected: Vec<String> = ["trials.csv", "steps.json", "summary.png", "summary.svg"]
        .iter()
        .map(|f| format!("{stem}-{f}"))
        .collect();
    // One page per step of the first trial: the start, then each lift.
    let steps: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join(format!("{stem}-steps.json"))).expect("steps"),
    )
    .expect("steps JSON");
    let count = steps["steps"].as_array().expect("steps").len();
    assert!(count >= 2, "the start and at least one lift: {count}");
    for k in 0..count {
        expected.push(format!("{stem}-step-{k}.png"));
        expected.push(format!("{stem}-step-{k}.svg"));
    }
    assert_holds(&names, &expected);
    assert_eq!(names.len(), expected.len(), "{names:?}");
    let csv = std::fs::read_to_string(out.join(format!("{stem}-trials.csv"))).expect("csv");
    assert_eq!(csv.lines().count(), 1 + 3, "a header and one row per trial");
    // The text output names the same files.
    let text = host_sim(&args);
    let text = String::from_utf8_lossy(&text.stdout);
    for e in &expected {
        assert!(text.contains(e.as_str()), "{e} not in: {text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn formation_writes_both_formations_and_their_figure() {
    let dir = temp_dir("formation");
    let scenario = renamed(&dir, "L-sim1", "../L shape");
    let out = dir.join("out");
    let (v, names) = files_of(
        &[
            "formation",
            "--scenario",
            path_str(&scenario),
            "--com",
            "0.3,0.2",
            "--mass",
            "3",
            "--output",
            path_str(&out),
        ],
        &out,
    );
    let expected: Vec<String> = ["csv", "png", "svg"]
        .iter()
        .map(|e| format!("L_shape-formation.{e}"))
        .collect();
    assert_holds(&names, &expected);
    assert_eq!(names.len(), 3, "{names:?}");
    assert!(v["det"].is_number(), "the usual report is still there: {v}");
    let csv = std::fs::read_to_string(out.join("L_shape-formation.csv")).expect("csv");
    assert_eq!(csv.lines().count(), 1 + 8, "a header and one row per robot");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn mission_writes_the_flight_and_the_one_page_summary() {
    let dir = temp_dir("mission");
    let out = dir.join("out");
    // The built-in rect-ex1: about a second.
    let (_, names) = files_of(&["mission", "--output", path_str(&out)], &out);
    let expected: Vec<String> = [
        "mission-flight.csv",
        "mission-flight.png",
        "mission-summary.png",
        "mission-summary.svg",
    ]
    .iter()
    .map(|f| format!("rect-ex1-{f}"))
    .collect();
    assert_holds(&names, &expected);
    assert_eq!(names.len(), expected.len(), "{names:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn without_output_nothing_is_listed() {
    let rect = scenario_path("rect-sim1");
    let output = host_sim(&["formation", "--scenario", path_str(&rect), "--json"]);
    let v: serde_json::Value =
        serde_json::from_str(&String::from_utf8_lossy(&output.stdout)).expect("JSON");
    assert!(v.get("files").is_none(), "{v}");
}
