//! Rotor thrust to ESC command: a piecewise-linear table, replaceable by a bench
//! calibration. The paper's map came from the motor maker's data and over-read thrust; ours is
//! a parameter table (`THR_MAP_20` .. `THR_MAP_80`): the thrust each command of 20, 40, 60 and
//! 80 % gives, as a fraction of the thrust at 100 % (the rotor's maximum thrust, which the
//! controller already knows). Zero command gives zero thrust. The default is the square law of a
//! fixed-pitch propeller whose speed follows the command.

/// Commands of the table's interior points, fractions of full command.
pub const COMMANDS: [f32; 4] = [0.2, 0.4, 0.6, 0.8];
/// The square law: thrust fractions at [`COMMANDS`].
pub const SQUARE_LAW: [f32; 4] = [0.04, 0.16, 0.36, 0.64];

/// Why a table is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ThrustMapError {
    /// A thrust fraction outside (0, 1) or not a number.
    OutOfRange {
        /// Which interior point (0 for 20 %).
        index: usize,
        /// The value given.
        value: f32,
    },
    /// Thrust does not rise with the command.
    NotIncreasing {
        /// The point that is not above the one before it.
        index: usize,
    },
}

impl core::fmt::Display for ThrustMapError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            // Thousandths, not `f32` formatting (which costs the firmware 14 KB of flash).
            Self::OutOfRange { index, value } => write!(
                f,
                "thrust map: the point at {} % command is {} thousandths, outside 0..1 (fraction of full thrust)",
                20 * (index + 1),
                if value.is_finite() {
                    (value * 1000.0) as i32
                } else {
                    i32::MIN
                }
            ),
            Self::NotIncreasing { index } => write!(
                f,
                "thrust map: thrust at {} % command is not above thrust at {} %",
                20 * (index + 1),
                20 * index
            ),
        }
    }
}

/// A validated map: thrust fractions at commands 0, 20, .., 100 %.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThrustMap {
    thrust: [f32; 6],
}

impl Default for ThrustMap {
    fn default() -> Self {
        Self::SQUARE
    }
}

impl ThrustMap {
    /// The square law ([`SQUARE_LAW`]).
    pub const SQUARE: Self = Self {
        thrust: [0.0, 0.04, 0.16, 0.36, 0.64, 1.0],
    };

    /// A map from the thrust fractions at 20, 40, 60 and 80 % command, which must rise
    /// strictly within (0, 1).
    pub fn new(interior: [f32; 4]) -> Result<Self, ThrustMapError> {
        let mut thrust = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        for (index, &value) in interior.iter().enumerate() {
            if !(value > 0.0 && value < 1.0) {
                return Err(ThrustMapError::OutOfRange { index, value });
            }
            if value <= thrust[index] {
                return Err(ThrustMapError::NotIncreasing { index });
            }
            thrust[index + 1] = value;
        }
        Ok(Self { thrust })
    }

    /// The command fraction that gives thrust fraction `thrust` (clamped to `[0, 1]`; zero for
    /// a non-finite value).
    pub fn command(&self, thrust: f32) -> f32 {
        if thrust.is_nan() || thrust <= 0.0 {
            return 0.0;
        }
        let thrust = thrust.min(1.0);
        let mut lower = 0;
        while lower < 4 && self.thrust[lower + 1] < thrust {
            lower += 1;
        }
        let (t0, t1) = (self.thrust[lower], self.thrust[lower + 1]);
        (lower as f32 + (thrust - t0) / (t1 - t0)) * 0.2
    }

    /// The thrust fraction command `command` gives (the table read forwards).
    pub fn thrust(&self, command: f32) -> f32 {
        if command.is_nan() || command <= 0.0 {
            return 0.0;
        }
        let position = command.min(1.0) * 5.0;
        let lower = (position as usize).min(4);
        let along = position - lower as f32;
        self.thrust[lower] + along * (self.thrust[lower + 1] - self.thrust[lower])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_square_law_by_hand() {
        let map = ThrustMap::new(SQUARE_LAW).unwrap();
        assert_eq!(map, ThrustMap::SQUARE);
        // At the table's points the inverse is exact.
        assert!((map.command(0.16) - 0.4).abs() < 1e-6);
        assert!((map.command(1.0) - 1.0).abs() < 1e-6);
        // Between 0.36 (60 %) and 0.64 (80 %): half-way is 0.5 -> 70 %.
        assert!((map.command(0.5) - 0.7).abs() < 1e-6);
        // Between 0 and 0.04 (20 %): 0.02 -> 10 %.
        assert!((map.command(0.02) - 0.1).abs() < 1e-6);
        assert_eq!(map.command(0.0), 0.0);
        assert_eq!(map.command(-1.0), 0.0);
        assert_eq!(map.command(f32::NAN), 0.0);
        assert!((map.command(3.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn command_inverts_thrust_everywhere() {
        let map = ThrustMap::new([0.1, 0.3, 0.5, 0.8]).unwrap();
        for i in 0..=100 {
            let c = i as f32 / 100.0;
            let back = map.command(map.thrust(c));
            assert!((back - c).abs() < 1e-5, "{c} -> {back}");
        }
    }

    #[test]
    fn bad_tables_are_refused_with_the_point_named() {
        assert_eq!(
            ThrustMap::new([0.1, 0.3, 0.3, 0.8]),
            Err(ThrustMapError::NotIncreasing { index: 2 })
        );
        assert_eq!(
            ThrustMap::new([0.1, 0.3, 0.5, 1.2]),
            Err(ThrustMapError::OutOfRange {
                index: 3,
                value: 1.2
            })
        );
        assert!(matches!(
            ThrustMap::new([f32::NAN, 0.3, 0.5, 0.8]),
            Err(ThrustMapError::OutOfRange { index: 0, .. })
        ));
        assert_eq!(
            ThrustMap::new([0.0, 0.3, 0.5, 0.8]),
            Err(ThrustMapError::OutOfRange {
                index: 0,
                value: 0.0
            })
        );
    }
}
