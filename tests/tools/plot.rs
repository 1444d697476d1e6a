//! `host-sim plot FILE.ulg --output DIR` (docs/formats.md#plotting-a-flight-log): rect-ex1
//! flown with its log, the log plotted by the binary; the page's files are listed, written and
//! well formed, and what the log says agrees with the mission (phases and their times, lifts,
//! the flight). A log cut short is plotted with what it has and says so; a log without lifts
//! or without a topic says which panel is empty. A missing, empty, foreign or hopeless file is
//! one line of error and exit code 1; no cut, flipped or random bytes make the reader or the
//! page panic.

use crate::common;
use common::{host_sim, scenario_path};

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use flight_log::reader;
use host_sim::log_summary::summarise;
use host_sim::mission_figures;
use host_sim::mission_run::{self, MissionOutcome, MissionSetup};
use host_sim::scenario_file;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One control step (400 Hz) and a little, s: how far a phase's time in the log may be from
/// the mission's.
const STEP_S: f32 = 2.6e-3;

/// A fresh folder for one test's files.
fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-plot-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// rect-ex1 flown once with its log: the outcome and the log's bytes.
fn flown() -> &'static (MissionOutcome, Vec<u8>) {
    static FLOWN: OnceLock<(MissionOutcome, Vec<u8>)> = OnceLock::new();
    FLOWN.get_or_init(|| {
        let path = temp_dir("flown").join("rect-ex1.ulg");
        let loaded = scenario_file::load(&scenario_path("rect-ex1")).expect("loads");
        let setup = MissionSetup {
            log: Some(path.clone()),
            ..MissionSetup::default()
        };
        let (outcome, _) = mission_run::run(&loaded.scenario, &setup, &mut |_, _, _| {})
            .expect("the mission runs");
        assert!(outcome.delivered);
        (outcome, std::fs::read(&path).expect("the log"))
    })
}

/// Writes `bytes` as `<dir>/<name>`.
fn log_file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write");
    path
}

/// Runs `plot` with `--json`; exit code, the JSON (if any) and stderr.
fn plot_json(args: &[&str]) -> (Option<i32>, serde_json::Value, String) {
    let out = host_sim(&[&["plot"], args, &["--json"]].concat());
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let v = serde_json::from_slice(&out.stdout).unwrap_or(serde_json::Value::Null);
    (out.status.code(), v, stderr)
}

/// The files a report lists, each checked: inside `out`, present, a well-formed PNG or SVG.
fn checked_files(v: &serde_json::Value, out: &Path) -> Vec<String> {
    let files: Vec<String> = v["files"]
        .as_array()
        .expect("files")
        .iter()
        .map(|f| f.as_str().expect("a path").to_string())
        .collect();
    for f in &files {
        let path = PathBuf::from(f);
        assert_eq!(path.parent(), Some(out), "{f} outside {out:?}");
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{f}: {e}"));
        if f.ends_with(".png") {
            assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{f}: not a PNG");
            assert!(bytes.ends_with(b"IEND\xaeB`\x82"), "{f}: an unfinished PNG");
        } else {
            let text = String::from_utf8_lossy(&bytes);
            assert!(
                f.ends_with(".svg") && text.contains("<svg") && text.trim_end().ends_with("</svg>"),
                "{f}: not a whole SVG"
            );
        }
    }
    files
}

/// The log's messages after its header as (start, type, whole message's bytes).
fn messages(bytes: &[u8]) -> Vec<(usize, u8, &[u8])> {
    let mut at = 16;
    let mut out = Vec::new();
    while at + 3 <= bytes.len() {
        let size = usize::from(u16::from_le_bytes([bytes[at], bytes[at + 1]]));
        out.push((at, bytes[at + 2], &bytes[at..at + 3 + size]));
        at += 3 + size;
    }
    out
}

/// The message id the log subscribes `topic` under.
fn msg_id(bytes: &[u8], topic: &str) -> u16 {
    messages(bytes)
        .into_iter()
        .find(|(_, kind, m)| *kind == b'A' && &m[6..] == topic.as_bytes())
        .map(|(_, _, m)| u16::from_le_bytes([m[4], m[5]]))
        .expect("subscribed")
}

