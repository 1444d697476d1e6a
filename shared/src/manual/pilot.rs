//! What a person at the sticks did since the previous control tick (docs/manual-control.md):
//! the manual control in force ([`super::source`]), whether it was lost or came back this
//! tick, the mode switch moved to a slot with a mode, and the kill switch's action
//! ([`super::kill`]). The mission decides what each means in the phase it is in.
//!
//! The kill switch is read from the RC receiver whichever source steers: a safety pilot's
//! switch works while a joystick flies. Its position is kept through a loss of the receiver
//! (a vehicle killed stays killed, then disarms) until a valid frame says otherwise.

use super::ManualSamples;
use super::config::{ManualConfig, PilotMode};
use super::kill::{KillAction, KillSwitch};
use super::source::{Manual, ManualSelector, Source};

/// Seconds to microseconds, never negative (NaN: 0).
const fn micros(seconds: f32) -> u64 {
    if seconds > 0.0 {
        (seconds * 1e6) as u64
    } else {
        0
    }
}

/// What this tick brought.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PilotTick {
    /// The manual control in force.
    pub manual: Manual,
    /// Lost this tick (valid until now).
    pub lost: bool,
    /// Back this tick (lost until now).
    pub regained: bool,
    /// The mode switch moved this tick to a slot with this mode.
    pub switched_to: Option<PilotMode>,
    /// What the kill switch asks of this tick.
    pub kill: KillAction,
    /// The kill switch was switched on (`Some(true)`) or off this tick.
    pub kill_switched: Option<bool>,
}

/// The person's side of the vehicle over time.
#[derive(Clone, Copy, Debug)]
pub struct Pilot {
    selector: ManualSelector,
    kill: KillSwitch,
    kill_on: bool,
    /// The mode switch's slot last seen.
    slot: Option<u8>,
    /// Manual control was valid at the last tick.
    valid: bool,
    /// The manual control in force at the last tick.
    last: Manual,
}

impl Pilot {
    /// No sample yet, for `config`.
    pub const fn new(config: &ManualConfig) -> Self {
        Self {
            selector: ManualSelector::new(config.input_mode, micros(config.loss_time)),
            kill: KillSwitch::new(micros(config.kill_disarm_time)),
            kill_on: false,
            slot: None,
            valid: false,
            last: Manual::Never,
        }
    }

    /// New settings; the samples, the switches' positions and the kill switch's time kept.
    pub fn configure(&mut self, config: &ManualConfig) {
        self.selector
            .configure(config.input_mode, micros(config.loss_time));
        self.kill.configure(micros(config.kill_disarm_time));
    }

    /// No source has sent a valid sample since power-up and the kill switch is off: a tick
    /// without samples changes nothing.
    pub fn unheard(&self) -> bool {
        matches!(self.last, Manual::Never) && !self.kill_on && !self.kill.is_on()
    }

    /// The manual control in force at the last tick.
    pub fn current(&self) -> Manual {
        self.last
    }

    /// Whether the kill switch is on.
    pub fn kill_on(&self) -> bool {
        self.kill_on
    }

    /// Whether an RC receiver sent a valid frame within the loss time at `now_us`.
    pub fn rc_valid(&self, now_us: u64) -> bool {
        self.selector.fresh(Source::Rc, now_us)
    }

    /// This tick's samples at `now_us`.
    pub fn tick(
        &mut self,
        samples: &ManualSamples,
        now_us: u64,
        config: &ManualConfig,
    ) -> PilotTick {
        if let Some(rc) = samples.rc {
            self.selector.receive(Source::Rc, rc, now_us);
            if rc.sticks.is_valid() && config.input_mode != super::source::InputMode::Disabled {
                self.kill_on = rc.kill;
            }
        }
        if let Some(joystick) = samples.joystick {
            self.selector.receive(Source::Mavlink, joystick, now_us);
        }
        let manual = self.selector.current(now_us);
        // Back only after a loss: the first valid sample is no news.
        let was_lost = matches!(self.last, Manual::Lost(_));
        self.last = manual;
        let valid = matches!(manual, Manual::Valid(..));
        let (lost, regained) = (self.valid && !valid, was_lost && valid);
        self.valid = valid;
        let mut switched_to = None;
        if let Manual::Valid(_, input) = manual
            && let Some(slot) = input.mode_slot
        {
            if self.slot.is_some_and(|was| was != slot) {
                switched_to = config
                    .flight_modes
                    .get(usize::from(slot))
                    .copied()
                    .flatten();
            }
            self.slot = Some(slot);
        }
        let was_on = self.kill.is_on();
        let kill = self.kill.update(self.kill_on, now_us);
        let kill_switched = (was_on != self.kill_on).then_some(self.kill_on);
        PilotTick {
            manual,
            lost,
            regained,
            switched_to,
            kill,
            kill_switched,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::manual::{ManualInput, Sticks};

    fn rc(kill: bool, slot: Option<u8>) -> ManualSamples {
        ManualSamples {
            rc: Some(ManualInput {
                sticks: Sticks::CENTRED,
                kill,
                mode_slot: slot,
            }),
            joystick: None,
        }
    }

    fn config() -> ManualConfig {
        let mut c = ManualConfig::DEFAULT;
        c.flight_modes[0] = Some(PilotMode::Mission);
        c.flight_modes[2] = Some(PilotMode::Position);
        c
    }

    #[test]
    fn the_mode_switch_acts_when_it_moves_not_at_the_first_frame() {
        let c = config();
        let mut p = Pilot::new(&c);
        assert_eq!(p.tick(&rc(false, Some(2)), 0, &c).switched_to, None);
        assert_eq!(p.tick(&rc(false, Some(2)), 10_000, &c).switched_to, None);
        let t = p.tick(&rc(false, Some(0)), 20_000, &c);
        assert_eq!(t.switched_to, Some(PilotMode::Mission));
        assert_eq!(
            p.tick(&rc(false, Some(2)), 30_000, &c).switched_to,
            Some(PilotMode::Position)
        );
        // A slot with no mode assigned: nothing.
        assert_eq!(p.tick(&rc(false, Some(4)), 40_000, &c).switched_to, None);
    }

    #[test]
    fn loss_and_return_are_said_once_each() {
        let c = config();
        let mut p = Pilot::new(&c);
        assert!(
            !p.tick(&rc(false, None), 0, &c).regained,
            "the first is no news"
        );
        let none = ManualSamples::NONE;
        assert!(!p.tick(&none, 400_000, &c).lost);
        assert!(p.tick(&none, 600_000, &c).lost);
        assert!(!p.tick(&none, 700_000, &c).lost);
        assert!(p.tick(&rc(false, None), 800_000, &c).regained);
    }

    #[test]
    fn the_kill_switch_stops_the_rotors_then_disarms_and_survives_a_lost_receiver() {
        let c = config();
        let mut p = Pilot::new(&c);
        p.tick(&rc(false, None), 0, &c);
        let on = p.tick(&rc(true, None), 10_000, &c);
        assert_eq!(
            (on.kill, on.kill_switched),
            (KillAction::RotorsOff, Some(true))
        );
        // The receiver goes silent: the switch stays on, and the vehicle disarms on time.
        let none = ManualSamples::NONE;
        assert_eq!(p.tick(&none, 3_000_000, &c).kill, KillAction::RotorsOff);
        assert_eq!(p.tick(&none, 5_010_000, &c).kill, KillAction::Disarm);
        let off = p.tick(&rc(false, None), 6_000_000, &c);
        assert_eq!(
            (off.kill, off.kill_switched),
            (KillAction::None, Some(false))
        );
    }
}
