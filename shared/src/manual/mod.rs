//! What a person at the sticks asks of the vehicle (docs/hardware.md#rc-receivers): the
//! sticks and switches of an RC receiver's channels or of a ground station's joystick
//! (`MANUAL_CONTROL`), as one [`ManualInput`]; which source is in force and when it is lost
//! ([`source`], PX4's `COM_RC_IN_MODE` and `COM_RC_LOSS_T`); the kill switch's rotors-off then
//! disarm ([`kill`], PX4's `COM_KILL_DISARM`); the channels' functions ([`rc_map`], PX4's
//! `RC_MAP_*`); what it may do ([`config`]: the modes, the loss's action).
//!
//! Plain state machines, inputs in and decisions out, as the rest of the mission: the
//! firmware feeds them receiver frames and `MANUAL_CONTROL` messages with the vehicle's time.

pub mod config;
pub mod kill;
pub mod pilot;
pub mod rc_map;
pub mod source;

/// Stick positions, normalised: roll, pitch and yaw in `[-1, 1]` (right, forward, clockwise
/// positive), throttle in `[0, 1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sticks {
    /// Roll: right positive.
    pub roll: f32,
    /// Pitch: forward positive.
    pub pitch: f32,
    /// Yaw: clockwise (seen from above) positive.
    pub yaw: f32,
    /// Throttle: 0 down, 1 up.
    pub throttle: f32,
}

impl Sticks {
    /// Centred sticks and the throttle at mid: hold where the vehicle is.
    pub const CENTRED: Self = Self {
        roll: 0.0,
        pitch: 0.0,
        yaw: 0.0,
        throttle: 0.5,
    };

    /// Every value finite and in its range.
    pub fn is_valid(&self) -> bool {
        let axis = |v: f32| v.is_finite() && (-1.0..=1.0).contains(&v);
        axis(self.roll)
            && axis(self.pitch)
            && axis(self.yaw)
            && self.throttle.is_finite()
            && (0.0..=1.0).contains(&self.throttle)
    }
}

/// One sample of manual control: the sticks, the kill switch and the flight-mode switch's slot.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ManualInput {
    /// The sticks.
    pub sticks: Sticks,
    /// The kill switch is on (rotors off).
    pub kill: bool,
    /// The flight-mode switch's slot, 0 to 5 (PX4's `COM_FLTMODE1..6`), when a channel is
    /// mapped to it.
    pub mode_slot: Option<u8>,
}

pub use config::{ManualConfig, ManualLossAction, PilotMode};
pub use pilot::{Pilot, PilotTick};

/// The manual samples that arrived since the previous control tick, one per source at most
/// (an RC receiver sends at 50 to 150 Hz, a joystick at 25 Hz: the newest is kept).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ManualSamples {
    /// From the RC receiver (a valid frame, not in failsafe).
    pub rc: Option<ManualInput>,
    /// From a ground station's joystick (`MANUAL_CONTROL`).
    pub joystick: Option<ManualInput>,
}

impl ManualSamples {
    /// None.
    pub const NONE: Self = Self {
        rc: None,
        joystick: None,
    };
}

impl ManualInput {
    /// Centred sticks, no switch.
    pub const NONE: Self = Self {
        sticks: Sticks::CENTRED,
        kill: false,
        mode_slot: None,
    };
}

/// Most a `MANUAL_CONTROL` axis carries (its x, y and r are -1000..1000, z 0..1000).
const MAVLINK_FULL_SCALE: f32 = 1000.0;

/// A joystick's `MANUAL_CONTROL` as manual input: x forward (pitch), y right (roll), r yaw,
/// z throttle (0..1000, 500 centred, as QGroundControl sends it); the joystick has no kill
/// or mode switch of its own. `None` for an axis out of its range (-1000..1000; z 0..1000),
/// or the "invalid" value `i16::MAX` MAVLink marks an unused axis with.
pub fn from_manual_control(x: i16, y: i16, z: i16, r: i16) -> Option<ManualInput> {
    let axis = |v: i16| {
        (-1000..=1000)
            .contains(&v)
            .then(|| f32::from(v) / MAVLINK_FULL_SCALE)
    };
    let throttle = (0..=1000)
        .contains(&z)
        .then(|| f32::from(z) / MAVLINK_FULL_SCALE)?;
    Some(ManualInput {
        sticks: Sticks {
            roll: axis(y)?,
            pitch: axis(x)?,
            yaw: axis(r)?,
            throttle,
        },
        kill: false,
        mode_slot: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_joystick_at_rest_is_centred_sticks() {
        let input = from_manual_control(0, 0, 500, 0).expect("in range");
        assert_eq!(input.sticks, Sticks::CENTRED);
        assert!(!input.kill);
    }

    #[test]
    fn a_joystick_axis_out_of_range_is_no_input() {
        assert_eq!(from_manual_control(1001, 0, 500, 0), None);
        assert_eq!(from_manual_control(0, 0, -1, 0), None);
        assert_eq!(from_manual_control(0, i16::MAX, 500, 0), None);
        let full = from_manual_control(1000, -1000, 1000, 1000).expect("in range");
        assert!(full.sticks.is_valid());
        assert_eq!((full.sticks.pitch, full.sticks.roll), (1.0, -1.0));
    }

    #[test]
    fn sticks_out_of_range_are_not_valid() {
        let mut s = Sticks::CENTRED;
        assert!(s.is_valid());
        s.roll = f32::NAN;
        assert!(!s.is_valid());
        s = Sticks::CENTRED;
        s.throttle = -0.1;
        assert!(!s.is_valid());
    }
}
