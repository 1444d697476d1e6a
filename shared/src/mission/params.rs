//! The mission's tunables as named 32-bit float parameters: every
//! field of [`MissionConfig`] an operator may change, with its unit, its range and what it
//! does, in one table. The ground link (`link::param`) serves this table over MAVLink's
//! parameter protocol and stores its values; the mission reads them back through
//! [`ParamValues::config`].
//!
//! A value is accepted only when it is finite, inside `[min, max]` and, for a parameter marked
//! integer, a whole number ([`check`]). The ranges bound what the mission has been shown to
//! tolerate or what is physically sensible; they are not tuning advice. The drivers' settings
//! ([`super::hardware`]: ESC protocol, thrust map, steppers) are parameters too. Not here: the
//! estimator's thrust-scale axis (a grid, not a number).

use crate::control::allocation::MixerKind;
use crate::mission::config::MissionConfig;
use crate::mission::supervision::GcsLossAction;
use crate::numbers::Num;

/// Longest parameter name, bytes (MAVLink's `param_id`).
pub const NAME_LEN: usize = 16;

/// One parameter: where it lives in the [`MissionConfig`] and what values it may take.
#[derive(Clone, Copy)]
pub struct ParamSpec {
    /// Name, at most [`NAME_LEN`] bytes, upper case (`GROUP_WHAT`).
    pub name: &'static str,
    /// Unit, as people write it (`-` for none).
    pub unit: &'static str,
    /// Smallest value accepted.
    pub min: f32,
    /// Largest value accepted.
    pub max: f32,
    /// Only whole numbers are accepted (counts, choices).
    pub integer: bool,
    /// What it does, one line (with the `docs` feature: the host's tables and README; the
    /// firmware does without the text).
    #[cfg(feature = "docs")]
    pub doc: &'static str,
    /// Reads it from a configuration.
    pub get: fn(&MissionConfig) -> f32,
    /// Writes it into a configuration (the value already checked).
    pub set: fn(&mut MissionConfig, f32),
}

impl ParamSpec {
    /// Its value in [`MissionConfig::DEFAULT`].
    pub fn default_value(&self) -> f32 {
        (self.get)(&MissionConfig::DEFAULT)
    }
}

impl core::fmt::Debug for ParamSpec {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ParamSpec")
            .field("name", &self.name)
            .finish()
    }
}

macro_rules! param {
    ($name:literal, $unit:literal, $min:expr, $max:expr, $doc:literal, |$c:ident| $field:expr) => {
        param!(@ $name, $unit, $min, $max, false, $doc, |$c| $field)
    };
    // A whole-number field (a count or a choice, of any integer type).
    (whole $name:literal, $unit:literal, $min:expr, $max:expr, $doc:literal, |$c:ident| $field:expr) => {
        ParamSpec {
            name: $name,
            unit: $unit,
            min: $min,
            max: $max,
            integer: true,
            #[cfg(feature = "docs")]
            doc: $doc,
            get: |$c: &MissionConfig| $field as f32,
            set: |$c: &mut MissionConfig, v: f32| $field = v as _,
        }
    };
    (@ $name:literal, $unit:literal, $min:expr, $max:expr, $int:expr, $doc:literal, |$c:ident| $field:expr) => {
        ParamSpec {
            name: $name,
            unit: $unit,
            min: $min,
            max: $max,
            integer: $int,
            #[cfg(feature = "docs")]
            doc: $doc,
            get: |$c: &MissionConfig| $field,
            set: |$c: &mut MissionConfig, v: f32| $field = v,
        }
    };
}

/// Number of parameters.
pub const COUNT: usize = 89;

