//! What the mission watches beyond its sensors: the ground link and the battery.
//!
//! - The ground link: a ground station sends `HEARTBEAT` once a second. [`LinkMonitor`] calls
//!   the link lost when none has come for [`SupervisionConfig::gcs_timeout`] seconds (PX4's
//!   `COM_DL_LOSS_T`), and regained at the next one. Without a link the mission does not start;
//!   lost after the start on the ground it stops there; lost in flight it does what
//!   [`GcsLossAction`] says: fly on to the target and land, or hold where it is for
//!   [`SupervisionConfig::gcs_hold_time`] and then land in place (a link back during the hold
//!   resumes the plan).
//! - The battery: [`BatteryMonitor`] low-passes the pack voltage (time constant
//!   [`BATTERY_FILTER_S`]) and grades it against two thresholds: below
//!   [`SupervisionConfig::battery_low`] a warning (and no start), below
//!   [`SupervisionConfig::battery_critical`] a landing in place. The grade only rises (a pack
//!   that recovers under a lighter load is not trusted again), as PX4's battery warnings do.
//!
//! Both take what one tick brings ([`Supervision`]) and are plain state machines; the mission
//! ([`super::machine`]) decides what each change means in its phase and says it as a
//! [`Notice`].

use crate::manual::{ManualLossAction, PilotMode};
use crate::mission::interface::CommandRefusal;
use crate::numbers::Fixed;

/// What one tick brings for the supervision: whether a ground station's heartbeat arrived
/// since the previous tick, and the pack voltage if one is measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Supervision {
    /// A ground station's `HEARTBEAT` arrived since the previous tick.
    pub gcs_heartbeat: bool,
    /// The battery pack's voltage, V (`None`: no measurement on this vehicle or this tick).
    pub battery_volts: Option<f32>,
}

impl Supervision {
    /// No heartbeat, no battery reading.
    pub const NONE: Self = Self {
        gcs_heartbeat: false,
        battery_volts: None,
    };

    /// A heartbeat every tick and no battery reading: a bench or test set-up whose link is
    /// always up.
    pub const LINKED: Self = Self {
        gcs_heartbeat: true,
        battery_volts: None,
    };
}

/// What the vehicle does when the ground link is lost in flight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GcsLossAction {
    /// Nothing: the link is not watched (no start refused, nothing done in flight).
    Off = 0,
    /// Fly on to the target and land there, as planned.
    Continue = 1,
    /// Hold where the vehicle is for the hold time, then land in place; a link that comes back
    /// during the hold resumes the plan.
    HoldThenLand = 2,
}

impl GcsLossAction {
    /// The action of a parameter value (0, 1, 2; anything else is [`Self::HoldThenLand`]).
    pub fn from_value(v: f32) -> Self {
        if v < 0.5 {
            Self::Off
        } else if v < 1.5 {
            Self::Continue
        } else {
            Self::HoldThenLand
        }
    }
}

/// What the vehicle does when it leaves its geofence (PX4's `GF_ACTION` numbers; PX4's 3,
/// return, and 4, terminate, are not offered: this vehicle has no return path, and stopping
/// the rotors drops the payload).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum FenceAction {
    /// Nothing: the fence is not watched.
    Off = 0,
    /// A warning (`STATUSTEXT`); the flight goes on.
    Warning = 1,
    /// Hold where the vehicle is until the operator lands it or resumes the plan.
    Hold = 2,
    /// Land where the vehicle is.
    Land = 5,
}

impl FenceAction {
    /// The action of a parameter value (0, 1, 2, 5; anything else is [`Self::Land`]).
    pub fn from_value(v: f32) -> Self {
        if v < 0.5 {
            Self::Off
        } else if v < 1.5 {
            Self::Warning
        } else if v < 2.5 {
            Self::Hold
        } else {
            Self::Land
        }
    }
}

