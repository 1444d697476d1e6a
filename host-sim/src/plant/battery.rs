//! The pack that feeds the rotors (docs/formats.md#the-plant-section). Its terminal voltage
//! falls with the current the rotors draw, `V = V0 - R I`, and each rotor's thrust for its
//! command falls with `(V / V0)^2`: at a given duty the motor's speed goes with the voltage and
//! the thrust with the speed squared. The current is the rotors' electrical power over the
//! voltage; a rotor's power for its thrust is momentum theory's ideal hover power
//! `T^1.5 / sqrt(2 rho A)` (J. G. Leishman, Principles of Helicopter Aerodynamics, ch. 2) over
//! the propeller's figure of merit ([`FIGURE_OF_MERIT`]) and the motor and ESC's efficiency
//! ([`DRIVE_EFFICIENCY`]): for the 10-inch propeller, 4.3 g/W at its largest thrust (14.2 N,
//! 23 A at 14.8 V) and 6 g/W at half of it. The robots' motor is not described; these figures
//! are to be checked against a thrust-stand table of the real motor and propeller.
//!
//! The model's pack ([`PACK_VOLTS`], [`PACK_SAG_VOLTS`]) is the one the command-to-thrust map
//! was measured with: its reading sags with the load, its rotors do not feel it. The `[plant]`
//! key `battery_sag` is the resistance beyond it, which they do.

use super::ground_effect::ROTOR_RADIUS;
use super::wind::AIR_DENSITY;

/// The simulated pack's open-circuit voltage, V: a 4S lithium-polymer pack near full (the
/// prototype's pack is not described; a 4S pack fits its 14.2 N rotors).
pub const PACK_VOLTS: f32 = 16.0;
/// The model pack's reading's sag with every rotor at full thrust, V (about 20 mOhm at 40 A);
/// in proportion below that.
pub const PACK_SAG_VOLTS: f32 = 0.8;
/// A small propeller's figure of merit in hover: its ideal power over its real (0.5 to 0.7
/// for propellers of this size; Leishman, ch. 2).
pub const FIGURE_OF_MERIT: f32 = 0.6;
/// The motor and ESC's efficiency, electrical power in to shaft power out (0.7 to 0.85 for
/// outrunners of this class near hover).
pub const DRIVE_EFFICIENCY: f32 = 0.75;

/// The electrical power a rotor draws to make `thrust` N, W.
pub fn electrical_power(thrust: f32) -> f32 {
    let disc = std::f32::consts::PI * ROTOR_RADIUS * ROTOR_RADIUS;
    let ideal = thrust.max(0.0).powf(1.5) / (2.0 * AIR_DENSITY * disc).sqrt();
    ideal / (FIGURE_OF_MERIT * DRIVE_EFFICIENCY)
}

/// A pack of internal resistance `resistance`, Ohm, and open-circuit voltage [`PACK_VOLTS`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pack {
    /// Internal resistance, Ohm.
    pub resistance: f32,
}

impl Pack {
    /// The terminal voltage while the rotors draw `power` W in all, V: the larger root of
    /// `V^2 - V0 V + R P = 0` (`V = V0 - R P / V`). A draw beyond the pack's largest power
    /// (`V0^2 / 4R`) holds it at `V0 / 2`, where it delivers that largest power.
    pub fn terminal_volts(&self, power: f32) -> f32 {
        let v0 = PACK_VOLTS;
        let discriminant = v0 * v0 - 4.0 * self.resistance * power.max(0.0);
        0.5 * (v0 + discriminant.max(0.0).sqrt())
    }

    /// Each rotor's thrust for its command at terminal voltage `volts`, relative to the
    /// thrust at the open-circuit voltage.
    pub fn thrust_factor(volts: f32) -> f32 {
        let v = volts / PACK_VOLTS;
        v * v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_power_for_a_thrust_is_a_10_inch_propellers_on_4s() {
        // Grams per watt at the largest thrust and at half of it.
        let grams_per_watt = |t: f32| t / 9.81 * 1000.0 / electrical_power(t);
        let full = grams_per_watt(14.2);
        let half = grams_per_watt(7.1);
        assert!((4.0..4.6).contains(&full), "{full} g/W");
        assert!((5.7..6.4).contains(&half), "{half} g/W");
        assert_eq!(electrical_power(0.0), 0.0);
        assert_eq!(electrical_power(-1.0), 0.0);
    }

    #[test]
    fn the_thrust_for_a_command_falls_as_the_current_rises() {
        let pack = Pack { resistance: 0.05 };
        // No draw: the open-circuit voltage and the full thrust.
        assert_eq!(pack.terminal_volts(0.0), PACK_VOLTS);
        assert_eq!(Pack::thrust_factor(pack.terminal_volts(0.0)), 1.0);
        let mut last = (PACK_VOLTS, 1.0);
        for rotors_at_half in 1..=8 {
            let power = rotors_at_half as f32 * electrical_power(7.1);
            let v = pack.terminal_volts(power);
            // The voltage is the one the current it makes gives: V = V0 - R P / V.
            assert!((v - (PACK_VOLTS - pack.resistance * power / v)).abs() < 1e-3);
            let factor = Pack::thrust_factor(v);
            assert!(v < last.0 && factor < last.1, "{rotors_at_half}: {v} V");
            last = (v, factor);
        }
        // Eight rotors at half thrust draw some 80 A: 4 V less, 0.57 of the thrust.
        assert!((0.5..0.62).contains(&last.1), "{last:?}");
        // No resistance, no sag.
        let ideal = Pack { resistance: 0.0 };
        assert_eq!(ideal.terminal_volts(2000.0), PACK_VOLTS);
        // Beyond the pack's largest power: half its voltage.
        let worn = Pack { resistance: 0.2 };
        assert_eq!(worn.terminal_volts(1.0e5), 0.5 * PACK_VOLTS);
    }
}
