//! What manual control may do and when it counts as lost (docs/manual-control.md, PX4's
//! `COM_RC_IN_MODE`, `COM_RC_LOSS_T`, `COM_KILL_DISARM`, `NAV_RCL_ACT`, `COM_FAIL_ACT_T` and
//! `COM_FLTMODE1..6`, with PX4's numbers), and the modes a person can choose.

use super::source::InputMode;
use crate::flight::ManualLimits;

/// A flight mode a person can choose with the mode switch or the ground station.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PilotMode {
    /// Fly the mission (PX4's Mission, `COM_FLTMODE` value 3).
    Mission,
    /// Hold where the vehicle is (PX4's Hold, 4).
    Hold,
    /// Land where the vehicle is (PX4's Land, 11).
    Land,
    /// The sticks steer the payload (PX4's Position, 2).
    Position,
}

impl PilotMode {
    /// The mode of a `COM_FLTMODEn` value; `None` for -1 (unassigned) and for PX4 modes this
    /// vehicle does not fly.
    pub fn from_param(value: f32) -> Option<Self> {
        [Self::Position, Self::Mission, Self::Hold, Self::Land]
            .into_iter()
            .find(|mode| mode.param_value() == value)
    }

    /// Its `COM_FLTMODEn` value (PX4's number).
    pub fn param_value(self) -> f32 {
        match self {
            Self::Position => 2.0,
            Self::Mission => 3.0,
            Self::Hold => 4.0,
            Self::Land => 11.0,
        }
    }

    /// Its name for people.
    pub fn name(self) -> &'static str {
        match self {
            Self::Mission => "Mission",
            Self::Hold => "Hold",
            Self::Land => "Land",
            Self::Position => "Position",
        }
    }
}

/// What the vehicle does when manual control is lost in Position mode (`NAV_RCL_ACT`), after
/// holding for the failsafe delay (`COM_FAIL_ACT_T`) as PX4 does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ManualLossAction {
    /// Hold where it is (1): until the sticks come back or the battery's failsafe lands it.
    Hold,
    /// Land where it is (3; PX4's default is Return, which this vehicle has not).
    Land,
    /// Stop the rotors (5): flight termination.
    Terminate,
}

impl ManualLossAction {
    /// The action of a `NAV_RCL_ACT` value; `None` for values this vehicle does not take.
    pub fn from_param(value: f32) -> Option<Self> {
        [(1.0, Self::Hold), (3.0, Self::Land), (5.0, Self::Terminate)]
            .iter()
            .find(|(v, _)| *v == value)
            .map(|(_, action)| *action)
    }
}

/// Manual control's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManualConfig {
    /// Where manual input may come from (`COM_RC_IN_MODE`).
    pub input_mode: InputMode,
    /// Time without a valid sample after which a source is lost, s (`COM_RC_LOSS_T`).
    pub loss_time: f32,
    /// Time the kill switch keeps the vehicle armed with its rotors off, s (`COM_KILL_DISARM`).
    pub kill_disarm_time: f32,
    /// What Position mode does when manual control is lost (`NAV_RCL_ACT`).
    pub loss_action: ManualLossAction,
    /// Time held before the loss's action, s (`COM_FAIL_ACT_T`).
    pub failsafe_delay: f32,
    /// The mode of each of the mode switch's six slots (`COM_FLTMODE1..6`).
    pub flight_modes: [Option<PilotMode>; 6],
    /// Position mode's speeds (`MPC_VEL_MANUAL`, `MPC_Z_VEL_MAX_UP`, ...).
    pub limits: ManualLimits,
}

impl ManualConfig {
    /// PX4's defaults (`NAV_RCL_ACT` Land where PX4's is Return; no mode-switch slot assigned).
    pub const DEFAULT: Self = Self {
        input_mode: InputMode::KeepFirst,
        loss_time: 0.5,
        kill_disarm_time: 5.0,
        loss_action: ManualLossAction::Land,
        failsafe_delay: 5.0,
        flight_modes: [None; 6],
        limits: ManualLimits::DEFAULT,
    };
}

impl Default for ManualConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn px4s_mode_and_action_numbers_map_and_others_do_not() {
        assert_eq!(PilotMode::from_param(2.0), Some(PilotMode::Position));
        assert_eq!(PilotMode::from_param(11.0), Some(PilotMode::Land));
        assert_eq!(PilotMode::from_param(-1.0), None);
        assert_eq!(PilotMode::from_param(0.0), None);
        assert_eq!(
            ManualLossAction::from_param(3.0),
            Some(ManualLossAction::Land)
        );
        assert_eq!(ManualLossAction::from_param(2.0), None);
        assert_eq!(ManualLossAction::from_param(f32::NAN), None);
    }
}
