//! The kill switch (PX4's `RC_MAP_KILL_SW` and `COM_KILL_DISARM`): the rotors at zero from the
//! control step that sees the switch on, whatever the mode; the vehicle stays armed for the
//! disarm delay, so a switch flipped by mistake and flipped back within it gives the rotors
//! back; after the delay it disarms.

/// What the kill switch asks of this control step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KillAction {
    /// Nothing: the rotors as the mission commands them.
    None,
    /// Every rotor command zero; still armed.
    RotorsOff,
    /// Every rotor command zero, and disarm now (the delay has passed).
    Disarm,
}

/// The kill switch's state.
#[derive(Clone, Copy, Debug)]
pub struct KillSwitch {
    disarm_after_us: u64,
    /// When the switch went on (while it stays on), us.
    on_since: Option<u64>,
}

impl KillSwitch {
    /// A kill switch that disarms after `disarm_after_us` on.
    pub const fn new(disarm_after_us: u64) -> Self {
        Self {
            disarm_after_us,
            on_since: None,
        }
    }

    /// A new disarm delay; the switch's time on kept.
    pub fn configure(&mut self, disarm_after_us: u64) {
        self.disarm_after_us = disarm_after_us;
    }

    /// Whether the switch was on at the last update.
    pub fn is_on(&self) -> bool {
        self.on_since.is_some()
    }

    /// The switch's position at `now_us`, and what it asks.
    pub fn update(&mut self, on: bool, now_us: u64) -> KillAction {
        if !on {
            self.on_since = None;
            return KillAction::None;
        }
        let since = *self.on_since.get_or_insert(now_us);
        if now_us.saturating_sub(since) >= self.disarm_after_us {
            KillAction::Disarm
        } else {
            KillAction::RotorsOff
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rotors_stop_at_once_and_the_vehicle_disarms_after_the_delay() {
        let mut k = KillSwitch::new(5_000_000);
        assert_eq!(k.update(false, 0), KillAction::None);
        assert_eq!(k.update(true, 1_000), KillAction::RotorsOff);
        assert_eq!(k.update(true, 5_000_999), KillAction::RotorsOff);
        assert_eq!(k.update(true, 5_001_000), KillAction::Disarm);
    }

    #[test]
    fn flipped_back_within_the_delay_the_rotors_come_back_and_the_delay_starts_anew() {
        let mut k = KillSwitch::new(5_000_000);
        assert_eq!(k.update(true, 0), KillAction::RotorsOff);
        assert_eq!(k.update(false, 2_000_000), KillAction::None);
        assert_eq!(k.update(true, 3_000_000), KillAction::RotorsOff);
        assert_eq!(k.update(true, 7_000_000), KillAction::RotorsOff);
        assert_eq!(k.update(true, 8_000_000), KillAction::Disarm);
    }
}
