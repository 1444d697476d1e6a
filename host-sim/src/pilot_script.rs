//! A person at the sticks, scripted (docs/manual-control.md#stick-scripts): timed stick and
//! switch positions that `mission --rc FILE` and `hil --rc FILE` play to the vehicle, as an RC
//! receiver's channels (CRSF frames into the firmware's receiver UART in HIL) or as a ground
//! station's joystick (`MANUAL_CONTROL`).
//!
//! ```toml
//! source = "rc"        # or "joystick"
//! rate_hz = 50         # frames a second (default: 50 for rc, 25 for a joystick)
//!
//! [[at]]               # each holds from its time until the next; times in s after take-off
//! t = 0.0              # began (the first also before it)
//! throttle = 0.5       # 0 down, 1 up, 0.5 centred; roll, pitch, yaw -1 to 1 (0 centred)
//!
//! [[at]]
//! t = 20.0
//! mode = "position"    # the mode switch: "mission", "position", "hold" or "land"
//! pitch = 0.5
//!
//! [[at]]
//! t = 30.0
//! kill = true          # the kill switch (rc only)
//! silent = true        # nothing sent from here (the receiver lost)
//! ```
//!
//! The receiver's channels are laid out as the vehicle's defaults map them (`RC_MAP_*`: roll,
//! pitch, throttle, yaw on 1 to 4), with the mode switch on channel [`MODE_CHANNEL`] and the kill
//! switch on [`KILL_CHANNEL`]; [`PilotScript::parameters`] are the parameters that map those two
//! and the mode switch's slots ([`MODE_SLOTS`]), which the run sets on the vehicle.

use anyhow::{Context, Result, anyhow, bail};
use serde::Deserialize;
use shared::manual::{ManualInput, ManualSamples, PilotMode, from_manual_control};
use shared::mission::MissionConfig;

/// The receiver channel of the mode switch.
pub const MODE_CHANNEL: u8 = 5;
/// The receiver channel of the kill switch.
pub const KILL_CHANNEL: u8 = 6;
/// The mode of each of the mode switch's slots a script uses (`COM_FLTMODE1..4`).
pub const MODE_SLOTS: [PilotMode; 4] = [
    PilotMode::Mission,
    PilotMode::Position,
    PilotMode::Hold,
    PilotMode::Land,
];
/// Channels a frame carries (CRSF's `RC_CHANNELS_PACKED`).
pub const CHANNELS: usize = 16;

/// Where the sticks come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PilotSource {
    /// An RC receiver (CRSF in HIL).
    Rc,
    /// A ground station's joystick (`MANUAL_CONTROL`).
    Joystick,
}

/// One position of the sticks and switches, from its time on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PilotStep {
    /// From this time on, s after take-off began.
    pub at: f32,
    /// Roll, -1 to 1 (right positive).
    pub roll: f32,
    /// Pitch, -1 to 1 (forward positive).
    pub pitch: f32,
    /// Yaw, -1 to 1 (clockwise positive).
    pub yaw: f32,
    /// Throttle, 0 to 1 (0.5 centred).
    pub throttle: f32,
    /// The mode switch's mode.
    pub mode: PilotMode,
    /// The kill switch on.
    pub kill: bool,
    /// Nothing is sent (the receiver or the joystick lost).
    pub silent: bool,
}

/// What is sent at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PilotFrame {
    /// An RC receiver's channels, pulse widths in us (1000 to 2000).
    Rc([u16; CHANNELS]),
    /// A joystick's `MANUAL_CONTROL` x, y, z, r.
    Joystick([i16; 4]),
}

/// A script.
#[derive(Clone, Debug, PartialEq)]
pub struct PilotScript {
    /// Where the sticks come from.
    pub source: PilotSource,
    /// Frames a second.
    pub rate_hz: f32,
    /// The steps, in time order.
    pub steps: Vec<PilotStep>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileScript {
    source: String,
    rate_hz: Option<f32>,
    at: Vec<FileStep>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileStep {
    t: f32,
    roll: Option<f32>,
    pitch: Option<f32>,
    yaw: Option<f32>,
    throttle: Option<f32>,
    mode: Option<String>,
    kill: Option<bool>,
    silent: Option<bool>,
}

/// `value` checked to lie in `[lo, hi]`, named in the error.
fn in_range(value: f32, lo: f32, hi: f32, what: &str, step: usize) -> Result<f32> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        bail!("step {step}: {what} = {value} is outside {lo} to {hi}")
    }
}

