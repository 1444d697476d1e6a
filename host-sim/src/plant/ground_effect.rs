//! Ground effect on each rotor (docs/formats.md#the-plant-section): Cheeseman and Bennett's
//! model (I. C. Cheeseman and W. E. Bennett, "The effect of the ground on a helicopter rotor in
//! forward flight", ARC R&M 3021, 1955), in hover: a rotor of radius `R` whose plane is `z`
//! above the ground makes `T_IGE / T_OGE = 1 / (1 - (R / 4z)^2)` of the thrust it makes clear
//! of the ground at the same power. The formula diverges at `z = R / 4`; the gain is held at its
//! value at `z = R / 2`, [`MAX_GAIN`] (4/3), below that: the method of images it rests on is not
//! meant for a rotor that close (Sanchez-Cuevas, Heredia and Ollero, "Characterization of the
//! aerodynamic ground effect and its influence in multirotor control", Int. J. Aerospace
//! Engineering, 2017, compare the same model with small rotors measured near the ground).

/// A rotor's radius, m: the 10-inch propeller the plant assumes
/// ([`super::RPM_AT_MAX_THRUST`]).
pub const ROTOR_RADIUS: f32 = 0.127;
/// The rotor plane's height above the payload plate's top face, m. The paper does not give it:
/// the robot rides the rail on the plate with its rotor on an arm outside the outline (SPEC),
/// the motor on top of the arm: some 8 cm, so the rotor stands 0.11 m (0.87 radius) above the
/// ground with the payload resting on it.
pub const ROTOR_ABOVE_PLATE: f32 = 0.08;
/// The largest gain: the formula's value at half a radius, 1 / (1 - 1/4).
pub const MAX_GAIN: f32 = 4.0 / 3.0;

/// The thrust gain of a rotor of radius `radius` whose plane is `height` above the ground
/// (both m): Cheeseman and Bennett's ratio, at most [`MAX_GAIN`].
pub fn gain(radius: f32, height: f32) -> f32 {
    if height <= 0.5 * radius {
        return MAX_GAIN;
    }
    let r = radius / (4.0 * height);
    1.0 / (1.0 - r * r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_the_ground_the_thrust_rises_by_the_formulas_amount_and_aloft_it_does_not() {
        let r = ROTOR_RADIUS;
        // One radius up: 1 / (1 - 1/16) = 16/15.
        assert!((gain(r, r) - 16.0 / 15.0).abs() < 1e-6, "{}", gain(r, r));
        // Two radii up: 1 / (1 - 1/64) = 64/63.
        assert!((gain(r, 2.0 * r) - 64.0 / 63.0).abs() < 1e-6);
        // Resting on the ground: the plate's thickness and the arm below the rotor.
        let resting = super::super::PLATE_THICKNESS + ROTOR_ABOVE_PLATE;
        let g = gain(r, resting);
        assert!((1.07..1.1).contains(&g), "resting {g}");
        // A metre up: a tenth of a percent, (0.127 / 4)^2; two metres up, a quarter of that.
        assert!((gain(r, 1.0) - 1.001_009).abs() < 2e-6, "{}", gain(r, 1.0));
        assert!(gain(r, 2.0) - 1.0 < 3e-4);
        // Falling monotonically with height, held at the cap below half a radius.
        let heights = [0.01, 0.05, 0.5 * r, 0.07, 0.1, 0.2, 0.5, 2.0];
        for w in heights.windows(2) {
            assert!(gain(r, w[0]) >= gain(r, w[1]), "{w:?}");
        }
        assert_eq!(gain(r, 0.01), MAX_GAIN);
        assert_eq!(gain(r, 0.5 * r), MAX_GAIN);
        assert!(gain(r, 0.5 * r + 1e-3) < MAX_GAIN);
    }
}
