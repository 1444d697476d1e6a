//! The flight log (docs/formats.md#flight-logs). The simulator's (`mission --log`) is ULog as
//! PX4 writes it, read here message by message (header, definitions before data, a
//! subscription for every data message, each topic's timestamps in order, a `lift` record for
//! every lift with the posterior's spread and the model at the estimate, the cascade's
//! setpoints at 100 Hz in flight, a logged string for every phase), and opened by pyulog, the
//! reference reader (`tests/ulog_check.py`, which also checks PX4's field names). The firmware's, flown under QEMU with `hil --storage`, is the
//! simulator's message for message (but the pack voltage, which the plant sends at 10 Hz in
//! millivolts), and pyulog opens it too. Without python3 and pyulog, or QEMU, a test says it
//! was skipped and why; with `HIL_REQUIRED=1` (CI, which installs them) it fails instead.

mod common;

use common::{image_or_skip, skip, workspace};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use flight_log::topics::Topic;
use host_sim::mission_run::{self, MissionSetup};
use host_sim::scenario_file;
use shared::mission::params::TABLE;

/// Flies rect-ex1 with its log written to a fresh file; the mission's outcome and the log.
/// `confirm_rails`: the rails confirmed with the first step and the start with the next, as
/// the HIL plant does.
fn fly_logged(name: &str, confirm_rails: bool) -> (mission_run::MissionOutcome, PathBuf) {
    let dir = std::env::temp_dir().join(format!("flight-log-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let path = dir.join("rect-ex1.ulg");
    let loaded =
        scenario_file::load(&workspace().join("tests/scenarios/rect-ex1.toml")).expect("loads");
    let setup = MissionSetup {
        log: Some(path.clone()),
        confirm_rails,
        ..MissionSetup::default()
    };
    let (outcome, _) =
        mission_run::run(&loaded.scenario, &setup, &mut |_, _, _| {}).expect("the mission runs");
    assert!(outcome.delivered);
    (outcome, path)
}

/// One ULog message: its type and payload.
struct Message<'a> {
    kind: u8,
    payload: &'a [u8],
}

/// The log's messages after the 16-byte header; panics on a message that runs past the end.
fn messages(bytes: &[u8]) -> Vec<Message<'_>> {
    assert_eq!(&bytes[..7], b"ULog\x01\x12\x35", "the file magic");
    let mut at = 16;
    let mut out = Vec::new();
    while at < bytes.len() {
        let size = u16::from_le_bytes([bytes[at], bytes[at + 1]]) as usize;
        let kind = bytes[at + 2];
        let end = at + 3 + size;
        assert!(
            end <= bytes.len(),
            "a '{}' message runs past the end",
            kind as char
        );
        out.push(Message {
            kind,
            payload: &bytes[at + 3..end],
        });
        at = end;
    }
    out
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

#[test]
fn the_mission_log_is_ulog_with_every_topic_parameter_lift_and_phase() {
    let (outcome, path) = fly_logged("structure", false);
    let bytes = std::fs::read(&path).expect("the log was written");
    let all = messages(&bytes);
    assert_eq!(all[0].kind, b'B', "the flag bits come first");
    // The data section starts with the opening step's logged string (its records begin with
    // the next step).
    let first_data = all
        .iter()
        .position(|m| m.kind == b'D' || m.kind == b'L')
        .expect("data");
    for m in &all[..first_data] {
        assert!(
            b"BFIPA".contains(&m.kind),
            "'{}' before the data",
            m.kind as char
        );
    }
    let formats: Vec<&str> = all
        .iter()
        .filter(|m| m.kind == b'F')
        .map(|m| std::str::from_utf8(m.payload).expect("text"))
        .collect();
    for topic in Topic::ALL {
        assert!(
            formats.contains(&topic.format()),
            "{} has no format",
            topic.name()
        );
    }
    let parameters: Vec<&[u8]> = all
        .iter()
        .filter(|m| m.kind == b'P')
        .map(|m| &m.payload[1..1 + m.payload[0] as usize])
        .collect();
    assert_eq!(parameters.len(), TABLE.len());
    for spec in &TABLE {
        let kind = if spec.integer { "int32_t" } else { "float" };
        let key = format!("{kind} {}", spec.name);
        assert!(parameters.contains(&key.as_bytes()), "no parameter {key}");
    }

    // Data: every message id subscribed before its data, each topic's time in order.
    let mut subscribed: HashMap<u16, String> = HashMap::new();
    let mut last: HashMap<u16, u64> = HashMap::new();
    let mut count: HashMap<String, usize> = HashMap::new();
    let mut strings = Vec::new();
    let mut lifts: Vec<Vec<u8>> = Vec::new();
    for m in &all {
        match m.kind {
            b'A' => {
                let id = u16::from_le_bytes([m.payload[1], m.payload[2]]);
                let name = String::from_utf8(m.payload[3..].to_vec()).expect("a name");
                subscribed.insert(id, name);
            }
            b'D' => {
                let id = u16::from_le_bytes([m.payload[0], m.payload[1]]);
                let name = subscribed.get(&id).expect("data of a subscribed id");
                let t = u64_at(m.payload, 2);
                let before = last.insert(id, t).unwrap_or(0);
                assert!(t >= before, "{name}: time {t} after {before}");
                *count.entry(name.clone()).or_default() += 1;
                if name == "lift" {
                    lifts.push(m.payload[2..].to_vec());
                }
            }
            b'L' => strings.push(String::from_utf8(m.payload[9..].to_vec()).expect("text")),
            _ => {}
        }
    }
    let ticks = count["sensor_combined"];
    // Every step but the one that opened the log (which holds its start and its texts).
    assert_eq!(
        ticks as u64 + 1,
        outcome.ticks,
        "an IMU sample a control step"
    );
    assert_eq!(count["actuator_outputs"], ticks);
    assert_eq!(count["lift"], outcome.lifts.len(), "a lift record a lift");
    assert_eq!(count["formation"], 1);
    // The setpoints at 100 Hz each while flying: a few seconds' worth, as many of each.
    let (attitude_sp, rates_sp) = (
        count["vehicle_attitude_setpoint"],
        count["vehicle_rates_setpoint"],
    );
    assert!(
        attitude_sp > 500 && attitude_sp <= ticks / 4 + 1,
        "{attitude_sp}"
    );
    assert!(
        attitude_sp.abs_diff(rates_sp) <= 1,
        "{attitude_sp} {rates_sp}"
    );
    // lift: timestamp, pair, information, lifted, thrust, lifts, com_x, com_y, mass,
    // confidence, then the spread per axis and the model's lift-off thrust.
    let f32_at = |b: &[u8], at: usize| f32::from_le_bytes(b[at..at + 4].try_into().expect("4"));
    for (k, lift) in lifts.iter().enumerate() {
        let spread = [38, 42, 46].map(|at| f32_at(lift, at));
        assert!(
            spread.iter().all(|s| *s > 0.0),
            "lift {k}: spread {spread:?}"
        );
    }
    // After the last lift the estimate has converged: the model at it is the model at the
    // truth, within the grid's resolution's worth.
    let last = lifts.last().expect("lifts");
    let truth_model = outcome.lifts.last().expect("a lift").2;
    let model_n = f32_at(last, 50);
    assert!(
        (model_n - truth_model).abs() < 0.5,
        "{model_n} N vs {truth_model} N"
    );
    for (phase, _) in &outcome.phases {
        assert!(
            strings
                .iter()
                .any(|s| s.starts_with(&format!("phase: {phase}: "))),
            "no logged string for the phase {phase}"
        );
    }
    let _ = std::fs::remove_file(&path);
}

#[test]
fn pyulog_opens_the_mission_log() {
    let (_, path) = fly_logged("pyulog", false);
    match pyulog_check(&path) {
        Ok(report) => {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "{report}");
        }
        Err(why) => skip("flight log with pyulog", &why),
    }
    let _ = std::fs::remove_file(&path);
}