/// Every parameter, in the order the protocol numbers them (`param_index`).
pub static TABLE: [ParamSpec; COUNT] = [
    // Estimation and lift-off detection.
    ParamSpec {
        name: "LIFT_SIGMA",
        unit: "N",
        min: 0.0,
        max: 5.0,
        integer: false,
        #[cfg(feature = "docs")]
        doc: "standard deviation of a lift reading (estimator noise model); 0: the scenario's noise_sigma",
        get: |c| c.lift_noise_sigma.unwrap_or(0.0),
        set: |c, v| c.lift_noise_sigma = (v > 0.0).then_some(v),
    },
    param!(
        "LIFT_RAMP",
        "N/s",
        0.05,
        10.0,
        "thrust ramp of each robot of the lifting pair",
        |c| c.liftoff.ramp_rate
    ),
    param!(
        "LIFT_TILT",
        "rad",
        0.002,
        0.1,
        "tilt from the resting attitude that counts as lift-off",
        |c| c.liftoff.tilt_threshold
    ),
    param!(
        "LIFT_DELAY",
        "s",
        0.0,
        0.1,
        "attitude-estimate latency compensated at lift-off",
        |c| c.liftoff.detection_delay
    ),
    param!(
        "LIFT_ONSET",
        "-",
        0.05,
        0.95,
        "share of the tilt threshold below which the tilt has not started",
        |c| c.liftoff.onset_fraction
    ),
    param!(
        "LIFT_SETTLE",
        "s",
        0.1,
        5.0,
        "hold at the start and at maximum thrust of a lift",
        |c| c.liftoff.settle_time
    ),
    param!(
        whole "MIS_CONFIRM",
        "-",
        1.0,
        5.0,
        "consecutive lifts the stopping rule must hold for (1: the paper's rule)",
        |c| c.confirmations
    ),
    // Rail.
    param!(
        "RAIL_SPEED",
        "m/s",
        0.01,
        1.0,
        "largest speed of a robot along the rail",
        |c| c.rail_limits.max_speed
    ),
    param!(
        "RAIL_ACCEL",
        "m/s^2",
        0.05,
        5.0,
        "largest acceleration of a robot along the rail",
        |c| c.rail_limits.max_acceleration
    ),
    // Mission timing and limits.
    param!(
        "MIS_HOVER_MAX",
        "-",
        0.2,
        0.95,
        "largest share of total thrust the heaviest plausible payload may need to hover",
        |c| c.max_hover_fraction
    ),
    param!(
        "MIS_CHECKS_T",
        "s",
        1.0,
        60.0,
        "time on the ground, rotors off, before the estimation",
        |c| c.checks_time
    ),
    param!(
        "MIS_RELAX_T",
        "s",
        0.2,
        30.0,
        "time with rotors off after each lift",
        |c| c.relax_time
    ),
    param!(
        "MIS_ARM_T",
        "s",
        0.2,
        10.0,
        "time armed on the ground before take-off",
        |c| c.arm_time
    ),
    ParamSpec {
        name: "MIS_MIXER",
        unit: "-",
        min: 0.0,
        max: 1.0,
        integer: true,
        #[cfg(feature = "docs")]
        doc: "flight mixer: 0 the paper's equal split, 1 full allocation",
        get: |c| match c.mixer {
            MixerKind::EqualSplit => 0.0,
            MixerKind::Allocation => 1.0,
        },
        set: |c, v| {
            c.mixer = if v >= 0.5 {
                MixerKind::Allocation
            } else {
                MixerKind::EqualSplit
            }
        },
    },
    // Flight failsafes.
    param!(
        "FS_TAKEOFF_T",
        "s",
        0.5,
        20.0,
        "time at take-off thrust on the ground before the take-off counts as failed",
        |c| c.flight.takeoff_timeout
    ),
    param!(
        "FS_ARRIVE_TOL",
        "m",
        0.02,
        1.0,
        "distance from a segment's end within which the vehicle has arrived",
        |c| c.flight.arrival_tolerance
    ),
    param!(
        "FS_ARRIVE_T",
        "s",
        1.0,
        120.0,
        "time past a segment's end without arriving before landing where it is",
        |c| c.flight.arrival_timeout
    ),
    param!(
        "FS_TOUCHDOWN_T",
        "s",
        0.5,
        30.0,
        "time after the plan's end near the ground before the rotors stop",
        |c| c.flight.touchdown_timeout
    ),
    param!(
        "FS_DESCENT_MRG",
        "s",
        0.0,
        10.0,
        "margin past the expected touchdown of a blind descent",
        |c| c.flight.failsafe_margin
    ),
    // Flight plan.
    param!("PLN_CLIMB_SPD", "m/s", 0.05, 2.0, "peak climb speed", |c| c
        .flight
        .plan
        .climb_speed),
    param!(
        "PLN_CRUISE_SPD",
        "m/s",
        0.05,
        3.0,
        "peak horizontal speed",
        |c| c.flight.plan.cruise_speed
    ),
    param!(
        "PLN_DESC_SPD",
        "m/s",
        0.05,
        1.0,
        "peak descent speed",
        |c| c.flight.plan.descent_speed
    ),
    param!(
        "PLN_HOVER_T",
        "s",
        0.0,
        60.0,
        "time over the target before landing",
        |c| c.flight.plan.hover_time
    ),
    // The cascade (shared::control::params), one parameter per axis.
    param!(
        "POS_P_X",
        "1/s",
        0.1,
        5.0,
        "position error to velocity, x",
        |c| c.flight.control.position_p.x
    ),
    param!(
        "POS_P_Y",
        "1/s",
        0.1,
        5.0,
        "position error to velocity, y",
        |c| c.flight.control.position_p.y
    ),
    param!(
        "POS_P_Z",
        "1/s",
        0.1,
        5.0,
        "position error to velocity, z",
        |c| c.flight.control.position_p.z
    ),
    param!(
        "VEL_P_X",
        "1/s",
        0.1,
        10.0,
        "velocity error to acceleration, x",
        |c| c.flight.control.velocity_p.x
    ),
    param!(
        "VEL_P_Y",
        "1/s",
        0.1,
        10.0,
        "velocity error to acceleration, y",
        |c| c.flight.control.velocity_p.y
    ),
    param!(
        "VEL_P_Z",
        "1/s",
        0.1,
        10.0,
        "velocity error to acceleration, z",
        |c| c.flight.control.velocity_p.z
    ),
    param!(
        "VEL_I_X",
        "1/s^2",
        0.0,
        5.0,
        "velocity integral gain, x",
        |c| c.flight.control.velocity_i.x
    ),
    param!(
        "VEL_I_Y",
        "1/s^2",
        0.0,
        5.0,
        "velocity integral gain, y",
        |c| c.flight.control.velocity_i.y
    ),
    param!(
        "VEL_I_Z",
        "1/s^2",
        0.0,
        5.0,
        "velocity integral gain, z",
        |c| c.flight.control.velocity_i.z
    ),
    param!(
        "VEL_D_X",
        "-",
        0.0,
        2.0,
        "velocity derivative gain, x",
        |c| c.flight.control.velocity_d.x
    ),
    param!(
        "VEL_D_Y",
        "-",
        0.0,
        2.0,
        "velocity derivative gain, y",
        |c| c.flight.control.velocity_d.y
    ),
    param!(
        "VEL_D_Z",
        "-",
        0.0,
        2.0,
        "velocity derivative gain, z",
        |c| c.flight.control.velocity_d.z
    ),
    param!(
        "VEL_ILIM_X",
        "m/s^2",
        0.0,
        8.0,
        "largest velocity integral, x",
        |c| c.flight.control.velocity_integral_limit.x
    ),
    param!(
        "VEL_ILIM_Y",
        "m/s^2",
        0.0,
        8.0,
        "largest velocity integral, y",
        |c| c.flight.control.velocity_integral_limit.y
    ),
    param!(
        "VEL_ILIM_Z",
        "m/s^2",
        0.0,
        8.0,
        "largest velocity integral, z",
        |c| c.flight.control.velocity_integral_limit.z
    ),
    param!(
        "ATT_P_R",
        "1/s",
        0.1,
        30.0,
        "attitude error to body rate, roll",
        |c| c.flight.control.attitude_p.x
    ),
    param!(
        "ATT_P_P",
        "1/s",
        0.1,
        30.0,
        "attitude error to body rate, pitch",
        |c| c.flight.control.attitude_p.y
    ),
    param!(
        "ATT_P_Y",
        "1/s",
        0.1,
        30.0,
        "attitude error to body rate, yaw",
        |c| c.flight.control.attitude_p.z
    ),
    param!(
        "RATE_MAX_R",
        "rad/s",
        0.1,
        6.0,
        "largest body-rate setpoint, roll",
        |c| c.flight.control.max_rate.x
    ),
    param!(
        "RATE_MAX_P",
        "rad/s",
        0.1,
        6.0,
        "largest body-rate setpoint, pitch",
        |c| c.flight.control.max_rate.y
    ),
    param!(
        "RATE_MAX_Y",
        "rad/s",
        0.1,
        6.0,
        "largest body-rate setpoint, yaw",
        |c| c.flight.control.max_rate.z
    ),
    param!(
        "RATE_P_R",
        "1/s",
        0.1,
        100.0,
        "rate error to angular acceleration, roll",
        |c| c.flight.control.rate_p.x
    ),
    param!(
        "RATE_P_P",
        "1/s",
        0.1,
        100.0,
        "rate error to angular acceleration, pitch",
        |c| c.flight.control.rate_p.y
    ),
    param!(
        "RATE_P_Y",
        "1/s",
        0.1,
        100.0,
        "rate error to angular acceleration, yaw",
        |c| c.flight.control.rate_p.z
    ),
    param!(
        "RATE_I_R",
        "1/s^2",
        0.0,
        200.0,
        "rate integral gain, roll",
        |c| c.flight.control.rate_i.x
    ),
    param!(
        "RATE_I_P",
        "1/s^2",
        0.0,
        200.0,
        "rate integral gain, pitch",
        |c| c.flight.control.rate_i.y
    ),
    param!(
        "RATE_I_Y",
        "1/s^2",
        0.0,
        200.0,
        "rate integral gain, yaw",
        |c| c.flight.control.rate_i.z
    ),
    param!(
        "RATE_D_R",
        "-",
        0.0,
        2.0,
        "rate derivative gain, roll",
        |c| c.flight.control.rate_d.x
    ),
    param!(
        "RATE_D_P",
        "-",
        0.0,
        2.0,
        "rate derivative gain, pitch",
        |c| c.flight.control.rate_d.y
    ),
    param!(
        "RATE_D_Y",
        "-",
        0.0,
        2.0,
        "rate derivative gain, yaw",
        |c| c.flight.control.rate_d.z
    ),
    param!(
        "RATE_ILIM_R",
        "rad/s^2",
        0.0,
        40.0,
        "largest rate integral, roll",
        |c| c.flight.control.rate_integral_limit.x
    ),
    param!(
        "RATE_ILIM_P",
        "rad/s^2",
        0.0,
        40.0,
        "largest rate integral, pitch",
        |c| c.flight.control.rate_integral_limit.y
    ),
    param!(
        "RATE_ILIM_Y",
        "rad/s^2",
        0.0,
        40.0,
        "largest rate integral, yaw",
        |c| c.flight.control.rate_integral_limit.z
    ),
    param!(
        "RATE_ACC_R",
        "rad/s^2",
        0.5,
        200.0,
        "largest angular acceleration command, roll",
        |c| c.flight.control.max_angular_acceleration.x
    ),
    param!(
        "RATE_ACC_P",
        "rad/s^2",
        0.5,
        200.0,
        "largest angular acceleration command, pitch",
        |c| c.flight.control.max_angular_acceleration.y
    ),
    param!(
        "RATE_ACC_Y",
        "rad/s^2",
        0.5,
        200.0,
        "largest angular acceleration command, yaw",
        |c| c.flight.control.max_angular_acceleration.z
    ),
    param!(
        "POS_SPD_XY",
        "m/s",
        0.1,
        5.0,
        "largest horizontal velocity setpoint",
        |c| c.flight.control.max_speed_xy
    ),
    param!(
        "POS_SPD_Z",
        "m/s",
        0.1,
        3.0,
        "largest vertical velocity setpoint",
        |c| c.flight.control.max_speed_z
    ),
    param!(
        "VEL_D_CUT",
        "Hz",
        1.0,
        100.0,
        "cut-off of the velocity derivative low-pass",
        |c| c.flight.control.velocity_d_cutoff_hz
    ),
    param!(
        "MAX_TILT",
        "rad",
        0.05,
        0.7,
        "largest tilt of the thrust vector from vertical",
        |c| c.flight.control.max_tilt
    ),
    param!(
        "RATE_D_CUT",
        "Hz",
        1.0,
        150.0,
        "cut-off of the rate derivative low-pass",
        |c| c.flight.control.rate_d_cutoff_hz
    ),
    param!(
        "MAX_COLLECTIVE",
        "-",
        0.3,
        0.98,
        "largest collective thrust, share of the rotors' total",
        |c| c.flight.control.max_collective_fraction
    ),
    // In-flight adaptation to a load that shifts (flight::adapt).
    ParamSpec {
        name: "ADPT_ENABLE",
        unit: "-",
        min: 0.0,
        max: 1.0,
        integer: true,
        #[cfg(feature = "docs")]
        doc: "re-form in flight when the measured COM moves: 1 on, 0 off",
        get: |c| if c.adapt.enabled { 1.0 } else { 0.0 },
        set: |c, v| c.adapt.enabled = v >= 0.5,
    },
    param!(
        "ADPT_THRESH",
        "m",
        0.02,
        0.5,
        "COM distance from the formation's that calls for a new formation",
        |c| c.adapt.threshold
    ),
    param!(
        "ADPT_HOLD",
        "s",
        0.1,
        10.0,
        "time a confident shift must last before the robots move",
        |c| c.adapt.hold
    ),
    param!(
        "ADPT_MAX_HOLD",
        "s",
        1.0,
        120.0,
        "longest the hover is held for one adaptation",
        |c| c.adapt.max_hold
    ),
    param!(
        "ADPT_RAIL_SPD",
        "m/s",
        0.01,
        0.5,
        "rail speed of the robots in flight",
        |c| c.adapt.rail.max_speed
    ),
    param!(
        "ADPT_RAIL_ACC",
        "m/s^2",
        0.01,
        1.0,
        "rail acceleration of the robots in flight",
        |c| c.adapt.rail.max_acceleration
    ),
    param!(
        "ADPT_TRIM_WIN",
        "s",
        0.5,
        10.0,
        "averaging window of the in-flight COM trim",
        |c| c.adapt.trim.window
    ),
    param!(
        "ADPT_TRIM_STDY",
        "m",
        0.005,
        0.2,
        "largest difference of the window's halves for a steady trim",
        |c| c.adapt.trim.steadiness
    ),
    // The drivers (mission::hardware): ESCs, thrust map, steppers.
    param!(
        whole "ESC_PROTOCOL",
        "-",
        0.0,
        2.0,
        "ESC protocol on the FMU outputs: 0 DShot600, 1 PWM, 2 OneShot125 (taken while disarmed)",
        |c| c.hardware.esc_protocol
    ),
    param!(
        "THR_MAP_20",
        "-",
        0.001,
        0.999,
        "thrust at 20 % ESC command, fraction of full thrust (a bench calibration; rising with the command)",
        |c| c.hardware.thrust_map[0]
    ),
    param!(
        "THR_MAP_40",
        "-",
        0.001,
        0.999,
        "thrust at 40 % ESC command, fraction of full thrust",
        |c| c.hardware.thrust_map[1]
    ),
    param!(
        "THR_MAP_60",
        "-",
        0.001,
        0.999,
        "thrust at 60 % ESC command, fraction of full thrust",
        |c| c.hardware.thrust_map[2]
    ),
    param!(
        "THR_MAP_80",
        "-",
        0.001,
        0.999,
        "thrust at 80 % ESC command, fraction of full thrust",
        |c| c.hardware.thrust_map[3]
    ),
    param!(
        whole "STP_STEPS_REV",
        "-",
        24.0,
        400.0,
        "full steps per stepper revolution (200 for 1.8 deg motors)",
        |c| c.hardware.drive.steps_per_rev
    ),
    param!(
        whole "STP_MICROSTEPS",
        "-",
        1.0,
        256.0,
        "microsteps per full step set in the TMC2209s (a power of two)",
        |c| c.hardware.drive.microsteps
    ),
    param!(
        "STP_PINION_D",
        "m",
        0.005,
        0.1,
        "pitch diameter of the robots' pinions",
        |c| c.hardware.drive.pinion_pitch_diameter
    ),
    param!(
        "STP_CURRENT",
        "A",
        0.1,
        2.0,
        "stepper motor current, RMS",
        |c| c.hardware.stepper_current
    ),
    param!(
        "STP_RSENSE",
        "ohm",
        0.05,
        0.5,
        "sense resistors of the TMC2209 boards",
        |c| c.hardware.stepper_r_sense
    ),
    param!(
        whole "STP_SGTHRS",
        "-",
        0.0,
        255.0,
        "StallGuard threshold (SGTHRS): stalled when SG_RESULT <= 2x this at speed; 0 off (tune on the bench)",
        |c| c.hardware.stall_threshold
    ),
    // The ground link's and the battery's failsafes (mission::supervision).
    ParamSpec {
        name: "FS_GCS_ACT",
        unit: "-",
        min: 0.0,
        max: 2.0,
        integer: true,
        #[cfg(feature = "docs")]
        doc: "ground link lost in flight: 0 not watched (no start refused), 1 fly on to the target and land, 2 hold FS_GCS_HOLD_T then land in place",
        get: |c| c.supervision.gcs_action as u8 as f32,
        set: |c, v| c.supervision.gcs_action = GcsLossAction::from_value(v),
    },
    param!(
        "FS_GCS_LOSS_T",
        "s",
        1.0,
        60.0,
        "time without a ground station's heartbeat before the link counts as lost (PX4's COM_DL_LOSS_T)",
        |c| c.supervision.gcs_timeout
    ),
    param!(
        "FS_GCS_HOLD_T",
        "s",
        0.0,
        300.0,
        "with FS_GCS_ACT 2: time held where the vehicle is before it lands in place (a link back meanwhile resumes the plan)",
        |c| c.supervision.gcs_hold_time
    ),
    param!(
        "BAT_LOW_V",
        "V",
        0.0,
        100.0,
        "filtered pack voltage below which the battery is low: a warning, and no start; 0 off",
        |c| c.supervision.battery_low
    ),
    param!(
        "BAT_CRIT_V",
        "V",
        0.0,
        100.0,
        "filtered pack voltage below which the battery is critical: landing in place (stop on the ground); 0 off",
        |c| c.supervision.battery_critical
    ),
];

