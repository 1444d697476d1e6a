//! What an ESC protocol is (docs/hardware.md#robots-a-board-drives): the one type every crate
//! uses for the `ESC_PROTOCOL` parameter's choices. Its values, names and the parameter's range
//! derive from [`EscProtocol::ALL`]; how many rotors a board drives with each is
//! [`super::drives::BoardDrives`]'s, the pulses on the FMU outputs `drivers::pulse`'s, the
//! frames on the CAN bus `drivers::dronecan`'s.

/// An ESC protocol, by `ESC_PROTOCOL`'s value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EscProtocol {
    /// DShot600 on the FMU outputs, digital; the default.
    Dshot600,
    /// Standard PWM on the FMU outputs: 1000-2000 us pulses at 400 Hz.
    Pwm,
    /// OneShot125 on the FMU outputs: 125-250 us pulses, one per control step.
    OneShot125,
    /// DroneCAN ESCs on the CAN bus: the FMU outputs send nothing, their lines held low.
    DroneCan,
}

/// A protocol number that names no protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UnknownProtocol(pub i32);

/// Every protocol's value and name, as a message lists them: "0 DShot600, 1 PWM, ...".
#[derive(Clone, Copy, Debug)]
pub struct Choices;

impl core::fmt::Display for Choices {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for (i, p) in EscProtocol::ALL.iter().enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            write!(f, "{sep}{} {}", p.value(), p.name())?;
        }
        Ok(())
    }
}

impl core::fmt::Display for UnknownProtocol {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "ESC protocol {} is unknown ({})", self.0, Choices)
    }
}

impl EscProtocol {
    /// Every protocol, in the order of their values (the value is the index).
    pub const ALL: [Self; 4] = [Self::Dshot600, Self::Pwm, Self::OneShot125, Self::DroneCan];

    /// Its `ESC_PROTOCOL` value.
    pub const fn value(self) -> u8 {
        match self {
            Self::Dshot600 => 0,
            Self::Pwm => 1,
            Self::OneShot125 => 2,
            Self::DroneCan => 3,
        }
    }

    /// The protocol a parameter value names.
    pub fn from_value(value: i32) -> Result<Self, UnknownProtocol> {
        usize::try_from(value)
            .ok()
            .and_then(|i| Self::ALL.get(i).copied())
            .ok_or(UnknownProtocol(value))
    }

    /// Its name for people.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Dshot600 => "DShot600",
            Self::Pwm => "PWM",
            Self::OneShot125 => "OneShot125",
            Self::DroneCan => "DroneCAN",
        }
    }

    /// Whether its ESCs sit on the CAN bus (their RPM comes one message at a time).
    pub const fn on_can_bus(self) -> bool {
        matches!(self, Self::DroneCan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_the_order_and_others_are_refused_naming_every_choice() {
        for (i, p) in EscProtocol::ALL.iter().enumerate() {
            assert_eq!(usize::from(p.value()), i);
            assert_eq!(EscProtocol::from_value(i as i32), Ok(*p));
        }
        assert_eq!(EscProtocol::from_value(-1), Err(UnknownProtocol(-1)));
        let err = EscProtocol::from_value(7).unwrap_err();
        assert_eq!(err, UnknownProtocol(7));
        assert_eq!(
            std::format!("{err}"),
            "ESC protocol 7 is unknown (0 DShot600, 1 PWM, 2 OneShot125, 3 DroneCAN)"
        );
        assert!(EscProtocol::DroneCan.on_can_bus() && !EscProtocol::Pwm.on_can_bus());
    }
}