impl PilotScript {
    /// Reads a script file.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read the stick script {}", path.display()))?;
        Self::parse(&text).with_context(|| format!("stick script {}", path.display()))
    }

    /// A script from its TOML text; every value checked (each step's values carry on from the
    /// step before unless given).
    pub fn parse(text: &str) -> Result<Self> {
        let file: FileScript = toml::from_str(text).map_err(|e| anyhow!("{}", e.message()))?;
        let source = match file.source.as_str() {
            "rc" => PilotSource::Rc,
            "joystick" => PilotSource::Joystick,
            other => bail!("source = \"{other}\": it is \"rc\" or \"joystick\""),
        };
        let rate_hz = file.rate_hz.unwrap_or(match source {
            PilotSource::Rc => 50.0,
            PilotSource::Joystick => 25.0,
        });
        if !(rate_hz.is_finite() && (1.0..=400.0).contains(&rate_hz)) {
            bail!("rate_hz = {rate_hz} is outside 1 to 400");
        }
        if file.at.is_empty() {
            bail!("no [[at]] step: a script needs at least one");
        }
        let mut steps: Vec<PilotStep> = Vec::with_capacity(file.at.len());
        let mut before = PilotStep {
            at: 0.0,
            roll: 0.0,
            pitch: 0.0,
            yaw: 0.0,
            throttle: 0.5,
            mode: PilotMode::Mission,
            kill: false,
            silent: false,
        };
        for (i, s) in file.at.iter().enumerate() {
            let n = i + 1;
            let at = in_range(s.t, -1e4, 1e4, "t", n)?;
            if steps.last().is_some_and(|p| p.at > at) {
                bail!("step {n}: t = {at} comes before the step above it");
            }
            let mode = match s.mode.as_deref() {
                None => before.mode,
                Some("mission") => PilotMode::Mission,
                Some("position") => PilotMode::Position,
                Some("hold") => PilotMode::Hold,
                Some("land") => PilotMode::Land,
                Some(other) => bail!(
                    "step {n}: mode = \"{other}\": it is \"mission\", \"position\", \"hold\" or \"land\""
                ),
            };
            let kill = s.kill.unwrap_or(before.kill);
            if kill && source == PilotSource::Joystick {
                bail!("step {n}: a joystick has no kill switch (source = \"rc\" has)");
            }
            if s.mode.is_some() && source == PilotSource::Joystick {
                bail!(
                    "step {n}: a joystick has no mode switch: the ground station sets the mode (source = \"rc\" has one)"
                );
            }
            let step = PilotStep {
                at,
                roll: in_range(s.roll.unwrap_or(before.roll), -1.0, 1.0, "roll", n)?,
                pitch: in_range(s.pitch.unwrap_or(before.pitch), -1.0, 1.0, "pitch", n)?,
                yaw: in_range(s.yaw.unwrap_or(before.yaw), -1.0, 1.0, "yaw", n)?,
                throttle: in_range(
                    s.throttle.unwrap_or(before.throttle),
                    0.0,
                    1.0,
                    "throttle",
                    n,
                )?,
                mode,
                kill,
                silent: s.silent.unwrap_or(before.silent),
            };
            steps.push(step);
            before = step;
        }
        Ok(Self {
            source,
            rate_hz,
            steps,
        })
    }

    /// The step in force `t` seconds after take-off began (the first before it).
    pub fn step_at(&self, t: f32) -> &PilotStep {
        let i = self.steps.partition_point(|s| s.at <= t);
        &self.steps[i.saturating_sub(1)]
    }

    /// What is sent at `t` seconds after take-off began, if anything.
    pub fn frame_at(&self, t: f32) -> Option<PilotFrame> {
        let step = self.step_at(t);
        if step.silent {
            return None;
        }
        Some(match self.source {
            PilotSource::Rc => PilotFrame::Rc(channels(step)),
            PilotSource::Joystick => PilotFrame::Joystick(joystick(step)),
        })
    }

    /// The parameters that map the script's switches on the vehicle: `RC_MAP_FLTMODE`,
    /// `RC_MAP_KILL_SW` and `COM_FLTMODE1..4` ([`MODE_SLOTS`]).
    pub fn parameters() -> Vec<(&'static str, f32)> {
        let mut p = vec![
            ("RC_MAP_FLTMODE", f32::from(MODE_CHANNEL)),
            ("RC_MAP_KILL_SW", f32::from(KILL_CHANNEL)),
        ];
        let names = [
            "COM_FLTMODE1",
            "COM_FLTMODE2",
            "COM_FLTMODE3",
            "COM_FLTMODE4",
        ];
        for (name, mode) in names.into_iter().zip(MODE_SLOTS) {
            p.push((name, mode.param_value()));
        }
        p
    }

    /// [`Self::parameters`] in a mission's configuration (the simulator's own).
    pub fn configure(config: &mut MissionConfig) {
        config.hardware.rc_map.mode_switch = MODE_CHANNEL;
        config.hardware.rc_map.kill_switch = KILL_CHANNEL;
        for (slot, mode) in MODE_SLOTS.into_iter().enumerate() {
            config.manual.flight_modes[slot] = Some(mode);
        }
    }
}