/// The supervision's tuning.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupervisionConfig {
    /// What to do when the ground link is lost.
    pub gcs_action: GcsLossAction,
    /// Time without a ground station's heartbeat after which the link counts as lost, s.
    pub gcs_timeout: f32,
    /// With [`GcsLossAction::HoldThenLand`]: how long to hold before landing in place, s.
    pub gcs_hold_time: f32,
    /// Pack voltage below which the battery is low: a warning, and no start, V (0: off).
    pub battery_low: f32,
    /// Pack voltage below which the battery is critical: a landing in place, V (0: off).
    pub battery_critical: f32,
    /// What to do outside the geofence.
    pub fence_action: FenceAction,
    /// The geofence's radius about the take-off point, m (0: no horizontal limit).
    pub fence_horizontal: f32,
    /// The geofence's height above the take-off point, m (0: no vertical limit).
    pub fence_vertical: f32,
    /// The pack the thrust map was measured with, for the rotors' voltage compensation.
    pub pack: crate::control::voltage_compensation::PackModel,
}

impl SupervisionConfig {
    /// Link lost after 5 s without a heartbeat (PX4's `COM_DL_LOSS_T` is 10 s; these flights
    /// last about 20 s), then hold 10 s and land in place; a 4S lithium-polymer pack (16.8 V
    /// full, 14.8 V nominal): low below 14.0 V (3.5 V a cell), critical below 13.2 V (3.3 V a
    /// cell).
    pub const DEFAULT: Self = Self {
        gcs_action: GcsLossAction::HoldThenLand,
        gcs_timeout: 5.0,
        gcs_hold_time: 10.0,
        battery_low: 14.0,
        battery_critical: 13.2,
        fence_action: FenceAction::Land,
        fence_horizontal: 20.0,
        fence_vertical: 10.0,
        pack: crate::control::voltage_compensation::PackModel::DEFAULT,
    };
}

impl Default for SupervisionConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A change of the ground link.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkChange {
    /// No heartbeat for the timeout.
    Lost,
    /// A heartbeat after the link was lost.
    Regained,
}

/// Watches the ground station's heartbeats.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkMonitor {
    /// Time of the last heartbeat, us (`None`: never one).
    last_us: Option<u64>,
    /// The link counts as up.
    up: bool,
}

impl Default for LinkMonitor {
    fn default() -> Self {
        Self::new()
    }
}

impl LinkMonitor {
    /// No heartbeat yet: the link is down (but was never lost).
    pub const fn new() -> Self {
        Self {
            last_us: None,
            up: false,
        }
    }

    /// Whether the link is up: a heartbeat within the timeout.
    pub fn up(&self) -> bool {
        self.up
    }

    /// Seconds since the last heartbeat at `time_us` (`None`: never one).
    pub fn silence(&self, time_us: u64) -> Option<f32> {
        self.last_us
            .map(|t| time_us.saturating_sub(t) as f32 * 1e-6)
    }

    /// One tick at `time_us`: `heartbeat` if one arrived; lost after `timeout` seconds of
    /// silence. The change this tick made, if any (the first heartbeat ever brings the link
    /// up without a change: it was never lost).
    pub fn update(&mut self, time_us: u64, heartbeat: bool, timeout: f32) -> Option<LinkChange> {
        if heartbeat {
            let was_lost = self.last_us.is_some() && !self.up;
            self.last_us = Some(time_us);
            self.up = true;
            return was_lost.then_some(LinkChange::Regained);
        }
        let silent = self.silence(time_us)?;
        if self.up && silent > timeout {
            self.up = false;
            return Some(LinkChange::Lost);
        }
        None
    }
}

/// Time constant of the battery voltage's low-pass filter, s: long enough to ride over the
/// sag of a gust's thrust burst and an ADC's noise, short enough to see a failing pack within
/// about two seconds.
pub const BATTERY_FILTER_S: f32 = 1.0;

/// How the battery stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum BatteryLevel {
    /// Above the low threshold (or not measured).
    Ok,
    /// Below the low threshold: warn; no start.
    Low,
    /// Below the critical threshold: land now.
    Critical,
}