/// Why a value was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamError {
    /// No parameter has this name or index.
    Unknown,
    /// Not a finite number.
    NotFinite,
    /// Outside the parameter's range.
    OutOfRange {
        /// Smallest accepted.
        min: f32,
        /// Largest accepted.
        max: f32,
    },
    /// A fraction given to a parameter that takes whole numbers.
    NotWhole,
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Unknown => write!(f, "no such parameter"),
            Self::NotFinite => write!(f, "not a finite number"),
            Self::OutOfRange { min, max } => write!(f, "outside {}..{}", Num(min), Num(max)),
            Self::NotWhole => write!(f, "not a whole number"),
        }
    }
}

/// Whether `value` is acceptable for parameter `index`.
pub fn check(index: usize, value: f32) -> Result<(), ParamError> {
    let spec = TABLE.get(index).ok_or(ParamError::Unknown)?;
    if !value.is_finite() {
        return Err(ParamError::NotFinite);
    }
    if value < spec.min || value > spec.max {
        return Err(ParamError::OutOfRange {
            min: spec.min,
            max: spec.max,
        });
    }
    if spec.integer && crate::math::floor(value) != value {
        return Err(ParamError::NotWhole);
    }
    Ok(())
}

/// The index of the parameter called `name` (MAVLink `param_id`: up to 16 bytes, NUL-padded).
pub fn find(name: &[u8]) -> Option<usize> {
    let end = name.iter().position(|&b| b == 0).unwrap_or(name.len());
    let name = &name[..end];
    TABLE.iter().position(|p| p.name.as_bytes() == name)
}

