//! The simulator's flight log (docs/formats.md#flight-logs; `mission --log`): ULog as PX4
//! writes it, read here message by message (header, definitions before data, a subscription
//! for every data message, each topic's timestamps in order, a `lift` record for every lift
//! with the posterior's spread and the model at the estimate, the cascade's setpoints at
//! 100 Hz in flight, a logged string for every phase), and opened by pyulog, the reference
//! reader (`tests/ulog_check.py`, which also checks PX4's field names). The firmware's log,
//! flown under QEMU, is checked against it in `hil::flight_log`. Without python3 and pyulog
//! the pyulog test says it was skipped and why; with `HIL_REQUIRED=1` (CI, which installs
//! them) it fails instead.

use crate::common;

use common::skip;
use common::ulog::{fly_logged, messages, pyulog_check};
use std::collections::HashMap;

use ::flight_log::topics::Topic;
use shared::mission::params::TABLE;

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
