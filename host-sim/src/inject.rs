//! Failure injection on the command line: `--inject KIND@SECONDS` (seconds after take-off
//! began; repeatable). The IMU's faults may also come on the ground: `KIND@start+SECONDS` is
//! that many seconds after the mission's start (the plant's time zero; `@start+0` from the
//! first sample). Each kind is parsed and range-checked here, with an error that names the
//! flag and what is wrong; the plant loop ([`crate::mission_run`]) applies it.
//!
//! Kinds (robots numbered from 1, as the mission's texts number them):
//! - `load-shift:DX,DY@T`: the payload's COM moves by (DX, DY) m over half a second, a load
//!   sliding on the plate (the in-flight adaptation's test);
//! - `stepper-stall:J`: robot J's stepper stalls halfway through the rearrangement before
//!   take-off and its driver reports it, as StallGuard does on the board (issue 15; no time).

use std::fmt;

use shared::geometry::Vec2;
use shared::scenario::MAX_ROBOTS;

/// Largest load shift, m: beyond the paper's payloads (1.76 m long at most).
pub const MAX_LOAD_SHIFT: f32 = 1.0;
/// Largest IMU noise factor: at 1000 times the simulated sensor's, the accelerometer's noise
/// (50 m/s^2) reaches a third of the ICM-42688-P's range (+-16 g) and the gyro's (5 rad/s)
/// a seventh of its +-2000 deg/s; beyond, a real sensor would read at full scale, which the
/// board's driver reports.
pub const MAX_IMU_NOISE: f32 = 1000.0;
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
}

/// What an injection's time counts from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Since {
    /// The take-off's beginning (`@T`).
    #[default]
    Takeoff,
    /// The mission's start, the plant's time zero (`@start+T`; IMU faults only).
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
        match self.fault {
            Fault::LoadShift(d) => write!(f, "load-shift:{},{}@", d.x, d.y),
            Fault::StepperStall(robot) => return write!(f, "stepper-stall:{}", robot + 1),
            Fault::ImuStuck => write!(f, "imu-stuck@"),
            Fault::ImuNoise(x) => write!(f, "imu-noise:{x}@"),
        }?;
        match self.since {
            Since::Takeoff => write!(f, "{}", self.after),
            Since::Start => write!(f, "start+{}", self.after),
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
        let (kind, at) = text
            .rsplit_once('@')
            .ok_or_else(|| format!("`{text}`: expected KIND@SECONDS, e.g. load-shift:0.15,0@11"))?;
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
        let (name, arg) = kind.split_once(':').unwrap_or((kind, ""));
        let fault = match name {
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
                Fault::LoadShift(d)
            }
            "imu-stuck" if arg.is_empty() => Fault::ImuStuck,
            "imu-stuck" => return Err(format!("`{text}`: imu-stuck takes no argument")),
            "imu-noise" => {
                let x = number(arg, "noise factor X").map_err(|e| {
                    format!("`{text}`: imu-noise:X takes X times the sensor's noise: {e}")
                })?;
                if !(x > 0.0 && x <= MAX_IMU_NOISE) {
                    return Err(format!(
                        "`{text}`: imu-noise factor {x} must be above 0 and at most {MAX_IMU_NOISE} (times the sensor's noise)"
                    ));
                }
                Fault::ImuNoise(x)
            }
            other => {
                return Err(format!(
                    "`{text}`: unknown fault `{other}` (known: load-shift:DX,DY@T, stepper-stall:J, imu-stuck@T, imu-noise:X@T; IMU faults also @start+T)"
                ));
            }
        };
        if since == Since::Start && !matches!(fault, Fault::ImuStuck | Fault::ImuNoise(_)) {
            return Err(format!(
                "`{text}`: only the IMU's faults take @start+T; a load shift happens in flight (@T, after take-off)"
            ));
        }
        Ok(Self {
            fault,
            after,
            since,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_load_shift_parses_and_bad_ones_say_why() {
        let i = Injection::parse("load-shift:0.15,-0.05@11").expect("valid");
        assert_eq!(i.fault, Fault::LoadShift(Vec2::new(0.15, -0.05)));
        assert_eq!(i.after, 11.0);
        assert_eq!(i.to_string(), "load-shift:0.15,-0.05@11");
        let stall = Injection::parse("stepper-stall:2").expect("valid");
        assert_eq!(stall.fault, Fault::StepperStall(1));
        assert_eq!(stall.to_string(), "stepper-stall:2");
        let stuck = Injection::parse("imu-stuck@4.5").expect("valid");
        assert_eq!(
            (stuck.fault, stuck.after, stuck.since),
            (Fault::ImuStuck, 4.5, Since::Takeoff)
        );
        assert_eq!(stuck.to_string(), "imu-stuck@4.5");
        let noisy = Injection::parse("imu-noise:50@start+2").expect("valid");
        assert_eq!(
            (noisy.fault, noisy.after, noisy.since),
            (Fault::ImuNoise(50.0), 2.0, Since::Start)
        );
        assert_eq!(noisy.to_string(), "imu-noise:50@start+2");
        for (bad, says) in [
            ("load-shift:0.15,0", "KIND@SECONDS"),
            ("load-shift:0.15@3", "DX,DY"),
            ("load-shift:nan,0@3", "finite"),
            ("load-shift:5,0@3", "beyond"),
            ("load-shift:0.1,0@-1", "from 0"),
            ("rotor-gone@3", "unknown fault"),
            ("stepper-stall:x", "robot's number"),
            ("stepper-stall:2@3", "no time"),
            ("stepper-stall:99", "numbered 1 to"),
            ("stepper-stall:0", "numbered 1 to"),
            ("imu-stuck:3@1", "no argument"),
            ("imu-noise@1", "not a number"),
            ("imu-noise:0@1", "above 0"),
            ("imu-noise:-5@1", "above 0"),
            ("imu-noise:1001@1", "at most 1000"),
            ("imu-noise:inf@1", "finite"),
            ("imu-stuck@start+x", "not a number"),
            ("imu-stuck@start+-1", "after the start"),
            ("load-shift:0.1,0@start+3", "only the IMU's faults"),
        ] {
            let err = Injection::parse(bad).expect_err(bad);
            assert!(err.contains(says), "{bad}: {err}");
        }
    }
}