/// Watches the pack voltage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatteryMonitor {
    /// The filtered voltage, V (`None`: no reading yet).
    filtered: Option<f32>,
    /// The grade (only rises).
    level: BatteryLevel,
}

impl Default for BatteryMonitor {
    fn default() -> Self {
        Self::new()
    }
}

impl BatteryMonitor {
    /// No reading yet.
    pub const fn new() -> Self {
        Self {
            filtered: None,
            level: BatteryLevel::Ok,
        }
    }

    /// The filtered pack voltage, V, once one was read.
    pub fn volts(&self) -> Option<f32> {
        self.filtered
    }

    /// How the battery stands.
    pub fn level(&self) -> BatteryLevel {
        self.level
    }

    /// Grades the battery afresh from the filtered voltage now (the mission starts: a pack
    /// changed since a low reading is not held against it).
    pub fn regrade(&mut self, config: &SupervisionConfig) {
        self.level = BatteryLevel::Ok;
        if let Some(v) = self.filtered {
            self.grade(v, config);
        }
    }

    /// Raises the grade to what `filtered` is; the new grade if it rose.
    fn grade(&mut self, filtered: f32, config: &SupervisionConfig) -> Option<BatteryLevel> {
        let below = |threshold: f32| threshold > 0.0 && filtered < threshold;
        let level = if below(config.battery_critical) {
            BatteryLevel::Critical
        } else if below(config.battery_low) {
            BatteryLevel::Low
        } else {
            BatteryLevel::Ok
        };
        if level > self.level {
            self.level = level;
            Some(level)
        } else {
            None
        }
    }

    /// One tick `dt` seconds after the last with this tick's reading, if any (a reading that
    /// is not a finite, non-negative number is ignored); thresholds of `config` (0: off). The
    /// new grade if it rose this tick.
    pub fn update(
        &mut self,
        volts: Option<f32>,
        dt: f32,
        config: &SupervisionConfig,
    ) -> Option<BatteryLevel> {
        let reading = volts.filter(|v| v.is_finite() && *v >= 0.0)?;
        let filtered = match self.filtered {
            None => reading,
            Some(f) => {
                let a = crate::math::clamp(dt / (BATTERY_FILTER_S + dt), 0.0, 1.0);
                f + a * (reading - f)
            }
        };
        self.filtered = Some(filtered);
        self.grade(filtered, config)
    }
}

/// Something the supervision has to tell people (the firmware sends it as `STATUSTEXT`, the
/// simulator prints it). Changes of phase carry their own reason; these are the rest. (The
/// rotors found stopped are said here too: every one of them, where the landing's reason
/// names the first.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Notice {
    /// The ground link is lost; what the vehicle does about it.
    LinkLost {
        /// Seconds without a heartbeat.
        silent: f32,
        /// What the vehicle does now.
        response: LinkResponse,
    },
    /// The ground link is back.
    LinkRegained {
        /// The vehicle was holding and flies on with its plan.
        resumed: bool,
    },
    /// The battery is low (the flight goes on).
    BatteryLow {
        /// The filtered pack voltage, V.
        volts: f32,
        /// The low threshold, V.
        threshold: f32,
    },
    /// The battery is critical outside a flight (in flight the landing's reason says it).
    BatteryCritical {
        /// The filtered pack voltage, V.
        volts: f32,
        /// The critical threshold, V.
        threshold: f32,
    },
    /// Rotors found stopped in flight this tick (docs/failures.md#rotors-that-stop-in-flight).
    RotorsOut {
        /// The rotors found now, bit `i` for robot `i`.
        newly: u16,
        /// Rotors found before, flown without already.
        earlier: u16,
        /// Rotors left turning.
        left: u8,
        /// Whether the rotors left hold a level hover; if not, the payload is kept level and
        /// comes down faster than planned.
        holdable: bool,
    },
    /// Manual control (RC or joystick) is lost (docs/manual-control.md#manual-control-lost).
    ManualLost {
        /// What the vehicle does now.
        response: ManualLossResponse,
    },
    /// Manual control is back.
    ManualRegained {
        /// The vehicle was holding for the loss and the sticks steer it again.
        resumed: bool,
    },
    /// The kill switch was switched on (rotors off) or off again.
    KillSwitch {
        /// On.
        on: bool,
    },
    /// The vehicle left its geofence (docs/failures.md#failures).
    FenceBreached {
        /// Its distance from the take-off point across the ground, m.
        distance: f32,
        /// Its height above the take-off point, m.
        height: f32,
        /// What it does about it.
        action: FenceAction,
    },
    /// A lift waits for the payload to come to rest, or starts again
    /// (docs/models.md#lift-off-detector).
    LiftDelayed {
        /// The lifting group, as the phase's reason names it.
        group: usize,
        /// What the lift does about it.
        delay: crate::liftoff_detector::LiftDelay,
    },
    /// The mode switch asked for a mode the vehicle refused.
    SwitchRefused {
        /// The mode asked for.
        mode: PilotMode,
        /// Why not.
        why: CommandRefusal,
    },
}

