//! An RC receiver's channels as manual input (PX4's `RC_MAP_ROLL`, `_PITCH`, `_THROTTLE`,
//! `_YAW`, `_KILL_SW`, `_FLTMODE`: a channel number from 1, 0 unassigned). Channels are pulse
//! widths in microseconds, as CRSF and SBUS receivers give them: 1000 to 2000 with 1500
//! centred (PX4's default `RC*_MIN`, `_TRIM`, `_MAX`), a dead band of 10 us about the centre on
//! roll, pitch and yaw (PX4's default `RC*_DZ`). A switch is on above 1750 us (PX4's 0.75
//! threshold); the mode switch's six slots split the range evenly.

use super::{ManualInput, Sticks};
use crate::math::clamp;

/// Pulse width of a stick's low end, us.
const LOW_US: f32 = 1000.0;
/// Pulse width of a centred stick, us.
const CENTRE_US: f32 = 1500.0;
/// Half the stick's travel, us.
const HALF_RANGE_US: f32 = 500.0;
/// The dead band about the centre, us.
const DEAD_BAND_US: f32 = 10.0;
/// A switch is on above this pulse width, us.
const SWITCH_ON_US: u16 = 1750;
/// The mode switch's slots (`COM_FLTMODE1..6`).
const MODE_SLOTS: u16 = 6;

/// Which channel (from 1; 0 unassigned) carries each function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RcMap {
    /// Roll stick.
    pub roll: u8,
    /// Pitch stick.
    pub pitch: u8,
    /// Throttle stick.
    pub throttle: u8,
    /// Yaw stick.
    pub yaw: u8,
    /// Kill switch.
    pub kill_switch: u8,
    /// Flight-mode switch.
    pub mode_switch: u8,
}

impl RcMap {
    /// Nothing assigned (PX4's defaults: the sticks are mapped at the radio's set-up).
    pub const UNASSIGNED: Self = Self {
        roll: 0,
        pitch: 0,
        throttle: 0,
        yaw: 0,
        kill_switch: 0,
        mode_switch: 0,
    };

    /// The sticks on the first four channels in the usual order of CRSF and SBUS radios
    /// (roll, pitch, throttle, yaw: "AETR"), no switch assigned.
    pub const AETR: Self = Self {
        roll: 1,
        pitch: 2,
        throttle: 3,
        yaw: 4,
        kill_switch: 0,
        mode_switch: 0,
    };

    /// The manual input `channels` (pulse widths, us) carry; `None` unless every stick is
    /// assigned to a channel the frame has.
    pub fn input(&self, channels: &[u16]) -> Option<ManualInput> {
        let channel = |n: u8| -> Option<f32> {
            let index = usize::from(n).checked_sub(1)?;
            channels.get(index).map(|&us| f32::from(us))
        };
        let axis = |n: u8| -> Option<f32> {
            let offset = channel(n)? - CENTRE_US;
            let beyond = libm::fmaxf(libm::fabsf(offset) - DEAD_BAND_US, 0.0);
            let value = libm::copysignf(beyond / (HALF_RANGE_US - DEAD_BAND_US), offset);
            Some(clamp(value, -1.0, 1.0))
        };
        let throttle = clamp(
            (channel(self.throttle)? - LOW_US) / (2.0 * HALF_RANGE_US),
            0.0,
            1.0,
        );
        let switch = |n: u8| channel(n).map(|us| us > f32::from(SWITCH_ON_US));
        let mode_slot = channel(self.mode_switch).map(|us| {
            let fraction = clamp((us - LOW_US) / (2.0 * HALF_RANGE_US), 0.0, 1.0);
            let slot = (fraction * f32::from(MODE_SLOTS)) as u16;
            slot.min(MODE_SLOTS - 1) as u8
        });
        Some(ManualInput {
            sticks: Sticks {
                roll: axis(self.roll)?,
                pitch: axis(self.pitch)?,
                yaw: axis(self.yaw)?,
                throttle,
            },
            kill: switch(self.kill_switch).unwrap_or(false),
            mode_slot,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const AETR: RcMap = RcMap {
        roll: 1,
        pitch: 2,
        throttle: 3,
        yaw: 4,
        kill_switch: 5,
        mode_switch: 6,
    };

    #[test]
    fn centred_sticks_and_the_switches_off() {
        let input = AETR
            .input(&[1500, 1505, 1500, 1495, 1000, 1000])
            .expect("every stick mapped");
        assert_eq!(input.sticks, Sticks::CENTRED);
        assert!(!input.kill);
        assert_eq!(input.mode_slot, Some(0));
    }

    #[test]
    fn full_deflection_the_kill_switch_and_the_top_mode_slot() {
        let input = AETR
            .input(&[2000, 1000, 2000, 2012, 2000, 2000])
            .expect("every stick mapped");
        assert_eq!(
            input.sticks,
            Sticks {
                roll: 1.0,
                pitch: -1.0,
                yaw: 1.0,
                throttle: 1.0
            }
        );
        assert!(input.kill);
        assert_eq!(input.mode_slot, Some(5));
    }

    #[test]
    fn six_mode_slots_split_the_range() {
        let slots: [u8; 6] = [1083, 1250, 1416, 1583, 1750, 1916].map(|us| {
            AETR.input(&[1500, 1500, 1000, 1500, 1000, us])
                .and_then(|i| i.mode_slot)
                .expect("a slot")
        });
        assert_eq!(slots, [0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn an_unassigned_or_missing_stick_is_no_input() {
        assert_eq!(RcMap::UNASSIGNED.input(&[1500; 16]), None);
        assert_eq!(AETR.input(&[1500, 1500, 1500]), None);
        let no_switches = RcMap {
            kill_switch: 0,
            mode_switch: 0,
            ..AETR
        };
        let input = no_switches.input(&[1500; 4]).expect("sticks mapped");
        assert!(!input.kill);
        assert_eq!(input.mode_slot, None);
    }
}
