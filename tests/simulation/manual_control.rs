//! A person takes over (docs/manual-control.md), in the physics plant with `shared`'s mission:
//! stick scripts (`mission --rc`) played as an RC receiver's channels through the vehicle's
//! own channel map, or as a joystick's `MANUAL_CONTROL`, on rect-ex1, seed 1. The kill switch
//! in the hover, a take-over into Position mode by the mode switch and by the ground station
//! with a joystick, and manual control lost in Position and in Mission mode.

use crate::common::load;
use host_sim::mission_run::{self, MissionOutcome, MissionSetup};
use host_sim::pilot_script::PilotScript;
use shared::mission::{AbortReason, OperatorCommand};

/// What a run said: each phase, notice and mode with its time, s.
struct Flown {
    outcome: MissionOutcome,
    said: Vec<(f32, String, String)>,
}

impl Flown {
    /// The first line of kind `name` whose text contains `text`.
    fn find(&self, name: &str, text: &str) -> Option<f32> {
        self.said
            .iter()
            .find(|(_, n, r)| n == name && r.contains(text))
            .map(|(t, _, _)| *t)
    }

    /// Take-off's time, s.
    fn takeoff(&self) -> f32 {
        self.outcome.takeoff_at.expect("took off")
    }

    /// North, east and height of the payload `after` s after take-off began (100 Hz), m.
    fn at(&self, after: f32) -> [f32; 3] {
        let t = self.takeoff() + after;
        let s = self
            .outcome
            .series
            .iter()
            .find(|s| s.t >= t)
            .expect("flying then");
        [s.xy[0], s.xy[1], s.height]
    }

    fn last_phase(&self) -> &str {
        self.outcome.phases.last().map_or("", |(n, _)| n.as_str())
    }
}

fn fly(script: &str, commands: Vec<(f32, OperatorCommand)>) -> Flown {
    fly_logged(script, commands, None)
}

fn fly_logged(
    script: &str,
    commands: Vec<(f32, OperatorCommand)>,
    log: Option<std::path::PathBuf>,
) -> Flown {
    let scenario = load("rect-ex1");
    let setup = MissionSetup {
        pilot: Some(PilotScript::parse(script).expect("a good script")),
        commands,
        log,
        ..MissionSetup::default()
    };
    let mut said = Vec::new();
    let (outcome, _) = mission_run::run(&scenario, &setup, &mut |t, name, reason| {
        said.push((t, name.to_string(), reason.to_string()))
    })
    .expect("runs");
    Flown { outcome, said }
}

/// Over the hover at 12 s the pilot takes over, flies north at 0.46 of full pitch (0.2 m/s past the dead zone)
/// for 5 s, centres the sticks, then lands with the throttle down at 26 s.
const TAKEOVER: &str = r#"
source = "rc"
[[at]]
t = 0
[[at]]
t = 12
mode = "position"
[[at]]
t = 14
pitch = 0.46
[[at]]
t = 19
pitch = 0.0
[[at]]
t = 26
throttle = 0.0
"#;

/// The take-over's flight: 1 m north, a still hold, a landing by throttle, upright.
fn check_takeover(f: &Flown, label: &str) {
    let took = f.outcome.steered.first().expect("the sticks took over");
    assert!(took.1, "{label}: {:?}", f.outcome.steered);
    let after = took.0 - f.takeoff();
    assert!(
        (after - 12.0).abs() < 0.05,
        "{label}: took over {after} s after take-off"
    );
    let before = f.at(13.9);
    let moved = f.at(21.0);
    let north = moved[0] - before[0];
    let east = moved[1] - before[1];
    assert!((0.85..=1.15).contains(&north), "{label}: {north} m north");
    assert!(east.abs() < 0.1, "{label}: {east} m east");
    // Centred sticks hold: under 0.1 m over 3 s.
    let (a, b) = (f.at(21.0), f.at(24.0));
    let drift = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    assert!(
        drift < 0.1,
        "{label}: drifted {drift} m in 3 s of centred sticks"
    );
    assert!(
        a[2] > 0.4,
        "{label}: held at {} m (the flight height, 0.5 m)",
        a[2]
    );
    // Throttle down: it lands and disarms, upright, where the pilot left it.
    assert_eq!(
        f.last_phase(),
        "disarmed",
        "{label}: {:?}",
        f.outcome.phases
    );
    assert!(f.find("disarmed", "landed").is_some(), "{label}");
    assert!(!f.outcome.dropped, "{label}");
    assert!(
        f.outcome.max_tilt_deg < 10.0,
        "{label}: tilt {}",
        f.outcome.max_tilt_deg
    );
    assert!(
        !f.outcome.delivered,
        "{label}: the pilot landed it elsewhere"
    );
}