/// What the vehicle does about lost manual control.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ManualLossResponse {
    /// Nothing: not flying on the sticks.
    Nothing,
    /// The mission goes on (PX4's `COM_RCL_EXCEPT` for missions).
    MissionGoesOn,
    /// Position mode: holds for this long, then the action.
    Hold(f32, ManualLossAction),
}

/// The robots of `mask` (from 1) as words: "rotor 3", "rotors 1 and 6", "rotors 1, 2 and 6".
fn rotors(f: &mut core::fmt::Formatter<'_>, mask: u16) -> core::fmt::Result {
    let count = mask.count_ones();
    write!(f, "{}", if count == 1 { "rotor" } else { "rotors" })?;
    for (k, robot) in (0..16u32).filter(|&i| mask & (1 << i) != 0).enumerate() {
        let joint = match k as u32 {
            0 => " ",
            k if k + 1 == count => " and ",
            _ => ", ",
        };
        write!(f, "{joint}{}", robot + 1)?;
    }
    Ok(())
}

/// What the vehicle does about a lost link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LinkResponse {
    /// Nothing to do (on the ground, not running; or already landing).
    Nothing,
    /// Flies on to the target and lands there.
    Continue,
    /// Holds where it is for this long, then lands in place, s.
    Hold(f32),
}

/// `volts` rounded down to hundredths: a voltage just below a threshold never reads as the
/// threshold itself (13.998 V below 14 V reads 13.99 V).
pub fn hundredths_down(volts: f32) -> f32 {
    crate::math::floor(volts * 100.0) / 100.0
}

