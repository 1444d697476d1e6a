//! A person takes over, in the loop (docs/hil.md, `hil --rc`): stick scripts played into the
//! firmware under QEMU, RC frames as CRSF bytes into the emulated board's receiver UART (the
//! firmware's own receiver task and parser), on rect-ex1, seed 1. The kill switch in the hover,
//! and `tests/pilot/takeover-rc.toml`'s take-over into Position mode and landing by throttle,
//! against the same script flown by the simulator alone (tests/simulation/manual_control.rs).

use crate::common;

use common::{image_or_skip, qemu_slot, workspace};

use host_sim::hil::qemu::{Guest, Qemu, QemuLink};
use host_sim::hil::run::{HilOutcome, HilSetup, run_with_rc};
use host_sim::hil::session::LoggedText;
use host_sim::mission_run::{self, MissionSetup};
use host_sim::pilot_script::PilotScript;
use host_sim::scenario_file;
use shared::mission::OperatorCommand;

/// The control period, s.
const STEP_S: f64 = 0.0025;

fn report(line: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// Flies rect-ex1 through the firmware with `script`; `None` when the test is skipped.
fn fly(test: &str, script: &PilotScript) -> Option<HilOutcome> {
    fly_with(test, script, Vec::new())
}

/// [`fly`], with a ground station's `commands` (s after take-off began).
fn fly_with(
    test: &str,
    script: &PilotScript,
    commands: Vec<(f32, OperatorCommand)>,
) -> Option<HilOutcome> {
    let elf = image_or_skip(test)?;
    let _slot = qemu_slot();
    let loaded =
        scenario_file::load(&workspace().join("tests/scenarios/rect-ex1.toml")).expect("rect-ex1");
    let guest = Guest {
        rc: true,
        ..Guest::default()
    };
    let (mut qemu, link) =
        Qemu::start_guest(&elf, &guest, QemuLink::Ethernet).expect("QEMU starts");
    let rc = qemu.take_rc();
    assert!(rc.is_some(), "the receiver UART is connected");
    let setup = HilSetup {
        pilot: Some(script.clone()),
        commands,
        ..HilSetup::default()
    };
    let print: Box<dyn FnMut(&LoggedText) + Send> =
        Box::new(|t: &LoggedText| println!("  step {:5}  firmware: {}", t.step, t.text));
    let outcome = run_with_rc(&loaded, link, rc, &setup, print).unwrap_or_else(|e| {
        panic!(
            "{test}: hil run failed: {e:#}\nQEMU said: {}",
            qemu.output()
        )
    });
    let (frames, waited) = outcome.rc_frames_sent;
    report(format_args!(
        "hil {test}: {} RC frames into the receiver UART ({:.1} ms of wall time each for QEMU to take), receiver frames good/bad {:?}, last RC_CHANNELS {:?}; {:.1} s simulated in {:.1} s",
        frames,
        1e3 * waited / frames.max(1) as f64,
        outcome.log.rc_frames,
        outcome
            .log
            .rc_channels
            .map(|(c, n, rssi)| (c[..6].to_vec(), n, rssi)),
        outcome.simulated_s,
        outcome.wall_s,
    ));
    Some(outcome)
}

/// The simulated time of the firmware's first text containing `text`, s (from the step it
/// came with).
fn said_at(o: &HilOutcome, text: &str) -> Option<f64> {
    o.log
        .texts
        .iter()
        .find(|t| t.text.contains(text))
        .map(|t| t.step as f64 * STEP_S)
}

/// North, east and height `after` s after take-off began, m.
fn at(o: &HilOutcome, after: f64) -> [f32; 3] {
    let t = o.takeoff_at_s.expect("took off") + after;
    let s = o
        .series
        .iter()
        .find(|s| f64::from(s.t) >= t)
        .expect("flying then");
    [s.xy[0], s.xy[1], s.height]
}

/// Frames the receiver task counted: good ones came, none was bad (QEMU's UART loses nothing).
fn check_receiver(o: &HilOutcome) {
    let (good, bad) = o.log.rc_frames;
    assert!(good > 100, "receiver frames good {good}");
    assert_eq!(bad, 0, "receiver frames bad");
    let (_, count, rssi) = o.log.rc_channels.expect("RC_CHANNELS streamed");
    assert_eq!((count, rssi), (16, 255), "16 channels, no link statistics");
}

#[test]
fn the_kill_switch_over_crsf_stops_every_rotor_within_a_step_and_disarms_later() {
    let script =
        PilotScript::parse("source = \"rc\"\n[[at]]\nt = 0\n[[at]]\nt = 12\nkill = true\n")
            .expect("a good script");
    let Some(o) = fly("the_kill_switch_over_crsf", &script) else {
        return;
    };
    check_receiver(&o);
    let sent = o.kill_sent_at.expect("the kill frame went out");
    let zero = o.rotors_zero_at.expect("the rotors stopped");
    let steps = ((zero - sent) / STEP_S).round() as i64;
    report(format_args!(
        "hil kill switch: frame written before step at {sent:.4} s, every rotor zero at {zero:.4} s: {steps} step(s) later"
    ));
    // The frame is in the UART before the step's sample goes (`RcLink::send`); the receiver
    // task (link executor) may run after that step's control step: one step at most.
    assert!(
        (0..=1).contains(&steps),
        "rotors zero {steps} steps after the frame"
    );
    let said = said_at(&o, "kill switch on").expect("the vehicle says kill switch on");
    assert!(said - sent < 0.01, "said {} s after", said - sent);
    let high = at(&o, 11.9)[2];
    let low = at(&o, 14.0)[2];
    assert!(high > 0.5 && low < 0.1, "fell from {high} m to {low} m");
    // Disarmed after COM_KILL_DISARM (5 s): the mission ends aborted.
    let ended = said_at(&o, "phase: aborted").expect("the mission ends");
    let waited = ended - sent;
    assert!(
        (waited - 5.0).abs() < 0.05,
        "disarmed {waited} s after the switch"
    );
    assert!(!o.delivered);
}

#[test]
fn takeover_rc_toml_takes_over_into_position_mode_and_lands_by_throttle_as_the_simulator() {
    let path = workspace().join("tests/pilot/takeover-rc.toml");
    let script = PilotScript::load(&path).expect("the script");
    let Some(o) = fly("takeover_rc_toml", &script) else {
        return;
    };
    check_receiver(&o);
    // The simulator alone, the same script and seed.
    let loaded =
        scenario_file::load(&workspace().join("tests/scenarios/rect-ex1.toml")).expect("rect-ex1");
    let (sim, _) = mission_run::run(
        &loaded.scenario,
        &MissionSetup {
            pilot: Some(script.clone()),
            ..MissionSetup::default()
        },
        &mut |_, _, _| {},
    )
    .expect("simulator");
    let takeoff = o.takeoff_at_s.expect("took off");
    let position = said_at(&o, "mode: Position").expect("Position mode") - takeoff;
    assert!(
        (position - 12.0).abs() < 0.05,
        "Position mode {position} s after take-off"
    );
    let sim_at = |after: f32| {
        let t = sim.takeoff_at.expect("took off") + after;
        let s = sim.series.iter().find(|s| s.t >= t).expect("flying");
        [s.xy[0], s.xy[1], s.height]
    };
    let north = at(&o, 21.0)[0] - at(&o, 13.9)[0];
    let east = at(&o, 21.0)[1] - at(&o, 13.9)[1];
    let sim_north = sim_at(21.0)[0] - sim_at(13.9)[0];
    report(format_args!(
        "hil takeover: {north:.3} m north ({sim_north:.3} m in the simulator), {east:.3} m east"
    ));
    assert!(
        (0.85..=1.15).contains(&north),
        "{north} m north (1 m asked)"
    );
    assert!(
        (north - sim_north).abs() < 0.05,
        "{north} m, simulator {sim_north} m"
    );
    assert!(east.abs() < 0.1, "{east} m east");
    let (a, b) = (at(&o, 21.0), at(&o, 24.0));
    let drift = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    assert!(drift < 0.1, "drifted {drift} m in 3 s of centred sticks");
    assert!(a[2] > 0.4, "held at {} m", a[2]);
    assert!(
        said_at(&o, "phase: disarmed").is_some(),
        "it lands and disarms"
    );
    assert_eq!(
        sim.phases.last().map(|(n, _)| n.as_str()),
        Some("disarmed"),
        "the simulator too"
    );
    assert!(!o.dropped);
    assert!(o.max_tilt_deg < 10.0, "tilt {}", o.max_tilt_deg);
    assert!(!o.delivered, "the pilot landed it elsewhere");
}

/// A pilot with only a joystick: the ground station's Position mode (`DO_SET_MODE`, PX4's
/// POSCTL) at 12 s and the joystick's `MANUAL_CONTROL` over the link, the same flight as the
/// RC take-over: 1 m north, a still hold, a landing by throttle, as the simulator flies it.
#[test]
fn a_joystick_alone_takes_over_with_the_ground_stations_mode_and_lands_by_throttle() {
    let path = workspace().join("tests/pilot/takeover-rc.toml");
    let text = std::fs::read_to_string(&path).expect("the script");
    let joystick = text
        .replace("source = \"rc\"", "source = \"joystick\"")
        .replace("mode = \"position\"\n", "");
    let script = PilotScript::parse(&joystick).expect("a joystick script");
    let commands = vec![(12.0, OperatorCommand::Position)];
    let Some(o) = fly_with("a_joystick_alone", &script, commands.clone()) else {
        return;
    };
    let loaded =
        scenario_file::load(&workspace().join("tests/scenarios/rect-ex1.toml")).expect("rect-ex1");
    let (sim, _) = mission_run::run(
        &loaded.scenario,
        &MissionSetup {
            pilot: Some(script.clone()),
            commands,
            ..MissionSetup::default()
        },
        &mut |_, _, _| {},
    )
    .expect("simulator");
    let takeoff = o.takeoff_at_s.expect("took off");
    let position = said_at(&o, "mode: Position").expect("Position mode") - takeoff;
    assert!(
        (position - 12.0).abs() < 0.1,
        "Position mode {position} s after take-off"
    );
    let sim_north = {
        let at = |after: f32| {
            let t = sim.takeoff_at.expect("took off") + after;
            sim.series.iter().find(|s| s.t >= t).expect("flying").xy[0]
        };
        at(21.0) - at(13.9)
    };
    let north = at(&o, 21.0)[0] - at(&o, 13.9)[0];
    report(format_args!(
        "hil joystick takeover: {north:.3} m north ({sim_north:.3} m in the simulator)"
    ));
    assert!(
        (0.85..=1.15).contains(&north),
        "{north} m north (1 m asked)"
    );
    assert!(
        (north - sim_north).abs() < 0.05,
        "{north} m, simulator {sim_north} m"
    );
    let (a, b) = (at(&o, 21.0), at(&o, 24.0));
    let drift = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    assert!(drift < 0.1, "drifted {drift} m in 3 s of centred sticks");
    assert!(
        said_at(&o, "phase: disarmed").is_some(),
        "it lands and disarms"
    );
    assert!(!o.dropped);
    assert!(o.max_tilt_deg < 10.0, "tilt {}", o.max_tilt_deg);
}
