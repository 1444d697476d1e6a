//! Failure injection on the command line: `--inject KIND@SECONDS` (seconds after take-off
//! began; repeatable). Faults that can come on the ground also take `KIND@start+SECONDS`, that
//! many seconds after the mission's start (the plant's time zero; `@start+0` from the first
//! sample). Each kind is parsed and range-checked here, with an error that names the flag and
//! what is wrong; the plant loop ([`crate::mission_run`]) applies it (docs/system.md#failsafes).
//!
//! Kinds (robots numbered from 1, as the mission's texts number them):
//! - `load-shift:DX,DY@T`: the payload's COM moves by (DX, DY) m over half a second, a load
//!   sliding on the plate (the in-flight adaptation's test);
//! - `stepper-stall:J`: robot J's stepper stalls halfway through the rearrangement before
//!   take-off and its driver reports it, as StallGuard does on the board (no time);
//! - `imu-stuck@T`: the IMU repeats its last sample; `imu-noise:X@T`: white noise of X times
//!   the simulated sensor's is added to every sample;
//! - `gcs-loss@T`: the simulated ground station stops sending its heartbeat (and, with
//!   `hil --gcs`, nothing from the real one reaches the vehicle any more); without a time, there
//!   is no ground station from the start;
//! - `battery:V@T`: the pack's open-circuit voltage drops to V volts; without a time, the pack
//!   is at V from the start;
//! - `rotor-out:J@T`: robot J's rotor stops and makes no thrust from then on, whatever is
//!   commanded (repeatable: two rotors can stop);
//! - `rotor-fade:J,S@T`: robot J's rotor makes less and less of its commanded thrust, none
//!   after S seconds (a damaged propeller, a failing ESC; repeatable with `rotor-out`);
//! - `mocap-loss@T`: motion capture stops (as `--mocap-lost-after T`).

use std::fmt;

use shared::geometry::Vec2;
use shared::scenario::MAX_ROBOTS;

use crate::mission_run::{
    BatteryDrop, ImuFaultKind, ImuInjection, LoadShift, MissionSetup, Onset, RotorStop,
};
use crate::scenario_file::LoadedScenario;

/// Largest load shift, m: beyond the paper's payloads (1.76 m long at most).
pub const MAX_LOAD_SHIFT: f32 = 1.0;
/// Largest IMU noise factor: at 1000 times the simulated sensor's, the accelerometer's noise
/// (50 m/s^2) reaches a third of the ICM-42688-P's range (+-16 g) and the gyro's (5 rad/s)
/// a seventh of its +-2000 deg/s; beyond, a real sensor would read at full scale, which the
/// board's driver reports.
pub const MAX_IMU_NOISE: f32 = 1000.0;
/// Highest pack voltage `battery:V` takes, V (a 24-cell pack).
pub const MAX_PACK_VOLTS: f32 = 100.0;
/// Longest fade of `rotor-fade:J,S`, s.
pub const MAX_FADE_TIME: f32 = 60.0;
/// Latest injection, s after take-off: the mission's own time limit.
pub const MAX_INJECT_TIME: f32 = crate::mission_run::MISSION_TIME_LIMIT;

/// What to inject.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// The payload's COM moves by this much, body frame, m.
    LoadShift(Vec2),
    /// This robot's stepper (index from 0; the command line numbers robots from 1, as the
    /// mission's texts do) stalls halfway through the rearrangement.
    StepperStall(usize),
    /// The IMU repeats its last sample.
    ImuStuck,
    /// White noise of this many times the simulated sensor's is added to the IMU's samples.
    ImuNoise(f32),
    /// The ground station's heartbeat stops.
    GcsLoss,
    /// The pack's voltage drops to this, V.
    Battery(f32),
    /// This robot's rotor (index from 0) stops: no thrust from then on.
    RotorOut(usize),
    /// This robot's rotor (index from 0) fades from what is commanded to nothing over this
    /// many seconds.
    RotorFade(usize, f32),
    /// Motion capture stops.
    MocapLoss,
}

