//! The vehicle's flight modes as ground stations show and command them
//! (docs/ground-link.md#flight-modes): MAVLink's standard modes protocol (`AVAILABLE_MODES`,
//! `CURRENT_MODE`, `MAV_CMD_DO_SET_STANDARD_MODE`) and PX4's custom-mode numbers in the
//! `HEARTBEAT` and `MAV_CMD_DO_SET_MODE`, which MAVSDK and pymavlink use for any autopilot.
//!
//! | mode | when | PX4 main/sub mode | standard mode |
//! |---|---|---|---|
//! | Ready | before the start, and once the mission is over | AUTO (4) / READY (1) | none |
//! | Mission | the mission runs: estimation, formation, take-off, the route, its landing | AUTO (4) / MISSION (4) | `MISSION` |
//! | Hold | in flight, held where it is by the operator (or while the ground link is lost) | AUTO (4) / LOITER (3) | none |
//! | Land | landing where it is (the operator's, or a failsafe's) | AUTO (4) / LAND (6) | `LAND` |
//! | Position | in flight, the sticks (RC or joystick) steer the payload (docs/manual-control.md) | POSCTL (3) / 0 | `POSITION_HOLD` |
//!
//! The `HEARTBEAT`'s `custom_mode` is PX4's number (main mode in bits 16 to 23, sub mode in
//! bits 24 to 31) with the [`MissionState`] in its low byte, which PX4's decoders leave
//! alone.

use crate::msg::{AVAILABLE_MODES_DATA, CURRENT_MODE_DATA, MavModeProperty, MavStandardMode};
use crate::status::MissionState;

/// PX4's main mode `AUTO`.
const PX4_MAIN_AUTO: u32 = 4;
/// PX4's main mode `POSCTL` (Position).
const PX4_MAIN_POSCTL: u32 = 3;
/// PX4's `AUTO` sub modes this vehicle has.
const PX4_SUB_READY: u32 = 1;
const PX4_SUB_LOITER: u32 = 3;
const PX4_SUB_MISSION: u32 = 4;
const PX4_SUB_LAND: u32 = 6;

/// A flight mode of the vehicle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum FlightMode {
    /// On the ground, waiting for the start, or the mission is over.
    Ready = 0,
    /// The mission runs.
    Mission = 1,
    /// Holding where it is in flight.
    Hold = 2,
    /// Landing where it is.
    Land = 3,
    /// The sticks steer the payload.
    Position = 4,
}

/// Every mode, in `AVAILABLE_MODES`' order (index 1 first).
pub const MODES: [FlightMode; 5] = [
    FlightMode::Ready,
    FlightMode::Mission,
    FlightMode::Hold,
    FlightMode::Land,
    FlightMode::Position,
];

impl FlightMode {
    /// The mode's name for people.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ready => "Ready",
            Self::Mission => "Mission",
            Self::Hold => "Hold",
            Self::Land => "Land",
            Self::Position => "Position",
        }
    }

    /// The mode coded as a byte ([`Self::from_code`] reads it back).
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The mode of a [`Self::code`].
    pub fn from_code(code: u8) -> Option<Self> {
        MODES.into_iter().find(|m| m.code() == code)
    }

    /// PX4's custom-mode number of the mode (main mode in bits 16 to 23, sub mode in 24 to 31).
    pub fn px4_custom_mode(self) -> u32 {
        let sub = match self {
            Self::Ready => PX4_SUB_READY,
            Self::Mission => PX4_SUB_MISSION,
            Self::Hold => PX4_SUB_LOITER,
            Self::Land => PX4_SUB_LAND,
            Self::Position => return PX4_MAIN_POSCTL << 16,
        };
        (PX4_MAIN_AUTO << 16) | (sub << 24)
    }

    /// The mode a PX4 main and sub mode (`MAV_CMD_DO_SET_MODE`'s parameters 2 and 3) name,
    /// if this vehicle has it.
    pub fn from_px4(main: f32, sub: f32) -> Option<Self> {
        if main == PX4_MAIN_POSCTL as f32 && sub == 0.0 {
            return Some(Self::Position);
        }
        if main != PX4_MAIN_AUTO as f32 {
            return None;
        }
        MODES
            .into_iter()
            .find(|m| (m.px4_custom_mode() >> 24) as f32 == sub)
    }

    /// The `HEARTBEAT`'s `custom_mode`: PX4's number with the mission's state in its low byte.
    pub fn heartbeat_custom_mode(self, state: MissionState) -> u32 {
        self.px4_custom_mode() | state as u32
    }

    /// The standard mode it is (`NON_STANDARD` for Ready and Hold).
    pub fn standard(self) -> MavStandardMode {
        match self {
            Self::Mission => MavStandardMode::MAV_STANDARD_MODE_MISSION,
            Self::Land => MavStandardMode::MAV_STANDARD_MODE_LAND,
            Self::Position => MavStandardMode::MAV_STANDARD_MODE_POSITION_HOLD,
            Self::Ready | Self::Hold => MavStandardMode::MAV_STANDARD_MODE_NON_STANDARD,
        }
    }

    /// The mode a standard mode number (`MAV_CMD_DO_SET_STANDARD_MODE`'s parameter 1) names,
    /// if this vehicle has it.
    pub fn from_standard(number: f32) -> Option<Self> {
        MODES.into_iter().find(|m| {
            m.standard() != MavStandardMode::MAV_STANDARD_MODE_NON_STANDARD
                && m.standard() as u32 as f32 == number
        })
    }

    /// `AVAILABLE_MODES` for this mode (index from 1 in [`MODES`]' order).
    pub fn available(self) -> AVAILABLE_MODES_DATA {
        let index = MODES.iter().position(|m| *m == self).unwrap_or(0) + 1;
        let mut mode_name = [0u8; 35];
        let name = self.name().as_bytes();
        mode_name[..name.len()].copy_from_slice(name);
        let mut properties = if self == Self::Position {
            MavModeProperty::empty()
        } else {
            MavModeProperty::MAV_MODE_PROPERTY_AUTO_MODE
        };
        if self == Self::Ready {
            properties |= MavModeProperty::MAV_MODE_PROPERTY_NOT_USER_SELECTABLE;
        }
        AVAILABLE_MODES_DATA {
            custom_mode: self.px4_custom_mode(),
            properties,
            number_modes: MODES.len() as u8,
            mode_index: index as u8,
            standard_mode: self.standard(),
            mode_name: mode_name.into(),
        }
    }

    /// `CURRENT_MODE` in this mode, `intended` the mode the operator last asked for.
    pub fn current(self, intended: FlightMode) -> CURRENT_MODE_DATA {
        CURRENT_MODE_DATA {
            custom_mode: self.px4_custom_mode(),
            intended_custom_mode: intended.px4_custom_mode(),
            standard_mode: self.standard(),
        }
    }
}