/// The current value of every parameter, in table order; always valid (every value passed
/// [`check`]).
#[derive(Clone, Debug)]
pub struct ParamValues {
    values: [f32; COUNT],
}

/// Equal when every parameter has the same value in force, bit for bit (one never set equals
/// one set to its default). Not derived: NaN marks "never set", and NaN equals nothing.
impl PartialEq for ParamValues {
    fn eq(&self, other: &Self) -> bool {
        (0..COUNT).all(|i| self.get(i).map(f32::to_bits) == other.get(i).map(f32::to_bits))
    }
}

impl Default for ParamValues {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl ParamValues {
    /// Every parameter at its default ([`MissionConfig::DEFAULT`]).
    pub const DEFAULT: Self = Self {
        values: [f32::NAN; COUNT],
    };

    /// Value of parameter `index` (`None` past the table).
    pub fn get(&self, index: usize) -> Option<f32> {
        let v = *self.values.get(index)?;
        // NaN marks "never set": the default, read from the table.
        Some(if v.is_nan() {
            TABLE[index].default_value()
        } else {
            v
        })
    }

    /// Sets parameter `index` to `value` if [`check`] accepts it; otherwise keeps the old value.
    pub fn set(&mut self, index: usize, value: f32) -> Result<(), ParamError> {
        check(index, value)?;
        self.values[index] = value;
        Ok(())
    }