impl Fault {
    /// Whether the fault can come on the ground, before take-off (`@start+T`, or no time).
    fn on_the_ground(self) -> bool {
        matches!(
            self,
            Self::ImuStuck | Self::ImuNoise(_) | Self::GcsLoss | Self::Battery(_)
        )
    }
}

/// What an injection's time counts from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Since {
    /// The take-off's beginning (`@T`).
    #[default]
    Takeoff,
    /// The mission's start, the plant's time zero (`@start+T`, or no time for `gcs-loss` and
    /// `battery:V`).
    Start,
}

/// One injection: a fault at a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Injection {
    /// The fault.
    pub fault: Fault,
    /// When, s after [`Self::since`].
    pub after: f32,
    /// What `after` counts from.
    pub since: Since,
}

impl fmt::Display for Injection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let from_start = self.since == Since::Start && self.after == 0.0;
        match self.fault {
            Fault::LoadShift(d) => write!(f, "load-shift:{},{}", d.x, d.y),
            Fault::StepperStall(robot) => return write!(f, "stepper-stall:{}", robot + 1),
            Fault::ImuStuck => write!(f, "imu-stuck"),
            Fault::ImuNoise(x) => write!(f, "imu-noise:{x}"),
            Fault::GcsLoss if from_start => return write!(f, "gcs-loss"),
            Fault::GcsLoss => write!(f, "gcs-loss"),
            Fault::Battery(v) if from_start => return write!(f, "battery:{v}"),
            Fault::Battery(v) => write!(f, "battery:{v}"),
            Fault::RotorOut(robot) => write!(f, "rotor-out:{}", robot + 1),
            Fault::RotorFade(robot, seconds) => write!(f, "rotor-fade:{},{seconds}", robot + 1),
            Fault::MocapLoss => write!(f, "mocap-loss"),
        }?;
        match self.since {
            Since::Takeoff => write!(f, "@{}", self.after),
            Since::Start => write!(f, "@start+{}", self.after),
        }
    }
}

fn number(text: &str, what: &str) -> Result<f32, String> {
    let v: f32 = text
        .trim()
        .parse()
        .map_err(|_| format!("{what} `{text}` is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{what} `{text}` is not a finite number"))
    }
}

fn pack_volts(v: &str, text: &str) -> Result<f32, String> {
    let volts = number(v, "V")?;
    if !(0.0..=MAX_PACK_VOLTS).contains(&volts) {
        return Err(format!(
            "`{text}`: a pack voltage is from 0 to {MAX_PACK_VOLTS} V"
        ));
    }
    Ok(volts)
}