/// The flight mode coded in a `HEARTBEAT`'s `custom_mode`, if it is one of this vehicle's.
pub fn flight_mode(custom_mode: u32) -> Option<FlightMode> {
    MODES
        .into_iter()
        .find(|m| m.px4_custom_mode() == custom_mode & 0xffff_0000)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn px4_numbers_are_those_mavsdk_and_pymavlink_decode() {
        // pymavlink's `interpret_px4_mode`: main = bits 16..24, sub = bits 24..32.
        let decode = |m: FlightMode| {
            let c = m.px4_custom_mode();
            ((c >> 16) & 0xff, c >> 24)
        };
        assert_eq!(decode(FlightMode::Mission), (4, 4));
        assert_eq!(decode(FlightMode::Hold), (4, 3));
        assert_eq!(decode(FlightMode::Land), (4, 6));
        assert_eq!(decode(FlightMode::Ready), (4, 1));
        assert_eq!(decode(FlightMode::Position), (3, 0));
        for m in MODES {
            let (main, sub) = decode(m);
            assert_eq!(FlightMode::from_px4(main as f32, sub as f32), Some(m));
            assert_eq!(FlightMode::from_code(m.code()), Some(m));
        }
        // PX4's return (4/5), altitude (2/0) and position's orbit (3/1) are not this vehicle's.
        assert_eq!(FlightMode::from_px4(4.0, 5.0), None);
        assert_eq!(FlightMode::from_px4(2.0, 0.0), None);
        assert_eq!(FlightMode::from_px4(3.0, 1.0), None);
        assert_eq!(FlightMode::from_px4(f32::NAN, 4.0), None);
    }

    #[test]
    fn the_heartbeat_carries_both_the_mode_and_the_mission_state() {
        for m in MODES {
            for s in [
                MissionState::Idle,
                MissionState::Running,
                MissionState::Completed,
                MissionState::Aborted,
            ] {
                let c = m.heartbeat_custom_mode(s);
                assert_eq!(MissionState::from_custom_mode(c), Some(s));
                assert_eq!(flight_mode(c), Some(m));
            }
        }
    }

    #[test]
    fn standard_modes_map_both_ways_and_list_every_mode_once() {
        assert_eq!(FlightMode::from_standard(6.0), Some(FlightMode::Mission));
        assert_eq!(FlightMode::from_standard(7.0), Some(FlightMode::Land));
        assert_eq!(FlightMode::from_standard(1.0), Some(FlightMode::Position));
        assert_eq!(FlightMode::from_standard(0.0), None);
        assert_eq!(FlightMode::from_standard(2.0), None);
        let listed: std::vec::Vec<_> = MODES.iter().map(|m| m.available()).collect();
        for (i, a) in listed.iter().enumerate() {
            assert_eq!(a.mode_index as usize, i + 1);
            assert_eq!(a.number_modes as usize, MODES.len());
        }
        let ready = FlightMode::Ready.available();
        assert!(
            ready
                .properties
                .contains(MavModeProperty::MAV_MODE_PROPERTY_NOT_USER_SELECTABLE)
        );
        assert!(&ready.mode_name[..5] == b"Ready");
    }
}
