//! `host-sim calibrate thrust` run as the engineer runs it (docs/commands.md#calibrating-the-thrust-map):
//! a bench sweep made from a known map gives that map back as the four parameters, in JSON and
//! as `param set` lines to paste, and every bench file it cannot use is refused with exit code
//! 1 and one line naming the file's line (or the missing interval) and what is wrong.

use crate::common;
use common::{host_sim, scenario_path, workspace};

use std::path::PathBuf;

/// The map the generated sweeps come from: not the square law (0.04, 0.16, 0.36, 0.64).
const MAP: [f64; 4] = [0.07, 0.21, 0.41, 0.68];
const FULL_N: f64 = 11.5;
const NAMES: [&str; 4] = ["THR_MAP_20", "THR_MAP_40", "THR_MAP_60", "THR_MAP_80"];
/// The map of the sample file tests/bench/thrust-sweep.csv (its comment says so), full thrust
/// 14.2 N, read with 0.04 N of noise.
const SAMPLE_MAP: [f64; 4] = [0.055, 0.19, 0.385, 0.66];

/// Thrust of `map` at `command`, N.
fn thrust(map: [f64; 4], full: f64, command: f64) -> f64 {
    let knots = [0.0, map[0], map[1], map[2], map[3], 1.0];
    let position = command * 5.0;
    let j = (position.ceil() as usize).clamp(1, 5) - 1;
    let along = position - j as f64;
    full * (knots[j] + along * (knots[j + 1] - knots[j]))
}

