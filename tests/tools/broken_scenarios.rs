//! The corpus of broken scenario files (`tests/broken-scenarios/`, one defect each) run through
//! every command (docs/formats.md#scenario-files): bad input ends with a one-line error naming the
//! key and a non-zero exit code, never a panic; nothing may hang on it either.
//!
//! Each file's second line says which key its error must name: `# expect: robots.spin`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Longest a command may take to refuse a broken file. They all refuse while reading it; a
/// command still running after this has started simulating a vehicle it should have refused.
const REFUSAL_TIMEOUT: Duration = Duration::from_secs(60);

fn corpus() -> Vec<(PathBuf, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/broken-scenarios");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("corpus folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).expect("readable");
            let key = text
                .lines()
                .find_map(|l| l.strip_prefix("# expect: "))
                .unwrap_or_else(|| panic!("{}: no `# expect:` line", path.display()))
                .trim()
                .to_string();
            (path, key)
        })
        .collect()
}

struct Run {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs `host-sim args`, killing it and failing the test after [`REFUSAL_TIMEOUT`].
fn run_with_timeout(args: &[&str]) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("host-sim starts");
    let started = Instant::now();
    loop {
        if child.try_wait().expect("wait").is_some() {
            break;
        }
        if started.elapsed() > REFUSAL_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("host-sim {args:?} still running after {REFUSAL_TIMEOUT:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let out = child.wait_with_output().expect("output");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

#[test]
fn the_corpus_covers_the_defects_it_should() {
    let keys: Vec<String> = corpus().into_iter().map(|(_, key)| key).collect();
    assert!(keys.len() >= 40, "{} files", keys.len());
    for key in [
        "payload.footprint",
        "payload.rail",
        "payload.candidates",
        "robots.pair_size",
        "robots.spin",
        "robots.torque_per_thrust",
        "estimation.grid_min/grid_max",
        "estimation.resolution",
        "flight.target",
        "flight.disturbance_torque",
        "truth.com",
    ] {
        assert!(keys.iter().any(|k| k == key), "no broken file for {key}");
    }
}

#[test]
fn every_command_refuses_every_broken_file_in_one_line_naming_the_key() {
    let commands: [(&str, &[&str]); 6] = [
        ("validate", &[]),
        ("lift", &["--pair", "0", "--com", "0.1,0.0", "--mass", "3"]),
        ("estimate", &["--trials", "2", "--seed", "1"]),
        ("formation", &[]),
        ("fly", &["--formation", "optimized"]),
        ("mission", &[]),
    ];
    let mut failures = Vec::new();
    for (path, key) in corpus() {
        let file = path.to_str().expect("utf-8 path");
        let tag = path.file_stem().unwrap().to_string_lossy().into_owned();
        for (command, extra) in commands {
            let mut args = vec![command, "--scenario", file, "--json"];
            args.extend_from_slice(extra);
            let run = run_with_timeout(&args);
            let err = run.stderr.trim_end();
            let mut why = Vec::new();
            if run.code != Some(1) {
                why.push(format!("exit code {:?}, not 1", run.code));
            }
            if !run.stdout.is_empty() {
                why.push(format!("stdout not empty: {:?}", run.stdout));
            }
            if err.lines().count() != 1 || !err.starts_with("error: ") {
                why.push("not one line starting with `error: `".to_string());
            }
            if !err.contains(key.as_str()) {
                why.push(format!("does not name {key}"));
            }
            if err.contains("panicked") || err.contains("18446744073709551615") {
                why.push("panic or overflowed count".to_string());
            }
            // Flags that were not given must not be blamed.
            for flag in ["--com", "--mass", "--truth", "--thrust-scale"] {
                if err.contains(flag) && !extra.contains(&flag) {
                    why.push(format!("blames {flag}, which was not given"));
                }
            }
            if !why.is_empty() {
                failures.push(format!("{tag} / {command}: {}: {err}", why.join("; ")));
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}