/// The fault named by `kind` (`NAME` or `NAME:ARG`, no time).
fn fault(kind: &str, text: &str) -> Result<Fault, String> {
    let (name, arg) = kind.split_once(':').unwrap_or((kind, ""));
    let no_argument = |fault| {
        if arg.is_empty() {
            Ok(fault)
        } else {
            Err(format!("`{text}`: {name} takes no argument"))
        }
    };
    match name {
        "load-shift" => {
            let (x, y) = arg.split_once(',').ok_or_else(|| {
                format!("`{text}`: load-shift takes DX,DY in metres, e.g. load-shift:0.15,0")
            })?;
            let d = Vec2::new(number(x, "DX")?, number(y, "DY")?);
            if d.norm() > MAX_LOAD_SHIFT {
                return Err(format!(
                    "`{text}`: a load shift of {:.3} m is beyond {MAX_LOAD_SHIFT} m",
                    d.norm()
                ));
            }
            Ok(Fault::LoadShift(d))
        }
        "imu-stuck" => no_argument(Fault::ImuStuck),
        "imu-noise" => {
            let x = number(arg, "noise factor X").map_err(|e| {
                format!("`{text}`: imu-noise:X takes X times the sensor's noise: {e}")
            })?;
            if !(x > 0.0 && x <= MAX_IMU_NOISE) {
                return Err(format!(
                    "`{text}`: imu-noise factor {x} must be above 0 and at most {MAX_IMU_NOISE} (times the sensor's noise)"
                ));
            }
            Ok(Fault::ImuNoise(x))
        }
        "gcs-loss" => no_argument(Fault::GcsLoss),
        "mocap-loss" => no_argument(Fault::MocapLoss),
        "rotor-out" => {
            let robot: usize = arg.trim().parse().map_err(|_| {
                format!(
                    "`{text}`: rotor-out takes a robot's number (1, 2, ...), e.g. rotor-out:3@8"
                )
            })?;
            if !(1..=MAX_ROBOTS).contains(&robot) {
                return Err(format!(
                    "`{text}`: robots are numbered 1 to {MAX_ROBOTS} at most"
                ));
            }
            Ok(Fault::RotorOut(robot - 1))
        }
        "rotor-fade" => {
            let usage = "rotor-fade:J,S takes a robot's number and the seconds its thrust takes to fade to nothing, e.g. rotor-fade:3,4@8";
            let (robot, seconds) = arg
                .split_once(',')
                .ok_or_else(|| format!("`{text}`: {usage}"))?;
            let robot: usize = robot
                .trim()
                .parse()
                .map_err(|_| format!("`{text}`: {usage}"))?;
            if !(1..=MAX_ROBOTS).contains(&robot) {
                return Err(format!(
                    "`{text}`: robots are numbered 1 to {MAX_ROBOTS} at most"
                ));
            }
            let seconds =
                number(seconds, "fade time S").map_err(|e| format!("`{text}`: {usage}: {e}"))?;
            if !(seconds > 0.0 && seconds <= MAX_FADE_TIME) {
                return Err(format!(
                    "`{text}`: the fade time {seconds} s must be above 0 and at most {MAX_FADE_TIME} s"
                ));
            }
            Ok(Fault::RotorFade(robot - 1, seconds))
        }
        "battery" => Ok(Fault::Battery(pack_volts(arg, text)?)),
        other => Err(format!(
            "`{text}`: unknown fault `{other}` (known: load-shift:DX,DY@T, rotor-out:J@T, rotor-fade:J,S@T, mocap-loss@T, stepper-stall:J, imu-stuck@T, imu-noise:X@T, gcs-loss[@T], battery:V[@T]; the IMU, ground-station and battery faults also @start+T)"
        )),
    }
}

impl Injection {
    /// Parses `KIND@SECONDS` (clap's value parser for `--inject`).
    pub fn parse(text: &str) -> Result<Self, String> {
        if let Some(robot) = text.strip_prefix("stepper-stall:") {
            let robot: usize = robot.trim().parse().map_err(|_| {
                format!("`{text}`: stepper-stall takes a robot's number (1, 2, ...) and no time")
            })?;
            if !(1..=MAX_ROBOTS).contains(&robot) {
                return Err(format!(
                    "`{text}`: robots are numbered 1 to {MAX_ROBOTS} at most"
                ));
            }
            return Ok(Self {
                fault: Fault::StepperStall(robot - 1),
                after: 0.0,
                since: Since::Takeoff,
            });
        }
        let Some((kind, at)) = text.rsplit_once('@') else {
            // Without a time: from the start, for the faults that have a state from the start.
            return match fault(text, text)? {
                fault @ (Fault::GcsLoss | Fault::Battery(_)) => Ok(Self {
                    fault,
                    after: 0.0,
                    since: Since::Start,
                }),
                _ => Err(format!(
                    "`{text}`: expected KIND@SECONDS, e.g. load-shift:0.15,0@11"
                )),
            };
        };
        let (since, at) = match at.trim().strip_prefix("start+") {
            Some(rest) => (Since::Start, rest),
            None => (Since::Takeoff, at),
        };
        let after = number(at, "time")?;
        let from = match since {
            Since::Takeoff => "take-off",
            Since::Start => "the start",
        };
        if !(0.0..=MAX_INJECT_TIME).contains(&after) {
            return Err(format!(
                "`{text}`: time {after} s must be from 0 to {MAX_INJECT_TIME} s after {from}"
            ));
        }
        let fault = fault(kind, text)?;
        if since == Since::Start && !fault.on_the_ground() {
            return Err(format!(
                "`{text}`: this fault happens in flight: give its time after take-off (@T), not @start+T"
            ));
        }
        Ok(Self {
            fault,
            after,
            since,
        })
    }
}