/// Writes `text` to a fresh file for test `tag` and returns its path.
fn bench_file(tag: &str, text: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("host-sim-thrust-cal-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("bench.csv");
    std::fs::write(&path, text).expect("write the bench file");
    path
}

/// Runs `calibrate thrust --bench FILE` with `extra` flags: (exit code, stdout, stderr).
fn calibrate(bench: &std::path::Path, extra: &[&str]) -> (Option<i32>, String, String) {
    let bench = bench.to_str().expect("utf-8 path");
    let args = [&["calibrate", "thrust", "--bench", bench][..], extra].concat();
    let out = host_sim(&args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The JSON of a run that succeeded.
fn report(bench: &std::path::Path, extra: &[&str]) -> serde_json::Value {
    let (code, stdout, stderr) = calibrate(bench, &[&["--json"][..], extra].concat());
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(stdout.lines().count(), 1, "one JSON line: {stdout}");
    serde_json::from_str(&stdout).expect("JSON")
}

/// The parameters of a report, in the order of [`NAMES`].
fn params(v: &serde_json::Value) -> [f64; 4] {
    NAMES.map(|name| v["params"][name].as_f64().expect("a number per parameter"))
}

/// Asserts a refusal of `text`: exit code 1, nothing on stdout, one line on stderr naming the
/// file and holding each of `says`. Returns the line.
fn refused(tag: &str, text: &str, says: &[&str]) -> String {
    let bench = bench_file(tag, text);
    let (code, stdout, stderr) = calibrate(&bench, &["--json"]);
    let err = stderr.trim_end();
    assert_eq!(code, Some(1), "{tag}: {err}");
    assert!(stdout.is_empty(), "{tag}: stdout {stdout}");
    assert_eq!(err.lines().count(), 1, "{tag}: one line: {err}");
    assert!(!err.contains("panicked"), "{tag}: {err}");
    assert!(
        err.starts_with(&format!("error: {}: ", bench.display())),
        "{tag}: names the file: {err}"
    );
    for s in says {
        assert!(err.contains(s), "{tag}: must say {s:?}: {err}");
    }
    err.to_string()
}

/// A good sweep as a bench tool writes it: extra columns, `thrust_n` before `command`, three
/// readings per command from 0 to 1 in steps of 0.05, a load cell reading `offset` N at rest.
fn good_sweep(offset: f64) -> String {
    let mut text = String::from("time_s,thrust_n,voltage_v,command\n");
    for i in 0..=20 {
        let command = f64::from(i) / 20.0;
        for k in 0..3 {
            let n = thrust(MAP, FULL_N, command) + offset;
            text.push_str(&format!("{},{n},16.2,{command}\n", 3 * i + k));
        }
    }
    text
}

#[test]
fn a_bench_sweep_gives_back_the_map_that_made_it() {
    let bench = bench_file("good", &good_sweep(0.02));
    let v = report(&bench, &[]);
    let got = params(&v);
    for k in 0..4 {
        assert!((got[k] - MAP[k]).abs() <= 1e-4, "{}: {got:?}", NAMES[k]);
    }
    let full = v["full_thrust_n"].as_f64().expect("full_thrust_n");
    assert!((full - FULL_N).abs() < 1e-9, "{full}");
    assert!((v["tare_n"].as_f64().expect("tare_n") - 0.02).abs() < 1e-12);
    let error = v["max_error_fraction"]
        .as_f64()
        .expect("max_error_fraction");
    assert!((0.0..1e-4).contains(&error), "{error}");
    assert_eq!(v["readings"], 63);
    assert_eq!(v["extrapolated"], false);
    let points = v["points"].as_array().expect("points");
    assert_eq!(points.len(), 21);
    assert_eq!(points[4]["command"], 0.2);
    assert_eq!(points[4]["lines"], serde_json::json!([14, 15, 16]));
    assert!(v["scenario_max_thrust_n"].is_null());
}

#[test]
fn the_sample_sweep_prints_the_lines_to_paste_into_mavproxy() {
    let sample = workspace().join("tests/bench/thrust-sweep.csv");
    let (code, stdout, stderr) = calibrate(&sample, &[]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("full thrust 14."), "{stdout}");
    assert!(stdout.contains("66 readings at 21 commands"), "{stdout}");
    let sets: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("param set "))
        .collect();
    assert_eq!(sets.len(), 4, "{stdout}");
    for ((line, name), want) in sets.iter().zip(NAMES).zip(SAMPLE_MAP) {
        let value = line
            .strip_prefix(&format!("param set {name} "))
            .unwrap_or_else(|| panic!("{line}: not {name}"));
        assert_eq!(value.len(), 6, "four decimals: {line}");
        let value: f64 = value.parse().expect("a number");
        // Three readings of 0.04 N noise per command against 14.2 N.
        assert!((value - want).abs() < 0.005, "{line} against {want}");
    }
    // The parameters are the last lines: what to paste ends the output.
    assert_eq!(stdout.lines().last(), sets.last().copied());

    let rect = scenario_path("rect-ex1");
    let v = report(&sample, &["--scenario", rect.to_str().expect("utf-8 path")]);
    assert_eq!(v["scenario_max_thrust_n"], 14.2);
    let full = v["full_thrust_n"].as_f64().expect("full_thrust_n");
    assert!((full - 14.2).abs() < 0.1, "{full}");
    let got = params(&v);
    for k in 0..4 {
        assert!(
            (got[k] - SAMPLE_MAP[k]).abs() < 0.005,
            "{}: {got:?}",
            NAMES[k]
        );
    }
    let error = v["max_error_fraction"]
        .as_f64()
        .expect("max_error_fraction");
    assert!(error > 0.0 && error < 0.01, "{error}");
}

#[test]
fn an_empty_file_is_refused() {
    refused("empty", "", &["line 1: the file is empty"]);
}

#[test]
fn a_missing_column_is_refused_naming_the_header() {
    refused(
        "column",
        "command,thrust\n0.2,1\n",
        &["line 1: the header has no `thrust_n` column"],
    );
}

#[test]
fn a_value_that_is_not_a_number_is_refused_naming_its_line() {
    let good = good_sweep(0.0);
    let nan = good.replacen(",16.2,0.25\n", ",16.2,NaN\n", 1);
    refused(
        "nan",
        &nan,
        &["line 17: `command` value `NaN` is not a finite number"],
    );
    let text = good.replacen("\n6,", "\n6,abc", 1);
    refused("text", &text, &["line 8: `thrust_n` value"]);
}

#[test]
fn a_command_outside_0_to_1_is_refused_naming_its_line() {
    let text = "command,thrust_n\n0.2,1\n40,2\n";
    refused(
        "percent",
        text,
        &["line 3: command 40 is outside 0..1", "not percent"],
    );
}

#[test]
fn thrust_that_falls_is_refused_naming_its_lines() {
    let text = "command,thrust_n\n0,0\n0.2,1\n0.4,3\n0.6,2.5\n0.6,2.4\n0.8,5\n1,7\n";
    refused(
        "falls",
        text,
        &[
            "lines 5 and 6: thrust falls as the command rises",
            "below the 3.000 N at command 0.4 (line 4)",
        ],
    );
    // Negative readings: a load cell mounted the other way.
    let text = "command,thrust_n\n0,0\n0.2,-1\n0.4,-3\n0.6,-5\n0.8,-7\n1,-9\n";
    refused(
        "negative",
        text,
        &["line 7: at the top command 1", "flip the sign"],
    );
}

#[test]
fn too_few_readings_are_refused_naming_what_is_missing() {
    refused(
        "header-only",
        "command,thrust_n\n",
        &["no readings below the header"],
    );
    let text = "command,thrust_n\n0,0\n0.2,1\n0.4,2\n0.8,5\n1,7\n";
    refused(
        "gap",
        text,
        &[
            "no reading with a command in (0.4, 0.6]",
            "to set the map at 60 % command",
        ],
    );
    let text = "command,thrust_n\n0,0\n0.2,1\n0.4,2\n0.6,3\n0.8,4\n0.85,5\n";
    refused(
        "short",
        text,
        &["line 7: the sweep stops at command 0.85, below 0.9"],
    );
}

#[test]
fn a_map_the_firmware_cannot_hold_is_refused_with_the_reason() {
    // No thrust up to 20 %: an ESC dead band the map cannot express.
    let text = "command,thrust_n\n0,0\n0.1,0\n0.2,0\n0.4,2\n0.6,4\n0.8,6\n1,8\n";
    refused(
        "dead-band",
        text,
        &[
            "THR_MAP_20 would be 0, outside 0.001..0.999",
            "at 20 % command",
        ],
    );
}