/// A stick's pulse width, us: -1 to 1 over 1000 to 2000.
fn stick_us(value: f32) -> u16 {
    (1500.0 + 500.0 * value.clamp(-1.0, 1.0)).round() as u16
}

/// The receiver's channels for `step`: the sticks (AETR), the mode switch in the middle of
/// its mode's slot, the kill switch high when on; the rest centred.
pub fn channels(step: &PilotStep) -> [u16; CHANNELS] {
    let mut ch = [1500u16; CHANNELS];
    ch[0] = stick_us(step.roll);
    ch[1] = stick_us(step.pitch);
    ch[2] = (1000.0 + 1000.0 * step.throttle.clamp(0.0, 1.0)).round() as u16;
    ch[3] = stick_us(step.yaw);
    let slot = MODE_SLOTS.iter().position(|m| *m == step.mode).unwrap_or(0);
    let slot_width = 1000.0 / 6.0;
    ch[usize::from(MODE_CHANNEL) - 1] = (1000.0 + slot_width * (slot as f32 + 0.5)).round() as u16;
    ch[usize::from(KILL_CHANNEL) - 1] = if step.kill { 2000 } else { 1000 };
    ch
}

/// A joystick's `MANUAL_CONTROL` axes for `step`: x pitch, y roll, z throttle (0..1000), r yaw.
pub fn joystick(step: &PilotStep) -> [i16; 4] {
    let axis = |v: f32| (v.clamp(-1.0, 1.0) * 1000.0).round() as i16;
    [
        axis(step.pitch),
        axis(step.roll),
        (step.throttle.clamp(0.0, 1.0) * 1000.0).round() as i16,
        axis(step.yaw),
    ]
}

/// What the vehicle's own mapping makes of `frame` (`config`'s `RC_MAP_*`), as the mission
/// takes it: the simulator's stand-in for the firmware's receiver path.
pub fn samples(frame: Option<&PilotFrame>, config: &MissionConfig) -> ManualSamples {
    match frame {
        Some(PilotFrame::Rc(ch)) => ManualSamples {
            rc: config.hardware.rc_map.input(ch),
            joystick: None,
        },
        Some(PilotFrame::Joystick([x, y, z, r])) => ManualSamples {
            rc: None,
            joystick: from_manual_control(*x, *y, *z, *r),
        },
        None => ManualSamples::NONE,
    }
}

/// The manual input `frame` carries with `config`'s mapping (for reports).
pub fn input(frame: &PilotFrame, config: &MissionConfig) -> Option<ManualInput> {
    let s = samples(Some(frame), config);
    s.rc.or(s.joystick)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCRIPT: &str = r#"
source = "rc"
[[at]]
t = 0
[[at]]
t = 10
mode = "position"
pitch = 0.5
[[at]]
t = 20
kill = true
"#;

    #[test]
    fn steps_carry_on_and_map_back_through_the_vehicles_channels() {
        let s = PilotScript::parse(SCRIPT).expect("a good script");
        assert_eq!(s.rate_hz, 50.0);
        assert_eq!(s.step_at(-5.0).mode, PilotMode::Mission);
        let later = s.step_at(25.0);
        assert_eq!(
            (later.mode, later.pitch, later.kill),
            (PilotMode::Position, 0.5, true)
        );
        let mut config = MissionConfig::DEFAULT;
        PilotScript::configure(&mut config);
        let frame = s.frame_at(15.0).expect("sent");
        let got = input(&frame, &config).expect("every stick mapped");
        assert_eq!(got.mode_slot, Some(1));
        assert_eq!(config.manual.flight_modes[1], Some(PilotMode::Position));
        assert!((got.sticks.pitch - 0.5).abs() < 0.02, "{got:?}");
        assert!(!got.kill);
        assert!(
            input(&s.frame_at(21.0).expect("sent"), &config)
                .expect("mapped")
                .kill
        );
    }

    #[test]
    fn bad_scripts_are_refused_naming_what_is_wrong() {
        let err = |text: &str| format!("{:#}", PilotScript::parse(text).expect_err("refused"));
        assert!(err("source = \"rc\"\nat = []").contains("no [[at]]"));
        assert!(err("source = \"radio\"\n[[at]]\nt = 0").contains("\"rc\" or \"joystick\""));
        assert!(err("source = \"rc\"\n[[at]]\nt = 0\npitch = 2").contains("pitch = 2"));
        assert!(err("source = \"rc\"\n[[at]]\nt = 5\n[[at]]\nt = 1").contains("comes before"));
        assert!(err("source = \"joystick\"\n[[at]]\nt = 0\nkill = true").contains("no kill"));
        assert!(err("source = \"rc\"\n[[at]]\nt = 0\npich = 1").contains("pich"));
    }
}