#[test]
fn a_pilot_takes_over_with_the_mode_switch_flies_north_holds_and_lands_by_throttle() {
    let dir = std::env::temp_dir().join(format!("manual-takeover-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let path = dir.join("takeover.ulg");
    let f = fly_logged(TAKEOVER, Vec::new(), Some(path.clone()));
    check_takeover(&f, "RC");
    // The log has the sticks (PX4's manual_control_setpoint, at 10 Hz) and the switches: the
    // RC in force, the pitch forward while the pilot flew north, the Position slot (2).
    let log = flight_log::reader::read_file(&path).expect("the log reads");
    let sticks = log
        .topic("manual_control_setpoint")
        .expect("the sticks logged");
    let (valid, source, pitch) = (
        sticks.field("valid").expect("valid"),
        sticks.field("data_source").expect("data_source"),
        sticks.field("pitch").expect("pitch"),
    );
    let pushed = sticks.records.iter().filter(|r| {
        valid.get(r, 0) == Some(1.0)
            && source.get(r, 0) == Some(0.0)
            && pitch.get(r, 0).is_some_and(|p| p > 0.4)
    });
    // 5 s forward at 10 Hz.
    assert!(
        (45..=55).contains(&pushed.count()),
        "records with the pitch forward"
    );
    let switches = log
        .topic("manual_control_switches")
        .expect("the switches logged");
    let slot = switches.field("mode_slot").expect("mode_slot");
    assert!(switches.records.iter().any(|r| slot.get(r, 0) == Some(2.0)));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_pilot_with_only_a_joystick_takes_over_from_the_ground_station_the_same_way() {
    let joystick = TAKEOVER
        .replace("source = \"rc\"", "source = \"joystick\"")
        .replace("mode = \"position\"\n", "");
    // The ground station's mode menu (DO_SET_MODE POSCTL) at the same time.
    let f = fly(&joystick, vec![(12.0, OperatorCommand::Position)]);
    check_takeover(&f, "joystick");
}

#[test]
fn the_kill_switch_stops_every_rotor_in_the_tick_that_sees_it_and_disarms_later() {
    let dir = std::env::temp_dir().join(format!("manual-kill-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let path = dir.join("kill.ulg");
    let f = fly_logged(
        "source = \"rc\"\n[[at]]\nt = 0\n[[at]]\nt = 12\nkill = true\n",
        Vec::new(),
        Some(path.clone()),
    );
    // The log shows it: the switch on (PX4's 1) from the kill on, every rotor's output zero
    // from the kill's tick, and the vehicle's words.
    let log = flight_log::reader::read_file(&path).expect("the log reads");
    let switches = log
        .topic("manual_control_switches")
        .expect("the switches logged");
    let kill = switches.field("kill_switch").expect("kill_switch");
    assert!(switches.records.iter().any(|r| kill.get(r, 0) == Some(1.0)));
    assert!(
        log.strings
            .iter()
            .any(|s| s.text.contains("kill switch on"))
    );
    let _ = std::fs::remove_dir_all(&dir);
    let sent = f.outcome.kill_sent_at.expect("the kill frame went out");
    let zero = f.outcome.rotors_zero_at.expect("the rotors stopped");
    assert_eq!(
        sent, zero,
        "every rotor command zero in the tick of the frame"
    );
    assert!(f.find("notice", "kill switch on").is_some());
    // The payload falls (on purpose) and the vehicle disarms after COM_KILL_DISARM (5 s).
    let high = f.at(11.9)[2];
    let low = f.at(14.0)[2];
    assert!(high > 0.5 && low < 0.1, "fell from {high} m to {low} m");
    assert_eq!(f.outcome.aborted, Some(AbortReason::Killed));
    let disarmed = f.find("aborted", "").expect("disarmed");
    let waited = disarmed - sent;
    assert!(
        (waited - 5.0).abs() < 0.05,
        "disarmed {waited} s after the switch"
    );
}

#[test]
fn manual_control_lost_in_position_mode_holds_then_lands_upright_where_it_is() {
    let f = fly(
        "source = \"rc\"\n[[at]]\nt = 0\n[[at]]\nt = 12\nmode = \"position\"\n[[at]]\nt = 15\nsilent = true\n",
        Vec::new(),
    );
    let lost = f
        .find("notice", "manual control lost")
        .expect("the loss said");
    let silent_for = lost - (f.takeoff() + 15.0);
    assert!(
        (0.45..0.6).contains(&silent_for),
        "lost after {silent_for} s (COM_RC_LOSS_T 0.5 s)"
    );
    assert!(
        f.find("notice", "holding 5 s, then landing in place")
            .is_some(),
        "{:?}",
        f.said
    );
    let landing = f.find("landing", "manual control lost").expect("it lands");
    assert!(
        (landing - lost - 5.0).abs() < 0.05,
        "held {} s",
        landing - lost
    );
    assert_eq!(f.last_phase(), "disarmed");
    assert!(!f.outcome.dropped);
    assert!(
        !f.outcome.delivered,
        "delivered nowhere: it landed where it held"
    );
    assert!(f.outcome.max_tilt_deg < 10.0);
    assert_eq!(f.outcome.aborted, Some(AbortReason::ManualLost));
}

#[test]
fn manual_control_lost_in_mission_mode_lets_the_mission_finish() {
    let f = fly(
        "source = \"rc\"\n[[at]]\nt = 0\n[[at]]\nt = 5\nsilent = true\n",
        Vec::new(),
    );
    assert!(
        f.find("notice", "the mission goes on").is_some(),
        "{:?}",
        f.said
    );
    assert!(
        f.outcome.delivered,
        "{:?}",
        f.outcome.final_position_error_m
    );
    assert!(f.outcome.aborted.is_none());
}
