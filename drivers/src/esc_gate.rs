//! What the ESC outputs send at each update: the control step's command only while
//! armed, the stop command while disarmed and whenever no command came within the feed
//! timeout (the control task stopped), and a change of protocol only while disarmed (the
//! timers change rate then, which would drop a spinning rotor's pulses).

use crate::pulse::EscProtocol;

/// One control step's command to `N` ESCs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EscCommand<const N: usize> {
    /// The protocol the parameters ask for.
    pub protocol: EscProtocol,
    /// Command fractions `[0, 1]`, one per output.
    pub fractions: [f32; N],
    /// Whether the rotors may turn.
    pub armed: bool,
}

/// What one update sends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EscUpdate<const N: usize> {
    /// Command fractions to send (all zero: stop).
    pub fractions: [f32; N],
    /// The protocol to switch the timers to before sending, if it changes.
    pub switch_to: Option<EscProtocol>,
}

/// The outputs' state: the protocol the timers run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EscGate {
    protocol: EscProtocol,
}

impl EscGate {
    /// Outputs whose timers run `protocol`.
    pub const fn new(protocol: EscProtocol) -> Self {
        Self { protocol }
    }

    /// The protocol the timers run.
    pub fn protocol(&self) -> EscProtocol {
        self.protocol
    }

    /// One update, with the latest command, or `None` if none came within the feed timeout.
    pub fn update<const N: usize>(&mut self, command: Option<&EscCommand<N>>) -> EscUpdate<N> {
        let mut switch_to = None;
        if let Some(c) = command
            && !c.armed
            && c.protocol != self.protocol
        {
            self.protocol = c.protocol;
            switch_to = Some(c.protocol);
        }
        let fractions = match command {
            Some(c) if c.armed && c.protocol == self.protocol => c.fractions,
            _ => [0.0; N],
        };
        EscUpdate {
            fractions,
            switch_to,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn command(protocol: EscProtocol, armed: bool) -> EscCommand<4> {
        EscCommand {
            protocol,
            fractions: [0.5, 0.6, 0.7, 0.8],
            armed,
        }
    }

    #[test]
    fn armed_commands_pass_and_everything_else_stops() {
        let mut gate = EscGate::new(EscProtocol::Dshot600);
        let armed = command(EscProtocol::Dshot600, true);
        assert_eq!(gate.update(Some(&armed)).fractions, armed.fractions);
        let disarmed = command(EscProtocol::Dshot600, false);
        assert_eq!(gate.update(Some(&disarmed)).fractions, [0.0; 4]);
        // The control task stopped feeding: stop, whatever came before.
        assert_eq!(gate.update::<4>(None).fractions, [0.0; 4]);
        assert_eq!(gate.update::<4>(None).switch_to, None);
    }

    #[test]
    fn the_protocol_changes_only_while_disarmed() {
        let mut gate = EscGate::new(EscProtocol::Dshot600);
        // Asked for in flight: refused, and the outputs stop rather than send PWM widths as
        // DShot frames.
        let up = gate.update(Some(&command(EscProtocol::Pwm, true)));
        assert_eq!(up.switch_to, None);
        assert_eq!(up.fractions, [0.0; 4]);
        assert_eq!(gate.protocol(), EscProtocol::Dshot600);
        // On the ground: taken.
        let up = gate.update(Some(&command(EscProtocol::Pwm, false)));
        assert_eq!(up.switch_to, Some(EscProtocol::Pwm));
        assert_eq!(up.fractions, [0.0; 4]);
        assert_eq!(gate.protocol(), EscProtocol::Pwm);
        // Then armed in the new protocol: the command passes, no further switch.
        let up = gate.update(Some(&command(EscProtocol::Pwm, true)));
        assert_eq!(up.switch_to, None);
        assert_eq!(up.fractions, [0.5, 0.6, 0.7, 0.8]);
    }
}
