//! How many robots a flight controller drives: rotors (for the ESC protocol in force) and
//! steppers, and the refusal of a payload description with more robots than that
//! (docs/hardware.md#robots-a-board-drives). A board that took such a description would lift
//! with robots that never move and fly with rotors that never spin, and say nothing.

use crate::scenario::MAX_ROBOTS;

use crate::mission::esc_protocol::EscProtocol;

/// ESC protocols ([`EscProtocol::ALL`]).
pub const ESC_PROTOCOLS: usize = EscProtocol::ALL.len();

/// `ESC_PROTOCOL`'s value for DroneCAN ESCs on the CAN bus.
pub const ESC_PROTOCOL_DRONECAN: u8 = EscProtocol::DroneCan.value();

/// An ESC protocol's name for people, from `ESC_PROTOCOL`'s value ("unknown" for none).
pub fn esc_protocol_name(value: u8) -> &'static str {
    EscProtocol::from_value(i32::from(value)).map_or("unknown", EscProtocol::name)
}

/// What one board drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoardDrives {
    /// Rotors it drives with each ESC protocol, by `ESC_PROTOCOL`'s value.
    pub rotors: [u8; ESC_PROTOCOLS],
    /// Steppers it drives.
    pub steppers: u8,
}

/// The Pixhawk 6C: eight FMU outputs with DShot, PWM or OneShot125 (its eight IO outputs go
/// through the IO co-processor, which this firmware does not drive), sixteen DroneCAN ESCs on
/// CAN1; sixteen TMC2209 on four UARTs.
pub const PIXHAWK_6C: BoardDrives = BoardDrives {
    rotors: [8, 8, 8, MAX_ROBOTS as u8],
    steppers: MAX_ROBOTS as u8,
};

/// QEMU's mps2-an500 in the loop: the plant takes every robot's command over the link.
pub const QEMU_MPS2_AN500: BoardDrives = BoardDrives::uniform(MAX_ROBOTS as u8, MAX_ROBOTS as u8);

/// The boards by the names the firmware reports and the command line takes.
pub const BOARDS: [(&str, BoardDrives); 2] = [("pixhawk6c", PIXHAWK_6C), ("qemu", QEMU_MPS2_AN500)];

/// The board of a name in [`BOARDS`].
pub fn board(name: &str) -> Option<BoardDrives> {
    BOARDS.iter().find(|(n, _)| *n == name).map(|&(_, d)| d)
}

impl BoardDrives {
    /// A board that drives `rotors` with every ESC protocol and `steppers`.
    pub const fn uniform(rotors: u8, steppers: u8) -> Self {
        Self {
            rotors: [rotors; ESC_PROTOCOLS],
            steppers,
        }
    }

    /// The same board driving at most `robots` of each (QEMU's `max-robots`).
    pub fn at_most(self, robots: u8) -> Self {
        Self {
            rotors: self.rotors.map(|r| r.min(robots)),
            steppers: self.steppers.min(robots),
        }
    }

    /// Rotors it drives with ESC protocol `esc_protocol` (none with an unknown one).
    pub fn rotors(&self, esc_protocol: u8) -> u8 {
        self.rotors
            .get(usize::from(esc_protocol))
            .copied()
            .unwrap_or(0)
    }

    /// `Ok` when it drives `robots` robots' rotors with `esc_protocol` and their steppers;
    /// otherwise what it drives.
    pub fn check(&self, robots: usize, esc_protocol: u8) -> Result<(), TooManyRobots> {
        let rotors = self.rotors(esc_protocol);
        if robots <= usize::from(rotors) && robots <= usize::from(self.steppers) {
            return Ok(());
        }
        Err(TooManyRobots {
            robots,
            rotors,
            steppers: self.steppers,
            esc_protocol,
        })
    }
}

/// A payload's robots are more than a board drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManyRobots {
    /// The payload description's robots.
    pub robots: usize,
    /// Rotors the board drives with the protocol.
    pub rotors: u8,
    /// Steppers the board drives.
    pub steppers: u8,
    /// The ESC protocol (`ESC_PROTOCOL`'s value).
    pub esc_protocol: u8,
}

impl core::fmt::Display for TooManyRobots {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} robots; this board drives {} rotors (ESC_PROTOCOL {}) and {} steppers",
            self.robots,
            self.rotors,
            esc_protocol_name(self.esc_protocol),
            self.steppers
        )
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;

    #[test]
    fn the_pixhawk_drives_eight_robots_on_its_outputs_and_sixteen_on_dronecan() {
        for protocol in 0..ESC_PROTOCOLS as u8 {
            assert_eq!(PIXHAWK_6C.check(8, protocol), Ok(()));
        }
        for protocol in 0..ESC_PROTOCOL_DRONECAN {
            assert!(PIXHAWK_6C.check(9, protocol).is_err(), "{protocol}");
        }
        let refusal = PIXHAWK_6C.check(12, 0).expect_err("12 robots");
        assert_eq!(
            refusal.to_string(),
            "12 robots; this board drives 8 rotors (ESC_PROTOCOL DShot600) and 16 steppers"
        );
        assert_eq!(PIXHAWK_6C.check(12, ESC_PROTOCOL_DRONECAN), Ok(()));
        assert_eq!(PIXHAWK_6C.check(MAX_ROBOTS, ESC_PROTOCOL_DRONECAN), Ok(()));
        assert_eq!(esc_protocol_name(ESC_PROTOCOL_DRONECAN), "DroneCAN");
    }

    #[test]
    fn the_fewer_of_rotors_and_steppers_limits_and_an_unknown_protocol_drives_none() {
        let board = BoardDrives {
            rotors: [16, 8, 8, 16],
            steppers: 12,
        };
        assert_eq!(board.check(12, 0), Ok(()));
        assert!(board.check(13, 0).is_err(), "13 robots, 12 steppers");
        assert!(board.check(12, 1).is_err(), "12 robots, 8 PWM rotors");
        assert_eq!(board.rotors(7), 0);
        assert!(board.check(1, 7).is_err());
    }

    #[test]
    fn qemu_drives_every_robot_unless_told_fewer() {
        assert_eq!(QEMU_MPS2_AN500.check(MAX_ROBOTS, 0), Ok(()));
        let eight = QEMU_MPS2_AN500.at_most(8);
        assert_eq!(eight, BoardDrives::uniform(8, 8));
        assert_eq!(board("qemu"), Some(QEMU_MPS2_AN500));
        assert_eq!(board("pixhawk6c"), Some(PIXHAWK_6C));
        assert_eq!(board("pixhawk"), None);
    }
}
