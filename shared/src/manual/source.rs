//! Which manual control source is in force, and when it is lost (PX4's `COM_RC_IN_MODE` and
//! `COM_RC_LOSS_T`): an RC receiver, a ground station's joystick (`MANUAL_CONTROL`), either
//! with the first valid one kept (PX4's default), or none. A source is lost when its last
//! valid sample is older than the loss time; a receiver in failsafe sends no valid sample.

use super::ManualInput;

/// Where manual input may come from (`COM_RC_IN_MODE`'s values).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputMode {
    /// An RC receiver only (0).
    RcOnly,
    /// A ground station's joystick only (1).
    MavlinkOnly,
    /// Either; the RC receiver in force whenever valid, the joystick while it is not (2).
    RcWithFallback,
    /// Either; the first valid one is kept (3, PX4's default).
    KeepFirst,
    /// No manual control (4).
    Disabled,
}

impl InputMode {
    /// The mode of a `COM_RC_IN_MODE` value; `None` outside 0..=4.
    pub fn from_param(value: f32) -> Option<Self> {
        const MODES: [InputMode; 5] = [
            InputMode::RcOnly,
            InputMode::MavlinkOnly,
            InputMode::RcWithFallback,
            InputMode::KeepFirst,
            InputMode::Disabled,
        ];
        MODES
            .iter()
            .enumerate()
            .find(|(i, _)| *i as f32 == value)
            .map(|(_, mode)| *mode)
    }

    /// Whether `source` may be used at all.
    pub fn allows(self, source: Source) -> bool {
        match self {
            Self::RcOnly => source == Source::Rc,
            Self::MavlinkOnly => source == Source::Mavlink,
            Self::RcWithFallback | Self::KeepFirst => true,
            Self::Disabled => false,
        }
    }
}

/// A manual control source.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// An RC receiver (CRSF or SBUS).
    Rc,
    /// A ground station's `MANUAL_CONTROL`.
    Mavlink,
}

/// The manual control in force now.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Manual {
    /// No source has sent a valid sample yet (or manual control is disabled).
    Never,
    /// The source in force and its newest sample.
    Valid(Source, ManualInput),
    /// The source in force sent nothing valid for longer than the loss time.
    Lost(Source),
}

/// One source's newest valid sample.
#[derive(Clone, Copy, Debug, Default)]
struct Last {
    input: ManualInput,
    time_us: Option<u64>,
}

impl Last {
    const NONE: Self = Self {
        input: ManualInput::NONE,
        time_us: None,
    };

    fn fresh(&self, now_us: u64, loss_us: u64) -> bool {
        self.time_us
            .is_some_and(|t| now_us.saturating_sub(t) <= loss_us)
    }
}

/// The choice of source over time.
#[derive(Clone, Copy, Debug)]
pub struct ManualSelector {
    mode: InputMode,
    loss_us: u64,
    rc: Last,
    mavlink: Last,
    /// The source kept ([`InputMode::KeepFirst`]) or last in force.
    chosen: Option<Source>,
}

impl ManualSelector {
    /// A selector for `mode`, a source lost after `loss_us` without a valid sample.
    pub const fn new(mode: InputMode, loss_us: u64) -> Self {
        Self {
            mode,
            loss_us,
            rc: Last::NONE,
            mavlink: Last::NONE,
            chosen: None,
        }
    }

    /// New settings; the samples and the source kept (or dropped, if the mode no longer allows
    /// it).
    pub fn configure(&mut self, mode: InputMode, loss_us: u64) {
        self.mode = mode;
        self.loss_us = loss_us;
        if self.chosen.is_some_and(|s| !mode.allows(s)) {
            self.chosen = None;
        }
    }

    /// Whether `source` sent a valid sample within the loss time at `now_us`.
    pub fn fresh(&self, source: Source, now_us: u64) -> bool {
        let last = match source {
            Source::Rc => &self.rc,
            Source::Mavlink => &self.mavlink,
        };
        self.mode.allows(source) && last.fresh(now_us, self.loss_us)
    }