impl core::fmt::Display for Notice {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::LinkLost { silent, response } => {
                write!(
                    f,
                    "ground link lost: no ground-station heartbeat for {} s",
                    Fixed(silent, 1)
                )?;
                match response {
                    LinkResponse::Nothing => Ok(()),
                    LinkResponse::Continue => write!(f, "; flying on to the target to land"),
                    LinkResponse::Hold(t) => {
                        write!(f, "; holding {} s, then landing in place", Fixed(t, 0))
                    }
                }
            }
            Self::LinkRegained { resumed: true } => {
                write!(f, "ground link regained; flying on with the plan")
            }
            Self::LinkRegained { resumed: false } => write!(f, "ground link regained"),
            Self::BatteryLow { volts, threshold } => write!(
                f,
                "battery low: {} V, below {} V (BAT_LOW_V)",
                Fixed(hundredths_down(volts), 2),
                Fixed(threshold, 2)
            ),
            Self::BatteryCritical { volts, threshold } => write!(
                f,
                "battery critical: {} V, below {} V (BAT_CRIT_V)",
                Fixed(hundredths_down(volts), 2),
                Fixed(threshold, 2)
            ),
            Self::ManualLost { response } => {
                write!(
                    f,
                    "manual control lost (no RC or joystick for COM_RC_LOSS_T)"
                )?;
                match response {
                    ManualLossResponse::Nothing => Ok(()),
                    ManualLossResponse::MissionGoesOn => write!(f, "; the mission goes on"),
                    ManualLossResponse::Hold(t, action) => {
                        let then = match action {
                            ManualLossAction::Hold => "holding until it is back",
                            ManualLossAction::Land => "landing in place",
                            ManualLossAction::Terminate => "stopping the rotors (NAV_RCL_ACT)",
                        };
                        write!(f, "; holding {} s, then {then}", Fixed(t, 0))
                    }
                }
            }
            Self::ManualRegained { resumed: true } => {
                write!(f, "manual control regained; the sticks steer again")
            }
            Self::ManualRegained { resumed: false } => write!(f, "manual control regained"),
            Self::KillSwitch { on: true } => write!(f, "kill switch on: rotors off"),
            Self::KillSwitch { on: false } => write!(f, "kill switch off"),
            Self::SwitchRefused { mode, why } => {
                write!(f, "mode switch: {} refused: {why}", mode.name())
            }
            Self::FenceBreached {
                distance,
                height,
                action,
            } => {
                write!(
                    f,
                    "geofence breached: {} m from the take-off point, {} m above it (GF_MAX_HOR_DIST, GF_MAX_VER_DIST)",
                    Fixed(distance, 1),
                    Fixed(height, 1)
                )?;
                match action {
                    FenceAction::Off | FenceAction::Warning => Ok(()),
                    FenceAction::Hold => write!(f, "; holding where it is"),
                    FenceAction::Land => write!(f, "; landing where it is"),
                }
            }
            Self::LiftDelayed { group, delay } => match delay {
                crate::liftoff_detector::LiftDelay::Waiting { moved } => write!(
                    f,
                    "lift with pair {group} waits: the payload moved {} deg in the last settle window",
                    Fixed(moved.to_degrees(), 2)
                ),
                crate::liftoff_detector::LiftDelay::Redone { count, after } => write!(
                    f,
                    "lift with pair {group} started again ({count}): the payload tipped {} s into the ramp, before the ramp could tip it",
                    Fixed(after, 2)
                ),
            },
            Self::RotorsOut {
                newly,
                earlier,
                left,
                holdable,
            } => {
                rotors(f, newly)?;
                write!(f, " stopped in flight")?;
                if earlier != 0 {
                    write!(f, " (after ")?;
                    rotors(f, earlier)?;
                    write!(f, ")")?;
                }
                if holdable {
                    write!(
                        f,
                        ": the {left} left hold a level hover; landing where it is"
                    )
                } else {
                    write!(
                        f,
                        ": the {left} left cannot hold a level hover; keeping the payload level, coming down faster than planned"
                    )
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn the_rotors_found_are_named_with_what_the_rest_can_do() {
        let said = |newly, earlier, left, holdable| {
            Notice::RotorsOut {
                newly,
                earlier,
                left,
                holdable,
            }
            .to_string()
        };
        assert_eq!(
            said(1 << 2, 0, 7, true),
            "rotor 3 stopped in flight: the 7 left hold a level hover; landing where it is"
        );
        assert_eq!(
            said((1 << 0) | (1 << 5), 0, 6, true),
            "rotors 1 and 6 stopped in flight: the 6 left hold a level hover; landing where it is"
        );
        let worse = said(1 << 7, (1 << 0) | (1 << 1), 5, false);
        assert!(
            worse.starts_with("rotor 8 stopped in flight (after rotors 1 and 2): the 5 left cannot hold a level hover"),
            "{worse}"
        );
        assert!(said(0b111, 0, 5, true).starts_with("rotors 1, 2 and 3 stopped"));
    }

    const S: u64 = 1_000_000;

    #[test]
    fn the_link_is_lost_after_the_timeout_and_regained_at_the_next_heartbeat() {
        let mut link = LinkMonitor::new();
        // Never a heartbeat: down, but never lost.
        assert_eq!(link.update(10 * S, false, 5.0), None);
        assert!(!link.up());
        assert_eq!(link.update(11 * S, true, 5.0), None);
        assert!(link.up());
        // Heartbeats at 1 Hz keep it up; silence for the timeout (not less) loses it.
        assert_eq!(link.update(12 * S, true, 5.0), None);
        assert_eq!(link.update(17 * S, false, 5.0), None);
        assert!(link.up());
        assert_eq!(link.update(17 * S + 1, false, 5.0), Some(LinkChange::Lost));
        assert!(!link.up());
        assert_eq!(link.update(18 * S, false, 5.0), None);
        assert_eq!(link.silence(18 * S), Some(6.0));
        assert_eq!(link.update(19 * S, true, 5.0), Some(LinkChange::Regained));
        assert!(link.up());
    }

    #[test]
    fn the_battery_is_filtered_and_its_grade_only_rises() {
        let config = SupervisionConfig::DEFAULT;
        let mut battery = BatteryMonitor::new();
        let dt = 0.0025;
        // No reading, or a meaningless one: nothing known, nothing said.
        assert_eq!(battery.update(None, dt, &config), None);
        assert_eq!(battery.update(Some(f32::NAN), dt, &config), None);
        assert_eq!(battery.update(Some(-1.0), dt, &config), None);
        assert_eq!(battery.volts(), None);
        assert_eq!(battery.update(Some(16.0), dt, &config), None);
        assert_eq!(battery.volts(), Some(16.0));
        // A one-tick dip to 12 V is filtered away.
        assert_eq!(battery.update(Some(12.0), dt, &config), None);
        assert_eq!(battery.level(), BatteryLevel::Ok);
        // A drop to 12 V: low, then critical, each once, within the filter's time.
        let mut changes = std::vec::Vec::new();
        for k in 1..=1200 {
            if let Some(level) = battery.update(Some(12.0), dt, &config) {
                changes.push((k, level));
            }
        }
        assert_eq!(changes.len(), 2, "{changes:?}");
        assert_eq!(changes[0].1, BatteryLevel::Low);
        assert_eq!(changes[1].1, BatteryLevel::Critical);
        // 16 V to 12 V: below 13.2 V after ln(4 / 1.2) = 1.2 time constants.
        let seconds = changes[1].0 as f32 * dt;
        assert!((seconds - 1.2).abs() < 0.05, "critical after {seconds} s");
        // A recovered pack is not trusted again.
        for _ in 0..4000 {
            assert_eq!(battery.update(Some(16.0), dt, &config), None);
        }
        assert_eq!(battery.level(), BatteryLevel::Critical);
    }

    #[test]
    fn thresholds_of_zero_are_off() {
        let config = SupervisionConfig {
            battery_low: 0.0,
            battery_critical: 0.0,
            ..SupervisionConfig::DEFAULT
        };
        let mut battery = BatteryMonitor::new();
        for _ in 0..100 {
            assert_eq!(battery.update(Some(0.0), 0.0025, &config), None);
        }
        assert_eq!(battery.level(), BatteryLevel::Ok);
    }

    #[test]
    fn notices_say_what_happened_and_what_the_vehicle_does() {
        let lost = Notice::LinkLost {
            silent: 5.0,
            response: LinkResponse::Hold(10.0),
        };
        assert_eq!(
            lost.to_string(),
            "ground link lost: no ground-station heartbeat for 5.0 s; holding 10 s, then landing in place"
        );
        let low = Notice::BatteryLow {
            volts: 13.998,
            threshold: 14.0,
        };
        assert_eq!(
            low.to_string(),
            "battery low: 13.99 V, below 14.00 V (BAT_LOW_V)"
        );
        assert_eq!(GcsLossAction::from_value(0.0), GcsLossAction::Off);
        assert_eq!(GcsLossAction::from_value(1.0), GcsLossAction::Continue);
        assert_eq!(GcsLossAction::from_value(2.0), GcsLossAction::HoldThenLand);
    }
}