    /// The mission configuration these values make (the defaults for what no parameter
    /// covers).
    pub fn config(&self) -> MissionConfig {
        let mut config = MissionConfig::DEFAULT;
        for (index, spec) in TABLE.iter().enumerate() {
            if let Some(v) = self.get(index) {
                (spec.set)(&mut config, v);
            }
        }
        config
    }
}

/// The parameter table in Markdown (name, unit, range, default, what it does), as
/// docs/ground-link.md lists it.
#[cfg(feature = "docs")]
pub fn markdown_table(out: &mut impl core::fmt::Write) -> core::fmt::Result {
    writeln!(out, "| index | name | unit | min | max | default | what |")?;
    writeln!(out, "|---|---|---|---|---|---|---|")?;
    for (i, p) in TABLE.iter().enumerate() {
        let kind = if p.integer { " (whole)" } else { "" };
        writeln!(
            out,
            "| {i} | `{}` | {} | {} | {} | {} | {}{kind} |",
            p.name,
            p.unit,
            p.min,
            p.max,
            p.default_value(),
            p.doc
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Found writing the `link_input` fuzz target: the derived `PartialEq` compared
    /// the storage, where NaN marks a parameter never set, so the defaults did not equal
    /// themselves.
    #[test]
    fn values_compare_by_the_values_in_force() {
        assert_eq!(ParamValues::DEFAULT, ParamValues::DEFAULT);
        let mut set = ParamValues::DEFAULT;
        set.set(0, TABLE[0].default_value())
            .expect("the default is valid");
        assert_eq!(
            set,
            ParamValues::DEFAULT,
            "set to the default equals never set"
        );
        let p = &TABLE[0];
        let other = if p.min != p.default_value() {
            p.min
        } else {
            p.max
        };
        set.set(0, other).expect("the range's ends are valid");
        assert_ne!(set, ParamValues::DEFAULT);
    }

    #[test]
    fn names_are_unique_short_and_in_mavlink_style() {
        for (i, p) in TABLE.iter().enumerate() {
            assert!(p.name.len() <= NAME_LEN, "{} too long", p.name);
            assert!(
                p.name
                    .bytes()
                    .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_'),
                "{}",
                p.name
            );
            assert_eq!(find(p.name.as_bytes()), Some(i), "{} not unique", p.name);
            assert!(!p.unit.is_empty());
            #[cfg(feature = "docs")]
            assert!(!p.doc.is_empty());
        }
    }

    #[test]
    fn the_defaults_are_in_range_and_make_the_default_configuration() {
        for (i, p) in TABLE.iter().enumerate() {
            assert_eq!(check(i, p.default_value()), Ok(()), "{}", p.name);
        }
        assert_eq!(ParamValues::DEFAULT.config(), MissionConfig::DEFAULT);
    }

    #[test]
    fn each_parameter_changes_its_own_field_and_no_other() {
        for (i, p) in TABLE.iter().enumerate() {
            let mut values = ParamValues::DEFAULT;
            // A value in range that differs from the default.
            let v = if p.default_value() == p.max {
                p.min
            } else {
                p.max
            };
            values.set(i, v).expect("in range");
            let config = values.config();
            assert_eq!((p.get)(&config), v, "{} not written", p.name);
            assert_ne!(config, MissionConfig::DEFAULT, "{} has no effect", p.name);
            for (j, q) in TABLE.iter().enumerate() {
                if j != i {
                    assert_eq!(
                        (q.get)(&config),
                        q.default_value(),
                        "{} moved {}",
                        p.name,
                        q.name
                    );
                }
            }
        }
    }

    #[test]
    fn bad_values_are_refused_and_the_old_value_kept() {
        let i = find(b"MAX_TILT").expect("exists");
        let mut values = ParamValues::DEFAULT;
        values.set(i, 0.5).expect("in range");
        for bad in [f32::NAN, f32::INFINITY, -0.1, 10.0] {
            assert!(values.set(i, bad).is_err(), "{bad} taken");
            assert_eq!(values.get(i), Some(0.5));
        }
        let c = find(b"MIS_CONFIRM").expect("exists");
        assert_eq!(values.set(c, 2.5), Err(ParamError::NotWhole));
        assert_eq!(values.set(c, 3.0), Ok(()));
        assert_eq!(values.config().confirmations, 3);
        assert_eq!(check(COUNT, 1.0), Err(ParamError::Unknown));
        assert_eq!(values.get(COUNT), None);
    }

    #[test]
    fn names_are_found_with_and_without_padding() {
        let mut id = [0u8; 16];
        id[..9].copy_from_slice(b"LIFT_RAMP");
        assert_eq!(find(&id), Some(1));
        assert_eq!(find(b"LIFT_RAMP"), Some(1));
        assert_eq!(find(b"LIFT_RAM"), None);
        assert_eq!(find(&[0xFF; 16]), None);
    }
}