/// The log without `topic`'s data, and without its subscription too when `unsubscribe`.
fn without(bytes: &[u8], topic: &str, unsubscribe: bool) -> Vec<u8> {
    let id = msg_id(bytes, topic);
    let mut out = bytes[..16].to_vec();
    for (_, kind, m) in messages(bytes) {
        // A data message's id follows its header; a subscription's, its instance byte.
        let data_of = kind == b'D' && u16::from_le_bytes([m[3], m[4]]) == id;
        let subscription_of = kind == b'A' && u16::from_le_bytes([m[4], m[5]]) == id;
        if data_of || (unsubscribe && subscription_of) {
            continue;
        }
        out.extend_from_slice(m);
    }
    out
}

#[test]
fn plot_draws_the_missions_summary_from_its_log_and_the_two_agree() {
    let (outcome, bytes) = flown();
    let dir = temp_dir("agree");
    let log = log_file(&dir, "rect-ex1.ulg", bytes);
    let out = dir.join("figures");
    let rect = scenario_path("rect-ex1");
    let (code, v, stderr) = plot_json(&[
        path_str(&log),
        "--output",
        path_str(&out),
        "--scenario",
        path_str(&rect),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stderr.is_empty(), "nothing to say of a whole log: {stderr}");
    let files = checked_files(&v, &out);
    let names: Vec<&str> = files
        .iter()
        .filter_map(|f| Path::new(f).file_name()?.to_str())
        .collect();
    assert_eq!(
        names,
        [
            "rect-ex1-mission-summary.png",
            "rect-ex1-mission-summary.svg"
        ]
    );
    assert_eq!(v["complete"], true);
    assert_eq!(v["mission_ended"], true);
    assert_eq!(v["bytes"], v["bytes_read"]);
    assert_eq!(v["sys_name"], "rail-transport");
    assert_eq!(v["notes"].as_array().map(Vec::len), Some(0), "{v}");

    // The phases read back are the mission's, entered at the same times within a control
    // step (the log's records begin with the step after the one that opens it, so the first
    // phase is seen a step late).
    let phases = v["phases"].as_array().expect("phases");
    assert_eq!(phases.len(), outcome.phases.len());
    let mut t = 0.0f32;
    for (read, (name, duration)) in phases.iter().zip(&outcome.phases) {
        assert_eq!(read["name"], name.as_str());
        let start = read["start_s"].as_f64().expect("a time") as f32;
        assert!(
            (start - t).abs() <= STEP_S,
            "{name}: {start} s against {t} s"
        );
        t += duration;
    }
    // The lifts: the same pairs and readings, the model beside each.
    let lifts = v["lifts"].as_array().expect("lifts");
    assert_eq!(lifts.len(), outcome.lifts.len());
    assert!(lifts.len() >= 2);
    for (read, (pair, reading, model)) in lifts.iter().zip(&outcome.lifts) {
        assert_eq!(read["pair"].as_u64(), Some(*pair as u64));
        let r = read["reading"].as_f64().map(|r| r as f32);
        assert_eq!(r, *reading);
        let m = read["model"].as_f64().expect("a model") as f32;
        assert!((m - model).abs() < 1e-4, "{m} against {model}");
    }
    // The flight: a sample every 10 ms from take-off, as the mission's.
    let samples = v["flight_samples"].as_u64().expect("a count") as usize;
    assert!(
        samples.abs_diff(outcome.series.len()) <= 2,
        "{samples} against {}",
        outcome.series.len()
    );
}

#[test]
fn the_page_from_the_log_holds_the_data_of_the_page_from_the_mission() {
    let (outcome, bytes) = flown();
    let loaded = scenario_file::load(&scenario_path("rect-ex1")).expect("loads");
    let log = reader::parse(bytes.clone()).expect("reads");
    let from_log = summarise(&log, "rect-ex1", Some(&loaded.scenario)).summary;
    let from_mission =
        mission_figures::summary("rect-ex1", outcome, loaded.scenario.robots.max_thrust);
    assert_eq!(from_log.lifts, from_mission.lifts);
    assert_eq!(from_log.max_thrust, from_mission.max_thrust);
    assert_eq!(from_log.phases.len(), from_mission.phases.len());
    for (a, b) in from_log.phases.iter().zip(&from_mission.phases) {
        assert_eq!(a.name, b.name);
        let (start, end) = ((a.start - b.start).abs(), (a.end - b.end).abs());
        assert!(
            start <= STEP_S && end <= STEP_S,
            "{}: {start} s, {end} s",
            a.name
        );
    }
    // The log starts with the start command, the mission's second step (as the vehicle takes
    // it, after the rails' confirmation): its clock is at most a step behind the plant's.
    let end = (from_log.end_s - from_mission.end_s).abs();
    assert!(end <= STEP_S, "the ends {end} s apart");
    // The flight: the log's estimate against the plant's truth.
    let top = |s: &[host_sim::figures::mission_summary::SummarySample]| {
        s.iter().map(|p| p.height).fold(f32::MIN, f32::max)
    };
    let (log_top, sim_top) = (top(&from_log.series), top(&from_mission.series));
    assert!(
        (log_top - sim_top).abs() < 0.03,
        "{log_top} m against {sim_top} m"
    );
    let first = from_log.series.first().expect("a flight");
    assert!((first.t - from_mission.series[0].t).abs() < 0.011);
    assert_eq!(first.thrust.len(), from_mission.series[0].thrust.len());
    let mean = |s: &[host_sim::figures::mission_summary::SummarySample]| {
        s.iter().flat_map(|p| p.thrust.iter()).sum::<f32>() / s.len() as f32
    };
    let (log_mean, sim_mean) = (mean(&from_log.series), mean(&from_mission.series));
    assert!(
        (log_mean - sim_mean).abs() < 0.02 * sim_mean,
        "{log_mean} N against {sim_mean} N"
    );
}

/// `at`, or the byte after it when `at` falls between two of the ULog's records (16 header
/// bytes, then records of a 2-byte size, a 1-byte type and `size` bytes): a cut there leaves
/// a part of a record, as a vehicle that loses power mid-write does.
fn inside_a_record(bytes: &[u8], at: usize) -> usize {
    let mut pos = 16;
    while pos < at && pos + 3 <= bytes.len() {
        pos += 3 + usize::from(u16::from_le_bytes([bytes[pos], bytes[pos + 1]]));
    }
    if pos == at { at + 1 } else { at }
}

#[test]
fn a_log_cut_short_is_plotted_with_what_it_has_and_says_so() {
    let (_, bytes) = flown();
    let dir = temp_dir("cut");
    // Cut in flight (take-off is at 43 s of 60.5) and during the lifts.
    for (share, in_flight) in [(0.85, true), (0.3, false)] {
        let cut = inside_a_record(bytes, (bytes.len() as f64 * share) as usize);
        let log = log_file(&dir, &format!("cut-{share}.ulg"), &bytes[..cut]);
        let out = dir.join(format!("figures-{share}"));
        let run = host_sim(&["plot", path_str(&log), "--output", path_str(&out)]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        let stdout = String::from_utf8_lossy(&run.stdout);
        assert_eq!(run.status.code(), Some(0), "{stderr}");
        assert!(stderr.contains("note: the log was cut short"), "{stderr}");
        assert!(stderr.contains(&format!("of its {cut} bytes")), "{stderr}");
        assert!(stderr.contains("before the mission ended"), "{stderr}");
        assert_eq!(stderr.contains("no take-off"), !in_flight, "{stderr}");
        assert!(stdout.contains("wrote "), "{stdout}");
        assert!(!stdout.contains("disarmed"), "{stdout}");

        let (code, v, _) = plot_json(&[path_str(&log), "--output", path_str(&out)]);
        assert_eq!(code, Some(0));
        checked_files(&v, &out);
        assert_eq!(v["complete"], false);
        assert_eq!(v["mission_ended"], false);
        let read = v["bytes_read"].as_u64().expect("bytes read") as usize;
        assert!(read <= cut && read + 200 > cut, "{read} of {cut}");
        assert_eq!(v["flight_samples"].as_u64().unwrap_or(0) > 0, in_flight);
    }
}

#[test]
fn a_log_without_lifts_or_a_topic_says_which_panel_is_empty() {
    let (_, bytes) = flown();
    let dir = temp_dir("lacks");
    let out = dir.join("figures");
    let no_lifts = log_file(&dir, "no-lifts.ulg", &without(bytes, "lift", false));
    let (code, v, _) = plot_json(&[path_str(&no_lifts), "--output", path_str(&out)]);
    assert_eq!(code, Some(0));
    checked_files(&v, &out);
    assert_eq!(v["lifts"].as_array().map(Vec::len), Some(0));
    let notes = v["notes"].to_string();
    assert!(
        notes.contains("the log has no lifts: the lift panel is empty"),
        "{notes}"
    );

    let no_position = without(bytes, "vehicle_local_position", true);
    let no_position = log_file(&dir, "no-position.ulg", &no_position);
    let run = host_sim(&["plot", path_str(&no_position), "--output", path_str(&out)]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains(
            "note: the log has no vehicle_local_position topic: the flight panels are empty"
        ),
        "{stderr}"
    );
    assert!(!stderr.contains("lift panel"), "{stderr}");
}

/// Asserts a refusal: exit code 1, one line on stderr naming `what`, nothing on stdout.
fn assert_refused(log: &Path, what: &str) {
    let out = log.with_extension("out");
    let run = host_sim(&["plot", path_str(log), "--output", path_str(&out)]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{log:?}: {stderr}");
    assert!(run.stdout.is_empty(), "{log:?}");
    let line = stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{line}");
    assert!(line.starts_with("error: "), "{line}");
    assert!(line.contains(what), "{log:?} must say {what}: {line}");
    assert!(line.contains(path_str(log)), "{line}");
    assert!(!out.exists(), "{log:?}: nothing written");
}

#[test]
fn a_file_that_is_no_flight_log_is_refused_naming_what_is_wrong() {
    let (_, bytes) = flown();
    let dir = temp_dir("refused");
    assert_refused(&dir.join("missing.ulg"), "cannot read");
    assert_refused(&log_file(&dir, "empty.ulg", b""), "the file is empty");
    assert_refused(
        &log_file(&dir, "text.ulg", b"flight notes: windy, landed fine\n"),
        "magic",
    );
    assert_refused(
        &log_file(&dir, "short.ulg", &bytes[..9]),
        "16-byte ULog header",
    );
    // The definitions without any data; cut inside the definitions.
    let first_data = messages(bytes)
        .into_iter()
        .find(|(_, kind, _)| *kind == b'D')
        .map(|(at, _, _)| at)
        .expect("data");
    assert_refused(
        &log_file(&dir, "no-data.ulg", &bytes[..first_data]),
        "holds no data",
    );
    let (middle, _, _) = messages(bytes)
        .into_iter()
        .take_while(|(at, _, _)| *at < first_data)
        .nth(10)
        .expect("definitions");
    assert_refused(
        &log_file(&dir, "cut-early.ulg", &bytes[..middle + 4]),
        "inside a message",
    );
    let mut flags = bytes.clone();
    flags[16 + 3 + 8] = 0x80; // an incompatible flag this reader does not know
    assert_refused(&log_file(&dir, "flags.ulg", &flags), "incompatible flag");
}

#[test]
fn no_cut_flipped_or_random_bytes_make_the_reader_or_the_page_panic() {
    let (_, bytes) = flown();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let check = |b: Vec<u8>| {
        if let Ok(log) = reader::parse(b) {
            let s = summarise(&log, "x", None);
            assert!(log.read <= log.len());
            assert!(s.summary.series.iter().all(|p| p.height.is_finite()));
        }
    };
    // Cut anywhere: in the header, the definitions, the data.
    let first_data = messages(bytes)
        .iter()
        .find(|(_, kind, _)| *kind == b'D')
        .map_or(0, |(at, _, _)| *at);
    for cut in (0..40).chain((0..first_data + 50).step_by(97)) {
        check(bytes[..cut.min(bytes.len())].to_vec());
    }
    for _ in 0..30 {
        let cut = rng.random_range(0..bytes.len());
        check(bytes[..cut].to_vec());
    }
    // Flipped bytes, in the definitions and anywhere.
    for k in 0..150 {
        let mut b = bytes.clone();
        let span = if k % 2 == 0 { first_data } else { b.len() };
        for _ in 0..rng.random_range(1..20) {
            let at = rng.random_range(16..span);
            b[at] ^= 1 << rng.random_range(0..8);
        }
        check(b);
    }
    // Random bytes, behind the magic and without it.
    for k in 0..100 {
        let len = rng.random_range(0..4000);
        let mut b: Vec<u8> = (0..len).map(|_| rng.random()).collect();
        if k % 2 == 0 && b.len() >= 16 {
            b[..16].copy_from_slice(&bytes[..16]);
        }
        check(b);
    }
    // And the whole command, the page drawn, on a few damaged logs: a summary or an error,
    // never a panic.
    let dir = temp_dir("damaged");
    for k in 0..6 {
        let mut b = bytes.clone();
        for _ in 0..50 {
            let at = rng.random_range(16..b.len());
            b[at] = rng.random();
        }
        if k % 2 == 1 {
            b.truncate(rng.random_range(1000..b.len()));
        }
        let log = log_file(&dir, &format!("damaged-{k}.ulg"), &b);
        let out = dir.join(format!("figures-{k}"));
        let run = host_sim(&["plot", path_str(&log), "--output", path_str(&out)]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(matches!(run.status.code(), Some(0 | 1)), "{k}: {stderr}");
        assert!(!stderr.contains("panicked"), "{k}: {stderr}");
    }
}