/// Refuses an injection that names a robot `loaded` does not have.
pub fn check_robots(injections: &[Injection], loaded: &LoadedScenario) -> anyhow::Result<()> {
    let robots = loaded.scenario.robots.count();
    for i in injections {
        if let Fault::StepperStall(robot) | Fault::RotorOut(robot) | Fault::RotorFade(robot, _) =
            i.fault
            && robot >= robots
        {
            anyhow::bail!("--inject {i}: {} has robots 1 to {robots}", loaded.name);
        }
    }
    Ok(())
}

/// `setup` with `injections` in it, as the plant loop takes them (for `mission` and `hil`
/// alike): every `rotor-out` and `rotor-fade` counts, the last one of another kind; `mocap-loss@T` replaces
/// the setup's `mocap_lost_after_takeoff`.
pub fn apply(injections: &[Injection], mut setup: MissionSetup) -> MissionSetup {
    let onset = |i: &Injection| match i.since {
        Since::Start => Onset::AfterStart(i.after),
        Since::Takeoff => Onset::AfterTakeoff(i.after),
    };
    for i in injections {
        match i.fault {
            Fault::LoadShift(offset) => {
                setup.load_shift = Some(LoadShift {
                    offset,
                    after: i.after,
                });
            }
            Fault::StepperStall(robot) => setup.stepper_stall = Some(robot),
            Fault::ImuStuck | Fault::ImuNoise(_) => {
                let kind = match i.fault {
                    Fault::ImuNoise(x) => ImuFaultKind::Noise(x),
                    _ => ImuFaultKind::Stuck,
                };
                setup.imu_fault = Some(ImuInjection {
                    kind,
                    after: i.after,
                    from_start: i.since == Since::Start,
                });
            }
            Fault::GcsLoss => setup.gcs_loss = Some(onset(i)),
            Fault::Battery(volts) => {
                setup.battery_drop = Some(BatteryDrop {
                    volts,
                    onset: onset(i),
                });
            }
            Fault::RotorOut(_) | Fault::RotorFade(..) => {}
            Fault::MocapLoss => setup.mocap_lost_after_takeoff = Some(i.after),
        }
    }
    setup.rotors_out = rotors_out(injections);
    setup
}

