//! The flight log's helpers, for the simulator's log tests (`simulation::flight_log`) and the
//! firmware's (`hil::flight_log`): rect-ex1 flown with its log, the log's messages, and pyulog's
//! check of a log (`tests/ulog_check.py`).

use super::workspace;
use std::path::{Path, PathBuf};
use std::process::Command;

use flight_log::topics::Topic;
use host_sim::mission_run::{self, MissionSetup};
use host_sim::scenario_file;
use shared::mission::params::TABLE;

/// Flies rect-ex1 with its log written to a fresh file; the mission's outcome and the log.
/// `confirm_rails`: the rails confirmed with the first step and the start with the next, as
/// the HIL plant does.
pub fn fly_logged(name: &str, confirm_rails: bool) -> (mission_run::MissionOutcome, PathBuf) {
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
pub struct Message<'a> {
    pub kind: u8,
    pub payload: &'a [u8],
}

/// The log's messages after the 16-byte header; panics on a message that runs past the end.
pub fn messages(bytes: &[u8]) -> Vec<Message<'_>> {
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

/// Runs `tests/ulog_check.py` on `path` for the topics of a normal flight: its report, or why
/// it could not run (`Err`, to skip).
pub fn pyulog_check(path: &Path) -> Result<String, String> {
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