    /// A sample from `source` at `now_us`; one whose sticks are out of range counts as none.
    pub fn receive(&mut self, source: Source, input: ManualInput, now_us: u64) {
        if !self.mode.allows(source) || !input.sticks.is_valid() {
            return;
        }
        let last = match source {
            Source::Rc => &mut self.rc,
            Source::Mavlink => &mut self.mavlink,
        };
        *last = Last {
            input,
            time_us: Some(now_us),
        };
        if self.chosen.is_none() {
            self.chosen = Some(source);
        }
    }

    /// The manual control in force at `now_us`.
    pub fn current(&mut self, now_us: u64) -> Manual {
        let (loss, rc, mav) = (self.loss_us, self.rc, self.mavlink);
        let fresh = |s: Source| match s {
            Source::Rc => rc.fresh(now_us, loss),
            Source::Mavlink => mav.fresh(now_us, loss),
        };
        if self.mode == InputMode::RcWithFallback {
            // The receiver whenever it is valid, else the joystick.
            if fresh(Source::Rc) {
                self.chosen = Some(Source::Rc);
            } else if fresh(Source::Mavlink) {
                self.chosen = Some(Source::Mavlink);
            }
        }
        let Some(source) = self.chosen else {
            return Manual::Never;
        };
        if !fresh(source) {
            return Manual::Lost(source);
        }
        let input = match source {
            Source::Rc => rc.input,
            Source::Mavlink => mav.input,
        };
        Manual::Valid(source, input)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::manual::Sticks;

    const LOSS: u64 = 500_000;

    fn input(throttle: f32) -> ManualInput {
        ManualInput {
            sticks: Sticks {
                throttle,
                ..Sticks::CENTRED
            },
            ..ManualInput::default()
        }
    }

    #[test]
    fn the_first_valid_source_is_kept_and_lost_after_the_loss_time() {
        let mut s = ManualSelector::new(InputMode::KeepFirst, LOSS);
        assert_eq!(s.current(0), Manual::Never);
        s.receive(Source::Mavlink, input(0.2), 1_000);
        s.receive(Source::Rc, input(0.9), 2_000);
        assert_eq!(s.current(3_000), Manual::Valid(Source::Mavlink, input(0.2)));
        assert_eq!(
            s.current(1_000 + LOSS),
            Manual::Valid(Source::Mavlink, input(0.2))
        );
        assert_eq!(s.current(1_001 + LOSS), Manual::Lost(Source::Mavlink));
    }

    #[test]
    fn rc_with_fallback_takes_the_joystick_only_while_the_receiver_is_silent() {
        let mut s = ManualSelector::new(InputMode::RcWithFallback, LOSS);
        s.receive(Source::Mavlink, input(0.2), 0);
        s.receive(Source::Rc, input(0.9), 0);
        assert_eq!(s.current(10), Manual::Valid(Source::Rc, input(0.9)));
        s.receive(Source::Mavlink, input(0.3), 600_000);
        assert_eq!(
            s.current(600_010),
            Manual::Valid(Source::Mavlink, input(0.3))
        );
        s.receive(Source::Rc, input(0.8), 700_000);
        assert_eq!(s.current(700_010), Manual::Valid(Source::Rc, input(0.8)));
    }

    #[test]
    fn a_source_the_mode_excludes_and_bad_samples_are_ignored() {
        let mut s = ManualSelector::new(InputMode::RcOnly, LOSS);
        s.receive(Source::Mavlink, input(0.2), 0);
        assert_eq!(s.current(1), Manual::Never);
        s.receive(Source::Rc, input(f32::NAN), 0);
        assert_eq!(s.current(1), Manual::Never);
        let mut off = ManualSelector::new(InputMode::Disabled, LOSS);
        off.receive(Source::Rc, input(0.5), 0);
        assert_eq!(off.current(1), Manual::Never);
    }

    #[test]
    fn com_rc_in_mode_values_map_as_px4_numbers_them() {
        assert_eq!(InputMode::from_param(3.0), Some(InputMode::KeepFirst));
        assert_eq!(InputMode::from_param(0.0), Some(InputMode::RcOnly));
        assert_eq!(InputMode::from_param(5.0), None);
        assert_eq!(InputMode::from_param(f32::NAN), None);
    }
}