/// The rotors that `injections` stop, in the plant loop's terms (for
/// [`crate::mission_run::MissionSetup::rotors_out`], whichever autopilot flies).
pub fn rotors_out(injections: &[Injection]) -> Vec<RotorStop> {
    injections
        .iter()
        .filter_map(|i| match i.fault {
            Fault::RotorOut(robot) => Some(RotorStop {
                robot,
                after: i.after,
                fade: 0.0,
            }),
            Fault::RotorFade(robot, fade) => Some(RotorStop {
                robot,
                after: i.after,
                fade,
            }),
            _ => None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn injections_parse_and_bad_ones_say_why() {
        let i = Injection::parse("load-shift:0.15,-0.05@11").expect("valid");
        assert_eq!(i.fault, Fault::LoadShift(Vec2::new(0.15, -0.05)));
        assert_eq!(i.after, 11.0);
        assert_eq!(i.to_string(), "load-shift:0.15,-0.05@11");
        let stall = Injection::parse("stepper-stall:2").expect("valid");
        assert_eq!(stall.fault, Fault::StepperStall(1));
        assert_eq!(stall.to_string(), "stepper-stall:2");
        for (text, fault, after, since) in [
            ("imu-stuck@4.5", Fault::ImuStuck, 4.5, Since::Takeoff),
            (
                "imu-noise:50@start+2",
                Fault::ImuNoise(50.0),
                2.0,
                Since::Start,
            ),
            ("gcs-loss@4", Fault::GcsLoss, 4.0, Since::Takeoff),
            ("gcs-loss", Fault::GcsLoss, 0.0, Since::Start),
            ("gcs-loss@start+3", Fault::GcsLoss, 3.0, Since::Start),
            ("battery:12.5@3", Fault::Battery(12.5), 3.0, Since::Takeoff),
            ("battery:13", Fault::Battery(13.0), 0.0, Since::Start),
            ("rotor-out:3@8.5", Fault::RotorOut(2), 8.5, Since::Takeoff),
            ("mocap-loss@6", Fault::MocapLoss, 6.0, Since::Takeoff),
        ] {
            let i = Injection::parse(text).expect(text);
            assert_eq!((i.fault, i.after, i.since), (fault, after, since), "{text}");
            assert_eq!(i.to_string(), text);
        }
        for (bad, says) in [
            ("load-shift:0.15,0", "KIND@SECONDS"),
            ("load-shift:0.15@3", "DX,DY"),
            ("load-shift:nan,0@3", "finite"),
            ("load-shift:5,0@3", "beyond"),
            ("load-shift:0.1,0@-1", "from 0"),
            ("load-shift:0.1,0@start+3", "in flight"),
            ("rotor-gone@3", "unknown fault"),
            ("stepper-stall:x", "robot's number"),
            ("stepper-stall:2@3", "no time"),
            ("stepper-stall:99", "numbered 1 to"),
            ("stepper-stall:0", "numbered 1 to"),
            ("imu-stuck", "KIND@SECONDS"),
            ("imu-stuck:3@1", "no argument"),
            ("imu-noise@1", "not a number"),
            ("imu-noise:0@1", "above 0"),
            ("imu-noise:-5@1", "above 0"),
            ("imu-noise:1001@1", "at most 1000"),
            ("imu-noise:inf@1", "finite"),
            ("imu-stuck@start+x", "not a number"),
            ("imu-stuck@start+-1", "from 0"),
            ("gcs-loss:2@3", "no argument"),
            ("battery@3", "not a number"),
            ("battery:x@3", "not a number"),
            ("battery:-1@3", "from 0 to"),
            ("battery:500", "from 0 to"),
            ("battery:nan", "finite"),
            ("rotor-out:3", "KIND@SECONDS"),
            ("rotor-out:x@3", "robot's number"),
            ("rotor-out:0@3", "numbered 1 to"),
            ("rotor-out:17@3", "numbered 1 to"),
            ("rotor-out:2@-1", "from 0"),
            ("rotor-out:2@start+1", "in flight"),
            ("rotor-fade:2@3", "fade to nothing"),
            ("rotor-fade:2,x@3", "fade time S"),
            ("rotor-fade:2,0@3", "above 0"),
            ("rotor-fade:2,61@3", "at most 60"),
            ("rotor-fade:0,2@3", "numbered 1 to"),
            ("mocap-loss:2@3", "no argument"),
        ] {
            let err = Injection::parse(bad).expect_err(bad);
            assert!(err.contains(says), "{bad}: {err}");
        }
        let two = [
            Injection::parse("rotor-out:3@8.5").expect("valid"),
            Injection::parse("rotor-fade:7,2.5@9").expect("valid"),
            Injection::parse("gcs-loss@2").expect("valid"),
        ];
        assert_eq!(
            rotors_out(&two),
            vec![
                RotorStop {
                    robot: 2,
                    after: 8.5,
                    fade: 0.0,
                },
                RotorStop {
                    robot: 6,
                    after: 9.0,
                    fade: 2.5,
                }
            ]
        );
    }
}
