//! The command line's own safety (docs/formats.md#command-line; docs/commands.md#exit-codes): flag values are
//! checked and named, negative numbers parse, a scenario cannot make the tool write outside
//! `--output`, an endless or huge file is refused, a closed stdout ends the run quietly, and
//! the exit code tells how a mission or flight ended.

use crate::common;
use common::{host_sim, scenario_path};

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// A fresh folder for one test's files.
fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-cli-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Runs host-sim and returns (exit code, stdout, stderr).
fn run(args: &[&str]) -> (Option<i32>, String, String) {
    let out = host_sim(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Asserts a bad-input refusal: exit code 1, one line on stderr naming `flag`, nothing on
/// stdout, no panic, and no `inf` or `NaN` that the input did not hold.
fn assert_refused(args: &[&str], flag: &str) -> String {
    let (code, stdout, stderr) = run(args);
    assert_eq!(code, Some(1), "{args:?}: {stderr}");
    assert!(stdout.is_empty(), "{args:?}: stdout {stdout}");
    let err = stderr.trim_end();
    assert_eq!(err.lines().count(), 1, "{args:?}: one line: {err}");
    assert!(err.contains(flag), "{args:?}: must name {flag}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    // A result that is not a number must never be printed (an input that is one may be
    // echoed).
    let given = args.join(" ").to_lowercase();
    for bad in ["NaN", " inf"] {
        if !given.contains(&bad.trim().to_lowercase()) {
            assert!(!err.contains(bad), "{args:?}: {err}");
        }
    }
    err.to_string()
}

#[test]
fn absurd_flag_values_are_refused_naming_the_flag() {
    let rect = scenario_path("rect-sim1");
    let rect = path_str(&rect);
    let lift = [
        "lift",
        "--scenario",
        rect,
        "--pair",
        "0",
        "--com",
        "0.1,0.0",
    ];
    let err = assert_refused(&[&lift[..], &["--mass", "1e40"]].concat(), "--mass");
    assert!(err.contains("1000 kg"), "{err}");
    assert_refused(&[&lift[..], &["--mass", "0"]].concat(), "--mass");
    assert_refused(&[&lift[..], &["--mass", "nan"]].concat(), "--mass");

    let estimate = ["estimate", "--scenario", rect, "--json"];
    assert_refused(&[&estimate[..], &["--truth=0,0,1e40"]].concat(), "--truth");
    let err = assert_refused(
        &[&estimate[..], &["--trials", "100000000"]].concat(),
        "--trials",
    );
    assert!(err.contains("10000"), "{err}");
    assert_refused(
        &[&estimate[..], &["--map-error", "1e30"]].concat(),
        "--map-error",
    );
    // A bad thrust-scale axis is the flag's fault, not the scenario file's.
    for axis in ["0.9,1e30,0.05", "1.2,0.9,0.05", "0.9,1.2,0", "0.9,1.2,1e-9"] {
        let err = assert_refused(
            &[&estimate[..], &["--thrust-scale", axis]].concat(),
            "--thrust-scale",
        );
        assert!(!err.contains("rect-sim1.toml"), "{err}");
    }

    let mission = ["mission", "--json"];
    assert_refused(
        &[&mission[..], &["--lift-sigma", "0"]].concat(),
        "--lift-sigma",
    );
    assert_refused(
        &[&mission[..], &["--lift-sigma", "1e9"]].concat(),
        "--lift-sigma",
    );
    assert_refused(
        &[&mission[..], &["--mocap-lost-after", "nan"]].concat(),
        "--mocap-lost-after",
    );
    assert_refused(
        &[&mission[..], &["--mocap-lost-after", "-1"]].concat(),
        "--mocap-lost-after",
    );
    assert_refused(
        &[&mission[..], &["--map-error", "1e30"]].concat(),
        "--map-error",
    );

    let formation = ["formation", "--scenario", rect, "--json"];
    assert_refused(&[&formation[..], &["--mass", "-3"]].concat(), "--mass");
    assert_refused(&[&formation[..], &["--com", "5,0"]].concat(), "--com");
}

#[test]
fn negative_numbers_parse_with_and_without_equals() {
    let rect = scenario_path("rect-sim1");
    let rect = path_str(&rect);
    let thrust = |com: &[&str]| -> f64 {
        let args = [
            &[
                "lift",
                "--scenario",
                rect,
                "--pair",
                "0",
                "--mass",
                "3",
                "--json",
            ][..],
            com,
        ]
        .concat();
        let (code, stdout, stderr) = run(&args);
        assert_eq!(code, Some(0), "{args:?}: {stderr}");
        let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
        v["thrust"].as_f64().expect("finite thrust")
    };
    let spaced = thrust(&["--com", "-0.2,-0.05"]);
    let joined = thrust(&["--com=-0.2,-0.05"]);
    assert_eq!(spaced, joined);
    assert_ne!(spaced, thrust(&["--com", "0.2,-0.05"]), "the sign was read");
    // A negative mass is read as a number (and refused as a mass), not as an unknown flag.
    let err = assert_refused(
        &[
            "lift",
            "--scenario",
            rect,
            "--pair",
            "0",
            "--com",
            "0,0",
            "--mass",
            "-3",
        ],
        "--mass",
    );
    assert!(err.contains("-3"), "{err}");
}

#[test]
fn json_numbers_print_as_their_shortest_decimal() {
    let rect = scenario_path("rect-sim1");
    let (code, stdout, stderr) = run(&["validate", "--scenario", path_str(&rect), "--json"]);
    assert_eq!(code, Some(0), "{stderr}");
    // The candidates' arc lengths are f32 values such as 0.12 and 0.56.
    assert!(stdout.contains("\"arc_length\":0.12"), "{stdout}");
    assert!(!stdout.contains("0.1199999"), "{stdout}");
    assert!(!stdout.contains("0.5600000"), "{stdout}");
}

#[test]
fn a_scenario_name_cannot_write_outside_the_output_folder() {
    let dir = temp_dir("escape");
    let text = std::fs::read_to_string(scenario_path("rect-sim1"))
        .expect("paper scenario")
        .replace("name = \"rect-sim1\"", "name = \"../../escaped\"");
    let scenario = dir.join("escape.toml");
    std::fs::write(&scenario, text).expect("write");
    let out = dir.join("a/b/out");
    let (code, stdout, stderr) = run(&[
        "fly",
        "--scenario",
        path_str(&scenario),
        "--formation",
        "optimized",
        "--output",
        path_str(&out),
        "--json",
    ]);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(code.is_some(), "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    let files: Vec<PathBuf> = v["files"]
        .as_array()
        .expect("files")
        .iter()
        .map(|f| PathBuf::from(f.as_str().expect("path")))
        .collect();
    assert!(!files.is_empty());
    for f in &files {
        assert_eq!(f.parent(), Some(out.as_path()), "{f:?} outside {out:?}");
        assert!(f.exists(), "{f:?}");
    }
    // Nothing landed where `../../` would have put it.
    for above in [dir.join("a"), dir.join("a/b")] {
        let stray: Vec<_> = std::fs::read_dir(&above)
            .expect("folder")
            .map(|e| e.expect("entry").file_name())
            .filter(|n| n.to_string_lossy().contains("escaped"))
            .collect();
        assert!(stray.is_empty(), "{above:?}: {stray:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_endless_scenario_file_is_refused_quickly() {
    let started = std::time::Instant::now();
    let err = assert_refused(&["validate", "--scenario", "/dev/zero"], "/dev/zero");
    assert!(err.contains("larger than 1024 KiB"), "{err}");
    // Reading 1 MiB takes milliseconds; reading /dev/zero to its end never ends.
    assert!(started.elapsed().as_secs() < 20, "{:?}", started.elapsed());
    let dir = temp_dir("binary");
    let binary = dir.join("binary.toml");
    std::fs::write(&binary, [0xff, 0xfe, 0x00, 0x41]).expect("write");
    let err = assert_refused(
        &["validate", "--scenario", path_str(&binary)],
        "binary.toml",
    );
    assert!(err.contains("UTF-8"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_closed_stdout_ends_the_mission_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("mission")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("host-sim starts");
    let stdout = child.stdout.take().expect("stdout");
    let mut first = String::new();
    BufReader::new(stdout)
        .read_line(&mut first)
        .expect("first line");
    assert!(first.starts_with("mission on rect-ex1"), "{first}");
    // The reader is dropped here, as `head -1` exits: the next line hits a broken pipe.
    let out = child.wait_with_output().expect("exits");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.trim().is_empty(), "quiet: {stderr}");
    assert_eq!(out.status.code(), Some(0), "{stderr}");
}

#[test]
fn a_mission_that_aborts_exits_with_its_own_code() {
    // One lift can never reach a 0.999 posterior mass: the mission aborts on the ground.
    let dir = temp_dir("abort");
    let text = std::fs::read_to_string(scenario_path("rect-ex1"))
        .expect("paper scenario")
        .replace("threshold = 0.53", "threshold = 0.999")
        .replace("max_measurements = 20", "max_measurements = 1");
    let scenario = dir.join("one-lift.toml");
    std::fs::write(&scenario, text).expect("write");
    let (code, stdout, stderr) = run(&["mission", "--scenario", path_str(&scenario), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert!(v["aborted"].is_string(), "{stdout}");
    assert_eq!(v["delivered"], false);
    assert_eq!(code, Some(3), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_flight_that_drops_the_payload_exits_with_its_own_code() {
    // The controller believes the COM at the far end from the truth (0.33, 0.01): the
    // formation balances the wrong point and the payload rolls over at take-off.
    let rect = scenario_path("rect-sim1");
    let (code, stdout, stderr) = run(&[
        "fly",
        "--scenario",
        path_str(&rect),
        "--formation",
        "optimized",
        "--com",
        "-0.5,0",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!(v["dropped"], true, "{stdout}");
    assert_eq!(code, Some(5), "{stderr}");
}

#[test]
fn a_delivered_flight_exits_zero() {
    let rect = scenario_path("rect-sim1");
    let (code, stdout, stderr) = run(&[
        "fly",
        "--scenario",
        path_str(&rect),
        "--formation",
        "optimized",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!(v["delivered"], true, "{stdout}");
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn a_comparison_reports_both_flights_with_the_command_line_names() {
    let dir = temp_dir("compare");
    let rect = scenario_path("rect-sim2");
    let args = [
        "fly",
        "--scenario",
        path_str(&rect),
        "--formation",
        "optimized",
        "--output",
        path_str(&dir),
        "--compare",
    ];
    let (code, stdout, stderr) = run(&args);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stdout.contains("optimised formation, equal-split mixer: delivered"),
        "{stdout}"
    );
    assert!(
        stdout.contains("even formation, equal-split mixer:"),
        "{stdout}"
    );
    for file in [
        "rect-sim2-optimized-equal-split.csv",
        "rect-sim2-even-equal-split.csv",
        "rect-sim2-height-comparison.png",
    ] {
        assert!(stdout.contains(file), "{file} not reported: {stdout}");
        assert!(dir.join(file).is_file(), "{file} not written");
    }
    assert!(
        !stdout.contains("EqualSplit") && !stdout.contains("Optimized"),
        "{stdout}"
    );
    let csv =
        std::fs::read_to_string(dir.join("rect-sim2-optimized-equal-split.csv")).expect("csv");
    assert!(
        csv.starts_with("t_s,x_m,y_m,z_down_m,ref_x_m,ref_y_m,ref_z_down_m,"),
        "{csv:.100}"
    );
    let (_, json, _) = run(&[&args[..], &["--json"]].concat());
    let v: serde_json::Value = serde_json::from_str(&json).expect("JSON");
    assert_eq!(v["formation"], "optimized", "{json}");
    assert_eq!(v["compared"]["formation"], "even", "{json}");
    assert!(v["compared"]["max_tilt_deg"].is_number(), "{json}");
}

#[test]
fn the_ground_link_notes_list_the_parameters_the_firmware_serves() {
    let (code, table, stderr) = run(&["params"]);
    assert_eq!(code, Some(0), "{stderr}");
    let notes_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/ground-link.md");
    let notes = std::fs::read_to_string(&notes_path).expect("docs/ground-link.md");
    let listed = notes
        .split_once("<!-- params:begin -->\n")
        .and_then(|(_, rest)| rest.split_once("<!-- params:end -->"))
        .map(|(block, _)| block)
        .expect("docs/ground-link.md has the parameter list between its markers");
    assert_eq!(
        listed.trim(),
        table.trim(),
        "docs/ground-link.md's parameter list is out of date: put the output of \
         `cargo run -p host-sim -- params` between its markers"
    );
    // The table's rows (after its two header lines) and the JSON's count agree.
    let rows = table.lines().filter(|l| l.starts_with("| ")).count() - 1;
    assert!(rows > 60, "{table}");
    let (code, json, _) = run(&["params", "--json"]);
    assert_eq!(code, Some(0));
    assert!(
        json.contains(&format!("\"count\":{rows},")),
        "{rows} rows: {json}"
    );
}

#[test]
fn validate_for_a_board_refuses_more_robots_than_it_drives_naming_both() {
    let twelve = scenario_path("rect-12");
    // The Pixhawk 6C drives eight: a twelve-robot description is refused before anyone flies.
    let err = assert_refused(
        &[
            "validate",
            "--scenario",
            path_str(&twelve),
            "--board",
            "pixhawk6c",
        ],
        "pixhawk6c",
    );
    assert!(
        err.contains(
            "12 robots; this board drives 8 rotors (ESC_PROTOCOL DShot600) and 16 steppers"
        ),
        "{err}"
    );
    // On DroneCAN ESCs the Pixhawk drives sixteen; on PWM still eight.
    let args = [
        "validate",
        "--scenario",
        path_str(&twelve),
        "--board",
        "pixhawk6c",
        "--esc-protocol",
        "3",
    ];
    let (code, stdout, stderr) = run(&args);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stdout.contains("pixhawk6c drives them: 16 rotors (ESC_PROTOCOL DroneCAN), 16 steppers"),
        "{stdout}"
    );
    let pwm = [&args[..6], &["1"]].concat();
    let err = assert_refused(&pwm, "ESC_PROTOCOL PWM");
    assert!(err.contains("this board drives 8 rotors"), "{err}");
    let unknown = [&args[..6], &["4"]].concat();
    let (code, _, stderr) = run(&unknown);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("no ESC_PROTOCOL"), "{stderr}");
    // QEMU's board and no board take it, as does the Pixhawk every paper case.
    for board in [&["--board", "qemu"][..], &[]] {
        let args = [&["validate", "--scenario", path_str(&twelve)][..], board].concat();
        let (code, stdout, stderr) = run(&args);
        assert_eq!(code, Some(0), "{args:?}: {stderr}");
        assert!(stdout.contains("12 robots"), "{stdout}");
    }
    for case in common::PAPER_CASES {
        let path = scenario_path(case);
        let args = [
            "validate",
            "--scenario",
            path_str(&path),
            "--board",
            "pixhawk6c",
        ];
        let (code, stdout, stderr) = run(&args);
        assert_eq!(code, Some(0), "{case}: {stderr}");
        assert!(
            stdout.contains("pixhawk6c drives them: 8 rotors"),
            "{stdout}"
        );
    }
    // The QEMU board told to drive 0 or 17 robots: refused before anything starts.
    for n in ["0", "17"] {
        assert_refused(
            &[
                "hil",
                "--scenario",
                path_str(&twelve),
                "--qemu",
                "/no/such.elf",
                "--max-robots",
                n,
            ],
            "--max-robots",
        );
    }
    // A board nobody has is a usage error naming the ones there are.
    let (code, _, stderr) = run(&[
        "validate",
        "--scenario",
        path_str(&twelve),
        "--board",
        "px4",
    ]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("pixhawk6c, qemu"), "{stderr}");
}