/// Runs `tests/ulog_check.py` on `path` for the topics of a normal flight: its report, or why
/// it could not run (`Err`, to skip).
fn pyulog_check(path: &Path) -> Result<String, String> {
    let mut args: Vec<String> = vec![
        workspace()
            .join("tests/ulog_check.py")
            .display()
            .to_string(),
        path.display().to_string(),
        TABLE.len().to_string(),
    ];
    // Every topic but `adaptation`, which has data only when the load shifts in flight
    // (pyulog lists the topics that have data).
    args.extend(
        Topic::ALL
            .iter()
            .filter(|t| **t != Topic::Adaptation)
            .map(|t| t.name().to_string()),
    );
    let output = Command::new("python3")
        .args(&args)
        .output()
        .map_err(|e| format!("python3 cannot be run ({e})"))?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    if output.status.code() == Some(2) {
        return Err(stderr.trim().to_string());
    }
    assert!(
        output.status.success(),
        "pyulog on {}: {stderr}",
        path.display()
    );
    Ok(String::from_utf8_lossy(&output.stdout).trim().to_string())
}

#[test]
fn the_firmware_in_the_loop_keeps_the_simulators_log_in_its_storage() {
    let Some(elf) = image_or_skip("flight log in the loop") else {
        return;
    };
    let (_, host_log) = fly_logged("hil", true);
    let storage = host_log.with_file_name("storage");
    let _ = std::fs::remove_dir_all(&storage);
    let output = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("hil")
        .arg("--scenario")
        .arg(workspace().join("tests/scenarios/rect-ex1.toml"))
        .arg("--qemu")
        .arg(&elf)
        .arg("--storage")
        .arg(&storage)
        .output()
        .expect("host-sim runs");
    assert!(
        output.status.success(),
        "hil: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let firmware_log = storage.join("log-000.ulg");
    let host_bytes = std::fs::read(&host_log).expect("the host's log");
    let firmware_bytes = std::fs::read(&firmware_log).expect("the firmware left its log");
    let data = |all: &[u8]| -> Vec<Vec<u8>> {
        messages(all)
            .into_iter()
            .filter(|m| b"DLO".contains(&m.kind))
            .map(|m| [&[m.kind][..], m.payload].concat())
            .collect()
    };
    let (host, firmware) = (data(&host_bytes), data(&firmware_bytes));
    assert_eq!(host.len(), firmware.len(), "as many messages");
    let battery = Topic::BatteryStatus.msg_id().to_le_bytes();
    for (i, (h, f)) in host.iter().zip(&firmware).enumerate() {
        if h[0] == b'D' && h[1..3] == battery {
            assert_eq!(
                f[..11],
                h[..11],
                "message {i}: a battery record at the same time"
            );
        } else {
            assert_eq!(f, h, "message {i} differs");
        }
    }
    match pyulog_check(&firmware_log) {
        Ok(report) => {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "firmware's log: {report}");
        }
        Err(why) => skip("flight log in the loop with pyulog", &why),
    }
    let _ = std::fs::remove_dir_all(&storage);
    let _ = std::fs::remove_file(&host_log);
}
